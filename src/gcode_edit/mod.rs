//! Editing another slicer's G-code by a density field: the paper's section 2.3.3.
//!
//! Entry: [`edit`]. A G-code file made by PrusaSlicer, Slic3r or Cura at a uniform infill
//! density ρ_s is rewritten so that each infill move extrudes for the density the field asks
//! at its midpoint (equation 6):
//!
//! ```text
//!   ΔE_e,i = ΔE_s,i · ρ_e,i / ρ_s,    ρ_e,i = clamp(ρ(midpoint_i + translation), ρ_min, ρ_max)
//! ```
//!
//! Only the digits of the `E` word of infill moves change; every other byte of the file is
//! copied as it is (comments, spacing, line endings, other words, other features).
//!
//! **Infill moves.** A `G0`/`G1` (or a bare parameter line repeating one) with XY motion and a
//! positive E delta while the current feature is an infill type ([`dialect`] lists each
//! slicer's markers, with example lines). Arcs (`G2`/`G3`) inside infill are left unchanged
//! and counted ([`EditReport::arcs_unchanged`]): slicers do not write infill as arcs unless
//! arc fitting is on, and one arc spans too much of the field for one midpoint value. Infill
//! moves whose midpoint has no density (outside the volume) are left unchanged too.
//!
//! **Modal state** comes from the shared machine model ([`crate::motion::Motion`]: G90/G91,
//! G92, G20/G21 inches, feed, arcs) and the shared lexer; the E mode (M82/M83, and G90/G91,
//! which as in Marlin reset it) and the E position in the file's own units are mirrored here
//! because the rewrite needs them and the machine model keeps them private.
//!
//! **Relative E (M83).** The E word is the delta: its number is replaced by the new delta.
//!
//! **Absolute E (M82).** An edited move gets `E = E_out + ΔE_new`, where `E_out` is the E
//! position the printer has after the edited file's previous lines. After a run of edited
//! moves the printer's E differs from the E the file's following lines were written for, so
//! one line `G92 E<the original absolute E>` (the last edited move's original number, copied
//! verbatim) is inserted before the next command line, and every following line stays byte
//! for byte valid. Design choice: the alternative, rewriting every later E word of the file,
//! would change every line after the first edit and hide the edit in a diff; the inserted
//! `G92` lines are counted in [`EditReport::resets_inserted`]. No line is inserted where the
//! next command is itself a `G92 E…`, where the edit printed the original number, or at the
//! end of the file. Relative edits followed by a switch to absolute E get the same reset
//! before the switch.
//!
//! **Limits.** Per edited move, with the stadium bead model (area = l_h·(E_w + (π/4 − 1)·l_h),
//! area = ΔE·π d_f²/4 / length): the width E_w against [`Options::width_max_mm`] (the paper's
//! E_w,max) and the volumetric flow area × feed against [`Options::q_max_mm3_s`] (Q_max).
//! [`Limit::Warn`] counts moves over them; [`Limit::Clamp`] also reduces their E to the
//! limit (below ρ_min if need be: the machine limit wins). The layer height l_h is the last
//! `;HEIGHT:`-style comment, else the Z step between layers.
//!
//! Cost: one pass over the bytes, no allocation per unchanged line (slices are copied into
//! one output buffer reserved at the input's size), the density evaluated once per infill
//! move. Memory: the output, about the input's size ([`estimate`]).

pub mod dialect;
pub mod rewrite;

use crate::budget::{Estimate, OverBudget, MAX_STAGE_BYTES};
use crate::geom::{Aabb, DVec3};
use crate::motion::lex::{self, lex_line, Command, Line, MAX_WORD_MAGNITUDE};
use crate::motion::{Motion, Step, MOTION_EPS};
use crate::scaffold::{max_bead_area, mean_along, width_of_area};
use crate::source::{for_each_line_chunk, ByteSource, ChunkError};
use dialect::{Dialect, InfillTypes};
use rewrite::{find_word, write_number, Found, Style};
use serde::{Deserialize, Serialize};

/// Infill density the file was sliced with: the paper's femur case (table 3), 47 %.
pub const DEFAULT_RHO_S: f64 = 0.47;
/// Volumetric flow limit, mm³/s: Q_max of the paper's PLA at 215 °C (section 3.1).
pub const DEFAULT_Q_MAX_MM3_S: f64 = 19.24;
/// Filament diameter, mm.
pub const DEFAULT_FILAMENT_MM: f64 = 1.75;
/// Floor of the target density ρ_e,min: ρ_s · E_w,min / E_w = 0.47 · 0.2 / 0.4 (at a fixed
/// cell size the density is proportional to the bead width, equation 4; E_w,min = l_h =
/// 0.2 mm by equation 2 and E_w = 0.4 mm the slicer's width, table 3).
pub const DEFAULT_RHO_MIN: f64 = 0.235;
/// Ceiling of the target density: solid.
pub const DEFAULT_RHO_MAX: f64 = 1.0;
/// Sampling step of the field along a move for the report's target ρ, mm (a quarter of the
/// femur case's 0.98 mm pixel). The edit itself reads the field at the midpoint only (the
/// paper's rule); the report measures how far that is from the field along the move.
pub const DEFAULT_TARGET_STEP_MM: f64 = 0.25;
/// Widest bead, mm: E_w,max = 3 × the 0.4 mm nozzle (equation 3).
pub const DEFAULT_WIDTH_MAX_MM: f64 = 1.2;
/// Feature names treated as infill by default: PrusaSlicer's `;TYPE:Internal infill`,
/// Cura's `;TYPE:FILL`, Slic3r 1.3's per-line `; infill`.
pub const DEFAULT_INFILL_TYPES: [&str; 3] = ["Internal infill", "FILL", "infill"];
/// E moves whose E word is read for the file's number style ([`rewrite::Style`]) whatever
/// their feature; after them only infill moves' words are (they are found anyway).
pub const STYLE_MOVES: usize = 4096;
/// Layer height assumed before the file states one or steps in Z, mm.
pub const DEFAULT_LAYER_HEIGHT_MM: f64 = 0.2;
/// Largest G-code file edited, bytes (the output is as large, and both are held at once).
pub const MAX_GCODE_BYTES: usize = 512 << 20;
/// Longest line read, bytes. Slicers write lines of under 100 bytes (thumbnails are split
/// into 78-character lines); a longer one is not G-code a printer would take.
pub const MAX_LINE_BYTES: usize = 1 << 20;
/// Feature names listed in [`Error::NoInfill`] at most.
pub const MAX_TYPES_SEEN: usize = 32;
/// Editing time per byte of G-code on the reference machine, s (release build, PrusaSlicer-
/// style file with 40 % infill moves: see the `edits_a_50_mb_file` test's printout).
pub const SECONDS_PER_BYTE: f64 = 1.3e-8;

/// What to do with a move over the flow or width limit: count it ([`EditReport::over_flow`],
/// [`EditReport::over_width`]), or also reduce its E so both limits hold.
pub use crate::scaffold::Limit;

/// Editing options.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Options {
    /// The infill density the file was sliced with, 0–1. Default [`DEFAULT_RHO_S`].
    pub rho_s: f64,
    /// Floor of the target density (ρ_e,min), 0–1. Default [`DEFAULT_RHO_MIN`].
    pub rho_min: f64,
    /// Ceiling of the target density, ρ_min–1. Default [`DEFAULT_RHO_MAX`].
    pub rho_max: f64,
    /// Per move over a limit: count ([`Limit::Warn`]) or also reduce E ([`Limit::Clamp`]).
    pub limit: Limit,
    /// Volumetric flow limit, mm³/s. Default [`DEFAULT_Q_MAX_MM3_S`].
    pub q_max_mm3_s: f64,
    /// Widest bead (E_w,max), mm. Default [`DEFAULT_WIDTH_MAX_MM`].
    pub width_max_mm: f64,
    /// Filament diameter (volume = E × π d²/4), mm. Default [`DEFAULT_FILAMENT_MM`].
    pub filament_mm: f64,
    /// Added to a G-code point to get the density field's point (p_field = p_gcode +
    /// translation), mm. Default zero.
    pub translation_mm: [f64; 3],
    /// Feature names treated as infill: `;TYPE:` (or `; FEATURE:`) markers, and per-line
    /// comments while the file has no marker (Slic3r). Exact, ignoring ASCII case. Default
    /// [`DEFAULT_INFILL_TYPES`].
    pub infill_types: Vec<String>,
    /// Sampling step of the report's target ρ along each move, mm. Default
    /// [`DEFAULT_TARGET_STEP_MM`].
    pub target_step_mm: f64,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            rho_s: DEFAULT_RHO_S,
            rho_min: DEFAULT_RHO_MIN,
            rho_max: DEFAULT_RHO_MAX,
            limit: Limit::Warn,
            q_max_mm3_s: DEFAULT_Q_MAX_MM3_S,
            width_max_mm: DEFAULT_WIDTH_MAX_MM,
            filament_mm: DEFAULT_FILAMENT_MM,
            translation_mm: [0.0; 3],
            infill_types: DEFAULT_INFILL_TYPES.iter().map(|s| s.to_string()).collect(),
            target_step_mm: DEFAULT_TARGET_STEP_MM,
        }
    }
}

pub use crate::scaffold::LayerStat;

/// What an edit did.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct EditReport {
    /// The slicer, from the header: `PrusaSlicer`, `Slic3r`, `Cura` or `unknown`.
    pub dialect: String,
    /// E mode of the file's E words: `relative`, `absolute` or `mixed`.
    pub extrusion: String,
    /// Lines read.
    pub lines: usize,
    /// Infill moves (extruding, with XY motion, in an infill feature).
    pub infill_moves: usize,
    /// Infill moves given a density and rewritten by equation 6 (the printed number may come
    /// out unchanged).
    pub edited_moves: usize,
    /// Infill moves whose midpoint has no density (outside the volume): left unchanged.
    pub outside_field: usize,
    /// Infill arcs (`G2`/`G3`): left unchanged.
    pub arcs_unchanged: usize,
    /// Edited moves whose target was below ρ_min (raised to it).
    pub clamped_low: usize,
    /// Edited moves whose target was above ρ_max (lowered to it).
    pub clamped_high: usize,
    /// Edited moves over the volumetric flow limit (before any clamp).
    pub over_flow: usize,
    /// Edited moves over the width limit (before any clamp).
    pub over_width: usize,
    /// `G92 E…` lines inserted after runs of edited absolute-E moves.
    pub resets_inserted: usize,
    /// Filament fed by the input: high-water mark of the net E, mm (as `weft analyze`
    /// reports it).
    pub filament_before_mm: f64,
    /// The same for the output, mm.
    pub filament_after_mm: f64,
    /// Filament volume of the infill moves in the input, mm³.
    pub infill_before_mm3: f64,
    /// The same in the output, mm³.
    pub infill_after_mm3: f64,
    /// Per layer of edited infill, in file order.
    pub layers: Vec<LayerStat>,
    /// Smallest corner of the extruding moves (the printed part's box), mm.
    pub bounds_min: [f64; 3],
    /// Largest corner, mm.
    pub bounds_max: [f64; 3],
}

/// The edited file and its report.
pub struct Edited {
    /// The edited G-code.
    pub text: Vec<u8>,
    /// What was done.
    pub report: EditReport,
}

/// Why a file could not be edited.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum Error {
    /// The file could not be read (moved or deleted since it was loaded).
    #[error("{file} could not be read ({message}); load it again")]
    Read {
        /// File name.
        file: String,
        /// Why, as the browser or the system said.
        message: String,
    },
    /// Binary data, not G-code.
    #[error("{file}: line {line} has a byte that is not text; this is not a G-code file (export G-code as plain text, not binary G-code)")]
    NotText {
        /// File name.
        file: String,
        /// 1-based line of the first binary byte.
        line: usize,
    },
    /// A word's number cannot be read.
    #[error("{file}: line {line}: {problem}; fix or delete that line")]
    Malformed {
        /// File name.
        file: String,
        /// 1-based line.
        line: usize,
        /// What is wrong.
        problem: String,
    },
    /// A line longer than [`MAX_LINE_BYTES`].
    #[error("{file}: line {line} is {bytes} bytes long, more than {MAX_LINE_BYTES}; G-code lines are short: this is not a slicer's G-code")]
    LineTooLong {
        /// File name.
        file: String,
        /// 1-based line.
        line: usize,
        /// Its length.
        bytes: usize,
    },
    /// An infill line carries a `*` checksum, which an edit would invalidate.
    #[error("{file}: line {line} has a checksum (*…); edit the slicer's G-code before a host adds line numbers and checksums")]
    Checksum {
        /// File name.
        file: String,
        /// 1-based line.
        line: usize,
    },
    /// No infill move was found.
    #[error("{file}: no infill moves found (infill types {wanted}); the file's features are {}; set infill_types to the name of its sparse infill, or slice it with infill (and, for Slic3r, verbose G-code: --gcode-comments)", seen(.types_seen))]
    NoInfill {
        /// File name.
        file: String,
        /// The infill types looked for, as a list.
        wanted: String,
        /// The `;TYPE:` names (or, without markers, per-line comments of extruding moves)
        /// found, in order of appearance, at most [`MAX_TYPES_SEEN`].
        types_seen: Vec<String>,
    },
    /// No extruding move at all ([`printed_bounds`]).
    #[error("{file}: no extruding move (G1 with XYZ motion and a positive E); this G-code prints nothing")]
    NoExtrusion {
        /// File name.
        file: String,
    },
    /// The work is over a budget.
    #[error("editing the G-code: {0}")]
    TooBig(OverBudget),
    /// An option is out of range.
    #[error("G-code edit option {option} = {value}: {problem}")]
    BadOption {
        /// Option name.
        option: &'static str,
        /// Its value, as given.
        value: String,
        /// The allowed range.
        problem: String,
    },
}

fn seen(types: &[String]) -> String {
    if types.is_empty() {
        "not named (no ;TYPE: markers, no per-line comments)".into()
    } else {
        types.iter().map(|t| format!("\"{t}\"")).collect::<Vec<_>>().join(", ")
    }
}

/// Checks the options' ranges.
fn validate(o: &Options) -> Result<(), Error> {
    let bad = |option: &'static str, value: f64, problem: &str| Err(Error::BadOption { option, value: value.to_string(), problem: problem.into() });
    if !(o.rho_s > 0.0 && o.rho_s <= 1.0) {
        return bad("rho_s", o.rho_s, "the sliced infill density must be in (0, 1] (47 % is 0.47)");
    }
    if !(0.0..=1.0).contains(&o.rho_min) {
        return bad("rho_min", o.rho_min, "must be in [0, 1]");
    }
    if !(o.rho_max >= o.rho_min && o.rho_max <= 1.0) {
        return bad("rho_max", o.rho_max, "must be in [rho_min, 1]");
    }
    if !(o.q_max_mm3_s > 0.0 && o.q_max_mm3_s.is_finite()) {
        return bad("q_max_mm3_s", o.q_max_mm3_s, "the flow limit must be a positive number of mm³/s");
    }
    if !(o.width_max_mm > 0.0 && o.width_max_mm.is_finite()) {
        return bad("width_max_mm", o.width_max_mm, "the width limit must be a positive number of mm");
    }
    if !(o.filament_mm > 0.0 && o.filament_mm <= 10.0) {
        return bad("filament_mm", o.filament_mm, "the filament diameter must be in (0, 10] mm (1.75 or 2.85)");
    }
    if let Some(&t) = o.translation_mm.iter().find(|t| !(t.is_finite() && t.abs() <= MAX_WORD_MAGNITUDE)) {
        return bad("translation_mm", t, "each component must be a finite number of mm");
    }
    if !(o.target_step_mm >= 0.001 && o.target_step_mm.is_finite()) {
        return bad("target_step_mm", o.target_step_mm, "the report's sampling step must be at least 0.001 mm");
    }
    if InfillTypes::new(&o.infill_types).is_empty() {
        return Err(Error::BadOption {
            option: "infill_types",
            value: format!("{:?}", o.infill_types),
            problem: "name at least one feature (\"Internal infill\", \"FILL\")".into(),
        });
    }
    Ok(())
}

/// Output bytes per input byte [`estimate`] plans for (an edited number may gain a decimal,
/// absolute-E files gain one `G92` line per run of infill).
const OUTPUT_GROWTH: f64 = 1.0625;

/// The work of editing `gcode_len` bytes: the output's size and memory, the time; refused
/// over [`MAX_GCODE_BYTES`] or the stage budgets. The options do not change the cost.
pub fn estimate(gcode_len: usize, options: &Options) -> Estimate {
    let _ = options;
    let n = gcode_len as f64;
    let out = n * OUTPUT_GROWTH + 4096.0;
    let fix = "edit a smaller G-code file (fewer layers or a smaller part)";
    Estimate::new("edit")
        .quantity("gcode_bytes", "G-code written (edited)", out, "bytes")
        .quantity("input_bytes", "G-code read", n, "bytes")
        .cost(out, n * SECONDS_PER_BYTE)
        .limit("the G-code to edit", n, MAX_GCODE_BYTES as f64, "bytes", fix)
        .budgets(fix)
}

/// Calls `f` for every line of `gcode` (a piece of the file that ends at a line end, after
/// `lines_before` lines) with its 1-based number in the file, its byte offset in the piece, the
/// whole line (with its newline) and its lexed content; maps the lexer's refusals to [`Error`].
/// Returns the number of the piece's last line.
fn for_each_line<'a>(
    name: &str,
    gcode: &'a [u8],
    lines_before: usize,
    mut f: impl FnMut(usize, usize, &'a [u8], &'a [u8], &Line<'a>) -> Result<(), Error>,
) -> Result<usize, Error> {
    if let Some(offset) = lex::first_binary_byte(gcode) {
        let line = lines_before + 1 + gcode[..offset].iter().filter(|&&b| b == b'\n').count();
        return Err(Error::NotText { file: name.to_string(), line });
    }
    let mut start = 0;
    let mut line_no = lines_before;
    while start < gcode.len() {
        let end = memchr::memchr(b'\n', &gcode[start..]).map_or(gcode.len(), |p| start + p + 1);
        line_no += 1;
        let full = &gcode[start..end];
        let mut content = full.strip_suffix(b"\n").unwrap_or(full);
        content = content.strip_suffix(b"\r").unwrap_or(content);
        if content.len() > MAX_LINE_BYTES {
            return Err(Error::LineTooLong { file: name.to_string(), line: line_no, bytes: content.len() });
        }
        let l = lex_line(content).map_err(|problem| Error::Malformed { file: name.to_string(), line: line_no, problem })?;
        f(line_no, start, full, content, &l)?;
        start = end;
    }
    Ok(line_no)
}

/// Grows `b` by the points of an extruding move.
fn grow(b: &mut Option<(DVec3, DVec3)>, m: &Motion, mv: &crate::motion::Move) {
    let pts = if mv.use_pts { &m.arc_pts[..] } else { std::slice::from_ref(&mv.to) };
    let from = DVec3::from(mv.from);
    let (lo, hi) = b.get_or_insert((from, from));
    for p in std::iter::once(&mv.from).chain(pts) {
        let p = DVec3::from(*p);
        *lo = lo.min(p);
        *hi = hi.max(p);
    }
}

/// The box of the extruding moves of `gcode` (any feature, arcs by their chords), mm: the
/// printed part, for aligning the density field to it automatically. One pass, nothing
/// allocated per line. Errors: [`Error::NotText`], [`Error::Malformed`],
/// [`Error::LineTooLong`], [`Error::NoExtrusion`].
pub fn printed_bounds(name: &str, gcode: &dyn ByteSource) -> Result<Aabb, Error> {
    let mut m = Motion::default();
    let mut b = None;
    let mut lines = 0;
    pieces(name, gcode, &mut |piece| {
        lines = for_each_line(name, piece, lines, |_, _, _, _, l| {
            if let Step::Move(mv) = m.line(l.cmd, &l.words, false) {
                if mv.de > 0.0 && mv.moves() {
                    grow(&mut b, &m, &mv);
                }
            }
            Ok(())
        })?;
        Ok(())
    })?;
    let (min, max) = b.ok_or_else(|| Error::NoExtrusion { file: name.to_string() })?;
    Ok(Aabb { min, max })
}

/// E mode, as Marlin keeps it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum EMode {
    /// Follows G90/G91.
    Follow,
    Absolute,
    Relative,
}

/// The modes the rewrite needs (mirrors [`Motion`]'s rules, which it keeps private).
#[derive(Clone, Copy, Debug)]
struct Modes {
    abs_xyz: bool,
    mode: EMode,
    /// mm per file unit (25.4 after G20).
    unit: f64,
}

impl Modes {
    fn relative(&self) -> bool {
        match self.mode {
            EMode::Follow => !self.abs_xyz,
            EMode::Absolute => false,
            EMode::Relative => true,
        }
    }

    /// Mode changes of a command.
    fn command(&mut self, cmd: Command) {
        match cmd {
            Command::G(90, 0) => (self.abs_xyz, self.mode) = (true, EMode::Follow),
            Command::G(91, 0) => (self.abs_xyz, self.mode) = (false, EMode::Follow),
            Command::M(82) => self.mode = EMode::Absolute,
            Command::M(83) => self.mode = EMode::Relative,
            Command::G(20, 0) => self.unit = 25.4,
            Command::G(21, 0) => self.unit = 1.0,
            _ => {}
        }
    }
}

/// The input's E state in the file's own units.
struct EState {
    modes: Modes,
    /// E position as the input's lines set it, file units.
    e: f64,
    /// The line that last set `e` absolutely (an absolute E word or a G92 E), whose number
    /// a reset copies verbatim (a copy: the piece it was read from may be gone).
    e_line: Option<Vec<u8>>,
}

/// Running sums of one layer.
struct LayerAcc {
    z: f64,
    moves: usize,
    len: f64,
    target: f64,
    achieved: f64,
    error: f64,
}

/// Edits `gcode` (named `name` in messages) by the density field `density` (p in the field's
/// frame, mm → ρ in 0–1, `None` outside the volume): the infill moves' E by equation 6, every
/// other byte kept (see the module documentation for the rules). `progress` gets the fraction
/// read, 0–1. Deterministic.
///
/// Errors: options out of range → [`Error::BadOption`]; over [`estimate`]'s budget →
/// [`Error::TooBig`] (before allocating); non-text bytes → [`Error::NotText`]; an unreadable
/// or out-of-range word → [`Error::Malformed`]; a line over [`MAX_LINE_BYTES`] →
/// [`Error::LineTooLong`]; an infill line with a checksum → [`Error::Checksum`]; no infill
/// move → [`Error::NoInfill`] with the feature names the file has.
pub fn edit(
    name: &str,
    gcode: &dyn ByteSource,
    density: &dyn Fn(DVec3) -> Option<f64>,
    options: &Options,
    progress: &mut dyn FnMut(f32),
) -> Result<Edited, Error> {
    validate(options)?;
    let total = gcode.len();
    let est = estimate(total, options);
    est.check().map_err(Error::TooBig)?;
    let o = options;
    let types = InfillTypes::new(&o.infill_types);
    let area_f = std::f64::consts::PI * o.filament_mm * o.filament_mm / 4.0;
    let translation = DVec3::from(o.translation_mm);

    let mut out: Vec<u8> = Vec::with_capacity(total + total / 16 + 4096);
    let max_out = MAX_STAGE_BYTES as usize;
    let mut scratch = Vec::with_capacity(32);
    let mut num = Vec::with_capacity(32);
    let mut m = Motion::default();
    let mut es = EState { modes: Modes { abs_xyz: true, mode: EMode::Follow, unit: 1.0 }, e: 0.0, e_line: None };
    let mut style = Style::default();
    let mut r = EditReport::default();
    let mut dialect = Dialect::Unknown;
    // Feature state: whether the current `;TYPE:` is infill (None before any marker).
    let mut type_infill: Option<bool> = None;
    let mut types_seen: Vec<Vec<u8>> = Vec::new();
    // Layer height: stated by a comment, or the last Z step between extruding moves.
    let mut lh_stated: Option<f64> = None;
    let mut lh_step: Option<f64> = None;
    let mut z_extruding: Option<f64> = None;
    // The printer's E differs from the input's (an edit printed another number), and the
    // E position the printer has after the last absolute edit.
    let mut drift = false;
    let mut e_out = 0.0;
    let (mut n_rel, mut n_abs) = (0usize, 0usize);
    let (mut net_before, mut hwm_before, mut net_after, mut hwm_after) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    let mut bounds = None;
    let mut layers: Vec<LayerAcc> = Vec::new();
    let mut next_progress = 0usize;
    const PROGRESS_STEP: usize = 4 << 20;

    let mut lines = 0;
    // Bytes of the pieces before the current one.
    let mut base = 0usize;
    pieces(name, gcode, &mut |gcode| {
        // Bytes of this piece before this offset are in `out`; the rest is copied when a line changes.
        let mut copied = 0usize;
        lines = for_each_line(name, gcode, lines, |line_no, offset, full, content, l| {
            if base + offset >= next_progress {
                progress((base + offset) as f32 / total.max(1) as f32);
                next_progress = base + offset + PROGRESS_STEP;
            }
            if let Some(c) = l.comment {
                if line_no <= dialect::HEADER_LINES && dialect == Dialect::Unknown {
                    dialect = dialect::detect(c).unwrap_or(Dialect::Unknown);
                }
                if let Some(t) = dialect::type_marker(c) {
                    type_infill = Some(types.matches(t));
                    note_type(&mut types_seen, t);
                } else if let Some(h) = dialect::layer_height(c) {
                    lh_stated = Some(h);
                }
            }
            let rel = es.modes.relative();
            let e_before = es.e;
            let e_word = l.words.get(b'E');
            let step = m.line(l.cmd, &l.words, false);
            let eol = &full[content.len()..];
            let mut edited: Option<f64> = None;
            if let (Step::Move(mv), Some(v)) = (&step, e_word) {
                if rel {
                    n_rel += 1;
                } else {
                    n_abs += 1;
                }
                let extruding = mv.de > 0.0 && mv.moves();
                if extruding {
                    grow(&mut bounds, &m, mv);
                    let z = mv.to[2];
                    match z_extruding {
                        Some(z0) if z > z0 + 1e-6 => lh_step = Some(z - z0),
                        None if z > 0.0 => lh_step = Some(z),
                        _ => {}
                    }
                    z_extruding = Some(z);
                }
                let (dx, dy) = (mv.to[0] - mv.from[0], mv.to[1] - mv.from[1]);
                let xy = dx * dx + dy * dy > MOTION_EPS * MOTION_EPS;
                let infill = mv.de > 0.0
                    && xy
                    && match type_infill {
                        Some(b) => b,
                        None => l.comment.is_some_and(|c| {
                            let d = dialect::line_description(c);
                            note_type(&mut types_seen, d);
                            types.matches(d)
                        }),
                    };
                // Where the E word is, and the file's number style (learnt from the first moves
                // and every infill move; other lines need no search).
                let found = if infill || n_rel + n_abs <= STYLE_MOVES { find_word(content, b'E') } else { Found { word: None, checksum: false } };
                let word = found.word;
                if let Some(w) = &word {
                    style.learn(w);
                }
                if infill {
                    r.infill_moves += 1;
                    let vol = mv.de * area_f;
                    r.infill_before_mm3 += vol;
                    let mid = (DVec3::from(mv.from) + DVec3::from(mv.to)) * 0.5 + translation;
                    let target = if mv.use_pts { None } else { density(mid).filter(|t| t.is_finite()) };
                    match (mv.use_pts, target, word) {
                        (true, _, _) => {
                            r.arcs_unchanged += 1;
                            r.infill_after_mm3 += vol;
                        }
                        (false, None, _) | (false, _, None) => {
                            r.outside_field += 1;
                            r.infill_after_mm3 += vol;
                        }
                        (false, Some(t), Some(w)) => {
                            if found.checksum {
                                return Err(Error::Checksum { file: name.to_string(), line: line_no });
                            }
                            let rho = if t < o.rho_min {
                                r.clamped_low += 1;
                                o.rho_min
                            } else if t > o.rho_max {
                                r.clamped_high += 1;
                                o.rho_max
                            } else {
                                t
                            };
                            let d_old = if rel { v } else { v - e_before };
                            let mut d_new = d_old * (rho / o.rho_s);
                            // Limits, in mm: bead area and its flow at this feed.
                            let lh = lh_stated.or(lh_step).unwrap_or(DEFAULT_LAYER_HEIGHT_MM);
                            let area = d_new * es.modes.unit * area_f / mv.len;
                            let over_flow = area * mv.v > o.q_max_mm3_s * (1.0 + 1e-9);
                            let over_width = width_of_area(area, lh) > o.width_max_mm * (1.0 + 1e-9);
                            r.over_flow += usize::from(over_flow);
                            r.over_width += usize::from(over_width);
                            if o.limit == Limit::Clamp && (over_flow || over_width) {
                                let area_max = max_bead_area(o.q_max_mm3_s, mv.v, o.width_max_mm, lh);
                                d_new = d_new.min(area_max * mv.len / area_f / es.modes.unit);
                            }
                            let e_prev_out = if drift && !rel { e_out } else { e_before };
                            let value = if rel { d_new } else { e_prev_out + d_new };
                            num.clear();
                            let printed = write_number(&mut num, &mut scratch, value, style);
                            if !(printed.abs() <= MAX_WORD_MAGNITUDE) {
                                return Err(Error::Malformed {
                                    file: name.to_string(),
                                    line: line_no,
                                    problem: format!(
                                        "the edited E would be {}, beyond the {MAX_WORD_MAGNITUDE:.0} a G-code number may have (check rho_s)",
                                        String::from_utf8_lossy(&num)
                                    ),
                                });
                            }
                            let d_printed = if rel { printed } else { printed - e_prev_out };
                            if rel {
                                drift |= printed != v;
                            } else {
                                drift = printed != v;
                                e_out = printed;
                            }
                            r.edited_moves += 1;
                            r.infill_after_mm3 += d_printed * es.modes.unit * area_f;
                            // Layer statistics on the printed numbers.
                            let achieved = if d_old > 0.0 { o.rho_s * d_printed / d_old } else { 0.0 };
                            let z = mv.to[2];
                            if layers.last().is_none_or(|a| (a.z - z).abs() > 1e-6) {
                                layers.push(LayerAcc { z, moves: 0, len: 0.0, target: 0.0, achieved: 0.0, error: 0.0 });
                            }
                            if let Some(a) = layers.last_mut() {
                                // The target along the whole move, as weft's own grading measures it.
                                let from = DVec3::from(mv.from) + translation;
                                let along =
                                    mean_along(from, DVec3::from(mv.to) + translation, o.target_step_mm, density).unwrap_or(t).clamp(o.rho_min, o.rho_max);
                                a.moves += 1;
                                a.len += mv.len;
                                a.target += mv.len * along;
                                a.achieved += mv.len * achieved;
                                a.error += mv.len * (achieved - along).abs();
                            }
                            if printed != v {
                                edited = Some(d_printed * es.modes.unit);
                                // Unchanged lines before this one go out as one slice.
                                out.extend_from_slice(&gcode[copied..offset]);
                                out.extend_from_slice(&content[..w.start]);
                                out.extend_from_slice(&num);
                                out.extend_from_slice(&content[w.end..]);
                                out.extend_from_slice(eol);
                                copied = offset + full.len();
                            } else {
                                edited = Some(mv.de);
                            }
                        }
                    }
                }
            }
            // Net E before and after (high-water marks, as the analyzer counts filament).
            if let Step::Move(mv) = &step {
                net_before += mv.de;
                hwm_before = hwm_before.max(net_before);
                net_after += edited.unwrap_or(mv.de);
                hwm_after = hwm_after.max(net_after);
            }
            if edited.is_none() {
                // A command line after edits: bring the printer's E back to the input's before a
                // line that reads it (an absolute-E line, or a switch to absolute E).
                if drift && l.cmd != Command::None {
                    let mut after = es.modes;
                    after.command(l.cmd);
                    if l.cmd == Command::G(92, 0) && l.words.get(b'E').is_some() {
                        drift = false;
                    } else if !rel || !after.relative() {
                        out.extend_from_slice(&gcode[copied..offset]);
                        copied = offset;
                        out.extend_from_slice(b"G92 E");
                        match es.e_line.as_deref().and_then(|line| find_word(line, b'E').word.map(|w| &line[w.start..w.end])) {
                            Some(t) => out.extend_from_slice(t),
                            None => {
                                write_number(&mut out, &mut scratch, es.e, style);
                            }
                        }
                        out.extend_from_slice(if eol.is_empty() { b"\n" } else { eol });
                        r.resets_inserted += 1;
                        drift = false;
                    }
                }
            }
            // The input's E state after this line.
            es.modes.command(l.cmd);
            if l.cmd == Command::G(92, 0) {
                if let Some(v) = l.words.get(b'E') {
                    es.e = v;
                    set_line(&mut es.e_line, content);
                }
            } else if let (Step::Move(_), Some(v)) = (&step, e_word) {
                if rel {
                    es.e += v;
                    es.e_line = None;
                } else {
                    es.e = v;
                    set_line(&mut es.e_line, content);
                }
            }
            let written = out.len() + offset.saturating_sub(copied);
            if written > max_out {
                return Err(Error::TooBig(OverBudget {
                    what: "the edited G-code".into(),
                    value: written as f64,
                    limit: max_out as f64,
                    unit: "bytes",
                    fix: "edit a smaller G-code file".into(),
                }));
            }
            Ok(())
        })?;
        out.extend_from_slice(&gcode[copied..]);
        base += gcode.len();
        Ok(())
    })?;
    if r.infill_moves == 0 {
        return Err(Error::NoInfill {
            file: name.to_string(),
            wanted: o.infill_types.iter().map(|t| format!("\"{t}\"")).collect::<Vec<_>>().join(", "),
            types_seen: types_seen.iter().map(|t| crate::import::clean(&String::from_utf8_lossy(t))).collect(),
        });
    }
    r.dialect = dialect.name().into();
    r.extrusion = match (n_rel > 0, n_abs > 0) {
        (true, true) => "mixed",
        (false, true) => "absolute",
        _ => "relative",
    }
    .into();
    r.lines = lines;
    r.filament_before_mm = hwm_before;
    r.filament_after_mm = hwm_after;
    r.layers = layers
        .into_iter()
        .map(|a| LayerStat {
            z_mm: a.z,
            moves: a.moves,
            length_mm: a.len,
            target_mean: a.target / a.len,
            achieved_mean: a.achieved / a.len,
            mean_abs_error: a.error / a.len,
        })
        .collect();
    if let Some((lo, hi)) = bounds {
        r.bounds_min = lo.to_array();
        r.bounds_max = hi.to_array();
    }
    progress(1.0);
    Ok(Edited { text: out, report: r })
}

/// Adds a feature name to the list of those seen (once, at most [`MAX_TYPES_SEEN`]).
fn note_type(seen: &mut Vec<Vec<u8>>, name: &[u8]) {
    if !name.is_empty() && seen.len() < MAX_TYPES_SEEN && !seen.iter().any(|s| s == name) {
        seen.push(name.to_vec());
    }
}

/// Keeps a copy of `line` in `slot`, reusing its allocation.
fn set_line(slot: &mut Option<Vec<u8>>, line: &[u8]) {
    let v = slot.get_or_insert_with(Vec::new);
    v.clear();
    v.extend_from_slice(line);
}

/// Longest piece read at once from a source not in memory: above [`MAX_LINE_BYTES`], so a
/// line split across pieces is one already refused as too long.
const PIECE_BYTES: usize = crate::source::CHUNK_BYTES;
const _: () = assert!(PIECE_BYTES > MAX_LINE_BYTES);

/// `f` over `gcode` in pieces ending at line ends (one piece when it is in memory).
fn pieces(name: &str, gcode: &dyn ByteSource, f: &mut dyn FnMut(&[u8]) -> Result<(), Error>) -> Result<(), Error> {
    for_each_line_chunk(gcode, PIECE_BYTES, f).map_err(|e| match e {
        ChunkError::Read(message) => Error::Read { file: name.to_string(), message },
        ChunkError::Stopped(e) => e,
    })
}

//! G-code analyzer: reads any Marlin-style G-code (weft's or another slicer's) and measures it,
//! reproducing the GIPPO paper's trajectory analysis of control G-code.
//!
//! Entry: [`analyze`]. Also builds the preview buffers the page draws.

use serde::Serialize;

mod estimate;
mod machine;
mod overlap;
#[cfg(any(not(target_arch = "wasm32"), feature = "wasm-threads"))]
mod pooled;
mod poses;
/// The G-code lexer (shared with the writer; lives in [`crate::motion::lex`]).
pub use crate::motion::lex as parse;
/// The time model (shared with the writer; lives in [`crate::motion::time`]).
pub use crate::motion::time;

pub use crate::motion::lex::{MAX_WORD_MAGNITUDE, MIN_RATE};
pub use crate::motion::{ARC_TOLERANCE_MM, DEFAULT_ACCELERATION_MM_S2, DEFAULT_FEED_MM_MIN, MAX_ARC_CHORDS};
pub use estimate::{peak_bytes, Estimate};
pub use machine::gippo_score;
pub use overlap::{MAX_SPAN_MM, MAX_WALK};

/// Most memory one analysis may need, bytes ([`Estimate::peak_bytes`]: preview buffers, the
/// largest layer's working set, per-layer records; the G-code text itself is the caller's).
/// The browser worker has about 2 GB of wasm memory for a whole run, and the G-code text, the
/// toolpath it was written from and the preview's copies handed to the page need the other
/// half. Measured peaks (native, `VmHWM`): a slicer-style print of 1M moves (39 MB) takes
/// 1.1 bytes per G-code byte with the preview and 0.04 without; the densest input (one layer
/// of 1M five-byte moves `X1E1`) 35 bytes per byte with the preview. The estimate bounds these
/// from above (2.8 bytes per byte for the print, with the preview), so this admits about
/// 9 million moves of a print with the preview (a 350 MB file) and any file with sane layers
/// without it.
pub const MAX_PEAK_BYTES: usize = 1_000_000_000;

/// Largest G-code file analysed, bytes (1 GiB). The text is held whole while it is read, and
/// in the browser it shares the worker's wasm memory with the analysis ([`MAX_PEAK_BYTES`]).
/// A slicer's print of a desktop-sized part is well under 100 MB; 1 GiB is about 30 million
/// moves. Checked from the size alone ([`check_size`]) before a file is read.
pub const MAX_FILE_BYTES: u64 = 1 << 30;

/// Most extrusion segments (moves, arcs by their chords) in one layer: the overlap measure
/// holds a layer at once, at up to about 360 bytes a segment (so at most about 380 MB). A
/// solid 300 × 300 mm layer of 0.45 mm lines is 200 m of extrusion: a million segments of
/// 0.2 mm, the densest layer a real print has.
pub const MAX_LAYER_SEGMENTS: usize = 1 << 20;

/// Default line width assumed when a file has no `;WIDTH:` comments, mm.
pub const DEFAULT_LINE_WIDTH_MM: f64 = 0.4;
/// Default filament diameter assumed when a file does not state one, mm.
pub const DEFAULT_FILAMENT_DIAMETER_MM: f64 = 1.75;

/// Analyzer options.
#[derive(Clone, Debug, PartialEq)]
pub struct Options {
    /// Build the preview buffers (costs memory: 40 bytes per extrusion segment, 12 more with
    /// tool axes; 28 per travel segment). Default false.
    pub collect_preview: bool,
    /// Line width when the file states none (`;WIDTH:`), mm. Default 0.4.
    pub default_line_width_mm: f64,
    /// Filament diameter when the file states none, mm. Default 1.75.
    pub filament_diameter_mm: f64,
    /// The machine the file is for. Default cartesian: `A B C` words are read and counted
    /// ([`Report::rotary_moves`]) but give no tool axis. A 5-axis machine turns them into the
    /// tool axis ([`Preview::axis`]) and the preview's positions into nozzle tips in the
    /// part's frame, through its forward kinematics ([`crate::machine`]). `I J K` vectors on
    /// `G0`/`G1` give the tool axis on any machine.
    pub machine: crate::machine::Machine,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            collect_preview: false,
            default_line_width_mm: DEFAULT_LINE_WIDTH_MM,
            filament_diameter_mm: DEFAULT_FILAMENT_DIAMETER_MM,
            machine: crate::machine::Machine::default(),
        }
    }
}

/// Numbers for one layer.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct LayerReport {
    /// Layer Z, mm.
    pub z: f64,
    /// Maximal runs of extruding moves.
    pub extrusion_paths: usize,
    /// Extruded path length, mm.
    pub extruded_mm: f64,
    /// Travel length, mm.
    pub travel_mm: f64,
    /// Retractions.
    pub retractions: usize,
    /// Extruded length lying on earlier extrusions of this layer, mm.
    pub overlap_mm: f64,
    /// GIPPO equation 1 over this layer's extrusion paths.
    pub gippo_score: f64,
}

/// The analyzer's report (`weft analyze --json`).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Report {
    /// Layers with extrusion.
    pub layers: usize,
    /// Maximal runs of extruding moves.
    pub extrusion_paths: usize,
    /// Extruded path length (XYZ distance while extruding), mm.
    pub extruded_mm: f64,
    /// Non-extruding move length, mm.
    pub travel_mm: f64,
    /// Retractions (E moving back, or G10).
    pub retractions: usize,
    /// Extruded length lying on already-extruded segments of the same layer, mm: the parts
    /// of each extruding segment that are nearly parallel (≤ 10°) to an earlier segment of
    /// its layer, within half a line width of it laterally and alongside it (segments that
    /// only touch or cross add nothing; a strut printed twice adds its length once).
    pub overlap_mm: f64,
    /// GIPPO equation 1 over all extrusion paths, averaged over layers weighted by nothing (mean of layers).
    pub gippo_score: f64,
    /// Estimated print time, s.
    pub estimated_time_s: f64,
    /// Filament fed (net E), mm.
    pub filament_mm: f64,
    /// Per layer.
    pub per_layer: Vec<LayerReport>,
    /// Moves with an `A`, `B` or `C` word.
    pub rotary_moves: usize,
    /// `G0`/`G1` moves with an `I`, `J` or `K` tool-vector word.
    pub ijk_moves: usize,
    /// Objects the file labels (Klipper's `EXCLUDE_OBJECT_DEFINE`/`_START`/`_END`, or
    /// `M486 T`/`S`/`A`), in the order they are declared or first started, with the extrusion
    /// printed inside each; empty when the file labels none.
    pub objects: Vec<ObjectReport>,
    /// Extruded length printed outside any object in a file that labels objects, mm (0 in a
    /// file that labels none).
    pub unlabelled_mm: f64,
}

/// One labelled object ([`Report::objects`]).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct ObjectReport {
    /// Its name (`NAME=`, `A"…"`; the index for an `M486` object without one).
    pub name: String,
    /// Extruded length printed while it was the current object, mm.
    pub extruded_mm: f64,
}

/// Buffers for the 3D preview, in printer coordinates (mm). Segments are in file order,
/// so each layer's segments are contiguous.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Preview {
    /// Extrusion segments: x0 y0 z0 x1 y1 z1 each.
    pub positions: Vec<f32>,
    /// Per extrusion segment: feature code ([`crate::geom::Feature::code`]), 255 = unknown.
    pub feature: Vec<u8>,
    /// Per extrusion segment: index of its extrusion path.
    pub path: Vec<u32>,
    /// Per extrusion segment: volumetric flow, mm³/s.
    pub flow: Vec<f32>,
    /// Per extrusion segment: filament fed per mm of the segment, mm/mm (ΔE / length).
    pub e_per_mm: Vec<f32>,
    /// Per extrusion segment: feed rate, mm/s.
    pub speed: Vec<f32>,
    /// Per extrusion segment: width, mm.
    pub width: Vec<f32>,
    /// First extrusion segment of each layer; one more entry than layers (the end).
    pub layer_segment_start: Vec<u32>,
    /// Travel segments: x0 y0 z0 x1 y1 z1 each.
    pub travel_positions: Vec<f32>,
    /// First travel segment of each layer; one more entry than layers.
    pub layer_travel_start: Vec<u32>,
    /// Z of each layer, mm.
    pub layer_z: Vec<f32>,
    /// Per extrusion segment: the tool axis at its end (unit x y z, 3 floats). Empty when the
    /// file never states an axis (no `I J K`, and no rotary words for a 5-axis machine);
    /// otherwise segments before the first stated axis get +Z.
    pub axis: Vec<f32>,
    /// Per extrusion segment: index of the G-code move (`G0`–`G3` command, 0-based, in file
    /// order) it comes from; non-decreasing (an arc gives several segments). With
    /// [`Preview::travel_move`] a print-order slider shows "everything up to move k".
    pub segment_move: Vec<u32>,
    /// Per travel segment: index of the G-code move it comes from.
    pub travel_move: Vec<u32>,
}

/// Report plus (optionally) preview.
#[derive(Clone, Debug, Default)]
pub struct Analysis {
    /// The numbers.
    pub report: Report,
    /// Preview buffers when [`Options::collect_preview`].
    pub preview: Option<Preview>,
}

/// Why a file could not be analysed.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum Error {
    /// Binary data, not G-code.
    #[error("{file}: byte {offset} is not text; this is not a G-code file (export G-code as plain text)")]
    NotText {
        /// File name.
        file: String,
        /// Byte offset of the first binary byte.
        offset: usize,
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
    /// The analysis would need more memory than [`MAX_PEAK_BYTES`], or a layer has more than
    /// [`MAX_LAYER_SEGMENTS`] segments.
    #[error("{file}: {}{problem}", at_line(*.line))]
    TooLarge {
        /// File name.
        file: String,
        /// 1-based line where the limit was reached; 0 when refused before reading.
        line: usize,
        /// The number, the limit and the fix.
        problem: String,
    },
}

fn at_line(line: usize) -> String {
    if line == 0 {
        String::new()
    } else {
        format!("line {line}: ")
    }
}

/// Bytes as "1.3 GB" / "12.0 MB".
pub(crate) fn human_bytes(n: usize) -> String {
    let n = n as f64;
    if n >= 1e9 {
        format!("{:.1} GB", n / 1e9)
    } else {
        format!("{:.1} MB", n / 1e6)
    }
}

/// Counts as "12.8M" / "3,200".
pub(crate) fn human_count(n: usize) -> String {
    if n >= 1_000_000 {
        format!("{:.1}M", n as f64 / 1e6)
    } else {
        n.to_string()
    }
}

/// Scans `bytes` for what [`analyze`] would need, without reading any number: lines, moves,
/// arcs and layers (upper bounds) and the peak memory ([`Estimate::peak_bytes`], compared
/// with [`MAX_PEAK_BYTES`]). Linear in the size of the file, allocates nothing.
pub fn estimate(bytes: &[u8], options: &Options) -> Estimate {
    estimate::scan(bytes, options)
}

/// The refusal of an analysis needing `need` bytes for `segments` segments in `layers` layers.
pub(crate) fn too_large(need: usize, segments: usize, layers: usize, preview: bool) -> String {
    format!(
        "the analysis needs about {} ({} segments, {} layers{}), limit {}: split the file at a layer change and analyse the parts{}",
        human_bytes(need),
        human_count(segments),
        human_count(layers),
        if preview { ", with the preview" } else { "" },
        human_bytes(MAX_PEAK_BYTES),
        // The page always draws; its users may not know weft has a command-line tool.
        if preview { ", or analyse it without the preview with weft's command-line tool (`weft analyze`, which draws none)" } else { "" }
    )
}

/// Refuses a G-code file of `len` bytes over [`MAX_FILE_BYTES`] from its size alone, so a
/// caller can check before reading it ([`analyze`] checks too).
pub fn check_size(file: &str, len: u64) -> Result<(), Error> {
    if len <= MAX_FILE_BYTES {
        return Ok(());
    }
    Err(Error::TooLarge {
        file: file.to_string(),
        line: 0,
        problem: format!(
            "the file is {} MiB, more than the {} MiB weft analyses: split it at a layer change and analyse the parts",
            crate::import::group(len.div_ceil(1 << 20)),
            crate::import::group(MAX_FILE_BYTES >> 20)
        ),
    })
}

/// Analyses G-code `bytes`; `file` names it in messages.
///
/// Reads Marlin-style G-code: `G0`/`G1`, `G2`/`G3` arcs (`I J` or `R`, XY plane, helical
/// Z), `G4` dwell, `G10`/`G11` firmware retraction (`G10` with `P` or `L` is a tool or
/// offset setting, not a retraction), `G20`/`G21` units, `G28` homing (named axes or all to
/// 0), `G90`/`G91` (which, as in Marlin, also reset the E mode), `M82`/`M83`, `G92`, `M204`
/// (`S` both, `P` print, `T` travel acceleration); comments after `;` and in parentheses,
/// `N` line numbers, `*` checksums, lowercase, CRLF; lines of parameters with no command
/// repeat the last motion command. Other commands are ignored (with their arguments).
/// Numbers are plain decimals: G-code has no exponents, and since a printer reads `X1e10` as
/// `X1` and an E word `e10`, such a word is refused rather than read either way (an uppercase
/// `E` right after a number is the compact form: `G1X40E4` is `X40 E4`). A letter given twice
/// on a line, a number larger than [`MAX_WORD_MAGNITUDE`] (10 km) and a feed rate or
/// acceleration below [`MIN_RATE`] are refused too, so every total stays finite.
///
/// Definitions:
/// - an *extruding move* is a `G0`–`G3` with XYZ motion and a positive E delta; other moves
///   with motion are *travels*;
/// - a *retraction* is the start of a retracted state: E moving back (with or without motion,
///   so a wipe followed by a retract counts once) or `G10`; extrusion or a positive E-only
///   move ends it;
/// - an *extrusion path* is a maximal run of extruding moves, broken by a travel, a
///   retraction or a layer change; `NumEdges` counts its moves (an arc is one edge);
/// - *layers*: when the file has `;LAYER:` or `;LAYER_CHANGE` comments, such a comment starts
///   a new layer at the next extruding move (several comments in a row make one change;
///   extrusion before the first comment, such as a purge line, belongs to the first layer);
///   otherwise an extruding move whose end Z differs from the layer's Z starts one. A layer's
///   Z is the end Z of its first extruding move. Travels and retractions between the last
///   extrusion of a layer and the first of the next belong to the next;
/// - `gippo_score` is GIPPO equation 1 per layer, and the report's is the mean over layers;
/// - `filament_mm` is the high-water mark of the net E fed (sum of all E deltas, ignoring
///   `G92` resets): filament retracted and fed again is not counted twice, and a final
///   retraction does not reduce it;
/// - `overlap_mm`: see the overlap rule in [`Report::overlap_mm`] (nearly parallel, within
///   half a line width, unioned per segment; arcs are measured on their preview chords:
///   within [`ARC_TOLERANCE_MM`] of the arc, at most [`MAX_ARC_CHORDS`] per arc);
/// - time: see [`time`].
///
/// A poses CSV (header `x,y,z,nx,ny,nz`, the `poses_csv` flavour) is read as one layer of
/// paths separated by blank lines, with the rows' axes in the preview (no time, no filament).
///
/// Cost: linear in the size of the file (the overlap search included, see [`MAX_WALK`]).
/// Memory: [`estimate`] is checked against [`MAX_PEAK_BYTES`] before reading, and again as
/// arcs expand and layers grow.
///
/// Errors: any NUL or other non-text control byte → [`Error::NotText`]; a parameter of an
/// interpreted command whose number cannot be read or is refused (above) →
/// [`Error::Malformed`] with its line; a file over [`MAX_FILE_BYTES`] or needing more than
/// [`MAX_PEAK_BYTES`], or a layer of more than [`MAX_LAYER_SEGMENTS`] segments →
/// [`Error::TooLarge`].
pub fn analyze(file: &str, bytes: &[u8], options: &Options) -> Result<Analysis, Error> {
    check_size(file, bytes.len() as u64)?;
    let est = estimate(bytes, options);
    if est.peak_bytes > MAX_PEAK_BYTES {
        return Err(Error::TooLarge { file: file.to_string(), line: 0, problem: too_large(est.peak_bytes, est.moves, est.layers, options.collect_preview) });
    }
    if poses::is_poses(bytes) {
        return poses::run(file, bytes, options);
    }
    machine::run(file, bytes, options, &est)
}

/// Analyzer time per segment on the reference machine, s, one thread (`cargo run --release
/// --example slice_bench`: 0.26 µs on the 1M-triangle sphere, 1.5 µs on solid cubes, whose
/// dense infill lines the overlap search meets; hostile overlapping layers cost up to 10 µs).
const SECONDS_PER_SEGMENT: f64 = 1.0e-6;

/// The analyzer's work on the G-code a run will write, before it is written (the run's plan):
/// `segments` moves over `layers` layers, from the upstream stages' estimates. Memory by
/// [`peak_bytes`] (a layer taken as twice the mean), refused over [`MAX_PEAK_BYTES`] as the
/// analysis itself would be.
pub fn plan(segments: f64, layers: f64, options: &Options) -> crate::budget::Estimate {
    let layers = layers.max(1.0);
    let largest = (2.0 * segments / layers).min(segments).min(MAX_LAYER_SEGMENTS as f64);
    let text = (segments * crate::gcode::GCODE_BYTES_PER_SEGMENT).min(usize::MAX as f64 / 4.0) as usize;
    let bytes = peak_bytes(text, segments.min(usize::MAX as f64 / 4.0) as usize, layers as usize, largest as usize, options.collect_preview) as f64;
    let fix = "print fewer or thicker layers, less infill, or a smaller part";
    crate::budget::Estimate::new("analyze")
        .quantity("segments", "Moves read back", segments, "")
        .cost(bytes, segments * SECONDS_PER_SEGMENT)
        // Lexing ahead and overlap behind the interpreter, on the pool (analyze/pooled.rs):
        // 1.85× natively at 2 threads. The interpreter itself (about a quarter of one
        // thread's time) bounds it near 3–4× however many threads.
        .parallel(0.85)
        .limit("the analysis' memory", bytes, MAX_PEAK_BYTES as f64, "bytes", fix)
        .budgets(fix)
}

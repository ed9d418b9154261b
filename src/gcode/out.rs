//! The emitter: the text being written and the machine state the writer tracks. The layer
//! loop (`writer.rs`) and the dialects (`flavor.rs`) both write through [`Out`]; it depends on
//! neither.
//!
//! Every motion line is also described to a [`Motion`] with its numbers exactly as printed
//! ([`super::format::as_printed`]), so the writer times its own output with the analyzer's
//! model. Lines are built straight into [`Out::text`], with no buffer per line.

use super::format::{printed_units, push_fixed_read, push_u64};
use crate::geom::DVec3;
use crate::motion::lex::{Command, Words};
use crate::motion::Motion;

/// Extra axis words a 5-axis machine adds to motion lines.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct AxisWords {
    /// Letters (`A B`, `B C` or `I J K`); unused slots are 0.
    pub letters: [u8; 3],
    /// Decimals printed.
    pub decimals: usize,
    /// All letters are written when any changes (`I J K`: a vector); otherwise each letter
    /// only when it changes (rotary axes are modal).
    pub all_or_none: bool,
}

/// The text being written and the machine state the writer tracks.
pub(crate) struct Out {
    /// G-code body.
    pub text: String,
    /// Current nozzle position in machine coordinates (exact, before rounding); `None` before
    /// the first move.
    pub pos: Option<DVec3>,
    /// Last Z written, in µm (rounded as printed).
    pub z_written: Option<i64>,
    /// Modal feed rate last written, mm/min.
    pub feed: Option<u64>,
    /// Exact running sum of extruded E (the absolute E position when not retracted).
    pub e_total: f64,
    /// M83 mode.
    pub relative_e: bool,
    /// Filament currently pulled back.
    pub retracted: bool,
    /// Retractions written.
    pub retractions: usize,
    /// The moves as a reader sees them: time and travel.
    pub motion: Motion,
    /// False once a line was fed that the analyzer would reject (user codes with binary bytes
    /// or unreadable numbers): the analyzer reports nothing for such a file, nor does the
    /// header.
    pub motion_ok: bool,
    /// 5-axis words, when the machine has them.
    pub axes: Option<AxisWords>,
    /// Axis values the next motion line should reach.
    pub axis_target: [f64; 3],
    /// Axis values last written, scaled to integers as printed.
    axis_written: [Option<i64>; 3],
}

impl Out {
    /// An empty body.
    pub fn new(relative_e: bool, axes: Option<AxisWords>) -> Out {
        Out {
            text: String::with_capacity(1 << 16),
            pos: None,
            z_written: None,
            feed: None,
            e_total: 0.0,
            relative_e,
            retracted: false,
            retractions: 0,
            motion: Motion::default(),
            motion_ok: true,
            axes,
            axis_target: [0.0; 3],
            axis_written: [None; 3],
        }
    }

    /// Appends one line that moves nothing (comments, temperatures, fan).
    pub fn line(&mut self, s: &str) {
        self.text.push_str(s);
        self.text.push('\n');
    }

    /// Appends user or fixed G-code text (one or more lines, no trailing newline needed) and
    /// reads it as the analyzer would.
    pub fn code(&mut self, s: &str) {
        self.line(s);
        if !self.motion.text(s) {
            self.motion_ok = false;
        }
    }

    /// Starts a motion line `G<g>` (0 or 1; written straight into [`Out::text`]).
    fn begin(&mut self, g: u32) -> (Command, Words) {
        self.text.push_str(if g == 0 { "G0" } else { "G1" });
        (Command::G(g, 0), Words::default())
    }

    /// Ends the motion line begun with [`Out::begin`] and feeds its words to the time model.
    fn end(&mut self, cmd: Command, words: &Words) {
        self.text.push('\n');
        self.motion.line(cmd, words, false);
    }

    /// Appends ` <letter><v>` and records the value as printed.
    fn word(&mut self, words: &mut Words, letter: u8, v: f64, decimals: usize) {
        self.text.push(' ');
        self.text.push(letter as char);
        words.set(letter, push_fixed_read(&mut self.text, v, decimals));
    }

    /// Appends ` F<feed>` when it differs from the modal feed rate.
    fn push_feed(&mut self, words: &mut Words, feed: u64) {
        if self.feed != Some(feed) {
            self.text.push_str(" F");
            push_u64(&mut self.text, feed);
            words.set(b'F', feed as f64);
            self.feed = Some(feed);
        }
    }

    /// Appends ` Z<z>` when the printed Z would change.
    fn push_z_if_changed(&mut self, words: &mut Words, z: f64) {
        let zi = printed_units(z, 3);
        if self.z_written != Some(zi) {
            self.word(words, b'Z', z, 3);
            self.z_written = Some(zi);
        }
    }

    /// The axis target as it would be printed (integers), `None` for unused letters.
    fn axis_scaled(&self, ax: AxisWords) -> [Option<i64>; 3] {
        std::array::from_fn(|k| (ax.letters[k] != 0).then(|| printed_units(self.axis_target[k], ax.decimals)))
    }

    /// Appends the 5-axis words that differ from those last written.
    fn push_axes(&mut self, words: &mut Words) {
        let Some(ax) = self.axes else { return };
        let scaled = self.axis_scaled(ax);
        let changed: [bool; 3] = std::array::from_fn(|k| scaled[k].is_some() && scaled[k] != self.axis_written[k]);
        let any = changed.iter().any(|c| *c);
        for k in 0..3 {
            if ax.letters[k] != 0 && (changed[k] || (ax.all_or_none && any)) {
                self.word(words, ax.letters[k], self.axis_target[k], ax.decimals);
                self.axis_written[k] = scaled[k];
            }
        }
    }

    /// `G0 <axes>` when the axis target has not been written yet (a reorientation without
    /// XYZ motion).
    pub fn flush_axes(&mut self) {
        let Some(ax) = self.axes else { return };
        if self.axis_scaled(ax).iter().zip(&self.axis_written).all(|(s, w)| s.is_none() || s == w) {
            return;
        }
        let (cmd, mut words) = self.begin(0);
        self.push_axes(&mut words);
        self.end(cmd, &words);
    }

    /// `G1 Z<z> F<feed>` when the printed Z changes.
    pub fn move_z(&mut self, z: f64, feed: u64) {
        self.move_z_with(1, z, feed);
    }

    /// `G<g> Z<z> F<feed>` (`g` is 0 or 1) when the printed Z changes.
    pub fn move_z_with(&mut self, g: u32, z: f64, feed: u64) {
        if self.z_written == Some(printed_units(z, 3)) {
            return;
        }
        let (cmd, mut words) = self.begin(g);
        self.push_z_if_changed(&mut words, z);
        self.push_feed(&mut words, feed);
        self.end(cmd, &words);
        if let Some(p) = &mut self.pos {
            p.z = z;
        }
    }

    /// `G0 X<x> Y<y> [axes] F<feed>`.
    pub fn move_xy(&mut self, to: DVec3, feed: u64) {
        let (cmd, mut words) = self.begin(0);
        self.word(&mut words, b'X', to.x, 3);
        self.word(&mut words, b'Y', to.y, 3);
        self.push_axes(&mut words);
        self.push_feed(&mut words, feed);
        self.end(cmd, &words);
        self.pos = Some(to);
    }

    /// `G1 X<x> Y<y> [Z<z>] [axes] [F<feed>]` without E.
    pub fn dry_move(&mut self, to: DVec3, feed: u64) {
        self.g1(to, None, feed);
    }

    /// `G1 X<x> Y<y> [Z<z>] [axes] E<e> [F<feed>]`, feeding `e` mm (E printed absolute or
    /// relative as the mode says).
    pub fn extrude_move(&mut self, to: DVec3, e: f64, feed: u64) {
        self.g1(to, Some(e), feed);
    }

    /// A `G1` to `to`, feeding `e` mm when given.
    fn g1(&mut self, to: DVec3, e: Option<f64>, feed: u64) {
        let (cmd, mut words) = self.begin(1);
        self.word(&mut words, b'X', to.x, 3);
        self.word(&mut words, b'Y', to.y, 3);
        self.push_z_if_changed(&mut words, to.z);
        self.push_axes(&mut words);
        if let Some(e) = e {
            self.e_total += e;
            let e_word = if self.relative_e { e } else { self.e_total };
            self.word(&mut words, b'E', e_word, 5);
        }
        self.push_feed(&mut words, feed);
        self.end(cmd, &words);
        self.pos = Some(to);
    }

    /// `G2` (clockwise) or `G3 X<x> Y<y> I<i> J<j> E<e> [F<feed>]` in the XY plane, feeding
    /// `e` mm; `ij` is the centre relative to the start (4 decimals). Z is not written: the
    /// arc stays at the current height.
    pub fn extrude_arc(&mut self, to: DVec3, ij: [f64; 2], clockwise: bool, e: f64, feed: u64) {
        let g = if clockwise { 2 } else { 3 };
        self.text.push_str(if clockwise { "G2" } else { "G3" });
        let mut words = Words::default();
        self.word(&mut words, b'X', to.x, 3);
        self.word(&mut words, b'Y', to.y, 3);
        self.word(&mut words, b'I', ij[0], 4);
        self.word(&mut words, b'J', ij[1], 4);
        self.e_total += e;
        let e_word = if self.relative_e { e } else { self.e_total };
        self.word(&mut words, b'E', e_word, 5);
        self.push_feed(&mut words, feed);
        self.end(Command::G(g, 0), &words);
        self.pos = Some(to);
    }

    /// `G1 E<e> [F<feed>]` without motion; `e` is the word's value.
    pub fn e_only(&mut self, e: f64, feed: u64) {
        let (cmd, mut words) = self.begin(1);
        self.word(&mut words, b'E', e, 5);
        self.push_feed(&mut words, feed);
        self.end(cmd, &words);
    }

    /// `G4 P<ms>[ ; comment]` when `seconds` rounds to at least 1 ms.
    pub fn dwell(&mut self, seconds: f64, comment: &str) {
        let ms = (seconds * 1000.0).round();
        if !(ms.is_finite() && ms >= 1.0) {
            return;
        }
        self.text.push_str("G4");
        let mut words = Words::default();
        self.word(&mut words, b'P', ms, 0);
        if !comment.is_empty() {
            self.text.push_str(" ; ");
            self.text.push_str(comment);
        }
        self.end(Command::G(4, 0), &words);
    }
}

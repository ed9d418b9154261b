//! The emitter: the text being written and the machine state the writer tracks. The layer
//! loop (`writer.rs`) and the dialects (`flavor.rs`) both write through [`Out`]; it depends on
//! neither.
//!
//! Every motion line is also described to a [`Motion`] with its numbers exactly as printed
//! ([`as_printed`]), so the writer times its own output with the analyzer's model.

use super::format::{as_printed, push_fixed, push_u64};
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

    /// Appends a motion line the writer built and feeds its words to the time model.
    fn moved(&mut self, line: &str, cmd: Command, words: &Words) {
        self.line(line);
        self.motion.line(cmd, words, false);
    }

    /// Appends ` <letter><v>` and records the value as printed.
    pub fn word(line: &mut String, words: &mut Words, letter: u8, v: f64, decimals: usize) {
        line.push(' ');
        line.push(letter as char);
        push_fixed(line, v, decimals);
        words.set(letter, as_printed(v, decimals));
    }

    /// Appends ` F<feed>` when it differs from the modal feed rate.
    pub fn push_feed(&mut self, line: &mut String, words: &mut Words, feed: u64) {
        if self.feed != Some(feed) {
            line.push_str(" F");
            push_u64(line, feed);
            words.set(b'F', feed as f64);
            self.feed = Some(feed);
        }
    }

    /// Appends ` Z<z>` when the printed Z would change.
    pub fn push_z_if_changed(&mut self, line: &mut String, words: &mut Words, z: f64) {
        let zi = (z * 1000.0).round() as i64;
        if self.z_written != Some(zi) {
            Self::word(line, words, b'Z', z, 3);
            self.z_written = Some(zi);
        }
    }

    /// Appends the 5-axis words that differ from those last written.
    fn push_axes(&mut self, line: &mut String, words: &mut Words) {
        let Some(ax) = self.axes else { return };
        let scale = [1.0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9][ax.decimals.min(9)];
        let scaled: [Option<i64>; 3] =
            std::array::from_fn(|k| if ax.letters[k] == 0 { None } else { Some((self.axis_target[k] * scale).round() as i64) });
        let changed: [bool; 3] = std::array::from_fn(|k| scaled[k].is_some() && scaled[k] != self.axis_written[k]);
        let any = changed.iter().any(|c| *c);
        for k in 0..3 {
            if ax.letters[k] != 0 && (changed[k] || (ax.all_or_none && any)) {
                Self::word(line, words, ax.letters[k], self.axis_target[k], ax.decimals);
                self.axis_written[k] = scaled[k];
            }
        }
    }

    /// Whether the axis target differs from what was last written.
    fn axes_pending(&self) -> bool {
        let Some(ax) = self.axes else { return false };
        let scale = [1.0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9][ax.decimals.min(9)];
        (0..3).any(|k| ax.letters[k] != 0 && Some((self.axis_target[k] * scale).round() as i64) != self.axis_written[k])
    }

    /// `G0 <axes>` when the axis target has not been written yet (a reorientation without
    /// XYZ motion).
    pub fn flush_axes(&mut self) {
        if !self.axes_pending() {
            return;
        }
        let mut line = String::from("G0");
        let mut words = Words::default();
        self.push_axes(&mut line, &mut words);
        self.moved(&line, Command::G(0, 0), &words);
    }

    /// `G1 Z<z> F<feed>` when the printed Z changes.
    pub fn move_z(&mut self, z: f64, feed: u64) {
        self.move_z_with("G1", z, feed);
    }

    /// `<code> Z<z> F<feed>` (`code` is `G0` or `G1`) when the printed Z changes.
    pub fn move_z_with(&mut self, code: &str, z: f64, feed: u64) {
        let zi = (z * 1000.0).round() as i64;
        if self.z_written == Some(zi) {
            return;
        }
        let mut line = String::from(code);
        let mut words = Words::default();
        self.push_z_if_changed(&mut line, &mut words, z);
        self.push_feed(&mut line, &mut words, feed);
        let cmd = if code == "G0" { Command::G(0, 0) } else { Command::G(1, 0) };
        self.moved(&line, cmd, &words);
        if let Some(p) = &mut self.pos {
            p.z = z;
        }
    }

    /// `G0 X<x> Y<y> [axes] F<feed>`.
    pub fn move_xy(&mut self, to: DVec3, feed: u64) {
        let mut line = String::from("G0");
        let mut words = Words::default();
        Self::word(&mut line, &mut words, b'X', to.x, 3);
        Self::word(&mut line, &mut words, b'Y', to.y, 3);
        self.push_axes(&mut line, &mut words);
        self.push_feed(&mut line, &mut words, feed);
        self.moved(&line, Command::G(0, 0), &words);
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
        let mut line = String::with_capacity(48);
        line.push_str("G1");
        let mut words = Words::default();
        Self::word(&mut line, &mut words, b'X', to.x, 3);
        Self::word(&mut line, &mut words, b'Y', to.y, 3);
        self.push_z_if_changed(&mut line, &mut words, to.z);
        self.push_axes(&mut line, &mut words);
        if let Some(e) = e {
            self.e_total += e;
            let e_word = if self.relative_e { e } else { self.e_total };
            Self::word(&mut line, &mut words, b'E', e_word, 5);
        }
        self.push_feed(&mut line, &mut words, feed);
        self.moved(&line, Command::G(1, 0), &words);
        self.pos = Some(to);
    }

    /// `G1 E<e> [F<feed>]` without motion; `e` is the word's value.
    pub fn e_only(&mut self, e: f64, feed: u64) {
        let mut line = String::from("G1");
        let mut words = Words::default();
        Self::word(&mut line, &mut words, b'E', e, 5);
        self.push_feed(&mut line, &mut words, feed);
        self.moved(&line, Command::G(1, 0), &words);
    }

    /// `G4 P<ms>[ ; comment]` when `seconds` rounds to at least 1 ms.
    pub fn dwell(&mut self, seconds: f64, comment: &str) {
        let ms = (seconds * 1000.0).round();
        if !(ms.is_finite() && ms >= 1.0) {
            return;
        }
        let mut line = String::from("G4");
        let mut words = Words::default();
        Self::word(&mut line, &mut words, b'P', ms, 0);
        if !comment.is_empty() {
            line.push_str(" ; ");
            line.push_str(comment);
        }
        self.moved(&line, Command::G(4, 0), &words);
    }
}

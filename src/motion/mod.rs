//! What a G-code file makes the machine do, shared by the analyzer and the writer: the line
//! lexer ([`lex`]), the time model ([`time`]) and the modal motion state ([`Motion`]:
//! positions, E, units, modes, feed, acceleration, rotary axes, the running time and travel).
//!
//! The writer feeds [`Motion`] the moves it prints (with the numbers exactly as printed) and
//! its start/end templates through [`lex`]; the analyzer feeds it every line of a file. Both
//! therefore measure time and travel with one piece of code, so the header the writer puts in
//! a file and `weft analyze` agree to the bit without the writer running the analyzer.

pub mod lex;
pub mod time;

use lex::{Command, Words};
use time::MotionTimer;

/// Moves shorter than this (mm) have no XYZ motion.
pub const MOTION_EPS: f64 = 1e-9;
/// Largest distance between an arc and the chords that stand for it in the preview and the
/// overlap measure, mm (a fortieth of a typical line width: invisible, and it does not move
/// the overlap figure).
pub const ARC_TOLERANCE_MM: f64 = 0.01;
/// Chords per arc at most (an arc turns at most once). Bounds the work per `G2`/`G3` line
/// whatever its radius; arcs larger than about 200 mm in radius reach it and deviate a little
/// more than [`ARC_TOLERANCE_MM`] (0.03 mm for a 100 mm full circle).
pub const MAX_ARC_CHORDS: usize = 128;
/// Feed rate before any F word, mm/min.
pub const DEFAULT_FEED_MM_MIN: f64 = 1500.0;
/// Acceleration before any M204, mm/s².
pub const DEFAULT_ACCELERATION_MM_S2: f64 = 1000.0;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum EMode {
    /// Follows G90/G91 (Marlin: G90/G91 reset the E mode).
    Follow,
    Absolute,
    Relative,
}

/// A move with XYZ motion or E, as [`Motion::line`] classified it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Move {
    /// Start, mm.
    pub from: [f64; 3],
    /// End, mm.
    pub to: [f64; 3],
    /// E delta, mm.
    pub de: f64,
    /// Path length (arc length for arcs), mm.
    pub len: f64,
    /// Feed, mm/s.
    pub v: f64,
    /// An arc whose chord points (ending at `to`) are in [`Motion::arc_pts`].
    pub use_pts: bool,
}

impl Move {
    /// Has XYZ motion.
    pub fn moves(&self) -> bool {
        self.len > MOTION_EPS && self.len.is_finite()
    }
}

/// Chords an arc of radius `r` turning `ang` radians is drawn with: each within
/// [`ARC_TOLERANCE_MM`] of the arc and turning at most 90°, at most [`MAX_ARC_CHORDS`].
pub fn arc_chords(r: f64, ang: f64) -> usize {
    let half_pi = std::f64::consts::FRAC_PI_2;
    let step = if r > ARC_TOLERANCE_MM { (2.0 * libm::acos(1.0 - ARC_TOLERANCE_MM / r)).min(half_pi) } else { half_pi };
    let n = ang.abs() / step;
    if n.is_nan() {
        1
    } else {
        n.ceil().clamp(1.0, MAX_ARC_CHORDS as f64) as usize
    }
}

/// What one line did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Step {
    /// Nothing the caller tracks (modes, dwells, unknown commands).
    None,
    /// A `G0`–`G3` move.
    Move(Move),
    /// `G28`: the named axes went home; the motion chain stopped.
    Home,
    /// `G10` without `P`/`L`: firmware retraction.
    Retract,
    /// `G11`: firmware unretraction.
    Unretract,
}

/// The modal machine state and its running time and travel.
#[derive(Clone, Debug)]
pub struct Motion {
    /// Position, mm.
    pub pos: [f64; 3],
    /// E position, mm.
    pub e: f64,
    abs_xyz: bool,
    e_mode: EMode,
    unit: f64,
    /// Feed, mm/min.
    pub feed: f64,
    accel_print: f64,
    accel_travel: f64,
    modal: Command,
    /// Time model.
    pub timer: MotionTimer,
    /// Non-extruding move length, mm.
    pub travel_mm: f64,
    /// Chord points of the last arc (when [`Move::use_pts`]).
    pub arc_pts: Vec<[f64; 3]>,
    /// A, B, C positions, degrees (absolute; `G91` makes the words relative).
    pub rotary: [f64; 3],
    /// Last `I J K` tool vector of a `G0`/`G1` (as written, not normalised).
    pub ijk: [f64; 3],
    /// Moves that carried an A, B or C word.
    pub rotary_moves: usize,
    /// Moves that carried an I, J or K word (`G0`/`G1` only: on arcs they are the centre).
    pub ijk_moves: usize,
}

impl Default for Motion {
    fn default() -> Self {
        Motion {
            pos: [0.0; 3],
            e: 0.0,
            abs_xyz: true,
            e_mode: EMode::Follow,
            unit: 1.0,
            feed: DEFAULT_FEED_MM_MIN,
            accel_print: DEFAULT_ACCELERATION_MM_S2,
            accel_travel: DEFAULT_ACCELERATION_MM_S2,
            modal: Command::G(1, 0),
            timer: MotionTimer::default(),
            travel_mm: 0.0,
            arc_pts: Vec::new(),
            rotary: [0.0; 3],
            ijk: [0.0, 0.0, 1.0],
            rotary_moves: 0,
            ijk_moves: 0,
        }
    }
}

impl Motion {
    fn e_relative(&self) -> bool {
        match self.e_mode {
            EMode::Follow => !self.abs_xyz,
            EMode::Absolute => false,
            EMode::Relative => true,
        }
    }

    /// Interprets one command with its words (`Command::Modal` repeats the last motion
    /// command). `arc_points`: always compute the chord points of arcs (for a preview).
    pub fn line(&mut self, cmd: Command, w: &Words, arc_points: bool) -> Step {
        let cmd = if cmd == Command::Modal { self.modal } else { cmd };
        match cmd {
            Command::G(0 | 1, 0) => {
                self.modal = cmd;
                return Step::Move(self.linear(w));
            }
            Command::G(g @ (2 | 3), 0) => {
                self.modal = cmd;
                return Step::Move(self.arc(w, g == 2, arc_points));
            }
            Command::G(4, 0) => {
                let s = w.get(b'S').unwrap_or(0.0) + w.get(b'P').unwrap_or(0.0) / 1000.0;
                self.timer.dwell(s);
            }
            Command::G(10, 0) if !w.has(b'P') && !w.has(b'L') => return Step::Retract,
            Command::G(11, 0) => return Step::Unretract,
            Command::G(20, 0) => self.unit = 25.4,
            Command::G(21, 0) => self.unit = 1.0,
            Command::G(28, 0) => {
                let any = w.has(b'X') || w.has(b'Y') || w.has(b'Z');
                for (k, letter) in [b'X', b'Y', b'Z'].into_iter().enumerate() {
                    if !any || w.has(letter) {
                        self.pos[k] = 0.0;
                    }
                }
                self.timer.stop();
                return Step::Home;
            }
            Command::G(90, 0) => {
                self.abs_xyz = true;
                self.e_mode = EMode::Follow;
            }
            Command::G(91, 0) => {
                self.abs_xyz = false;
                self.e_mode = EMode::Follow;
            }
            Command::G(92, 0) => {
                for (k, letter) in [b'X', b'Y', b'Z'].into_iter().enumerate() {
                    if let Some(v) = w.get(letter) {
                        self.pos[k] = v * self.unit;
                    }
                }
                for (k, letter) in [b'A', b'B', b'C'].into_iter().enumerate() {
                    if let Some(v) = w.get(letter) {
                        self.rotary[k] = v;
                    }
                }
                if let Some(v) = w.get(b'E') {
                    self.e = v * self.unit;
                }
            }
            Command::M(82) => self.e_mode = EMode::Absolute,
            Command::M(83) => self.e_mode = EMode::Relative,
            Command::M(204) => {
                if let Some(s) = w.get(b'S').filter(|v| *v > 0.0) {
                    self.accel_print = s;
                    self.accel_travel = s;
                }
                if let Some(p) = w.get(b'P').filter(|v| *v > 0.0) {
                    self.accel_print = p;
                }
                if let Some(t) = w.get(b'T').filter(|v| *v > 0.0) {
                    self.accel_travel = t;
                }
            }
            _ => {}
        }
        Step::None
    }

    /// Target of a motion command and its E delta (updates E, F and the rotary axes).
    fn target(&mut self, w: &Words) -> ([f64; 3], f64) {
        let mut t = self.pos;
        for (k, letter) in [b'X', b'Y', b'Z'].into_iter().enumerate() {
            if let Some(v) = w.get(letter) {
                let v = v * self.unit;
                t[k] = if self.abs_xyz { v } else { self.pos[k] + v };
            }
        }
        // Rotary axes are degrees whatever the length unit.
        let mut rotary = false;
        for (k, letter) in [b'A', b'B', b'C'].into_iter().enumerate() {
            if let Some(v) = w.get(letter) {
                self.rotary[k] = if self.abs_xyz { v } else { self.rotary[k] + v };
                rotary = true;
            }
        }
        if rotary {
            self.rotary_moves += 1;
        }
        let mut de = 0.0;
        if let Some(v) = w.get(b'E') {
            let v = v * self.unit;
            if self.e_relative() {
                de = v;
                self.e += v;
            } else {
                de = v - self.e;
                self.e = v;
            }
        }
        if let Some(f) = w.get(b'F') {
            if f > 0.0 {
                self.feed = f * self.unit;
            }
        }
        (t, de)
    }

    fn linear(&mut self, w: &Words) -> Move {
        let (t, de) = self.target(w);
        // On G0/G1, I J K are the tool vector (absent components keep their value).
        if w.get(b'I').is_some() || w.get(b'J').is_some() || w.get(b'K').is_some() {
            for (k, letter) in [b'I', b'J', b'K'].into_iter().enumerate() {
                if let Some(v) = w.get(letter) {
                    self.ijk[k] = v;
                }
            }
            self.ijk_moves += 1;
        }
        let p = self.pos;
        let d = [t[0] - p[0], t[1] - p[1], t[2] - p[2]];
        let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        let dir = if len > 0.0 { [d[0] / len, d[1] / len, d[2] / len] } else { [0.0; 3] };
        self.motion(t, de, len, dir, dir, false)
    }

    fn arc(&mut self, w: &Words, cw: bool, want_points: bool) -> Move {
        let (t, de) = self.target(w);
        let p = self.pos;
        let center = if w.get(b'I').is_some() || w.get(b'J').is_some() {
            Some([p[0] + w.get(b'I').unwrap_or(0.0) * self.unit, p[1] + w.get(b'J').unwrap_or(0.0) * self.unit])
        } else if let Some(r) = w.get(b'R') {
            let r = r * self.unit;
            let (dx, dy) = (t[0] - p[0], t[1] - p[1]);
            let d = (dx * dx + dy * dy).sqrt();
            if r != 0.0 && d > 0.0 {
                let e = if cw ^ (r < 0.0) { -1.0 } else { 1.0 };
                let h2 = r * r - d * d / 4.0;
                let h = if h2 > 0.0 { h2.sqrt() } else { 0.0 };
                let (mx, my) = ((p[0] + t[0]) / 2.0, (p[1] + t[1]) / 2.0);
                let (sx, sy) = (-dy / d, dx / d);
                Some([mx + e * h * sx, my + e * h * sy])
            } else {
                None
            }
        } else {
            None
        };
        let fallback = |m: &mut Self| {
            let d = [t[0] - p[0], t[1] - p[1], t[2] - p[2]];
            let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            let dir = if len > 0.0 { [d[0] / len, d[1] / len, d[2] / len] } else { [0.0; 3] };
            m.motion(t, de, len, dir, dir, false)
        };
        let Some(c) = center else { return fallback(self) };
        let (rpx, rpy) = (p[0] - c[0], p[1] - c[1]);
        let (rtx, rty) = (t[0] - c[0], t[1] - c[1]);
        let r = (rpx * rpx + rpy * rpy).sqrt();
        if r.is_nan() || r <= MOTION_EPS || !r.is_finite() {
            return fallback(self);
        }
        let two_pi = 2.0 * std::f64::consts::PI;
        let mut ang = libm::atan2(rpx * rty - rpy * rtx, rpx * rtx + rpy * rty);
        if ang < 0.0 {
            ang += two_pi;
        }
        if cw {
            ang -= two_pi;
        }
        if ang == 0.0 && p[0] == t[0] && p[1] == t[1] {
            ang = two_pi;
        }
        let dz = t[2] - p[2];
        let xy = ang.abs() * r;
        let len = (xy * xy + dz * dz).sqrt();
        // Tangents at both ends (unit, including the helical Z component).
        let s = if cw { -1.0 } else { 1.0 };
        let th0 = libm::atan2(rpy, rpx);
        let th1 = th0 + ang;
        let tz = if len > 0.0 { dz / len } else { 0.0 };
        let txy = if len > 0.0 { xy / len } else { 0.0 };
        let dir_in = [-s * libm::sin(th0) * txy, s * libm::cos(th0) * txy, tz];
        let dir_out = [-s * libm::sin(th1) * txy, s * libm::cos(th1) * txy, tz];
        let need_points = (de > 0.0 && xy > MOTION_EPS) || want_points;
        let mut pts = std::mem::take(&mut self.arc_pts);
        pts.clear();
        if need_points {
            let n = arc_chords(r, ang);
            for k in 1..n {
                let f = k as f64 / n as f64;
                let th = th0 + ang * f;
                pts.push([c[0] + r * libm::cos(th), c[1] + r * libm::sin(th), p[2] + dz * f]);
            }
            pts.push(t);
        }
        self.arc_pts = pts;
        self.motion(t, de, len, dir_in, dir_out, need_points)
    }

    /// Times a move from the current position to `t` feeding `de` and counts its travel.
    fn motion(&mut self, t: [f64; 3], de: f64, len: f64, dir_in: [f64; 3], dir_out: [f64; 3], use_pts: bool) -> Move {
        let p0 = self.pos;
        let v = self.feed / 60.0;
        if len > MOTION_EPS && len.is_finite() {
            if de > 0.0 {
                self.timer.push(len, dir_in, dir_out, v, self.accel_print);
            } else {
                self.timer.push(len, dir_in, dir_out, v, self.accel_travel);
                self.travel_mm += len;
            }
        } else if de != 0.0 && de.is_finite() {
            self.timer.push_isolated(de.abs(), v, self.accel_print);
        }
        self.pos = t;
        Move { from: p0, to: t, de, len, v, use_pts }
    }

    /// Feeds G-code text (one or more lines, as the analyzer splits them); false when a line
    /// is not text or cannot be read (the analyzer would reject the file).
    pub fn text(&mut self, text: &str) -> bool {
        let bytes = text.as_bytes();
        if lex::first_binary_byte(bytes).is_some() {
            return false;
        }
        for mut line in bytes.split(|&b| b == b'\n') {
            if let Some((&b'\r', rest)) = line.split_last() {
                line = rest;
            }
            let Ok(l) = lex::lex_line(line) else { return false };
            self.line(l.cmd, &l.words, false);
        }
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::{FRAC_PI_2, PI};

    #[test]
    fn arc_chords_follow_the_tolerance_and_the_cap() {
        // A quarter circle of 10 mm: chords of 2·acos(1 − 0.01/10) ≈ 5.1°.
        assert_eq!(arc_chords(10.0, FRAC_PI_2), 18);
        assert_eq!(arc_chords(10.0, -FRAC_PI_2), 18);
        // Huge radii reach the cap; tiny ones still get 4 chords a turn.
        assert_eq!(arc_chords(1e7, 2.0 * PI), MAX_ARC_CHORDS);
        assert_eq!(arc_chords(1e300, 2.0 * PI), MAX_ARC_CHORDS);
        assert_eq!(arc_chords(0.001, 2.0 * PI), 4);
        // Degenerate input gives one chord.
        assert_eq!(arc_chords(10.0, 0.0), 1);
        assert_eq!(arc_chords(10.0, f64::NAN), 1);
    }
}

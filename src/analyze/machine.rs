//! The interpreter: machine state, classification of moves, layers, paths and the report.

use super::overlap::{Overlap, Seg};
use super::parse::{lex_line, parse_number, trim_start, Command, Line, Words};
use super::time::MotionTimer;
use super::{Analysis, Error, LayerReport, Options, Preview, Report};
use crate::geom::Feature;

/// Moves shorter than this (mm) have no XYZ motion.
const MOTION_EPS: f64 = 1e-9;
/// Z-based layer detection: a Z change larger than this starts a layer, mm.
const LAYER_Z_EPS: f64 = 1e-6;
/// Longest preview chord of an arc, mm.
const ARC_CHORD_MM: f64 = 0.5;
/// Largest preview angle step of an arc, rad (10°).
const ARC_STEP_RAD: f64 = std::f64::consts::PI / 18.0;
/// Feed rate before any F word, mm/min.
pub const DEFAULT_FEED_MM_MIN: f64 = 1500.0;
/// Acceleration before any M204, mm/s².
pub const DEFAULT_ACCELERATION_MM_S2: f64 = 1000.0;

#[derive(Clone, Copy, PartialEq, Eq)]
enum EMode {
    /// Follows G90/G91 (Marlin: G90/G91 reset the E mode).
    Follow,
    Absolute,
    Relative,
}

struct LayerAcc {
    z: f64,
    travel_start: f64,
    retractions_start: usize,
    extruded: f64,
    overlap: f64,
    gippo: f64,
    paths: usize,
}

pub(crate) struct Machine<'o> {
    opts: &'o Options,
    comment_layers: bool,
    pos: [f64; 3],
    e: f64,
    abs_xyz: bool,
    e_mode: EMode,
    unit: f64,
    feed: f64,
    accel_print: f64,
    accel_travel: f64,
    modal: Command,
    width: f64,
    feature: u8,
    area: f64,

    e_net: f64,
    e_high: f64,
    retracted: bool,
    in_run: bool,
    layer_pending: bool,
    seen_layer_comment: bool,
    merge_first: bool,

    extruded_mm: f64,
    travel_mm: f64,
    retractions: usize,
    paths_total: usize,

    travel_at_ext: f64,
    retractions_at_ext: usize,
    travel_segs_at_ext: usize,

    layers: Vec<LayerAcc>,
    segs: Vec<Seg>,
    layer_paths: Vec<(f64, u32)>,
    overlap: Overlap,
    /// Native builds measure overlap on a second thread: layers go out here (index, segments)…
    overlap_out: Option<std::sync::mpsc::SyncSender<(usize, Vec<Seg>)>>,
    /// …and their overlap comes back here, in layer order.
    overlap_in: Option<std::sync::mpsc::Receiver<(usize, f64)>>,
    timer: MotionTimer,
    arc_pts: Vec<[f64; 3]>,
    preview: Option<Preview>,
}

impl<'o> Machine<'o> {
    pub fn new(opts: &'o Options, comment_layers: bool) -> Self {
        let fd = if opts.filament_diameter_mm > 0.0 { opts.filament_diameter_mm } else { super::DEFAULT_FILAMENT_DIAMETER_MM };
        Machine {
            opts,
            comment_layers,
            pos: [0.0; 3],
            e: 0.0,
            abs_xyz: true,
            e_mode: EMode::Follow,
            unit: 1.0,
            feed: DEFAULT_FEED_MM_MIN,
            accel_print: DEFAULT_ACCELERATION_MM_S2,
            accel_travel: DEFAULT_ACCELERATION_MM_S2,
            modal: Command::G(1, 0),
            width: opts.default_line_width_mm,
            feature: 255,
            area: std::f64::consts::PI * fd * fd / 4.0,
            e_net: 0.0,
            e_high: 0.0,
            retracted: false,
            in_run: false,
            layer_pending: false,
            seen_layer_comment: false,
            merge_first: false,
            extruded_mm: 0.0,
            travel_mm: 0.0,
            retractions: 0,
            paths_total: 0,
            travel_at_ext: 0.0,
            retractions_at_ext: 0,
            travel_segs_at_ext: 0,
            layers: Vec::new(),
            segs: Vec::new(),
            layer_paths: Vec::new(),
            overlap: Overlap::default(),
            overlap_out: None,
            overlap_in: None,
            timer: MotionTimer::default(),
            arc_pts: Vec::new(),
            preview: if opts.collect_preview { Some(Preview::default()) } else { None },
        }
    }

    fn e_relative(&self) -> bool {
        match self.e_mode {
            EMode::Follow => !self.abs_xyz,
            EMode::Absolute => false,
            EMode::Relative => true,
        }
    }

    /// Interprets one line.
    pub fn line(&mut self, l: &Line<'_>) {
        if let Some(c) = l.comment {
            self.comment(c);
        }
        let w = &l.words;
        let cmd = if l.cmd == Command::Modal { self.modal } else { l.cmd };
        match cmd {
            Command::G(0 | 1, 0) => {
                self.modal = cmd;
                self.linear(w);
            }
            Command::G(g @ (2 | 3), 0) => {
                self.modal = cmd;
                self.arc(w, g == 2);
            }
            Command::G(4, 0) => {
                let s = w.get(b'S').unwrap_or(0.0) + w.get(b'P').unwrap_or(0.0) / 1000.0;
                self.timer.dwell(s);
            }
            Command::G(10, 0) if !w.has(b'P') && !w.has(b'L') => self.retract(),
            Command::G(11, 0) => self.retracted = false,
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
                self.in_run = false;
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
    }

    fn comment(&mut self, c: &[u8]) {
        let c = trim_start(c);
        if c.starts_with(b"LAYER:") || c.starts_with(b"LAYER_CHANGE") {
            if self.comment_layers {
                if !self.seen_layer_comment {
                    // Extrusion before the first layer comment (a purge line) joins layer 0.
                    self.seen_layer_comment = true;
                    self.merge_first = true;
                }
                if !self.merge_first {
                    self.layer_pending = true;
                }
            }
        } else if let Some(name) = c.strip_prefix(b"TYPE:") {
            self.feature = std::str::from_utf8(name).ok().and_then(Feature::from_gcode_name).map_or(255, Feature::code);
        } else if let Some(v) = c.strip_prefix(b"WIDTH:") {
            if let Some((w, _)) = parse_number(trim_start(v)) {
                if w.is_finite() && w > 0.0 {
                    self.width = w;
                }
            }
        }
    }

    /// Target of a motion command and its E delta (updates E and F).
    fn target(&mut self, w: &Words) -> ([f64; 3], f64) {
        let mut t = self.pos;
        for (k, letter) in [b'X', b'Y', b'Z'].into_iter().enumerate() {
            if let Some(v) = w.get(letter) {
                let v = v * self.unit;
                t[k] = if self.abs_xyz { v } else { self.pos[k] + v };
            }
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

    fn linear(&mut self, w: &Words) {
        let (t, de) = self.target(w);
        let p = self.pos;
        let d = [t[0] - p[0], t[1] - p[1], t[2] - p[2]];
        let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        let dir = if len > 0.0 { [d[0] / len, d[1] / len, d[2] / len] } else { [0.0; 3] };
        self.motion(t, de, len, dir, dir, false);
    }

    fn arc(&mut self, w: &Words, cw: bool) {
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
            m.motion(t, de, len, dir, dir, false);
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
        let need_points = (de > 0.0 && xy > MOTION_EPS) || self.preview.is_some();
        let mut pts = std::mem::take(&mut self.arc_pts);
        pts.clear();
        if need_points {
            let n1 = (xy / ARC_CHORD_MM).ceil();
            let n2 = (ang.abs() / ARC_STEP_RAD).ceil();
            let n = if n1.is_finite() { n1.max(n2).clamp(1.0, 1024.0) as usize } else { 1 };
            for k in 1..n {
                let f = k as f64 / n as f64;
                let th = th0 + ang * f;
                pts.push([c[0] + r * libm::cos(th), c[1] + r * libm::sin(th), p[2] + dz * f]);
            }
            pts.push(t);
        }
        self.arc_pts = pts;
        self.motion(t, de, len, dir_in, dir_out, need_points);
    }

    fn retract(&mut self) {
        if !self.retracted {
            self.retractions += 1;
            self.retracted = true;
        }
        self.in_run = false;
    }

    /// A move from the current position to `t` feeding `de`, of length `len` (arc length for
    /// arcs, whose chord points are in `self.arc_pts` when `use_pts`).
    fn motion(&mut self, t: [f64; 3], de: f64, len: f64, dir_in: [f64; 3], dir_out: [f64; 3], use_pts: bool) {
        let p0 = self.pos;
        self.e_net += de;
        if self.e_net > self.e_high {
            self.e_high = self.e_net;
        }
        let v = self.feed / 60.0;
        if len > MOTION_EPS && len.is_finite() {
            if de > 0.0 {
                self.timer.push(len, dir_in, dir_out, v, self.accel_print);
                self.extrude(p0, t, de, len, use_pts, v);
            } else {
                self.timer.push(len, dir_in, dir_out, v, self.accel_travel);
                if de < 0.0 {
                    self.retract();
                }
                self.travel_mm += len;
                self.in_run = false;
                if let Some(pv) = &mut self.preview {
                    let mut a = p0;
                    if use_pts {
                        for &b in &self.arc_pts {
                            push6(&mut pv.travel_positions, a, b);
                            a = b;
                        }
                    } else {
                        push6(&mut pv.travel_positions, a, t);
                    }
                }
            }
        } else if de != 0.0 && de.is_finite() {
            self.timer.push_isolated(de.abs(), v, self.accel_print);
            if de < 0.0 {
                self.retract();
            } else {
                self.retracted = false;
            }
        }
        self.pos = t;
    }

    fn extrude(&mut self, p0: [f64; 3], t: [f64; 3], de: f64, len: f64, use_pts: bool, v: f64) {
        self.retracted = false;
        let new_layer = match self.layers.last() {
            None => true,
            Some(l) => {
                if self.comment_layers {
                    self.layer_pending
                } else {
                    (t[2] - l.z).abs() > LAYER_Z_EPS
                }
            }
        };
        self.layer_pending = false;
        self.merge_first = false;
        if new_layer {
            self.start_layer(t[2]);
        }
        if !self.in_run {
            self.paths_total += 1;
            self.layer_paths.push((0.0, 0));
            self.in_run = true;
        }
        if let Some(path) = self.layer_paths.last_mut() {
            path.0 += len;
            path.1 += 1;
        }
        self.extruded_mm += len;
        let w = self.width;
        let path_index = (self.paths_total - 1) as u32;
        let mut a = p0;
        let n_pts = if use_pts { self.arc_pts.len() } else { 1 };
        for k in 0..n_pts {
            let b = if use_pts { self.arc_pts[k] } else { t };
            self.segs.push(Seg { a: [a[0], a[1]], b: [b[0], b[1]], w });
            if let Some(pv) = &mut self.preview {
                let d = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
                let seg_len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                // Each chord gets its share of E; flow = volume / time at the feed rate.
                let share = if use_pts { de / n_pts as f64 } else { de };
                let flow = if seg_len > 0.0 && v > 0.0 { share * self.area / (seg_len / v) } else { 0.0 };
                push6(&mut pv.positions, a, b);
                pv.feature.push(self.feature);
                pv.path.push(path_index);
                pv.flow.push(flow as f32);
                pv.width.push(w as f32);
            }
            a = b;
        }
        self.travel_at_ext = self.travel_mm;
        self.retractions_at_ext = self.retractions;
        self.travel_segs_at_ext = self.preview.as_ref().map_or(0, |p| p.travel_positions.len() / 6);
    }

    fn start_layer(&mut self, z: f64) {
        self.finish_layer();
        let first = self.layers.is_empty();
        self.layers.push(LayerAcc {
            z,
            travel_start: if first { 0.0 } else { self.travel_at_ext },
            retractions_start: if first { 0 } else { self.retractions_at_ext },
            extruded: 0.0,
            overlap: 0.0,
            gippo: 0.0,
            paths: 0,
        });
        if let Some(pv) = &mut self.preview {
            pv.layer_segment_start.push((pv.positions.len() / 6) as u32);
            pv.layer_travel_start.push(if first { 0 } else { self.travel_segs_at_ext as u32 });
            pv.layer_z.push(z as f32);
        }
        self.in_run = false;
    }

    /// Computes overlap and GIPPO score of the current layer and clears its buffers.
    fn finish_layer(&mut self) {
        let index = self.layers.len().wrapping_sub(1);
        let Some(layer) = self.layers.last_mut() else { return };
        if self.layer_paths.is_empty() {
            return;
        }
        match &self.overlap_out {
            // The overlap thread owns the buffer from here; the result is filled in at finish().
            Some(tx) if tx.send((index, std::mem::take(&mut self.segs))).is_ok() => {}
            _ => layer.overlap = self.overlap.layer(&self.segs, self.opts.default_line_width_mm),
        }
        layer.gippo = gippo_score(&self.layer_paths);
        layer.paths = self.layer_paths.len();
        layer.extruded = self.layer_paths.iter().map(|p| p.0).sum();
        self.segs.clear();
        self.layer_paths.clear();
    }

    /// Ends the file and builds the analysis.
    pub fn finish(mut self) -> Analysis {
        self.timer.stop();
        self.finish_layer();
        // Closing the channel ends the overlap thread once it has measured every layer sent.
        drop(self.overlap_out.take());
        if let Some(rx) = self.overlap_in.take() {
            for (index, overlap) in rx {
                if let Some(layer) = self.layers.get_mut(index) {
                    layer.overlap = overlap;
                }
            }
        }
        let n = self.layers.len();
        let mut per_layer = Vec::with_capacity(n);
        for i in 0..n {
            let l = &self.layers[i];
            let (travel_end, retr_end) = match self.layers.get(i + 1) {
                Some(next) => (next.travel_start, next.retractions_start),
                None => (self.travel_mm, self.retractions),
            };
            per_layer.push(LayerReport {
                z: l.z,
                extrusion_paths: l.paths,
                extruded_mm: l.extruded,
                travel_mm: travel_end - l.travel_start,
                retractions: retr_end - l.retractions_start,
                overlap_mm: l.overlap,
                gippo_score: l.gippo,
            });
        }
        let gippo = if n > 0 { per_layer.iter().map(|l| l.gippo_score).sum::<f64>() / n as f64 } else { 0.0 };
        let report = Report {
            layers: n,
            extrusion_paths: self.paths_total,
            extruded_mm: self.extruded_mm,
            travel_mm: self.travel_mm,
            retractions: self.retractions,
            overlap_mm: per_layer.iter().map(|l| l.overlap_mm).sum(),
            gippo_score: gippo,
            estimated_time_s: self.timer.total(),
            filament_mm: self.e_high,
            per_layer,
        };
        let preview = self.preview.take().map(|mut pv| {
            pv.layer_segment_start.push((pv.positions.len() / 6) as u32);
            pv.layer_travel_start.push((pv.travel_positions.len() / 6) as u32);
            pv
        });
        Analysis { report, preview }
    }
}

#[inline]
fn push6(v: &mut Vec<f32>, a: [f64; 3], b: [f64; 3]) {
    v.extend_from_slice(&[a[0] as f32, a[1] as f32, a[2] as f32, b[0] as f32, b[1] as f32, b[2] as f32]);
}

/// GIPPO equation 1 over paths given as (length mm, segment count):
/// Σ length_i · edges_i / (total length · number of paths).
pub fn gippo_score(paths: &[(f64, u32)]) -> f64 {
    let total: f64 = paths.iter().map(|p| p.0).sum();
    if paths.is_empty() || total.is_nan() || total <= 0.0 {
        return 0.0;
    }
    paths.iter().map(|p| p.0 * p.1 as f64).sum::<f64>() / (total * paths.len() as f64)
}

/// Position of the first `\n` in `s`, eight bytes at a time.
#[inline]
fn find_newline(s: &[u8]) -> Option<usize> {
    const ONES: u64 = 0x0101_0101_0101_0101;
    const HIGHS: u64 = 0x8080_8080_8080_8080;
    const NL: u64 = 0x0a0a_0a0a_0a0a_0a0a;
    let mut chunks = s.chunks_exact(8);
    let mut base = 0;
    for c in &mut chunks {
        let x = u64::from_le_bytes([c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]]) ^ NL;
        // The lowest high bit set marks the first zero byte of x (borrows only move up).
        let z = x.wrapping_sub(ONES) & !x & HIGHS;
        if z != 0 {
            return Some(base + (z.trailing_zeros() / 8) as usize);
        }
        base += 8;
    }
    chunks.remainder().iter().position(|&b| b == b'\n').map(|p| base + p)
}

/// Runs the analyzer over `bytes`.
pub(crate) fn run(file: &str, bytes: &[u8], options: &Options) -> Result<Analysis, Error> {
    if let Some(offset) = super::parse::first_binary_byte(bytes) {
        return Err(Error::NotText { file: file.to_string(), offset });
    }
    let layer_comments = super::parse::has_layer_comments(bytes);
    #[cfg(not(target_arch = "wasm32"))]
    if bytes.len() >= PARALLEL_OVERLAP_MIN_BYTES {
        // Overlap is per layer and independent of parsing: measure it on a second core while
        // the next layers are parsed. Same layers, same order, same arithmetic → same results.
        return std::thread::scope(|scope| {
            let (seg_tx, seg_rx) = std::sync::mpsc::sync_channel::<(usize, Vec<Seg>)>(8);
            let (res_tx, res_rx) = std::sync::mpsc::channel();
            let width = options.default_line_width_mm;
            scope.spawn(move || {
                let mut overlap = Overlap::default();
                for (index, segs) in seg_rx {
                    if res_tx.send((index, overlap.layer(&segs, width))).is_err() {
                        break;
                    }
                }
            });
            let mut m = Machine::new(options, layer_comments);
            m.overlap_out = Some(seg_tx);
            m.overlap_in = Some(res_rx);
            parse_all(file, bytes, m)
        });
    }
    parse_all(file, bytes, Machine::new(options, layer_comments))
}

/// Files at least this large (bytes) measure overlap on a second thread (native builds).
#[cfg(not(target_arch = "wasm32"))]
const PARALLEL_OVERLAP_MIN_BYTES: usize = 1 << 20;

fn parse_all(file: &str, bytes: &[u8], mut m: Machine) -> Result<Analysis, Error> {
    let mut start = 0;
    let mut line_no = 0usize;
    while start < bytes.len() {
        let end = find_newline(&bytes[start..]).map_or(bytes.len(), |p| start + p);
        line_no += 1;
        let mut line = &bytes[start..end];
        if let Some((&b'\r', rest)) = line.split_last() {
            line = rest;
        }
        let l = lex_line(line).map_err(|problem| Error::Malformed { file: file.to_string(), line: line_no, problem })?;
        m.line(&l);
        start = end + 1;
    }
    Ok(m.finish())
}

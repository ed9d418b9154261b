//! The interpreter: machine state, classification of moves, layers, paths and the report.

use super::overlap::{Overlap, Seg};
use super::{Analysis, Error, Estimate, LayerReport, Options, Preview, Report, MAX_LAYER_SEGMENTS, MAX_PEAK_BYTES};
use crate::geom::Feature;
use crate::motion::lex::{lex_line, parse_number, trim_start, Command, Line};
use crate::motion::{Motion, Move, Step};

/// Z-based layer detection: a Z change larger than this starts a layer, mm.
const LAYER_Z_EPS: f64 = 1e-6;
/// Most objects a file's labels may declare (more share the last one).
const MAX_OBJECTS: usize = 1000;

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
    /// Positions, modes, feed, time and travel (shared with the writer).
    m: Motion,
    width: f64,
    feature: u8,
    area: f64,

    e_net: f64,
    e_high: f64,
    retracted: bool,
    in_run: bool,
    /// The run going on when the layer changed, not broken since: it continues in the new
    /// layer (a spiral vase, a VTP foam's endless thread) and counts once in the total.
    run_across_layers: bool,
    layer_pending: bool,
    seen_layer_comment: bool,
    merge_first: bool,

    extruded_mm: f64,
    retractions: usize,
    paths_total: usize,

    travel_at_ext: f64,
    retractions_at_ext: usize,
    travel_segs_at_ext: usize,

    layers: Vec<LayerAcc>,
    segs: Vec<Seg>,
    layer_paths: Vec<(f64, u32)>,
    overlap: Overlap,
    /// Layers handed to the pool for their overlap (index, segments), when the analysis runs
    /// on several threads ([`super::pooled`]): the driver takes them from here and gives the
    /// results back through [`Machine::set_overlap`]. `None` measures every layer here.
    pub(super) handed: Option<Vec<(usize, Vec<Seg>)>>,
    preview: Option<Preview>,
    /// The options' machine is 5-axis: positions are turned into tips (forward kinematics).
    fk: bool,
    /// Tip of the previous move's end (when `fk`).
    last_view: [f64; 3],
    /// G-code moves (`G0`–`G3`) read so far.
    moves: u32,
    /// Tool axis at the current position, once the file has stated one.
    axis: Option<[f64; 3]>,
    /// The estimate made before reading (moves and layers, upper bounds).
    est: Estimate,
    /// Chords of the arcs read so far beyond the one per arc the estimate counted.
    arc_extra: usize,
    /// Labelled objects and the one being printed ([`super::Report::objects`]).
    objects: Vec<super::ObjectReport>,
    object: Option<usize>,
    unlabelled_mm: f64,
}

impl<'o> Machine<'o> {
    pub fn new(opts: &'o Options, est: &Estimate) -> Self {
        let fd = if opts.filament_diameter_mm > 0.0 { opts.filament_diameter_mm } else { super::DEFAULT_FILAMENT_DIAMETER_MM };
        Machine {
            opts,
            comment_layers: est.layer_comments,
            m: Motion::default(),
            width: opts.default_line_width_mm,
            feature: 255,
            area: std::f64::consts::PI * fd * fd / 4.0,
            e_net: 0.0,
            e_high: 0.0,
            retracted: false,
            in_run: false,
            run_across_layers: false,
            layer_pending: false,
            seen_layer_comment: false,
            merge_first: false,
            extruded_mm: 0.0,
            retractions: 0,
            paths_total: 0,
            travel_at_ext: 0.0,
            retractions_at_ext: 0,
            travel_segs_at_ext: 0,
            layers: Vec::new(),
            segs: Vec::new(),
            layer_paths: Vec::new(),
            overlap: Overlap::default(),
            handed: None,
            preview: if opts.collect_preview { Some(Preview::default()) } else { None },
            fk: opts.machine.is_five_axis(),
            last_view: [0.0; 3],
            moves: 0,
            axis: None,
            est: *est,
            arc_extra: 0,
            objects: Vec::new(),
            object: None,
            unlabelled_mm: 0.0,
        }
    }

    /// Interprets one line; `Err` (a problem for [`Error::TooLarge`]) when it would take the
    /// analysis over a limit.
    pub fn line(&mut self, l: &Line<'_>) -> Result<(), String> {
        if let Some(c) = l.comment {
            self.comment(c);
        }
        if let Some(args) = l.args {
            self.label(l.cmd, args);
        }
        // Whether the position or the angles may have changed, and the tip is not yet known.
        let stale = match self.m.line(l.cmd, &l.words, self.preview.is_some()) {
            Step::Move(mv) => {
                self.update_axis();
                let viewed = self.motion(&mv)?;
                self.moves = self.moves.saturating_add(1);
                !viewed
            }
            Step::Retract => {
                self.retract();
                false
            }
            Step::Unretract => {
                self.retracted = false;
                false
            }
            Step::Home => {
                self.in_run = false;
                self.run_across_layers = false;
                true
            }
            Step::None => l.cmd == Command::G(92, 0),
        };
        if self.fk && stale {
            self.last_view = self.view(self.m.pos);
        }
        Ok(())
    }

    /// Admits the `n` segments a move is about to add (to the current layer when
    /// `extruding`): refuses a layer over [`MAX_LAYER_SEGMENTS`] and, when an arc adds chords
    /// the estimate did not count, an analysis over [`MAX_PEAK_BYTES`].
    fn admit(&mut self, n: usize, extruding: bool) -> Result<(), String> {
        if extruding && self.segs.len() + n > MAX_LAYER_SEGMENTS {
            let layer = self.layers.len();
            return Err(format!(
                "layer {layer} has more than {MAX_LAYER_SEGMENTS} extrusion segments (arcs count by their chords), limit {MAX_LAYER_SEGMENTS}: no print has that many in one layer; check the file, or split that layer"
            ));
        }
        // Check again when arcs add chords the estimate did not count, and whenever the layer
        // outgrows the estimate's largest by another 64k segments.
        let layer = if extruding { self.segs.len() + n } else { 0 };
        let grew = layer > self.est.largest_layer && (layer - n) >> 16 != layer >> 16;
        if n > 1 || grew {
            self.arc_extra += n - 1;
            let segments = self.est.moves.saturating_add(self.arc_extra);
            let largest = self.est.largest_layer.max(layer);
            let need = super::peak_bytes(self.est.bytes, segments, self.est.layers, largest, self.preview.is_some());
            if need > MAX_PEAK_BYTES {
                let arcs = if self.arc_extra > 0 { format!("the arcs up to here add {} chords; ", super::human_count(self.arc_extra)) } else { String::new() };
                return Err(format!("{arcs}{}", super::too_large(need, segments, self.est.layers, self.preview.is_some())));
            }
        }
        Ok(())
    }

    /// The rotary angles of the options' machine (letter order).
    fn angles(&self) -> [f64; 2] {
        self.opts.machine.rotary_indices().map(|k| self.m.rotary[k])
    }

    /// Where a machine position `p` puts the tip (forward kinematics at the current angles);
    /// `p` itself unless the options name a 5-axis machine and the file has rotary words.
    fn view(&self, p: [f64; 3]) -> [f64; 3] {
        if !self.fk || self.m.rotary_moves == 0 {
            return p;
        }
        self.opts.machine.to_tip(crate::geom::DVec3::from_array(p), self.angles()).to_array()
    }

    /// The tool axis after a move: from `I J K` (normalised), or the forward kinematics of the
    /// rotary words on a 5-axis machine; `None` until the file states one.
    fn update_axis(&mut self) {
        let axis = if self.m.ijk_moves > 0 {
            let v = crate::geom::DVec3::from_array(self.m.ijk);
            let n = v.length();
            Some(if n > 0.0 && n.is_finite() { (v / n).to_array() } else { [0.0, 0.0, 1.0] })
        } else if self.fk && self.m.rotary_moves > 0 {
            Some(self.opts.machine.tool_axis(self.angles()).to_array())
        } else {
            None
        };
        if axis.is_none() {
            return;
        }
        if let (None, Some(pv)) = (self.axis, &mut self.preview) {
            // Segments before the first stated axis had the default, vertical one.
            pv.axis.reserve(3 * pv.feature.len());
            for _ in 0..pv.feature.len() {
                pv.axis.extend_from_slice(&[0.0, 0.0, 1.0]);
            }
        }
        self.axis = axis;
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

    /// The object named `name`, added when new.
    fn object_named(&mut self, name: &str) -> usize {
        match self.objects.iter().position(|o| o.name.eq_ignore_ascii_case(name)) {
            Some(i) => i,
            None => {
                // A hostile file cannot grow this without bound: past the cap, names share one.
                if self.objects.len() >= MAX_OBJECTS {
                    return self.objects.len() - 1;
                }
                self.objects.push(super::ObjectReport { name: name.to_string(), extruded_mm: 0.0 });
                self.objects.len() - 1
            }
        }
    }

    /// Object labels: `M486 T<n>`, `M486 S<i> [A"name"]`, `EXCLUDE_OBJECT_DEFINE/_START/_END
    /// NAME=…`.
    fn label(&mut self, cmd: Command, args: &[u8]) {
        let text = String::from_utf8_lossy(args);
        let mut words = text.split_ascii_whitespace();
        if cmd == Command::M(486) {
            let (mut index, mut name): (Option<i64>, Option<String>) = (None, None);
            let rest: Vec<&str> = words.collect();
            for (k, w) in rest.iter().enumerate() {
                let (letter, value) = w.split_at(w.chars().next().map_or(0, char::len_utf8));
                match letter.to_ascii_uppercase().as_str() {
                    "T" => {
                        for i in 0..value.parse::<usize>().unwrap_or(0).min(MAX_OBJECTS) {
                            if self.objects.len() <= i {
                                self.objects.push(super::ObjectReport { name: i.to_string(), extruded_mm: 0.0 });
                            }
                        }
                    }
                    "S" => index = value.parse().ok(),
                    "A" => name = Some(rest[k..].join(" ")[1..].trim_matches('"').to_string()),
                    _ => {}
                }
                if name.is_some() {
                    break;
                }
            }
            match index {
                Some(i) if i >= 0 && (i as usize) < MAX_OBJECTS => {
                    let i = i as usize;
                    while self.objects.len() <= i {
                        let n = self.objects.len();
                        self.objects.push(super::ObjectReport { name: n.to_string(), extruded_mm: 0.0 });
                    }
                    if let Some(n) = name.filter(|n| !n.is_empty()) {
                        self.objects[i].name = n;
                    }
                    self.object = Some(i);
                }
                Some(_) => self.object = None,
                None => {}
            }
            return;
        }
        let Some(command) = words.next() else { return };
        let name = words.find_map(|w| w.strip_prefix("NAME=").or_else(|| w.strip_prefix("name="))).map(|n| n.trim_matches('"').to_string());
        match (command.to_ascii_uppercase().as_str(), name) {
            ("EXCLUDE_OBJECT_DEFINE", Some(n)) => {
                self.object_named(&n);
            }
            ("EXCLUDE_OBJECT_START", Some(n)) => self.object = Some(self.object_named(&n)),
            ("EXCLUDE_OBJECT_END", _) => self.object = None,
            _ => {}
        }
    }

    fn retract(&mut self) {
        if !self.retracted {
            self.retractions += 1;
            self.retracted = true;
        }
        self.in_run = false;
        self.run_across_layers = false;
    }

    /// Bookkeeping of a move [`Motion`] has timed: net E, extrusion or travel, retraction.
    /// True when it set [`Machine::last_view`] (5-axis, the tip of the move's end computed).
    fn motion(&mut self, mv: &Move) -> Result<bool, String> {
        let Move { from: p0, to: t, de, len, v, use_pts } = *mv;
        self.e_net += de;
        if self.e_net > self.e_high {
            self.e_high = self.e_net;
        }
        if mv.moves() {
            if de > 0.0 {
                self.extrude(p0, t, de, len, use_pts, v)?;
                return Ok(self.fk);
            }
            if de < 0.0 {
                self.retract();
            }
            self.in_run = false;
            self.run_across_layers = false;
            if self.preview.is_some() {
                let mut va = if self.fk { self.last_view } else { p0 };
                let n_pts = if use_pts { self.m.arc_pts.len() } else { 1 };
                self.admit(n_pts, false)?;
                for k in 0..n_pts {
                    let b = if use_pts { self.m.arc_pts[k] } else { t };
                    let vb = if self.fk { self.view(b) } else { b };
                    if let Some(pv) = &mut self.preview {
                        push6(&mut pv.travel_positions, va, vb);
                        pv.travel_move.push(self.moves);
                    }
                    va = vb;
                }
                if self.fk {
                    self.last_view = va;
                    return Ok(true);
                }
            }
        } else if de != 0.0 && de.is_finite() {
            if de < 0.0 {
                self.retract();
            } else {
                self.retracted = false;
            }
        }
        Ok(false)
    }

    fn extrude(&mut self, p0: [f64; 3], t: [f64; 3], de: f64, len: f64, use_pts: bool, v: f64) -> Result<(), String> {
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
        let n_pts = if use_pts { self.m.arc_pts.len() } else { 1 };
        self.admit(n_pts, true)?;
        if !self.in_run {
            if !std::mem::take(&mut self.run_across_layers) {
                self.paths_total += 1;
            }
            self.layer_paths.push((0.0, 0));
            self.in_run = true;
        }
        if let Some(path) = self.layer_paths.last_mut() {
            path.0 += len;
            path.1 += 1;
        }
        self.extruded_mm += len;
        match self.object {
            Some(i) => self.objects[i].extruded_mm += len,
            None => self.unlabelled_mm += len,
        }
        let w = self.width;
        let path_index = (self.paths_total - 1) as u32;
        let mut a = p0;
        let mut va = if self.fk { self.last_view } else { p0 };
        for k in 0..n_pts {
            let b = if use_pts { self.m.arc_pts[k] } else { t };
            // Overlap and preview are in the part's frame (tips), flow at the machine's motion.
            let vb = if self.fk { self.view(b) } else { b };
            self.segs.push(Seg { a: [va[0], va[1]], b: [vb[0], vb[1]], z: [va[2], vb[2]], w });
            if let Some(pv) = &mut self.preview {
                let d = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
                let seg_len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                // Each chord gets its share of E; flow = volume / time at the feed rate.
                let share = if use_pts { de / n_pts as f64 } else { de };
                let flow = if seg_len > 0.0 && v > 0.0 { share * self.area / (seg_len / v) } else { 0.0 };
                push6(&mut pv.positions, va, vb);
                pv.feature.push(self.feature);
                pv.path.push(path_index);
                pv.flow.push(flow as f32);
                pv.e_per_mm.push(if seg_len > 0.0 { (share / seg_len) as f32 } else { 0.0 });
                pv.speed.push(v as f32);
                pv.width.push(w as f32);
                pv.segment_move.push(self.moves);
                if let Some(n) = self.axis {
                    pv.axis.extend_from_slice(&[n[0] as f32, n[1] as f32, n[2] as f32]);
                }
            }
            a = b;
            va = vb;
        }
        if self.fk {
            self.last_view = va;
        }
        self.travel_at_ext = self.m.travel_mm;
        self.retractions_at_ext = self.retractions;
        self.travel_segs_at_ext = self.preview.as_ref().map_or(0, |p| p.travel_positions.len() / 6);
        Ok(())
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
        self.run_across_layers = self.in_run;
        self.in_run = false;
    }

    /// Computes overlap and GIPPO score of the current layer and clears its buffers.
    fn finish_layer(&mut self) {
        let index = self.layers.len().wrapping_sub(1);
        let Some(layer) = self.layers.last_mut() else { return };
        if self.layer_paths.is_empty() {
            return;
        }
        match &mut self.handed {
            // The pool measures it; the result comes back through set_overlap(). Large layers
            // are measured here, so that the layers in flight stay small; so are tiny ones,
            // which cost less than handing them over.
            Some(out) if (PARALLEL_LAYER_MIN_SEGMENTS..=PARALLEL_LAYER_SEGMENTS).contains(&self.segs.len()) => {
                out.push((index, std::mem::take(&mut self.segs)));
            }
            _ => layer.overlap = self.overlap.layer(&self.segs, self.opts.default_line_width_mm),
        }
        layer.gippo = gippo_score(&self.layer_paths);
        layer.paths = self.layer_paths.len();
        layer.extruded = self.layer_paths.iter().map(|p| p.0).sum();
        self.segs.clear();
        self.layer_paths.clear();
    }

    /// The overlap of layer `index`, measured elsewhere (see [`Machine::handed`]).
    #[cfg(any(not(target_arch = "wasm32"), feature = "wasm-threads"))]
    pub(super) fn set_overlap(&mut self, index: usize, overlap: f64) {
        if let Some(layer) = self.layers.get_mut(index) {
            layer.overlap = overlap;
        }
    }

    /// Ends the file: the last layer is finished (and handed over, when layers are).
    pub(super) fn close(&mut self) {
        self.m.timer.stop();
        self.finish_layer();
    }

    /// Ends the file and builds the analysis.
    pub fn finish(mut self) -> Analysis {
        self.close();
        let n = self.layers.len();
        let mut per_layer = Vec::with_capacity(n);
        for i in 0..n {
            let l = &self.layers[i];
            let (travel_end, retr_end) = match self.layers.get(i + 1) {
                Some(next) => (next.travel_start, next.retractions_start),
                None => (self.m.travel_mm, self.retractions),
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
            travel_mm: self.m.travel_mm,
            retractions: self.retractions,
            overlap_mm: per_layer.iter().map(|l| l.overlap_mm).sum(),
            gippo_score: gippo,
            estimated_time_s: self.m.timer.total(),
            rotary_moves: self.m.rotary_moves,
            ijk_moves: self.m.ijk_moves,
            filament_mm: self.e_high,
            per_layer,
            unlabelled_mm: if self.objects.is_empty() { 0.0 } else { self.unlabelled_mm },
            objects: std::mem::take(&mut self.objects),
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
pub(super) fn push6(v: &mut Vec<f32>, a: [f64; 3], b: [f64; 3]) {
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

/// `text` cut into blocks of about `block_bytes`, each ending after a newline (the last at the
/// end of the text): whole lines, to be read side by side.
pub(super) fn cut_lines(text: &[u8], block_bytes: usize) -> Vec<std::ops::Range<usize>> {
    let block_bytes = block_bytes.max(1);
    let mut out = Vec::with_capacity(text.len() / block_bytes + 1);
    let mut start = 0;
    while start < text.len() {
        let cut = (start + block_bytes).min(text.len());
        let end = find_newline(&text[cut - 1..]).map_or(text.len(), |p| cut + p);
        out.push(start..end);
        start = end;
    }
    out
}

/// Position of the first `\n` in `s`, eight bytes at a time.
#[inline]
pub(super) fn find_newline(s: &[u8]) -> Option<usize> {
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
pub(crate) fn run(file: &str, bytes: &[u8], options: &Options, est: &Estimate) -> Result<Analysis, Error> {
    if let Some(offset) = crate::motion::lex::first_binary_byte(bytes) {
        return Err(Error::NotText { file: file.to_string(), offset });
    }
    let m = Machine::new(options, est);
    #[cfg(any(not(target_arch = "wasm32"), feature = "wasm-threads"))]
    if bytes.len() >= super::pooled::MIN_BYTES && crate::par::can_wait_on_pool() {
        // Interpreted on one of the pool's threads, which lexes and measures too while it
        // waits, the caller asleep: from outside, the caller would be one thread more than the
        // cores, and the interpreter, the pipeline's slowest part, would share one.
        return crate::par::on_pool(|| super::pooled::run(file, bytes, m, options.default_line_width_mm));
    }
    parse_all(file, bytes, m)
}

/// Layers of at most this many segments are measured on the pool ([`super::pooled`]); larger
/// ones on the reading thread, so that the layers in flight stay within a few tens of MB.
pub(super) const PARALLEL_LAYER_SEGMENTS: usize = 1 << 16;
/// Layers of fewer segments are measured on the reading thread (a file of a million one-move
/// layers would otherwise spend its time handing them over).
const PARALLEL_LAYER_MIN_SEGMENTS: usize = 64;

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
        m.line(&l).map_err(|problem| Error::TooLarge { file: file.to_string(), line: line_no, problem })?;
        start = end + 1;
    }
    Ok(m.finish())
}

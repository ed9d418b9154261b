//! Arc fitting: runs of one planar extrusion path (a polyline) become `G2`/`G3` arcs.
//!
//! Entry: [`fit`] (default limits) or [`fit_with`] ([`ArcParams`]). The answer is a list of
//! [`Move`]s covering the polyline in order: each move ends at a point of the polyline (its
//! index, [`Move::end`]) and starts where the previous one ended (the first at index 0), so the
//! writer sums the extrusion of the covered segments exactly and an arc ends exactly on a
//! polyline point (no drift). [`spans`] pairs each move with its start index.
//!
//! # Tolerance rule
//! A run of points `s..=e` becomes one arc about centre `c`, radius `r = |p_s − c|` (the radius
//! firmware takes from `I J`), only if all of the following hold:
//! - at least [`MIN_SEGMENTS`] segments of non-zero length, at most [`ArcParams::max_points`]
//!   points; every point finite and at exactly the z of `p_s` (a run whose z varies is never an
//!   arc: no helical moves);
//! - the centre lies on the perpendicular bisector of `p_s p_e` (both ends exactly on the
//!   circle), placed there by least squares on the interior points;
//! - every point is within `tol` of the circle, `| |p_k − c| − r | ≤ tol`, and every chord
//!   (segment) is too: its point nearest `c` satisfies `r − dist ≤ tol` (its far side is bounded
//!   by its end points). This is exact over the whole chord and implies the chord-midpoint test;
//! - the points advance monotonically around `c` in one direction, each step less than 90°, and
//!   the polyline turns with the arc at every interior vertex (a collinear vertex, i.e. two
//!   segments of a straight stretch, or a turn the other way ends the arc; this is what keeps
//!   straight sides and zig-zags out of arcs); zero-length segments (duplicates, under 1e-6 mm)
//!   are carried along but not judged for direction;
//! - the sweep is below [`ArcParams::max_sweep_rad`] (315° by default: no full circles, and the
//!   end stays well apart from the start, which firmware would read as a full circle);
//! - `min_radius ≤ r ≤ max_radius_mm`, where `min_radius` is the larger of
//!   [`ArcParams::min_radius_mm`] (0.5 mm) and `s² / (8·tol)` for the firmware's chord length `s`
//!   ([`ArcParams::firmware_segment_mm`], 1 mm: Klipper's default `resolution`, Marlin's
//!   `MAX_ARC_SEGMENT_MM`), so the firmware's own chords of the arc stay within `tol` of it;
//! - the arc is worth it: its sagitta over the run (largest distance of the arc from the chord
//!   `p_s p_e`) is at least `tol`. A run that fits but is flatter than that is kept as lines.
//!
//! Together these bound the distance both ways: every point of the polyline run is within
//! `tol` of the arc and every point of the arc is within `tol` of the polyline run (the ray from
//! `c` through an arc point crosses the chord spanning that angle at a distance from `c` in
//! `[r − tol, r + tol]`).
//!
//! # Search and complexity
//! Greedy from the current start `s`: try `s..=s+3`, then double the run (6, 12, 24, …
//! segments, capped at `max_points`) while it fits, then bisect between the last run that fit
//! and the first that did not. A run that fits but is not worth an arc becomes lines up to its
//! end. Before an arc `s..=e` is taken, one try of `s+1..=e+3` checks whether the arc swallowed
//! the last segment of a straight stretch; if that run fits, it is extended the same way and a
//! line to `s+1` plus that arc is taken instead (so a corner arc does not start one segment
//! early on its side).
//!
//! One try over `L` points costs `O(L)` (a least-squares pass and a check pass, one `atan2`).
//! A start that yields an arc or a flat run of `L` segments costs `O(L log L)` and advances by
//! `L`; a start that yields nothing costs `O(1)` and advances by one segment. Total:
//! `O(n log k)` point evaluations for `n` points and the point cap `k` (500), i.e. linear in `n`
//! with a constant of a few tens (measured: 27 evaluations a point on 100k points of
//! circles, 8 on one long circle, under 10 on a raster), and `O(n)` memory for the answer
//! only. About 0.1 s for 1M points natively.
//!
//! # Limits worth knowing
//! - Both ends of an arc lie exactly on its circle, so the polyline's own chords must be
//!   within `tol` of the circle it samples (chord sagitta ≤ `tol`): a circle tessellated more
//!   coarsely than the tolerance stays lines.
//! - On a micrometre grid, a curve sampled so finely that each vertex sits less than about
//!   1.5 µm off the line through its neighbours (chord² / 2r) has turns decided by rounding and
//!   stays lines; tessellations to a sagitta of 1 µm or more are unaffected.
//! - Arcs are planar (no `Z` change within one): helices stay lines.
//!
//! # Determinism
//! Pure f64 arithmetic in a fixed order (`sqrt` is IEEE-exact, `atan2` is `libm`'s), no hashing,
//! no threads: the same input gives the same moves on every target.
//!
//! # For the writer
//! `Arc { clockwise: true }` is `G2`, otherwise `G3`; `X Y` are the end point's, `I J` are
//! [`center_offset`] (centre − start, relative offsets: how Marlin, Klipper and RepRapFirmware
//! read them by default; `R` cannot tell the two arcs over and under 180° apart, do not use it);
//! no `Z` word (arcs are planar). `E` is the sum of the covered segments' E; [`arc_length`]
//! gives the travelled length for time estimates. Fit the very points the writer prints (after
//! merging short moves, in printer coordinates), since indices refer to them. Rounding `X Y I J`
//! to 3 decimals moves the circle by under 1 µm (print `I J` with 4 if that matters); firmware
//! interpolates at the start radius and ends exactly on `X Y`.

use core::f64::consts::{FRAC_PI_4, PI, TAU};
use glam::{DVec2, DVec3};

/// Fewest segments (of non-zero length) one arc replaces.
pub const MIN_SEGMENTS: usize = 3;
/// Default lower bound of the radius (mm), before the firmware's chord bound.
pub const DEFAULT_MIN_RADIUS_MM: f64 = 0.5;
/// Default upper bound of the radius (mm): flatter runs stay lines.
pub const DEFAULT_MAX_RADIUS_MM: f64 = 1000.0;
/// Default length (mm) of the chords firmware cuts an arc into (Klipper's `resolution` and
/// Marlin's `MAX_ARC_SEGMENT_MM` default to 1 mm).
pub const DEFAULT_FIRMWARE_SEGMENT_MM: f64 = 1.0;
/// Default cap on the points of one arc (bounds the work per arc).
pub const DEFAULT_MAX_POINTS: usize = 500;
/// Default cap on one arc's sweep: 315° (2π − π/4).
pub const DEFAULT_MAX_SWEEP_RAD: f64 = TAU - FRAC_PI_4;

/// Largest sweep [`ArcParams::max_sweep_rad`] may ask for (≈ 354°).
const SWEEP_LIMIT_RAD: f64 = TAU - 0.1;
/// Largest point cap honoured (keeps the index arithmetic far from overflow).
const POINTS_LIMIT: usize = 1 << 20;
/// Segments shorter than this (mm) are duplicates: carried along, not judged for direction.
const DEGENERATE_SEG_MM: f64 = 1e-6;
/// Shortest chord `p_s p_e` (mm) an arc may have.
const MIN_CHORD_MM: f64 = 1e-4;
/// Smallest turn at a vertex inside an arc, as sin of the angle (below: straight).
const TURN_EPS: f64 = 1e-9;

/// One move of the fitted path, ending at polyline point `end`; it starts where the previous
/// move ended (the first at point 0).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Move {
    /// A straight move (`G1`) over one segment.
    Line {
        /// Index of the polyline point the move ends at.
        end: usize,
    },
    /// An arc over at least [`MIN_SEGMENTS`] segments: `G2` if `clockwise` (seen from +Z),
    /// else `G3`.
    Arc {
        /// Index of the polyline point the move ends at (exactly on the arc).
        end: usize,
        /// Centre of the arc, absolute XY (mm); `I J` = centre − start point.
        center: DVec2,
        /// Clockwise seen from +Z (`G2`); counter-clockwise is `G3`.
        clockwise: bool,
    },
}

impl Move {
    /// Index of the polyline point the move ends at.
    pub fn end(&self) -> usize {
        match *self {
            Move::Line { end } | Move::Arc { end, .. } => end,
        }
    }
}

/// Each move with the index of the point it starts at (the previous move's end, 0 first).
/// The move covers segments `start..end`, i.e. points `start..=end`.
pub fn spans(moves: &[Move]) -> impl Iterator<Item = (usize, &Move)> + '_ {
    let mut start = 0;
    moves.iter().map(move |m| {
        let s = start;
        start = m.end();
        (s, m)
    })
}

/// Limits of the fit. [`ArcParams::new`] gives the defaults for a tolerance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ArcParams {
    /// Largest distance (mm) between the polyline and the arc, both ways. Not finite or ≤ 0:
    /// no arcs.
    pub tol_mm: f64,
    /// Smallest radius (mm), whatever the firmware bound says.
    pub min_radius_mm: f64,
    /// Largest radius (mm).
    pub max_radius_mm: f64,
    /// Chord length (mm) the firmware cuts arcs into; the radius is kept at least
    /// `firmware_segment_mm² / (8·tol_mm)` so those chords stay within `tol_mm` of the arc.
    /// 0 disables the bound (firmware that chords by angle, e.g. Marlin with small
    /// `MIN_ARC_SEGMENT_MM` and `MIN_CIRCLE_SEGMENTS`).
    pub firmware_segment_mm: f64,
    /// Most points in one arc (≥ 4 for any arc; capped at 2^20).
    pub max_points: usize,
    /// Largest sweep of one arc (radians), capped at ≈ 354°.
    pub max_sweep_rad: f64,
}

impl ArcParams {
    /// The defaults for tolerance `tol_mm`: radius 0.5 to 1000 mm, firmware chords of 1 mm,
    /// 500 points, 315°.
    pub fn new(tol_mm: f64) -> Self {
        ArcParams {
            tol_mm,
            min_radius_mm: DEFAULT_MIN_RADIUS_MM,
            max_radius_mm: DEFAULT_MAX_RADIUS_MM,
            firmware_segment_mm: DEFAULT_FIRMWARE_SEGMENT_MM,
            max_points: DEFAULT_MAX_POINTS,
            max_sweep_rad: DEFAULT_MAX_SWEEP_RAD,
        }
    }

    /// The smallest radius an arc may have: the larger of `min_radius_mm` and
    /// `firmware_segment_mm² / (8·tol_mm)` (6.25 mm at 0.02 mm with 1 mm chords).
    pub fn min_radius(&self) -> f64 {
        let firmware = self.firmware_segment_mm * self.firmware_segment_mm / (8.0 * self.tol_mm);
        if firmware > self.min_radius_mm {
            firmware
        } else {
            self.min_radius_mm
        }
    }
}

/// Fits arcs to `points` with the default limits ([`ArcParams::new`]) and tolerance `tol_mm`.
/// Fewer than 2 points: no moves. See the module documentation for the rule and the cost.
pub fn fit(points: &[DVec3], tol_mm: f64) -> Vec<Move> {
    fit_with(points, &ArcParams::new(tol_mm))
}

/// Fits arcs to `points` with the limits `params`. Fewer than 2 points: no moves; a tolerance
/// that is not finite and positive: one line per segment.
pub fn fit_with(points: &[DVec3], params: &ArcParams) -> Vec<Move> {
    fit_counted(points, params, &mut 0)
}

/// Angle (radians, in `(0, 2π]`) swept going from `from` to `to` about `center` in the given
/// direction. `to` on the ray of `from` (e.g. `to == from`) is a full turn, as firmware reads it.
pub fn sweep_angle(from: DVec2, to: DVec2, center: DVec2, clockwise: bool) -> f64 {
    let (a, b) = (from - center, to - center);
    let sign = if clockwise { -1.0 } else { 1.0 };
    let angle = libm::atan2(a.perp_dot(b) * sign, a.dot(b));
    if angle > 0.0 {
        angle
    } else {
        angle + TAU
    }
}

/// Length (mm) of the arc from `from` to `to` about `center` in the given direction, at the
/// radius `|from − center|` (the one firmware uses). See [`sweep_angle`] for the angle.
pub fn arc_length(from: DVec2, to: DVec2, center: DVec2, clockwise: bool) -> f64 {
    (from - center).length() * sweep_angle(from, to, center, clockwise)
}

/// The `I J` words of an arc starting at `start` about `center`: `center − start` (relative
/// offsets, the form Marlin, Klipper and RepRapFirmware read by default).
pub fn center_offset(start: DVec2, center: DVec2) -> DVec2 {
    center - start
}

/// The limits, checked and derived once per call.
struct Limits {
    tol: f64,
    min_r: f64,
    max_r: f64,
    max_sweep: f64,
    max_points: usize,
}

impl Limits {
    /// `None` when no arc can pass (tolerance not finite and positive, cap under 4 points).
    fn new(params: &ArcParams) -> Option<Limits> {
        let tol = params.tol_mm;
        if !(tol > 0.0 && tol.is_finite()) || params.max_points < MIN_SEGMENTS + 1 {
            return None;
        }
        let max_sweep = if params.max_sweep_rad < SWEEP_LIMIT_RAD { params.max_sweep_rad } else { SWEEP_LIMIT_RAD };
        Some(Limits { tol, min_r: params.min_radius(), max_r: params.max_radius_mm, max_sweep, max_points: params.max_points.min(POINTS_LIMIT) })
    }
}

/// A run that fits a circle (every rule but "worth it").
struct ArcFit {
    /// Centre relative to the run's first point.
    center: DVec2,
    clockwise: bool,
    radius: f64,
    sweep: f64,
    chord: f64,
    /// Segments of non-zero length.
    steps: usize,
}

impl ArcFit {
    /// At least [`MIN_SEGMENTS`] real segments and a sagitta over the run of at least `tol`.
    fn worth(&self, tol: f64) -> bool {
        let h = 0.5 * self.chord;
        let rr = self.radius * self.radius - h * h;
        let k = if rr > 0.0 { rr.sqrt() } else { 0.0 };
        // r − k written as h² / (r + k): no cancellation for large radii.
        let sagitta = if self.sweep <= PI { h * h / (self.radius + k) } else { self.radius + k };
        self.steps >= MIN_SEGMENTS && sagitta >= tol
    }
}

/// [`fit_with`], counting point evaluations in `work` (one per point of a least-squares pass,
/// two per segment of a check pass).
fn fit_counted(points: &[DVec3], params: &ArcParams, work: &mut u64) -> Vec<Move> {
    let n = points.len();
    let mut moves = Vec::new();
    if n < 2 {
        return moves;
    }
    let limits = Limits::new(params);
    let arc = |s: usize, e: usize, f: &ArcFit| Move::Arc { end: e, center: points[s].truncate() + f.center, clockwise: f.clockwise };
    let mut s = 0;
    while s + 1 < n {
        let found = match &limits {
            Some(lim) => longest_run(points, s, lim, work).map(|(e, f)| (e, f.worth(lim.tol).then_some(f))),
            None => None,
        };
        match found {
            Some((e, Some(f))) => {
                // The arc may have swallowed the last segment of a straight stretch (its first
                // vertex turns with the arc): if the arc from the next point reaches at least
                // three points further (one or two is rounding at a cap), a line now and that
                // arc serve the shape better. One try (O(L)) decides whether to search at all.
                if let Some(lim) = &limits {
                    let e2 = e + 3;
                    if e2 < n && e2 - (s + 1) < lim.max_points {
                        if let Some(f2) = try_arc(points, s + 1, e2, lim, work) {
                            let (e1, f1) = extend(points, s + 1, e2, f2, lim, work);
                            if f1.worth(lim.tol) {
                                moves.push(Move::Line { end: s + 1 });
                                moves.push(arc(s + 1, e1, &f1));
                                s = e1;
                                continue;
                            }
                        }
                    }
                }
                moves.push(arc(s, e, &f));
                s = e;
            }
            Some((e, None)) => {
                // Fits a circle but too flat to be worth an arc: lines over the whole run.
                moves.extend((s + 1..=e).map(|end| Move::Line { end }));
                s = e;
            }
            None => {
                moves.push(Move::Line { end: s + 1 });
                s += 1;
            }
        }
    }
    moves
}

/// The longest run from `s` found by doubling then bisection, with its fit; `None` when even
/// [`MIN_SEGMENTS`] segments do not fit.
fn longest_run(points: &[DVec3], s: usize, lim: &Limits, work: &mut u64) -> Option<(usize, ArcFit)> {
    let last = (points.len() - 1).min(s + (lim.max_points - 1));
    let first = s + MIN_SEGMENTS;
    if first > last {
        return None;
    }
    let good = try_arc(points, s, first, lim, work)?;
    Some(extend(points, s, first, good, lim, work))
}

/// From a run `s..=good_e` that fits (`good`), the longest run found by doubling its segments
/// while it fits (up to the point cap), then bisecting between the last that fit and the first
/// that did not.
fn extend(points: &[DVec3], s: usize, mut good_e: usize, mut good: ArcFit, lim: &Limits, work: &mut u64) -> (usize, ArcFit) {
    let last = (points.len() - 1).min(s + (lim.max_points - 1));
    let mut bad_e = None;
    while good_e < last {
        let e = (s + 2 * (good_e - s)).min(last);
        match try_arc(points, s, e, lim, work) {
            Some(f) => (good_e, good) = (e, f),
            None => {
                bad_e = Some(e);
                break;
            }
        }
    }
    if let Some(mut bad) = bad_e {
        while bad - good_e > 1 {
            let mid = good_e + (bad - good_e) / 2;
            match try_arc(points, s, mid, lim, work) {
                Some(f) => (good_e, good) = (mid, f),
                None => bad = mid,
            }
        }
    }
    (good_e, good)
}

/// The circle of the run `s..=e` and whether it passes every rule but "worth it" (module
/// documentation). Coordinates are taken relative to `p_s` for precision. `O(e − s)`.
fn try_arc(points: &[DVec3], s: usize, e: usize, lim: &Limits, work: &mut u64) -> Option<ArcFit> {
    let run = &points[s..=e];
    let z = run[0].z;
    let origin = run[0].truncate();
    if !(origin.is_finite() && z.is_finite()) {
        return None;
    }
    let chord_vec = run[run.len() - 1].truncate() - origin;
    let chord2 = chord_vec.length_squared();
    if !(chord2 > MIN_CHORD_MM * MIN_CHORD_MM && chord2.is_finite()) {
        return None;
    }
    let chord = chord2.sqrt();

    // Pass 1: same z, finite, and the centre c = m + t·n on the bisector of the chord. For a
    // point q (relative to p_s), |q − c|² − r² = a − b·t with a = |q − m|² − h², b = 2 n·(q − m)
    // (r² = h² + t², n ⟂ the chord), linear in t: least squares gives t = Σab / Σb².
    let half = chord_vec * 0.5;
    let h2 = chord2 * 0.25;
    let normal = chord_vec.perp() / chord;
    let (mut sab, mut sbb) = (0.0, 0.0);
    for p in &run[1..] {
        *work += 1;
        if p.z != z || !p.is_finite() {
            return None;
        }
        let w = p.truncate() - origin - half;
        let a = w.length_squared() - h2;
        let b = 2.0 * normal.dot(w);
        sab += a * b;
        sbb += b * b;
    }
    let t = sab / sbb;
    if !t.is_finite() {
        return None;
    }
    let c = half + normal * t;
    let r = c.length();
    if !(r >= lim.min_r && r <= lim.max_r) {
        return None;
    }

    // Pass 2: tolerance of points and chords, direction, turning, winding.
    let to_start = -c;
    let mut dir = 0.0;
    let mut prev_seg: Option<(DVec2, f64)> = None;
    let mut past_half_turn = false;
    let mut steps = 0;
    let mut a = DVec2::ZERO;
    for p in &run[1..] {
        *work += 2;
        let b = p.truncate() - origin;
        let vb = b - c;
        if !((vb.length() - r).abs() <= lim.tol) {
            return None;
        }
        let seg = b - a;
        let len = seg.length();
        let nearest = if len > 0.0 { a + seg * ((c - a).dot(seg) / (len * len)).clamp(0.0, 1.0) } else { a };
        if !(r - nearest.distance(c) <= lim.tol) {
            return None;
        }
        if len > DEGENERATE_SEG_MM {
            let va = a - c;
            let cross = va.perp_dot(vb);
            if dir == 0.0 {
                dir = if cross > 0.0 {
                    1.0
                } else if cross < 0.0 {
                    -1.0
                } else {
                    return None;
                };
            }
            // Advances in the arc's direction by less than 90°.
            if !(cross * dir > 0.0 && va.dot(vb) > 0.0) {
                return None;
            }
            // Turns with the arc at every vertex (a straight vertex ends the arc).
            if let Some((prev, prev_len)) = prev_seg {
                if !(prev.perp_dot(seg) * dir > TURN_EPS * prev_len * len) {
                    return None;
                }
            }
            prev_seg = Some((seg, len));
            steps += 1;
            // Winding: past half a turn once the point crosses to the start ray's other side;
            // crossing back means a full turn.
            let side = to_start.perp_dot(vb) * dir;
            if !past_half_turn {
                past_half_turn = side <= 0.0;
            } else if side > 0.0 {
                return None;
            }
        }
        a = b;
    }
    if dir == 0.0 {
        return None;
    }
    let to_end = chord_vec - c;
    let angle = libm::atan2(to_start.perp_dot(to_end) * dir, to_start.dot(to_end));
    let sweep = if past_half_turn && angle <= 0.0 { angle + TAU } else { angle };
    if !(sweep > 0.0 && sweep < lim.max_sweep) {
        return None;
    }
    Some(ArcFit { center: c, clockwise: dir < 0.0, radius: r, sweep, chord, steps })
}

#[cfg(test)]
mod tests {
    use super::*;

    const TOL: f64 = 0.02;

    fn xy(p: DVec3) -> DVec2 {
        p.truncate()
    }

    /// Points on a circle: `count` steps of `step` radians from `a0`, at height `z`.
    fn circle(center: DVec2, r: f64, a0: f64, step: f64, count: usize, z: f64) -> Vec<DVec3> {
        (0..=count)
            .map(|k| {
                let a = a0 + step * k as f64;
                (center + r * DVec2::new(libm::cos(a), libm::sin(a))).extend(z)
            })
            .collect()
    }

    fn dist_to_segment(p: DVec2, a: DVec2, b: DVec2) -> f64 {
        let d = b - a;
        let l2 = d.length_squared();
        let u = if l2 > 0.0 { ((p - a).dot(d) / l2).clamp(0.0, 1.0) } else { 0.0 };
        p.distance(a + d * u)
    }

    /// Moves cover points 0..n-1 in order, ends strictly increasing, arcs ≥ 3 segments.
    fn check_cover(points: &[DVec3], moves: &[Move]) {
        if points.len() < 2 {
            assert!(moves.is_empty());
            return;
        }
        let mut prev = 0;
        for (start, m) in spans(moves) {
            assert_eq!(start, prev);
            assert!(m.end() > start, "ends strictly increasing");
            if let Move::Arc { end, .. } = *m {
                assert!(end - start >= MIN_SEGMENTS);
            }
            prev = m.end();
        }
        assert_eq!(prev, points.len() - 1);
    }

    /// Independent check of one arc against the polyline run `start..=end`, both ways; returns
    /// the largest deviation seen.
    fn check_arc(points: &[DVec3], start: usize, end: usize, center: DVec2, clockwise: bool, params: &ArcParams) -> f64 {
        let tol = params.tol_mm;
        let run = &points[start..=end];
        let (ps, pe) = (xy(run[0]), xy(run[run.len() - 1]));
        let r = ps.distance(center);
        assert!((pe.distance(center) - r).abs() < 1e-9, "end on the circle");
        assert!(r >= params.min_radius() && r <= params.max_radius_mm);
        assert!(run.iter().all(|p| p.z == run[0].z), "planar");
        let mut worst: f64 = 0.0;
        // Points and chords (chord midpoints and 15 more samples each) to the circle.
        for w in run.windows(2) {
            for i in 0..=16 {
                let q = xy(w[0]).lerp(xy(w[1]), i as f64 / 16.0);
                worst = worst.max((q.distance(center) - r).abs());
            }
        }
        // The arc, sampled densely, to the polyline run.
        let sweep = sweep_angle(ps, pe, center, clockwise);
        assert!(sweep < DEFAULT_MAX_SWEEP_RAD + 1e-9 && sweep > 0.0);
        let a0 = libm::atan2(ps.y - center.y, ps.x - center.x);
        let sign = if clockwise { -1.0 } else { 1.0 };
        let samples = 400.max(4 * run.len());
        for i in 0..=samples {
            let a = a0 + sign * sweep * i as f64 / samples as f64;
            let q = center + r * DVec2::new(libm::cos(a), libm::sin(a));
            let d = run.windows(2).map(|w| dist_to_segment(q, xy(w[0]), xy(w[1]))).fold(f64::INFINITY, f64::min);
            worst = worst.max(d);
        }
        assert!(worst <= tol + 1e-9, "arc {start}..{end} deviates {worst} > {tol}");
        worst
    }

    /// Checks cover and every arc (default limits); returns (lines, arcs).
    fn check_all(points: &[DVec3], moves: &[Move], tol: f64) -> (usize, usize) {
        check_all_with(points, moves, &ArcParams::new(tol))
    }

    fn check_all_with(points: &[DVec3], moves: &[Move], params: &ArcParams) -> (usize, usize) {
        check_cover(points, moves);
        let (mut lines, mut arcs) = (0, 0);
        for (start, m) in spans(moves) {
            match *m {
                Move::Line { .. } => lines += 1,
                Move::Arc { end, center, clockwise } => {
                    check_arc(points, start, end, center, clockwise, params);
                    arcs += 1;
                }
            }
        }
        (lines, arcs)
    }

    #[test]
    fn circle_of_360_points_is_two_arcs() {
        // Closed loop: 360 points 1° apart plus the first again (360 segments), radius 10.
        let pts = circle(DVec2::new(100.0, 80.0), 10.0, 0.3, TAU / 360.0, 360, 0.2);
        let moves = fit(&pts, TOL);
        let (lines, arcs) = check_all(&pts, &moves, TOL);
        assert_eq!((lines, arcs), (0, 2), "{moves:?}");
        // First arc as long as the 315° cap allows, then the rest; both counter-clockwise.
        assert!(matches!(moves[0], Move::Arc { end: 314 | 315, clockwise: false, .. }), "{:?}", moves[0]);
        for m in &moves {
            if let Move::Arc { center, .. } = *m {
                assert!(center.distance(DVec2::new(100.0, 80.0)) < 1e-6);
            }
        }
        // Clockwise the other way round.
        let rev: Vec<DVec3> = pts.iter().rev().copied().collect();
        let moves = fit(&rev, TOL);
        assert_eq!(check_all(&rev, &moves, TOL), (0, 2));
        assert!(moves.iter().all(|m| matches!(m, Move::Arc { clockwise: true, .. })));
    }

    /// Rounded square: sides of `side` mm cut in `cuts` collinear segments, corners of radius
    /// `r` in `corner_segs` segments; closed. Returns points and the corner index ranges.
    fn rounded_square(side: f64, r: f64, cuts: usize, corner_segs: usize) -> (Vec<DVec3>, Vec<(usize, usize)>) {
        let mut pts = vec![DVec3::new(r, 0.0, 0.4)];
        let mut corners = Vec::new();
        let straight = side - 2.0 * r;
        let dirs = [DVec2::X, DVec2::Y, -DVec2::X, -DVec2::Y];
        for (i, d) in dirs.iter().enumerate() {
            let start = xy(pts[pts.len() - 1]);
            for k in 1..=cuts {
                pts.push((start + *d * straight * k as f64 / cuts as f64).extend(0.4));
            }
            let c = xy(pts[pts.len() - 1]) + d.perp() * r;
            let a0 = (i as f64 - 1.0) * FRAC_PI_2;
            let first = pts.len() - 1;
            for k in 1..=corner_segs {
                let a = a0 + FRAC_PI_2 * k as f64 / corner_segs as f64;
                pts.push((c + r * DVec2::new(libm::cos(a), libm::sin(a))).extend(0.4));
            }
            corners.push((first, pts.len() - 1));
        }
        (pts, corners)
    }
    use core::f64::consts::FRAC_PI_2;

    #[test]
    fn rounded_square_sides_stay_lines_corners_become_arcs() {
        let (pts, corners) = rounded_square(40.0, 8.0, 4, 30);
        let moves = fit(&pts, TOL);
        let (lines, arcs) = check_all(&pts, &moves, TOL);
        assert_eq!((lines, arcs), (16, 4), "{moves:?}");
        let arc_spans: Vec<(usize, usize)> = spans(&moves).filter(|(_, m)| matches!(m, Move::Arc { .. })).map(|(s, m)| (s, m.end())).collect();
        assert_eq!(arc_spans, corners);
        let segments = pts.len() - 1;
        // 136 segments → 20 moves: 85% fewer.
        assert_eq!((segments, moves.len()), (136, 20));
    }

    #[test]
    fn zigzag_and_raster_give_no_arcs() {
        // Infill raster: long lines joined by short steps, turning left, left, right, right.
        let mut raster = Vec::new();
        for row in 0..50 {
            let y = row as f64 * 0.4;
            let (x0, x1) = if row % 2 == 0 { (0.0, 30.0) } else { (30.0, 0.0) };
            raster.push(DVec3::new(x0, y, 0.2));
            raster.push(DVec3::new(x1, y, 0.2));
        }
        let moves = fit(&raster, 0.05);
        assert_eq!(check_all(&raster, &moves, 0.05), (99, 0));
        // A zig-zag hugging a circle (radius alternating ±0.004, well within tolerance): the
        // turns alternate, so no arcs.
        let zig: Vec<DVec3> = (0..=300)
            .map(|k| {
                let a = k as f64 * TAU / 360.0;
                let r = if k % 2 == 0 { 10.004 } else { 9.996 };
                DVec3::new(r * libm::cos(a), r * libm::sin(a), 0.2)
            })
            .collect();
        let moves = fit(&zig, TOL);
        assert_eq!(check_all(&zig, &moves, TOL), (300, 0));
    }

    #[test]
    fn non_planar_runs_give_no_arcs() {
        // A helix: the circle of the first test climbing 0.001 mm a point.
        let mut helix = circle(DVec2::ZERO, 10.0, 0.0, TAU / 360.0, 360, 0.2);
        for (k, p) in helix.iter_mut().enumerate() {
            p.z += 0.001 * k as f64;
        }
        let moves = fit(&helix, TOL);
        assert_eq!(check_all(&helix, &moves, TOL), (360, 0));
        // One point off the plane splits the circle: no arc contains it.
        let mut stepped = circle(DVec2::ZERO, 10.0, 0.0, TAU / 360.0, 360, 0.2);
        stepped[100].z = 0.4;
        let moves = fit(&stepped, TOL);
        let (_, arcs) = check_all(&stepped, &moves, TOL);
        assert!(arcs >= 2);
        for (s, m) in spans(&moves) {
            if matches!(m, Move::Arc { .. }) {
                assert!(!(s..=m.end()).contains(&100));
            }
        }
    }

    /// Seeded linear congruential generator (64-bit, Knuth's constants).
    struct Lcg(u64);

    impl Lcg {
        fn unit(&mut self) -> f64 {
            self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (self.0 >> 11) as f64 / (1u64 << 53) as f64
        }
        fn below(&mut self, n: usize) -> usize {
            ((self.unit() * n as f64) as usize).min(n - 1)
        }
    }

    /// A wandering path of `n` points: tangent arcs of random radius, sampling and noise,
    /// straight runs, jitter, duplicates, layer changes and short helices.
    fn random_path(seed: u64, n: usize) -> Vec<DVec3> {
        let mut rng = Lcg(seed);
        let mut pts = vec![DVec3::new(50.0, 50.0, 0.2)];
        let mut heading: f64 = 0.0;
        let mut z = 0.2;
        while pts.len() < n {
            let last = xy(pts[pts.len() - 1]);
            match rng.below(8) {
                0..=2 => {
                    let r = 0.3 + 80.0 * rng.unit() * rng.unit();
                    let sag = 0.0002 + 0.03 * rng.unit();
                    let step = (2.0 * libm::acos((1.0 - sag / r).max(-1.0))).min(0.6);
                    let ccw = rng.below(2) == 0;
                    let sign = if ccw { 1.0 } else { -1.0 };
                    let noise = if rng.below(3) == 0 { 0.01 * rng.unit() } else { 0.0 };
                    let dir = DVec2::new(libm::cos(heading), libm::sin(heading));
                    let c = last + dir.perp() * sign * r;
                    let a0 = libm::atan2(last.y - c.y, last.x - c.x);
                    let count = 2 + rng.below(150);
                    let helix = if rng.below(10) == 0 { 0.002 } else { 0.0 };
                    for k in 1..=count {
                        let a = a0 + sign * step * k as f64;
                        let rr = r + noise * (rng.unit() - 0.5);
                        z += helix;
                        pts.push((c + rr * DVec2::new(libm::cos(a), libm::sin(a))).extend(z));
                    }
                    heading += sign * step * count as f64;
                }
                3 | 4 => {
                    if rng.below(2) == 0 {
                        heading += (rng.unit() - 0.5) * 3.0;
                    }
                    let dir = DVec2::new(libm::cos(heading), libm::sin(heading));
                    let len = 0.1 + 10.0 * rng.unit();
                    let cuts = 1 + rng.below(6);
                    for k in 1..=cuts {
                        pts.push((last + dir * len * k as f64 / cuts as f64).extend(z));
                    }
                }
                5 => {
                    for _ in 0..1 + rng.below(10) {
                        let p = xy(pts[pts.len() - 1]) + DVec2::new(rng.unit() - 0.5, rng.unit() - 0.5) * 2.0;
                        pts.push(p.extend(z));
                    }
                    let d = xy(pts[pts.len() - 1]) - xy(pts[pts.len() - 2]);
                    heading = libm::atan2(d.y, d.x);
                }
                6 => {
                    for _ in 0..1 + rng.below(3) {
                        pts.push(pts[pts.len() - 1]);
                    }
                }
                _ => {
                    z += 0.2;
                    pts.push(last.extend(z));
                }
            }
        }
        pts.truncate(n);
        pts
    }

    #[test]
    fn random_paths_keep_cover_and_tolerance() {
        for (seed, tol) in [(1, 0.02), (2, 0.05), (3, 0.01), (4, 0.03)] {
            let pts = random_path(seed, 10_000);
            let moves = fit(&pts, tol);
            let (lines, arcs) = check_all(&pts, &moves, tol);
            eprintln!("random seed {seed}, tol {tol}: {arcs} arcs, {lines} lines");
            assert!(arcs > 30, "seed {seed}: {arcs} arcs, {lines} lines");
            assert_eq!(moves, fit(&pts, tol), "deterministic");
        }
    }

    /// ~100k points: circles of radius 7 to 50 mm, chords of 1 to 15 µm sagitta, on a
    /// micrometre grid, joined end to end (the circle-ish input); 200k points of one slow
    /// circle (the point cap); a raster (nothing fits).
    #[test]
    fn work_is_linear() {
        let mut rng = Lcg(7);
        let mut pts = Vec::new();
        let micrometre = |v: DVec2| (v * 1000.0).round() / 1000.0;
        while pts.len() < 100_000 {
            let r = 7.0 + 43.0 * rng.unit();
            // Chords of sagitta 1 to 15 µm, as a mesh tessellated to that accuracy gives.
            let sagitta = 0.001 + 0.014 * rng.unit();
            let step = 2.0 * libm::acos(1.0 - sagitta / r);
            let c = DVec2::new(100.0 + rng.unit(), 100.0 + rng.unit());
            for k in 0..(TAU / step) as usize {
                let a = k as f64 * step;
                pts.push(micrometre(c + r * DVec2::new(libm::cos(a), libm::sin(a))).extend(0.2));
            }
        }
        let mut work = 0;
        let moves = fit_counted(&pts, &ArcParams::new(TOL), &mut work);
        let (lines, arcs) = check_all(&pts[..], &moves, TOL);
        let per_point = work as f64 / pts.len() as f64;
        eprintln!("circle-ish: {} points, {arcs} arcs, {lines} lines, {per_point:.1} evaluations a point", pts.len());
        assert!(arcs > 1000 && per_point <= 40.0, "{per_point}");

        // The cap: 200k points 0.05° apart on a radius of 400 mm, arcs of 500 points.
        let big = circle(DVec2::ZERO, 400.0, 0.0, 0.05f64.to_radians(), 200_000, 0.2);
        let mut work = 0;
        let moves = fit_counted(&big, &ArcParams::new(TOL), &mut work);
        check_cover(&big, &moves);
        assert!(moves.iter().all(|m| matches!(m, Move::Arc { .. })));
        let per_point = work as f64 / big.len() as f64;
        eprintln!("slow circle: {} points, {} arcs, {per_point:.1} evaluations a point", big.len(), moves.len());
        assert!(per_point <= 40.0, "{per_point}");

        // Nothing fits: the raster costs a few evaluations a point.
        let raster: Vec<DVec3> = (0..100_000).map(|k| DVec3::new(if (k / 2) % 2 == 0 { 0.0 } else { 30.0 }, (k / 2) as f64 * 0.4, 0.2)).collect();
        let mut work = 0;
        fit_counted(&raster, &ArcParams::new(TOL), &mut work);
        eprintln!("raster: {} points, {:.1} evaluations a point", raster.len(), work as f64 / raster.len() as f64);
        assert!(work <= 10 * raster.len() as u64, "{work}");
    }

    #[test]
    fn degenerate_inputs_do_not_panic() {
        let nan = f64::NAN;
        let inf = f64::INFINITY;
        assert!(fit(&[], TOL).is_empty());
        assert!(fit(&[DVec3::ONE], TOL).is_empty());
        assert_eq!(fit(&[DVec3::ZERO, DVec3::ONE], TOL), vec![Move::Line { end: 1 }]);
        assert_eq!(fit(&[DVec3::ZERO, DVec3::ONE, DVec3::X], TOL).len(), 2);
        let ring = circle(DVec2::ZERO, 10.0, 0.0, TAU / 360.0, 90, 0.2);
        // Tolerance ≤ 0, NaN or infinite: all lines.
        for tol in [0.0, -1.0, nan, inf, f64::MAX] {
            assert_eq!(check_all(&ring, &fit(&ring, tol), 1.0).1, 0, "tol {tol}");
        }
        // NaN and infinite points: no arc through them, cover intact.
        for bad in [DVec3::new(nan, 0.0, 0.2), DVec3::new(0.0, inf, 0.2), DVec3::new(1.0, 1.0, nan), DVec3::splat(-inf)] {
            let mut pts = ring.clone();
            pts[40] = bad;
            let moves = fit(&pts, TOL);
            check_cover(&pts, &moves);
            for (s, m) in spans(&moves) {
                if matches!(m, Move::Arc { .. }) {
                    assert!(!(s..=m.end()).contains(&40));
                }
            }
            let all_bad = vec![bad; 50];
            check_cover(&all_bad, &fit(&all_bad, TOL));
        }
        // Duplicates only, duplicates inside a circle, collinear, huge coordinates.
        let dup = vec![DVec3::new(3.0, 4.0, 0.2); 100];
        assert_eq!(check_all(&dup, &fit(&dup, TOL), TOL), (99, 0));
        let mut doubled = Vec::new();
        for p in &ring {
            doubled.push(*p);
            doubled.push(*p);
        }
        let (_, arcs) = check_all(&doubled, &fit(&doubled, TOL), TOL);
        assert_eq!(arcs, 1);
        let line: Vec<DVec3> = (0..100).map(|k| DVec3::new(k as f64 * 0.3, k as f64 * 0.1, 0.2)).collect();
        assert_eq!(check_all(&line, &fit(&line, TOL), TOL), (99, 0));
        let huge: Vec<DVec3> = (0..100).map(|k| DVec3::new(1e300 * libm::cos(k as f64), 1e300 * libm::sin(k as f64), 0.0)).collect();
        check_cover(&huge, &fit(&huge, TOL));
        let tiny = circle(DVec2::ZERO, 1e-9, 0.0, 0.1, 100, 0.0);
        assert_eq!(check_all(&tiny, &fit(&tiny, TOL), TOL).1, 0);
        // Odd limits.
        for p in [
            ArcParams { max_points: 0, ..ArcParams::new(TOL) },
            ArcParams { max_points: usize::MAX, ..ArcParams::new(TOL) },
            ArcParams { max_sweep_rad: 100.0, ..ArcParams::new(TOL) },
            ArcParams { min_radius_mm: nan, max_radius_mm: nan, firmware_segment_mm: nan, ..ArcParams::new(TOL) },
        ] {
            check_cover(&ring, &fit_with(&ring, &p));
        }
    }

    #[test]
    fn radius_bounds_follow_the_firmware_chord() {
        // Radius 3 mm: under 1²/(8·0.02) = 6.25 mm, lines by default; an arc once the firmware
        // chords by angle (firmware_segment_mm = 0).
        let small = circle(DVec2::ZERO, 3.0, 0.0, TAU / 120.0, 60, 0.2);
        assert_eq!(check_all(&small, &fit(&small, TOL), TOL).1, 0);
        let p = ArcParams { firmware_segment_mm: 0.0, ..ArcParams::new(TOL) };
        assert_eq!(check_all_with(&small, &fit_with(&small, &p), &p), (0, 1));
        assert_eq!(ArcParams::new(0.02).min_radius(), 6.25);
        assert_eq!(ArcParams::new(1.0).min_radius(), DEFAULT_MIN_RADIUS_MM);
        // Radius 2000 mm: beyond the upper bound, lines.
        let flat = circle(DVec2::ZERO, 2000.0, 0.0, 0.001, 400, 0.2);
        assert_eq!(check_all(&flat, &fit(&flat, TOL), TOL).1, 0);
    }

    #[test]
    fn corner_arcs_take_at_most_one_side_segment() {
        // Sides cut in 1 to 48 collinear segments, corners of 8 mm in 15 to 45 chords: one arc
        // per corner, exactly the corner while side segments are long, at most one short side
        // segment more at each end (within tolerance of the circle) when they are short.
        for cuts in [1, 2, 4, 12, 24, 48] {
            for corner_segs in [15, 30, 45] {
                let (pts, corners) = rounded_square(40.0, 8.0, cuts, corner_segs);
                let moves = fit(&pts, TOL);
                let (lines, arcs) = check_all(&pts, &moves, TOL);
                assert_eq!(arcs, 4, "cuts {cuts}, corner {corner_segs}: {moves:?}");
                let arc_spans = spans(&moves).filter(|(_, m)| matches!(m, Move::Arc { .. })).map(|(s, m)| (s, m.end()));
                for ((s, e), (cs, ce)) in arc_spans.zip(corners) {
                    assert!(s <= cs && s + 1 >= cs && e >= ce && e <= ce + 1, "cuts {cuts}: arc {s}..{e}, corner {cs}..{ce}");
                    if cuts <= 24 {
                        assert_eq!((s, e), (cs, ce));
                    }
                }
                assert_eq!(lines + arcs, moves.len());
            }
        }
    }

    #[test]
    fn arc_helpers() {
        let c = DVec2::new(1.0, 1.0);
        let (a, b) = (DVec2::new(2.0, 1.0), DVec2::new(1.0, 2.0));
        assert!((sweep_angle(a, b, c, false) - FRAC_PI_2).abs() < 1e-12);
        assert!((sweep_angle(a, b, c, true) - 3.0 * FRAC_PI_2).abs() < 1e-12);
        assert!((arc_length(a, b, c, false) - FRAC_PI_2).abs() < 1e-12);
        assert_eq!(sweep_angle(a, a, c, true), TAU);
        assert_eq!(center_offset(a, c), DVec2::new(-1.0, 0.0));
        // The fitted arcs' lengths are those of the circle.
        let pts = circle(DVec2::ZERO, 10.0, 0.0, TAU / 360.0, 360, 0.2);
        let total: f64 = spans(&fit(&pts, TOL))
            .map(|(s, m)| match *m {
                Move::Arc { end, center, clockwise } => arc_length(xy(pts[s]), xy(pts[end]), center, clockwise),
                Move::Line { end } => pts[s].distance(pts[end]),
            })
            .sum();
        assert!((total - TAU * 10.0).abs() < 1e-9, "{total}");
    }
}

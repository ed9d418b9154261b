//! Infill path through uniform (u, θ) points on an axisymmetric platform (the paper's
//! section 2.4): a nearest-neighbour Hamiltonian path from a start point, improved by 2-opt
//! (Croes), each segment drawn as the geodesic between its points.
//!
//! Stages of [`plan`]:
//! 1. 3-D kd-tree of the points and k-nearest candidate lists (chord distance picks the
//!    candidates, the caller's geodesic `dist` ranks them), so NN and each 2-opt pass cost
//!    about n·k·log n, not n².
//! 2. Nearest-neighbour open path from the start (unvisited candidates first; when all are
//!    visited, the kd-tree's nearest live point by chord).
//! 3. 2-opt on the open path with the start kept first: neighbour-list moves, first
//!    improvement, at most `two_opt_passes` passes.
//! 4. Geodesics of the segments, sampled at ≤ `step_mm` in 3-D.
//! 5. Crossing check in the (u, θ) map on the sampled polylines (geodesics bend in the map, so
//!    straight chords are not enough), through a segment grid; each crossing is undone by the
//!    2-opt move that swaps its two segments, for at most `uncross_rounds` rounds. Whatever
//!    remains is reported in [`Tour::crossings_left`], never looped on.
//!
//! Holes: a caller may pass `avoid(a, b)` (true when the straight map segment a → b crosses a
//! hole of the domain). Such a pair costs [`HOLE_PENALTY_MM`] more in the nearest-neighbour
//! choice and in 2-opt (whose candidate lists skip neighbours across a hole), so both route
//! around holes where they can; the segments whose sampled geodesic still crosses a hole are
//! listed in [`Tour::hole_segments`]: the job writes them as travel hops (no extrusion), so
//! nothing is printed over a hole. The lengths reported leave the penalty out.
//!
//! The map check takes each segment's θ unwrapped from its start: a domain spanning the θ seam
//! (θ and θ + 2π both present) is not checked across the seam.
//!
//! Deterministic: ties broken by point index, ordered containers only, `libm` transcendentals.

use super::geodesic::{self, geodesic};
use super::platform::{self, Profile};
use crate::budget::{Estimate, OverBudget};
use serde::{Deserialize, Serialize};
use std::cell::Cell;
use std::collections::{BTreeMap, BTreeSet};
use std::f64::consts::PI;

/// Default sampling step of each segment's geodesic, mm (about a fifth of a 0.4 mm nozzle's
/// spacing is not needed: the geodesic is smooth, 0.5 mm keeps the chord error ≪ 0.01 mm on
/// the presets' ≥ 25 mm radii).
pub const DEFAULT_STEP_MM: f64 = 0.5;
/// Smallest accepted step, mm (below this the samples outnumber any machine's resolution).
pub const MIN_STEP_MM: f64 = 0.01;
/// Largest accepted step, mm (larger than any platform: each segment is then its two ends).
pub const MAX_STEP_MM: f64 = 10_000.0;
/// Default cap of 2-opt passes (each pass is about n·k moves tried; random points converge in
/// well under 20).
pub const DEFAULT_TWO_OPT_PASSES: usize = 50;
/// Default candidate-list length k (Johnson & McGeoch: 8–10 neighbours find nearly all
/// improving 2-opt moves).
pub const DEFAULT_NEIGHBOURS: usize = 10;
/// Largest accepted candidate-list length.
pub const MAX_NEIGHBOURS: usize = 64;
/// Default cap of crossing-removal rounds (one move per round; a crossing left after it is
/// reported, not looped on).
pub const DEFAULT_UNCROSS_ROUNDS: usize = 1000;
/// Most points one tour takes (a uniform infill slice of the paper's size has a few thousand;
/// the 2-opt reversal is O(n) per move, so far more would be slow).
pub const MAX_POINTS: usize = 20_000;
/// Most path samples (poses) one tour may make: 48 bytes each, 2 M ≈ 100 MB with the map
/// samples.
pub const MAX_SAMPLES: f64 = 2e6;
/// Extra cost, mm, of a pair whose straight map segment crosses a hole: more than any path
/// through a few thousand points saves by taking it, so 2-opt trades any detour for it.
pub const HOLE_PENALTY_MM: f64 = 1000.0;
/// Time per point on the reference machine, s: one Clairaut geodesic per segment and its
/// sampling dominate (200 hourglass points take 0.15 s); a safe upper value.
const SECONDS_PER_POINT: f64 = 2e-3;

/// The stage's form rows (paths relative to [`Options`]).
pub const FIELDS: &[crate::settings::Field] = {
    use crate::settings::{choice_docs, int, num, other, when, Kind};
    &[
        choice_docs(
            other("start.kind", "Path", "Start", Kind::Choice, &["corner", "nearest"], "Where the path begins."),
            &["At the point nearest the patch's (u to, θ from) corner, as the paper.", "At the point nearest a (u, θ) you give, e.g. where the walls ended."],
        ),
        when(num("start.u", "Path", "Start near u", "", 0.0, 64.0, 0.01, "Parameter along the profile of the wanted start."), "start.kind", "nearest"),
        when(num("start.theta", "Path", "Start near θ", "rad", -7.0, 7.0, 0.01, "Angle around the axis of the wanted start."), "start.kind", "nearest"),
        num(
            "step_mm",
            "Path",
            "Sample step",
            "mm",
            MIN_STEP_MM,
            MAX_STEP_MM,
            0.1,
            "Each segment follows the surface's shortest curve, written as points this far apart.",
        ),
        int(
            "two_opt_passes",
            "Path",
            "2-opt passes",
            0.0,
            10_000.0,
            "Most rounds of segment swaps that shorten the path (0 keeps the nearest-neighbour path).",
        ),
        int(
            "neighbours",
            "Path",
            "Swap candidates",
            1.0,
            MAX_NEIGHBOURS as f64,
            "How many nearest points each point tries to swap towards (8–10 finds nearly every gain).",
        ),
        int("uncross_rounds", "Path", "Uncrossing rounds", 0.0, 100_000.0, "Most moves spent removing places where the path crosses itself."),
    ]
};

/// Where the path starts.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, Default)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Start {
    /// The point nearest the domain's (u_max, θ_min) corner (the paper's "bottom-right corner"),
    /// distance measured in mm with the metric at u_max.
    #[default]
    Corner,
    /// The point nearest (u, θ) (e.g. where the walls ended), distance in mm with the metric at u.
    Nearest {
        /// Parameter along the generatrix.
        u: f64,
        /// Angle, rad.
        theta: f64,
    },
}

/// Tour settings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Options {
    /// Start point rule (default [`Start::Corner`]).
    pub start: Start,
    /// See [`DEFAULT_STEP_MM`]; within [[`MIN_STEP_MM`], [`MAX_STEP_MM`]].
    pub step_mm: f64,
    /// See [`DEFAULT_TWO_OPT_PASSES`] (0 keeps the NN path).
    pub two_opt_passes: usize,
    /// See [`DEFAULT_NEIGHBOURS`]; 1..=[`MAX_NEIGHBOURS`].
    pub neighbours: usize,
    /// See [`DEFAULT_UNCROSS_ROUNDS`].
    pub uncross_rounds: usize,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            start: Start::Corner,
            step_mm: DEFAULT_STEP_MM,
            two_opt_passes: DEFAULT_TWO_OPT_PASSES,
            neighbours: DEFAULT_NEIGHBOURS,
            uncross_rounds: DEFAULT_UNCROSS_ROUNDS,
        }
    }
}

/// Why a tour could not be planned.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum Error {
    /// No points.
    #[error("no points to join: place points on the platform first")]
    NoPoints,
    /// A point is NaN or infinite.
    #[error("point {index} is not a finite (u, θ) pair; give u and θ as numbers")]
    NotFinite {
        /// Point index.
        index: usize,
    },
    /// A point is off the platform or too near its pole.
    #[error("point {index} cannot be used: {source}")]
    Point {
        /// Point index.
        index: usize,
        /// The platform's reason.
        source: super::Error,
    },
    /// An option out of range.
    #[error("option {name} = {value} is out of range: {hint}")]
    BadOption {
        /// Option name.
        name: &'static str,
        /// Value given.
        value: f64,
        /// Allowed range.
        hint: &'static str,
    },
    /// The distance function returned NaN, ∞ or a negative value.
    #[error("the distance from point {from} to point {to} came out as {value}; the distance function must return a finite length ≥ 0 mm")]
    BadDistance {
        /// First point index.
        from: usize,
        /// Second point index.
        to: usize,
        /// Value returned.
        value: f64,
    },
    /// A segment's geodesic failed.
    #[error("the geodesic from point {from} to point {to} failed: {source}")]
    Geodesic {
        /// First point index.
        from: usize,
        /// Second point index.
        to: usize,
        /// The solver's reason.
        source: super::Error,
    },
    /// Over a stated limit (points, samples, memory, time).
    #[error(transparent)]
    OverBudget(#[from] OverBudget),
}

/// A tool pose: tip position and tool axis.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Pose {
    /// Tip position, mm.
    pub position: [f64; 3],
    /// Outward unit normal of the platform = tool axis from the tip toward the head.
    pub normal: [f64; 3],
}

/// A planned path.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Tour {
    /// Point indices in path order; `order[0]` is the start.
    pub order: Vec<usize>,
    /// Length after 2-opt and crossing removal, by the caller's `dist`, mm.
    pub length_mm: f64,
    /// Length of the nearest-neighbour path (before 2-opt), by `dist`, mm.
    pub nn_length_mm: f64,
    /// Length of the sampled geodesics (sum of the geodesic solver's lengths), mm.
    pub geodesic_length_mm: f64,
    /// 2-opt passes run.
    pub two_opt_passes: usize,
    /// 2-opt moves applied.
    pub two_opt_moves: usize,
    /// Crossings found in the map after 2-opt minus those left.
    pub crossings_removed: usize,
    /// Crossings left (0 unless `uncross_rounds` ran out or two consecutive geodesics cross).
    pub crossings_left: usize,
    /// Segments whose sampled geodesic crosses a hole (by the caller's `avoid`; 0 without).
    pub hole_crossings: usize,
    /// Which segments (index k: `order[k] → order[k + 1]`) those are, ascending.
    pub hole_segments: Vec<usize>,
    /// Per segment `order[k] → order[k + 1]`: its geodesic sampled in (u, θ), ends included
    /// (θ unwrapped from the segment's start).
    pub samples: Vec<Vec<[f64; 2]>>,
    /// The whole path in order, joints not repeated.
    pub poses: Vec<Pose>,
}

/// The work a tour of `n_points` points about `spacing_mm` apart states before it runs
/// (the point limit first, then the samples: segments ≈ 1.5 spacings long, one sample per
/// step).
pub fn estimate(n_points: usize, o: &Options, spacing_mm: f64) -> Estimate {
    let n = n_points as f64;
    let k = o.neighbours.clamp(1, MAX_NEIGHBOURS) as f64;
    let samples = n * (1.0 + (1.5 * spacing_mm / o.step_mm.max(MIN_STEP_MM)).ceil());
    // Candidates (index + distance), kd-tree, order and position arrays per point; a pose
    // and a map sample per sample.
    let bytes = n * (k * 16.0 + 96.0) + samples * 64.0;
    Estimate::new("tour")
        .quantity("points", "points joined", n, "")
        .quantity("samples", "path samples (tool poses)", samples, "")
        .cost(bytes, n * SECONDS_PER_POINT + samples * 2e-7)
        .limit("points in one tour", n, MAX_POINTS as f64, "", "lower the infill density or split the domain")
        .limit("path samples", samples, MAX_SAMPLES, "", "raise the sample step")
        .budgets("lower the infill density or split the domain")
}

/// A test of whether the straight map segment between two (u, θ) points crosses a hole.
pub type Avoid<'a> = &'a dyn Fn([f64; 2], [f64; 2]) -> bool;

/// A sampled path in the (u, θ) map.
type MapPath = Vec<[f64; 2]>;

/// Sampled geodesics per unordered pair of points (lower index first): length and path.
type GeodesicCache = BTreeMap<(usize, usize), (f64, MapPath)>;

/// Plans the path through `points` (u, θ) on `p` (the platform, or an offset of it). `dist` is
/// the geodesic distance (mm) between two points; `avoid`, when given, marks pairs whose
/// segment would cross a hole (see the module notes); `progress` gets 0..=1.
pub fn plan(
    p: &dyn Profile,
    points: &[[f64; 2]],
    o: &Options,
    dist: &dyn Fn([f64; 2], [f64; 2]) -> f64,
    avoid: Option<Avoid>,
    progress: &mut dyn FnMut(f32),
) -> Result<Tour, Error> {
    check_options(o)?;
    if points.is_empty() {
        return Err(Error::NoPoints);
    }
    // The samples are checked once the path length is known (below).
    estimate(points.len(), o, 0.0).check()?;
    if let Some(index) = points.iter().position(|q| !q[0].is_finite() || !q[1].is_finite()) {
        return Err(Error::NotFinite { index });
    }
    for (index, q) in points.iter().enumerate() {
        platform::check_domain(p, q[0], q[0], platform::DEFAULT_MIN_POLE_RADIUS_MM).map_err(|source| Error::Point { index, source })?;
    }
    let n = points.len();
    let start = start_point(p, points, &o.start);
    let pose = |q: [f64; 2], sign: f64| {
        let m = platform::normal(p, q[0], q[1]);
        Pose { position: platform::position(p, q[0], q[1]), normal: [sign * m[0], sign * m[1], sign * m[2]] }
    };
    let sign = outward_sign(p);
    if n == 1 {
        progress(1.0);
        return Ok(Tour {
            order: vec![0],
            length_mm: 0.0,
            nn_length_mm: 0.0,
            geodesic_length_mm: 0.0,
            two_opt_passes: 0,
            two_opt_moves: 0,
            crossings_removed: 0,
            crossings_left: 0,
            hole_crossings: 0,
            hole_segments: Vec::new(),
            samples: Vec::new(),
            poses: vec![pose(points[0], sign)],
        });
    }

    // Symmetric, checked distance: always asked from the lower index so a solver's small
    // asymmetry cannot make a 2-opt move look improving both ways.
    let bad: Cell<Option<(usize, usize, f64)>> = Cell::new(None);
    let crosses = |i: usize, j: usize| i != j && avoid.is_some_and(|f| f(points[i.min(j)], points[i.max(j)]));
    let raw = |i: usize, j: usize| -> f64 {
        let (a, b) = if i < j { (i, j) } else { (j, i) };
        if a == b {
            return 0.0;
        }
        let v = dist(points[a], points[b]);
        if v.is_finite() && v >= 0.0 {
            if crosses(a, b) {
                v + HOLE_PENALTY_MM
            } else {
                v
            }
        } else {
            if bad.get().is_none() {
                bad.set(Some((a, b, v)));
            }
            f64::INFINITY
        }
    };
    let check_bad = || match bad.get() {
        Some((from, to, value)) => Err(Error::BadDistance { from, to, value }),
        None => Ok(()),
    };

    let xyz: Vec<[f64; 3]> = points.iter().map(|q| platform::position(p, q[0], q[1])).collect();
    let mut kd = Kd::new(&xyz);
    let k = o.neighbours.min(n - 1);
    let mut cand: Vec<usize> = Vec::with_capacity(n * k);
    for i in 0..n {
        if avoid.is_none() {
            cand.extend(kd.knn(xyz[i], i, k));
            continue;
        }
        // Beside a hole the nearest points across it are useless candidates: draw from 4k
        // and keep the k nearest reachable without crossing (then the others, if short).
        let wide = kd.knn(xyz[i], i, (4 * k).min(n - 1));
        let (ok, over): (Vec<usize>, Vec<usize>) = wide.into_iter().partition(|&c| !crosses(i, c));
        cand.extend(ok.into_iter().chain(over).take(k));
    }
    let cand_d: Vec<f64> = (0..n * k).map(|e| raw(e / k, cand[e])).collect();
    check_bad()?;
    progress(0.1);
    let dd = |i: usize, j: usize| -> f64 {
        if let Some(e) = cand[i * k..(i + 1) * k].iter().position(|&c| c == j) {
            return cand_d[i * k + e];
        }
        raw(i, j)
    };

    // Nearest-neighbour path.
    let mut order = Vec::with_capacity(n);
    let mut visited = vec![false; n];
    let mut cur = start;
    loop {
        visited[cur] = true;
        kd.remove(cur);
        order.push(cur);
        if order.len() == n {
            break;
        }
        let mut best: Option<(f64, usize)> = None;
        for e in cur * k..(cur + 1) * k {
            let c = cand[e];
            if !visited[c] && best.is_none_or(|(bd, bi)| cand_d[e] < bd || (cand_d[e] == bd && c < bi)) {
                best = Some((cand_d[e], c));
            }
        }
        cur = match best {
            Some((_, c)) => c,
            None => kd.nearest_live(xyz[cur]),
        };
    }
    // The length without the hole penalty (what is printed).
    let path_len = |t: &[usize]| t.windows(2).map(|w| dd(w[0], w[1]) - if crosses(w[0], w[1]) { HOLE_PENALTY_MM } else { 0.0 }).sum::<f64>();
    let nn_length_mm = path_len(&order);
    check_bad()?;
    progress(0.25);

    // 2-opt.
    let mut pos = vec![0; n];
    for (i, &v) in order.iter().enumerate() {
        pos[v] = i;
    }
    let (passes, moves) = two_opt(&mut order, &mut pos, &cand, k, &dd, o.two_opt_passes, progress);
    check_bad()?;
    progress(0.6);

    // State the samples before making them: the path length by `dist` over the step, plus the
    // ends, plus room for geodesics longer than `dist` says.
    let est_samples = 1.5 * (path_len(&order) / o.step_mm + 2.0 * n as f64);
    Estimate::new("tour")
        .quantity("samples", "path samples", est_samples, "")
        .limit("path samples", est_samples, MAX_SAMPLES, "", "raise step_mm or lower the infill density")
        .check()?;

    // Geodesics, cached per unordered pair (computed from the lower index for determinism).
    let mut cache: GeodesicCache = BTreeMap::new();
    let gopts = geodesic::Options::default();
    let segment = |i: usize, j: usize, cache: &mut GeodesicCache| -> Result<(f64, MapPath), Error> {
        let (a, b) = if i < j { (i, j) } else { (j, i) };
        if let std::collections::btree_map::Entry::Vacant(e) = cache.entry((a, b)) {
            let s = sample_geodesic(p, points[a], points[b], raw(a, b) - if crosses(a, b) { HOLE_PENALTY_MM } else { 0.0 }, o.step_mm, &gopts)
                .map_err(|source| Error::Geodesic { from: a, to: b, source })?;
            e.insert(s);
        }
        let (len, path) = &cache[&(a, b)];
        let mut path = path.clone();
        if i > a {
            path.reverse();
            // Start exactly at point i, θ shifted by whole turns only.
            let turns = libm::round((path[0][1] - points[i][1]) / (2.0 * PI));
            for q in &mut path {
                q[1] -= turns * 2.0 * PI;
            }
            path[0] = points[i];
        }
        Ok((*len, path))
    };
    let build = |order: &[usize], cache: &mut GeodesicCache| -> Result<(f64, Vec<MapPath>), Error> {
        let mut total = 0.0;
        let mut out = Vec::with_capacity(order.len() - 1);
        for w in order.windows(2) {
            let (len, path) = segment(w[0], w[1], cache)?;
            total += len;
            out.push(path);
        }
        Ok((total, out))
    };
    let (mut geodesic_length_mm, mut samples) = build(&order, &mut cache)?;
    check_bad()?;
    progress(0.85);

    // Crossings in the map.
    let found = crossings(&samples);
    let mut now = found.clone();
    for _ in 0..o.uncross_rounds {
        // Two consecutive segments cannot be swapped by 2-opt: take the first other pair
        // whose swap does not bring in a segment over a hole (without holes: the first).
        let Some(&(i, j)) =
            now.iter().find(|&&(i, j)| j > i + 1 && !crosses(order[i], order[j]) && (j + 1 >= order.len() || !crosses(order[i + 1], order[j + 1])))
        else {
            break;
        };
        order[i + 1..=j].reverse();
        (geodesic_length_mm, samples) = build(&order, &mut cache)?;
        now = crossings(&samples);
    }
    check_bad()?;
    let length_mm = path_len(&order);
    progress(0.95);

    let hole_segments: Vec<usize> = match avoid {
        Some(f) => (0..samples.len()).filter(|&k| samples[k].windows(2).any(|w| f(w[0], w[1]))).collect(),
        None => Vec::new(),
    };
    let hole_crossings = hole_segments.len();
    let mut poses = Vec::with_capacity(samples.iter().map(|s| s.len()).sum::<usize>());
    for (s, seg) in samples.iter().enumerate() {
        for &q in &seg[if s == 0 { 0 } else { 1 }..] {
            poses.push(pose(q, sign));
        }
    }
    progress(1.0);
    Ok(Tour {
        order,
        length_mm,
        nn_length_mm,
        geodesic_length_mm,
        two_opt_passes: passes,
        two_opt_moves: moves,
        crossings_removed: found.len().saturating_sub(now.len()),
        crossings_left: now.len(),
        hole_crossings,
        hole_segments,
        samples,
        poses,
    })
}

fn check_options(o: &Options) -> Result<(), Error> {
    if !(MIN_STEP_MM..=MAX_STEP_MM).contains(&o.step_mm) {
        return Err(Error::BadOption { name: "step_mm", value: o.step_mm, hint: "give a step between 0.01 and 10 000 mm (0.5 mm is typical)" });
    }
    if !(1..=MAX_NEIGHBOURS).contains(&o.neighbours) {
        return Err(Error::BadOption { name: "neighbours", value: o.neighbours as f64, hint: "give 1 to 64 candidates per point (10 is typical)" });
    }
    if let Start::Nearest { u, theta } = o.start {
        if !u.is_finite() {
            return Err(Error::BadOption { name: "start.u", value: u, hint: "give a finite u" });
        }
        if !theta.is_finite() {
            return Err(Error::BadOption { name: "start.theta", value: theta, hint: "give a finite θ in radians" });
        }
    }
    Ok(())
}

/// Index of the start point: nearest (in mm, metric at the target's u, θ wrapped) to the
/// corner or the given point; lowest index on ties.
fn start_point(p: &dyn Profile, points: &[[f64; 2]], s: &Start) -> usize {
    let target = match *s {
        Start::Corner => {
            let u = points.iter().map(|q| q[0]).fold(f64::NEG_INFINITY, f64::max);
            let t = points.iter().map(|q| q[1]).fold(f64::INFINITY, f64::min);
            [u, t]
        }
        Start::Nearest { u, theta } => [u, theta],
    };
    let (lo, hi) = p.u_range();
    let j = p.jet(target[0].clamp(lo, hi));
    let (su, st) = (libm::hypot(j.x[1], j.z[1]), j.x[0].abs());
    let mut best = (f64::INFINITY, 0);
    for (i, q) in points.iter().enumerate() {
        let dt = libm::remainder(q[1] - target[1], 2.0 * PI);
        let d = ((q[0] - target[0]) * su).powi(2) + (dt * st).powi(2);
        if d < best.0 {
            best = (d, i);
        }
    }
    best.1
}

/// +1 when r_u × r_θ points out of the solid the generatrix bounds with the axis, else −1:
/// the closed curve (generatrix, then back along the axis) is clockwise in (x, z) exactly when
/// the left-hand normal (−z′, x′) points outward.
fn outward_sign(p: &dyn Profile) -> f64 {
    let (lo, hi) = p.u_range();
    // 64 samples per unit u (per Bézier segment on a platform).
    let m = 64 * libm::ceil(hi - lo).max(1.0) as usize;
    let pt = |i: usize| {
        let j = p.jet(lo + (hi - lo) * i as f64 / m as f64);
        [j.x[0], j.z[0]]
    };
    let mut curve: Vec<[f64; 2]> = (0..=m).map(pt).collect();
    let (first, last) = (curve[0], curve[m]);
    curve.push([0.0, last[1]]);
    curve.push([0.0, first[1]]);
    let mut area2 = 0.0;
    for w in 0..curve.len() {
        let (a, b) = (curve[w], curve[(w + 1) % curve.len()]);
        area2 += a[0] * b[1] - b[0] * a[1];
    }
    if area2 <= 0.0 {
        1.0
    } else {
        -1.0
    }
}

/// Geodesic a → b sampled so that consecutive samples are ≤ `step` apart in 3-D, ends exact.
fn sample_geodesic(p: &dyn Profile, a: [f64; 2], b: [f64; 2], est_len: f64, step: f64, o: &geodesic::Options) -> Result<(f64, Vec<[f64; 2]>), super::Error> {
    // The ODE path has one sample per RK4 step at most; finer sampling comes from bisection.
    let m = if est_len.is_finite() { libm::ceil(2.0 * est_len / step) as usize + 1 } else { 3 };
    let g = geodesic(p, a, b, &geodesic::Options { path_samples: m.clamp(3, o.ode_steps + 1), ..o.clone() })?;
    let mut path = g.path;
    path[0] = a;
    let last = path.len() - 1;
    let turns = libm::round((path[last][1] - b[1]) / (2.0 * PI));
    path[last] = [b[0], b[1] + turns * 2.0 * PI];
    // Dense: bisect (linearly in the map, between geodesic samples) to ≤ step/2 in 3-D.
    let at = |q: [f64; 2]| platform::position(p, q[0], q[1]);
    let mut dense = vec![path[0]];
    for w in path.windows(2) {
        bisect(&at, w[0], w[1], at(w[0]), at(w[1]), 0.5 * step, 40, &mut dense);
    }
    // Thin: keep the farthest dense sample within `step` of the last kept one.
    let mut out = vec![dense[0]];
    let mut kept = at(dense[0]);
    let mut i = 0;
    while i + 1 < dense.len() {
        let mut j = i + 1;
        while j + 1 < dense.len() && chord(kept, at(dense[j + 1])) <= step {
            j += 1;
        }
        out.push(dense[j]);
        kept = at(dense[j]);
        i = j;
    }
    Ok((g.length_mm, out))
}

#[allow(clippy::too_many_arguments)]
fn bisect(at: &dyn Fn([f64; 2]) -> [f64; 3], a: [f64; 2], b: [f64; 2], pa: [f64; 3], pb: [f64; 3], h: f64, depth: u32, out: &mut Vec<[f64; 2]>) {
    if depth == 0 || chord(pa, pb) <= h {
        out.push(b);
        return;
    }
    let m = [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])];
    let pm = at(m);
    bisect(at, a, m, pa, pm, h, depth - 1, out);
    bisect(at, m, b, pm, pb, h, depth - 1, out);
}

fn chord(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// Neighbour-list 2-opt on the open path `t` (t[0] fixed), first improvement. Returns
/// (passes, moves).
fn two_opt(
    t: &mut [usize],
    pos: &mut [usize],
    cand: &[usize],
    k: usize,
    dd: &dyn Fn(usize, usize) -> f64,
    passes: usize,
    progress: &mut dyn FnMut(f32),
) -> (usize, usize) {
    let n = t.len();
    let mut moves = 0;
    let mut used = 0;
    let reverse = |t: &mut [usize], pos: &mut [usize], l: usize, r: usize| {
        t[l..=r].reverse();
        for (i, &v) in t[l..=r].iter().enumerate() {
            pos[v] = l + i;
        }
    };
    // Strict improvement by more than rounding: every move shortens the path, so no cycling.
    let tol = |x: f64| 1e-9 * (1.0 + x);
    for pass in 0..passes {
        used = pass + 1;
        let mut improved = false;
        let mut i = 0;
        while i + 1 < n {
            let (a, b) = (t[i], t[i + 1]);
            let dab = dd(a, b);
            let mut moved = false;
            // New edge (a, c).
            for &c in &cand[a * k..(a + 1) * k] {
                let dac = dd(a, c);
                if dac >= dab {
                    continue;
                }
                let j = pos[c];
                if j > i + 1 {
                    // Reverse t[i+1..=j]: (a,b),(c,t[j+1]) → (a,c),(b,t[j+1]); open end if j = n−1.
                    let gain = if j + 1 < n { dab + dd(c, t[j + 1]) - dac - dd(b, t[j + 1]) } else { dab - dac };
                    if gain > tol(dab) {
                        reverse(t, pos, i + 1, j);
                        moved = true;
                        break;
                    }
                } else if j < i {
                    // Reverse t[j+1..=i]: (c,e),(a,b) → (c,a),(e,b).
                    let e = t[j + 1];
                    let gain = dab + dd(c, e) - dac - dd(e, b);
                    if gain > tol(dab) {
                        reverse(t, pos, j + 1, i);
                        moved = true;
                        break;
                    }
                }
            }
            if !moved {
                // New edge (b, c).
                for &c in &cand[b * k..(b + 1) * k] {
                    let dbc = dd(b, c);
                    if dbc >= dab {
                        continue;
                    }
                    let j = pos[c];
                    if j > i + 2 {
                        // Reverse t[i+1..=j−1]: (a,b),(e,c) → (a,e),(b,c).
                        let e = t[j - 1];
                        let gain = dab + dd(e, c) - dd(a, e) - dbc;
                        if gain > tol(dab) {
                            reverse(t, pos, i + 1, j - 1);
                            moved = true;
                            break;
                        }
                    } else if j < i && j >= 1 {
                        // Reverse t[j..=i]: (e,c),(a,b) → (e,a),(c,b); t[0] stays.
                        let e = t[j - 1];
                        let gain = dab + dd(e, c) - dd(e, a) - dbc;
                        if gain > tol(dab) {
                            reverse(t, pos, j, i);
                            moved = true;
                            break;
                        }
                    }
                }
            }
            if moved {
                moves += 1;
                improved = true;
            } else {
                i += 1;
            }
        }
        progress(0.25 + 0.35 * (pass + 1) as f32 / passes as f32);
        if !improved {
            break;
        }
    }
    (used, moves)
}

/// Pairs (i < j) of segments whose sampled polylines cross properly in the (u, θ) map, sorted.
/// Consecutive segments meeting at their shared point do not count.
pub fn crossings(samples: &[Vec<[f64; 2]>]) -> Vec<(usize, usize)> {
    let mut pieces: Vec<(usize, usize)> = Vec::new(); // (segment, piece index)
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for (s, seg) in samples.iter().enumerate() {
        for (q, w) in seg.windows(2).enumerate() {
            pieces.push((s, q));
            for v in w {
                for d in 0..2 {
                    lo[d] = lo[d].min(v[d]);
                    hi[d] = hi[d].max(v[d]);
                }
            }
        }
    }
    if pieces.len() < 2 {
        return Vec::new();
    }
    // About one piece per cell, cells shaped like the bounding box.
    let (w, h) = ((hi[0] - lo[0]).max(1e-12), (hi[1] - lo[1]).max(1e-12));
    let np = pieces.len() as f64;
    let nx = (libm::ceil((np * w / h).sqrt()) as usize).clamp(1, 4096);
    let ny = (libm::ceil((np * h / w).sqrt()) as usize).clamp(1, 4096);
    let cell = |v: f64, d: usize, m: usize| (((v - lo[d]) / (hi[d] - lo[d]).max(1e-300) * m as f64) as usize).min(m - 1);
    let mut cells: Vec<Vec<u32>> = vec![Vec::new(); nx * ny];
    for (id, &(s, q)) in pieces.iter().enumerate() {
        let (a, b) = (samples[s][q], samples[s][q + 1]);
        let (x0, x1) = (cell(a[0].min(b[0]), 0, nx), cell(a[0].max(b[0]), 0, nx));
        let (y0, y1) = (cell(a[1].min(b[1]), 1, ny), cell(a[1].max(b[1]), 1, ny));
        for x in x0..=x1 {
            for y in y0..=y1 {
                cells[x * ny + y].push(id as u32);
            }
        }
    }
    let mut found = BTreeSet::new();
    for c in &cells {
        for (ia, &pa) in c.iter().enumerate() {
            let (sa, qa) = pieces[pa as usize];
            for &pb in &c[ia + 1..] {
                let (sb, qb) = pieces[pb as usize];
                if sa == sb || found.contains(&(sa.min(sb), sa.max(sb))) {
                    continue;
                }
                if proper(samples[sa][qa], samples[sa][qa + 1], samples[sb][qb], samples[sb][qb + 1]) {
                    found.insert((sa.min(sb), sa.max(sb)));
                }
            }
        }
    }
    found.into_iter().collect()
}

/// Segments ab and cd cross at one interior point of both (touching does not count).
pub fn proper(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> bool {
    let orient = |p: [f64; 2], q: [f64; 2], r: [f64; 2]| (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0]);
    let (o1, o2) = (orient(a, b, c), orient(a, b, d));
    let (o3, o4) = (orient(c, d, a), orient(c, d, b));
    ((o1 > 0.0 && o2 < 0.0) || (o1 < 0.0 && o2 > 0.0)) && ((o3 > 0.0 && o4 < 0.0) || (o3 < 0.0 && o4 > 0.0))
}

/// Implicit 3-D kd-tree (median splits on the widest axis) with live counts for the
/// nearest-unvisited query.
struct Kd<'a> {
    pts: &'a [[f64; 3]],
    idx: Vec<usize>,
    axis: Vec<u8>,
    /// Live points in the subtree rooted at slot m.
    live_count: Vec<usize>,
    live: Vec<bool>,
    slot: Vec<usize>,
}

impl<'a> Kd<'a> {
    fn new(pts: &'a [[f64; 3]]) -> Kd<'a> {
        let n = pts.len();
        let mut kd = Kd { pts, idx: (0..n).collect(), axis: vec![0; n], live_count: vec![0; n], live: vec![true; n], slot: vec![0; n] };
        kd.build(0, n);
        for (s, &i) in kd.idx.iter().enumerate() {
            kd.slot[i] = s;
        }
        kd
    }

    fn build(&mut self, lo: usize, hi: usize) {
        if lo >= hi {
            return;
        }
        let (mut a, mut b) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for &i in &self.idx[lo..hi] {
            for d in 0..3 {
                a[d] = a[d].min(self.pts[i][d]);
                b[d] = b[d].max(self.pts[i][d]);
            }
        }
        let ax = (0..3).fold(0, |m, d| if b[d] - a[d] > b[m] - a[m] { d } else { m });
        let mid = lo + (hi - lo) / 2;
        let pts = self.pts;
        self.idx[lo..hi].select_nth_unstable_by(mid - lo, |&x, &y| pts[x][ax].total_cmp(&pts[y][ax]).then(x.cmp(&y)));
        self.axis[mid] = ax as u8;
        self.live_count[mid] = hi - lo;
        self.build(lo, mid);
        self.build(mid + 1, hi);
    }

    fn d2(&self, q: [f64; 3], i: usize) -> f64 {
        let p = self.pts[i];
        (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)
    }

    /// The k nearest points to q other than `me`, by (distance, index).
    fn knn(&self, q: [f64; 3], me: usize, k: usize) -> Vec<usize> {
        let mut best: Vec<(f64, usize)> = Vec::with_capacity(k + 1);
        self.knn_rec(0, self.pts.len(), q, me, k, &mut best);
        best.into_iter().map(|(_, i)| i).collect()
    }

    fn knn_rec(&self, lo: usize, hi: usize, q: [f64; 3], me: usize, k: usize, best: &mut Vec<(f64, usize)>) {
        if lo >= hi {
            return;
        }
        let mid = lo + (hi - lo) / 2;
        let i = self.idx[mid];
        if i != me {
            let d = self.d2(q, i);
            if best.len() < k || (d, i) < best[k - 1] {
                let at = best.partition_point(|&e| e < (d, i));
                best.insert(at, (d, i));
                best.truncate(k);
            }
        }
        let ax = self.axis[mid] as usize;
        let diff = q[ax] - self.pts[i][ax];
        let (near, far) = if diff < 0.0 { ((lo, mid), (mid + 1, hi)) } else { ((mid + 1, hi), (lo, mid)) };
        self.knn_rec(near.0, near.1, q, me, k, best);
        if best.len() < k || diff * diff <= best[k - 1].0 {
            self.knn_rec(far.0, far.1, q, me, k, best);
        }
    }

    fn remove(&mut self, p: usize) {
        self.live[p] = false;
        let (mut lo, mut hi) = (0, self.pts.len());
        let s = self.slot[p];
        while lo < hi {
            let mid = lo + (hi - lo) / 2;
            self.live_count[mid] -= 1;
            if mid == s {
                break;
            }
            if s < mid {
                hi = mid
            } else {
                lo = mid + 1
            }
        }
    }

    /// Nearest live point to q (call only while one is live).
    fn nearest_live(&self, q: [f64; 3]) -> usize {
        let mut best = (f64::INFINITY, usize::MAX);
        self.near_rec(0, self.pts.len(), q, &mut best);
        best.1
    }

    fn near_rec(&self, lo: usize, hi: usize, q: [f64; 3], best: &mut (f64, usize)) {
        if lo >= hi {
            return;
        }
        let mid = lo + (hi - lo) / 2;
        if self.live_count[mid] == 0 {
            return;
        }
        let i = self.idx[mid];
        if self.live[i] {
            let d = self.d2(q, i);
            if (d, i) < *best {
                *best = (d, i);
            }
        }
        let ax = self.axis[mid] as usize;
        let diff = q[ax] - self.pts[i][ax];
        let (near, far) = if diff < 0.0 { ((lo, mid), (mid + 1, hi)) } else { ((mid + 1, hi), (lo, mid)) };
        self.near_rec(near.0, near.1, q, best);
        if diff * diff <= best.0 {
            self.near_rec(far.0, far.1, q, best);
        }
    }
}

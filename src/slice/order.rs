//! Print order within a layer, and seams.
//!
//! Regions: nearest neighbour (distance from the current nozzle position to the region's
//! bounding box), starting from where the previous layer ended. Inside a region: perimeters
//! from the innermost level outwards, external perimeter last (inner-first keeps the visible
//! outer wall from being pushed around by later loops), then infill. Loops of one level and
//! infill polylines are each taken nearest-first (a loop by its seam); a polyline is reversed
//! when its far end is nearer. Ties break on index, so the order is deterministic.
//!
//! Seams ([`Seam`]): each external loop's start is chosen by the mode (aligned: nearest the
//! seam of the layer below, which is why this runs layer after layer, carrying [`Seams`]);
//! inner loops start at their vertex nearest the region's external seam, so a layer has its
//! seam in one place. `nearest` starts every loop at its vertex nearest the nozzle. A loop is
//! then split where its overhang class changes ([`Loop::over`]) into paths that continue one
//! another.

use super::Seam;
use crate::geom::{DVec2, DVec3, Feature, Path};

/// One perimeter loop, implicitly closed, mm: `over[k]` is whether segment `k` (from `pts[k]`
/// to the next point, the last to the first) hangs over air.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct Loop {
    pub pts: Vec<DVec2>,
    pub over: Vec<bool>,
}

impl Loop {
    /// A loop that rests on the layer below everywhere.
    pub(crate) fn plain(pts: Vec<DVec2>) -> Loop {
        let over = vec![false; pts.len()];
        Loop { pts, over }
    }
}

/// The material of one region, ready to be ordered.
#[derive(Clone, Debug, Default)]
pub(crate) struct RegionWork {
    /// Bounding box of the region, mm: min, max.
    pub min: DVec2,
    pub max: DVec2,
    /// Perimeter loops by level (0 = external).
    pub perimeters: Vec<Vec<Loop>>,
    /// Infill polylines, mm.
    pub infill: Vec<(Feature, Vec<DVec2>)>,
}

/// Seam choice carried from layer to layer.
#[derive(Clone, Debug, Default)]
pub(crate) struct Seams {
    mode: Seam,
    /// Index of the layer being ordered.
    layer: u64,
    /// The external seams of the layer below.
    prev: Vec<DVec2>,
    cur: Vec<DVec2>,
}

impl Seams {
    pub(crate) fn new(mode: Seam) -> Seams {
        Seams { mode, ..Seams::default() }
    }
}

/// Farthest the seam of the layer below may be from a loop to steer it (aligned), mm.
const ALIGN_REACH_MM: f64 = 3.0;
/// A concave corner turning at least this much (radians, 20°) takes the first seam.
const MIN_CORNER: f64 = 0.35;

pub(crate) fn box_dist2(p: DVec2, min: DVec2, max: DVec2) -> f64 {
    let d = (min - p).max(p - max).max(DVec2::ZERO);
    d.length_squared()
}

/// Orders the regions' paths; `pos` is the nozzle position, updated to the last point.
/// Layers must be ordered bottom to top with the same `seams`.
pub(crate) fn order_layer(regions: Vec<RegionWork>, pos: &mut DVec2, z: f64, width: f64, seams: &mut Seams) -> Vec<Path> {
    let mut paths = Vec::new();
    let mut left: Vec<Option<RegionWork>> = regions.into_iter().map(Some).collect();
    // External loops numbered in the regions' given order (the random seam's seed).
    let mut firsts = Vec::with_capacity(left.len());
    let mut count = 0u64;
    for r in left.iter_mut().flatten() {
        for level in &mut r.perimeters {
            level.retain(|l| l.pts.len() >= 2);
        }
        firsts.push(count);
        count += r.perimeters.first().map_or(0, |l| l.len()) as u64;
    }
    for _ in 0..left.len() {
        let mut best: Option<(f64, usize)> = None;
        for (i, r) in left.iter().enumerate() {
            if let Some(r) = r {
                let d = box_dist2(*pos, r.min, r.max);
                if best.is_none_or(|(bd, _)| d < bd) {
                    best = Some((d, i));
                }
            }
        }
        let Some((_, i)) = best else { break };
        let r = left[i].take().unwrap_or_default();
        let fixed = fixed_seams(&r.perimeters, seams, firsts[i], width);
        let mk = |pts: Vec<DVec2>, feature: Feature| Path::new(pts.into_iter().map(|p| DVec3::new(p.x, p.y, z)).collect(), feature, width);
        let mut fixed = fixed.map(|f| f.into_iter().map(Some).collect::<Vec<_>>());
        for (level, loops) in r.perimeters.into_iter().enumerate().rev() {
            let feature = if level == 0 { Feature::ExternalPerimeter } else { Feature::Perimeter };
            let at = fixed.as_mut().and_then(|f| f[level].take());
            for (l, k, p) in order_loops(loops, at, pos) {
                for (over, pts) in start_loop(l, k, p, width) {
                    paths.push(mk(pts, if over { Feature::OverhangPerimeter } else { feature }));
                }
            }
        }
        for (feature, pts) in order_polylines(r.infill, pos) {
            paths.push(mk(pts, feature));
        }
    }
    seams.prev = std::mem::take(&mut seams.cur);
    seams.layer += 1;
    paths
}

/// Skirt and brim loops in the order given (outside in), each started at its vertex nearest
/// the nozzle and closed; `pos` ends at the last one's end.
pub(crate) fn order_skirt(loops: Vec<Vec<DVec2>>, pos: &mut DVec2, z: f64, width: f64) -> Vec<Path> {
    let mut paths = Vec::with_capacity(loops.len());
    for l in loops {
        if l.len() < 2 {
            continue;
        }
        for (l, k, p) in order_loops(vec![Loop::plain(l)], None, pos) {
            for (_, pts) in start_loop(l, k, p, width) {
                paths.push(Path::new(pts.into_iter().map(|p| DVec3::new(p.x, p.y, z)).collect(), Feature::Skirt, width));
            }
        }
    }
    paths
}

/// The seam of every loop of a region by level (segment index, point on it), or `None` for
/// `nearest` (chosen from the nozzle as the loops are ordered). Records the external seams.
fn fixed_seams(levels: &[Vec<Loop>], seams: &mut Seams, first: u64, width: f64) -> Option<Vec<Vec<(usize, DVec2)>>> {
    if seams.mode == Seam::Nearest {
        return None;
    }
    let ext: Vec<(usize, DVec2)> = levels
        .first()
        .map(|ls| {
            ls.iter()
                .enumerate()
                .map(|(j, l)| match seams.mode {
                    Seam::Rear => rear(&l.pts),
                    Seam::Random => random(&l.pts, seams.layer, first + j as u64),
                    _ => aligned(&l.pts, &seams.prev, width),
                })
                .collect()
        })
        .unwrap_or_default();
    seams.cur.extend(ext.iter().map(|s| s.1));
    let mut out = vec![ext];
    for ls in levels.iter().skip(1) {
        out.push(
            ls.iter()
                .map(|l| {
                    let mut best: Option<(f64, usize)> = None;
                    for (k, p) in l.pts.iter().enumerate() {
                        for (_, q) in &out[0] {
                            let d = p.distance_squared(*q);
                            if best.is_none_or(|(bd, _)| d < bd) {
                                best = Some((d, k));
                            }
                        }
                    }
                    let k = best.map_or(0, |b| b.1);
                    (k, l.pts[k])
                })
                .collect(),
        );
    }
    Some(out)
}

/// Turn at vertex `k` (radians, left positive) between the points about `reach` mm before
/// and after it.
fn turn(pts: &[DVec2], k: usize, reach: f64) -> f64 {
    let n = pts.len();
    let v = pts[k];
    let (mut a, mut b) = (v, v);
    for s in 1..n {
        a = pts[(k + n - s) % n];
        if a.distance(v) >= reach {
            break;
        }
    }
    for s in 1..n {
        b = pts[(k + s) % n];
        if b.distance(v) >= reach {
            break;
        }
    }
    let (e1, e2) = (v - a, b - v);
    e1.perp_dot(e2).atan2(e1.dot(e2))
}

/// Aligned: the vertex nearest the seam of the layer below (a concave corner counting two
/// line widths nearer), or on a first layer the sharpest concave corner, else the rear-most
/// vertex. Loops run with the material on their left, so a concave corner turns right.
fn aligned(pts: &[DVec2], prev: &[DVec2], width: f64) -> (usize, DVec2) {
    let (min, max) = bounds(pts);
    let reach2 = ALIGN_REACH_MM * ALIGN_REACH_MM;
    let mut target: Option<(f64, DVec2)> = None;
    for q in prev {
        if box_dist2(*q, min, max) > reach2 {
            continue;
        }
        let d = pts.iter().map(|p| p.distance_squared(*q)).fold(f64::INFINITY, f64::min);
        if d <= reach2 && target.is_none_or(|(bd, _)| d < bd) {
            target = Some((d, *q));
        }
    }
    let concave: Vec<f64> = (0..pts.len()).map(|k| (-turn(pts, k, width)).max(0.0)).collect();
    if let Some((_, q)) = target {
        let mut best: Option<(f64, usize)> = None;
        for (k, p) in pts.iter().enumerate() {
            let s = p.distance(q) - 2.0 * width * (concave[k] / std::f64::consts::FRAC_PI_2).min(1.0);
            if best.is_none_or(|(bs, _)| s < bs) {
                best = Some((s, k));
            }
        }
        let k = best.map_or(0, |b| b.1);
        return (k, pts[k]);
    }
    let sharpest = concave.iter().copied().fold(0.0, f64::max);
    let cx = (min.x + max.x) / 2.0;
    let mut best: Option<usize> = None;
    for (k, p) in pts.iter().enumerate() {
        if sharpest >= MIN_CORNER && concave[k] < sharpest - 1e-3 {
            continue;
        }
        let better = best.is_none_or(|b| {
            let q = pts[b];
            p.y > q.y || (p.y == q.y && (p.x - cx).abs() < (q.x - cx).abs())
        });
        if better {
            best = Some(k);
        }
    }
    let k = best.unwrap_or(0);
    (k, pts[k])
}

fn bounds(pts: &[DVec2]) -> (DVec2, DVec2) {
    pts.iter().fold((DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)), |(a, b), p| (a.min(*p), b.max(*p)))
}

/// Rear: the point of largest Y; along a level top edge, the one nearest the loop's middle.
fn rear(pts: &[DVec2]) -> (usize, DVec2) {
    let n = pts.len();
    let (min, max) = bounds(pts);
    let cx = (min.x + max.x) / 2.0;
    let mut best: Option<(f64, usize, DVec2)> = None;
    let mut offer = |k: usize, p: DVec2| {
        let d = (p.x - cx).abs();
        if best.is_none_or(|(bd, _, _)| d < bd) {
            best = Some((d, k, p));
        }
    };
    for k in 0..n {
        let (a, b) = (pts[k], pts[(k + 1) % n]);
        if a.y == max.y {
            offer(k, a);
            if b.y == max.y {
                offer(k, DVec2::new(cx.clamp(a.x.min(b.x), a.x.max(b.x)), max.y));
            }
        }
    }
    best.map_or((0, pts[0]), |(_, k, p)| (k, p))
}

fn splitmix64(x: u64) -> u64 {
    let mut z = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Random: a point along the loop from a hash of the layer and the loop's number (a vertex
/// when within 0.01 mm of one).
fn random(pts: &[DVec2], layer: u64, loop_no: u64) -> (usize, DVec2) {
    let n = pts.len();
    let total: f64 = (0..n).map(|k| pts[k].distance(pts[(k + 1) % n])).sum();
    let h = splitmix64(splitmix64(layer) ^ loop_no);
    let mut t = (h >> 11) as f64 / (1u64 << 53) as f64 * total;
    for k in 0..n {
        let (a, b) = (pts[k], pts[(k + 1) % n]);
        let len = a.distance(b);
        if t <= len {
            if t < 0.01 {
                return (k, a);
            }
            if len - t < 0.01 {
                return ((k + 1) % n, b);
            }
            return (k, a.lerp(b, t / len));
        }
        t -= len;
    }
    (0, pts[0])
}

/// Nearest-first loops with their seams (segment index, point): the given ones, or for
/// `None` the vertex nearest the nozzle. `pos` ends at each seam (a loop ends where it starts).
fn order_loops(loops: Vec<Loop>, fixed: Option<Vec<(usize, DVec2)>>, pos: &mut DVec2) -> Vec<(Loop, usize, DVec2)> {
    let mut left: Vec<Option<Loop>> = loops.into_iter().map(Some).collect();
    let mut out = Vec::with_capacity(left.len());
    for _ in 0..left.len() {
        let mut best: Option<(f64, usize, usize, DVec2)> = None;
        for (i, l) in left.iter().enumerate() {
            let Some(l) = l else { continue };
            match &fixed {
                Some(f) => {
                    let (k, p) = f[i];
                    let d = p.distance_squared(*pos);
                    if best.is_none_or(|(bd, ..)| d < bd) {
                        best = Some((d, i, k, p));
                    }
                }
                None => {
                    for (j, p) in l.pts.iter().enumerate() {
                        let d = p.distance_squared(*pos);
                        if best.is_none_or(|(bd, ..)| d < bd) {
                            best = Some((d, i, j, *p));
                        }
                    }
                }
            }
        }
        let Some((_, i, k, p)) = best else { break };
        let l = left[i].take().unwrap_or_default();
        *pos = p;
        out.push((l, k, p));
    }
    out
}

/// `l` started at `p` on its segment `k` (a point inserted there unless it is the vertex) and
/// closed, cut where its overhang class changes: pieces that continue one another, each with
/// its class. A piece shorter than `width` at either end (the seam cut a run) joins its
/// neighbour's class.
fn start_loop(l: Loop, k: usize, p: DVec2, width: f64) -> Vec<(bool, Vec<DVec2>)> {
    let Loop { mut pts, mut over } = l;
    let n = pts.len();
    let mut j = k;
    if pts[(k + 1) % n] == p {
        // The end of the segment: that vertex (no zero-length move).
        j = (k + 1) % n;
    } else if pts[k] != p {
        pts.insert(k + 1, p);
        over.insert(k + 1, over[k]);
        j = k + 1;
    }
    pts.rotate_left(j);
    over.rotate_left(j);
    pts.push(pts[0]);
    // Runs of segments: (class, first segment, last segment + 1, length).
    let mut runs: Vec<(bool, usize, usize, f64)> = Vec::new();
    for (s, &o) in over.iter().enumerate() {
        let len = pts[s].distance(pts[s + 1]);
        match runs.last_mut() {
            Some(r) if r.0 == o => {
                r.2 = s + 1;
                r.3 += len;
            }
            _ => runs.push((o, s, s + 1, len)),
        }
    }
    if runs.len() > 1 {
        let n = runs.len();
        if runs[0].3 < width {
            runs[0].0 = runs[1].0;
        }
        if runs[n - 1].3 < width {
            runs[n - 1].0 = runs[n - 2].0;
        }
    }
    let mut out: Vec<(bool, Vec<DVec2>)> = Vec::new();
    let mut from = 0;
    for (i, r) in runs.iter().enumerate() {
        if i + 1 == runs.len() || runs[i + 1].0 != r.0 {
            out.push((r.0, pts[from..=r.2].to_vec()));
            from = r.2;
        }
    }
    out
}

/// Support lines before the part: the sparse support, then its interface, each nearest-first
/// (a closed sheath loop is a polyline whose ends meet).
pub(crate) fn order_support(base: Vec<Vec<DVec2>>, interface: Vec<Vec<DVec2>>, pos: &mut DVec2, z: f64, width: f64) -> Vec<Path> {
    let mut paths = Vec::with_capacity(base.len() + interface.len());
    for (feature, lines) in [(Feature::Support, base), (Feature::SupportInterface, interface)] {
        let lines = lines.into_iter().map(|l| (feature, l)).collect();
        for (f, pts) in order_polylines(lines, pos) {
            paths.push(Path::new(pts.into_iter().map(|p| DVec3::new(p.x, p.y, z)).collect(), f, width));
        }
    }
    paths
}

/// Nearest-first polylines, reversed when their last point is the nearer end.
fn order_polylines(lines: Vec<(Feature, Vec<DVec2>)>, pos: &mut DVec2) -> Vec<(Feature, Vec<DVec2>)> {
    let mut left: Vec<Option<(Feature, Vec<DVec2>)>> = lines.into_iter().filter(|l| l.1.len() >= 2).map(Some).collect();
    let mut out = Vec::with_capacity(left.len());
    for _ in 0..left.len() {
        let mut best: Option<(f64, usize, bool)> = None;
        for (i, l) in left.iter().enumerate() {
            let Some((_, l)) = l else { continue };
            for (rev, p) in [(false, l[0]), (true, l[l.len() - 1])] {
                let d = p.distance_squared(*pos);
                if best.is_none_or(|(bd, _, _)| d < bd) {
                    best = Some((d, i, rev));
                }
            }
        }
        let Some((_, i, rev)) = best else { break };
        let (f, mut l) = left[i].take().unwrap_or((Feature::Infill, Vec::new()));
        if rev {
            l.reverse();
        }
        *pos = l[l.len() - 1];
        out.push((f, l));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inner_first_seam_near_and_closed() {
        let sq = |s: f64| vec![DVec2::new(-s, -s), DVec2::new(s, -s), DVec2::new(s, s), DVec2::new(-s, s)];
        let r = RegionWork {
            min: DVec2::splat(-5.0),
            max: DVec2::splat(5.0),
            perimeters: vec![vec![Loop::plain(sq(5.0))], vec![Loop::plain(sq(4.0))]],
            infill: vec![(Feature::SolidInfill, vec![DVec2::new(3.0, 0.0), DVec2::new(-3.0, 0.0)])],
        };
        let mut pos = DVec2::new(10.0, 10.0);
        let paths = order_layer(vec![r], &mut pos, 0.2, 0.4, &mut Seams::new(Seam::Nearest));
        assert_eq!(paths.len(), 3);
        assert_eq!(paths[0].feature, Feature::Perimeter);
        assert_eq!(paths[1].feature, Feature::ExternalPerimeter);
        assert_eq!(paths[0].points[0], DVec3::new(4.0, 4.0, 0.2));
        assert_eq!(paths[0].points.first(), paths[0].points.last());
        assert_eq!(paths[2].points[0].x, 3.0);
        assert_eq!(pos, DVec2::new(-3.0, 0.0));
    }

    #[test]
    fn a_seam_on_a_segment_is_inserted_once_and_overhangs_split_the_loop() {
        let sq = vec![DVec2::new(0.0, 0.0), DVec2::new(10.0, 0.0), DVec2::new(10.0, 10.0), DVec2::new(0.0, 10.0)];
        let l = Loop { pts: sq.clone(), over: vec![false, true, false, false] };
        // At the end of segment 0: vertex 1, no point added.
        let runs = start_loop(l.clone(), 0, sq[1], 0.4);
        assert_eq!(runs.len(), 2);
        assert_eq!(runs[0], (true, vec![sq[1], sq[2]]));
        assert_eq!(runs[1], (false, vec![sq[2], sq[3], sq[0], sq[1]]));
        // Inside segment 1: the overhang is cut there and continues at the loop's end.
        let p = DVec2::new(10.0, 4.0);
        let runs = start_loop(l, 1, p, 0.4);
        assert_eq!(runs, vec![(true, vec![p, sq[2]]), (false, vec![sq[2], sq[3], sq[0], sq[1]]), (true, vec![sq[1], p])]);
    }
}

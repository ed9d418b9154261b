//! Bridges: the parts of a layer's solid area that lie over air, and the direction in which
//! straight lines cross each of them from material to material.
//!
//! [`detect`] is pure (integer micrometre shapes in, areas and angles out) so the planar
//! slicer ([`super::fill_layer`]) and the support generator share it: the slicer fills each
//! [`BridgeArea::area`] with [`lines`] (`Feature::Bridge`), the support generator leaves out
//! each [`BridgeArea::over_air`], which the bridge lines hold up by themselves.
//!
//! Detection, per connected piece of air (the solid area minus the layer below, opened by half
//! a line width so slivers narrower than a line, which the material below still holds, are
//! not pieces): for every candidate direction (every 5°, and perpendicular to the piece's
//! longest edges that border material below), lines one width apart are cut by the piece and
//! by the piece grown by [`ANCHOR_REACH`] widths (clipped to the solid area). A line is
//! anchored when the grown piece continues at least [`MIN_ANCHOR`] widths beyond the air at
//! both of its ends (there it lies on the layer below), or at least a quarter width when the
//! solid area itself ends there (a lid on thin walls: the lines reach the layer's perimeters,
//! which lie on the walls). The direction that anchors the most
//! air wins; among directions within [`COVERAGE_SLACK`] of it, the one whose longest span is
//! shortest (as PrusaSlicer's bridge detector), then the one whose mean span (weighted by
//! length: long spans weigh most) is shortest, then the first candidate. (The mean alone
//! would favour a direction a few degrees off across a rectangle: its corner lines are
//! short.)
//! A piece with no anchored line (a cantilever) gives no bridge: it needs support.
//!
//! Everything runs in one thread in a fixed order (no hash maps), so the result is the same
//! on every target.

use super::perimeters::{inset, outset};
use super::regions::{difference, intersect, union_all};
use crate::geom::DVec2;
use i_overlay::i_float::int::point::IntPoint;
use i_overlay::i_shape::int::shape::{IntShape, IntShapes};

/// How far (in line widths) a bridge's area reaches beyond its air onto the material below:
/// the lines' anchors.
pub(crate) const ANCHOR_REACH: f64 = 2.0;
/// Shortest anchor (in line widths) at each end of a line for it to count as anchored (a
/// quarter width where the solid area ends on material).
pub(crate) const MIN_ANCHOR: f64 = 1.0;
/// Directions anchoring at least this fraction of the best one's air compete on span.
pub(crate) const COVERAGE_SLACK: f64 = 0.97;
/// Step of the candidate directions, degrees.
const ANGLE_STEP_DEG: f64 = 5.0;
/// Edges of a piece whose perpendiculars are also tried (the longest ones bordering material).
const EDGE_CANDIDATES: usize = 8;

/// One bridge: a connected piece of air under a layer's solid area, and how to cross it.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct BridgeArea {
    /// The air that the anchored lines cover (µm): what the lines hold up themselves, so the
    /// support generator need not support it.
    pub over_air: IntShapes<i32>,
    /// Where the bridge lines go (µm): `over_air` grown by [`ANCHOR_REACH`] line widths onto
    /// the material below, clipped to the solid area. Areas of one layer do not overlap (each
    /// keeps a line width away from the ones before it).
    pub area: IntShapes<i32>,
    /// Direction of the lines, radians in [0, π).
    pub angle: f64,
    /// Longest air crossed by one anchored line, mm.
    pub span_mm: f64,
}

/// The bridges of a layer. `solid`: the layer's solid-infill area (µm; include room for the
/// anchors: the lines only reach onto material inside it); `below`: the regions of the layer
/// below (their full outlines: anything inside them, sparse infill included, is material);
/// `w_um`: the line width (also the line spacing). Pieces of air anchored on one side only
/// (cantilevers) are not returned. Ordered by the pieces' lowest corner.
pub(crate) fn detect(solid: &IntShapes<i32>, below: &IntShapes<i32>, w_um: i32) -> Vec<BridgeArea> {
    if solid.is_empty() || w_um <= 0 {
        return Vec::new();
    }
    let w = w_um as f64;
    let air = difference(solid, below);
    // Opening: pieces narrower than a line width are held by the material beside them.
    let air = outset(&inset(&air, w_um / 2), w_um / 2);
    let air = intersect(&air, solid);
    let mut pieces = air;
    super::regions::sort_shapes(&mut pieces);
    let reach = (ANCHOR_REACH * w).round() as i32;
    let mut out: Vec<BridgeArea> = Vec::new();
    let mut taken: IntShapes<i32> = Vec::new();
    for piece in pieces {
        let piece = vec![piece];
        let grown = intersect(&outset(&piece, reach), solid);
        let mut best: Option<Candidate> = None;
        let mut cands: Vec<Candidate> = Vec::new();
        for a in candidate_angles(&piece, below, w) {
            let c = evaluate(&piece, &grown, a, w);
            cands.push(c);
        }
        let top = cands.iter().map(|c| c.coverage).fold(0.0, f64::max);
        if top <= 0.0 {
            continue;
        }
        for c in cands {
            if c.coverage < COVERAGE_SLACK * top {
                continue;
            }
            let better = match &best {
                None => true,
                Some(b) => c.max_span.total_cmp(&b.max_span).then(c.mean_span.total_cmp(&b.mean_span)).is_lt(),
            };
            if better {
                best = Some(c);
            }
        }
        let Some(c) = best else { continue };
        // The covered air: each anchored line's air, a width wide, within the piece.
        let (sn, cs) = (libm::sin(c.angle), libm::cos(c.angle));
        let strips: IntShapes<i32> = c.anchored.iter().map(|&(y, lo, hi)| vec![rect(lo, hi, y - w / 2.0, y + w / 2.0, sn, cs)]).collect();
        let over_air = intersect(&union_all(&strips), &piece);
        if over_air.is_empty() {
            continue;
        }
        let mut area = intersect(&outset(&over_air, reach), solid);
        if !taken.is_empty() {
            area = difference(&area, &outset(&taken, w_um));
        }
        if area.is_empty() {
            continue;
        }
        taken.extend(area.iter().cloned());
        out.push(BridgeArea { over_air, area, angle: c.angle, span_mm: c.max_span / 1000.0 });
    }
    out
}

/// The straight lines (mm) that fill a bridge `area` at `angle`, one line width `w_um` apart
/// on a global grid: each line is one straight segment. Consecutive lines are joined into
/// one polyline, boustrophedon, when the connector between their ends is short (under two
/// widths) and lies inside `below` (on material); otherwise they are
/// separate polylines (a travel between them). Pieces shorter than `min_len_um` are dropped.
pub(crate) fn lines(area: &[IntShape<i32>], below: &[IntShape<i32>], angle: f64, w_um: i32, min_len_um: f64) -> Vec<Vec<DVec2>> {
    let w = w_um as f64;
    if area.is_empty() || w <= 0.0 {
        return Vec::new();
    }
    let (sn, cs) = (libm::sin(angle), libm::cos(angle));
    let rows = scan(area, sn, cs, w);
    // (k, x0, x1) in scan order.
    let mut segs: Vec<(i64, f64, f64)> = Vec::new();
    for (k, xs) in &rows {
        for p in xs.chunks_exact(2) {
            if p[1] - p[0] >= min_len_um {
                segs.push((*k, p[0], p[1]));
            }
        }
    }
    let world = |x: f64, k: i64| {
        let y = k as f64 * w;
        DVec2::new((x * cs - y * sn) / 1000.0, (x * sn + y * cs) / 1000.0)
    };
    let on = |p: DVec2| inside_any(below, p.x * 1000.0, p.y * 1000.0);
    let mut out: Vec<Vec<DVec2>> = Vec::new();
    // The open chain: its polyline, the scanline of its last line and that line's end (x).
    let mut chain: Option<(Vec<DVec2>, i64, f64)> = None;
    let mut used = vec![false; segs.len()];
    // Greedy boustrophedon: from the chain's end, the line on the next scanline whose near
    // end is closest, when the connector is on material.
    let mut start = 0;
    loop {
        if chain.is_none() {
            while start < segs.len() && used[start] {
                start += 1;
            }
            if start == segs.len() {
                break;
            }
            used[start] = true;
            let (k, x0, x1) = segs[start];
            chain = Some((vec![world(x0, k), world(x1, k)], k, x1));
            continue;
        }
        let Some((mut pts, k, xe)) = chain.take() else { break };
        let mut next: Option<(f64, usize, bool)> = None;
        let from_j = segs.partition_point(|s| s.0 <= k);
        for (j, &(kj, x0, x1)) in segs.iter().enumerate().skip(from_j) {
            if kj != k + 1 {
                break;
            }
            if used[j] {
                continue;
            }
            for (rev, x) in [(false, x0), (true, x1)] {
                let d = (x - xe).abs();
                if next.is_none_or(|(bd, _, _)| d < bd) {
                    next = Some((d, j, rev));
                }
            }
        }
        let joined = next.and_then(|(_, j, rev)| {
            let (kj, x0, x1) = segs[j];
            let (a, b) = if rev { (x1, x0) } else { (x0, x1) };
            let from = world(xe, k);
            let to = world(a, kj);
            let len = from.distance(to) * 1000.0;
            let steps = (len / (w / 4.0)).ceil().max(1.0) as usize;
            let ok = len < 2.0 * w && (0..=steps).all(|s| on(from + (to - from) * (s as f64 / steps as f64)));
            ok.then_some((j, kj, a, b))
        });
        match joined {
            Some((j, kj, a, b)) => {
                used[j] = true;
                pts.push(world(a, kj));
                pts.push(world(b, kj));
                chain = Some((pts, kj, b));
            }
            None => out.push(pts),
        }
    }
    if let Some((pts, _, _)) = chain {
        out.push(pts);
    }
    out
}

/// One candidate direction's anchored lines.
struct Candidate {
    angle: f64,
    /// Air crossed by anchored lines, µm (× the spacing: the area they cover).
    coverage: f64,
    /// Mean span weighted by span (Σ s² / Σ s), µm.
    mean_span: f64,
    max_span: f64,
    /// Each anchored line: its scanline's y and its air's first and last x (turned frame, µm).
    anchored: Vec<(f64, f64, f64)>,
}

fn evaluate(piece: &[IntShape<i32>], grown: &[IntShape<i32>], angle: f64, w: f64) -> Candidate {
    let (sn, cs) = (libm::sin(angle), libm::cos(angle));
    let air_rows = scan(piece, sn, cs, w);
    let grown_rows = scan(grown, sn, cs, w);
    let min_anchor = MIN_ANCHOR * w;
    let reach_um = ANCHOR_REACH * w;
    let (mut coverage, mut s1, mut s2, mut max_span) = (0.0, 0.0, 0.0, 0.0f64);
    let mut anchored = Vec::new();
    for (k, air) in &air_rows {
        let Ok(gi) = grown_rows.binary_search_by(|(kg, _)| kg.cmp(k)) else { continue };
        let g = &grown_rows[gi].1;
        for span in g.chunks_exact(2) {
            let (a, b) = (span[0], span[1]);
            let mut lo = f64::INFINITY;
            let mut hi = f64::NEG_INFINITY;
            let mut len = 0.0;
            for p in air.chunks_exact(2) {
                let (p0, p1) = (p[0].max(a), p[1].min(b));
                if p1 > p0 {
                    lo = lo.min(p0);
                    hi = hi.max(p1);
                    len += p1 - p0;
                }
            }
            // An end is anchored by MIN_ANCHOR widths on material, or by a quarter width when
            // the solid area ends there (a wall below: the layer's perimeters lie beside it).
            let held = |run: f64| run >= min_anchor || (run >= w / 4.0 && run < reach_um - 1.0);
            if len <= 0.0 || !held(lo - a) || !held(b - hi) {
                continue;
            }
            let s = hi - lo;
            coverage += len;
            s1 += s;
            s2 += s * s;
            max_span = max_span.max(s);
            anchored.push((*k as f64 * w, lo, hi));
        }
    }
    let mean_span = if s1 > 0.0 { s2 / s1 } else { f64::INFINITY };
    Candidate { angle, coverage, mean_span, max_span, anchored }
}

/// Candidate directions in [0, π): every [`ANGLE_STEP_DEG`], then the perpendiculars of the
/// piece's longest edges (at least two widths long) that border material below, skipping
/// any within 0.5° of one already listed.
fn candidate_angles(piece: &[IntShape<i32>], below: &[IntShape<i32>], w: f64) -> Vec<f64> {
    let pi = std::f64::consts::PI;
    let steps = (180.0 / ANGLE_STEP_DEG).round() as usize;
    let mut out: Vec<f64> = (0..steps).map(|i| (i as f64 * ANGLE_STEP_DEG).to_radians()).collect();
    let mut edges: Vec<(f64, f64)> = Vec::new();
    for c in piece.iter().flat_map(|s| s.iter()) {
        let n = c.len();
        for i in 0..n {
            let (p, q) = (c[i], c[(i + 1) % n]);
            let d = DVec2::new((q.x - p.x) as f64, (q.y - p.y) as f64);
            let len = d.length();
            if len < 2.0 * w {
                continue;
            }
            // Outer contours run counter-clockwise and holes clockwise: the outside is on
            // the right of every edge.
            let mid = DVec2::new((p.x + q.x) as f64 / 2.0, (p.y + q.y) as f64 / 2.0);
            let out_n = DVec2::new(d.y, -d.x) / len;
            let probe = mid + out_n * w;
            if !inside_any(below, probe.x, probe.y) {
                continue;
            }
            let a = (libm::atan2(d.y, d.x) + pi / 2.0).rem_euclid(pi);
            edges.push((len, a));
        }
    }
    edges.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.total_cmp(&b.1)));
    for &(_, a) in edges.iter() {
        if out.len() >= steps + EDGE_CANDIDATES {
            break;
        }
        let near = out.iter().any(|&b| {
            let d = (a - b).rem_euclid(pi);
            d.min(pi - d) < 0.5f64.to_radians()
        });
        if !near {
            out.push(a);
        }
    }
    out
}

/// Crossings of `shapes` with the lines `y = k·w` of the frame turned by −angle (sine `sn`,
/// cosine `cs`): per scanline `k` (ascending), its crossings' x sorted, in pairs
/// inside/outside (even–odd; edges are half-open in y, so a vertex on a line counts once).
fn scan(shapes: &[IntShape<i32>], sn: f64, cs: f64, w: f64) -> Vec<(i64, Vec<f64>)> {
    let mut hits: Vec<(i64, f64)> = Vec::new();
    for c in shapes.iter().flat_map(|s| s.iter()) {
        let n = c.len();
        if n < 3 {
            continue;
        }
        let turned: Vec<DVec2> = c
            .iter()
            .map(|p| {
                let (x, y) = (p.x as f64, p.y as f64);
                DVec2::new(x * cs + y * sn, -x * sn + y * cs)
            })
            .collect();
        for e in 0..n {
            let (p, q) = (turned[e], turned[(e + 1) % n]);
            if p.y == q.y {
                continue;
            }
            let (ylo, yhi) = if p.y < q.y { (p.y, q.y) } else { (q.y, p.y) };
            let mut k = libm::ceil(ylo / w) as i64;
            loop {
                let y = k as f64 * w;
                if y >= yhi {
                    break;
                }
                if y >= ylo {
                    let t = (y - p.y) / (q.y - p.y);
                    hits.push((k, p.x + t * (q.x - p.x)));
                }
                k += 1;
            }
        }
    }
    hits.sort_by(|a, b| a.0.cmp(&b.0).then(a.1.total_cmp(&b.1)));
    let mut rows: Vec<(i64, Vec<f64>)> = Vec::new();
    for (k, x) in hits {
        match rows.last_mut() {
            Some((kk, xs)) if *kk == k => xs.push(x),
            _ => rows.push((k, vec![x])),
        }
    }
    rows.retain(|(_, xs)| xs.len() % 2 == 0);
    rows
}

/// The rectangle `[x0, x1] × [y0, y1]` of the turned frame, back in the plate's frame (µm),
/// counter-clockwise.
fn rect(x0: f64, x1: f64, y0: f64, y1: f64, sn: f64, cs: f64) -> Vec<IntPoint<i32>> {
    let back = |x: f64, y: f64| IntPoint::new(libm::round(x * cs - y * sn) as i32, libm::round(x * sn + y * cs) as i32);
    vec![back(x0, y0), back(x1, y0), back(x1, y1), back(x0, y1)]
}

/// Even–odd point-in-shapes test (µm).
fn inside_any(shapes: &[IntShape<i32>], x: f64, y: f64) -> bool {
    shapes.iter().any(|s| {
        let mut inside = false;
        for c in s {
            let n = c.len();
            for i in 0..n {
                let (a, b) = (c[i], c[(i + 1) % n]);
                let (ax, ay, bx, by) = (a.x as f64, a.y as f64, b.x as f64, b.y as f64);
                if (ay > y) != (by > y) && x < ax + (y - ay) / (by - ay) * (bx - ax) {
                    inside = !inside;
                }
            }
        }
        inside
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rect_um(x0: i32, y0: i32, x1: i32, y1: i32) -> IntShape<i32> {
        vec![vec![IntPoint::new(x0, y0), IntPoint::new(x1, y0), IntPoint::new(x1, y1), IntPoint::new(x0, y1)]]
    }

    fn deg(a: f64) -> f64 {
        a.to_degrees()
    }

    /// Angle between two line directions, degrees (0–90).
    fn between(a: f64, b_deg: f64) -> f64 {
        let d = (deg(a) - b_deg).rem_euclid(180.0);
        d.min(180.0 - d)
    }

    #[test]
    fn gap_between_two_pillars_is_crossed_along_the_span() {
        // Pillars x ∈ [-20, -10] and [10, 20] mm, a slab over both and the 20 mm gap.
        let below = vec![rect_um(-20_000, -5_000, -10_000, 5_000), rect_um(10_000, -5_000, 20_000, 5_000)];
        let solid = vec![rect_um(-19_000, -4_000, 19_000, 4_000)];
        let b = detect(&solid, &below, 400);
        assert_eq!(b.len(), 1);
        assert!(between(b[0].angle, 0.0) < 1.0, "{}", deg(b[0].angle));
        assert!((b[0].span_mm - 20.0).abs() < 0.5, "{}", b[0].span_mm);
        // The whole gap is covered (8 mm × 20 mm), and the area reaches 0.8 mm onto each pillar.
        let air = super::super::regions::shapes_area2(&b[0].over_air) as f64 / 2e6;
        // 20 lines, y = -4.0 … 3.6 mm, each covering 0.4 mm: 7.8 mm of the 8.
        assert!((air - 156.0).abs() < 1.0, "{air}");
        let (lo, hi) = super::super::bbox_mm(&b[0].area[0]);
        assert!((lo.x + 10.8).abs() < 0.01 && (hi.x - 10.8).abs() < 0.01, "{lo:?} {hi:?}");
        // The lines: straight, along X, from pillar to pillar.
        let ls = lines(&b[0].area, &below, b[0].angle, 400, 100.0);
        assert!(!ls.is_empty());
        let mut straight = 0;
        for l in &ls {
            for s in l.windows(2) {
                let d = s[1] - s[0];
                if d.length() > 10.0 {
                    assert!(d.y.abs() < 1e-6 && d.length() > 21.0, "{s:?}");
                    straight += 1;
                }
            }
        }
        assert_eq!(straight, 20, "lines at y = -4.0, -3.6, …, 3.6");
        assert_eq!(ls.len(), 1, "connectors on the pillars join the lines");
    }

    #[test]
    fn cantilever_is_not_a_bridge() {
        let below = vec![rect_um(-10_000, -5_000, 0, 5_000)];
        let solid = vec![rect_um(-9_000, -4_000, 20_000, 4_000)];
        assert!(detect(&solid, &below, 400).is_empty());
        // Nor is a solid area wholly on material.
        assert!(detect(&vec![rect_um(-9_000, -4_000, -1_000, 4_000)], &below, 400).is_empty());
    }

    #[test]
    fn hole_anchored_all_round_is_crossed_the_short_way() {
        // A plate with a 20 × 6 mm window below, solid over all of it.
        let mut plate = rect_um(-20_000, -10_000, 20_000, 10_000);
        plate.push(vec![IntPoint::new(-10_000, -3_000), IntPoint::new(-10_000, 3_000), IntPoint::new(10_000, 3_000), IntPoint::new(10_000, -3_000)]);
        let below = vec![plate];
        let solid = vec![rect_um(-19_000, -9_000, 19_000, 9_000)];
        let b = detect(&solid, &below, 400);
        assert_eq!(b.len(), 1);
        assert!(between(b[0].angle, 90.0) < 1.0, "{}", deg(b[0].angle));
        assert!((b[0].span_mm - 6.0).abs() < 0.5, "{}", b[0].span_mm);
        // Turned 90°: a 6 × 20 mm window is crossed along X.
        let mut plate = rect_um(-20_000, -20_000, 20_000, 20_000);
        plate.push(vec![IntPoint::new(-3_000, -10_000), IntPoint::new(-3_000, 10_000), IntPoint::new(3_000, 10_000), IntPoint::new(3_000, -10_000)]);
        let b = detect(&vec![rect_um(-19_000, -19_000, 19_000, 19_000)], &vec![plate], 400);
        assert_eq!(b.len(), 1);
        assert!(between(b[0].angle, 0.0) < 1.0, "{}", deg(b[0].angle));
    }

    #[test]
    fn lid_on_thin_walls_is_a_bridge() {
        // A 20 mm box with 1.2 mm walls below; the lid's solid area stops 1 mm inside its
        // outline (two perimeters and a half width), 0.2 mm onto the walls.
        let mut walls = rect_um(-10_000, -10_000, 10_000, 10_000);
        walls.push(vec![IntPoint::new(-8_800, -8_800), IntPoint::new(-8_800, 8_800), IntPoint::new(8_800, 8_800), IntPoint::new(8_800, -8_800)]);
        let solid = vec![rect_um(-9_000, -9_000, 9_000, 9_000)];
        let b = detect(&solid, &vec![walls.clone()], 400);
        assert_eq!(b.len(), 1);
        assert!((b[0].span_mm - 17.6).abs() < 0.3, "{}", b[0].span_mm);
        // Walls too far out to be reached: not a bridge (the lines would end over air).
        let solid = vec![rect_um(-8_700, -8_700, 8_700, 8_700)];
        assert!(detect(&solid, &vec![walls], 400).is_empty());
    }

    #[test]
    fn slanted_gap_is_crossed_perpendicular_to_its_edges() {
        // Two slabs below with a 10 mm gap between parallel edges at 37° (no 5° step).
        let t = 37f64.to_radians();
        let (u, v) = (DVec2::new(t.cos(), t.sin()), DVec2::new(-t.sin(), t.cos()));
        let quad = |a: f64, b: f64| -> IntShape<i32> {
            let pts = [u * a + v * -15_000.0, u * b + v * -15_000.0, u * b + v * 15_000.0, u * a + v * 15_000.0];
            vec![pts.iter().map(|p| IntPoint::new(p.x.round() as i32, p.y.round() as i32)).collect()]
        };
        let below = vec![quad(-20_000.0, -5_000.0), quad(5_000.0, 20_000.0)];
        let solid = vec![rect_um(-8_000, -8_000, 8_000, 8_000)];
        let b = detect(&solid, &below, 400);
        assert_eq!(b.len(), 1);
        assert!(between(b[0].angle, 37.0) < 0.5, "{}", deg(b[0].angle));
    }
}

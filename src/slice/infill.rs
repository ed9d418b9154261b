//! Rectilinear infill: parallel lines clipped to an area and joined zig-zag along its boundary.
//!
//! The area is rotated so the lines run along X; scanlines sit at `y = k × spacing` for integer
//! `k` (a global grid, so consecutive layers with the same angle line up). Each contour edge is
//! intersected with the scanlines it spans (half-open in Y, so a vertex on a scanline counts
//! once) and the crossings of each scanline are paired inside/outside (the area comes from
//! i_overlay, so its contours do not cross and even–odd pairing is exact). This is the clip
//! i_overlay's string clipping would do, but it also tells which boundary edge every line end
//! lies on, which the zig-zag linking needs.
//!
//! Linking: two line ends on adjacent scanlines that are neighbours along the same contour
//! (no other crossing between them) are joined by following that contour; the connector is
//! on the area's boundary, so it never leaves the area. Connectors longer than three spacings
//! are not made.

use crate::geom::DVec2;
use i_overlay::core::fill_rule::FillRule;
use i_overlay::i_float::int::point::IntPoint;
use i_overlay::i_shape::int::shape::IntShape;
use i_overlay::string::clip::{ClipRule, IntClip};
use std::collections::BTreeMap;

#[derive(Clone, Copy, Debug)]
struct Hit {
    k: i64,
    x: f64,
    contour: u32,
    edge: u32,
    t: f64,
}

/// Infill polylines (mm) for `area` (µm shapes): lines at `angle_rad`, `spacing_um` apart,
/// pieces shorter than `min_len_um` dropped.
pub(crate) fn rectilinear(area: &[IntShape<i32>], spacing_um: f64, angle_rad: f64, min_len_um: f64) -> Vec<Vec<DVec2>> {
    if area.is_empty() || spacing_um.is_nan() || spacing_um <= 0.0 {
        return Vec::new();
    }
    let (s, c) = (libm::sin(angle_rad), libm::cos(angle_rad));
    // Rotate by −angle: the infill direction becomes +X.
    let contours: Vec<Vec<DVec2>> = area
        .iter()
        .flat_map(|sh| sh.iter())
        .filter(|ct| ct.len() >= 3)
        .map(|ct| {
            ct.iter()
                .map(|p| {
                    let (x, y) = (p.x as f64, p.y as f64);
                    DVec2::new(x * c + y * s, -x * s + y * c)
                })
                .collect()
        })
        .collect();

    let mut hits: Vec<Hit> = Vec::new();
    for (ci, ct) in contours.iter().enumerate() {
        let n = ct.len();
        for e in 0..n {
            let p = ct[e];
            let q = ct[(e + 1) % n];
            if p.y == q.y {
                continue;
            }
            let (ylo, yhi) = if p.y < q.y { (p.y, q.y) } else { (q.y, p.y) };
            let mut k = libm::ceil(ylo / spacing_um) as i64;
            loop {
                let y = k as f64 * spacing_um;
                if y >= yhi {
                    break;
                }
                if y >= ylo {
                    let t = (y - p.y) / (q.y - p.y);
                    hits.push(Hit { k, x: p.x + t * (q.x - p.x), contour: ci as u32, edge: e as u32, t });
                }
                k += 1;
            }
        }
    }
    if hits.is_empty() {
        return Vec::new();
    }
    hits.sort_by(|a, b| a.k.cmp(&b.k).then(a.x.total_cmp(&b.x)).then(a.contour.cmp(&b.contour)).then(a.edge.cmp(&b.edge)).then(a.t.total_cmp(&b.t)));

    // Lines: pairs of consecutive crossings on each scanline.
    let nh = hits.len();
    let mut seg_of = vec![usize::MAX; nh];
    let mut segs: Vec<[usize; 2]> = Vec::new();
    let mut i = 0;
    while i < nh {
        let mut j = i;
        while j < nh && hits[j].k == hits[i].k {
            j += 1;
        }
        let mut a = i;
        while a + 1 < j {
            if hits[a + 1].x - hits[a].x >= min_len_um {
                seg_of[a] = segs.len();
                seg_of[a + 1] = segs.len();
                segs.push([a, a + 1]);
            }
            a += 2;
        }
        i = j;
    }

    // Neighbours of every crossing along its contour (cyclic order by edge, t).
    let mut along: Vec<usize> = (0..nh).collect();
    along.sort_by(|&a, &b| {
        let (ha, hb) = (&hits[a], &hits[b]);
        ha.contour.cmp(&hb.contour).then(ha.edge.cmp(&hb.edge)).then(ha.t.total_cmp(&hb.t)).then(a.cmp(&b))
    });
    let mut next_along = vec![0usize; nh];
    let mut prev_along = vec![0usize; nh];
    let mut g = 0;
    while g < nh {
        let mut h = g;
        while h < nh && hits[along[h]].contour == hits[along[g]].contour {
            h += 1;
        }
        let m = h - g;
        for r in 0..m {
            let cur = along[g + r];
            next_along[cur] = along[g + (r + 1) % m];
            prev_along[cur] = along[g + (r + m - 1) % m];
        }
        g = h;
    }

    let max_conn = 3.0 * spacing_um;
    let point = |h: usize| DVec2::new(hits[h].x, hits[h].k as f64 * spacing_um);
    // Boundary path from crossing `a` to crossing `b` along the contour (forward = increasing
    // edge order), excluding both crossing points; `None` if longer than `max_conn`.
    let path = |a: usize, b: usize, forward: bool| -> Option<Vec<DVec2>> {
        let ct = &contours[hits[a].contour as usize];
        let n = ct.len();
        let mut pts = Vec::new();
        let (ea, eb) = (hits[a].edge as usize, hits[b].edge as usize);
        if forward {
            let same = ea == eb && hits[b].t >= hits[a].t;
            if !same {
                let mut v = (ea + 1) % n;
                loop {
                    pts.push(ct[v]);
                    if v == eb || pts.len() > n {
                        break;
                    }
                    v = (v + 1) % n;
                }
            }
        } else {
            let same = ea == eb && hits[b].t <= hits[a].t;
            if !same {
                let mut v = ea;
                loop {
                    pts.push(ct[v]);
                    if v == (eb + 1) % n || pts.len() > n {
                        break;
                    }
                    v = (v + n - 1) % n;
                }
            }
        }
        let mut len = 0.0;
        let mut last = point(a);
        for &p in pts.iter().chain(std::iter::once(&point(b))) {
            len += last.distance(p);
            last = p;
            if len > max_conn {
                return None;
            }
        }
        Some(pts)
    };

    let mut used = vec![false; segs.len()];
    let mut out: Vec<Vec<DVec2>> = Vec::new();
    // Extends a chain from crossing `end` (the end just reached); returns the points added.
    let extend = |used: &mut Vec<bool>, mut end: usize| -> Vec<DVec2> {
        let mut pts = Vec::new();
        loop {
            let mut step = None;
            for (nb, forward) in [(next_along[end], true), (prev_along[end], false)] {
                let sg = seg_of[nb];
                if nb == end || sg == usize::MAX || used[sg] || (hits[nb].k - hits[end].k).abs() != 1 {
                    continue;
                }
                if let Some(p) = path(end, nb, forward) {
                    step = Some((nb, sg, p));
                    break;
                }
            }
            let Some((nb, sg, conn)) = step else { break };
            used[sg] = true;
            pts.extend(conn);
            pts.push(point(nb));
            let other = if segs[sg][0] == nb { segs[sg][1] } else { segs[sg][0] };
            pts.push(point(other));
            end = other;
        }
        pts
    };
    for si in 0..segs.len() {
        if used[si] {
            continue;
        }
        used[si] = true;
        let [l, r] = segs[si];
        let fwd = extend(&mut used, r);
        let back = extend(&mut used, l);
        let mut pts: Vec<DVec2> = back.into_iter().rev().collect();
        pts.push(point(l));
        pts.push(point(r));
        pts.extend(fwd);
        // Rotate back by +angle and convert to mm.
        out.push(pts.into_iter().map(|p| DVec2::new((p.x * c - p.y * s) / 1000.0, (p.x * s + p.y * c) / 1000.0)).collect());
    }
    out
}

/// The box of `area`'s vertices in the frame turned by −`angle` (sine `sn`, cosine `cs`): the
/// pattern's own frame, where its lines are generated before clipping. `None` for no vertices.
pub(crate) fn turned_bounds(area: &[IntShape<i32>], sn: f64, cs: f64) -> Option<(DVec2, DVec2)> {
    let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
    for p in area.iter().flat_map(|s| s.iter()).flat_map(|c| c.iter()) {
        let (x, y) = (p.x as f64, p.y as f64);
        let q = DVec2::new(x * cs + y * sn, -x * sn + y * cs);
        lo = lo.min(q);
        hi = hi.max(q);
    }
    (lo.x <= hi.x).then_some((lo, hi))
}

/// Clips open polylines (µm, integer) to `area` (even–odd) with i_overlay's string clipping,
/// re-joins the pieces the clipper splits at its graph nodes (two piece ends on one point and
/// nothing else there), drops pieces shorter than `min_len_um` and returns them in mm.
///
/// The gyroid and 3D honeycomb patterns generate their curves over the area's bounding box
/// and clip them here; the result is deterministic (pieces in the clipper's order, which is
/// geometric).
pub(crate) fn clip_polylines(area: &[IntShape<i32>], lines: &[Vec<IntPoint<i32>>], min_len_um: f64) -> Vec<Vec<DVec2>> {
    if area.is_empty() || lines.is_empty() {
        return Vec::new();
    }
    let rule = ClipRule { invert: false, boundary_included: false };
    let pieces = area.clip_paths(lines, FillRule::EvenOdd, rule);
    // Piece ends by point, in point order (no hash order reaches the output).
    let mut ends: BTreeMap<(i32, i32), Vec<(usize, bool)>> = BTreeMap::new();
    for (i, p) in pieces.iter().enumerate() {
        if p.len() < 2 || p[0] == p[p.len() - 1] {
            continue;
        }
        ends.entry((p[0].x, p[0].y)).or_default().push((i, false));
        let l = p[p.len() - 1];
        ends.entry((l.x, l.y)).or_default().push((i, true));
    }
    // The piece joined at the other side of an end, when exactly two ends meet there.
    let partner = |pt: IntPoint<i32>, me: usize| -> Option<(usize, bool)> {
        match ends.get(&(pt.x, pt.y)).map(Vec::as_slice) {
            Some(&[a, b]) if a.0 != b.0 => Some(if a.0 == me { b } else { a }),
            _ => None,
        }
    };
    let mut used = vec![false; pieces.len()];
    let mut out = Vec::new();
    for start in 0..pieces.len() {
        if used[start] || pieces[start].len() < 2 {
            continue;
        }
        used[start] = true;
        // The chain through `start`: pieces met walking back from its first point (prepended),
        // then walking on from its last point; each with whether it is traversed reversed.
        let mut chain: std::collections::VecDeque<(usize, bool)> = std::collections::VecDeque::from([(start, false)]);
        for backward in [true, false] {
            let (mut cur, mut rev) = (start, false);
            loop {
                let p = &pieces[cur];
                // The free end on this side: the head when walking back, the tail walking on.
                let at = if backward != rev { p[0] } else { p[p.len() - 1] };
                let Some((q, at_end)) = partner(at, cur) else { break };
                if used[q] {
                    break;
                }
                used[q] = true;
                // Walking back, `q` must run into `at` (forward when its end is there);
                // walking on, it must run out of `at` (forward when its start is there).
                rev = if backward { !at_end } else { at_end };
                cur = q;
                if backward {
                    chain.push_front((q, rev));
                } else {
                    chain.push_back((q, rev));
                }
            }
        }
        let mut pts: Vec<IntPoint<i32>> = Vec::new();
        for &(k, rev) in &chain {
            let p = &pieces[k];
            let seq: Box<dyn Iterator<Item = &IntPoint<i32>>> = if rev { Box::new(p.iter().rev()) } else { Box::new(p.iter()) };
            for &q in seq {
                if pts.last() != Some(&q) {
                    pts.push(q);
                }
            }
        }
        let len: f64 = pts.windows(2).map(|w| DVec2::new(w[0].x as f64, w[0].y as f64).distance(DVec2::new(w[1].x as f64, w[1].y as f64))).sum();
        if pts.len() >= 2 && len >= min_len_um {
            out.push(pts.iter().map(|p| DVec2::new(p.x as f64, p.y as f64) / 1000.0).collect());
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use i_overlay::i_float::int::point::IntPoint;

    fn square(side: i32) -> Vec<IntShape<i32>> {
        vec![vec![vec![IntPoint::new(0, 0), IntPoint::new(side, 0), IntPoint::new(side, side), IntPoint::new(0, side)]]]
    }

    fn total_len(ls: &[Vec<DVec2>]) -> f64 {
        ls.iter().map(|l| l.windows(2).map(|w| w[0].distance(w[1])).sum::<f64>()).sum()
    }

    #[test]
    fn solid_square_is_one_zigzag_covering_the_area() {
        let lines = rectilinear(&square(10_000), 400.0, 0.0, 40.0);
        assert_eq!(lines.len(), 1, "one connected zig-zag");
        // 25 lines of 10 mm plus connectors of 0.4 mm.
        let len = total_len(&lines);
        assert!((len - (25.0 * 10.0 + 24.0 * 0.4)).abs() < 1e-6, "{len}");
        for p in &lines[0] {
            assert!(p.x >= -1e-9 && p.x <= 10.0 + 1e-9 && p.y >= -1e-9 && p.y <= 10.0 + 1e-9);
        }
    }

    #[test]
    fn diagonal_lines_cover_area() {
        let lines = rectilinear(&square(10_000), 400.0, std::f64::consts::FRAC_PI_4, 40.0);
        let len = total_len(&lines);
        assert!((len * 0.4 - 100.0).abs() < 8.0, "{len}");
    }

    #[test]
    fn lines_do_not_cross_a_hole() {
        let mut a = square(10_000);
        a[0].push(vec![IntPoint::new(3_000, 3_000), IntPoint::new(3_000, 7_000), IntPoint::new(7_000, 7_000), IntPoint::new(7_000, 3_000)]);
        let lines = rectilinear(&a, 400.0, 0.0, 40.0);
        for l in &lines {
            for w in l.windows(2) {
                let m = (w[0] + w[1]) * 0.5;
                assert!(!(m.x > 3.0 + 1e-9 && m.x < 7.0 - 1e-9 && m.y > 3.0 + 1e-9 && m.y < 7.0 - 1e-9), "{m:?}");
            }
        }
    }
}

//! Overhanging stretches of perimeter loops: where a loop's centre line leaves the region of
//! the layer below, more than half the bead hangs over air.
//!
//! The lower layer's outline edges are bucketed in horizontal strips; each loop segment is
//! split where it crosses that outline and every piece is classed by its middle (even–odd
//! test). Runs shorter than a line width are then merged into their neighbours, and split
//! points that no longer separate two classes are removed again, so a loop that does not
//! overhang keeps exactly its points.

use super::order::Loop;
use crate::geom::tolerance::UNITS_PER_MM;
use crate::geom::DVec2;
use i_overlay::i_shape::int::shape::IntShapes;

/// The outline of a layer's regions, indexed by Y for point and crossing queries, mm.
pub(crate) struct Lower {
    y0: f64,
    y1: f64,
    inv: f64,
    strips: Vec<Vec<[DVec2; 2]>>,
}

impl Lower {
    pub(crate) fn new(shapes: &IntShapes<i32>) -> Lower {
        let mut edges = Vec::new();
        for c in shapes.iter().flat_map(|s| s.iter()) {
            let n = c.len();
            for i in 0..n {
                let (a, b) = (c[i], c[(i + 1) % n]);
                let a = DVec2::new(a.x as f64, a.y as f64) / UNITS_PER_MM;
                let b = DVec2::new(b.x as f64, b.y as f64) / UNITS_PER_MM;
                if a != b {
                    edges.push([a, b]);
                }
            }
        }
        let (mut y0, mut y1) = (f64::INFINITY, f64::NEG_INFINITY);
        for e in &edges {
            y0 = y0.min(e[0].y).min(e[1].y);
            y1 = y1.max(e[0].y).max(e[1].y);
        }
        let k = ((edges.len() as f64).sqrt().ceil() as usize).clamp(1, 4096);
        let inv = if y1 > y0 { k as f64 / (y1 - y0) } else { 0.0 };
        let mut lower = Lower { y0, y1, inv, strips: vec![Vec::new(); k] };
        for e in edges {
            let (s0, s1) = (lower.strip(e[0].y.min(e[1].y)), lower.strip(e[0].y.max(e[1].y)));
            for s in s0..=s1 {
                lower.strips[s].push(e);
            }
        }
        lower
    }

    fn strip(&self, y: f64) -> usize {
        let s = ((y - self.y0) * self.inv).floor();
        if s.is_finite() {
            s.clamp(0.0, (self.strips.len() - 1) as f64) as usize
        } else {
            0
        }
    }

    /// Even–odd: is `p` inside the regions?
    pub(crate) fn contains(&self, p: DVec2) -> bool {
        if !(p.y >= self.y0 && p.y <= self.y1) {
            return false;
        }
        let mut inside = false;
        for [a, b] in &self.strips[self.strip(p.y)] {
            if (a.y > p.y) != (b.y > p.y) && p.x < a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x) {
                inside = !inside;
            }
        }
        inside
    }

    /// Parameters in (0, 1) where segment `a`–`b` crosses the outline, appended to `out`
    /// (unsorted, possibly repeated).
    fn crossings(&self, a: DVec2, b: DVec2, out: &mut Vec<f64>) {
        let (lo, hi) = (a.y.min(b.y), a.y.max(b.y));
        if hi < self.y0 || lo > self.y1 {
            return;
        }
        let d = b - a;
        for s in self.strip(lo)..=self.strip(hi) {
            for [c, e] in &self.strips[s] {
                let f = *e - *c;
                let den = d.perp_dot(f);
                if den == 0.0 {
                    continue;
                }
                let ac = *c - a;
                let t = ac.perp_dot(f) / den;
                let u = ac.perp_dot(d) / den;
                if t > 0.0 && t < 1.0 && (0.0..=1.0).contains(&u) {
                    out.push(t);
                }
            }
        }
    }
}

/// `pts` (a closed loop, mm) with each segment classed as hanging over air (outside `lower`)
/// or not; runs shorter than `width` mm take their neighbours' class.
pub(crate) fn classify(pts: Vec<DVec2>, lower: &Lower, width: f64) -> Loop {
    let n = pts.len();
    let mut out: Vec<DVec2> = Vec::with_capacity(n);
    let mut over: Vec<bool> = Vec::with_capacity(n);
    let mut inserted: Vec<bool> = Vec::with_capacity(n);
    let mut ts = Vec::new();
    for k in 0..n {
        let (a, b) = (pts[k], pts[(k + 1) % n]);
        let len = a.distance(b);
        ts.clear();
        lower.crossings(a, b, &mut ts);
        ts.sort_by(f64::total_cmp);
        out.push(a);
        inserted.push(false);
        let mut t0 = 0.0;
        for &t in &ts {
            // Pieces under 0.1 µm are not worth a point.
            if (t - t0) * len < 1e-4 || (1.0 - t) * len < 1e-4 {
                continue;
            }
            over.push(!lower.contains(a.lerp(b, (t0 + t) / 2.0)));
            out.push(a.lerp(b, t));
            inserted.push(true);
            t0 = t;
        }
        over.push(!lower.contains(a.lerp(b, (t0 + 1.0) / 2.0)));
    }
    merge_short_runs(&out, &mut over, width);
    // Split points that separate nothing any more go again.
    let m = out.len();
    if inserted.iter().any(|&x| x) {
        let keep: Vec<bool> = (0..m).map(|j| !inserted[j] || over[(j + m - 1) % m] != over[j]).collect();
        let pts: Vec<DVec2> = (0..m).filter(|&j| keep[j]).map(|j| out[j]).collect();
        let fl: Vec<bool> = (0..m).filter(|&j| keep[j]).map(|j| over[j]).collect();
        return Loop { pts, over: fl };
    }
    Loop { pts: out, over }
}

/// Flips the shortest run of segments shorter than `width` (joining it to its neighbours)
/// until none is left or the loop is one run.
fn merge_short_runs(pts: &[DVec2], over: &mut [bool], width: f64) {
    let m = pts.len();
    let seg = |j: usize| pts[j].distance(pts[(j + 1) % m]);
    loop {
        let Some(start) = (0..m).find(|&j| over[j] != over[(j + m - 1) % m]) else { return };
        // Runs from a class boundary round the loop: (first segment, count, length).
        let mut runs: Vec<(usize, usize, f64)> = Vec::new();
        for s in 0..m {
            let j = (start + s) % m;
            if s == 0 || over[j] != over[(j + m - 1) % m] {
                runs.push((j, 0, 0.0));
            }
            let r = runs.last_mut().unwrap_or_else(|| unreachable!());
            r.1 += 1;
            r.2 += seg(j);
        }
        let Some(&(j, count, len)) = runs.iter().min_by(|a, b| a.2.total_cmp(&b.2)) else { return };
        if len >= width {
            return;
        }
        for s in 0..count {
            let q = (j + s) % m;
            over[q] = !over[q];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use i_overlay::i_float::int::point::IntPoint;

    fn rect(x0: i32, y0: i32, x1: i32, y1: i32) -> IntShapes<i32> {
        vec![vec![vec![IntPoint::new(x0, y0), IntPoint::new(x1, y0), IntPoint::new(x1, y1), IntPoint::new(x0, y1)]]]
    }

    #[test]
    fn ledge_splits_at_the_lower_outline() {
        // A 10 mm square below, a 30 × 10 mm slab's perimeter above.
        let lower = Lower::new(&rect(-5000, -5000, 5000, 5000));
        let slab = vec![DVec2::new(-14.8, -4.8), DVec2::new(14.8, -4.8), DVec2::new(14.8, 4.8), DVec2::new(-14.8, 4.8)];
        let l = classify(slab, &lower, 0.4);
        assert_eq!(l.pts.len(), 8, "{:?}", l.pts);
        let over_len: f64 = (0..l.pts.len()).filter(|&j| l.over[j]).map(|j| l.pts[j].distance(l.pts[(j + 1) % l.pts.len()])).sum();
        // 2 × (9.8 + 9.6 + 9.8) mm hang.
        assert!((over_len - 58.4).abs() < 1e-6, "{over_len}");
        // Resting entirely on the layer below: unchanged, nothing hangs.
        let sq = vec![DVec2::new(-4.8, -4.8), DVec2::new(4.8, -4.8), DVec2::new(4.8, 4.8), DVec2::new(-4.8, 4.8)];
        let l = classify(sq.clone(), &lower, 0.4);
        assert_eq!(l.pts, sq);
        assert!(l.over.iter().all(|&o| !o));
        // A sliver of overhang (0.1 mm past the edge, 0.1 mm long) is merged away.
        let nub = vec![
            DVec2::new(-4.8, -4.8),
            DVec2::new(4.8, -4.8),
            DVec2::new(4.8, 0.0),
            DVec2::new(5.1, 0.0),
            DVec2::new(5.1, 0.1),
            DVec2::new(4.8, 0.1),
            DVec2::new(4.8, 4.8),
            DVec2::new(-4.8, 4.8),
        ];
        let l = classify(nub.clone(), &lower, 0.4);
        assert_eq!(l.pts, nub);
        assert!(l.over.iter().all(|&o| !o));
    }
}

//! Lines that would end in air: a bead is held when the layer below printed something within
//! one line width of its centre (the two beads overlap or touch). Along a line, a stretch that
//! is not held is kept when it lies inside one straight segment held at both ends (a bridge);
//! any other stretch no longer than `max_cut` (a stub past the last line below, a connector
//! over a gap) is cut out of the line, leaving two pieces or one. Longer stretches are real
//! overhangs and stay (support holds them, or the user chose to print them into air).
//!
//! Used for the support's own lines (everything unheld is cut) and for the part's infill
//! (only stubs and connectors are cut: `Sparse` below).

use crate::geom::DVec2;

/// The pieces of `line` (mm) to print: held samples (every `step` mm), bridges, and unheld
/// stretches longer than `max_cut`; pieces shorter than `min_len` are dropped.
pub(crate) fn held_pieces(line: &[DVec2], held: &dyn Fn(DVec2) -> bool, step: f64, min_len: f64, max_cut: f64, out: &mut Vec<Vec<DVec2>>) {
    struct S {
        seg: usize,
        p: DVec2,
        keep: bool,
    }
    let mut samples: Vec<S> = Vec::new();
    for (seg, w) in line.windows(2).enumerate() {
        let (a, b) = (w[0], w[1]);
        let k = ((a.distance(b) / step).ceil().min(1e6) as usize).max(1);
        let start = samples.len();
        for i in 0..=k {
            let p = a.lerp(b, i as f64 / k as f64);
            samples.push(S { seg, p, keep: held(p) });
        }
        // Inside one straight segment, what lies between two held samples is a bridge.
        let range = &mut samples[start..];
        if let (Some(f), Some(l)) = (range.iter().position(|s| s.keep), range.iter().rposition(|s| s.keep)) {
            for s in &mut range[f..=l] {
                s.keep = true;
            }
        }
    }
    if max_cut.is_finite() {
        let mut i = 0;
        while i < samples.len() {
            if samples[i].keep {
                i += 1;
                continue;
            }
            let mut j = i;
            let mut len = 0.0;
            while j + 1 < samples.len() && !samples[j + 1].keep {
                len += samples[j].p.distance(samples[j + 1].p);
                j += 1;
            }
            if len > max_cut {
                for s in &mut samples[i..=j] {
                    s.keep = true;
                }
            }
            i = j + 1;
        }
    }
    let flush = |piece: &mut Vec<(usize, DVec2)>, out: &mut Vec<Vec<DVec2>>| {
        let pts: Vec<DVec2> = piece.drain(..).map(|(_, p)| p).collect();
        if pts.len() >= 2 && pts.windows(2).map(|w| w[0].distance(w[1])).sum::<f64>() >= min_len {
            out.push(pts);
        }
    };
    let mut piece: Vec<(usize, DVec2)> = Vec::new();
    // The segment of the last interval added to the piece: another interval of it moves the
    // piece's end instead of adding a point.
    let mut along: Option<usize> = None;
    for k in 1..samples.len() {
        let (a, b) = (&samples[k - 1], &samples[k]);
        if !(a.keep && b.keep) {
            flush(&mut piece, out);
            along = None;
            continue;
        }
        if a.seg != b.seg {
            continue; // the shared vertex: the same point twice
        }
        if piece.is_empty() {
            piece.push((a.seg, a.p));
        }
        if along == Some(b.seg) {
            if let Some(last) = piece.last_mut() {
                last.1 = b.p;
            }
        } else {
            piece.push((b.seg, b.p));
            along = Some(b.seg);
        }
    }
    flush(&mut piece, out);
}

/// Segments of one layer's lines in buckets of a square grid, for "is anything within `reach`
/// of this point" queries.
pub(crate) struct Near {
    reach: f64,
    cell: f64,
    min: DVec2,
    nx: usize,
    ny: usize,
    start: Vec<u32>,
    segs: Vec<(DVec2, DVec2)>,
}

impl Near {
    /// The segments of `lines` (mm), queried within `reach` mm.
    pub(crate) fn new<'a>(lines: impl Iterator<Item = &'a [DVec2]> + Clone, reach: f64) -> Near {
        let cell = (4.0 * reach).max(1e-3);
        let mut lo = DVec2::splat(f64::INFINITY);
        let mut hi = DVec2::splat(f64::NEG_INFINITY);
        for p in lines.clone().flatten() {
            lo = lo.min(*p);
            hi = hi.max(*p);
        }
        if !lo.is_finite() {
            return Near { reach, cell, min: DVec2::ZERO, nx: 0, ny: 0, start: vec![0], segs: Vec::new() };
        }
        let min = lo - DVec2::splat(reach);
        let nx = (((hi.x - lo.x + 2.0 * reach) / cell).ceil() as usize).clamp(1, 2048);
        let ny = (((hi.y - lo.y + 2.0 * reach) / cell).ceil() as usize).clamp(1, 2048);
        let cell_of = |v: f64, m: f64, n: usize| (((v - m) / cell).floor().max(0.0) as usize).min(n - 1);
        // Counting sort of (cell, segment) pairs.
        // Each segment goes into the cells within `reach` of it: walked in steps of half a
        // cell, each step's cell and its neighbours (a reach is a quarter cell), so a long
        // diagonal line costs its length, not its bounding box.
        let mut pairs: Vec<(u32, (DVec2, DVec2))> = Vec::new();
        let mut cells: Vec<u32> = Vec::new();
        for l in lines {
            for w in l.windows(2) {
                let (a, b) = (w[0], w[1]);
                let steps = ((a.distance(b) / (0.5 * cell)).ceil() as usize).clamp(1, 1 << 20);
                cells.clear();
                for k in 0..=steps {
                    let p = a.lerp(b, k as f64 / steps as f64);
                    let (cx, cy) = (cell_of(p.x, min.x, nx), cell_of(p.y, min.y, ny));
                    for y in cy.saturating_sub(1)..=(cy + 1).min(ny - 1) {
                        for x in cx.saturating_sub(1)..=(cx + 1).min(nx - 1) {
                            cells.push((y * nx + x) as u32);
                        }
                    }
                }
                cells.sort_unstable();
                cells.dedup();
                pairs.extend(cells.iter().map(|&c| (c, (a, b))));
            }
        }
        let mut start = vec![0u32; nx * ny + 1];
        for (c, _) in &pairs {
            start[*c as usize + 1] += 1;
        }
        for i in 0..nx * ny {
            start[i + 1] += start[i];
        }
        let mut fill = start.clone();
        let mut segs = vec![(DVec2::ZERO, DVec2::ZERO); pairs.len()];
        for (c, s) in pairs {
            segs[fill[c as usize] as usize] = s;
            fill[c as usize] += 1;
        }
        Near { reach, cell, min, nx, ny, start, segs }
    }

    /// Whether a segment passes within `reach` of `p`.
    pub(crate) fn holds(&self, p: DVec2) -> bool {
        self.within(p, self.reach)
    }

    /// Whether a segment passes within `r` (at most the reach it was built for) of `p`.
    pub(crate) fn within(&self, p: DVec2, r: f64) -> bool {
        if self.nx == 0 {
            return false;
        }
        let fx = ((p.x - self.min.x) / self.cell).floor();
        let fy = ((p.y - self.min.y) / self.cell).floor();
        if fx < 0.0 || fy < 0.0 || fx >= self.nx as f64 || fy >= self.ny as f64 {
            return false;
        }
        let c = fy as usize * self.nx + fx as usize;
        let r2 = r.min(self.reach) * r.min(self.reach);
        self.segs[self.start[c] as usize..self.start[c + 1] as usize].iter().any(|&(a, b)| {
            let d = b - a;
            let len2 = d.length_squared();
            let t = if len2 > 0.0 { ((p - a).dot(d) / len2).clamp(0.0, 1.0) } else { 0.0 };
            p.distance_squared(a + d * t) <= r2
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stubs_are_cut_bridges_and_long_overhangs_stay() {
        // Material below: two lines across Y at x = 2 and x = 8.
        let below = [vec![DVec2::new(2.0, -5.0), DVec2::new(2.0, 5.0)], vec![DVec2::new(8.0, -5.0), DVec2::new(8.0, 5.0)]];
        let near = Near::new(below.iter().map(|l| l.as_slice()), 0.36);
        let held = |p: DVec2| near.holds(p);
        // A straight line from x = 0 to x = 10: the middle is a bridge, the stubs are cut.
        let mut out = Vec::new();
        held_pieces(&[DVec2::new(0.0, 0.0), DVec2::new(10.0, 0.0)], &held, 0.1, 0.4, 3.0, &mut out);
        assert_eq!(out.len(), 1);
        assert!((out[0][0].x - 1.7).abs() < 0.11 && (out[0][out[0].len() - 1].x - 8.3).abs() < 0.11, "{:?}", out[0]);
        // A bend over air (two segments) is cut at the corner: two pieces.
        let mut out = Vec::new();
        held_pieces(&[DVec2::new(2.0, 0.0), DVec2::new(5.0, 0.0), DVec2::new(8.0, 0.0)], &held, 0.1, 0.1, 10.0, &mut out);
        assert_eq!(out.len(), 2, "{out:?}");
        // The same with max_cut shorter than the stretch: kept whole.
        let mut out = Vec::new();
        held_pieces(&[DVec2::new(2.0, 0.0), DVec2::new(5.0, 0.0), DVec2::new(8.0, 0.0)], &held, 0.1, 0.1, 2.0, &mut out);
        assert_eq!(out.len(), 1);
        assert_eq!(out[0].len(), 3, "collinear samples merged: {:?}", out[0]);
    }
}

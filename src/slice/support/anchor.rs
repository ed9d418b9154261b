//! Support must not print into air itself: each support line is checked against what the
//! layer below printed (the part's regions and that layer's support lines), on a raster of a
//! quarter line width. A point is held when the layer below has material within one line
//! width of it (its bead then overlaps the bead below by at least half its width... touching
//! it). A stretch of points that are not held is kept only when it lies inside one straight
//! segment held at both ends (a bridge); any other is cut out of the line.

use super::{Input, LayerSupport};
use crate::geom::DVec2;
use crate::slice::anchor::held_pieces;
use i_overlay::i_shape::int::shape::IntShapes;

/// A bit raster over a rectangle, cells of `px` mm.
struct Raster {
    min: DVec2,
    px: f64,
    nx: usize,
    ny: usize,
    bits: Vec<u64>,
}

impl Raster {
    fn new(min: DVec2, max: DVec2, px: f64) -> Raster {
        let nx = (((max.x - min.x) / px).ceil() as usize + 1).max(1);
        let ny = (((max.y - min.y) / px).ceil() as usize + 1).max(1);
        Raster { min, px, nx, ny, bits: vec![0; (nx * ny).div_ceil(64)] }
    }
    fn set(&mut self, x: usize, y: usize) {
        let k = y * self.nx + x;
        self.bits[k / 64] |= 1 << (k % 64);
    }
    fn get(&self, p: DVec2) -> bool {
        let fx = ((p.x - self.min.x) / self.px).round();
        let fy = ((p.y - self.min.y) / self.px).round();
        if fx < 0.0 || fy < 0.0 || fx >= self.nx as f64 || fy >= self.ny as f64 {
            return false;
        }
        let k = fy as usize * self.nx + fx as usize;
        self.bits[k / 64] & (1 << (k % 64)) != 0
    }
    /// Cells whose centre lies within `r` mm of segment `a`–`b`.
    fn capsule(&mut self, a: DVec2, b: DVec2, r: f64) {
        let lo = a.min(b) - DVec2::splat(r);
        let hi = a.max(b) + DVec2::splat(r);
        let x0 = ((lo.x - self.min.x) / self.px).floor().max(0.0) as usize;
        let y0 = ((lo.y - self.min.y) / self.px).floor().max(0.0) as usize;
        let x1 = (((hi.x - self.min.x) / self.px).ceil().max(0.0) as usize).min(self.nx - 1);
        let y1 = (((hi.y - self.min.y) / self.px).ceil().max(0.0) as usize).min(self.ny - 1);
        let d = b - a;
        let len2 = d.length_squared();
        for y in y0..=y1 {
            for x in x0..=x1 {
                let p = self.min + DVec2::new(x as f64, y as f64) * self.px;
                let t = if len2 > 0.0 { ((p - a).dot(d) / len2).clamp(0.0, 1.0) } else { 0.0 };
                if p.distance_squared(a + d * t) <= r * r {
                    self.set(x, y);
                }
            }
        }
    }
    /// Cells whose centre lies inside `shapes` (µm, even–odd), by rows of edge crossings.
    fn fill(&mut self, shapes: &IntShapes<i32>) {
        let mut rows: Vec<Vec<f64>> = vec![Vec::new(); self.ny];
        for c in shapes.iter().flat_map(|s| s.iter()) {
            let m = c.len();
            for i in 0..m {
                let (a, b) = (c[i], c[(i + 1) % m]);
                let (ay, by) = (a.y as f64 / 1000.0, b.y as f64 / 1000.0);
                if ay == by {
                    continue;
                }
                let (ax, bx) = (a.x as f64 / 1000.0, b.x as f64 / 1000.0);
                let (ylo, yhi) = (ay.min(by), ay.max(by));
                let r0 = ((ylo - self.min.y) / self.px).ceil().max(0.0);
                let r1 = ((yhi - self.min.y) / self.px).ceil().min(self.ny as f64);
                let mut r = r0;
                while r < r1 {
                    let y = self.min.y + r * self.px;
                    rows[r as usize].push(ax + (y - ay) / (by - ay) * (bx - ax));
                    r += 1.0;
                }
            }
        }
        for (y, xs) in rows.iter_mut().enumerate() {
            xs.sort_by(f64::total_cmp);
            for pair in xs.chunks_exact(2) {
                let x0 = ((pair[0] - self.min.x) / self.px).ceil().max(0.0) as usize;
                let x1 = ((pair[1] - self.min.x) / self.px).floor();
                if x1 < 0.0 {
                    continue;
                }
                for x in x0..=(x1 as usize).min(self.nx - 1) {
                    self.set(x, y);
                }
            }
        }
    }
}

/// The support of each layer, cut back to what the layer below holds (the first layer rests
/// on the plate). Layers are checked bottom up, each against what was kept below it.
pub(crate) fn anchor(input: &Input, raw: Vec<LayerSupport>) -> Vec<LayerSupport> {
    let w = input.w_um as f64 / 1000.0;
    let px = w / 4.0;
    let reach = 1.05 * w;
    let step = px;
    let mut out: Vec<LayerSupport> = Vec::with_capacity(raw.len());
    for (j, layer) in raw.into_iter().enumerate() {
        if j == 0 || (layer.base.is_empty() && layer.interface.is_empty()) {
            out.push(layer);
            continue;
        }
        let mut lo = DVec2::splat(f64::INFINITY);
        let mut hi = DVec2::splat(f64::NEG_INFINITY);
        for p in layer.base.iter().chain(&layer.interface).flatten() {
            lo = lo.min(*p);
            hi = hi.max(*p);
        }
        let (lo, hi) = (lo - DVec2::splat(2.0 * w), hi + DVec2::splat(2.0 * w));
        // At most about 50 M cells (6 MiB) and a million rows, whatever the part's size: a
        // coarser raster only errs on the generous side.
        let span = hi - lo;
        let px = px.max((span.x * span.y / 5e7).sqrt()).max(span.x.max(span.y) / 1e6);
        let mut r = Raster::new(lo, hi, px);
        // The part below holds a bead whose centre is within half a line of its outline.
        let part = crate::slice::perimeters::outset(&input.part[j - 1], (input.w_um / 2).max(1));
        r.fill(&part);
        let below = &out[j - 1];
        for l in below.base.iter().chain(&below.interface) {
            for s in l.windows(2) {
                r.capsule(s[0], s[1], reach);
            }
        }
        let held = |p: DVec2| r.get(p);
        let mut kept = LayerSupport::default();
        for l in &layer.base {
            held_pieces(l, &held, step, w, f64::INFINITY, &mut kept.base);
        }
        for l in &layer.interface {
            held_pieces(l, &held, step, w, f64::INFINITY, &mut kept.interface);
        }
        out.push(kept);
    }
    out
}

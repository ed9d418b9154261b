//! Re-entrant (bow-tie) honeycomb.
//!
//! Hexagons with two vertical sides `s = 2h/3` long at `x = ±w/2` and their top and bottom
//! corners pulled inward by `h/6` (the re-entrant angle `atan(h / (3w))` below the horizontal
//! for the inclined struts). Rows `h/2` apart, every other row shifted by `w/2`; the unit cell
//! (one period in X and Y) is `w × h` and holds two bow-ties (six struts).

use super::graph::{Graph, Rect};
use crate::geom::DVec2;

/// Bow-tie cells, unit cell `w × h`, covering `rect`.
pub(crate) fn reentrant(w: f64, h: f64, rect: Rect) -> Graph {
    let mut g = Graph::default();
    let row = h * 0.5; // vertical distance between rows: side − inset
    let side = h * 2.0 / 3.0;
    let inset = h / 6.0;
    let (j0, j1) = (libm::floor(rect.min.y / row) as i64 - 1, libm::ceil(rect.max.y / row) as i64 + 1);
    for j in j0..=j1 {
        let shift = if j.rem_euclid(2) == 1 { w * 0.5 } else { 0.0 };
        let (i0, i1) = (libm::floor((rect.min.x - shift) / w) as i64 - 1, libm::ceil((rect.max.x - shift) / w) as i64 + 1);
        let cy = row * j as f64;
        for i in i0..=i1 {
            let cx = w * i as f64 + shift;
            let (l, r) = (cx - w * 0.5, cx + w * 0.5);
            let (b, t) = (cy - side * 0.5, cy + side * 0.5);
            let hex = [DVec2::new(r, b), DVec2::new(r, t), DVec2::new(cx, t - inset), DVec2::new(l, t), DVec2::new(l, b), DVec2::new(cx, b + inset)];
            g.polyline(&hex, true);
        }
    }
    g
}

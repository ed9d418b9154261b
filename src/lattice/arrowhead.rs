//! Arrowhead (double-arrowhead) auxetic lattice.
//!
//! Unit cell `w × h` with its tips at `(i·w, j·h)`: an outer chevron from tip to tip through
//! `(i·w + w/2, j·h + h/2)`, an inner chevron from the same tips through
//! `(i·w + w/2, j·h + h/4)` — together an arrowhead-shaped pore pointing +Y — and a vertical
//! strut joining each tip to the tip above. The remaining pore, between an outer chevron and
//! the inner chevron of the row above, is a larger arrowhead with straight sides; under
//! tension along Y both chevrons open out and the lattice widens (negative Poisson's ratio).
//! Five struts per unit cell.

use super::graph::{Graph, Rect};
use crate::geom::DVec2;

/// Outer chevron depth as a fraction of the cell height.
pub const OUTER_DEPTH: f64 = 0.5;
/// Inner chevron depth as a fraction of the cell height.
pub const INNER_DEPTH: f64 = 0.25;

/// Arrowhead cells `w × h` covering `rect`.
pub(crate) fn arrowhead(w: f64, h: f64, rect: Rect) -> Graph {
    let mut g = Graph::default();
    let (i0, i1) = (libm::floor(rect.min.x / w) as i64 - 1, libm::ceil(rect.max.x / w) as i64 + 1);
    let (j0, j1) = (libm::floor(rect.min.y / h) as i64 - 1, libm::ceil(rect.max.y / h) as i64 + 1);
    for j in j0..=j1 {
        for i in i0..=i1 {
            let (x, y) = (w * i as f64, h * j as f64);
            let tip = DVec2::new(x, y);
            let next = DVec2::new(w * (i + 1) as f64, y);
            let outer = DVec2::new(x + w * 0.5, y + h * OUTER_DEPTH);
            let inner = DVec2::new(x + w * 0.5, y + h * INNER_DEPTH);
            g.polyline(&[tip, outer, next], false);
            g.polyline(&[tip, inner, next], false);
            if j < j1 {
                g.seg(tip, DVec2::new(x, h * (j + 1) as f64));
            }
        }
    }
    g
}

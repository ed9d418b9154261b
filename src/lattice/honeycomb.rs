//! Regular honeycomb: pointy-top hexagons of circumradius `r` (edge length `r`), one hexagon
//! centred on the origin.

use super::graph::{sqrt3, Graph, Rect};
use crate::geom::DVec2;

/// Hexagon corners in units of (r·√3/2, r/2) around the centre, counter-clockwise.
const CORNERS: [(i64, i64); 6] = [(0, 2), (-1, 1), (-1, -1), (0, -2), (1, -1), (1, 1)];

/// Hexagons of circumradius `r` covering `rect`.
pub(crate) fn honeycomb(r: f64, rect: Rect) -> Graph {
    let mut g = Graph::default();
    let s = r * sqrt3() * 0.5;
    let h = r * 0.5;
    // Centre (i, j) is at (s·(2i + j), 3h·j); corners at (s·(2i + j + dx), h·(3j + dy)).
    let (j0, j1) = (libm::floor((rect.min.y - r) / (3.0 * h)) as i64, libm::ceil((rect.max.y + r) / (3.0 * h)) as i64);
    let p = |a: i64, b: i64| DVec2::new(s * a as f64, h * b as f64);
    for j in j0..=j1 {
        let i0 = libm::floor((rect.min.x - 2.0 * s) / (2.0 * s) - j as f64 * 0.5) as i64;
        let i1 = libm::ceil((rect.max.x + 2.0 * s) / (2.0 * s) - j as f64 * 0.5) as i64;
        for i in i0..=i1 {
            let (cx, cy) = (2 * i + j, 3 * j);
            for k in 0..6 {
                let (ax, ay) = CORNERS[k];
                let (bx, by) = CORNERS[(k + 1) % 6];
                g.seg(p(cx + ax, cy + ay), p(cx + bx, cy + by));
            }
        }
    }
    g
}

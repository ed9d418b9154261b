//! Rectilinear lines, square grid and equilateral triangle grid, all through the origin.

use super::graph::{sqrt3, Graph, Rect};
use crate::geom::DVec2;

/// Lines along X at `y = k·s` spanning the rectangle (one edge per line: no nodes).
pub(crate) fn rectilinear(s: f64, r: Rect) -> Graph {
    let mut g = Graph::default();
    let (k0, k1) = (libm::floor(r.min.y / s) as i64, libm::ceil(r.max.y / s) as i64);
    for k in k0..=k1 {
        let y = s * k as f64;
        g.seg(DVec2::new(r.min.x, y), DVec2::new(r.max.x, y));
    }
    g
}

/// Square cells of side `c` with nodes at `(i·c, j·c)`; one edge per strut between nodes.
pub(crate) fn square(c: f64, r: Rect) -> Graph {
    let mut g = Graph::default();
    let (i0, i1) = (libm::floor(r.min.x / c) as i64, libm::ceil(r.max.x / c) as i64);
    let (j0, j1) = (libm::floor(r.min.y / c) as i64, libm::ceil(r.max.y / c) as i64);
    let p = |i: i64, j: i64| DVec2::new(c * i as f64, c * j as f64);
    for j in j0..=j1 {
        for i in i0..=i1 {
            if i < i1 {
                g.seg(p(i, j), p(i + 1, j));
            }
            if j < j1 {
                g.seg(p(i, j), p(i, j + 1));
            }
        }
    }
    g
}

/// Equilateral triangles of side `c`: nodes at `(c/2·(2i + j), c·√3/2·j)`, each joined to its
/// six neighbours.
pub(crate) fn triangle(c: f64, r: Rect) -> Graph {
    let mut g = Graph::default();
    let hx = c * 0.5;
    let hy = c * sqrt3() * 0.5;
    let (j0, j1) = (libm::floor(r.min.y / hy) as i64, libm::ceil(r.max.y / hy) as i64);
    let p = |i: i64, j: i64| DVec2::new(hx * (2 * i + j) as f64, hy * j as f64);
    for j in j0..=j1 {
        let i0 = libm::floor(r.min.x / c - j as f64 * 0.5) as i64 - 1;
        let i1 = libm::ceil(r.max.x / c - j as f64 * 0.5) as i64 + 1;
        for i in i0..=i1 {
            g.seg(p(i, j), p(i + 1, j));
            if j < j1 {
                g.seg(p(i, j), p(i, j + 1));
                g.seg(p(i, j), p(i - 1, j + 1));
            }
        }
    }
    g
}

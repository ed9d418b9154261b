//! Snub-square tiling (3.3.4.3.4) with edge `a`.
//!
//! Squares of side `a` centred on the lattice `(m·L, n·L)`, `L = a·(√2 + √6)/2`, turned by
//! +15°, and (implicitly) squares centred on `((m + ½)·L, (n + ½)·L)` turned by −15°; every
//! vertex belongs to one square of each kind. The vertices are the first squares' corners,
//! `(m·L, n·L) + (p, q), (−q, p), (−p, −q), (q, −p)` with `p = a·√2/4`, `q = a·√6/4`; the edges
//! are all vertex pairs `a` apart (square sides and triangle sides; nothing else is `a` apart).

use super::graph::{Graph, Rect};
use crate::geom::DVec2;

/// Snub-square tiling of edge `a` covering `rect`.
pub(crate) fn snub_square(a: f64, rect: Rect) -> Graph {
    let mut g = Graph::default();
    let p = a * 2f64.sqrt() * 0.25;
    let q = a * 6f64.sqrt() * 0.25;
    let l = 2.0 * (p + q);
    let off = [DVec2::new(p, q), DVec2::new(-q, p), DVec2::new(-p, -q), DVec2::new(q, -p)];
    let v = |m: i64, n: i64, k: usize| DVec2::new(l * m as f64, l * n as f64) + off[k];
    let (m0, m1) = (libm::floor(rect.min.x / l) as i64 - 1, libm::ceil(rect.max.x / l) as i64 + 1);
    let (n0, n1) = (libm::floor(rect.min.y / l) as i64 - 1, libm::ceil(rect.max.y / l) as i64 + 1);
    let tol = a * 1e-9;
    for n in n0..=n1 {
        for m in m0..=m1 {
            for k in 0..4 {
                let here = v(m, n, k);
                for dn in -1..=1 {
                    for dm in -1..=1 {
                        let (mm, nn) = (m + dm, n + dn);
                        if mm < m0 || mm > m1 || nn < n0 || nn > n1 {
                            continue;
                        }
                        for kk in 0..4 {
                            let there = v(mm, nn, kk);
                            if ((there - here).length() - a).abs() <= tol {
                                g.seg(here, there);
                            }
                        }
                    }
                }
            }
        }
    }
    g
}

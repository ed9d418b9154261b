//! Penrose rhombus (P3) tiling by Robinson-triangle deflation.
//!
//! A sun of 10 half-rhombus triangles around the origin is deflated `n` times (triangles that
//! cannot reach the fill rectangle are dropped at every step); each triangle `(A, B, C)` is half
//! of a rhombus whose other half shares its base `BC`, so only its legs `CA` and `AB` (the
//! rhombus edges, all `a` long) are output — never the rhombus diagonals.

use super::graph::{Graph, Rect};
use crate::geom::DVec2;

#[derive(Clone, Copy)]
struct Tri {
    thick: bool,
    a: DVec2,
    b: DVec2,
    c: DVec2,
}

fn phi() -> f64 {
    (1.0 + 5f64.sqrt()) * 0.5
}

/// Number of deflations for a sun that covers `rect` with rhombus edge `a`.
fn deflations(a: f64, rect: Rect) -> u32 {
    let far = [rect.min, rect.max, DVec2::new(rect.min.x, rect.max.y), DVec2::new(rect.max.x, rect.min.y)].iter().map(|p| p.length()).fold(0.0, f64::max);
    // The sun's inscribed radius is R·cos 18° > 0.95 R.
    let mut n = 0;
    let mut r = a;
    while r * 0.95 < far + a && n < 200 {
        r *= phi();
        n += 1;
    }
    n
}

/// Penrose P3 tiling with rhombus edge `a` covering `rect` (the sun centred on the origin).
pub(crate) fn penrose(a: f64, rect: Rect) -> Graph {
    let n = deflations(a, rect);
    let radius = a * libm::pow(phi(), n as f64);
    let pi = std::f64::consts::PI;
    let mut tris = Vec::with_capacity(10);
    for i in 0..10 {
        let t1 = (2 * i - 1) as f64 * pi / 10.0;
        let t2 = (2 * i + 1) as f64 * pi / 10.0;
        let mut b = DVec2::new(radius * libm::cos(t1), radius * libm::sin(t1));
        let mut c = DVec2::new(radius * libm::cos(t2), radius * libm::sin(t2));
        if i % 2 == 0 {
            std::mem::swap(&mut b, &mut c);
        }
        tris.push(Tri { thick: false, a: DVec2::ZERO, b, c });
    }
    let keep = rect.grown(a * 0.01);
    let inv = 1.0 / phi();
    for _ in 0..n {
        let mut next = Vec::with_capacity(tris.len() * 3);
        for t in &tris {
            if !t.thick {
                let p = t.a + (t.b - t.a) * inv;
                next.push(Tri { thick: false, a: t.c, b: p, c: t.b });
                next.push(Tri { thick: true, a: p, b: t.c, c: t.a });
            } else {
                let q = t.b + (t.a - t.b) * inv;
                let r = t.b + (t.c - t.b) * inv;
                next.push(Tri { thick: true, a: r, b: t.c, c: t.a });
                next.push(Tri { thick: true, a: q, b: r, c: t.b });
                next.push(Tri { thick: false, a: r, b: q, c: t.a });
            }
        }
        next.retain(|t| {
            let bb = Rect { min: t.a.min(t.b).min(t.c), max: t.a.max(t.b).max(t.c) };
            bb.overlaps(&keep)
        });
        tris = next;
    }
    let mut g = Graph::default();
    for t in &tris {
        g.seg(t.c, t.a);
        g.seg(t.a, t.b);
    }
    g
}

//! Voronoi cells of a Poisson point process.
//!
//! Points: the plane is cut into square blocks holding 8 points on average; block `(bx, by)`
//! draws a Poisson count and uniform positions from its own `Pcg64` stream seeded with the
//! design seed (mixed with a fixed constant and the block index). The points therefore depend
//! only on the seed and the density, never on the layer, its rotation or the fill area.
//!
//! Cells: each point's cell is the fill box clipped by the bisectors of its neighbours, taken
//! nearest first in growing rings of a bucket grid until no farther point can cut the cell
//! (security radius). Cell edges made by the box are not output; an edge made by the bisector
//! with point `j` is output once, by the cell of the lower-numbered point.

use super::graph::{Graph, Rect};
use crate::geom::DVec2;
use rand_core::{Rng, SeedableRng};
use rand_pcg::Pcg64;

/// Mixed into the design seed for Voronoi points (layer-independent).
pub const VORONOI_SEED_SALT: u64 = 0x5EED_0FC0_DEB0_A7A7;

/// Mean points per block.
const PER_BLOCK: f64 = 8.0;

fn mix(mut z: u64) -> u64 {
    // splitmix64 finaliser
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

fn unit(rng: &mut Pcg64) -> f64 {
    (rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// The Poisson points (density per mm²) inside `rect`, in a deterministic order.
pub(crate) fn points(density: f64, seed: u64, rect: Rect) -> Vec<DVec2> {
    let block = (PER_BLOCK / density).sqrt();
    let (bx0, bx1) = (libm::floor(rect.min.x / block) as i64, libm::floor(rect.max.x / block) as i64);
    let (by0, by1) = (libm::floor(rect.min.y / block) as i64, libm::floor(rect.max.y / block) as i64);
    let limit = libm::exp(-PER_BLOCK);
    let mut pts = Vec::new();
    for by in by0..=by1 {
        for bx in bx0..=bx1 {
            let key = mix(mix(seed ^ VORONOI_SEED_SALT) ^ mix(bx as u64).rotate_left(17) ^ mix(by as u64 ^ 0xB10C));
            let mut rng = Pcg64::seed_from_u64(key);
            // Knuth's Poisson sampler.
            let mut count = 0usize;
            let mut prod = unit(&mut rng);
            while prod > limit && count < 64 {
                count += 1;
                prod *= unit(&mut rng);
            }
            let origin = DVec2::new(bx as f64 * block, by as f64 * block);
            for _ in 0..count {
                let p = origin + DVec2::new(unit(&mut rng), unit(&mut rng)) * block;
                if p.x >= rect.min.x && p.x <= rect.max.x && p.y >= rect.min.y && p.y <= rect.max.y {
                    pts.push(p);
                }
            }
        }
    }
    pts
}

/// Clips the convex polygon `poly` (vertex, label of the edge starting there) by the half
/// plane closer to `s` than to `t` (label `lab`).
fn clip(poly: &mut Vec<(DVec2, i64)>, s: DVec2, t: DVec2, lab: i64, scratch: &mut Vec<(DVec2, i64)>) {
    let n = t - s;
    let m = (s + t) * 0.5;
    scratch.clear();
    let k = poly.len();
    for i in 0..k {
        let (v0, l0) = poly[i];
        let (v1, _) = poly[(i + 1) % k];
        let d0 = (v0 - m).dot(n);
        let d1 = (v1 - m).dot(n);
        if d0 <= 0.0 {
            scratch.push((v0, l0));
            if d1 > 0.0 {
                scratch.push((v0 + (v1 - v0) * (d0 / (d0 - d1)), lab));
            }
        } else if d1 <= 0.0 {
            scratch.push((v0 + (v1 - v0) * (d0 / (d0 - d1)), l0));
        }
    }
    std::mem::swap(poly, scratch);
}

/// Voronoi diagram of Poisson points of `density` per mm² (seeded) over `rect`.
pub(crate) fn voronoi(density: f64, seed: u64, rect: Rect) -> Graph {
    let spacing = 1.0 / density.sqrt();
    let area = rect.grown(3.0 * spacing);
    let pts = points(density, seed, area);
    let mut g = Graph::default();
    if pts.is_empty() {
        return g;
    }
    // Bucket grid, about one point per bucket.
    let cell = spacing;
    let nx = (libm::ceil((area.max.x - area.min.x) / cell) as usize).max(1);
    let ny = (libm::ceil((area.max.y - area.min.y) / cell) as usize).max(1);
    let bucket_of = |p: DVec2| -> (usize, usize) {
        let x = (((p.x - area.min.x) / cell) as usize).min(nx - 1);
        let y = (((p.y - area.min.y) / cell) as usize).min(ny - 1);
        (x, y)
    };
    let mut start = vec![0u32; nx * ny + 1];
    for &p in &pts {
        let (x, y) = bucket_of(p);
        start[y * nx + x + 1] += 1;
    }
    for i in 0..nx * ny {
        start[i + 1] += start[i];
    }
    let mut fill = start.clone();
    let mut order = vec![0u32; pts.len()];
    for (i, &p) in pts.iter().enumerate() {
        let (x, y) = bucket_of(p);
        let b = y * nx + x;
        order[fill[b] as usize] = i as u32;
        fill[b] += 1;
    }
    let box_poly = [(area.min, -1i64), (DVec2::new(area.max.x, area.min.y), -1), (area.max, -1), (DVec2::new(area.min.x, area.max.y), -1)];
    let mut poly = Vec::with_capacity(16);
    let mut scratch = Vec::with_capacity(16);
    let mut near: Vec<(f64, u32)> = Vec::new();
    for (i, &s) in pts.iter().enumerate() {
        poly.clear();
        poly.extend_from_slice(&box_poly);
        let (bx, by) = bucket_of(s);
        let mut ring = 0i64;
        loop {
            near.clear();
            for dy in -ring..=ring {
                for dx in -ring..=ring {
                    if dx.abs() != ring && dy.abs() != ring {
                        continue;
                    }
                    let (x, y) = (bx as i64 + dx, by as i64 + dy);
                    if x < 0 || y < 0 || x >= nx as i64 || y >= ny as i64 {
                        continue;
                    }
                    let b = y as usize * nx + x as usize;
                    for &j in &order[start[b] as usize..start[b + 1] as usize] {
                        if j as usize != i {
                            near.push(((pts[j as usize] - s).length_squared(), j));
                        }
                    }
                }
            }
            near.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            for &(_, j) in &near {
                clip(&mut poly, s, pts[j as usize], j as i64, &mut scratch);
            }
            ring += 1;
            // Every point not yet used is farther than `ring_reach` from s.
            let ring_reach = cell * (ring - 1) as f64;
            let reach2 = poly.iter().map(|(v, _)| (*v - s).length_squared()).fold(0.0, f64::max);
            let exhausted = ring as usize > nx.max(ny);
            if exhausted || 4.0 * reach2 <= ring_reach * ring_reach {
                break;
            }
        }
        let k = poly.len();
        for e in 0..k {
            let (v0, lab) = poly[e];
            if lab > i as i64 {
                g.seg(v0, poly[(e + 1) % k].0);
            }
        }
    }
    g
}

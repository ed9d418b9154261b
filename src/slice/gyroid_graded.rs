//! Gyroid infill whose cell size varies from place to place ([`CellField`]).
//!
//! The fixed-cell gyroid ([`super::gyroid`]) is solved in closed form; with a cell size
//! `L(p)` that changes across the part no closed form exists, so here the layer's cut is the
//! zero set of a blended implicit function, traced by marching squares:
//!
//! - cell sizes are snapped to a geometric ladder `L_i = L_ref · 2^(i/4)` and a point with
//!   `L(p)` between `L_i` and `L_{i+1}` takes `G = (1 − t) G_i + t G_{i+1}` (`t` the
//!   fraction of the step in `log L`), `G_i` the gyroid of period `L_i` on the global grid.
//!   Where `L(p) = L_i` exactly the curves are that gyroid's; between, the walls of the two
//!   periods merge continuously (no ends cut at a zone border). Writing
//!   `sin(2π x / L(p))` directly would distort the period by `x · ∇(1/L)`, which grows with the
//!   distance from the origin;
//! - the function is sampled on a square grid of step `L_min / 24` (at most
//!   [`MAX_SAMPLES`] per layer, coarser beyond), crossings placed by linear interpolation
//!   (error `O(h² / L)`, under 1 % of `L`), saddle cells split by the centre value;
//! - crossings are joined into polylines along shared cell edges, thinned to the closed-form
//!   gyroid's chord tolerance ([`super::gyroid::chord_tolerance_um`]) and clipped to the area.
//!
//! In a blend zone the toolpath length per area is between the two periods' (`k_c m / L`),
//! not exactly `k_c m / L(p)`; the grading that uses `L(p)` is exact where the ladder is hit
//! and approximate (by at most the ladder step, 19 %) between.

use super::infill::{clip_polylines, turned_bounds};
use crate::geom::{DVec2, DVec3};
use i_overlay::i_float::int::point::IntPoint;
use i_overlay::i_shape::int::shape::IntShape;
use serde::{Deserialize, Serialize};
use std::f64::consts::TAU;

/// Most samples of the implicit function per layer (the grid coarsens beyond).
pub const MAX_SAMPLES: usize = 4_000_000;
/// Grid steps per smallest cell.
pub const STEPS_PER_CELL: f64 = 24.0;
/// Ladder steps per doubling of the cell size.
pub const LADDER_PER_OCTAVE: f64 = 4.0;

/// A cell size over space: values at the nodes of a regular grid (mm, in the toolpath's
/// frame), trilinear between them, clamped at the edges.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CellField {
    /// The first node, mm.
    pub origin_mm: [f64; 3],
    /// Node spacing, mm (> 0).
    pub step_mm: f64,
    /// Nodes along x, y, z (each ≥ 1).
    pub dims: [usize; 3],
    /// Cell size at each node, mm, x fastest.
    pub cell_mm: Vec<f64>,
    /// The ladder's reference size (the uniform cell), mm.
    pub reference_mm: f64,
}

impl CellField {
    /// The cell size at `p`, mm.
    pub fn at(&self, p: DVec3) -> f64 {
        let mut i0 = [0usize; 3];
        let mut f = [0.0; 3];
        for k in 0..3 {
            let n = self.dims[k];
            let u = ((p[k] - self.origin_mm[k]) / self.step_mm).clamp(0.0, (n - 1) as f64);
            let i = (libm::floor(u) as usize).min(n.saturating_sub(2));
            i0[k] = i;
            f[k] = if n > 1 { u - i as f64 } else { 0.0 };
        }
        let idx = |dx: usize, dy: usize, dz: usize| {
            let x = (i0[0] + dx).min(self.dims[0] - 1);
            let y = (i0[1] + dy).min(self.dims[1] - 1);
            let z = (i0[2] + dz).min(self.dims[2] - 1);
            self.cell_mm[x + self.dims[0] * (y + self.dims[1] * z)]
        };
        let lerp = |a: f64, b: f64, t: f64| a + (b - a) * t;
        let x00 = lerp(idx(0, 0, 0), idx(1, 0, 0), f[0]);
        let x10 = lerp(idx(0, 1, 0), idx(1, 1, 0), f[0]);
        let x01 = lerp(idx(0, 0, 1), idx(1, 0, 1), f[0]);
        let x11 = lerp(idx(0, 1, 1), idx(1, 1, 1), f[0]);
        lerp(lerp(x00, x10, f[1]), lerp(x01, x11, f[1]), f[2])
    }

    /// The smallest and largest node values, mm.
    pub fn range(&self) -> (f64, f64) {
        self.cell_mm.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), &l| (lo.min(l), hi.max(l)))
    }

    /// Whether the field is usable: finite positive sizes, a node per value.
    pub fn is_valid(&self) -> bool {
        let n = self.dims.iter().product::<usize>();
        n > 0
            && self.cell_mm.len() == n
            && self.step_mm > 0.0
            && self.step_mm.is_finite()
            && self.reference_mm > 0.0
            && self.cell_mm.iter().all(|l| l.is_finite() && *l > 0.0)
    }
}

/// The ladder position of size `l`: `log₂(l / reference) · LADDER_PER_OCTAVE`.
fn rung(l: f64, reference: f64) -> f64 {
    libm::log2(l / reference) * LADDER_PER_OCTAVE
}

/// One ladder period's sines and cosines along the grid's columns and rows.
struct Level {
    sin_x: Vec<f64>,
    cos_x: Vec<f64>,
    sin_y: Vec<f64>,
    cos_y: Vec<f64>,
    sin_z: f64,
    cos_z: f64,
}

/// Graded gyroid polylines (mm) for `area` (µm shapes) at height `z_mm`, the pattern turned
/// by `angle_rad` about the origin, pieces shorter than `min_len_um` dropped.
pub fn gyroid_graded(area: &[IntShape<i32>], field: &CellField, z_mm: f64, angle_rad: f64, min_len_um: f64) -> Vec<Vec<DVec2>> {
    if area.is_empty() || !field.is_valid() || !z_mm.is_finite() {
        return Vec::new();
    }
    let (sn, cs) = (libm::sin(angle_rad), libm::cos(angle_rad));
    let Some((lo, hi)) = turned_bounds(area, sn, cs) else { return Vec::new() };
    let (l_min, _) = field.range();
    // Grid in the pattern frame, µm, one step of margin.
    let mut h = l_min * 1000.0 / STEPS_PER_CELL;
    let (w, d) = (hi.x - lo.x, hi.y - lo.y);
    let samples = |h: f64| ((w / h) as usize + 3) * ((d / h) as usize + 3);
    while samples(h) > MAX_SAMPLES {
        h *= 1.25;
    }
    let (nx, ny) = ((w / h) as usize + 3, (d / h) as usize + 3);
    let x0 = lo.x - h;
    let y0 = lo.y - h;
    let to_area = |x: f64, y: f64| DVec2::new(x * cs - y * sn, x * sn + y * cs);
    // The cell size at each sample, as a ladder position.
    let mut rungs = vec![0.0; nx * ny];
    let (mut r_lo, mut r_hi) = (i64::MAX, i64::MIN);
    for j in 0..ny {
        for i in 0..nx {
            let p = to_area(x0 + i as f64 * h, y0 + j as f64 * h) / 1000.0;
            let r = rung(field.at(DVec3::new(p.x, p.y, z_mm)), field.reference_mm);
            rungs[i + nx * j] = r;
            r_lo = r_lo.min(libm::floor(r) as i64);
            r_hi = r_hi.max(libm::floor(r) as i64 + 1);
        }
    }
    let levels: Vec<Level> = (r_lo..=r_hi)
        .map(|k| {
            let l_um = field.reference_mm * 1000.0 * libm::exp2(k as f64 / LADDER_PER_OCTAVE);
            let s = TAU / l_um;
            let xs: Vec<f64> = (0..nx).map(|i| (x0 + i as f64 * h) * s).collect();
            let ys: Vec<f64> = (0..ny).map(|j| (y0 + j as f64 * h) * s).collect();
            let z = z_mm * 1000.0 * s;
            Level {
                sin_x: xs.iter().map(|&x| libm::sin(x)).collect(),
                cos_x: xs.iter().map(|&x| libm::cos(x)).collect(),
                sin_y: ys.iter().map(|&y| libm::sin(y)).collect(),
                cos_y: ys.iter().map(|&y| libm::cos(y)).collect(),
                sin_z: libm::sin(z),
                cos_z: libm::cos(z),
            }
        })
        .collect();
    let g = |lv: &Level, i: usize, j: usize| lv.sin_x[i] * lv.cos_y[j] + lv.sin_y[j] * lv.cos_z + lv.sin_z * lv.cos_x[i];
    let mut values = vec![0.0; nx * ny];
    for j in 0..ny {
        for i in 0..nx {
            let r = rungs[i + nx * j];
            let k = libm::floor(r);
            let t = r - k;
            let a = &levels[(k as i64 - r_lo) as usize];
            let b = &levels[(k as i64 - r_lo + 1) as usize];
            values[i + nx * j] = (1.0 - t) * g(a, i, j) + t * g(b, i, j);
        }
    }
    drop(rungs);
    let lines = trace(&values, nx, ny);
    let tolerance_um = super::gyroid::chord_tolerance_um(l_min * 1000.0);
    let to_um = |e: &Crossing| {
        let p = to_area(x0 + e.x * h, y0 + e.y * h);
        IntPoint::new(libm::round(p.x) as i32, libm::round(p.y) as i32)
    };
    let lines: Vec<Vec<IntPoint<i32>>> = lines
        .iter()
        .map(|l| {
            let mut out: Vec<IntPoint<i32>> = Vec::with_capacity(l.len());
            for c in l {
                let q = to_um(c);
                if out.last() != Some(&q) {
                    out.push(q);
                }
            }
            simplify(&out, tolerance_um)
        })
        .filter(|l| l.len() >= 2)
        .collect();
    clip_polylines(area, &lines, min_len_um)
}

/// `line` with the points dropped that lie within `tol` µm of the chord of their kept
/// neighbours (Douglas–Peucker): the grid leaves a point every `h`, far more than the curve
/// needs at the closed-form gyroid's chord tolerance.
fn simplify(line: &[IntPoint<i32>], tol: f64) -> Vec<IntPoint<i32>> {
    if line.len() < 3 {
        return line.to_vec();
    }
    let p = |q: IntPoint<i32>| DVec2::new(q.x as f64, q.y as f64);
    let mut keep = vec![false; line.len()];
    keep[0] = true;
    keep[line.len() - 1] = true;
    let mut stack = vec![(0usize, line.len() - 1)];
    while let Some((a, b)) = stack.pop() {
        let (pa, pb) = (p(line[a]), p(line[b]));
        let d = pb - pa;
        let len = d.length();
        let (mut worst, mut at) = (0.0, a);
        for (k, q) in line.iter().enumerate().take(b).skip(a + 1) {
            let off = if len > 0.0 { (p(*q) - pa).perp_dot(d).abs() / len } else { p(*q).distance(pa) };
            if off > worst {
                (worst, at) = (off, k);
            }
        }
        if worst > tol {
            keep[at] = true;
            stack.push((a, at));
            stack.push((at, b));
        }
    }
    line.iter().zip(&keep).filter(|(_, k)| **k).map(|(q, _)| *q).collect()
}

/// A zero crossing on a grid edge, in grid units.
#[derive(Clone, Copy, Debug)]
struct Crossing {
    x: f64,
    y: f64,
}

/// The zero set of `values` (an `nx × ny` grid, x fastest) as polylines in grid units, by
/// marching squares (non-negative is inside; saddles split by the mean of the corners).
fn trace(values: &[f64], nx: usize, ny: usize) -> Vec<Vec<Crossing>> {
    let v = |i: usize, j: usize| values[i + nx * j];
    // Edge ids: 2·node for the edge to +x, 2·node + 1 for the edge to +y.
    let edge_h = |i: usize, j: usize| 2 * (i + nx * j);
    let edge_v = |i: usize, j: usize| 2 * (i + nx * j) + 1;
    let crossing = |e: usize| {
        let node = e / 2;
        let (i, j) = (node % nx, node / nx);
        let (a, b, dx, dy) = if e % 2 == 0 { (v(i, j), v(i + 1, j), 1.0, 0.0) } else { (v(i, j), v(i, j + 1), 0.0, 1.0) };
        let t = (a / (a - b)).clamp(0.0, 1.0);
        Crossing { x: i as f64 + t * dx, y: j as f64 + t * dy }
    };
    let mut segments: Vec<[usize; 2]> = Vec::new();
    for j in 0..ny.saturating_sub(1) {
        for i in 0..nx.saturating_sub(1) {
            let (a, b, c, d) = (v(i, j), v(i + 1, j), v(i + 1, j + 1), v(i, j + 1));
            let case = usize::from(a >= 0.0) | usize::from(b >= 0.0) << 1 | usize::from(c >= 0.0) << 2 | usize::from(d >= 0.0) << 3;
            let (s, e, n, w) = (edge_h(i, j), edge_v(i + 1, j), edge_h(i, j + 1), edge_v(i, j));
            match case {
                0 | 15 => {}
                1 | 14 => segments.push([w, s]),
                2 | 13 => segments.push([s, e]),
                3 | 12 => segments.push([w, e]),
                4 | 11 => segments.push([e, n]),
                6 | 9 => segments.push([s, n]),
                7 | 8 => segments.push([w, n]),
                5 | 10 => {
                    // Saddle: the centre decides which corners connect.
                    let centre_in = (a + b + c + d) >= 0.0;
                    if (case == 5) == centre_in {
                        segments.push([w, n]);
                        segments.push([s, e]);
                    } else {
                        segments.push([w, s]);
                        segments.push([e, n]);
                    }
                }
                _ => unreachable!(),
            }
        }
    }
    // Each edge is shared by at most two segments: join them into chains.
    let mut ends: Vec<(usize, usize)> = segments.iter().enumerate().flat_map(|(k, s)| [(s[0], k), (s[1], k)]).collect();
    ends.sort_unstable();
    let other = |edge: usize, seg: usize| -> Option<usize> {
        let at = ends.partition_point(|&(e, _)| e < edge);
        ends[at..].iter().take_while(|&&(e, _)| e == edge).map(|&(_, k)| k).find(|&k| k != seg)
    };
    let mut used = vec![false; segments.len()];
    let mut lines = Vec::new();
    for start in 0..segments.len() {
        if used[start] {
            continue;
        }
        used[start] = true;
        // Walk forward from the segment's second edge, then backward from its first.
        let mut forward = vec![segments[start][0], segments[start][1]];
        for dir in 0..2 {
            let mut seg = start;
            let mut edge = if dir == 0 { segments[start][1] } else { segments[start][0] };
            let mut chain = Vec::new();
            while let Some(next) = other(edge, seg) {
                if used[next] {
                    break;
                }
                used[next] = true;
                edge = if segments[next][0] == edge { segments[next][1] } else { segments[next][0] };
                chain.push(edge);
                seg = next;
            }
            if dir == 0 {
                forward.extend(chain);
            } else {
                chain.reverse();
                chain.extend(forward);
                forward = chain;
                break;
            }
        }
        lines.push(forward.into_iter().map(crossing).collect());
    }
    lines
}

#[cfg(test)]
mod tests {
    use super::*;

    fn uniform(l: f64) -> CellField {
        CellField { origin_mm: [0.0; 3], step_mm: 10.0, dims: [1, 1, 1], cell_mm: vec![l], reference_mm: l }
    }

    #[test]
    fn trilinear_field_is_exact_on_a_linear_ramp() {
        let f = CellField { origin_mm: [0.0; 3], step_mm: 2.0, dims: [3, 2, 2], cell_mm: (0..12).map(|k| 2.0 + (k % 3) as f64).collect(), reference_mm: 2.0 };
        for x in [0.0, 0.7, 1.9, 3.3, 4.0] {
            assert!((f.at(DVec3::new(x, 1.0, 1.0)) - (2.0 + x / 2.0)).abs() < 1e-12);
        }
        assert_eq!(f.at(DVec3::new(-5.0, 0.0, 0.0)), 2.0);
        assert_eq!(f.at(DVec3::new(50.0, 0.0, 0.0)), 4.0);
    }

    #[test]
    fn traced_points_lie_on_the_uniform_gyroid() {
        // Uniform field: every crossing is on the gyroid of that period, to the grid's
        // interpolation error.
        let l = 4.0;
        let square = IntShape::from(vec![vec![IntPoint::new(0, 0), IntPoint::new(20_000, 0), IntPoint::new(20_000, 20_000), IntPoint::new(0, 20_000)]]);
        for z in [0.1, 0.9, 2.3] {
            let lines = gyroid_graded(std::slice::from_ref(&square), &uniform(l), z, 0.0, 0.0);
            assert!(lines.len() >= 4, "{} lines", lines.len());
            let s = TAU / l;
            for p in lines.iter().flatten() {
                let (x, y, zz) = (p.x * s, p.y * s, z * s);
                let g = libm::sin(x) * libm::cos(y) + libm::sin(y) * libm::cos(zz) + libm::sin(zz) * libm::cos(x);
                assert!(g.abs() < 0.02, "({}, {}) at z {z}: {g}", p.x, p.y);
            }
            // As long as the closed-form section's.
            let len = |ls: &[Vec<DVec2>]| ls.iter().map(|l| l.windows(2).map(|w| w[0].distance(w[1])).sum::<f64>()).sum::<f64>();
            let exact = super::super::gyroid::gyroid(std::slice::from_ref(&square), l * 1000.0, z, 0.0, 0.0);
            let (a, b) = (len(&lines), len(&exact));
            assert!((a - b).abs() < 0.01 * b, "traced {a} mm against {b} mm at z {z}");
        }
    }
}

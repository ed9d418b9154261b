//! Gyroid infill: the layer's plane cutting the gyroid surface, as PrusaSlicer draws it.
//!
//! With `(x, y, z)` scaled by `2π / L` (`L` the cell size), the surface is
//! `sin x cos y + sin y cos z + sin z cos x = 0`. At a fixed `z` it is a family of wavy curves
//! that are graphs of one coordinate over the other: where `|cos z| ≥ |sin z|` the equation
//! `sin x · cos y + cos z · sin y = −sin z cos x` is `A cos y + B sin y = C` with `B = cos z`
//! never zero, so `y = −atan(A/B) + {asin u, π − asin u} + 2πk` with
//! `u = sign(B) C / √(A² + B²)`, and `|u| ≤ 1` holds in that range; elsewhere the same is
//! done for `x` over `y` (`sin z · cos x + cos y · sin x = −cos z sin y`, `sin z` never zero).
//! Each `2π` of the cross direction holds two curves (PrusaSlicer's odd and even waves), so
//! a cell of side `L` holds two toolpaths per layer (m = 2 in the paper's table 1).
//!
//! One period of each curve is sampled by bisection until the midpoint of every chord lies
//! within [`chord_tolerance_um`] of the curve (at most `0.01 L` and 5 µm), repeated over the
//! area's bounding box on a global grid (the pattern is the same wherever the part is),
//! turned by the pattern angle and clipped to the area with i_overlay's string clipping.
//!
//! Length: the mean over `z` of the curves' length per unit area is `k_c · m / L` with
//! `k_c · m` = [`LENGTH_PER_AREA_FACTOR`]; a layer's own ranges from about 0.94 to 1.14 times
//! that mean (longest near the heights where the curves switch between the two forms and
//! pinch into corners).

use super::infill::clip_polylines;
use crate::geom::DVec2;
use i_overlay::i_float::int::point::IntPoint;
use i_overlay::i_shape::int::shape::IntShape;
use std::f64::consts::{PI, TAU};

/// Mean toolpath length per unit layer area times the cell size `L` (the paper's `k_c · m`):
/// the two branches' arc length over one period, / 2π, averaged over a period in `z` (400
/// heights, 20 000 steps per period: 2.4586; k_c = 1.2293, 0.7 % above table 1's 1.221,
/// which PrusaSlicer's coarser 0.2 mm chord tolerance would explain). `tests/it/infill_patterns.rs`
/// measures the clipped toolpaths against it.
pub const LENGTH_PER_AREA_FACTOR: f64 = 2.4586;

/// Most bisection levels per sampled interval (a floor on the step of `2π / 16 / 2¹⁶`).
const MAX_DEPTH: u32 = 16;

/// Chord tolerance of the sampled curves for cell size `cell_um`, µm: `0.01 L`, at most 5 µm.
pub fn chord_tolerance_um(cell_um: f64) -> f64 {
    (0.01 * cell_um).min(5.0)
}

/// Solves `P cos t + Q sin t = C` where `Q` is the coefficient kept away from zero: the two
/// solution branches, each continuous in the parameters.
fn solve_sin(p: f64, q: f64, c: f64) -> [f64; 2] {
    let r = (p * p + q * q).sqrt();
    let u = (q.signum() * c / r).clamp(-1.0, 1.0);
    let a = libm::atan(p / q);
    let s = libm::asin(u);
    [s - a, PI - s - a]
}

/// Same, with `P` the coefficient kept away from zero.
fn solve_cos(p: f64, q: f64, c: f64) -> [f64; 2] {
    let r = (p * p + q * q).sqrt();
    let u = (p.signum() * c / r).clamp(-1.0, 1.0);
    let b = libm::atan(q / p);
    let s = libm::acos(u);
    [b + s, b - s]
}

/// The two curves at scaled height `z`, as the cross coordinate over the along coordinate
/// `s` (both scaled, period `2π`): `along_x` tells whether `s` is x (curves run along X).
struct Section {
    sin_z: f64,
    cos_z: f64,
    along_x: bool,
}

impl Section {
    fn new(z: f64) -> Self {
        let (sin_z, cos_z) = (libm::sin(z), libm::cos(z));
        Section { sin_z, cos_z, along_x: cos_z.abs() >= sin_z.abs() }
    }

    fn cross(&self, s: f64, branch: usize) -> f64 {
        let (ss, cs) = (libm::sin(s), libm::cos(s));
        if self.along_x {
            // sin x · cos y + cos z · sin y = −sin z · cos x, solved for y.
            solve_sin(ss, self.cos_z, -self.sin_z * cs)[branch]
        } else {
            // sin z · cos x + cos y · sin x = −cos z · sin y, solved for x.
            solve_cos(self.sin_z, cs, -self.cos_z * ss)[branch]
        }
    }

    /// One period `s ∈ [0, 2π]` of a branch, sampled to `tol` (scaled units).
    fn period(&self, branch: usize, tol: f64) -> Vec<DVec2> {
        let f = |s: f64| DVec2::new(s, self.cross(s, branch));
        let mut out = vec![f(0.0)];
        const START: usize = 16;
        for i in 0..START {
            let (a, b) = (f(TAU * i as f64 / START as f64), f(TAU * (i + 1) as f64 / START as f64));
            self.refine(&f, a, b, tol, 0, &mut out);
        }
        out
    }

    /// Appends the points after `a` up to `b`, bisecting while the midpoint is off the chord.
    fn refine(&self, f: &dyn Fn(f64) -> DVec2, a: DVec2, b: DVec2, tol: f64, depth: u32, out: &mut Vec<DVec2>) {
        let m = f(0.5 * (a.x + b.x));
        let d = b - a;
        let off = (m - a).perp_dot(d).abs() / d.length().max(1e-300);
        if depth < MAX_DEPTH && off > tol {
            self.refine(f, a, m, tol, depth + 1, out);
            self.refine(f, m, b, tol, depth + 1, out);
        } else {
            out.push(b);
        }
    }
}

/// Gyroid infill polylines (mm) for `area` (µm shapes) at height `z_mm`: cell size `cell_um`,
/// the pattern turned by `angle_rad` about the origin, pieces shorter than `min_len_um` dropped.
pub fn gyroid(area: &[IntShape<i32>], cell_um: f64, z_mm: f64, angle_rad: f64, min_len_um: f64) -> Vec<Vec<DVec2>> {
    if area.is_empty() || !cell_um.is_finite() || cell_um <= 0.0 || !z_mm.is_finite() {
        return Vec::new();
    }
    let scale = cell_um / TAU; // µm per scaled unit
    let (sn, cs) = (libm::sin(angle_rad), libm::cos(angle_rad));
    // Bounding box of the area in the pattern frame (turned by −angle).
    let Some((lo, hi)) = super::infill::turned_bounds(area, sn, cs) else { return Vec::new() };
    let sec = Section::new(TAU * z_mm * 1000.0 / cell_um);
    let tol = chord_tolerance_um(cell_um) / scale;
    // Along and cross ranges of the box, in periods (one extra each side: a branch wanders
    // up to about π from its mean).
    let (a_lo, a_hi, c_lo, c_hi) = if sec.along_x { (lo.x, hi.x, lo.y, hi.y) } else { (lo.y, hi.y, lo.x, hi.x) };
    let p0 = libm::floor(a_lo / cell_um) as i64;
    let p1 = libm::ceil(a_hi / cell_um) as i64;
    let k0 = libm::floor(c_lo / cell_um) as i64 - 1;
    let k1 = libm::ceil(c_hi / cell_um) as i64 + 1;
    let mut lines: Vec<Vec<IntPoint<i32>>> = Vec::new();
    for branch in 0..2 {
        let one = sec.period(branch, tol);
        for k in k0..=k1 {
            let mut line: Vec<IntPoint<i32>> = Vec::with_capacity(one.len() * (p1 - p0) as usize);
            for p in p0..p1 {
                for (i, q) in one.iter().enumerate() {
                    if i == 0 && p > p0 {
                        continue; // the previous period's last point
                    }
                    let (s, c) = ((q.x + TAU * p as f64) * scale, (q.y + TAU * k as f64) * scale);
                    let (x, y) = if sec.along_x { (s, c) } else { (c, s) };
                    // Back to the area's frame (turn by +angle), µm.
                    let w = IntPoint::new(libm::round(x * cs - y * sn) as i32, libm::round(x * sn + y * cs) as i32);
                    if line.last() != Some(&w) {
                        line.push(w);
                    }
                }
            }
            if line.len() >= 2 {
                lines.push(line);
            }
        }
    }
    clip_polylines(area, &lines, min_len_um)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sampled_points_lie_on_the_surface() {
        for z in [0.0, 0.3, 0.7, 0.785, 1.0, 2.0, 3.0, 4.5, 5.9] {
            let sec = Section::new(z);
            for branch in 0..2 {
                for q in sec.period(branch, 1e-3) {
                    let (x, y) = if sec.along_x { (q.x, q.y) } else { (q.y, q.x) };
                    let g = libm::sin(x) * libm::cos(y) + libm::sin(y) * libm::cos(z) + libm::sin(z) * libm::cos(x);
                    assert!(g.abs() < 1e-9, "z {z}, ({x}, {y}): {g}");
                }
            }
        }
    }

    #[test]
    fn the_two_branches_are_different_curves() {
        let sec = Section::new(0.3);
        let (a, b) = (sec.cross(1.0, 0), sec.cross(1.0, 1));
        let d = (a - b).rem_euclid(TAU);
        assert!(d > 0.5 && d < TAU - 0.5, "{a} {b}");
    }
}

//! 3D honeycomb infill: layer sections of a space-filling tessellation of truncated octahedra,
//! as PrusaSlicer's "3D Honeycomb" (Slic3r, after David Eccles) draws them.
//!
//! Construction, in grid units `d = L / 2` (`L` the cell size: the pattern's period across
//! its lines). The walls of the tessellation cut at height `z` form a truncated square
//! tiling: a checkerboard of octagons and squares whose grid lines are zig-zags. Column `i`
//! (at `x = i`) runs along Y; over grid square `j` it is straight at `x = i + s·o/2` for
//! `y ∈ [j + |o|/2, j + 1 − |o|/2]`, with `s = ±1` alternating with the parity of `i + j`, and
//! joins the next straight part by a 45° diagonal. The offset `o` is a triangle wave in `z`
//! between `+½` and `−½` with period `√2 d` (`o = ±½` at the octahedra's centres, `0` between
//! them), so the sections change with height and repeat every `√2 d`; half a period later the
//! pattern is the same shifted by one grid unit along the lines (the body-centred stacking).
//! Those are the sections of regular truncated octahedra on a body-centred cubic lattice of
//! side `√2 d`, turned 45° about Z: the diagonals are the square faces between octahedra of
//! one layer of cells, the straight parts the hexagonal faces towards the next.
//!
//! Like PrusaSlicer, a layer prints one family, columns or rows (alternating layer by layer),
//! so no diagonal is printed twice in one layer: each column covers its straight walls and
//! every diagonal it meets, the rows of the next layer the other straight walls and the same
//! diagonals. A cell of side `L` then holds two zig-zags per layer (m = 2).
//!
//! Length per unit area of one family: `(1 − |o| + √2 |o|) / d`; `|o|` is uniform on
//! `[0, ½]` over a `z` period, so the mean is `(1 + (√2 − 1) / 4) / d`, i.e.
//! `k_c · m = 2 + (√2 − 1) / 2 ≈ 2.2071` per `L` ([`LENGTH_PER_AREA_FACTOR`]); a layer ranges
//! from `2` (`o = 0`) to `1 + √2` (`o = ±½`).

use super::infill::clip_polylines;
use crate::geom::DVec2;
use i_overlay::i_float::int::point::IntPoint;
use i_overlay::i_shape::int::shape::IntShape;
use std::f64::consts::SQRT_2;

/// Mean toolpath length per unit layer area times the cell size `L` (the paper's `k_c · m`):
/// `2 + (√2 − 1) / 2` (table 1 of the paper: 1.011 × 2 = 2.022).
pub const LENGTH_PER_AREA_FACTOR: f64 = 2.0 + (SQRT_2 - 1.0) / 2.0;

/// Period of the sections in `z` for cell size `cell`: `√2 · L / 2` (the truncated octahedra's
/// cubic lattice side), in the unit of `cell`.
pub fn z_period(cell: f64) -> f64 {
    SQRT_2 * cell / 2.0
}

/// The zig-zag offset `o ∈ [−½, ½]` (grid units) at height `z` (grid units): a triangle wave of
/// period `√2`, `+½` at `z = 0`.
pub fn offset(z: f64) -> f64 {
    let u = z.rem_euclid(SQRT_2);
    0.5 * ((u - SQRT_2 / 2.0).abs() / SQRT_2 * 4.0 - 1.0)
}

/// One zig-zag in grid units: line number `i` (its cross coordinate), along-coordinates from
/// grid square `j0` to `j1`, as (along, cross) pairs.
fn zigzag(i: i64, j0: i64, j1: i64, o: f64) -> Vec<(f64, f64)> {
    let h = o.abs() / 2.0;
    let side = |j: i64| if (i + j).rem_euclid(2) == 1 { 1.0 } else { -1.0 };
    let mut out = Vec::with_capacity(2 * (j1 - j0) as usize + 2);
    for j in j0..j1 {
        let c = i as f64 + side(j) * o / 2.0;
        out.push((j as f64 + h, c));
        out.push((j as f64 + 1.0 - h, c));
    }
    out
}

/// 3D honeycomb polylines (mm) for `area` (µm shapes) at height `z_mm`: cell size `cell_um`,
/// `rows` picks the family (lines along X; else columns along Y), the pattern turned by
/// `angle_rad` about the origin, pieces shorter than `min_len_um` dropped.
pub fn honeycomb3d(area: &[IntShape<i32>], cell_um: f64, z_mm: f64, rows: bool, angle_rad: f64, min_len_um: f64) -> Vec<Vec<DVec2>> {
    if area.is_empty() || !cell_um.is_finite() || cell_um <= 0.0 || !z_mm.is_finite() {
        return Vec::new();
    }
    let d = cell_um / 2.0;
    let (sn, cs) = (libm::sin(angle_rad), libm::cos(angle_rad));
    let Some((lo, hi)) = super::infill::turned_bounds(area, sn, cs) else { return Vec::new() };
    let o = offset(z_mm * 1000.0 / d);
    let (a_lo, a_hi, c_lo, c_hi) = if rows { (lo.x, hi.x, lo.y, hi.y) } else { (lo.y, hi.y, lo.x, hi.x) };
    let j0 = libm::floor(a_lo / d) as i64 - 1;
    let j1 = libm::ceil(a_hi / d) as i64 + 1;
    let i0 = libm::floor(c_lo / d) as i64 - 1;
    let i1 = libm::ceil(c_hi / d) as i64 + 1;
    let mut lines = Vec::new();
    for i in i0..=i1 {
        let line: Vec<IntPoint<i32>> = zigzag(i, j0, j1, o)
            .into_iter()
            .map(|(a, c)| {
                let (x, y) = if rows { (a * d, c * d) } else { (c * d, a * d) };
                IntPoint::new(libm::round(x * cs - y * sn) as i32, libm::round(x * sn + y * cs) as i32)
            })
            .collect();
        lines.push(line);
    }
    clip_polylines(area, &lines, min_len_um)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offset_is_a_triangle_wave() {
        assert!((offset(0.0) - 0.5).abs() < 1e-12);
        assert!(offset(SQRT_2 / 2.0).abs() - 0.5 < 1e-12 && offset(SQRT_2 / 2.0) < -0.5 + 1e-12);
        assert!(offset(SQRT_2 / 4.0).abs() < 1e-12);
        assert!((offset(0.1) + offset(0.1 + SQRT_2 / 2.0)).abs() < 1e-12, "antisymmetric over half a period");
    }

    #[test]
    fn zigzag_length_per_unit() {
        for o in [0.0, 0.2, -0.35, 0.5] {
            let z = zigzag(0, 0, 10, o);
            let len: f64 = z.windows(2).map(|w| (w[1].0 - w[0].0).hypot(w[1].1 - w[0].1)).sum();
            // Ten straight parts and the nine 45° diagonals between them.
            let want = 10.0 * (1.0 - o.abs()) + 9.0 * SQRT_2 * o.abs();
            assert!((len - want).abs() < 1e-9, "o {o}: {len} vs {want}");
        }
    }
}

//! Trilinear interpolation of a volume at a point of the volume frame.
//!
//! The point `p` (mm) becomes continuous voxel coordinates `u = p / spacing`; the cell is the
//! voxel `floor(u)` and its seven neighbours towards `+i, +j, +k` (the last cell along an axis
//! is the one ending at the last voxel, so `p` on the far face is inside), and the value is the
//! usual product of the three linear weights. Coordinates within 1e-9 voxel of an integer are
//! snapped to it, so the value at a voxel centre is that voxel's value exactly (`(i·s)/s` is
//! not always `i` in floating point). An axis with a single voxel has extent 0: only the
//! coordinate 0 is inside along it, and there is nothing to interpolate along it.
//!
//! The paper (section 2.3.3) interpolates the relative-density field, not the HU field: a
//! non-linear HU → ρ mapping applied after interpolation would differ, so
//! [`Volume::sample_with`] maps the eight corner values first.

use super::Volume;
use crate::geom::DVec3;

/// Distance (in voxels) under which a continuous coordinate is snapped to the voxel centre.
pub const SNAP_VOXELS: f64 = 1e-9;

impl Volume {
    /// Trilinear interpolation at `p` (volume frame, mm); `None` outside `[0, extent]` on any
    /// axis (or non-finite `p`, or an empty volume). A grid with 1 voxel along an axis is
    /// constant along it (and its extent along it is 0).
    pub fn sample(&self, p: DVec3) -> Option<f64> {
        self.sample_with(p, f64::from)
    }

    /// Same as [`Volume::sample`] with `f` applied to the 8 corner values before interpolating
    /// (used to interpolate ρ = f(HU) as the paper does: the ρ field is interpolated, not HU).
    pub fn sample_with(&self, p: DVec3, f: impl Fn(f32) -> f64) -> Option<f64> {
        // A volume whose values do not match its dims is malformed: answer None, never panic.
        if self.is_empty() || self.values.len() < self.len() {
            return None;
        }
        let p = p.to_array();
        let mut base = [0usize; 3];
        let mut t = [0.0f64; 3];
        for a in 0..3 {
            let (n, s) = (self.dims[a], self.spacing_mm[a]);
            let extent = (n - 1) as f64 * s;
            if !(p[a].is_finite() && s > 0.0 && p[a] >= 0.0 && p[a] <= extent) {
                return None;
            }
            if n == 1 {
                continue; // base 0, weight 0: constant along this axis
            }
            let mut u = (p[a] / s).min((n - 1) as f64);
            let r = libm::round(u);
            if (u - r).abs() < SNAP_VOXELS {
                u = r;
            }
            // The last cell is [n-2, n-1], so u = n-1 has weight 1 on the last voxel.
            let i0 = (libm::floor(u) as usize).min(n - 2);
            base[a] = i0;
            t[a] = u - i0 as f64;
        }
        // Neighbour offsets; 0 along single-voxel axes (their weight is 0 anyway).
        let step = [usize::from(self.dims[0] > 1), usize::from(self.dims[1] > 1), usize::from(self.dims[2] > 1)];
        let corner = |di: usize, dj: usize, dk: usize| {
            f(self.at(base[0] + di * step[0], base[1] + dj * step[1], base[2] + dk * step[2]))
        };
        // (1 − t)·a + t·b: exact at t = 0 and t = 1.
        let lerp = |a: f64, b: f64, t: f64| (1.0 - t) * a + t * b;
        let [tx, ty, tz] = t;
        let c00 = lerp(corner(0, 0, 0), corner(1, 0, 0), tx);
        let c10 = lerp(corner(0, 1, 0), corner(1, 1, 0), tx);
        let c01 = lerp(corner(0, 0, 1), corner(1, 0, 1), tx);
        let c11 = lerp(corner(0, 1, 1), corner(1, 1, 1), tx);
        let c0 = lerp(c00, c10, ty);
        let c1 = lerp(c01, c11, ty);
        Some(lerp(c0, c1, tz))
    }
}

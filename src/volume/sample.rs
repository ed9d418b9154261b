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
    /// For many points, a [`Sampler`] keeps the last cell's mapped corners.
    pub fn sample_with(&self, p: DVec3, f: impl Fn(f32) -> f64) -> Option<f64> {
        Sampler::new(self, f).sample(p)
    }

    /// The cell of `p`: its first voxel's index and the weights along each axis.
    fn locate(&self, p: DVec3) -> Option<(usize, [f64; 3])> {
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
            // 0 ≤ u ≤ n − 1: floor is the integer part (a cast, exact) and round (half away
            // from zero) the floor plus one from a fraction of ½ (u − floor(u) is exact) — the
            // same numbers as f64::floor / f64::round, without a libm call per axis per sample.
            let mut u = (p[a] / s).min((n - 1) as f64);
            let f = (u as usize) as f64;
            let r = if u - f >= 0.5 { f + 1.0 } else { f };
            if (u - r).abs() < SNAP_VOXELS {
                u = r;
            }
            // The last cell is [n-2, n-1], so u = n-1 has weight 1 on the last voxel.
            let i0 = (u as usize).min(n - 2);
            base[a] = i0;
            t[a] = u - i0 as f64;
        }
        Some((self.index(base[0], base[1], base[2]), t))
    }
}

/// Trilinear samples of `f(value)` ([`Volume::sample_with`]) at many points: consecutive points
/// in the same cell (a move sampled every quarter voxel) map its 8 corners once. The same
/// numbers as [`Volume::sample_with`], bit for bit.
pub struct Sampler<'v, F> {
    vol: &'v Volume,
    f: F,
    /// The last cell's first voxel (`usize::MAX`: none yet) and its mapped corners.
    last: std::cell::Cell<(usize, [f64; 8])>,
}

impl<'v, F: Fn(f32) -> f64> Sampler<'v, F> {
    /// Samples of `vol` mapped by `f`.
    pub fn new(vol: &'v Volume, f: F) -> Self {
        Sampler { vol, f, last: std::cell::Cell::new((usize::MAX, [0.0; 8])) }
    }

    /// The value at `p` (see [`Volume::sample_with`]).
    pub fn sample(&self, p: DVec3) -> Option<f64> {
        let v = self.vol;
        let (origin, [tx, ty, tz]) = v.locate(p)?;
        let (cached, mut c) = self.last.get();
        if cached != origin {
            // Neighbour offsets in the value array; 0 along single-voxel axes (weight 0 there).
            let d = [usize::from(v.dims[0] > 1), v.dims[0] * usize::from(v.dims[1] > 1), v.dims[0] * v.dims[1] * usize::from(v.dims[2] > 1)];
            for (n, c) in c.iter_mut().enumerate() {
                *c = (self.f)(v.values[origin + (n & 1) * d[0] + (n >> 1 & 1) * d[1] + (n >> 2) * d[2]]);
            }
            self.last.set((origin, c));
        }
        // (1 − t)·a + t·b: exact at t = 0 and t = 1. Corner n is (n & 1, n >> 1 & 1, n >> 2).
        let lerp = |a: f64, b: f64, t: f64| (1.0 - t) * a + t * b;
        let c00 = lerp(c[0], c[1], tx);
        let c10 = lerp(c[2], c[3], tx);
        let c01 = lerp(c[4], c[5], tx);
        let c11 = lerp(c[6], c[7], tx);
        let c0 = lerp(c00, c10, ty);
        let c1 = lerp(c01, c11, ty);
        Some(lerp(c0, c1, tz))
    }
}

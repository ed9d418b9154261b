//! Histogram of the voxel values inside a region of interest (the viewer's value histogram,
//! and the HU range the calibration's end points are read from, as in the paper's section
//! 3.2: "HU_min and HU_max of the 3D scalar field inside the femur bone section").
//!
//! Voxels are those whose centres lie in the [`Roi`] box ([`Roi::voxels`]); non-finite values
//! are skipped (not counted in `voxels`, not in the mean). Bins are equal: bin `b` holds
//! `[min + b·w, min + (b+1)·w)`, the last one also its upper end. [`histogram`] spans the
//! values' own `[min, max]`; [`histogram_in`] a fixed range, with values outside it counted in
//! the end bins, so the counts always add up to `voxels`. The mean is the plain sum divided by
//! the count, summed in f64 in grid order (deterministic).

use super::{Roi, Volume};
use serde::Serialize;

/// Most bins a histogram has; more are reduced to this (a screen is a few thousand pixels).
pub const MAX_BINS: usize = 65_536;

/// Counts of voxel values in equal bins.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Histogram {
    /// Lower end of the first bin (the value unit: HU for CT).
    pub min: f64,
    /// Upper end of the last bin.
    pub max: f64,
    /// Width of each bin, `(max − min) / bins` (0 when `max == min`: everything is in bin 0).
    pub bin_width: f64,
    /// Voxels per bin.
    pub counts: Vec<u64>,
    /// Voxels counted (finite values with their centre in the region).
    pub voxels: u64,
    /// Mean of the counted values (0 when none).
    pub mean: f64,
}

/// Histogram of the finite values in `roi` in `bins` bins (1 to [`MAX_BINS`]) spanning their
/// own minimum and maximum. An empty region gives zero counts, `min = max = 0`.
pub fn histogram(volume: &Volume, roi: &Roi, bins: usize) -> Histogram {
    build(volume, roi, None, bins)
}

/// Histogram of the finite values in `roi` in `bins` bins (1 to [`MAX_BINS`]) spanning `range`
/// (its ends in either order); values outside it are counted in the first or last bin. A
/// non-finite range falls back to the values' own range, as [`histogram`].
pub fn histogram_in(volume: &Volume, roi: &Roi, range: [f64; 2], bins: usize) -> Histogram {
    let fixed = (range[0].is_finite() && range[1].is_finite()).then(|| (range[0].min(range[1]), range[0].max(range[1])));
    build(volume, roi, fixed, bins)
}

/// Calls `f` with every finite value in the region, in grid order (`i` fastest).
fn each(volume: &Volume, roi: &Roi, mut f: impl FnMut(f64)) {
    if volume.values.len() < volume.len() {
        return;
    }
    let Some([ri, rj, rk]) = roi.voxels(volume) else { return };
    for k in rk {
        for j in rj.clone() {
            for i in ri.clone() {
                let v = volume.at(i, j, k);
                if v.is_finite() {
                    f(f64::from(v));
                }
            }
        }
    }
}

fn build(volume: &Volume, roi: &Roi, fixed: Option<(f64, f64)>, bins: usize) -> Histogram {
    let bins = bins.clamp(1, MAX_BINS);
    let (mut lo, mut hi, mut sum, mut n) = (f64::INFINITY, f64::NEG_INFINITY, 0.0f64, 0u64);
    each(volume, roi, |v| {
        lo = lo.min(v);
        hi = hi.max(v);
        sum += v;
        n += 1;
    });
    if n == 0 {
        (lo, hi) = (0.0, 0.0);
    }
    let (min, max) = fixed.unwrap_or((lo, hi));
    let bin_width = (max - min) / bins as f64;
    let mut counts = vec![0u64; bins];
    each(volume, roi, |v| {
        let b = if bin_width > 0.0 { libm::floor((v - min) / bin_width).clamp(0.0, (bins - 1) as f64) as usize } else { 0 };
        counts[b] += 1;
    });
    Histogram { min, max, bin_width, counts, voxels: n, mean: if n > 0 { sum / n as f64 } else { 0.0 } }
}

//! Uniformity metrics of a point set (the paper's section 2.5): the kernel density function
//! per point and the distances to each point's 2n nearest neighbours, all geodesic.

use super::surface::{Node, Surface};
use super::uniform::Grid;
use std::f64::consts::PI;

/// Uniformity metrics.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct Metrics {
    /// KDF ρ_i = Σ_{j≠i} W_ij per point (equation (6)), 1/mm².
    pub kdf: Vec<f64>,
    /// The same, ascending.
    pub kdf_sorted: Vec<f64>,
    /// Kernel radius h = 4·n·e/ρ_c, mm.
    pub kernel_radius_mm: f64,
    /// Per point, its distances to its 2n nearest neighbours (row-major, 2n per point), mm.
    pub nn_distances_mm: Vec<f64>,
    /// Mean of those distances, mm.
    pub nn_mean_mm: f64,
    /// Their standard deviation, mm.
    pub nn_std_mm: f64,
    /// e / mean (the paper's density check: close to ρ_c when uniform).
    pub ratio: f64,
    /// Per point, its 2n-NN distances over its own target spacing s(q_i) (row-major as
    /// `nn_distances_mm`): 1 is on target, graded or not.
    pub nn_relative: Vec<f64>,
    /// Mean of `nn_relative`.
    pub rel_mean: f64,
    /// Standard deviation of `nn_relative` (uniform: `nn_std_mm` / s).
    pub rel_std: f64,
    /// Per point, the density its neighbours give: n·e / (mean of its 2n-NN distances).
    pub local_density: Vec<f64>,
    /// Per point, the KDF over what points at the target density give inside Ω (1.5/(h_i·s_i²):
    /// the kernel's integral 1.5/h times 1/s² points per mm²); about 1 inside, less at edges.
    pub kdf_relative: Vec<f64>,
    /// The same, ascending.
    pub kdf_relative_sorted: Vec<f64>,
}

/// A histogram: `counts[k]` values fall in [lo + k·w, lo + (k + 1)·w), w = (hi − lo)/bins.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Histogram {
    /// Lowest value.
    pub lo: f64,
    /// Highest value.
    pub hi: f64,
    /// Counts per bin.
    pub counts: Vec<usize>,
}

/// Histogram of the finite `values` in `bins` bins (at least 1).
pub fn histogram(values: &[f64], bins: usize) -> Histogram {
    let bins = bins.max(1);
    let v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let mut counts = vec![0; bins];
    if v.is_empty() {
        return Histogram { lo: 0.0, hi: 0.0, counts };
    }
    let w = (hi - lo) / bins as f64;
    for x in v {
        let k = if w > 0.0 { (((x - lo) / w) as usize).min(bins - 1) } else { 0 };
        counts[k] += 1;
    }
    Histogram { lo, hi, counts }
}

/// Two value sets counted on the same `bins` bins (so a seed and a result compare bar by bar):
/// (the bins + 1 edges, counts of `a`, counts of `b`), as a histogram plot takes them.
pub fn shared_histogram(a: &[f64], b: &[f64], bins: usize) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let both: Vec<f64> = a.iter().chain(b).copied().collect();
    let h = histogram(&both, bins);
    let bins = h.counts.len();
    let w = (h.hi - h.lo) / bins as f64;
    let count = |v: &[f64]| {
        let mut c = vec![0.0; bins];
        for &x in v.iter().filter(|x| x.is_finite()) {
            let k = if w > 0.0 { (((x - h.lo) / w) as usize).min(bins - 1) } else { 0 };
            c[k] += 1.0;
        }
        c
    };
    let edges = (0..=bins).map(|k| h.lo + k as f64 * w).collect();
    (edges, count(a), count(b))
}

/// Metrics of `points` for n = `rasters`, ρ_c = `density`, e = `line_width_mm`.
pub fn metrics(s: &Surface, points: &[[f64; 2]], rasters: u32, density: f64, line_width_mm: f64) -> Metrics {
    let spacing = rasters.max(1) as f64 * line_width_mm / density;
    graded_metrics(s, points, rasters, line_width_mm, spacing, &vec![spacing; points.len()])
}

/// Metrics against a graded target: point i's target spacing is `local[i]` (mm), its kernel
/// radius h_i = 4·local[i] (the paper's h = 4·n·e/ρ with the local ρ); `spacing` is the
/// command density's, reported as `kernel_radius_mm`. With every `local[i]` = `spacing` this
/// is [`metrics`] (the same numbers).
pub fn graded_metrics(s: &Surface, points: &[[f64; 2]], rasters: u32, line_width_mm: f64, spacing: f64, local: &[f64]) -> Metrics {
    let k = 2 * rasters.max(1) as usize;
    let ne = rasters.max(1) as f64 * line_width_mm;
    let h = 4.0 * spacing;
    let h_max = 4.0 * local.iter().copied().fold(spacing, f64::max);
    let nodes: Vec<Node> = crate::par::map(points.len(), &mut |_| {}, |i| s.node(points[i]));
    let n = nodes.len();
    if !(h > 0.0 && h.is_finite() && h_max.is_finite()) || n == 0 || local.len() != n {
        return Metrics { kernel_radius_mm: h, ..Default::default() };
    }
    let grid = Grid::new(nodes.iter().map(|n| n.p), h_max);
    // Each point's kernel density and nearest distances on its own, points side by side.
    let rows = crate::par::map(n, &mut |_| {}, |i| {
        let hi = 4.0 * local[i];
        let norm = 15.0 / (PI * hi.powi(6));
        let mut cand = Vec::new();
        grid.near(nodes[i].p, h_max, &mut cand);
        let mut kdf = 0.0;
        let mut d: Vec<f64> = Vec::with_capacity(cand.len());
        for &j in &cand {
            if j as usize != i {
                let dij = s.pair(&nodes[i], &nodes[j as usize]).0;
                d.push(dij);
                if dij <= hi {
                    kdf += norm * (hi - dij).powi(3);
                }
            }
        }
        if d.iter().filter(|&&x| x <= hi).count() < k {
            // Sparse neighbourhood: every other point (the chord query only saw radius h).
            d = (0..n).filter(|&j| j != i).map(|j| s.pair(&nodes[i], &nodes[j]).0).collect();
        }
        d.sort_by(f64::total_cmp);
        d.truncate(k);
        (kdf, d)
    });
    let kdf: Vec<f64> = rows.iter().map(|r| r.0).collect();
    let nn: Vec<f64> = rows.into_iter().flat_map(|r| r.1).collect();
    let (mean, std) = mean_std(&nn);
    let mut kdf_sorted = kdf.clone();
    kdf_sorted.sort_by(f64::total_cmp);
    // Per point: distances over its own target, and the density they measure.
    let mut nn_relative = Vec::with_capacity(nn.len());
    let mut local_density = Vec::with_capacity(n);
    // Every row holds min(2n, N − 1) distances.
    let per = nn.len().checked_div(n).unwrap_or(0);
    for i in 0..n {
        let row = &nn[i * per..(i + 1) * per];
        nn_relative.extend(row.iter().map(|x| x / local[i]));
        let m = if row.is_empty() { 0.0 } else { row.iter().sum::<f64>() / row.len() as f64 };
        local_density.push(if m > 0.0 { ne / m } else { 0.0 });
    }
    let (rel_mean, rel_std) = mean_std(&nn_relative);
    let kdf_relative: Vec<f64> = (0..n).map(|i| kdf[i] * 4.0 * local[i] * local[i] * local[i] / 1.5).collect();
    let mut kdf_relative_sorted = kdf_relative.clone();
    kdf_relative_sorted.sort_by(f64::total_cmp);
    Metrics {
        kdf,
        kdf_sorted,
        kernel_radius_mm: h,
        nn_distances_mm: nn,
        nn_mean_mm: mean,
        nn_std_mm: std,
        ratio: if mean > 0.0 { line_width_mm / mean } else { 0.0 },
        nn_relative,
        rel_mean,
        rel_std,
        local_density,
        kdf_relative,
        kdf_relative_sorted,
    }
}

/// (mean, population standard deviation); zeros when empty.
fn mean_std(v: &[f64]) -> (f64, f64) {
    let mean = if v.is_empty() { 0.0 } else { v.iter().sum::<f64>() / v.len() as f64 };
    let var = if v.is_empty() { 0.0 } else { v.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / v.len() as f64 };
    (mean, var.sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn histogram_counts_every_value() {
        let h = histogram(&[0.0, 0.5, 1.0, 1.0, f64::NAN], 2);
        assert_eq!(h.counts, vec![1, 3]);
        assert_eq!((h.lo, h.hi), (0.0, 1.0));
    }
}

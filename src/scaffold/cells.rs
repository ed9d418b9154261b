//! Graded cell size (beyond the paper): where equation 6 would need a bead outside
//! `[E_w,min, E_w,max]` at the uniform cell `L_s`, the cell is re-sized instead, so the bead
//! stays printable and the density is still reached.
//!
//! At a fixed cell the density is proportional to the bead's `E_w + (π/4 − 1) l_h` (equation 1
//! with the bead width in place of `1.25 φ`, [`super::density_at_width`]); at a fixed bead it is
//! inversely proportional to the cell. So a node whose mean density `ρ` needs a bead wider than
//! `E_w,max` at `L_s` takes the cell at which `E_w,max` gives `ρ` (smaller), and one needing a
//! bead narrower than `E_w,min` takes the cell at which `E_w,min` gives it (larger)
//! ([`super::cell_size_at_width`]); the others keep `L_s`. Sizes are bounded to
//! `[L_s / max_ratio, L_s · max_ratio]`; a node still out of range there is counted.
//!
//! Nodes sit on a grid of step `L_s` over the part (the field is trilinear between them,
//! [`CellField`]); each node's density is the mean of 3 × 3 × 3 samples of the field within
//! half a cell, so a re-sized cell answers the density around it, not at one voxel.

use super::{cell_size_at_width, width_for_density, Cell};
use crate::budget::{Estimate, OverBudget};
use crate::geom::{Aabb, DVec3};
use crate::slice::gyroid_graded::CellField;
use serde::{Deserialize, Serialize};

/// Largest ratio between a re-sized cell and the uniform one, either way.
pub const DEFAULT_MAX_RATIO: f64 = 3.0;
/// Most nodes of the cell grid.
pub const MAX_NODES: usize = 4_000_000;
/// Re-sized nodes listed in the report at most (all are counted).
pub const MAX_LISTED: usize = 200;

/// What to size cells for.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Options {
    /// The pattern's coefficients (table 1).
    pub cell: Cell,
    /// The uniform cell `L_s`, mm (equation 1 at ρ_s).
    pub reference_mm: f64,
    /// Narrowest bead, mm (E_w,min).
    pub width_min_mm: f64,
    /// Widest bead, mm (E_w,max).
    pub width_max_mm: f64,
    /// Layer height, mm.
    pub layer_mm: f64,
    /// Bound on `L / L_s` and `L_s / L`. Default [`DEFAULT_MAX_RATIO`].
    pub max_ratio: f64,
}

/// One re-sized node.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Resized {
    /// Its centre, mm (the toolpath's frame).
    pub centre_mm: [f64; 3],
    /// Mean target density around it.
    pub rho: f64,
    /// The bead equation 6 would need at `L_s`, mm.
    pub width_at_reference_mm: f64,
    /// Its cell, mm.
    pub cell_mm: f64,
    /// The bead at that cell, mm.
    pub width_mm: f64,
}

/// What sizing did.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct CellsReport {
    /// Nodes of the grid.
    pub nodes: usize,
    /// Nodes with density under them.
    pub sampled: usize,
    /// Nodes given a smaller cell (density above what `E_w,max` gives at `L_s`).
    pub smaller: usize,
    /// Nodes given a larger cell (density below what `E_w,min` gives at `L_s`).
    pub larger: usize,
    /// Re-sized nodes whose bead is still out of range at the size bound.
    pub still_out_of_range: usize,
    /// Smallest and largest cell, mm.
    pub min_cell_mm: f64,
    /// Largest cell, mm.
    pub max_cell_mm: f64,
    /// The first [`MAX_LISTED`] re-sized nodes, in grid order.
    pub resized: Vec<Resized>,
}

/// A sized grid.
pub struct Sized {
    /// The cell size over space.
    pub field: CellField,
    /// What sizing did.
    pub report: CellsReport,
}

/// Why sizing failed.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum Error {
    /// An option is out of its range.
    #[error("cell sizing: {0}")]
    BadOption(String),
    /// Over a budget.
    #[error(transparent)]
    TooBig(#[from] OverBudget),
}

fn dims(bounds: &Aabb, step: f64) -> [usize; 3] {
    let e = bounds.max - bounds.min;
    [e.x, e.y, e.z].map(|x| (libm::ceil((x / step).max(0.0)) as usize).saturating_add(1))
}

/// Most samples of the traced gyroid over all layers (the slicing this sizing leads to).
pub const MAX_TRACE_SAMPLES: f64 = 5e9;

/// The work of sizing over `bounds` (nodes, 27 samples each) and of tracing the graded gyroid
/// it leads to in every layer ([`crate::slice::gyroid_graded`]: a grid of `L_min / 24` over
/// the layer's box, at most its sample limit per layer; about 30 ns per sample).
pub fn estimate(bounds: &Aabb, options: &Options) -> Estimate {
    let n = dims(bounds, options.reference_mm.max(1e-3)).iter().map(|&d| d as f64).product::<f64>();
    let e = bounds.max - bounds.min;
    let h = (options.reference_mm / options.max_ratio.max(1.0) / crate::slice::gyroid_graded::STEPS_PER_CELL).max(1e-4);
    let per_layer = ((e.x / h + 3.0) * (e.y / h + 3.0)).min(crate::slice::gyroid_graded::MAX_SAMPLES as f64);
    let samples = per_layer * (e.z / options.layer_mm.max(1e-3)).max(1.0);
    Estimate::new("cells")
        .quantity("nodes", "Cell-size nodes", n, "")
        .quantity("trace_samples", "Gyroid samples (slicing)", samples, "")
        .limit("cell-size nodes", n, MAX_NODES as f64, "", "a larger infill cell (lower ρ_s) or a smaller part")
        .limit(
            "samples of the graded gyroid",
            samples,
            MAX_TRACE_SAMPLES,
            "",
            "crop the ROI, raise the layer height, or narrow the cell size range (job.density.max_cell_ratio)",
        )
        .cost(n * 40.0 + per_layer * 24.0, n * 27.0 * 2e-8 + samples * 3e-8)
}

/// Sizes the cells over `bounds` by `density` (ρ at a point of the toolpath's frame, `None`
/// outside the field).
pub fn size_cells(bounds: &Aabb, density: &dyn Fn(DVec3) -> Option<f64>, options: &Options) -> Result<Sized, Error> {
    let o = options;
    let ok = |x: f64| x.is_finite() && x > 0.0;
    if !(ok(o.reference_mm)
        && ok(o.width_min_mm)
        && o.width_max_mm > o.width_min_mm
        && o.width_max_mm.is_finite()
        && ok(o.layer_mm)
        && o.max_ratio >= 1.0
        && o.max_ratio.is_finite())
    {
        return Err(Error::BadOption(format!("options out of range: {o:?}")));
    }
    if let Some(r) = estimate(bounds, o).refused {
        return Err(Error::TooBig(r));
    }
    let step = o.reference_mm;
    let d = dims(bounds, step);
    let (lo_l, hi_l) = (o.reference_mm / o.max_ratio, o.reference_mm * o.max_ratio);
    let mut cells = Vec::with_capacity(d[0] * d[1] * d[2]);
    let mut r = CellsReport { nodes: d[0] * d[1] * d[2], min_cell_mm: f64::INFINITY, ..Default::default() };
    for k in 0..d[2] {
        for j in 0..d[1] {
            for i in 0..d[0] {
                let c = bounds.min + DVec3::new(i as f64, j as f64, k as f64) * step;
                let l = match mean_around(c, step, density) {
                    None => o.reference_mm,
                    Some(rho) => {
                        r.sampled += 1;
                        let rho = rho.clamp(1e-3, 1.0);
                        let w = width_for_density(o.cell, o.reference_mm, rho, o.layer_mm);
                        let want = if w > o.width_max_mm {
                            cell_size_at_width(o.cell, o.width_max_mm, rho, o.layer_mm)
                        } else if w < o.width_min_mm {
                            cell_size_at_width(o.cell, o.width_min_mm, rho, o.layer_mm)
                        } else {
                            o.reference_mm
                        };
                        let l = want.clamp(lo_l, hi_l);
                        if l != o.reference_mm {
                            if l < o.reference_mm {
                                r.smaller += 1;
                            } else {
                                r.larger += 1;
                            }
                            let width = width_for_density(o.cell, l, rho, o.layer_mm);
                            if !(o.width_min_mm * (1.0 - 1e-9)..=o.width_max_mm * (1.0 + 1e-9)).contains(&width) {
                                r.still_out_of_range += 1;
                            }
                            if r.resized.len() < MAX_LISTED {
                                r.resized.push(Resized { centre_mm: c.to_array(), rho, width_at_reference_mm: w, cell_mm: l, width_mm: width });
                            }
                        }
                        l
                    }
                };
                r.min_cell_mm = r.min_cell_mm.min(l);
                r.max_cell_mm = r.max_cell_mm.max(l);
                cells.push(l);
            }
        }
    }
    let field = CellField { origin_mm: bounds.min.to_array(), step_mm: step, dims: d, cell_mm: cells, reference_mm: o.reference_mm };
    Ok(Sized { field, report: r })
}

/// The mean of `density` over 3 × 3 × 3 points within half of `step` of `c`.
fn mean_around(c: DVec3, step: f64, density: &dyn Fn(DVec3) -> Option<f64>) -> Option<f64> {
    let (mut sum, mut n) = (0.0, 0usize);
    for dz in [-1.0, 0.0, 1.0] {
        for dy in [-1.0, 0.0, 1.0] {
            for dx in [-1.0, 0.0, 1.0] {
                if let Some(v) = density(c + DVec3::new(dx, dy, dz) * (step / 3.0)).filter(|v| v.is_finite()) {
                    sum += v;
                    n += 1;
                }
            }
        }
    }
    (n > 0).then(|| sum / n as f64)
}

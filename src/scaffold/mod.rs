//! The scaffold model of the CT-graded-density paper (sections 2.2.1 and 2.3.2, equations
//! 1–4 and 7, table 1): how infill cell size, bead width and relative density relate, and how
//! a CT value (HU) becomes a target relative density.
//!
//! Quantities (lengths in mm):
//! - **ρ_s**, the *infill density* the slicer is set to: the fraction of the volume the infill
//!   fills when every bead has the slicer's nominal width. **ρ** is a relative density in
//!   general (1 = solid), **P = 1 − ρ** the porosity.
//! - **L_cell** (`cell_mm`), the size of the infill's unit cell (the period of the gyroid,
//!   the line spacing pattern of rectilinear, …). The cell stays fixed across a graded part;
//!   density is graded by the bead width.
//! - **E_w** (`width_mm`), the extrusion width of a bead; a bead is a *stadium*: a rectangle
//!   `(E_w − l_h) × l_h` with half-discs of diameter `l_h` at both sides, cross-section
//!   `l_h (E_w + (π/4 − 1) l_h)` ([`bead_area`]). Equation 1 is this area with the nominal
//!   width `1.25 φ`, times the toolpath length per cell `k_c · m · L_cell`, over the cell's
//!   volume per layer `L_cell² · l_h`.
//! - **φ** (`nozzle_mm`) the nozzle diameter, **l_h** (`layer_mm`) the layer height.
//! - **k_c**, **m** ([`Cell`], table 1): toolpath length per cell over `L_cell`, and the
//!   number of independent toolpaths per cell in a layer.
//!
//! Files: [`model`] (equations 1–4 and the bead), [`calibration`] (HU → porosity, eq 7),
//! [`grade`] (equation 6 applied to weft's own sliced toolpath), [`cells`] (beyond the paper:
//! the cell re-sized where the bead would leave its printable range).

pub mod calibration;
pub mod cells;
pub mod grade;
pub mod model;

pub use calibration::{Calibration, Curve, DEFAULT_POINTS};
pub use model::*;

use crate::geom::DVec3;
use serde::{Deserialize, Serialize};

/// What to do with a graded bead over the flow or width limit (both routes: weft's own
/// infill, [`grade`], and another slicer's, `crate::gcode_edit`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Limit {
    /// Count it in the report, write it as graded.
    #[default]
    Warn,
    /// Count it and reduce its flow to the limit.
    Clamp,
}

/// The largest bead cross-section within both limits, mm²: the volumetric flow `q_max_mm3_s`
/// at `feed_mm_s`, and the stadium bead of width `width_max_mm` at `layer_mm`.
pub fn max_bead_area(q_max_mm3_s: f64, feed_mm_s: f64, width_max_mm: f64, layer_mm: f64) -> f64 {
    (q_max_mm3_s / feed_mm_s).min(bead_area(width_max_mm, layer_mm)).max(0.0)
}

/// One layer of graded infill, measured the same way on both routes.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct LayerStat {
    /// Z of its infill moves (the layer top), mm.
    pub z_mm: f64,
    /// Infill moves graded (weft's own: segments after splitting).
    pub moves: usize,
    /// Their length, mm.
    pub length_mm: f64,
    /// Length-weighted mean of the target ρ.
    pub target_mean: f64,
    /// Length-weighted mean of the achieved ρ: ρ_s · (bead or E as written) / nominal.
    pub achieved_mean: f64,
    /// Length-weighted mean of |achieved − target|.
    pub mean_abs_error: f64,
}

/// Table 1 of the paper: the three infill types with their coefficients, for reports.
pub fn coefficients_table() -> [(&'static str, Cell); 3] {
    [("gyroid", GYROID), ("rectilinear", RECTILINEAR), ("3D honeycomb", HONEYCOMB_3D)]
}

/// The mean of `density` along `a`–`b`, sampled at the centres of pieces no longer than
/// `step` (at most 256 samples); `None` when no sample is inside the field. Both routes
/// measure a move's target ρ with it, so their per-layer errors compare.
pub fn mean_along(a: DVec3, b: DVec3, step: f64, density: &dyn Fn(DVec3) -> Option<f64>) -> Option<f64> {
    let pieces = (libm::ceil(a.distance(b) / step).max(1.0) as usize).min(256);
    let (mut sum, mut n) = (0.0, 0usize);
    for k in 0..pieces {
        if let Some(r) = density(a.lerp(b, (k as f64 + 0.5) / pieces as f64)) {
            sum += r;
            n += 1;
        }
    }
    (n > 0).then(|| sum / n as f64)
}

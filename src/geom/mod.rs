//! Shared vocabulary of every stage: meshes, 2D regions, toolpaths, tolerances.
//!
//! Conventions: millimetres everywhere, Z up, the build plate at Z = 0. 2D regions are
//! outer loops counter-clockwise and holes clockwise. Coordinates are `f64` (glam's
//! `DVec2`/`DVec3`, scalar on every target) so that native and wasm builds compute
//! bit-identical results; 2D booleans run in integer micrometres (see [`tolerance`]).

mod mesh;
mod polygon;
pub mod shapes;
mod stroke;
pub mod tolerance;
mod toolpath;

pub use glam::{DVec2, DVec3};
pub use mesh::{Aabb, Mesh};
pub use polygon::{signed_area, Polygon};
pub use stroke::{Stroke, StrokeLayer};
pub use toolpath::{Feature, Pass, PassKind, Path, PointData, PointFlow, Toolpath};

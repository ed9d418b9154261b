//! Viscous-thread-printed foams graded between regions (Nakura, Sarkar, Revier, Emery, Lipton,
//! *An interpolative slicing algorithm for continuously graded stiffness in viscous thread
//! printed foams*): the weighting functions of a transition between two regions
//! ([`weight`], appendix A), a point's pair from its region and its distances to the shared
//! boundaries ([`blend`], Algorithm 2) and the printing numbers of one piece of toolpath
//! ([`vtp`], section 3.2.4). The job kind `foam` (`crate::kinds::foam`) runs them as stages:
//! [`regions`] (parry3d-f64 solids, shared boundaries, the paper's region rules), the
//! foundation's slicer on the union, [`layers`] (one outline a layer), [`raster`] (one continuous path per layer), [`field`]
//! (π along the path with few queries), [`grade`] (each piece printed with its pair);
//! [`models`] builds the examples' regions. Beyond the
//! paper: [`stiffness`] turns a target modulus into V*, and [`blend`] joins several
//! transitions where regions meet along lines.

pub mod blend;
pub mod field;
pub mod grade;
pub mod layers;
pub mod models;
pub mod raster;
pub mod regions;
pub mod stiffness;
pub mod vtp;
pub mod weight;

pub use blend::{pair_at, Junction, Transition};
pub use vtp::{Pair, Piece, Process};
pub use weight::Weighting;

//! Freeform (wireframe) printing: beams extruded along 3D paths between joints, sequenced under
//! the process constraints of Gelber, Hurst and Bhargava, *Freeform Assembly Planning*
//! (`../shared/papers/freeform-assembly-planning.txt`).
//!
//! Stages, one file each, each a function of the ones before:
//! - [`wireframe`] reads a design (`assembly_instances` and `conmech` JSON, OBJ line elements, a
//!   CSV of beams) into joints and beams in mm with its grounded joints, listing every problem;
//!   [`models`] makes the built-in designs (a lattice tower, a dome, a bridge);
//! - [`precedence`] computes the constraints that do not depend on the state for a 3-axis
//!   nozzle (section II.A): each beam's allowed directions, and the collision precedences
//!   (parry3d's BVH and GJK, nozzle cone + cylinder against the beams' capsules);
//! - [`frame`] is the linear elastic frame of section II.B (direct stiffness, faer's sparse
//!   Cholesky) and its incremental form for planning;
//! - [`plan`] is the best-first search of section III over consistent subassemblies (strict
//!   mode) or the bottleneck greedy (relaxed mode), with the exact or the heuristic cost;
//! - [`optimal`] (beyond the paper) searches every order of a small design for the least
//!   largest ε: it proves the planner's sequence optimal or beats it, and decides the designs
//!   the planner's search gives up on;
//! - [`bands`] (beyond the paper) plans a design too big to plan whole band by band up its
//!   height, the bands below rigid, and the costs stage measures what the joins cost;
//! - [`deadhead`] orders the plan within its recorded constraints, greedy on deadhead time
//!   (lift above the highest printed beam, move, lower);
//! - [`cost`] replays a sequence and measures both costs of every step (the paper's Fig. 8).

pub mod bands;
pub mod cost;
pub mod deadhead;
pub mod frame;
pub mod models;
pub mod optimal;
pub mod plan;
pub mod precedence;
pub mod wireframe;

pub use wireframe::{read, Wireframe};

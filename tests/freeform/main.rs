//! The freeform job (issue 13), in one test binary (each binary links the whole library):
//! reading wireframes ([`wireframe`]), the frame, the constraints and the planner replayed by
//! an independent checker ([`plan`]), the exact search over every order against a brute force
//! and the planner ([`optimal`]), the job end to end read back by the analyzer ([`job`]).

#[path = "../common/mod.rs"]
mod common;
mod job;
mod optimal;
mod plan;
mod wireframe;

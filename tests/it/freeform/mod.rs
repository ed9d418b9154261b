//! The freeform job (issue 13): reading wireframes ([`wireframe`]), the frame, the constraints
//! and the planner replayed by an independent checker ([`plan`]), the exact search over every
//! order against a brute force and the planner ([`optimal`]), the job end to end read back by
//! the analyzer ([`job`]).

mod job;
mod optimal;
mod plan;
mod wireframe;

//! Shared by the integration tests that walk the shipped examples.
#![allow(dead_code)]

/// The planar lattice examples (every example lattice that is not projected onto a surface).
pub const PLANAR_LATTICES: &[&str] = &[
    "honeycomb-10mm",
    "voronoi-10mm",
    "penrose-10mm",
    "snub-square-10mm",
    "arrowhead-10mm",
    "reentrant-honeycomb-10mm",
    "tensile-honeycomb",
    "ball-burst-disc-48mm",
    "concave-cylinder-honeycomb",
];

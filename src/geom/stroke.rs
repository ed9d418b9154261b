use super::Feature;
use glam::DVec2;

/// A 2D polyline to be printed as drawn (a lattice strut chain, a contour, handle lines).
/// Closed contours repeat their first point at the end.
#[derive(Clone, Debug, PartialEq)]
pub struct Stroke {
    /// Points in mm.
    pub points: Vec<DVec2>,
    /// What it is.
    pub feature: Feature,
    /// One curved strut: the whole polyline is one graph edge (its inner points are bends,
    /// printed in order but not nodes of the path graph). False for chains of straight struts,
    /// contours and handle lines (every segment an edge).
    pub curved: bool,
}

/// The strokes of one layer: the lattice stage's output and the path optimiser's input.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StrokeLayer {
    /// Height of the layer's top (nozzle Z for planar layers), mm.
    pub z: f64,
    /// Layer thickness, mm.
    pub height: f64,
    /// Strokes in no particular order (the optimiser decides the print order).
    pub strokes: Vec<Stroke>,
}

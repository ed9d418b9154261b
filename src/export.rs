//! Exports a lattice design's printed struts as a closed triangle mesh (binary STL), so other
//! slicers can be given the same lattice (`weft export-stl`, BENCHMARKS.md "Against other
//! slicers").
//!
//! Each graph edge of each layer (what weft prints: strokes merged and split at crossings, as
//! `paths::optimise` sees them) becomes a box: as wide as the nozzle, as tall as the layer,
//! from `z - height` to `z`. An end where the strut meets another strut at a shared node
//! (degree ≥ 2) is extended by half the width so struts meeting at an angle overlap instead of
//! leaving a notch; a free end (degree 1: a strut cut by the domain's edge) is not, so two
//! cropped struts whose ends lie a fraction of a width apart do not touch in the STL when they
//! do not touch in the lattice (extended, honeycomb-10mm's boundary ends 0.208 mm apart
//! overlapped and PrusaSlicer joined them with beads the design does not have). Boxes of
//! struts that share no node never intersect on the shipped examples (`tests/export_stl.rs`).
//! A curved strut (one graph edge with bend points) is one box per sampled segment.
//! Boxes are not unioned (slicers union the overlapping volumes themselves).

use crate::design::Design;
use crate::jobs::lattice::LatticeJob;
use crate::geom::{DVec2, Mesh};
use crate::pipeline::{self, Files};

/// An exported lattice.
pub struct Exported {
    /// Binary STL.
    pub stl: Vec<u8>,
    /// Struts (boxes).
    pub struts: usize,
    /// Triangles.
    pub triangles: usize,
    /// Total strut (graph edge) length, mm: the nominal extruded length.
    pub strut_mm: f64,
}

/// Why an export failed.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// Not a lattice job.
    #[error("export-stl takes a lattice design, this is a {0} job")]
    NotLattice(String),
    /// Generating the lattice failed.
    #[error(transparent)]
    Pipeline(#[from] pipeline::Error),
}

/// Builds the STL of `design`'s struts.
pub fn lattice_stl(design: &Design) -> Result<Exported, Error> {
    let job: LatticeJob = design.job.settings().ok_or_else(|| Error::NotLattice(design.job.kind().to_string()))?;
    let layers = crate::jobs::lattice::lattice_strokes(design, &Files::new())?;
    let w = design.printer.nozzle_diameter_mm;
    let mut mesh = Mesh::default();
    let mut struts = 0;
    let mut strut_mm = 0.0;
    for layer in &layers {
        let g = crate::paths::build_graph(layer, job.paths.merge_tolerance_mm);
        let (z0, z1) = (layer.z - layer.height, layer.z);
        for (e, c) in strut_boxes(&g, w) {
            let _ = e;
            let base = mesh.vertices.len() as u32;
            for z in [z0, z1] {
                for v in c {
                    mesh.vertices.push([v.x as f32, v.y as f32, z as f32]);
                }
            }
            // Bottom 0..4 (counter-clockwise from above), top 4..8; outward normals.
            let quads = [[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7]];
            for [i, j, k, l] in quads {
                mesh.triangles.push([base + i, base + j, base + k]);
                mesh.triangles.push([base + i, base + k, base + l]);
            }
        }
        struts += g.edges.iter().filter(|e| e.length > 0.0).count();
        strut_mm += g.edges.iter().map(|e| e.length).sum::<f64>();
    }
    let triangles = mesh.triangles.len();
    Ok(Exported { stl: mesh.to_stl_binary(), struts, triangles, strut_mm })
}

/// The footprint of every strut of `g` as counter-clockwise rectangles `width_mm` wide, with
/// the edge each belongs to: one per straight piece of the edge's printed polyline. A piece's
/// end is extended by half the width where it meets more of the lattice (a node of degree ≥ 2,
/// or a bend inside a curved strut) and not at a free end (degree 1).
pub fn strut_boxes(g: &crate::paths::Graph, width_mm: f64) -> Vec<(usize, [DVec2; 4])> {
    let mut out = Vec::new();
    for (ei, e) in g.edges.iter().enumerate() {
        let pts = g.edge_points(ei);
        let last = pts.len() - 1;
        for i in 0..last {
            let (a, b) = (pts[i], pts[i + 1]);
            let d = b - a;
            let len = d.length();
            if len <= 0.0 {
                continue;
            }
            let u = d / len * (width_mm / 2.0);
            let n = DVec2::new(-u.y, u.x);
            let ext_a = i > 0 || g.degree(e.a) >= 2;
            let ext_b = i + 1 < last || g.degree(e.b) >= 2;
            let p = if ext_a { a - u } else { a };
            let q = if ext_b { b + u } else { b };
            out.push((ei, [p - n, q - n, q + n, p + n]));
        }
    }
    out
}

/// Whether two convex polygons overlap or touch (separating-axis test; `gap` is the clearance
/// under which they count as touching, mm).
pub fn convex_touch(a: &[DVec2], b: &[DVec2], gap: f64) -> bool {
    for poly in [a, b] {
        for i in 0..poly.len() {
            let d = poly[(i + 1) % poly.len()] - poly[i];
            let len = d.length();
            if len == 0.0 {
                continue;
            }
            let n = DVec2::new(-d.y, d.x) / len;
            let span = |p: &[DVec2]| {
                p.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(n.dot(*v)), hi.max(n.dot(*v))))
            };
            let (alo, ahi) = span(a);
            let (blo, bhi) = span(b);
            if alo > bhi + gap || blo > ahi + gap {
                return false;
            }
        }
    }
    true
}

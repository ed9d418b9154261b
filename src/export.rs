//! Exports a lattice design's printed struts as a closed triangle mesh (binary STL), so other
//! slicers can be given the same lattice (`weft export-stl`, BENCHMARKS.md "Against other
//! slicers").
//!
//! Each graph edge of each layer (what weft prints: strokes merged and split at crossings, as
//! `paths::optimise` sees them) becomes a prism: as wide as the nozzle, as tall as the layer,
//! from `z - height` to `z`. An end where the strut meets another strut at a shared node
//! (degree ≥ 2) gets a round cap of half the width (a half octagon inscribed in the bead's
//! round end) so struts meeting at an angle overlap instead of leaving a notch; a free end
//! (degree 1: a strut cut by the domain's edge) gets none, so two cropped struts whose ends
//! lie a fraction of a width apart do not touch in the STL when they do not touch in the
//! lattice (extended, honeycomb-10mm's boundary ends 0.208 mm apart overlapped and
//! PrusaSlicer joined them with beads the design does not have). The cap is round rather than
//! a square extension because a square one reaches 0.141 mm from the node at its corners: on
//! voronoi-10mm, whose joints crowd, it made 23 pairs of struts 0.208–0.279 mm apart (beads
//! that do not touch) touch in the STL. So two prisms of struts sharing no node touch only where
//! the struts' centrelines are within one width, i.e. where weft's own beads touch too
//! (`tests/it/export_stl.rs`). A curved strut (one graph edge with bend points) is one prism per
//! sampled segment. Prisms are not unioned (slicers union the overlapping volumes themselves).

use crate::design::Design;
use crate::geom::{DVec2, Mesh};
use crate::kinds::lattice::LatticeJob;
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
    let layers = crate::kinds::lattice::lattice_strokes(design, &Files::new())?;
    let w = design.printer.nozzle_diameter_mm;
    let mut mesh = Mesh::default();
    let mut struts = 0;
    let mut strut_mm = 0.0;
    for layer in &layers {
        let g = crate::paths::build_graph(layer, job.paths.merge_tolerance_mm);
        let (z0, z1) = (layer.z - layer.height, layer.z);
        for (_, c) in strut_boxes(&g, w) {
            let base = mesh.vertices.len() as u32;
            let k = c.len() as u32;
            for z in [z0, z1] {
                for v in &c {
                    mesh.vertices.push([v.x as f32, v.y as f32, z as f32]);
                }
            }
            // Bottom 0..k (counter-clockwise from above), top k..2k; outward normals.
            for j in 1..k - 1 {
                mesh.triangles.push([base, base + j + 1, base + j]);
                mesh.triangles.push([base + k, base + k + j, base + k + j + 1]);
            }
            for i in 0..k {
                let i1 = (i + 1) % k;
                mesh.triangles.push([base + i, base + i1, base + k + i1]);
                mesh.triangles.push([base + i, base + k + i1, base + k + i]);
            }
        }
        struts += g.edges.iter().filter(|e| e.length > 0.0).count();
        strut_mm += g.edges.iter().map(|e| e.length).sum::<f64>();
    }
    let triangles = mesh.triangles.len();
    Ok(Exported { stl: mesh.to_stl_binary(), struts, triangles, strut_mm })
}

/// The footprint of every strut of `g` as a counter-clockwise convex polygon `width_mm` wide,
/// with the edge each belongs to: one per straight piece of the edge's printed polyline. A
/// piece's end gets a round cap (half an octagon inscribed in the circle of radius
/// `width_mm / 2` about the end, 3 more vertices) where it meets more of the lattice (a node
/// of degree ≥ 2, or a bend inside a curved strut) and is cut square at a free end (degree
/// 1). Polygons have 4, 7 or 10 vertices.
pub fn strut_boxes(g: &crate::paths::Graph, width_mm: f64) -> Vec<(usize, Vec<DVec2>)> {
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
            // Cap points at angles θ from the strut's direction: c + u cos θ + n sin θ.
            let cap = |c: DVec2, degs: [f64; 3]| degs.map(|d: f64| c + u * d.to_radians().cos() + n * d.to_radians().sin());
            let mut poly = vec![a - n, b - n];
            if ext_b {
                poly.extend(cap(b, [-45.0, 0.0, 45.0]));
            }
            poly.extend([b + n, a + n]);
            if ext_a {
                poly.extend(cap(a, [135.0, 180.0, 225.0]));
            }
            out.push((ei, poly));
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
            let span = |p: &[DVec2]| p.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(n.dot(*v)), hi.max(n.dot(*v))));
            let (alo, ahi) = span(a);
            let (blo, bhi) = span(b);
            if alo > bhi + gap || blo > ahi + gap {
                return false;
            }
        }
    }
    true
}

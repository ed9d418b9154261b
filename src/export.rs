//! Exports a lattice design's printed struts as a closed triangle mesh (binary STL), so other
//! slicers can be given the same lattice (`weft export-stl`, BENCHMARKS.md "Against other
//! slicers").
//!
//! Each graph edge of each layer (what weft prints: strokes merged and split at crossings, as
//! `paths::optimise` sees them) becomes a box: as wide as the nozzle, as tall as the layer,
//! from `z - height` to `z`, and extended by half the width at both ends so struts meeting at
//! an angle overlap instead of leaving a notch. Boxes are not unioned (slicers union the
//! overlapping volumes themselves).

use crate::design::Design;
use crate::jobs::lattice::LatticeJob;
use crate::geom::Mesh;
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
        for e in &g.edges {
            let (a, b) = (g.nodes[e.a], g.nodes[e.b]);
            let d = b - a;
            let len = d.length();
            if len <= 0.0 {
                continue;
            }
            let u = d / len * (w / 2.0);
            let n = crate::geom::DVec2::new(-u.y, u.x);
            let (p, q) = (a - u, b + u);
            let c = [p - n, q - n, q + n, p + n];
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
            struts += 1;
            strut_mm += e.length;
        }
    }
    let triangles = mesh.triangles.len();
    Ok(Exported { stl: mesh.to_stl_binary(), struts, triangles, strut_mm })
}

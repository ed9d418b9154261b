//! Taubin λ/μ smoothing (G. Taubin, "A signal processing approach to fair surface design",
//! SIGGRAPH 1995): each iteration moves every vertex a fraction λ towards the mean of its
//! neighbours, then a fraction μ < −λ away from it. The pair is a low-pass filter on the
//! vertex graph: it removes the voxel staircase (high frequencies) without the shrinkage of
//! plain Laplacian smoothing (a sphere keeps its radius).
//!
//! Constraints: a cap vertex keeps its coordinate on its ROI face (it slides in the plane),
//! and every vertex is kept inside the ROI box, so the caps stay flat and on the faces.
//! Only positions change, so a closed mesh stays closed.

use crate::geom::Mesh;

/// Shrinking step (fraction of the way to the neighbours' mean).
const LAMBDA: f64 = 0.5;
/// Inflating step. 1/λ + 1/μ = 0.039 is the pass-band frequency: below it the filter
/// slightly amplifies, so it is kept small (a voxelized 6 mm sphere grows 0.8 % in volume over
/// 20 iterations, against 2.3 % at Taubin's 0.1; the staircase goes as fast).
const MU: f64 = -0.51;

/// Smooths `mesh` in place (module doc). `on_plane[v]`: 0 for a free vertex, `1 + 2·axis +
/// side` for one on the cap plane `planes[axis][side]` (mm); `planes` is the ROI box.
pub(super) fn taubin(mesh: &mut Mesh, on_plane: &[u8], planes: [[f64; 2]; 3], iterations: u32, progress: &mut dyn FnMut(f32)) {
    if iterations == 0 || mesh.vertices.is_empty() {
        return;
    }
    let (start, neighbours) = adjacency(mesh);
    let mut next = mesh.vertices.clone();
    for it in 0..iterations {
        for f in [LAMBDA, MU] {
            for (v, out) in next.iter_mut().enumerate() {
                let ns = &neighbours[start[v] as usize..start[v + 1] as usize];
                let p = mesh.vertices[v];
                if ns.is_empty() {
                    *out = p;
                    continue;
                }
                let mut mean = [0.0f64; 3];
                for &n in ns {
                    let q = mesh.vertices[n as usize];
                    for a in 0..3 {
                        mean[a] += q[a] as f64;
                    }
                }
                let k = ns.len() as f64;
                for a in 0..3 {
                    let x = p[a] as f64 + f * (mean[a] / k - p[a] as f64);
                    out[a] = x.clamp(planes[a][0], planes[a][1]) as f32;
                }
                if let Some(c) = on_plane.get(v).copied().filter(|&c| c > 0) {
                    let (axis, side) = ((c as usize - 1) / 2, (c as usize - 1) % 2);
                    out[axis] = planes[axis][side] as f32;
                }
            }
            std::mem::swap(&mut mesh.vertices, &mut next);
        }
        progress((it + 1) as f32 / iterations as f32);
    }
}

/// The vertex graph in compressed rows: the neighbours of `v` are
/// `neighbours[start[v]..start[v + 1]]`, sorted, each once.
fn adjacency(mesh: &Mesh) -> (Vec<u32>, Vec<u32>) {
    let nv = mesh.vertices.len();
    let mut start = vec![0u32; nv + 1];
    for t in &mesh.triangles {
        for &v in t {
            // Each triangle gives each of its corners two neighbours.
            start[v as usize + 1] += 2;
        }
    }
    for v in 0..nv {
        start[v + 1] += start[v];
    }
    let mut fill = start.clone();
    let mut neighbours = vec![0u32; start[nv] as usize];
    for t in &mesh.triangles {
        for q in 0..3 {
            let (v, a, b) = (t[q], t[(q + 1) % 3], t[(q + 2) % 3]);
            let f = &mut fill[v as usize];
            neighbours[*f as usize] = a;
            neighbours[*f as usize + 1] = b;
            *f += 2;
        }
    }
    // Sort and dedupe each row (every neighbour of a closed mesh is listed twice), compacting.
    let mut write = 0usize;
    let mut compact_start = vec![0u32; nv + 1];
    for v in 0..nv {
        let row = start[v] as usize..start[v + 1] as usize;
        neighbours[row.clone()].sort_unstable();
        let mut last = u32::MAX;
        for r in row {
            let n = neighbours[r];
            if n != last {
                neighbours[write] = n;
                write += 1;
                last = n;
            }
        }
        compact_start[v + 1] = write as u32;
    }
    neighbours.truncate(write);
    (compact_start, neighbours)
}

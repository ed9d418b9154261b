//! Vertical ray casts onto the print surface: the highest surface point under (x, y) and its
//! outward unit normal.
//!
//! Meshes use a small uniform XY grid over the triangles rather than parry3d: every ray here
//! is vertical, so a 2D grid of triangle bounding boxes plus a 2D barycentric test is exact and
//! simple (~150 lines), computes in f64 (bit-identical on native and wasm), and adds nothing to
//! the wasm binary, whereas parry3d pulls in nalgebra/simba and its f32 build (hundreds of kB
//! of wasm for one query type).

use super::{Error, Surface};
use crate::geom::{DVec2, DVec3, Mesh};

/// A surface point and its outward unit normal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Hit {
    /// Point on the surface.
    pub p: DVec3,
    /// Outward unit normal (pointing up, towards the nozzle).
    pub n: DVec3,
}

/// A surface ready for ray casts.
pub(crate) enum Caster {
    Sphere { center: DVec3, radius: f64 },
    Cylinder { radius: f64, axis_z: f64 },
    Mesh(Box<MeshGrid>),
}

impl Caster {
    /// Prepares `surface` (`mesh` is the job's surface mesh, for [`Surface::Mesh`]).
    pub fn new(surface: &Surface, mesh: Option<&Mesh>) -> Result<Caster, Error> {
        Ok(match *surface {
            Surface::Sphere { radius_mm, center_mm } => Caster::Sphere { center: DVec3::from_array(center_mm), radius: radius_mm },
            Surface::Cylinder { radius_mm, axis_z_mm } => Caster::Cylinder { radius: radius_mm, axis_z: axis_z_mm },
            Surface::Mesh => {
                let mesh = mesh.ok_or(Error::NoSurfaceMesh)?;
                let grid = MeshGrid::new(mesh).ok_or(Error::NoSurfaceMesh)?;
                Caster::Mesh(Box::new(grid))
            }
        })
    }

    /// The first surface point a ray going down at (x, y) meets (the highest one), or `None`.
    pub fn cast(&self, x: f64, y: f64) -> Option<Hit> {
        match self {
            Caster::Sphere { center, radius } => {
                let (dx, dy) = (x - center.x, y - center.y);
                let h2 = radius * radius - dx * dx - dy * dy;
                if h2 < 0.0 {
                    return None;
                }
                let p = DVec3::new(x, y, center.z + h2.sqrt());
                Some(Hit { p, n: (p - *center) / *radius })
            }
            Caster::Cylinder { radius, axis_z } => {
                let h2 = radius * radius - y * y;
                if h2 < 0.0 {
                    return None;
                }
                let h = h2.sqrt();
                Some(Hit { p: DVec3::new(x, y, axis_z + h), n: DVec3::new(0.0, y / radius, h / radius) })
            }
            Caster::Mesh(g) => g.cast(x, y),
        }
    }
}

/// One triangle in f64 with its corner normals (oriented up).
struct Tri {
    v: [DVec3; 3],
    n: [DVec3; 3],
    /// 2D barycentric denominator.
    det: f64,
}

/// Triangles bucketed by the XY cells their bounding boxes overlap (CSR layout).
pub(crate) struct MeshGrid {
    tris: Vec<Tri>,
    min: DVec2,
    cell: f64,
    nx: usize,
    ny: usize,
    /// `items[start[c]..start[c + 1]]` are the triangles (ascending) of cell `c`.
    start: Vec<u32>,
    items: Vec<u32>,
}

/// Most bucket entries of a mesh of `tris` triangles: 32 per triangle (a regular mesh needs
/// 1–4), at most 32M (128 MiB). A grid holding more gets coarser cells. Proportional to the
/// triangles, so a fan of long wedges keeps its cell size as it gets more of them (its casts
/// then test a number of wedges proportional to the wedges, not to their square).
pub(crate) fn bucket_budget(tris: usize) -> usize {
    tris.saturating_mul(32).clamp(1024, 32 << 20)
}

/// About how many cells of side `cell` the triangles' footprints meet: a shape of area A and
/// perimeter P meets about A/c² + 2P/(πc) + 1 of them.
fn estimated_entries(tris: &[Tri], cell: f64) -> f64 {
    tris.iter()
        .map(|t| {
            let p = [t.v[0].truncate(), t.v[1].truncate(), t.v[2].truncate()];
            let perimeter = p[0].distance(p[1]) + p[1].distance(p[2]) + p[2].distance(p[0]);
            0.5 * t.det.abs() / (cell * cell) + 2.0 * perimeter / (std::f64::consts::PI * cell) + 1.0
        })
        .sum()
}

/// Calls `f` with every cell (of the `nx × ny` grid of `cell`-wide cells from `lo`) that the
/// XY projection of `t`, grown by a hair, overlaps: row by row, the x-extent of the triangle
/// within the row's band. Bounding boxes alone put a long thin triangle (a cone's fan) in
/// every cell of its box: a 100,000-triangle cone then needed billions of entries.
///
/// The hair (1e-6 of the triangle's size, plus 1 nm) covers every point [`MeshGrid::cast`]'s
/// barycentric test (tolerance 1e-9) accepts, so each cell lists every triangle a ray in it
/// can hit, in increasing order: casts find exactly what they found with box buckets.
fn cover(t: &Tri, lo: DVec2, cell: f64, nx: usize, ny: usize, f: &mut dyn FnMut(usize)) {
    let p = [t.v[0].truncate(), t.v[1].truncate(), t.v[2].truncate()];
    let bmin = p[0].min(p[1]).min(p[2]);
    let bmax = p[0].max(p[1]).max(p[2]);
    let hair = 1e-6 * (bmax - bmin).max_element() + 1e-6;
    let idx = |v: f64, n: usize| ((v / cell).floor().max(0.0) as usize).min(n - 1);
    let (y0, y1) = (idx(bmin.y - hair - lo.y, ny), idx(bmax.y + hair - lo.y, ny));
    for cy in y0..=y1 {
        // The band of the row, grown by the hair; the triangle's x-extent within it.
        let (b0, b1) = (lo.y + cy as f64 * cell - hair, lo.y + (cy + 1) as f64 * cell + hair);
        let (b0, b1) = if cy == 0 { (f64::NEG_INFINITY, b1) } else { (b0, b1) };
        let (b0, b1) = if cy == ny - 1 { (b0, f64::INFINITY) } else { (b0, b1) };
        let (mut xmin, mut xmax) = (f64::INFINITY, f64::NEG_INFINITY);
        for k in 0..3 {
            let (a, b) = (p[k], p[(k + 1) % 3]);
            if a.y >= b0 && a.y <= b1 {
                xmin = xmin.min(a.x);
                xmax = xmax.max(a.x);
            }
            if a.y != b.y {
                for yb in [b0, b1] {
                    let t = (yb - a.y) / (b.y - a.y);
                    if t > 0.0 && t < 1.0 {
                        let x = a.x + (b.x - a.x) * t;
                        xmin = xmin.min(x);
                        xmax = xmax.max(x);
                    }
                }
            }
        }
        if xmin > xmax {
            continue;
        }
        let (x0, x1) = (idx(xmin - hair - lo.x, nx), idx(xmax + hair - lo.x, nx));
        for cx in x0..=x1 {
            f(cy * nx + cx);
        }
    }
}

/// Faces meeting at a vertex are smoothed together when their normals are within this angle
/// (cos 40°): curved surfaces get continuous normals, sharp edges (a box's rim) stay sharp.
const CREASE_COS: f64 = 0.766_044_443_118_978;
/// cos 19.9°: faces within this of their mean normal are pairwise within the crease angle
/// (with a margin for rounding).
const HALF_CREASE_COS: f64 = 0.940_288_0;
/// Most faces at a vertex smoothed pair by pair (cost valence²) when they are not all within
/// the crease angle of each other.
const MAX_SMOOTH_VALENCE: usize = 1024;

impl MeshGrid {
    /// `None` when no triangle has an XY footprint.
    fn new(mesh: &Mesh) -> Option<MeshGrid> {
        // Weld vertices by exact position so unwelded meshes (STL) still get smooth normals.
        let mut order: Vec<u32> = (0..mesh.vertices.len() as u32).collect();
        let key = |i: u32| {
            let v = mesh.vertices[i as usize];
            [v[0].to_bits(), v[1].to_bits(), v[2].to_bits()]
        };
        order.sort_by_key(|&i| (key(i), i));
        let mut canon = vec![0u32; mesh.vertices.len()];
        let mut k = 0usize;
        while k < order.len() {
            let mut j = k;
            while j < order.len() && key(order[j]) == key(order[k]) {
                canon[order[j] as usize] = order[k];
                j += 1;
            }
            k = j;
        }
        // Face normals oriented up (a ray from above sees the upper side), unit length.
        struct Face {
            idx: [u32; 3],
            n: DVec3,
            angle: [f64; 3],
        }
        let mut faces = Vec::new();
        for t in &mesh.triangles {
            let idx = [canon[t[0] as usize], canon[t[1] as usize], canon[t[2] as usize]];
            let v = [mesh.vertex(idx[0]), mesh.vertex(idx[1]), mesh.vertex(idx[2])];
            let c = (v[1] - v[0]).cross(v[2] - v[0]);
            let len = c.length();
            if !len.is_finite() || len <= 1e-18 {
                continue;
            }
            let mut n = c / len;
            if n.z < 0.0 {
                n = -n;
            }
            let mut angle = [0.0; 3];
            for (k, a) in angle.iter_mut().enumerate() {
                let e1 = (v[(k + 1) % 3] - v[k]).normalize_or_zero();
                let e2 = (v[(k + 2) % 3] - v[k]).normalize_or_zero();
                *a = libm::acos(e1.dot(e2).clamp(-1.0, 1.0));
            }
            faces.push(Face { idx, n, angle });
        }
        // Vertex → faces (CSR).
        let nv = mesh.vertices.len();
        let mut vstart = vec![0u32; nv + 1];
        for f in &faces {
            for &i in &f.idx {
                vstart[i as usize + 1] += 1;
            }
        }
        for i in 0..nv {
            vstart[i + 1] += vstart[i];
        }
        let mut fill = vstart.clone();
        let mut vfaces = vec![0u32; vstart[nv] as usize];
        for (fi, f) in faces.iter().enumerate() {
            for &i in &f.idx {
                vfaces[fill[i as usize] as usize] = fi as u32;
                fill[i as usize] += 1;
            }
        }
        // A vertex shared by many faces (a cone's apex: every wedge) would cost valence² to
        // smooth face by face. When all its faces lie within half the crease angle of their
        // mean normal, every pair passes the crease test, so every corner there gets the same
        // sum, taken once in the same order (same bits). Otherwise, above
        // `MAX_SMOOTH_VALENCE` faces, its corners keep their faces' own normals (sharp).
        let corner_at = |g: &Face, vi: usize| g.idx.iter().position(|&x| x as usize == vi).unwrap_or(0);
        let shared: Vec<Option<DVec3>> = (0..nv)
            .map(|vi| {
                let around = &vfaces[vstart[vi] as usize..vstart[vi + 1] as usize];
                if around.len() <= 8 {
                    return None;
                }
                let mean = around.iter().fold(DVec3::ZERO, |m, &g| m + faces[g as usize].n).normalize_or_zero();
                let tight = around.iter().all(|&g| faces[g as usize].n.dot(mean) >= HALF_CREASE_COS);
                tight.then(|| {
                    around.iter().fold(DVec3::ZERO, |sum, &g| {
                        let g = &faces[g as usize];
                        sum + g.n * g.angle[corner_at(g, vi)]
                    })
                })
            })
            .collect();
        let mut tris = Vec::new();
        let mut lo = DVec2::splat(f64::INFINITY);
        let mut hi = DVec2::splat(f64::NEG_INFINITY);
        for f in &faces {
            let v = [mesh.vertex(f.idx[0]), mesh.vertex(f.idx[1]), mesh.vertex(f.idx[2])];
            let det = (v[1].y - v[2].y) * (v[0].x - v[2].x) + (v[2].x - v[1].x) * (v[0].y - v[2].y);
            if det.abs() < 1e-14 || f.n.z <= 1e-9 {
                continue; // vertical: no footprint
            }
            let mut n = [f.n; 3];
            for (k, nk) in n.iter_mut().enumerate() {
                let vi = f.idx[k] as usize;
                let around = &vfaces[vstart[vi] as usize..vstart[vi + 1] as usize];
                let sum = match shared[vi] {
                    Some(sum) => sum,
                    None if around.len() > MAX_SMOOTH_VALENCE => continue,
                    None => {
                        let mut sum = DVec3::ZERO;
                        for &g in around {
                            let g = &faces[g as usize];
                            if g.n.dot(f.n) >= CREASE_COS {
                                sum += g.n * g.angle[corner_at(g, vi)];
                            }
                        }
                        sum
                    }
                };
                let s = sum.normalize_or_zero();
                if s != DVec3::ZERO {
                    *nk = s;
                }
            }
            for p in &v {
                lo = lo.min(p.truncate());
                hi = hi.max(p.truncate());
            }
            tris.push(Tri { v, n, det });
        }
        if tris.is_empty() {
            return None;
        }
        let size = (hi - lo).max(DVec2::splat(1e-6));
        let mut cell = ((size.x * size.y / tris.len() as f64).sqrt() * 1.5).max(size.x.max(size.y) / 1024.0).max(1e-6);
        // Coarser cells until the buckets fit their budget (long thin triangles, e.g. a
        // cone's fan, cross many cells).
        let budget = bucket_budget(tris.len());
        // Counting the entries at a cell size costs as much as the entries: start from the
        // first size whose entries, estimated from each triangle's area and perimeter, fit.
        while estimated_entries(&tris, cell) > budget as f64 && cell < size.max_element() {
            cell *= 1.1;
        }
        let (nx, ny, start) = loop {
            let nx = ((size.x / cell).ceil() as usize).clamp(1, 1024);
            let ny = ((size.y / cell).ceil() as usize).clamp(1, 1024);
            let mut start = vec![0u32; nx * ny + 1];
            let mut items = 0usize;
            for t in &tris {
                cover(t, lo, cell, nx, ny, &mut |c| {
                    start[c + 1] += 1;
                    items += 1;
                });
            }
            if items <= budget || (nx == 1 && ny == 1) {
                break (nx, ny, start);
            }
            cell *= 1.1;
        };
        let mut g = MeshGrid { tris, min: lo, cell, nx, ny, start, items: Vec::new() };
        for c in 0..nx * ny {
            g.start[c + 1] += g.start[c];
        }
        let mut fill = g.start.clone();
        g.items = vec![0; g.start[nx * ny] as usize];
        for (ti, t) in g.tris.iter().enumerate() {
            cover(t, lo, cell, nx, ny, &mut |c| {
                g.items[fill[c] as usize] = ti as u32;
                fill[c] += 1;
            });
        }
        Some(g)
    }

    fn cell_of(&self, x: f64, y: f64) -> (usize, usize) {
        let cx = ((x - self.min.x) / self.cell).floor().clamp(0.0, (self.nx - 1) as f64) as usize;
        let cy = ((y - self.min.y) / self.cell).floor().clamp(0.0, (self.ny - 1) as f64) as usize;
        (cx, cy)
    }

    fn cast(&self, x: f64, y: f64) -> Option<Hit> {
        let eps = 1e-9;
        let span = DVec2::new(self.nx as f64, self.ny as f64) * self.cell;
        if !(x >= self.min.x - eps && y >= self.min.y - eps && x <= self.min.x + span.x + eps && y <= self.min.y + span.y + eps) {
            return None;
        }
        let (cx, cy) = self.cell_of(x, y);
        let c = cy * self.nx + cx;
        let mut best: Option<(f64, &Tri, [f64; 3])> = None;
        let candidates = &self.items[self.start[c] as usize..self.start[c + 1] as usize];
        // Triangles tested (the growth checks count them).
        crate::work::add(candidates.len());
        for &ti in candidates {
            let t = &self.tris[ti as usize];
            let [a, b, cc] = t.v;
            let l1 = ((b.y - cc.y) * (x - cc.x) + (cc.x - b.x) * (y - cc.y)) / t.det;
            let l2 = ((cc.y - a.y) * (x - cc.x) + (a.x - cc.x) * (y - cc.y)) / t.det;
            let l3 = 1.0 - l1 - l2;
            if l1 < -eps || l2 < -eps || l3 < -eps {
                continue;
            }
            let z = l1 * a.z + l2 * b.z + l3 * cc.z;
            if best.is_none_or(|(bz, _, _)| z > bz) {
                best = Some((z, t, [l1, l2, l3]));
            }
        }
        let (z, t, l) = best?;
        let l = [l[0].clamp(0.0, 1.0), l[1].clamp(0.0, 1.0), l[2].clamp(0.0, 1.0)];
        let n = (t.n[0] * l[0] + t.n[1] * l[1] + t.n[2] * l[2]).normalize_or_zero();
        let n = if n == DVec3::ZERO { t.n[0] } else { n };
        Some(Hit { p: DVec3::new(x, y, z), n })
    }
}

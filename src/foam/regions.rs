//! The regions Ω^j of a foam and the boundaries they share (the paper's sections 3.1.1 and
//! 3.2.1), with parry3d-f64 for every point query.
//!
//! - A region is a closed mesh; a point's region is the one whose solid holds it (parry's
//!   pseudo-normal inside test on an oriented `TriMesh`), else the one with the least signed
//!   distance (Algorithm 2's rule, for points on or just off a boundary).
//! - The boundary shared by Ω^j and Ω^k: the parts of Ω^j's faces within ε of Ω^k's surface.
//!   The paper grows both meshes by ε and intersects them (Algorithm 1); here each face of
//!   Ω^j near Ω^k is kept whole when its corners are within ε, dropped when its bounding
//!   sphere is farther than ε, and split in four otherwise (down to [`Options::depth`]): the
//!   same set without a mesh boolean, and exact for faces that match or lie on one plane.
//! - Checked here, each naming the meshes: a region deeper than ε inside another (overlap);
//!   a region sharing boundaries with more than one other (the paper's rule, unless relaxed);
//!   regions not all joined by shared boundaries (the union is not one domain). The per-layer
//!   rules (overlap in a layer, one polygon per layer) are checked on the slices by the job.

use crate::geom::{Aabb, DVec3, Mesh};
use parry3d_f64::math::Vector;
use parry3d_f64::query::PointQuery;
use parry3d_f64::shape::{TriMesh, TriMeshFlags};

/// Default ε as a fraction of the model's diagonal (the paper's "on the order of 10⁻⁶").
pub const DEFAULT_EPSILON_REL: f64 = 1e-6;
/// Smallest ε, mm: STL stores coordinates in f32, about 1e-5 mm at 100 mm.
pub const MIN_EPSILON_MM: f64 = 1e-4;
/// Default levels of splitting a face in four that partly touches another region (1/64 of a
/// face at 6).
pub const DEFAULT_DEPTH: u32 = 6;
/// Most face pieces examined while finding shared boundaries (refused above, before more work).
pub const MAX_PIECES: usize = 8_000_000;

/// How regions are read.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Options {
    /// ε as a fraction of the model's diagonal; default [`DEFAULT_EPSILON_REL`].
    pub epsilon_rel: f64,
    /// Splitting depth of partly touching faces; default [`DEFAULT_DEPTH`].
    pub depth: u32,
    /// Allow a region to share boundaries with several others (beyond the paper; its rule is
    /// at most one). Default false.
    pub many_neighbours: bool,
}

impl Default for Options {
    fn default() -> Self {
        Options { epsilon_rel: DEFAULT_EPSILON_REL, depth: DEFAULT_DEPTH, many_neighbours: false }
    }
}

/// Why the regions cannot make a foam.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum Error {
    /// No regions.
    #[error("a foam needs at least one region mesh; load the region meshes (one file per region)")]
    NoRegions,
    /// A region mesh parry cannot use as a solid.
    #[error("region {region}: {message}; export it as one closed (watertight) mesh")]
    BadMesh {
        /// Region name.
        region: String,
        /// What is wrong.
        message: String,
    },
    /// Two regions overlap.
    #[error("regions {a} and {b} overlap: the point ({x:.3}, {y:.3}, {z:.3}) mm of {a} lies {depth_mm:.3} mm inside {b}; regions must only touch (move or trim one of them)")]
    Overlap {
        /// The region whose point is inside.
        a: String,
        /// The region it is inside.
        b: String,
        /// How deep, mm.
        depth_mm: f64,
        /// The point.
        x: f64,
        /// The point.
        y: f64,
        /// The point.
        z: f64,
    },
    /// A region shares boundaries with several others.
    #[error("region {region} shares a boundary with {} regions ({}); the paper's method allows at most one (split the model differently, or allow several neighbours)", neighbours.len(), neighbours.join(", "))]
    TooManyNeighbours {
        /// The region.
        region: String,
        /// Its neighbours.
        neighbours: Vec<String>,
    },
    /// The regions are not all joined.
    #[error("the regions do not make one connected foam: {} touch(es) none of {} (regions must share a face with a neighbour, not just an edge or a corner)", groups[1..].iter().map(|g| g.join(" + ")).collect::<Vec<_>>().join(" and "), groups[0].join(", "))]
    Disconnected {
        /// Groups of regions joined among themselves; the first is the largest.
        groups: Vec<Vec<String>>,
    },
    /// Over the work limit.
    #[error("finding the shared boundaries would examine more than {MAX_PIECES} face pieces; use meshes with fewer triangles where regions touch")]
    TooBig,
}

/// One region: its name and solid.
pub struct Region {
    /// The name (its file).
    pub name: String,
    solid: TriMesh,
    /// Bounds, mm.
    pub bounds: Aabb,
    /// Triangles.
    pub triangles: usize,
}

/// The boundary shared by two regions.
pub struct Boundary {
    /// The region on one side (the lower index).
    pub a: usize,
    /// The region on the other side.
    pub b: usize,
    /// Its triangles (pieces of a's faces), mm.
    pub triangles: Vec<[DVec3; 3]>,
    /// Its area, mm².
    pub area_mm2: f64,
    surface: TriMesh,
    bounds: Aabb,
}

/// The regions of a foam and their shared boundaries.
pub struct Regions {
    /// Regions in the design's order.
    pub regions: Vec<Region>,
    /// Shared boundaries, by (a, b).
    pub boundaries: Vec<Boundary>,
    /// ε, mm.
    pub epsilon_mm: f64,
}

fn v(p: DVec3) -> Vector {
    Vector::new(p.x, p.y, p.z)
}

fn from_v(p: Vector) -> DVec3 {
    DVec3::new(p.x, p.y, p.z)
}

fn bounds_of(points: impl Iterator<Item = DVec3>) -> Option<Aabb> {
    let mut b: Option<Aabb> = None;
    for p in points {
        b = Some(match b {
            None => Aabb { min: p, max: p },
            Some(b) => Aabb { min: b.min.min(p), max: b.max.max(p) },
        });
    }
    b
}

fn near(a: &Aabb, b: &Aabb, margin: f64) -> bool {
    (a.min.x <= b.max.x + margin && b.min.x <= a.max.x + margin)
        && (a.min.y <= b.max.y + margin && b.min.y <= a.max.y + margin)
        && (a.min.z <= b.max.z + margin && b.min.z <= a.max.z + margin)
}

/// Distance from `p` to the box (0 inside).
fn box_distance(b: &Aabb, p: DVec3) -> f64 {
    let d = (b.min - p).max(p - b.max).max(DVec3::ZERO);
    d.length()
}

impl Region {
    /// Signed distance from `p` to the region's surface, mm (negative inside).
    pub fn signed_distance(&self, p: DVec3) -> f64 {
        let q = self.solid.project_local_point(v(p), false);
        let d = (from_v(q.point) - p).length();
        if q.is_inside {
            -d
        } else {
            d
        }
    }

    /// Distance from `p` to the region's surface, mm.
    fn surface_distance(&self, p: DVec3) -> f64 {
        let q = self.solid.project_local_point(v(p), false);
        (from_v(q.point) - p).length()
    }
}

impl Boundary {
    /// Distance from `p` to the shared boundary, mm; `None` when it is at least `beyond`
    /// (known from the boundary's box without a query).
    pub fn distance_within(&self, p: DVec3, beyond: f64) -> Option<f64> {
        if box_distance(&self.bounds, p) >= beyond {
            return None;
        }
        let q = self.surface.project_local_point(v(p), true);
        Some((from_v(q.point) - p).length())
    }

    /// Distance from `p` to the shared boundary, mm.
    pub fn distance(&self, p: DVec3) -> f64 {
        let q = self.surface.project_local_point(v(p), true);
        (from_v(q.point) - p).length()
    }

    /// The region across the boundary from `r` (`None` when `r` is not one of its sides).
    pub fn other(&self, r: usize) -> Option<usize> {
        if r == self.a {
            Some(self.b)
        } else if r == self.b {
            Some(self.a)
        } else {
            None
        }
    }
}

impl Regions {
    /// The region holding `p`: `hint` first (the previous point's), then the others; a point in
    /// none (on a boundary, or just outside after rounding) goes to the least signed distance.
    pub fn locate(&self, p: DVec3, hint: usize) -> usize {
        self.locate_signed(p, hint).0
    }

    /// [`Regions::locate`] and the signed distance to that region (negative inside; for a
    /// point inside, only its sign is certain: the search stops at the first solid holding it).
    pub fn locate_signed(&self, p: DVec3, hint: usize) -> (usize, f64) {
        let order = std::iter::once(hint).chain((0..self.regions.len()).filter(|&r| r != hint));
        let mut best = (f64::INFINITY, hint);
        for r in order {
            let Some(region) = self.regions.get(r) else { continue };
            if box_distance(&region.bounds, p) > best.0.max(0.0) {
                continue;
            }
            let d = region.signed_distance(p);
            if d < 0.0 {
                return (r, d);
            }
            if d < best.0 {
                best = (d, r);
            }
        }
        (best.1, best.0)
    }

    /// Names of regions.
    pub fn names(&self) -> Vec<String> {
        self.regions.iter().map(|r| r.name.clone()).collect()
    }

    /// The boundary between regions `a` and `b`, if they share one.
    pub fn boundary(&self, a: usize, b: usize) -> Option<usize> {
        self.boundaries.iter().position(|x| (x.a, x.b) == (a.min(b), a.max(b)))
    }
}

/// One face piece to classify.
struct Piece {
    t: [DVec3; 3],
    depth: u32,
}

/// Reads `input` (name, mesh in place) as regions and finds their shared boundaries.
pub fn regions(input: Vec<(String, Mesh)>, options: &Options) -> Result<Regions, Error> {
    if input.is_empty() {
        return Err(Error::NoRegions);
    }
    let mut out = Vec::with_capacity(input.len());
    for (name, mesh) in input {
        let points: Vec<Vector> = mesh.vertices.iter().map(|p| Vector::new(p[0] as f64, p[1] as f64, p[2] as f64)).collect();
        let bounds =
            bounds_of(points.iter().map(|p| from_v(*p))).ok_or_else(|| Error::BadMesh { region: name.clone(), message: "the mesh has no vertices".into() })?;
        let triangles = mesh.triangles.len();
        let solid = TriMesh::with_flags(points, mesh.triangles, TriMeshFlags::ORIENTED | TriMeshFlags::MERGE_DUPLICATE_VERTICES)
            .map_err(|e| Error::BadMesh { region: name.clone(), message: format!("it cannot be read as a solid ({e})") })?;
        out.push(Region { name, solid, bounds, triangles });
    }
    let all = bounds_of(out.iter().flat_map(|r| [r.bounds.min, r.bounds.max])).unwrap_or(Aabb { min: DVec3::ZERO, max: DVec3::ZERO });
    let epsilon = (options.epsilon_rel * (all.max - all.min).length()).max(MIN_EPSILON_MM);
    // A region must not reach into another deeper than ε: its corners are tested (a crossing
    // without a corner inside shows in the layers, which the job checks).
    for (i, r) in out.iter().enumerate() {
        for (j, s) in out.iter().enumerate() {
            if i == j || !near(&r.bounds, &s.bounds, 0.0) {
                continue;
            }
            for p in r.solid.vertices() {
                let p = from_v(*p);
                if box_distance(&s.bounds, p) > 0.0 {
                    continue;
                }
                let d = s.signed_distance(p);
                if d < -epsilon {
                    return Err(Error::Overlap { a: r.name.clone(), b: s.name.clone(), depth_mm: -d, x: p.x, y: p.y, z: p.z });
                }
            }
        }
    }
    let mut boundaries = Vec::new();
    let mut pieces = 0usize;
    for a in 0..out.len() {
        for b in a + 1..out.len() {
            if !near(&out[a].bounds, &out[b].bounds, epsilon) {
                continue;
            }
            // Faces of the region with fewer triangles, against the other's surface.
            let (from, to) = if out[a].triangles <= out[b].triangles { (a, b) } else { (b, a) };
            let tris = shared_faces(&out[from], &out[to], epsilon, options.depth, &mut pieces)?;
            let area_mm2: f64 = tris.iter().map(|t| (t[1] - t[0]).cross(t[2] - t[0]).length() / 2.0).sum();
            // A contact along an edge or at a corner has no area: not a shared boundary.
            if tris.is_empty() || area_mm2 <= (100.0 * epsilon).powi(2) {
                continue;
            }
            let bounds = bounds_of(tris.iter().flatten().copied()).unwrap_or(all);
            let verts: Vec<Vector> = tris.iter().flatten().map(|p| v(*p)).collect();
            let idx: Vec<[u32; 3]> = (0..tris.len() as u32).map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect();
            let surface = TriMesh::new(verts, idx)
                .map_err(|e| Error::BadMesh { region: out[a].name.clone(), message: format!("its boundary with {} cannot be built ({e})", out[b].name) })?;
            boundaries.push(Boundary { a, b, triangles: tris, area_mm2, surface, bounds });
        }
    }
    let names: Vec<String> = out.iter().map(|r| r.name.clone()).collect();
    if !options.many_neighbours {
        for (r, name) in names.iter().enumerate() {
            let neighbours: Vec<String> = boundaries.iter().filter_map(|b| b.other(r)).map(|o| names[o].clone()).collect();
            if neighbours.len() > 1 {
                return Err(Error::TooManyNeighbours { region: name.clone(), neighbours });
            }
        }
    }
    // Joined by shared boundaries: union-find over regions.
    let mut parent: Vec<usize> = (0..out.len()).collect();
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    for b in &boundaries {
        let (x, y) = (root(&mut parent, b.a), root(&mut parent, b.b));
        parent[x.max(y)] = x.min(y);
    }
    let mut groups: Vec<Vec<String>> = Vec::new();
    let mut group_of: Vec<(usize, usize)> = Vec::new();
    for (r, name) in names.iter().enumerate() {
        let g = root(&mut parent, r);
        match group_of.iter().find(|(root, _)| *root == g) {
            Some(&(_, k)) => groups[k].push(name.clone()),
            None => {
                group_of.push((g, groups.len()));
                groups.push(vec![name.clone()]);
            }
        }
    }
    if groups.len() > 1 {
        groups.sort_by_key(|g| std::cmp::Reverse(g.len()));
        return Err(Error::Disconnected { groups });
    }
    Ok(Regions { regions: out, boundaries, epsilon_mm: epsilon })
}

/// The pieces of `from`'s faces within `epsilon` of `to`'s surface.
fn shared_faces(from: &Region, to: &Region, epsilon: f64, depth: u32, count: &mut usize) -> Result<Vec<[DVec3; 3]>, Error> {
    let verts = from.solid.vertices();
    let mut out = Vec::new();
    let mut stack: Vec<Piece> = Vec::new();
    for t in from.solid.indices() {
        let tri = [from_v(verts[t[0] as usize]), from_v(verts[t[1] as usize]), from_v(verts[t[2] as usize])];
        let Some(b) = bounds_of(tri.iter().copied()) else { continue };
        if !near(&b, &to.bounds, epsilon) {
            continue;
        }
        stack.push(Piece { t: tri, depth: 0 });
        while let Some(Piece { t, depth: d }) = stack.pop() {
            *count += 1;
            if *count > MAX_PIECES {
                return Err(Error::TooBig);
            }
            let corners = t.map(|p| to.surface_distance(p));
            if corners.iter().all(|&c| c <= epsilon) {
                out.push(t);
                continue;
            }
            let centre = (t[0] + t[1] + t[2]) / 3.0;
            let radius = t.iter().map(|p| (*p - centre).length()).fold(0.0, f64::max);
            let at_centre = to.surface_distance(centre);
            if at_centre > radius + epsilon {
                continue;
            }
            if d >= depth {
                if at_centre <= epsilon {
                    out.push(t);
                }
                continue;
            }
            let m = [(t[0] + t[1]) / 2.0, (t[1] + t[2]) / 2.0, (t[2] + t[0]) / 2.0];
            for s in [[t[0], m[0], m[2]], [m[0], t[1], m[1]], [m[2], m[1], t[2]], [m[0], m[1], m[2]]] {
                stack.push(Piece { t: s, depth: d + 1 });
            }
        }
    }
    Ok(out)
}

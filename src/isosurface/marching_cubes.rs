//! Marching cubes with a case table derived from one rule, so the surface is closed and
//! consistently oriented for every sign pattern.
//!
//! The classic Lorensen–Cline / Bourke table resolves an *ambiguous face* (solid corners on
//! one diagonal, empty on the other) differently in different cases, so two cubes sharing
//! such a face can cut it differently and leave a crack. Here the table is not typed in but
//! built (256 cases, once per run) from a rule that depends only on the face's four corners:
//!
//! 1. On each face of a cube, walk the four corners counter-clockwise seen from outside the
//!    cube. Where the walk leaves the solid (solid corner → empty corner) a segment starts; it
//!    ends at the next crossed edge along the walk. So an ambiguous face always joins its two
//!    solid corners and cuts off each empty corner alone (the empty side is 6-connected, the
//!    same connectivity the cavity fill uses), whichever cube looks at it.
//! 2. Each crossed edge starts exactly one segment and ends one (the two faces at an edge walk
//!    it in opposite directions), so a cube's segments form closed loops, each going around
//!    the solid part of the cube's surface with the solid on its left.
//! 3. Each loop is capped by a disk of triangles inside the cube: a fan from its first vertex,
//!    or, when the loop crosses one face twice (only possible through an ambiguous face), a fan
//!    from a new vertex at the loop's centroid — a fan diagonal across that face could be
//!    chosen by the neighbouring cube too and make an edge of four triangles.
//!
//! Why this is closed: a neighbouring cube sees the shared face's corners in the opposite
//! order, so it makes the same segments in the opposite direction. Every mesh edge is
//! either such a face segment (one triangle in each of the two cubes, opposite directions), a
//! fan diagonal or centroid spoke (two triangles of one disk, opposite directions; a fan
//! diagonal joins two vertices with no common face, so no other cube has it). The grid is
//! padded with empty voxels, so no segment lies on the grid's outer faces. Tested on random
//! noise in `tests/it/isosurface.rs`.
//!
//! Every crossed grid edge makes one vertex, shared by the (up to four) cubes around it:
//! vertex indices of the current and previous layer of points are kept in two layer caches.
//! Vertices are made layer by layer and triangles cube by cube in grid order, so the output
//! order is deterministic. A vertex's position along its edge is clamped to
//! [`EDGE_MARGIN`]..1 − [`EDGE_MARGIN`], so vertices of different edges never coincide (a
//! corner exactly at the isovalue would put three vertices on it) and an importer's weld
//! never merges them. Edges to the padding put their vertex on the ROI face (the cap).

use crate::geom::Mesh;
use crate::volume::Volume;

/// No vertex on this edge.
const NONE: u32 = u32::MAX;

/// Nearest a vertex comes to either end of its grid edge, as a fraction of the edge.
pub(super) const EDGE_MARGIN: f64 = 1e-3;

/// Grid states in the padded classification grid.
pub(super) const SOLID: u8 = 1;

/// The 12 cube edges as (low corner, axis). Corner `c` sits at offset
/// `(c & 1, (c >> 1) & 1, (c >> 2) & 1)`.
const EDGES: [(usize, usize); 12] = [(0, 0), (2, 0), (4, 0), (6, 0), (0, 1), (1, 1), (4, 1), (5, 1), (0, 2), (1, 2), (2, 2), (3, 2)];

fn corner_offset(c: usize) -> [usize; 3] {
    [c & 1, (c >> 1) & 1, (c >> 2) & 1]
}

/// The cube edge joining corners `a` and `b` (which differ in one bit).
fn edge_between(a: usize, b: usize) -> usize {
    let (lo, axis) = (a.min(b), (a ^ b).trailing_zeros() as usize);
    EDGES.iter().position(|&e| e == (lo, axis)).expect("corners of one cube edge")
}

/// One loop of a case: the cube edges its vertices lie on, in order (solid on the left seen
/// from outside the cube), and whether it is fanned from a centroid vertex.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Loop {
    /// Cube edges, 3 to 12 of them.
    pub edges: Vec<u8>,
    /// Fan from a new centroid vertex (the loop crosses some face twice).
    pub centroid: bool,
}

impl Loop {
    /// Triangles this loop becomes.
    pub fn triangles(&self) -> usize {
        if self.centroid {
            self.edges.len()
        } else {
            self.edges.len() - 2
        }
    }
}

/// The 256 cases (bit `c` of the case = corner `c` is solid).
pub(super) struct Table {
    /// Loops of each case.
    pub cases: Vec<Vec<Loop>>,
    /// Triangles of each case.
    pub triangles: [u8; 256],
}

impl Table {
    /// Builds the table from the face rule (module doc).
    pub fn new() -> Table {
        // Faces as four corners counter-clockwise seen from outside: axis a, side s; with
        // (u, v) = the next two axes cyclically, e_u × e_v = e_a.
        let mut faces = [[0usize; 4]; 6];
        for a in 0..3 {
            let (u, v) = ((a + 1) % 3, (a + 2) % 3);
            for s in 0..2 {
                let walk: [(usize, usize); 4] = if s == 1 { [(0, 0), (1, 0), (1, 1), (0, 1)] } else { [(0, 0), (0, 1), (1, 1), (1, 0)] };
                for (q, &(pu, pv)) in walk.iter().enumerate() {
                    faces[2 * a + s][q] = (s << a) | (pu << u) | (pv << v);
                }
            }
        }
        let mut cases = Vec::with_capacity(256);
        let mut triangles = [0u8; 256];
        for (case, count) in triangles.iter_mut().enumerate() {
            let solid = |c: usize| case >> c & 1 == 1;
            // next[e] = the edge where the segment starting at edge e ends; face[e] its face.
            let mut next = [usize::MAX; 12];
            let mut face_of = [usize::MAX; 12];
            for (f, q) in faces.iter().enumerate() {
                let crossed = |m: usize| solid(q[m]) != solid(q[(m + 1) % 4]);
                for m in 0..4 {
                    if crossed(m) && solid(q[m]) {
                        let m2 = (1..4).map(|d| (m + d) % 4).find(|&m2| crossed(m2)).expect("crossings come in pairs");
                        let (e, e2) = (edge_between(q[m], q[(m + 1) % 4]), edge_between(q[m2], q[(m2 + 1) % 4]));
                        next[e] = e2;
                        face_of[e] = f;
                    }
                }
            }
            let mut loops = Vec::new();
            let mut seen = [false; 12];
            for start in 0..12 {
                if next[start] == usize::MAX || seen[start] {
                    continue;
                }
                let (mut edges, mut faces_used, mut e) = (Vec::new(), Vec::new(), start);
                while !seen[e] {
                    seen[e] = true;
                    edges.push(e as u8);
                    faces_used.push(face_of[e]);
                    e = next[e];
                }
                debug_assert_eq!(e, start, "segments close into loops");
                faces_used.sort_unstable();
                let centroid = faces_used.windows(2).any(|w| w[0] == w[1]);
                loops.push(Loop { edges, centroid });
            }
            *count = loops.iter().map(Loop::triangles).sum::<usize>() as u8;
            cases.push(loops);
        }
        Table { cases, triangles }
    }
}

/// The region to mesh: a padded classification grid over the ROI's voxels.
pub(super) struct Grid<'a> {
    /// The volume (values for interpolation).
    pub volume: &'a Volume,
    /// First ROI voxel along i, j, k.
    pub start: [usize; 3],
    /// ROI voxels along i, j, k.
    pub n: [usize; 3],
    /// `(n + 2)` points per axis, `i` fastest; [`SOLID`] marks the solid, anything else is
    /// empty; the outer layer (the padding) is empty.
    pub cells: &'a [u8],
    /// Isovalue.
    pub iso: f64,
    /// Cap planes: coordinate (mm) of the low and high ROI face along each axis.
    pub planes: [[f64; 2]; 3],
}

/// The mesh and, per vertex, the cap plane it must stay on.
pub(super) struct Extracted {
    /// Outward-facing, counter-clockwise triangles.
    pub mesh: Mesh,
    /// Per vertex: 0 = free, `1 + 2·axis + side` = on that cap plane.
    pub on_plane: Vec<u8>,
    /// ROI faces (−x, +x, −y, +y, −z, +z) where the surface was capped.
    pub capped: [bool; 6],
}

impl Grid<'_> {
    fn dims(&self) -> [usize; 3] {
        [self.n[0] + 2, self.n[1] + 2, self.n[2] + 2]
    }

    fn value(&self, p: [usize; 3]) -> f64 {
        let v = self.volume;
        let idx = v.index(self.start[0] + p[0] - 1, self.start[1] + p[1] - 1, self.start[2] + p[2] - 1);
        v.values.get(idx).map_or(f64::NAN, |&x| x as f64)
    }

    /// The vertex on the crossed grid edge from padded point `p` along `axis`, and its cap
    /// plane code.
    fn vertex(&self, p: [usize; 3], axis: usize) -> ([f32; 3], u8) {
        let s = self.volume.spacing_mm;
        let mut pos = [0.0f64; 3];
        for b in 0..3 {
            if b != axis {
                // The edge is crossed, so one end is a solid ROI voxel: p[b] ≥ 1.
                pos[b] = (self.start[b] + p[b] - 1) as f64 * s[b];
            }
        }
        let mut plane = 0;
        if p[axis] == 0 {
            pos[axis] = self.planes[axis][0];
            plane = 1 + 2 * axis as u8;
        } else if p[axis] == self.n[axis] {
            pos[axis] = self.planes[axis][1];
            plane = 2 + 2 * axis as u8;
        } else {
            let mut q = p;
            q[axis] += 1;
            let (a, b) = (self.value(p), self.value(q));
            let t = (self.iso - a) / (b - a);
            let t = if t.is_finite() { t.clamp(EDGE_MARGIN, 1.0 - EDGE_MARGIN) } else { 0.5 };
            pos[axis] = ((self.start[axis] + p[axis] - 1) as f64 + t) * s[axis];
        }
        ([pos[0] as f32, pos[1] as f32, pos[2] as f32], plane)
    }
}

/// The case of the cube whose lowest corner is point `base` of a padded grid with rows of `m0`
/// points and layers of `plane`.
#[inline]
fn case_at(cells: &[u8], base: usize, m0: usize, plane: usize) -> usize {
    let mut case = 0usize;
    for c in 0..8 {
        let [dx, dy, dz] = corner_offset(c);
        if cells[base + dx + dy * m0 + dz * plane] == SOLID {
            case |= 1 << c;
        }
    }
    case
}

/// Triangles [`extract`] makes from the padded grid `cells` (`m` points per axis): each
/// cube's from its case. One pass, nothing allocated.
pub(super) fn count(cells: &[u8], m: [usize; 3], table: &Table) -> u64 {
    let [m0, m1, m2] = m;
    let plane = m0 * m1;
    let mut total = 0u64;
    for k in 0..m2 - 1 {
        for j in 0..m1 - 1 {
            for i in 0..m0 - 1 {
                total += table.triangles[case_at(cells, k * plane + j * m0 + i, m0, plane)] as u64;
            }
        }
    }
    total
}

/// Meshes `grid` (module doc) into `triangles` triangles (from [`count`]). `progress` gets
/// 0..1 as the layers are done.
pub(super) fn extract(grid: &Grid, table: &Table, triangles: usize, progress: &mut dyn FnMut(f32)) -> Extracted {
    let [m0, m1, m2] = grid.dims();
    let plane = m0 * m1;
    let cells = grid.cells;
    let solid = |idx: usize| cells[idx] == SOLID;
    let mut out = Extracted { mesh: Mesh::default(), on_plane: Vec::new(), capped: [false; 6] };
    out.mesh.triangles.reserve_exact(triangles);
    // Vertex ids of the x edges (first half) and y edges (second half) of a layer of points,
    // and of the z edges between two layers.
    let mut prev = vec![NONE; 2 * plane];
    let mut cur = vec![NONE; 2 * plane];
    let mut zs = vec![NONE; plane];
    let add = |out: &mut Extracted, p: [usize; 3], axis: usize| -> u32 {
        let (pos, on) = grid.vertex(p, axis);
        if on > 0 {
            out.capped[on as usize - 1] = true;
        }
        out.mesh.vertices.push(pos);
        out.on_plane.push(on);
        (out.mesh.vertices.len() - 1) as u32
    };
    let mut ids = [0u32; 12];
    for k in 0..m2 {
        cur.fill(NONE);
        // The padding layers (k = 0, m2 − 1) are empty: no crossing within them.
        if k > 0 && k + 1 < m2 {
            for j in 0..m1 {
                for i in 0..m0 {
                    let idx = k * plane + j * m0 + i;
                    if i + 1 < m0 && solid(idx) != solid(idx + 1) {
                        cur[j * m0 + i] = add(&mut out, [i, j, k], 0);
                    }
                    if j + 1 < m1 && solid(idx) != solid(idx + m0) {
                        cur[plane + j * m0 + i] = add(&mut out, [i, j, k], 1);
                    }
                }
            }
        }
        if k > 0 {
            let kz = k - 1;
            zs.fill(NONE);
            for j in 0..m1 {
                for i in 0..m0 {
                    let idx = kz * plane + j * m0 + i;
                    if solid(idx) != solid(idx + plane) {
                        zs[j * m0 + i] = add(&mut out, [i, j, kz], 2);
                    }
                }
            }
            // Cubes between point layers kz and k.
            for j in 0..m1 - 1 {
                for i in 0..m0 - 1 {
                    let case = case_at(cells, kz * plane + j * m0 + i, m0, plane);
                    if case == 0 || case == 255 {
                        continue;
                    }
                    for lp in &table.cases[case] {
                        for (slot, &e) in ids.iter_mut().zip(&lp.edges) {
                            let (c, axis) = EDGES[e as usize];
                            let [dx, dy, dz] = corner_offset(c);
                            let layer = if dz == 1 { &cur } else { &prev };
                            *slot = match axis {
                                0 => layer[(j + dy) * m0 + i],
                                1 => layer[plane + j * m0 + i + dx],
                                _ => zs[(j + dy) * m0 + i + dx],
                            };
                            debug_assert_ne!(*slot, NONE);
                        }
                        emit(&mut out, &ids[..lp.edges.len()], lp.centroid);
                    }
                }
            }
        }
        std::mem::swap(&mut prev, &mut cur);
        progress((k + 1) as f32 / m2 as f32);
    }
    out
}

/// Triangles of one loop (vertex ids in loop order), reversed so they face out of the solid
/// (the loop goes counter-clockwise around the solid seen from outside the cube, i.e. seen
/// from the empty side it is clockwise).
fn emit(out: &mut Extracted, l: &[u32], centroid: bool) {
    let tris = &mut out.mesh.triangles;
    if centroid {
        let mut sum = [0.0f64; 3];
        for &v in l {
            let p = out.mesh.vertices[v as usize];
            for a in 0..3 {
                sum[a] += p[a] as f64;
            }
        }
        let n = l.len() as f64;
        out.mesh.vertices.push([(sum[0] / n) as f32, (sum[1] / n) as f32, (sum[2] / n) as f32]);
        out.on_plane.push(0);
        let c = (out.mesh.vertices.len() - 1) as u32;
        for q in 0..l.len() {
            tris.push([c, l[(q + 1) % l.len()], l[q]]);
        }
    } else {
        for q in 1..l.len() - 1 {
            tris.push([l[0], l[q + 1], l[q]]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_has_the_known_shape() {
        let t = Table::new();
        assert!(t.cases[0].is_empty() && t.cases[255].is_empty());
        // One solid corner: one triangle; its complement: one triangle.
        assert_eq!(t.cases[1].len(), 1);
        assert_eq!(t.triangles[1], 1);
        assert_eq!(t.triangles[254], 1);
        // Two solid corners on a face diagonal (0 and 3): joined, one loop of 6 crossing the
        // z = 0 face twice → a centroid fan.
        assert_eq!(t.cases[0b1001].len(), 1);
        assert!(t.cases[0b1001][0].centroid);
        // Its complement: empty corners 0 and 3 cut off alone: two triangles.
        assert_eq!(t.cases[255 ^ 0b1001].len(), 2);
        // Body diagonal (0 and 7): two separate corners.
        assert_eq!(t.cases[0b1000_0001].len(), 2);
        // Every crossed edge is in exactly one loop of its case.
        for case in 1..255usize {
            let mut used = [0; 12];
            for l in &t.cases[case] {
                for &e in &l.edges {
                    used[e as usize] += 1;
                }
            }
            for (e, &(c, axis)) in EDGES.iter().enumerate() {
                let crossed = (case >> c & 1) != (case >> (c | 1 << axis) & 1);
                assert_eq!(used[e], crossed as i32, "case {case} edge {e}");
            }
        }
    }
}

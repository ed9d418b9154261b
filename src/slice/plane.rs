//! Triangle–plane intersection and the Z sweep that hands each layer only the triangles
//! spanning its cutting plane.
//!
//! Robustness: a vertex exactly on the plane is treated as lying slightly *above* it
//! (symbolic perturbation), so every triangle is either not cut or cut through exactly two
//! of its edges, and shared edges are cut identically by both neighbouring triangles.
//! Intersection points are computed from the edge's lower vertex to its upper one (a fixed
//! order), so the two triangles sharing an edge produce bit-identical points.

use crate::geom::tolerance::to_um;
use crate::geom::Mesh;

/// A point in integer micrometres (x, y). Ordered lexicographically.
pub(crate) type Pt = [i32; 2];

/// A directed contour segment: the solid lies on its left (outer loops come out CCW).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub(crate) struct Seg {
    pub a: Pt,
    pub b: Pt,
}

#[inline]
fn vtx(mesh: &Mesh, i: u32) -> [f64; 3] {
    let v = mesh.vertices[i as usize];
    [v[0] as f64, v[1] as f64, v[2] as f64]
}

/// Point where the edge from `lo` (strictly below `h`) to `hi` (at or above `h`) meets the plane.
#[inline]
fn cut(lo: [f64; 3], hi: [f64; 3], h: f64) -> Pt {
    if hi[2] == h {
        return [to_um(hi[0]), to_um(hi[1])];
    }
    let t = (h - lo[2]) / (hi[2] - lo[2]);
    [to_um(lo[0] + t * (hi[0] - lo[0])), to_um(lo[1] + t * (hi[1] - lo[1]))]
}

/// Intersection point of edge (p, q) with the plane, whichever of p, q is the lower one.
#[inline]
fn cut_edge(p: [f64; 3], q: [f64; 3], h: f64) -> Pt {
    if p[2] < h {
        cut(p, q, h)
    } else {
        cut(q, p, h)
    }
}

/// The oriented segment where triangle `t` crosses the plane `z = h`, if it does.
///
/// With `a` the vertex alone on its side and `(a, b, c)` the triangle's counter-clockwise
/// order (seen from outside), the segment runs P(ab) → P(ca) when `a` is above and the other
/// way when `a` is below; this puts the solid on the segment's left.
pub(crate) fn cut_triangle(mesh: &Mesh, t: [u32; 3], h: f64) -> Option<Seg> {
    let v = [vtx(mesh, t[0]), vtx(mesh, t[1]), vtx(mesh, t[2])];
    let above = [v[0][2] >= h, v[1][2] >= h, v[2][2] >= h];
    let n_above = above.iter().filter(|&&x| x).count();
    if n_above == 0 || n_above == 3 {
        return None;
    }
    let lone_above = n_above == 1;
    // The lone vertex is the one whose side differs from the other two.
    let k = (0..3).find(|&i| above[i] == lone_above)?;
    let (a, b, c) = (v[k], v[(k + 1) % 3], v[(k + 2) % 3]);
    let pab = cut_edge(a, b, h);
    let pca = cut_edge(c, a, h);
    let (s, e) = if lone_above { (pab, pca) } else { (pca, pab) };
    if s == e {
        return None;
    }
    Some(Seg { a: s, b: e })
}

/// The triangles sorted by their lowest Z, for sweeping planes up through them: shared (read
/// only) by the [`Cursor`]s that sweep runs of layers side by side.
pub(crate) struct Sweep<'a> {
    mesh: &'a Mesh,
    /// Triangle indices sorted by (min z, index).
    order: Vec<u32>,
    zmin: Vec<f32>,
    zmax: Vec<f32>,
    /// Highest Z over the usable triangles (finite coordinates), or `None` if there are none.
    pub top: Option<f64>,
}

/// A sweep of increasing plane heights, keeping an active list of the triangles that may
/// still be cut. Each call to [`Cursor::segments`] costs O(triangles spanning the plane +
/// triangles entering), not O(all triangles).
pub(crate) struct Cursor<'s, 'a> {
    sweep: &'s Sweep<'a>,
    next: usize,
    active: Vec<u32>,
    last_h: f64,
}

impl<'a> Sweep<'a> {
    pub fn new(mesh: &'a Mesh) -> Sweep<'a> {
        let n = mesh.triangles.len();
        let mut zmin = vec![0f32; n];
        let mut zmax = vec![0f32; n];
        let mut order = Vec::with_capacity(n);
        let mut top: Option<f32> = None;
        for (i, t) in mesh.triangles.iter().enumerate() {
            let vs = [mesh.vertices[t[0] as usize], mesh.vertices[t[1] as usize], mesh.vertices[t[2] as usize]];
            if vs.iter().any(|v| !(v[0].is_finite() && v[1].is_finite() && v[2].is_finite())) {
                continue;
            }
            let lo = vs[0][2].min(vs[1][2]).min(vs[2][2]);
            let hi = vs[0][2].max(vs[1][2]).max(vs[2][2]);
            if lo == hi {
                continue; // horizontal: never produces a segment
            }
            zmin[i] = lo;
            zmax[i] = hi;
            top = Some(top.map_or(hi, |t| t.max(hi)));
            order.push(i as u32);
        }
        // A total order (ties by index): the same order at any thread count.
        crate::par::sort_unstable_by(&mut order, |&a, &b| zmin[a as usize].total_cmp(&zmin[b as usize]).then(a.cmp(&b)));
        Sweep { mesh, order, zmin, zmax, top: top.map(f64::from) }
    }

    /// A cursor whose first plane is `h`: its active list is the one a sweep from the bottom
    /// would hold there (the triangles entered below `h` and reaching it, in entering order),
    /// so runs of layers swept apart cut the same segments in the same order.
    pub fn cursor(&self, h: f64) -> Cursor<'_, 'a> {
        let next = self.order.partition_point(|&t| (self.zmin[t as usize] as f64) < h);
        let active = self.order[..next].iter().copied().filter(|&t| self.zmax[t as usize] as f64 >= h).collect();
        Cursor { sweep: self, next, active, last_h: h }
    }
}

impl Cursor<'_, '_> {
    /// The oriented segments of the plane `z = h`. Heights must not decrease between calls.
    pub fn segments(&mut self, h: f64, out: &mut Vec<Seg>) {
        debug_assert!(h >= self.last_h);
        self.last_h = h;
        out.clear();
        let s = self.sweep;
        while self.next < s.order.len() && (s.zmin[s.order[self.next] as usize] as f64) < h {
            self.active.push(s.order[self.next]);
            self.next += 1;
        }
        let zmax = &s.zmax;
        self.active.retain(|&t| zmax[t as usize] as f64 >= h);
        for &t in &self.active {
            if let Some(seg) = cut_triangle(s.mesh, s.mesh.triangles[t as usize], h) {
                out.push(seg);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::shapes::Shape;

    #[test]
    fn vertex_on_plane_counts_as_above() {
        let mesh = Mesh { vertices: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 1.0], [0.0, 1.0, 1.0]], triangles: vec![[0, 1, 2]] };
        // Plane through the two upper vertices: the segment is exactly that edge.
        let s = cut_triangle(&mesh, [0, 1, 2], 1.0).unwrap();
        let mut ends = [s.a, s.b];
        ends.sort();
        assert_eq!(ends, [[0, 1000], [1000, 0]]);
        // Plane through the lowest vertex only: it counts as above, so nothing is below.
        assert!(cut_triangle(&mesh, [0, 1, 2], 0.0).is_none());
    }

    #[test]
    fn cube_segments_run_counter_clockwise() {
        let mesh = Shape::Cube { size: [2.0, 2.0, 2.0] }.mesh();
        let sweep = Sweep::new(&mesh);
        let mut segs = Vec::new();
        sweep.cursor(0.0).segments(1.0, &mut segs);
        assert_eq!(segs.len(), 8);
        // Twice the signed area, summed over the segments (a closed loop).
        let twice: i64 = segs.iter().map(|s| s.a[0] as i64 * s.b[1] as i64 - s.b[0] as i64 * s.a[1] as i64).sum();
        assert_eq!(twice, 2 * 4_000_000);
    }
}

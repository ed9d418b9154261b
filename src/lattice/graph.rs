//! Strut graphs: welded vertices and de-duplicated edges, in the pattern's frame (mm).

use crate::geom::DVec2;
use crate::paths::graph::IntMap;
use std::collections::HashSet;
use std::hash::BuildHasherDefault;

/// The weld index and the edge set are look-ups only (their iteration order never reaches the
/// output), so they use the small multiplicative hasher of the path graph: SipHash made
/// `vertex` a third of the generation time on big layers.
type IntSet<K> = HashSet<K, BuildHasherDefault<crate::paths::graph::IntHasher>>;

/// Points closer than about this (mm) are the same vertex (shared corners of cells generated
/// cell by cell, computed along different float paths).
const WELD_MM: f64 = 1e-6;

/// An axis-aligned rectangle, mm.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Rect {
    pub min: DVec2,
    pub max: DVec2,
}

impl Rect {
    /// The rectangle grown by `m` on every side.
    pub fn grown(&self, m: f64) -> Rect {
        Rect { min: self.min - DVec2::splat(m), max: self.max + DVec2::splat(m) }
    }
    /// Width × height, mm².
    pub fn area(&self) -> f64 {
        let s = self.max - self.min;
        s.x.max(0.0) * s.y.max(0.0)
    }
    /// Bounding box of points (None when empty).
    pub fn of_points<'a>(pts: impl IntoIterator<Item = &'a DVec2>) -> Option<Rect> {
        let mut it = pts.into_iter();
        let first = *it.next()?;
        let mut r = Rect { min: first, max: first };
        for p in it {
            r.min = r.min.min(*p);
            r.max = r.max.max(*p);
        }
        Some(r)
    }
    /// Whether two rectangles overlap (closed).
    pub fn overlaps(&self, o: &Rect) -> bool {
        self.min.x <= o.max.x && o.min.x <= self.max.x && self.min.y <= o.max.y && o.min.y <= self.max.y
    }
}

/// Vertices and edges of a pattern. Vertices within [`WELD_MM`] are merged; each edge (as an
/// unordered vertex pair) is stored once, in insertion order (deterministic).
#[derive(Default)]
pub(crate) struct Graph {
    pub pts: Vec<DVec2>,
    pub edges: Vec<[u32; 2]>,
    /// Set for curved patterns: every edge is printed as this sampled curve
    /// ([`super::curved`]).
    pub curve: Option<super::curved::Curve>,
    index: IntMap<(i64, i64), u32>,
    seen: IntSet<(u32, u32)>,
}

impl Graph {
    /// The vertex at `p` (an existing one within the weld distance, or a new one).
    pub fn vertex(&mut self, p: DVec2) -> u32 {
        let kx = libm::floor(p.x / WELD_MM) as i64;
        let ky = libm::floor(p.y / WELD_MM) as i64;
        if let Some(&i) = self.index.get(&(kx, ky)) {
            return i;
        }
        for dx in -1..=1 {
            for dy in -1..=1 {
                if let Some(&i) = self.index.get(&(kx + dx, ky + dy)) {
                    if (self.pts[i as usize] - p).length_squared() <= WELD_MM * WELD_MM * 4.0 {
                        return i;
                    }
                }
            }
        }
        let i = self.pts.len() as u32;
        self.pts.push(p);
        self.index.insert((kx, ky), i);
        i
    }

    /// Adds the segment `a`–`b` unless it is degenerate or already present.
    pub fn seg(&mut self, a: DVec2, b: DVec2) {
        let i = self.vertex(a);
        let j = self.vertex(b);
        if i == j {
            return;
        }
        if self.seen.insert((i.min(j), i.max(j))) {
            self.edges.push([i, j]);
        }
    }

    /// Adds a polyline (consecutive segments); `closed` also joins the last point to the first.
    pub fn polyline(&mut self, pts: &[DVec2], closed: bool) {
        for w in pts.windows(2) {
            self.seg(w[0], w[1]);
        }
        if closed && pts.len() > 2 {
            self.seg(pts[pts.len() - 1], pts[0]);
        }
    }
}

impl Graph {
    /// Contracts every edge shorter than `min_len` (its end vertices become one, at the
    /// lowest-numbered vertex of the group), so that no strut shorter than `min_len` is left
    /// to be dropped later (which would disconnect the lattice). Edge order is kept.
    pub fn contract_short(&mut self, min_len: f64) {
        let n = self.pts.len();
        let mut parent: Vec<u32> = (0..n as u32).collect();
        fn find(p: &mut [u32], mut i: u32) -> u32 {
            while p[i as usize] != i {
                p[i as usize] = p[p[i as usize] as usize];
                i = p[i as usize];
            }
            i
        }
        let mut any = false;
        for e in &self.edges {
            if (self.pts[e[0] as usize] - self.pts[e[1] as usize]).length() < min_len {
                let (a, b) = (find(&mut parent, e[0]), find(&mut parent, e[1]));
                if a != b {
                    parent[a.max(b) as usize] = a.min(b);
                    any = true;
                }
            }
        }
        if !any {
            return;
        }
        let old = std::mem::take(&mut self.edges);
        self.seen.clear();
        for e in old {
            let (a, b) = (find(&mut parent, e[0]), find(&mut parent, e[1]));
            if a != b && self.seen.insert((a.min(b), a.max(b))) {
                self.edges.push([a, b]);
            }
        }
    }
}

/// √3 (sqrt is correctly rounded on every target).
pub(crate) fn sqrt3() -> f64 {
    3f64.sqrt()
}

//! Cleaning a raw triangle list: weld close vertices, drop degenerate and duplicate
//! triangles, count open edges.
//!
//! Deterministic: vertices keep the order of their first appearance and triangles the file
//! order; hash tables are used only for lookups, never iterated.
//!
//! Bounded and linear on any input: every step works in place on the raw arrays (kept items
//! move down, never up) and looks up through open-addressing tables of `u32` ids sized once
//! from the input counts (no growth, no rehash), so the memory high-water mark is a fixed
//! function of the counts ([`extra_peak`]), whatever the geometry. The hash is seeded from
//! the vertex data itself, so a file cannot be crafted to make its keys collide (which
//! would make each lookup scan the table: quadratic).

use super::RawMesh;
use crate::geom::Mesh;

/// A cleaned mesh and what was done to it.
#[derive(Debug)]
pub(super) struct Repaired {
    pub mesh: Mesh,
    pub degenerate_removed: usize,
    pub duplicates_removed: usize,
    pub open_edges: usize,
}

const NONE: u32 = u32::MAX;

/// Twice the area below this fraction of the longest edge squared counts as zero area.
const ZERO_AREA_RATIO: f64 = 1e-12;

/// Bytes of a [`Table`] for `n` entries (fixed size, or grown to hold `n`).
fn table_bytes(n: u64) -> u64 {
    4 * n.saturating_mul(2).max(16).next_power_of_two()
}

/// Upper bound of the bytes [`repair`] allocates beyond the raw mesh it is given
/// (`v` vertices, `t` triangles, 12 bytes each, reused in place), by step: exact dedupe
/// (map + table), weld (table, chain, map), triangle dedupe (table), compaction (id map,
/// then shrinking copies), open edges (a `u64` per corner).
pub(super) fn extra_peak(v: u64, t: u64) -> u64 {
    // The dedupe table starts small and doubles: at most the full size plus the half it left.
    let dedupe = 4 * v + table_bytes(v) + table_bytes(v) / 2;
    let weld = 8 * v + table_bytes(v);
    let tris = table_bytes(t);
    let compact = 12 * v.max(t);
    let edges = 24 * t;
    dedupe.max(weld).max(tris).max(compact).max(edges)
}

/// Cleans `raw`. `tolerance_mm` ≤ 0 (or NaN, or below 1 nm) welds only identical positions.
pub(super) fn repair(raw: RawMesh, tolerance_mm: f64) -> Repaired {
    let RawMesh { mut vertices, mut triangles } = raw;
    let seed = seed_of(&vertices);
    // 1. Identical positions → one vertex (first appearance order).
    let map = dedupe_exact(&mut vertices, seed);
    remap(&mut triangles, &map);
    drop(map);
    // 2. Weld positions closer than the tolerance.
    if tolerance_mm.is_finite() && tolerance_mm >= 1e-6 {
        let map = weld(&mut vertices, tolerance_mm, seed);
        remap(&mut triangles, &map);
    } else if tolerance_mm == f64::INFINITY {
        let map = vec![0u32; vertices.len()];
        vertices.truncate(1);
        remap(&mut triangles, &map);
    }
    let welded = &vertices;

    // 3. Degenerate and duplicate triangles, kept ones moved down in place.
    let (mut degenerate_removed, mut duplicates_removed) = (0, 0);
    let mut seen = Table::new(triangles.len());
    let mut kept = 0usize;
    for i in 0..triangles.len() {
        let Some(&t) = triangles.get(i) else { break };
        if t.contains(&NONE) || t[0] == t[1] || t[1] == t[2] || t[0] == t[2] || zero_area(welded, t) {
            degenerate_removed += 1;
            continue;
        }
        let key = sorted(t);
        let h = hash3(seed ^ 0x7472_6973, key);
        let found = seen.find_or_insert(h, kept as u32, |id| triangles.get(id as usize).map(|&u| sorted(u)) == Some(key));
        if found.is_some() {
            duplicates_removed += 1;
            continue;
        }
        if let Some(slot) = triangles.get_mut(kept) {
            *slot = t;
        }
        kept += 1;
    }
    drop(seen);
    triangles.truncate(kept);

    // 4. Keep referenced vertices only, in welded order.
    let mut new_id = vec![NONE; vertices.len()];
    for t in &triangles {
        for &i in t {
            if let Some(slot) = new_id.get_mut(i as usize) {
                *slot = 0;
            }
        }
    }
    let mut used = 0usize;
    for i in 0..vertices.len() {
        if new_id.get(i) == Some(&0) {
            if let (Some(&v), Some(id)) = (vertices.get(i), new_id.get_mut(i)) {
                *id = used as u32;
                if let Some(dst) = vertices.get_mut(used) {
                    *dst = v;
                }
                used += 1;
            }
        }
    }
    vertices.truncate(used);
    remap(&mut triangles, &new_id);
    drop(new_id);
    // The mesh lives on through slicing: give back what the raw arrays over-held.
    vertices.shrink_to_fit();
    triangles.shrink_to_fit();

    // 5. Open edges: undirected edges used by exactly one triangle.
    let mut edges: Vec<u64> = Vec::with_capacity(triangles.len().saturating_mul(3));
    for t in &triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            let (lo, hi) = if a < b { (a, b) } else { (b, a) };
            edges.push(((lo as u64) << 32) | hi as u64);
        }
    }
    // Plain values (equal ones are alike): the same order at any thread count.
    crate::par::sort_unstable_by(&mut edges, |a, b| a.cmp(b));
    let open_edges = edges.chunk_by(|a, b| a == b).filter(|run| run.len() == 1).count();
    drop(edges);

    Repaired { mesh: Mesh { vertices, triangles }, degenerate_removed, duplicates_removed, open_edges }
}

/// Replaces every index `i` by `map[i]` (`NONE` when out of range: dropped as degenerate).
fn remap(triangles: &mut [[u32; 3]], map: &[u32]) {
    for t in triangles.iter_mut() {
        for i in t.iter_mut() {
            *i = map.get(*i as usize).copied().unwrap_or(NONE);
        }
    }
}

fn sorted(mut t: [u32; 3]) -> [u32; 3] {
    t.sort_unstable();
    t
}

/// Open-addressing table of `u32` ids with linear probing; the keys live in the caller's
/// array (compared through a closure). Sized once to a power of two ≥ 2× the most entries
/// it will hold, so it is at most half full and probe runs stay short.
struct Table {
    slots: Vec<u32>,
    mask: usize,
}

impl Table {
    fn new(entries: usize) -> Self {
        let size = (table_bytes(entries as u64) / 4) as usize;
        Table { slots: vec![NONE; size], mask: size - 1 }
    }

    /// The id whose key equals the one hashed to `h` (`same` decides), else inserts `id` and
    /// returns `None`. Always ends: the table is never full.
    #[inline]
    fn find_or_insert(&mut self, h: u64, id: u32, same: impl Fn(u32) -> bool) -> Option<u32> {
        let mut at = h as usize & self.mask;
        loop {
            match self.slots.get(at).copied() {
                Some(NONE) | None => {
                    if let Some(s) = self.slots.get_mut(at) {
                        *s = id;
                    }
                    return None;
                }
                Some(other) if same(other) => return Some(other),
                Some(_) => at = (at + 1) & self.mask,
            }
        }
    }

    /// Doubles the table when one more entry would fill it past half; `hash` gives the hash
    /// of an id already in it. Used where the final count is unknown and usually far below
    /// the bound (exact duplicates: an STL's corners are ~6 copies of each vertex).
    fn reserve_one(&mut self, entries: usize, hash: impl Fn(u32) -> u64) {
        if 2 * (entries + 1) <= self.slots.len() {
            return;
        }
        let size = 2 * self.slots.len();
        let old = std::mem::replace(&mut self.slots, vec![NONE; size]);
        self.mask = size - 1;
        for id in old.into_iter().filter(|&id| id != NONE) {
            let mut at = hash(id) as usize & self.mask;
            while let Some(s) = self.slots.get_mut(at) {
                if *s == NONE {
                    *s = id;
                    break;
                }
                at = (at + 1) & self.mask;
            }
        }
    }

    /// The slot holding the id `same` accepts, or the empty slot where it would go.
    #[inline]
    fn slot(&self, h: u64, same: impl Fn(u32) -> bool) -> usize {
        let mut at = h as usize & self.mask;
        loop {
            match self.slots.get(at).copied() {
                Some(NONE) | None => return at,
                Some(other) if same(other) => return at,
                Some(_) => at = (at + 1) & self.mask,
            }
        }
    }
}

/// A seed that depends on every vertex bit: keys chosen to collide under one seed change
/// the seed.
fn seed_of(vertices: &[[f32; 3]]) -> u64 {
    let mut h: u64 = 0x6a09_e667_f3bc_c909 ^ vertices.len() as u64;
    for v in vertices {
        let w = (v[0].to_bits() as u64) | ((v[1].to_bits() as u64) << 32);
        h = (h.rotate_left(23) ^ w).wrapping_mul(0x9e37_79b9_7f4a_7c15);
        h = (h.rotate_left(23) ^ v[2].to_bits() as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15);
    }
    finish(h)
}

#[inline]
fn finish(mut h: u64) -> u64 {
    h ^= h >> 29;
    h = h.wrapping_mul(0xbf58_476d_1ce4_e5b9);
    h ^= h >> 32;
    h = h.wrapping_mul(0x94d0_49bb_1331_11eb);
    h ^ (h >> 31)
}

#[inline]
fn hash3(seed: u64, k: [u32; 3]) -> u64 {
    let mut h = seed;
    for w in k {
        h = (h.rotate_left(5) ^ w as u64).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
    finish(h)
}

#[inline]
fn hash3_64(seed: u64, k: [u64; 3]) -> u64 {
    let mut h = seed;
    for w in k {
        h = (h.rotate_left(5) ^ w).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
    finish(h)
}

/// Bits of a coordinate with -0.0 folded into +0.0.
#[inline]
fn key(v: &[f32; 3]) -> [u32; 3] {
    [(v[0] + 0.0).to_bits(), (v[1] + 0.0).to_bits(), (v[2] + 0.0).to_bits()]
}

/// Keeps the first of each set of identical positions, in first-appearance order, moved
/// down in place; returns the map input index → unique index.
fn dedupe_exact(vertices: &mut Vec<[f32; 3]>, seed: u64) -> Vec<u32> {
    let n = vertices.len();
    // Sized for an STL's typical 1 unique in 6 and grown as needed: a sparse table of all
    // corners would be 12× larger than its entries and miss the caches on every lookup.
    let mut table = Table::new(n / 6);
    let mut map = Vec::with_capacity(n);
    let mut unique = 0usize;
    for i in 0..n {
        let Some(&v) = vertices.get(i) else { break };
        let p = [v[0] + 0.0, v[1] + 0.0, v[2] + 0.0];
        let k = key(&p);
        let found = {
            let vs = &*vertices;
            table.reserve_one(unique, |id| vs.get(id as usize).map_or(0, |q| hash3(seed, key(q))));
            table.find_or_insert(hash3(seed, k), unique as u32, |id| vs.get(id as usize).map(key) == Some(k))
        };
        match found {
            Some(id) => map.push(id),
            None => {
                // unique ≤ i: the slot was read already.
                if let Some(dst) = vertices.get_mut(unique) {
                    *dst = p;
                }
                map.push(unique as u32);
                unique += 1;
            }
        }
    }
    vertices.truncate(unique);
    map
}

/// Greedy weld in input order: each position joins the earliest kept position within `tol`
/// (checked in a grid of cells 4·tol wide, looking into a neighbour cell only when the
/// point is within `tol` of that side), else it is kept itself. Kept positions move down in
/// place; returns the map input index → kept index. A cell's kept points are pairwise ≥ tol
/// apart, so at most ~125 share a cell: each lookup is O(1).
fn weld(points: &mut Vec<[f32; 3]>, tol: f64, seed: u64) -> Vec<u32> {
    let cell = 4.0 * tol;
    let tol2 = tol * tol;
    let n = points.len();
    // Cell → the most recent kept point in it; `next_in_cell` chains the earlier ones.
    let mut heads = Table::new(n);
    let mut next_in_cell: Vec<u32> = Vec::with_capacity(n);
    let mut map = Vec::with_capacity(n);
    let mut kept = 0usize;
    let home = |p: &[f32; 3]| -> [u64; 3] { [0, 1, 2].map(|a| cell_key((p[a] as f64 / cell).floor())) };
    for i in 0..n {
        let Some(&p) = points.get(i) else { break };
        let pd = [p[0] as f64, p[1] as f64, p[2] as f64];
        // Cell coordinates as f64 bits: exact for any magnitude, no integer overflow.
        let mut lo = [0f64; 3];
        let mut hi = [0f64; 3];
        let mut own = [0f64; 3];
        for a in 0..3 {
            let s = pd[a] / cell;
            let f = s.floor();
            own[a] = f;
            let frac = (s - f) * cell;
            lo[a] = if frac < tol { f - 1.0 } else { f };
            hi[a] = if cell - frac < tol { f + 1.0 } else { f };
        }
        let mut best = NONE;
        {
            let ps = &*points;
            let in_cell = |id: u32, c: [u64; 3]| ps.get(id as usize).map(home) == Some(c);
            for x in dedup2(lo[0], hi[0]) {
                for y in dedup2(lo[1], hi[1]) {
                    for z in dedup2(lo[2], hi[2]) {
                        let c = [cell_key(x), cell_key(y), cell_key(z)];
                        let at = heads.slot(hash3_64(seed, c), |id| in_cell(id, c));
                        let mut r = heads.slots.get(at).copied().unwrap_or(NONE);
                        while let Some(q) = ps.get(r as usize).filter(|_| r != NONE) {
                            let d = [q[0] as f64 - pd[0], q[1] as f64 - pd[1], q[2] as f64 - pd[2]];
                            if d[0] * d[0] + d[1] * d[1] + d[2] * d[2] < tol2 && r < best {
                                best = r;
                            }
                            r = next_in_cell.get(r as usize).copied().unwrap_or(NONE);
                        }
                    }
                }
            }
        }
        if best == NONE {
            best = kept as u32;
            // kept ≤ i: the slot was read already.
            if let Some(dst) = points.get_mut(kept) {
                *dst = p;
            }
            kept += 1;
            let c = own.map(cell_key);
            let ps = &*points;
            let at = heads.slot(hash3_64(seed, c), |id| ps.get(id as usize).map(home) == Some(c));
            if let Some(s) = heads.slots.get_mut(at) {
                next_in_cell.push(*s);
                *s = best;
            }
        }
        map.push(best);
    }
    points.truncate(kept);
    map
}

#[inline]
fn cell_key(c: f64) -> u64 {
    (c + 0.0).to_bits()
}

/// `[a]` or `[a, b]` (b only when it differs), as an iterator.
#[inline]
fn dedup2(a: f64, b: f64) -> impl Iterator<Item = f64> {
    std::iter::once(a).chain((a != b).then_some(b))
}

fn zero_area(v: &[[f32; 3]], t: [u32; 3]) -> bool {
    let p = |i: u32| v.get(i as usize).map_or([0.0; 3], |q| [q[0] as f64, q[1] as f64, q[2] as f64]);
    let (a, b, c) = (p(t[0]), p(t[1]), p(t[2]));
    let sub = |x: [f64; 3], y: [f64; 3]| [x[0] - y[0], x[1] - y[1], x[2] - y[2]];
    let dot = |x: [f64; 3]| x[0] * x[0] + x[1] * x[1] + x[2] * x[2];
    let (e1, e2, e3) = (sub(b, a), sub(c, a), sub(c, b));
    let cr = [e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]];
    let longest2 = dot(e1).max(dot(e2)).max(dot(e3));
    let area2 = dot(cr).sqrt();
    // NaN (cannot happen: coordinates are finite) would also count as degenerate.
    area2.partial_cmp(&(ZERO_AREA_RATIO * longest2)) != Some(std::cmp::Ordering::Greater)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn raw(v: &[[f32; 3]], t: &[[u32; 3]]) -> RawMesh {
        RawMesh { vertices: v.to_vec(), triangles: t.to_vec() }
    }

    #[test]
    fn welds_close_vertices_but_not_far_ones() {
        let v = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.00005, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0002]];
        let r = repair(raw(&v, &[[0, 1, 2], [3, 4, 5]]), 1e-4);
        // Vertex 3 welds onto 0, 4 is 1 exactly, 5 stays (0.2 µm... 0.2e-3 mm > tol).
        assert_eq!(r.mesh.vertices.len(), 4);
        assert_eq!(r.mesh.triangles, vec![[0, 1, 2], [0, 1, 3]]);
        assert_eq!(r.duplicates_removed, 0);
    }

    #[test]
    fn welds_across_cell_borders() {
        // Points straddling a cell border (cell = 4e-4) must still weld.
        let v = [[3.99999e-4, 0.0, 0.0], [4.00001e-4, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]];
        let r = repair(raw(&v, &[[0, 2, 3], [1, 2, 3]]), 1e-4);
        assert_eq!(r.mesh.vertices.len(), 3);
        assert_eq!(r.duplicates_removed, 1);
    }

    #[test]
    fn drops_degenerate_and_duplicates_and_counts_open_edges() {
        let v = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [2.0, 0.0, 0.0], [1.0, 1.0, 0.0]];
        let t = [[0, 1, 2], [1, 0, 2], [2, 0, 1], [0, 1, 3], [0, 0, 2], [1, 4, 2]];
        let r = repair(raw(&v, &t), 1e-4);
        // [1,0,2] and [2,0,1] share the vertex set of [0,1,2]; [0,1,3] is collinear; [0,0,2] repeats.
        assert_eq!(r.duplicates_removed, 2);
        assert_eq!(r.degenerate_removed, 2);
        assert_eq!(r.mesh.triangles.len(), 2);
        assert_eq!(r.mesh.vertices.len(), 4, "vertex 3 is no longer used");
        assert_eq!(r.open_edges, 4, "two triangles sharing one edge");
    }

    #[test]
    fn odd_tolerances_do_not_hang_or_panic() {
        let v: Vec<[f32; 3]> = (0..2000).map(|i| [i as f32 * 1e30, -(i as f32) * 3e37, 1e-40 * i as f32]).collect();
        let t: Vec<[u32; 3]> = (0..1998u32).map(|i| [i, i + 1, i + 2]).collect();
        for tol in [0.0, -1.0, f64::NAN, 1e-300, 1e-4, 1e300, f64::INFINITY, f64::MAX] {
            let r = repair(raw(&v, &t), tol);
            assert!(r.mesh.triangles.iter().flatten().all(|&i| (i as usize) < r.mesh.vertices.len()));
        }
    }

    #[test]
    fn negative_zero_is_zero() {
        let v = [[0.0, 0.0, 0.0], [-0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let r = repair(raw(&v, &[[0, 2, 3], [1, 2, 3]]), 0.0);
        assert_eq!(r.mesh.vertices.len(), 3);
        assert_eq!(r.duplicates_removed, 1);
    }
}

//! Cleaning a raw triangle list: weld close vertices, drop degenerate and duplicate
//! triangles, count open edges.
//!
//! Deterministic: vertices keep the order of their first appearance and triangles the file
//! order; hash maps are used only for lookups, never iterated.

use super::{FxHashMap, FxHashSet, RawMesh};
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

/// Cleans `raw`. `tolerance_mm` ≤ 0 (or NaN, or below 1 nm) welds only identical positions.
pub(super) fn repair(raw: RawMesh, tolerance_mm: f64) -> Repaired {
    let RawMesh { vertices, triangles } = raw;
    // 1. Identical positions → one vertex (first appearance order).
    let (unique, exact_map) = dedupe_exact(&vertices);
    drop(vertices);
    // 2. Weld positions closer than the tolerance.
    let (welded, weld_map) = if tolerance_mm.is_finite() && tolerance_mm >= 1e-6 {
        weld(&unique, tolerance_mm)
    } else if tolerance_mm == f64::INFINITY {
        (unique.first().copied().into_iter().collect(), vec![0; unique.len()])
    } else {
        let ids = (0..unique.len() as u32).collect();
        (unique, ids)
    };
    let map = |i: u32| -> u32 {
        exact_map.get(i as usize).and_then(|&u| weld_map.get(u as usize)).copied().unwrap_or(NONE)
    };

    // 3. Degenerate and duplicate triangles.
    let mut kept: Vec<[u32; 3]> = Vec::with_capacity(triangles.len());
    let mut seen: FxHashSet<[u32; 3]> = FxHashSet::default();
    seen.reserve(triangles.len());
    let (mut degenerate_removed, mut duplicates_removed) = (0, 0);
    for t in &triangles {
        let t = [map(t[0]), map(t[1]), map(t[2])];
        if t.contains(&NONE) || t[0] == t[1] || t[1] == t[2] || t[0] == t[2] || zero_area(&welded, t) {
            degenerate_removed += 1;
            continue;
        }
        let mut key = t;
        key.sort_unstable();
        if !seen.insert(key) {
            duplicates_removed += 1;
            continue;
        }
        kept.push(t);
    }
    drop(seen);
    drop(triangles);

    // 4. Keep referenced vertices only, in welded order.
    let mut new_id = vec![NONE; welded.len()];
    for t in &kept {
        for &i in t {
            if let Some(slot) = new_id.get_mut(i as usize) {
                *slot = 0;
            }
        }
    }
    let mut out_vertices = Vec::new();
    for (slot, v) in new_id.iter_mut().zip(&welded) {
        if *slot == 0 {
            *slot = out_vertices.len() as u32;
            out_vertices.push(*v);
        }
    }
    for t in &mut kept {
        for i in t.iter_mut() {
            *i = new_id.get(*i as usize).copied().unwrap_or(0);
        }
    }

    // 5. Open edges: undirected edges used by exactly one triangle.
    let mut edges: Vec<u64> = Vec::with_capacity(kept.len().saturating_mul(3));
    for t in &kept {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            let (lo, hi) = if a < b { (a, b) } else { (b, a) };
            edges.push(((lo as u64) << 32) | hi as u64);
        }
    }
    edges.sort_unstable();
    let open_edges = edges.chunk_by(|a, b| a == b).filter(|run| run.len() == 1).count();

    Repaired {
        mesh: Mesh { vertices: out_vertices, triangles: kept },
        degenerate_removed,
        duplicates_removed,
        open_edges,
    }
}

/// Bits of a coordinate with -0.0 folded into +0.0.
#[inline]
fn key(v: &[f32; 3]) -> [u32; 3] {
    [(v[0] + 0.0).to_bits(), (v[1] + 0.0).to_bits(), (v[2] + 0.0).to_bits()]
}

/// Unique positions in first-appearance order, and the map input index → unique index.
fn dedupe_exact(vertices: &[[f32; 3]]) -> (Vec<[f32; 3]>, Vec<u32>) {
    let mut index: FxHashMap<[u32; 3], u32> = FxHashMap::default();
    index.reserve(vertices.len() / 2 + 1);
    let mut unique = Vec::with_capacity(vertices.len() / 2 + 1);
    let mut map = Vec::with_capacity(vertices.len());
    for v in vertices {
        let next = unique.len() as u32;
        let id = *index.entry(key(v)).or_insert(next);
        if id == next {
            unique.push([v[0] + 0.0, v[1] + 0.0, v[2] + 0.0]);
        }
        map.push(id);
    }
    (unique, map)
}

/// Greedy weld in input order: each position joins the earliest kept position within `tol`
/// (checked in a grid of cells 4·tol wide, looking into a neighbour cell only when the
/// point is within `tol` of that side), else it is kept itself.
fn weld(points: &[[f32; 3]], tol: f64) -> (Vec<[f32; 3]>, Vec<u32>) {
    let cell = 4.0 * tol;
    let tol2 = tol * tol;
    let mut heads: FxHashMap<[u64; 3], u32> = FxHashMap::default();
    heads.reserve(points.len());
    let mut next_in_cell: Vec<u32> = Vec::with_capacity(points.len());
    let mut kept: Vec<[f32; 3]> = Vec::with_capacity(points.len());
    let mut map = Vec::with_capacity(points.len());
    for p in points {
        let pd = [p[0] as f64, p[1] as f64, p[2] as f64];
        // Cell coordinates as f64 bits: exact for any magnitude, no integer overflow.
        let mut lo = [0f64; 3];
        let mut hi = [0f64; 3];
        let mut home = [0f64; 3];
        for a in 0..3 {
            let s = pd[a] / cell;
            let f = s.floor();
            home[a] = f;
            let frac = (s - f) * cell;
            lo[a] = if frac < tol { f - 1.0 } else { f };
            hi[a] = if cell - frac < tol { f + 1.0 } else { f };
        }
        let mut best = NONE;
        for x in dedup2(lo[0], hi[0]) {
            for y in dedup2(lo[1], hi[1]) {
                for z in dedup2(lo[2], hi[2]) {
                    let mut r = heads.get(&cell_key([x, y, z])).copied().unwrap_or(NONE);
                    while let Some(q) = kept.get(r as usize) {
                        let d = [q[0] as f64 - pd[0], q[1] as f64 - pd[1], q[2] as f64 - pd[2]];
                        if d[0] * d[0] + d[1] * d[1] + d[2] * d[2] < tol2 && r < best {
                            best = r;
                        }
                        r = next_in_cell.get(r as usize).copied().unwrap_or(NONE);
                    }
                }
            }
        }
        if best == NONE {
            best = kept.len() as u32;
            kept.push(*p);
            let slot = heads.entry(cell_key(home)).or_insert(NONE);
            next_in_cell.push(*slot);
            *slot = best;
        }
        map.push(best);
    }
    (kept, map)
}

#[inline]
fn cell_key(c: [f64; 3]) -> [u64; 3] {
    [(c[0] + 0.0).to_bits(), (c[1] + 0.0).to_bits(), (c[2] + 0.0).to_bits()]
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

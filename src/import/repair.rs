//! Cleaning a raw triangle list: weld close vertices, drop degenerate and duplicate
//! triangles, count open edges.
//!
//! Deterministic: vertices keep the order of their first appearance and triangles the file
//! order; hash tables are used only for lookups, never iterated. Each step's result is a
//! function of the items alone (the first item of each key, a flag, a count), so it is the
//! same bytes however the work is split over threads.
//!
//! Linear and on every core. One table over millions of keys missed the caches on nearly
//! every lookup, the more the larger the mesh (4× the triangles took 6–7× the time), so no
//! step looks anything up across the whole input in one table: identical vertices are found
//! per chunk of the file in a table that fits a core's cache (mesh files list a vertex's
//! copies close together: corners of neighbouring triangles), then the chunks' firsts across
//! the file through hash partitioning (keys spread over buckets that each fit a cache, the
//! buckets worked on side by side: [`super::buckets`]); close vertices through partitioning
//! a grid's cells; repeated triangles and open edges by grouping them under their lowest
//! vertex (counting, no table). The greedy weld, where each choice depends on the earlier
//! ones, still runs in input order, but only over the vertices that have another within
//! reach (usually none).
//!
//! Bounded: the arrays are a fixed number of bytes per item and the tables are sized once
//! per bucket, so the memory high-water mark stays under [`extra_peak`] whatever the
//! geometry. The hash is seeded from the vertex data itself, so a file cannot be crafted to
//! make its keys collide (which would make the lookups scan a table: quadratic).

use super::buckets::{bucket_count, bucket_of, each_bucket, map_chunks, map_chunks_with, partition, Chunked, Words, CHUNK};
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

/// A raw triangle list as the cleaner reads it: parsed into a [`RawMesh`], or read in place
/// (a binary STL's records). Every index is in range and every coordinate finite.
pub(super) trait Soup: Sync {
    /// Whether the raw arrays are held in memory (the estimate counts 24 bytes a triangle for
    /// them either way: a soup read in place leaves them free for the cleaner).
    const HELD: bool = true;
    /// Vertices read.
    fn vertex_count(&self) -> usize;
    /// Vertex `i` (`i` < `vertex_count()`).
    fn vertex(&self, i: usize) -> [f32; 3];
    /// Triangles read.
    fn triangle_count(&self) -> usize;
    /// The corners of the triangles, through the map vertex → first identical vertex made by
    /// [`dedupe_exact`]; the vertices are not read again.
    fn into_corners(self, map: Words) -> Corners;
}

impl Soup for RawMesh {
    fn vertex_count(&self) -> usize {
        self.vertices.len()
    }

    fn vertex(&self, i: usize) -> [f32; 3] {
        self.vertices.get(i).copied().unwrap_or_default()
    }

    fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    fn into_corners(self, map: Words) -> Corners {
        // In place, so the map and the raw vertices are freed before the weld.
        let RawMesh { vertices, mut triangles } = self;
        drop(vertices);
        for t in triangles.iter_mut() {
            *t = t.map(|i| map.get(i as usize));
        }
        Corners::Triangles(triangles)
    }
}

/// Triangles as indices of the identical-vertex-free vertices: an array, or (a binary STL,
/// whose triangle `i` is read's vertices `3i`, `3i + 1`, `3i + 2`) the map itself.
pub(super) enum Corners {
    Triangles(Vec<[u32; 3]>),
    Map(Words),
}

impl Corners {
    #[inline]
    fn get(&self, i: usize) -> [u32; 3] {
        match self {
            Corners::Triangles(t) => t.get(i).copied().unwrap_or([NONE; 3]),
            Corners::Map(m) => [m.get(3 * i), m.get(3 * i + 1), m.get(3 * i + 2)],
        }
    }
}

const NONE: u32 = u32::MAX;

/// Twice the area below this fraction of the longest edge squared counts as zero area.
const ZERO_AREA_RATIO: f64 = 1e-12;

/// Bytes of a [`Table`] for `n` entries.
fn table_bytes(n: u64) -> u64 {
    4 * n.saturating_mul(2).max(16).next_power_of_two()
}

/// Upper bound of the bytes [`repair`] allocates beyond the raw mesh it is given (`v`
/// vertices, `t` triangles, 12 bytes each). The bound of the previous, one-table cleaner,
/// kept so estimates and budgets do not change; every step stays under it (a binary STL's
/// raw mesh is never made, which leaves its 24 bytes a triangle free; the raw vertices of
/// the others are freed after step 1): identical vertices (map 4 B and records 8 B a vertex,
/// then the positions kept), weld (records at most 16 B a vertex, or the greedy weld's
/// chain, map and table over all), triangles (marked copy 12 B, records 8 B a triangle),
/// compaction (id map), open edges (records 8 B an edge; in two halves when the raw mesh
/// was held).
pub(super) fn extra_peak(v: u64, t: u64) -> u64 {
    // The old dedupe table started small and doubled: at most the full size plus the half.
    let dedupe = 4 * v + table_bytes(v) + table_bytes(v) / 2;
    let weld = 8 * v + table_bytes(v);
    let tris = table_bytes(t);
    let compact = 12 * v.max(t);
    let edges = 24 * t;
    dedupe.max(weld).max(tris).max(compact).max(edges)
}

/// Cleans `raw`. `tolerance_mm` ≤ 0 (or NaN, or below 1 nm) welds only identical positions.
pub(super) fn repair<S: Soup>(raw: S, tolerance_mm: f64) -> Repaired {
    let seed = seed_of(&raw);
    // 1. Identical positions → one vertex (first appearance order).
    let (mut vertices, map) = dedupe_exact(&raw, seed);
    let triangles = raw.triangle_count();
    let corners = raw.into_corners(map);
    // 2. Weld positions closer than the tolerance.
    let welded = if tolerance_mm.is_finite() && tolerance_mm >= 1e-6 {
        weld(&mut vertices, tolerance_mm, seed)
    } else if tolerance_mm == f64::INFINITY {
        let map = vec![0u32; vertices.len()];
        vertices.truncate(1);
        Some(map)
    } else {
        None
    };
    // 3. Degenerate and duplicate triangles dropped, the kept ones in file order.
    let (triangles, degenerate_removed, duplicates_removed) = {
        let marked = remap_and_mark(triangles, corners, welded.as_deref(), &vertices);
        drop(welded);
        drop_duplicates(marked, vertices.len())
    };
    // 4. Keep referenced vertices only, in welded order.
    let (vertices, triangles) = drop_unused(vertices, triangles);
    // 5. Open edges: undirected edges used by exactly one triangle.
    let open_edges = open_edges(&triangles, vertices.len(), if S::HELD { 2 } else { 1 });
    Repaired { mesh: Mesh { vertices, triangles }, degenerate_removed, duplicates_removed, open_edges }
}

/// A seed that depends on every vertex bit and its place: keys chosen to collide under one
/// seed change the seed. A sum of independent mixes (so the loop does not wait on itself),
/// over chunks on every core.
fn seed_of(raw: &impl Soup) -> u64 {
    let parts = map_chunks(raw.vertex_count(), |range| {
        range.fold(0u64, |h, i| {
            let v = raw.vertex(i);
            let w = (v[0].to_bits() as u64) | ((v[1].to_bits() as u64) << 32);
            let x = w.wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ (v[2].to_bits() as u64 | (i as u64) << 32);
            h.wrapping_add(finish(x))
        })
    });
    let h = parts.iter().fold(0x6a09_e667_f3bc_c909 ^ raw.vertex_count() as u64, |h, &p| h.wrapping_add(p));
    finish(h)
}

/// The first of each set of identical positions (-0.0 folded into +0.0), in first-appearance
/// order, and the map vertex → its index among them.
///
/// In two levels, for the order of mesh files (a vertex's copies are corners of neighbouring
/// triangles, near each other in the file): each chunk finds its own firsts in a table that
/// fits a core's cache, on every core, and only those (about one corner in five of an STL)
/// are looked up across the file ([`first_of_each`]). A file whose chunks find few repeats
/// is looked up in one level.
fn dedupe_exact(raw: &impl Soup, seed: u64) -> (Vec<[f32; 3]>, Words) {
    let n = raw.vertex_count();
    // Per chunk: each vertex's first's ordinal among the chunk's firsts, and the firsts.
    let local = map_chunks_with(n, |range, (table, keys): &mut (Table, Vec<[u32; 3]>)| {
        keys.clear();
        keys.extend(range.clone().map(|i| key(&raw.vertex(i))));
        table.reset(keys.len());
        let mut ord: Vec<u32> = Vec::with_capacity(keys.len());
        let mut firsts: Vec<u32> = Vec::new();
        for (j, k) in keys.iter().enumerate() {
            let o = match table.find_or_insert(hash3(seed, *k), j as u32, |id| keys.get(id as usize) == Some(k)) {
                Some(f) => ord.get(f as usize).copied().unwrap_or(NONE),
                None => {
                    firsts.push((range.start + j) as u32);
                    (firsts.len() - 1) as u32
                }
            };
            ord.push(o);
        }
        (ord, firsts)
    });
    let m: usize = local.iter().map(|(_, f)| f.len()).sum();
    if 2 * m > n {
        drop(local);
        return dedupe_in_one_level(raw, seed);
    }
    let mut starts = Vec::with_capacity(local.len());
    let mut firsts: Vec<u32> = Vec::with_capacity(m);
    let mut ords = Vec::with_capacity(local.len());
    for (ord, f) in local {
        starts.push(firsts.len());
        firsts.extend_from_slice(&f);
        ords.push(ord);
    }
    let vertex = |j: usize| raw.vertex(firsts.get(j).copied().unwrap_or(NONE) as usize);
    let global = first_of_each(m, |j| Some(key(&vertex(j))), |k| hash3(seed, *k));
    let (vertices, index) = number_firsts(global, m, vertex);
    // Each vertex's ordinal becomes its index, in place.
    let map = Words::from_parts(ords);
    map_chunks(n, |range| {
        let start = starts.get(range.start / CHUNK).copied().unwrap_or(usize::MAX);
        for i in range {
            map.set(i, index.get(start.saturating_add(map.get(i) as usize)));
        }
    });
    (vertices, map)
}

/// [`dedupe_exact`] in one level: every vertex looked up across the file.
fn dedupe_in_one_level(raw: &impl Soup, seed: u64) -> (Vec<[f32; 3]>, Words) {
    let n = raw.vertex_count();
    let first = first_of_each(n, |i| Some(key(&raw.vertex(i))), |k| hash3(seed, *k));
    number_firsts(first, n, |i| raw.vertex(i))
}

/// The positions (-0.0 folded) of the items that are their own first in `first` (items
/// `0..n`), in order, and each item's index among them (its first's), in place of `first`.
/// In chunks on every core: the firsts are numbered from each chunk's count (marked by the
/// top bit), then every item takes its first's number.
fn number_firsts(first: Words, n: usize, vertex: impl Fn(usize) -> [f32; 3] + Sync) -> (Vec<[f32; 3]>, Words) {
    const MARK: u32 = 1 << 31;
    let is_first = |i: usize| first.get(i) as usize == i;
    let counts = map_chunks(n, |range| range.filter(|&i| is_first(i)).count());
    let mut starts = Vec::with_capacity(counts.len());
    let mut unique = 0usize;
    for c in counts {
        starts.push(unique);
        unique += c;
    }
    if n >= MARK as usize {
        // Numbers would not leave the mark free (beyond any file weft reads): one by one.
        let mut vertices = Vec::with_capacity(unique);
        for i in 0..n {
            let f = first.get(i) as usize;
            if f == i {
                let v = vertex(i);
                first.set(i, vertices.len() as u32);
                vertices.push([v[0] + 0.0, v[1] + 0.0, v[2] + 0.0]);
            } else {
                first.set(i, first.get(f));
            }
        }
        return (vertices, first);
    }
    let parts = map_chunks(n, |range| {
        let from = starts.get(range.start / CHUNK).copied().unwrap_or(0) as u32;
        let mut positions = Vec::new();
        for (k, i) in (from..).zip(range.filter(|&i| is_first(i))) {
            first.set(i, k | MARK);
            let v = vertex(i);
            positions.push([v[0] + 0.0, v[1] + 0.0, v[2] + 0.0]);
        }
        positions
    });
    // A marked word is a first's number; any other is a repeat's first, whose word is its
    // number, marked or (unmarked by its own chunk) not: the same number either way.
    map_chunks(n, |range| {
        for i in range {
            let f = first.get(i);
            let number = if f & MARK != 0 { f } else { first.get(f as usize) };
            first.set(i, number & !MARK);
        }
    });
    let mut vertices = Vec::with_capacity(unique);
    for part in parts {
        vertices.extend_from_slice(&part);
    }
    (vertices, first)
}

/// Welds `points` as [`greedy_weld`] does, moving kept points down in place; returns the map
/// point → kept index, or `None` when the close-point search shows nothing is welded.
///
/// A point with no other point within `tol` is kept by the greedy weld and never chosen by
/// another, so the greedy weld runs only over the points [`close_points`] finds (a superset
/// of those with a neighbour within `tol`), in input order, and the rest are kept. When those
/// are many (dense or hostile input), or their search would need too much memory, it runs
/// over all, as before.
fn weld(points: &mut Vec<[f32; 3]>, tol: f64, seed: u64) -> Option<Vec<u32>> {
    let n = points.len();
    let close = match close_points(points, tol, seed) {
        Some(c) if c.len() <= n / 4 => c,
        _ => return Some(greedy_weld(points, tol, seed)),
    };
    if close.is_empty() {
        return None;
    }
    let mut some: Vec<[f32; 3]> = close.iter().filter_map(|&i| points.get(i as usize).copied()).collect();
    let some_map = greedy_weld(&mut some, tol, seed);
    drop(some);
    if some_map.iter().enumerate().all(|(k, &m)| m as usize == k) {
        // Close but none within tol (a fine fan's tip): all kept.
        return None;
    }
    // All points in order: a close one the greedy weld joined to an earlier one takes that
    // one's index; every other point is kept.
    let mut map = Vec::with_capacity(n);
    let mut kept_close: Vec<u32> = Vec::new();
    let mut next = close.iter().zip(&some_map).peekable();
    let mut kept = 0usize;
    for i in 0..n {
        let joined = match next.peek() {
            Some(&(&c, &m)) if c as usize == i => {
                next.next();
                let joined = kept_close.get(m as usize).copied();
                if joined.is_none() {
                    kept_close.push(kept as u32);
                }
                joined
            }
            _ => None,
        };
        if let Some(id) = joined {
            map.push(id);
            continue;
        }
        // kept ≤ i: the slot was read already.
        if let Some(&p) = points.get(i) {
            if let Some(dst) = points.get_mut(kept) {
                *dst = p;
            }
        }
        map.push(kept as u32);
        kept += 1;
    }
    points.truncate(kept);
    Some(map)
}

/// A bucket's scratch in [`close_points`]: its table, each cell's (hash, some point's own,
/// records), and each record's cell.
type CellScratch = (Table, Vec<(u32, bool, u32)>, Vec<u32>);

/// Cells of the close-point search are this many tolerances wide: not a power of two or
/// ten, so the round coordinates of CAD exports do not all fall on cell borders.
const CLOSE_CELL: f64 = 27.0;

/// The points (in order) that may have another point within `tol`: every point that has
/// one, and some more (a superset is all [`weld`] needs). `None` when the search would need
/// more than 16 bytes a point (points built to sit on cell corners) or the points cannot be
/// numbered in 31 bits.
///
/// A grid of cells 27·tol wide, shifted half a cell: a point is recorded in its own cell and,
/// per axis, in the neighbour cell it is within 2·tol of (so rounding cannot hide a point
/// within tol, whose cell is within tol of it): about 1.5 records a point. A cell that is a
/// point's own and holds another record makes all of them close. A record is the cell as 32
/// bits of its hash, which also picks its bucket, beside the point (two cells sharing a hash
/// only make more points close); each bucket is counted on its own, on every core, reading
/// nothing but its records.
fn close_points(points: &[[f32; 3]], tol: f64, seed: u64) -> Option<Vec<u32>> {
    let n = points.len();
    if n >= 1 << 31 {
        return None;
    }
    const OWN: u64 = 1 << 31;
    let (scale, reach) = (1.0 / (CLOSE_CELL * tol), 2.0 / CLOSE_CELL);
    // Per axis: the cell, and the neighbour cell within reach (the cell itself if none), as
    // whole numbers (saturating far out, where no two coordinates are within tol unless
    // equal: one cell there, still right). The floor by a cast, not a libm call.
    let cells = move |p: &[f32; 3]| -> [[i64; 2]; 3] {
        [0, 1, 2].map(|a| {
            let s = p[a] as f64 * scale + 0.5;
            let t = s as i64;
            let f = t.saturating_sub(i64::from(t as f64 > s));
            let frac = s - f as f64;
            let other = if frac < reach {
                f.saturating_sub(1)
            } else if 1.0 - frac < reach {
                f.saturating_add(1)
            } else {
                f
            };
            [f, other]
        })
    };
    let buckets = bucket_count(n + n / 2);
    let parts = partition::<8, _>(n, buckets, 2 * n, |i, out| {
        let Some(p) = points.get(i) else { return 0 };
        let c = cells(p);
        let count = |a: usize| if c[a][0] == c[a][1] { 1 } else { 2 };
        let mut k = 0;
        for x in 0..count(0) {
            for y in 0..count(1) {
                for z in 0..count(2) {
                    let cell = [c[0][x], c[1][y], c[2][z]];
                    let h = hash3_64(seed, cell.map(|w| w as u64));
                    let own = if x + y + z == 0 { OWN } else { 0 };
                    if let Some(slot) = out.get_mut(k) {
                        *slot = (bucket_of(h, buckets), (h << 32) | own | i as u64);
                        k += 1;
                    }
                }
            }
        }
        k
    })?;
    // Per bucket: each cell's hash, whether it is some point's own, and its records; then
    // the points of the cells that are both.
    let flagged = each_bucket(&parts, |records, (table, cells, cell_of): &mut CellScratch| {
        table.reset(records.len());
        cells.clear();
        cell_of.clear();
        for &r in records {
            let h = r >> 32;
            let at = table.slot(h, |id| cells.get(id as usize).is_some_and(|c| c.0 as u64 == h));
            let id = match table.slots.get(at).copied() {
                Some(NONE) | None => {
                    if let Some(s) = table.slots.get_mut(at) {
                        *s = cells.len() as u32;
                    }
                    cells.push((h as u32, false, 0));
                    cells.len() - 1
                }
                Some(id) => id as usize,
            };
            cell_of.push(id as u32);
            if let Some(c) = cells.get_mut(id) {
                c.1 |= r & OWN != 0;
                c.2 += 1;
            }
        }
        let busy = |id: u32| cells.get(id as usize).is_some_and(|c| c.1 && c.2 >= 2);
        records.iter().zip(cell_of.iter()).filter(|(_, &id)| busy(id)).map(|(&r, _)| r as u32 & !(OWN as u32)).collect::<Vec<u32>>()
    });
    drop(parts);
    let mut close: Vec<u32> = flagged.into_iter().flatten().collect();
    close.sort_unstable();
    close.dedup();
    Some(close)
}

/// The triangles through `weld` (when some vertices were welded), each degenerate one (a
/// corner out of range, repeated corners, zero area) as `[NONE; 3]`. On every core.
fn remap_and_mark(n: usize, corners: Corners, weld: Option<&[u32]>, vertices: &[[f32; 3]]) -> Chunked<[u32; 3]> {
    let at = |i: u32| match weld {
        Some(w) => w.get(i as usize).copied().unwrap_or(NONE),
        None => i,
    };
    Chunked::new(n, |range| {
        range
            .map(|k| {
                let t = corners.get(k).map(at);
                let degenerate = t.contains(&NONE) || t[0] == t[1] || t[1] == t[2] || t[0] == t[2] || zero_area(vertices, t);
                if degenerate {
                    [NONE; 3]
                } else {
                    t
                }
            })
            .collect()
    })
}

/// The triangles `marked` keeps (not degenerate, not the repeat of an earlier one with the
/// same corners in any order), in order; and how many were degenerate and repeated.
/// Triangles are grouped by their lowest corner ([`by_vertex`]): a repeat is in its
/// original's group.
fn drop_duplicates(marked: Chunked<[u32; 3]>, vertices: usize) -> (Vec<[u32; 3]>, usize, usize) {
    let n = marked.len();
    let corners = |i: u32| marked.get(i as usize).map_or([NONE; 3], |&t| sorted(t));
    let parts = by_vertex::<1, Vec<u32>, _, _>(
        n,
        vertices,
        1,
        |i, out| match marked.get(i) {
            Some(t) if t[0] != NONE => {
                out[0] = (sorted(*t)[0], i as u32);
                1
            }
            _ => 0,
        },
        |group, repeats| {
            if group.len() <= 16 {
                for (q, &i) in group.iter().enumerate() {
                    let c = corners(i);
                    if group.iter().take(q).any(|&e| corners(e) == c) {
                        repeats.push(i);
                    }
                }
            } else {
                // Each set of equal corners in triangle order: all but the first repeat.
                let mut keyed: Vec<([u32; 3], u32)> = group.iter().map(|&i| (corners(i), i)).collect();
                keyed.sort_unstable();
                for same in keyed.chunk_by(|a, b| a.0 == b.0) {
                    repeats.extend(same.iter().skip(1).map(|&(_, i)| i));
                }
            }
        },
    );
    let mut repeats: Vec<u32> = parts.into_iter().flatten().collect();
    repeats.sort_unstable();
    // Each chunk's kept triangles (on every core), then joined.
    let parts = map_chunks(n, |range| {
        let from = repeats.partition_point(|&r| (r as usize) < range.start);
        let mut next = repeats.get(from..).unwrap_or_default().iter().peekable();
        let (mut kept, mut degenerate) = (Vec::with_capacity(range.len()), 0usize);
        for i in range {
            if next.peek().is_some_and(|&&r| r as usize == i) {
                next.next();
                continue;
            }
            match marked.get(i) {
                Some(&t) if t[0] != NONE => kept.push(t),
                _ => degenerate += 1,
            }
        }
        (kept, degenerate)
    });
    // Freed before the kept ones are joined: two copies of the triangles at most.
    drop(marked);
    let degenerate = parts.iter().map(|p| p.1).sum();
    let mut kept = Vec::with_capacity(parts.iter().map(|p| p.0.len()).sum());
    for (part, _) in parts {
        kept.extend_from_slice(&part);
    }
    (kept, degenerate, repeats.len())
}

/// Items grouped by a vertex, without a hash table: `emit(i, out)` writes item `i`'s
/// (vertex, value) pairs to `out` and returns how many (at most `K`); `f(values, acc)` reads
/// each vertex's values (in item order; `f` may reorder them) into `acc`. The pairs go to
/// buckets by vertex range ([`partition`]; in mesh files nearby items use nearby vertices,
/// so its writes stay near each other), and each bucket is grouped by counting, on every
/// core; in `phases`, each holding a share of the buckets (less memory, more passes). The
/// buckets' accumulators in order.
fn by_vertex<const K: usize, A, E, F>(n: usize, vertices: usize, phases: usize, emit: E, f: F) -> Vec<A>
where
    A: Default + Send,
    E: Fn(usize, &mut [(u32, u32); K]) -> usize + Sync,
    F: Fn(&mut [u32], &mut A) + Sync,
{
    let buckets = bucket_count(n.saturating_mul(K)).min(vertices.max(1).next_power_of_two());
    // Bucket = the top bits of the vertex (below 2^bits).
    let bits = usize::BITS - vertices.saturating_sub(1).leading_zeros();
    let shift = bits.saturating_sub(buckets.trailing_zeros());
    // In phases of a share of the buckets each (each emits every pair, keeps its own).
    let phases = phases.clamp(1, buckets);
    let mut accs = Vec::with_capacity(buckets);
    for phase in 0..phases {
        let keep = phase * buckets / phases..(phase + 1) * buckets / phases;
        let parts = partition::<K, _>(n, keep.len(), usize::MAX, |i, out| {
            let mut pairs = [(0, 0); K];
            let k = emit(i, &mut pairs);
            let mut kept = 0;
            for &(v, value) in pairs.iter().take(k) {
                let b = (v >> shift) as usize;
                if let (true, Some(slot)) = (keep.contains(&b), out.get_mut(kept)) {
                    *slot = (b - keep.start, (v as u64) << 32 | value as u64);
                    kept += 1;
                }
            }
            kept
        });
        if let Some(parts) = parts {
            accs.extend(group_by_vertex(&parts, &f));
        }
    }
    accs
}

/// [`by_vertex`]'s grouping of each bucket (its records' vertices span less than a bucket's
/// range): counted, placed, and each group handed to `f`.
fn group_by_vertex<A, F>(parts: &super::buckets::Buckets, f: &F) -> Vec<A>
where
    A: Default + Send,
    F: Fn(&mut [u32], &mut A) + Sync,
{
    each_bucket(parts, |records, (offsets, values): &mut (Vec<u32>, Vec<u32>)| {
        let mut acc = A::default();
        let Some(base) = records.iter().map(|&r| r >> 32).min() else { return acc };
        let span = records.iter().map(|&r| r >> 32).max().unwrap_or(base) - base + 1;
        offsets.clear();
        offsets.resize(span as usize + 1, 0);
        for &r in records {
            if let Some(c) = offsets.get_mut(((r >> 32) - base) as usize + 1) {
                *c += 1;
            }
        }
        for g in 1..offsets.len() {
            let before = offsets.get(g - 1).copied().unwrap_or(0);
            if let Some(o) = offsets.get_mut(g) {
                *o += before;
            }
        }
        values.clear();
        values.resize(records.len(), 0);
        // Placed from the end, so each group keeps item order and its offset ends at its start.
        for &r in records.iter().rev() {
            if let Some(at) = offsets.get_mut(((r >> 32) - base) as usize + 1) {
                *at -= 1;
                if let Some(slot) = values.get_mut(*at as usize) {
                    *slot = r as u32;
                }
            }
        }
        for g in 1..offsets.len() {
            let (lo, hi) = (offsets.get(g).copied().unwrap_or(0), offsets.get(g + 1).copied().unwrap_or(records.len() as u32));
            if let Some(group) = values.get_mut(lo as usize..hi as usize).filter(|g| !g.is_empty()) {
                f(group, &mut acc);
            }
        }
        acc
    })
}

/// The vertices some triangle uses, in order, and the triangles renumbered to them.
fn drop_unused(mut vertices: Vec<[f32; 3]>, mut triangles: Vec<[u32; 3]>) -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
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
    if used < new_id.len() {
        for t in triangles.iter_mut() {
            for i in t.iter_mut() {
                *i = new_id.get(*i as usize).copied().unwrap_or(NONE);
            }
        }
    }
    drop(new_id);
    // The mesh lives on through slicing: give back what the arrays over-hold.
    vertices.shrink_to_fit();
    triangles.shrink_to_fit();
    (vertices, triangles)
}

/// For every item `0..n`, the first item with the same key (itself when it is the first, or
/// when `key` gives `None`: not looked up). 12 bytes an item at the peak.
///
/// The items go to buckets by the top bits of `hash(key)`, each as 8 bytes: 32 more bits of
/// the hash beside the item. A bucket finds the first item of each hash in its own small
/// table, reading nothing but its records (no keys scattered over the whole input), on every
/// core. A pass in item order then checks each item's key against its first's (near it in
/// most files); only the items of a hash shared by different keys (rare: 42 bits) fail, all
/// of a key together, and are looked up again by key.
fn first_of_each<K, F, H>(n: usize, key: F, hash: H) -> Words
where
    K: Ord,
    F: Fn(usize) -> Option<K> + Sync,
    H: Fn(&K) -> u64 + Sync,
{
    let buckets = bucket_count(n);
    let first = Words::new(n, |i| i as u32);
    if let Some(parts) = partition::<1, _>(n, buckets, usize::MAX, |i, out| match key(i) {
        Some(k) => {
            let h = hash(&k);
            out[0] = (bucket_of(h, buckets), (h << 32) | i as u32 as u64);
            1
        }
        None => 0,
    }) {
        each_bucket(&parts, |records, table: &mut Table| {
            table.reset(records.len());
            for (j, &r) in records.iter().enumerate() {
                let found = table.find_or_insert(r >> 32, j as u32, |id| records.get(id as usize).is_some_and(|&q| q >> 32 == r >> 32));
                if let Some(&f) = found.and_then(|f| records.get(f as usize)) {
                    // Each item is in one bucket: one writer per word.
                    first.set(r as u32 as usize, f as u32);
                }
            }
        });
    }
    // The first of an item's hash is its key's first exactly when their keys agree.
    let wrong: Vec<Vec<u32>> = map_chunks(n, |range| {
        range
            .filter(|&i| {
                let f = first.get(i) as usize;
                f != i && key(f) != key(i)
            })
            .map(|i| i as u32)
            .collect()
    });
    let mut firsts = std::collections::BTreeMap::new();
    for i in wrong.into_iter().flatten() {
        if let Some(k) = key(i as usize) {
            first.set(i as usize, *firsts.entry(k).or_insert(i));
        }
    }
    first
}

/// Undirected edges used by exactly one triangle: the edges grouped by their lower end
/// ([`by_vertex`], in `phases`: 8 bytes an edge at once in one, 12 bytes a triangle in two),
/// each group's upper ends counted.
fn open_edges(triangles: &[[u32; 3]], vertices: usize, phases: usize) -> usize {
    let parts = by_vertex::<3, usize, _, _>(
        triangles.len(),
        vertices,
        phases,
        |i, out| {
            let t = triangles.get(i).copied().unwrap_or([NONE; 3]);
            for (k, slot) in out.iter_mut().enumerate() {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                *slot = if a < b { (a, b) } else { (b, a) };
            }
            3
        },
        |uppers, singles| {
            if uppers.len() <= 16 {
                *singles += uppers.iter().filter(|&&u| uppers.iter().filter(|&&w| w == u).count() == 1).count();
            } else {
                uppers.sort_unstable();
                *singles += uppers.chunk_by(|a, b| a == b).filter(|run| run.len() == 1).count();
            }
        },
    );
    parts.iter().sum()
}

fn sorted(mut t: [u32; 3]) -> [u32; 3] {
    t.sort_unstable();
    t
}

/// Open-addressing table of `u32` ids with linear probing; the keys live in the caller's
/// array (compared through a closure). Sized once to a power of two ≥ 2× the most entries
/// it will hold, so it is at most half full and probe runs stay short.
#[derive(Default)]
struct Table {
    slots: Vec<u32>,
    mask: usize,
}

impl Table {
    fn new(entries: usize) -> Self {
        let mut table = Table::default();
        table.reset(entries);
        table
    }

    /// Empties the table and sizes it for `entries` (reusing its memory: one per bucket run).
    fn reset(&mut self, entries: usize) {
        let size = (table_bytes(entries as u64) / 4) as usize;
        self.slots.clear();
        self.slots.resize(size, NONE);
        self.mask = size - 1;
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

    /// The slot holding the id `same` accepts, or the empty slot where it would go.
    #[inline]
    fn slot(&self, h: u64, same: impl Fn(u32) -> bool) -> usize {
        let mut at = h as usize & self.mask;
        // Slots probed past the first (the growth checks count them: a table that fills up
        // or hashes badly probes more per record).
        let mut probes = 0;
        loop {
            match self.slots.get(at).copied() {
                Some(NONE) | None => break,
                Some(other) if same(other) => break,
                Some(_) => {
                    at = (at + 1) & self.mask;
                    probes += 1;
                }
            }
        }
        if probes > 0 {
            crate::work::add(probes);
        }
        at
    }
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

/// Greedy weld in input order: each position joins the earliest kept position within `tol`
/// (checked in a grid of cells 4·tol wide, looking into a neighbour cell only when the
/// point is within `tol` of that side), else it is kept itself. Kept positions move down in
/// place; returns the map input index → kept index. A cell's kept points are pairwise ≥ tol
/// apart, so at most ~125 share a cell: each lookup is O(1).
fn greedy_weld(points: &mut Vec<[f32; 3]>, tol: f64, seed: u64) -> Vec<u32> {
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

    /// A small deterministic generator for the tests below.
    fn rng(seed: &mut u64) -> u64 {
        *seed ^= *seed << 13;
        *seed ^= *seed >> 7;
        *seed ^= *seed << 17;
        *seed
    }

    #[test]
    fn first_of_each_is_exact_when_hashes_collide() {
        let mut seed = 7u64;
        let n = 3 * CHUNK + 11;
        let keys: Vec<u32> = (0..n).map(|_| (rng(&mut seed) % 5000) as u32).collect();
        let mut naive = std::collections::HashMap::new();
        let want: Vec<u32> = keys.iter().enumerate().map(|(i, k)| *naive.entry(*k).or_insert(i as u32)).collect();
        // One hash for all (every key but the first fails the check and is looked up again),
        // two hashes, and a good one.
        for hash in [&(|_: &u32| 0u64) as &(dyn Fn(&u32) -> u64 + Sync), &|k| (*k as u64 & 1) << 40, &|k| finish(*k as u64)] {
            let first = first_of_each(n, |i| keys.get(i).copied(), hash);
            assert!((0..n).all(|i| first.get(i) == want[i]));
        }
        // Items without a key are their own first.
        let first = first_of_each(n, |i| keys.get(i).copied().filter(|_| i % 3 != 0), |k| finish(*k as u64));
        assert!((0..n).all(|i| first.get(i) as usize == i || i % 3 != 0));
    }

    #[test]
    fn close_points_has_every_point_with_a_neighbour_within_tolerance() {
        let mut seed = 99u64;
        let tol = 1e-4;
        let mut unit = || (rng(&mut seed) >> 11) as f64 / (1u64 << 53) as f64;
        // Scattered points, some pairs placed within (or just beyond) tol of each other.
        let mut points: Vec<[f32; 3]> = (0..20_000).map(|_| [0, 1, 2].map(|_| (unit() * 2.0) as f32)).collect();
        for k in 0..2000 {
            let p = points[k * 7];
            let d = [0.3, 0.7, 0.99, 1.01, 1.9][k % 5] * tol;
            points.push([p[0] + d as f32, p[1], p[2]]);
            points.push([p[0], p[1] - (d / 2.0) as f32, p[2] + (d / 2.0) as f32]);
        }
        let close = close_points(&points, tol, 1).unwrap();
        let mut cells = std::collections::HashMap::<[i64; 3], Vec<usize>>::new();
        let cell = |p: &[f32; 3]| p.map(|c| (c as f64 / tol).floor() as i64);
        for (i, p) in points.iter().enumerate() {
            cells.entry(cell(p)).or_default().push(i);
        }
        let mut must = 0;
        for (i, p) in points.iter().enumerate() {
            let c = cell(p);
            let near = (0..27).any(|d: i64| {
                let q = [c[0] + d % 3 - 1, c[1] + d / 3 % 3 - 1, c[2] + d / 9 - 1];
                cells.get(&q).is_some_and(|js| {
                    js.iter().any(|&j| {
                        let d = [0, 1, 2].map(|a| points[j][a] as f64 - p[a] as f64);
                        j != i && d[0] * d[0] + d[1] * d[1] + d[2] * d[2] < tol * tol
                    })
                })
            });
            if near {
                must += 1;
                assert!(close.binary_search(&(i as u32)).is_ok(), "point {i} has a neighbour within tol but is not close");
            }
        }
        assert!(must > 2000 && close.len() < 3 * must, "{must} must, {} found", close.len());
        // Points built to sit on the search's cell corners are over its record limit.
        let corner: Vec<[f32; 3]> = (0..1000).map(|k| [0, 1, 2].map(|a| (((k * (a + 3) % 40) as f64 + 0.5) * CLOSE_CELL * tol) as f32)).collect();
        assert!(close_points(&corner, tol, 1).is_none());
    }

    #[test]
    fn fans_group_by_vertex_as_counting_does() {
        // A fan around vertex 0 (one big group) with repeated triangles and a hole.
        let n = 5000u32;
        let mut tris: Vec<[u32; 3]> = (1..n).map(|k| [0, k, k + 1]).collect();
        tris.extend((1..200).map(|k| [k + 1, 0, k]));
        tris.remove(2500);
        let marked = Chunked::new(tris.len(), |range| range.map(|i| tris[i]).collect());
        let (kept, degenerate, repeated) = drop_duplicates(marked, n as usize + 1);
        assert_eq!((kept.len(), degenerate, repeated), (tris.len() - 199, 0, 199));
        assert_eq!(kept, tris[..tris.len() - 199].to_vec());
        let naive = {
            let mut count = std::collections::HashMap::new();
            for t in &kept {
                for k in 0..3 {
                    let (a, b) = (t[k], t[(k + 1) % 3]);
                    *count.entry((a.min(b), a.max(b))).or_insert(0) += 1;
                }
            }
            count.values().filter(|&&c| c == 1).count()
        };
        assert_eq!(open_edges(&kept, n as usize + 1, 1), naive);
        assert_eq!(open_edges(&kept, n as usize + 1, 2), naive);
    }
}

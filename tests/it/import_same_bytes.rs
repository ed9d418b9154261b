//! The importer gives the same bytes as before it was made parallel (issue: import on every
//! core, linear in size): the mesh (vertex order and bits, triangle order, welded indices) and
//! the report of `read_mesh` are compared with the previous, one-table cleaner, kept here as
//! the reference, on meshes made to reach every path (shuffled, soups, near-duplicates on
//! either side of the tolerance, cell borders, -0.0, dense clusters, degenerate and repeated
//! triangles, holes, huge and tiny coordinates), at every tolerance kind, in binary STL and
//! OBJ, at 1, 2 and 4 threads.

use rayon::ThreadPoolBuilder;
use weft::import::{read_mesh, ImportReport, Options};

// ---------- the previous cleaner (src/import/repair.rs before the change), verbatim ----------

struct RawMesh {
    vertices: Vec<[f32; 3]>,
    triangles: Vec<[u32; 3]>,
}

struct Repaired {
    vertices: Vec<[f32; 3]>,
    triangles: Vec<[u32; 3]>,
    degenerate_removed: usize,
    duplicates_removed: usize,
    open_edges: usize,
}

const NONE: u32 = u32::MAX;

/// Twice the area below this fraction of the longest edge squared counts as zero area.
const ZERO_AREA_RATIO: f64 = 1e-12;

/// Bytes of a [`Table`] for `n` entries (fixed size, or grown to hold `n`).
fn table_bytes(n: u64) -> u64 {
    4 * n.saturating_mul(2).max(16).next_power_of_two()
}

/// Cleans `raw`. `tolerance_mm` ≤ 0 (or NaN, or below 1 nm) welds only identical positions.
fn repair(raw: RawMesh, tolerance_mm: f64) -> Repaired {
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
    edges.sort_unstable();
    let open_edges = edges.chunk_by(|a, b| a == b).filter(|run| run.len() == 1).count();
    drop(edges);

    Repaired { vertices, triangles, degenerate_removed, duplicates_removed, open_edges }
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

// ---------- meshes ----------

/// The crate's deterministic generator (rand_pcg), seeded per test.
struct Rng(rand_pcg::Pcg64);

impl Rng {
    fn seeded(seed: u64) -> Rng {
        Rng(rand_core::SeedableRng::seed_from_u64(seed))
    }
    fn next(&mut self) -> u64 {
        rand_core::Rng::next_u64(&mut self.0)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
    fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// A triangle soup: three corners per triangle.
type Soup = Vec<[[f32; 3]; 3]>;

/// A UV sphere as `/tmp/sphere.py` makes it (radius `r`, `seg` around, `seg / 2` rings).
fn sphere(seg: usize, r: f64, centre: [f64; 3]) -> Soup {
    let rings = seg / 2;
    let p = |ring: usize, s: usize| -> [f32; 3] {
        let th = std::f64::consts::PI * ring as f64 / rings as f64;
        let ph = 2.0 * std::f64::consts::PI * (s % seg) as f64 / seg as f64;
        [(centre[0] + r * th.sin() * ph.cos()) as f32, (centre[1] + r * th.sin() * ph.sin()) as f32, (centre[2] + r * th.cos()) as f32]
    };
    let mut out = Vec::new();
    for ring in 0..rings {
        for s in 0..seg {
            let (a, b, c, d) = (p(ring, s), p(ring, s + 1), p(ring + 1, s), p(ring + 1, s + 1));
            if ring > 0 {
                out.push([a, c, b]);
            }
            if ring + 1 < rings {
                out.push([b, c, d]);
            }
        }
    }
    out
}

fn shuffled(mut soup: Soup, rng: &mut Rng) -> Soup {
    for i in (1..soup.len()).rev() {
        soup.swap(i, rng.below(i + 1));
    }
    soup
}

/// Moves some corners by a fraction of `tol` (some within it, some just out), along one
/// axis or all.
fn jittered(mut soup: Soup, tol: f64, share: f64, rng: &mut Rng) -> Soup {
    let steps = [0.2, 0.5, 0.9, 0.999, 1.001, 1.5, 3.0, 7.9, 8.1, 16.5, 31.9, 33.0];
    for t in soup.iter_mut() {
        for c in t.iter_mut() {
            if rng.unit() < share {
                let d = steps[rng.below(steps.len())] * tol * if rng.below(2) == 0 { 1.0 } else { -1.0 };
                match rng.below(4) {
                    3 => c.iter_mut().for_each(|x| *x = (*x as f64 + d / 3f64.sqrt()) as f32),
                    a => c[a] = (c[a] as f64 + d) as f32,
                }
            }
        }
    }
    soup
}

/// Degenerate (repeated corner, collinear) and repeated (same corners in another order)
/// triangles mixed in, and some dropped (holes: open edges).
fn damaged(soup: Soup, rng: &mut Rng) -> Soup {
    let mut out = Vec::with_capacity(soup.len() * 2);
    for (i, t) in soup.iter().enumerate() {
        match rng.below(40) {
            0 => {} // a hole
            1 => out.push([t[0], t[0], t[1]]),
            2 => {
                let mid = [0, 1, 2].map(|a| ((t[0][a] as f64 + t[1][a] as f64) / 2.0) as f32);
                out.push([t[0], mid, t[1]]);
                out.push(*t);
            }
            3 => {
                out.push(*t);
                out.push([t[2], t[0], t[1]]);
            }
            4 => {
                out.push(*t);
                out.push([t[1], t[0], t[2]]);
                if let Some(u) = soup.get(rng.below(i + 1)) {
                    out.push(*u);
                }
            }
            _ => out.push(*t),
        }
    }
    out
}

/// Points packed within `tol` of each other around a few centres (the greedy weld's work).
fn clusters(count: usize, per: usize, tol: f64, rng: &mut Rng) -> Soup {
    let mut out = Vec::new();
    for k in 0..count {
        let c = [k as f64 * 5.0, 1.0, -2.0];
        let mut p = || [0, 1, 2].map(|a| (c[a] + (rng.unit() - 0.5) * 3.0 * tol) as f32);
        for _ in 0..per {
            out.push([p(), p(), p()]);
        }
    }
    out
}

/// Corners on and around the borders of grid cells of 4·tol and 27·tol (shifted half a cell),
/// signed zeros, huge and tiny coordinates.
fn borders(tol: f64, rng: &mut Rng) -> Soup {
    let mut coords: Vec<f64> = vec![0.0, -0.0, 1e-40, -1e-40, 1e30, -3e37, 1e-4, 2e-4];
    for k in -6i32..6 {
        for cell in [4.0 * tol, 27.0 * tol] {
            let b = (k as f64 + 0.5) * cell;
            coords.extend([b, b - 0.999 * tol, b + 0.999 * tol, b - 1.001 * tol, b + 1.001 * tol, k as f64 * cell, b - 2.0 * tol, b + 2.0 * tol]);
        }
    }
    let mut pick = || [0, 1, 2].map(|_| coords[rng.below(coords.len())] as f32);
    (0..3000).map(|_| [pick(), pick(), pick()]).collect()
}

/// Corners all near the corners of the close-point search's cells (27·tol, shifted half a
/// cell): eight records a point, over its limit, so the greedy weld runs over all.
fn cell_corners(tol: f64, rng: &mut Rng) -> Soup {
    let cell = 27.0 * tol;
    let mut p = || [0, 1, 2].map(|_| ((rng.below(50) as f64 + 0.5) * cell + (rng.unit() - 0.5) * tol) as f32);
    (0..2000).map(|_| [p(), p(), p()]).collect()
}

/// Triangles sharing no corner.
fn soup(n: usize) -> Soup {
    (0..n)
        .map(|i| {
            let (x, y) = ((i % 100) as f32 * 3.0, (i / 100) as f32 * 3.0);
            [[x, y, 0.0], [x + 1.0, y, 0.0], [x, y + 1.0, 0.5]]
        })
        .collect()
}

fn binary_stl(soup: &Soup) -> Vec<u8> {
    let mut b = vec![0u8; 80];
    b.extend_from_slice(&(soup.len() as u32).to_le_bytes());
    for t in soup {
        b.extend_from_slice(&[0u8; 12]);
        for c in t.iter().flatten() {
            b.extend_from_slice(&c.to_le_bytes());
        }
        b.extend_from_slice(&[0, 0]);
    }
    b
}

/// An OBJ of the soup with its exactly equal corners shared (as an exporter writes them),
/// and its raw mesh as the OBJ reader makes it.
fn obj(soup: &Soup) -> (Vec<u8>, RawMesh) {
    let mut index = std::collections::HashMap::new();
    let mut raw = RawMesh { vertices: Vec::new(), triangles: Vec::new() };
    let mut text = String::from("o test\n");
    for t in soup {
        let tri = t.map(|c| {
            let bits = c.map(f32::to_bits);
            *index.entry(bits).or_insert_with(|| {
                raw.vertices.push(c);
                text.push_str(&format!("v {:?} {:?} {:?}\n", c[0] as f64, c[1] as f64, c[2] as f64));
                (raw.vertices.len() - 1) as u32
            })
        });
        text.push_str(&format!("f {} {} {}\n", tri[0] + 1, tri[1] + 1, tri[2] + 1));
        raw.triangles.push(tri);
    }
    (text.into_bytes(), raw)
}

fn raw_of(soup: &Soup) -> RawMesh {
    RawMesh { vertices: soup.iter().flatten().copied().collect(), triangles: (0..soup.len() as u32).map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect() }
}

// ---------- the comparison ----------

fn same(what: &str, file: &str, bytes: &[u8], raw: impl Fn() -> RawMesh) {
    for tol in [1e-4, 0.0, -1.0, f64::NAN, 1e-7, 1e-3, 0.05, 1.0, f64::INFINITY] {
        let old = repair(raw(), tol);
        for threads in [1, 2, 4] {
            let pool = ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            let got = pool.install(|| read_mesh(file, bytes, &Options { weld_tolerance_mm: tol }));
            let at = format!("{what}, tolerance {tol}, {threads} threads");
            let Ok(got) = got else {
                assert!(old.triangles.is_empty(), "{at}: {:?}", got.err());
                continue;
            };
            let bits = |v: &[[f32; 3]]| v.iter().map(|p| p.map(f32::to_bits)).collect::<Vec<_>>();
            assert!(bits(&got.mesh.vertices) == bits(&old.vertices), "{at}: vertices differ ({} vs {})", got.mesh.vertices.len(), old.vertices.len());
            assert!(got.mesh.triangles == old.triangles, "{at}: triangles differ ({} vs {})", got.mesh.triangles.len(), old.triangles.len());
            let ImportReport { triangles, vertices, degenerate_removed, duplicates_removed, open_edges, .. } = got.report;
            assert_eq!(
                (triangles, vertices, degenerate_removed, duplicates_removed, open_edges),
                (old.triangles.len(), old.vertices.len(), old.degenerate_removed, old.duplicates_removed, old.open_edges),
                "{at}: report"
            );
        }
    }
}

fn both(what: &str, soup: &Soup) {
    same(&format!("{what} (binary STL)"), "a.stl", &binary_stl(soup), || raw_of(soup));
    let (text, _) = obj(soup);
    same(&format!("{what} (OBJ)"), "a.obj", &text, || obj(soup).1);
}

#[test]
fn spheres_in_file_order_and_shuffled() {
    let mut rng = Rng::seeded(0x9e37_79b9_7f4a_7c15);
    both("sphere", &sphere(120, 40.0, [0.0, 0.0, 40.0]));
    both("shuffled sphere", &shuffled(sphere(90, 10.0, [3.0, -2.0, 10.0]), &mut rng));
    // Big enough for many chunks and buckets (the two-level lookup and its boundaries).
    let big = sphere(700, 40.0, [0.0, 0.0, 40.0]);
    same("big sphere", "a.stl", &binary_stl(&big), || raw_of(&big));
    let big = shuffled(big, &mut rng);
    same("big sphere, shuffled", "a.stl", &binary_stl(&big), || raw_of(&big));
}

#[test]
fn near_duplicates_degenerate_and_repeated_triangles() {
    let mut rng = Rng::seeded(0x2545_f491_4f6c_dd1d);
    for tol in [1e-4, 1e-3, 0.05] {
        let s = damaged(jittered(sphere(80, 5.0, [0.0, 0.0, 0.0]), tol, 0.3, &mut rng), &mut rng);
        both(&format!("jittered by {tol}, damaged"), &s);
        let s = shuffled(s, &mut rng);
        both(&format!("jittered by {tol}, damaged, shuffled"), &s);
    }
    // A big mesh with a few close points: the greedy weld over the close ones only.
    let mut big = sphere(500, 40.0, [0.0, 0.0, 40.0]);
    big.extend(clusters(20, 30, 1e-4, &mut rng));
    let big = damaged(big, &mut rng);
    same("big sphere with clusters", "a.stl", &binary_stl(&big), || raw_of(&big));
}

#[test]
fn clusters_borders_soups_and_far_coordinates() {
    let mut rng = Rng::seeded(0x5851_f42d_4c95_7f2d);
    both("clusters", &clusters(10, 400, 1e-4, &mut rng));
    both("clusters at 1e-3", &clusters(10, 400, 1e-3, &mut rng));
    both("cell borders", &borders(1e-4, &mut rng));
    both("cell borders at 1e-3", &borders(1e-3, &mut rng));
    both("cell corners", &cell_corners(1e-4, &mut rng));
    both("soup", &soup(5000));
    let big = soup(150_000);
    same("big soup", "a.stl", &binary_stl(&big), || raw_of(&big));
}

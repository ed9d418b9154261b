//! Strokes → planar graph: every stroke segment becomes an edge, edges are split where they
//! cross or touch other edges, nodes closer than the tolerance merge, degenerate and
//! duplicate edges go. A curved stroke ([`crate::geom::Stroke::curved`]: one curved strut) is
//! split and merged the same way, then each run of its pieces through nodes nothing else
//! touches becomes one edge whose inner points are kept as bends ([`Graph::bends`]): path
//! optimisation, counts and the lower bound see one strut, and the printed path walks its
//! sampled polyline.
//!
//! Deterministic by construction: nodes are numbered in order of first use while walking the
//! strokes in input order, adjacency lists are sorted by edge index, and no hash-map
//! iteration order reaches the output (hash maps are only used for look-ups).

use crate::geom::{DVec2, Feature, StrokeLayer};
use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

/// One strut: a straight edge between two nodes, or a curved one through its bends.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Edge {
    /// First node (index into [`Graph::nodes`]).
    pub a: usize,
    /// Second node.
    pub b: usize,
    /// Euclidean length between the two (merged) nodes (through the bends for a curved
    /// strut), mm: the edge weight.
    pub length: f64,
    /// Feature of the stroke the edge came from.
    pub feature: Feature,
}

/// The undirected graph of one layer.
#[derive(Clone, Debug, Default)]
pub struct Graph {
    /// Node positions, mm.
    pub nodes: Vec<DVec2>,
    /// Edges; no edge is a loop, and between two nodes there is at most one straight edge
    /// (curved struts of different shapes may share their two nodes).
    pub edges: Vec<Edge>,
    /// Bend points of the curved edges: edge `e`'s are `bends[bend_start[e]..bend_start[e + 1]]`,
    /// in order from node `a` to node `b`. Both empty when no edge is curved.
    pub bends: Vec<DVec2>,
    /// See `bends`.
    pub bend_start: Vec<usize>,
    /// Edges dropped because they were shorter than the merge tolerance (raw stroke segments
    /// and pieces whose ends merged).
    pub degenerate_dropped: usize,
    /// Duplicate edges (same two nodes, hence the same straight geometry) collapsed into one.
    pub duplicates_collapsed: usize,
    /// Component index of every node (components numbered by their lowest node).
    pub component: Vec<usize>,
    /// Number of connected components.
    pub components: usize,
    adj_start: Vec<usize>,
    adj: Vec<usize>,
}

impl Graph {
    /// Bend points of edge `e`, from `a` to `b` (empty for a straight edge).
    pub fn edge_bends(&self, e: usize) -> &[DVec2] {
        if self.bend_start.is_empty() {
            &[]
        } else {
            &self.bends[self.bend_start[e]..self.bend_start[e + 1]]
        }
    }

    /// The printed polyline of edge `e` from `a` to `b`: its nodes and bends.
    pub fn edge_points(&self, e: usize) -> Vec<DVec2> {
        let edge = &self.edges[e];
        let mut v = Vec::with_capacity(self.edge_bends(e).len() + 2);
        v.push(self.nodes[edge.a]);
        v.extend_from_slice(self.edge_bends(e));
        v.push(self.nodes[edge.b]);
        v
    }

    /// The bends of edge `e` in the order they are met walking it from node `from`.
    pub fn bends_from(&self, e: usize, from: usize) -> impl Iterator<Item = DVec2> + '_ {
        let b = self.edge_bends(e);
        let fwd = self.edges[e].a == from;
        (0..b.len()).map(move |i| if fwd { b[i] } else { b[b.len() - 1 - i] })
    }

    /// Edges incident to node `n`, by increasing edge index.
    pub fn incident(&self, n: usize) -> &[usize] {
        &self.adj[self.adj_start[n]..self.adj_start[n + 1]]
    }

    /// Degree of node `n`.
    pub fn degree(&self, n: usize) -> usize {
        self.adj_start[n + 1] - self.adj_start[n]
    }

    /// The end of edge `e` that is not `n`.
    pub fn other(&self, e: usize, n: usize) -> usize {
        let edge = &self.edges[e];
        if edge.a == n {
            edge.b
        } else {
            edge.a
        }
    }

    /// Number of odd-degree nodes.
    pub fn odd_nodes(&self) -> usize {
        (0..self.nodes.len()).filter(|&n| self.degree(n) % 2 == 1).count()
    }

    /// Odd-degree nodes per component.
    pub fn odd_per_component(&self) -> Vec<usize> {
        let mut odd = vec![0; self.components];
        for n in 0..self.nodes.len() {
            if self.degree(n) % 2 == 1 {
                odd[self.component[n]] += 1;
            }
        }
        odd
    }

    /// The proven minimum number of paths covering every edge once:
    /// Σ over components of max(1, odd/2).
    pub fn lower_bound_paths(&self) -> usize {
        self.odd_per_component().iter().map(|&o| (o / 2).max(1)).sum()
    }

    /// Total edge length, mm.
    pub fn total_length(&self) -> f64 {
        self.edges.iter().map(|e| e.length).sum()
    }
}

/// A small deterministic multiplicative hasher for integer keys (look-ups only).
#[derive(Default, Clone, Copy)]
pub(crate) struct IntHasher(u64);

impl Hasher for IntHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(b as u64);
        }
    }
    fn write_u64(&mut self, v: u64) {
        self.0 = (self.0.rotate_left(5) ^ v).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
    fn write_i64(&mut self, v: i64) {
        self.write_u64(v as u64);
    }
    fn write_u32(&mut self, v: u32) {
        self.write_u64(v as u64);
    }
    fn write_usize(&mut self, v: usize) {
        self.write_u64(v as u64);
    }
}

/// Hash map with [`IntHasher`].
pub(crate) type IntMap<K, V> = HashMap<K, V, BuildHasherDefault<IntHasher>>;

#[derive(Clone, Copy)]
struct Seg {
    p: DVec2,
    q: DVec2,
    feature: Feature,
    /// Index of the curved stroke the segment belongs to, or [`NOT_CURVED`].
    curve: u32,
}

const NOT_CURVED: u32 = u32::MAX;

/// Joins the pieces of each curved stroke through its bends (nodes of degree 2 whose two
/// edges belong to the same curved stroke) into one edge; nodes renumbered in order of first
/// use, edges in the order of their first piece. A run that would close on itself (a loop)
/// is left as it was. Returns (nodes, edges, bends, bend_start).
fn join_curves(nodes: Vec<DVec2>, edges: Vec<Edge>, curve: &[u32]) -> (Vec<DVec2>, Vec<Edge>, Vec<DVec2>, Vec<usize>) {
    let (start, adj) = incidence(nodes.len(), edges.iter().map(|e| (e.a, e.b)));
    let inc = |v: usize| &adj[start[v]..start[v + 1]];
    let bend = |v: usize, c: u32| {
        let i = inc(v);
        c != NOT_CURVED && i.len() == 2 && curve[i[0]] == c && curve[i[1]] == c
    };
    let other = |e: usize, v: usize| if edges[e].a == v { edges[e].b } else { edges[e].a };
    let mut done = vec![false; edges.len()];
    let mut remap = vec![usize::MAX; nodes.len()];
    let (mut out_nodes, mut out_edges, mut bends, mut bend_start) = (Vec::new(), Vec::new(), Vec::new(), vec![0usize]);
    let mut chain: Vec<usize> = Vec::new();
    let mut walk: Vec<usize> = Vec::new();
    for e0 in 0..edges.len() {
        if done[e0] {
            continue;
        }
        let c = curve[e0];
        // The run through e0: back from a, then forward from b (node sequence in `chain`).
        chain.clear();
        walk.clear();
        done[e0] = true;
        walk.push(e0);
        // Walks from node `v` away from edge `e` through bends of curve `c`, pushing the nodes
        // reached to `out` and the edges to `walk`; true when it comes back to a walked edge.
        let mut extend = |mut v: usize, mut e: usize, out: &mut Vec<usize>, walk: &mut Vec<usize>| {
            while bend(v, c) {
                let i = inc(v);
                let next = if i[0] == e { i[1] } else { i[0] };
                if done[next] {
                    return true;
                }
                done[next] = true;
                walk.push(next);
                v = other(next, v);
                e = next;
                out.push(v);
            }
            false
        };
        let mut back = vec![edges[e0].a];
        let closed = extend(edges[e0].a, e0, &mut back, &mut walk);
        back.reverse();
        chain.extend_from_slice(&back);
        chain.push(edges[e0].b);
        let closed = closed || extend(edges[e0].b, e0, &mut chain, &mut walk);
        let mut node = |n: usize, out_nodes: &mut Vec<DVec2>| {
            if remap[n] == usize::MAX {
                remap[n] = out_nodes.len();
                out_nodes.push(nodes[n]);
            }
            remap[n]
        };
        if closed || chain.len() == 2 || chain[0] == chain[chain.len() - 1] {
            // As it was: every piece its own edge (walked order: e0 first).
            let mut ws = walk.clone();
            ws.sort_unstable();
            for &w in &ws {
                let (a, b) = (node(edges[w].a, &mut out_nodes), node(edges[w].b, &mut out_nodes));
                out_edges.push(Edge { a, b, ..edges[w] });
                bend_start.push(bends.len());
            }
            continue;
        }
        let a = node(chain[0], &mut out_nodes);
        let b = node(chain[chain.len() - 1], &mut out_nodes);
        let length = chain.windows(2).map(|w| nodes[w[0]].distance(nodes[w[1]])).sum();
        bends.extend(chain[1..chain.len() - 1].iter().map(|&n| nodes[n]));
        bend_start.push(bends.len());
        out_edges.push(Edge { a, b, length, feature: edges[e0].feature });
    }
    (out_nodes, out_edges, bends, bend_start)
}

/// A split point on segment `seg` at parameter `t`.
#[derive(Clone, Copy)]
struct Split {
    seg: u32,
    t: f64,
    at: DVec2,
}

/// Builds the graph of one layer. `merge_tolerance_mm` (> 0; non-positive or non-finite
/// values fall back to the default) is the distance under which points are one node, the
/// length under which edges are dropped, and the reach of T-junction detection.
///
/// Cost: a uniform grid finds candidate crossing pairs, so the work is about linear in the
/// number of segments for lattice-like input (100,000 edges in a few tens of milliseconds).
pub fn build_graph(layer: &StrokeLayer, merge_tolerance_mm: f64) -> Graph {
    let tol = if merge_tolerance_mm.is_finite() && merge_tolerance_mm > 0.0 { merge_tolerance_mm } else { super::DEFAULT_MERGE_TOLERANCE_MM };
    let mut degenerate = 0usize;

    // 1. Raw segments.
    let mut segs: Vec<Seg> = Vec::new();
    let mut any_curved = false;
    for (si, stroke) in layer.strokes.iter().enumerate() {
        if stroke.curved && stroke.points.len() > 2 && stroke.points.iter().all(|p| p.is_finite()) {
            // One strut: inner points closer than the tolerance to the previous kept one go
            // (the last point stays; it replaces an inner point too close to it).
            let pts = &stroke.points;
            let mut kept = vec![pts[0]];
            for &p in &pts[1..pts.len() - 1] {
                if kept.last().unwrap().distance(p) >= tol {
                    kept.push(p);
                }
            }
            let last = pts[pts.len() - 1];
            if kept.len() > 1 && kept.last().unwrap().distance(last) < tol {
                kept.pop();
            }
            kept.push(last);
            if kept.len() > 2 {
                any_curved = true;
            }
            let curve = if kept.len() > 2 { si as u32 } else { NOT_CURVED };
            for w in kept.windows(2) {
                if w[0].distance(w[1]) < tol {
                    degenerate += 1;
                    continue;
                }
                segs.push(Seg { p: w[0], q: w[1], feature: stroke.feature, curve });
            }
            continue;
        }
        for w in stroke.points.windows(2) {
            let (p, q) = (w[0], w[1]);
            if !(p.is_finite() && q.is_finite()) {
                degenerate += 1;
                continue;
            }
            if p.distance(q) < tol {
                degenerate += 1;
                continue;
            }
            segs.push(Seg { p, q, feature: stroke.feature, curve: NOT_CURVED });
        }
    }
    if segs.is_empty() {
        return Graph { degenerate_dropped: degenerate, adj_start: vec![0], ..Graph::default() };
    }

    // 2. Split points at crossings and T-junctions.
    let mut splits = find_splits(&segs, tol);
    splits.sort_by(|x, y| x.seg.cmp(&y.seg).then(x.t.total_cmp(&y.t)));

    // 3. Pieces, 4. node merging.
    let mut merger = Merger::new(tol);
    let mut raw_edges: Vec<(usize, usize, Feature)> = Vec::with_capacity(segs.len() + splits.len());
    let mut raw_curve: Vec<u32> = Vec::new();
    let mut k = 0usize;
    let mut add_piece = |a: DVec2, b: DVec2, s: &Seg, merger: &mut Merger, degenerate: &mut usize| {
        let na = merger.node(a);
        let nb = merger.node(b);
        if na == nb {
            *degenerate += 1;
        } else {
            raw_edges.push((na, nb, s.feature));
            if any_curved {
                raw_curve.push(s.curve);
            }
        }
    };
    for (si, s) in segs.iter().enumerate() {
        let len = s.p.distance(s.q);
        let mut last_point = s.p;
        let mut last_t_len = 0.0;
        while k < splits.len() && splits[k].seg as usize == si {
            let sp = splits[k];
            k += 1;
            let along = sp.t * len;
            if along - last_t_len <= tol || len - along <= tol || sp.at.distance(last_point) <= tol {
                continue;
            }
            add_piece(last_point, sp.at, s, &mut merger, &mut degenerate);
            last_point = sp.at;
            last_t_len = along;
        }
        add_piece(last_point, s.q, s, &mut merger, &mut degenerate);
    }
    let positions = merger.nodes;

    // 5. Edges: drop short ones, collapse duplicates (keep the first).
    let mut keyed: Vec<(usize, usize, usize)> = Vec::with_capacity(raw_edges.len());
    let mut keep = vec![true; raw_edges.len()];
    for (i, &(a, b, _)) in raw_edges.iter().enumerate() {
        if positions[a].distance(positions[b]) < tol {
            keep[i] = false;
            degenerate += 1;
        } else {
            keyed.push((a.min(b), a.max(b), i));
        }
    }
    keyed.sort_unstable();
    let mut duplicates = 0usize;
    for w in keyed.windows(2) {
        // Pieces of two different curved struts between the same nodes are different struts.
        let curved = any_curved && (raw_curve[w[0].2] != NOT_CURVED || raw_curve[w[1].2] != NOT_CURVED);
        if w[0].0 == w[1].0 && w[0].1 == w[1].1 && !(curved && raw_curve[w[0].2] != raw_curve[w[1].2]) {
            keep[w[1].2] = false;
            duplicates += 1;
        }
    }

    // 6. Compact nodes in order of first use.
    let mut remap = vec![usize::MAX; positions.len()];
    let mut nodes = Vec::new();
    let mut edges = Vec::new();
    let mut edge_curve = Vec::new();
    for (i, &(a, b, feature)) in raw_edges.iter().enumerate() {
        if !keep[i] {
            continue;
        }
        for n in [a, b] {
            if remap[n] == usize::MAX {
                remap[n] = nodes.len();
                nodes.push(positions[n]);
            }
        }
        let (a, b) = (remap[a], remap[b]);
        edges.push(Edge { a, b, length: nodes[a].distance(nodes[b]), feature });
        if any_curved {
            edge_curve.push(raw_curve[i]);
        }
    }
    let (mut bends, mut bend_start) = (Vec::new(), Vec::new());
    if any_curved {
        (nodes, edges, bends, bend_start) = join_curves(nodes, edges, &edge_curve);
    }

    // 7. Adjacency (CSR), lists sorted by edge index.
    let n = nodes.len();
    let (adj_start, adj) = incidence(n, edges.iter().map(|e| (e.a, e.b)));

    // 8. Components (union-find, numbered by lowest node).
    let mut parent: Vec<usize> = (0..n).collect();
    fn find(parent: &mut [usize], mut x: usize) -> usize {
        while parent[x] != x {
            parent[x] = parent[parent[x]];
            x = parent[x];
        }
        x
    }
    for e in &edges {
        let ra = find(&mut parent, e.a);
        let rb = find(&mut parent, e.b);
        if ra != rb {
            let (lo, hi) = (ra.min(rb), ra.max(rb));
            parent[hi] = lo;
        }
    }
    let mut component = vec![usize::MAX; n];
    let mut root_comp = vec![usize::MAX; n];
    let mut components = 0;
    for (i, comp) in component.iter_mut().enumerate() {
        let r = find(&mut parent, i);
        if root_comp[r] == usize::MAX {
            root_comp[r] = components;
            components += 1;
        }
        *comp = root_comp[r];
    }

    Graph { nodes, edges, bends, bend_start, degenerate_dropped: degenerate, duplicates_collapsed: duplicates, component, components, adj_start, adj }
}

/// Greedy deterministic node merging on a grid of cells 2·tol wide: a point joins the nearest
/// existing node within `tol` (lowest index on ties), else becomes a node.
struct Merger {
    tol: f64,
    inv_cell: f64,
    nodes: Vec<DVec2>,
    next: Vec<u32>,
    heads: IntMap<(i64, i64), u32>,
}

impl Merger {
    fn new(tol: f64) -> Merger {
        Merger { tol, inv_cell: 1.0 / (2.0 * tol), nodes: Vec::new(), next: Vec::new(), heads: IntMap::default() }
    }

    fn node(&mut self, p: DVec2) -> usize {
        let fx = p.x * self.inv_cell;
        let fy = p.y * self.inv_cell;
        let cx = fx.floor();
        let cy = fy.floor();
        let x0 = if fx - cx < 0.5 { cx as i64 - 1 } else { cx as i64 };
        let y0 = if fy - cy < 0.5 { cy as i64 - 1 } else { cy as i64 };
        let mut best = u32::MAX;
        let mut best_d = f64::INFINITY;
        for dy in 0..2 {
            for dx in 0..2 {
                if let Some(&h) = self.heads.get(&(x0 + dx, y0 + dy)) {
                    let mut i = h;
                    while i != u32::MAX {
                        let d = self.nodes[i as usize].distance(p);
                        if d <= self.tol && (d < best_d || (d == best_d && i < best)) {
                            best_d = d;
                            best = i;
                        }
                        i = self.next[i as usize];
                    }
                }
            }
        }
        if best != u32::MAX {
            return best as usize;
        }
        let id = self.nodes.len() as u32;
        self.nodes.push(p);
        let key = (cx as i64, cy as i64);
        let head = self.heads.entry(key).or_insert(u32::MAX);
        self.next.push(*head);
        *head = id;
        id as usize
    }
}

/// Candidate pairs from a uniform grid; exact tests for crossings and T-junctions.
fn find_splits(segs: &[Seg], tol: f64) -> Vec<Split> {
    let mut min = DVec2::splat(f64::INFINITY);
    let mut max = DVec2::splat(f64::NEG_INFINITY);
    for s in segs {
        min = min.min(s.p).min(s.q);
        max = max.max(s.p).max(s.q);
    }
    min -= DVec2::splat(2.0 * tol);
    max += DVec2::splat(2.0 * tol);
    let size = max - min;
    let n = segs.len() as f64;
    let mut cell = (size.x * size.y / n).sqrt().max(4.0 * tol);
    // At most ~4 cells per segment (and a sane absolute cap).
    let cap = (4.0 * n + 16.0).min(4.0e7);
    while (size.x / cell + 1.0) * (size.y / cell + 1.0) > cap {
        cell *= 1.5;
    }
    let nx = (size.x / cell).floor() as usize + 1;
    let ny = (size.y / cell).floor() as usize + 1;
    let inv = 1.0 / cell;

    // Cells covered by a segment expanded by tol: per row band, clip the segment to the band
    // widened by tol and take its x range widened by tol.
    let cover = |s: &Seg, out: &mut dyn FnMut(usize)| {
        let y_lo = s.p.y.min(s.q.y) - tol;
        let y_hi = s.p.y.max(s.q.y) + tol;
        let r0 = (((y_lo - min.y) * inv).floor().max(0.0) as usize).min(ny - 1);
        let r1 = (((y_hi - min.y) * inv).floor().max(0.0) as usize).min(ny - 1);
        let d = s.q - s.p;
        for r in r0..=r1 {
            let band_lo = min.y + r as f64 * cell - tol;
            let band_hi = band_lo + cell + 2.0 * tol;
            let (x_lo, x_hi) = if d.y.abs() < 1e-12 {
                (s.p.x.min(s.q.x), s.p.x.max(s.q.x))
            } else {
                let ta = ((band_lo - s.p.y) / d.y).clamp(0.0, 1.0);
                let tb = ((band_hi - s.p.y) / d.y).clamp(0.0, 1.0);
                let xa = s.p.x + d.x * ta;
                let xb = s.p.x + d.x * tb;
                (xa.min(xb), xa.max(xb))
            };
            let c0 = (((x_lo - tol - min.x) * inv).floor().max(0.0) as usize).min(nx - 1);
            let c1 = (((x_hi + tol - min.x) * inv).floor().max(0.0) as usize).min(nx - 1);
            for c in c0..=c1 {
                out(r * nx + c);
            }
        }
    };

    // CSR of cell → segments (two passes: count, fill).
    let mut start = vec![0u32; nx * ny + 1];
    for s in segs {
        cover(s, &mut |c| start[c + 1] += 1);
    }
    for i in 0..nx * ny {
        start[i + 1] += start[i];
    }
    let mut fill: Vec<u32> = start[..nx * ny].to_vec();
    let mut items = vec![0u32; start[nx * ny] as usize];
    for (i, s) in segs.iter().enumerate() {
        cover(s, &mut |c| {
            items[fill[c] as usize] = i as u32;
            fill[c] += 1;
        });
    }

    let mut boxes: Vec<(DVec2, DVec2)> = Vec::with_capacity(segs.len());
    for s in segs {
        boxes.push((s.p.min(s.q) - DVec2::splat(tol), s.p.max(s.q) + DVec2::splat(tol)));
    }
    let mut splits = Vec::new();
    for c in 0..nx * ny {
        let list = &items[start[c] as usize..start[c + 1] as usize];
        for (x, &i) in list.iter().enumerate() {
            let (ilo, ihi) = boxes[i as usize];
            for &j in &list[x + 1..] {
                let (jlo, jhi) = boxes[j as usize];
                if ilo.x > jhi.x || jlo.x > ihi.x || ilo.y > jhi.y || jlo.y > ihi.y {
                    continue;
                }
                intersect(segs, i, j, tol, &mut splits);
            }
        }
    }
    splits
}

/// Parameter of `e`'s projection on segment p + r·t when it lies within `tol` of the segment
/// and more than `tol` from both ends.
fn interior_projection(p: DVec2, r: DVec2, len: f64, e: DVec2, tol: f64) -> Option<f64> {
    let t = (e - p).dot(r) / (len * len);
    if t * len > tol && (1.0 - t) * len > tol && (p + r * t).distance(e) <= tol {
        Some(t)
    } else {
        None
    }
}

fn intersect(segs: &[Seg], i: u32, j: u32, tol: f64, out: &mut Vec<Split>) {
    let (si, sj) = (&segs[i as usize], &segs[j as usize]);
    let (p, r) = (si.p, si.q - si.p);
    let (q, s) = (sj.p, sj.q - sj.p);
    let (li, lj) = (r.length(), s.length());
    // T-junctions (and collinear overlaps): an endpoint of one on the other's interior.
    for e in [sj.p, sj.q] {
        if let Some(t) = interior_projection(p, r, li, e, tol) {
            out.push(Split { seg: i, t, at: e });
        }
    }
    for e in [si.p, si.q] {
        if let Some(u) = interior_projection(q, s, lj, e, tol) {
            out.push(Split { seg: j, t: u, at: e });
        }
    }
    // Proper crossing, away from every end.
    let d = r.perp_dot(s);
    if d.abs() > 1e-12 * li * lj {
        let qp = q - p;
        let t = qp.perp_dot(s) / d;
        let u = qp.perp_dot(r) / d;
        if t * li > tol && (1.0 - t) * li > tol && u * lj > tol && (1.0 - u) * lj > tol {
            let at = p + r * t;
            out.push(Split { seg: i, t, at });
            out.push(Split { seg: j, t: u, at });
        }
    }
}

/// Incidence lists in CSR form of `n` nodes and the edges `(a, b)` (by position): node `v`'s
/// edges are `adj[start[v]..start[v + 1]]`, in edge order. Returns `(start, adj)`.
pub(crate) fn incidence(n: usize, ends: impl Iterator<Item = (usize, usize)> + Clone) -> (Vec<usize>, Vec<usize>) {
    let mut start = vec![0usize; n + 1];
    for (a, b) in ends.clone() {
        start[a + 1] += 1;
        start[b + 1] += 1;
    }
    for i in 0..n {
        start[i + 1] += start[i];
    }
    let mut fill = start.clone();
    let mut adj = vec![0usize; start[n]];
    for (i, (a, b)) in ends.enumerate() {
        adj[fill[a]] = i;
        fill[a] += 1;
        adj[fill[b]] = i;
        fill[b] += 1;
    }
    (start, adj)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::Stroke;

    fn layer(strokes: &[&[(f64, f64)]]) -> StrokeLayer {
        StrokeLayer {
            z: 0.2,
            height: 0.2,
            strokes: strokes
                .iter()
                .map(|s| Stroke { points: s.iter().map(|&(x, y)| DVec2::new(x, y)).collect(), feature: Feature::Lattice, curved: false })
                .collect(),
        }
    }

    #[test]
    fn x_of_two_strokes_is_four_edges_one_hub() {
        let g = build_graph(&layer(&[&[(0.0, 0.0), (2.0, 2.0)], &[(0.0, 2.0), (2.0, 0.0)]]), 0.005);
        assert_eq!(g.edges.len(), 4);
        assert_eq!(g.nodes.len(), 5);
        let hubs: Vec<usize> = (0..g.nodes.len()).filter(|&n| g.degree(n) == 4).collect();
        assert_eq!(hubs.len(), 1);
        assert!(g.nodes[hubs[0]].distance(DVec2::new(1.0, 1.0)) < 1e-12);
        assert_eq!(g.components, 1);
    }

    #[test]
    fn t_junction_and_overlap() {
        // T: the stem ends on the bar's interior (within tolerance).
        let g = build_graph(&layer(&[&[(0.0, 0.0), (4.0, 0.0)], &[(2.0, 3.0), (2.0, 0.003)]]), 0.005);
        assert_eq!(g.edges.len(), 3);
        assert_eq!(g.nodes.len(), 4);
        // Collinear overlap: 0..10 and 5..15 → 0-5, 5-10, 10-15.
        let g = build_graph(&layer(&[&[(0.0, 0.0), (10.0, 0.0)], &[(5.0, 0.0), (15.0, 0.0)]]), 0.005);
        assert_eq!(g.edges.len(), 3);
        assert_eq!(g.duplicates_collapsed, 1);
    }

    #[test]
    fn merge_and_degenerate() {
        let g = build_graph(&layer(&[&[(0.0, 0.0), (1.0, 0.0)], &[(1.002, 0.001), (1.0, 1.0)], &[(3.0, 3.0), (3.001, 3.0)]]), 0.005);
        assert_eq!(g.edges.len(), 2);
        assert_eq!(g.nodes.len(), 3);
        assert_eq!(g.degenerate_dropped, 1);
        assert_eq!(g.components, 1);
    }
}

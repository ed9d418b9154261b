//! Minimum-cost perfect matching on a **sparse** graph (edge list, integer costs) by Edmonds'
//! primal–dual blossom algorithm (Edmonds 1965; the "all free vertices grow alternating trees
//! at once" form of Galil's 1986 survey), with its **dual solution**, so a caller can prove
//! that pairs left out of the graph could not lower the cost ([`certified_pairing`]).
//!
//! Written here rather than taken from a crate: `integer-blossom` is dense-only and returns
//! no duals, `mwmatching` keeps i32 duals private, `fusion-blossom` pulls a CLI's worth of
//! dependencies.
//!
//! Duals (LP with odd-set cuts): maximise Σ y_v + Σ z_S subject to
//! y_u + y_v + Σ_{S: uv ∈ δ(S)} z_S ≤ c_uv on every edge, z_S ≥ 0. Internally every cost is
//! multiplied by [`DUAL_SCALE`] = 4 and every dual stays an integer: starting potentials are
//! half the cheapest incident edge (even after scaling), so all free vertices share a parity,
//! every tree vertex has its root's parity (tight edges join equal parities) and the halving of
//! an S–S slack is exact. The solver keeps per vertex the *total* potential
//! Y_v = y_v + Σ_{S ∋ v} z_S: an edge between different outer blossoms has slack
//! c − Y_u − Y_v, and a dual step changes Y of a whole tree blossom at once.
//!
//! Speed on geometric instances: a jump start (potentials, then a greedy matching of tight
//! edges); an augmentation dissolves only the two trees it joins (the others keep their
//! labels, so there are no O(n) stage restarts); best-edge tracking per vertex (to S vertices)
//! and per S-blossom (to other S-blossoms, merged when blossoms form) so a dual step never
//! rescans edges; lazy duals (one running Σδ, written back when a blossom's label changes) and
//! a heap of dual-step events, so a dual step is O(log m) rather than the size of the forest.
//! Best edges into dissolved trees are looked up again (their slack stopped shrinking).
//! Everything is deterministic (index order, first minimum wins, heap ties by id).

use std::cmp::Reverse;
use std::collections::BinaryHeap;

const NONE: usize = usize::MAX;
const NO_EDGE: (usize, usize) = (NONE, NONE);
/// Costs are multiplied by this inside the solver; duals are reported in these units.
pub const DUAL_SCALE: i64 = 4;

const FREE: u8 = 0;
const S: u8 = 1;
const T: u8 = 2;

/// The candidate graph has no perfect matching.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct NoPerfectMatching;

impl std::fmt::Display for NoPerfectMatching {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("no perfect matching on these candidates")
    }
}

/// A dual solution, in units of 1/[`DUAL_SCALE`] of a cost: total potentials and the laminar
/// family of odd sets (as a forest: each set's parent set, its z, its size).
#[derive(Clone, Debug, Default)]
pub struct Duals {
    /// Y_v = y_v + Σ_{S ∋ v} z_S. A pair through v is charged at most this (scaled).
    pub total: Vec<i64>,
    /// Smallest odd set containing each vertex, or `usize::MAX`.
    pub vertex_set: Vec<usize>,
    /// Enclosing set of each set, or `usize::MAX`.
    pub set_parent: Vec<usize>,
    /// z_S ≥ 0.
    pub set_z: Vec<i64>,
    /// |S| (odd).
    pub set_size: Vec<usize>,
    /// Σ z over the set and its ancestors.
    set_z_up: Vec<i64>,
    set_depth: Vec<usize>,
}

impl Duals {
    /// y_v (scaled).
    pub fn y(&self, v: usize) -> i64 {
        let s = self.vertex_set[v];
        self.total[v] - if s == NONE { 0 } else { self.set_z_up[s] }
    }

    /// Σ y + Σ z (scaled): a lower bound on DUAL_SCALE × the cost of every perfect matching
    /// whose pairs all satisfy the constraints.
    pub fn objective(&self) -> i64 {
        let y: i64 = self.total.iter().sum();
        let z: i64 = self.set_z.iter().zip(&self.set_size).map(|(&z, &s)| z * (s as i64 - 1)).sum();
        y - z
    }

    /// Σ z over the sets containing both u and v.
    fn common_z(&self, u: usize, v: usize) -> i64 {
        let (mut a, mut b) = (self.vertex_set[u], self.vertex_set[v]);
        if a == NONE || b == NONE {
            return 0;
        }
        while self.set_depth[a] > self.set_depth[b] {
            a = self.set_parent[a];
        }
        while self.set_depth[b] > self.set_depth[a] {
            b = self.set_parent[b];
        }
        while a != b {
            a = self.set_parent[a];
            b = self.set_parent[b];
            if a == NONE || b == NONE {
                return 0;
            }
        }
        self.set_z_up[a]
    }

    /// Reduced cost (scaled) of the pair (u, v) at cost `c` (unscaled): DUAL_SCALE·c − y_u − y_v
    /// − Σ_{S crossing} z_S. Negative: the pair violates the dual (it might lower the cost).
    pub fn reduced_cost(&self, u: usize, v: usize, c: i64) -> i64 {
        DUAL_SCALE * c - self.total[u] - self.total[v] + 2 * self.common_z(u, v)
    }

    /// max Y_v.
    pub fn max_total(&self) -> i64 {
        self.total.iter().copied().max().unwrap_or(0)
    }
}

/// A minimum-cost perfect matching and the dual solution certifying it.
#[derive(Clone, Debug)]
pub struct Matching {
    /// Every vertex's partner.
    pub mates: Vec<usize>,
    /// Σ cost of the matched edges (unscaled).
    pub cost: i64,
    /// The dual solution that proves it minimal on the edges given.
    pub duals: Duals,
}

/// Minimum-cost perfect matching of `n` vertices on `edges` (u, v, cost ≥ 0; cost · 4 must fit
/// i64 with room for sums); parallel edges keep the cheapest, loops are ignored. Memory O(n + m).
pub fn min_cost_perfect_matching(n: usize, edges: &[(usize, usize, i64)]) -> Result<Matching, NoPerfectMatching> {
    if n % 2 == 1 {
        return Err(NoPerfectMatching);
    }
    if n == 0 {
        return Ok(Matching { mates: Vec::new(), cost: 0, duals: Duals::default() });
    }
    let mut list: Vec<(usize, usize, i64)> = edges.iter().filter(|e| e.0 != e.1).map(|&(u, v, c)| (u.min(v), u.max(v), c)).collect();
    list.sort_unstable();
    list.dedup_by_key(|e| (e.0, e.1));
    let mut s = Solver::new(n, list);
    s.solve()?;
    Ok(s.result())
}

/// Why [`certified_pairing`] gave no certified matching.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CertifyError {
    /// The candidates have no perfect matching.
    NoPerfectMatching,
    /// The violator search hit its work bound, or the rounds ran out.
    GaveUp,
}

/// A matching proven minimal on the *complete* graph: every pair left out has a
/// non-negative reduced cost under `duals`.
#[derive(Clone, Debug)]
pub struct Certified {
    /// The matching and the duals of its last solve.
    pub matching: Matching,
    /// Solves done (1 + rounds that added violating pairs).
    pub solves: usize,
    /// Pairs added by the violator search.
    pub added: usize,
}

/// Violator search: pushes pairs (u, v, cost) that may have a negative reduced cost under the
/// duals; false when it hit its work bound.
pub type ViolatorSearch<'a> = dyn FnMut(&Duals, &mut Vec<(usize, usize, i64)>) -> bool + 'a;

/// Minimum-cost perfect matching of `n` items on the complete graph, solved on a sparse
/// candidate set: solve on `candidates`, ask `find_violators(duals, out)` for pairs with a
/// negative reduced cost (`duals.reduced_cost(u, v, c) < 0`; it returns false when it hit its
/// own work bound), add them and re-solve, at most `max_solves` solves. When none is left the
/// duals are feasible for every pair, so Σy + Σz = cost proves the optimum (weak duality).
pub fn certified_pairing(
    n: usize,
    mut candidates: Vec<(usize, usize, i64)>,
    find_violators: &mut ViolatorSearch<'_>,
    max_solves: usize,
) -> Result<Certified, CertifyError> {
    let mut added = 0;
    let mut found = Vec::new();
    for solves in 1..=max_solves {
        let m = min_cost_perfect_matching(n, &candidates).map_err(|_| CertifyError::NoPerfectMatching)?;
        found.clear();
        if !find_violators(&m.duals, &mut found) {
            return Err(CertifyError::GaveUp);
        }
        found.retain(|&(u, v, c)| u != v && m.duals.reduced_cost(u, v, c) < 0);
        if found.is_empty() {
            return Ok(Certified { matching: m, solves, added });
        }
        added += found.len();
        candidates.extend_from_slice(&found);
    }
    Err(CertifyError::GaveUp)
}

struct Solver {
    n: usize,
    /// (u, v, DUAL_SCALE · cost).
    edges: Vec<(usize, usize, i64)>,
    adj_start: Vec<usize>,
    adj: Vec<usize>,
    mate: Vec<usize>,
    /// Outermost blossom of each vertex.
    inblossom: Vec<usize>,
    /// Ids n..2n are blossoms; ids < n are the trivial blossoms (vertices).
    parent: Vec<usize>,
    /// Children around the cycle, the base's child first.
    childs: Vec<Vec<usize>>,
    /// `ends[b][i]` = (x in childs[i], y in childs[i+1 mod k]): the edge joining them.
    ends: Vec<Vec<(usize, usize)>>,
    base: Vec<usize>,
    /// Label of each outer blossom (and of the vertex a label arrived at).
    label: Vec<u8>,
    /// (outside vertex, inside vertex) of the edge that gave the label; none for roots.
    labeledge: Vec<(usize, usize)>,
    /// Root vertex of the alternating tree of each labelled outer blossom.
    tree_of: Vec<usize>,
    /// Blossoms labelled in each root's tree (stale entries filtered when read).
    tree_members: Vec<Vec<usize>>,
    /// Vertex (not in an S-blossom): least-slack edge to an S vertex; S-blossom: least-slack
    /// edge to another S-blossom. Checked when read: an end may have left its tree.
    bestedge: Vec<usize>,
    /// S-blossom: least-slack edge to each neighbouring S-blossom (None: scan its vertices).
    bestlist: Vec<Option<Vec<usize>>>,
    /// Vertices: Y_v; blossoms: z_b. Scaled.
    dual: Vec<i64>,
    free_ids: Vec<usize>,
    queue: Vec<usize>,
    /// Σ of all dual steps so far. Duals are lazy: an outer S (T) blossom's vertices and z
    /// are `dual` + (−) (`ds` − `stamp`), written back only when its label changes, so a dual
    /// step is O(log) instead of the size of the forest.
    ds: i64,
    stamp: Vec<i64>,
    /// Dual-step events keyed by the `ds` at which they happen: (key, kind, id, edge) with
    /// kind 2 = S–free edge tight (id: the free vertex), 3 = S–S edge tight (id: the S-blossom),
    /// 4 = T-blossom z reaches 0. Stale entries are checked and dropped when they surface.
    heap: BinaryHeap<Reverse<(i64, u8, usize, usize)>>,
    mark: Vec<u32>,
    mark_stamp: u32,
    bestto: Vec<usize>,
    buf: Vec<usize>,
}

impl Solver {
    fn new(n: usize, list: Vec<(usize, usize, i64)>) -> Solver {
        let edges: Vec<(usize, usize, i64)> = list.into_iter().map(|(u, v, c)| (u, v, c * DUAL_SCALE)).collect();
        let mut adj_start = vec![0usize; n + 1];
        for &(u, v, _) in &edges {
            adj_start[u + 1] += 1;
            adj_start[v + 1] += 1;
        }
        for i in 0..n {
            adj_start[i + 1] += adj_start[i];
        }
        let mut fill = adj_start.clone();
        let mut adj = vec![0usize; adj_start[n]];
        for (k, &(u, v, _)) in edges.iter().enumerate() {
            adj[fill[u]] = k;
            fill[u] += 1;
            adj[fill[v]] = k;
            fill[v] += 1;
        }
        let nb = 2 * n;
        Solver {
            n,
            edges,
            adj_start,
            adj,
            mate: vec![NONE; n],
            inblossom: (0..n).collect(),
            parent: vec![NONE; nb],
            childs: vec![Vec::new(); nb],
            ends: vec![Vec::new(); nb],
            base: (0..n).chain(std::iter::repeat_n(NONE, n)).collect(),
            label: vec![FREE; nb],
            labeledge: vec![NO_EDGE; nb],
            tree_of: vec![NONE; nb],
            tree_members: vec![Vec::new(); n],
            bestedge: vec![NONE; nb],
            bestlist: vec![None; nb],
            dual: vec![0; nb],
            free_ids: (n..nb).rev().collect(),
            queue: Vec::new(),
            ds: 0,
            stamp: vec![0; nb],
            heap: BinaryHeap::new(),
            mark: vec![0; nb],
            mark_stamp: 0,
            bestto: vec![NONE; nb],
            buf: Vec::new(),
        }
    }

    /// Lazy offset of outer blossom b's duals.
    fn offset(&self, b: usize) -> i64 {
        match self.label[b] {
            S => self.ds - self.stamp[b],
            T => self.stamp[b] - self.ds,
            _ => 0,
        }
    }

    /// Current Y_v.
    fn y(&self, v: usize) -> i64 {
        self.dual[v] + self.offset(self.inblossom[v])
    }

    fn slack(&self, k: usize) -> i64 {
        let (u, v, c) = self.edges[k];
        c - self.y(u) - self.y(v)
    }

    /// Writes outer blossom b's lazy offset back into its vertices and z.
    fn settle(&mut self, b: usize) {
        let off = self.offset(b);
        self.stamp[b] = self.ds;
        if off == 0 {
            return;
        }
        let mut buf = std::mem::take(&mut self.buf);
        buf.clear();
        self.leaves(b, &mut buf);
        for &v in &buf {
            self.dual[v] += off;
        }
        if b >= self.n {
            self.dual[b] += off;
        }
        self.buf = buf;
    }

    fn push_vertex_best(&mut self, w: usize, k: usize) {
        self.bestedge[w] = k;
        let key = self.slack(k) + self.ds;
        self.heap.push(Reverse((key, 2, w, k)));
    }

    fn push_blossom_best(&mut self, b: usize, k: usize) {
        self.bestedge[b] = k;
        if k != NONE {
            let s = self.slack(k);
            debug_assert!(s % 2 == 0, "odd S–S slack {s}");
            self.heap.push(Reverse((s / 2 + self.ds, 3, b, k)));
        }
    }

    fn other(&self, k: usize, v: usize) -> usize {
        let (a, b, _) = self.edges[k];
        if a == v {
            b
        } else {
            a
        }
    }

    fn is_outer(&self, b: usize) -> bool {
        self.parent[b] == NONE && self.base[b] != NONE
    }

    /// Appends the vertices of blossom `b` to `out`.
    fn leaves(&self, b: usize, out: &mut Vec<usize>) {
        if b < self.n {
            out.push(b);
            return;
        }
        let mut stack = vec![b];
        while let Some(x) = stack.pop() {
            for &c in self.childs[x].iter().rev() {
                if c < self.n {
                    out.push(c);
                } else {
                    stack.push(c);
                }
            }
        }
    }

    /// Jump start: Y_v = half the cheapest incident edge, then (vertex order) raise each free
    /// vertex to its tightest edge (by an even amount, keeping free vertices' parity) and match
    /// it when the other end is free.
    fn jump_start(&mut self) -> Result<(), NoPerfectMatching> {
        for v in 0..self.n {
            let mut m = i64::MAX;
            for &k in &self.adj[self.adj_start[v]..self.adj_start[v + 1]] {
                m = m.min(self.edges[k].2);
            }
            if m == i64::MAX {
                return Err(NoPerfectMatching);
            }
            self.dual[v] = m / 2;
        }
        for v in 0..self.n {
            if self.mate[v] != NONE {
                continue;
            }
            // Tightest edge, a free partner first among equals, then index order.
            let mut best = (i64::MAX, 1u8, NONE);
            for &k in &self.adj[self.adj_start[v]..self.adj_start[v + 1]] {
                let w = self.other(k, v);
                let key = (self.slack(k), u8::from(self.mate[w] != NONE), w);
                if key < best {
                    best = key;
                }
            }
            let (s, _, w) = best;
            self.dual[v] += s & !1;
            if s & 1 == 0 && self.mate[w] == NONE {
                self.mate[v] = w;
                self.mate[w] = v;
            }
        }
        Ok(())
    }

    /// All free vertices grow alternating trees at once; an augmentation dissolves only the two
    /// trees it joins, the others keep growing (no stage restarts).
    fn solve(&mut self) -> Result<(), NoPerfectMatching> {
        self.jump_start()?;
        let mut free = 0;
        for v in 0..self.n {
            if self.mate[v] == NONE {
                free += 1;
                self.assign_label(v, S, NO_EDGE, v);
            }
        }
        while free > 0 {
            if let Some((v, w)) = self.grow()? {
                let roots = [self.tree_of[self.inblossom[v]], self.tree_of[self.inblossom[w]]];
                self.augment(v, w);
                self.dissolve(roots);
                free -= 2;
            }
        }
        Ok(())
    }

    fn assign_label(&mut self, w: usize, t: u8, e: (usize, usize), root: usize) {
        let b = self.inblossom[w];
        self.label[w] = t;
        self.label[b] = t;
        self.labeledge[w] = e;
        self.labeledge[b] = e;
        self.bestedge[w] = NONE;
        self.bestedge[b] = NONE;
        self.tree_of[b] = root;
        self.tree_members[root].push(b);
        self.stamp[b] = self.ds;
        if t == S {
            let mut buf = std::mem::take(&mut self.buf);
            buf.clear();
            self.leaves(b, &mut buf);
            self.queue.extend_from_slice(&buf);
            self.buf = buf;
        } else {
            if b >= self.n {
                self.heap.push(Reverse((self.dual[b] + self.ds, 4, b, 0)));
            }
            let base = self.base[b];
            let m = self.mate[base];
            self.assign_label(m, S, (base, m), root);
        }
    }

    /// Scans S vertices and makes dual steps until an augmenting edge (v, w) is tight.
    fn grow(&mut self) -> Result<Option<(usize, usize)>, NoPerfectMatching> {
        while let Some(v) = self.queue.pop() {
            if self.label[self.inblossom[v]] != S {
                continue; // Its tree was dissolved after it was queued.
            }
            for idx in self.adj_start[v]..self.adj_start[v + 1] {
                let k = self.adj[idx];
                let w = self.other(k, v);
                let (bv, bw) = (self.inblossom[v], self.inblossom[w]);
                if bv == bw {
                    continue;
                }
                let ks = self.slack(k);
                match self.label[bw] {
                    FREE if ks <= 0 => {
                        let root = self.tree_of[bv];
                        self.assign_label(w, T, (v, w), root);
                    }
                    FREE if self.bestedge[w] == NONE || ks < self.slack(self.bestedge[w]) => {
                        self.push_vertex_best(w, k);
                    }
                    S if ks <= 0 => match self.scan_blossom(v, w) {
                        Some(base) => self.add_blossom(base, v, w),
                        None => return Ok(Some((v, w))),
                    },
                    S => {
                        let b = self.inblossom[v];
                        if self.bestedge[b] == NONE || ks < self.slack(self.bestedge[b]) {
                            self.push_blossom_best(b, k);
                        }
                    }
                    _ => {} // T: found again when its blossom expands or its tree dissolves.
                }
            }
        }
        self.dual_step()?;
        Ok(None)
    }

    /// The S-side outer blossom of edge k if both ends are in different S-blossoms.
    fn s_s_edge(&self, k: usize) -> bool {
        let (u, v, _) = self.edges[k];
        let (bu, bv) = (self.inblossom[u], self.inblossom[v]);
        bu != bv && self.label[bu] == S && self.label[bv] == S
    }

    /// Least-slack edge from vertex x (outside S-blossoms) to an S vertex.
    fn rescan_vertex(&mut self, x: usize) {
        let bx = self.inblossom[x];
        let mut best = NONE;
        for idx in self.adj_start[x]..self.adj_start[x + 1] {
            let k = self.adj[idx];
            let bw = self.inblossom[self.other(k, x)];
            if bw != bx && self.label[bw] == S && (best == NONE || self.slack(k) < self.slack(best)) {
                best = k;
            }
        }
        self.bestedge[x] = NONE;
        if best != NONE {
            self.push_vertex_best(x, best);
        }
    }

    /// Least-slack edge from S-blossom b to another S-blossom, from all its vertices.
    fn rescan_blossom(&mut self, b: usize) {
        let mut lv = Vec::new();
        self.leaves(b, &mut lv);
        let mut best = NONE;
        for &x in &lv {
            for idx in self.adj_start[x]..self.adj_start[x + 1] {
                let k = self.adj[idx];
                if self.s_s_edge(k) && (best == NONE || self.slack(k) < self.slack(best)) {
                    best = k;
                }
            }
        }
        self.bestlist[b] = None;
        self.push_blossom_best(b, best);
    }

    /// The next dual-step event: (2) an S–free edge, (3) an S–S edge gets tight, (4) a
    /// T-blossom's z reaches 0. Moves `ds` there (every forest dual at once) and acts.
    fn dual_step(&mut self) -> Result<(), NoPerfectMatching> {
        while let Some(Reverse((key, kind, id, k))) = self.heap.pop() {
            let cur = match kind {
                2 => {
                    if self.label[self.inblossom[id]] != FREE || self.bestedge[id] != k {
                        continue;
                    }
                    if self.label[self.inblossom[self.other(k, id)]] != S {
                        self.rescan_vertex(id);
                        continue;
                    }
                    self.slack(k) + self.ds
                }
                3 => {
                    if !self.is_outer(id) || self.label[id] != S || self.bestedge[id] != k {
                        continue;
                    }
                    if !self.s_s_edge(k) {
                        self.rescan_blossom(id);
                        continue;
                    }
                    self.slack(k) / 2 + self.ds
                }
                _ => {
                    if !self.is_outer(id) || self.label[id] != T {
                        continue;
                    }
                    self.dual[id] + self.stamp[id]
                }
            };
            if cur != key {
                self.heap.push(Reverse((cur, kind, id, k)));
                continue;
            }
            debug_assert!(key >= self.ds);
            self.ds = key;
            // Debug builds check dual feasibility after every step on small graphs.
            #[cfg(debug_assertions)]
            if self.n <= 16 {
                for e in 0..self.edges.len() {
                    let (u, v, _) = self.edges[e];
                    if self.inblossom[u] != self.inblossom[v] {
                        assert!(
                            self.slack(e) >= 0,
                            "after step kind {kind} id {id} edge {u}-{v} slack {} labels {} {} inbl {} {}",
                            self.slack(e),
                            self.label[self.inblossom[u]],
                            self.label[self.inblossom[v]],
                            self.inblossom[u],
                            self.inblossom[v]
                        );
                    }
                }
            }
            match kind {
                2 | 3 => {
                    let (u, v, _) = self.edges[k];
                    self.queue.push(if self.label[self.inblossom[u]] == S { u } else { v });
                }
                _ => self.expand_blossom(id),
            }
            return Ok(());
        }
        Err(NoPerfectMatching)
    }

    /// After an augmentation: the two trees it joined lose their labels; their vertices look
    /// again for edges to the S vertices of the other trees.
    fn dissolve(&mut self, roots: [usize; 2]) {
        let mut verts = Vec::new();
        for r in roots {
            for b in std::mem::take(&mut self.tree_members[r]) {
                if !self.is_outer(b) || self.label[b] == FREE || self.tree_of[b] != r {
                    continue;
                }
                self.settle(b);
                self.label[b] = FREE;
                self.labeledge[b] = NO_EDGE;
                self.bestedge[b] = NONE;
                self.bestlist[b] = None;
                self.tree_of[b] = NONE;
                self.leaves(b, &mut verts);
            }
        }
        for &x in &verts {
            self.label[x] = FREE;
            self.labeledge[x] = NO_EDGE;
            self.bestedge[x] = NONE;
        }
        for &x in &verts {
            self.rescan_vertex(x);
        }
        // Best edges of the other trees' S-blossoms and of free vertices that end in the
        // dissolved trees are out of date (their slack stopped shrinking, and a dissolved vertex
        // labelled S again would revive them with too late a key): look again.
        self.mark_stamp += 1;
        for &x in &verts {
            self.mark[x] = self.mark_stamp;
        }
        let gone = |s: &Self, k: usize| k != NONE && (s.mark[s.edges[k].0] == s.mark_stamp || s.mark[s.edges[k].1] == s.mark_stamp);
        for &x in &verts {
            for idx in self.adj_start[x]..self.adj_start[x + 1] {
                let w = self.other(self.adj[idx], x);
                if self.mark[w] == self.mark_stamp {
                    continue;
                }
                let bw = self.inblossom[w];
                if self.label[bw] == FREE && gone(self, self.bestedge[w]) {
                    self.rescan_vertex(w);
                } else if self.label[bw] == S && gone(self, self.bestedge[bw]) {
                    self.rescan_blossom(bw);
                }
            }
        }
    }

    /// Traces from v and w to their roots; the first blossom both reach is the new base's,
    /// none when the trees differ (an augmenting path).
    fn scan_blossom(&mut self, v: usize, w: usize) -> Option<usize> {
        self.mark_stamp += 1;
        let (mut v, mut w) = (v, w);
        while v != NONE {
            let b = self.inblossom[v];
            if self.mark[b] == self.mark_stamp {
                return Some(self.base[b]);
            }
            self.mark[b] = self.mark_stamp;
            if self.labeledge[b].0 == NONE {
                v = NONE;
            } else {
                let bt = self.inblossom[self.labeledge[b].0];
                v = self.labeledge[bt].0;
            }
            if w != NONE {
                std::mem::swap(&mut v, &mut w);
            }
        }
        None
    }

    fn add_blossom(&mut self, base: usize, v: usize, w: usize) {
        let bb = self.inblossom[base];
        let (bv, bw) = (self.inblossom[v], self.inblossom[w]);
        for (mut c, end) in [(bv, bb), (bw, bb)] {
            loop {
                self.settle(c);
                if c == end {
                    break;
                }
                c = self.inblossom[self.labeledge[c].0];
            }
        }
        let b = self.free_ids.pop().expect("blossom ids");
        self.base[b] = base;
        self.parent[b] = NONE;
        self.parent[bb] = b;
        let mut childs = vec![bb];
        let mut ends = Vec::new();
        let (mut side, mut side_ends) = (Vec::new(), Vec::new());
        let mut c = bv;
        while c != bb {
            self.parent[c] = b;
            side.push(c);
            side_ends.push(self.labeledge[c]);
            c = self.inblossom[self.labeledge[c].0];
        }
        childs.extend(side.iter().rev());
        ends.extend(side_ends.iter().rev());
        ends.push((v, w));
        let mut c = bw;
        while c != bb {
            self.parent[c] = b;
            childs.push(c);
            let (x, y) = self.labeledge[c];
            ends.push((y, x));
            c = self.inblossom[x];
        }
        let root = self.tree_of[bb];
        self.label[b] = S;
        self.labeledge[b] = self.labeledge[bb];
        self.tree_of[b] = root;
        self.tree_members[root].push(b);
        self.dual[b] = 0;
        self.stamp[b] = self.ds;
        let mut buf = std::mem::take(&mut self.buf);
        buf.clear();
        for &c in &childs {
            self.leaves(c, &mut buf);
        }
        for &x in &buf {
            if self.label[self.inblossom[x]] == T {
                self.queue.push(x);
            }
            self.inblossom[x] = b;
        }
        self.buf = buf;
        // Least-slack edges to the other S-blossoms, merged from the children's.
        let mut found = Vec::new();
        for &ch in &childs {
            let list = match self.bestlist[ch].take() {
                Some(l) => l,
                None => {
                    let mut l = Vec::new();
                    let mut lv = Vec::new();
                    self.leaves(ch, &mut lv);
                    for &x in &lv {
                        l.extend_from_slice(&self.adj[self.adj_start[x]..self.adj_start[x + 1]]);
                    }
                    l
                }
            };
            for k in list {
                let (i, j, _) = self.edges[k];
                let o = if self.inblossom[i] == b { j } else { i };
                let bj = self.inblossom[o];
                if bj != b && self.label[bj] == S && (self.bestto[bj] == NONE || self.slack(k) < self.slack(self.bestto[bj])) {
                    if self.bestto[bj] == NONE {
                        found.push(bj);
                    }
                    self.bestto[bj] = k;
                }
            }
            self.bestedge[ch] = NONE;
        }
        let mut list = Vec::with_capacity(found.len());
        let mut best = NONE;
        for bj in found {
            let k = self.bestto[bj];
            self.bestto[bj] = NONE;
            if best == NONE || self.slack(k) < self.slack(best) {
                best = k;
            }
            list.push(k);
        }
        self.bestlist[b] = Some(list);
        self.childs[b] = childs;
        self.push_blossom_best(b, best);
        self.ends[b] = ends;
    }

    fn free_blossom(&mut self, b: usize) {
        self.childs[b].clear();
        self.ends[b].clear();
        self.label[b] = FREE;
        self.labeledge[b] = NO_EDGE;
        self.tree_of[b] = NONE;
        self.bestedge[b] = NONE;
        self.bestlist[b] = None;
        self.base[b] = NONE;
        self.parent[b] = NONE;
        self.dual[b] = 0;
        self.free_ids.push(b);
    }

    /// Expands T-blossom b (its z reached 0): the children on the even path from where it was
    /// entered to its base become T and S, the others unlabelled (and look for S neighbours).
    fn expand_blossom(&mut self, b: usize) {
        self.settle(b);
        let childs = std::mem::take(&mut self.childs[b]);
        let ends = std::mem::take(&mut self.ends[b]);
        let mut buf = Vec::new();
        for &s in &childs {
            self.parent[s] = NONE;
            buf.clear();
            self.leaves(s, &mut buf);
            for &x in &buf {
                self.inblossom[x] = s;
            }
        }
        let root = self.tree_of[b];
        let k = childs.len();
        let (x, w) = self.labeledge[b];
        let entry = self.inblossom[w];
        let mut j = childs.iter().position(|&c| c == entry).expect("entry child");
        let mut on_path = vec![false; k];
        let forward = j % 2 == 1;
        let mut edge = (x, w);
        // T children along the even path to the base child; each cascades to the S child
        // matched to it; the base child's mate is outside (already S): no cascade.
        while j != 0 {
            let (next_s, into_t) = if forward {
                let s = (j + 1) % k;
                (s, ends[s])
            } else {
                let s = j - 1;
                let (a, bb) = ends[s - 1];
                (s, (bb, a))
            };
            on_path[j] = true;
            on_path[next_s] = true;
            self.assign_label(edge.1, T, edge, root);
            edge = into_t;
            j = if forward { (next_s + 1) % k } else { next_s - 1 };
        }
        on_path[0] = true;
        let c0 = childs[0];
        self.label[c0] = T;
        self.label[edge.1] = T;
        self.labeledge[c0] = edge;
        self.labeledge[edge.1] = edge;
        self.bestedge[c0] = NONE;
        self.tree_of[c0] = root;
        self.tree_members[root].push(c0);
        self.stamp[c0] = self.ds;
        if c0 >= self.n {
            self.heap.push(Reverse((self.dual[c0] + self.ds, 4, c0, 0)));
        }
        self.free_blossom(b);
        buf.clear();
        for (i, &c) in childs.iter().enumerate() {
            if !on_path[i] {
                self.label[c] = FREE;
                self.labeledge[c] = NO_EDGE;
                self.tree_of[c] = NONE;
                self.bestedge[c] = NONE;
                self.leaves(c, &mut buf);
            }
        }
        for &v in &buf {
            self.label[v] = FREE;
        }
        for &v in &buf {
            self.rescan_vertex(v);
        }
    }

    /// Rematches inside blossom b so that its vertex v becomes the base.
    fn augment_blossom(&mut self, b: usize, v: usize) {
        let mut t = v;
        while self.parent[t] != b {
            t = self.parent[t];
        }
        if t >= self.n {
            self.augment_blossom(t, v);
        }
        let k = self.childs[b].len();
        let i = self.childs[b].iter().position(|&c| c == t).expect("child");
        if i != 0 {
            let mut flips = Vec::new();
            if i % 2 == 1 {
                let mut j = i + 1;
                while j < k {
                    flips.push(j);
                    j += 2;
                }
            } else {
                let mut j = i as isize - 2;
                while j >= 0 {
                    flips.push(j as usize);
                    j -= 2;
                }
            }
            for j in flips {
                let (a, bb) = self.ends[b][j];
                let (ca, cb) = (self.childs[b][j], self.childs[b][(j + 1) % k]);
                if ca >= self.n {
                    self.augment_blossom(ca, a);
                }
                if cb >= self.n {
                    self.augment_blossom(cb, bb);
                }
                self.mate[a] = bb;
                self.mate[bb] = a;
            }
            self.childs[b].rotate_left(i);
            self.ends[b].rotate_left(i);
        }
        self.base[b] = v;
    }

    fn augment(&mut self, v: usize, w: usize) {
        for (s0, j0) in [(v, w), (w, v)] {
            let (mut s, mut j) = (s0, j0);
            loop {
                let bs = self.inblossom[s];
                if bs >= self.n {
                    self.augment_blossom(bs, s);
                }
                self.mate[s] = j;
                let t = self.labeledge[bs].0;
                if t == NONE {
                    break;
                }
                let bt = self.inblossom[t];
                let (x, y) = self.labeledge[bt];
                if bt >= self.n {
                    self.augment_blossom(bt, y);
                }
                self.mate[y] = x;
                s = x;
                j = y;
            }
        }
    }

    fn result(&mut self) -> Matching {
        let n = self.n;
        for b in 0..2 * n {
            if self.is_outer(b) && self.label[b] != FREE {
                self.settle(b);
                self.label[b] = FREE;
            }
        }
        let mut cost = 0;
        for &(u, v, c) in &self.edges {
            if self.mate[u] == v {
                cost += c / DUAL_SCALE;
            }
        }
        // Odd sets: every live blossom, numbered in id order.
        let mut index = vec![NONE; 2 * n];
        let mut ids = Vec::new();
        for b in n..2 * n {
            if self.base[b] != NONE {
                index[b] = ids.len();
                ids.push(b);
            }
        }
        let mut d = Duals {
            total: self.dual[..n].to_vec(),
            vertex_set: vec![NONE; n],
            set_parent: ids.iter().map(|&b| if self.parent[b] == NONE { NONE } else { index[self.parent[b]] }).collect(),
            set_z: ids.iter().map(|&b| self.dual[b]).collect(),
            set_size: vec![0; ids.len()],
            set_z_up: vec![0; ids.len()],
            set_depth: vec![0; ids.len()],
        };
        for v in 0..n {
            if self.parent[v] != NONE {
                d.vertex_set[v] = index[self.parent[v]];
            }
        }
        // Parents before children: walk each top-level blossom downwards.
        let mut stack: Vec<usize> = ids.iter().copied().filter(|&b| self.parent[b] == NONE).collect();
        while let Some(b) = stack.pop() {
            let i = index[b];
            let p = d.set_parent[i];
            d.set_z_up[i] = d.set_z[i] + if p == NONE { 0 } else { d.set_z_up[p] };
            d.set_depth[i] = if p == NONE { 0 } else { d.set_depth[p] + 1 };
            let mut lv = Vec::new();
            self.leaves(b, &mut lv);
            d.set_size[i] = lv.len();
            stack.extend(self.childs[b].iter().copied().filter(|&c| c >= n));
        }
        Matching { mates: self.mate.clone(), cost, duals: d }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rng(seed: u64) -> impl FnMut() -> u64 {
        let mut s = seed;
        move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            s
        }
    }

    fn brute(n: usize, edges: &[(usize, usize, i64)]) -> Option<i64> {
        let mut c = vec![None; n * n];
        for &(u, v, w) in edges {
            if u != v {
                let old: Option<i64> = c[u * n + v];
                let w = old.map_or(w, |o| o.min(w));
                c[u * n + v] = Some(w);
                c[v * n + u] = Some(w);
            }
        }
        fn rec(n: usize, c: &[Option<i64>], used: &mut Vec<bool>) -> Option<i64> {
            let Some(a) = (0..n).find(|&i| !used[i]) else { return Some(0) };
            used[a] = true;
            let mut best: Option<i64> = None;
            for b in a + 1..n {
                if !used[b] {
                    if let Some(w) = c[a * n + b] {
                        used[b] = true;
                        if let Some(r) = rec(n, c, used) {
                            best = Some(best.map_or(w + r, |x: i64| x.min(w + r)));
                        }
                        used[b] = false;
                    }
                }
            }
            used[a] = false;
            best
        }
        rec(n, &c, &mut vec![false; n])
    }

    /// Mates form a perfect matching on the edges, duals feasible, matched edges tight, and
    /// Σy + Σz = cost.
    pub(crate) fn check(n: usize, edges: &[(usize, usize, i64)], m: &Matching) {
        for v in 0..n {
            assert_eq!(m.mates[m.mates[v]], v);
            assert_ne!(m.mates[v], v);
        }
        let mut cost = 0;
        let mut seen = vec![false; n];
        // Parallel edges: the cheapest is the one that counts (first after sorting).
        let mut edges: Vec<(usize, usize, i64)> = edges.iter().filter(|e| e.0 != e.1).map(|&(u, v, c)| (u.min(v), u.max(v), c)).collect();
        edges.sort_unstable();
        for &(u, v, c) in &edges {
            let r = m.duals.reduced_cost(u, v, c);
            assert!(r >= 0, "edge {u}-{v} reduced {r}");
            if m.mates[u] == v && !seen[u] {
                assert_eq!(r, 0, "matched {u}-{v} not tight");
                seen[u] = true;
                seen[v] = true;
                cost += c;
            }
        }
        assert_eq!(cost, m.cost);
        assert!(m.duals.set_z.iter().all(|&z| z >= 0));
        assert!(m.duals.set_size.iter().all(|&s| s % 2 == 1));
        assert_eq!(m.duals.objective(), DUAL_SCALE * m.cost, "strong duality");
    }

    #[test]
    fn equals_brute_force_on_small_graphs() {
        let mut r = rng(77);
        for round in 0..20000 {
            let n = 2 + (r() % 11) as usize;
            let density = 1 + r() % 4; // out of 4
            let maxc = [3, 10, 1000][round % 3];
            let mut edges = Vec::new();
            for u in 0..n {
                for v in u + 1..n {
                    if r() % 4 < density {
                        edges.push((u, v, (r() % maxc) as i64));
                    }
                }
            }
            let want = brute(n, &edges);
            match min_cost_perfect_matching(n, &edges) {
                Ok(m) => {
                    assert_eq!(Some(m.cost), want, "round {round} n {n} {edges:?}");
                    check(n, &edges, &m);
                }
                Err(_) => assert_eq!(want, None, "round {round} n {n} {edges:?}"),
            }
        }
    }

    #[test]
    fn equals_dense_blossom_on_random_sparse_graphs() {
        // Non-edges cost BIG in the dense solve: a dense optimum using one means no perfect
        // matching on the sparse graph.
        const BIG: i64 = 1 << 40;
        let mut r = rng(4242);
        for round in 0..300 {
            let n = 2 * (10 + (r() % 60) as usize);
            let deg = 2 + r() % 6;
            let mut edges = Vec::new();
            for u in 0..n {
                for _ in 0..deg {
                    let v = if r() % 3 == 0 { (r() % n as u64) as usize } else { (u + 1 + (r() % 5) as usize) % n };
                    edges.push((u, v, (r() % [5, 100, 100_000][round % 3]) as i64));
                }
            }
            let mut dense = vec![BIG; n * n];
            for &(u, v, c) in &edges {
                if u != v {
                    let (a, b) = (u.min(v), u.max(v));
                    dense[a * n + b] = dense[a * n + b].min(c);
                }
            }
            let mates = integer_blossom::min_weight_perfect_matching(&dense, n);
            let want: i64 = (0..n).filter(|&i| i < mates[i]).map(|i| dense[i * n + mates[i]]).sum();
            match min_cost_perfect_matching(n, &edges) {
                Ok(m) => {
                    assert_eq!(m.cost, want, "round {round}");
                    check(n, &edges, &m);
                }
                Err(_) => assert!(want >= BIG, "round {round}: missed a perfect matching"),
            }
        }
    }
}

//! Continuous printing (the *open* Chinese postman): per component, one nozzle walk that prints
//! every strut once and travels, without extruding, along the fewest millimetres of struts
//! ("deadhead"); the walk may start and end anywhere.
//!
//! The struts travelled are a shortest T-join: the odd-degree nodes are paired by their
//! shortest-path distance *in the graph*, except two, which become the walk's ends. Those two are
//! chosen by the matching itself: two virtual nodes, "start" and "end", are joined to every odd
//! node (at cost 0, or at the straight distance to the previous / next piece when the walks are
//! re-planned for the travel between pieces, [`replan`]) and not to each other; the odd nodes
//! matched to them are the ends. The pairing is exact (blossom: certified sparse, or dense) where
//! the work estimate allows, else greedy + 2-opt with a dual lower bound on the open problem
//! ([`super::matching::open_lower_bound`]). The struts along each pair's shortest path are
//! duplicated (duplicates of one strut cancel in pairs) and an Euler trail of the augmented
//! multigraph walked from the start (Hierholzer, preferring printing edges, then the straightest
//! continuation). It ends at the end node; every duplicated strut is walked once, so the
//! deadhead is exactly the pairing's length. The walk becomes extrusion paths split at the
//! duplicated runs; those runs are the next path's `approach` route.

use super::euler::{circuits, odd_by_component, walk_nodes, AugEdge};
use super::graph::Graph;
use super::matching::{choose_method, exact_units, PairingMethod, CANDIDATES_PER_NODE};
use super::Chain;
use crate::geom::DVec2;
use std::cell::RefCell;
use std::cmp::Ordering;
use std::collections::BinaryHeap;

#[derive(Clone, Copy, PartialEq)]
struct Item {
    d: f64,
    v: usize,
}
impl Eq for Item {}
impl Ord for Item {
    fn cmp(&self, o: &Self) -> Ordering {
        // Min-heap by distance, then node.
        o.d.total_cmp(&self.d).then(o.v.cmp(&self.v))
    }
}
impl PartialOrd for Item {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}

/// Reusable single-source Dijkstra.
struct Dijkstra {
    dist: Vec<f64>,
    pred: Vec<usize>,
    done: Vec<bool>,
    touched: Vec<usize>,
    heap: BinaryHeap<Item>,
}

impl Dijkstra {
    fn new(n: usize) -> Dijkstra {
        Dijkstra { dist: vec![f64::INFINITY; n], pred: vec![usize::MAX; n], done: vec![false; n], touched: Vec::new(), heap: BinaryHeap::new() }
    }

    fn reset(&mut self) {
        for &v in &self.touched {
            self.dist[v] = f64::INFINITY;
            self.pred[v] = usize::MAX;
            self.done[v] = false;
        }
        self.touched.clear();
        self.heap.clear();
    }

    /// Settles nodes from `src` in distance order, calling `visit(node, dist)` on each; stops
    /// when `visit` returns false or the component is exhausted.
    fn run(&mut self, g: &Graph, src: usize, visit: &mut dyn FnMut(usize, f64) -> bool) {
        self.reset();
        self.dist[src] = 0.0;
        self.touched.push(src);
        self.heap.push(Item { d: 0.0, v: src });
        // Nodes popped and edges relaxed (the growth checks count them).
        let mut steps = 0usize;
        while let Some(Item { d, v }) = self.heap.pop() {
            steps += 1;
            if self.done[v] || d > self.dist[v] {
                continue;
            }
            self.done[v] = true;
            if !visit(v, d) {
                break;
            }
            steps += g.incident(v).len();
            for &e in g.incident(v) {
                let w = g.other(e, v);
                let nd = d + g.edges[e].length;
                if nd < self.dist[w] {
                    if self.dist[w] == f64::INFINITY {
                        self.touched.push(w);
                    }
                    self.dist[w] = nd;
                    self.pred[w] = e;
                    self.heap.push(Item { d: nd, v: w });
                }
            }
        }
        crate::work::add(steps);
    }
}

/// Pair distances `(i, j, d)` (i < j) found so far, looked up by pair: the last one found for a
/// pair wins. A hash map of them was a cache miss per insert on big layers; a CSR by `i`
/// built at the first look-up keeps the candidate search sequential.
#[derive(Default)]
struct Known {
    found: Vec<(usize, usize, f64)>,
    /// Entries of `found` covered by the index.
    indexed: usize,
    start: Vec<usize>,
    /// `(j, d)` by `i`, each `i`'s sorted by `j`, one per pair.
    items: Vec<(usize, f64)>,
}

impl Known {
    fn get(&mut self, n: usize, i: usize, j: usize) -> Option<f64> {
        if self.indexed != self.found.len() {
            self.index(n);
        }
        let list = &self.items[self.start[i]..self.start[i + 1]];
        list.binary_search_by(|&(k, _)| k.cmp(&j)).ok().map(|x| list[x].1)
    }

    fn index(&mut self, n: usize) {
        // Stable by (i, j): the last of a run is the one found last.
        let mut order: Vec<usize> = (0..self.found.len()).collect();
        order.sort_by_key(|&x| (self.found[x].0, self.found[x].1));
        self.start = vec![0; n + 1];
        self.items.clear();
        for (k, &x) in order.iter().enumerate() {
            let (i, j, d) = self.found[x];
            if order.get(k + 1).is_some_and(|&y| (self.found[y].0, self.found[y].1) == (i, j)) {
                continue;
            }
            self.start[i + 1] += 1;
            self.items.push((j, d));
        }
        for i in 0..n {
            self.start[i + 1] += self.start[i];
        }
        self.indexed = self.found.len();
    }
}

/// Seconds per (source × component edge) of the all-pairs Dijkstra an exact solve needs (an
/// upper bound: each search stops when it has reached every odd node).
pub(crate) const DIJKSTRA_EDGE_SECONDS: f64 = 0.1e-6;

/// Nodes the 2-opt step's bounded Dijkstra settles at most when a pair's distance is not yet
/// known (keeps the heuristic linear when a leftover pair is long).
const SWAP_SEARCH_NODES: usize = 256;

/// Estimated seconds of pairing `odd` odd nodes of a component of `edges` edges exactly.
pub(crate) fn exact_seconds(odd: usize, edges: usize) -> f64 {
    super::matching::exact_seconds(odd) + odd as f64 * edges as f64 * DIJKSTRA_EDGE_SECONDS
}

/// Estimated seconds of a certified sparse pairing of `odd` odd nodes of a component of `edges`
/// edges: the solves, and per solve a candidate or violator Dijkstra from every odd node that
/// settles about [`super::matching::SPARSE_CANDIDATES`] odd nodes' share of the component.
pub(crate) fn sparse_seconds(odd: usize, edges: usize) -> f64 {
    super::matching::sparse_seconds(odd)
        + (super::matching::SPARSE_MAX_SOLVES * 2 * super::matching::SPARSE_CANDIDATES) as f64 * edges as f64 * DIJKSTRA_EDGE_SECONDS
}

/// Settled nodes per odd node and round the violator searches may use before giving up.
const VIOLATOR_SETTLED_PER_ODD: usize = 2000;

/// Certified minimum pairing of a component's odd `nodes` by graph distance (nm), proven for
/// every pair: candidates are the [`super::matching::SPARSE_CANDIDATES`] nearest odd nodes
/// along the struts; a pair (u, v) can violate the duals only if 4·d < Y_u + Y_v ≤ 2·max, so
/// each u runs a Dijkstra bounded by Y_u / 2 to the odd nodes ranked below it by (Y, index).
/// `extra`: every pair (i, j, nm) of the items beyond the odd nodes (the walk's virtual ends),
/// given in full, so the searches need not look for them. None when the searches hit their
/// bound or the candidates have no perfect matching.
fn sparse_pairing(graph: &Graph, nodes: &[usize], local: &[usize], dij: &mut Dijkstra, extra: Vec<(usize, usize, i64)>) -> Option<Vec<usize>> {
    let m = nodes.len();
    let k = super::matching::SPARSE_CANDIDATES.min(m - 1);
    let mut cands = Vec::with_capacity(m * k);
    for (i, &src) in nodes.iter().enumerate() {
        let mut found = 0;
        dij.run(graph, src, &mut |v, d| {
            let j = local[v];
            if v != src && j != NONE {
                cands.push((i.min(j), i.max(j), exact_units(d)));
                found += 1;
            }
            found < k
        });
    }
    let scale = super::blossom::DUAL_SCALE as f64;
    let mut find = |duals: &super::blossom::Duals, out: &mut Vec<(usize, usize, i64)>| -> bool {
        let mut budget = VIOLATOR_SETTLED_PER_ODD * m;
        for (u, &src) in nodes.iter().enumerate() {
            let yu = duals.total[u];
            if yu <= 0 {
                continue;
            }
            let r = (yu as f64 * 2.0 / scale + 1.0) / super::matching::EXACT_UNITS_PER_MM;
            let mut over = false;
            dij.run(graph, src, &mut |v, d| {
                if d > r {
                    return false;
                }
                if budget == 0 {
                    over = true;
                    return false;
                }
                budget -= 1;
                let j = local[v];
                if j != NONE && (duals.total[j], j) < (yu, u) {
                    let c = exact_units(d);
                    if duals.reduced_cost(u, j, c) < 0 {
                        out.push((u.min(j), u.max(j), c));
                    }
                }
                true
            });
            if over {
                return false;
            }
        }
        true
    };
    let items = extra.iter().map(|&(i, j, _)| i.max(j) + 1).fold(m, usize::max);
    // Every perfect matching uses one pair per extra item, so a constant added to their costs
    // changes no choice; the largest candidate's keeps them from being every node's cheapest
    // pair, which the blossom's start potentials (half the cheapest pair) would otherwise all
    // set to 0.
    let offset = cands.iter().map(|c| c.2).max().unwrap_or(0);
    cands.extend(extra.into_iter().map(|(i, j, c)| (i, j, c + offset)));
    super::blossom::certified_pairing(items, cands, &mut find, super::matching::SPARSE_MAX_SOLVES).ok().map(|c| c.matching.mates)
}

/// Where the walk of a component should begin and finish for the travel around it: near the
/// previous piece's end (`from`) and the next piece's start (`to`); `None`: anywhere.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Anchors {
    pub from: Option<DVec2>,
    pub to: Option<DVec2>,
}

impl Anchors {
    /// Straight travel into the walk at `start` and out of it at `end`, mm.
    fn cost(&self, start: DVec2, end: DVec2) -> f64 {
        self.from.map_or(0.0, |p| p.distance(start)) + self.to.map_or(0.0, |q| end.distance(q))
    }
}

/// One component's pairing: the odd nodes' partners (indices into its odd nodes; the two
/// virtual nodes are `m` (start) and `m + 1` (end)), the walk's start and end nodes.
#[derive(Clone, Debug)]
pub(crate) struct Pairing {
    partner: Vec<usize>,
    /// The walk's first node.
    start: usize,
    /// The walk's last node (its start when it is closed).
    end: usize,
    /// A proven lower bound on the component's shortest deadhead (None: solved exactly).
    bound: Option<f64>,
}

/// Continuous result: one chain (open walk) per component with struts, in component order;
/// each component's pairing; the total length of the struts travelled twice ("deadhead"), mm;
/// a proven lower bound on the shortest deadhead of open walks that print every strut
/// (the open Chinese postman's, per component), mm; whether the deadhead is that shortest.
pub(crate) struct PostmanPaths {
    pub chains: Vec<Chain>,
    pairings: Vec<Option<Pairing>>,
    pub pairing_mm: f64,
    pub lower_bound_mm: f64,
    pub optimal: bool,
}

/// The per-layer state of the pairing: reused searches and marks.
struct Solver<'g> {
    graph: &'g Graph,
    odd: Vec<Vec<usize>>,
    comp_edges: Vec<usize>,
    dij: Dijkstra,
    local: Vec<usize>,
    mark: Vec<u32>,
    stamp: u32,
}

const NONE: usize = usize::MAX;

impl<'g> Solver<'g> {
    fn new(graph: &'g Graph) -> Solver<'g> {
        let n = graph.nodes.len();
        let mut comp_edges = vec![0usize; graph.components];
        for e in &graph.edges {
            comp_edges[graph.component[e.a]] += 1;
        }
        Solver { graph, odd: odd_by_component(graph), comp_edges, dij: Dijkstra::new(n), local: vec![NONE; n], mark: vec![0; n], stamp: 0 }
    }

    /// Estimated seconds of an exact pairing of component `c` (the cheaper method) and the method
    /// chosen with `left` seconds left.
    fn method(&self, c: usize, left: f64) -> (PairingMethod, f64) {
        let m = self.odd[c].len() + 2;
        choose_method(exact_seconds(m, self.comp_edges[c]), sparse_seconds(m, self.comp_edges[c]), left)
    }

    /// Pairs component `c`'s odd nodes, leaving two as the walk's ends, by `method`, with the
    /// ends' costs from `anchors`. A component without odd nodes is a closed walk from the node
    /// that makes the anchors' travel least (the first node in index order on ties).
    fn pair(&mut self, c: usize, method: PairingMethod, anchors: Anchors, members: &[usize]) -> Pairing {
        let graph = self.graph;
        let nodes = std::mem::take(&mut self.odd[c]);
        let m = nodes.len();
        if m == 0 {
            let mut best = (f64::INFINITY, NONE);
            for &v in members {
                let p = graph.nodes[v];
                let t = anchors.cost(p, p);
                if t < best.0 {
                    best = (t, v);
                }
            }
            self.odd[c] = nodes;
            return Pairing { partner: Vec::new(), start: best.1, end: best.1, bound: None };
        }
        for (i, &v) in nodes.iter().enumerate() {
            self.local[v] = i;
        }
        let pos: Vec<DVec2> = nodes.iter().map(|&v| graph.nodes[v]).collect();
        // Cost of joining odd node i to the start (m) or the end (m + 1), mm.
        let end_cost = |i: usize, end: usize| -> f64 {
            let anchor = if end == m { anchors.from } else { anchors.to };
            anchor.map_or(0.0, |a| a.distance(pos[i]))
        };
        let (sparse, dense) = match method {
            PairingMethod::Sparse { dense_fallback } => (self.sparse(&nodes, &end_cost), dense_fallback),
            PairingMethod::Dense => (None, true),
            PairingMethod::Heuristic => (None, false),
        };
        let (partner, bound) = if let Some(p) = sparse {
            (p, None)
        } else if dense {
            (self.dense(&nodes, &end_cost), None)
        } else {
            self.heuristic(&nodes, &end_cost)
        };
        for &v in &nodes {
            self.local[v] = NONE;
        }
        let (start, end) = (nodes[partner[m]], nodes[partner[m + 1]]);
        self.odd[c] = nodes;
        Pairing { partner, start, end, bound }
    }

    /// Certified sparse pairing ([`sparse_pairing`]) with the two virtual ends.
    fn sparse(&mut self, nodes: &[usize], end_cost: &dyn Fn(usize, usize) -> f64) -> Option<Vec<usize>> {
        let m = nodes.len();
        let virtual_pairs: Vec<(usize, usize, i64)> =
            (0..m).flat_map(|i| [(i, m, exact_units(end_cost(i, m))), (i, m + 1, exact_units(end_cost(i, m + 1)))]).collect();
        sparse_pairing(self.graph, nodes, &self.local, &mut self.dij, virtual_pairs)
    }

    /// Dense exact pairing on all graph distances, the two virtual ends joined to every odd node
    /// and (at a cost no optimum can pay) to each other.
    fn dense(&mut self, nodes: &[usize], end_cost: &dyn Fn(usize, usize) -> f64) -> Vec<usize> {
        let (graph, local) = (self.graph, &self.local);
        let m = nodes.len();
        let w = m + 2;
        let mut dist = vec![0.0; w * w];
        for i in 0..m.saturating_sub(1) {
            let mut need = m - 1 - i;
            self.dij.run(graph, nodes[i], &mut |v, d| {
                let j = local[v];
                if j != NONE && j > i {
                    dist[i * w + j] = d;
                    need -= 1;
                }
                need > 0
            });
        }
        let mut worst = 0.0f64;
        for i in 0..m {
            dist[i * w + m] = end_cost(i, m);
            dist[i * w + m + 1] = end_cost(i, m + 1);
            for j in i + 1..w {
                worst = worst.max(dist[i * w + j]);
            }
        }
        // More than any perfect matching that leaves it out costs.
        dist[m * w + m + 1] = worst * w as f64 + 1.0;
        super::matching::exact_pairing(w, &dist)
    }

    /// Greedy + 2-opt: the closed pairing of the odd nodes, opened at the pair whose ends cost
    /// least against it, then improved with the virtual ends as items; the lower bound is the
    /// open problem's ([`super::matching::open_lower_bound`], ends at cost 0).
    fn heuristic(&mut self, nodes: &[usize], end_cost: &dyn Fn(usize, usize) -> f64) -> (Vec<usize>, Option<f64>) {
        let graph = self.graph;
        let m = nodes.len();
        let (local, mark) = (&self.local, &mut self.mark);
        let stamp = &mut self.stamp;
        // Graph distances found by the candidate searches, for the matching's improvement step.
        let known = RefCell::new(Known::default());
        let dij_cell = RefCell::new(&mut self.dij);
        let mut candidates = |active: &[usize]| -> Vec<(f64, usize, usize)> {
            *stamp += 1;
            for &i in active {
                mark[nodes[i]] = *stamp;
            }
            let k = CANDIDATES_PER_NODE.min(active.len() - 1);
            let mut out = Vec::with_capacity(active.len() * k);
            let mut d = dij_cell.borrow_mut();
            let mut known = known.borrow_mut();
            for &i in active {
                let src = nodes[i];
                let mut found = 0;
                d.run(graph, src, &mut |v, dist| {
                    if v != src && mark[v] == *stamp {
                        let j = local[v];
                        out.push((dist, i.min(j), i.max(j)));
                        known.found.push((i.min(j), i.max(j), dist));
                        found += 1;
                    }
                    found < k
                });
            }
            out
        };
        // Known distances, else a Dijkstra from i bounded by `limit`; the virtual ends' costs.
        let mut cost = |i: usize, j: usize, limit: f64| -> Option<f64> {
            let (i, j) = (i.min(j), i.max(j));
            if j >= m {
                return (i < m).then(|| end_cost(i, j)).filter(|&c| c < limit);
            }
            if let Some(d) = known.borrow_mut().get(m, i, j) {
                return (d < limit).then_some(d);
            }
            let (src, dst) = (nodes[i], nodes[j]);
            let mut reached = None;
            let mut settled = 0usize;
            dij_cell.borrow_mut().run(graph, src, &mut |v, d| {
                settled += 1;
                if d >= limit || settled > SWAP_SEARCH_NODES {
                    return false;
                }
                if v == dst {
                    reached = Some(d);
                    return false;
                }
                true
            });
            reached
        };
        let h = super::matching::min_pairing(m, &mut candidates, &mut cost);
        let y = super::matching::dual_potentials(m, &h.first, CANDIDATES_PER_NODE);
        let bound = super::matching::open_lower_bound(&y);
        // Open the closed pairing where the ends save the most.
        let (mut partner, mut pcost) = (h.partner, h.pair_cost);
        let mut best: Option<(f64, usize, usize)> = None;
        for a in 0..m {
            let b = partner[a];
            if b == NONE {
                continue;
            }
            let gain = pcost[a] - end_cost(a, m) - end_cost(b, m + 1);
            if best.is_none_or(|(g, _, _)| gain > g) {
                best = Some((gain, a, b));
            }
        }
        partner.extend([NONE, NONE]);
        pcost.extend([0.0, 0.0]);
        if let Some((_, a, b)) = best {
            partner[a] = m;
            partner[m] = a;
            partner[b] = m + 1;
            partner[m + 1] = b;
            pcost[a] = end_cost(a, m);
            pcost[m] = pcost[a];
            pcost[b] = end_cost(b, m + 1);
            pcost[m + 1] = pcost[b];
        }
        let mut pairs = h.seen;
        for i in 0..m {
            pairs.push((end_cost(i, m), i, m));
            pairs.push((end_cost(i, m + 1), i, m + 1));
        }
        super::matching::improve_pairing(m + 2, &mut partner, &mut pcost, &pairs, &mut cost);
        (partner, Some(bound))
    }
}

/// The nodes of every component (CSR: `start[c]..start[c + 1]` of `items`), in node order.
fn members(graph: &Graph) -> (Vec<usize>, Vec<usize>) {
    let mut start = vec![0usize; graph.components + 1];
    for &c in &graph.component {
        start[c + 1] += 1;
    }
    for c in 0..graph.components {
        start[c + 1] += start[c];
    }
    let mut fill = start.clone();
    let mut items = vec![0; graph.nodes.len()];
    for (v, &c) in graph.component.iter().enumerate() {
        items[fill[c]] = v;
        fill[c] += 1;
    }
    (start, items)
}

/// Open Chinese-postman walks of every component. Components are paired exactly (graph
/// distances, blossom: certified sparse or dense, whichever is estimated cheaper), in order,
/// while the estimated solves ([`sparse_seconds`], [`exact_seconds`]) fit in `exact_budget`
/// seconds (for the layer); the rest by the heuristic with a dual lower bound.
pub(crate) fn run(graph: &Graph, exact_budget: f64) -> PostmanPaths {
    let mut solver = Solver::new(graph);
    let (start, items) = members(graph);
    let mut left = exact_budget;
    let mut pairings = Vec::with_capacity(graph.components);
    for c in 0..graph.components {
        let (method, cost) = if solver.odd[c].is_empty() { (PairingMethod::Dense, 0.0) } else { solver.method(c, left) };
        left -= cost;
        pairings.push(Some(solver.pair(c, method, Anchors::default(), &items[start[c]..start[c + 1]])));
    }
    walks(&mut solver, pairings, None)
}

/// Re-plans the walks of a layer of several components printed in the order of `chains` (each
/// one component's walk, as [`run`] made it, maybe reversed) after `from` (the previous layer's
/// end): in that order, each component solved exactly before is paired again with its ends
/// joined to the previous walk's (new) end and the next walk's start at their straight distance, so the deadhead and the travel between pieces
/// are chosen together. The exact solves take at most `exact_budget` estimated seconds again;
/// components beyond it, and those paired by the heuristic, keep their walks. Returns the walks
/// in the same order and their deadhead; the lower bound stays [`run`]'s (`first`).
pub(crate) fn replan(graph: &Graph, first: &PostmanPaths, chains: &[Chain], from: Option<DVec2>, exact_budget: f64) -> PostmanPaths {
    let mut solver = Solver::new(graph);
    let (start, items) = members(graph);
    let comps: Vec<usize> = chains.iter().map(|ch| graph.component[ch.nodes[0]]).collect();
    let ends: Vec<[DVec2; 2]> = chains.iter().map(|ch| super::order::printed_ends(ch, graph)).collect();
    let mut pairings = first.pairings.clone();
    let mut left = exact_budget;
    let mut prev = from;
    for (k, &c) in comps.iter().enumerate() {
        let old = pairings[c].as_ref().expect("a chain's component is paired");
        let next = ends.get(k + 1).map(|e| e[0]);
        if old.bound.is_none() {
            let (method, cost) = if solver.odd[c].is_empty() { (PairingMethod::Dense, 0.0) } else { solver.method(c, left) };
            if method != PairingMethod::Heuristic {
                left -= cost;
                let p = solver.pair(c, method, Anchors { from: prev, to: next }, &items[start[c]..start[c + 1]]);
                pairings[c] = Some(p);
            }
        }
        let p = pairings[c].as_ref().expect("paired");
        // The walk as it will be printed: from its start to its end (a kept heuristic walk in
        // the direction it was printed).
        prev = Some(if p.bound.is_some() { ends[k][1] } else { graph.nodes[p.end] });
    }
    let mut out = walks(&mut solver, pairings, Some(first.lower_bound_mm));
    // Back into the printing order, each walk from its start.
    let mut by_comp: Vec<Option<Chain>> = vec![None; graph.components];
    for ch in out.chains.drain(..) {
        let c = graph.component[ch.nodes[0]];
        by_comp[c] = Some(ch);
    }
    for (k, &c) in comps.iter().enumerate() {
        let mut ch = by_comp[c].take().expect("each component walked once");
        if out.pairings[c].as_ref().is_some_and(|p| p.bound.is_some()) && chains[k].nodes[0] != ch.nodes[0] {
            ch.reverse();
        }
        out.chains.push(ch);
    }
    out
}

/// The walks of the pairings: the struts along each pair's shortest path duplicated (parity),
/// an Euler trail per component from its start. `bound`: the lower bound to report (else the
/// pairings' own).
fn walks(solver: &mut Solver, pairings: Vec<Option<Pairing>>, bound: Option<f64>) -> PostmanPaths {
    let graph = solver.graph;
    let mut aug: Vec<AugEdge> = graph.edges.iter().enumerate().map(|(i, e)| AugEdge { a: e.a, b: e.b, base: i, real: true }).collect();
    // Times each strut is duplicated: an even count cancels (the walk needs only parity).
    let mut duplicated = vec![0u32; graph.edges.len()];
    let mut starts = vec![NONE; graph.components];
    for (c, p) in pairings.iter().enumerate() {
        let Some(p) = p else { continue };
        starts[c] = p.start;
        let nodes = &solver.odd[c];
        let m = nodes.len();
        for (i, &j) in p.partner.iter().enumerate() {
            if j >= m || i >= m || i > j {
                continue;
            }
            let (src, dst) = (nodes[i], nodes[j]);
            let mut reached = false;
            solver.dij.run(graph, src, &mut |v, _| {
                reached = v == dst;
                !reached
            });
            if !reached {
                continue; // Unreachable: cannot happen within a component.
            }
            let mut v = dst;
            while v != src {
                let e = solver.dij.pred[v];
                duplicated[e] += 1;
                v = graph.other(e, v);
            }
        }
    }
    for (e, &k) in duplicated.iter().enumerate() {
        if k % 2 == 1 {
            let edge = &graph.edges[e];
            aug.push(AugEdge { a: edge.a, b: edge.b, base: e, real: false });
        }
    }
    let chains = trails(graph, &aug, &starts);
    // The deadhead as walked, per component.
    let mut walked = vec![0.0f64; graph.components];
    for ch in &chains {
        let c = graph.component[ch.nodes[0]];
        walked[c] += ch.edges.iter().zip(&ch.travel).filter(|(_, &t)| t).map(|(&e, _)| graph.edges[e].length).sum::<f64>();
    }
    let pairing_mm: f64 = walked.iter().sum();
    let mut lower_bound_mm: f64 = (0..graph.components).map(|c| pairings[c].as_ref().and_then(|p| p.bound).map_or(walked[c], |b| b.min(walked[c]))).sum();
    if let Some(b) = bound {
        lower_bound_mm = b;
    }
    lower_bound_mm = lower_bound_mm.min(pairing_mm);
    // In exact units: the optimum of the nm-rounded lengths.
    let optimal = exact_units(lower_bound_mm) >= exact_units(pairing_mm) - graph.components as i64;
    PostmanPaths { chains, pairings, pairing_mm, lower_bound_mm, optimal }
}

/// The Euler trail of each component of the augmented multigraph from its start (components
/// without a start are skipped), leading and trailing travelled runs dropped (a walk never
/// starts or ends travelling).
fn trails(graph: &Graph, aug: &[AugEdge], starts: &[usize]) -> Vec<Chain> {
    let from: Vec<usize> = starts.iter().copied().filter(|&s| s != NONE).collect();
    let mut chains = Vec::with_capacity(from.len());
    for (k, steps) in circuits(&graph.nodes, aug, &from).into_iter().enumerate() {
        if steps.is_empty() {
            continue;
        }
        let nodes = walk_nodes(aug, from[k], &steps);
        let first = steps.iter().position(|&e| aug[e].real).unwrap_or(0);
        let last = steps.iter().rposition(|&e| aug[e].real).map_or(0, |l| l + 1);
        let mut chain = Chain::default();
        chain.nodes.extend_from_slice(&nodes[first..=last]);
        for &e in &steps[first..last] {
            chain.edges.push(aug[e].base);
            chain.travel.push(!aug[e].real);
        }
        chains.push(chain);
    }
    chains
}

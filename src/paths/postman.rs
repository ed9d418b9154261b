//! Continuous printing (Chinese postman): per component, pair the odd-degree nodes by their
//! shortest-path distance *in the graph* (bounded Dijkstra candidates + the near-optimal
//! matching of [`super::matching`]), duplicate the edges along each pair's shortest path as
//! non-extruding "travel along struts", and walk an Euler circuit of the augmented multigraph
//! (Hierholzer, preferring printing edges, then the straightest continuation).
//!
//! The nozzle need not return to its start, so the circuit is cut open by dropping its
//! longest run of duplicated edges (first such run on ties): one open walk per component
//! that starts and ends printing. The walk becomes extrusion paths split at the remaining
//! duplicated runs; those runs are the next path's `approach` route. Every real edge is
//! printed exactly once.

use super::euler::{circuits, component_starts, odd_by_component, walk_nodes, AugEdge};
use super::graph::Graph;
use super::matching::{choose_method, exact_units, min_pairing, PairingMethod, CANDIDATES_PER_NODE};
use super::Chain;
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

/// Continuous result: one chain (open walk) per component; the total length of the
/// duplicated (travelled) struts before cutting the circuits open, mm (after duplicates of one
/// strut cancel in pairs: a T-join of the odd nodes); a proven lower bound on the shortest
/// such length (the Chinese postman's); whether it is that shortest.
pub(crate) struct PostmanPaths {
    pub chains: Vec<Chain>,
    pub pairing_mm: f64,
    pub lower_bound_mm: f64,
    pub optimal: bool,
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
/// None when the searches hit their bound or the candidates have no perfect matching.
fn sparse_pairing(graph: &Graph, nodes: &[usize], local: &[usize], dij: &mut Dijkstra) -> Option<Vec<usize>> {
    const NONE: usize = usize::MAX;
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
    super::blossom::certified_pairing(m, cands, &mut find, super::matching::SPARSE_MAX_SOLVES).ok().map(|c| c.matching.mates)
}

/// Chinese-postman walks of every component. Components are paired exactly (graph distances,
/// blossom: certified sparse or dense, whichever is estimated cheaper), in order, while the
/// estimated solves ([`sparse_seconds`], [`exact_seconds`]) fit in `exact_budget` seconds (for
/// the layer); the rest by the heuristic with a dual lower bound.
pub(crate) fn run(graph: &Graph, exact_budget: f64) -> PostmanPaths {
    const NONE: usize = usize::MAX;
    let n = graph.nodes.len();
    let mut aug: Vec<AugEdge> = graph.edges.iter().enumerate().map(|(i, e)| AugEdge { a: e.a, b: e.b, base: i, real: true }).collect();
    let odd = odd_by_component(graph);
    let mut dij = Dijkstra::new(n);
    let mut local = vec![NONE; n];
    let mut mark = vec![0u32; n];
    let mut stamp = 0u32;
    let mut comp_edges = vec![0usize; graph.components];
    for e in &graph.edges {
        comp_edges[graph.component[e.a]] += 1;
    }
    // Times each strut is duplicated: an even count cancels (the walk needs only parity).
    let mut duplicated = vec![0u32; graph.edges.len()];
    // Per component: proven lower bound (None: optimal, the travelled length itself).
    let mut bounds: Vec<Option<f64>> = vec![None; graph.components];
    let mut left = exact_budget;

    for (c, nodes) in odd.iter().enumerate() {
        if nodes.is_empty() {
            continue;
        }
        let m = nodes.len();
        for (i, &v) in nodes.iter().enumerate() {
            local[v] = i;
        }
        let (method, cost) = choose_method(exact_seconds(m, comp_edges[c]), sparse_seconds(m, comp_edges[c]), left);
        left -= cost;
        let (sparse, dense) = match method {
            PairingMethod::Sparse { dense_fallback } => (sparse_pairing(graph, nodes, &local, &mut dij), dense_fallback),
            PairingMethod::Dense => (None, true),
            PairingMethod::Heuristic => (None, false),
        };
        let partner = if let Some(p) = sparse {
            p
        } else if dense {
            let mut dist = vec![0.0; m * m];
            for i in 0..m.saturating_sub(1) {
                let mut need = m - 1 - i;
                dij.run(graph, nodes[i], &mut |v, d| {
                    let j = local[v];
                    if j != NONE && j > i {
                        dist[i * m + j] = d;
                        need -= 1;
                    }
                    need > 0
                });
            }
            super::matching::exact_pairing(m, &dist)
        } else {
            // Graph distances found by the candidate searches, for the matching's improvement step.
            let known = RefCell::new(Known::default());
            let dij_cell = RefCell::new(&mut dij);
            let mut candidates = |active: &[usize]| -> Vec<(f64, usize, usize)> {
                stamp += 1;
                for &i in active {
                    mark[nodes[i]] = stamp;
                }
                let k = CANDIDATES_PER_NODE.min(active.len() - 1);
                let mut out = Vec::with_capacity(active.len() * k);
                let mut d = dij_cell.borrow_mut();
                let mut known = known.borrow_mut();
                for &i in active {
                    let src = nodes[i];
                    let mut found = 0;
                    d.run(graph, src, &mut |v, dist| {
                        if v != src && mark[v] == stamp {
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
            // Known distances, else a Dijkstra from i bounded by `limit`.
            let mut cost = |i: usize, j: usize, limit: f64| -> Option<f64> {
                if let Some(d) = known.borrow_mut().get(m, i.min(j), i.max(j)) {
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
            let (partner, first) = min_pairing(m, &mut candidates, &mut cost);
            bounds[c] = Some(super::matching::dual_lower_bound(m, &first, CANDIDATES_PER_NODE));
            partner
        };
        // Duplicate the struts along each pair's shortest path.
        for (i, &j) in partner.iter().enumerate() {
            if j == NONE || i > j {
                continue;
            }
            let (src, dst) = (nodes[i], nodes[j]);
            let mut reached = false;
            dij.run(graph, src, &mut |v, _| {
                reached = v == dst;
                !reached
            });
            if !reached {
                continue; // Unreachable: cannot happen within a component.
            }
            let mut v = dst;
            while v != src {
                let e = dij.pred[v];
                duplicated[e] += 1;
                v = graph.other(e, v);
            }
        }
        for &v in nodes {
            local[v] = NONE;
        }
    }
    let mut travelled = vec![0.0f64; graph.components];
    for (e, &k) in duplicated.iter().enumerate() {
        if k % 2 == 1 {
            let edge = &graph.edges[e];
            travelled[graph.component[edge.a]] += edge.length;
            aug.push(AugEdge { a: edge.a, b: edge.b, base: e, real: false });
        }
    }
    let (mut pairing_mm, mut lower_bound_mm, mut optimal) = (0.0, 0.0, true);
    for c in 0..graph.components {
        pairing_mm += travelled[c];
        let lb = bounds[c].map_or(travelled[c], |b| b.min(travelled[c]));
        optimal &= lb >= travelled[c];
        lower_bound_mm += lb;
    }

    let starts = component_starts(graph, &odd);
    let mut chains = Vec::with_capacity(starts.len());
    for (c, circuit) in circuits(&graph.nodes, &aug, &starts).into_iter().enumerate() {
        if circuit.is_empty() {
            continue;
        }
        let nodes = walk_nodes(&aug, starts[c], &circuit);
        let len = circuit.len();
        // The longest (circular) run of duplicated edges: where the walk is cut open.
        let mut cut: Option<(usize, f64)> = None; // (index of the run's last edge, length)
        if let Some(real_at) = circuit.iter().position(|&e| aug[e].real) {
            let mut k = 0;
            while k < len {
                let i = (real_at + 1 + k) % len;
                if aug[circuit[i]].real {
                    k += 1;
                    continue;
                }
                let mut run_len = 0.0;
                let mut last = i;
                while k < len && !aug[circuit[(real_at + 1 + k) % len]].real {
                    last = (real_at + 1 + k) % len;
                    run_len += graph.edges[aug[circuit[last]].base].length;
                    k += 1;
                }
                if cut.is_none_or(|(_, l)| run_len > l) {
                    cut = Some((last, run_len));
                }
            }
        }
        let begin = cut.map_or(0, |(last, _)| (last + 1) % len);
        let mut chain = Chain::default();
        chain.nodes.push(nodes[begin]);
        for k in 0..len {
            let i = (begin + k) % len;
            chain.nodes.push(nodes[i + 1]);
            chain.edges.push(aug[circuit[i]].base);
            chain.travel.push(!aug[circuit[i]].real);
        }
        // Drop the trailing duplicated run (the cut).
        while chain.travel.last() == Some(&true) {
            chain.travel.pop();
            chain.edges.pop();
            chain.nodes.pop();
        }
        chains.push(chain);
    }
    PostmanPaths { chains, pairing_mm, lower_bound_mm, optimal }
}

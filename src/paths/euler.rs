//! Minimum number of paths: per component, pair the odd-degree nodes (near-optimal Euclidean
//! matching, [`super::matching`]), add the pairs as virtual edges, walk an Euler circuit
//! (Hierholzer, preferring real edges and then the straightest continuation) and cut it at
//! the virtual edges. That gives exactly max(1, odd/2) paths per component — the proven lower
//! bound — and every virtual edge is one free travel (when the paths are printed in circuit
//! order).
//!
//! Also home of the Hierholzer walk shared with [`super::postman`].

use super::graph::Graph;
use super::matching::{choose_method, pair_points};
use super::Chain;
use crate::geom::DVec2;

/// "No edge".
const NONE: usize = usize::MAX;

/// An edge of the augmented multigraph.
#[derive(Clone, Copy, Debug)]
pub(crate) struct AugEdge {
    pub a: usize,
    pub b: usize,
    /// The graph edge it prints or travels along; [`NONE`] for a virtual (free travel) edge.
    pub base: usize,
    /// Printed (a real edge) rather than a virtual edge or a duplicated travel.
    pub real: bool,
}

/// Euler circuits of a multigraph whose nodes all have even degree, one per start node
/// (one start per component). Each circuit is its edge sequence from the start.
/// At every node the walk prefers real edges, then the one straightest relative to the
/// incoming direction (largest cosine), then the lowest index.
pub(crate) fn circuits(pos: &[DVec2], edges: &[AugEdge], starts: &[usize]) -> Vec<Vec<usize>> {
    let n = pos.len();
    let (adj_start, adj) = super::graph::incidence(n, edges.iter().map(|e| (e.a, e.b)));
    let mut ptr: Vec<usize> = adj_start[..n].to_vec();
    let mut used = vec![false; edges.len()];
    let other = |e: usize, v: usize| if edges[e].a == v { edges[e].b } else { edges[e].a };

    let mut out = Vec::with_capacity(starts.len());
    let mut stack: Vec<(usize, usize)> = Vec::new();
    for &s in starts {
        let mut circuit = Vec::new();
        stack.clear();
        stack.push((s, NONE));
        while let Some(&(v, ein)) = stack.last() {
            while ptr[v] < adj_start[v + 1] && used[adj[ptr[v]]] {
                ptr[v] += 1;
            }
            let dir_in = if ein == NONE {
                DVec2::ZERO
            } else {
                let d = pos[v] - pos[other(ein, v)];
                let l = d.length();
                if l > 0.0 {
                    d / l
                } else {
                    DVec2::ZERO
                }
            };
            let mut pick = NONE;
            let mut key = (false, f64::NEG_INFINITY);
            for &e in &adj[ptr[v]..adj_start[v + 1]] {
                if used[e] {
                    continue;
                }
                let d = pos[other(e, v)] - pos[v];
                let l = d.length();
                let cos = if l > 0.0 { dir_in.dot(d) / l } else { 0.0 };
                let k = (edges[e].real, cos);
                if pick == NONE || (k.0 && !key.0) || (k.0 == key.0 && k.1 > key.1) {
                    pick = e;
                    key = k;
                }
            }
            if pick != NONE {
                used[pick] = true;
                stack.push((other(pick, v), pick));
            } else {
                stack.pop();
                if ein != NONE {
                    circuit.push(ein);
                }
            }
        }
        circuit.reverse();
        out.push(circuit);
    }
    out
}

/// The node sequence of a walk from `start` along `steps` (len + 1 nodes).
pub(crate) fn walk_nodes(edges: &[AugEdge], start: usize, steps: &[usize]) -> Vec<usize> {
    let mut nodes = Vec::with_capacity(steps.len() + 1);
    let mut v = start;
    nodes.push(v);
    for &e in steps {
        v = if edges[e].a == v { edges[e].b } else { edges[e].a };
        nodes.push(v);
    }
    nodes
}

/// Odd-degree nodes grouped by component, in node order.
pub(crate) fn odd_by_component(graph: &Graph) -> Vec<Vec<usize>> {
    let mut odd = vec![Vec::new(); graph.components];
    for v in 0..graph.nodes.len() {
        if graph.degree(v) % 2 == 1 {
            odd[graph.component[v]].push(v);
        }
    }
    odd
}

/// One start node per component: its first odd node, else its lowest node.
pub(crate) fn component_starts(graph: &Graph, odd: &[Vec<usize>]) -> Vec<usize> {
    let mut starts = vec![NONE; graph.components];
    for v in 0..graph.nodes.len() {
        let c = graph.component[v];
        if starts[c] == NONE {
            starts[c] = v;
        }
    }
    for (c, o) in odd.iter().enumerate() {
        if let Some(&v) = o.first() {
            starts[c] = v;
        }
    }
    starts
}

/// Euler result: paths in circuit order (component by component), the total length of the
/// odd-node pairing (the virtual edges), mm, a proven lower bound on it, and whether it is
/// optimal (every component solved exactly or at its bound).
pub(crate) struct EulerPaths {
    pub chains: Vec<Chain>,
    pub pairing_mm: f64,
    pub lower_bound_mm: f64,
    pub optimal: bool,
}

/// Minimum-path decomposition of every component. Components are paired exactly, in order,
/// while the estimated exact solves (the cheaper of [`super::matching::sparse_seconds`] and
/// [`super::matching::exact_seconds`]) fit in `exact_seconds` (for the layer); the rest by the
/// heuristic.
pub(crate) fn run(graph: &Graph, exact_seconds: f64) -> EulerPaths {
    let mut aug: Vec<AugEdge> = graph.edges.iter().enumerate().map(|(i, e)| AugEdge { a: e.a, b: e.b, base: i, real: true }).collect();
    let odd = odd_by_component(graph);
    let mut pairing_mm = 0.0;
    let mut lower_bound_mm = 0.0;
    let mut optimal = true;
    let mut left = exact_seconds;
    for nodes in &odd {
        if nodes.is_empty() {
            continue;
        }
        let pts: Vec<DVec2> = nodes.iter().map(|&v| graph.nodes[v]).collect();
        let n = pts.len();
        let (method, cost) = choose_method(super::matching::exact_seconds(n), super::matching::sparse_seconds(n), left);
        left -= cost;
        let p = pair_points(&pts, method);
        pairing_mm += p.total;
        lower_bound_mm += p.lower_bound;
        optimal &= p.optimal;
        for (i, j) in p.pairs {
            aug.push(AugEdge { a: nodes[i], b: nodes[j], base: NONE, real: false });
        }
    }
    let starts = component_starts(graph, &odd);
    let mut chains = Vec::new();
    for (c, circuit) in circuits(&graph.nodes, &aug, &starts).into_iter().enumerate() {
        let nodes = walk_nodes(&aug, starts[c], &circuit);
        let Some(first_virtual) = circuit.iter().position(|&e| !aug[e].real) else {
            if !circuit.is_empty() {
                let edges: Vec<usize> = circuit.iter().map(|&e| aug[e].base).collect();
                let travel = vec![false; edges.len()];
                chains.push(Chain { nodes, edges, travel });
            }
            continue;
        };
        // Rotate to start just after a virtual edge, then split at the virtual edges.
        let len = circuit.len();
        let mut cur = Chain::default();
        for k in 0..len {
            let i = (first_virtual + 1 + k) % len;
            let e = circuit[i];
            if !aug[e].real {
                if !cur.edges.is_empty() {
                    chains.push(std::mem::take(&mut cur));
                }
                continue;
            }
            if cur.nodes.is_empty() {
                cur.nodes.push(nodes[i]);
            }
            cur.nodes.push(nodes[i + 1]);
            cur.edges.push(aug[e].base);
            cur.travel.push(false);
        }
        if !cur.edges.is_empty() {
            chains.push(cur);
        }
    }
    EulerPaths { chains, pairing_mm, lower_bound_mm, optimal }
}

//! GIPPO (the paper's Algorithm 1): randomised greedy growth of paths from both extremities.
//!
//! Per iteration, until every edge is used: start a path at a uniformly random *incomplete*
//! node (one with unused edges); then repeatedly look at the unused edges of both path
//! extremities and extend at the one whose neighbour is farthest (`gippo_max`) or closest
//! (`gippo_min`); lengths equal within [`TIE_MM`] are ties, broken uniformly by the seeded RNG
//! (reservoir sampling). The path stops when neither extremity has an unused edge. Each
//! solution is scored by equation 1; the best (first best on equal scores) is kept and its
//! paths are sorted longest → shortest (by segments, then length).
//!
//! The iteration loop allocates nothing: all buffers are sized once and reset per iteration.

use super::graph::Graph;
use super::Chain;
use rand_core::Rng;
use rand_pcg::Pcg64;

/// Neighbour distances closer than this are ties, mm.
pub const TIE_MM: f64 = 1e-9;

/// GIPPO's result for one layer.
pub(crate) struct Solution {
    /// Paths of the best solution, longest first.
    pub chains: Vec<Chain>,
    /// Equation 1 of the best solution.
    pub score: f64,
    /// Equation 1 of every iteration.
    pub iteration_scores: Vec<f64>,
}

/// Uniform integer in 0..n (n > 0), by multiply-shift: identical on every target.
#[inline]
pub(crate) fn below(rng: &mut Pcg64, n: usize) -> usize {
    ((rng.next_u64() as u128 * n as u128) >> 64) as usize
}

/// A flat solution: edges of every path in order, path offsets, first node of every path.
#[derive(Default)]
struct Flat {
    edges: Vec<u32>,
    starts: Vec<u32>,
    first: Vec<u32>,
}

impl Flat {
    fn clear(&mut self) {
        self.edges.clear();
        self.starts.clear();
        self.first.clear();
    }
}

/// Runs `iterations` (≥ 1) GIPPO iterations.
pub(crate) fn run(graph: &Graph, iterations: u32, maximise: bool, rng: &mut Pcg64) -> Solution {
    let n = graph.nodes.len();
    let m = graph.edges.len();
    if m == 0 {
        return Solution { chains: Vec::new(), score: 0.0, iteration_scores: Vec::new() };
    }
    let mut iteration_scores = Vec::with_capacity(iterations as usize);
    let total_length = graph.total_length();
    let degree: Vec<u32> = (0..n).map(|v| graph.degree(v) as u32).collect();
    // Compact adjacency: (edge, other end, length) per incidence, CSR by node.
    let mut adj_start: Vec<u32> = Vec::with_capacity(n + 1);
    let mut adj: Vec<(u32, u32, f64)> = Vec::with_capacity(2 * m);
    for v in 0..n {
        adj_start.push(adj.len() as u32);
        for &e in graph.incident(v) {
            adj.push((e as u32, graph.other(e, v) as u32, graph.edges[e].length));
        }
    }
    adj_start.push(adj.len() as u32);

    let mut used = vec![false; m];
    let mut free = degree.clone();
    let mut incomplete: Vec<u32> = Vec::with_capacity(n);
    let mut pos = vec![0u32; n];
    let mut front: Vec<u32> = Vec::with_capacity(m);
    let mut back: Vec<u32> = Vec::with_capacity(m);
    let mut cur = Flat::default();
    let mut best = Flat::default();
    cur.edges.reserve(m);
    best.edges.reserve(m);
    let mut best_score = f64::NEG_INFINITY;

    for _ in 0..iterations {
        used.fill(false);
        free.copy_from_slice(&degree);
        incomplete.clear();
        for v in 0..n {
            if degree[v] > 0 {
                pos[v] = incomplete.len() as u32;
                incomplete.push(v as u32);
            }
        }
        cur.clear();
        let mut weighted = 0.0;
        let mut paths = 0usize;

        while !incomplete.is_empty() {
            let start = incomplete[below(rng, incomplete.len())] as usize;
            let (mut fnode, mut bnode) = (start, start);
            front.clear();
            back.clear();
            let mut length = 0.0;
            loop {
                // Candidate (at_back, edge, length) over both extremities.
                let mut pick: Option<(bool, usize, usize, f64)> = None;
                let mut ties = 0u64;
                for (at_back, ext) in [(true, bnode), (false, fnode)] {
                    if !at_back && fnode == bnode {
                        break;
                    }
                    if free[ext] == 0 {
                        continue;
                    }
                    for &(e, w, len) in &adj[adj_start[ext] as usize..adj_start[ext + 1] as usize] {
                        let (e, w) = (e as usize, w as usize);
                        if used[e] {
                            continue;
                        }
                        match pick {
                            None => {
                                pick = Some((at_back, e, w, len));
                                ties = 1;
                            }
                            Some((_, _, _, bl)) => {
                                let better = if maximise { len > bl + TIE_MM } else { len < bl - TIE_MM };
                                if better {
                                    pick = Some((at_back, e, w, len));
                                    ties = 1;
                                } else if (len - bl).abs() <= TIE_MM {
                                    ties += 1;
                                    if below(rng, ties as usize) == 0 {
                                        pick = Some((at_back, e, w, len));
                                    }
                                }
                            }
                        }
                    }
                }
                let Some((at_back, e, w, len)) = pick else { break };
                used[e] = true;
                length += len;
                let ext = if at_back { bnode } else { fnode };
                for v in [ext, w] {
                    free[v] -= 1;
                    if free[v] == 0 {
                        // Swap-remove from the incomplete list.
                        let p = pos[v] as usize;
                        let last = *incomplete.last().expect("node listed");
                        incomplete[p] = last;
                        pos[last as usize] = p as u32;
                        incomplete.pop();
                    }
                }
                if at_back {
                    back.push(e as u32);
                    bnode = w;
                } else {
                    front.push(e as u32);
                    fnode = w;
                }
            }
            // Path = reverse(front) ++ back, starting at the front extremity.
            cur.starts.push(cur.edges.len() as u32);
            cur.first.push(fnode as u32);
            cur.edges.extend(front.iter().rev());
            cur.edges.extend_from_slice(&back);
            let segments = front.len() + back.len();
            weighted += length * segments as f64;
            paths += 1;
        }
        let score = weighted / (total_length * paths as f64);
        iteration_scores.push(score);
        if score > best_score {
            best_score = score;
            std::mem::swap(&mut cur, &mut best);
        }
    }

    // Best solution → chains, longest first (segments, then length; stable).
    let mut chains = Vec::with_capacity(best.starts.len());
    for (i, &s) in best.starts.iter().enumerate() {
        let end = best.starts.get(i + 1).map_or(best.edges.len(), |&x| x as usize);
        let edges: Vec<usize> = best.edges[s as usize..end].iter().map(|&e| e as usize).collect();
        let mut nodes = Vec::with_capacity(edges.len() + 1);
        let mut v = best.first[i] as usize;
        nodes.push(v);
        for &e in &edges {
            v = graph.other(e, v);
            nodes.push(v);
        }
        let travel = vec![false; edges.len()];
        chains.push(Chain { nodes, edges, travel });
    }
    super::order::sort_longest_first(&mut chains, graph);
    Solution { chains, score: best_score, iteration_scores }
}

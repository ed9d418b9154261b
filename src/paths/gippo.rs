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

/// One slot of the node records (see [`run`]): a node's header, then one slot per incidence.
#[derive(Clone, Copy)]
struct Slot {
    /// Header: the degree. Incidence: the other end's record.
    a: u32,
    /// Header: the node's place in the incomplete list. Incidence: the edge, with [`USED`] set
    /// once it is in a path of the current iteration.
    b: u32,
    /// Header: the node's unused edges (a small whole number). Incidence: the edge's length.
    len: f64,
}

/// The bit of an incidence's edge marking it used in the current iteration (edges number far
/// fewer than 2³¹: a layer is limited to a few million).
const USED: u32 = 1 << 31;

/// Runs `iterations` (≥ 1) GIPPO iterations.
pub(crate) fn run(graph: &Graph, iterations: u32, maximise: bool, rng: &mut Pcg64) -> Solution {
    run_observed(graph, iterations, maximise, rng, &mut ())
}

/// Watches a GIPPO run: told of every new best-so-far solution (see [`Recorder`]). The unit
/// observer watches nothing and costs nothing (its calls are compiled away).
pub(crate) trait Observer {
    /// A new best at `iteration` (0-based) with `score`: does the observer want its paths?
    fn wants(&mut self, iteration: u32, score: f64) -> bool;
    /// The paths of the best so far (longest first), when [`Observer::wants`] said so.
    fn record(&mut self, iteration: u32, score: f64, chains: Vec<Chain>);
}

impl Observer for () {
    #[inline(always)]
    fn wants(&mut self, _: u32, _: f64) -> bool {
        false
    }
    #[inline(always)]
    fn record(&mut self, _: u32, _: f64, _: Vec<Chain>) {}
}

/// One recorded best-so-far solution of a GIPPO run.
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// Iteration it was found at (0-based).
    pub iteration: u32,
    /// Its equation 1 score.
    pub score: f64,
    /// Its paths, longest first: edges of every path in order, one after the other.
    pub edges: Vec<u32>,
    /// Where each path starts in `edges`.
    pub starts: Vec<u32>,
    /// First node of every path.
    pub first: Vec<u32>,
}

impl Frame {
    /// Bytes it holds (its arrays and itself).
    pub fn bytes(&self) -> usize {
        std::mem::size_of::<Frame>() + 4 * (self.edges.len() + self.starts.len() + self.first.len())
    }

    /// Paths: (first node, edges).
    pub fn paths(&self) -> impl Iterator<Item = (usize, &[u32])> + '_ {
        self.starts.iter().enumerate().map(move |(i, &s)| {
            let end = self.starts.get(i + 1).map_or(self.edges.len(), |&x| x as usize);
            (self.first[i] as usize, &self.edges[s as usize..end])
        })
    }

    fn of(iteration: u32, score: f64, chains: &[Chain]) -> Frame {
        let mut f = Frame { iteration, score, edges: Vec::new(), starts: Vec::with_capacity(chains.len()), first: Vec::with_capacity(chains.len()) };
        f.edges.reserve(chains.iter().map(|c| c.edges.len()).sum());
        for c in chains {
            f.starts.push(f.edges.len() as u32);
            f.first.push(c.nodes.first().copied().unwrap_or(0) as u32);
            f.edges.extend(c.edges.iter().map(|&e| e as u32));
        }
        f
    }
}

/// Records the best-so-far solutions of a run, at most `cap` of them: every one when there
/// are no more, else the first, the last and evenly spaced ones between (by improvement
/// count). Each improvement whose number is a multiple of the stride is kept; when `cap` are
/// kept and another comes, every other one goes and the stride doubles. The latest
/// improvement is held aside until a later one replaces it, and closes the record (in place of
/// the last kept one when full). Memory: at most `cap` frames plus the one aside.
pub(crate) struct Recorder {
    cap: usize,
    stride: usize,
    improvements: usize,
    /// Kept frames, in iteration order.
    frames: Vec<Frame>,
    /// The latest improvement when it is not in `frames`.
    latest: Option<Frame>,
}

impl Recorder {
    /// A recorder of at most `cap` (≥ 2, raised to 2) frames.
    pub fn new(cap: usize) -> Recorder {
        Recorder { cap: cap.max(2), stride: 1, improvements: 0, frames: Vec::new(), latest: None }
    }

    /// Improvements seen.
    pub fn improvements(&self) -> usize {
        self.improvements
    }

    /// The frames kept, in iteration order: the first improvement, evenly spaced ones, the last.
    pub fn finish(mut self) -> Vec<Frame> {
        if let Some(f) = self.latest.take() {
            // The last improvement replaces the last kept one when the record is full.
            if self.frames.len() >= self.cap {
                self.frames.pop();
            }
            self.frames.push(f);
        }
        self.frames
    }
}

impl Observer for Recorder {
    fn wants(&mut self, _: u32, _: f64) -> bool {
        // Every improvement might be the last one.
        true
    }

    fn record(&mut self, iteration: u32, score: f64, chains: Vec<Chain>) {
        let k = self.improvements;
        self.improvements += 1;
        let frame = Frame::of(iteration, score, &chains);
        if k % self.stride != 0 {
            self.latest = Some(frame);
            return;
        }
        self.latest = None;
        if self.frames.len() >= self.cap {
            // Full: keep improvements 0, 2·stride, 4·stride, … (every other frame); this one
            // is kept too when it falls on the doubled stride, else held aside as the latest.
            let mut i = 0;
            self.frames.retain(|_| {
                i += 1;
                i % 2 == 1
            });
            self.stride *= 2;
            if k % self.stride != 0 {
                self.latest = Some(frame);
                return;
            }
        }
        self.frames.push(frame);
    }
}

/// [`run`], telling `observer` of every new best so far. The draws, hence the result, are
/// the same whatever the observer.
pub(crate) fn run_observed<O: Observer>(graph: &Graph, iterations: u32, maximise: bool, rng: &mut Pcg64, observer: &mut O) -> Solution {
    let n = graph.nodes.len();
    let m = graph.edges.len();
    if m == 0 {
        return Solution { chains: Vec::new(), score: 0.0, iteration_scores: Vec::new() };
    }
    let mut iteration_scores = Vec::with_capacity(iterations as usize);
    let total_length = graph.total_length();
    // One record per node, in node order: a header then its incidences (in the graph's order,
    // so ties are met in the same order). Starting a path at a random node then touches one
    // record (a honeycomb node's is 64 bytes) instead of five arrays (free count, position,
    // adjacency start, adjacency, used flags): on big layers every start is a cache miss, and
    // this halves them (a GIPPO iteration over a 160 mm honeycomb of 0.2 mm cells, 740k
    // edges: 205 → 119 ms). Nothing else changes: the same draws make the same choices.
    let mut rec: Vec<Slot> = Vec::with_capacity(n + 2 * m);
    let mut at = vec![0u32; n];
    let mut offset = 0u32;
    for v in 0..n {
        at[v] = offset;
        offset += 1 + graph.degree(v) as u32;
    }
    for v in 0..n {
        rec.push(Slot { a: graph.degree(v) as u32, b: 0, len: 0.0 });
        for &e in graph.incident(v) {
            rec.push(Slot { a: at[graph.other(e, v)], b: e as u32, len: graph.edges[e].length });
        }
    }
    // Nodes with edges, in node order: the incomplete list at the start of an iteration.
    let incomplete0: Vec<u32> = (0..n).filter(|&v| graph.degree(v) > 0).map(|v| at[v]).collect();

    let mut incomplete: Vec<u32> = Vec::with_capacity(n);
    let mut front: Vec<u32> = Vec::with_capacity(m);
    let mut back: Vec<u32> = Vec::with_capacity(m);
    let mut cur = Flat::default();
    let mut best = Flat::default();
    cur.edges.reserve(m);
    best.edges.reserve(m);
    let mut best_score = f64::NEG_INFINITY;

    for iteration in 0..iterations {
        for slot in &mut rec {
            slot.b &= !USED;
        }
        incomplete.clear();
        incomplete.extend_from_slice(&incomplete0);
        for (k, &o) in incomplete0.iter().enumerate() {
            let h = &mut rec[o as usize];
            h.b = k as u32;
            h.len = h.a as f64;
        }
        cur.clear();
        let mut weighted = 0.0;
        let mut paths = 0usize;
        // Node records read (the growth checks count them).
        let mut scanned = 0usize;

        while !incomplete.is_empty() {
            let start = incomplete[below(rng, incomplete.len())] as usize;
            let (mut fnode, mut bnode) = (start, start);
            front.clear();
            back.clear();
            let mut length = 0.0;
            loop {
                // Candidate (at_back, edge, other end, length) over both extremities.
                let mut pick: Option<(bool, usize, usize, f64)> = None;
                let mut ties = 0u64;
                for (at_back, ext) in [(true, bnode), (false, fnode)] {
                    if !at_back && fnode == bnode {
                        break;
                    }
                    let h = rec[ext];
                    scanned += 1;
                    if h.len == 0.0 {
                        continue;
                    }
                    scanned += h.a as usize;
                    for (k, s) in rec[ext + 1..ext + 1 + h.a as usize].iter().enumerate() {
                        if s.b & USED != 0 {
                            continue;
                        }
                        let (w, e, len) = (s.a as usize, ext + 1 + k, s.len);
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
                let Some((at_back, slot, w, len)) = pick else { break };
                // Used, at both ends (the other end's record is touched next anyway).
                rec[slot].b |= USED;
                let e = rec[slot].b & !USED;
                let deg = rec[w].a as usize;
                scanned += deg;
                for t in &mut rec[w + 1..w + 1 + deg] {
                    if t.b == e {
                        t.b |= USED;
                        break;
                    }
                }
                let e = e as usize;
                length += len;
                let ext = if at_back { bnode } else { fnode };
                for v in [ext, w] {
                    rec[v].len -= 1.0;
                    if rec[v].len == 0.0 {
                        // Swap-remove from the incomplete list.
                        let p = rec[v].b as usize;
                        let last = *incomplete.last().expect("node listed");
                        incomplete[p] = last;
                        rec[last as usize].b = p as u32;
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
        crate::work::add(scanned);
        let score = weighted / (total_length * paths as f64);
        iteration_scores.push(score);
        if score > best_score {
            best_score = score;
            std::mem::swap(&mut cur, &mut best);
            if observer.wants(iteration, score) {
                observer.record(iteration, score, chains_of(&best, &at, graph));
            }
        }
    }
    let chains = chains_of(&best, &at, graph);
    Solution { chains, score: best_score, iteration_scores }
}

/// A flat solution → chains, longest first (segments, then length; stable). Its first nodes
/// are node records (`at[v]`), turned back into node numbers (records are in node order).
fn chains_of(best: &Flat, at: &[u32], graph: &Graph) -> Vec<Chain> {
    let mut chains = Vec::with_capacity(best.starts.len());
    for (i, &s) in best.starts.iter().enumerate() {
        let end = best.starts.get(i + 1).map_or(best.edges.len(), |&x| x as usize);
        let edges: Vec<usize> = best.edges[s as usize..end].iter().map(|&e| e as usize).collect();
        let mut nodes = Vec::with_capacity(edges.len() + 1);
        let mut v = at.partition_point(|&o| o < best.first[i]);
        nodes.push(v);
        for &e in &edges {
            v = graph.other(e, v);
            nodes.push(v);
        }
        let travel = vec![false; edges.len()];
        chains.push(Chain { nodes, edges, travel });
    }
    super::order::sort_longest_first(&mut chains, graph);
    chains
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::{DVec2, Feature, Stroke, StrokeLayer};
    use rand_core::SeedableRng;

    /// The loop as first written (one array per field), to check that the records change nothing.
    fn reference(graph: &Graph, iterations: u32, maximise: bool, rng: &mut Pcg64) -> (Vec<u32>, Vec<u32>, Vec<u32>, Vec<f64>) {
        let n = graph.nodes.len();
        let m = graph.edges.len();
        if m == 0 {
            return Default::default();
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

        (best.edges, best.starts, best.first, iteration_scores)
    }

    /// A messy layer: a grid of struts of slightly random lengths (some ties, some not), some
    /// verticals, random crossing strokes.
    fn layer(n: usize, seed: u64) -> StrokeLayer {
        let mut s = seed | 1;
        let mut rnd = move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s % 1_000_000) as f64 / 1e6
        };
        let mut strokes = Vec::new();
        for i in 0..n {
            for j in 0..n {
                let (x, y) = (i as f64, j as f64 * 0.9);
                let dy = if (i * 7 + j) % 3 == 0 { 0.0 } else { 0.3 * rnd() };
                strokes.push(Stroke { points: vec![DVec2::new(x, y), DVec2::new(x + 1.0, y + dy)], feature: Feature::Lattice, curved: false });
                if (i + j) % 2 == 0 {
                    strokes.push(Stroke { points: vec![DVec2::new(x, y), DVec2::new(x, y + 0.9)], feature: Feature::Lattice, curved: false });
                }
            }
        }
        for _ in 0..n {
            let (a, b) = (DVec2::new(rnd(), rnd()) * n as f64, DVec2::new(rnd(), rnd()) * n as f64);
            strokes.push(Stroke { points: vec![a, b], feature: Feature::Contour, curved: false });
        }
        StrokeLayer { z: 0.2, height: 0.2, strokes }
    }

    #[test]
    fn the_node_records_change_no_choice() {
        for (n, seed) in [(3, 1), (12, 7), (30, 3), (60, 11)] {
            let g = crate::paths::build_graph(&layer(n, seed), 0.005);
            for maximise in [true, false] {
                let (edges, starts, first, scores) = reference(&g, 7, maximise, &mut Pcg64::seed_from_u64(seed));
                let sol = run(&g, 7, maximise, &mut Pcg64::seed_from_u64(seed));
                assert_eq!(sol.iteration_scores, scores);
                // The same paths (run sorts them longest first): compare as sorted lists.
                let mut want: Vec<(u32, Vec<usize>)> = (0..starts.len())
                    .map(|i| {
                        let end = starts.get(i + 1).map_or(edges.len(), |&x| x as usize);
                        (first[i], edges[starts[i] as usize..end].iter().map(|&e| e as usize).collect())
                    })
                    .collect();
                let mut got: Vec<(u32, Vec<usize>)> = sol.chains.iter().map(|c| (c.nodes[0] as u32, c.edges.clone())).collect();
                want.sort();
                got.sort();
                assert_eq!(got, want, "n {n}, seed {seed}");
            }
        }
    }

    #[test]
    fn a_recorded_run_ends_on_the_normal_run() {
        for (n, seed) in [(3, 1), (12, 7), (30, 3)] {
            let g = crate::paths::build_graph(&layer(n, seed), 0.005);
            for maximise in [true, false] {
                for cap in [2, 3, 5, 64] {
                    let sol = run(&g, 200, maximise, &mut Pcg64::seed_from_u64(seed));
                    let mut rec = Recorder::new(cap);
                    let watched = run_observed(&g, 200, maximise, &mut Pcg64::seed_from_u64(seed), &mut rec);
                    let improvements = rec.improvements();
                    let frames = rec.finish();
                    // The same draws: the same scores and the same solution.
                    assert_eq!(watched.iteration_scores, sol.iteration_scores);
                    assert_eq!(watched.score, sol.score);
                    let last = frames.last().expect("a frame");
                    assert_eq!(*last, Frame::of(last.iteration, sol.score, &sol.chains), "n {n}, seed {seed}, cap {cap}");
                    // Bounded, first and last kept, scores rising, each a real improvement.
                    assert!(frames.len() <= cap && frames.len() <= improvements, "{} frames, cap {cap}", frames.len());
                    assert_eq!(frames[0].iteration, 0);
                    assert!(frames.windows(2).all(|w| w[0].iteration < w[1].iteration && w[0].score < w[1].score));
                    let mut best = f64::NEG_INFINITY;
                    let firsts: Vec<u32> = (0..200u32)
                        .filter(|&i| {
                            let s = sol.iteration_scores[i as usize];
                            let up = s > best;
                            best = best.max(s);
                            up
                        })
                        .collect();
                    assert_eq!(firsts.len(), improvements);
                    assert!(frames.iter().all(|f| firsts.contains(&f.iteration) && f.score == sol.iteration_scores[f.iteration as usize]));
                    if improvements <= cap {
                        assert_eq!(frames.len(), improvements);
                    }
                    // Every frame covers every edge once.
                    for f in &frames {
                        let mut e: Vec<u32> = f.edges.clone();
                        e.sort_unstable();
                        assert_eq!(e, (0..g.edges.len() as u32).collect::<Vec<_>>());
                    }
                }
            }
        }
    }

    #[test]
    fn the_recorder_keeps_the_first_the_last_and_evenly_spaced_ones() {
        for cap in 2..12 {
            for n in 1..200u32 {
                let mut rec = Recorder::new(cap);
                for k in 0..n {
                    rec.record(k, k as f64, Vec::new());
                }
                let kept: Vec<u32> = rec.finish().iter().map(|f| f.iteration).collect();
                assert!(kept.len() <= cap, "cap {cap}, n {n}: {kept:?}");
                assert_eq!((kept[0], *kept.last().unwrap()), (0, n - 1), "cap {cap}, n {n}");
                assert!(kept.windows(2).all(|w| w[0] < w[1]));
                if n as usize <= cap {
                    assert_eq!(kept, (0..n).collect::<Vec<_>>());
                } else {
                    // Evenly spaced but for the last: one stride apart.
                    let stride = kept[1] - kept[0];
                    assert!(kept[..kept.len() - 1].windows(2).all(|w| w[1] - w[0] == stride), "cap {cap}, n {n}: {kept:?}");
                    assert!(kept.len() >= cap / 2, "cap {cap}, n {n}: {kept:?}");
                }
            }
        }
    }
}

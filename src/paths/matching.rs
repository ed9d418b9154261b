//! Minimum-weight perfect matching of odd-degree nodes: an **exact** blossom solve where the
//! work estimate allows it ([`exact_pairing`], the `integer-blossom` crate on the dense
//! distance matrix of one component), else a **near-optimal heuristic** with a certified
//! lower bound ([`min_pairing`] + [`dual_lower_bound`]).
//!
//! Heuristic:
//! 1. Candidate pairs: the k nearest partners of every node (a grid k-NN for Euclidean
//!    distance, bounded Dijkstra for graph distance — supplied by the caller).
//! 2. Greedy: candidates by increasing cost (ties by index), pair when both are free. Nodes
//!    left over (their candidates were all taken) get fresh candidates among the leftovers
//!    only, until everyone is paired (each round pairs at least the closest leftover pair).
//! 3. Improvement: 2-opt pair swaps — for a pair (a, b) and a candidate neighbour c of a
//!    paired with d, re-pair as (a, c), (b, d) when that is shorter — until no swap helps.
//!    The b–d cost is asked of the caller with the largest value that would still pay, so a
//!    graph-distance caller runs a Dijkstra bounded by it (every useful swap is seen).
//!
//! Lower bound ([`dual_lower_bound`]): a feasible solution of the matching LP's dual without
//! odd-set constraints — node potentials `y` with `y_u + y_v ≤ d(u, v)` for *every* pair —
//! so `Σ y` ≤ the optimum (weak duality). Pairs outside the candidate graph are covered by
//! capping `y_u` at half the distance to `u`'s k-th candidate: a non-candidate pair is at
//! least that far from both ends. Every choice is deterministic.

use crate::geom::DVec2;

/// Candidate partners per node.
pub const CANDIDATES_PER_NODE: usize = 6;
/// Improvement passes at most.
const MAX_PASSES: usize = 64;
/// Below this many active nodes, every pair is a candidate.
const ALL_PAIRS_BELOW: usize = 48;

/// Candidate generator: candidate pairs `(cost, i, j)` among the given active items.
pub type Candidates<'a> = dyn FnMut(&[usize]) -> Vec<(f64, usize, usize)> + 'a;

/// A heuristic pairing: every item's partner and the pair's cost, and the first round's
/// candidates (every item active: what [`dual_lower_bound`] needs).
pub struct Heuristic {
    /// Every item's partner.
    pub partner: Vec<usize>,
    /// The cost of every item's pair.
    pub pair_cost: Vec<f64>,
    /// The first round's candidate pairs `(cost, i, j)`.
    pub first: Vec<(f64, usize, usize)>,
    /// Every candidate pair seen (the improvement step's neighbours).
    pub seen: Vec<(f64, usize, usize)>,
}

/// Pairs `n` (even) items. `candidates(active)` returns candidate pairs `(cost, i, j)` among
/// the `active` items; `cost(i, j, limit)` returns the cost of a pair when it is below `limit`
/// (else `None`) for the improvement step ([`improve_pairing`]).
pub fn min_pairing(n: usize, candidates: &mut Candidates<'_>, cost: &mut dyn FnMut(usize, usize, f64) -> Option<f64>) -> Heuristic {
    const NONE: usize = usize::MAX;
    let mut partner = vec![NONE; n];
    let mut pcost = vec![0.0f64; n];
    let mut all: Vec<(f64, usize, usize)> = Vec::new();
    let mut active: Vec<usize> = (0..n).collect();
    let mut first: Option<Vec<(f64, usize, usize)>> = None;
    while active.len() >= 2 {
        let mut cands = candidates(&active);
        if first.is_none() {
            first = Some(cands.clone());
        }
        // (cost, i, j) is a total order, so the unstable sort gives the same sequence.
        cands.sort_unstable_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)).then(x.2.cmp(&y.2)));
        let mut matched = false;
        for &(c, i, j) in &cands {
            if i != j && partner[i] == NONE && partner[j] == NONE {
                partner[i] = j;
                partner[j] = i;
                pcost[i] = c;
                pcost[j] = c;
                matched = true;
            }
        }
        all.extend_from_slice(&cands);
        active.retain(|&i| partner[i] == NONE);
        if !matched {
            // Cannot happen with sane candidate generators; pair in order to stay total.
            for w in active.chunks(2) {
                if let [i, j] = *w {
                    partner[i] = j;
                    partner[j] = i;
                    let c = cost(i, j, f64::INFINITY).unwrap_or(f64::INFINITY);
                    pcost[i] = c;
                    pcost[j] = c;
                }
            }
            break;
        }
    }
    improve_pairing(n, &mut partner, &mut pcost, &all, cost);
    Heuristic { partner, pair_cost: pcost, first: first.unwrap_or_default(), seen: all }
}

/// 2-opt pair swaps on a pairing of `n` items (`partner`, each pair's cost `pcost`): for a pair
/// (a, b) and a neighbour c of a (from `pairs`) paired with d, re-pair as (a, c), (b, d) when
/// that is shorter, until no swap helps ([`MAX_PASSES`] at most). `cost(i, j, limit)` as in
/// [`min_pairing`]; a pair it answers `None` for is never made.
pub fn improve_pairing(
    n: usize,
    partner: &mut [usize],
    pcost: &mut [f64],
    pairs: &[(f64, usize, usize)],
    cost: &mut dyn FnMut(usize, usize, f64) -> Option<f64>,
) {
    const NONE: usize = usize::MAX;
    let all = pairs;
    // Neighbour lists (CSR) from every candidate seen.
    let mut start = vec![0usize; n + 1];
    for &(_, i, j) in all {
        start[i + 1] += 1;
        start[j + 1] += 1;
    }
    for i in 0..n {
        start[i + 1] += start[i];
    }
    let mut fill = start.clone();
    let mut nbr = vec![0usize; start[n]];
    for &(_, i, j) in all {
        nbr[fill[i]] = j;
        fill[i] += 1;
        nbr[fill[j]] = i;
        fill[j] += 1;
    }

    // a–c costs never change: evaluate them once (with the same `cost`, so the same bits).
    let mut nbr_cost = vec![None; nbr.len()];
    for a in 0..n {
        for k in start[a]..start[a + 1] {
            if nbr[k] != a {
                nbr_cost[k] = cost(a, nbr[k], f64::INFINITY);
            }
        }
    }
    for _ in 0..MAX_PASSES {
        let mut improved = false;
        for a in 0..n {
            for k in start[a]..start[a + 1] {
                let c = nbr[k];
                let b = partner[a];
                let d = partner[c];
                if c == a || c == b || b == NONE || d == NONE {
                    continue;
                }
                let budget = pcost[a] + pcost[c] - 1e-9;
                // Costs are ≥ 0: when a–c alone uses the budget, no b–d can make the swap pay.
                let Some(ac) = nbr_cost[k] else { continue };
                if ac >= budget {
                    continue;
                }
                let Some(bd) = cost(b, d, budget - ac) else { continue };
                if ac + bd < budget {
                    partner[a] = c;
                    partner[c] = a;
                    partner[b] = d;
                    partner[d] = b;
                    pcost[a] = ac;
                    pcost[c] = ac;
                    pcost[b] = bd;
                    pcost[d] = bd;
                    improved = true;
                }
            }
        }
        if !improved {
            break;
        }
    }
}

/// A pairing and how good it is provably.
#[derive(Clone, Debug, PartialEq)]
pub struct Pairing {
    /// Pairs (i < j), sorted.
    pub pairs: Vec<(usize, usize)>,
    /// Total cost.
    pub total: f64,
    /// A proven lower bound on the optimum (the total itself when `optimal`).
    pub lower_bound: f64,
    /// Solved exactly (or the heuristic met its lower bound).
    pub optimal: bool,
}

/// Euclidean perfect matching of `points` (even count) by `method`: exact (dense, or sparse
/// certified — falling back to the heuristic when its search gives up), else the heuristic
/// with its certified lower bound.
pub fn pair_points(points: &[DVec2], method: PairingMethod) -> Pairing {
    let n = points.len();
    let dense = || {
        let mut dist = vec![0.0; n * n];
        for i in 0..n {
            for j in i + 1..n {
                dist[i * n + j] = points[i].distance(points[j]);
            }
        }
        exact_pairing(n, &dist)
    };
    let exact = match method {
        PairingMethod::Dense => Some(dense()),
        PairingMethod::Sparse { dense_fallback } => match certified_points(points) {
            Ok(c) => Some(c.matching.mates),
            Err(_) if dense_fallback => Some(dense()),
            Err(_) => None,
        },
        PairingMethod::Heuristic => None,
    };
    let optimal = exact.is_some();
    let partner = exact.unwrap_or_else(|| {
        min_pairing(n, &mut |active| knn_candidates(points, active, CANDIDATES_PER_NODE), &mut |i, j, _| Some(points[i].distance(points[j]))).partner
    });
    let mut pairs = Vec::with_capacity(n / 2);
    let mut total = 0.0;
    for (i, &j) in partner.iter().enumerate() {
        if i < j && j != usize::MAX {
            pairs.push((i, j));
            total += points[i].distance(points[j]);
        }
    }
    if optimal {
        return Pairing { pairs, total, lower_bound: total, optimal: true };
    }
    let all: Vec<usize> = (0..n).collect();
    let cands = knn_candidates(points, &all, CANDIDATES_PER_NODE);
    let lower_bound = dual_lower_bound(n, &cands, CANDIDATES_PER_NODE).min(total);
    Pairing { pairs, total, lower_bound, optimal: lower_bound >= total }
}

/// Lengths in mm are rounded to integers of this many per mm (nanometres) for the exact
/// solver: an "optimal" pairing is optimal for the rounded lengths, so within n/2 nm of the
/// real optimum.
pub const EXACT_UNITS_PER_MM: f64 = 1e6;
/// Seconds per n³ (n odd nodes) of the dense blossom solve, on the reference machine:
/// `integer-blossom` on random points took 0.13 s at n = 400, 1.15 s at 800, 4.7 s at 1200
/// (2.0–2.7 ns · n³; see BENCHMARKS.md).
pub const EXACT_SECONDS_PER_CUBE: f64 = 2.7e-9;
/// Peak bytes per n² of the dense solve (its (2n+1)² edge table of 16-byte entries and the
/// (2n+1)(n+1) blossom table of 4-byte ids, the caller's n² distances).
pub const EXACT_BYTES_PER_SQUARE: f64 = 80.0;

/// Estimated seconds of an exact solve of `n` nodes (the distances not included).
pub fn exact_seconds(n: usize) -> f64 {
    (n as f64).powi(3) * EXACT_SECONDS_PER_CUBE
}

/// Minimum-weight perfect matching of `n` (even) items with the row-major `n × n` cost
/// matrix `dist` (mm, ≥ 0; only `i < j` is read), exactly (blossom algorithm, lengths rounded
/// to [`EXACT_UNITS_PER_MM`]). Returns every item's partner. O(n³) time, O(n²) memory.
pub fn exact_pairing(n: usize, dist: &[f64]) -> Vec<usize> {
    let cost: Vec<i64> = dist.iter().map(|&d| (d * EXACT_UNITS_PER_MM).round() as i64).collect();
    integer_blossom::min_weight_perfect_matching(&cost, n)
}

/// Candidate partners per node of the certified sparse solve ([`certified_points`]).
pub const SPARSE_CANDIDATES: usize = 10;
/// Solves of the certified sparse solve at most (the first + re-solves with violators).
pub const SPARSE_MAX_SOLVES: usize = 6;
/// Pair checks per node and round the violator search may make before it gives up.
pub const VIOLATOR_CHECKS_PER_NODE: usize = 400;
/// Seconds per n^1.5 (n odd nodes) of a certified sparse solve, all solves and violator
/// searches included, on the reference machine: measured 0.16–0.45 µs · n^1.5 on random points
/// (n = 1752…40 000; see BENCHMARKS.md), so at least 2.2× conservative.
pub const SPARSE_SECONDS_PER_N15: f64 = 1.0e-6;

/// Peak bytes per node of the certified sparse solve: its edge list and adjacency (about
/// 1.5 × [`SPARSE_CANDIDATES`] edges of 24 + 16 bytes after the violators), 2n blossom slots
/// of about 150 bytes, the candidate list and the heap.
pub const SPARSE_BYTES_PER_NODE: f64 = 1500.0;

/// Estimated seconds of a certified sparse solve of `n` points.
pub fn sparse_seconds(n: usize) -> f64 {
    (n as f64).powf(1.5) * SPARSE_SECONDS_PER_N15
}

/// How a component's odd nodes are paired.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PairingMethod {
    /// Dense exact blossom (`integer-blossom`).
    Dense,
    /// Certified sparse blossom ([`super::blossom::certified_pairing`]); when it gives up (the
    /// candidates have no perfect matching, or the violator search hit its bound), the dense
    /// solve if `dense_fallback`, else the heuristic.
    Sparse {
        /// The dense solve fits the budget too.
        dense_fallback: bool,
    },
    /// Greedy + 2-opt with a dual lower bound.
    Heuristic,
}

/// The method for a component whose dense and sparse exact solves are estimated at `dense` and
/// `sparse` seconds, with `left` seconds of the layer's budget left, and the seconds to charge.
/// The sparse solve is faster at every size measured (n = 10…1752, BENCHMARKS.md), so it comes
/// first; the dense one is its fallback when both fit (charged only the sparse estimate: the
/// fallback runs only when the sparse solve gives up early), or used alone when only it fits.
pub fn choose_method(dense: f64, sparse: f64, left: f64) -> (PairingMethod, f64) {
    if sparse <= left {
        (PairingMethod::Sparse { dense_fallback: sparse + dense <= left }, sparse)
    } else if dense <= left {
        (PairingMethod::Dense, dense)
    } else {
        (PairingMethod::Heuristic, 0.0)
    }
}

/// Integer cost (nm) of a length in mm.
pub fn exact_units(mm: f64) -> i64 {
    (mm * EXACT_UNITS_PER_MM).round() as i64
}

/// Euclidean minimum-weight perfect matching of `points`, proven optimal for the complete graph:
/// the sparse blossom on the [`SPARSE_CANDIDATES`] nearest neighbours, then pairs whose
/// reduced cost is negative are searched (a grid, within the radius the duals allow), added and
/// re-solved. Lengths rounded to [`EXACT_UNITS_PER_MM`].
pub fn certified_points(points: &[DVec2]) -> Result<super::blossom::Certified, super::blossom::CertifyError> {
    let n = points.len();
    let all: Vec<usize> = (0..n).collect();
    let cands: Vec<(usize, usize, i64)> = knn_candidates(points, &all, SPARSE_CANDIDATES).into_iter().map(|(d, i, j)| (i, j, exact_units(d))).collect();
    let grid = Grid::new(points);
    let mut find =
        |duals: &super::blossom::Duals, out: &mut Vec<(usize, usize, i64)>| -> bool { grid.violators(points, duals, VIOLATOR_CHECKS_PER_NODE * n, out) };
    super::blossom::certified_pairing(n, cands, &mut find, SPARSE_MAX_SOLVES)
}

/// Uniform grid of points (CSR by cell) for radius searches.
struct Grid {
    min: DVec2,
    cell: f64,
    nx: usize,
    ny: usize,
    start: Vec<usize>,
    items: Vec<usize>,
}

impl Grid {
    fn new(points: &[DVec2]) -> Grid {
        Grid::over(points, 0..points.len())
    }

    /// The grid of `points[i]` for the `i` of `items` (each once); cells hold them in that order.
    fn over(points: &[DVec2], items: impl Iterator<Item = usize> + Clone) -> Grid {
        let m = items.clone().count().max(1);
        let mut min = DVec2::splat(f64::INFINITY);
        let mut max = DVec2::splat(f64::NEG_INFINITY);
        for i in items.clone() {
            min = min.min(points[i]);
            max = max.max(points[i]);
        }
        if min.x > max.x {
            min = DVec2::ZERO;
            max = DVec2::ZERO;
        }
        let size = (max - min).max(DVec2::splat(1e-9));
        let mut cell = (size.x * size.y / m as f64).sqrt().max(size.x.max(size.y) / m as f64).max(1e-9);
        while (size.x / cell + 1.0) * (size.y / cell + 1.0) > 4.0 * m as f64 + 16.0 {
            cell *= 1.5;
        }
        let nx = (size.x / cell).floor() as usize + 1;
        let ny = (size.y / cell).floor() as usize + 1;
        let mut g = Grid { min, cell, nx, ny, start: vec![0; nx * ny + 1], items: Vec::new() };
        for i in items.clone() {
            let c = g.cell_of(points[i]);
            g.start[c + 1] += 1;
        }
        for c in 0..nx * ny {
            g.start[c + 1] += g.start[c];
        }
        let mut fill = g.start.clone();
        g.items = vec![0; g.start[nx * ny]];
        for i in items {
            let c = g.cell_of(points[i]);
            g.items[fill[c]] = i;
            fill[c] += 1;
        }
        g
    }

    fn coord(&self, v: f64, lo: f64, count: usize) -> usize {
        (((v - lo) / self.cell).floor().max(0.0) as usize).min(count - 1)
    }

    fn cell_of(&self, p: DVec2) -> usize {
        self.coord(p.y, self.min.y, self.ny) * self.nx + self.coord(p.x, self.min.x, self.nx)
    }

    /// Pairs (u, v) with a negative reduced cost. Such a pair has 4c < Y_u + Y_v ≤ 2 max(Y), so
    /// each u looks only for partners v ranked below it by (Y, index), within c < Y_u / 2.
    /// False when more than `max_checks` pairs would be checked.
    fn violators(&self, points: &[DVec2], duals: &super::blossom::Duals, max_checks: usize, out: &mut Vec<(usize, usize, i64)>) -> bool {
        let scale = super::blossom::DUAL_SCALE as f64;
        let mut checks = 0usize;
        for u in 0..points.len() {
            let yu = duals.total[u];
            if yu <= 0 {
                continue;
            }
            // c < Y_u·4/(2·4) in nm; one nm of rounding slack.
            let r = (yu as f64 * 2.0 / scale + 1.0) / EXACT_UNITS_PER_MM;
            let p = points[u];
            let (x0, x1) = (self.coord(p.x - r, self.min.x, self.nx), self.coord(p.x + r, self.min.x, self.nx));
            let (y0, y1) = (self.coord(p.y - r, self.min.y, self.ny), self.coord(p.y + r, self.min.y, self.ny));
            checks += (x1 - x0 + 1) * (y1 - y0 + 1);
            if checks > max_checks {
                crate::work::add(checks);
                return false;
            }
            for cy in y0..=y1 {
                for cx in x0..=x1 {
                    let c = cy * self.nx + cx;
                    for &v in &self.items[self.start[c]..self.start[c + 1]] {
                        if (duals.total[v], v) >= (yu, u) {
                            continue;
                        }
                        checks += 1;
                        let cost = exact_units(p.distance(points[v]));
                        if duals.reduced_cost(u, v, cost) < 0 {
                            out.push((u.min(v), u.max(v), cost));
                        }
                    }
                }
            }
            if checks > max_checks {
                crate::work::add(checks);
                return false;
            }
        }
        // Cells and pairs checked (the growth checks count them).
        crate::work::add(checks);
        true
    }
}

/// A lower bound on the minimum-weight perfect matching of `n` items from candidate pairs
/// `(cost, i, j)` that contain, for every item, its `k` nearest partners (fewer only when it
/// has fewer: then all of them). Node potentials by coordinate ascent over the candidates
/// (index order, a few passes), each capped at half the distance to its k-th candidate so
/// that non-candidate pairs stay feasible; returns Σ potentials.
pub fn dual_lower_bound(n: usize, cands: &[(f64, usize, usize)], k: usize) -> f64 {
    dual_potentials(n, cands, k).iter().sum()
}

/// A lower bound on the cheapest pairing of all but two of the items (the two left over are
/// free: an open walk's ends), from feasible potentials `y` of the pairing's dual
/// ([`dual_potentials`]). Two ends joined to every item at cost 0 have potentials −t, so every
/// potential is capped at t; the best t is the third largest potential (the bound
/// Σ min(y, t) − 2t grows while more than two potentials exceed t). 0 with two items or fewer.
pub fn open_lower_bound(y: &[f64]) -> f64 {
    if y.len() <= 2 {
        return 0.0;
    }
    let mut sorted = y.to_vec();
    sorted.sort_by(|a, b| b.total_cmp(a));
    let t = sorted[2];
    y.iter().map(|&v| v.min(t)).sum::<f64>() - 2.0 * t
}

/// Feasible potentials of the pairing's dual (no odd-set constraints) from candidate pairs, as
/// [`dual_lower_bound`] describes: `y_u + y_v ≤ cost(u, v)` for every pair.
pub fn dual_potentials(n: usize, cands: &[(f64, usize, usize)], k: usize) -> Vec<f64> {
    // CSR of (partner, cost), one per partner (the smaller cost when found twice).
    let mut start = vec![0usize; n + 1];
    for &(_, i, j) in cands {
        if i != j {
            start[i + 1] += 1;
            start[j + 1] += 1;
        }
    }
    for i in 0..n {
        start[i + 1] += start[i];
    }
    let mut fill = start.clone();
    let mut adj = vec![(0usize, 0.0f64); start[n]];
    for &(c, i, j) in cands {
        if i != j {
            adj[fill[i]] = (j, c);
            fill[i] += 1;
            adj[fill[j]] = (i, c);
            fill[j] += 1;
        }
    }
    let mut lists: Vec<Vec<(usize, f64)>> = Vec::with_capacity(n);
    let mut cap = vec![f64::INFINITY; n];
    for u in 0..n {
        let mut l = adj[start[u]..start[u + 1]].to_vec();
        l.sort_by(|a, b| a.0.cmp(&b.0).then(a.1.total_cmp(&b.1)));
        l.dedup_by_key(|x| x.0);
        if l.len() >= k {
            let mut d: Vec<f64> = l.iter().map(|x| x.1).collect();
            d.sort_by(f64::total_cmp);
            cap[u] = 0.5 * d[k - 1];
        }
        lists.push(l);
    }
    let mut y: Vec<f64> = (0..n).map(|u| lists[u].iter().map(|x| 0.5 * x.1).fold(cap[u], f64::min)).collect();
    for u in 0..n {
        if lists[u].is_empty() && cap[u].is_infinite() {
            y[u] = 0.0; // No partner seen at all: nothing is known.
        }
    }
    for _ in 0..DUAL_PASSES {
        for u in 0..n {
            let best = lists[u].iter().map(|&(v, c)| c - y[v]).fold(cap[u], f64::min);
            if best.is_finite() && best > y[u] {
                y[u] = best;
            }
        }
    }
    y
}

/// Coordinate-ascent passes of [`dual_lower_bound`].
const DUAL_PASSES: usize = 4;

/// The `k` nearest active neighbours of every active point (grid search), as (distance, i, j).
pub fn knn_candidates(points: &[DVec2], active: &[usize], k: usize) -> Vec<(f64, usize, usize)> {
    let m = active.len();
    let mut out = Vec::with_capacity(m * k);
    if m <= ALL_PAIRS_BELOW {
        for (x, &i) in active.iter().enumerate() {
            for &j in &active[x + 1..] {
                out.push((points[i].distance(points[j]), i.min(j), i.max(j)));
            }
        }
        return out;
    }
    let g = Grid::over(points, active.iter().copied());
    let (nx, ny, cell) = (g.nx, g.ny, g.cell);
    let cell_of = |p: DVec2| (g.coord(p.x, g.min.x, nx), g.coord(p.y, g.min.y, ny));
    let (start, items) = (&g.start, &g.items);
    let mut best: Vec<(f64, usize)> = Vec::with_capacity(k + 1);
    let max_r = nx.max(ny);
    // Cells and points looked at (the growth checks count them).
    let mut looked = 0usize;
    for &i in active {
        let p = points[i];
        let (cx, cy) = cell_of(p);
        best.clear();
        let mut r = 0usize;
        loop {
            let (x0, x1) = (cx as isize - r as isize, cx as isize + r as isize);
            let (y0, y1) = (cy as isize - r as isize, cy as isize + r as isize);
            for y in y0..=y1 {
                if y < 0 || y >= ny as isize {
                    continue;
                }
                let ring_row = y == y0 || y == y1;
                let mut x = x0;
                while x <= x1 {
                    looked += 1;
                    if x >= 0 && x < nx as isize {
                        let c = y as usize * nx + x as usize;
                        looked += start[c + 1] - start[c];
                        for &j in &items[start[c]..start[c + 1]] {
                            if j == i {
                                continue;
                            }
                            let d = p.distance(points[j]);
                            if best.len() < k || d < best[best.len() - 1].0 || (d == best[best.len() - 1].0 && j < best[best.len() - 1].1) {
                                let at = best.partition_point(|&(bd, bj)| bd < d || (bd == d && bj < j));
                                best.insert(at, (d, j));
                                best.truncate(k);
                            }
                        }
                    }
                    // Interior rows: only the two ring columns.
                    x = if ring_row || x == x1 { x + 1 } else { x1 };
                }
            }
            if (best.len() >= k && best[best.len() - 1].0 <= r as f64 * cell) || r > max_r {
                break;
            }
            r += 1;
        }
        for &(d, j) in &best {
            out.push((d, i.min(j), i.max(j)));
        }
    }
    crate::work::add(looked);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Exact optimum by brute force (n ≤ 12).
    fn optimum(points: &[DVec2]) -> f64 {
        fn rec(points: &[DVec2], left: &mut Vec<usize>) -> f64 {
            if left.is_empty() {
                return 0.0;
            }
            let a = left.remove(0);
            let mut best = f64::INFINITY;
            for x in 0..left.len() {
                let b = left.remove(x);
                best = best.min(points[a].distance(points[b]) + rec(points, left));
                left.insert(x, b);
            }
            left.insert(0, a);
            best
        }
        rec(points, &mut (0..points.len()).collect())
    }

    /// A xorshift stream of numbers in [0, modulus / 1000), for repeatable random points.
    fn xorshift(mut s: u64, modulus: u64) -> impl FnMut() -> f64 {
        move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s % modulus) as f64 / 1000.0
        }
    }

    #[test]
    fn perfect_and_near_optimal() {
        let mut rnd = xorshift(12345, 10_000);
        let mut worst: f64 = 1.0;
        for _ in 0..40 {
            let pts: Vec<DVec2> = (0..10).map(|_| DVec2::new(rnd(), rnd())).collect();
            let p = pair_points(&pts, PairingMethod::Heuristic);
            let (pairs, total) = (p.pairs, p.total);
            assert_eq!(pairs.len(), 5);
            let mut seen = [false; 10];
            for &(i, j) in &pairs {
                assert!(!seen[i] && !seen[j]);
                seen[i] = true;
                seen[j] = true;
            }
            worst = worst.max(total / optimum(&pts));
        }
        assert!(worst < 1.35, "worst ratio {worst}");
    }

    #[test]
    fn many_points_all_paired() {
        let pts: Vec<DVec2> = (0..2000).map(|i| DVec2::new((i % 50) as f64, (i / 50) as f64 * 1.3)).collect();
        let p = pair_points(&pts, PairingMethod::Heuristic);
        let (pairs, total) = (p.pairs, p.total);
        assert_eq!(pairs.len(), 1000);
        // Optimum pairs horizontal neighbours: 1000 · 1.0.
        assert!(total <= 1000.0 * 1.05, "{total}");
    }

    #[test]
    fn exact_equals_brute_force_and_bound_is_valid() {
        let mut rnd = xorshift(987654321, 10_000);
        for round in 0..60 {
            let n = 2 + 2 * (round % 6);
            let pts: Vec<DVec2> = (0..n).map(|_| DVec2::new(rnd(), rnd())).collect();
            let best = optimum(&pts);
            let exact = pair_points(&pts, PairingMethod::Dense);
            assert!(exact.optimal);
            assert_eq!(exact.pairs.len(), n / 2);
            assert!((exact.total - best).abs() <= 1e-6 * n as f64, "n {n}: {} vs {best}", exact.total);
            let heur = pair_points(&pts, PairingMethod::Heuristic);
            let gap = heur.total / heur.lower_bound;
            assert!(gap >= 1.0, "gap {gap}");
            assert!(heur.total / gap <= best * (1.0 + 1e-12), "bound {} over optimum {best}", heur.total / gap);
            assert!(heur.total >= best * (1.0 - 1e-12));
        }
    }

    #[test]
    fn bound_is_valid_beyond_the_candidates() {
        // 300 random points: candidates are the 6 nearest, the exact optimum is known.
        let mut rnd = xorshift(4242, 100_000);
        let pts: Vec<DVec2> = (0..300).map(|_| DVec2::new(rnd(), rnd())).collect();
        let exact = pair_points(&pts, PairingMethod::Dense);
        let heur = pair_points(&pts, PairingMethod::Heuristic);
        assert!(heur.lower_bound <= exact.total * (1.0 + 1e-12), "{} > {}", heur.lower_bound, exact.total);
        assert!(heur.total >= exact.total * (1.0 - 1e-12));
        assert!(heur.lower_bound > 0.5 * exact.total, "weak bound {} of {}", heur.lower_bound, exact.total);
    }

    fn random_points(n: usize, seed: u64, side: f64) -> Vec<DVec2> {
        let mut s = seed;
        let mut rnd = move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s % 1_000_000) as f64 / 1_000_000.0 * side
        };
        (0..n).map(|_| DVec2::new(rnd(), rnd())).collect()
    }

    fn nm_cost(points: &[DVec2], mates: &[usize]) -> i64 {
        (0..points.len()).filter(|&i| i < mates[i]).map(|i| exact_units(points[i].distance(points[mates[i]]))).sum()
    }

    #[test]
    fn sparse_certified_equals_dense_and_duals_certify_every_pair() {
        use super::super::blossom::DUAL_SCALE;
        for (round, &n) in [50usize, 100, 200, 400, 600].iter().enumerate() {
            let pts = random_points(n, 1000 + round as u64, 100.0);
            let mut dist = vec![0.0; n * n];
            for i in 0..n {
                for j in i + 1..n {
                    dist[i * n + j] = pts[i].distance(pts[j]);
                }
            }
            let dense = nm_cost(&pts, &exact_pairing(n, &dist));
            let c = certified_points(&pts).expect("certified");
            let m = &c.matching;
            assert_eq!(m.cost, nm_cost(&pts, &m.mates));
            assert_eq!(m.cost, dense, "n {n}");
            // Duals feasible on every pair of the complete graph, tight on matched pairs.
            for u in 0..n {
                for v in u + 1..n {
                    let r = m.duals.reduced_cost(u, v, exact_units(pts[u].distance(pts[v])));
                    assert!(r >= 0, "n {n}: pair {u}-{v} reduced {r}");
                    if m.mates[u] == v {
                        assert_eq!(r, 0);
                    }
                }
            }
            assert_eq!(m.duals.objective(), DUAL_SCALE * m.cost, "strong duality n {n}");
            let p = pair_points(&pts, PairingMethod::Sparse { dense_fallback: false });
            assert!(p.optimal);
            assert!((p.total - dense as f64 / EXACT_UNITS_PER_MM).abs() < 1e-3);
        }
    }

    #[test]
    fn violator_loop_adds_missing_optimal_pairs() {
        use super::super::blossom::{certified_pairing, DUAL_SCALE};
        // Few candidates (3 nearest): the first solve misses optimal pairs, the grid search
        // finds the violating pairs, and the re-solves reach the dense optimum.
        let mut hit = 0;
        for seed in 0..20u64 {
            let n = 300;
            let pts = random_points(n, 77 + seed, 100.0);
            let all: Vec<usize> = (0..n).collect();
            let cands: Vec<(usize, usize, i64)> = knn_candidates(&pts, &all, 3).into_iter().map(|(d, i, j)| (i, j, exact_units(d))).collect();
            let Ok(first) = super::super::blossom::min_cost_perfect_matching(n, &cands) else { continue };
            let grid = Grid::new(&pts);
            let mut find = |d: &super::super::blossom::Duals, out: &mut Vec<(usize, usize, i64)>| grid.violators(&pts, d, usize::MAX, out);
            let c = certified_pairing(n, cands, &mut find, 50).expect("certified");
            let mut dist = vec![0.0; n * n];
            for i in 0..n {
                for j in i + 1..n {
                    dist[i * n + j] = pts[i].distance(pts[j]);
                }
            }
            let dense = nm_cost(&pts, &exact_pairing(n, &dist));
            assert_eq!(c.matching.cost, dense);
            assert_eq!(c.matching.duals.objective(), DUAL_SCALE * dense);
            if first.cost > dense {
                assert!(c.added > 0 && c.solves > 1);
                hit += 1;
            }
        }
        assert!(hit > 0, "no instance needed the violator loop");
    }

    #[test]
    fn sparse_falls_back_when_candidates_have_no_perfect_matching() {
        // Two far clusters of 25 points: every point's 10 nearest are in its own cluster, so the
        // candidate graph (odd parts) has no perfect matching.
        let mut pts = random_points(25, 5, 1.0);
        pts.extend(random_points(25, 6, 1.0).into_iter().map(|p| p + DVec2::new(100.0, 0.0)));
        assert_eq!(certified_points(&pts).unwrap_err(), super::super::blossom::CertifyError::NoPerfectMatching);
        let dense = pair_points(&pts, PairingMethod::Dense);
        let fallback = pair_points(&pts, PairingMethod::Sparse { dense_fallback: true });
        assert!(fallback.optimal);
        assert_eq!(fallback.pairs, dense.pairs);
        let heur = pair_points(&pts, PairingMethod::Sparse { dense_fallback: false });
        assert!(heur.total >= dense.total - 1e-9);
    }

    /// Timing table for BENCHMARKS.md: `cargo test --release --lib bench_sparse_vs_dense -- --ignored --nocapture`.
    #[test]
    #[ignore]
    fn bench_sparse_vs_dense() {
        let sizes: Vec<usize> =
            std::env::var("WEFT_BENCH_N").map(|v| v.split(',').map(|x| x.parse().unwrap()).collect()).unwrap_or(vec![400, 800, 1752, 5000, 20000]);
        for &n in &sizes {
            let pts = random_points(n, 5 + n as u64, 1000.0);
            let dense = if n <= 1752 && std::env::var("WEFT_BENCH_NO_DENSE").is_err() {
                let t = std::time::Instant::now();
                let mut dist = vec![0.0; n * n];
                for i in 0..n {
                    for j in i + 1..n {
                        dist[i * n + j] = pts[i].distance(pts[j]);
                    }
                }
                let c = nm_cost(&pts, &exact_pairing(n, &dist));
                Some((t.elapsed().as_secs_f64(), c))
            } else {
                None
            };
            let t = std::time::Instant::now();
            let c = certified_points(&pts).expect("certified");
            let ts = t.elapsed().as_secs_f64();
            println!("n {n}: dense {:?} sparse {ts:.4} s cost {} solves {} added {} est {:.4} s", dense, c.matching.cost, c.solves, c.added, sparse_seconds(n));
        }
    }
}

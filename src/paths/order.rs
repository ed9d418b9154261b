//! Print order of the chains of a layer (a chain is one GIPPO / Euler path, or one
//! continuous walk of a component).
//!
//! * [`sort_longest_first`]: the paper's order — by printed segments, then printed length,
//!   both descending (stable).
//! * circuit order: the chains as the method emits them (for euler / continuous the walk
//!   order, where every travel between two paths is one pairing edge).
//! * [`min_travel`]: up to [`EXACT_CHAINS`] chains, the least travel exactly (a dynamic
//!   programme over the chains printed). Beyond, never worse than the circuit order: two
//!   candidates — the circuit order rotated (either direction) to start nearest the previous
//!   layer's end, and a nearest neighbour tour over both ends of every chain — are each
//!   improved by windowed 2-opt
//!   (segment reversal with chain flips) and or-opt (one chain moved, maybe flipped), moves
//!   accepted only when they shorten the travel; the shorter wins (ties: the circuit one).
//!   The travel measured is the straight distance from the previous layer's end to the first
//!   path plus the straight distances between chains, exactly what the G-code travels.
//! * [`sort_directional`]: the user's direction — along a chosen angle, or from the centre
//!   out.

use super::graph::Graph;
use super::Chain;
use crate::geom::DVec2;

/// 2-opt / or-opt window (chains).
const WINDOW: usize = 48;
/// Local-search passes at most.
const MAX_PASSES: usize = 16;
/// Below this many chains left, nearest neighbour scans them all.
const BRUTE_BELOW: usize = 96;
/// Smallest improvement a local-search move must make, mm.
pub(crate) const GAIN_MM: f64 = 1e-9;

/// The paper's order: most segments first, then longest printed length first; stable.
pub(crate) fn sort_longest_first(chains: &mut [Chain], graph: &Graph) {
    let key = |c: &Chain| -> (usize, f64) {
        let mut segs = 0;
        let mut len = 0.0;
        for (i, &e) in c.edges.iter().enumerate() {
            if !c.travel[i] {
                segs += 1;
                len += graph.edges[e].length;
            }
        }
        (segs, len)
    };
    let mut keyed: Vec<(usize, f64, usize)> = chains
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let (s, l) = key(c);
            (s, l, i)
        })
        .collect();
    keyed.sort_by(|x, y| y.0.cmp(&x.0).then(y.1.total_cmp(&x.1)).then(x.2.cmp(&y.2)));
    let mut taken: Vec<Option<Chain>> = chains.iter_mut().map(|c| Some(std::mem::take(c))).collect();
    for (slot, &(_, _, i)) in keyed.iter().enumerate() {
        chains[slot] = taken[i].take().expect("each chain once");
    }
}

/// Nearest neighbour from `from` over both ends of every chain (a chain may be printed
/// reversed), on a grid.
fn nearest_neighbour(ends: &[[DVec2; 2]], from: DVec2) -> Vec<(usize, bool)> {
    let m = ends.len();

    // Nearest neighbour over chain ends, on a grid.
    let mut min = DVec2::splat(f64::INFINITY);
    let mut max = DVec2::splat(f64::NEG_INFINITY);
    for e in ends {
        for p in e {
            min = min.min(*p);
            max = max.max(*p);
        }
    }
    let size = (max - min).max(DVec2::splat(1e-9));
    let mut cell = (size.x * size.y / (2 * m) as f64).sqrt().max(size.x.max(size.y) / (2 * m) as f64).max(1e-9);
    while (size.x / cell + 1.0) * (size.y / cell + 1.0) > 8.0 * m as f64 + 16.0 {
        cell *= 1.5;
    }
    let nx = (size.x / cell).floor() as usize + 1;
    let ny = (size.y / cell).floor() as usize + 1;
    let cell_xy = |p: DVec2| -> (isize, isize) { (((p.x - min.x) / cell).floor() as isize, ((p.y - min.y) / cell).floor() as isize) };
    let mut cells: Vec<Vec<u32>> = vec![Vec::new(); nx * ny];
    for (i, e) in ends.iter().enumerate() {
        for (w, p) in e.iter().enumerate() {
            let (cx, cy) = cell_xy(*p);
            cells[cy as usize * nx + cx as usize].push((2 * i + w) as u32);
        }
    }
    let mut remaining: Vec<usize> = (0..m).collect();
    let mut rem_pos: Vec<usize> = (0..m).collect();
    let mut order: Vec<(usize, bool)> = Vec::with_capacity(m);
    let mut cur = from;
    let better = |d: f64, id: u32, best: &Option<(f64, u32)>| match best {
        None => true,
        Some((bd, bid)) => d < *bd || (d == *bd && id < *bid),
    };
    // Chain ends and grid cells looked at (the growth checks count them).
    let mut looked = 0usize;
    while !remaining.is_empty() {
        let mut best: Option<(f64, u32)> = None;
        if remaining.len() < BRUTE_BELOW || order.is_empty() {
            looked += 2 * remaining.len();
            for &i in &remaining {
                for (w, p) in ends[i].iter().enumerate() {
                    let id = (2 * i + w) as u32;
                    let d = cur.distance(*p);
                    if better(d, id, &best) {
                        best = Some((d, id));
                    }
                }
            }
        } else {
            let (cx, cy) = cell_xy(cur);
            // `cur` is a chain end, hence inside the grid.
            let mut r = 0isize;
            let max_r = nx.max(ny) as isize + 1;
            loop {
                for y in cy - r..=cy + r {
                    if y < 0 || y >= ny as isize {
                        continue;
                    }
                    let edge_row = y == cy - r || y == cy + r;
                    let mut x = cx - r;
                    while x <= cx + r {
                        looked += 1;
                        if x >= 0 && x < nx as isize {
                            looked += cells[y as usize * nx + x as usize].len();
                            for &id in &cells[y as usize * nx + x as usize] {
                                let i = id as usize / 2;
                                let d = cur.distance(ends[i][id as usize % 2]);
                                if better(d, id, &best) {
                                    best = Some((d, id));
                                }
                            }
                        }
                        x = if edge_row || x == cx + r { x + 1 } else { cx + r };
                    }
                }
                if best.is_some_and(|(d, _)| d <= r as f64 * cell) || r > max_r {
                    break;
                }
                r += 1;
            }
        }
        let (_, id) = best.expect("a chain remains");
        let i = id as usize / 2;
        let reversed = id % 2 == 1;
        order.push((i, reversed));
        cur = ends[i][if reversed { 0 } else { 1 }];
        // Remove chain i from the remaining list and from the grid.
        let p = rem_pos[i];
        let last = *remaining.last().expect("non-empty");
        remaining[p] = last;
        rem_pos[last] = p;
        remaining.pop();
        for (w, p) in ends[i].iter().enumerate() {
            let (x, y) = cell_xy(*p);
            let list = &mut cells[y as usize * nx + x as usize];
            looked += list.len();
            if let Some(k) = list.iter().position(|&e| e as usize == 2 * i + w) {
                list.swap_remove(k);
            }
        }
    }
    crate::work::add(looked);
    order
}

/// The first and last printed node of a chain (where its free travels arrive and leave; a
/// chain without printed steps: its end nodes).
pub(crate) fn printed_ends(c: &Chain, graph: &Graph) -> [DVec2; 2] {
    let first = c.travel.iter().position(|t| !t);
    let last = c.travel.iter().rposition(|t| !t);
    match (first, last) {
        (Some(f), Some(l)) => [graph.nodes[c.nodes[f]], graph.nodes[c.nodes[l + 1]]],
        _ => [graph.nodes[c.nodes[0]], graph.nodes[*c.nodes.last().expect("chain has nodes")]],
    }
}

fn link(a: Option<DVec2>, b: Option<DVec2>) -> f64 {
    match (a, b) {
        (Some(a), Some(b)) => a.distance(b),
        _ => 0.0,
    }
}

/// Travel of chains printed in `order` (chain, reversed): from `from` (when given) to the
/// first, then between chains, straight, mm.
pub(crate) fn travel_of(order: &[(usize, bool)], ends: &[[DVec2; 2]], from: Option<DVec2>) -> f64 {
    let mut cur = from;
    let mut t = 0.0;
    for &(i, r) in order {
        t += link(cur, Some(ends[i][r as usize]));
        cur = Some(ends[i][1 - r as usize]);
    }
    t
}

/// The circuit order rotated to start where the travel is least: forwards from chain k, or
/// backwards (every chain reversed) from chain k. Rotation 0 forwards is the circuit order
/// itself, so the result is never longer.
fn best_rotation(ends: &[[DVec2; 2]], from: Option<DVec2>) -> Vec<(usize, bool)> {
    let m = ends.len();
    // l[k]: end of k → start of k + 1 (cyclic).
    let l: Vec<f64> = (0..m).map(|k| ends[k][1].distance(ends[(k + 1) % m][0])).collect();
    let total: f64 = l.iter().sum();
    let mut best = (travel_of(&(0..m).map(|i| (i, false)).collect::<Vec<_>>(), ends, from), 0usize, false);
    for k in 0..m {
        let fwd = link(from, Some(ends[k][0])) + total - l[(k + m - 1) % m];
        if fwd < best.0 - GAIN_MM {
            best = (fwd, k, false);
        }
        let bwd = link(from, Some(ends[k][1])) + total - l[k];
        if bwd < best.0 - GAIN_MM {
            best = (bwd, k, true);
        }
    }
    let (_, k, back) = best;
    if back {
        (0..m).map(|j| ((k + m - j) % m, true)).collect()
    } else {
        (0..m).map(|j| ((k + j) % m, false)).collect()
    }
}

/// Windowed 2-opt and or-opt, accepting only moves that shorten the travel.
fn improve(order: &mut Vec<(usize, bool)>, ends: &[[DVec2; 2]], from: Option<DVec2>) {
    let m = order.len();
    let mut s: Vec<DVec2> = order.iter().map(|&(i, r)| ends[i][r as usize]).collect();
    let mut e: Vec<DVec2> = order.iter().map(|&(i, r)| ends[i][1 - r as usize]).collect();
    for _ in 0..MAX_PASSES {
        // Moves tried, and elements shifted by a chain moved (the growth checks count them).
        crate::work::add(m * 2 * (WINDOW + 1));
        let mut improved = false;
        // 2-opt: reverse the run i..=j (each chain flipped).
        for i in 0..m {
            for j in i..m.min(i + WINDOW) {
                let prev = if i == 0 { from } else { Some(e[i - 1]) };
                let next = if j + 1 < m { Some(s[j + 1]) } else { None };
                let before = link(prev, Some(s[i])) + link(Some(e[j]), next);
                let after = link(prev, Some(e[j])) + link(Some(s[i]), next);
                if after < before - GAIN_MM {
                    order[i..=j].reverse();
                    s[i..=j].reverse();
                    e[i..=j].reverse();
                    for k in i..=j {
                        order[k].1 = !order[k].1;
                        std::mem::swap(&mut s[k], &mut e[k]);
                    }
                    improved = true;
                }
            }
        }
        // Or-opt: move chain i before position q (q = m: to the end), either way round.
        let mut i = 0;
        while i < m {
            let prev = if i == 0 { from } else { Some(e[i - 1]) };
            let next = if i + 1 < m { Some(s[i + 1]) } else { None };
            let removal = link(prev, Some(s[i])) + link(Some(e[i]), next) - link(prev, next);
            let mut best: Option<(f64, usize, bool)> = None;
            for q in i.saturating_sub(WINDOW)..=m.min(i + WINDOW) {
                if q == i || q == i + 1 {
                    continue;
                }
                let p = if q == 0 { from } else { Some(e[q - 1]) };
                let n = if q < m { Some(s[q]) } else { None };
                for flip in [false, true] {
                    let (a, b) = if flip { (e[i], s[i]) } else { (s[i], e[i]) };
                    let delta = link(p, Some(a)) + link(Some(b), n) - link(p, n) - removal;
                    if delta < -GAIN_MM && best.is_none_or(|(d, _, _)| delta < d) {
                        best = Some((delta, q, flip));
                    }
                }
            }
            if let Some((_, q, flip)) = best {
                crate::work::add(2 * m);
                let (mut c, mut a, mut b) = (order.remove(i), s.remove(i), e.remove(i));
                if flip {
                    c.1 = !c.1;
                    std::mem::swap(&mut a, &mut b);
                }
                let at = if q > i { q - 1 } else { q };
                order.insert(at, c);
                s.insert(at, a);
                e.insert(at, b);
                improved = true;
            }
            i += 1;
        }
        if !improved {
            break;
        }
    }
}

/// Travel-minimising order, never longer than the circuit order (the order of `chains`);
/// starts near `from` (the previous layer's end) when given; without it (the first layer),
/// the tour is walked whichever way starts nearer `hint` (the same travel either way).
pub(crate) fn min_travel(chains: Vec<Chain>, graph: &Graph, from: Option<DVec2>, hint: DVec2) -> Vec<Chain> {
    let m = chains.len();
    if m == 0 {
        return chains;
    }
    let ends: Vec<[DVec2; 2]> = chains.iter().map(|c| printed_ends(c, graph)).collect();
    let mut order = if m <= EXACT_CHAINS {
        exact_order(&ends, from)
    } else {
        let mut circuit = best_rotation(&ends, from);
        improve(&mut circuit, &ends, from);
        let mut nn = nearest_neighbour(&ends, from.unwrap_or(ends[0][0]));
        improve(&mut nn, &ends, from);
        if travel_of(&nn, &ends, from) < travel_of(&circuit, &ends, from) - GAIN_MM {
            nn
        } else {
            circuit
        }
    };
    if from.is_none() {
        let (first, last) = (order[0], order[m - 1]);
        if hint.distance(ends[last.0][last.1 as usize ^ 1]) < hint.distance(ends[first.0][first.1 as usize]) {
            order.reverse();
            for o in &mut order {
                o.1 = !o.1;
            }
        }
    }
    apply(chains, order)
}

/// Up to this many chains, [`min_travel`] finds the least travel exactly ([`exact_order`]).
pub(crate) const EXACT_CHAINS: usize = 10;

/// The order and directions of the chains with the least travel ([`travel_of`]), exactly: a
/// dynamic programme over the sets of chains printed (Held–Karp), each state the last chain
/// and its direction; 2^m · 2m states, for m ≤ [`EXACT_CHAINS`]. Ties: the first found in
/// index order.
fn exact_order(ends: &[[DVec2; 2]], from: Option<DVec2>) -> Vec<(usize, bool)> {
    let m = ends.len();
    let states = 2 * m;
    let full = (1usize << m) - 1;
    let mut best = vec![f64::INFINITY; (full + 1) * states];
    let mut back = vec![usize::MAX; (full + 1) * states];
    for i in 0..m {
        for r in 0..2 {
            best[(1 << i) * states + 2 * i + r] = link(from, Some(ends[i][r]));
        }
    }
    for mask in 1..=full {
        for last in 0..states {
            let here = best[mask * states + last];
            if !here.is_finite() {
                continue;
            }
            let at = ends[last / 2][1 - last % 2];
            for j in 0..m {
                if mask & (1 << j) != 0 {
                    continue;
                }
                let next = mask | (1 << j);
                for r in 0..2 {
                    let t = here + at.distance(ends[j][r]);
                    let slot = next * states + 2 * j + r;
                    if t < best[slot] {
                        best[slot] = t;
                        back[slot] = last;
                    }
                }
            }
        }
    }
    crate::work::add((full + 1) * states * states);
    let mut last = (0..states).fold(0, |b, k| if best[full * states + k] < best[full * states + b] { k } else { b });
    let mut mask = full;
    let mut order = Vec::with_capacity(m);
    loop {
        order.push((last / 2, last % 2 == 1));
        let prev = back[mask * states + last];
        mask &= !(1 << (last / 2));
        if prev == usize::MAX {
            break;
        }
        last = prev;
    }
    order.reverse();
    order
}

/// The chains in `order`, reversed where asked.
fn apply(chains: Vec<Chain>, order: Vec<(usize, bool)>) -> Vec<Chain> {
    let mut slots: Vec<Option<Chain>> = chains.into_iter().map(Some).collect();
    order
        .into_iter()
        .map(|(i, r)| {
            let mut c = slots[i].take().expect("each chain once");
            if r {
                c.reverse();
            }
            c
        })
        .collect()
}

/// The user's direction: chains sorted by where they start along `dir` (unit vector; each
/// chain printed from its end lower along `dir`), or, with `dir` none, from the centre of the
/// layer out (each chain printed from its end nearer the centre). Ties by index.
pub(crate) fn sort_directional(chains: Vec<Chain>, graph: &Graph, dir: Option<DVec2>) -> Vec<Chain> {
    let ends: Vec<[DVec2; 2]> = chains.iter().map(|c| printed_ends(c, graph)).collect();
    let mut lo = DVec2::splat(f64::INFINITY);
    let mut hi = DVec2::splat(f64::NEG_INFINITY);
    for p in ends.iter().flatten() {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    let centre = (lo + hi) * 0.5;
    let key = |p: DVec2| match dir {
        Some(d) => p.dot(d),
        None => p.distance(centre),
    };
    let mut keyed: Vec<(f64, usize, bool)> = ends
        .iter()
        .enumerate()
        .map(|(i, e)| {
            let (a, b) = (key(e[0]), key(e[1]));
            if b < a {
                (b, i, true)
            } else {
                (a, i, false)
            }
        })
        .collect();
    keyed.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
    apply(chains, keyed.into_iter().map(|(_, i, r)| (i, r)).collect())
}

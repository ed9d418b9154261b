//! Print order of the chains of a layer (a chain is one GIPPO / Euler path, or one
//! continuous walk of a component).
//!
//! * [`sort_longest_first`]: the paper's order — by printed segments, then printed length,
//!   both descending (stable).
//! * [`min_travel`]: nearest neighbour from the given start point over both ends of every
//!   chain (a chain may be printed reversed), then windowed 2-opt (segment reversal with
//!   chain flips) on the straight travel distances, until no improvement.

use super::graph::Graph;
use super::Chain;
use crate::geom::DVec2;

/// 2-opt window (chains).
const WINDOW: usize = 48;
/// 2-opt passes at most.
const MAX_PASSES: usize = 16;
/// Below this many chains left, nearest neighbour scans them all.
const BRUTE_BELOW: usize = 96;

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
    let mut keyed: Vec<(usize, f64, usize)> = chains.iter().enumerate().map(|(i, c)| {
        let (s, l) = key(c);
        (s, l, i)
    }).collect();
    keyed.sort_by(|x, y| y.0.cmp(&x.0).then(y.1.total_cmp(&x.1)).then(x.2.cmp(&y.2)));
    let mut taken: Vec<Option<Chain>> = chains.iter_mut().map(|c| Some(std::mem::take(c))).collect();
    for (slot, &(_, _, i)) in keyed.iter().enumerate() {
        chains[slot] = taken[i].take().expect("each chain once");
    }
}

/// Travel-minimising order starting near `from`.
pub(crate) fn min_travel(chains: Vec<Chain>, graph: &Graph, from: DVec2) -> Vec<Chain> {
    let m = chains.len();
    if m == 0 {
        return chains;
    }
    let start_of = |c: &Chain| graph.nodes[c.nodes[0]];
    let end_of = |c: &Chain| graph.nodes[*c.nodes.last().expect("chain has nodes")];
    let ends: Vec<[DVec2; 2]> = chains.iter().map(|c| [start_of(c), end_of(c)]).collect();

    // Nearest neighbour over chain ends, on a grid.
    let mut min = DVec2::splat(f64::INFINITY);
    let mut max = DVec2::splat(f64::NEG_INFINITY);
    for e in &ends {
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
    let cell_xy = |p: DVec2| -> (isize, isize) {
        (((p.x - min.x) / cell).floor() as isize, ((p.y - min.y) / cell).floor() as isize)
    };
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
    while !remaining.is_empty() {
        let mut best: Option<(f64, u32)> = None;
        if remaining.len() < BRUTE_BELOW || order.is_empty() {
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
                        if x >= 0 && x < nx as isize {
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
            if let Some(k) = list.iter().position(|&e| e as usize == 2 * i + w) {
                list.swap_remove(k);
            }
        }
    }

    // Windowed 2-opt on (start, end) points of the oriented sequence.
    let mut s: Vec<DVec2> = order.iter().map(|&(i, r)| ends[i][r as usize]).collect();
    let mut e: Vec<DVec2> = order.iter().map(|&(i, r)| ends[i][1 - r as usize]).collect();
    for _ in 0..MAX_PASSES {
        let mut improved = false;
        for i in 0..m {
            let prev = if i == 0 { from } else { e[i - 1] };
            for j in i..m.min(i + WINDOW) {
                let next = if j + 1 < m { Some(s[j + 1]) } else { None };
                let before = prev.distance(s[i]) + next.map_or(0.0, |n| e[j].distance(n));
                let after = prev.distance(e[j]) + next.map_or(0.0, |n| s[i].distance(n));
                if after < before - 1e-9 {
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
        if !improved {
            break;
        }
    }

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

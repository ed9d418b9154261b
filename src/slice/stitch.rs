//! Segments → closed loops.
//!
//! 1. Exact chaining: segment ends are integer micrometre points, so a segment continues the
//!    one whose end equals its start. Lookup is by binary search in a sorted table (no hash
//!    maps: the output order depends only on the input).
//! 2. Gap closing: the remaining open chains are joined end → start, nearest pairs first,
//!    when the ends are at most `gap_closing` apart (a chain may close on itself). Joins of
//!    zero length only repair the chaining order and are not counted as gaps.
//! 3. Flipped triangles: chains still open are joined end to end in either direction (nearest
//!    ends first, same gap limit); a loop closed this way takes the orientation of the
//!    majority (by length) of its pieces.
//! 4. Chains still open are dropped and counted. Gaps are counted only in loops that closed.
//!
//! Closed loops lose points within 1 µm of the line through their neighbours (the collinear
//! cut through a facet's two triangles), see [`simplify`].

use super::plane::{Pt, Seg};

/// What stitching repaired.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct StitchStats {
    pub gaps_closed: usize,
    /// Largest gap closed, µm.
    pub largest_gap_um: f64,
    pub open_dropped: usize,
}

#[inline]
fn dist2(a: Pt, b: Pt) -> i64 {
    let dx = a[0] as i64 - b[0] as i64;
    let dy = a[1] as i64 - b[1] as i64;
    dx * dx + dy * dy
}

/// Removes points that deviate at most 1 µm from the line through their kept neighbours
/// (the rounding of cut points to whole micrometres makes facets' collinear cuts jitter),
/// and repeated points. Deterministic single pass plus a wrap-around fix-up.
pub(crate) fn simplify(pts: &mut Vec<Pt>) {
    // |cross(b − a, c − a)| <= 1 µm × |c − a| means b is within 1 µm of the line a–c.
    fn keep(a: Pt, b: Pt, c: Pt) -> bool {
        let (ax, ay) = (a[0] as i64, a[1] as i64);
        let (ux, uy) = (b[0] as i64 - ax, b[1] as i64 - ay);
        let (vx, vy) = (c[0] as i64 - ax, c[1] as i64 - ay);
        let cross = (ux as i128) * (vy as i128) - (uy as i128) * (vx as i128);
        let len2 = (vx as i128) * (vx as i128) + (vy as i128) * (vy as i128);
        // Also keep b when it lies beyond the segment a–c (a spike doubling back).
        let dot = (ux as i128) * (vx as i128) + (uy as i128) * (vy as i128);
        cross * cross > len2 || dot < 0 || dot > len2
    }
    pts.dedup();
    while pts.len() > 1 && pts.first() == pts.last() {
        pts.pop();
    }
    if pts.len() < 4 {
        return;
    }
    let mut out: Vec<Pt> = Vec::with_capacity(pts.len());
    for &p in pts.iter() {
        while out.len() >= 2 && !keep(out[out.len() - 2], out[out.len() - 1], p) {
            out.pop();
        }
        out.push(p);
    }
    // Wrap-around: the last and first points against their cyclic neighbours.
    while out.len() >= 4 && !keep(out[out.len() - 2], out[out.len() - 1], out[0]) {
        out.pop();
    }
    while out.len() >= 4 && !keep(out[out.len() - 1], out[0], out[1]) {
        out.remove(0);
    }
    *pts = out;
}

/// Chains `segs` into closed loops (points in µm, last point not repeated). `segs` is sorted
/// and deduplicated in place (identical directed segments come from duplicate triangles).
pub(crate) fn stitch(segs: &mut Vec<Seg>, gap_um: f64) -> (Vec<Vec<Pt>>, StitchStats) {
    let mut stats = StitchStats::default();
    segs.sort_unstable();
    segs.dedup();
    let n = segs.len();
    // Segments sorted by start point: `segs` itself (sorted by (a, b)).
    let mut used = vec![false; n];
    // Per start point, the first candidate not yet tried (skips used ones quickly).
    let find_next = |used: &[bool], p: Pt| -> Option<usize> {
        let mut i = segs.partition_point(|s| s.a < p);
        while i < n && segs[i].a == p {
            if !used[i] {
                return Some(i);
            }
            i += 1;
        }
        None
    };

    let mut loops: Vec<Vec<Pt>> = Vec::new();
    let mut open: Vec<Vec<Pt>> = Vec::new();
    for i in 0..n {
        if used[i] {
            continue;
        }
        used[i] = true;
        let start = segs[i].a;
        let mut chain = vec![start, segs[i].b];
        let mut cur = segs[i].b;
        let mut closed = false;
        while let Some(j) = find_next(&used, cur) {
            used[j] = true;
            cur = segs[j].b;
            if cur == start {
                closed = true;
                break;
            }
            chain.push(cur);
        }
        if closed {
            simplify(&mut chain);
            if chain.len() >= 3 {
                loops.push(chain);
            }
        } else {
            open.push(chain);
        }
    }
    if open.is_empty() {
        return (loops, stats);
    }

    // Join open chains: candidate pairs (end of i, start of j) within the gap, nearest first.
    let gap = gap_um.max(0.0);
    let gap2 = (gap * gap).floor() as i64;
    let reach = gap.ceil() as i64;
    let mut starts: Vec<(Pt, usize)> = open.iter().enumerate().map(|(j, c)| (c[0], j)).collect();
    starts.sort_unstable();
    let mut cands: Vec<(i64, usize, usize)> = Vec::new();
    for (i, c) in open.iter().enumerate() {
        let e = *c.last().unwrap();
        let lo = starts.partition_point(|(p, _)| (p[0] as i64) < e[0] as i64 - reach);
        for &(p, j) in &starts[lo..] {
            if p[0] as i64 > e[0] as i64 + reach {
                break;
            }
            let d2 = dist2(e, p);
            if d2 <= gap2 {
                cands.push((d2, i, j));
            }
        }
    }
    cands.sort_unstable();
    let m = open.len();
    let mut next: Vec<Option<usize>> = vec![None; m];
    let mut has_prev = vec![false; m];
    let mut join_d2 = vec![0i64; m];
    // Groups (union-find) so that joining i→j when j already leads back to i closes a loop,
    // which is allowed; any pair is allowed as long as both ends are free.
    for &(d2, i, j) in &cands {
        if next[i].is_some() || has_prev[j] {
            continue;
        }
        next[i] = Some(j);
        has_prev[j] = true;
        join_d2[i] = d2;
    }
    // Gaps are counted only once their loop is closed (a dropped chain repairs nothing).
    let count_gap = |stats: &mut StitchStats, d2: i64| {
        if d2 > 0 {
            stats.gaps_closed += 1;
            stats.largest_gap_um = stats.largest_gap_um.max((d2 as f64).sqrt());
        }
    };
    // Walk: open paths start at chains without predecessor; what remains are cycles.
    let mut visited = vec![false; m];
    // Open paths with the lengths² of the joins inside them.
    let mut paths: Vec<(Vec<Pt>, Vec<i64>)> = Vec::new();
    let concat = |pts: &mut Vec<Pt>, c: &[Pt]| {
        for &p in c {
            if pts.last() != Some(&p) {
                pts.push(p);
            }
        }
    };
    for s in 0..m {
        if has_prev[s] || visited[s] {
            continue;
        }
        let mut pts = Vec::new();
        let mut gaps = Vec::new();
        let mut k = Some(s);
        while let Some(c) = k {
            visited[c] = true;
            concat(&mut pts, &open[c]);
            k = next[c];
            if k.is_some() {
                gaps.push(join_d2[c]);
            }
        }
        paths.push((pts, gaps));
    }
    for s in 0..m {
        if visited[s] {
            continue;
        }
        let mut pts: Vec<Pt> = Vec::new();
        let mut c = s;
        while !visited[c] {
            visited[c] = true;
            concat(&mut pts, &open[c]);
            count_gap(&mut stats, join_d2[c]);
            match next[c] {
                Some(nc) => c = nc,
                None => break,
            }
        }
        simplify(&mut pts);
        if pts.len() >= 3 {
            loops.push(pts);
        }
    }
    if !paths.is_empty() {
        join_undirected(paths, gap2, reach, &mut loops, &mut stats);
    }
    (loops, stats)
}

fn path_len(p: &[Pt]) -> f64 {
    p.windows(2).map(|w| (dist2(w[0], w[1]) as f64).sqrt()).sum()
}

/// Last resort for inconsistently oriented triangles (a flipped triangle's segment runs
/// backwards, so directed chaining stops at it): joins the remaining open paths end to end
/// in either direction, nearest ends first, within the gap. A closed result is oriented like
/// the majority (by length) of its pieces. Paths still open are dropped and counted.
fn join_undirected(paths: Vec<(Vec<Pt>, Vec<i64>)>, gap2: i64, reach: i64, loops: &mut Vec<Vec<Pt>>, stats: &mut StitchStats) {
    let m = paths.len();
    // End e of path p has id 2p + e (e = 0: first point, e = 1: last point).
    let end_pt = |id: usize| if id % 2 == 0 { paths[id / 2].0[0] } else { *paths[id / 2].0.last().unwrap() };
    let mut ends: Vec<(Pt, usize)> = (0..2 * m).map(|id| (end_pt(id), id)).collect();
    ends.sort_unstable();
    let mut cands: Vec<(i64, usize, usize)> = Vec::new();
    for (i, &(p, a)) in ends.iter().enumerate() {
        for &(q, b) in &ends[i + 1..] {
            if q[0] as i64 > p[0] as i64 + reach {
                break;
            }
            let d2 = dist2(p, q);
            if d2 <= gap2 {
                cands.push((d2, a.min(b), a.max(b)));
            }
        }
    }
    cands.sort_unstable();
    let mut link: Vec<Option<usize>> = vec![None; 2 * m];
    for &(_, a, b) in &cands {
        if link[a].is_some() || link[b].is_some() {
            continue;
        }
        link[a] = Some(b);
        link[b] = Some(a);
    }
    // Groups: follow path → its other end → link → next path.
    let mut seen = vec![false; m];
    let mut closed_joins = Vec::new();
    for s in 0..m {
        if seen[s] {
            continue;
        }
        // Find one free end of the group, if any (open group), by walking from s's end 0.
        let mut id = 2 * s;
        let mut cycle = false;
        loop {
            match link[id] {
                None => break,
                Some(o) => {
                    id = o ^ 1; // through the linked path to its far end
                    if id / 2 == s {
                        cycle = true;
                        break;
                    }
                }
            }
        }
        // Walk from `start` (an end id): enter the path at that end, leave by the other.
        let start = if cycle { 2 * s } else { id };
        let mut pts: Vec<Pt> = Vec::new();
        let mut forward_len = 0.0;
        let mut cur = start;
        loop {
            let p = cur / 2;
            if seen[p] {
                break;
            }
            seen[p] = true;
            let piece = &paths[p].0;
            closed_joins.extend_from_slice(&paths[p].1);
            let l = path_len(piece);
            if cur % 2 == 0 {
                forward_len += l;
                for &q in piece {
                    if pts.last() != Some(&q) {
                        pts.push(q);
                    }
                }
            } else {
                forward_len -= l;
                for &q in piece.iter().rev() {
                    if pts.last() != Some(&q) {
                        pts.push(q);
                    }
                }
            }
            match link[cur ^ 1] {
                Some(o) => {
                    if cycle || !seen[o / 2] {
                        closed_joins.push(dist2(end_pt(cur ^ 1), end_pt(o)));
                    }
                    cur = o;
                }
                None => break,
            }
        }
        if !cycle {
            closed_joins.clear();
            stats.open_dropped += 1;
            continue;
        }
        for d2 in closed_joins.drain(..) {
            if d2 > 0 {
                stats.gaps_closed += 1;
                stats.largest_gap_um = stats.largest_gap_um.max((d2 as f64).sqrt());
            }
        }
        if forward_len < 0.0 {
            pts.reverse();
        }
        simplify(&mut pts);
        if pts.len() >= 3 {
            loops.push(pts);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square_segs(offset: i32) -> Vec<Seg> {
        let p = [[0, 0], [1000, 0], [1000, 1000], [0, 1000]];
        (0..4).map(|i| Seg { a: [p[i][0] + offset, p[i][1]], b: [p[(i + 1) % 4][0] + offset, p[(i + 1) % 4][1]] }).collect()
    }

    #[test]
    fn closes_exact_loop_and_ignores_duplicates() {
        let mut segs = square_segs(0);
        segs.extend(square_segs(0));
        let (loops, st) = stitch(&mut segs, 50.0);
        assert_eq!(loops.len(), 1);
        assert_eq!(loops[0].len(), 4);
        assert_eq!(st, StitchStats::default());
    }

    #[test]
    fn closes_small_gap_and_drops_large() {
        let mut segs = square_segs(0);
        segs[1].a[0] += 20; // 20 µm gap between segment 0's end and segment 1's start
        let (loops, st) = stitch(&mut segs, 50.0);
        assert_eq!(loops.len(), 1);
        assert_eq!(st.gaps_closed, 1);
        assert!((st.largest_gap_um - 20.0).abs() < 1e-9);

        let mut segs = square_segs(0);
        segs.remove(2);
        let (loops, st) = stitch(&mut segs, 50.0);
        assert!(loops.is_empty());
        assert_eq!(st.open_dropped, 1);
    }

    #[test]
    fn simplify_drops_jittered_collinear_points() {
        let mut l = vec![[0, 0], [500, 1], [1000, 0], [1000, 1000], [500, 999], [0, 1000], [0, 500]];
        simplify(&mut l);
        assert_eq!(l, vec![[0, 0], [1000, 0], [1000, 1000], [0, 1000]]);
        let mut t = vec![[0, 0], [1000, 0], [0, 1000]];
        simplify(&mut t);
        assert_eq!(t.len(), 3);
    }

    #[test]
    fn flipped_segment_is_joined_and_oriented_by_majority() {
        let mut segs = square_segs(0);
        segs[1] = Seg { a: segs[1].b, b: segs[1].a };
        let (loops, st) = stitch(&mut segs, 50.0);
        assert_eq!(loops.len(), 1);
        assert_eq!(st, StitchStats::default());
        let l = &loops[0];
        let twice: i64 = (0..l.len())
            .map(|i| {
                let (a, b) = (l[i], l[(i + 1) % l.len()]);
                a[0] as i64 * b[1] as i64 - b[0] as i64 * a[1] as i64
            })
            .sum();
        assert_eq!(twice, 2_000_000, "counter-clockwise like three of its four pieces");
    }

    #[test]
    fn chaining_from_the_middle_is_repaired() {
        // Start point ordering makes the first chain begin mid-contour.
        let mut segs = square_segs(0);
        segs.reverse();
        let (loops, st) = stitch(&mut segs, 0.0);
        assert_eq!(loops.len(), 1);
        assert_eq!(st.gaps_closed, 0);
    }
}

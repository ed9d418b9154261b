//! Isolines of a slice image by marching squares (the paper's figure 8: isocurves at 250, 350
//! and 600 HU over a CT slice).
//!
//! Method. Cells join four neighbouring pixel centres. A corner is *high* when its value is
//! `≥ level`. Every cell edge with one high and one low end is crossed once, at the point
//! where the linear interpolation along the edge equals the level (computed from the edge
//! alone, so the two cells sharing an edge give the same bits). A cell with two crossings
//! has one segment; a saddle (two opposite high corners) has two, and the average of the four
//! corners decides which way: average `≥ level` joins the high corners (the low ones are cut
//! off), otherwise the high corners are cut off. Cells with a non-finite corner are skipped.
//!
//! Orientation. Walking a cell's boundary counter-clockwise (in the image's x-right, y-up
//! frame: corners `(c, r) → (c+1, r) → (c+1, r+1) → (c, r+1)`), crossings alternate between
//! *leaving* the high set and *entering* it; each segment runs from a leaving crossing to an
//! entering one, which puts the high side on its **left**: with `d = (x1 − x0, y1 − y0)`, the
//! values increase towards `(−d.y, d.x)`. (Drawn with row 0 at the top, y down, that is the
//! right-hand side on screen.) A closed isoline around a peak therefore runs counter-clockwise
//! in the x-right, y-up frame (positive signed area), one around a pit clockwise.
//!
//! Chaining. A crossed edge ends the segment of one cell and starts the segment of its
//! neighbour, so the segments link into polylines by edge identity (exact, no tolerance).
//! Output is level by level; within a level, open polylines (ending at the image border or at
//! skipped cells) first, in the order of their first segment's cell, then closed loops; each
//! polyline's segments in order, so a segment's end is the next segment's start. Segments of
//! zero length (a corner exactly at the level) are left out; the polyline stays continuous.
//! No hash map: the order is the same on every target.

use super::SliceImage;

/// One segment being chained: the crossed edges it starts and ends on.
#[derive(Clone, Copy)]
struct Seg {
    from: usize,
    to: usize,
}

/// Marching squares on a slice image at each level: segments in the image's mm frame
/// (x = column·pixel_mm[0], y = row·pixel_mm[1], pixel centres), each
/// `[x0, y0, x1, y1, level_index]`; saddles resolved by the cell-centre average; each segment
/// has the higher values on its left (`(−dy, dx)` side, x-right y-up), and segments are
/// chained so that each one's end is the next one's start along an isoline. Non-finite levels
/// give no segments. The output holds at most two segments per cell and level.
pub fn isolines(image: &SliceImage, levels: &[f64]) -> Vec<[f32; 5]> {
    let (w, h) = (image.width, image.height);
    let mut out = Vec::new();
    if w < 2 || h < 2 || image.values.len() < w * h {
        return out;
    }
    // Edge ids: horizontal edges (c, r)–(c+1, r) first, then vertical (c, r)–(c, r+1).
    let horizontal = (w - 1) * h;
    let edge_ends = |e: usize| -> ((usize, usize), (usize, usize)) {
        if e < horizontal {
            let (c, r) = (e % (w - 1), e / (w - 1));
            ((c, r), (c + 1, r))
        } else {
            let e = e - horizontal;
            let (c, r) = (e % w, e / w);
            ((c, r), (c, r + 1))
        }
    };
    let value = |(c, r): (usize, usize)| f64::from(image.values[c + w * r]);
    for (li, &level) in levels.iter().enumerate() {
        if !level.is_finite() {
            continue;
        }
        let mut segs: Vec<Seg> = Vec::new();
        for r in 0..h - 1 {
            for c in 0..w - 1 {
                cell(c, r, level, &value, w, horizontal, &mut segs);
            }
        }
        if segs.is_empty() {
            continue;
        }
        // Each edge starts at most one segment and ends at most one: sorted lookups.
        let mut by_from: Vec<usize> = (0..segs.len()).collect();
        by_from.sort_unstable_by_key(|&s| segs[s].from);
        let mut ends: Vec<usize> = segs.iter().map(|s| s.to).collect();
        ends.sort_unstable();
        let next = |edge: usize| by_from.binary_search_by_key(&edge, |&s| segs[s].from).ok().map(|p| by_from[p]);
        let point = |e: usize| -> [f32; 2] {
            let (a, b) = edge_ends(e);
            let (va, vb) = (value(a), value(b));
            let t = ((level - va) / (vb - va)).clamp(0.0, 1.0);
            let x = (a.0 as f64 + t * (b.0 as f64 - a.0 as f64)) * image.pixel_mm[0];
            let y = (a.1 as f64 + t * (b.1 as f64 - a.1 as f64)) * image.pixel_mm[1];
            [x as f32, y as f32]
        };
        let mut used = vec![false; segs.len()];
        let emit = |start: usize, used: &mut Vec<bool>, out: &mut Vec<[f32; 5]>| {
            let mut s = start;
            while !used[s] {
                used[s] = true;
                let (p, q) = (point(segs[s].from), point(segs[s].to));
                if p != q {
                    out.push([p[0], p[1], q[0], q[1], li as f32]);
                }
                match next(segs[s].to) {
                    Some(n) => s = n,
                    None => break,
                }
            }
        };
        // Open polylines start on an edge that no segment ends on.
        for s in 0..segs.len() {
            if !used[s] && ends.binary_search(&segs[s].from).is_err() {
                emit(s, &mut used, &mut out);
            }
        }
        for s in 0..segs.len() {
            if !used[s] {
                emit(s, &mut used, &mut out);
            }
        }
    }
    out
}

/// The segments of cell `(c, r)` at `level`, oriented high-on-the-left.
fn cell(c: usize, r: usize, level: f64, value: &impl Fn((usize, usize)) -> f64, w: usize, horizontal: usize, segs: &mut Vec<Seg>) {
    // Corners counter-clockwise (x right, y up) and the edge from each to the next.
    let corners = [(c, r), (c + 1, r), (c + 1, r + 1), (c, r + 1)];
    let v = corners.map(value);
    if v.iter().any(|x| !x.is_finite()) {
        return;
    }
    let high = v.map(|x| x >= level);
    let edges = [c + (w - 1) * r, horizontal + (c + 1) + w * r, c + (w - 1) * (r + 1), horizontal + c + w * r];
    // Crossings on edge e (corner e → corner e+1): leaving when high → low.
    let mut leaving = [false; 4];
    let mut crossed = [false; 4];
    for e in 0..4 {
        let (a, b) = (high[e], high[(e + 1) % 4]);
        crossed[e] = a != b;
        leaving[e] = a && !b;
    }
    match crossed.iter().filter(|&&x| x).count() {
        2 => {
            // Around a cell the crossings alternate, so of two one leaves and one enters.
            let from = (0..4).find(|&e| crossed[e] && leaving[e]);
            let to = (0..4).find(|&e| crossed[e] && !leaving[e]);
            if let (Some(from), Some(to)) = (from, to) {
                segs.push(Seg { from: edges[from], to: edges[to] });
            }
        }
        4 => {
            // Saddle. Centre high: the low corners are cut off, each leaving crossing pairs
            // with the next edge's entering one; centre low: the high corners are cut off,
            // each leaving crossing pairs with the previous edge's entering one.
            let centre_high = (v[0] + v[1] + v[2] + v[3]) / 4.0 >= level;
            for e in (0..4).filter(|&e| leaving[e]) {
                let to = if centre_high { (e + 1) % 4 } else { (e + 3) % 4 };
                segs.push(Seg { from: edges[e], to: edges[to] });
            }
        }
        _ => {}
    }
}

//! Overlap: extruded length lying on earlier extrusions of the same layer.
//!
//! A later segment B lies on an earlier segment A where the two are nearly parallel (angle
//! ≤ 10°, either direction), B is within half a line width (the mean of the two widths,
//! halved) of A's line, and B's point projects inside A. For each B the parameter intervals
//! found against all earlier segments are unioned, so nothing counts twice. Segments that
//! only meet at an end point or cross count zero.
//!
//! Candidates come from a uniform grid hashed into a table of linked lists: every segment is
//! cut into pieces no longer than a cell; each segment first queries the cells of its pieces'
//! boxes grown by the tolerance, then registers itself in the cells its pieces' boxes touch.
//!
//! Cost stays linear in the number of segments whatever they are:
//! - the cell is 3 line widths, grown when the layer's segments are long so that they make at
//!   most [`PIECES_PER_SEGMENT`] pieces each on average (long moves crossing the bed do not
//!   visit thousands of cells each);
//! - a query walks at most [`MAX_WALK`] entries of a cell, newest first, and stops as soon as
//!   the segment is covered end to end but for 10⁻⁹ of its length (a move repeated or stacked
//!   many times is covered by a recent copy, so it does not compare with every earlier copy).
//!
//! A segment therefore visits at most about 9 cells per piece and [`MAX_WALK`] entries per cell
//! (the worst case, a blob of segments through one spot in every direction, costs about
//! 10 µs a segment; a print about 0.1 µs).
//!
//! These bounds do not change the figure on real prints beyond rounding: the result does not
//! depend on the cell size, and a cell of a print holds far fewer than [`MAX_WALK`] segments
//! (lines at least a width apart cross a cell a few at a time, even a grown one: see
//! [`PIECES_PER_SEGMENT`]); only hostile input (hundreds of segments through one spot that do
//! not cover each other) has candidates left unexamined.

/// One extrusion segment: x, y in the layer plane, z kept so that a non-planar layer (a
/// path over a curved surface, whose parts may lie above one another) counts only what
/// also lies within half a width in height.
#[derive(Clone, Copy, Debug)]
pub struct Seg {
    /// Start x, y (mm).
    pub a: [f64; 2],
    /// End x, y (mm).
    pub b: [f64; 2],
    /// Start and end z (mm).
    pub z: [f64; 2],
    /// Line width (mm).
    pub w: f64,
}

/// sin(10°).
const SIN_MAX_ANGLE: f64 = 0.173_648_177_666_930_35;
/// Segments spanning more than this along X or Y are ignored by the overlap measure, mm.
pub const MAX_SPAN_MM: f64 = 2000.0;
/// Pieces per segment at most.
const MAX_PIECES: usize = 8192;
/// Mean pieces per segment the cell size allows before it grows: a layer whose segments span
/// less than about 5 mm on average keeps the 3-width cell; one of long infill lines gets cells
/// a quarter of their length (so a cell of a solid 300 mm layer holds about 160 of them, under
/// [`MAX_WALK`]). Low, because the registrations (memory) grow with it.
pub const PIECES_PER_SEGMENT: f64 = 4.0;
/// Entries of one cell a query walks at most (newest first).
pub const MAX_WALK: usize = 256;
/// Cells per piece axis at most (only reached after the piece cap).
const MAX_CELLS_AXIS: i64 = 16;

/// Reusable buffers.
#[derive(Default)]
pub struct Overlap {
    /// First node of each bucket's list.
    head: Vec<u32>,
    /// List nodes: [next node, segment].
    nodes: Vec<[u32; 2]>,
    /// Last query (2j) or registration (2j + 1) that visited each bucket.
    bucket_stamp: Vec<u32>,
    /// Last query that tested each segment.
    stamp: Vec<u32>,
    /// Prepared segments of the layer.
    prep: Vec<Prep>,
    intervals: Vec<(f64, f64)>,
}

#[inline]
fn cell_of(v: f64, inv: f64) -> i64 {
    // floor without a libm call; `as` saturates and maps NaN to 0.
    let t = v * inv;
    let c = t as i64;
    if (c as f64) > t {
        c - 1
    } else {
        c
    }
}

#[inline]
fn bucket(cx: i64, cy: i64, mask: u64) -> u32 {
    let h = (cx as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ (cy as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F);
    ((h ^ (h >> 29)) & mask) as u32
}

/// The extent of `s` along X or Y, when it takes part in overlap (finite, not longer than any
/// printer, at a sane position).
#[inline]
fn span(s: &Seg) -> Option<f64> {
    let span = (s.b[0] - s.a[0]).abs().max((s.b[1] - s.a[1]).abs());
    let sane = span <= MAX_SPAN_MM && s.a[0].abs() <= 1e9 && s.a[1].abs() <= 1e9;
    sane.then_some(span)
}

/// Pieces a segment of extent `span` is cut into (each no longer than a cell `cs`).
#[inline]
fn pieces(span: f64, cs: f64) -> usize {
    ((span / cs).ceil() as usize).clamp(1, MAX_PIECES)
}

/// Calls `f(cx, cy)` for every cell touched by the box of each piece of `s`, grown by `grow`,
/// until `f` returns false.
#[inline]
fn for_piece_cells(s: &Seg, cs: f64, grow: f64, mut f: impl FnMut(i64, i64) -> bool) {
    let inv = 1.0 / cs;
    let dx = s.b[0] - s.a[0];
    let dy = s.b[1] - s.a[1];
    // Pieces no longer than a cell along either axis. Segments longer than any printer
    // (or at non-finite positions) take no part in overlap.
    let Some(span) = span(s) else { return };
    let n = pieces(span, cs);
    let step = 1.0 / n as f64;
    for k in 0..n {
        let t0 = k as f64 * step;
        let t1 = if k + 1 == n { 1.0 } else { (k + 1) as f64 * step };
        let (x0, y0) = (s.a[0] + dx * t0, s.a[1] + dy * t0);
        let (x1, y1) = (s.a[0] + dx * t1, s.a[1] + dy * t1);
        let cx0 = cell_of(x0.min(x1) - grow, inv);
        let cx1 = cell_of(x0.max(x1) + grow, inv).min(cx0.saturating_add(MAX_CELLS_AXIS));
        let cy0 = cell_of(y0.min(y1) - grow, inv);
        let cy1 = cell_of(y0.max(y1) + grow, inv).min(cy0.saturating_add(MAX_CELLS_AXIS));
        let mut cy = cy0;
        while cy <= cy1 {
            let mut cx = cx0;
            while cx <= cx1 {
                if !f(cx, cy) {
                    return;
                }
                cx += 1;
            }
            cy += 1;
        }
    }
}

/// A segment with the quantities [`on_segment`] needs, computed once per segment (not once
/// per candidate pair).
#[derive(Clone, Copy, Debug)]
struct Prep {
    /// Start x, y.
    a: [f64; 2],
    /// End x, y.
    b: [f64; 2],
    /// End minus start.
    d: [f64; 2],
    /// Squared length.
    l2: f64,
    /// Start z and its change (0 in a planar layer).
    z: [f64; 2],
    /// Line width.
    w: f64,
}

impl Prep {
    #[inline]
    fn new(s: &Seg) -> Prep {
        let (dx, dy) = (s.b[0] - s.a[0], s.b[1] - s.a[1]);
        Prep { a: s.a, b: s.b, d: [dx, dy], l2: dx * dx + dy * dy, z: [s.z[0], s.z[1] - s.z[0]], w: s.w }
    }
}

/// The part of `b` (as a parameter interval of `b`) lying on `a`, if longer than nothing.
#[inline]
fn on_segment(a: &Prep, b: &Prep) -> Option<(f64, f64)> {
    if a.z[1] != 0.0 || b.z[1] != 0.0 || a.z[0] != b.z[0] {
        return on_segment_3d(a, b);
    }
    let [ax, ay] = a.d;
    let [bx, by] = b.d;
    let la2 = a.l2;
    let lb2 = b.l2;
    if !(la2 > 0.0 && lb2 > 0.0) {
        return None;
    }
    let cross = ax * by - ay * bx;
    if cross * cross > SIN_MAX_ANGLE * SIN_MAX_ANGLE * la2 * lb2 {
        return None;
    }
    let tol = 0.25 * (a.w + b.w);
    // Cheap rejections (no square roots): B wholly to one side of A's line beyond the
    // tolerance, or wholly before or after A along it.
    let (rx, ry) = (b.a[0] - a.a[0], b.a[1] - a.a[1]);
    let (qx, qy) = (b.b[0] - a.a[0], b.b[1] - a.a[1]);
    let c0 = ax * ry - ay * rx;
    let c1 = ax * qy - ay * qx;
    if (c0 > 0.0) == (c1 > 0.0) {
        let m = c0.abs().min(c1.abs());
        if m * m > tol * tol * la2 {
            return None;
        }
    }
    let p0 = ax * rx + ay * ry;
    let p1 = ax * qx + ay * qy;
    if (p0 <= 0.0 && p1 <= 0.0) || (p0 >= la2 && p1 >= la2) {
        return None;
    }
    let la = la2.sqrt();
    let (ux, uy) = (ax / la, ay / la);
    // Lateral distance d(t) = d0 + t·dd and projection s(t) = s0 + t·ds along A.
    let d0 = rx * -uy + ry * ux;
    let dd = bx * -uy + by * ux;
    let s0 = rx * ux + ry * uy;
    let ds = bx * ux + by * uy;
    let mut lo = 0.0f64;
    let mut hi = 1.0f64;
    clip(&mut lo, &mut hi, d0, dd, -tol, tol)?;
    clip(&mut lo, &mut hi, s0, ds, 0.0, la)?;
    if hi - lo > 1e-12 {
        Some((lo, hi))
    } else {
        None
    }
}

/// [`on_segment`] in space, for segments not in one horizontal plane (a path over a curved
/// surface, where parts of one layer lie above one another or run up a wall): the same rule
/// with the angle, the lateral distance and the projection measured in 3-D. In a horizontal
/// plane it gives the planar rule's interval.
fn on_segment_3d(a: &Prep, b: &Prep) -> Option<(f64, f64)> {
    let da = [a.d[0], a.d[1], a.z[1]];
    let db = [b.d[0], b.d[1], b.z[1]];
    let dot = |p: [f64; 3], q: [f64; 3]| p[0] * q[0] + p[1] * q[1] + p[2] * q[2];
    let (la2, lb2) = (dot(da, da), dot(db, db));
    if !(la2 > 0.0 && lb2 > 0.0) {
        return None;
    }
    let c = [da[1] * db[2] - da[2] * db[1], da[2] * db[0] - da[0] * db[2], da[0] * db[1] - da[1] * db[0]];
    if dot(c, c) > SIN_MAX_ANGLE * SIN_MAX_ANGLE * la2 * lb2 {
        return None;
    }
    let tol = 0.25 * (a.w + b.w);
    let la = la2.sqrt();
    let u = [da[0] / la, da[1] / la, da[2] / la];
    // B(t) − A's start: r0 + t·db; along A: s(t) = s0 + t·ds; across: l(t) = l0 + t·dl.
    let r0 = [b.a[0] - a.a[0], b.a[1] - a.a[1], b.z[0] - a.z[0]];
    let (s0, ds) = (dot(r0, u), dot(db, u));
    let l0 = [r0[0] - s0 * u[0], r0[1] - s0 * u[1], r0[2] - s0 * u[2]];
    let dl = [db[0] - ds * u[0], db[1] - ds * u[1], db[2] - ds * u[2]];
    let mut lo = 0.0f64;
    let mut hi = 1.0f64;
    clip(&mut lo, &mut hi, s0, ds, 0.0, la)?;
    // |l(t)|² ≤ tol²: a convex quadratic in t.
    let (qa, qb, qc) = (dot(dl, dl), 2.0 * dot(l0, dl), dot(l0, l0) - tol * tol);
    if qa > 0.0 {
        let disc = qb * qb - 4.0 * qa * qc;
        if disc < 0.0 {
            return None;
        }
        let root = disc.sqrt();
        lo = lo.max((-qb - root) / (2.0 * qa));
        hi = hi.min((-qb + root) / (2.0 * qa));
    } else if qc > 0.0 {
        return None;
    }
    if hi - lo > 1e-12 {
        Some((lo, hi))
    } else {
        None
    }
}

/// Narrows `[lo, hi]` to where `v0 + t·dv` lies in `[min, max]`.
#[inline]
fn clip(lo: &mut f64, hi: &mut f64, v0: f64, dv: f64, min: f64, max: f64) -> Option<()> {
    if dv == 0.0 {
        return if v0 >= min && v0 <= max { Some(()) } else { None };
    }
    let mut t0 = (min - v0) / dv;
    let mut t1 = (max - v0) / dv;
    if t0 > t1 {
        std::mem::swap(&mut t0, &mut t1);
    }
    *lo = lo.max(t0);
    *hi = hi.min(t1);
    if *hi > *lo {
        Some(())
    } else {
        None
    }
}

/// Whether a parameter interval covers a whole segment but for rounding: the search stops
/// there, since what other candidates could still add is below 2·10⁻⁹ of its length.
#[inline]
fn covers(iv: (f64, f64)) -> bool {
    iv.0 <= 1e-9 && iv.1 >= 1.0 - 1e-9
}

/// Merges `iv` (parameter intervals within [0, 1]) into disjoint sorted intervals, in place.
/// Comparisons only, so the covered length is the same whenever and however often it is done.
fn merge(iv: &mut Vec<(f64, f64)>) {
    iv.sort_by(|x, y| x.0.total_cmp(&y.0));
    let mut w = 0;
    for r in 1..iv.len() {
        let (l, h) = iv[r];
        if l > iv[w].1 {
            w += 1;
            iv[w] = (l, h);
        } else if h > iv[w].1 {
            iv[w].1 = h;
        }
    }
    iv.truncate(w + 1);
}

/// Bytes [`Overlap::layer`] holds for a layer of `segments` segments at most (its buffers and
/// the caller's segment list), for the analyzer's memory estimate.
pub fn layer_bytes(segments: usize) -> usize {
    use std::mem::size_of;
    // Per segment: the caller's list (grown by doubling: up to twice its length) and its path
    // records (16 bytes, doubled), the prepared copy, the stamp; registrations (a segment's
    // first piece touches at most 4 cells, each further one at most 3 new ones, and pieces are
    // at most 1 + PIECES_PER_SEGMENT per segment on average); buckets (head and stamp, at most
    // 4 per segment rounded up to a power of two).
    let pieces = 1 + PIECES_PER_SEGMENT as usize;
    let per = 2 * size_of::<Seg>() + 2 * 16 + size_of::<Prep>() + 4 + (1 + 3 * pieces) * 8 + 8 * 8;
    segments.saturating_mul(per)
}

impl Overlap {
    /// Total overlapping length of `segs` (in print order), mm.
    pub fn layer(&mut self, segs: &[Seg], default_width: f64) -> f64 {
        if segs.len() < 2 || segs.len() >= (u32::MAX / 2) as usize {
            return 0.0;
        }
        let mut wmax = 0.0f64;
        for s in segs {
            if s.w.is_finite() && s.w > wmax {
                wmax = s.w;
            }
        }
        if wmax <= 0.0 {
            wmax = if default_width > 0.0 && default_width.is_finite() { default_width } else { 0.4 };
        }
        // Long segments grow the cell so that the layer makes at most PIECES_PER_SEGMENT pieces
        // per segment on average.
        let total_span: f64 = segs.iter().filter_map(span).sum();
        let cs = (3.0 * wmax).max(0.5).max(total_span / (PIECES_PER_SEGMENT * segs.len() as f64));
        let total_pieces: usize = segs.iter().map(|s| span(s).map_or(0, |sp| pieces(sp, cs))).sum();
        let grow = 0.5 * wmax + 1e-9;

        // Incremental grid: query a segment against what is registered, then register it.
        // A bucket is walked at most once per query and holds a segment at most once (both
        // through `bucket_stamp`); each segment is tested at most once per query (`stamp`).
        let buckets = (2 * total_pieces).clamp(segs.len(), 4 * segs.len()).next_power_of_two().max(64);
        let probe_mask = (buckets - 1) as u64;
        self.head.clear();
        self.head.resize(buckets, u32::MAX);
        self.bucket_stamp.clear();
        self.bucket_stamp.resize(buckets, u32::MAX);
        self.nodes.clear();
        self.stamp.clear();
        self.stamp.resize(segs.len(), u32::MAX);
        self.prep.clear();
        self.prep.extend(segs.iter().map(Prep::new));
        let mut total = 0.0;
        for (j, b) in segs.iter().enumerate() {
            let j32 = j as u32;
            // Stamps: 2j for the query, 2j + 1 for the registration.
            let (q_mark, r_mark) = (2 * j32, 2 * j32 + 1);
            self.intervals.clear();
            let bp = &self.prep[j];
            let (head, nodes, stamp, bstamp, intervals, prep) =
                (&self.head, &self.nodes, &mut self.stamp, &mut self.bucket_stamp, &mut self.intervals, &self.prep);
            // Cells and links visited (the growth checks count them).
            let mut visited = 0usize;
            if !nodes.is_empty() {
                let mut merge_at = 16;
                for_piece_cells(b, cs, grow, |cx, cy| {
                    visited += 1;
                    let k = bucket(cx, cy, probe_mask) as usize;
                    if bstamp[k] == q_mark {
                        return true;
                    }
                    bstamp[k] = q_mark;
                    let mut link = head[k];
                    let mut walked = 0;
                    while link != u32::MAX && walked < MAX_WALK {
                        walked += 1;
                        visited += 1;
                        let [next, i] = nodes[link as usize];
                        link = next;
                        let i = i as usize;
                        if stamp[i] == j32 {
                            continue;
                        }
                        stamp[i] = j32;
                        if let Some(iv) = on_segment(&prep[i], bp) {
                            intervals.push(iv);
                            // Covered end to end (to rounding): stop looking.
                            if covers(iv) {
                                return false;
                            }
                            if intervals.len() >= merge_at {
                                merge(intervals);
                                if intervals.len() == 1 && covers(intervals[0]) {
                                    return false;
                                }
                                merge_at = (2 * intervals.len()).max(16);
                            }
                        }
                    }
                    true
                });
            }
            {
                let (head, nodes, bstamp) = (&mut self.head, &mut self.nodes, &mut self.bucket_stamp);
                for_piece_cells(b, cs, 0.0, |cx, cy| {
                    visited += 1;
                    let k = bucket(cx, cy, probe_mask) as usize;
                    if bstamp[k] != r_mark {
                        bstamp[k] = r_mark;
                        nodes.push([head[k], j32]);
                        head[k] = (nodes.len() - 1) as u32;
                    }
                    true
                });
            }
            crate::work::add(visited);
            if self.intervals.is_empty() {
                continue;
            }
            merge(&mut self.intervals);
            let covered = self.intervals.iter().map(|(lo, hi)| hi - lo).sum::<f64>();
            let (dx, dy) = (b.b[0] - b.a[0], b.b[1] - b.a[1]);
            total += covered * (dx * dx + dy * dy).sqrt();
        }
        total
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn prep(a: [f64; 3], b: [f64; 3]) -> Prep {
        Prep::new(&Seg { a: [a[0], a[1]], b: [b[0], b[1]], z: [a[2], b[2]], w: 0.4 })
    }

    fn overlap_mm(a: &Prep, b: &Prep) -> f64 {
        on_segment(a, b).map_or(0.0, |(lo, hi)| (hi - lo) * b.l2.sqrt().hypot(b.z[1]))
    }

    #[test]
    fn layers_of_a_curved_path_count_in_space() {
        // Up a vertical wall (x = 10): a second strand 0.1 mm beside the first lies on it,
        // one 1 mm beside it does not, though both project onto the same point in XY.
        let a = prep([10.0, 0.0, 0.0], [10.0, 0.0, 5.0]);
        assert!((overlap_mm(&a, &prep([10.0, 0.1, 0.0], [10.0, 0.1, 5.0])) - 5.0).abs() < 1e-9);
        assert_eq!(overlap_mm(&a, &prep([10.0, 1.0, 0.0], [10.0, 1.0, 5.0])), 0.0);
        // Stacked: the same XY line 1 mm higher is not on it; 0.1 mm higher is.
        let flat = prep([0.0, 0.0, 2.0], [4.0, 0.0, 2.0]);
        assert_eq!(overlap_mm(&flat, &prep([0.0, 0.0, 3.0], [4.0, 0.0, 3.0])), 0.0);
        assert!((overlap_mm(&flat, &prep([1.0, 0.0, 2.1], [3.0, 0.0, 2.1])) - 2.0).abs() < 1e-9);
        // A sloped strand half on it: [2, 6] along A's [0, 4].
        let slope = prep([0.0, 0.0, 0.0], [4.0, 0.0, 4.0]);
        let got = overlap_mm(&slope, &prep([2.0, 0.0, 2.0], [6.0, 0.0, 6.0]));
        assert!((got - 2.0 * 2f64.sqrt()).abs() < 1e-9, "{got}");
        // Crossing at 90° in space counts nothing.
        assert_eq!(overlap_mm(&slope, &prep([2.0, -2.0, 2.0], [2.0, 2.0, 2.0])), 0.0);
    }
}

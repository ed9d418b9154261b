//! The continuous raster of one VTP foam layer: ONE path that fills the layer's polygon and never
//! leaves it.
//!
//! Viscous thread printing extrudes at a constant rate (see [`super::vtp`]): the nozzle cannot
//! stop, travel and start again, so a layer is one path, and every link of it runs inside the
//! polygon (along a scan line or along the boundary). The path is a boustrophedon raster:
//!
//! 1. The polygon is turned by −angle so that the scan lines are horizontal, one every `spacing`
//!    from half a spacing above the lowest point; each line is cut by every ring and the
//!    crossings, taken pairwise, are the *intervals* (the parts of the line inside).
//! 2. A graph holds each ring as a cycle of nodes (its vertices and the intervals' ends, in order
//!    along it) and each interval as an edge between its two ends.
//! 3. Two intervals on consecutive lines that share one piece of the strip between the lines, and
//!    share it with no other interval, belong to the same *cell*. A cell zig-zags: an interval,
//!    the boundary up to the next interval on the same side, that interval back, and so on.
//! 4. From where it stands the path goes to the nearest corner of a cell not printed yet (Dijkstra
//!    along the rings and the intervals already printed; only when nothing is left that way also
//!    along intervals not printed yet), prints that cell, and goes on until every cell is printed.
//!
//! A vertex lying exactly on a scan line is taken as lying just below it (an edge is cut by the
//! line at `y` when `(a.y <= y) != (b.y <= y)`): every edge then either crosses a line or misses
//! it, every ring crosses each line an even number of times, and crossings at the same point are
//! ordered as they are just above the line. A vertex that only touches a line makes an interval
//! of zero length or splits one in two, consistently with the strips on both sides.
//!
//! Determinism: f64 only, `libm` for the rotation, sorts with total orders and index
//! tie-breaks, no hash maps; the same input gives the same bytes natively and in wasm.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use crate::geom::{DVec2, Polygon};

/// Default distance between scan lines, mm: about one VTP thread's coil width.
pub const DEFAULT_SPACING_MM: f64 = 2.0;

/// Default direction of the scan lines, degrees counter-clockwise from +X (0: along X).
pub const DEFAULT_ANGLE_DEG: f64 = 0.0;

/// Most scan intervals (scan lines × crossings ÷ 2) one layer may have; [`raster`] refuses more
/// before building anything, as [`estimate_intervals`] counts them.
pub const MAX_SCAN_INTERSECTIONS: usize = 2_000_000;

/// Options of the continuous raster (mm, degrees).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Options {
    /// Distance between scan lines, mm, above 0; default [`DEFAULT_SPACING_MM`].
    pub spacing_mm: f64,
    /// Direction of the scan lines, degrees counter-clockwise from +X, any finite value;
    /// default [`DEFAULT_ANGLE_DEG`].
    pub angle_deg: f64,
}

impl Default for Options {
    fn default() -> Self {
        Options { spacing_mm: DEFAULT_SPACING_MM, angle_deg: DEFAULT_ANGLE_DEG }
    }
}

/// The one path of a layer and what it is made of.
#[derive(Clone, Debug, PartialEq)]
pub struct Raster {
    /// The path, in order, mm (consecutive duplicates removed). Starts at the graph node nearest
    /// to `start`, or at the bottom-left end of the lowest interval when there is no `start`.
    pub points: Vec<DVec2>,
    /// Length of the scan lines (the raster proper), mm.
    pub raster_mm: f64,
    /// Length of the links between scan lines / cells that run along the boundary, mm.
    pub boundary_mm: f64,
    /// Length of links that re-run a scan line already printed (needed to reach a cell across a
    /// hole or a narrow part), mm.
    pub retraced_mm: f64,
    /// Number of boustrophedon cells.
    pub cells: usize,
}

/// Why a layer has no continuous raster.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum Error {
    /// The line spacing is not a number above 0.
    #[error("raster line spacing must be a finite number of millimetres above 0 (got {spacing_mm}); the default is 2 mm")]
    BadSpacing {
        /// The spacing given, mm.
        spacing_mm: f64,
    },
    /// The angle is not a finite number.
    #[error("raster angle must be a finite number of degrees (got {angle_deg}); 0 runs the scan lines along X, 90 along Y")]
    BadAngle {
        /// The angle given, degrees.
        angle_deg: f64,
    },
    /// The start point is not finite.
    #[error("the layer's start point must have finite coordinates (got ({x}, {y})); give the previous layer's last point, or none")]
    BadStart {
        /// X given, mm.
        x: f64,
        /// Y given, mm.
        y: f64,
    },
    /// The polygon has too few points, coordinates that are not numbers, or no area.
    #[error("the layer's polygon is degenerate: {reason}; drop this layer or fix its outline")]
    Degenerate {
        /// What is wrong with it.
        reason: String,
    },
    /// No scan line runs inside the polygon for any length.
    #[error(
        "the polygon is {width_mm:.4} mm wide at most across the scan lines and no scan line at {spacing_mm} mm spacing runs inside it; lower the line spacing"
    )]
    TooNarrow {
        /// The polygon's extent across the scan lines, mm.
        width_mm: f64,
        /// The spacing given, mm.
        spacing_mm: f64,
    },
    /// Part of the polygon cannot be reached from the rest without leaving it.
    #[error("a part of the polygon near ({x:.3}, {y:.3}) mm cannot be reached from the rest without leaving the polygon (no scan line or boundary joins them); the layer must be one connected piece: check that its holes lie inside the outline and do not cross it")]
    Unreachable {
        /// A point of the unreached part, mm.
        x: f64,
        /// A point of the unreached part, mm.
        y: f64,
    },
    /// More intervals than [`MAX_SCAN_INTERSECTIONS`] (found before building anything).
    #[error("the raster would have about {intervals} scan intervals at {spacing_mm} mm spacing, over the limit of {limit}; raise the line spacing to at least about {suggested_mm:.4} mm")]
    TooMuchWork {
        /// Estimated intervals ([`estimate_intervals`]).
        intervals: usize,
        /// [`MAX_SCAN_INTERSECTIONS`].
        limit: usize,
        /// The spacing given, mm.
        spacing_mm: f64,
        /// A spacing that would be within the limit, mm.
        suggested_mm: f64,
    },
}

/// Estimated intervals (scan lines × crossings) for `polygon` at `options`, for a budget check
/// before running. It counts, edge by edge, the scan lines each edge crosses (no allocation), so
/// it is the number [`raster`] would cut; 0 when the options or coordinates are not finite, and
/// saturating at `usize::MAX` for absurdly fine spacings.
pub fn estimate_intervals(polygon: &Polygon, options: &Options) -> usize {
    if check_options(options).is_err() {
        return 0;
    }
    let frame = Frame::new(options.angle_deg);
    let Some((y_min, y_max)) = y_range(polygon, &frame) else { return 0 };
    let lines = match Lines::new(y_min, y_max, options.spacing_mm) {
        Ok(lines) => lines,
        // Far too many lines to count one by one: each one cuts the polygon at least once.
        Err(approx_lines) => return approx_lines,
    };
    let mut crossings: usize = 0;
    for ring in rings(polygon) {
        let n = ring.len();
        for e in 0..n {
            let a = frame.to_scan(ring[e]);
            let b = frame.to_scan(ring[(e + 1) % n]);
            crossings = crossings.saturating_add(lines.cutting(a.y, b.y).len());
        }
    }
    crossings / 2
}

/// The continuous raster of one layer: one path through every scan interval of `polygon`,
/// starting at the graph node nearest to `start` (the caller joins the previous layer's end to
/// `points[0]`), or at the bottom-left end of the lowest interval when `start` is `None`.
pub fn raster(polygon: &Polygon, start: Option<DVec2>, options: &Options) -> Result<Raster, Error> {
    check_options(options)?;
    check_polygon(polygon)?;
    if let Some(p) = start {
        if !(p.x.is_finite() && p.y.is_finite()) {
            return Err(Error::BadStart { x: p.x, y: p.y });
        }
    }
    // The budget check comes before any allocation that grows with the work.
    let intervals = estimate_intervals(polygon, options);
    if intervals > MAX_SCAN_INTERSECTIONS {
        return Err(too_much_work(intervals, options.spacing_mm));
    }
    let graph = Graph::build(polygon, options)?;
    let mut walk = Walk::new(&graph);
    walk.run(start)?;
    Ok(walk.finish())
}

// ----------------------------------------------------------------------------------------------
// Checks

fn check_options(options: &Options) -> Result<(), Error> {
    if !(options.spacing_mm.is_finite() && options.spacing_mm > 0.0) {
        return Err(Error::BadSpacing { spacing_mm: options.spacing_mm });
    }
    if !options.angle_deg.is_finite() {
        return Err(Error::BadAngle { angle_deg: options.angle_deg });
    }
    Ok(())
}

fn check_polygon(polygon: &Polygon) -> Result<(), Error> {
    let degenerate = |reason: String| Err(Error::Degenerate { reason });
    if polygon.outer.len() < 3 {
        return degenerate(format!("its outline has {} point(s), at least 3 are needed", polygon.outer.len()));
    }
    for (i, hole) in polygon.holes.iter().enumerate() {
        if hole.len() < 3 {
            return degenerate(format!("hole {i} has {} point(s), at least 3 are needed", hole.len()));
        }
    }
    if let Some(p) = rings(polygon).flatten().find(|p| !(p.x.is_finite() && p.y.is_finite())) {
        return degenerate(format!("it has a point that is not a number: ({}, {})", p.x, p.y));
    }
    if crate::geom::signed_area(&polygon.outer) == 0.0 {
        return degenerate("its outline encloses no area (its points are collinear)".to_string());
    }
    Ok(())
}

fn too_much_work(intervals: usize, spacing_mm: f64) -> Error {
    // Intervals grow as 1/spacing; 10 % over the proportional value leaves room for rounding.
    let suggested_mm = spacing_mm * (intervals as f64 / MAX_SCAN_INTERSECTIONS as f64) * 1.1;
    Error::TooMuchWork { intervals, limit: MAX_SCAN_INTERSECTIONS, spacing_mm, suggested_mm }
}

/// The outline, then the holes.
fn rings(polygon: &Polygon) -> impl Iterator<Item = &[DVec2]> {
    std::iter::once(&polygon.outer[..]).chain(polygon.holes.iter().map(|h| &h[..]))
}

// ----------------------------------------------------------------------------------------------
// The scan frame and its lines

/// The rotation that makes the scan lines horizontal.
struct Frame {
    cos: f64,
    sin: f64,
}

impl Frame {
    fn new(angle_deg: f64) -> Frame {
        // Quarter turns exactly (libm's cos(π/2) is 6e-17, not 0), anything else through libm so
        // that native and wasm agree bit for bit.
        let a = angle_deg % 360.0;
        let (cos, sin) = if a == 0.0 {
            (1.0, 0.0)
        } else if a == 90.0 || a == -270.0 {
            (0.0, 1.0)
        } else if a == 180.0 || a == -180.0 {
            (-1.0, 0.0)
        } else if a == 270.0 || a == -90.0 {
            (0.0, -1.0)
        } else {
            let r = a * (std::f64::consts::PI / 180.0);
            (libm::cos(r), libm::sin(r))
        };
        Frame { cos, sin }
    }

    /// Turned by −angle: the scan lines become horizontal.
    fn to_scan(&self, p: DVec2) -> DVec2 {
        DVec2::new(p.x * self.cos + p.y * self.sin, p.y * self.cos - p.x * self.sin)
    }

    /// Turned back by +angle.
    fn to_polygon(&self, q: DVec2) -> DVec2 {
        DVec2::new(q.x * self.cos - q.y * self.sin, q.x * self.sin + q.y * self.cos)
    }
}

/// Lowest and highest y of every ring in the scan frame; `None` when a coordinate is not finite.
fn y_range(polygon: &Polygon, frame: &Frame) -> Option<(f64, f64)> {
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for p in rings(polygon).flatten() {
        let y = frame.to_scan(*p).y;
        if !y.is_finite() {
            return None;
        }
        lo = lo.min(y);
        hi = hi.max(y);
    }
    (lo <= hi).then_some((lo, hi))
}

/// The scan lines: `y_k = y_min + spacing·(k + ½)` while below `y_max`, or one line through the
/// middle when the polygon is thinner than the spacing.
struct Lines {
    y_min: f64,
    spacing: f64,
    count: usize,
    /// The single middle line of a polygon thinner than the spacing.
    middle: Option<f64>,
}

impl Lines {
    /// `Err(approximate count)` when there are too many lines to be worth listing (any count over
    /// this is refused by the budget anyway).
    fn new(y_min: f64, y_max: f64, spacing: f64) -> Result<Lines, usize> {
        let height = y_max - y_min;
        if height < spacing {
            return Ok(Lines { y_min, spacing, count: 1, middle: Some(y_min + height * 0.5) });
        }
        let approx = libm::ceil(height / spacing - 0.5);
        if approx.is_nan() || approx > 4.0 * MAX_SCAN_INTERSECTIONS as f64 {
            return Err(approx as usize);
        }
        let mut lines = Lines { y_min, spacing, count: approx as usize, middle: None };
        // The division may be off by one ulp: settle the count on the same y_k as the cuts use.
        while lines.count > 1 && lines.y(lines.count - 1) >= y_max {
            lines.count -= 1;
        }
        while lines.y(lines.count) < y_max {
            lines.count += 1;
        }
        Ok(lines)
    }

    fn y(&self, k: usize) -> f64 {
        match self.middle {
            Some(y) => y,
            None => self.y_min + self.spacing * (0.5 + k as f64),
        }
    }

    /// The first line at or above `v`.
    fn first_at_or_above(&self, v: f64) -> usize {
        if self.middle.is_some() {
            return usize::from(self.y(0) < v);
        }
        let guess = libm::ceil((v - self.y_min) / self.spacing - 0.5);
        let mut k = if guess > 0.0 { (guess as usize).min(self.count) } else { 0 };
        while k > 0 && self.y(k - 1) >= v {
            k -= 1;
        }
        while k < self.count && self.y(k) < v {
            k += 1;
        }
        k
    }

    /// The lines that cut the edge from height `a` to `b`: `min <= y < max`, the half-open rule
    /// `(a <= y) != (b <= y)` (a vertex on a line counts as below it).
    fn cutting(&self, a: f64, b: f64) -> std::ops::Range<usize> {
        let (lo, hi) = if a < b { (a, b) } else { (b, a) };
        if lo == hi {
            return 0..0;
        }
        self.first_at_or_above(lo)..self.first_at_or_above(hi)
    }
}

// ----------------------------------------------------------------------------------------------
// The graph: rings as cycles of nodes, intervals as edges, intervals grouped into cells

const NONE: u32 = u32::MAX;

/// One scan interval, between two crossing nodes (left end has the smaller x in the scan frame).
struct Interval {
    line: u32,
    left: u32,
    right: u32,
}

struct Graph {
    /// Node positions in the polygon's frame, mm.
    pos: Vec<DVec2>,
    /// The ring of each node.
    ring_of: Vec<u32>,
    /// Node ids of each ring: consecutive, in the ring's order.
    ring_span: Vec<(u32, u32)>,
    /// The interval a crossing node ends; `NONE` for a ring vertex.
    interval_of: Vec<u32>,
    /// A crossing node's ring edge goes up: the ring, followed forward, goes above its line.
    up_forward: Vec<bool>,
    /// The next crossing node along the ring, forward and backward (`NONE` for vertices).
    next_cut: Vec<u32>,
    prev_cut: Vec<u32>,
    intervals: Vec<Interval>,
    /// Cells, bottom to top: `cell_intervals[cell_start[c]..cell_start[c + 1]]`.
    cell_intervals: Vec<u32>,
    cell_start: Vec<u32>,
    /// `cell·4 + corner` of a cell's corner node (0 bottom-left, 1 bottom-right, 2 top-left,
    /// 3 top-right), `NONE` elsewhere.
    corner_of: Vec<u32>,
}

/// A crossing of a ring edge by a scan line.
struct Cut {
    node: u32,
    line: u32,
    x: f64,
    /// dx/dy of the edge: orders crossings at the same x as they are just above the line.
    dxdy: f64,
}

impl Graph {
    fn build(polygon: &Polygon, options: &Options) -> Result<Graph, Error> {
        let frame = Frame::new(options.angle_deg);
        let (y_min, y_max) =
            y_range(polygon, &frame).ok_or_else(|| Error::Degenerate { reason: "its coordinates are too large to turn to the scan direction".to_string() })?;
        let spacing = options.spacing_mm;
        let lines = Lines::new(y_min, y_max, spacing).map_err(|n| too_much_work(n, spacing))?;

        // Nodes ring by ring, in ring order: each vertex, then the cuts of its edge in the
        // edge's direction (so that no sort is needed to thread them on the ring).
        let mut g = Graph {
            pos: Vec::new(),
            ring_of: Vec::new(),
            ring_span: Vec::new(),
            interval_of: Vec::new(),
            up_forward: Vec::new(),
            next_cut: Vec::new(),
            prev_cut: Vec::new(),
            intervals: Vec::new(),
            cell_intervals: Vec::new(),
            cell_start: Vec::new(),
            corner_of: Vec::new(),
        };
        let mut cuts: Vec<Cut> = Vec::new();
        for (r, ring) in rings(polygon).enumerate() {
            let first = g.pos.len() as u32;
            let scan: Vec<DVec2> = ring.iter().map(|&p| frame.to_scan(p)).collect();
            let n = ring.len();
            for e in 0..n {
                let (a, b) = (scan[e], scan[(e + 1) % n]);
                g.push_node(ring[e], r as u32, false);
                let range = lines.cutting(a.y, b.y);
                let up = b.y > a.y;
                let mut cut = |k: usize| {
                    let y = lines.y(k);
                    // Exact ends where the line meets a vertex; the vertex's own coordinates there.
                    let (x, at) = if a.y == y {
                        (a.x, ring[e])
                    } else if b.y == y {
                        (b.x, ring[(e + 1) % n])
                    } else {
                        let t = (y - a.y) / (b.y - a.y);
                        let x = a.x + t * (b.x - a.x);
                        (x, frame.to_polygon(DVec2::new(x, y)))
                    };
                    cuts.push(Cut { node: g.pos.len() as u32, line: k as u32, x, dxdy: (b.x - a.x) / (b.y - a.y) });
                    g.push_node(at, r as u32, up);
                };
                if up {
                    range.for_each(&mut cut);
                } else {
                    range.rev().for_each(&mut cut);
                }
            }
            g.ring_span.push((first, g.pos.len() as u32));
        }

        // Intervals: the cuts of each line by x (ties as just above the line), taken pairwise.
        // Every ring crosses every line an even number of times under the half-open rule.
        cuts.sort_by(|p, q| p.line.cmp(&q.line).then(p.x.total_cmp(&q.x)).then(p.dxdy.total_cmp(&q.dxdy)).then(p.node.cmp(&q.node)));
        let mut longest: f64 = 0.0;
        for line in cuts.chunk_by(|p, q| p.line == q.line) {
            debug_assert!(line.len() % 2 == 0, "odd crossings on a scan line");
            for pair in line.chunks_exact(2) {
                let i = g.intervals.len() as u32;
                g.interval_of[pair[0].node as usize] = i;
                g.interval_of[pair[1].node as usize] = i;
                g.intervals.push(Interval { line: pair[0].line, left: pair[0].node, right: pair[1].node });
                longest = longest.max(pair[1].x - pair[0].x);
            }
        }
        if longest <= 0.0 {
            return Err(Error::TooNarrow { width_mm: y_max - y_min, spacing_mm: spacing });
        }
        drop(cuts);

        g.thread_cuts_and_cells();
        Ok(g)
    }

    fn push_node(&mut self, pos: DVec2, ring: u32, up_forward: bool) {
        self.pos.push(pos);
        self.ring_of.push(ring);
        self.interval_of.push(NONE);
        self.up_forward.push(up_forward);
        self.next_cut.push(NONE);
        self.prev_cut.push(NONE);
    }

    fn line_of(&self, node: u32) -> u32 {
        self.intervals[self.interval_of[node as usize] as usize].line
    }

    /// The strip a ring chain runs in, leaving crossing `node` forward (`true`) or backward:
    /// strip `s` lies between lines `s − 1` and `s`.
    fn strip(&self, node: u32, forward: bool) -> u32 {
        self.line_of(node) + u32::from(self.up_forward[node as usize] == forward)
    }

    /// Links every crossing to the next along its ring, finds the pieces of each strip between
    /// two lines (union-find over the intervals' top and bottom sides, joined by the ring chains
    /// that run in the strip) and makes cells of the intervals joined one to one.
    fn thread_cuts_and_cells(&mut self) {
        let count = self.intervals.len();
        // Side 2i is interval i's bottom (in strip line_i), 2i + 1 its top (strip line_i + 1).
        let mut sets = UnionFind::new(2 * count);
        let side = |g: &Graph, node: u32, strip: u32| -> Option<u32> {
            let line = g.line_of(node);
            let i = g.interval_of[node as usize];
            if strip == line + 1 {
                Some(2 * i + 1)
            } else if strip == line {
                Some(2 * i)
            } else {
                None
            }
        };
        let mut ring_cuts: Vec<u32> = Vec::new();
        for r in 0..self.ring_span.len() {
            let (first, end) = self.ring_span[r];
            ring_cuts.clear();
            ring_cuts.extend((first..end).filter(|&n| self.interval_of[n as usize] != NONE));
            let m = ring_cuts.len();
            for j in 0..m {
                let (c, d) = (ring_cuts[j], ring_cuts[(j + 1) % m]);
                self.next_cut[c as usize] = d;
                self.prev_cut[d as usize] = c;
                // Between two consecutive crossings the ring crosses no line: the chain is in one
                // strip and joins the sides of the two intervals that face it.
                let strip = self.strip(c, true);
                if let (Some(p), Some(q)) = (side(self, c, strip), side(self, d, strip)) {
                    sets.union(p, q);
                }
            }
        }

        // A piece of a strip with exactly one interval below and one above joins them.
        let (mut tops, mut bottoms) = (vec![0u32; 2 * count], vec![0u32; 2 * count]);
        let (mut top_of, mut bottom_of) = (vec![NONE; 2 * count], vec![NONE; 2 * count]);
        for i in 0..count as u32 {
            let t = sets.find(2 * i + 1) as usize;
            tops[t] += 1;
            top_of[t] = i;
            let b = sets.find(2 * i) as usize;
            bottoms[b] += 1;
            bottom_of[b] = i;
        }
        let mut next = vec![NONE; count];
        let mut has_below = vec![false; count];
        for i in 0..count as u32 {
            let t = sets.find(2 * i + 1) as usize;
            if tops[t] == 1 && bottoms[t] == 1 {
                next[i as usize] = bottom_of[t];
                has_below[bottom_of[t] as usize] = true;
            }
        }

        // Cells from their lowest interval up, in the order of that interval (bottom to top,
        // left to right): cell 0 holds the lowest interval.
        self.corner_of = vec![NONE; self.pos.len()];
        for i in 0..count as u32 {
            if has_below[i as usize] {
                continue;
            }
            let c = self.cell_start.len() as u32;
            self.cell_start.push(self.cell_intervals.len() as u32);
            let mut k = i;
            while k != NONE {
                self.cell_intervals.push(k);
                k = next[k as usize];
            }
            let (bottom, top) = (&self.intervals[i as usize], &self.intervals[*self.cell_intervals.last().unwrap() as usize]);
            for (corner, node) in [bottom.left, bottom.right, top.left, top.right].into_iter().enumerate() {
                // A one-interval cell has its corners twice: the lower number wins.
                if self.corner_of[node as usize] == NONE {
                    self.corner_of[node as usize] = c * 4 + corner as u32;
                }
            }
        }
        self.cell_start.push(self.cell_intervals.len() as u32);
    }

    fn cells(&self) -> usize {
        self.cell_start.len() - 1
    }

    fn cell(&self, c: usize) -> &[u32] {
        &self.cell_intervals[self.cell_start[c] as usize..self.cell_start[c + 1] as usize]
    }

    fn ring_next(&self, n: u32) -> u32 {
        let (first, end) = self.ring_span[self.ring_of[n as usize] as usize];
        if n + 1 == end {
            first
        } else {
            n + 1
        }
    }

    fn ring_prev(&self, n: u32) -> u32 {
        let (first, end) = self.ring_span[self.ring_of[n as usize] as usize];
        if n == first {
            end - 1
        } else {
            n - 1
        }
    }

    fn length(&self, a: u32, b: u32) -> f64 {
        let d = self.pos[a as usize] - self.pos[b as usize];
        (d.x * d.x + d.y * d.y).sqrt()
    }
}

/// Union-find with the smaller index as root (deterministic).
struct UnionFind {
    parent: Vec<u32>,
}

impl UnionFind {
    fn new(n: usize) -> UnionFind {
        UnionFind { parent: (0..n as u32).collect() }
    }

    fn find(&mut self, mut x: u32) -> u32 {
        while self.parent[x as usize] != x {
            let up = self.parent[self.parent[x as usize] as usize];
            self.parent[x as usize] = up;
            x = up;
        }
        x
    }

    fn union(&mut self, a: u32, b: u32) {
        let (a, b) = (self.find(a), self.find(b));
        let (lo, hi) = if a < b { (a, b) } else { (b, a) };
        self.parent[hi as usize] = lo;
    }
}

// ----------------------------------------------------------------------------------------------
// The walk: cells joined by shortest links

/// What a step of the path is.
#[derive(Clone, Copy, PartialEq)]
enum Kind {
    Raster,
    Boundary,
    Retraced,
}

struct Walk<'g> {
    g: &'g Graph,
    /// Nodes of the path and, for each after the first, the kind of the step that reaches it.
    nodes: Vec<u32>,
    kinds: Vec<Kind>,
    printed: Vec<bool>,
    cell_done: Vec<bool>,
    search: Search,
}

impl<'g> Walk<'g> {
    fn new(g: &'g Graph) -> Walk<'g> {
        Walk {
            g,
            nodes: Vec::new(),
            kinds: Vec::new(),
            printed: vec![false; g.intervals.len()],
            cell_done: vec![false; g.cells()],
            search: Search::new(g.pos.len()),
        }
    }

    fn step(&mut self, node: u32, kind: Kind) {
        if self.nodes.last() != Some(&node) {
            self.nodes.push(node);
            self.kinds.push(kind);
        }
    }

    fn run(&mut self, start: Option<DVec2>) -> Result<(), Error> {
        let g = self.g;
        let first = match start {
            None => g.intervals[0].left,
            Some(p) => self.nearest_node(p),
        };
        self.nodes.push(first);
        let mut here = first;
        for _ in 0..g.cells() {
            // Nearest corner of a cell not printed yet, first without running over intervals not
            // printed yet (they would be printed twice), then, if that reaches none, with them.
            let done = &self.cell_done;
            let goal = |n: u32| {
                let key = g.corner_of[n as usize];
                (key != NONE && !done[(key / 4) as usize]).then_some(key)
            };
            let found = match self.search.run(g, &self.printed, here, false, goal) {
                Some(found) => Some(found),
                None => self.search.run(g, &self.printed, here, true, goal),
            };
            let Some(entry) = found else {
                let c = (0..g.cells()).find(|&c| !self.cell_done[c]).expect("a cell is left");
                let p = g.pos[g.intervals[g.cell(c)[0] as usize].left as usize];
                return Err(Error::Unreachable { x: p.x, y: p.y });
            };
            self.follow_route(here, entry);
            let key = g.corner_of[entry as usize];
            here = self.print_cell((key / 4) as usize, key % 4);
        }
        Ok(())
    }

    /// The node nearest to `p` among those from which the cells can be reached (a hole that no
    /// scan line cuts is a ring of its own), ties to the lower index.
    fn nearest_node(&self, p: DVec2) -> u32 {
        let g = self.g;
        let mut sets = UnionFind::new(g.pos.len());
        for n in 0..g.pos.len() as u32 {
            sets.union(n, g.ring_next(n));
        }
        for iv in &g.intervals {
            sets.union(iv.left, iv.right);
        }
        let mut reaches = vec![false; g.pos.len()];
        for iv in &g.intervals {
            let root = sets.find(iv.left);
            reaches[root as usize] = true;
        }
        let mut best = (f64::INFINITY, g.intervals[0].left);
        for n in 0..g.pos.len() as u32 {
            if !reaches[sets.find(n) as usize] {
                continue;
            }
            let d = g.pos[n as usize] - p;
            let d2 = d.x * d.x + d.y * d.y;
            if d2 < best.0 {
                best = (d2, n);
            }
        }
        best.1
    }

    /// Appends the route the last search found from `from` to `to`.
    fn follow_route(&mut self, from: u32, to: u32) {
        let route = self.search.route(from, to);
        for (node, via) in route {
            let kind = if via == NONE { Kind::Boundary } else { Kind::Retraced };
            if via != NONE {
                self.printed[via as usize] = true;
            }
            self.step(node, kind);
        }
    }

    /// Prints cell `c` from `corner`; returns the node where it ends.
    fn print_cell(&mut self, c: usize, corner: u32) -> u32 {
        let g = self.g;
        self.cell_done[c] = true;
        let cell = g.cell(c);
        let upward = corner < 2;
        let mut left_to_right = corner % 2 == 0;
        let count = cell.len();
        let mut here = *self.nodes.last().unwrap();
        for j in 0..count {
            let i = if upward { cell[j] } else { cell[count - 1 - j] };
            let iv = &g.intervals[i as usize];
            let to = if left_to_right { iv.right } else { iv.left };
            self.step(to, Kind::Raster);
            self.printed[i as usize] = true;
            here = to;
            if j + 1 < count {
                let n = if upward { cell[j + 1] } else { cell[count - 2 - j] };
                let next = &g.intervals[n as usize];
                let target = if left_to_right { next.right } else { next.left };
                here = self.link(here, target, iv.line.max(next.line));
                left_to_right = !left_to_right;
            }
        }
        here
    }

    /// Within a cell: the ring chain from crossing `from` to crossing `to` in `strip`.
    fn link(&mut self, from: u32, to: u32, strip: u32) -> u32 {
        let g = self.g;
        let forward = if g.next_cut[from as usize] == to && g.strip(from, true) == strip {
            Some(true)
        } else if g.prev_cut[from as usize] == to && g.strip(from, false) == strip {
            Some(false)
        } else {
            None
        };
        match forward {
            Some(forward) => {
                let mut n = from;
                while n != to {
                    n = if forward { g.ring_next(n) } else { g.ring_prev(n) };
                    self.step(n, Kind::Boundary);
                }
            }
            // Not met in a valid polygon (the one-to-one strip piece is bounded by exactly these
            // chains); kept so that a self-touching outline still gets a path inside it.
            None => {
                let reached = self.search.run(g, &self.printed, from, true, |n| (n == to).then_some(0));
                debug_assert!(reached.is_some(), "cell link without a route");
                if reached.is_some() {
                    self.follow_route(from, to);
                }
            }
        }
        to
    }

    fn finish(self) -> Raster {
        let g = self.g;
        let (mut raster_mm, mut boundary_mm, mut retraced_mm) = (0.0, 0.0, 0.0);
        let mut points = Vec::with_capacity(self.nodes.len());
        points.push(g.pos[self.nodes[0] as usize]);
        for (w, kind) in self.nodes.windows(2).zip(&self.kinds) {
            let length = g.length(w[0], w[1]);
            match kind {
                Kind::Raster => raster_mm += length,
                Kind::Boundary => boundary_mm += length,
                Kind::Retraced => retraced_mm += length,
            }
            let p = g.pos[w[1] as usize];
            if points.last() != Some(&p) {
                points.push(p);
            }
        }
        Raster { points, raster_mm, boundary_mm, retraced_mm, cells: g.cells() }
    }
}

/// Dijkstra over the graph, with its arrays kept between searches (only touched entries reset).
struct Search {
    dist: Vec<f64>,
    /// Predecessor node, and the interval stepped along to come from it (`NONE`: a ring piece).
    pred: Vec<(u32, u32)>,
    settled: Vec<bool>,
    touched: Vec<u32>,
    heap: BinaryHeap<Reverse<(u64, u32)>>,
}

impl Search {
    fn new(nodes: usize) -> Search {
        Search { dist: vec![f64::INFINITY; nodes], pred: vec![(NONE, NONE); nodes], settled: vec![false; nodes], touched: Vec::new(), heap: BinaryHeap::new() }
    }

    fn reach(&mut self, node: u32, d: f64, from: u32, via: u32) {
        let n = node as usize;
        if d < self.dist[n] {
            if self.dist[n] == f64::INFINITY {
                self.touched.push(node);
            }
            self.dist[n] = d;
            self.pred[n] = (from, via);
            // Non-negative f64 bits order like the numbers: a total, deterministic key.
            self.heap.push(Reverse((d.to_bits(), node)));
        }
    }

    /// The goal node nearest to `from` (ties: lowest goal key, then lowest node), walking ring
    /// pieces and printed intervals (and the others when `any_interval`).
    fn run(&mut self, g: &Graph, printed: &[bool], from: u32, any_interval: bool, goal: impl Fn(u32) -> Option<u32>) -> Option<u32> {
        for &n in &self.touched {
            self.dist[n as usize] = f64::INFINITY;
            self.pred[n as usize] = (NONE, NONE);
            self.settled[n as usize] = false;
        }
        self.touched.clear();
        self.heap.clear();
        self.reach(from, 0.0, NONE, NONE);
        let mut best: Option<(f64, u32, u32)> = None;
        while let Some(Reverse((bits, u))) = self.heap.pop() {
            let d = f64::from_bits(bits);
            if self.settled[u as usize] || d > self.dist[u as usize] {
                continue;
            }
            if best.is_some_and(|(bd, _, _)| d > bd) {
                break;
            }
            self.settled[u as usize] = true;
            if let Some(key) = goal(u) {
                if best.is_none_or(|(_, bk, _)| key < bk) {
                    best = Some((d, key, u));
                }
            }
            let mut go = |v: u32, via: u32| self.reach(v, d + g.length(u, v), u, via);
            go(g.ring_next(u), NONE);
            go(g.ring_prev(u), NONE);
            let i = g.interval_of[u as usize];
            if i != NONE && (any_interval || printed[i as usize]) {
                let iv = &g.intervals[i as usize];
                go(if iv.left == u { iv.right } else { iv.left }, i);
            }
        }
        best.map(|(_, _, node)| node)
    }

    /// The route of the last search from `from` to `to`: each node after `from` with the interval
    /// stepped along to reach it (`NONE` for a ring piece).
    fn route(&self, from: u32, to: u32) -> Vec<(u32, u32)> {
        let mut route = Vec::new();
        let mut n = to;
        while n != from {
            let (p, via) = self.pred[n as usize];
            route.push((n, via));
            n = p;
        }
        route.reverse();
        route
    }
}

//! The tree style: branches instead of a block.
//!
//! Under each contact come its interface layers (as in the grid style); under the lowest of
//! them, *tips* (circles of 1.5 line widths) on a grid of the support spacing inside the
//! contact and along its edge, close enough that every interface line crosses one, unless a branch already passes there. Layer by
//! layer downwards every branch leans towards its nearest neighbour (at most `h · tan 40°` a
//! layer, so each circle still rests on the one below), two that meet merge into one a
//! little thicker, and all keep the side gap from the part: a branch that would touch the
//! part steps aside, and one that cannot stops on the part (everywhere) or is removed with
//! everything above it (on the plate only). Each layer's circles are unioned and printed as
//! the grid style prints an island: a sheath, and lines inside trunks wide enough for them.

use super::areas::{um, Areas};
use super::{gap_layers, Input, LayerSupport, Options};
use crate::geom::DVec2;
use crate::slice::anchor::Near;
use crate::slice::perimeters::outset;
use crate::slice::regions::{difference, union};
use i_overlay::i_float::int::point::IntPoint;
use i_overlay::i_shape::int::shape::IntShapes;

/// Steepest lean of a branch from vertical, degrees.
const LEAN_DEG: f64 = 40.0;
/// Largest branch radius, mm.
const MAX_RADIUS_MM: f64 = 4.0;
/// Neighbours farther than this many support spacings do not attract a branch.
const ATTRACT_SPACINGS: f64 = 4.0;

#[derive(Clone, Copy, Debug)]
struct Node {
    p: DVec2,
    r: f64,
    tree: usize,
}

/// The part at one layer as an obstacle: inside it, or within a distance of its outline.
struct Obstacle {
    near: Near,
    rows: Vec<Vec<(DVec2, DVec2)>>,
    y0: f64,
    row_h: f64,
}

impl Obstacle {
    fn new(shapes: &IntShapes<i32>, reach: f64) -> Obstacle {
        let loops: Vec<Vec<DVec2>> = super::grid::loops_mm(shapes);
        let near = Near::new(loops.iter().map(|l| l.as_slice()), reach);
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for p in loops.iter().flatten() {
            lo = lo.min(p.y);
            hi = hi.max(p.y);
        }
        let row_h = 1.0;
        if !lo.is_finite() {
            return Obstacle { near, rows: Vec::new(), y0: 0.0, row_h };
        }
        let nrows = (((hi - lo) / row_h).floor() as usize + 1).min(1 << 16);
        let mut rows = vec![Vec::new(); nrows];
        for l in &loops {
            for s in l.windows(2) {
                let (a, b) = (s[0], s[1]);
                let r0 = (((a.y.min(b.y) - lo) / row_h).floor().max(0.0) as usize).min(nrows - 1);
                let r1 = (((a.y.max(b.y) - lo) / row_h).floor().max(0.0) as usize).min(nrows - 1);
                for row in rows.iter_mut().take(r1 + 1).skip(r0) {
                    row.push((a, b));
                }
            }
        }
        Obstacle { near, rows, y0: lo, row_h }
    }

    fn inside(&self, p: DVec2) -> bool {
        let r = ((p.y - self.y0) / self.row_h).floor();
        if self.rows.is_empty() || r < 0.0 || r >= self.rows.len() as f64 {
            return false;
        }
        let mut inside = false;
        for &(a, b) in &self.rows[r as usize] {
            if (a.y > p.y) != (b.y > p.y) && p.x < a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x) {
                inside = !inside;
            }
        }
        inside
    }

    /// Whether a circle of radius `r` at `p` touches the part.
    fn hits(&self, p: DVec2, r: f64) -> bool {
        self.inside(p) || self.near.within(p, r)
    }
}

fn find(parent: &mut [usize], mut x: usize) -> usize {
    while parent[x] != x {
        parent[x] = parent[parent[x]];
        x = parent[x];
    }
    x
}

/// A circle as an integer polygon (µm), CCW.
fn circle(c: DVec2, r: f64) -> Vec<IntPoint<i32>> {
    let k = ((std::f64::consts::TAU * r / 0.5).ceil() as usize).clamp(8, 48);
    (0..k)
        .map(|i| {
            let a = std::f64::consts::TAU * i as f64 / k as f64;
            IntPoint::new(((c.x + r * libm::cos(a)) * 1000.0).round() as i32, ((c.y + r * libm::sin(a)) * 1000.0).round() as i32)
        })
        .collect()
}

/// Points where tips go under `contact`: a grid of `spacing` inside it, and every `spacing`
/// along its edge (inset by `inset` mm).
fn tip_points(contact: &IntShapes<i32>, spacing: f64, inset: f64) -> Vec<DVec2> {
    let mut pts = Vec::new();
    let mut edge = crate::slice::perimeters::inset(contact, um(inset).max(1));
    if edge.is_empty() {
        edge = contact.clone();
    }
    for l in super::grid::loops_mm(&edge) {
        let mut carry = 0.0;
        for s in l.windows(2) {
            let len = s[0].distance(s[1]);
            let mut t = carry;
            while t < len {
                pts.push(s[0].lerp(s[1], t / len.max(1e-12)));
                t += spacing;
            }
            carry = t - len;
        }
    }
    // Interior grid points (on a global grid, offset half a spacing).
    let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
    for p in super::grid::loops_mm(&edge).iter().flatten() {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    if lo.is_finite() {
        let (x0, x1) = ((lo.x / spacing - 0.5).ceil() as i64, (hi.x / spacing - 0.5).floor() as i64);
        let (y0, y1) = ((lo.y / spacing - 0.5).ceil() as i64, (hi.y / spacing - 0.5).floor() as i64);
        if (x1 - x0 + 1).max(0) * (y1 - y0 + 1).max(0) <= 1_000_000 {
            for yi in y0..=y1 {
                for xi in x0..=x1 {
                    let p = DVec2::new((xi as f64 + 0.5) * spacing, (yi as f64 + 0.5) * spacing);
                    if crate::slice::contains_any(&edge, p) {
                        pts.push(p);
                    }
                }
            }
        }
    }
    pts
}

pub(crate) fn paths(o: &Options, input: &Input, areas: &Areas) -> Vec<LayerSupport> {
    let n = input.part.len();
    let w = input.w_um as f64 / 1000.0;
    let g = gap_layers(o, input.layer_height_mm);
    let m = o.interface_layers as usize;
    let xy = o.xy_gap_mm;
    let spacing = o.spacing_mm.max(2.0 * w);
    let r0 = 1.5 * w;
    let h = input.layer_height_mm;
    let step = (h * libm::tan(LEAN_DEG.to_radians())).min(0.45 * w);
    let grow = 0.05 * step;
    let attract = ATTRACT_SPACINGS * spacing;
    let keep_out_um = um(xy);
    // Interface under each contact: its `m` layers, less the part.
    let iface: Vec<IntShapes<i32>> = crate::par::map(n, &mut |_| {}, |j| {
        let mut under: IntShapes<i32> = Vec::new();
        for c in areas.contact.iter().take((j + g + m + 1).min(n)).skip(j + 1 + g) {
            under = union(&under, c);
        }
        if under.is_empty() {
            return under;
        }
        // Closed by a line width, as the grid's areas: a dome's thin rings become one band.
        let close = input.w_um.max(1);
        let under = crate::slice::perimeters::inset(&outset(&under, close), close);
        difference(&under, &outset(&input.part[j], keep_out_um))
    });
    let mut nodes: Vec<Node> = Vec::new();
    let mut parent: Vec<usize> = Vec::new();
    let mut circles: Vec<Vec<(DVec2, f64, usize)>> = vec![Vec::new(); n];
    let mut dead: Vec<bool> = Vec::new();
    for j in (0..n).rev() {
        let obstacle = Obstacle::new(&input.part[j], MAX_RADIUS_MM + xy + step);
        // Move the branches of the layer above down to this one.
        nodes.sort_by(|a, b| a.p.x.total_cmp(&b.p.x).then(a.p.y.total_cmp(&b.p.y)));
        let mut moved: Vec<Node> = Vec::with_capacity(nodes.len());
        for (k, a) in nodes.iter().enumerate() {
            // Nearest neighbour within reach (nodes sorted by x).
            let mut best: Option<(f64, DVec2)> = None;
            for b in nodes[k + 1..].iter().take_while(|b| b.p.x - a.p.x <= attract).chain(nodes[..k].iter().rev().take_while(|b| a.p.x - b.p.x <= attract)) {
                let d = a.p.distance(b.p);
                if d <= attract && best.is_none_or(|(bd, _)| d < bd) {
                    best = Some((d, b.p));
                }
            }
            let want = match best {
                Some((d, q)) if d > 1e-9 => a.p + (q - a.p) * ((step.min(d / 2.0)) / d),
                _ => a.p,
            };
            let r = (a.r + grow).min(MAX_RADIUS_MM);
            let mut at = None;
            if !obstacle.hits(want, r + xy) {
                at = Some(want);
            } else if !obstacle.hits(a.p, r + xy) {
                at = Some(a.p);
            } else {
                for i in 0..8 {
                    let ang = std::f64::consts::TAU * i as f64 / 8.0;
                    let q = a.p + DVec2::new(libm::cos(ang), libm::sin(ang)) * step;
                    if !obstacle.hits(q, r + xy) {
                        at = Some(q);
                        break;
                    }
                }
            }
            match at {
                Some(p) => moved.push(Node { p, r, tree: a.tree }),
                None => {
                    // Stops here: on the part (everywhere), or not at all (on the plate only).
                    if o.on_plate_only {
                        let t = find(&mut parent, a.tree);
                        dead[t] = true;
                    }
                }
            }
        }
        // Merge branches that meet.
        moved.sort_by(|a, b| a.p.x.total_cmp(&b.p.x).then(a.p.y.total_cmp(&b.p.y)));
        let mut merged: Vec<Node> = Vec::with_capacity(moved.len());
        let mut gone = vec![false; moved.len()];
        for k in 0..moved.len() {
            if gone[k] {
                continue;
            }
            let mut a = moved[k];
            for (l, b) in moved.iter().enumerate().skip(k + 1) {
                if b.p.x - a.p.x > 2.0 * step + 2.0 * MAX_RADIUS_MM {
                    break;
                }
                if gone[l] || a.p.distance(b.p) > 2.0 * step {
                    continue;
                }
                let (wa, wb) = (a.r * a.r, b.r * b.r);
                let p = (a.p * wa + b.p * wb) / (wa + wb);
                let r = (a.r.max(b.r) + 0.25 * a.r.min(b.r)).min(MAX_RADIUS_MM);
                let (ta, tb) = (find(&mut parent, a.tree), find(&mut parent, b.tree));
                if ta != tb {
                    parent[tb] = ta;
                    dead[ta] = dead[ta] || dead[tb];
                }
                if !obstacle.hits(p, r + xy) {
                    a = Node { p, r, tree: ta };
                } else {
                    a.tree = ta;
                }
                gone[l] = true;
            }
            merged.push(a);
        }
        nodes = merged;
        // New tips under the contacts whose interface ends just above this layer.
        let top: Option<&IntShapes<i32>> = if m > 0 { iface.get(j + 1) } else { areas.contact.get(j + 1 + g) };
        if let Some(top) = top.filter(|t| !t.is_empty()) {
            nodes.sort_by(|a, b| a.p.x.total_cmp(&b.p.x).then(a.p.y.total_cmp(&b.p.y)));
            let old = nodes.len();
            let window = MAX_RADIUS_MM + 0.4 * spacing;
            // Tips close enough that every interface line above crosses one.
            let tips = 2.0 * (r0 + w);
            for p in tip_points(top, tips, 0.5 * r0) {
                let from = nodes[..old].partition_point(|q| q.p.x < p.x - window);
                let covered = nodes[from..old].iter().take_while(|q| q.p.x <= p.x + window).any(|q| q.p.distance(p) < q.r + 0.4 * tips);
                if covered || obstacle.hits(p, r0 + xy) {
                    continue;
                }
                let id = parent.len();
                parent.push(id);
                dead.push(false);
                nodes.push(Node { p, r: r0, tree: id });
            }
        }
        circles[j] = nodes.iter().map(|q| (q.p, q.r, q.tree)).collect();
    }
    let roots: Vec<usize> = (0..parent.len()).map(|t| find(&mut parent, t)).collect();
    crate::par::map(n, &mut |_| {}, |j| {
        let mut shapes: IntShapes<i32> = Vec::new();
        let live: Vec<Vec<Vec<IntPoint<i32>>>> = circles[j].iter().filter(|c| !dead[roots[c.2]]).map(|c| vec![circle(c.0, c.1)]).collect();
        if !live.is_empty() {
            shapes = crate::slice::regions::union_all(&live);
        }
        let region = union(&shapes, &iface[j]);
        super::grid::fill(o, input.w_um, &region, &iface[j])
    })
}

//! The process constraints of a 3-axis nozzle (section II.A) that do not depend on the state:
//! directionality (a beam steeper than the nozzle's cone, going down, would be printed into
//! the nozzle: it must be printed upward) and collision (if the nozzle swept along beam A meets
//! beam B, A precedes B). For a 3-axis machine the nozzle never turns, so these are computed
//! once for the whole design (the paper, section V).
//!
//! The nozzle is a cone (apex at the tip, axis +Z, half-angle θ) widening to a cylinder of
//! radius R and height H. Beam B is hit while printing A when the nozzle body N placed at some
//! point of A meets B's capsule: N ∩ (B ⊖ A) ≠ ∅, where B ⊖ A = {b − a} is a parallelogram
//! (two triangles) inflated by B's radius. That is a distance between convex shapes, computed by
//! parry3d's GJK (cone and cylinder against each triangle). Candidate pairs come from parry's
//! BVH over the beams' boxes queried with the box of A's sweep, then a 2D segment distance
//! filter: no all-pairs scan.
//!
//! A beam B that shares a joint with A always touches the nozzle at that joint; it is tested
//! by its axis from a small distance off the joint (radius 0): it is hit when it runs into the
//! cone there (two beams rising steeper than the cone from one joint each block the other: a
//! cycle, and the design cannot be printed in this orientation).
//!
//! Beyond the paper, a nozzle that may tilt (a 5-axis head, or a robot): each beam is printed
//! with the nozzle's axis chosen among +Z and rings of tilts up to the limit ([`TILT_RINGS`]
//! rings of [`TILT_AZIMUTHS`] directions), the one that allows the most directions of the
//! beam, then hits the fewest beams, then tilts least. The directions and precedences follow
//! from the chosen axis; a beam is tilted only when that removes something, and the report
//! counts them. The chosen axis goes to the G-code as the tool axis.

use glam::DVec3;
use parry3d_f64::bounding_volume::Aabb;
use parry3d_f64::math::{Pose, Rot3, Vector};
use parry3d_f64::partitioning::{Bvh, BvhBuildStrategy};
use parry3d_f64::shape::{Cone, Cylinder, Triangle};

/// Default half-angle of the nozzle's cone, degrees: the paper's needle made collision
/// unavoidable for two beams at a joint both within about 13° of the vertical.
pub const DEFAULT_HALF_ANGLE_DEG: f64 = 13.0;
/// Default radius of the nozzle body above the cone, mm.
pub const DEFAULT_RADIUS_MM: f64 = 2.0;
/// Default height of the nozzle body's cylinder above the cone, mm.
pub const DEFAULT_HEIGHT_MM: f64 = 20.0;
/// Most precedence pairs stored (refused above: a nozzle this large makes the order a chain).
pub const MAX_PAIRS: usize = 20_000_000;
/// Default tilt limit of the nozzle, degrees (0: a 3-axis machine, the nozzle stays vertical).
pub const DEFAULT_TILT_DEG: f64 = 0.0;
/// Largest tilt limit, degrees.
pub const MAX_TILT_DEG: f64 = 60.0;
/// Directions around the vertical tried per ring of tilts.
pub const TILT_AZIMUTHS: usize = 8;
/// Rings of tilts tried: at 1/2 and 2/2 of the limit.
pub const TILT_RINGS: usize = 2;

/// The nozzle's shape.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Nozzle {
    /// Half-angle of the cone at the tip, degrees (0–89).
    pub half_angle_deg: f64,
    /// Radius where the cone ends and the cylinder starts, mm.
    pub radius_mm: f64,
    /// Height of the cylinder, mm.
    pub height_mm: f64,
}

impl Default for Nozzle {
    fn default() -> Self {
        Nozzle { half_angle_deg: DEFAULT_HALF_ANGLE_DEG, radius_mm: DEFAULT_RADIUS_MM, height_mm: DEFAULT_HEIGHT_MM }
    }
}

impl Nozzle {
    /// Height of the cone from the tip to where it reaches the radius, mm.
    pub fn cone_height(&self) -> f64 {
        self.radius_mm / libm::tan(self.half_angle_deg.to_radians())
    }
    /// Height of the whole body above the tip, mm.
    pub fn top(&self) -> f64 {
        self.cone_height() + self.height_mm
    }
    /// Whether a beam going from its start in direction `d` (unit) may be printed that way: the
    /// part already printed trails behind the tip along −d and must stay out of the cone.
    pub fn can_print(&self, d: DVec3) -> bool {
        self.can_print_along(d, DVec3::Z)
    }
    /// [`Nozzle::can_print`] with the nozzle's axis along `axis` (unit, tip to body).
    pub fn can_print_along(&self, d: DVec3, axis: DVec3) -> bool {
        // −d inside the cone: angle(−d, axis) < θ ⇔ −d·axis > cos θ.
        -d.dot(axis) <= libm::cos(self.half_angle_deg.to_radians()) + 1e-12
    }
}

/// What the constraints are computed with.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Options {
    /// The nozzle.
    pub nozzle: Nozzle,
    /// Beam radius, mm.
    pub beam_radius_mm: f64,
    /// Directionality on (off: every beam may be printed either way).
    pub directionality: bool,
    /// Collision on (off: no precedences).
    pub collision: bool,
    /// How far the nozzle may tilt from the vertical, degrees (0: a 3-axis machine).
    pub tilt_deg: f64,
}

/// The nozzle axes tried for a tilt limit: +Z first, then each ring outward, azimuths from +X
/// anticlockwise.
pub fn tilt_axes(tilt_deg: f64) -> Vec<DVec3> {
    let mut out = vec![DVec3::Z];
    if tilt_deg > 0.0 {
        for ring in 1..=TILT_RINGS {
            let phi = (tilt_deg * ring as f64 / TILT_RINGS as f64).to_radians();
            for k in 0..TILT_AZIMUTHS {
                let psi = std::f64::consts::TAU * k as f64 / TILT_AZIMUTHS as f64;
                out.push(DVec3::new(libm::sin(phi) * libm::cos(psi), libm::sin(phi) * libm::sin(psi), libm::cos(phi)));
            }
        }
    }
    out
}

/// The state-independent constraints of a design.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Constraints {
    /// Per beam: may be printed from its first joint to its second.
    pub forward: Vec<bool>,
    /// Per beam: may be printed from its second joint to its first.
    pub backward: Vec<bool>,
    /// `pred[pred_start[b]..pred_start[b + 1]]`: the beams that must be printed before `b`,
    /// ascending.
    pub pred_start: Vec<u32>,
    /// See `pred_start`.
    pub pred: Vec<u32>,
    /// `succ[succ_start[a]..succ_start[a + 1]]`: the beams that must be printed after `a`.
    pub succ_start: Vec<u32>,
    /// See `succ_start`.
    pub succ: Vec<u32>,
    /// Pairs given to the exact test (after the BVH and the 2D filter).
    pub tested: usize,
    /// Per beam: the nozzle's axis it is printed with (+Z unless the nozzle may tilt).
    pub axis: Vec<DVec3>,
    /// Beams printed with a tilted nozzle.
    pub tilted: usize,
    /// Precedences a vertical nozzle would have had (equal to the pairs without tilting).
    pub vertical_pairs: usize,
}

impl Constraints {
    /// The constraints among `beams` alone (global indices, ascending), renumbered 0.. in that
    /// order: precedences with beams outside are dropped (the caller has them printed).
    pub fn restricted(&self, beams: &[usize]) -> Constraints {
        let local = |b: u32| beams.binary_search(&(b as usize)).ok().map(|i| i as u32);
        let mut pairs: Vec<(u32, u32)> = Vec::new();
        for (i, &a) in beams.iter().enumerate() {
            for &s in self.succs(a) {
                if let Some(j) = local(s) {
                    pairs.push((i as u32, j));
                }
            }
        }
        let m = beams.len();
        let (succ_start, succ, pred_start, pred) = both_csr(&pairs, m);
        Constraints {
            forward: beams.iter().map(|&b| self.forward[b]).collect(),
            backward: beams.iter().map(|&b| self.backward[b]).collect(),
            pred_start,
            pred,
            succ_start,
            succ,
            tested: 0,
            axis: beams.iter().map(|&b| self.axis.get(b).copied().unwrap_or(DVec3::Z)).collect(),
            tilted: 0,
            vertical_pairs: 0,
        }
    }
    /// The beams that must precede `b`.
    pub fn preds(&self, b: usize) -> &[u32] {
        &self.pred[self.pred_start[b] as usize..self.pred_start[b + 1] as usize]
    }
    /// The beams that must follow `a`.
    pub fn succs(&self, a: usize) -> &[u32] {
        &self.succ[self.succ_start[a] as usize..self.succ_start[a + 1] as usize]
    }
    /// Precedence pairs.
    pub fn pairs(&self) -> usize {
        self.pred.len()
    }
}

/// Why the constraints could not be computed.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum Error {
    /// Too many precedence pairs to keep.
    #[error("more than {MAX_PAIRS} collision precedences: the nozzle is very large for this design; lower the nozzle's radius or height")]
    TooManyPairs,
    /// A setting out of range.
    #[error("{0}")]
    Setting(String),
}

fn v(p: DVec3) -> Vector {
    Vector::new(p.x, p.y, p.z)
}

/// The nozzle's two convex parts, tip at the origin.
struct Body {
    cone: Cone,
    cone_pose: Pose,
    cylinder: Cylinder,
    cylinder_pose: Pose,
}

impl Body {
    /// The body with its axis along `axis` (unit), tip at the origin.
    fn along(n: &Nozzle, axis: DVec3) -> Body {
        let hc = n.cone_height();
        // parry's cone: apex at +y; turned so the apex points down (−z) at the origin, then
        // the whole body turned from +Z onto the axis.
        let tilt = Rot3::from_rotation_arc(Vector::Z, v(axis).normalize());
        let down = tilt * Rot3::from_rotation_x(-std::f64::consts::FRAC_PI_2);
        let up = tilt * Rot3::from_rotation_x(std::f64::consts::FRAC_PI_2);
        Body {
            cone: Cone::new(hc / 2.0, n.radius_mm),
            cone_pose: Pose::from_parts(tilt * Vector::new(0.0, 0.0, hc / 2.0), down),
            cylinder: Cylinder::new(n.height_mm / 2.0, n.radius_mm),
            cylinder_pose: Pose::from_parts(tilt * Vector::new(0.0, 0.0, hc + n.height_mm / 2.0), up),
        }
    }

    /// Whether a point set `tri` (a triangle of b − a) comes within `r` of the body.
    fn near(&self, tri: &Triangle, r: f64) -> bool {
        let id = Pose::IDENTITY;
        let d1 = parry3d_f64::query::distance(&self.cone_pose, &self.cone, &id, tri).map_or(f64::INFINITY, |d| d.distance);
        if d1 <= r {
            return true;
        }
        if self.cylinder.half_height > 0.0 {
            let d2 = parry3d_f64::query::distance(&self.cylinder_pose, &self.cylinder, &id, tri).map_or(f64::INFINITY, |d| d.distance);
            return d2 <= r;
        }
        false
    }

    /// Whether the nozzle swept along a0→a1 meets the segment b0→b1 inflated by `r`.
    fn sweep_hits(&self, a0: DVec3, a1: DVec3, b0: DVec3, b1: DVec3, r: f64) -> bool {
        let (p, q, s, t) = (b0 - a0, b1 - a0, b1 - a1, b0 - a1);
        self.near(&Triangle::new(v(p), v(q), v(s)), r) || self.near(&Triangle::new(v(p), v(s), v(t)), r)
    }
}

/// Whether the nozzle printing beam `a` (its two joints, in either order: the sweep is the same)
/// meets beam `b`: its capsule of radius `beam_radius`, or, when the two share the joint
/// `shared`, its axis from a little off that joint. The exact test of [`constraints`], for
/// checks and tools.
pub fn collides(nozzle: &Nozzle, a: [DVec3; 2], b: [DVec3; 2], shared: Option<DVec3>, beam_radius: f64) -> bool {
    collides_along(nozzle, DVec3::Z, a, b, shared, beam_radius)
}

/// [`collides`] with the nozzle's axis along `axis` (unit).
pub fn collides_along(nozzle: &Nozzle, axis: DVec3, a: [DVec3; 2], b: [DVec3; 2], shared: Option<DVec3>, beam_radius: f64) -> bool {
    let body = Body::along(nozzle, axis);
    match shared {
        Some(s) => {
            let (from, to) = if b[0].distance(s) <= b[1].distance(s) { (b[0], b[1]) } else { (b[1], b[0]) };
            body.sweep_hits(a[0], a[1], off_joint(from, to, beam_radius), to, 0.0)
        }
        None => body.sweep_hits(a[0], a[1], b[0], b[1], beam_radius),
    }
}

/// The start of a beam's axis tested against a nozzle at a joint it shares: a little off the
/// joint (twice the radius, at least 0.1 % of the beam, at most half of it).
fn off_joint(from: DVec3, to: DVec3, beam_radius: f64) -> DVec3 {
    let len = from.distance(to);
    let off = (beam_radius * 2.0).max(len * 1e-3).min(len * 0.5);
    from + (to - from) * (off / len)
}

/// Squared distance between 2D segments (XY of the given points).
fn seg_dist2_xy(a0: DVec3, a1: DVec3, b0: DVec3, b1: DVec3) -> f64 {
    let (p, q, r, s) = (a0.truncate(), a1.truncate(), b0.truncate(), b1.truncate());
    let pt_seg = |x: glam::DVec2, a: glam::DVec2, b: glam::DVec2| {
        let d = b - a;
        let l = d.length_squared();
        let t = if l > 0.0 { ((x - a).dot(d) / l).clamp(0.0, 1.0) } else { 0.0 };
        (a + d * t).distance_squared(x)
    };
    // Crossing segments: 0.
    let cross = |o: glam::DVec2, a: glam::DVec2, b: glam::DVec2| (a - o).perp_dot(b - o);
    let (d1, d2, d3, d4) = (cross(r, s, p), cross(r, s, q), cross(p, q, r), cross(p, q, s));
    if ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0)) && ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0)) {
        return 0.0;
    }
    pt_seg(p, r, s).min(pt_seg(q, r, s)).min(pt_seg(r, p, q)).min(pt_seg(s, p, q))
}

/// The constraints of the design `beams` over `joints` (mm).
pub fn constraints(joints: &[DVec3], beams: &[[usize; 2]], options: &Options, progress: &mut dyn FnMut(f32)) -> Result<Constraints, Error> {
    let n = &options.nozzle;
    if !(n.half_angle_deg > 0.0 && n.half_angle_deg < 90.0) {
        return Err(Error::Setting(format!("a cone half-angle of {}° is not a nozzle: use more than 0° and less than 90°", n.half_angle_deg)));
    }
    if !(n.radius_mm > 0.0 && n.height_mm >= 0.0 && options.beam_radius_mm >= 0.0) {
        return Err(Error::Setting("the nozzle's radius must be above 0 mm and its height and the beam radius 0 mm or more".into()));
    }
    if !(0.0..=MAX_TILT_DEG).contains(&options.tilt_deg) {
        return Err(Error::Setting(format!("a tilt of {}° is out of range: use 0° (a 3-axis machine) to {MAX_TILT_DEG}°", options.tilt_deg)));
    }
    let m = beams.len();
    let axes = tilt_axes(options.tilt_deg);
    // The directions each axis allows a beam.
    let dirs = |b: usize, axis: DVec3| -> (bool, bool) {
        if !options.directionality {
            return (true, true);
        }
        let [i, j] = beams[b];
        let d = (joints[j] - joints[i]).normalize_or_zero();
        (n.can_print_along(d, axis), n.can_print_along(-d, axis))
    };
    let mut forward = vec![true; m];
    let mut backward = vec![true; m];
    let mut axis = vec![DVec3::Z; m];
    for b in 0..m {
        (forward[b], backward[b]) = dirs(b, DVec3::Z);
    }
    let mut pairs: Vec<(u32, u32)> = Vec::new();
    let mut tested = 0usize;
    let mut vertical_pairs = 0usize;
    let mut tilted = 0usize;
    if !options.collision && axes.len() > 1 {
        // Only directions to gain: the first axis that allows both, or the vertical.
        for b in 0..m {
            if !(forward[b] && backward[b]) {
                if let Some(&t) = axes.iter().find(|&&t| dirs(b, t) == (true, true)) {
                    axis[b] = t;
                    (forward[b], backward[b]) = (true, true);
                    tilted += 1;
                }
            }
        }
    }
    if options.collision && m > 0 {
        let r = options.beam_radius_mm;
        let boxes: Vec<Aabb> = beams
            .iter()
            .map(|&[i, j]| {
                let (a, b) = (joints[i], joints[j]);
                Aabb::new(v(a.min(b) - DVec3::splat(r)), v(a.max(b) + DVec3::splat(r)))
            })
            .collect();
        let bvh = Bvh::from_leaves(BvhBuildStrategy::Binned, &boxes);
        let bodies: Vec<Body> = axes.iter().map(|&t| Body::along(n, t)).collect();
        // A tilted body reaches farther sideways (its top swings out) and its rim may dip
        // below the tip.
        let sin_tilt = libm::sin(options.tilt_deg.to_radians());
        let (reach, top) = (n.radius_mm + r + n.top() * sin_tilt, n.top() + r);
        let below = r + n.radius_mm * sin_tilt;
        // Each beam's queries on their own, beams side by side (runs reuse their buffers);
        // a shared count of pairs stops every run once the design is refused.
        let total = std::sync::atomic::AtomicUsize::new(0);
        let runs = if crate::par::threads() > 1 { 8 * crate::par::threads() } else { 1 };
        let per_beam = crate::par::map_runs(m, runs, &mut |d| progress(d as f32 / m as f32), |range, tick| {
            let mut found: Vec<u32> = Vec::new();
            let mut near: NearBeams = Vec::new();
            let mut hits: Vec<u32> = Vec::new();
            range
                .map(|a| {
                    let out = if total.load(std::sync::atomic::Ordering::Relaxed) > MAX_PAIRS {
                        BeamQueries::default()
                    } else {
                        let q = beam_queries(a, joints, beams, &bvh, &bodies, &axes, &dirs, (reach, top, below), r, (&mut found, &mut near, &mut hits));
                        total.fetch_add(q.hits.len(), std::sync::atomic::Ordering::Relaxed);
                        q
                    };
                    tick();
                    out
                })
                .collect::<Vec<_>>()
        });
        if total.into_inner() > MAX_PAIRS {
            return Err(Error::TooManyPairs);
        }
        for (a, q) in per_beam.into_iter().enumerate() {
            tested += q.tested;
            vertical_pairs += q.vertical_pairs;
            axis[a] = q.axis;
            (forward[a], backward[a]) = q.directions;
            if q.axis != DVec3::Z {
                tilted += 1;
            }
            pairs.extend(q.hits.iter().map(|&b| (a as u32, b)));
        }
    }
    let (succ_start, succ, pred_start, pred) = both_csr(&pairs, m);
    Ok(Constraints { forward, backward, pred_start, pred, succ_start, succ, tested, axis, tilted, vertical_pairs })
}

/// What the collision queries of one beam found.
#[derive(Default)]
struct BeamQueries {
    /// The nozzle axis chosen and the directions it allows.
    axis: DVec3,
    directions: (bool, bool),
    /// Beams its sweep hits along that axis (it precedes them).
    hits: Vec<u32>,
    /// Exact pair tests made; hits along the vertical.
    tested: usize,
    vertical_pairs: usize,
}

/// Beams near a beam A, each with the joint it shares with A (if any).
type NearBeams = Vec<(u32, Option<usize>)>;

/// The collision queries of beam `a`: near beams from the BVH, then each axis in turn (the
/// vertical first); a tilt is kept when it allows more directions, or as many and hits fewer
/// beams. `reach` is (sideways, above, below) of the nozzle's box; the buffers are reused.
#[allow(clippy::too_many_arguments)]
fn beam_queries(
    a: usize,
    joints: &[DVec3],
    beams: &[[usize; 2]],
    bvh: &Bvh,
    bodies: &[Body],
    axes: &[DVec3],
    dirs: &dyn Fn(usize, DVec3) -> (bool, bool),
    (reach, top, below): (f64, f64, f64),
    r: f64,
    (found, near, hits): (&mut Vec<u32>, &mut NearBeams, &mut Vec<u32>),
) -> BeamQueries {
    let [i, j] = beams[a];
    let (a0, a1) = (joints[i], joints[j]);
    let lo = a0.min(a1) - DVec3::new(reach, reach, below);
    let hi = a0.max(a1) + DVec3::new(reach, reach, top);
    let query = Aabb::new(v(lo), v(hi));
    found.clear();
    found.extend(bvh.intersect_aabb(&query).filter(|&b| b as usize != a));
    found.sort_unstable();
    near.clear();
    for &b in found.iter() {
        let [k, l] = beams[b as usize];
        if seg_dist2_xy(a0, a1, joints[k], joints[l]) <= reach * reach {
            near.push((b, [i, j].iter().find(|&&x| x == k || x == l).copied()));
        }
    }
    // Unless an axis is chosen below, the vertical's directions (none) stand.
    let mut out = BeamQueries { axis: DVec3::Z, directions: dirs(a, DVec3::Z), ..Default::default() };
    let mut best_key = (0u8, usize::MAX);
    for (t, body) in bodies.iter().enumerate() {
        let (f, bk) = dirs(a, axes[t]);
        let allowed = u8::from(f) + u8::from(bk);
        if allowed == 0 || (t > 0 && best_key.0 == 2 && best_key.1 == 0) {
            continue;
        }
        hits.clear();
        for &(b, shared) in near.iter() {
            let [k, l] = beams[b as usize];
            let (b0, b1) = (joints[k], joints[l]);
            out.tested += 1;
            // A joint shared with A: B's axis from a little off that joint, radius 0.
            let hit = match shared {
                Some(s) => {
                    let (from, to) = if k == s { (b0, b1) } else { (b1, b0) };
                    body.sweep_hits(a0, a1, off_joint(from, to, r), to, 0.0)
                }
                None => body.sweep_hits(a0, a1, b0, b1, r),
            };
            if hit {
                hits.push(b);
                if allowed == best_key.0 && hits.len() >= best_key.1 {
                    break;
                }
            }
        }
        if t == 0 {
            out.vertical_pairs += hits.len();
        }
        if (allowed, std::cmp::Reverse(hits.len())) > (best_key.0, std::cmp::Reverse(best_key.1)) || t == 0 {
            best_key = (allowed, hits.len());
            out.hits.clone_from(hits);
            out.axis = axes[t];
            out.directions = (f, bk);
        }
    }
    out
}

/// A precedence pair (A, B) mapped to the (row, column) of a CSR.
type PairKey = dyn Fn(&(u32, u32)) -> (u32, u32);

/// Precedence pairs (A before B) as CSR both ways: (succ_start, succ, pred_start, pred).
fn both_csr(pairs: &[(u32, u32)], m: usize) -> (Vec<u32>, Vec<u32>, Vec<u32>, Vec<u32>) {
    let csr = |key: &PairKey| -> (Vec<u32>, Vec<u32>) {
        let mut sorted: Vec<(u32, u32)> = pairs.iter().map(key).collect();
        sorted.sort_unstable();
        let mut start = vec![0u32; m + 1];
        for &(x, _) in &sorted {
            start[x as usize + 1] += 1;
        }
        for x in 0..m {
            start[x + 1] += start[x];
        }
        (start, sorted.into_iter().map(|(_, y)| y).collect())
    };
    let (succ_start, succ) = csr(&|&(a, b)| (a, b));
    let (pred_start, pred) = csr(&|&(a, b)| (b, a));
    (succ_start, succ, pred_start, pred)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn body_is_above_the_tip() {
        let b = Body::along(&Nozzle { half_angle_deg: 13.0, radius_mm: 0.5, height_mm: 5.0 }, DVec3::Z);
        let tri = |p: DVec3| Triangle::new(v(p), v(p + DVec3::new(1e-3, 0.0, 0.0)), v(p + DVec3::new(0.0, 1e-3, 0.0)));
        for (p, inside) in [
            (DVec3::new(0.0, 0.0, 1.0), true),
            (DVec3::new(0.0, 0.0, 6.0), true),
            (DVec3::new(0.0, 0.0, -1.0), false),
            (DVec3::new(3.0, 0.0, 1.0), false),
            (DVec3::new(0.3, 0.0, 3.0), true),
            (DVec3::new(0.3, 0.0, 0.5), false),
            (DVec3::new(0.0, 0.0, 8.0), false),
        ] {
            assert_eq!(b.near(&tri(p), 0.0), inside, "{p:?}");
        }
    }
}

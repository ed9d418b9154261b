//! Fast Clairaut solver: the geodesic between two (u, θ) points of a surface of revolution as
//! a one-dimensional root find, with fixed Gauss–Kronrod quadrature instead of adaptive
//! integration, so one pair costs a few hundred profile evaluations (microseconds) rather
//! than tens of thousands.
//!
//! Along a geodesic x·sin ψ = c (ψ: angle to the meridian). While u moves monotonically,
//! dθ/du = c·s/(x·√(x² − c²)) and ds/du = x·s/√(x² − c²), s = √g_uu. Both integrands have a
//! 1/√ singularity where x = c (at the lowest-radius end of the pair, or at a turning point);
//! the substitution u = u_anchor + (u_far − u_anchor)·t² removes it, and panels graded
//! geometrically towards t = 0 resolve the near-singular case (a pair almost along a parallel).
//!
//! Two shapes of geodesic are solved:
//! - monotone in u: unknown c ∈ [0, x_min), Δθ(c) increasing; x_min is an end of the pair or an
//!   interior waist (then the interval is split there);
//! - turning once in u, beyond the lower-radius end u_e (the geodesic bulges towards the axis):
//!   unknown w = distance of the turning point past u_e, c = x(u_e ± w).
//!
//! Anything else (two critical points of x between the ends, a pair on a parallel where
//! x′ = 0, a quadrature that will not converge) returns `None` and the caller uses the
//! general ODE shooter. Every answer is checked: the Kronrod–Gauss difference of Δθ and of
//! the length must be below [`QUADRATURE_REL_TOL`] or the panels are refined.

use super::platform::{Jet, Profile};

/// Accepted |Kronrod − Gauss| of Δθ and of the length, relative. This is the 7-point Gauss
/// value's error; the 15-point Kronrod value used is far more accurate (for an analytic
/// integrand its error goes as the Gauss error to the power 23/14, about 1e-10 here). The
/// sphere test holds the result to 1e-9 relative over turning and near-parallel pairs.
pub const QUADRATURE_REL_TOL: f64 = 1e-6;
/// Below this |u − u_anchor| the radius difference x(u) − x(u_anchor) is taken from the
/// anchor's third-order Taylor expansion (error x⁗·h⁴/24 ≈ 1e-12 mm on the presets), so the
/// differences that matter near x = c do not cancel.
const TAYLOR_H: f64 = 1e-3;
/// Panels per leg on the first try, then on refinement: (panels graded by 4 over t ∈ [0, ¼],
/// equal panels over [¼, 1]); (0, 1) is one panel over [0, 1], enough for most short pairs.
const PANELS: [(usize, usize); 6] = [(0, 1), (1, 1), (3, 2), (6, 4), (10, 8), (16, 16)];
/// The root finders stop when Δθ is within this of the target (relative, plus 1e-9 rad),
/// then take one closed-form Newton step, which leaves an O(1e-18) error.
const ROOT_TOL: f64 = 1e-9;
/// Root-finder iteration caps.
const MAX_ROOT_ITERATIONS: usize = 100;
const MAX_BRACKET_STEPS: usize = 60;

// Gauss–Kronrod 7/15 on [−1, 1] (QUADPACK's qk15): abscissae ≥ 0, Kronrod weights, and the
// Gauss weights of the abscissae with odd index.
const XGK: [f64; 8] = [
    0.991_455_371_120_812_6,
    0.949_107_912_342_758_5,
    0.864_864_423_359_769_1,
    0.741_531_185_599_394_4,
    0.586_087_235_467_691_1,
    0.405_845_151_377_397_2,
    0.207_784_955_007_898_5,
    0.0,
];
const WGK: [f64; 8] = [
    0.022_935_322_010_529_22,
    0.063_092_092_629_978_55,
    0.104_790_010_322_250_2,
    0.140_653_259_715_525_9,
    0.169_004_726_639_267_9,
    0.190_350_578_064_785_4,
    0.204_432_940_075_298_9,
    0.209_482_141_084_727_8,
];
const WG: [f64; 4] = [0.129_484_966_168_869_7, 0.279_705_391_489_276_7, 0.381_830_050_505_118_9, 0.417_959_183_673_469_4];

/// A solved geodesic.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Solution {
    /// Length, mm.
    pub length_mm: f64,
    /// Clairaut's constant c = x·sin ψ, mm.
    pub c: f64,
    /// Unit tangent (du/ds, dθ/ds) leaving the first point.
    pub start: [f64; 2],
    /// Unit tangent (du/ds, dθ/ds) arriving at the second point.
    pub end: [f64; 2],
    /// u where the geodesic turns back, if it does.
    pub turn: Option<f64>,
    /// Smallest radius along the geodesic, mm (c at a turning point, else the lowest of the
    /// ends and any waist between them).
    pub min_radius_mm: f64,
}

/// One quadrature node: radius, radius above the leg's anchor, weighted s = √g_uu.
#[derive(Clone, Copy)]
struct QNode {
    x: f64,
    inv_x: f64,
    dx: f64,
    /// Kronrod weight × du/dt × s.
    wk: f64,
    /// Gauss weight × du/dt × s (0 off the Gauss nodes).
    wg: f64,
}

/// An integration interval from an anchor (where x may equal c) to a far end.
struct Leg {
    nodes: Vec<QNode>,
}

/// Kronrod and Gauss sums of Δθ, length and dΔθ/dc over a leg.
#[derive(Clone, Copy, Default)]
struct Sums {
    theta: f64,
    theta_g: f64,
    len: f64,
    len_g: f64,
    dtheta_dc: f64,
}

impl Sums {
    fn add(self, o: Sums, k: f64) -> Sums {
        Sums {
            theta: self.theta + k * o.theta,
            theta_g: self.theta_g + k * o.theta_g,
            len: self.len + k * o.len,
            len_g: self.len_g + k * o.len_g,
            dtheta_dc: self.dtheta_dc + k * o.dtheta_dc,
        }
    }
    fn converged(&self) -> bool {
        (self.theta - self.theta_g).abs() <= QUADRATURE_REL_TOL * self.theta.abs().max(1e-9) && (self.len - self.len_g).abs() <= QUADRATURE_REL_TOL * self.len
    }
}

fn speed(j: &Jet) -> f64 {
    (j.x[1] * j.x[1] + j.z[1] * j.z[1]).sqrt()
}

/// x(u) − x(anchor) given x(u), without cancellation near the anchor.
fn rise_x(x: f64, anchor_u: f64, anchor: &Jet, u: f64) -> f64 {
    let h = u - anchor_u;
    if h.abs() <= TAYLOR_H {
        h * (anchor.x[1] + h * (0.5 * anchor.x[2] + h * anchor.x[3] / 6.0))
    } else {
        x - anchor.x[0]
    }
}

fn rise(j: &Jet, anchor_u: f64, anchor: &Jet, u: f64) -> f64 {
    rise_x(j.x[0], anchor_u, anchor, u)
}

impl Leg {
    /// Nodes on u = anchor + (k − anchor)·t², t ∈ [0, 1], up to the first knot k between the
    /// anchor and the far end (or the far end): `panels.1` equal panels over [¼, 1] and
    /// `panels.0` panels graded by 4 towards t = 0; then `panels.1` plain panels per piece
    /// between knots (the integrand is analytic only within a polynomial piece). `None` if x
    /// dips below the anchor's radius (a critical point the caller did not split at).
    fn new<P: Profile + ?Sized>(p: &P, anchor_u: f64, anchor: &Jet, far_u: f64, panels: (usize, usize)) -> Option<Leg> {
        let mut cuts = Vec::new();
        p.knots_between(anchor_u.min(far_u), anchor_u.max(far_u), &mut cuts);
        if far_u < anchor_u {
            cuts.reverse();
        }
        cuts.push(far_u);
        let (graded, top) = panels;
        let mut nodes = Vec::with_capacity(15 * (graded + top * cuts.len()));
        // (piece start, piece end, t-panel [a, b], squared map?)
        let mut push = |from: f64, to: f64, a: f64, b: f64, squared: bool| -> Option<()> {
            let span = to - from;
            let (mid, half) = (0.5 * (a + b), 0.5 * (b - a));
            for i in 0..15 {
                let (xi, wk, wg) = if i < 7 {
                    (-XGK[i], WGK[i], if i % 2 == 1 { WG[i / 2] } else { 0.0 })
                } else if i == 7 {
                    (0.0, WGK[7], WG[3])
                } else {
                    let m = 14 - i;
                    (XGK[m], WGK[m], if m % 2 == 1 { WG[m / 2] } else { 0.0 })
                };
                let t = mid + half * xi;
                let (u, du_dt) = if squared { (from + span * t * t, 2.0 * span.abs() * t) } else { (from + span * t, span.abs()) };
                let [x, _, su] = p.radius_speed(u);
                let dx = rise_x(x, anchor_u, anchor, u);
                if !(dx >= -1e-12 * anchor.x[0].abs().max(1.0)) || !(x > 0.0) {
                    return None;
                }
                let f = half * du_dt * su;
                nodes.push(QNode { x, inv_x: 1.0 / x, dx: dx.max(0.0), wk: wk * f, wg: wg * f });
            }
            Some(())
        };
        let mut b = 1.0;
        for k in 0..graded + top {
            let a = if k + 1 == graded + top {
                0.0
            } else if k < top {
                1.0 - 0.75 * (k + 1) as f64 / top as f64
            } else {
                b * 0.25
            };
            push(anchor_u, cuts[0], a, b, true)?;
            b = a;
        }
        for w in cuts.windows(2) {
            for k in 0..top {
                push(w[0], w[1], k as f64 / top as f64, (k + 1) as f64 / top as f64, false)?;
            }
        }
        Some(Leg { nodes })
    }

    /// Sums for Clairaut constant c, with x − c = dx + `offset` at every node.
    fn sums(&self, c: f64, offset: f64) -> Option<Sums> {
        let mut s = Sums::default();
        for n in &self.nodes {
            let xmc = n.dx + offset;
            let q2 = xmc * (n.x + c);
            if !(q2 > 0.0) {
                return None;
            }
            let iq = 1.0 / q2.sqrt();
            let th = c * n.inv_x * iq;
            let ln = n.x * iq;
            s.theta += n.wk * th;
            s.theta_g += n.wg * th;
            s.len += n.wk * ln;
            s.len_g += n.wg * ln;
            s.dtheta_dc += n.wk * ln * iq * iq;
        }
        Some(s)
    }
}

/// [lo, hi] cut at the radius's critical points into pieces where x is monotone, each
/// integrated from its lower-radius end; `base` = that end's radius above the lowest one.
struct Span {
    /// (u, jet) of the cut points, ascending, both ends included.
    cuts: Vec<(f64, Jet)>,
    /// Index in `cuts` of the lowest radius.
    min: usize,
}

impl Span {
    fn new<P: Profile + ?Sized>(p: &P, lo: (f64, Jet), hi: (f64, Jet)) -> Span {
        let mut crit = Vec::new();
        p.radius_turns(lo.0, hi.0, &mut crit);
        let mut cuts = Vec::with_capacity(crit.len() + 2);
        cuts.push(lo);
        cuts.extend(crit.into_iter().map(|u| (u, p.jet(u))));
        cuts.push(hi);
        let min = (0..cuts.len()).fold(0, |m, i| if cuts[i].1.x[0] < cuts[m].1.x[0] { i } else { m });
        Span { cuts, min }
    }

    fn lowest(&self) -> (f64, Jet) {
        self.cuts[self.min]
    }

    /// The radius's lowest point is an end of the span with x′ ≠ 0 there: Δθ stays finite as
    /// c → x_min, and beyond it the geodesic turns.
    fn min_at_end(&self) -> bool {
        (self.min == 0 || self.min + 1 == self.cuts.len()) && self.cuts[self.min].1.x[1] != 0.0
    }

    /// One leg per piece, with its base above the lowest radius.
    fn legs<P: Profile + ?Sized>(&self, p: &P, panels: (usize, usize)) -> Option<Vec<(Leg, f64)>> {
        let x_min = self.cuts[self.min].1.x[0];
        self.cuts
            .windows(2)
            .enumerate()
            .map(|(i, w)| {
                let (anchor, far, ai) = if w[0].1.x[0] <= w[1].1.x[0] { (&w[0], &w[1], i) } else { (&w[1], &w[0], i + 1) };
                let base = if ai == self.min { 0.0 } else { (anchor.1.x[0] - x_min).max(0.0) };
                Some((Leg::new(p, anchor.0, &anchor.1, far.0, panels)?, base))
            })
            .collect()
    }
}

/// Kronrod and Gauss sums over legs for constant c, x − c = dx + base + `offset`.
fn total(legs: &[(Leg, f64)], c: f64, offset: f64) -> Option<Sums> {
    let mut s = Sums::default();
    for (l, base) in legs {
        s = s.add(l.sums(c, base + offset)?, 1.0);
    }
    Some(s)
}

/// Geodesic from `a` to `b` (θ of `b` already the nearer turn: |Δθ| ≤ π). Both points must be
/// inside the profile's range and at least `min_r` from the axis (the caller checks);
/// `None` = not a shape this solver handles, use the ODE shooter.
pub fn solve<P: Profile + ?Sized>(p: &P, a: [f64; 2], b: [f64; 2], min_r: f64) -> Option<Solution> {
    let (u0, u1) = (a[0], b[0]);
    let dt = b[1] - a[1];
    let target = dt.abs();
    let st = if dt < 0.0 { -1.0 } else { 1.0 };
    let (ja, jb) = (p.jet(u0), p.jet(u1));
    let same_u = (u1 - u0).abs() <= 1e-12 * (1.0 + u0.abs());
    if same_u {
        return if target == 0.0 { None } else { turning(p, a, b, min_r, st) };
    }
    let su = if u1 > u0 { 1.0 } else { -1.0 };
    let span = if u0 < u1 { Span::new(p, (u0, ja), (u1, jb)) } else { Span::new(p, (u1, jb), (u0, ja)) };
    let (anchor_u, anchor) = span.lowest();
    let x_ref = anchor.x[0];
    // x − c at the ends is (x − x_ref) + δ.
    let a_rise = rise(&ja, anchor_u, &anchor, u0);
    let b_rise = rise(&jb, anchor_u, &anchor, u1);
    let tangent = |j: &Jet, x_minus_c: f64, c: f64| -> [f64; 2] {
        let x = j.x[0];
        let cos = (x_minus_c.max(0.0) * (x + c)).sqrt() / x;
        [su * cos / speed(j), st * c / (x * x)]
    };
    // Start from the direction of the chord in the midpoint's metric (the first-order
    // geodesic), so Newton starts within its quadratic range on short pairs.
    let jm = p.jet(0.5 * (u0 + u1));
    let (along_u, along_t) = (speed(&jm) * (u1 - u0).abs(), jm.x[0] * target);
    let c0 = (jm.x[0] * along_t / (along_u * along_u + along_t * along_t).sqrt()).min(x_ref * (1.0 - 1e-6));
    for &panels in &PANELS {
        let legs = span.legs(p, panels)?;
        let finish = |s: Sums, c: f64, delta: f64| Solution {
            length_mm: s.len,
            c,
            start: tangent(&ja, a_rise + delta, c),
            end: tangent(&jb, b_rise + delta, c),
            turn: None,
            min_radius_mm: x_ref,
        };
        if target == 0.0 {
            let s = total(&legs, 0.0, x_ref)?;
            if s.converged() {
                return Some(finish(s, 0.0, x_ref));
            }
            continue;
        }
        if span.min_at_end() && c0 > 0.5 * x_ref {
            // Δθ of the geodesic that leaves the lower end along the parallel: beyond it the
            // geodesic turns. (Only a pair heading within 30° of the parallel can; the root
            // finder below also hands over if it finds no root. The turning solver checks its
            // own quadrature; at the boundary both shapes meet in the same geodesic.)
            let s = total(&legs, x_ref, 0.0)?;
            if target >= s.theta {
                return turning(p, a, b, min_r, st);
            }
        }
        // Root of Δθ(δ) − target in r = √δ, c = x_ref − δ (Δθ falls as δ grows):
        // safeguarded Newton inside a bracket, bisection when Newton leaves it.
        let (mut r_lo, mut r_hi) = (0.0f64, x_ref.sqrt());
        let mut r = (x_ref - c0).sqrt();
        let mut found = None;
        for _ in 0..MAX_ROOT_ITERATIONS {
            let delta = r * r;
            let c = x_ref - delta;
            let mut s = total(&legs, c, delta)?;
            let g = s.theta - target;
            if g.abs() <= ROOT_TOL * (1.0 + target) && s.dtheta_dc > 0.0 {
                // One more Newton step in closed form: δ moves by g/Δθ′(c) and the length by
                // −c·g (first variation: dL/dc = c·dΔθ/dc); what is left is O(g²).
                let delta = (delta + g / s.dtheta_dc).max(0.0);
                s.len -= c * g;
                found = Some((s, x_ref - delta, delta));
                break;
            }
            if r_hi - r_lo <= 1e-16 * (1.0 + r_hi) {
                if r_lo == 0.0 && g < 0.0 && span.min_at_end() {
                    // Δθ stays below the target up to the parallel: it turns.
                    return turning(p, a, b, min_r, st);
                }
                return None;
            }
            if g > 0.0 {
                r_lo = r
            } else {
                r_hi = r
            }
            // dΔθ/dr = −dΔθ/dc · 2r.
            let slope = -s.dtheta_dc * 2.0 * r;
            let next = r - g / slope;
            r = if next > r_lo && next < r_hi && slope < 0.0 { next } else { 0.5 * (r_lo + r_hi) };
        }
        let (s, c, delta) = found?;
        if s.converged() {
            return Some(finish(s, c, delta));
        }
    }
    None
}

/// The geodesic that turns back in u once, past the lower-radius end.
fn turning<P: Profile + ?Sized>(p: &P, a: [f64; 2], b: [f64; 2], min_r: f64, st: f64) -> Option<Solution> {
    let (u0, u1) = (a[0], b[0]);
    let target = (b[1] - a[1]).abs();
    let (ja, jb) = (p.jet(u0), p.jet(u1));
    let same_u = (u1 - u0).abs() <= 1e-12 * (1.0 + u0.abs());
    // u_e: the lower end; σ: outward from it (away from the other end; on one parallel, the
    // side where x falls).
    let (ue, je, uo, jo) = if ja.x[0] <= jb.x[0] { (u0, ja, u1, jb) } else { (u1, jb, u0, ja) };
    let sigma = if same_u {
        if je.x[1] == 0.0 {
            return None;
        }
        -je.x[1].signum()
    } else {
        (ue - uo).signum()
    };
    // x must fall outward, clearly (else the parallel itself is nearly a geodesic).
    if !(je.x[1] * sigma < -1e-9 * speed(&je)) {
        return None;
    }
    let (range_lo, range_hi) = p.u_range();
    let w_max = if sigma > 0.0 { range_hi - ue } else { ue - range_lo };
    if !(w_max > 0.0) {
        return None;
    }
    // Between the ends: the pieces of [u_e, u_o], measured from x_e (the lowest there).
    let span = if same_u {
        None
    } else {
        let s = if ue < uo { Span::new(p, (ue, je), (uo, jo)) } else { Span::new(p, (uo, jo), (ue, je)) };
        if s.lowest().0 != ue {
            return None;
        }
        Some(s)
    };
    for &panels in &PANELS {
        let legs_b = match &span {
            Some(s) => s.legs(p, panels)?,
            None => Vec::new(),
        };
        // Δθ and friends for a turning point w past u_e; None = invalid (range, pole, or
        // past a minimum of x).
        let eval = |w: f64| -> Option<(Sums, f64, f64, Jet)> {
            let ut = ue + sigma * w;
            let jt = p.jet(ut);
            let c = jt.x[0];
            if !(c >= min_r) || jt.x[1] * sigma >= 0.0 {
                return None;
            }
            let leg_a = Leg::new(p, ut, &jt, ue, panels)?;
            let sa = leg_a.sums(c, 0.0)?;
            let off_e = rise(&je, ut, &jt, ue);
            if !(off_e > 0.0) {
                return None;
            }
            let s = Sums::default().add(sa, 2.0).add(total(&legs_b, c, off_e)?, 1.0);
            Some((s, c, off_e, jt))
        };
        // Bracket in r = √w: Δθ − target < 0 as r → 0 and grows with r; grow r until it is
        // positive, halving back towards the last good r where the turning point is invalid.
        let r_max = w_max.sqrt();
        let (mut r_lo, mut g_lo) = (0.0f64, f64::NAN);
        let (mut r_hi, mut g_hi) = (f64::NAN, f64::NAN);
        let mut r_bad = f64::INFINITY;
        let mut r = (1e-6 * w_max).sqrt();
        for _ in 0..MAX_BRACKET_STEPS {
            match eval(r * r) {
                None => {
                    r_bad = r;
                    r = 0.5 * (r_lo + r);
                }
                Some((s, ..)) if s.theta > target => {
                    r_hi = r;
                    g_hi = s.theta - target;
                    break;
                }
                Some((s, ..)) => {
                    r_lo = r;
                    g_lo = s.theta - target;
                    if r >= r_max {
                        return None;
                    }
                    r = if r_bad.is_finite() { 0.5 * (r + r_bad) } else { (2.0 * r).min(r_max) };
                }
            }
        }
        if !r_hi.is_finite() {
            return None;
        }
        // Illinois regula falsi.
        let mut side = 0;
        let mut found = None;
        for _ in 0..MAX_ROOT_ITERATIONS {
            let r = if g_lo.is_finite() && g_hi.is_finite() && g_hi != g_lo { (r_lo * g_hi - r_hi * g_lo) / (g_hi - g_lo) } else { 0.5 * (r_lo + r_hi) };
            let r = if r > r_lo && r < r_hi { r } else { 0.5 * (r_lo + r_hi) };
            let (s, c, off_e, jt) = eval(r * r)?;
            let g = s.theta - target;
            if g.abs() <= 1e-14 * (1.0 + target) || r_hi - r_lo <= 1e-16 * (1.0 + r_hi) {
                found = Some((s, c, off_e, jt, r * r));
                break;
            }
            if g > 0.0 {
                r_hi = r;
                g_hi = g;
                if side == 1 {
                    g_lo *= 0.5;
                }
                side = 1;
            } else {
                r_lo = r;
                g_lo = g;
                if side == -1 {
                    g_hi *= 0.5;
                }
                side = -1;
            }
        }
        let (s, c, off_e, jt, w) = found?;
        if !s.converged() {
            continue;
        }
        let ut = ue + sigma * w;
        // Leaving a: outward (σ) in both cases; arriving at b: inward (−σ).
        let x_minus_c = |j: &Jet, u: f64| if u == ue { off_e } else { rise(j, ut, &jt, u) };
        let tangent = |j: &Jet, u: f64, su: f64| -> [f64; 2] {
            let x = j.x[0];
            let cos = (x_minus_c(j, u).max(0.0) * (x + c)).sqrt() / x;
            [su * cos / speed(j), st * c / (x * x)]
        };
        return Some(Solution { length_mm: s.len, c, start: tangent(&ja, u0, sigma), end: tangent(&jb, u1, -sigma), turn: Some(ut), min_radius_mm: c });
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::axisym::platform::Platform;
    use crate::axisym::testing::{great_circle, Sphere};

    /// Unit tangent of the great circle from a towards b, in (du/ds, dθ/ds).
    fn great_circle_start(r: f64, a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
        let pos = |q: [f64; 2]| [libm::sin(q[0]) * libm::cos(q[1]), libm::sin(q[0]) * libm::sin(q[1]), libm::cos(q[0])];
        let (pa, pb) = (pos(a), pos(b));
        let d = pa[0] * pb[0] + pa[1] * pb[1] + pa[2] * pb[2];
        let t = [pb[0] - d * pa[0], pb[1] - d * pa[1], pb[2] - d * pa[2]];
        let n = (t[0] * t[0] + t[1] * t[1] + t[2] * t[2]).sqrt();
        let t = [t[0] / n, t[1] / n, t[2] / n];
        let e_u = [libm::cos(a[0]) * libm::cos(a[1]), libm::cos(a[0]) * libm::sin(a[1]), -libm::sin(a[0])];
        let e_t = [-libm::sin(a[1]), libm::cos(a[1]), 0.0];
        let du = t[0] * e_u[0] + t[1] * e_u[1] + t[2] * e_u[2];
        let dt = t[0] * e_t[0] + t[1] * e_t[1] + t[2] * e_t[2];
        [du / r, dt / (r * libm::sin(a[0]))]
    }

    #[test]
    fn sphere_lengths_and_directions_to_1e_9() {
        let s = Sphere(10.0);
        let mut worst = 0.0f64;
        let mut turned = 0;
        // Monotone, turning, nearly along a parallel, on one parallel, long and short.
        let mut cases = vec![
            ([1.0, 0.0], [2.2, 0.9]),
            ([0.6, 0.3], [1.4, 0.5]),
            ([1.2, 0.0], [1.2, 1.0]),
            ([0.9, 0.0], [1.0, 1.5]),
            ([2.3, 0.2], [2.1, 1.9]),
            ([1.0, 0.0], [1.0 + 1e-7, 0.01]),
            ([1.3, 0.0], [1.31, 0.002]),
            ([0.5, 0.0], [0.8, 0.0]),
            ([1.0, 1.0], [1.0000001, 0.3]),
        ];
        for i in 0..200 {
            let f = i as f64;
            let a = [0.3 + 2.5 * libm::fabs(libm::sin(f * 1.7)), libm::sin(f * 0.37)];
            let b = [(a[0] + 0.3 * libm::sin(f * 2.3)).clamp(0.2, 2.9), a[1] + 0.4 * libm::cos(f * 1.1)];
            cases.push((a, b));
        }
        for (a, b) in cases {
            let sol = solve(&s, a, b, 0.1).unwrap_or_else(|| panic!("{a:?}→{b:?}: no solution"));
            let exact = great_circle(10.0, a, b);
            let err = (sol.length_mm - exact).abs() / exact;
            worst = worst.max(err);
            assert!(err < 1e-9, "{a:?}→{b:?}: {} vs {exact}", sol.length_mm);
            let t = great_circle_start(10.0, a, b);
            let g = [10.0 * (t[0] - sol.start[0]), 10.0 * libm::sin(a[0]) * (t[1] - sol.start[1])];
            assert!(g[0].hypot(g[1]) < 1e-7, "{a:?}→{b:?}: start {:?} vs {t:?}", sol.start);
            let back = great_circle_start(10.0, b, a);
            let g = [10.0 * (back[0] + sol.end[0]), 10.0 * libm::sin(b[0]) * (back[1] + sol.end[1])];
            assert!(g[0].hypot(g[1]) < 1e-7, "{a:?}→{b:?}: end {:?} vs {back:?}", sol.end);
            turned += sol.turn.is_some() as usize;
        }
        assert!(turned > 10, "turning geodesics exercised: {turned}");
        println!("sphere: worst relative length error {worst:.2e}, {turned} turning");
    }

    #[test]
    fn agrees_with_the_ode_shooter_on_the_presets() {
        use crate::axisym::geodesic::{geodesic, Method, Options};
        let ode = Options { method: Method::Ode, ..Options::default() };
        let mut n = 0;
        for (p, lo, hi) in [(Platform::barrel(), 0.6, 1.4), (Platform::hourglass(), 0.8, 3.2)] {
            for i in 0..60 {
                let f = i as f64;
                let a = [lo + (hi - lo) * 0.5 * (1.0 + libm::sin(f * 1.3)), 0.5 * libm::sin(f)];
                let b = [(a[0] + 0.08 * libm::sin(f * 2.9)).clamp(lo, hi), a[1] + 0.15 * libm::cos(f * 0.7)];
                let Some(sol) = solve(&p, a, b, 1.0) else { continue };
                let want = geodesic(&p, a, b, &ode).unwrap().length_mm;
                assert!(((sol.length_mm - want) / want).abs() < 1e-8, "{a:?}→{b:?}: {} vs {want}", sol.length_mm);
                n += 1;
            }
        }
        assert!(n >= 110, "solved {n} of 120");
    }
}

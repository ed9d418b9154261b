//! The build platform: a generatrix in the (x = radius, z = height) half-plane, revolved about
//! the z axis.
//!
//! Parametrisation (the paper's section 2.1 and table 1): segment k (0-based) of a composition
//! of K degree-6 Bézier segments covers u ∈ [k, k + 1] with its local Bézier parameter
//! t = u − k, so u runs over [0, K] from the first control point to the last (the barrel:
//! u ∈ [0, 2], the hourglass: u ∈ [0, 4]; table 1's domains are in these units). θ is the
//! angle of revolution in radians. The embedded map is
//! r(u, θ) = (x(u)·cos θ, x(u)·sin θ, z(u)).
//!
//! Differential geometry of any surface of revolution (`'` = d/du):
//! - metric: g_uu = x′² + z′², g_θθ = x², g_uθ = 0;
//! - Christoffel symbols of the second kind (all others zero):
//!   Γ^u_uu = (x′x″ + z′z″)/g_uu, Γ^u_θθ = −x·x′/g_uu, Γ^θ_uθ = Γ^θ_θu = x′/x;
//! - signed curvature of the generatrix: κ = (x′z″ − z′x″)/(x′² + z′²)^{3/2};
//! - unit normal r_u × r_θ / |…| = (−z′cos θ, −z′sin θ, x′)/√g_uu (outward when the
//!   generatrix runs from top to bottom, as in the presets).

use super::Error;

/// Default relative tolerance of the C³ check: a derivative jump at a knot counts when it
/// exceeds this times the larger of the two one-sided derivatives (and the polygon's size).
/// Derivatives of the presets match exactly; 1e-9 leaves room for decimal control points.
pub const DEFAULT_CONTINUITY_REL_TOL: f64 = 1e-9;
/// Default samples per segment for the cusp, radius and self-intersection checks.
pub const DEFAULT_SAMPLES_PER_SEGMENT: usize = 128;
/// Default speed |S′| (relative to the polygon's size, per unit u) under which the generatrix
/// has a cusp: there the tangent and the normal are undefined.
pub const DEFAULT_MIN_SPEED_REL: f64 = 1e-6;
/// Default minimum distance from the axis (mm) a domain or geodesic must keep: g_θθ = x² → 0
/// and Γ^θ_uθ = x′/x → ∞ at the poles (the paper's section 3.1), so the geodesic equation is
/// unstable there; 1 mm keeps Γ^θ_uθ within a few tens on the presets.
pub const DEFAULT_MIN_POLE_RADIUS_MM: f64 = 1.0;

/// Validation settings.
#[derive(Clone, Debug, PartialEq)]
pub struct Options {
    /// See [`DEFAULT_CONTINUITY_REL_TOL`].
    pub continuity_rel_tol: f64,
    /// See [`DEFAULT_SAMPLES_PER_SEGMENT`].
    pub samples_per_segment: usize,
    /// See [`DEFAULT_MIN_SPEED_REL`].
    pub min_speed_rel: f64,
}

impl Default for Options {
    fn default() -> Self {
        Options { continuity_rel_tol: DEFAULT_CONTINUITY_REL_TOL, samples_per_segment: DEFAULT_SAMPLES_PER_SEGMENT, min_speed_rel: DEFAULT_MIN_SPEED_REL }
    }
}

/// x(u), z(u) and their first three derivatives: `x[k]` = dᵏx/duᵏ.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Jet {
    /// Radius and derivatives, mm per uᵏ.
    pub x: [f64; 4],
    /// Height and derivatives, mm per uᵏ.
    pub z: [f64; 4],
}

/// A generatrix: anything with a radius x(u) and height z(u) and three derivatives. The
/// geodesic code takes any profile, so analytic surfaces (an exact sphere) can test it.
pub trait Profile: Sync {
    /// The parameter range [u_min, u_max].
    fn u_range(&self) -> (f64, f64);
    /// Values and derivatives at u.
    fn jet(&self, u: f64) -> Jet;
    /// Parameters strictly inside (lo, hi) where the profile is only finitely smooth (knots
    /// between polynomial pieces), ascending: quadrature splits there to keep its accuracy.
    fn knots_between(&self, _lo: f64, _hi: f64, _out: &mut Vec<f64>) {}
    /// Appends the critical points of the radius (x′ = 0) strictly inside (lo, hi),
    /// ascending. The default samples x′ at 33 points and bisects each sign change; a table
    /// can answer from precomputed roots.
    fn radius_turns(&self, lo: f64, hi: f64, out: &mut Vec<f64>) {
        let n = 32;
        let mut prev = (lo, self.radius_speed(lo)[1]);
        for i in 1..=n {
            let u = if i == n { hi } else { lo + (hi - lo) * i as f64 / n as f64 };
            let d = self.radius_speed(u)[1];
            if (prev.1 > 0.0) != (d > 0.0) {
                let (mut l, mut h) = (prev.0, u);
                let rising = d > 0.0;
                for _ in 0..60 {
                    let m = 0.5 * (l + h);
                    if (self.radius_speed(m)[1] > 0.0) == rising {
                        h = m
                    } else {
                        l = m
                    }
                }
                let r = 0.5 * (l + h);
                if r > lo && r < hi {
                    out.push(r);
                }
            }
            prev = (u, d);
        }
    }
    /// [x, x′, √g_uu] at u: what quadrature along a meridian needs (a table can give it
    /// cheaper than a full jet).
    fn radius_speed(&self, u: f64) -> [f64; 3] {
        let j = self.jet(u);
        [j.x[0], j.x[1], (j.x[1] * j.x[1] + j.z[1] * j.z[1]).sqrt()]
    }
}

/// Nonzero metric components at u (g_uθ = 0 on a surface of revolution).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Metric {
    /// g_uu = x′² + z′², mm² per u².
    pub g_uu: f64,
    /// g_θθ = x², mm² per rad².
    pub g_tt: f64,
}

/// Nonzero Christoffel symbols of the second kind at u.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Christoffel {
    /// Γ^u_uu.
    pub u_uu: f64,
    /// Γ^u_θθ.
    pub u_tt: f64,
    /// Γ^θ_uθ = Γ^θ_θu.
    pub t_ut: f64,
}

/// Metric at u.
pub fn metric<P: Profile + ?Sized>(p: &P, u: f64) -> Metric {
    let j = p.jet(u);
    Metric { g_uu: j.x[1] * j.x[1] + j.z[1] * j.z[1], g_tt: j.x[0] * j.x[0] }
}

/// Christoffel symbols at u (Γ^θ_uθ is infinite on the axis).
pub fn christoffel<P: Profile + ?Sized>(p: &P, u: f64) -> Christoffel {
    christoffel_of(&p.jet(u))
}

pub(crate) fn christoffel_of(j: &Jet) -> Christoffel {
    let g = j.x[1] * j.x[1] + j.z[1] * j.z[1];
    Christoffel { u_uu: (j.x[1] * j.x[2] + j.z[1] * j.z[2]) / g, u_tt: -j.x[0] * j.x[1] / g, t_ut: j.x[1] / j.x[0] }
}

/// Signed curvature κ of the generatrix at u, 1/mm (positive when it turns counter-clockwise
/// in the (x, z) plane).
pub fn curvature<P: Profile + ?Sized>(p: &P, u: f64) -> f64 {
    curvature_of(&p.jet(u))
}

/// κ from a jet already at hand.
pub(crate) fn curvature_of(j: &Jet) -> f64 {
    let s2 = j.x[1] * j.x[1] + j.z[1] * j.z[1];
    (j.x[1] * j.z[2] - j.z[1] * j.x[2]) / (s2 * s2.sqrt())
}

/// Point r(u, θ) in mm.
pub fn position<P: Profile + ?Sized>(p: &P, u: f64, theta: f64) -> [f64; 3] {
    let j = p.jet(u);
    [j.x[0] * libm::cos(theta), j.x[0] * libm::sin(theta), j.z[0]]
}

/// Unit normal r_u × r_θ / |r_u × r_θ| at (u, θ) (defined on the axis too, from the tangent).
pub fn normal<P: Profile + ?Sized>(p: &P, u: f64, theta: f64) -> [f64; 3] {
    let j = p.jet(u);
    let s = (j.x[1] * j.x[1] + j.z[1] * j.z[1]).sqrt();
    [-j.z[1] * libm::cos(theta) / s, -j.z[1] * libm::sin(theta) / s, j.x[1] / s]
}

/// The u interval whose radius is at least `min_radius_mm`, found from each end of the range
/// inwards (the poles are at the ends; an interior radius ≤ 0 is a [`Problem`] of the
/// platform). `None` if no sample reaches the radius.
pub fn pole_clearance<P: Profile + ?Sized>(p: &P, min_radius_mm: f64) -> Option<(f64, f64)> {
    let (lo, hi) = p.u_range();
    let n = 4096;
    let at = |i: usize| lo + (hi - lo) * i as f64 / n as f64;
    let ok = |u: f64| p.jet(u).x[0] >= min_radius_mm;
    let first = (0..=n).find(|&i| ok(at(i)))?;
    let last = (0..=n).rev().find(|&i| ok(at(i)))?;
    // Bisect the crossing between the last failing and first passing sample.
    let refine = |mut bad: f64, mut good: f64| {
        for _ in 0..60 {
            let m = 0.5 * (bad + good);
            if ok(m) {
                good = m
            } else {
                bad = m
            }
        }
        good
    };
    let a = if first == 0 { lo } else { refine(at(first - 1), at(first)) };
    let b = if last == n { hi } else { refine(at(last + 1), at(last)) };
    Some((a, b))
}

/// Refuses a domain u ∈ [u_min, u_max] that comes closer than `min_radius_mm` to the axis,
/// with the allowed u interval in the error.
pub fn check_domain<P: Profile + ?Sized>(p: &P, u_min: f64, u_max: f64, min_radius_mm: f64) -> Result<(), Error> {
    let (lo, hi) = p.u_range();
    for u in [u_min, u_max] {
        if !(lo..=hi).contains(&u) {
            return Err(Error::OutOfRange { u, u_min: lo, u_max: hi });
        }
    }
    let n = 1024;
    let (mut worst_u, mut worst_x) = (u_min, f64::INFINITY);
    for i in 0..=n {
        let u = u_min + (u_max - u_min) * i as f64 / n as f64;
        let x = p.jet(u).x[0];
        if x < worst_x {
            worst_u = u;
            worst_x = x;
        }
    }
    if worst_x >= min_radius_mm {
        return Ok(());
    }
    let (a, b) = pole_clearance(p, min_radius_mm).unwrap_or((f64::NAN, f64::NAN));
    Err(Error::TooNearPole { u: worst_u, radius_mm: worst_x, min_radius_mm, u_allowed_min: a, u_allowed_max: b })
}

/// One thing wrong with a generatrix.
#[derive(Clone, Debug, PartialEq)]
pub enum Problem {
    /// A derivative of order `order` (0 = position) jumps at a knot.
    Discontinuous {
        /// Knot u.
        u: f64,
        /// Derivative order 0..=3.
        order: usize,
        /// Absolute jump, mm per u^order.
        jump: f64,
        /// Tolerance it exceeds.
        tolerance: f64,
    },
    /// The generatrix stops (zero speed): a cusp.
    Cusp {
        /// Where.
        u: f64,
        /// |S′| there, mm per u.
        speed: f64,
    },
    /// The generatrix crosses itself.
    SelfIntersection {
        /// First passage.
        u_a: f64,
        /// Second passage.
        u_b: f64,
        /// Crossing (x, z), mm.
        at: [f64; 2],
    },
    /// The radius is zero or negative away from the ends.
    RadiusNotPositive {
        /// First u of the run.
        u_from: f64,
        /// Last u of the run.
        u_to: f64,
        /// Smallest radius in the run, mm.
        min_x: f64,
    },
}

impl std::fmt::Display for Problem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        const ORDER: [&str; 4] = ["position (segments do not meet)", "first derivative", "second derivative", "third derivative"];
        match self {
            Problem::Discontinuous { u, order, jump, tolerance } => write!(
                f,
                "the {} jumps by {jump:.3e} (tolerance {tolerance:.3e}) at the knot u = {u}: make the last {n} control points of the segment before and the first {n} of the one after mirror each other (equal {order}-th differences)",
                ORDER[*order],
                n = order + 1
            ),
            Problem::Cusp { u, speed } => write!(
                f,
                "the generatrix stops (speed {speed:.3e} mm per u) near u = {u:.6}, a cusp: move apart the coinciding control points there"
            ),
            Problem::SelfIntersection { u_a, u_b, at } => write!(
                f,
                "the generatrix crosses itself at (x, z) = ({:.4}, {:.4}) mm (u = {u_a:.6} and u = {u_b:.6}): move the control points so the curve does not loop",
                at[0], at[1]
            ),
            Problem::RadiusNotPositive { u_from, u_to, min_x } => write!(
                f,
                "the radius drops to {min_x:.4} mm for u in [{u_from:.6}, {u_to:.6}]: only the first and last control points may lie on the axis (x = 0); move the others to x > 0"
            ),
        }
    }
}

/// C³ continuity at the knots.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct Continuity {
    /// Per interior knot: (u, absolute jump of derivative order 0..=3).
    pub knots: Vec<(f64, [f64; 4])>,
    /// Worst absolute jump per order over all knots.
    pub worst: [f64; 4],
    /// Worst jump per order relative to its tolerance scale (compare with the tolerance).
    pub worst_rel: [f64; 4],
}

/// Result of [`Platform::check`]: the continuity report and every problem.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Check {
    /// Knot continuity.
    pub continuity: Continuity,
    /// Every problem found (empty: the platform is usable).
    pub problems: Vec<Problem>,
}

/// A generatrix made of degree-6 Bézier segments; control points (x, z) in mm.
#[derive(Clone, Debug, PartialEq)]
pub struct Platform {
    /// Segment k's seven control points; u ∈ [k, k + 1].
    pub segments: Vec<[[f64; 2]; 7]>,
}

const BARREL: [[[f64; 2]; 7]; 2] = [
    [[0.0, 50.0], [5.0, 50.0], [10.0, 50.0], [25.0, 50.0], [25.0, 35.0], [25.0, 30.0], [25.0, 25.0]],
    [[25.0, 25.0], [25.0, 20.0], [25.0, 15.0], [25.0, 0.0], [10.0, 0.0], [5.0, 0.0], [0.0, 0.0]],
];

// Table 3 as printed, columns read as segments 1 to 4 left to right (its header rows are
// scrambled). The 75 mm points are in the table; segments 1/4 and 2/3 mirror each other about
// z = 50, which supports that reading.
const HOURGLASS: [[[f64; 2]; 7]; 4] = [
    [[0.0, 100.0], [5.0, 100.0], [10.0, 100.0], [75.0, 100.0], [50.0, 95.0], [50.0, 90.0], [50.0, 85.0]],
    [[50.0, 85.0], [50.0, 80.0], [50.0, 75.0], [25.0, 70.0], [25.0, 60.0], [25.0, 55.0], [25.0, 50.0]],
    [[25.0, 50.0], [25.0, 45.0], [25.0, 40.0], [25.0, 30.0], [50.0, 25.0], [50.0, 20.0], [50.0, 15.0]],
    [[50.0, 15.0], [50.0, 10.0], [50.0, 5.0], [75.0, 0.0], [10.0, 0.0], [5.0, 0.0], [0.0, 0.0]],
];

impl Platform {
    /// From segments of seven control points each (a segment's first point should repeat the
    /// previous one's last; a gap is reported by [`Platform::check`] as an order-0 jump).
    pub fn from_segments(segments: Vec<[[f64; 2]; 7]>) -> Result<Platform, Error> {
        if segments.is_empty() {
            return Err(Error::BadPolygonLength { points: 0 });
        }
        for (s, seg) in segments.iter().enumerate() {
            if let Some(i) = seg.iter().position(|p| !p[0].is_finite() || !p[1].is_finite()) {
                return Err(Error::NotFinite { segment: s, index: i });
            }
        }
        Ok(Platform { segments })
    }

    /// From a flat control polygon of 6·K + 1 points, consecutive segments sharing a point.
    pub fn from_polygon(points: &[[f64; 2]]) -> Result<Platform, Error> {
        if points.len() < 7 || (points.len() - 1) % 6 != 0 {
            return Err(Error::BadPolygonLength { points: points.len() });
        }
        let segments = points.windows(7).step_by(6).map(|w| std::array::from_fn(|i| w[i])).collect();
        Platform::from_segments(segments)
    }

    /// The paper's barrel (table 2): u ∈ [0, 2], radius 25 mm at the equator u = 1.
    pub fn barrel() -> Platform {
        Platform { segments: BARREL.to_vec() }
    }

    /// The paper's hourglass (table 3): u ∈ [0, 4], neck of radius 25 mm at u = 2.
    pub fn hourglass() -> Platform {
        Platform { segments: HOURGLASS.to_vec() }
    }

    /// Size of the control polygon (bounding-box diagonal, mm), the scale of the checks.
    fn size(&self) -> f64 {
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for p in self.segments.iter().flatten() {
            for k in 0..2 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        ((hi[0] - lo[0]).powi(2) + (hi[1] - lo[1]).powi(2)).sqrt().max(1e-12)
    }

    /// Jet of segment `k` at local parameter t (t may lie outside [0, 1]).
    pub fn segment_jet(&self, k: usize, t: f64) -> Jet {
        let c = &self.segments[k];
        let mut d: [[f64; 2]; 7] = *c;
        let mut out = [[0.0; 2]; 4];
        // Forward differences give the derivative control polygons; n!/(n−r)! scales them.
        let scale = [1.0, 6.0, 30.0, 120.0];
        for (r, o) in out.iter_mut().enumerate() {
            let n = 7 - r;
            for axis in 0..2 {
                o[axis] = scale[r] * casteljau(&d[..n], axis, t);
            }
            for i in 0..n - 1 {
                for axis in 0..2 {
                    d[i][axis] = d[i + 1][axis] - d[i][axis];
                }
            }
        }
        Jet { x: out.map(|p| p[0]), z: out.map(|p| p[1]) }
    }

    /// Fourth derivative (x⁗, z⁗) of segment `k` at local parameter t: the degree-2 polygon
    /// of fourth differences, scaled by 6·5·4·3. The offset surfaces need it for κ″.
    pub fn segment_fourth(&self, k: usize, t: f64) -> [f64; 2] {
        let mut d: [[f64; 2]; 7] = self.segments[k];
        for r in 0..4 {
            for i in 0..6 - r {
                for axis in 0..2 {
                    d[i][axis] = d[i + 1][axis] - d[i][axis];
                }
            }
        }
        [360.0 * casteljau(&d[..3], 0, t), 360.0 * casteljau(&d[..3], 1, t)]
    }

    /// Runs every check and returns all problems with the continuity report.
    pub fn check(&self, options: &Options) -> Check {
        let size = self.size();
        let mut problems = Vec::new();
        // C⁰…C³ at the knots.
        let mut cont = Continuity::default();
        for k in 1..self.segments.len() {
            let (a, b) = (self.segment_jet(k - 1, 1.0), self.segment_jet(k, 0.0));
            let mut jumps = [0.0; 4];
            for r in 0..4 {
                let jump = ((a.x[r] - b.x[r]).powi(2) + (a.z[r] - b.z[r]).powi(2)).sqrt();
                let scale = size.max(libm::hypot(a.x[r], a.z[r])).max(libm::hypot(b.x[r], b.z[r]));
                let tol = options.continuity_rel_tol * scale;
                jumps[r] = jump;
                cont.worst[r] = cont.worst[r].max(jump);
                cont.worst_rel[r] = cont.worst_rel[r].max(jump / scale);
                if jump > tol {
                    problems.push(Problem::Discontinuous { u: k as f64, order: r, jump, tolerance: tol });
                }
            }
            cont.knots.push((k as f64, jumps));
        }
        // Samples for the other checks.
        let n = options.samples_per_segment.max(8);
        let (u0, u1) = self.u_range();
        let mut samples: Vec<(f64, Jet)> = Vec::new();
        for k in 0..self.segments.len() {
            for i in 0..n {
                let t = i as f64 / n as f64;
                samples.push((k as f64 + t, self.segment_jet(k, t)));
            }
        }
        samples.push((u1, self.segment_jet(self.segments.len() - 1, 1.0)));
        // Cusps: refine every local minimum of the speed by golden-section search.
        let speed = |u: f64| {
            let j = self.jet(u);
            libm::hypot(j.x[1], j.z[1])
        };
        let min_speed = options.min_speed_rel * size;
        let sp: Vec<f64> = samples.iter().map(|(_, j)| libm::hypot(j.x[1], j.z[1])).collect();
        let h = (u1 - u0) / (samples.len() - 1) as f64;
        let mut last_cusp = f64::NEG_INFINITY;
        for i in 0..sp.len() {
            let left = if i == 0 { f64::INFINITY } else { sp[i - 1] };
            let right = if i + 1 == sp.len() { f64::INFINITY } else { sp[i + 1] };
            if sp[i] <= left && sp[i] <= right {
                let (mut a, mut b) = ((samples[i].0 - h).max(u0), (samples[i].0 + h).min(u1));
                let g = 0.5 * (5f64.sqrt() - 1.0);
                for _ in 0..80 {
                    let (c, d) = (b - g * (b - a), a + g * (b - a));
                    if speed(c) < speed(d) {
                        b = d
                    } else {
                        a = c
                    }
                }
                let u = 0.5 * (a + b);
                let s = speed(u);
                if s < min_speed && u - last_cusp > h {
                    problems.push(Problem::Cusp { u, speed: s });
                    last_cusp = u;
                }
            }
        }
        // Radius ≤ 0 away from the two ends (which may sit on the axis: the poles).
        let tol_x = 1e-9 * size;
        let mut run: Option<(f64, f64, f64)> = None;
        for (idx, (u, j)) in samples.iter().enumerate() {
            let end = idx == 0 || idx + 1 == samples.len();
            let bad = j.x[0] < -tol_x || (!end && j.x[0] <= tol_x);
            match (&mut run, bad) {
                (Some(r), true) => {
                    r.1 = *u;
                    r.2 = r.2.min(j.x[0]);
                }
                (None, true) => run = Some((*u, *u, j.x[0])),
                (Some(r), false) => {
                    problems.push(Problem::RadiusNotPositive { u_from: r.0, u_to: r.1, min_x: r.2 });
                    run = None;
                }
                (None, false) => {}
            }
        }
        if let Some(r) = run {
            problems.push(Problem::RadiusNotPositive { u_from: r.0, u_to: r.1, min_x: r.2 });
        }
        // Self-intersection of the sampled polyline (non-adjacent pieces crossing properly).
        let pts: Vec<[f64; 2]> = samples.iter().map(|(_, j)| [j.x[0], j.z[0]]).collect();
        for i in 0..pts.len() - 1 {
            for k in i + 2..pts.len() - 1 {
                if let Some((s, t)) = cross(pts[i], pts[i + 1], pts[k], pts[k + 1]) {
                    let at = [pts[i][0] + s * (pts[i + 1][0] - pts[i][0]), pts[i][1] + s * (pts[i + 1][1] - pts[i][1])];
                    let (ua, ub) = (samples[i].0 + s * h, samples[k].0 + t * h);
                    problems.push(Problem::SelfIntersection { u_a: ua, u_b: ub, at });
                }
            }
        }
        Check { continuity: cont, problems }
    }

    /// [`Platform::check`] as a result: the continuity report, or every problem.
    pub fn validate(&self, options: &Options) -> Result<Continuity, Error> {
        let c = self.check(options);
        if c.problems.is_empty() {
            Ok(c.continuity)
        } else {
            Err(Error::Invalid { problems: c.problems })
        }
    }
}

impl Profile for Platform {
    fn u_range(&self) -> (f64, f64) {
        (0.0, self.segments.len() as f64)
    }

    fn jet(&self, u: f64) -> Jet {
        // Knot u = k belongs to segment k (the last knot to the last segment); outside the
        // range the end segments extrapolate.
        let last = self.segments.len() - 1;
        let k = if u <= 0.0 { 0 } else { (libm::floor(u) as usize).min(last) };
        self.segment_jet(k, u - k as f64)
    }

    fn knots_between(&self, lo: f64, hi: f64, out: &mut Vec<f64>) {
        // Segment k covers [k, k + 1]: the knots are the integers inside the range.
        let first = libm::floor(lo).max(0.0) as usize + 1;
        out.extend((first..self.segments.len()).map(|k| k as f64).filter(|&k| k > lo && k < hi));
    }
}

/// A profile that also gives exact fourth derivatives (what an offset of it needs).
pub trait Profile4: Profile {
    /// (x⁗, z⁗) at u.
    fn fourth(&self, u: f64) -> [f64; 2];
}

impl Profile4 for Platform {
    fn fourth(&self, u: f64) -> [f64; 2] {
        // The same segment choice as `jet`.
        let last = self.segments.len() - 1;
        let k = if u <= 0.0 { 0 } else { (libm::floor(u) as usize).min(last) };
        self.segment_fourth(k, u - k as f64)
    }
}

fn casteljau(p: &[[f64; 2]], axis: usize, t: f64) -> f64 {
    let mut b = [0.0; 7];
    for (i, q) in p.iter().enumerate() {
        b[i] = q[axis];
    }
    for r in 1..p.len() {
        for i in 0..p.len() - r {
            b[i] = (1.0 - t) * b[i] + t * b[i + 1];
        }
    }
    b[0]
}

/// Proper crossing of segments ab and cd: parameters along each.
fn cross(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> Option<(f64, f64)> {
    let r = [b[0] - a[0], b[1] - a[1]];
    let s = [d[0] - c[0], d[1] - c[1]];
    let den = r[0] * s[1] - r[1] * s[0];
    if den == 0.0 {
        return None;
    }
    let q = [c[0] - a[0], c[1] - a[1]];
    let t = (q[0] * s[1] - q[1] * s[0]) / den;
    let v = (q[0] * r[1] - q[1] * r[0]) / den;
    if t > 0.0 && t < 1.0 && v > 0.0 && v < 1.0 {
        Some((t, v))
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn elevate(p: &[[f64; 2]]) -> Vec<[f64; 2]> {
        let n = p.len(); // degree n − 1 → n
        (0..=n)
            .map(|i| {
                let a = i as f64 / n as f64;
                let prev = if i == 0 { p[0] } else { p[i - 1] };
                let cur = if i == n { p[n - 1] } else { p[i] };
                [a * prev[0] + (1.0 - a) * cur[0], a * prev[1] + (1.0 - a) * cur[1]]
            })
            .collect()
    }

    #[test]
    fn presets_are_c3_and_valid() {
        for (name, p) in [("barrel", Platform::barrel()), ("hourglass", Platform::hourglass())] {
            let c = p.validate(&Options::default()).unwrap_or_else(|e| panic!("{name}: {e}"));
            eprintln!("{name}: worst jump per order 0..3 = {:?} (relative {:?})", c.worst, c.worst_rel);
            assert!(c.worst_rel.iter().all(|&w| w <= DEFAULT_CONTINUITY_REL_TOL));
        }
        // Ends on the axis (poles), the tables' knots where expected.
        let b = Platform::barrel();
        assert_eq!(b.u_range(), (0.0, 2.0));
        assert_eq!(b.jet(0.0).x[0], 0.0);
        assert_eq!([b.jet(1.0).x[0], b.jet(1.0).z[0]], [25.0, 25.0]);
        let h = Platform::hourglass();
        assert_eq!([h.jet(2.0).x[0], h.jet(2.0).z[0]], [25.0, 50.0]);
    }

    #[test]
    fn geometry_is_consistent() {
        let p = Platform::hourglass();
        for &u in &[0.3, 1.0, 1.7, 2.0, 2.6, 3.5] {
            let j = p.jet(u);
            // Derivatives against central differences.
            let d = 1e-5;
            let (jp, jm) = (p.jet(u + d), p.jet(u - d));
            for r in 0..3 {
                let fx = (jp.x[r] - jm.x[r]) / (2.0 * d);
                assert!((fx - j.x[r + 1]).abs() < 1e-4 * (1.0 + j.x[r + 1].abs()), "u {u} order {r}");
            }
            let m = metric(&p, u);
            let g = christoffel(&p, u);
            let dg = (metric(&p, u + d).g_uu - metric(&p, u - d).g_uu) / (2.0 * d);
            assert!((g.u_uu - dg / (2.0 * m.g_uu)).abs() < 1e-5 * (1.0 + g.u_uu.abs()));
            let n = normal(&p, u, 0.4);
            assert!(((n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt() - 1.0).abs() < 1e-12);
            // Normal ⟂ r_u.
            let ru = [j.x[1] * libm::cos(0.4), j.x[1] * libm::sin(0.4), j.z[1]];
            assert!((n[0] * ru[0] + n[1] * ru[1] + n[2] * ru[2]).abs() < 1e-9);
        }
        // κ changes sign along the hourglass (the paper's section 3.1: positive and negative
        // regions); its knots have S″ = 0, so κ = 0 there.
        let k: Vec<f64> = [0.5, 1.0, 1.5, 2.0, 2.5].iter().map(|&u| curvature(&p, u)).collect();
        eprintln!("hourglass κ at u = 0.5, 1, 1.5, 2, 2.5: {k:?}");
        assert!(k.iter().any(|&v| v > 1e-6) && k.iter().any(|&v| v < -1e-6));
        // Barrel equator: outward normal is horizontal.
        let n = normal(&Platform::barrel(), 1.0, 0.0);
        assert!((n[0] - 1.0).abs() < 1e-12 && n[2].abs() < 1e-12);
    }

    #[test]
    fn kink_is_reported() {
        let mut segs = Platform::barrel().segments;
        segs[1][1] = [28.0, 20.0];
        let p = Platform::from_segments(segs).unwrap();
        let c = p.check(&Options::default());
        eprintln!("kinked: {:?}", c.problems);
        assert!(c.problems.iter().any(|q| matches!(q, Problem::Discontinuous { order: 1, u, .. } if *u == 1.0)));
        assert!(!c.problems.iter().any(|q| matches!(q, Problem::Discontinuous { order: 0, .. })));
        let e = p.validate(&Options::default()).unwrap_err().to_string();
        assert!(e.contains("first derivative") && e.contains("u = 1"), "{e}");
    }

    #[test]
    fn loop_cusp_and_axis_are_reported() {
        // A cubic with a loop, elevated to degree 6, moved off the axis.
        let cubic = [[0.0, 0.0], [2.0, 1.0], [-1.0, 1.0], [1.0, 0.0]];
        let mut q: Vec<[f64; 2]> = cubic.iter().map(|p| [20.0 + 20.0 * p[0], 20.0 * p[1]]).collect();
        for _ in 0..3 {
            q = elevate(&q);
        }
        let p = Platform::from_polygon(&q).unwrap();
        let c = p.check(&Options::default());
        assert!(c.problems.iter().any(|q| matches!(q, Problem::SelfIntersection { .. })), "{:?}", c.problems);
        // Cusp: three coinciding control points in the middle make S′ vanish at t = 1/2? Use a
        // symmetric polygon whose derivative polygon is odd about the middle.
        let cusp = [[10.0, 0.0], [20.0, 10.0], [30.0, 20.0], [40.0, 30.0], [30.0, 20.0], [20.0, 10.0], [10.0, 0.0]];
        let c = Platform::from_polygon(&cusp).unwrap().check(&Options::default());
        assert!(c.problems.iter().any(|q| matches!(q, Problem::Cusp { u, .. } if (u - 0.5).abs() < 1e-3)), "{:?}", c.problems);
        // Crossing the axis in the middle.
        let axis = [[0.0, 60.0], [10.0, 50.0], [-10.0, 40.0], [-10.0, 30.0], [-10.0, 20.0], [10.0, 10.0], [20.0, 0.0]];
        let c = Platform::from_polygon(&axis).unwrap().check(&Options::default());
        assert!(c.problems.iter().any(|q| matches!(q, Problem::RadiusNotPositive { .. })), "{:?}", c.problems);
        assert!(matches!(Platform::from_polygon(&axis[..6]), Err(Error::BadPolygonLength { points: 6 })));
    }

    #[test]
    fn polar_domains_are_refused() {
        let p = Platform::barrel();
        assert!(check_domain(&p, 0.8, 1.2, DEFAULT_MIN_POLE_RADIUS_MM).is_ok());
        let e = check_domain(&p, 0.0, 0.5, DEFAULT_MIN_POLE_RADIUS_MM).unwrap_err();
        let Error::TooNearPole { u_allowed_min, u_allowed_max, radius_mm, .. } = e.clone() else { panic!("{e}") };
        assert_eq!(radius_mm, 0.0);
        assert!((p.jet(u_allowed_min).x[0] - 1.0).abs() < 1e-9 && (p.jet(u_allowed_max).x[0] - 1.0).abs() < 1e-9);
        assert!(u_allowed_min > 0.0 && u_allowed_max < 2.0);
        eprintln!("{e}");
        assert!(e.to_string().contains("1 mm"));
    }
}

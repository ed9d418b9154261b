//! The domain Ω in the embedded map (u, θ): a rectangle or a simple (possibly non-convex)
//! polygon, optionally with holes, its validation, membership, projection and true surface
//! area. Everything the point spreading uses ([`Domain::contains`],
//! [`Domain::project_inside`], [`Domain::theta_intervals`], [`Domain::area_mm2`]) excludes the
//! holes, so the seeds and the repulsion keep out of them.

use super::platform::{pole_clearance, Profile, DEFAULT_MIN_POLE_RADIUS_MM};
use super::surface::Surface;
use std::f64::consts::PI;

/// Most polygon vertices accepted (the self-intersection check is quadratic).
pub const MAX_POLYGON_POINTS: usize = 4096;
/// Relative tolerance of the area quadrature.
pub const AREA_REL_TOL: f64 = 1e-10;

/// Ω in (u, θ); θ in radians.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Domain {
    /// u ∈ [u₀, u₁], θ ∈ [θ₀, θ₁].
    Rectangle {
        /// u range.
        u: [f64; 2],
        /// θ range, rad.
        theta: [f64; 2],
    },
    /// A simple polygon of (u, θ) points (a closing point equal to the first is allowed),
    /// minus the holes inside it.
    Polygon {
        /// Vertices (u, θ).
        points: Vec<[f64; 2]>,
        /// Holes: simple polygons inside the outline, apart from it and from each other
        /// (left out of the JSON when there are none, so older designs keep their bytes).
        #[serde(default, skip_serializing_if = "Vec::is_empty")]
        holes: Vec<Vec<[f64; 2]>>,
    },
}

/// One thing wrong with a domain.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum DomainProblem {
    /// Too few vertices.
    #[error("the polygon has {0} distinct points; give at least 3 (u, θ) points")]
    TooFewPoints(usize),
    /// Too many vertices.
    #[error("the polygon has {0} points, more than {MAX_POLYGON_POINTS}; simplify it")]
    TooManyPoints(usize),
    /// NaN or infinite coordinate.
    #[error("point {0} is not a finite number; enter u and θ (rad) as numbers")]
    NotFinite(usize),
    /// Edges cross.
    #[error("edges {0} and {1} of the polygon cross; reorder the points so the outline does not cross itself")]
    SelfIntersecting(usize, usize),
    /// Zero area.
    #[error("the domain has zero area; give a u range and a θ range of positive width (or a polygon that encloses an area)")]
    ZeroArea,
    /// u outside the platform's range.
    #[error("u = {u} lies outside the platform's range [{lo}, {hi}]; keep u inside it")]
    OutsideRange {
        /// Offending u.
        u: f64,
        /// Range start.
        lo: f64,
        /// Range end.
        hi: f64,
    },
    /// Too close to the pole.
    #[error("the domain reaches u = {u:.6}, where the radius is {radius_mm:.3} mm: too near the pole (the metric g_θθ = x² vanishes there); a domain must stay at least {min_mm} mm from the axis, so keep u within [{allowed_lo:.6}, {allowed_hi:.6}]")]
    NearPole {
        /// Offending u.
        u: f64,
        /// Radius there.
        radius_mm: f64,
        /// Required minimum.
        min_mm: f64,
        /// Allowed u interval start.
        allowed_lo: f64,
        /// Allowed u interval end.
        allowed_hi: f64,
    },
    /// A hole with too few points.
    #[error("hole {hole} has {points} distinct points; give at least 3 (u, θ) points per hole", hole = .0 + 1, points = .1)]
    HoleTooFewPoints(usize, usize),
    /// A hole point is NaN or infinite.
    #[error("point {} of hole {} is not a finite number; enter u and θ (rad) as numbers", .1 + 1, .0 + 1)]
    HoleNotFinite(usize, usize),
    /// A hole's edges cross.
    #[error("edges {a} and {b} of hole {hole} cross; reorder its points so its outline does not cross itself", hole = .0 + 1, a = .1, b = .2)]
    HoleSelfIntersecting(usize, usize, usize),
    /// A hole encloses no area.
    #[error("hole {} has zero area; give it points that enclose an area", .0 + 1)]
    HoleZeroArea(usize),
    /// A hole lies (partly) outside the outline.
    #[error("hole {} is not inside the outline (it crosses it or lies outside): a hole must lie wholly inside the polygon; move its points in or drop it", .0 + 1)]
    HoleOutside(usize),
    /// Two holes overlap.
    #[error("holes {} and {} overlap (their outlines cross or one lies in the other): merge them into one hole", .0 + 1, .1 + 1)]
    HolesOverlap(usize, usize),
    /// θ span over a full turn.
    #[error("the domain spans {0:.4} rad in θ, more than a full turn (2π); narrow the θ range")]
    ThetaSpan(f64),
}

impl Domain {
    /// The outline as a closed ring (no repeated closing point).
    pub fn ring(&self) -> Vec<[f64; 2]> {
        match self {
            Domain::Rectangle { u, theta } => vec![[u[0], theta[0]], [u[1], theta[0]], [u[1], theta[1]], [u[0], theta[1]]],
            Domain::Polygon { points, .. } => open_ring(points),
        }
    }

    /// The holes as closed rings (no repeated closing points); none for a rectangle.
    pub fn holes(&self) -> Vec<Vec<[f64; 2]>> {
        match self {
            Domain::Rectangle { .. } => Vec::new(),
            Domain::Polygon { holes, .. } => holes.iter().map(|h| open_ring(h)).collect(),
        }
    }

    /// Whether the straight (u, θ) segment a → b crosses or enters a hole (a path drawn
    /// along it would print over the opening).
    pub fn segment_crosses_hole(&self, a: [f64; 2], b: [f64; 2]) -> bool {
        let Domain::Polygon { holes, .. } = self else { return false };
        holes.iter().any(|h| {
            let r = open_ring(h);
            let n = r.len();
            point_in_ring(&r, a) || point_in_ring(&r, b) || (0..n).any(|i| segments_touch(a, b, r[i], r[(i + 1) % n], false))
        })
    }

    /// Bounding box [[u_min, θ_min], [u_max, θ_max]].
    pub fn bounds(&self) -> [[f64; 2]; 2] {
        let mut b = [[f64::INFINITY; 2], [f64::NEG_INFINITY; 2]];
        for p in self.ring() {
            for k in 0..2 {
                b[0][k] = b[0][k].min(p[k]);
                b[1][k] = b[1][k].max(p[k]);
            }
        }
        b
    }

    /// Every problem with this domain on `p` (empty when usable).
    pub fn problems(&self, p: &dyn Profile) -> Vec<DomainProblem> {
        let mut out = Vec::new();
        let ring = match self {
            Domain::Rectangle { u, theta } => {
                for (i, v) in [u[0], u[1], theta[0], theta[1]].iter().enumerate() {
                    if !v.is_finite() {
                        out.push(DomainProblem::NotFinite(i / 2));
                    }
                }
                if !out.is_empty() {
                    return out;
                }
                if !(u[1] > u[0] && theta[1] > theta[0]) {
                    out.push(DomainProblem::ZeroArea);
                }
                self.ring()
            }
            Domain::Polygon { points, holes } => {
                let total = points.len() + holes.iter().map(Vec::len).sum::<usize>();
                if total > MAX_POLYGON_POINTS {
                    return vec![DomainProblem::TooManyPoints(total)];
                }
                for (i, q) in points.iter().enumerate() {
                    if !q[0].is_finite() || !q[1].is_finite() {
                        out.push(DomainProblem::NotFinite(i));
                    }
                }
                if !out.is_empty() {
                    return out;
                }
                let ring = self.ring();
                if ring.len() < 3 {
                    out.push(DomainProblem::TooFewPoints(ring.len()));
                    return out;
                }
                let n = ring.len();
                for i in 0..n {
                    for j in i + 1..n {
                        // Neighbouring edges share a vertex; only a real crossing or overlap counts.
                        let adjacent = j == i + 1 || (i == 0 && j == n - 1);
                        if segments_touch(ring[i], ring[(i + 1) % n], ring[j], ring[(j + 1) % n], adjacent) {
                            out.push(DomainProblem::SelfIntersecting(i, j));
                        }
                    }
                }
                if signed_area(&ring).abs() <= 1e-14 * (1.0 + ring.iter().map(|q| q[0].abs() + q[1].abs()).fold(0.0, f64::max)).powi(2) {
                    out.push(DomainProblem::ZeroArea);
                }
                if out.is_empty() {
                    hole_problems(&ring, holes, &mut out);
                }
                ring
            }
        };
        let b = bounds_of(&ring);
        if b[1][1] - b[0][1] > 2.0 * PI {
            out.push(DomainProblem::ThetaSpan(b[1][1] - b[0][1]));
        }
        let (lo, hi) = p.u_range();
        let mut in_range = true;
        for u in [b[0][0], b[1][0]] {
            if !(lo..=hi).contains(&u) {
                out.push(DomainProblem::OutsideRange { u, lo, hi });
                in_range = false;
            }
        }
        if in_range {
            // The radius over the u span, sampled finely (the same as platform::check_domain).
            let (u0, u1) = (b[0][0], b[1][0]);
            let (mut wu, mut wx) = (u0, f64::INFINITY);
            for i in 0..=1024 {
                let u = u0 + (u1 - u0) * i as f64 / 1024.0;
                let x = p.jet(u).x[0];
                if x < wx {
                    wu = u;
                    wx = x;
                }
            }
            if !(wx >= DEFAULT_MIN_POLE_RADIUS_MM) {
                let (a, c) = pole_clearance(p, DEFAULT_MIN_POLE_RADIUS_MM).unwrap_or((f64::NAN, f64::NAN));
                out.push(DomainProblem::NearPole { u: wu, radius_mm: wx, min_mm: DEFAULT_MIN_POLE_RADIUS_MM, allowed_lo: a, allowed_hi: c });
            }
        }
        out
    }

    /// Whether q lies in Ω (boundary included for rectangles; even–odd rule for polygons).
    pub fn contains(&self, q: [f64; 2]) -> bool {
        match self {
            Domain::Rectangle { u, theta } => q[0] >= u[0] && q[0] <= u[1] && q[1] >= theta[0] && q[1] <= theta[1],
            Domain::Polygon { .. } => point_in_ring(&self.ring(), q) && !self.holes().iter().any(|h| point_in_ring(h, q)),
        }
    }

    /// The nearest point of Ω to q, distances measured with the metric at q (so it is the
    /// nearest on the surface to first order); q itself when inside. Polygon results are
    /// nudged just inside so [`Domain::contains`] holds for them.
    pub fn project_inside(&self, s: &Surface, q: [f64; 2]) -> [f64; 2] {
        match self {
            Domain::Rectangle { u, theta } => [q[0].clamp(u[0], u[1]), q[1].clamp(theta[0], theta[1])],
            Domain::Polygon { .. } => {
                let ring = self.ring();
                if !point_in_ring(&ring, q) {
                    // Holes keep apart from the outline, so its inside is never in a hole.
                    return project_ring(&ring, s, q, true);
                }
                match self.holes().iter().find(|h| point_in_ring(h, q)) {
                    // Out of the hole onto its edge, nudged to the domain's side.
                    Some(h) => project_ring(h, s, q, false),
                    None => q,
                }
            }
        }
    }

    /// θ intervals of Ω on the line u (sorted, disjoint).
    pub fn theta_intervals(&self, u: f64) -> Vec<[f64; 2]> {
        match self {
            Domain::Rectangle { u: ur, theta } => {
                if u >= ur[0] && u <= ur[1] {
                    vec![*theta]
                } else {
                    Vec::new()
                }
            }
            Domain::Polygon { .. } => {
                // Even–odd over the outline and the holes together: the holes lie apart inside
                // the outline, so their intervals drop out of the outline's.
                let mut xs = Vec::new();
                for ring in std::iter::once(self.ring()).chain(self.holes()) {
                    let n = ring.len();
                    for i in 0..n {
                        let (a, b) = (ring[i], ring[(i + 1) % n]);
                        // Half-open rule so a vertex on the line counts once.
                        if (a[0] <= u) != (b[0] <= u) {
                            xs.push(a[1] + (u - a[0]) / (b[0] - a[0]) * (b[1] - a[1]));
                        }
                    }
                }
                xs.sort_by(f64::total_cmp);
                xs.chunks_exact(2).map(|c| [c[0], c[1]]).collect()
            }
        }
    }

    /// True surface area ∫∫_Ω x(u)·√g_uu du dθ, mm² (the θ width is piecewise linear in u
    /// and the integrand smooth between vertices: see [`Domain::integrate_u`]).
    pub fn area_mm2(&self, s: &Surface) -> f64 {
        let p = s.profile();
        let f = |u: f64| {
            let j = p.jet(u);
            let w: f64 = self.theta_intervals(u).iter().map(|i| i[1] - i[0]).sum();
            j.x[0] * libm::hypot(j.x[1], j.z[1]) * w
        };
        self.integrate_u(&f, AREA_REL_TOL)
    }

    /// ∫ f(u) du over Ω's u range by adaptive Simpson, split at every vertex u of the outline
    /// and the holes: integrands built on [`Domain::theta_intervals`] are only piecewise
    /// smooth, with kinks or jumps at those u.
    pub fn integrate_u(&self, f: &dyn Fn(f64) -> f64, rel_tol: f64) -> f64 {
        let mut us: Vec<f64> = self.ring().iter().chain(self.holes().iter().flatten()).map(|q| q[0]).collect();
        us.sort_by(f64::total_cmp);
        us.dedup();
        let mut total = 0.0;
        for w in us.windows(2) {
            // Evaluate just inside each interval: the width is discontinuous at vertices
            // where edges start or end horizontally.
            let (a, b) = (w[0], w[1]);
            let e = (b - a) * 1e-12;
            total += simpson(f, a + e, b - e, rel_tol);
        }
        total
    }
}

fn open_ring(points: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let mut v = points.to_vec();
    if v.len() > 1 && v.first() == v.last() {
        v.pop();
    }
    v
}

/// Each hole: finite, at least 3 points, simple, with area, wholly inside `outline`, apart
/// from it and from the other holes.
fn hole_problems(outline: &[[f64; 2]], holes: &[Vec<[f64; 2]>], out: &mut Vec<DomainProblem>) {
    let mut usable = Vec::new();
    for (k, h) in holes.iter().enumerate() {
        if let Some(i) = h.iter().position(|q| !q[0].is_finite() || !q[1].is_finite()) {
            out.push(DomainProblem::HoleNotFinite(k, i));
            continue;
        }
        let r = open_ring(h);
        if r.len() < 3 {
            out.push(DomainProblem::HoleTooFewPoints(k, r.len()));
            continue;
        }
        let n = r.len();
        let mut simple = true;
        for i in 0..n {
            for j in i + 1..n {
                let adjacent = j == i + 1 || (i == 0 && j == n - 1);
                if segments_touch(r[i], r[(i + 1) % n], r[j], r[(j + 1) % n], adjacent) {
                    out.push(DomainProblem::HoleSelfIntersecting(k, i, j));
                    simple = false;
                }
            }
        }
        if signed_area(&r).abs() <= 1e-14 * (1.0 + r.iter().map(|q| q[0].abs() + q[1].abs()).fold(0.0, f64::max)).powi(2) {
            out.push(DomainProblem::HoleZeroArea(k));
            simple = false;
        }
        if !r.iter().all(|&q| point_in_ring(outline, q)) || rings_touch(&r, outline) {
            out.push(DomainProblem::HoleOutside(k));
            simple = false;
        }
        if simple {
            usable.push((k, r));
        }
    }
    for a in 0..usable.len() {
        for b in a + 1..usable.len() {
            let ((ka, ra), (kb, rb)) = (&usable[a], &usable[b]);
            if rings_touch(ra, rb) || point_in_ring(rb, ra[0]) || point_in_ring(ra, rb[0]) {
                out.push(DomainProblem::HolesOverlap(*ka, *kb));
            }
        }
    }
}

/// Whether any edge of ring `a` crosses or touches any edge of ring `b`.
fn rings_touch(a: &[[f64; 2]], b: &[[f64; 2]]) -> bool {
    let (n, m) = (a.len(), b.len());
    (0..n).any(|i| (0..m).any(|j| segments_touch(a[i], a[(i + 1) % n], b[j], b[(j + 1) % m], false)))
}

fn bounds_of(ring: &[[f64; 2]]) -> [[f64; 2]; 2] {
    let mut b = [[f64::INFINITY; 2], [f64::NEG_INFINITY; 2]];
    for p in ring {
        for k in 0..2 {
            b[0][k] = b[0][k].min(p[k]);
            b[1][k] = b[1][k].max(p[k]);
        }
    }
    b
}

fn signed_area(r: &[[f64; 2]]) -> f64 {
    let n = r.len();
    (0..n).map(|i| r[i][0] * r[(i + 1) % n][1] - r[(i + 1) % n][0] * r[i][1]).sum::<f64>() * 0.5
}

fn orient(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

/// Whether segments ab and cd cross or overlap (for adjacent edges: only overlap back along
/// the shared vertex counts).
fn segments_touch(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2], adjacent: bool) -> bool {
    let (d1, d2, d3, d4) = (orient(c, d, a), orient(c, d, b), orient(a, b, c), orient(a, b, d));
    if adjacent {
        // Collinear and folding back onto each other.
        let shared = if b == c { b } else { a };
        let (p, q) = if b == c { (a, d) } else { (b, c) };
        let v1 = [p[0] - shared[0], p[1] - shared[1]];
        let v2 = [q[0] - shared[0], q[1] - shared[1]];
        return orient(shared, p, q) == 0.0 && v1[0] * v2[0] + v1[1] * v2[1] > 0.0;
    }
    if ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0)) && ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0)) {
        return true;
    }
    let on = |p: [f64; 2], q: [f64; 2], r: [f64; 2]| r[0] >= p[0].min(q[0]) && r[0] <= p[0].max(q[0]) && r[1] >= p[1].min(q[1]) && r[1] <= p[1].max(q[1]);
    (d1 == 0.0 && on(c, d, a)) || (d2 == 0.0 && on(c, d, b)) || (d3 == 0.0 && on(a, b, c)) || (d4 == 0.0 && on(a, b, d))
}

fn point_in_ring(r: &[[f64; 2]], q: [f64; 2]) -> bool {
    let n = r.len();
    let mut inside = false;
    for i in 0..n {
        let (a, b) = (r[i], r[(i + 1) % n]);
        if (a[1] > q[1]) != (b[1] > q[1]) {
            let x = a[0] + (q[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
            if q[0] < x {
                inside = !inside;
            }
        }
    }
    inside
}

/// The nearest point of `ring`'s edges to q, nudged to its inside (`inside`) or its outside
/// until [`point_in_ring`] agrees.
fn project_ring(ring: &[[f64; 2]], s: &Surface, q: [f64; 2], inside: bool) -> [f64; 2] {
    // Metric at q: scale (u, θ) to mm so the nearest point is nearest on the surface.
    let j = s.profile().jet(q[0]);
    let (su, st) = (libm::hypot(j.x[1], j.z[1]), j.x[0].abs().max(1e-9));
    let n = ring.len();
    let (mut best, mut best_d, mut best_e) = (ring[0], f64::INFINITY, 0);
    for i in 0..n {
        let (a, b) = (ring[i], ring[(i + 1) % n]);
        let ab = [(b[0] - a[0]) * su, (b[1] - a[1]) * st];
        let aq = [(q[0] - a[0]) * su, (q[1] - a[1]) * st];
        let l2 = ab[0] * ab[0] + ab[1] * ab[1];
        let t = if l2 > 0.0 { ((aq[0] * ab[0] + aq[1] * ab[1]) / l2).clamp(0.0, 1.0) } else { 0.0 };
        let c = [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])];
        let d = ((q[0] - c[0]) * su).powi(2) + ((q[1] - c[1]) * st).powi(2);
        if d < best_d {
            best_d = d;
            best = c;
            best_e = i;
        }
    }
    // Nudge inside: towards the inward side of the nearest edge, then towards the ring's
    // centroid, with growing steps, until inside (for the outside of a hole: the other way).
    let scale = bounds_of(ring);
    let size = (scale[1][0] - scale[0][0]).max(scale[1][1] - scale[0][1]).max(1e-12);
    let (a, b) = (ring[best_e], ring[(best_e + 1) % n]);
    let sign = if (signed_area(ring) > 0.0) == inside { 1.0 } else { -1.0 };
    let e = [b[0] - a[0], b[1] - a[1]];
    let el = (e[0] * e[0] + e[1] * e[1]).sqrt().max(1e-300);
    let inward = [-sign * e[1] / el, sign * e[0] / el];
    let centroid = {
        let m = ring.iter().fold([0.0, 0.0], |s, p| [s[0] + p[0], s[1] + p[1]]);
        [m[0] / n as f64, m[1] / n as f64]
    };
    let mut eps = 1e-12 * size;
    for _ in 0..40 {
        let c = [best[0] + eps * inward[0], best[1] + eps * inward[1]];
        if point_in_ring(ring, c) == inside {
            return c;
        }
        let away = if inside { 1.0 } else { -1.0 };
        let to = [away * (centroid[0] - best[0]), away * (centroid[1] - best[1])];
        let tl = (to[0] * to[0] + to[1] * to[1]).sqrt().max(1e-300);
        let c = [best[0] + eps * to[0] / tl, best[1] + eps * to[1] / tl];
        if point_in_ring(ring, c) == inside {
            return c;
        }
        eps *= 4.0;
    }
    best
}

/// Adaptive Simpson on [a, b] to relative tolerance `tol` (depth-capped, deterministic).
pub(crate) fn simpson(f: &dyn Fn(f64) -> f64, a: f64, b: f64, tol: f64) -> f64 {
    // The recursion's state is its arguments (interval, three samples, estimate, tolerance, depth).
    #[allow(clippy::too_many_arguments)]
    fn rec(f: &dyn Fn(f64) -> f64, a: f64, b: f64, fa: f64, fm: f64, fb: f64, whole: f64, eps: f64, depth: u32) -> f64 {
        let m = 0.5 * (a + b);
        let (lm, rm) = (0.5 * (a + m), 0.5 * (m + b));
        let (flm, frm) = (f(lm), f(rm));
        let left = (m - a) / 6.0 * (fa + 4.0 * flm + fm);
        let right = (b - m) / 6.0 * (fm + 4.0 * frm + fb);
        if depth == 0 || (left + right - whole).abs() <= 15.0 * eps {
            return left + right + (left + right - whole) / 15.0;
        }
        rec(f, a, m, fa, flm, fm, left, 0.5 * eps, depth - 1) + rec(f, m, b, fm, frm, fb, right, 0.5 * eps, depth - 1)
    }
    if !(b > a) {
        return 0.0;
    }
    let (fa, fm, fb) = (f(a), f(0.5 * (a + b)), f(b));
    let whole = (b - a) / 6.0 * (fa + 4.0 * fm + fb);
    let eps = tol * whole.abs().max(1e-300);
    // Eight panels first so a narrow feature is not missed by the first estimate.
    let mut sum = 0.0;
    for i in 0..8 {
        let (s0, s1) = (a + (b - a) * i as f64 / 8.0, a + (b - a) * (i + 1) as f64 / 8.0);
        let (f0, f1, f2) = (f(s0), f(0.5 * (s0 + s1)), f(s1));
        sum += rec(f, s0, s1, f0, f1, f2, (s1 - s0) / 6.0 * (f0 + 4.0 * f1 + f2), eps / 8.0, 30);
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::axisym::platform::Platform;

    /// Cylinder of radius 20 mm, z = 60 − 30u, u ∈ [0, 2].
    pub(crate) fn cylinder() -> Platform {
        let pts: Vec<[f64; 2]> = (0..13).map(|i| [20.0, 60.0 - 5.0 * i as f64]).collect();
        Platform::from_polygon(&pts).unwrap()
    }

    #[test]
    fn cylinder_patch_area_by_hand() {
        let p = cylinder();
        let s = Surface::new(&p);
        // u ∈ [0.5, 1.5] is 30 mm of height; θ ∈ [0, 1] is 20 mm of arc: 600 mm².
        let d = Domain::Rectangle { u: [0.5, 1.5], theta: [0.0, 1.0] };
        assert!(d.problems(&p).is_empty());
        assert!((d.area_mm2(&s) - 600.0).abs() < 1e-6, "{}", d.area_mm2(&s));
        // An L-shaped polygon: the rectangle minus its upper-right quarter: 450 mm².
        let l = Domain::Polygon { holes: Vec::new(), points: vec![[0.5, 0.0], [1.5, 0.0], [1.5, 0.5], [1.0, 0.5], [1.0, 1.0], [0.5, 1.0], [0.5, 0.0]] };
        assert!(l.problems(&p).is_empty(), "{:?}", l.problems(&p));
        assert!((l.area_mm2(&s) - 450.0).abs() < 1e-6, "{}", l.area_mm2(&s));
        // A triangle: half of the rectangle.
        let t = Domain::Polygon { holes: Vec::new(), points: vec![[0.5, 0.0], [1.5, 0.0], [0.5, 1.0]] };
        assert!((t.area_mm2(&s) - 300.0).abs() < 1e-6, "{}", t.area_mm2(&s));
        assert!(l.contains([0.7, 0.7]) && !l.contains([1.2, 0.7]));
        let q = l.project_inside(&s, [1.2, 0.7]);
        assert!(l.contains(q), "{q:?}");
    }

    #[test]
    fn barrel_rectangle_area_matches_a_fine_sum() {
        let p = Platform::barrel();
        let s = Surface::new(&p);
        let d = Domain::Rectangle { u: [0.8, 1.2], theta: [0.0, 1.0] };
        let n = 200_000;
        let h = 0.4 / n as f64;
        let sum: f64 = (0..n)
            .map(|i| {
                let j = p.jet(0.8 + (i as f64 + 0.5) * h);
                j.x[0] * j.x[1].hypot(j.z[1]) * h
            })
            .sum();
        assert!((d.area_mm2(&s) - sum).abs() < 1e-6 * sum, "{} vs {sum}", d.area_mm2(&s));
    }

    #[test]
    fn bad_domains_list_every_problem() {
        let p = Platform::barrel();
        let bow = Domain::Polygon { holes: Vec::new(), points: vec![[0.8, 0.0], [1.2, 1.0], [1.2, 0.0], [0.8, 1.0]] };
        assert!(bow.problems(&p).iter().any(|e| matches!(e, DomainProblem::SelfIntersecting(..))));
        let pole = Domain::Rectangle { u: [0.0, 0.5], theta: [0.0, 1.0] };
        assert!(pole.problems(&p).iter().any(|e| matches!(e, DomainProblem::NearPole { .. })), "{:?}", pole.problems(&p));
        let nan = Domain::Rectangle { u: [f64::NAN, 0.5], theta: [0.0, 1.0] };
        assert!(matches!(nan.problems(&p)[0], DomainProblem::NotFinite(_)));
        let many = Domain::Rectangle { u: [0.8, 2.5], theta: [0.0, 7.0] };
        let pr = many.problems(&p);
        assert!(pr.iter().any(|e| matches!(e, DomainProblem::ThetaSpan(_))) && pr.iter().any(|e| matches!(e, DomainProblem::OutsideRange { .. })), "{pr:?}");
        let two = Domain::Polygon { holes: Vec::new(), points: vec![[0.8, 0.0], [1.0, 0.0], [0.8, 0.0]] };
        assert!(matches!(two.problems(&p)[0], DomainProblem::TooFewPoints(2)));
        let json = r#"{"kind":"rectangle","u":[0.8,1.2],"theta":[0,1]}"#;
        let d: Domain = serde_json::from_str(json).unwrap();
        assert_eq!(d, Domain::Rectangle { u: [0.8, 1.2], theta: [0.0, 1.0] });
    }

    /// [0.5, 1.5] × [0, 1] on the cylinder with the hole [0.8, 1.2] × [0.3, 0.7].
    fn square_with_hole() -> Domain {
        Domain::Polygon { points: vec![[0.5, 0.0], [1.5, 0.0], [1.5, 1.0], [0.5, 1.0]], holes: vec![vec![[0.8, 0.3], [0.8, 0.7], [1.2, 0.7], [1.2, 0.3]]] }
    }

    #[test]
    fn a_hole_is_left_out_of_area_membership_and_projection() {
        let p = cylinder();
        let s = Surface::new(&p);
        let d = square_with_hole();
        assert!(d.problems(&p).is_empty(), "{:?}", d.problems(&p));
        // 30 × 20 mm minus the hole's 12 × 8 mm.
        assert!((d.area_mm2(&s) - 504.0).abs() < 1e-6, "{}", d.area_mm2(&s));
        assert_eq!(d.theta_intervals(1.0), vec![[0.0, 0.3], [0.7, 1.0]]);
        assert_eq!(d.theta_intervals(0.6), vec![[0.0, 1.0]]);
        assert!(!d.contains([1.0, 0.5]) && d.contains([0.6, 0.5]) && d.contains([1.0, 0.2]));
        // Out of the hole onto its nearest edge (θ = 0.7 is 0.05 rad = 1 mm away, u = 1.2 is
        // 0.1 u = 3 mm away), just outside it.
        let q = d.project_inside(&s, [1.1, 0.65]);
        assert!(d.contains(q) && (q[1] - 0.7).abs() < 1e-9 && (q[0] - 1.1).abs() < 1e-12, "{q:?}");
        // Outside the outline: back in, never into the hole.
        let q = d.project_inside(&s, [1.0, 1.4]);
        assert!(d.contains(q) && (q[1] - 1.0).abs() < 1e-9, "{q:?}");
        // Crossing the hole or not, in the map.
        assert!(d.segment_crosses_hole([1.0, 0.1], [1.0, 0.9]));
        assert!(!d.segment_crosses_hole([0.6, 0.1], [0.6, 0.9]));
        assert!(!Domain::Rectangle { u: [0.5, 1.5], theta: [0.0, 1.0] }.segment_crosses_hole([1.0, 0.1], [1.0, 0.9]));
        // No holes: the JSON has no `holes` key (designs and share links keep their bytes).
        let plain = Domain::Polygon { holes: Vec::new(), points: vec![[0.5, 0.0], [1.5, 0.0], [0.5, 1.0]] };
        assert!(!serde_json::to_string(&plain).unwrap().contains("holes"));
        let back: Domain = serde_json::from_str(&serde_json::to_string(&d).unwrap()).unwrap();
        assert_eq!(back, d);
    }

    #[test]
    fn bad_holes_are_named() {
        let p = cylinder();
        let outline = vec![[0.5, 0.0], [1.5, 0.0], [1.5, 1.0], [0.5, 1.0]];
        let with = |holes: Vec<Vec<[f64; 2]>>| Domain::Polygon { points: outline.clone(), holes }.problems(&p);
        let inside = vec![[0.8, 0.3], [0.8, 0.5], [1.0, 0.5], [1.0, 0.3]];
        assert!(with(vec![inside.clone()]).is_empty());
        let crossing = vec![[1.4, 0.3], [1.4, 0.5], [1.7, 0.5], [1.7, 0.3]];
        let outside = vec![[1.6, 0.3], [1.6, 0.5], [1.7, 0.5], [1.7, 0.3]];
        let overlapping = vec![[0.9, 0.4], [0.9, 0.6], [1.1, 0.6], [1.1, 0.4]];
        let bow = vec![[0.6, 0.1], [0.7, 0.2], [0.7, 0.1], [0.6, 0.2]];
        let pr = with(vec![inside, crossing, outside, overlapping, bow, vec![[0.6, 0.6], [f64::NAN, 0.7], [0.7, 0.6]], vec![[0.6, 0.6], [0.7, 0.6]]]);
        eprintln!("{}", pr.iter().map(|e| e.to_string()).collect::<Vec<_>>().join("\n"));
        assert!(pr.contains(&DomainProblem::HoleOutside(1)) && pr.contains(&DomainProblem::HoleOutside(2)), "{pr:?}");
        assert!(pr.contains(&DomainProblem::HolesOverlap(0, 3)), "{pr:?}");
        assert!(pr.iter().any(|e| matches!(e, DomainProblem::HoleSelfIntersecting(4, ..))), "{pr:?}");
        assert!(pr.contains(&DomainProblem::HoleNotFinite(5, 1)) && pr.contains(&DomainProblem::HoleTooFewPoints(6, 2)), "{pr:?}");
        assert!(pr.iter().any(|e| e.to_string().contains("hole 4 overlap") || e.to_string().contains("holes 1 and 4 overlap")), "{pr:?}");
    }

    #[test]
    fn points_keep_out_of_a_hole_and_n_follows_equation_4_on_the_area_left() {
        use crate::axisym::uniform::{distribute, Options, SeedMethod};
        let p = cylinder();
        let d = square_with_hole();
        for method in [SeedMethod::Ebns, SeedMethod::Ere] {
            let o = Options { density: 0.5, seed_method: method, iterations: 20, ..Options::default() };
            let r = distribute(&p, &d, &o, 0.4, 7, &mut |_| {}).unwrap();
            // N = A·ρ²/e² on A = 504 mm²: 787.5 (rounding of the quadrature picks 787 or 788).
            assert!((r.points.len() as f64 - 504.0 * 0.25 / 0.16).abs() <= 0.5 + 1e-9, "{}", r.points.len());
            assert!((r.area_mm2 - 504.0).abs() < 1e-6);
            for q in r.seed_points.iter().chain(&r.points) {
                assert!(d.contains(*q), "{method:?}: {q:?} in the hole or out of Ω");
            }
            // Repulsion pushes points up to the hole's edge: some lie within a spacing of it.
            let near = r.points.iter().filter(|q| q[0] > 0.78 && q[0] < 1.22 && q[1] > 0.28 && q[1] < 0.72).count();
            eprintln!(
                "{method:?}: N {}, {near} points within ~0.6 mm of the hole, std {:.3} → {:.3} mm",
                r.points.len(),
                r.seed_metrics.nn_std_mm,
                r.metrics.nn_std_mm
            );
            assert!(near > 10);
            assert!(r.metrics.nn_std_mm < r.seed_metrics.nn_std_mm);
        }
    }
}

//! Fast point, normal and geodesic-distance queries on a surface of revolution, for the hot
//! loops of the uniform-point stage.
//!
//! Distance between near points: the 3-D chord c with a normal-curvature correction,
//! d ≈ c·(1 + κ_n²c²/24), κ_n the normal curvature of the surface in the chord's direction
//! (averaged over the two ends). A geodesic's space curvature is its normal curvature, and
//! arc vs chord of a curve of curvature κ is s = c(1 + κ²c²/24 + O(c⁴)); taking κ at the
//! middle kills the odd term, so the relative error is at most [`CHORD_ERROR_CONSTANT`]·(c·K)⁴
//! with K the local curvature scale (largest principal curvature and the square root of the
//! largest arc-length derivative of one, over the pair's u span). Where that bound is above
//! the tolerance the exact Clairaut [`geodesic`] is called instead.
//!
//! Gradient of the distance with respect to the first point: it is minus the unit tangent
//! covector of the geodesic at that point. The chord's projection onto the tangent plane gives
//! that direction to O((cK)²) (the paper's chord-length gradient, equation (5), with one
//! chord); for exact pairs the first sub-chord of the geodesic path is used, so the error is
//! O((cK/64)²). Both are normalised to unit length in the metric, as the true gradient is.

use super::geodesic::{self, geodesic};
use super::platform::{Jet, Profile};

/// Jet-table cells per unit of u: Hermite error ≤ h⁴/384·|f⁗| ≈ 3e-11 of the presets' values.
const JET_CELLS_PER_U: f64 = 1024.0;

/// Default largest relative error of the chord approximation; pairs whose bound is above it
/// get an exact geodesic.
pub const DEFAULT_CHORD_REL_TOL: f64 = 1e-6;
/// C in the bound |d_chord − d_geo|/d_geo ≤ C·(c·K)⁴. A circle arc gives 3/640 ≈ 0.0047 (the
/// next term of 2/κ·asin(κc/2)); the test `chord_bound_holds_on_presets` measures at most
/// 0.11 on the barrel and 0.97 on the hourglass (the ends' average stands in for the middle's
/// κ_n, which adds a κ·κ″ term), so 4 keeps a safety factor of four.
pub const CHORD_ERROR_CONSTANT: f64 = 4.0;
/// Cells of the curvature-scale table over the u range.
const CELLS: usize = 2048;

/// Everything the pair formulas need at one point, computed once per point (one jet
/// evaluation, one sin/cos) so pair queries touch no Bézier evaluation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Node {
    /// (u, θ).
    pub q: [f64; 2],
    /// Position, mm.
    pub p: [f64; 3],
    /// r_u, mm per unit u.
    pub r_u: [f64; 3],
    /// r_θ, mm per rad.
    pub r_t: [f64; 3],
    /// Meridian (k_m) and parallel (k_p) principal curvatures, 1/mm.
    pub k: [f64; 2],
    /// g_uu and g_θθ.
    pub g: [f64; 2],
}

/// One pair evaluation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PairEval {
    /// Geodesic distance, mm.
    pub d: f64,
    /// ∂d/∂(u, θ) at the first point.
    pub ga: [f64; 2],
    /// ∂d/∂(u, θ) at the second point.
    pub gb: [f64; 2],
    /// Whether the geodesic was solved (shooting or Clairaut) rather than estimated.
    pub exact: bool,
}

/// A platform (any [`Profile`]) with the tables the fast queries use.
pub struct Surface<'a> {
    profile: &'a dyn Profile,
    /// Relative error allowed for the chord approximation (see [`DEFAULT_CHORD_REL_TOL`]).
    pub chord_rel_tol: f64,
    /// Options of the exact geodesic calls.
    pub geodesic: geodesic::Options,
    u_lo: f64,
    u_hi: f64,
    /// Jets at both ends of each table cell (cubic Hermite in between: every jet the hot
    /// loops need comes from here, about ten times cheaper than a Bézier evaluation).
    jets: Vec<[Jet; 2]>,
    /// The same Hermite cubics of x, x′ and z′ per cell in the power basis of t ∈ [0, 1]
    /// (12 numbers, Horner in [`Profile::radius_speed`], the quadrature's hot call).
    rs: Vec<[f64; 12]>,
    /// Every critical point of the radius over the range, ascending.
    turns: Vec<f64>,
    jet_h: f64,
    /// Sparse table: `scale[k][i]` = max curvature scale over cells i .. i + 2^k.
    scale: Vec<Vec<f64>>,
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

impl<'a> Surface<'a> {
    /// Tables for `profile` (about 10⁴ jet evaluations).
    pub fn new(profile: &'a dyn Profile) -> Surface<'a> {
        let (u_lo, u_hi) = profile.u_range();
        let h = (u_hi - u_lo) / CELLS as f64;
        // Principal curvatures on a fine grid (4 samples per cell), then per cell the largest
        // curvature and √|dk/ds| (finite differences in arc length).
        let sub_n = 4 * CELLS;
        let ks: Vec<([f64; 2], f64)> = (0..=sub_n)
            .map(|i| {
                let u = u_lo + (u_hi - u_lo) * i as f64 / sub_n as f64;
                let j = profile.jet(u);
                let s = libm::hypot(j.x[1], j.z[1]);
                let km = (j.x[1] * j.z[2] - j.z[1] * j.x[2]) / (s * s * s);
                // Near a pole x → 0: the parallel curvature is capped by the meridian's limit
                // there only in theory; keep it finite so the table stays usable.
                let kp = if j.x[0] > 1e-9 { j.z[1] / (j.x[0] * s) } else { km };
                ([km, kp], s)
            })
            .collect();
        let mut base = vec![0.0f64; CELLS];
        for (c, slot) in base.iter_mut().enumerate() {
            let mut k = 0.0f64;
            for i in 4 * c..4 * c + 4 {
                let (ka, sa) = ks[i];
                let (kb, sb) = ks[i + 1];
                let ds = 0.5 * (sa + sb) * h / 4.0;
                for t in 0..2 {
                    k = k.max(ka[t].abs()).max(kb[t].abs());
                    if ds > 0.0 {
                        k = k.max(((kb[t] - ka[t]) / ds).abs().sqrt());
                    }
                }
            }
            *slot = if k.is_finite() { k } else { f64::INFINITY };
        }
        // Neighbouring cells too: the finite differences can straddle a sharp change.
        let widened: Vec<f64> = (0..CELLS).map(|i| base[i.saturating_sub(1)].max(base[i]).max(base[(i + 1).min(CELLS - 1)])).collect();
        let mut scale = vec![widened];
        let mut w = 1;
        while 2 * w <= CELLS {
            let prev = scale.last().unwrap();
            let next: Vec<f64> = (0..CELLS).map(|i| if i + w < CELLS { prev[i].max(prev[i + w]) } else { prev[i] }).collect();
            scale.push(next);
            w *= 2;
        }
        let cells = (((u_hi - u_lo) * JET_CELLS_PER_U).ceil() as usize).clamp(1, 1 << 20);
        let jet_h = (u_hi - u_lo) / cells as f64;
        let jets: Vec<[Jet; 2]> = (0..cells).map(|i| [profile.jet(u_lo + i as f64 * jet_h), profile.jet(u_lo + (i + 1) as f64 * jet_h)]).collect();
        // Hermite (f0, h·f0′, f1, h·f1′) → power basis: f0 + m0·t + (3Δ − 2m0 − m1)·t² + (m0 + m1 − 2Δ)·t³.
        let power = |f0: f64, d0: f64, f1: f64, d1: f64| {
            let (m0, m1, d) = (jet_h * d0, jet_h * d1, f1 - f0);
            [f0, m0, 3.0 * d - 2.0 * m0 - m1, m0 + m1 - 2.0 * d]
        };
        let rs = jets
            .iter()
            .map(|[a, b]| {
                let (x, x1, z1) = (power(a.x[0], a.x[1], b.x[0], b.x[1]), power(a.x[1], a.x[2], b.x[1], b.x[2]), power(a.z[1], a.z[2], b.z[1], b.z[2]));
                [x[0], x[1], x[2], x[3], x1[0], x1[1], x1[2], x1[3], z1[0], z1[1], z1[2], z1[3]]
            })
            .collect();
        let mut s = Surface {
            profile,
            chord_rel_tol: DEFAULT_CHORD_REL_TOL,
            geodesic: geodesic::Options::default(),
            u_lo,
            u_hi,
            jets,
            rs,
            turns: Vec::new(),
            jet_h,
            scale,
        };
        // x′ changes sign within a cell: bisect on the cell's cubic.
        for i in 0..s.jets.len() {
            let (d0, d1) = (s.jets[i][0].x[1], s.jets[i][1].x[1]);
            if (d0 > 0.0) != (d1 > 0.0) {
                let (mut l, mut h) = (u_lo + i as f64 * jet_h, u_lo + (i + 1) as f64 * jet_h);
                let rising = d1 > 0.0;
                for _ in 0..60 {
                    let m = 0.5 * (l + h);
                    if (s.radius_speed(m)[1] > 0.0) == rising {
                        h = m
                    } else {
                        l = m
                    }
                }
                s.turns.push(0.5 * (l + h));
            }
        }
        s
    }

    /// x, z and derivatives at u from the table (the profile itself outside its range).
    pub fn jet(&self, u: f64) -> Jet {
        let f = (u - self.u_lo) / self.jet_h;
        if !(f >= 0.0 && f <= self.jets.len() as f64) {
            return self.profile.jet(u);
        }
        let i = (f as usize).min(self.jets.len() - 1);
        let t = f - i as f64;
        let [a, b] = &self.jets[i];
        let h = self.jet_h;
        // Cubic Hermite of each order k from values k and slopes k + 1; the third
        // derivative linearly.
        let (t2, t3) = (t * t, t * t * t);
        let (h00, h10, h01, h11) = (2.0 * t3 - 3.0 * t2 + 1.0, t3 - 2.0 * t2 + t, -2.0 * t3 + 3.0 * t2, t3 - t2);
        let herm = |fa: &[f64; 4], fb: &[f64; 4], k: usize| h00 * fa[k] + h10 * h * fa[k + 1] + h01 * fb[k] + h11 * h * fb[k + 1];
        let x = [herm(&a.x, &b.x, 0), herm(&a.x, &b.x, 1), herm(&a.x, &b.x, 2), a.x[3] + t * (b.x[3] - a.x[3])];
        let z = [herm(&a.z, &b.z, 0), herm(&a.z, &b.z, 1), herm(&a.z, &b.z, 2), a.z[3] + t * (b.z[3] - a.z[3])];
        Jet { x, z }
    }

    /// The profile.
    pub fn profile(&self) -> &'a dyn Profile {
        self.profile
    }

    /// Per-point data for the pair queries.
    pub fn node(&self, q: [f64; 2]) -> Node {
        let j = self.jet(q[0]);
        let (s, c) = (libm::sin(q[1]), libm::cos(q[1]));
        let g_uu = j.x[1] * j.x[1] + j.z[1] * j.z[1];
        let sp = g_uu.sqrt();
        let km = (j.x[1] * j.z[2] - j.z[1] * j.x[2]) / (g_uu * sp);
        let kp = if j.x[0] > 1e-9 { j.z[1] / (j.x[0] * sp) } else { km };
        Node {
            q,
            p: [j.x[0] * c, j.x[0] * s, j.z[0]],
            r_u: [j.x[1] * c, j.x[1] * s, j.z[1]],
            r_t: [-j.x[0] * s, j.x[0] * c, 0.0],
            k: [km, kp],
            g: [g_uu, j.x[0] * j.x[0]],
        }
    }

    /// Point r(u, θ), mm.
    pub fn point(&self, q: [f64; 2]) -> [f64; 3] {
        super::platform::position(self.profile, q[0], q[1])
    }

    /// Unit normal at (u, θ).
    pub fn normal(&self, q: [f64; 2]) -> [f64; 3] {
        super::platform::normal(self.profile, q[0], q[1])
    }

    /// Geodesic distance, mm.
    pub fn distance(&self, a: [f64; 2], b: [f64; 2]) -> f64 {
        self.pair(&self.node(a), &self.node(b)).0
    }

    /// ∂d/∂(u, θ) of the geodesic distance with respect to `a` (a covector: mm per u, mm per
    /// rad); zero when the points coincide.
    pub fn direction(&self, a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
        self.pair(&self.node(a), &self.node(b)).1
    }

    /// Largest curvature scale K (1/mm) over u ∈ [lo, hi].
    pub fn curvature_scale(&self, lo: f64, hi: f64) -> f64 {
        let h = (self.u_hi - self.u_lo) / CELLS as f64;
        let cell = |u: f64| (((u - self.u_lo) / h).floor().max(0.0) as usize).min(CELLS - 1);
        let (i, j) = (cell(lo), cell(hi));
        let len = j - i + 1;
        let k = (usize::BITS - 1 - len.leading_zeros()) as usize;
        let t = &self.scale[k];
        t[i].max(t[j + 1 - (1 << k)])
    }

    /// Normal curvature at `n` in the direction of `d` (projected onto the tangent plane).
    fn normal_curvature(n: &Node, d: [f64; 3]) -> f64 {
        let a = dot(d, n.r_u);
        let b = dot(d, n.r_t);
        let (a2, b2) = (a * a / n.g[0], if n.g[1] > 0.0 { b * b / n.g[1] } else { 0.0 });
        let t = a2 + b2;
        if t > 0.0 {
            (n.k[0] * a2 + n.k[1] * b2) / t
        } else {
            0.0
        }
    }

    /// The chord estimate: (distance, bound on its relative error).
    pub fn chord_estimate(&self, a: &Node, b: &Node) -> (f64, f64) {
        let d = sub(b.p, a.p);
        let c = dot(d, d).sqrt();
        let kn = 0.5 * (Self::normal_curvature(a, d) + Self::normal_curvature(b, d));
        // The geodesic may bulge past the ends' u span by about its sagitta; half a chord in
        // u units covers that with room.
        let du = 0.5 * c / a.g[0].sqrt().min(b.g[0].sqrt()).max(1e-300);
        let k = self.curvature_scale(a.q[0].min(b.q[0]) - du, a.q[0].max(b.q[0]) + du);
        let ck = c * k;
        (c * (1.0 + kn * kn * c * c / 24.0), CHORD_ERROR_CONSTANT * ck * ck * ck * ck)
    }

    /// (distance, ∂d/∂(u, θ) at a, exact geodesic used).
    pub fn pair(&self, a: &Node, b: &Node) -> (f64, [f64; 2], bool) {
        let e = self.pair_both(a, b);
        (e.d, e.ga, e.exact)
    }

    /// Distance and both gradients (∂d/∂a, ∂d/∂b) in one evaluation.
    pub fn pair_both(&self, a: &Node, b: &Node) -> PairEval {
        let d = sub(b.p, a.p);
        if dot(d, d) == 0.0 {
            return PairEval { d: 0.0, ga: [0.0; 2], gb: [0.0; 2], exact: false };
        }
        let (est, bound) = self.chord_estimate(a, b);
        if bound <= self.chord_rel_tol {
            return PairEval { d: est, ga: Self::chord_gradient(a, d), gb: Self::chord_gradient(b, sub(a.p, b.p)), exact: false };
        }
        if let Some(e) = self.clairaut(a, b) {
            return e;
        }
        if let Some(e) = self.shoot(a, b, bound) {
            return e;
        }
        match geodesic(self.profile, a.q, b.q, &self.geodesic) {
            Ok(g) if g.length_mm.is_finite() && g.path.len() >= 2 => {
                let n = g.path.len();
                let first = self.node(g.path[1]);
                let last = self.node(g.path[n - 2]);
                let (da, db) = (sub(first.p, a.p), sub(last.p, b.p));
                let ga = if dot(da, da) > 0.0 { Self::chord_gradient(a, da) } else { Self::chord_gradient(a, d) };
                let gb = if dot(db, db) > 0.0 { Self::chord_gradient(b, db) } else { Self::chord_gradient(b, sub(a.p, b.p)) };
                PairEval { d: g.length_mm, ga, gb, exact: true }
            }
            // The exact solver refused (a path near a pole): the estimate is still a
            // distance ≥ the chord, and the caller's domain checks keep this rare.
            _ => PairEval { d: est, ga: Self::chord_gradient(a, d), gb: Self::chord_gradient(b, sub(a.p, b.p)), exact: false },
        }
    }

    /// The exact geodesic by Clairaut's relation ([`super::clairaut`]): length and both end
    /// directions in closed form from c. `None` for the shapes it leaves to the shooter.
    fn clairaut(&self, a: &Node, b: &Node) -> Option<PairEval> {
        let mut dt = libm::remainder(b.q[1] - a.q[1], 2.0 * std::f64::consts::PI);
        if dt <= -std::f64::consts::PI {
            dt += 2.0 * std::f64::consts::PI;
        }
        let sol = super::clairaut::solve(self, a.q, [b.q[0], a.q[1] + dt], self.geodesic.min_pole_radius_mm)?;
        if !(sol.length_mm > 0.0 && sol.min_radius_mm >= self.geodesic.min_pole_radius_mm) {
            return None;
        }
        // ∂d/∂a = −(unit tangent leaving a), ∂d/∂b = +(unit tangent arriving at b), lowered
        // by the metric.
        Some(PairEval { d: sol.length_mm, ga: [-a.g[0] * sol.start[0], -a.g[1] * sol.start[1]], gb: [b.g[0] * sol.end[0], b.g[1] * sol.end[1]], exact: true })
    }

    /// Geodesic by shooting: the geodesic equation integrated by RK4 over τ ∈ [0, 1] with
    /// enough steps for the pair's c·K (the RK4 error is ∝ (cK/steps)⁴), the initial velocity
    /// from the second-order expansion v = Δ + ½Γ(Δ, Δ) and corrected by Newton with one
    /// finite-difference Jacobian. The length is the (conserved) speed |v|_g. `None` when it
    /// does not converge to 1e-10 of the distance; the caller then asks [`geodesic`].
    fn shoot(&self, a: &Node, b: &Node, bound: f64) -> Option<PairEval> {
        let mut dt = libm::remainder(b.q[1] - a.q[1], 2.0 * std::f64::consts::PI);
        if dt <= -std::f64::consts::PI {
            dt += 2.0 * std::f64::consts::PI;
        }
        let target = [b.q[0], a.q[1] + dt];
        let delta = [b.q[0] - a.q[0], dt];
        let ja = self.jet(a.q[0]);
        let ch = super::platform::christoffel_of(&ja);
        let mut v = [delta[0] + 0.5 * (ch.u_uu * delta[0] * delta[0] + ch.u_tt * delta[1] * delta[1]), delta[1] + ch.t_ut * delta[0] * delta[1]];
        // (cK)⁴·C = bound; steps so that (cK/steps)⁴ is ~1e-14.
        let ck = libm::sqrt(libm::sqrt(bound / CHORD_ERROR_CONSTANT));
        // RK4's error is ∝ (cK/steps)⁴ with a small constant; the test checks 1e-6 holds.
        let steps = ((ck * 40.0).ceil() as usize).clamp(4, 64);
        let (lo, hi) = (self.u_lo, self.u_hi);
        let shoot = |v: [f64; 2]| -> Option<[f64; 4]> {
            let rhs = |y: &[f64; 4]| -> Option<[f64; 4]> {
                if !(lo..=hi).contains(&y[0]) {
                    return None;
                }
                let j = self.jet(y[0]);
                if !(j.x[0] > 0.0) {
                    return None;
                }
                let g = super::platform::christoffel_of(&j);
                Some([y[2], y[3], -g.u_uu * y[2] * y[2] - g.u_tt * y[3] * y[3], -2.0 * g.t_ut * y[2] * y[3]])
            };
            let h = 1.0 / steps as f64;
            let mut y = [a.q[0], a.q[1], v[0], v[1]];
            let add = |y: &[f64; 4], k: &[f64; 4], s: f64| [y[0] + s * k[0], y[1] + s * k[1], y[2] + s * k[2], y[3] + s * k[3]];
            for _ in 0..steps {
                let k1 = rhs(&y)?;
                let k2 = rhs(&add(&y, &k1, 0.5 * h))?;
                let k3 = rhs(&add(&y, &k2, 0.5 * h))?;
                let k4 = rhs(&add(&y, &k3, h))?;
                for i in 0..4 {
                    y[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
                }
            }
            Some(y)
        };
        let c = dot(sub(b.p, a.p), sub(b.p, a.p)).sqrt();
        let miss_mm = |y: &[f64; 4]| {
            let e = [target[0] - y[0], target[1] - y[1]];
            (e, (b.g[0] * e[0] * e[0] + b.g[1] * e[1] * e[1]).sqrt())
        };
        let mut y = shoot(v)?;
        let (mut e, mut m) = miss_mm(&y);
        // Jacobian d(end)/dv by forward differences, once (the chord method: the map is
        // close to the identity for near pairs, so the reused Jacobian converges fast).
        let hv = 1e-7 * (v[0].abs() + v[1].abs()).max(1e-12);
        let y0 = shoot([v[0] + hv, v[1]])?;
        let y1 = shoot([v[0], v[1] + hv])?;
        let jm = [[(y0[0] - y[0]) / hv, (y1[0] - y[0]) / hv], [(y0[1] - y[1]) / hv, (y1[1] - y[1]) / hv]];
        let det = jm[0][0] * jm[1][1] - jm[0][1] * jm[1][0];
        if !(det.abs() > 0.0) {
            return None;
        }
        for _ in 0..12 {
            if m <= 1e-10 * c {
                break;
            }
            v[0] += (jm[1][1] * e[0] - jm[0][1] * e[1]) / det;
            v[1] += (-jm[1][0] * e[0] + jm[0][0] * e[1]) / det;
            y = shoot(v)?;
            (e, m) = miss_mm(&y);
        }
        if !(m <= 1e-10 * c) {
            return None;
        }
        let speed = (a.g[0] * v[0] * v[0] + a.g[1] * v[1] * v[1]).sqrt();
        let speed_b = (b.g[0] * y[2] * y[2] + b.g[1] * y[3] * y[3]).sqrt();
        if !(speed > 0.0 && speed_b > 0.0) {
            return None;
        }
        Some(PairEval { d: speed, ga: [-a.g[0] * v[0] / speed, -a.g[1] * v[1] / speed], gb: [b.g[0] * y[2] / speed_b, b.g[1] * y[3] / speed_b], exact: true })
    }

    /// The 3-D chord and its exact gradients (the Euclidean energy of the ERE seed).
    pub fn chord_pair(&self, a: &Node, b: &Node) -> PairEval {
        let d = sub(b.p, a.p);
        let c = dot(d, d).sqrt();
        if c == 0.0 {
            return PairEval { d: 0.0, ga: [0.0; 2], gb: [0.0; 2], exact: true };
        }
        let ga = [-dot(d, a.r_u) / c, -dot(d, a.r_t) / c];
        let gb = [dot(d, b.r_u) / c, dot(d, b.r_t) / c];
        PairEval { d: c, ga, gb, exact: true }
    }

    /// −(unit tangent covector towards d) at a: the chord's tangent-plane projection,
    /// normalised in the metric.
    fn chord_gradient(a: &Node, d: [f64; 3]) -> [f64; 2] {
        let gu = -dot(d, a.r_u);
        let gt = -dot(d, a.r_t);
        let n2 = gu * gu / a.g[0] + if a.g[1] > 0.0 { gt * gt / a.g[1] } else { 0.0 };
        if n2 > 0.0 {
            let n = n2.sqrt();
            [gu / n, gt / n]
        } else {
            [0.0, 0.0]
        }
    }
}

/// The tabulated profile: the fast Clairaut solver's quadrature nodes read their jets here.
impl Profile for Surface<'_> {
    fn u_range(&self) -> (f64, f64) {
        (self.u_lo, self.u_hi)
    }
    fn jet(&self, u: f64) -> Jet {
        Surface::jet(self, u)
    }
    fn knots_between(&self, lo: f64, hi: f64, out: &mut Vec<f64>) {
        self.profile.knots_between(lo, hi, out)
    }
    fn radius_turns(&self, lo: f64, hi: f64, out: &mut Vec<f64>) {
        let from = self.turns.partition_point(|&t| t <= lo);
        out.extend(self.turns[from..].iter().take_while(|&&t| t < hi));
    }
    fn radius_speed(&self, u: f64) -> [f64; 3] {
        let f = (u - self.u_lo) / self.jet_h;
        if !(f >= 0.0 && f <= self.jets.len() as f64) {
            let j = self.profile.jet(u);
            return [j.x[0], j.x[1], (j.x[1] * j.x[1] + j.z[1] * j.z[1]).sqrt()];
        }
        let i = (f as usize).min(self.rs.len() - 1);
        let t = f - i as f64;
        let c = &self.rs[i];
        let x = c[0] + t * (c[1] + t * (c[2] + t * c[3]));
        let x1 = c[4] + t * (c[5] + t * (c[6] + t * c[7]));
        let z1 = c[8] + t * (c[9] + t * (c[10] + t * c[11]));
        [x, x1, (x1 * x1 + z1 * z1).sqrt()]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::axisym::platform::Platform;
    use rand_core::{Rng, SeedableRng};
    use rand_pcg::Pcg64;

    fn unit(rng: &mut Pcg64) -> f64 {
        (rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    #[test]
    fn chord_bound_holds_on_presets() {
        for (name, p, u_lo, u_hi) in [("barrel", Platform::barrel(), 0.15, 1.85), ("hourglass", Platform::hourglass(), 0.3, 3.7)] {
            let s = Surface::new(&p);
            let mut rng = Pcg64::seed_from_u64(7);
            let (mut worst_ratio, mut worst_used, mut used, mut total) = (0.0f64, 0.0f64, 0, 0);
            let t0 = std::time::Instant::now();
            let (mut exact_time, mut fast_time) = (0.0, 0.0);
            for _ in 0..150 {
                let a = [u_lo + (u_hi - u_lo) * unit(&mut rng), 6.0 * unit(&mut rng)];
                // Near pairs: up to ~8 mm apart.
                let len = 8.0 * unit(&mut rng);
                let ang = std::f64::consts::TAU * unit(&mut rng);
                let m = crate::axisym::platform::metric(&p, a[0]);
                let b = [(a[0] + len * libm::cos(ang) / m.g_uu.sqrt()).clamp(u_lo, u_hi), a[1] + len * libm::sin(ang) / m.g_tt.sqrt()];
                let (na, nb) = (s.node(a), s.node(b));
                let (est, bound) = s.chord_estimate(&na, &nb);
                let t = std::time::Instant::now();
                let exact = geodesic(&p, a, b, &geodesic::Options::default()).unwrap().length_mm;
                exact_time += t.elapsed().as_secs_f64();
                if exact < 1e-9 {
                    continue;
                }
                let err = (est - exact).abs() / exact;
                total += 1;
                // The bound is C·(cK)⁴; err/bound·C is the constant the data needs.
                if bound > 1e-15 {
                    worst_ratio = worst_ratio.max(err / bound * CHORD_ERROR_CONSTANT);
                }
                if bound <= DEFAULT_CHORD_REL_TOL {
                    used += 1;
                    worst_used = worst_used.max(err);
                    assert!(err <= DEFAULT_CHORD_REL_TOL, "{name}: chord used with error {err:.3e}");
                }
                // The fast distance agrees with the exact one either way.
                let t = std::time::Instant::now();
                let fast = s.distance(a, b);
                fast_time += t.elapsed().as_secs_f64();
                assert!((fast - exact).abs() <= DEFAULT_CHORD_REL_TOL * exact + 1e-9, "{name}: fast {fast} exact {exact}");
                // The gradient is minus the unit tangent: check it against finite differences.
                let g = s.direction(a, b);
                let h = 1e-6;
                let fd_u = (geodesic(&p, [a[0] + h, a[1]], b, &geodesic::Options::default()).unwrap().length_mm
                    - geodesic(&p, [a[0] - h, a[1]], b, &geodesic::Options::default()).unwrap().length_mm)
                    / (2.0 * h);
                let g_scale = m.g_uu.sqrt();
                assert!((g[0] - fd_u).abs() <= 2e-3 * g_scale, "{name}: ∂d/∂u {} vs fd {fd_u}", g[0]);
            }
            println!(
                "{name}: {total} pairs, chord used for {used} (worst error there {worst_used:.2e}); measured constant {worst_ratio:.2e} (bound uses {CHORD_ERROR_CONSTANT}); exact geodesic {:.1} µs/pair, fast {:.2} µs/pair; test {:.2} s",
                exact_time / total as f64 * 1e6,
                fast_time / total as f64 * 1e6,
                t0.elapsed().as_secs_f64()
            );
            assert!(worst_ratio <= CHORD_ERROR_CONSTANT, "{name}: the bound's constant is too small");
            assert!(used > 0);
        }
    }
}

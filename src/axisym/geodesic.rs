//! Geodesic distance and path between two (u, θ) points on a surface of revolution.
//!
//! Primary: Clairaut's relation x·sin ψ = c (ψ: angle to the meridian) turns the boundary
//! value problem into a one-dimensional root find in c, solved with fixed Gauss–Kronrod
//! quadrature by [`super::clairaut`], for geodesics monotone in u and for those that turn
//! back once; the path is then one RK4 shot from the solved start direction.
//!
//! Fallback: the geodesic equation (the paper's equation (1), with Γ^θ_uθ in the θ row) for
//! (u, θ)(τ), τ ∈ [0, 1], integrated by classical RK4 with a fixed number of steps, and
//! Newton shooting on the initial velocity (finite-difference Jacobian, backtracking). It
//! finds the geodesic nearest the straight line in (u, θ), which is the shortest one for the
//! short segments the later stages join; it is not a global search.
//!
//! θ wrap-around: the end θ is moved by a multiple of 2π so that |Δθ| ≤ π (the shorter way
//! round); the returned path's θ is continuous (unwrapped) from the start θ.

use super::platform::{christoffel_of, Jet, Profile, DEFAULT_MIN_POLE_RADIUS_MM};
use super::Error;
use std::f64::consts::PI;

/// Default number of RK4 steps over τ ∈ [0, 1] for the ODE shooter (error ∝ steps⁻⁴; 256 gives
/// better than 1e-9 relative on a sphere quarter circle).
pub const DEFAULT_ODE_STEPS: usize = 256;
/// Default shooting tolerance: the end point may miss by this much, mm.
pub const DEFAULT_TOLERANCE_MM: f64 = 1e-10;
/// Default cap of shooting iterations.
pub const DEFAULT_MAX_ITERATIONS: usize = 100;
/// Default number of points in the returned path (both ends included).
pub const DEFAULT_PATH_SAMPLES: usize = 65;

/// Which solver.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// Clairaut first, the ODE shooter when it cannot (a pair on a parallel where x′ = 0,
    /// two critical points of the radius between the ends).
    Auto,
    /// Clairaut only ([`Error::TurningPoint`] when it cannot).
    Clairaut,
    /// ODE shooter only.
    Ode,
}

/// Geodesic settings.
#[derive(Clone, Debug, PartialEq)]
pub struct Options {
    /// Solver choice.
    pub method: Method,
    /// Minimum distance from the axis, mm (see [`DEFAULT_MIN_POLE_RADIUS_MM`]).
    pub min_pole_radius_mm: f64,
    /// See [`DEFAULT_ODE_STEPS`].
    pub ode_steps: usize,
    /// See [`DEFAULT_TOLERANCE_MM`].
    pub tolerance_mm: f64,
    /// See [`DEFAULT_MAX_ITERATIONS`].
    pub max_iterations: usize,
    /// See [`DEFAULT_PATH_SAMPLES`].
    pub path_samples: usize,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            method: Method::Auto,
            min_pole_radius_mm: DEFAULT_MIN_POLE_RADIUS_MM,
            ode_steps: DEFAULT_ODE_STEPS,
            tolerance_mm: DEFAULT_TOLERANCE_MM,
            max_iterations: DEFAULT_MAX_ITERATIONS,
            path_samples: DEFAULT_PATH_SAMPLES,
        }
    }
}

/// A geodesic.
#[derive(Clone, Debug, PartialEq)]
pub struct Geodesic {
    /// Length, mm.
    pub length_mm: f64,
    /// Sampled path, (u, θ) with θ unwrapped from the start.
    pub path: Vec<[f64; 2]>,
    /// The solver that produced it ([`Method::Clairaut`] or [`Method::Ode`]).
    pub method: Method,
}

/// Geodesic from `a` = (u, θ) to `b` on profile `p`.
pub fn geodesic<P: Profile + ?Sized>(p: &P, a: [f64; 2], b: [f64; 2], o: &Options) -> Result<Geodesic, Error> {
    if !(o.min_pole_radius_mm > 0.0) {
        return Err(Error::BadOption { name: "min_pole_radius_mm", value: o.min_pole_radius_mm, hint: "must be > 0 mm" });
    }
    if o.ode_steps < 4 {
        return Err(Error::BadOption { name: "ode_steps", value: o.ode_steps as f64, hint: "at least 4" });
    }
    if o.path_samples < 2 {
        return Err(Error::BadOption { name: "path_samples", value: o.path_samples as f64, hint: "at least 2" });
    }
    if !(o.tolerance_mm > 0.0) {
        return Err(Error::BadOption { name: "tolerance_mm", value: o.tolerance_mm, hint: "must be > 0 mm" });
    }
    for q in [a, b] {
        check_point(p, q[0], o.min_pole_radius_mm)?;
    }
    let mut dt = libm::remainder(b[1] - a[1], 2.0 * PI);
    if dt <= -PI {
        dt += 2.0 * PI;
    }
    let b = [b[0], a[1] + dt];
    if a[0] == b[0] && dt == 0.0 {
        return Ok(Geodesic { length_mm: 0.0, path: vec![a; o.path_samples], method: o.method_used() });
    }
    match o.method {
        Method::Clairaut => clairaut(p, a, b, o),
        Method::Ode => ode(p, a, b, o, [b[0] - a[0], b[1] - a[1]]),
        Method::Auto => match clairaut(p, a, b, o) {
            Err(Error::TurningPoint { .. }) => ode(p, a, b, o, [b[0] - a[0], b[1] - a[1]]),
            r => r,
        },
    }
}

impl Options {
    fn method_used(&self) -> Method {
        if self.method == Method::Ode {
            Method::Ode
        } else {
            Method::Clairaut
        }
    }
}

fn check_point<P: Profile + ?Sized>(p: &P, u: f64, min_r: f64) -> Result<(), Error> {
    let (lo, hi) = p.u_range();
    if !(lo..=hi).contains(&u) {
        return Err(Error::OutOfRange { u, u_min: lo, u_max: hi });
    }
    let x = p.jet(u).x[0];
    if x < min_r {
        let (a, b) = super::platform::pole_clearance(p, min_r).unwrap_or((f64::NAN, f64::NAN));
        return Err(Error::TooNearPole { u, radius_mm: x, min_radius_mm: min_r, u_allowed_min: a, u_allowed_max: b });
    }
    Ok(())
}

/// Clairaut's relation through [`super::clairaut::solve`], then the path by one RK4 shot
/// from the solved start direction (its end miss, far below the samples' spacing, is spread
/// linearly along the path; a larger miss hands over to the ODE shooter from that start).
fn clairaut<P: Profile + ?Sized>(p: &P, a: [f64; 2], b: [f64; 2], o: &Options) -> Result<Geodesic, Error> {
    let Some(sol) = super::clairaut::solve(p, a, b, o.min_pole_radius_mm) else {
        return Err(Error::TurningPoint { u0: a[0], u1: b[0] });
    };
    if sol.min_radius_mm < o.min_pole_radius_mm {
        let (lo, hi) = super::platform::pole_clearance(p, o.min_pole_radius_mm).unwrap_or((f64::NAN, f64::NAN));
        return Err(Error::TooNearPole {
            u: sol.turn.unwrap_or(a[0]),
            radius_mm: sol.min_radius_mm,
            min_radius_mm: o.min_pole_radius_mm,
            u_allowed_min: lo,
            u_allowed_max: hi,
        });
    }
    let v = [sol.length_mm * sol.start[0], sol.length_mm * sol.start[1]];
    let per = (64 + o.path_samples - 2) / (o.path_samples - 1);
    let steps = per * (o.path_samples - 1);
    let path = shoot(p, a, v, steps, o.min_pole_radius_mm, true).map(|(_, path)| path);
    let jb = p.jet(b[0]);
    match path {
        Some(path) => {
            let end = path[steps];
            let miss = [b[0] - end[0], b[1] - end[1]];
            let miss_mm = libm::hypot(miss[0] * libm::hypot(jb.x[1], jb.z[1]), miss[1] * jb.x[0]);
            if miss_mm <= 1e-6 * sol.length_mm.max(1e-3) {
                let out = (0..o.path_samples)
                    .map(|i| {
                        let q = path[i * per];
                        let f = i as f64 / (o.path_samples - 1) as f64;
                        if i + 1 == o.path_samples {
                            b
                        } else {
                            [q[0] + f * miss[0], q[1] + f * miss[1]]
                        }
                    })
                    .collect();
                return Ok(Geodesic { length_mm: sol.length_mm, path: out, method: Method::Clairaut });
            }
            ode(p, a, b, o, v).map(|g| Geodesic { length_mm: sol.length_mm, method: Method::Clairaut, ..g })
        }
        None => ode(p, a, b, o, v).map(|g| Geodesic { length_mm: sol.length_mm, method: Method::Clairaut, ..g }),
    }
}

/// RK4 over τ ∈ [0, 1] of (u, θ, u̇, θ̇, s). `None` if it leaves the range or nears a pole.
fn shoot<P: Profile + ?Sized>(p: &P, a: [f64; 2], v: [f64; 2], steps: usize, min_r: f64, keep: bool) -> Option<([f64; 5], Vec<[f64; 2]>)> {
    let (lo, hi) = p.u_range();
    let rhs = |y: &[f64; 5]| -> Option<[f64; 5]> {
        if !(lo..=hi).contains(&y[0]) {
            return None;
        }
        let j: Jet = p.jet(y[0]);
        if !(j.x[0] >= min_r) {
            return None;
        }
        let g = christoffel_of(&j);
        let guu = j.x[1] * j.x[1] + j.z[1] * j.z[1];
        Some([
            y[2],
            y[3],
            -g.u_uu * y[2] * y[2] - g.u_tt * y[3] * y[3],
            -2.0 * g.t_ut * y[2] * y[3],
            (guu * y[2] * y[2] + j.x[0] * j.x[0] * y[3] * y[3]).sqrt(),
        ])
    };
    let h = 1.0 / steps as f64;
    let mut y = [a[0], a[1], v[0], v[1], 0.0];
    let mut path = Vec::new();
    if keep {
        path.push(a);
    }
    let add = |y: &[f64; 5], k: &[f64; 5], s: f64| std::array::from_fn::<f64, 5, _>(|i| y[i] + s * k[i]);
    for _ in 0..steps {
        let k1 = rhs(&y)?;
        let k2 = rhs(&add(&y, &k1, 0.5 * h))?;
        let k3 = rhs(&add(&y, &k2, 0.5 * h))?;
        let k4 = rhs(&add(&y, &k3, h))?;
        y = std::array::from_fn(|i| y[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]));
        if keep {
            path.push([y[0], y[1]]);
        }
    }
    rhs(&y)?;
    Some((y, path))
}

/// Newton shooting on the initial velocity, from `v` (the straight line in (u, θ) when no
/// better guess is known).
fn ode<P: Profile + ?Sized>(p: &P, a: [f64; 2], b: [f64; 2], o: &Options, v: [f64; 2]) -> Result<Geodesic, Error> {
    // Residual in mm: the miss in u and θ scaled by the metric at the target.
    let jb = p.jet(b[0]);
    let (su, st) = (libm::hypot(jb.x[1], jb.z[1]), jb.x[0]);
    let res = |y: &[f64; 5]| [(y[0] - b[0]) * su, (y[1] - b[1]) * st];
    let norm = |r: [f64; 2]| libm::hypot(r[0], r[1]);
    let run = |v: [f64; 2]| shoot(p, a, v, o.ode_steps, o.min_pole_radius_mm, false).map(|(y, _)| y);
    let fail = |r: f64| Error::NoConvergence { u0: a[0], t0: a[1], u1: b[0], t1: b[1], residual_mm: r };
    let mut v = v;
    let mut y = run(v).ok_or_else(|| fail(f64::INFINITY))?;
    let mut r = res(&y);
    for _ in 0..o.max_iterations {
        if norm(r) <= o.tolerance_mm {
            let (y, path) = shoot(p, a, v, o.ode_steps, o.min_pole_radius_mm, true).ok_or_else(|| fail(f64::INFINITY))?;
            let stride = o.ode_steps as f64 / (o.path_samples - 1) as f64;
            let mut out: Vec<[f64; 2]> = (0..o.path_samples).map(|i| path[libm::round(i as f64 * stride) as usize]).collect();
            *out.last_mut().unwrap() = b;
            return Ok(Geodesic { length_mm: y[4], path: out, method: Method::Ode });
        }
        // Jacobian of the residual by central differences.
        let mut jac = [[0.0; 2]; 2];
        for k in 0..2 {
            let d = 1e-6 * (1.0 + v[k].abs());
            let (mut vp, mut vm) = (v, v);
            vp[k] += d;
            vm[k] -= d;
            let (yp, ym) = (run(vp).ok_or_else(|| fail(norm(r)))?, run(vm).ok_or_else(|| fail(norm(r)))?);
            let (rp, rm) = (res(&yp), res(&ym));
            for i in 0..2 {
                jac[i][k] = (rp[i] - rm[i]) / (2.0 * d);
            }
        }
        let det = jac[0][0] * jac[1][1] - jac[0][1] * jac[1][0];
        if det == 0.0 || !det.is_finite() {
            return Err(fail(norm(r)));
        }
        let step = [(jac[1][1] * r[0] - jac[0][1] * r[1]) / det, (jac[0][0] * r[1] - jac[1][0] * r[0]) / det];
        // Backtracking: halve the step until the miss shrinks and the path stays valid.
        let mut lambda = 1.0;
        let mut accepted = false;
        for _ in 0..40 {
            let vt = [v[0] - lambda * step[0], v[1] - lambda * step[1]];
            if let Some(yt) = run(vt) {
                let rt = res(&yt);
                if norm(rt) < norm(r) {
                    v = vt;
                    y = yt;
                    r = rt;
                    accepted = true;
                    break;
                }
            }
            lambda *= 0.5;
        }
        if !accepted {
            break;
        }
    }
    let _ = y;
    Err(fail(norm(r)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::axisym::platform::Platform;
    use crate::axisym::testing::{great_circle, Sphere};

    /// Exact cylinder of radius 20 mm from two collinear degree-6 segments: z = 60 − 30u.
    fn cylinder() -> Platform {
        let pts: Vec<[f64; 2]> = (0..13).map(|i| [20.0, 60.0 - 5.0 * i as f64]).collect();
        Platform::from_polygon(&pts).unwrap()
    }

    fn opts(method: Method) -> Options {
        Options { method, ..Options::default() }
    }

    fn close(got: f64, want: f64) -> bool {
        ((got - want) / want).abs() <= 1e-6
    }

    #[test]
    fn cylinder_matches_unrolled_plane() {
        let p = cylinder();
        let cases = [
            ([0.3, 0.1], [1.6, 1.2], 1.1),
            ([1.5, 2.0], [0.2, -0.5], -2.5),
            // Wrap-around: 6.0 → 0.2 + 2π is +0.483 rad the short way.
            ([0.4, 6.0], [1.1, 0.2], 0.2 + 2.0 * PI - 6.0),
            ([0.5, 0.0], [1.9, 0.0], 0.0),
        ];
        for (a, b, dt) in cases {
            let exact = (20.0f64 * dt).hypot(30.0 * (b[0] - a[0]));
            for m in [Method::Clairaut, Method::Ode] {
                let g = geodesic(&p, a, b, &opts(m)).unwrap();
                assert_eq!(g.method, m);
                assert!(close(g.length_mm, exact), "{m:?} {a:?}→{b:?}: {} vs {exact}", g.length_mm);
                // On the unrolled plane the path is straight: θ linear in u.
                let mid = g.path[g.path.len() / 2];
                let t = (mid[0] - a[0]) / (b[0] - a[0]);
                assert!((mid[1] - (a[1] + t * dt)).abs() < 1e-6, "{m:?} path {mid:?}");
                let end = *g.path.last().unwrap();
                assert!(end[0] == b[0] && (end[1] - (a[1] + dt)).abs() < 1e-12, "{end:?}");
            }
        }
        // Same u on a cylinder (x′ = 0 everywhere): the parallel; Clairaut hands over and
        // Auto falls back to the ODE: a circle arc.
        let (a, b) = ([0.7, 0.2], [0.7, 1.4]);
        assert!(matches!(geodesic(&p, a, b, &opts(Method::Clairaut)), Err(Error::TurningPoint { .. })));
        let g = geodesic(&p, a, b, &Options::default()).unwrap();
        assert_eq!(g.method, Method::Ode);
        assert!(close(g.length_mm, 20.0 * 1.2));
    }

    #[test]
    fn sphere_matches_great_circles() {
        let s = Sphere(10.0);
        // No turning point between the ends: both methods.
        for (a, b) in [([1.0, 0.0], [2.2, 0.9]), ([0.6, 0.3], [1.4, 0.5]), ([2.0, 6.1], [1.2, 0.4])] {
            let exact = great_circle(10.0, a, b);
            for m in [Method::Clairaut, Method::Ode, Method::Auto] {
                let g = geodesic(&s, a, b, &opts(m)).unwrap();
                assert!(close(g.length_mm, exact), "{m:?} {a:?}→{b:?}: {} vs {exact}", g.length_mm);
            }
        }
        // Turning points (same latitude, or bulging past an end): both methods.
        for (a, b, m) in [([1.2, 0.0], [1.2, 1.0]), ([0.9, 0.0], [1.0, 1.5]), ([2.3, 0.2], [2.1, 1.9])]
            .into_iter()
            .flat_map(|(a, b)| [(a, b, Method::Clairaut), (a, b, Method::Ode)])
        {
            let exact = great_circle(10.0, a, b);
            let g = geodesic(&s, a, b, &opts(m)).unwrap();
            assert_eq!(g.method, m, "{a:?}→{b:?}");
            assert!(close(g.length_mm, exact), "{m:?} {a:?}→{b:?}: {} vs {exact}", g.length_mm);
            // Every path point on the great circle: its plane through the centre.
            let pa = crate::axisym::platform::position(&s, a[0], a[1]);
            let pb = crate::axisym::platform::position(&s, b[0], b[1]);
            let n = [pa[1] * pb[2] - pa[2] * pb[1], pa[2] * pb[0] - pa[0] * pb[2], pa[0] * pb[1] - pa[1] * pb[0]];
            for q in &g.path {
                let x = crate::axisym::platform::position(&s, q[0], q[1]);
                assert!((x[0] * n[0] + x[1] * n[1] + x[2] * n[2]).abs() < 1e-6 * 100.0);
            }
        }
    }

    #[test]
    fn methods_agree_on_the_presets() {
        for (p, a, b) in [
            (Platform::barrel(), [0.85, 0.1], [1.15, 0.9]),
            (Platform::barrel(), [0.8, 0.0], [1.2, 1.0]),
            (Platform::hourglass(), [1.2, 0.0], [2.8, 1.0]),
            (Platform::hourglass(), [1.5, 0.9], [2.5, 0.1]),
        ] {
            let c = geodesic(&p, a, b, &opts(Method::Auto)).unwrap();
            let o = geodesic(&p, a, b, &opts(Method::Ode)).unwrap();
            eprintln!("{a:?}→{b:?}: auto ({:?}) {} mm, ode {} mm", c.method, c.length_mm, o.length_mm);
            assert!(close(c.length_mm, o.length_mm));
        }
    }

    #[test]
    fn poles_and_ranges_are_refused() {
        let p = Platform::barrel();
        let e = geodesic(&p, [0.001, 0.0], [1.0, 0.5], &Options::default()).unwrap_err();
        assert!(matches!(e, Error::TooNearPole { .. }), "{e}");
        let e = geodesic(&p, [2.5, 0.0], [1.0, 0.5], &Options::default()).unwrap_err();
        assert!(matches!(e, Error::OutOfRange { .. }), "{e}");
        let g = geodesic(&p, [1.0, 0.3], [1.0, 0.3 + 2.0 * PI], &Options::default()).unwrap();
        assert!(g.length_mm.abs() < 1e-12);
    }
}

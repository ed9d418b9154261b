//! The platform offset by a distance h along its unit normal: the surface a layer is printed
//! on (layer k of a several-layer job spreads its points on the offset by k·h, the top of the
//! layer below).
//!
//! With P = (x, z)(u), s = |P′|, the unit normal n = (−z′, x′)/s (as [`super::platform::normal`])
//! and the signed curvature κ = (x′z″ − z′x″)/s³, dn/du = −κ·P′, so P_o = P + h·n has
//! P_o′ = (1 − hκ)P′, P_o″ = (1 − hκ)P″ − hκ′P′, P_o‴ = (1 − hκ)P‴ − 2hκ′P″ − hκ″P′
//! (κ″ from the base's exact fourth derivatives). The offset shares u and the knots with its
//! base, and its normal is the base's wherever 1 − hκ > 0. Where 1 − hκ reaches 0 (the height
//! reaches the radius of curvature of a concave bend) the offset folds into a cusp:
//! [`Offset::new`] refuses well before that.

use super::platform::{curvature_of, Jet, Profile, Profile4};
use super::Error;

/// Default smallest stretch 1 − hκ of the offset's meridian against its base: below 0.2 the
/// offset's radius of curvature is under a fifth of the base's and a fold (at 0) is close.
pub const DEFAULT_MIN_STRETCH: f64 = 0.2;
/// Samples per unit u of the fold and pole checks (a Bézier segment spans one unit).
pub const CHECK_SAMPLES_PER_U: f64 = 256.0;

/// `base` offset by `h` mm along its unit normal.
#[derive(Clone, Copy, Debug)]
pub struct Offset<'a, P: ?Sized> {
    base: &'a P,
    h: f64,
}

impl<'a, P: Profile4 + ?Sized> Offset<'a, P> {
    /// The offset by `h_mm`, refused where, for u in `span` (the part of the profile a domain
    /// uses), it folds (1 − hκ < [`DEFAULT_MIN_STRETCH`]) or comes nearer than `min_radius_mm`
    /// to the axis; the error gives the largest height allowed over `span`.
    pub fn new(base: &'a P, h_mm: f64, span: [f64; 2], min_radius_mm: f64) -> Result<Self, Error> {
        if !h_mm.is_finite() {
            return Err(Error::BadOption { name: "offset height", value: h_mm, hint: "a finite height in mm" });
        }
        let o = Offset { base, h: h_mm };
        // The largest height allowed (a second pass) is only needed for a refusal's message.
        let max_height_mm = || largest_height(base, span, min_radius_mm);
        for u in samples(base, span) {
            let j = base.jet(u);
            if j.x[0] < min_radius_mm {
                // The pole region: the domain's own check names it.
                continue;
            }
            let k = curvature_of(&j);
            if !(1.0 - h_mm * k >= DEFAULT_MIN_STRETCH) {
                return Err(Error::OffsetFolds { height_mm: h_mm, u, radius_of_curvature_mm: 1.0 / k, max_height_mm: max_height_mm() });
            }
            // The offset radius x − h·z′/s (what `jet` gives as x[0], without its derivatives).
            let r = j.x[0] - h_mm * j.z[1] / (j.x[1] * j.x[1] + j.z[1] * j.z[1]).sqrt();
            if !(r >= min_radius_mm) {
                return Err(Error::OffsetNearPole { height_mm: h_mm, u, radius_mm: r, min_radius_mm, max_height_mm: max_height_mm() });
            }
        }
        Ok(o)
    }
}

impl<P: ?Sized> Offset<'_, P> {
    /// The offset distance, mm.
    pub fn height_mm(&self) -> f64 {
        self.h
    }
}

fn samples<P: Profile + ?Sized>(p: &P, span: [f64; 2]) -> impl Iterator<Item = f64> {
    let (lo, hi) = p.u_range();
    let (a, b) = (span[0].max(lo), span[1].min(hi));
    // A NaN span gives no samples (the domain's own check refuses it).
    let n = if b >= a { ((b - a) * CHECK_SAMPLES_PER_U).ceil().clamp(1.0, 1e6) as usize } else { 0 };
    (0..=n).filter(move |_| b >= a).map(move |i| a + (b - a) * i as f64 / n as f64)
}

/// The largest outward offset (≥ 0, mm) of `base` that neither folds nor comes nearer than
/// `min_radius_mm` to the axis for u in `span` (∞ when nothing limits it).
pub fn largest_height<P: Profile + ?Sized>(base: &P, span: [f64; 2], min_radius_mm: f64) -> f64 {
    let mut best = f64::INFINITY;
    for u in samples(base, span) {
        let j = base.jet(u);
        if j.x[0] < min_radius_mm {
            continue;
        }
        let k = curvature_of(&j);
        if k > 0.0 {
            best = best.min((1.0 - DEFAULT_MIN_STRETCH) / k);
        }
        // The radius moves by h·(−z′/s): inward when z′ > 0.
        let s = libm::hypot(j.x[1], j.z[1]);
        let dr = -j.z[1] / s;
        if dr < 0.0 {
            best = best.min((j.x[0] - min_radius_mm) / -dr);
        }
    }
    best.max(0.0)
}

impl<P: Profile4 + ?Sized> Profile for Offset<'_, P> {
    fn u_range(&self) -> (f64, f64) {
        self.base.u_range()
    }

    fn jet(&self, u: f64) -> Jet {
        let j = self.base.jet(u);
        let [x4, z4] = self.base.fourth(u);
        let ([x0, x1, x2, x3], [z0, z1, z2, z3]) = (j.x, j.z);
        let h = self.h;
        // κ = c·q^(−3/2) with q = s², c = x′z″ − z′x″, differentiated twice.
        let q = x1 * x1 + z1 * z1;
        let s = q.sqrt();
        let q32 = q * s;
        let (c, c1, c2) = (x1 * z2 - z1 * x2, x1 * z3 - z1 * x3, x2 * z3 + x1 * z4 - z2 * x3 - z1 * x4);
        let (q1, q2) = (2.0 * (x1 * x2 + z1 * z2), 2.0 * (x2 * x2 + x1 * x3 + z2 * z2 + z1 * z3));
        let k = c / q32;
        let k1 = c1 / q32 - 1.5 * c * q1 / (q32 * q);
        let k2 = c2 / q32 - 3.0 * c1 * q1 / (q32 * q) + 3.75 * c * q1 * q1 / (q32 * q * q) - 1.5 * c * q2 / (q32 * q);
        let a = 1.0 - h * k;
        Jet {
            x: [x0 - h * z1 / s, a * x1, a * x2 - h * k1 * x1, a * x3 - 2.0 * h * k1 * x2 - h * k2 * x1],
            z: [z0 + h * x1 / s, a * z1, a * z2 - h * k1 * z1, a * z3 - 2.0 * h * k1 * z2 - h * k2 * z1],
        }
    }

    fn knots_between(&self, lo: f64, hi: f64, out: &mut Vec<f64>) {
        self.base.knots_between(lo, hi, out)
    }

    fn radius_turns(&self, lo: f64, hi: f64, out: &mut Vec<f64>) {
        // x_o′ = (1 − hκ)·x′ and 1 − hκ > 0 where the offset is used: the same roots.
        self.base.radius_turns(lo, hi, out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::axisym::geodesic::{self, geodesic};
    use crate::axisym::platform::{Platform, DEFAULT_MIN_POLE_RADIUS_MM};
    use std::f64::consts::PI;

    /// A sphere of radius r about the origin, generatrix from the top pole (u = 0) to the
    /// bottom one (u = 1): x = r·sin πu, z = r·cos πu.
    struct Sphere(f64);
    impl Profile for Sphere {
        fn u_range(&self) -> (f64, f64) {
            (0.0, 1.0)
        }
        fn jet(&self, u: f64) -> Jet {
            let f = |k: usize, phase: f64| self.0 * PI.powi(k as i32) * libm::sin(PI * u + phase + k as f64 * PI / 2.0);
            Jet { x: std::array::from_fn(|k| f(k, 0.0)), z: std::array::from_fn(|k| f(k, PI / 2.0)) }
        }
    }
    impl Profile4 for Sphere {
        fn fourth(&self, u: f64) -> [f64; 2] {
            let p4 = PI.powi(4) * self.0;
            [p4 * libm::sin(PI * u), p4 * libm::cos(PI * u)]
        }
    }

    fn close(a: &Jet, b: &Jet, tol: f64) -> bool {
        (0..4).all(|k| (a.x[k] - b.x[k]).abs() <= tol * (1.0 + b.x[k].abs()) && (a.z[k] - b.z[k]).abs() <= tol * (1.0 + b.z[k].abs()))
    }

    #[test]
    fn offset_sphere_and_cylinder_are_the_analytic_ones() {
        let (r, h) = (20.0, 1.5);
        let base = Sphere(r);
        let o = Offset::new(&base, h, [0.0, 1.0], DEFAULT_MIN_POLE_RADIUS_MM).unwrap();
        for &u in &[0.05, 0.2, 0.37, 0.5, 0.81, 0.95] {
            let (a, b) = (o.jet(u), Sphere(r + h).jet(u));
            assert!(close(&a, &b, 1e-9), "u {u}: {a:?} vs {b:?}");
        }
        // A Bézier cylinder of radius 20 (z = 60 − 30u): the offset is the radius-22 one.
        let pts: Vec<[f64; 2]> = (0..13).map(|i| [20.0, 60.0 - 5.0 * i as f64]).collect();
        let cyl = Platform::from_polygon(&pts).unwrap();
        let o = Offset::new(&cyl, 2.0, [0.0, 2.0], DEFAULT_MIN_POLE_RADIUS_MM).unwrap();
        for &u in &[0.0, 0.3, 1.0, 1.7, 2.0] {
            let j = o.jet(u);
            let want = Jet { x: [22.0, 0.0, 0.0, 0.0], z: [60.0 - 30.0 * u, -30.0, 0.0, 0.0] };
            assert!(close(&j, &want, 1e-12), "u {u}: {j:?}");
        }
        // Geodesics on the offset cylinder are straight in the unrolled plane: √(Δz² + (R·Δθ)²).
        for (a, b) in [([0.5, 0.1], [1.4, 0.9]), ([0.2, -0.5], [1.8, 0.4]), ([1.0, 0.0], [1.0, 1.2])] {
            let g = geodesic(&o, a, b, &geodesic::Options::default()).unwrap();
            let want = libm::hypot(30.0 * (b[0] - a[0]), 22.0 * (b[1] - a[1]));
            assert!((g.length_mm - want).abs() < 1e-6, "{a:?} → {b:?}: {} vs {want}", g.length_mm);
        }
    }

    #[test]
    fn hourglass_offset_is_a_parallel_curve_with_consistent_derivatives() {
        let p = Platform::hourglass();
        let h = 0.6;
        let o = Offset::new(&p, h, [0.5, 3.5], DEFAULT_MIN_POLE_RADIUS_MM).unwrap();
        for &u in &[0.6, 1.2, 1.9, 2.0, 2.4, 3.3] {
            let (b, j) = (p.jet(u), o.jet(u));
            // h away from the base along its normal, tangent parallel to the base's.
            assert!((libm::hypot(j.x[0] - b.x[0], j.z[0] - b.z[0]) - h).abs() < 1e-12);
            assert!((j.x[1] * b.z[1] - j.z[1] * b.x[1]).abs() < 1e-9 * (1.0 + b.x[1].abs() + b.z[1].abs()).powi(2));
            // Derivatives against central differences of the order below (away from knots,
            // where the third derivative of a C³ spline is only continuous).
            if u.fract() != 0.0 {
                let d = 1e-5;
                let (jp, jm) = (o.jet(u + d), o.jet(u - d));
                for r in 0..3 {
                    let fx = (jp.x[r] - jm.x[r]) / (2.0 * d);
                    let fz = (jp.z[r] - jm.z[r]) / (2.0 * d);
                    assert!((fx - j.x[r + 1]).abs() < 1e-4 * (1.0 + j.x[r + 1].abs()), "u {u} order {r}: {fx} vs {}", j.x[r + 1]);
                    assert!((fz - j.z[r + 1]).abs() < 1e-4 * (1.0 + j.z[r + 1].abs()), "u {u} order {r}: {fz} vs {}", j.z[r + 1]);
                }
            }
        }
    }

    #[test]
    fn a_folding_offset_is_refused_with_the_largest_height() {
        // The hourglass neck is concave: an offset reaching its radius of curvature folds.
        let p = Platform::hourglass();
        let span = [1.0, 3.0];
        let max = largest_height(&p, span, DEFAULT_MIN_POLE_RADIUS_MM);
        eprintln!("hourglass u ∈ [1, 3]: largest offset {max:.4} mm");
        assert!(max.is_finite() && max > 1.0);
        assert!(Offset::new(&p, 0.99 * max, span, DEFAULT_MIN_POLE_RADIUS_MM).is_ok());
        let e = Offset::new(&p, 1.05 * max, span, DEFAULT_MIN_POLE_RADIUS_MM).unwrap_err();
        assert!(matches!(e, Error::OffsetFolds { max_height_mm, .. } if max_height_mm == max), "{e}");
        eprintln!("{e}");
        // The convex barrel never folds outward.
        assert_eq!(largest_height(&Platform::barrel(), [0.8, 1.2], DEFAULT_MIN_POLE_RADIUS_MM), f64::INFINITY);
        assert!(matches!(Offset::new(&p, f64::NAN, span, 1.0), Err(Error::BadOption { .. })));
    }
}

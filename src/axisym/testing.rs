//! Exact answers the axisym unit tests compare with.

use super::platform::{Jet, Profile};
use std::f64::consts::PI;

/// Exact sphere of radius R: u = colatitude (rad), x = R sin u, z = R cos u.
pub(crate) struct Sphere(pub f64);

impl Profile for Sphere {
    fn u_range(&self) -> (f64, f64) {
        (0.0, PI)
    }
    fn jet(&self, u: f64) -> Jet {
        let (s, c, r) = (libm::sin(u), libm::cos(u), self.0);
        Jet { x: [r * s, r * c, -r * s, -r * c], z: [r * c, -r * s, -r * c, r * s] }
    }
}

/// Great-circle distance on a sphere of radius `r` between (colatitude, longitude) points, in
/// Vincenty's form (well conditioned at all distances).
pub(crate) fn great_circle(r: f64, a: [f64; 2], b: [f64; 2]) -> f64 {
    let (p1, p2) = (PI / 2.0 - a[0], PI / 2.0 - b[0]);
    let dl = b[1] - a[1];
    let y = ((libm::cos(p2) * libm::sin(dl)).powi(2) + (libm::cos(p1) * libm::sin(p2) - libm::sin(p1) * libm::cos(p2) * libm::cos(dl)).powi(2)).sqrt();
    let x = libm::sin(p1) * libm::sin(p2) + libm::cos(p1) * libm::cos(p2) * libm::cos(dl);
    r * libm::atan2(y, x)
}

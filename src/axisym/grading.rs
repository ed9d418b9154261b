//! Graded command density (the paper's future work, issue 10 "beyond the paper" item 2): a
//! density ρ(q) that varies over Ω instead of the constant ρ_c, its target spacing
//! s(q) = n·e/ρ(q) and point count N = ∫_Ω ρ² dA / (n²e²) (equation (4) with ρ under the
//! integral: equation (4) per area element).
//!
//! ρ runs from the command density ρ_c (the stage's `density`) to `density_to`, linearly in
//! one coordinate: u or θ across Ω's bounding box, or the geodesic distance r from a centre
//! (ρ_c at the centre, `density_to` from `radius_mm` on). Linear in the coordinate, not in the
//! spacing: a linear ρ is what a user sweeping "density" reads.

use super::domain::{simpson, Domain};
use super::surface::{Node, Surface};

/// Default density at the far end of the grading (fraction; half the default ρ_c).
pub const DEFAULT_DENSITY_TO: f64 = 0.25;
/// Default centre of a radial grading, u.
pub const DEFAULT_CENTRE_U: f64 = 1.0;
/// Default centre of a radial grading, θ (rad): the middle of the default Ω1.
pub const DEFAULT_CENTRE_THETA_RAD: f64 = 0.5;
/// Default radius of a radial grading: the geodesic distance over which ρ goes from ρ_c to
/// `density_to`, mm.
pub const DEFAULT_RADIUS_MM: f64 = 10.0;
/// Relative tolerance of the ∫ρ² dA quadrature (N is rounded to a whole point: 1e-7 of a few
/// thousand points is far below the rounding).
pub const INTEGRAL_REL_TOL: f64 = 1e-7;

/// The coordinate ρ varies along.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Along {
    /// Linear in u: ρ_c at Ω's lowest u, `density_to` at its highest.
    #[default]
    U,
    /// Linear in θ: ρ_c at Ω's lowest θ, `density_to` at its highest.
    Theta,
    /// Linear in the geodesic distance from (`centre_u`, `centre_theta_rad`): ρ_c there,
    /// `density_to` at `radius_mm` and beyond.
    Radial,
}

/// A graded density (the optional `grading` block of the points options; absent: uniform).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Grading {
    /// Which coordinate ρ varies along ([`Along::U`]).
    pub along: Along,
    /// ρ at the far end, fraction in (0, 1] ([`DEFAULT_DENSITY_TO`]).
    pub density_to: f64,
    /// Radial: centre u ([`DEFAULT_CENTRE_U`]).
    pub centre_u: f64,
    /// Radial: centre θ, rad ([`DEFAULT_CENTRE_THETA_RAD`]).
    pub centre_theta_rad: f64,
    /// Radial: geodesic distance from ρ_c to `density_to`, mm ([`DEFAULT_RADIUS_MM`]).
    pub radius_mm: f64,
}

impl Default for Grading {
    fn default() -> Self {
        Grading {
            along: Along::U,
            density_to: DEFAULT_DENSITY_TO,
            centre_u: DEFAULT_CENTRE_U,
            centre_theta_rad: DEFAULT_CENTRE_THETA_RAD,
            radius_mm: DEFAULT_RADIUS_MM,
        }
    }
}

/// The density field of one run: ρ(q), its gradient and s(q), fixed to Ω's bounding box.
#[derive(Clone, Debug)]
pub struct Field {
    along: Along,
    rho0: f64,
    rho1: f64,
    /// Coordinate range: [u or θ at ρ0, at ρ1], or [0, R] for radial.
    range: [f64; 2],
    centre: Option<Node>,
    /// n·e, mm.
    ne: f64,
}

impl Field {
    /// The field for command density `rho_c`, `g`, on Ω = `domain`, n·e = `ne` mm. The
    /// options must have been checked (finite, densities in (0, 1], radius > 0).
    pub fn new(s: &Surface, domain: &Domain, g: &Grading, rho_c: f64, ne: f64) -> Field {
        let b = domain.bounds();
        let (range, centre) = match g.along {
            Along::U => ([b[0][0], b[1][0]], None),
            Along::Theta => ([b[0][1], b[1][1]], None),
            Along::Radial => ([0.0, g.radius_mm], Some(s.node([g.centre_u, g.centre_theta_rad]))),
        };
        Field { along: g.along, rho0: rho_c, rho1: g.density_to, range, centre, ne }
    }

    /// The grading coordinate of a point: u, θ (rad) or the geodesic distance r (mm).
    pub fn coordinate(&self, s: &Surface, n: &Node) -> f64 {
        match self.along {
            Along::U => n.q[0],
            Along::Theta => n.q[1],
            Along::Radial => self.centre.as_ref().map_or(0.0, |c| s.pair(n, c).0),
        }
    }

    /// (name, unit) of the coordinate, for plots.
    pub fn coordinate_label(&self) -> (&'static str, &'static str) {
        match self.along {
            Along::U => ("u", ""),
            Along::Theta => ("θ", "rad"),
            Along::Radial => ("Distance from the centre", "mm"),
        }
    }

    /// The coordinate span [ρ_c end, far end] (radial: [0, R]).
    pub fn range(&self) -> [f64; 2] {
        self.range
    }

    /// ρ at coordinate value c (clamped to the range).
    pub fn density_at(&self, c: f64) -> f64 {
        let w = self.range[1] - self.range[0];
        let t = if w > 0.0 { ((c - self.range[0]) / w).clamp(0.0, 1.0) } else { 0.0 };
        self.rho0 + t * (self.rho1 - self.rho0)
    }

    /// ρ at a node.
    pub fn density(&self, s: &Surface, n: &Node) -> f64 {
        self.density_at(self.coordinate(s, n))
    }

    /// (ρ, ∂ρ/∂(u, θ)) at a node (a covector; zero where ρ is clamped).
    pub fn density_gradient(&self, s: &Surface, n: &Node) -> (f64, [f64; 2]) {
        let w = self.range[1] - self.range[0];
        let slope = if w > 0.0 { (self.rho1 - self.rho0) / w } else { 0.0 };
        let (c, dc) = match self.along {
            Along::U => (n.q[0], [1.0, 0.0]),
            Along::Theta => (n.q[1], [0.0, 1.0]),
            Along::Radial => self.centre.as_ref().map_or((0.0, [0.0; 2]), |c| {
                let (d, g, _) = s.pair(n, c);
                (d, g)
            }),
        };
        let inside = c > self.range[0] && c < self.range[1];
        let k = if inside { slope } else { 0.0 };
        (self.density_at(c), [k * dc[0], k * dc[1]])
    }

    /// Target spacing s = n·e/ρ, mm.
    pub fn spacing_of(&self, rho: f64) -> f64 {
        self.ne / rho
    }

    /// Smallest and largest ρ over the field.
    pub fn density_bounds(&self) -> [f64; 2] {
        [self.rho0.min(self.rho1), self.rho0.max(self.rho1)]
    }

    /// ∫_D ρ² dA over `domain` (any part of the platform, e.g. a third of Ω), mm²: adaptive
    /// Simpson in u between the vertex u values of the outline and holes (x·√g_uu times the θ integral); the
    /// θ integral is exact for u and θ gradings (ρ constant or linear in θ) and adaptive
    /// Simpson for the radial one.
    pub fn integral_rho2(&self, s: &Surface, domain: &Domain) -> f64 {
        let p = s.profile();
        let theta_part = |u: f64| -> f64 {
            let mut sum = 0.0;
            for [a, b] in domain.theta_intervals(u) {
                sum += match self.along {
                    Along::U => {
                        let r = self.density_at(u);
                        r * r * (b - a)
                    }
                    Along::Theta => {
                        // ρ linear on [a, b] (inside the range): ∫ρ² = (b − a)(ρa² + ρaρb + ρb²)/3.
                        let (ra, rb) = (self.density_at(a), self.density_at(b));
                        (b - a) * (ra * ra + ra * rb + rb * rb) / 3.0
                    }
                    Along::Radial => {
                        let f = |t: f64| {
                            let r = self.density(s, &s.node([u, t]));
                            r * r
                        };
                        simpson(&f, a, b, INTEGRAL_REL_TOL)
                    }
                };
            }
            sum
        };
        let f = |u: f64| {
            let j = p.jet(u);
            j.x[0] * libm::hypot(j.x[1], j.z[1]) * theta_part(u)
        };
        domain.integrate_u(&f, INTEGRAL_REL_TOL)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::axisym::platform::Platform;

    /// Cylinder R = 20 mm, z = 60 − 30u: x·√g_uu = 600 mm² per unit u per rad.
    fn cylinder() -> Platform {
        let pts: Vec<[f64; 2]> = (0..13).map(|i| [20.0, 60.0 - 5.0 * i as f64]).collect();
        Platform::from_polygon(&pts).unwrap()
    }

    #[test]
    fn integral_matches_hand_values_on_a_cylinder() {
        let p = cylinder();
        let s = Surface::new(&p);
        let d = Domain::Rectangle { u: [0.5, 1.5], theta: [0.0, 0.8] };
        // Linear in u or θ from 0.6 to 0.3: A·(a² + ab + b²)/3 = 480·0.21 = 100.8 mm².
        for along in [Along::U, Along::Theta] {
            let f = Field::new(&s, &d, &Grading { along, density_to: 0.3, ..Grading::default() }, 0.6, 0.4);
            let i = f.integral_rho2(&s, &d);
            assert!((i - 100.8).abs() < 1e-6 * 100.8, "{along:?}: {i}");
        }
        // Radial, R = 5 mm about the middle (a disc well inside the 30 × 16 mm patch; the
        // cylinder unrolls, so geodesic distance is planar): 2πR²[a²/2 + 2a(b − a)/3 + (b − a)²/4]
        // inside plus b²(A − πR²) outside.
        let (a, b, r) = (0.6, 0.3, 5.0);
        let g = Grading { along: Along::Radial, density_to: b, centre_u: 1.0, centre_theta_rad: 0.4, radius_mm: r };
        let f = Field::new(&s, &d, &g, a, 0.4);
        let pi = std::f64::consts::PI;
        let want = 2.0 * pi * r * r * (a * a / 2.0 + 2.0 * a * (b - a) / 3.0 + (b - a) * (b - a) / 4.0) + b * b * (480.0 - pi * r * r);
        let i = f.integral_rho2(&s, &d);
        assert!((i - want).abs() < 1e-4 * want, "radial: {i} vs {want}");
        // The gradient of ρ: radial, halfway out along u (30 mm per unit u).
        let n = s.node([1.0 + 2.5 / 30.0, 0.4]);
        let (rho, g) = f.density_gradient(&s, &n);
        assert!((rho - 0.45).abs() < 1e-6, "{rho}");
        assert!((g[0] - 30.0 * (b - a) / r).abs() < 1e-3 && g[1].abs() < 1e-6, "{g:?}");
    }
}

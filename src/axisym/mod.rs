//! Axisymmetric build platforms (groundwork for issue 10, job kind `axisymmetric`).
//!
//! The geometry behind job kind `axisymmetric` ([`crate::kinds::axisymmetric`]); each stage is a
//! pure function of its inputs.
//!
//! - [`platform`]: the generatrix, a composition of degree-6 Bézier segments in the (x = radius,
//!   z = height) half-plane, revolved about z into the embedded map r(u, θ); its metric,
//!   Christoffel symbols, curvature, normal and validation (C³ at knots, cusps,
//!   self-intersections, radius > 0, pole clearance).
//! - [`contour`]: where a part meets the (offset) platform, as closed (u, θ) polygons: the
//!   paper's domain Ω₂ (marching triangles on the signed distance to the surface).
//! - [`geodesic`]: shortest paths between two (u, θ) points on any [`platform::Profile`]:
//!   Clairaut shooting first, Runge–Kutta shooting as the fallback.
//! - [`grading`]: a command density that varies over Ω (linear in u, θ or the geodesic
//!   distance from a centre), its local spacing and N = ∫ρ² dA/(n²e²) (the paper's future work).
//! - [`offset`]: the platform offset along its normal (the surface a higher layer lies on),
//!   exact to the third derivative, refused where it would fold.
//! - [`tour`]: the infill path through given (u, θ) points (nearest neighbour + 2-opt, no
//!   crossings in the map), sampled along geodesics into tool poses.
//! - [`dynamics`]: the tool axis smoothed within a tilt for the rotary axes, and their speed
//!   and acceleration at a feed.
//!
//! Units: millimetres, radians. Deterministic: transcendentals through `libm`, no hash maps.

// `!(x > 0.0)` is deliberate throughout: a NaN must fail every check it reaches.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod clairaut;
pub mod contour;
pub mod domain;
pub mod dynamics;
pub mod geodesic;
pub mod grading;
pub mod metrics;
pub mod offset;
pub mod platform;
pub mod surface;
#[cfg(test)]
mod testing;
pub mod tour;
pub mod uniform;

pub use geodesic::{geodesic, Geodesic, Method};
pub use platform::{Platform, Problem, Profile};

/// Why a platform or geodesic could not be built.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum Error {
    /// The control polygon is not 6·k + 1 points.
    #[error("the control polygon has {points} points but needs 6·k + 1 (k ≥ 1 degree-6 segments, each next one starting at the previous one's last point): add or remove points")]
    BadPolygonLength {
        /// Points given.
        points: usize,
    },
    /// A control point is NaN or infinite.
    #[error("control point {index} of segment {segment} is not a finite number; enter x and z in mm")]
    NotFinite {
        /// Segment index (0-based).
        segment: usize,
        /// Point index in the segment (0..=6).
        index: usize,
    },
    /// Validation found problems (all of them listed).
    #[error("the generatrix is not a usable build platform:\n{}", describe(problems))]
    Invalid {
        /// Every problem found.
        problems: Vec<Problem>,
    },
    /// A point or domain comes closer to the axis than the metric can be trusted.
    #[error("u = {u:.6} lies {radius_mm:.4} mm from the axis, closer than the {min_radius_mm} mm a domain must keep from the pole (the Christoffel symbol Γ^θ_uθ = x′/x grows without bound there); keep u within [{u_allowed_min:.6}, {u_allowed_max:.6}] on this platform")]
    TooNearPole {
        /// Offending u.
        u: f64,
        /// Radius there, mm.
        radius_mm: f64,
        /// Minimum radius required, mm.
        min_radius_mm: f64,
        /// Smallest u keeping the minimum radius.
        u_allowed_min: f64,
        /// Largest u keeping the minimum radius.
        u_allowed_max: f64,
    },
    /// A point lies outside the generatrix parameter range.
    #[error("u = {u} is outside the generatrix parameter range [{u_min}, {u_max}]; pick u inside it")]
    OutOfRange {
        /// Offending u.
        u: f64,
        /// Range start.
        u_min: f64,
        /// Range end.
        u_max: f64,
    },
    /// The Clairaut solver does not handle this pair (only when [`Method::Clairaut`] is
    /// forced; `Auto` falls back to the ODE shooter).
    #[error("the Clairaut solver does not handle the geodesic from u = {u0} to u = {u1} (both ends on a parallel where x′ = 0, or more than one critical point of the radius between them); use Method::Auto or Method::Ode")]
    TurningPoint {
        /// Start u.
        u0: f64,
        /// End u.
        u1: f64,
    },
    /// The shooting did not converge.
    #[error("the geodesic shooting from (u, θ) = ({u0}, {t0}) to ({u1}, {t1}) did not converge (residual {residual_mm:.3e} mm): the points may be too far apart or the path runs near a pole; split the segment or raise max_iterations")]
    NoConvergence {
        /// Start u.
        u0: f64,
        /// Start θ.
        t0: f64,
        /// End u.
        u1: f64,
        /// End θ.
        t1: f64,
        /// Remaining miss, mm.
        residual_mm: f64,
    },
    /// An offset surface would fold (its height reaches a concave bend's radius of curvature).
    #[error("the platform offset by {height_mm} mm folds near u = {u:.5}, where a concave bend has a radius of curvature of {radius_of_curvature_mm:.3} mm: the offset must stay well under it; offsets up to {max_height_mm:.4} mm are allowed over the domain, so use fewer layers or a smaller layer height")]
    OffsetFolds {
        /// Offset asked for, mm.
        height_mm: f64,
        /// Where it folds.
        u: f64,
        /// 1/κ there, mm.
        radius_of_curvature_mm: f64,
        /// Largest offset allowed over the domain's u span, mm.
        max_height_mm: f64,
    },
    /// An offset surface comes too near the axis.
    #[error("the platform offset by {height_mm} mm comes within {radius_mm:.4} mm of the axis at u = {u:.5} (at least {min_radius_mm} mm needed, the metric degenerates at the pole); offsets up to {max_height_mm:.4} mm are allowed over the domain, so use fewer layers or a smaller layer height")]
    OffsetNearPole {
        /// Offset asked for, mm.
        height_mm: f64,
        /// Where.
        u: f64,
        /// The offset's radius there, mm.
        radius_mm: f64,
        /// Minimum radius, mm.
        min_radius_mm: f64,
        /// Largest offset allowed over the domain's u span, mm.
        max_height_mm: f64,
    },
    /// Options out of range.
    #[error("option {name} = {value} is out of range: {hint}")]
    BadOption {
        /// Option name.
        name: &'static str,
        /// Value given.
        value: f64,
        /// Allowed range.
        hint: &'static str,
    },
}

fn describe(problems: &[Problem]) -> String {
    problems.iter().map(|p| format!("- {p}")).collect::<Vec<_>>().join("\n")
}

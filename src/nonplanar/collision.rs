//! Collision check: a straight nozzle move must not dip into the surface or the layer beneath.

use super::surface::Caster;
use crate::geom::DVec3;

/// How far a move may dip below the layer beneath before it counts as a collision, mm (1 µm).
pub(crate) const TOLERANCE_MM: f64 = 1e-3;

/// Signed height of `m` above the surface offset by `d` mm along its normal (negative: below),
/// or `None` where the vertical ray at `m` misses the surface (nothing to collide with).
///
/// Spheres and cylinders are exact (distance to the centre or axis minus radius and offset);
/// meshes use the tangent plane of the offset surface at the vertical projection of `m`.
pub(crate) fn clearance(caster: &Caster, m: DVec3, d: f64) -> Option<f64> {
    let hit = caster.cast(m.x, m.y)?;
    Some(match caster {
        Caster::Sphere { center, radius } => (m - *center).length() - (radius + d),
        Caster::Cylinder { radius, axis_z } => (m.y * m.y + (m.z - axis_z) * (m.z - axis_z)).sqrt() - (radius + d),
        Caster::Mesh(_) => (m - (hit.p + hit.n * d)).dot(hit.n),
    })
}

/// Whether the straight move `a → b` on the layer whose beneath-offset is `d_below` collides.
pub(crate) fn collides(caster: &Caster, a: DVec3, b: DVec3, d_below: f64) -> bool {
    clearance(caster, (a + b) * 0.5, d_below).is_some_and(|c| c < -TOLERANCE_MM)
}

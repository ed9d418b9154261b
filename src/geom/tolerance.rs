//! Tolerances and the integer micrometre grid used for 2D booleans.

/// Integer units per millimetre for clipping and offsetting (1 unit = 1 µm).
pub const UNITS_PER_MM: f64 = 1000.0;

/// Default distance under which two points are the same point, in mm.
pub const DEFAULT_TOLERANCE_MM: f64 = 1e-3;

/// Millimetres → integer micrometres (rounded to nearest).
#[inline]
pub fn to_um(mm: f64) -> i32 {
    (mm * UNITS_PER_MM).round() as i32
}

/// Integer micrometres → millimetres.
#[inline]
pub fn from_um(um: i32) -> f64 {
    um as f64 / UNITS_PER_MM
}

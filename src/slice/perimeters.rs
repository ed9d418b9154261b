//! Inward offsets (perimeter centre lines and the infill area) with i_overlay's integer
//! outline builder (deterministic integer construction math).

use i_overlay::i_float::int::angle::Angle;
use i_overlay::i_shape::int::shape::{IntShape, IntShapes};
use i_overlay::mesh::int::outline::offset::IntOutlineOffset;
use i_overlay::mesh::int::style::{IntLineJoin, IntOutlineStyle};

/// Shrinks `shapes` by `d_um` micrometres (miter joins, corners sharper than 22.5° clipped).
/// `d_um <= 0` returns the input unchanged.
pub(crate) fn inset(shapes: &[IntShape<i32>], d_um: i32) -> IntShapes<i32> {
    if d_um <= 0 {
        return shapes.to_vec();
    }
    if shapes.is_empty() {
        return Vec::new();
    }
    let style = IntOutlineStyle::new(-d_um).line_join(IntLineJoin::Miter(Angle::from_bits(1 << 28)));
    let mut out = shapes.outline(&style).unwrap_or_default();
    super::regions::sort_shapes(&mut out);
    out
}

/// Grows `shapes` by `d_um` micrometres (miter joins). `d_um <= 0` returns the input unchanged.
pub(crate) fn outset(shapes: &[IntShape<i32>], d_um: i32) -> IntShapes<i32> {
    if d_um <= 0 || shapes.is_empty() {
        return shapes.to_vec();
    }
    let style = IntOutlineStyle::new(d_um).line_join(IntLineJoin::Miter(Angle::from_bits(1 << 28)));
    let mut out = shapes.outline(&style).unwrap_or_default();
    super::regions::sort_shapes(&mut out);
    out
}

/// Perimeter centre lines of one region: level 0 is the external perimeter (inset by
/// `width / 2`), level `k` is inset by another `k × width`. Each level is a list of shapes
/// (an inset may split a region in parts, or vanish).
pub(crate) fn perimeter_levels(region: &IntShape<i32>, count: u32, width_um: i32) -> Vec<IntShapes<i32>> {
    let one = std::slice::from_ref(region);
    let mut levels = Vec::new();
    for k in 0..count as i64 {
        let d = width_um as i64 / 2 + k * width_um as i64;
        let shapes = inset(one, d.min(i32::MAX as i64) as i32);
        if shapes.is_empty() {
            break;
        }
        levels.push(shapes);
    }
    levels
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::slice::regions::shapes_area2;
    use i_overlay::i_float::int::point::IntPoint;

    #[test]
    fn square_insets() {
        let sq: IntShape<i32> = vec![vec![IntPoint::new(0, 0), IntPoint::new(10_000, 0), IntPoint::new(10_000, 10_000), IntPoint::new(0, 10_000)]];
        let levels = perimeter_levels(&sq, 3, 400);
        assert_eq!(levels.len(), 3);
        // 10 mm − 2 × 0.2 mm, then − 2 × 0.6 mm, − 2 × 1.0 mm.
        for (k, side) in [9_600i64, 8_800, 8_000].iter().enumerate() {
            assert_eq!(shapes_area2(&levels[k]), 2 * side * side, "level {k}");
        }
        // A too-thin region loses its inner levels.
        let thin: IntShape<i32> = vec![vec![IntPoint::new(0, 0), IntPoint::new(10_000, 0), IntPoint::new(10_000, 1_300), IntPoint::new(0, 1_300)]];
        assert_eq!(perimeter_levels(&thin, 3, 400).len(), 2);
    }
}

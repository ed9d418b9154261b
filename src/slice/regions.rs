//! Loops → regions (polygons with holes) by an i_overlay union under the NonZero fill rule.
//!
//! The loops' orientation comes from the triangle winding (solid on the left), so outer
//! boundaries are CCW and holes CW; NonZero then unions overlapping or interpenetrating
//! shells, and also accepts a shell whose triangles all face inwards.

use super::plane::Pt;
use crate::geom::tolerance::from_um;
use crate::geom::{DVec2, Polygon};
use i_overlay::core::fill_rule::FillRule;
use i_overlay::core::overlay::Overlay;
use i_overlay::core::overlay_rule::OverlayRule;
use i_overlay::i_float::int::point::IntPoint;
use i_overlay::i_shape::int::shape::{IntContour, IntShape, IntShapes};

/// Twice the signed area of a loop, µm² (exact integer arithmetic).
pub(crate) fn area2(c: &[IntPoint<i32>]) -> i64 {
    let n = c.len();
    let mut s = 0i64;
    for i in 0..n {
        let a = c[i];
        let b = c[(i + 1) % n];
        s += a.x as i64 * b.y as i64 - b.x as i64 * a.y as i64;
    }
    s
}

/// Twice the area of shapes (outer minus holes), µm².
pub(crate) fn shapes_area2(shapes: &[IntShape<i32>]) -> i64 {
    shapes.iter().flat_map(|s| s.iter()).map(|c| area2(c)).sum()
}

/// Sorts shapes by the lowest (x, y) corner of their outer boundary's bounding box.
pub(crate) fn sort_shapes(shapes: &mut IntShapes<i32>) {
    let key = |s: &IntShape<i32>| {
        let o = &s[0];
        let mx = o.iter().map(|p| p.x).min().unwrap_or(0);
        let my = o.iter().map(|p| p.y).min().unwrap_or(0);
        (mx, my)
    };
    shapes.retain(|s| !s.is_empty() && !s[0].is_empty());
    shapes.sort_by(|a, b| key(a).cmp(&key(b)).then_with(|| a.cmp(b)));
}

/// Unions the loops. Returns the regions and whether the union shows overlapping material
/// (the loops' summed signed area exceeds the union's area by more than 0.1 % + 0.01 mm²).
pub(crate) fn union_loops(loops: &[Vec<Pt>]) -> (IntShapes<i32>, bool) {
    if loops.is_empty() {
        return (Vec::new(), false);
    }
    let contours: Vec<IntContour<i32>> = loops.iter().map(|l| l.iter().map(|p| IntPoint::new(p[0], p[1])).collect()).collect();
    let sum: i64 = contours.iter().map(|c| area2(c)).sum();
    let mut shapes = Overlay::from_subj(&contours).overlay(OverlayRule::Subject, FillRule::NonZero);
    sort_shapes(&mut shapes);
    let union = shapes_area2(&shapes);
    let overlap = sum > union + union / 1000 + 20_000;
    (shapes, overlap)
}

/// Integer shapes → `Polygon`s in mm (outer CCW, holes CW, as i_overlay outputs them).
pub(crate) fn to_polygons(shapes: &[IntShape<i32>]) -> Vec<Polygon> {
    let conv = |c: &IntContour<i32>| c.iter().map(|p| DVec2::new(from_um(p.x), from_um(p.y))).collect::<Vec<_>>();
    shapes.iter().map(|s| Polygon { outer: conv(&s[0]), holes: s[1..].iter().map(conv).collect() }).collect()
}

/// Intersection of two shape sets (NonZero).
pub(crate) fn intersect(a: &IntShapes<i32>, b: &IntShapes<i32>) -> IntShapes<i32> {
    if a.is_empty() || b.is_empty() {
        return Vec::new();
    }
    Overlay::from_subj_and_clip(a, b).overlay(OverlayRule::Intersect, FillRule::NonZero)
}

/// Difference `a − b` (NonZero).
pub(crate) fn difference(a: &IntShapes<i32>, b: &IntShapes<i32>) -> IntShapes<i32> {
    if a.is_empty() || b.is_empty() {
        return a.clone();
    }
    Overlay::from_subj_and_clip(a, b).overlay(OverlayRule::Difference, FillRule::NonZero)
}

/// Union of two shape sets (NonZero; either may be empty, and overlapping shapes within one
/// set merge too).
pub(crate) fn union(a: &IntShapes<i32>, b: &IntShapes<i32>) -> IntShapes<i32> {
    if a.is_empty() && b.is_empty() {
        return Vec::new();
    }
    let mut out = Overlay::from_subj_and_clip(a, b).overlay(OverlayRule::Union, FillRule::NonZero);
    sort_shapes(&mut out);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sq(x0: i32, y0: i32, s: i32, ccw: bool) -> Vec<Pt> {
        let mut v = vec![[x0, y0], [x0 + s, y0], [x0 + s, y0 + s], [x0, y0 + s]];
        if !ccw {
            v.reverse();
        }
        v
    }

    #[test]
    fn hole_and_overlap() {
        let (shapes, overlap) = union_loops(&[sq(0, 0, 10_000, true), sq(2_000, 2_000, 1_000, false)]);
        assert_eq!(shapes.len(), 1);
        assert_eq!(shapes[0].len(), 2);
        assert!(!overlap);
        assert_eq!(shapes_area2(&shapes), 2 * (100_000_000 - 1_000_000));

        let (shapes, overlap) = union_loops(&[sq(0, 0, 10_000, true), sq(5_000, 0, 10_000, true)]);
        assert_eq!(shapes.len(), 1);
        assert!(overlap);
        assert_eq!(shapes_area2(&shapes), 2 * 150_000_000);
        let p = to_polygons(&shapes);
        assert!((p[0].area() - 150.0).abs() < 1e-9);
    }
}

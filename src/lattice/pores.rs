//! Pore fraction of a layer: the part of the domain no strut covers, from the **area of the
//! union of the struts** (i_overlay, integer micrometres), so a joint where struts overlap is
//! counted once. Each strut segment is a rectangle `line_width` wide with flat ends, and every
//! strut point carries a regular 16-gon of diameter `line_width` (the bead's round joint),
//! all clipped to the domain.

use crate::geom::tolerance::to_um;
use crate::geom::{DVec2, Polygon, Stroke};
use i_overlay::core::fill_rule::FillRule;
use i_overlay::core::overlay::Overlay;
use i_overlay::core::overlay_rule::OverlayRule;
use i_overlay::i_float::int::point::IntPoint;
use i_overlay::i_shape::int::shape::IntContour;

/// Sides of the polygon drawn round every strut point.
const JOINT_SIDES: usize = 16;

/// Twice the signed area of a loop, µm².
fn area2(c: &[IntPoint<i32>]) -> i64 {
    let n = c.len();
    (0..n)
        .map(|i| {
            let (a, b) = (c[i], c[(i + 1) % n]);
            a.x as i64 * b.y as i64 - b.x as i64 * a.y as i64
        })
        .sum()
}

fn ip(p: DVec2) -> IntPoint<i32> {
    IntPoint::new(to_um(p.x), to_um(p.y))
}

/// A ring as a contour turning the given way (counter-clockwise when `ccw`).
fn ring(points: &[DVec2], ccw: bool) -> IntContour<i32> {
    let mut c: IntContour<i32> = points.iter().map(|p| ip(*p)).collect();
    if (area2(&c) > 0) != ccw {
        c.reverse();
    }
    c
}

/// Covered area of `struts` (each `line_width` wide) inside `regions`, mm².
pub(crate) fn covered_area(regions: &[Polygon], struts: &[Stroke], line_width: f64) -> f64 {
    let h = line_width / 2.0;
    let mut subj: Vec<IntContour<i32>> = Vec::new();
    // Table of the joint polygon's corners (exact, deterministic: no platform trig).
    let corners: Vec<DVec2> = (0..JOINT_SIDES)
        .map(|k| {
            let a = 2.0 * std::f64::consts::PI * k as f64 / JOINT_SIDES as f64;
            DVec2::new(libm::cos(a), libm::sin(a)) * h
        })
        .collect();
    for s in struts {
        for w in s.points.windows(2) {
            let d = w[1] - w[0];
            let len = d.length();
            if len <= 0.0 {
                continue;
            }
            let n = DVec2::new(-d.y, d.x) * (h / len);
            subj.push(ring(&[w[0] - n, w[1] - n, w[1] + n, w[0] + n], true));
        }
        for p in &s.points {
            subj.push(corners.iter().map(|c| ip(*p + *c)).collect());
        }
    }
    if subj.is_empty() {
        return 0.0;
    }
    let mut clip: Vec<IntContour<i32>> = Vec::new();
    for r in regions {
        clip.push(ring(&r.outer, true));
        clip.extend(r.holes.iter().map(|hole| ring(hole, false)));
    }
    let union = Overlay::from_subj(&subj).overlay(OverlayRule::Subject, FillRule::NonZero);
    let shapes = Overlay::from_subj_and_clip(&union, &clip).overlay(OverlayRule::Intersect, FillRule::NonZero);
    let a2: i64 = shapes.iter().flatten().map(|c| area2(c)).sum();
    a2 as f64 / 2.0 * 1e-6
}

/// Pore fraction 0–1: 1 − covered area / domain area (0 for an empty domain).
pub(crate) fn pore_fraction(regions: &[Polygon], struts: &[Stroke], line_width: f64) -> f64 {
    let area: f64 = regions.iter().map(|p| p.area()).sum();
    if area <= 0.0 {
        return 0.0;
    }
    (1.0 - covered_area(regions, struts, line_width) / area).clamp(0.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::Feature;

    fn square(x0: f64, y0: f64, s: f64) -> Polygon {
        Polygon { outer: vec![DVec2::new(x0, y0), DVec2::new(x0 + s, y0), DVec2::new(x0 + s, y0 + s), DVec2::new(x0, y0 + s)], holes: vec![] }
    }

    #[test]
    fn square_grid_matches_the_closed_form() {
        // Lines every a mm both ways, w wide, over a domain of whole cells centred on the
        // lines' crossings: each cell a × a keeps an (a − w)² pore.
        let (a, w, n) = (1.0, 0.2, 10);
        let side = n as f64 * a;
        let mut struts = Vec::new();
        for k in 0..=n {
            let t = k as f64 * a;
            struts.push(Stroke { points: vec![DVec2::new(-1.0, t), DVec2::new(side + 1.0, t)], feature: Feature::Lattice, curved: false });
            struts.push(Stroke { points: vec![DVec2::new(t, -1.0), DVec2::new(t, side + 1.0)], feature: Feature::Lattice, curved: false });
        }
        // Interior of the domain: from a/2 to side − a/2 on both axes, whole cells around
        // crossings (n − 1 cells each way).
        let dom = square(a / 2.0, a / 2.0, side - a);
        let p = pore_fraction(&[dom], &struts, w);
        let closed = (a - w) * (a - w) / (a * a);
        assert!((p - closed).abs() < 1e-4, "{p} vs {closed}");
        // The old estimate 1 − L·w/A counts each crossing twice.
        let old = 1.0 - 2.0 * w / a;
        assert!(p - old > 0.03);
    }

    #[test]
    fn a_hole_is_not_domain() {
        let mut d = square(0.0, 0.0, 10.0);
        d.holes.push(square(4.0, 4.0, 2.0).outer.into_iter().rev().collect());
        let s = Stroke { points: vec![DVec2::new(0.0, 5.0), DVec2::new(10.0, 5.0)], feature: Feature::Lattice, curved: false };
        // 10 × 0.2 strip minus the 2 mm inside the hole.
        assert!((covered_area(&[d], &[s], 0.2) - 8.0 * 0.2).abs() < 1e-6);
    }
}

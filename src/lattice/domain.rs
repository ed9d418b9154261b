//! Planar domains: rectangle, disc and tensile specimen layers.

use super::{Domain, LayerDomain, Options};
use crate::geom::{DVec2, Polygon};

/// Largest distance (mm) between a disc and its polygon (the polygon is inscribed).
pub const DISC_CHORD_ERROR_MM: f64 = 0.5e-3;

/// Counter-clockwise axis-aligned rectangle `[x0, x1] × [y0, y1]`.
pub(crate) fn rect_polygon(x0: f64, y0: f64, x1: f64, y1: f64) -> Polygon {
    Polygon { outer: vec![DVec2::new(x0, y0), DVec2::new(x1, y0), DVec2::new(x1, y1), DVec2::new(x0, y1)], holes: Vec::new() }
}

/// Sides of a polygon inscribed in a circle of radius `r` whose chord error is at most
/// [`DISC_CHORD_ERROR_MM`] (16 to 8192 sides).
pub fn disc_sides(r: f64) -> usize {
    if r.is_nan() || r <= DISC_CHORD_ERROR_MM {
        return 16;
    }
    // sagitta = r (1 − cos(π / n)) ≤ e  ⇔  n ≥ π / acos(1 − e / r)
    let n = libm::ceil(std::f64::consts::PI / libm::acos(1.0 - DISC_CHORD_ERROR_MM / r));
    (n as usize).clamp(16, 8192)
}

/// Counter-clockwise regular polygon inscribed in the circle of radius `r` about the origin.
pub(crate) fn disc_polygon(r: f64) -> Polygon {
    let n = disc_sides(r);
    let outer = (0..n)
        .map(|k| {
            let t = 2.0 * std::f64::consts::PI * k as f64 / n as f64;
            DVec2::new(r * libm::cos(t), r * libm::sin(t))
        })
        .collect();
    Polygon { outer, holes: Vec::new() }
}

fn usable(v: f64) -> bool {
    v.is_finite() && v > 0.0
}

/// See [`super::planar_domains`].
pub(crate) fn planar(domain: &Domain, options: &Options) -> Option<Vec<LayerDomain>> {
    let (regions, handles) = match *domain {
        Domain::Solid => return None,
        Domain::Rectangle { width_mm, height_mm } => {
            if usable(width_mm) && usable(height_mm) {
                (vec![rect_polygon(-width_mm / 2.0, -height_mm / 2.0, width_mm / 2.0, height_mm / 2.0)], vec![])
            } else {
                (vec![], vec![])
            }
        }
        Domain::Disc { diameter_mm } => {
            if usable(diameter_mm) {
                (vec![disc_polygon(diameter_mm / 2.0)], vec![])
            } else {
                (vec![], vec![])
            }
        }
        Domain::TensileSpecimen { width_mm, length_mm, handle_length_mm } => {
            if usable(width_mm) && usable(length_mm) {
                let (hw, hl) = (width_mm / 2.0, length_mm / 2.0);
                let lattice = vec![rect_polygon(-hl, -hw, hl, hw)];
                let handles = if usable(handle_length_mm) {
                    vec![rect_polygon(-hl - handle_length_mm, -hw, -hl, hw), rect_polygon(hl, -hw, hl + handle_length_mm, hw)]
                } else {
                    vec![]
                };
                (lattice, handles)
            } else {
                (vec![], vec![])
            }
        }
    };
    let t = options.layer_thickness_mm;
    Some((0..options.layers).map(|i| LayerDomain { z: (i + 1) as f64 * t, height: t, regions: regions.clone(), handles: handles.clone() }).collect())
}

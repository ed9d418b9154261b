//! The grid style: a loop (sheath) around each support island and straight lines inside it
//! on a fixed grid, the same every layer so each line rests on the one below; the interface
//! is lines one line-gap apart, across the base lines, also on a fixed grid.

use super::areas::{um, Areas};
use super::{Input, LayerSupport, Options};
use crate::geom::tolerance::UNITS_PER_MM;
use crate::geom::DVec2;
use crate::slice::infill::rectilinear;
use crate::slice::perimeters::{inset, outset};
use crate::slice::regions::{difference, intersect};
use i_overlay::i_shape::int::shape::IntShapes;

/// Direction of the base lines, radians (along X); the interface crosses them (along Y).
pub(crate) const BASE_ANGLE: f64 = 0.0;
pub(crate) const INTERFACE_ANGLE: f64 = std::f64::consts::FRAC_PI_2;

/// Closed loops (first point repeated) of every contour of `shapes`, mm.
pub(crate) fn loops_mm(shapes: &IntShapes<i32>) -> Vec<Vec<DVec2>> {
    let mut out = Vec::new();
    for c in shapes.iter().flat_map(|s| s.iter()) {
        if c.len() < 3 {
            continue;
        }
        let mut l: Vec<DVec2> = c.iter().map(|p| DVec2::new(p.x as f64, p.y as f64) / UNITS_PER_MM).collect();
        l.push(l[0]);
        out.push(l);
    }
    out
}

/// Sheath, base lines and interface lines of `support` with interface area `iface`.
pub(crate) fn fill(o: &Options, w: i32, support: &IntShapes<i32>, iface: &IntShapes<i32>) -> LayerSupport {
    if support.is_empty() {
        return LayerSupport::default();
    }
    let mut base = loops_mm(&inset(support, w / 2));
    let inner = inset(support, w);
    let iface = if iface.is_empty() { Vec::new() } else { intersect(&inner, iface) };
    let body = if iface.is_empty() { inner } else { difference(&inner, &outset(&iface, w / 2)) };
    let min_len = w as f64;
    base.extend(rectilinear(&body, um(o.spacing_mm) as f64, BASE_ANGLE, min_len));
    let pitch = (w + um(o.interface_spacing_mm)) as f64;
    let interface = rectilinear(&iface, pitch, INTERFACE_ANGLE, min_len);
    LayerSupport { base, interface }
}

pub(crate) fn paths(o: &Options, input: &Input, areas: &Areas) -> Vec<LayerSupport> {
    let n = input.part.len();
    crate::par::map(n, &mut |_| {}, |j| fill(o, input.w_um, &areas.support[j], &areas.interface[j]))
}

//! Pattern thumbnails for the page.

use super::crop::Clipper;
use super::domain::rect_polygon;
use super::graph::Rect;
use super::{cell_length, crop_graph, pattern_graph, validate, Pattern};
use crate::geom::{DVec2, Feature};

/// The segments `[x0, y0, x1, y1]` (mm) of `pattern` cropped to a `size_mm` square centred on
/// the origin (unturned, µm-rounded, each edge once). Empty when the size or the pattern's
/// parameters are unusable, or when the square would hold too many struts.
pub fn thumbnail(pattern: &Pattern, size_mm: f64, seed: u64) -> Vec<[f64; 4]> {
    if !(size_mm.is_finite() && size_mm > 0.0) || validate(pattern).is_err() {
        return Vec::new();
    }
    let h = size_mm / 2.0;
    let rect = Rect { min: DVec2::splat(-h), max: DVec2::splat(h) }.grown(cell_length(pattern));
    let Ok(g) = pattern_graph(pattern, rect, seed) else { return Vec::new() };
    let clip = Clipper::new(&[rect_polygon(-h, -h, h, h)]);
    let mut strokes = Vec::new();
    crop_graph(&g, (1.0, 0.0), &clip, None, Feature::Lattice, &mut strokes);
    strokes.iter().flat_map(|s| s.points.windows(2).map(|w| [w[0].x, w[0].y, w[1].x, w[1].y])).collect()
}

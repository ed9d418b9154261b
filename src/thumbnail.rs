//! A small picture of a result: its extrusion seen from above at an angle, as SVG (the page's
//! example list; built by `scripts/build-www.sh`). Pure and bounded: at most
//! [`Options::max_segments`] segments are drawn (whole layers are skipped evenly when there are
//! more), coordinates are rounded to 0.1 px, and the output stays under a few hundred KB.

use crate::analyze::Preview;
use crate::geom::Feature;
use std::fmt::Write;

/// Default picture side, px.
pub const DEFAULT_SIZE_PX: u32 = 96;
/// Default most segments drawn.
pub const DEFAULT_MAX_SEGMENTS: usize = 2500;
/// Default tilt: 0 = straight from above, 1 = the isometric view.
pub const DEFAULT_TILT: f64 = 0.6;

/// How the picture is drawn.
#[derive(Clone, Debug)]
pub struct Options {
    /// Side of the square picture, px. Default [`DEFAULT_SIZE_PX`].
    pub size_px: u32,
    /// Most segments drawn. Default [`DEFAULT_MAX_SEGMENTS`].
    pub max_segments: usize,
    /// Tilt of the view. Default [`DEFAULT_TILT`].
    pub tilt: f64,
}

impl Default for Options {
    fn default() -> Self {
        Options { size_px: DEFAULT_SIZE_PX, max_segments: DEFAULT_MAX_SEGMENTS, tilt: DEFAULT_TILT }
    }
}

/// The extrusion of `preview` as an SVG picture (an empty frame when there is none).
pub fn svg(preview: &Preview, options: &Options) -> String {
    let size = f64::from(options.size_px.max(8));
    let n = preview.feature.len();
    let layers = preview.layer_segment_start.len().saturating_sub(1);
    // Whole layers, evenly skipped, so a part keeps its outline at every height.
    let step = if n > options.max_segments && layers > 0 { n.div_ceil(options.max_segments.max(1)).min(layers) } else { 1 };
    let drawn: Vec<usize> = if layers == 0 {
        (0..n).step_by(n.div_ceil(options.max_segments.max(1)).max(1)).collect()
    } else {
        let mut v = Vec::new();
        let mut l = layers - 1; // the top layer always
        loop {
            let (a, b) = (preview.layer_segment_start[l] as usize, preview.layer_segment_start[l + 1] as usize);
            v.extend(a.min(n)..b.min(n));
            if l < step {
                break;
            }
            l -= step;
        }
        v.truncate(options.max_segments.max(1) * 2);
        v.sort_unstable();
        v
    };
    // The view: turned 45° about Z (cos = sin = 1/√2), tilted by `tilt`.
    let r = std::f64::consts::FRAC_1_SQRT_2;
    let t = options.tilt.clamp(0.0, 1.0);
    let project = |x: f64, y: f64, z: f64| -> (f64, f64) { ((x - y) * r, -((x + y) * r * (1.0 - 0.5 * t) + z * t)) };
    let p = &preview.positions;
    let mut pts: Vec<(f64, f64, f64, f64, u8)> = Vec::with_capacity(drawn.len());
    let (mut min, mut max) = ((f64::INFINITY, f64::INFINITY), (f64::NEG_INFINITY, f64::NEG_INFINITY));
    for &i in &drawn {
        let Some(q) = p.get(i * 6..i * 6 + 6) else { continue };
        let (a, b) = (project(q[0].into(), q[1].into(), q[2].into()), project(q[3].into(), q[4].into(), q[5].into()));
        for (u, v) in [a, b] {
            min = (min.0.min(u), min.1.min(v));
            max = (max.0.max(u), max.1.max(v));
        }
        pts.push((a.0, a.1, b.0, b.1, preview.feature.get(i).copied().unwrap_or(255)));
    }
    let mut out = String::new();
    let _ = write!(out, r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 {size} {size}" width="{size}" height="{size}">"#);
    if pts.is_empty() || !(max.0 > min.0 || max.1 > min.1) {
        out.push_str("</svg>");
        return out;
    }
    let margin = size * 0.06;
    let scale = (size - 2.0 * margin) / (max.0 - min.0).max(max.1 - min.1);
    let (ox, oy) = (margin + (size - 2.0 * margin - (max.0 - min.0) * scale) / 2.0, margin + (size - 2.0 * margin - (max.1 - min.1) * scale) / 2.0);
    let px = |u: f64| ((ox + (u - min.0) * scale) * 10.0).round() / 10.0;
    let py = |v: f64| ((oy + (v - min.1) * scale) * 10.0).round() / 10.0;
    // One path element per feature, in feature order (deterministic).
    let mut by_feature: Vec<(u8, String)> = Vec::new();
    for (u0, v0, u1, v1, f) in pts {
        let d = match by_feature.iter_mut().find(|(k, _)| *k == f) {
            Some((_, d)) => d,
            None => {
                by_feature.push((f, String::new()));
                &mut by_feature.last_mut().expect("just pushed").1
            }
        };
        let _ = write!(d, "M{} {}L{} {}", px(u0), py(v0), px(u1), py(v1));
    }
    by_feature.sort_by_key(|(f, _)| *f);
    for (f, d) in by_feature {
        let color = Feature::ALL.get(usize::from(f)).map_or("#bebebe", |x| x.color());
        let _ = write!(out, r#"<path d="{d}" fill="none" stroke="{color}" stroke-width="0.8" stroke-linecap="round"/>"#);
    }
    out.push_str("</svg>");
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square_layers(layers: usize) -> Preview {
        let mut p = Preview::default();
        for l in 0..layers {
            p.layer_segment_start.push(p.feature.len() as u32);
            let z = l as f32 * 0.2 + 0.2;
            let c = [[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0], [0.0, 0.0]];
            for w in c.windows(2) {
                p.positions.extend([w[0][0], w[0][1], z, w[1][0], w[1][1], z]);
                p.feature.push(0);
            }
        }
        p.layer_segment_start.push(p.feature.len() as u32);
        p
    }

    #[test]
    fn draws_every_segment_of_a_small_result() {
        let svg = svg(&square_layers(3), &Options::default());
        assert!(svg.starts_with("<svg") && svg.ends_with("</svg>"));
        assert_eq!(svg.matches('M').count(), 12, "{svg}");
    }

    #[test]
    fn a_big_result_is_bounded_and_keeps_the_top_layer() {
        let p = square_layers(10_000);
        let o = Options { max_segments: 400, ..Options::default() };
        let svg = svg(&p, &o);
        let drawn = svg.matches('M').count();
        assert!((100..=2 * 400).contains(&drawn), "{drawn}");
        assert!(svg.len() < 100_000);
    }

    #[test]
    fn nothing_to_draw_is_an_empty_frame() {
        assert!(svg(&Preview::default(), &Options::default()).ends_with("\"></svg>"));
    }
}

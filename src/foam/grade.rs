//! Grading the raster (section 3.2.4 with Algorithm 2): each layer's path cut into pieces of at
//! most `piece_mm`, each piece printed with the V*/H* pair of its end from the [`Field`]: its
//! filament per mm and feed ([`Process`]) and its height above the layer. One free pass per
//! layer whose first point is the last layer's end, so the print is one uninterrupted
//! extrusion.

use super::field::Field;
use super::vtp::Process;
use crate::geom::{DVec2, DVec3, Feature, Pass, PassKind, Path, PointData, PointFlow, Toolpath};

/// One layer's raster: the top of the layer (mm) and its path.
pub struct LayerRaster<'a> {
    /// Top of the layer, mm.
    pub z: f64,
    /// The path, mm.
    pub points: &'a [DVec2],
}

/// The graded toolpath and what grading counted.
pub struct Graded {
    /// One free pass per layer.
    pub toolpath: Toolpath,
    /// Pieces printed.
    pub pieces: usize,
    /// Field queries made (region look-ups along the path).
    pub queries: usize,
    /// Least and greatest V* printed.
    pub v_range: (f64, f64),
}

/// Grades `layers` (each `layer_height_mm` thick) with `field` and `process`, pieces at most
/// `piece_mm` long; line width `width_mm`. `progress` gets the fraction of layers done.
pub fn grade(
    field: &Field,
    process: &Process,
    layers: &[LayerRaster],
    layer_height_mm: f64,
    piece_mm: f64,
    width_mm: f64,
    progress: &mut dyn FnMut(f32),
) -> Graded {
    let (p, h) = (process, layer_height_mm);
    let mut passes = Vec::with_capacity(layers.len());
    let (mut pieces, mut queries) = (0usize, 0usize);
    let (mut v_lo, mut v_hi) = (f64::INFINITY, f64::NEG_INFINITY);
    let mut prev_end: Option<DVec3> = None;
    for (k, layer) in layers.iter().enumerate() {
        let mut walker = field.walker();
        let n_est = layer.points.len() * 2;
        let mut pts: Vec<DVec3> = Vec::with_capacity(n_est);
        let mut flow: Vec<f64> = Vec::with_capacity(n_est);
        let mut feed: Vec<f64> = Vec::with_capacity(n_est);
        let mut push = |q: DVec2, pts: &mut Vec<DVec3>, flow: &mut Vec<f64>, feed: &mut Vec<f64>| {
            let (pair, _) = walker.next(DVec3::new(q.x, q.y, layer.z - h / 2.0));
            v_lo = v_lo.min(pair.v_star);
            v_hi = v_hi.max(pair.v_star);
            pts.push(DVec3::new(q.x, q.y, layer.z + p.z_offset_mm(pair.h_star, h)));
            flow.push(p.filament_per_mm(pair.v_star));
            feed.push(p.speed_mm_s(pair.v_star));
        };
        // The rise from the last layer's end is extruded too.
        if let Some(e) = prev_end {
            pts.push(e);
            flow.push(0.0);
            feed.push(0.0);
        }
        let Some(&first) = layer.points.first() else { continue };
        push(first, &mut pts, &mut flow, &mut feed);
        for w in layer.points.windows(2) {
            let len = w[0].distance(w[1]);
            let n = (len / piece_mm).ceil().max(1.0) as usize;
            for i in 1..=n {
                push(w[0].lerp(w[1], i as f64 / n as f64), &mut pts, &mut flow, &mut feed);
            }
        }
        queries += walker.queries;
        if prev_end.is_none() {
            // The first point of the print: nothing is extruded up to it.
            flow[0] = 0.0;
            feed[0] = 0.0;
        }
        pieces += pts.len() - 1;
        prev_end = pts.last().copied();
        let data = PointData { flow: Some(PointFlow::FilamentPerMm(flow)), feed_mm_s: Some(feed), tool_axis: None, dwell_s: None };
        let path = Path {
            points: pts,
            feature: Feature::Infill,
            width: width_mm,
            speed_factor: 1.0,
            approach: if k == 0 { None } else { Some(Vec::new()) },
            data: Some(Box::new(data)),
        };
        passes.push(Pass { kind: PassKind::Free, z: layer.z, height: h, paths: vec![path] });
        progress((k + 1) as f32 / layers.len() as f32);
    }
    Graded { toolpath: Toolpath { passes }, pieces, queries, v_range: (v_lo, v_hi) }
}

//! The axisymmetric job's views: Ω on the (θ, u) map with its points and path, and the platform revolved in 3D with the path on it.

use super::*;

/// One of the kind's views at `index` (`Kind::inspect`).
pub(super) fn inspect(j: &AxisymJob, ctx: &mut Ctx, view: &str, index: usize) -> Result<Inspection, Error> {
    let platform = platform_stage(j, ctx)?;
    check_layers(j)?;
    // The path comes from the stage cache when the run made it (the worker's session).
    match view {
        "map" => {
            let index = index.min(3 * j.layers - 1);
            let (layer, step) = (index / 3, index % 3);
            // The points of a layer do not need the paths below it; its path does.
            let layers = all_layers(j, ctx, &platform, layer + 1, step == 2)?;
            let l = &layers[layer];
            Ok(map_view(&l.domain, &l.points, l.tour.as_deref(), layer, j.layers, step, j.domain.kind == DomainKind::Polygon))
        }
        "platform3d" => {
            let layers = all_layers(j, ctx, &platform, j.layers, true)?;
            let tours: Vec<&tour::Tour> = layers.iter().filter_map(|l| l.tour.as_deref()).collect();
            Ok(platform_view(&platform, &tours, j.layer_height_mm))
        }
        "omega" => omega_view(j, ctx, &platform, index),
        "repulsion" => repulsion_view(j, ctx, &platform, index),
        "axes3d" => axes_view(j, ctx, &platform, index),
        _ => Err(Error::UnknownView { view: view.into(), job: AxisymKind::NAME }),
    }
}

/// Half the size of a point's cross in the map view, in map units.
pub(super) const CROSS: f32 = 0.004;

/// The map of layer `layer` at `step` (seed, result, path); with `drawable` (a polygon
/// domain) the page offers to draw the outline on it (`meta.draw`: field, pair order).
#[allow(clippy::too_many_arguments)]
pub(super) fn map_view(
    domain: &Domain,
    d: &uniform::Distribution,
    tour: Option<&tour::Tour>,
    layer: usize,
    layers: usize,
    step: usize,
    drawable: bool,
) -> Inspection {
    let index = 3 * layer + step;
    let mut data: Vec<f32> = Vec::new();
    let mut seg = |a: [f64; 2], b: [f64; 2], code: u8| data.extend_from_slice(&[a[1] as f32, a[0] as f32, b[1] as f32, b[0] as f32, code as f32]);
    // Outline of Ω and its holes (x: θ, y: u).
    for ring in std::iter::once(domain.ring()).chain(domain.holes()) {
        for k in 0..ring.len() {
            seg(ring[k], ring[(k + 1) % ring.len()], Feature::Contour.code());
        }
    }
    let pts = if step == 0 { &d.seed_points } else { &d.points };
    if step < 2 {
        for p in pts {
            let (u, t) = (p[0] as f32, p[1] as f32);
            data.extend_from_slice(&[t - CROSS, u, t + CROSS, u, Feature::Lattice.code() as f32]);
            data.extend_from_slice(&[t, u - CROSS, t, u + CROSS, Feature::Lattice.code() as f32]);
        }
    } else if let Some(t) = tour {
        for s in &t.samples {
            for w in s.windows(2) {
                data.extend_from_slice(&[w[0][1] as f32, w[0][0] as f32, w[1][1] as f32, w[1][0] as f32, Feature::Infill.code() as f32]);
            }
        }
    }
    let labels = ["seed points", "after repulsion", "path"];
    // Several layers name the layer; one layer says what the frame holds, with units.
    let caption = if layers > 1 {
        format!("layer {} of {layers}: {}", layer + 1, labels[step])
    } else {
        match (step, tour) {
            (0, _) => format!("seed points: {} (N from equation 4 over {:.0} mm²)", d.seed_points.len(), d.area_mm2),
            (1, _) => format!(
                "after repulsion: {} points, {} iterations, energy E/E₀ {:.3e}",
                d.points.len(),
                d.iterations.len(),
                d.iterations.last().map_or(1.0, |i| i.energy)
            ),
            (_, Some(t)) => format!("path: {:.1} mm of geodesics through {} points", t.geodesic_length_mm, d.points.len()),
            _ => labels[step].to_string(),
        }
    };
    Inspection {
        view: "map".into(),
        shape: Shape::Lines2d,
        index,
        count: 3 * layers,
        stride: Shape::Lines2d.stride(),
        data,
        overlay: Vec::new(),
        meta: serde_json::json!({
            "x_label": "θ (rad)", "y_label": "u", "scale_bar": false, "caption": caption,
            "legend": legend(&[(Feature::Contour, "outline of Ω"), (Feature::Lattice, labels[step.min(1)]), (Feature::Infill, "path (geodesics)")]),
            // x is θ and y is u here; the polygon field holds (u, θ) pairs.
            "draw": if drawable { serde_json::json!({ "path": "job.domain.polygon", "pair": ["y", "x"], "label": "Draw Ω on the map", "min_points": 3 }) } else { serde_json::Value::Null },
        }),
    }
}

/// Meridians and parallels drawn on the platform view.
pub(super) const MERIDIANS: usize = 24;
pub(super) const PARALLELS_PER_SEGMENT: usize = 6;
pub(super) const RING_STEPS: usize = 96;

pub(super) fn platform_view(p: &Platform, tours: &[&tour::Tour], h: f64) -> Inspection {
    let mut data: Vec<f32> = Vec::new();
    let code = Feature::Contour.code() as f32;
    let k = p.segments.len();
    let steps = k * 32;
    let mut push =
        |a: [f64; 3], b: [f64; 3], c: f32| data.extend_from_slice(&[a[0] as f32, a[1] as f32, a[2] as f32, b[0] as f32, b[1] as f32, b[2] as f32, c]);
    for m in 0..MERIDIANS {
        let th = std::f64::consts::TAU * m as f64 / MERIDIANS as f64;
        for i in 0..steps {
            let (u0, u1) = (k as f64 * i as f64 / steps as f64, k as f64 * (i + 1) as f64 / steps as f64);
            push(platform::position(p, u0, th), platform::position(p, u1, th), code);
        }
    }
    for i in 0..=k * PARALLELS_PER_SEGMENT {
        let u = i as f64 / PARALLELS_PER_SEGMENT as f64;
        for s in 0..RING_STEPS {
            let (a, b) = (std::f64::consts::TAU * s as f64 / RING_STEPS as f64, std::f64::consts::TAU * (s + 1) as f64 / RING_STEPS as f64);
            push(platform::position(p, u, a), platform::position(p, u, b), code);
        }
    }
    // Every layer's path, each tip one layer height out from its layer's surface.
    for t in tours {
        for w in t.poses.windows(2) {
            push(tip(&w[0], h).to_array(), tip(&w[1], h).to_array(), Feature::Infill.code() as f32);
        }
    }
    let meta = serde_json::json!({ "legend": legend(&[(Feature::Contour, "platform (meridians, parallels)"), (Feature::Infill, "path (nozzle tip)")]) });
    Inspection { view: "platform3d".into(), shape: Shape::Lines3d, index: 0, count: 1, stride: Shape::Lines3d.stride(), data, overlay: Vec::new(), meta }
}

/// A view's legend: feature code → what the view draws with it.
pub(super) fn legend(entries: &[(Feature, &str)]) -> serde_json::Value {
    serde_json::Value::Object(entries.iter().map(|(f, text)| (f.code().to_string(), serde_json::Value::from(*text))).collect())
}

//! The views the "How it works" steps add: Ω alone on the map, the repulsion replayed frame by
//! frame, and the platform with the path's tool axes.

use super::*;

/// Most frames the repulsion view keeps (the seed, evenly spaced iterations, the last one).
pub const REPULSION_FRAMES: usize = 64;
/// Most bytes the repulsion view's frames take: fewer frames for many points.
pub const REPULSION_BYTES: usize = 8 << 20;
/// Length of a tool-axis stroke in the axes view, mm.
pub const AXIS_STROKE_MM: f64 = 4.0;
/// Tool axes drawn per layer at most (evenly along the path).
pub const AXES_PER_LAYER: usize = 120;

/// The frames of layer 0's repulsion, recorded on demand (cached with the points stage's key).
pub(super) struct Frames {
    frames: Vec<uniform::Frame>,
    iterations: usize,
    cap: usize,
    bytes: usize,
}

/// The frame cap for `points` points: [`REPULSION_FRAMES`], fewer when their points would pass
/// [`REPULSION_BYTES`] (at least 2: the seed and the result).
pub fn repulsion_cap(points: usize) -> usize {
    (REPULSION_BYTES / (points.max(1) * std::mem::size_of::<[f64; 2]>())).clamp(2, REPULSION_FRAMES)
}

/// Ω's outline and holes (x: θ, y: u) with the Contour code.
fn outline(domain: &Domain, data: &mut Vec<f32>) {
    for ring in std::iter::once(domain.ring()).chain(domain.holes()) {
        for k in 0..ring.len() {
            let (a, b) = (ring[k], ring[(k + 1) % ring.len()]);
            data.extend_from_slice(&[a[1] as f32, a[0] as f32, b[1] as f32, b[0] as f32, Feature::Contour.code() as f32]);
        }
    }
}

/// A cross per point (x: θ, y: u) with the Lattice code.
fn crosses(points: &[[f64; 2]], data: &mut Vec<f32>) {
    let c = Feature::Lattice.code() as f32;
    for p in points {
        let (u, t) = (p[0] as f32, p[1] as f32);
        data.extend_from_slice(&[t - CROSS, u, t + CROSS, u, c, t, u - CROSS, t, u + CROSS, c]);
    }
}

fn lines2d(view: &str, index: usize, count: usize, data: Vec<f32>, meta: serde_json::Value) -> Inspection {
    Inspection { view: view.into(), shape: Shape::Lines2d, index, count, stride: Shape::Lines2d.stride(), data, overlay: Vec::new(), meta }
}

/// Ω of layer `index` alone on the (θ, u) map, its area on the layer's surface.
pub(super) fn omega_view(j: &AxisymJob, ctx: &mut Ctx, platform: &Out<Platform>, index: usize) -> Result<Inspection, Error> {
    let k = index.min(j.layers - 1);
    let domain = domain_stage(j, ctx, platform, k)?;
    let surface = layer_offset(&platform.value, j, k, &domain.value).map_err(|e| Error::stage("domain", e))?;
    let area = domain.area_mm2(&Surface::new(surface.profile()));
    let [[u0, t0], [u1, t1]] = domain.bounds();
    let mut data = Vec::new();
    outline(&domain.value, &mut data);
    let holes = domain.holes().len();
    let caption = format!(
        "Ω of layer {} of {}: u {u0:.3}–{u1:.3}, θ {t0:.3}–{t1:.3} rad, {area:.0} mm² on the platform{}",
        k + 1,
        j.layers,
        if holes > 0 { format!(", {holes} hole(s)") } else { String::new() }
    );
    let meta = serde_json::json!({
        "x_label": "θ (rad)", "y_label": "u", "scale_bar": false, "caption": caption, "area_mm2": area,
        "legend": legend(&[(Feature::Contour, "outline of Ω (and its holes)")]),
    });
    Ok(lines2d("omega", k, j.layers, data, meta))
}

/// Frame `index` of layer 0's geodesic repulsion: Ω and the points then.
pub(super) fn repulsion_view(j: &AxisymJob, ctx: &mut Ctx, platform: &Out<Platform>, index: usize) -> Result<Inspection, Error> {
    let frames = repulsion_frames(j, ctx, platform)?;
    let domain = domain_stage(j, ctx, platform, 0)?;
    let count = frames.frames.len();
    let index = index.min(count.saturating_sub(1));
    let mut data = Vec::new();
    outline(&domain.value, &mut data);
    let Some(f) = frames.frames.get(index) else {
        return Ok(lines2d("repulsion", 0, 1, data, serde_json::json!({ "caption": "no points to repel" })));
    };
    crosses(&f.points, &mut data);
    let change = 100.0 * (f.energy - 1.0);
    let sign = if change < 0.0 { "−" } else { "+" };
    let caption = format!(
        "repulsion iteration {} of {}: energy E/E₀ {} ({sign}{:.1} %), {} points",
        f.iteration,
        frames.iterations,
        if f.energy >= 0.01 { format!("{:.3}", f.energy) } else { format!("{:.2e}", f.energy) },
        change.abs(),
        f.points.len()
    );
    let meta = serde_json::json!({
        "x_label": "θ (rad)", "y_label": "u", "scale_bar": false, "caption": caption,
        "iteration": f.iteration, "iterations": frames.iterations, "energy": f.energy,
        "frames": count, "cap": frames.cap, "recorded_bytes": frames.bytes,
        "legend": legend(&[(Feature::Contour, "outline of Ω"), (Feature::Lattice, "points at this iteration")]),
    });
    Ok(lines2d("repulsion", index, count, data, meta))
}

/// Layer 0's repulsion replayed with its frames kept: made only when the view asks (a run
/// records nothing), cached under the points stage's key.
fn repulsion_frames(j: &AxisymJob, ctx: &mut Ctx, platform: &Out<Platform>) -> Result<Out<Frames>, Error> {
    let layers = all_layers(j, ctx, platform, 1, false)?;
    let l = &layers[0];
    let cap = repulsion_cap(l.points.points.len());
    let (width, seed) = (line_width(ctx.design), layer_seed(ctx.design.seed, 0));
    ctx.recording("points", "repulsion_frames", &cap, &[l.points.key], |_| {
        let surface = layer_offset(&platform.value, j, 0, &l.domain.value).map_err(|e| Error::stage("points", e))?;
        let r = uniform::record(surface.profile(), &l.domain.value, &j.points, width, seed, cap).map_err(|e| Error::stage("points", e))?;
        let bytes = r.bytes();
        Ok((Frames { frames: r.frames, iterations: r.iterations, cap, bytes }, None))
    })
}

/// Step 0: the platform alone; step 1: every layer's path on it with a tool-axis stroke at
/// evenly spaced poses.
pub(super) fn axes_view(j: &AxisymJob, ctx: &mut Ctx, platform: &Out<Platform>, index: usize) -> Result<Inspection, Error> {
    let h = j.layer_height_mm;
    let index = index.min(1);
    if index == 0 {
        let mut v = platform_view(&platform.value, &[], h);
        let (mut z, mut r) = ((f64::INFINITY, f64::NEG_INFINITY), 0.0f64);
        for s in v.data.chunks_exact(7) {
            for p in [&s[0..3], &s[3..6]] {
                z = (z.0.min(p[2] as f64), z.1.max(p[2] as f64));
                r = r.max(libm::hypot(p[0] as f64, p[1] as f64));
            }
        }
        v.view = "axes3d".into();
        v.count = 2;
        v.meta["caption"] =
            format!("platform: {} degree-6 Bézier segment(s) revolved, z {:.1}–{:.1} mm, radius up to {r:.1} mm", platform.segments.len(), z.0, z.1).into();
        return Ok(v);
    }
    let layers = all_layers(j, ctx, platform, j.layers, true)?;
    let tours: Vec<&tour::Tour> = layers.iter().filter_map(|l| l.tour.as_deref()).collect();
    let keys: Vec<_> = layers.iter().map(|l| l.tour.as_ref().map_or(l.points.key, |t| t.key)).collect();
    let axes = axes_stage(j, ctx, &tours, &keys)?;
    let mut v = platform_view(&platform.value, &tours, h);
    let (mut drawn, mut poses, mut lean) = (0usize, 0usize, 0.0f64);
    for (t, a) in tours.iter().zip(axes.iter()) {
        let n = t.poses.len().min(a.len());
        poses += n;
        let step = n.div_ceil(AXES_PER_LAYER).max(1);
        for i in (0..n).step_by(step) {
            let p = tip(&t.poses[i], h);
            let axis = DVec3::from_array(a[i]).normalize_or_zero();
            let q = p + axis * AXIS_STROKE_MM;
            v.data.extend_from_slice(&[p.x as f32, p.y as f32, p.z as f32, q.x as f32, q.y as f32, q.z as f32, Feature::Lattice.code() as f32]);
            lean = lean.max(libm::acos(axis.z.clamp(-1.0, 1.0)).to_degrees());
            drawn += 1;
        }
    }
    v.view = "axes3d".into();
    v.index = 1;
    v.count = 2;
    v.meta = serde_json::json!({
        "caption": format!("{drawn} of {poses} tool axes drawn ({AXIS_STROKE_MM} mm strokes); up to {lean:.1}° from vertical"),
        "legend": legend(&[(Feature::Contour, "platform (meridians, parallels)"), (Feature::Infill, "path (nozzle tip)"), (Feature::Lattice, "tool axis (surface normal)")]),
    });
    Ok(v)
}

//! The axisymmetric job's stages: platform, domain Ω per layer, seed points and their repulsion, the path, the tool axes; the work each will do, and the toolpath they give.

use super::*;

/// The work each stage will do (`Kind::estimate`), refused over a budget before any is done.
pub(super) fn estimate(j: &AxisymJob, ctx: &mut Ctx) -> Result<Vec<crate::budget::Estimate>, Error> {
    let platform = platform_stage(j, ctx)?;
    let width = line_width(ctx.design);
    check_layers(j)?;
    // A part's outlines are found first (their own estimate bounds that: linear in
    // triangles); every layer states its points, the sums are refused over the budgets.
    let (mut points, mut paths) = (Vec::new(), Vec::new());
    for k in 0..j.layers {
        let domain = domain_stage(j, ctx, &platform, k)?;
        let surface = layer_offset(&platform, j, k, &domain).map_err(|e| Error::stage("points", e))?;
        let e = uniform::estimate(surface.profile(), &domain.value, &j.points, width);
        paths.push(tour::estimate(e.get("points") as usize, &j.path, uniform::largest_spacing(&j.points, width)));
        points.push(e);
    }
    Ok(vec![
        crate::budget::Estimate::new("platform"),
        sum_layers(points, "lower the density, the iterations, cutoff_spacings or the layers"),
        sum_layers(paths, "lower the infill density, the layers or split the domain"),
    ])
}

pub(super) fn platform_stage(j: &AxisymJob, ctx: &mut Ctx) -> Result<Out<Platform>, Error> {
    ctx.stage("platform", "platform", &j.platform.control_points, &[], |_| {
        let p = Platform::from_polygon(&j.platform.control_points).map_err(|e| Error::stage("platform", e))?;
        let continuity = p.validate(&platform::Options::default()).map_err(|e| Error::stage("platform", e))?;
        let report = platform_report(&p, &continuity);
        Ok((p, Some(report)))
    })
}

/// The layer count within 1..=[`MAX_LAYERS`] (the settings table says so too; a design read
/// without its checks must not loop or index out of range).
pub(super) fn check_layers(j: &AxisymJob) -> Result<(), Error> {
    if (1..=MAX_LAYERS).contains(&j.layers) {
        Ok(())
    } else {
        Err(Error::stage("points", crate::axisym::Error::BadOption { name: "layers", value: j.layers as f64, hint: "1 to 100 layers" }))
    }
}

/// The stage cache id of `stage` for layer k: the plain name for layer 0 (so a one-layer job
/// keeps its ids, keys and reports), `name@k` above.
pub(super) fn layer_id(stage: &str, k: usize) -> String {
    if k == 0 {
        stage.to_string()
    } else {
        format!("{stage}@{k}")
    }
}

/// The seed of layer k: the design seed for layer 0, a fixed odd multiple of k mixed in above.
pub fn layer_seed(seed: u64, k: usize) -> u64 {
    seed ^ (k as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
}

/// The surface layer k spreads its points on: the platform itself, or its offset by k·h.
pub(super) enum LayerSurface<'a> {
    Base(&'a Platform),
    Offset(Offset<'a, Platform>),
}

impl LayerSurface<'_> {
    pub(super) fn profile(&self) -> &dyn Profile {
        match self {
            LayerSurface::Base(p) => *p,
            LayerSurface::Offset(o) => o,
        }
    }
}

/// Why a layer's surface cannot be used.
#[derive(Debug, thiserror::Error)]
#[error("layer {layer} (on the platform offset by {offset_mm} mm): {source}")]
pub struct LayerError {
    /// Layer, 1-based.
    pub layer: usize,
    /// Its offset, mm.
    pub offset_mm: f64,
    /// The offset's reason.
    pub source: crate::axisym::Error,
}

/// Layer k's surface, checked over the u span of its domain.
pub(super) fn layer_offset<'a>(p: &'a Platform, j: &AxisymJob, k: usize, domain: &Domain) -> Result<LayerSurface<'a>, LayerError> {
    if k == 0 {
        return Ok(LayerSurface::Base(p));
    }
    let h = k as f64 * j.layer_height_mm;
    let b = domain.bounds();
    Offset::new(p, h, [b[0][0], b[1][0]], platform::DEFAULT_MIN_POLE_RADIUS_MM).map(LayerSurface::Offset).map_err(|source| LayerError {
        layer: k + 1,
        offset_mm: h,
        source,
    })
}

/// Sums per-layer estimates of one stage: counts and times add, the peak memory is the
/// largest layer's, the first layer refused refuses, then the budgets on the totals.
pub(super) fn sum_layers(layers: Vec<crate::budget::Estimate>, fix: &str) -> crate::budget::Estimate {
    let mut it = layers.into_iter();
    let Some(mut total) = it.next() else { return crate::budget::Estimate::new("axisym_uniform") };
    let mut more = false;
    for e in it {
        more = true;
        for q in e.quantities {
            match total.quantities.iter_mut().find(|t| t.key == q.key) {
                Some(t) => t.value += q.value,
                None => total.quantities.push(q),
            }
        }
        total.bytes = total.bytes.max(e.bytes);
        total.seconds += e.seconds;
        if total.refused.is_none() {
            total.refused = e.refused;
        }
    }
    // One layer: exactly its own estimate.
    if more {
        total.budgets(fix)
    } else {
        total
    }
}

/// One layer's stages.
pub(super) struct Layer {
    pub(super) offset_mm: f64,
    pub(super) domain: Out<Domain>,
    pub(super) points: Out<uniform::Distribution>,
    pub(super) tour: Option<Out<tour::Tour>>,
}

/// Layers 0..count: domains and points, and with `paths` each layer's path (layer k + 1's
/// starting nearest where layer k's ended).
pub(super) fn all_layers(j: &AxisymJob, ctx: &mut Ctx, platform: &Out<Platform>, count: usize, paths: bool) -> Result<Vec<Layer>, Error> {
    check_layers(j)?;
    let mut out: Vec<Layer> = Vec::with_capacity(count);
    for k in 0..count {
        let domain = domain_stage(j, ctx, platform, k)?;
        let points = points_stage(j, ctx, platform, &domain, k)?;
        out.push(Layer { offset_mm: k as f64 * j.layer_height_mm, domain, points, tour: None });
    }
    if paths {
        for k in 0..count {
            let start = if k == 0 {
                None
            } else {
                let prev = &out[k - 1];
                prev.tour.as_ref().and_then(|t| t.order.last()).map(|&i| prev.points.points[i])
            };
            let t = path_stage(j, ctx, platform, &out[k].domain, &out[k].points, k, start)?;
            out[k].tour = Some(t);
        }
    }
    Ok(out)
}

/// Ω of layer k ([`domain_of`]), refused when the layer's nozzle tip, (k + 1)·h out along the
/// normal, would go below the plate: checked here, before the points and path stages spend
/// their time (the writer would refuse the toolpath only at the end).
pub(super) fn domain_stage(j: &AxisymJob, ctx: &mut Ctx, platform: &Out<Platform>, k: usize) -> Result<Out<Domain>, Error> {
    let domain = domain_of(j, ctx, platform, k)?;
    let [[u_lo, _], [u_hi, _]] = domain.value.bounds();
    below_plate(&*platform.value, u_lo, u_hi, (k + 1) as f64 * j.layer_height_mm).map_err(|e| Error::stage("domain", e))?;
    Ok(domain)
}

/// The nozzle tip would go below the plate.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("the nozzle tip would reach z = {z_mm:.3} mm at u = {u:.4}, below the plate (Z < 0): raise the platform by at least {raise_mm:.3} mm (add it to every control point's z), or keep the domain's u where the platform stands higher")]
pub struct BelowPlate {
    /// Lowest tip height, mm.
    pub z_mm: f64,
    /// Where along the profile.
    pub u: f64,
    /// How far to raise the platform, mm.
    pub raise_mm: f64,
}

/// Samples of the tip height per unit u when looking for its lowest point (then refined).
pub(super) const PLATE_SAMPLES_PER_U: f64 = 512.0;

/// Checks that the tip, `h` out along the normal, stays at Z ≥ 0 for u ∈ [u_lo, u_hi] (the
/// height depends on u only, and every u of a connected domain's range is in the domain).
pub(super) fn below_plate(p: &dyn platform::Profile, u_lo: f64, u_hi: f64, h: f64) -> Result<(), BelowPlate> {
    let tip_z = |u: f64| platform::position(p, u, 0.0)[2] + platform::normal(p, u, 0.0)[2] * h;
    let n = (((u_hi - u_lo) * PLATE_SAMPLES_PER_U).ceil() as usize).clamp(1, 1 << 16);
    let at = |i: usize| u_lo + (u_hi - u_lo) * i as f64 / n as f64;
    let k = (0..=n).map(|i| (i, tip_z(at(i)))).min_by(|a, b| a.1.total_cmp(&b.1)).map_or(0, |(i, _)| i);
    // Golden-section refinement in the bracket around the lowest sample.
    let (mut a, mut b) = (at(k.saturating_sub(1)), at((k + 1).min(n)));
    for _ in 0..60 {
        let (c, d) = (b - 0.618_033_988_749_895 * (b - a), a + 0.618_033_988_749_895 * (b - a));
        if tip_z(c) < tip_z(d) {
            b = d
        } else {
            a = c
        }
    }
    let (u, z) = [at(k), 0.5 * (a + b)].into_iter().map(|u| (u, tip_z(u))).min_by(|x, y| x.1.total_cmp(&y.1)).unwrap_or((u_lo, 0.0));
    // The writer's tolerance (1e-6 mm).
    if z < -1e-6 {
        Err(BelowPlate { z_mm: z, u, raise_mm: -z })
    } else {
        Ok(())
    }
}

/// Ω of layer k: the settings' rectangle or polygon (every layer the same (u, θ) region), or
/// the largest outline where the part meets the platform offset by k·h, with the holes in it
/// (smaller outlines are reported, not filled).
pub(super) fn domain_of(j: &AxisymJob, ctx: &mut Ctx, platform: &Out<Platform>, k: usize) -> Result<Out<Domain>, Error> {
    if let Some(d) = j.domain.domain() {
        return ctx.stage("domain", "domain", &d, &[platform.key], |_| {
            let corners = d.ring().len();
            let mut r = StageReport::new("domain", "Finding the domain Ω", &d).metric(
                "corners",
                "Outline corners",
                corners as f64,
                "",
                "Corners of Ω in the embedded map (a rectangle has 4).",
            );
            if !d.holes().is_empty() {
                r = r.metric(
                    "holes",
                    "Holes kept",
                    d.holes().len() as f64,
                    "",
                    "Openings inside the outline, left unfilled: the points and the path keep out of them.",
                );
            }
            Ok((d.clone(), Some(r)))
        });
    }
    let input = j.part.as_ref().ok_or_else(|| Error::NoInput("a part domain needs the part: load it, or pass --input part=FILE".into()))?;
    // In the file's own coordinates: the platform's axis is Z through the origin.
    let mesh = ctx.mesh_in_place(&SLOTS[0], input)?;
    let offset_mm = k as f64 * j.layer_height_mm;
    ctx.stage("domain", &layer_id("domain", k), &offset_mm, &[platform.key, mesh.key], |_| {
        let c = contour::platform_contours(&mesh.value, &platform.value, &contour::Options { offset_mm, ..contour::Options::default() })
            .map_err(|e| Error::stage("domain", e))?;
        // (A hole always lies in an outline, so an outline exists whenever a loop does.)
        let outline = (0..c.loops.len()).find(|&i| !c.is_hole[i]).ok_or_else(|| {
            Error::NoInput("the part meets the platform in no closed outline (an open mesh?): repair the part or move it onto the platform".into())
        })?;
        let kept: Vec<usize> = (0..c.loops.len()).filter(|&i| c.is_hole[i] && c.parent[i] == Some(outline)).collect();
        let outlines = c.is_hole.iter().filter(|h| !**h).count();
        let d = Domain::Polygon { points: c.loops[outline].clone(), holes: kept.iter().map(|&i| c.loops[i].clone()).collect() };
        let r = StageReport::new("domain", "Finding the domain Ω", &d)
            .metric(
                "corners",
                "Outline corners",
                c.loops[outline].len() as f64,
                "",
                "Points of the outline where the part meets the platform, in the embedded map.",
            )
            .metric("area", "Outline area", c.area_mm2[outline], "mm²", "The area the outline encloses on the platform (its holes not taken off).")
            .metric("holes", "Holes kept", kept.len() as f64, "", "Openings inside the outline, left unfilled: the points and the path keep out of them.")
            .metric(
                "other_outlines",
                "Smaller outlines left out",
                (outlines - 1) as f64,
                "",
                "Other places the part meets the platform; only the largest is filled.",
            )
            .metric(
                "open_chains",
                "Open cuts dropped",
                c.open_chains as f64,
                "",
                "Cuts that did not close because the mesh is open there: repair the mesh if this is not 0.",
            );
        // Only layer 0 reports; the others are in the per-layer table.
        Ok((d, (k == 0).then_some(r)))
    })
}

/// The path of layer k through its points (with its report for layer 0), starting nearest
/// `start` when given (where the layer below ended); the toolpath is made from it by the run.
#[allow(clippy::too_many_arguments)]
pub(super) fn path_stage(
    j: &AxisymJob,
    ctx: &mut Ctx,
    platform: &Out<Platform>,
    domain: &Out<Domain>,
    distribution: &Out<uniform::Distribution>,
    k: usize,
    start: Option<[f64; 2]>,
) -> Result<Out<tour::Tour>, Error> {
    let mut o = j.path.clone();
    if let Some([u, theta]) = start {
        o.start = tour::Start::Nearest { u, theta };
    }
    let parts = (&o, k as f64 * j.layer_height_mm);
    ctx.stage("path", &layer_id("path", k), &parts, &[platform.key, domain.key, distribution.key], |progress| {
        let surface = layer_offset(&platform.value, j, k, &domain.value).map_err(|e| Error::stage("path", e))?;
        let profile = surface.profile();
        let s = Surface::new(profile);
        let dist = |a: [f64; 2], b: [f64; 2]| s.distance(a, b);
        let d = &*domain.value;
        let crosses = |a: [f64; 2], b: [f64; 2]| d.segment_crosses_hole(a, b);
        let avoid: Option<tour::Avoid> = if d.holes().is_empty() { None } else { Some(&crosses) };
        let t = tour::plan(profile, &distribution.points, &o, &dist, avoid, progress).map_err(|e| Error::stage("path", e))?;
        let report = (k == 0).then(|| path_report(&t, &distribution.value, avoid.is_some()));
        Ok((t, report))
    })
}

/// The tool axes along each layer's tour, one unit axis per pose (the normals, or smoothed within the tilt) and what
/// they ask of the machine at the infill speed, before and after smoothing: the largest speed
/// and acceleration of each axis over the layers (each layer is its own pass).
pub(super) fn axes_stage(j: &AxisymJob, ctx: &mut Ctx, tours: &[&tour::Tour], keys: &[crate::stage::Key]) -> Result<Out<Vec<Vec<[f64; 3]>>>, Error> {
    let design = ctx.design;
    let (h, feed, machine) = (j.layer_height_mm, design.speeds.infill_mm_s, &design.printer.machine);
    ctx.stage("axes", "axes", &(&j.tool_axis, h, feed, machine), keys, |_| {
        let (mut layers, mut raw_all, mut after_all, mut tilt) = (Vec::new(), Vec::new(), Vec::new(), 0.0f64);
        for t in tours {
            let positions: Vec<[f64; 3]> = t.poses.iter().map(|p| p.position).collect();
            let normals: Vec<[f64; 3]> = t.poses.iter().map(|p| p.normal).collect();
            let tips: Vec<[f64; 3]> = t.poses.iter().map(|p| tip(p, h).to_array()).collect();
            let smoothed = dynamics::smooth_axes(&positions, &normals, &j.tool_axis).map_err(|e| Error::stage("axes", e))?;
            let raw = dynamics::dynamics(&tips, &normals, machine, feed).map_err(|e| Error::stage("axes", e))?;
            // Smoothing off (the default): the axes are the normals, the same dynamics.
            let after = if smoothed.axes == normals {
                raw.clone()
            } else {
                dynamics::dynamics(&tips, &smoothed.axes, machine, feed).map_err(|e| Error::stage("axes", e))?
            };
            raw_all.push(raw);
            after_all.push(after);
            tilt = tilt.max(smoothed.max_tilt_deg);
            layers.push(smoothed.axes);
        }
        // The tool's lean from vertical (what a head must reach), over every pose.
        let from_vertical = layers
            .iter()
            .flatten()
            .map(|a| libm::acos((a[2] / libm::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).max(1e-12)).clamp(-1.0, 1.0)).to_degrees())
            .fold(0.0, f64::max);
        let report = axes_report(&j.tool_axis, tilt, &worst(&raw_all), &worst(&after_all), feed).metric(
            "max_from_vertical",
            "Largest tilt from vertical",
            from_vertical,
            "°",
            "The tool axis's largest lean from +Z over the whole path: how far the head must tilt.",
        );
        Ok((layers, Some(report)))
    })
}

/// The largest speed and acceleration of each axis over several passes, their lengths and
/// times added.
pub(super) fn worst(all: &[dynamics::Dynamics]) -> dynamics::Dynamics {
    let mut out = all.first().cloned().unwrap_or(dynamics::Dynamics { axes: Vec::new(), path_mm: 0.0, duration_s: 0.0 });
    for d in all.iter().skip(1) {
        for (o, a) in out.axes.iter_mut().zip(&d.axes) {
            o.max_speed_deg_s = o.max_speed_deg_s.max(a.max_speed_deg_s);
            o.max_accel_deg_s2 = o.max_accel_deg_s2.max(a.max_accel_deg_s2);
        }
        out.path_mm += d.path_mm;
        out.duration_s += d.duration_s;
    }
    out
}

/// Layer k's points on its surface, seeded by [`layer_seed`] (layer 0 reports).
pub(super) fn points_stage(
    j: &AxisymJob,
    ctx: &mut Ctx,
    platform: &Out<Platform>,
    domain: &Out<Domain>,
    k: usize,
) -> Result<Out<uniform::Distribution>, Error> {
    let design = ctx.design;
    let width = line_width(design);
    let seed = layer_seed(design.seed, k);
    let parts = (&j.points, width, seed, k as f64 * j.layer_height_mm);
    ctx.stage("points", &layer_id("points", k), &parts, &[platform.key, domain.key], |progress| {
        let surface = layer_offset(&platform.value, j, k, &domain.value).map_err(|e| Error::stage("points", e))?;
        let d = uniform::distribute(surface.profile(), &domain.value, &j.points, width, seed, progress).map_err(|e| Error::stage("points", e))?;
        let report = (k == 0).then(|| points_report(&d, &j.points, width));
        Ok((d, report))
    })
}

/// The nozzle tip of a pose: `h` out along the normal from the layer's surface.
pub(super) fn tip(p: &tour::Pose, h: f64) -> DVec3 {
    DVec3::from_array(p.position) + DVec3::from_array(p.normal) * h
}

/// The lowest nozzle tip Z over every layer's path, mm (∞ without poses): what must stay on or
/// above the plate (Z ≥ 0).
pub fn lowest_tip_z(tours: &[&tour::Tour], h: f64) -> f64 {
    tours.iter().flat_map(|t| &t.poses).map(|p| tip(p, h).z).fold(f64::INFINITY, f64::min)
}

/// Each layer's tour as one free pass: the tip `h` out along the normal from the layer's
/// surface ((k + 1)·h from the platform), the tool axes `axes[k]` (one per pose: the normals,
/// or smoothed).
pub(super) fn toolpath_of(tours: &[&tour::Tour], axes: &[Vec<[f64; 3]>], h: f64, width: f64) -> Toolpath {
    let mut passes = Vec::with_capacity(tours.len());
    for (t, axes) in tours.iter().zip(axes) {
        if t.poses.len() < 2 {
            continue;
        }
        // A segment that still crosses a hole is not printed: the path stops at its start and
        // the next one starts at its end, reached along the segment's geodesic without
        // extruding (the writer's approach route), so no strand is laid over the hole.
        let mut cuts: Vec<(usize, usize)> = Vec::with_capacity(t.hole_segments.len());
        let mut start = 0;
        let mut next_hole = t.hole_segments.iter().peekable();
        for (k, seg) in t.samples.iter().enumerate() {
            let end = start + seg.len().saturating_sub(1);
            if next_hole.next_if_eq(&&k).is_some() {
                cuts.push((start, end));
            }
            start = end;
        }
        let mut paths = Vec::with_capacity(cuts.len() + 1);
        let mut from = 0;
        let mut approach = None;
        for (a, b) in cuts.into_iter().chain(std::iter::once((t.poses.len() - 1, t.poses.len() - 1))) {
            if a > from {
                let points: Vec<DVec3> = t.poses[from..=a].iter().map(|p| tip(p, h)).collect();
                let data = PointData { tool_axis: Some(axes[from..=a].iter().map(|a| DVec3::from_array(*a)).collect()), ..PointData::default() };
                paths.push(Path { points, feature: Feature::Infill, width, speed_factor: 1.0, approach: approach.take(), data: Some(Box::new(data)) });
            }
            // The hop's inner samples, at the tip height.
            approach = Some(t.poses[(a + 1).min(b)..b].iter().map(|p| tip(p, h)).collect::<Vec<_>>());
            from = b;
        }
        if !paths.is_empty() {
            passes.push(Pass { kind: PassKind::Free, z: lowest_tip_z(&[t], h), height: h, paths });
        }
    }
    Toolpath { passes }
}

//! The layer loop: header, start template, layers, end template. Flavour specifics live in
//! [`super::flavor`].

use super::bgcode::ThumbnailFormat;
use super::flavor::{dialect, feed_mm_min, PathCtx};
use super::format::{duration, fixed, push_fixed, push_u64};
use super::objects::{self, Objects};
use super::out::{AxisWords, Out};
use super::template::expand;
use super::{meta, thumbs};
use super::{Error, Flavor, Gcode, GcodeStats, ObjectLabels, Options, Origin};
use super::{DEFAULT_END_GCODE, DEFAULT_PNEUMATIC_END_GCODE, DEFAULT_PNEUMATIC_START_GCODE, DEFAULT_START_GCODE};
use crate::geom::{DVec3, Feature, PassKind, Path, PointFlow, Toolpath};
use crate::machine::{AxisOutput, Machine};

/// Speed of `feature` in mm/s, before the path's speed factor.
fn feature_speed(options: &Options, feature: Feature, first_layer: bool) -> f64 {
    let s = &options.speeds;
    if first_layer {
        return s.first_layer_mm_s;
    }
    match feature {
        Feature::ExternalPerimeter => s.external_perimeter_mm_s,
        Feature::Perimeter | Feature::Skirt => s.perimeter_mm_s,
        Feature::Infill => s.infill_mm_s,
        Feature::SolidInfill => s.solid_infill_mm_s,
        Feature::Lattice | Feature::Contour | Feature::Handle | Feature::Beam => s.lattice_mm_s,
        Feature::Support | Feature::SupportInterface => s.support_mm_s,
        Feature::Bridge => s.bridge_mm_s,
        Feature::OverhangPerimeter => s.overhang_mm_s,
    }
}

/// GIPPO equation 4: filament length for a segment, mm.
pub fn equation4_e(length_mm: f64, layer_height_mm: f64, width_mm: f64, em: f64, k: f64, filament_diameter_mm: f64) -> f64 {
    k * 4.0 * length_mm * layer_height_mm * em * width_mm / (std::f64::consts::PI * filament_diameter_mm * filament_diameter_mm)
}

/// Filament for a segment of `len` mm: the path's per-point flow at its end point `j`, or
/// equation 4 (exactly as before for paths without per-point flow; with
/// `material.compensate_swell`, its width is the predicted swollen width B·w).
pub(crate) fn segment_e(options: &Options, path: &Path, height: f64, j: usize, len: f64) -> f64 {
    let m = &options.material;
    let fd = options.printer.filament_diameter_mm;
    match path.data.as_deref().and_then(|d| d.flow.as_ref()) {
        // A bridge is a round strand of the line's width (nothing under it to flatten it).
        None if path.feature == Feature::Bridge => m.k * m.extrusion_multiplier * m.bridge_flow * len * path.width * path.width / (fd * fd),
        None if m.compensate_swell => equation4_e(len, height, m.swollen_width(path.width), m.extrusion_multiplier, m.k, fd),
        None => equation4_e(len, height, path.width, m.extrusion_multiplier, m.k, fd),
        Some(PointFlow::AreaMm2(a)) => m.k * m.extrusion_multiplier * len * a[j] / (std::f64::consts::PI * fd * fd / 4.0),
        Some(PointFlow::FilamentPerMm(f)) => f[j] * len,
    }
}

/// Extruding moves shorter than this are merged into their neighbours, mm (a twentieth of
/// the narrowest line weft prints, and under the 0.001 mm its coordinates are written to
/// ten times over).
pub const MIN_MOVE_MM: f64 = 0.01;

/// A whole path shorter than [`MIN_MOVE_MM`] with no dwell: the writer leaves it out.
pub(crate) fn is_sliver(path: &Path) -> bool {
    let dwells = path.data.as_deref().and_then(|d| d.dwell_s.as_deref());
    path.length() < MIN_MOVE_MM && !dwells.is_some_and(|d| d.iter().any(|&s| s > 0.0))
}

/// Which points of `path` a written move ends at, and how many moves were merged: a point
/// closer than [`MIN_MOVE_MM`] to the last one kept is passed over (its move joins the next),
/// unless a dwell is asked there; the last point is always kept, and when the last move is
/// the short one the point before it is passed over instead. Zero-length moves are not
/// counted as merges (they write nothing either way).
pub(crate) fn kept_points(path: &Path, dwells: Option<&[f64]>) -> (Vec<bool>, usize) {
    let n = path.points.len();
    let mut keep = vec![true; n];
    if n < 3 {
        return (keep, 0);
    }
    let dwell_at = |j: usize| dwells.is_some_and(|d| d.get(j).is_some_and(|&s| s > 0.0));
    let mut merged = 0usize;
    let mut last = 0usize;
    for j in 1..n - 1 {
        let d = path.points[last].distance(path.points[j]);
        if d < MIN_MOVE_MM && !dwell_at(j) {
            keep[j] = false;
            if path.points[j - 1].distance(path.points[j]) > 0.0 {
                merged += 1;
            }
        } else {
            last = j;
        }
    }
    // A short last move joins the one before it.
    while last > 0 && !dwell_at(last) && (0.0..MIN_MOVE_MM).contains(&path.points[last].distance(path.points[n - 1])) && path.points[last] != path.points[n - 1]
    {
        keep[last] = false;
        merged += 1;
        last = (0..last).rev().find(|&k| keep[k]).unwrap_or(0);
    }
    (keep, merged)
}

/// Every path's per-point data is usable, and a 3-axis printer gets only vertical tool axes.
pub(crate) fn check_point_data(toolpath: &Toolpath, three_axis: bool) -> Result<(), Error> {
    for (pi, pass) in toolpath.passes.iter().enumerate() {
        for (qi, path) in pass.paths.iter().enumerate() {
            let Some(data) = path.data.as_deref() else { continue };
            let problems = data.problems(path.points.len());
            if !problems.is_empty() {
                return Err(Error::BadPointData { pass: pi, path: qi, problems });
            }
            if three_axis {
                if let Some((k, a)) = data.tool_axis.iter().flatten().enumerate().find(|(_, a)| (**a - DVec3::Z).length() > 1e-9) {
                    return Err(Error::NeedsFiveAxis { pass: pi, path: qi, point: k, axis: a.to_array() });
                }
            }
        }
    }
    Ok(())
}

/// Tool axis of point `k` of `path` (+Z without per-point axes).
pub(crate) fn axis_at(path: &Path, k: usize) -> DVec3 {
    path.data.as_deref().and_then(|d| d.tool_axis.as_ref()).and_then(|v| v.get(k).copied()).unwrap_or(DVec3::Z)
}

/// A planned 5-axis pose of a path point.
struct Pose {
    /// Rotary angles, letter order, degrees.
    angles: [f64; 2],
    /// Machine X Y Z of the point at those angles (printer coordinates).
    machine: DVec3,
}

/// The pose of every point of every path (paths in print order, those with fewer than two
/// points empty), angles continuous along the whole print; checks the machine's travel and
/// rotary limits in machine coordinates (path points, approach routes with the path's first
/// pose, and the z-hop above path starts).
fn plan_five_axis(toolpath: &Toolpath, options: &Options, offset: DVec3) -> Result<Vec<Vec<Pose>>, Error> {
    let m = &options.printer.machine;
    let bed = options.printer.bed_size_mm;
    let (lo, hi) = match options.printer.origin {
        Origin::Corner => ([0.0, 0.0, 0.0], bed),
        Origin::Center => ([-bed[0] / 2.0, -bed[1] / 2.0, 0.0], [bed[0] / 2.0, bed[1] / 2.0, bed[2]]),
    };
    let (tlo, thi) = (m.travel_min_mm.unwrap_or(lo), m.travel_max_mm.unwrap_or(hi));
    let travel_setting = if m.travel_min_mm.is_some() || m.travel_max_mm.is_some() {
        "printer.machine.travel_min_mm / travel_max_mm"
    } else {
        "the bed size, printer.bed_size_mm"
    };
    let idx = m.rotary_indices();
    let letters = m.rotary_letters();
    let hop = options.printer.retraction.z_hop_mm.max(0.0);
    let mut prev: Option<[f64; 2]> = None;
    let mut out = Vec::new();
    for (pi, pass) in toolpath.passes.iter().enumerate() {
        for (qi, path) in pass.paths.iter().enumerate() {
            if path.points.len() < 2 {
                out.push(Vec::new());
                continue;
            }
            let limit = |point: usize, axis: char, value: f64, lo: f64, hi: f64, unit: &'static str, setting: &'static str, fix: &'static str| {
                if value >= lo && value <= hi {
                    return Ok(());
                }
                let above = value.is_nan() || value > hi;
                Err(Error::MachineLimit { pass: pi, path: qi, point, axis, value, limit: if above { hi } else { lo }, above, unit, setting, fix })
            };
            let check_xyz = |point: usize, p: DVec3| -> Result<(), Error> {
                for (k, axis) in ['X', 'Y', 'Z'].into_iter().enumerate() {
                    limit(
                        point,
                        axis,
                        p[k],
                        tlo[k] - 1e-6,
                        thi[k] + 1e-6,
                        "mm",
                        travel_setting,
                        "move the part, change the rotary centre or pivot, or widen the travel limits if the machine allows it",
                    )?;
                }
                Ok(())
            };
            let mut poses = Vec::with_capacity(path.points.len());
            for (k, p) in path.points.iter().enumerate() {
                let a = m.inverse(axis_at(path, k), prev);
                prev = Some(a);
                for j in 0..2 {
                    let (rlo, rhi) = (m.rotary_min_deg[idx[j]], m.rotary_max_deg[idx[j]]);
                    limit(
                        k,
                        letters[j] as char,
                        a[j],
                        rlo,
                        rhi,
                        "°",
                        "printer.machine.rotary_min_deg / rotary_max_deg",
                        "tilt the part or its tool axes less, pick the other layout or rotary pair, or widen the limit if the machine allows it",
                    )?;
                }
                let q = m.to_machine(*p + offset, a);
                check_xyz(k, q)?;
                if k == 0 && hop > 0.0 {
                    check_xyz(k, q + DVec3::new(0.0, 0.0, hop))?;
                }
                poses.push(Pose { angles: a, machine: q });
            }
            for (j, r) in path.approach.iter().flatten().enumerate() {
                check_xyz(path.points.len() + j, m.to_machine(*r + offset, poses[0].angles))?;
            }
            out.push(poses);
        }
    }
    Ok(out)
}

/// `s` on one line: a name written into a comment or a placeholder cannot start a G-code
/// line of its own (control characters, including CR, LF and NEL, and the Unicode line and
/// paragraph separators become spaces).
pub(super) fn one_line(s: &str) -> String {
    s.chars().map(|c| if c.is_control() || matches!(c, '\u{2028}' | '\u{2029}') { ' ' } else { c }).collect()
}

fn fan_pwm(percent: f64) -> u64 {
    let v = (percent.clamp(0.0, 100.0) * 255.0 / 100.0).round();
    if v.is_finite() {
        v as u64
    } else {
        0
    }
}

/// Offset from model to printer coordinates: printer point = model point + this.
pub fn bed_offset(options: &Options) -> DVec3 {
    let bed = options.printer.bed_size_mm;
    match options.printer.origin {
        Origin::Corner => DVec3::new(bed[0] / 2.0, bed[1] / 2.0, 0.0),
        Origin::Center => DVec3::ZERO,
    }
}

fn check_bed(toolpath: &Toolpath, options: &Options, offset: DVec3) -> Result<(), Error> {
    let mut min = DVec3::splat(f64::INFINITY);
    let mut max = DVec3::splat(f64::NEG_INFINITY);
    for l in &toolpath.passes {
        for p in &l.paths {
            for q in p.points.iter().chain(p.approach.iter().flatten()) {
                min = min.min(*q + offset);
                max = max.max(*q + offset);
            }
        }
    }
    let bed = options.printer.bed_size_mm;
    let (lo, hi) = match options.printer.origin {
        Origin::Corner => (DVec3::ZERO, DVec3::new(bed[0], bed[1], bed[2])),
        Origin::Center => (DVec3::new(-bed[0] / 2.0, -bed[1] / 2.0, 0.0), DVec3::new(bed[0] / 2.0, bed[1] / 2.0, bed[2])),
    };
    let eps = 1e-6;
    let finite = min.is_finite() && max.is_finite();
    if !finite || min.x < lo.x - eps || min.y < lo.y - eps || min.z < lo.z - eps || max.x > hi.x + eps || max.y > hi.y + eps || max.z > hi.z + eps {
        let size = max - min;
        let below_plate_mm = if finite && min.z < lo.z - eps { lo.z - min.z } else { 0.0 };
        return Err(Error::OutsideBed { size_mm: [size.x, size.y, size.z], bed_mm: bed, below_plate_mm });
    }
    Ok(())
}

/// Writes a path's extruding moves as lines and arcs: the moves kept by `keep` (zero-length
/// ones dropped) in printer coordinates, fitted by [`super::arcs::fit`]; each arc feeds the
/// filament of the segments it replaces. Returns the length written (arcs along their
/// circle) and the arcs written.
#[allow(clippy::too_many_arguments)]
fn write_with_arcs(
    out: &mut Out,
    d: &mut dyn super::flavor::Dialect,
    path: &Path,
    keep: &[bool],
    offset: DVec3,
    tol: f64,
    feed: u64,
    e_of: impl Fn(usize, f64) -> f64,
) -> (f64, usize) {
    // Kept points and, per move to each, its length and filament.
    let mut pts = vec![path.points[0] + offset];
    let mut moves: Vec<(f64, f64)> = Vec::new();
    let (mut len, mut e) = (0.0f64, 0.0f64);
    for (i, w) in path.points.windows(2).enumerate() {
        let j = i + 1;
        let step = w[0].distance(w[1]);
        if step > 0.0 {
            len += step;
            e += e_of(j, step);
        }
        if keep[j] && len > 0.0 {
            pts.push(path.points[j] + offset);
            moves.push((len, e));
            (len, e) = (0.0, 0.0);
        }
    }
    let (mut written, mut arcs) = (0.0, 0usize);
    for (start, m) in super::arcs::spans(&super::arcs::fit(&pts, tol)) {
        match *m {
            super::arcs::Move::Line { end } => {
                for k in start + 1..=end {
                    d.segment(out, pts[k], moves[k - 1].1, feed);
                    written += moves[k - 1].0;
                }
            }
            super::arcs::Move::Arc { end, center, clockwise } => {
                let e: f64 = moves[start..end].iter().map(|m| m.1).sum();
                let from = pts[start].truncate();
                let ij = super::arcs::center_offset(from, center);
                out.extrude_arc(pts[end], [ij.x, ij.y], clockwise, e, feed);
                written += super::arcs::arc_length(from, pts[end].truncate(), center, clockwise);
                arcs += 1;
            }
        }
    }
    (written, arcs)
}

/// Writes the G-code; see [`super::write_gcode`].
pub(crate) fn write(toolpath: &Toolpath, options: &Options) -> Result<Gcode, Error> {
    if toolpath.passes.iter().all(|l| l.paths.iter().all(|p| p.points.len() < 2)) {
        return Err(Error::Empty);
    }
    let offset = bed_offset(options);
    check_bed(toolpath, options, offset)?;
    let printer = &options.printer;
    let material = &options.material;
    if printer.flavor == Flavor::PosesCsv {
        check_point_data(toolpath, false)?;
        return Ok(super::poses::write(toolpath, options, offset));
    }
    let machine: &Machine = &printer.machine;
    check_point_data(toolpath, !machine.is_five_axis())?;
    let plan = if machine.is_five_axis() { Some(plan_five_axis(toolpath, options, offset)?) } else { None };
    let pwm = fan_pwm(material.fan_percent);
    let boost_pwm = fan_pwm(material.bridge_fan_percent);
    let vars: Vec<(&str, String)> = vec![
        ("nozzle_temp_c", fixed(material.nozzle_temp_c, 1)),
        ("first_layer_nozzle_temp_c", fixed(material.first_layer_nozzle_temp_c, 1)),
        ("bed_temp_c", fixed(material.bed_temp_c, 1)),
        ("bed_x_mm", fixed(printer.bed_size_mm[0], 3)),
        ("bed_y_mm", fixed(printer.bed_size_mm[1], 3)),
        ("fan_pwm", pwm.to_string()),
        ("design_name", one_line(&options.design_name)),
    ];
    let pneumatic = printer.flavor == Flavor::Pneumatic;
    let start_template = if pneumatic && printer.start_gcode == DEFAULT_START_GCODE { DEFAULT_PNEUMATIC_START_GCODE } else { &printer.start_gcode };
    let end_template = if pneumatic && printer.end_gcode == DEFAULT_END_GCODE { DEFAULT_PNEUMATIC_END_GCODE } else { &printer.end_gcode };
    let start = expand(start_template, "start_gcode", &vars)?;
    let end = expand(end_template, "end_gcode", &vars)?;

    // Rotary angles: 5 decimals (≤ 5e-6° rounding, under 1e-7 rad on the axis); I J K: 7.
    let axes = plan.as_ref().map(|_| match machine.axis_output {
        AxisOutput::Rotary => {
            let l = machine.rotary_letters();
            AxisWords { letters: [l[0], l[1], 0], decimals: 5, all_or_none: false }
        }
        AxisOutput::Ijk => AxisWords { letters: [b'I', b'J', b'K'], decimals: 7, all_or_none: true },
    });
    let rotary_xyz = plan.is_some() && machine.axis_output == AxisOutput::Rotary;
    let mut out = Out::new(printer.relative_e, axes);
    let mut d = dialect(printer.flavor);
    // Object labels (Marlin flavour): declared before the start code, each path inside its
    // object's start and end lines, every object ended at its layer's end.
    let labels = if printer.flavor == Flavor::Marlin { printer.object_labels } else { ObjectLabels::None };
    let objects = if labels == ObjectLabels::None { Objects::default() } else { objects::find(toolpath, offset, &options.design_name) };
    let defined = objects::define(&objects.list, labels);
    if !defined.is_empty() {
        out.line(defined.strip_suffix('\n').unwrap_or(&defined));
    }
    let mut in_object: Option<usize> = None;
    if !start.is_empty() {
        out.code(start.strip_suffix('\n').unwrap_or(&start));
    }
    d.prologue(&mut out, options);

    let mut extruded_mm = 0.0;
    let mut layers_written = 0usize;
    // Planar layers written (first-layer rules and the fan count only these).
    let mut planar = 0usize;
    let mut fan_on = false;
    // The fan as last written: bridges and overhangs raise it to `boost_pwm` for their paths.
    let mut fan_now = 0u64;
    let mut temp_switched = false;
    let mut path_no = 0usize;
    let mut line = String::new();
    let mut route_buf: Vec<DVec3> = Vec::new();
    let mut merged_moves = 0usize;
    let arc_tol = if printer.flavor == Flavor::Marlin && printer.arc_tolerance_mm.is_finite() { printer.arc_tolerance_mm.max(0.0) } else { 0.0 };
    let mut arcs_written = 0usize;
    let (mut dropped_paths, mut dropped_e) = (0usize, 0.0f64);
    for layer in &toolpath.passes {
        if layer.paths.iter().all(|p| p.points.len() < 2) {
            path_no += layer.paths.len();
            continue;
        }
        if let Some(i) = in_object.take() {
            out.line(&objects::end(&objects.list, i, labels));
        }
        let n = layers_written;
        layers_written += 1;
        let free = layer.kind == PassKind::Free;
        let first_layer = !free && planar == 0;
        line.clear();
        line.push_str(";LAYER_CHANGE\n;Z:");
        push_fixed(&mut line, layer.z, 3);
        line.push_str("\n;HEIGHT:");
        push_fixed(&mut line, layer.height, 3);
        line.push_str("\n;LAYER:");
        push_u64(&mut line, n as u64);
        out.line(&line);
        // A free pass is never a first layer: full fan and the normal temperature.
        if pwm > 0 && !fan_on && (free || planar as u64 == material.fan_start_layer as u64) {
            out.line(&format!("M106 S{pwm}"));
            fan_on = true;
            fan_now = pwm;
        }
        if !temp_switched && (free || planar == 1) {
            out.line(&format!("M104 S{}", fixed(material.nozzle_temp_c, 1)));
            temp_switched = true;
        }
        if !free {
            planar += 1;
        }
        let mut feature: Option<Feature> = None;
        let mut width: Option<i64> = None;
        for path in &layer.paths {
            let poses: &[Pose] = plan.as_ref().map_or(&[], |p| &p[path_no]);
            let object = objects.of_path.get(path_no).copied().flatten();
            path_no += 1;
            if path.points.len() < 2 {
                continue;
            }
            let data = path.data.as_deref();
            let feeds = data.and_then(|d| d.feed_mm_s.as_deref());
            let dwells = data.and_then(|d| d.dwell_s.as_deref());
            // A whole path shorter than the shortest move (a sliver a clip left) has no
            // neighbour to join: it is left out, with its travel and retraction, and counted.
            if is_sliver(path) {
                dropped_paths += 1;
                dropped_e +=
                    (1..path.points.len()).map(|j| segment_e(options, path, layer.height, j, path.points[j - 1].distance(path.points[j]))).sum::<f64>();
                continue;
            }
            // Where a point on the segment to point `k` is written: machine X Y Z for rotary
            // output, the tip otherwise (path points themselves: `at`, planned already); and
            // the axis words it carries.
            let place = |q: DVec3, k: usize| if rotary_xyz { machine.to_machine(q + offset, poses[k].angles) } else { q + offset };
            let at = |k: usize| if rotary_xyz { poses[k].machine } else { path.points[k] + offset };
            let aim = |out: &mut Out, k: usize| {
                if out.axes.is_some() {
                    out.axis_target = match machine.axis_output {
                        AxisOutput::Rotary => [poses[k].angles[0], poses[k].angles[1], 0.0],
                        AxisOutput::Ijk => axis_at(path, k).to_array(),
                    };
                }
            };
            if object != in_object {
                if let Some(i) = in_object {
                    out.line(&objects::end(&objects.list, i, labels));
                }
                if let Some(i) = object {
                    out.line(&objects::start(&objects.list, i, labels));
                }
                in_object = object;
            }
            aim(&mut out, 0);
            let first = at(0);
            match &path.approach {
                Some(route) if out.pos.is_some() => {
                    route_buf.clear();
                    route_buf.extend(route.iter().map(|q| place(*q, 0)));
                    d.approach(&mut out, &route_buf, first, options);
                }
                _ => d.travel(&mut out, first, options),
            }
            out.flush_axes();
            let boost = matches!(path.feature, Feature::Bridge | Feature::OverhangPerimeter) && boost_pwm > 0;
            let want = if boost {
                boost_pwm.max(if fan_on { pwm } else { 0 })
            } else if fan_on {
                pwm
            } else {
                0
            };
            if want != fan_now {
                out.line(&if want == 0 { "M107".to_string() } else { format!("M106 S{want}") });
                fan_now = want;
            }
            if feature != Some(path.feature) {
                out.line(&format!(";TYPE:{}", path.feature.gcode_name()));
                feature = Some(path.feature);
            }
            let wi = (path.width * 1000.0).round() as i64;
            if width != Some(wi) {
                out.line(&format!(";WIDTH:{}", fixed(path.width, 3)));
                width = Some(wi);
            }
            let speed = feature_speed(options, path.feature, first_layer) * path.speed_factor;
            let feed = feed_mm_min(speed);
            let ctx = PathCtx { speed_factor: path.speed_factor, speed_mm_s: speed };
            d.path_begin(&mut out, options, &ctx);
            if let Some(dw) = dwells {
                out.dwell(dw[0], "");
            }
            // The dialect may end the path early (pneumatic post-flow): from `cut` mm on, the
            // remaining moves are coasts.
            let lead = d.end_lead_mm(options, &ctx);
            let cut = if lead > 0.0 { (path.length() - lead).max(0.0) } else { f64::INFINITY };
            let mut done = 0.0;
            let mut open = true;
            if cut <= 0.0 {
                d.path_end(&mut out, options);
                open = false;
            }
            // Moves shorter than MIN_MOVE_MM are merged into the next (dust stutters a
            // printer's planner): their filament goes with it, so the total is unchanged.
            let (keep, merged) = kept_points(path, dwells);
            merged_moves += merged;
            // Arcs (Marlin, 3-axis, a planar path without per-point feeds or dwells): the kept
            // moves, fitted with G2/G3 where they lie within the tolerance of an arc.
            if arc_tol > 0.0 && plan.is_none() && feeds.is_none() && dwells.is_none() && lead <= 0.0 && path.points.iter().all(|q| q.z == path.points[0].z) {
                let (written, arcs) =
                    write_with_arcs(&mut out, &mut *d, path, &keep, offset, arc_tol, feed, |j, step| segment_e(options, path, layer.height, j, step));
                extruded_mm += written;
                arcs_written += arcs;
                d.path_end(&mut out, options);
                continue;
            }
            let (mut from, mut len, mut e) = (0usize, 0.0f64, 0.0f64);
            for (i, w) in path.points.windows(2).enumerate() {
                let j = i + 1;
                let step = w[0].distance(w[1]);
                if step > 0.0 {
                    len += step;
                    e += segment_e(options, path, layer.height, j, step);
                }
                if !keep[j] {
                    continue;
                }
                let (start, piece, piece_e) = (path.points[from], len, e);
                from = j;
                (len, e) = (0.0, 0.0);
                if piece <= 0.0 {
                    if let Some(dw) = dwells {
                        out.dwell(dw[j], "");
                    }
                    continue;
                }
                let feed = feeds.map_or(feed, |f| feed_mm_min(f[j]));
                extruded_mm += piece;
                aim(&mut out, j);
                let to = at(j);
                if !open {
                    d.coast(&mut out, to, feed);
                } else if done + piece > cut + 1e-9 {
                    let t = (cut - done) / piece;
                    if t * piece > 1e-9 {
                        d.segment(&mut out, place(start.lerp(path.points[j], t), j), piece_e * t, feed);
                    }
                    d.path_end(&mut out, options);
                    open = false;
                    d.coast(&mut out, to, feed);
                } else {
                    d.segment(&mut out, to, piece_e, feed);
                }
                done += piece;
                if let Some(dw) = dwells {
                    out.dwell(dw[j], "");
                }
            }
            if open {
                d.path_end(&mut out, options);
            }
        }
    }
    if let Some(i) = in_object.take() {
        out.line(&objects::end(&objects.list, i, labels));
    }
    let moves_end = out.text.len();
    d.epilogue(&mut out, options);
    if !end.is_empty() {
        out.code(end.strip_suffix('\n').unwrap_or(&end));
    }

    // Time and travel of the moves as printed, with the analyzer's model (`crate::motion`), so
    // header, stats and `weft analyze` agree; nothing when a user code makes the file unreadable.
    out.motion.timer.stop();
    let (time_s, travel_mm) = if out.motion_ok { (out.motion.timer.total(), out.motion.travel_mm) } else { (0.0, 0.0) };
    let stats = GcodeStats {
        layers: layers_written,
        extruded_mm,
        filament_mm: out.e_total,
        travel_mm,
        retractions: out.retractions,
        estimated_time_s: time_s,
        merged_moves,
        dropped_paths,
        dropped_filament_mm: dropped_e,
        arcs: arcs_written,
        arc_bytes_saved: 0,
    };

    let volume_cm3 = meta::volume_cm3(out.e_total, printer.filament_diameter_mm);
    let mut header = meta::generated_line(&options.date);
    if printer.flavor == Flavor::Marlin {
        // PNG for hosts and web pages, then QOI for Prusa's screens.
        let pngs: Vec<(u32, u32, Vec<u8>)> = printer.thumbnails.iter().take(super::MAX_THUMBNAILS).map(|&[w, h]| (w, h, thumbs::png(toolpath, w, h))).collect();
        header.push_str(&meta::thumbnail_blocks(&pngs, ThumbnailFormat::Png));
        let qois: Vec<(u32, u32, Vec<u8>)> =
            printer.thumbnails_qoi.iter().take(super::MAX_THUMBNAILS).map(|&[w, h]| (w, h, thumbs::qoi(toolpath, w, h))).collect();
        header.push_str(&meta::thumbnail_blocks(&qois, ThumbnailFormat::Qoi));
    }
    header.push_str(&format!("; design: {}\n", one_line(&options.design_name)));
    header.push_str(&format!("; printer: {}\n", one_line(&printer.name)));
    header.push_str(&format!("; material: {}\n", one_line(&material.name)));
    header.push_str(&format!("; estimated printing time (normal mode) = {}\n", duration(time_s)));
    header.push_str(&format!("; filament used [mm] = {}\n", fixed(out.e_total, 2)));
    header.push_str(&format!("; filament used [cm3] = {}\n", fixed(volume_cm3, 3)));
    header.push_str(&format!("; extruded path length [mm] = {}\n", fixed(extruded_mm, 2)));
    header.push_str(&format!(";FLAVOR:{}\n", printer.flavor.name()));
    header.push_str(&format!(";TIME:{}\n", fixed(time_s, 0)));
    header.push_str(&format!(";Filament used: {}m\n", fixed(out.e_total / 1000.0, 5)));
    header.push_str(&format!(";LAYER_COUNT:{layers_written}\n"));
    let header_len = header.len();
    header.push_str(&out.text);
    let body_len = header.len();
    header.push_str(";\n");
    header.push_str(&meta::footer(toolpath, options, &meta::Totals { filament_mm: out.e_total, time_s, layers: layers_written }));
    let footer_len = header.len() - body_len;
    Ok(Gcode { text: header, stats, header_len, moves_end: header_len + moves_end, footer_len })
}

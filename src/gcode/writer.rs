//! The layer loop: header, start template, layers, end template. Flavour specifics live in
//! [`super::flavor`].

use super::flavor::{dialect, feed_mm_min, PathCtx};
use super::out::Out;
use super::format::{duration, fixed, push_fixed, push_u64};
use super::template::expand;
use super::{Error, Flavor, Gcode, GcodeStats, Options, Origin};
use super::{DEFAULT_END_GCODE, DEFAULT_PNEUMATIC_END_GCODE, DEFAULT_PNEUMATIC_START_GCODE, DEFAULT_START_GCODE};
use crate::geom::{DVec3, Feature, Toolpath};

/// Speed of `feature` in mm/s, before the path's speed factor.
fn feature_speed(options: &Options, feature: Feature, layer: usize) -> f64 {
    let s = &options.speeds;
    if layer == 0 {
        return s.first_layer_mm_s;
    }
    match feature {
        Feature::ExternalPerimeter => s.external_perimeter_mm_s,
        Feature::Perimeter | Feature::Skirt => s.perimeter_mm_s,
        Feature::Infill => s.infill_mm_s,
        Feature::SolidInfill => s.solid_infill_mm_s,
        Feature::Lattice | Feature::Contour | Feature::Handle => s.lattice_mm_s,
    }
}

/// GIPPO equation 4: filament length for a segment, mm.
pub fn equation4_e(length_mm: f64, layer_height_mm: f64, width_mm: f64, em: f64, k: f64, filament_diameter_mm: f64) -> f64 {
    k * 4.0 * length_mm * layer_height_mm * em * width_mm / (std::f64::consts::PI * filament_diameter_mm * filament_diameter_mm)
}

/// Text safe inside a `;` comment line.
fn one_line(s: &str) -> String {
    s.chars().map(|c| if c.is_control() { ' ' } else { c }).collect()
}

fn fan_pwm(percent: f64) -> u64 {
    let v = (percent.clamp(0.0, 100.0) * 255.0 / 100.0).round();
    if v.is_finite() { v as u64 } else { 0 }
}

/// Offset from model to printer coordinates.
fn bed_offset(options: &Options) -> DVec3 {
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

/// Writes the G-code; see [`super::write_gcode`].
pub(crate) fn write(toolpath: &Toolpath, options: &Options) -> Result<Gcode, Error> {
    if toolpath.passes.iter().all(|l| l.paths.iter().all(|p| p.points.len() < 2)) {
        return Err(Error::Empty);
    }
    let offset = bed_offset(options);
    check_bed(toolpath, options, offset)?;
    let printer = &options.printer;
    let material = &options.material;
    let pwm = fan_pwm(material.fan_percent);
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

    let mut out = Out::new(printer.relative_e, None);
    let mut d = dialect(printer.flavor);
    if !start.is_empty() {
        out.code(start.strip_suffix('\n').unwrap_or(&start));
    }
    d.prologue(&mut out, options);

    let mut extruded_mm = 0.0;
    let mut layers_written = 0usize;
    let mut line = String::new();
    let mut route_buf: Vec<DVec3> = Vec::new();
    for layer in &toolpath.passes {
        if layer.paths.iter().all(|p| p.points.len() < 2) {
            continue;
        }
        let n = layers_written;
        layers_written += 1;
        line.clear();
        line.push_str(";LAYER_CHANGE\n;Z:");
        push_fixed(&mut line, layer.z, 3);
        line.push_str("\n;HEIGHT:");
        push_fixed(&mut line, layer.height, 3);
        line.push_str("\n;LAYER:");
        push_u64(&mut line, n as u64);
        out.line(&line);
        if n as u64 == material.fan_start_layer as u64 && pwm > 0 {
            out.line(&format!("M106 S{pwm}"));
        }
        if n == 1 {
            out.line(&format!("M104 S{}", fixed(material.nozzle_temp_c, 1)));
        }
        let mut feature: Option<Feature> = None;
        let mut width: Option<i64> = None;
        for path in &layer.paths {
            if path.points.len() < 2 {
                continue;
            }
            let first = path.points[0] + offset;
            match &path.approach {
                Some(route) if out.pos.is_some() => {
                    route_buf.clear();
                    route_buf.extend(route.iter().map(|q| *q + offset));
                    d.approach(&mut out, &route_buf, first, options);
                }
                _ => d.travel(&mut out, first, options),
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
            let speed = feature_speed(options, path.feature, n) * path.speed_factor;
            let feed = feed_mm_min(speed);
            let ctx = PathCtx { speed_factor: path.speed_factor, speed_mm_s: speed };
            d.path_begin(&mut out, options, &ctx);
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
            for w in path.points.windows(2) {
                let len = w[0].distance(w[1]);
                if len <= 0.0 {
                    continue;
                }
                let e = equation4_e(len, layer.height, path.width, material.extrusion_multiplier, material.k, printer.filament_diameter_mm);
                extruded_mm += len;
                let to = w[1] + offset;
                if !open {
                    d.coast(&mut out, to, feed);
                } else if done + len > cut + 1e-9 {
                    let t = (cut - done) / len;
                    if t * len > 1e-9 {
                        d.segment(&mut out, w[0].lerp(w[1], t) + offset, e * t, feed);
                    }
                    d.path_end(&mut out, options);
                    open = false;
                    d.coast(&mut out, to, feed);
                } else {
                    d.segment(&mut out, to, e, feed);
                }
                done += len;
            }
            if open {
                d.path_end(&mut out, options);
            }
        }
    }
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
    };

    let fd = printer.filament_diameter_mm;
    let volume_cm3 = out.e_total * std::f64::consts::PI * fd * fd / 4.0 / 1000.0;
    let mut header = String::new();
    header.push_str(&format!("; generated by weft {}\n", env!("CARGO_PKG_VERSION")));
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
    header.push_str(&out.text);
    Ok(Gcode { text: header, stats })
}

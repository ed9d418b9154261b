//! The axisymmetric job's checks of a design: every problem listed with its path and its fix.

use super::*;

/// Every problem of the design for this kind (`Kind::validate`), each with its path.
pub(super) fn validate(design: &Design, j: &AxisymJob, out: &mut Vec<Problem>) {
    out.extend(crate::kinds::thicker_than_nozzle("job.layer_height_mm", j.layer_height_mm, design.printer.nozzle_diameter_mm));
    if !design.printer.machine.is_five_axis() && design.printer.flavor != crate::gcode::Flavor::PosesCsv {
        out.push(Problem {
            path: "printer.machine.kind".into(),
            message: "this job tilts the tool along the platform's normal: pick a 5-axis machine (printer profile '5-axis head (B/C)', --printer five-axis-head) or the poses CSV output (printer.flavor = poses_csv)".into(),
        });
    }
    let platform = match Platform::from_polygon(&j.platform.control_points) {
        Ok(p) => p,
        Err(e) => {
            out.push(Problem { path: "job.platform.control_points".into(), message: e.to_string() });
            return;
        }
    };
    if let Err(e) = platform.validate(&platform::Options::default()) {
        out.push(Problem { path: "job.platform.control_points".into(), message: e.to_string() });
        return;
    }
    let path = match j.domain.kind {
        DomainKind::Rectangle => "job.domain",
        DomainKind::Polygon => "job.domain.polygon",
        DomainKind::Part => "job.part",
    };
    match j.domain.domain() {
        Some(d) => {
            let problems = d.problems(&platform);
            for message in &problems {
                out.push(Problem { path: path.into(), message: message.to_string() });
            }
            // The top layer's surface is the furthest offset: if it neither folds nor nears
            // the axis over Ω, no lower one does.
            if problems.is_empty() && (2..=MAX_LAYERS).contains(&j.layers) && j.layer_height_mm.is_finite() {
                let k = j.layers - 1;
                if let Err(e) = layer_offset(&platform, j, k, &d) {
                    out.push(Problem { path: "job.layers".into(), message: e.to_string() });
                }
            }
        }
        None if j.part.is_none() => out.push(Problem {
            path: path.into(),
            message: "the domain is where a part meets the platform: load the part (its drop zone, or --input part=FILE) or pick a rectangle or polygon".into(),
        }),
        None => {}
    }
    // A radial grading's centre needs the metric too (the form's range allows the poles).
    if let Err(e) = uniform::check_centre(&platform, &j.points) {
        out.push(Problem { path: "job.points.grading.centre_u".into(), message: e.to_string() });
    }
}

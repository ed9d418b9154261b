//! The freeform job's checks of a design: every problem listed with its path and its fix.

use super::*;

/// Every problem of the design for this kind (`Kind::validate`), each with its path.
pub(super) fn validate(_design: &Design, j: &FreeformJob, out: &mut Vec<Problem>) {
    if j.model.is_none() && j.input.is_none() {
        out.push(Problem { path: "job.input".into(), message: "a freeform job needs a wireframe: load one, or switch on a built-in design".into() });
    }
    if let Some(m) = &j.model {
        for message in models::problems(m) {
            out.push(Problem { path: "job.model".into(), message });
        }
    }
    let n = &j.nozzle;
    if !(n.half_angle_deg > 0.0 && n.half_angle_deg < 90.0) {
        out.push(Problem {
            path: "job.nozzle.half_angle_deg".into(),
            message: format!("{}° is not a cone: use more than 0° and less than 90°", n.half_angle_deg),
        });
    }
    if n.tilt_deg > 0.0 && _design.printer.machine.kind == crate::machine::Kind::Cartesian {
        out.push(Problem {
            path: "job.nozzle.tilt_deg".into(),
            message: format!(
                "a nozzle that tilts {}° needs a 5-axis machine: set the printer's machine to five_axis, or the tilt to 0° for a 3-axis printer",
                n.tilt_deg
            ),
        });
    }
}

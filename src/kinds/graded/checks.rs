//! The graded job's checks of a design: every problem listed with its path and its fix.

use super::*;

/// Every problem of the design for this kind (`Kind::validate`), each with its path.
pub(super) fn validate(design: &Design, j: &GradedJob, out: &mut Vec<Problem>) {
    out.extend(crate::kinds::thicker_than_nozzle("job.slice.layer_height_mm", j.slice.layer_height_mm, design.printer.nozzle_diameter_mm));
    for message in j.density.calibration.problems() {
        out.push(Problem { path: "job.density.points".into(), message });
    }
    if j.density.min_width_mm >= j.density.max_width_mm {
        out.push(Problem { path: "job.density.min_width_mm".into(), message: "E_w,min must be narrower than E_w,max".into() });
    }
    if let Some(r) = &j.roi {
        if (0..3).any(|a| !(r.max_mm[a] > r.min_mm[a])) {
            out.push(Problem { path: "job.roi".into(), message: "each 'to' corner value must be larger than its 'from' value".into() });
        }
    }
    if j.density.cell_sizing == CellSizing::Graded && (j.route != Route::Native || j.slice.infill_pattern != InfillPattern::Gyroid) {
        out.push(Problem {
            path: "job.density.cell_sizing".into(),
            message: "a graded cell size needs route 'native' and the gyroid pattern (job.slice.infill_pattern); or set it to 'fixed'".into(),
        });
    }
    if !(j.density.max_cell_ratio >= 1.0 && j.density.max_cell_ratio <= 10.0) {
        out.push(Problem { path: "job.density.max_cell_ratio".into(), message: "the cell size range must be between 1 and 10".into() });
    }
    if j.route == Route::Edit && j.gcode.is_none() {
        out.push(Problem {
            path: "job.gcode".into(),
            message: "route 'edit' rewrites another slicer's G-code: load it (its drop zone, or --input gcode=FILE), or pick route 'native'".into(),
        });
    }
}

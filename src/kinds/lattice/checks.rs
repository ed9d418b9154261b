//! The lattice job's checks of a design: every problem listed with its path and its fix.

use super::*;

/// Every problem of the design for this kind (`Kind::validate`), each with its path.
pub(super) fn validate(design: &Design, j: &LatticeJob, out: &mut Vec<Problem>) {
    out.extend(crate::kinds::thicker_than_nozzle("job.lattice.layer_thickness_mm", j.lattice.layer_thickness_mm, design.printer.nozzle_diameter_mm));
    if j.domain == Domain::Solid && j.input.is_none() {
        out.push(Problem { path: "job.input".into(), message: "a solid domain needs a solid: load a mesh or set job.input".into() });
    }
    if let Some(np) = &j.nonplanar {
        if np.surface == nonplanar::Surface::Mesh && j.surface_input.is_none() {
            out.push(Problem {
                path: "job.surface_input".into(),
                message: "a mesh surface needs a mesh: load the surface file or set job.surface_input".into(),
            });
        }
    }
    for o in &j.lattice.overrides {
        if o.layer >= j.lattice.layers && j.domain != Domain::Solid {
            out.push(Problem {
                path: "job.lattice.overrides".into(),
                message: format!("layer {} does not exist (the lattice has {} layers, numbered from 0)", o.layer, j.lattice.layers),
            });
        }
    }
}

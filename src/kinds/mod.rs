//! Job kinds as plug-ins. Each kind is one module that declares, in one place, its settings
//! (serde) and their form rows, its input slots, its stages (for progress), its validation
//! rules, its extra views and its run function. [`Registry::builtin`] lists them: adding a
//! kind is one new module plus one line there; the design, the pipeline, the CLI and the page
//! read everything else from the kind.
//!
//! ```text
//!  Design.job {kind, …} ──► Registry::get(kind) ──► JobKind::run(ctx) ──► Product (toolpath)
//!                                                      │ ctx.stage(name, key, …)  (cached per stage)
//!                                                      ▼
//!                                       pipeline: gcode ─► analyze ─► RunReport
//! ```

pub mod axisymmetric;
pub mod foam;
pub mod freeform;
pub mod graded;
pub mod lattice;
pub mod slice;

use crate::design::Design;
use crate::settings::Problem;
use crate::stage::Error;
pub use crate::stage::{settings, with_kind, Inspection, JobKind, Kind, Product, Shape, Slot, SlotKind, StageInfo, StepInfo, Teach, ViewInfo, FILE_HEAD_BYTES};

/// The slice stage's report as the page shows it: the repairs made while cutting layers, each
/// only when it happened (the layer count is in the run's overall statistics).
pub fn slice_report(r: &crate::slice::SliceReport, label: &str) -> crate::report::StageReport {
    let mut report = crate::report::StageReport::new("slice", label, r);
    for (key, label, value, unit, hint) in [
        ("gaps_closed", "Gaps closed", r.gaps_closed as f64, "", "Open outlines whose ends were joined (the mesh has small holes)."),
        ("largest_gap", "Largest gap closed", r.largest_gap_closed_mm, "mm", "The widest hole bridged in a layer outline."),
        (
            "open_contours_dropped",
            "Open outlines dropped",
            r.open_contours_dropped as f64,
            "",
            "Outlines too open to close: those parts are not printed; repair the mesh.",
        ),
        ("layers_with_overlaps", "Layers with overlaps", r.layers_with_overlaps as f64, "", "Layers where shells overlap; they were merged into one region."),
    ] {
        if value > 0.0 {
            report = report.metric(key, label, value, unit, hint);
        }
    }
    report
}

/// Refuses a placed `mesh` that does not fit the design's printer, before any slicing: the
/// message gives the part's real size and the bed's.
pub fn part_fits(design: &Design, mesh: &crate::geom::Mesh) -> Result<(), Error> {
    let Some(b) = mesh.bounds() else { return Ok(()) };
    let size = b.max - b.min;
    crate::gcode::check_fits([size.x, size.y, size.z], &design.printer).map_err(|e| Error::stage("the part", e))
}

/// The problem of a layer `height` thicker than the nozzle (`path` names the field): a
/// strand cannot be squashed thicker than the hole it comes out of.
pub fn thicker_than_nozzle(path: &str, height: f64, nozzle: f64) -> Option<Problem> {
    (height > nozzle).then(|| Problem {
        path: path.into(),
        message: format!("{} mm is thicker than the {} mm nozzle: use at most the nozzle diameter", crate::settings::fmt(height), crate::settings::fmt(nozzle)),
    })
}

/// The job kinds a build knows.
#[derive(Clone)]
pub struct Registry {
    kinds: Vec<&'static dyn JobKind>,
}

impl Registry {
    /// The kinds built into weft. **Register a new kind here** (one line).
    pub fn builtin() -> Registry {
        Registry {
            kinds: vec![&slice::SliceKind, &lattice::LatticeKind, &axisymmetric::AxisymKind, &graded::GradedKind, &foam::FoamKind, &freeform::FreeformKind],
        }
    }

    /// This registry plus `kind` (a kind defined outside the crate, e.g. in a test).
    pub fn with(mut self, kind: &'static dyn JobKind) -> Registry {
        self.kinds.retain(|k| k.name() != kind.name());
        self.kinds.push(kind);
        self
    }

    /// The kind named `name`.
    pub fn get(&self, name: &str) -> Option<&'static dyn JobKind> {
        self.kinds.iter().copied().find(|k| k.name() == name)
    }

    /// The first slot named `name` among the kinds (slots of one name are of one kind).
    pub fn slot(&self, name: &str) -> Option<&'static Slot> {
        self.kinds.iter().flat_map(|k| k.slots()).find(|s| s.name == name)
    }

    /// Every kind, in menu order.
    pub fn kinds(&self) -> &[&'static dyn JobKind] {
        &self.kinds
    }

    /// Names of every kind.
    pub fn names(&self) -> Vec<&'static str> {
        self.kinds.iter().map(|k| k.name()).collect()
    }
}

impl Default for Registry {
    fn default() -> Self {
        Registry::builtin()
    }
}

#[cfg(test)]
mod tests {
    use super::SlotKind;

    /// The browser's worker addresses files with a 32-bit `usize`: every slot must refuse a
    /// file of 4 GiB or more from its head and size, whatever the head says.
    #[test]
    fn every_slot_refuses_a_file_the_worker_cannot_address() {
        let kinds = [SlotKind::Mesh, SlotKind::Meshes, SlotKind::Surface, SlotKind::Volume, SlotKind::Gcode, SlotKind::Frame];
        for kind in kinds {
            // Fails to compile when a kind is added, so the list above is kept whole.
            match kind {
                SlotKind::Mesh | SlotKind::Meshes | SlotKind::Surface | SlotKind::Volume | SlotKind::Gcode | SlotKind::Frame => {}
            }
            // A binary STL's head whose count matches the length, and plain text.
            let triangles: u32 = 86_000_000;
            let len = 84 + 50 * u64::from(triangles);
            let mut stl = vec![0u8; 84];
            stl[80..84].copy_from_slice(&triangles.to_le_bytes());
            for (head, len) in [(stl, len), (b"solid x\n".to_vec(), 4 << 30), (b"G1 X0\n".to_vec(), (4 << 30) + 1)] {
                assert!(len >= 4 << 30);
                let refused = kind.check_file("big", &head, len);
                assert!(refused.as_ref().is_err_and(|m| m.starts_with("big")), "{kind:?} admits {len} bytes: {refused:?}");
            }
        }
    }
}

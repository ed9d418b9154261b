//! The `lattice` job (the GIPPO method): a lattice from the atlas fills a domain layer by
//! layer, each layer becomes a graph printed along optimised paths, optionally projected onto
//! a non-planar surface.
//!
//! Stages: `import` + `slice` (only for a solid domain: its layers are the domains),
//! `lattice`, `paths`, `nonplanar` (when set). The report draws the score of every GIPPO
//! iteration (the paper's Fig. 2(i)), the path classes and a table of paths per layer.

mod checks;
mod form;
mod report;
mod settings;
mod stages;
mod views;
use checks::*;
use form::*;
use report::*;
pub use settings::*;
pub use stages::*;
use views::*;

use super::{Inspection, Kind, Product, Shape, Slot, SlotKind, StageInfo, ViewInfo};
use crate::design::{Design, Input};
use crate::geom::shapes;
use crate::geom::StrokeLayer;
use crate::lattice::{self, Domain, LayerDomain};
use crate::nonplanar;
use crate::paths::{self, PathsReport};
use crate::report::{Axis, Column, Plot, PlotKind, Row as TableRow, Series, StageReport, Table};
use crate::settings::{mount, other, widget, Field, Kind as FieldKind, Problem, Row};
use crate::slice;
use crate::stage::{Ctx, Error, Out};
use serde::{Deserialize, Serialize};

/// The `lattice` job kind.
pub struct LatticeKind;

const SLOTS: &[Slot] = &[
    Slot {
        name: "mesh",
        label: "Solid to fill",
        kind: SlotKind::Mesh,
        path: "job.input",
        required: false,
        doc: "A solid whose every layer is filled with the lattice (the domain becomes 'solid').",
    },
    Slot {
        name: "surface",
        label: "Surface to print on",
        kind: SlotKind::Surface,
        path: "job.surface_input",
        required: false,
        doc: "A surface mesh the layers are projected onto (non-planar printing on a mesh).",
    },
];

const STAGES: &[StageInfo] = &[
    StageInfo { name: "import", label: "Reading the mesh" },
    StageInfo { name: "slice", label: "Slicing the solid" },
    StageInfo { name: "lattice", label: "Generating the lattice" },
    StageInfo { name: "paths", label: "Optimising print paths" },
    StageInfo { name: "nonplanar", label: "Projecting onto the surface" },
];

const VIEWS: &[ViewInfo] = &[ViewInfo {
    id: "layer2d",
    stage: "lattice",
    label: "Lattice layer",
    shape: Shape::Lines2d,
    index_label: "Layer",
    doc: "The struts of one layer as generated, before path optimisation (mm).",
}];

impl Kind for LatticeKind {
    type Settings = LatticeJob;
    const NAME: &'static str = "lattice";
    const LABEL: &'static str = "Lattice (GIPPO)";
    const DOC: &'static str = "A lattice from the atlas, every strut printed once along optimised paths (GIPPO), optionally on a curved surface.";
    const SLOTS: &'static [Slot] = SLOTS;
    const STAGES: &'static [StageInfo] = STAGES;
    const VIEWS: &'static [ViewInfo] = VIEWS;

    fn fields() -> Vec<Row> {
        rows()
    }

    fn validate(design: &Design, j: &LatticeJob, out: &mut Vec<Problem>) {
        validate(design, j, out)
    }

    /// A solid loaded into the `mesh` slot is filled: the domain becomes `solid`, and its
    /// paths are printed in travel-minimising order. The paper's longest-first order suits its
    /// one-layer coupons, but on a filled part it sends the nozzle across every layer again and
    /// again (a 30 mm sphere: travel 4.5–5.6× the extrusion, against 0.29–0.46× in
    /// travel-minimising order; BENCHMARKS.md "A lattice filling a solid").
    fn slot_filled(slot: &str, mut j: LatticeJob) -> LatticeJob {
        if slot == "mesh" {
            j.domain = Domain::Solid;
            j.paths.order = paths::Order::MinTravel;
        }
        j
    }

    /// The lattice, paths and (when set) non-planar stages' estimates, chained: each stage's
    /// input is the previous one's estimated output. A solid domain is measured from its mesh
    /// (box, footprint, volume: [`lattice::DomainSize::of_mesh`]), not sliced.
    fn estimate(j: &LatticeJob, ctx: &mut Ctx) -> Result<Vec<crate::budget::Estimate>, Error> {
        estimate(j, ctx)
    }

    fn run(j: &LatticeJob, ctx: &mut Ctx) -> Result<Product, Error> {
        let strokes = strokes(j, ctx)?;
        let design = ctx.design;
        // The printer's retraction rule is in the key: the report counts its retractions.
        let key = (&j.paths, line_width(design), design.seed, &design.printer.retraction, design.printer.flavor);
        let optimised = ctx.stage("paths", "paths", &key, &[strokes.key], |progress| {
            let mut o = paths::optimise(&strokes, &j.paths, line_width(design), design.seed, progress).map_err(|e| Error::stage("paths", e))?;
            let counts = crate::gcode::retractions_per_pass(&o.toolpath, &design.printer);
            for (l, n) in o.report.layers.iter_mut().zip(counts) {
                l.retractions = n;
            }
            let report = paths_report(&o.report);
            Ok((o.toolpath, Some(report)))
        })?;
        drop(strokes);
        let Some(np) = &j.nonplanar else { return Ok(Product::Toolpath(optimised)) };
        let surface = match (&np.surface, &j.surface_input) {
            (nonplanar::Surface::Mesh, Some(input)) => Some(ctx.mesh(&SLOTS[1], input)?),
            _ => None,
        };
        let upstream: Vec<_> = std::iter::once(optimised.key).chain(surface.as_ref().map(|s| s.key)).collect();
        let projected = ctx.stage("nonplanar", "nonplanar", np, &upstream, |_| {
            let p = nonplanar::project(&optimised, surface.as_deref(), np).map_err(|e| Error::stage("non-planar", e))?;
            let r = &p.report;
            let report = StageReport::new("nonplanar", "Projecting onto the surface", r)
                .metric(
                    "missed_points",
                    "Points off the surface",
                    r.missed_points as f64,
                    "",
                    "Points with no surface under them (kept at the lowest surface height).",
                )
                .metric("collisions", "Digging segments", r.collisions as f64, "", "Moves that would cut into the layer below; 0 is safe.");
            Ok((p.toolpath, Some(report)))
        })?;
        Ok(Product::Toolpath(projected))
    }

    fn inspect(j: &LatticeJob, ctx: &mut Ctx, view: &str, index: usize) -> Result<Inspection, Error> {
        inspect(j, ctx, view, index)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solid_slot_switches_the_domain() {
        let j = <LatticeKind as Kind>::slot_filled("mesh", LatticeJob::default());
        assert_eq!(j.domain, Domain::Solid);
        let j = <LatticeKind as Kind>::slot_filled("surface", LatticeJob::default());
        assert_ne!(j.domain, Domain::Solid);
    }
}

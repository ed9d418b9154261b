//! The `lattice` job (the GIPPO method): a lattice from the atlas fills a domain layer by
//! layer, each layer becomes a graph printed along optimised paths, optionally projected onto
//! a non-planar surface.
//!
//! Stages: `import` + `slice` (only for a solid domain: its layers are the domains),
//! `lattice`, `paths`, `nonplanar` (when set). The report draws the score of every GIPPO
//! iteration (the paper's Fig. 2(i)), the path classes and a table of paths per layer.

mod checks;
mod form;
mod method;
mod report;
mod settings;
mod stages;
mod steps;
mod views;
use checks::*;
use form::*;
use method::*;
use report::*;
pub use settings::*;
pub use stages::*;
use steps::*;
use views::*;

use super::{Inspection, Kind, Product, Shape, Slot, SlotKind, StageInfo, StepInfo, ViewInfo};
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

const VIEWS: &[ViewInfo] = &[
    ViewInfo {
        id: "layer2d",
        card: true,
        stage: "lattice",
        label: "Lattice layer",
        shape: Shape::Lines2d,
        index_label: "Layer",
        doc: "The struts of one layer as generated, before path optimisation (mm).",
    },
    ViewInfo {
        id: "graph",
        card: false,
        stage: "paths",
        label: "Graph",
        shape: Shape::Lines2d,
        index_label: "Layer",
        doc: "One layer as a graph: its struts (edges), its nodes, the odd-degree nodes marked (mm).",
    },
    ViewInfo {
        id: "pairing",
        card: false,
        stage: "paths",
        label: "Odd-node pairing",
        shape: Shape::Lines2d,
        index_label: "Layer",
        doc: "The shortest straight lines pairing the odd-degree nodes of each piece, over the struts: half the odd nodes is the fewest paths possible (mm).",
    },
    ViewInfo {
        id: "gippo",
        card: false,
        stage: "paths",
        label: "GIPPO search",
        shape: Shape::Lines2d,
        index_label: "Frame",
        doc: "GIPPO's iterations replayed on the first layer with struts: the best paths so far each time an iteration beats them, coloured long, medium, short (mm).",
    },
    ViewInfo {
        id: "trails",
        card: false,
        stage: "paths",
        label: "Kept paths",
        shape: Shape::Lines2d,
        index_label: "Layer",
        doc: "The paths kept for one layer, coloured long (over 15 nodes), medium (5 to 15) and short (under 5) (mm).",
    },
    ViewInfo {
        id: "order",
        card: false,
        stage: "paths",
        label: "Print order",
        shape: Shape::Lines2d,
        index_label: "Path",
        doc: "The paths in the order they are printed, one more each frame, with the travel moves between them (mm).",
    },
    ViewInfo {
        id: "gcode",
        card: false,
        stage: "paths",
        label: "Toolpath",
        shape: Shape::Lines2d,
        index_label: "Layer",
        doc: "One layer as the G-code writer gets it: extrusions, the short paths slowed down, travel through the air and along struts (mm).",
    },
];

impl Kind for LatticeKind {
    type Settings = LatticeJob;
    const NAME: &'static str = "lattice";
    const LABEL: &'static str = "Lattice (GIPPO)";
    const DOC: &'static str = "A lattice from the atlas, every strut printed once along optimised paths (GIPPO), optionally on a curved surface.";
    const SLOTS: &'static [Slot] = SLOTS;
    const STAGES: &'static [StageInfo] = STAGES;
    const VIEWS: &'static [ViewInfo] = VIEWS;
    const STEPS: &'static [StepInfo] = STEPS;

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
        let optimised = paths_stage(j, ctx, &strokes)?;
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

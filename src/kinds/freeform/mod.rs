//! The `freeform` job: a wireframe printed beam by beam along 3D paths, in an order planned
//! under the process constraints and the stability cost of Gelber, Hurst and Bhargava
//! (`../shared/papers/freeform-assembly-planning.txt`), or a proof that it cannot be printed.
//!
//! Stages: `import` (a wireframe file, or a built-in tower / dome / bridge, placed on the plate),
//! `constraints` (directions and collision precedences, [`freeform::precedence`]), `plan`
//! (consistent subassemblies best-first, [`freeform::plan`]), `order` (greedy on deadhead time,
//! [`freeform::deadhead`]), `costs` (the exact and heuristic ε of every step,
//! [`freeform::cost`]). The G-code prints each beam as one pass of 3D moves at its feed with
//! the extrusion of its diameter, dwells at the end joint, and deadheads by lifting above the
//! highest printed beam.

mod checks;
mod form;
mod planning;
mod report;
mod settings;
mod stages;
mod steps;
mod views;
use checks::*;
use form::*;
pub use planning::*;
pub use report::*;
pub use settings::*;
pub use stages::*;
use steps::*;
use views::*;

use super::{Inspection, Kind, Product, Shape, Slot, SlotKind, StageInfo, StepInfo, ViewInfo};
use crate::budget::Estimate;
use crate::design::{Design, Input};
use crate::freeform::bands;
use crate::freeform::cost::{self, Costs};
use crate::freeform::deadhead::{self, Ordered};
use crate::freeform::frame::{Section, DEFAULT_E_MPA, DEFAULT_G_MPA, DEFAULT_LOAD_N};
use crate::freeform::models::{self, Model};
use crate::freeform::optimal::{self, Optimum};
use crate::freeform::plan::{self, Assembly, Cost, Mode, Plan, Unconstructable};
use crate::freeform::precedence::{self, Constraints, Nozzle};
use crate::freeform::wireframe::{self, Ground, Wireframe};
use crate::geom::{DVec3, Feature, Pass, PassKind, Path, PointData, PointFlow, Toolpath};
use crate::report::{Axis, Column, Plot, PlotKind, Row as TableRow, Series, StageReport, Table};
use crate::settings::{mount, num, other, Field as Row0, Kind as FieldKind, Problem, Row};
use crate::stage::{Ctx, Error, Out};
use serde::{Deserialize, Serialize};

/// The `freeform` job kind.
pub struct FreeformKind;

const SLOTS: &[Slot] = &[Slot {
    name: "frame",
    label: "Wireframe",
    kind: SlotKind::Frame,
    path: "job.input",
    required: false,
    doc: "Joints and beams: assembly_instances or conmech JSON, OBJ with line elements, a CSV of beams (x1 y1 z1 x2 y2 z2, mm), or a triangle mesh (OBJ faces, STL) whose edges are the beams.",
}];

const STAGES: &[StageInfo] = &[
    StageInfo { name: "import", label: "Reading the wireframe" },
    StageInfo { name: "constraints", label: "Directions and collisions" },
    StageInfo { name: "plan", label: "Planning the sequence" },
    StageInfo { name: "optimum", label: "Exact search (small designs)" },
    StageInfo { name: "order", label: "Ordering deadheads" },
    StageInfo { name: "costs", label: "Joint errors, exact and heuristic" },
];

const VIEWS: &[ViewInfo] = &[
    ViewInfo {
        id: "sequence",
        card: true,
        stage: "order",
        label: "Print sequence",
        shape: Shape::Lines3d,
        index_label: "Step",
        doc: "The wireframe after each step: printed beams, the beam being printed, the cantilevered ones, and those still to print (mm).",
    },
    ViewInfo {
        id: "beams",
        card: false,
        stage: "import",
        label: "Beams",
        shape: Shape::Lines3d,
        index_label: "",
        doc: "The wireframe as read and placed: its beams, those standing on the substrate, and the grounded joints marked (mm).",
    },
    ViewInfo {
        id: "precedence",
        card: false,
        stage: "plan",
        label: "Precedences",
        shape: Shape::Lines3d,
        index_label: "",
        doc: "Which beam must be printed before which: arrows from the middle of the earlier beam to the later one, for the nozzle's collisions and for each path from its root (mm).",
    },
];

impl Kind for FreeformKind {
    type Settings = FreeformJob;
    const NAME: &'static str = "freeform";
    const LABEL: &'static str = "Freeform wireframe";
    const DOC: &'static str =
        "A wireframe printed beam by beam in free space, in an order that never collides, never strands a joint, and keeps joints where they belong.";
    const SLOTS: &'static [Slot] = SLOTS;
    const STAGES: &'static [StageInfo] = STAGES;
    const VIEWS: &'static [ViewInfo] = VIEWS;
    const STEPS: &'static [StepInfo] = STEPS;

    fn fields() -> Vec<Row> {
        rows()
    }

    /// Switched to a freeform job with nothing to print: the built-in tower.
    fn adopted(design: &mut serde_json::Value) {
        if let Some(job) = design.get_mut("job").and_then(|j| j.as_object_mut()) {
            if !job.contains_key("input") && !job.contains_key("model") {
                job.insert("model".into(), serde_json::to_value(Model::default()).unwrap_or_default());
            }
        }
    }

    fn validate(_design: &Design, j: &FreeformJob, out: &mut Vec<Problem>) {
        validate(_design, j, out)
    }

    fn slot_filled(slot: &str, mut j: FreeformJob) -> FreeformJob {
        if slot == "frame" {
            j.model = None;
        }
        j
    }

    fn estimate(j: &FreeformJob, ctx: &mut Ctx) -> Result<Vec<Estimate>, Error> {
        estimate(j, ctx)
    }

    fn run(j: &FreeformJob, ctx: &mut Ctx) -> Result<Product, Error> {
        let w = import_stage(j, ctx)?;
        let c = constraints_stage(j, ctx, &w)?;
        let p = chosen_plan(j, ctx, &w, &c)?;
        let o = order_stage(j, ctx, &w, &c, &p)?;
        let costs = costs_stage(j, ctx, &w, &p, &o)?;
        let design = ctx.design;
        let parts = (j.beam.diameter_mm, j.print, design.printer.travel_speed_mm_s);
        let toolpath = ctx.stage("toolpath", "toolpath", &parts, &[o.key, costs.key, c.key], |_| Ok((toolpath(j, &w, &o, &c), None)))?;
        Ok(Product::Toolpath(toolpath))
    }

    fn inspect(j: &FreeformJob, ctx: &mut Ctx, view: &str, index: usize) -> Result<Inspection, Error> {
        inspect(j, ctx, view, index)
    }
}

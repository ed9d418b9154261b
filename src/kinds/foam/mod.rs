//! The `foam` job: a viscous-thread-printed foam graded between regions (Nakura et al.,
//! `../shared/papers/vtp-graded-foams.txt`), printed as one uninterrupted extrusion.
//!
//! Stages: `import` (each region mesh) or `model` (built-in regions), `regions` (solids and
//! shared boundaries, [`foam::regions`]), `slice` (the union sliced by the foundation's slicer,
//! one outline per layer or refused), `raster` (one continuous path per layer, each starting
//! where the last ended, [`foam::raster`]), `grade` (pieces of the set length, each with the
//! pair π of its end point, [`foam::field`], and the VTP numbers of section 3.2.4).
//!
//! The report draws the weighting functions, and V*, H*, ΔE/mm and the modulus the calibration
//! (by default the paper's fit) gives at each V* along a probe line (the paper's Fig. 6); views show the shared boundaries and each layer's path.
//!
//! Beyond the paper: a region's V* may be set by a target modulus through the calibration of
//! [`foam::stiffness`]; a transition may keep the modulus linear exactly
//! ([`Weighting::LinearModulus`]); with several neighbours allowed, a point near several
//! boundaries blends them by distance ([`foam::blend`]).

mod checks;
mod form;
mod report;
mod settings;
mod stages;
mod steps;
mod thread;
mod views;
use checks::*;
use form::*;
use report::*;
pub use settings::*;
pub use stages::*;
use thread::*;
pub use thread::{value_bin, VALUE_CODES};
use views::*;

use super::{Inspection, Kind, Product, Shape, Slot, SlotKind, StageInfo, StepInfo, Teach, ViewInfo};
use crate::budget::Estimate;
use crate::design::{Design, Input};
use crate::foam::field::Field;
use crate::foam::layers::{check_layers, inset, Cut, Layer};
use crate::foam::models::{self, Model};
use crate::foam::regions::{self, Regions};
use crate::foam::stiffness::Calibration;
use crate::foam::{grade, raster};
use crate::foam::{Junction, Pair, Process, Transition, Weighting};
use crate::geom::{DVec2, DVec3, Feature, Mesh, Toolpath};
use crate::report::{Axis, Metric, Plot, PlotKind, Series, StageReport};
use crate::settings::{mount, num, other, percent, when, Field as Row0, Kind as FieldKind, Problem, Row};
use crate::slice;
use crate::stage::{Ctx, Error, Out};
use serde::{Deserialize, Serialize};

/// The `foam` job kind.
pub struct FoamKind;

const SLOTS: &[Slot] = &[Slot {
    name: "regions",
    label: "Region meshes",
    kind: SlotKind::Meshes,
    path: "job.meshes",
    required: false,
    doc: "One closed mesh per region, in order (region 1 is the first file); regions touch but do not overlap.",
}];

const STAGES: &[StageInfo] = &[
    StageInfo { name: "import", label: "Reading the region meshes" },
    StageInfo { name: "regions", label: "Finding shared boundaries" },
    StageInfo { name: "slice", label: "Slicing the union" },
    StageInfo { name: "raster", label: "One continuous path per layer" },
    StageInfo { name: "grade", label: "Grading V* and H* along the path" },
];

const VIEWS: &[ViewInfo] = &[
    ViewInfo {
        id: "boundaries",
        card: true,
        stage: "regions",
        label: "Shared boundaries",
        shape: Shape::Mesh,
        index_label: "Boundary",
        doc: "The faces two regions share (highlighted), where transitions are centred (mm).",
    },
    ViewInfo {
        id: "layer",
        card: true,
        stage: "raster",
        label: "Layer path",
        shape: Shape::Lines2d,
        index_label: "Layer",
        doc: "One layer's continuous path: scan lines, turns along the outline, and the outline (mm).",
    },
    ViewInfo {
        id: "v_star",
        card: false,
        stage: "grade",
        label: "V* along the thread",
        shape: Shape::Lines2d,
        index_label: "Layer",
        doc: "One layer's path, each piece coloured by the V* it is printed with (binned; the legend gives each bin's range).",
    },
    ViewInfo {
        id: "h_star",
        card: false,
        stage: "grade",
        label: "H* along the thread",
        shape: Shape::Lines2d,
        index_label: "Layer",
        doc: "One layer's path, each piece coloured by the H* it is printed with (binned; the legend gives each bin's range).",
    },
];

impl Kind for FoamKind {
    type Settings = FoamJob;
    const NAME: &'static str = "foam";
    const LABEL: &'static str = "Graded foam (VTP)";
    const DOC: &'static str = "A viscous-thread-printed foam whose stiffness is graded between regions, printed as one uninterrupted thread.";
    const SLOTS: &'static [Slot] = SLOTS;
    const STAGES: &'static [StageInfo] = STAGES;
    const VIEWS: &'static [ViewInfo] = VIEWS;
    const STEPS: &'static [StepInfo] = steps::STEPS;
    /// Opens coloured by speed: V* × the thread's speed, so the foam's grading shows.
    const TEACH: Teach = Teach { color_by: "speed", backdrop: None };

    fn fields() -> Vec<Row> {
        rows()
    }

    /// Switched to a foam with nothing to print: the paper's dogbone.
    fn adopted(design: &mut serde_json::Value) {
        if let Some(job) = design.get_mut("job").and_then(|j| j.as_object_mut()) {
            if !job.contains_key("meshes") && !job.contains_key("model") {
                job.insert("model".into(), serde_json::to_value(Model::default()).unwrap_or_default());
            }
        }
    }

    fn validate(design: &Design, j: &FoamJob, out: &mut Vec<Problem>) {
        validate(design, j, out)
    }

    /// Region files loaded: the built-in model is switched off and every file has a V*/H*
    /// pair (new regions get the defaults). Rows are never dropped: files given one by one,
    /// as a folder or all at once give the same design, and a row set before its file came
    /// is kept (rows beyond the files wait, unused, and the run says so).
    fn slot_filled(slot: &str, mut j: FoamJob) -> FoamJob {
        if slot == "regions" {
            j.model = None;
            let n = mesh_names(&j).len().min(MAX_REGIONS);
            if j.regions.len() < n {
                j.regions.resize(n, RegionSpec::new(DEFAULT_V_STAR, DEFAULT_H_STAR));
            }
        }
        j
    }

    fn estimate(j: &FoamJob, ctx: &mut Ctx) -> Result<Vec<Estimate>, Error> {
        estimate(j, ctx)
    }

    fn run(j: &FoamJob, ctx: &mut Ctx) -> Result<Product, Error> {
        let regions = regions_stage(j, ctx)?;
        let layers = slice_stage(j, ctx, &regions)?;
        let paths = raster_stage(j, ctx, &layers)?;
        let design = ctx.design;
        let p = process(design, j);
        let f = &j.foam;
        let parts = (
            &j.regions,
            &j.transitions,
            (f.piece_mm, f.layer_height_mm, f.probe_axis, f.junction, f.calibration),
            p.nozzle_mm,
            p.die_swell,
            p.filament_mm,
            p.feed_mm_s,
        );
        let toolpath = ctx.stage("grade", "grade", &parts, &[regions.key, paths.key], |progress| grade(j, &p, &regions, &layers, &paths, progress))?;
        Ok(Product::Toolpath(toolpath))
    }

    fn inspect(j: &FoamJob, ctx: &mut Ctx, view: &str, index: usize) -> Result<Inspection, Error> {
        inspect(j, ctx, view, index)
    }
}

//! The `axisymmetric` job (Guzman-Bautista et al. 2025): quasi-uniform infill points on a
//! curved, axisymmetric build platform, joined by one geodesic path, printed by a 5-axis head
//! whose tool axis follows the surface normal.
//!
//! Stages: `platform` (the generatrix checked: C³ at the knots, no cusps or self-intersections,
//! pole clearance; κ, metric and Christoffel symbols plotted along u), `points` (N from the
//! paper's equation 4, a seed by EBNS / ERE / GBNS, geodesic repulsion energy; the validation
//! metrics of section 2.5 for the seed and the result), `path` (nearest neighbour + 2-opt,
//! each segment the geodesic between its points, on the surface offset by the layer height).
//! The writer gets one free pass per layer with a tool axis per point: the printer must be
//! 5-axis (the `five-axis-head` profile), or write the poses CSV flavour.
//!
//! Beyond the paper: the polygon domain may have holes (the points and the path keep out of
//! them), and `layers` > 1 stacks layers: layer k (0-based) spreads its own points on the
//! platform offset by k·h along its normal ([`crate::axisym::offset`], the top of the layer
//! below) with its own domain (the same (u, θ) region, or for a part the contour at that
//! offset), seeded from the design seed and k; its path starts nearest where layer k − 1's
//! ended, and its tip rides (k + 1)·h out along the normal. Layer 0 is exactly the one-layer
//! job (its stage ids, seed and bytes).

mod checks;
mod form;
mod frames;
mod report;
mod settings;
mod stages;
mod steps;
mod views;
use checks::*;
use form::*;
use frames::*;
pub use frames::{repulsion_cap, AXES_PER_LAYER, AXIS_STROKE_MM, REPULSION_BYTES, REPULSION_FRAMES};
pub use report::*;
pub use settings::*;
pub use stages::*;
use views::*;

use super::{Inspection, Kind, Product, Shape, Slot, SlotKind, StageInfo, StepInfo, Teach, ViewInfo};
use crate::axisym::contour;
use crate::axisym::domain::Domain;
use crate::axisym::offset::Offset;
use crate::axisym::platform::{self, Platform, Profile};
use crate::axisym::{dynamics, surface::Surface, tour, uniform};
use crate::design::{Design, Input};
use crate::geom::{DVec3, Feature, Pass, PassKind, Path, PointData, Toolpath};
use crate::report::{Axis, Plot, PlotKind, Series, StageReport};
use crate::settings::{choice_docs, int, mount, num, other, points, rings, when, Field, Kind as FieldKind, Problem, Row};
use crate::stage::{Ctx, Error, Out};
use serde::{Deserialize, Serialize};

/// The `axisymmetric` job kind.
pub struct AxisymKind;

const SLOTS: &[Slot] = &[Slot {
    name: "part",
    label: "Part on the platform",
    kind: SlotKind::Mesh,
    path: "job.part",
    required: false,
    doc: "A solid resting on the curved platform: the outline where it meets the platform becomes the domain Ω.",
}];

const STAGES: &[StageInfo] = &[
    StageInfo { name: "platform", label: "Checking the build platform" },
    StageInfo { name: "domain", label: "Finding the domain Ω" },
    StageInfo { name: "points", label: "Spreading uniform points (geodesic repulsion)" },
    StageInfo { name: "path", label: "Joining the points by geodesics" },
    StageInfo { name: "axes", label: "Tool axis and machine dynamics" },
];

const VIEWS: &[ViewInfo] = &[
    ViewInfo {
        id: "map",
        card: true,
        stage: "points",
        label: "Embedded map (u, θ)",
        shape: Shape::Lines2d,
        index_label: "Step",
        doc: "The domain Ω in the (θ, u) plane: 0 the seed points, 1 after repulsion, 2 the path (x: θ in rad, y: u); with several layers, 3·layer + step.",
    },
    ViewInfo {
        id: "platform3d",
        card: true,
        stage: "path",
        label: "Path on the platform",
        shape: Shape::Lines3d,
        index_label: "View",
        doc: "The revolved platform (meridians and parallels) with the printed path on it, mm.",
    },
    ViewInfo {
        id: "omega",
        card: false,
        stage: "domain",
        label: "Ω on the map",
        shape: Shape::Lines2d,
        index_label: "Layer",
        doc: "The domain Ω alone in the (θ, u) plane (x: θ in rad, y: u), with its area on the layer's surface.",
    },
    ViewInfo {
        id: "repulsion",
        card: false,
        stage: "points",
        label: "Geodesic repulsion",
        shape: Shape::Lines2d,
        index_label: "Frame",
        doc: "Layer 0's points during the geodesic repulsion, frame by frame (the seed, evenly spaced iterations, the result) with the energy E/E₀; recorded when shown.",
    },
    ViewInfo {
        id: "axes3d",
        card: false,
        stage: "axes",
        label: "Platform and tool axes",
        shape: Shape::Lines3d,
        index_label: "Step",
        doc: "0: the revolved platform alone; 1: the path on it with a short tool-axis stroke at evenly spaced poses, mm.",
    },
];

impl Kind for AxisymKind {
    type Settings = AxisymJob;
    const NAME: &'static str = "axisymmetric";
    const LABEL: &'static str = "Uniform infill on a curved platform";
    const DOC: &'static str =
        "Quasi-uniform infill points on an axisymmetric build platform, joined by geodesics and printed by a 5-axis head along the surface normal.";
    const SLOTS: &'static [Slot] = SLOTS;
    const STAGES: &'static [StageInfo] = STAGES;
    const VIEWS: &'static [ViewInfo] = VIEWS;
    const STEPS: &'static [StepInfo] = steps::STEPS;
    /// Opens with the platform drawn behind the path (`axes3d` at 0: the platform alone).
    const TEACH: Teach = Teach { color_by: "feature", backdrop: Some("axes3d") };

    fn fields() -> Vec<Row> {
        rows()
    }

    fn validate(design: &Design, j: &AxisymJob, out: &mut Vec<Problem>) {
        validate(design, j, out)
    }

    /// Switching to this kind on a machine that cannot tilt the tool puts the `five-axis-head`
    /// profile in place (the poses CSV output is kept: it needs no machine).
    fn adopted(design: &mut serde_json::Value) {
        let printer = &design["printer"];
        let five_axis = printer.pointer("/machine/kind").and_then(|k| k.as_str()) == Some("five_axis");
        let poses = printer.get("flavor").and_then(|f| f.as_str()) == Some("poses_csv");
        if !five_axis && !poses {
            if let Ok(p) = crate::gcode::presets::preset(FIVE_AXIS_PRESET) {
                if let Ok(v) = serde_json::to_value(&p.printer) {
                    design["printer"] = v;
                }
            }
        }
    }

    fn slot_filled(slot: &str, mut j: AxisymJob) -> AxisymJob {
        if slot == "part" {
            j.domain.kind = DomainKind::Part;
        }
        j
    }

    fn estimate(j: &AxisymJob, ctx: &mut Ctx) -> Result<Vec<crate::budget::Estimate>, Error> {
        estimate(j, ctx)
    }

    fn run(j: &AxisymJob, ctx: &mut Ctx) -> Result<Product, Error> {
        let platform = platform_stage(j, ctx)?;
        let layers = all_layers(j, ctx, &platform, j.layers, true)?;
        let (h, width) = (j.layer_height_mm, line_width(ctx.design));
        let tours: Vec<&tour::Tour> = layers.iter().filter_map(|l| l.tour.as_deref()).collect();
        let mut keys: Vec<_> = layers.iter().map(|l| l.tour.as_ref().map_or(l.points.key, |t| t.key)).collect();
        let axes = axes_stage(j, ctx, &tours, &keys)?;
        keys.push(axes.key);
        let toolpath = ctx.stage("axes", "toolpath", &(h, width), &keys, |_| Ok((toolpath_of(&tours, &axes, h, width), None)))?;
        // The per-layer table joins the path stage's report (cached or not, it is added here).
        let table = layer_table(&layers, h);
        if let Some(r) = ctx.reports.iter_mut().find(|r| r.stage == "path") {
            r.tables.retain(|t| t.key != "layers");
            r.tables.push(table);
        }
        Ok(Product::Toolpath(toolpath))
    }

    fn inspect(j: &AxisymJob, ctx: &mut Ctx, view: &str, index: usize) -> Result<Inspection, Error> {
        inspect(j, ctx, view, index)
    }
}

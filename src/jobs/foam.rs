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

use super::{Inspection, Kind, Product, Shape, Slot, SlotKind, StageInfo, ViewInfo};
use crate::budget::Estimate;
use crate::design::{Design, Input};
use crate::foam::field::Field;
use crate::foam::models::{self, Model};
use crate::foam::regions::{self, Regions};
use crate::foam::stiffness::Calibration;
use crate::foam::{grade, raster};
use crate::foam::{Junction, Pair, Process, Transition, Weighting};
use crate::geom::{DVec2, DVec3, Feature, Mesh, Polygon, Toolpath};
use crate::report::{Axis, Metric, Plot, PlotKind, Series, StageReport};
use crate::settings::{mount, num, other, percent, when, Field as Row0, Kind as FieldKind, Problem, Row};
use crate::slice;
use crate::stage::{Ctx, Error, Out};
use serde::{Deserialize, Serialize};

/// Most regions a foam may have (the form shows this many).
pub const MAX_REGIONS: usize = 8;
/// Most transitions.
pub const MAX_TRANSITIONS: usize = 8;
/// Default V* of a new region (the middle of the paper's 0.15–0.4).
pub const DEFAULT_V_STAR: f64 = 0.25;
/// Default target modulus of a region set by its stiffness, kPa (inside the paper's
/// calibration, 1.01–22.68 kPa).
pub const DEFAULT_MODULUS_KPA: f64 = 5.0;
/// Default H* of a region: the nozzle 8 swollen thread diameters above the layer.
pub const DEFAULT_H_STAR: f64 = 8.0;
/// Default layer height, mm.
pub const DEFAULT_LAYER_HEIGHT_MM: f64 = 1.0;
/// Default distance between raster lines, mm.
pub const DEFAULT_LINE_SPACING_MM: f64 = 2.0;
/// Default length of the pieces a path is refined into, mm.
pub const DEFAULT_PIECE_MM: f64 = 0.5;
/// Default filament feed speed C, mm/s (constant over the print).
pub const DEFAULT_FEED_MM_S: f64 = 1.5;
/// Most pieces a foam may have (refused above, before the raster is built).
pub const MAX_PIECES: f64 = 20e6;
/// Points along the probe line.
pub const PROBE_SAMPLES: usize = 241;

/// What sets a region's V*.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SetBy {
    /// V* itself.
    #[default]
    VStar,
    /// A target modulus, through the calibration (beyond the paper).
    Modulus,
}

/// A region's pair, by its place in the regions list.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RegionSpec {
    /// What sets V*: `v_star`, or `modulus_kpa` through the calibration (the other is unused).
    #[serde(default)]
    pub set_by: SetBy,
    /// V* = nozzle speed ÷ speed of the thread leaving the nozzle.
    #[serde(default = "default_v_star")]
    pub v_star: f64,
    /// Target compressive modulus, kPa (when set by the modulus).
    #[serde(default = "default_modulus")]
    pub modulus_kpa: f64,
    /// H* = nozzle height ÷ (die swell × nozzle diameter).
    pub h_star: f64,
}

fn default_v_star() -> f64 {
    DEFAULT_V_STAR
}

fn default_modulus() -> f64 {
    DEFAULT_MODULUS_KPA
}

impl RegionSpec {
    /// A region set by its V*.
    pub fn new(v_star: f64, h_star: f64) -> RegionSpec {
        RegionSpec { set_by: SetBy::VStar, v_star, modulus_kpa: DEFAULT_MODULUS_KPA, h_star }
    }

    /// Its pair: V* given, or the calibration's V* of its modulus.
    pub fn pair(&self, c: &Calibration) -> Pair {
        let v_star = match self.set_by {
            SetBy::VStar => self.v_star,
            SetBy::Modulus => c.v_star(self.modulus_kpa),
        };
        Pair { v_star, h_star: self.h_star }
    }
}

/// A transition between two regions (numbered from 1, as the form shows them).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TransitionSpec {
    /// The region on the negative side (w = 0 there).
    pub from: usize,
    /// The region on the positive side (w = 1 there).
    pub to: usize,
    /// Length α_T across the shared boundary, mm (0: a step).
    pub length_mm: f64,
    /// Weighting function.
    #[serde(default)]
    pub weighting: Weighting,
}

/// Slicing and printing settings of a foam.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Options {
    /// Layer height l_h, mm.
    pub layer_height_mm: f64,
    /// Distance between raster lines, mm.
    pub line_spacing_mm: f64,
    /// Raster direction of the first layer, degrees from X.
    pub raster_angle_deg: f64,
    /// Turn the raster 90° every other layer.
    pub alternate: bool,
    /// How far inside the outline the raster's turns run, as a fraction of the line spacing.
    pub inset: f64,
    /// Pieces the path is cut into, mm (each takes π at its end).
    pub piece_mm: f64,
    /// Filament feed speed C, mm/s.
    pub feed_mm_s: f64,
    /// Let a region share boundaries with several others (beyond the paper).
    pub many_neighbours: bool,
    /// How a point near several boundaries of its region takes its pair.
    pub junction: Junction,
    /// The modulus of the foam against V* (regions set by a modulus, the modulus plotted along
    /// the probe): by default the paper's fit, applied, not measured.
    pub calibration: Calibration,
    /// Axis of the probe line (through the middle of the part).
    pub probe_axis: ProbeAxis,
}

/// Axis of the probe line.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ProbeAxis {
    /// Along X.
    #[default]
    X,
    /// Along Y.
    Y,
    /// Along Z.
    Z,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            layer_height_mm: DEFAULT_LAYER_HEIGHT_MM,
            line_spacing_mm: DEFAULT_LINE_SPACING_MM,
            raster_angle_deg: 0.0,
            alternate: true,
            inset: 0.5,
            piece_mm: DEFAULT_PIECE_MM,
            feed_mm_s: DEFAULT_FEED_MM_S,
            many_neighbours: false,
            junction: Junction::Blend,
            calibration: Calibration::default(),
            probe_axis: ProbeAxis::X,
        }
    }
}

/// Settings of a `foam` job.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FoamJob {
    /// The region meshes (one file per region, in order).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub meshes: Option<Input>,
    /// A built-in model used instead of files.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub model: Option<Model>,
    /// Each region's pair, in the order of the meshes.
    #[serde(default = "default_regions")]
    pub regions: Vec<RegionSpec>,
    /// Transitions between regions that share a boundary.
    #[serde(default = "default_transitions")]
    pub transitions: Vec<TransitionSpec>,
    /// Slicing and printing.
    #[serde(default)]
    pub foam: Options,
}

fn default_regions() -> Vec<RegionSpec> {
    vec![RegionSpec::new(0.15, DEFAULT_H_STAR), RegionSpec::new(0.4, DEFAULT_H_STAR)]
}

fn default_transitions() -> Vec<TransitionSpec> {
    vec![TransitionSpec { from: 1, to: 2, length_mm: 40.0, weighting: Weighting::Linear }]
}

/// The paper's dogbone with V* 0.15 → 0.4 over a 40 mm linear transition.
impl Default for FoamJob {
    fn default() -> Self {
        FoamJob { meshes: None, model: Some(Model::default()), regions: default_regions(), transitions: default_transitions(), foam: Options::default() }
    }
}

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
        stage: "regions",
        label: "Shared boundaries",
        shape: Shape::Mesh,
        index_label: "Boundary",
        doc: "The faces two regions share (highlighted), where transitions are centred (mm).",
    },
    ViewInfo {
        id: "layer",
        stage: "raster",
        label: "Layer path",
        shape: Shape::Lines2d,
        index_label: "Layer",
        doc: "One layer's continuous path: scan lines, turns along the outline, and the outline (mm).",
    },
];

const OPTION_FIELDS: &[Row0] = &[
    num("layer_height_mm", "Foam", "Layer height", "mm", 0.05, 20.0, 0.05, "Height between layers of thread."),
    num("line_spacing_mm", "Foam", "Line spacing", "mm", 0.1, 50.0, 0.1, "Distance between neighbouring raster lines of a layer."),
    num("raster_angle_deg", "Foam", "Raster angle", "°", -360.0, 360.0, 1.0, "Direction of the raster lines on the first layer."),
    other("alternate", "Foam", "Cross the layers", FieldKind::Bool, &[], "Turn the raster 90° on every other layer."),
    percent(num(
        "inset",
        "Foam",
        "Turns inside the outline",
        "",
        0.0,
        1.0,
        0.05,
        "How far inside the outline the path turns, in line spacings (50 %: half a spacing).",
    )),
    num("piece_mm", "Foam", "Piece length", "mm", 0.01, 100.0, 0.05, "The path is cut into pieces this long; each gets the V* and H* of its end."),
    num(
        "feed_mm_s",
        "Foam",
        "Filament feed C",
        "mm/s",
        0.01,
        100.0,
        0.1,
        "Filament fed into the extruder per second, the same everywhere (constant extrusion).",
    ),
    other("many_neighbours", "Foam", "Several neighbours", FieldKind::Bool, &[], "Let a region touch several others (the paper allows one)."),
    when(
        crate::settings::choice_docs(
            other(
                "junction",
                "Foam",
                "Near several boundaries",
                FieldKind::Choice,
                &["blend", "nearest"],
                "How a point within reach of several transitions of its region takes V* and H*.",
            ),
            &[
                "Average the transitions' blends, weighted by closeness: no jumps where boundaries meet.",
                "Take the nearest boundary's blend only: jumps where the nearest changes.",
            ],
        ),
        "many_neighbours",
        "true",
    ),
    num(
        "calibration.f_kpa",
        "Stiffness",
        "Modulus fit F",
        "kPa",
        1e-6,
        1e6,
        0.01,
        "F of the modulus measured along a linear V* sweep, E = F·e^(b·u) (the paper's 4.79).",
    ),
    num(
        "calibration.b",
        "Stiffness",
        "Modulus fit b",
        "",
        -100.0,
        100.0,
        0.01,
        "b of that fit; u runs from −½ at the sweep's first V* to ½ at its last (the paper's −3.11).",
    ),
    num("calibration.v_star_from", "Stiffness", "Sweep from V*", "", 0.01, 10.0, 0.01, "V* where the measured sweep started (the paper's 0.15)."),
    num(
        "calibration.v_star_to",
        "Stiffness",
        "Sweep to V*",
        "",
        0.01,
        10.0,
        0.01,
        "V* where it ended (the paper's 0.4); moduli outside the sweep are refused.",
    ),
    other(
        "probe_axis",
        "Probe",
        "Probe line along",
        FieldKind::Choice,
        &["x", "y", "z"],
        "The report plots V*, H* and ΔE/mm along this axis through the middle of the part.",
    ),
];

const REGION_V: [&str; MAX_REGIONS] =
    ["Region 1: V*", "Region 2: V*", "Region 3: V*", "Region 4: V*", "Region 5: V*", "Region 6: V*", "Region 7: V*", "Region 8: V*"];
const REGION_SET: [&str; MAX_REGIONS] = [
    "Region 1: set by",
    "Region 2: set by",
    "Region 3: set by",
    "Region 4: set by",
    "Region 5: set by",
    "Region 6: set by",
    "Region 7: set by",
    "Region 8: set by",
];
const REGION_E: [&str; MAX_REGIONS] = [
    "Region 1: modulus",
    "Region 2: modulus",
    "Region 3: modulus",
    "Region 4: modulus",
    "Region 5: modulus",
    "Region 6: modulus",
    "Region 7: modulus",
    "Region 8: modulus",
];
const REGION_H: [&str; MAX_REGIONS] =
    ["Region 1: H*", "Region 2: H*", "Region 3: H*", "Region 4: H*", "Region 5: H*", "Region 6: H*", "Region 7: H*", "Region 8: H*"];
const T_FROM: [&str; MAX_TRANSITIONS] = [
    "Transition 1: from region",
    "Transition 2: from region",
    "Transition 3: from region",
    "Transition 4: from region",
    "Transition 5: from region",
    "Transition 6: from region",
    "Transition 7: from region",
    "Transition 8: from region",
];

/// The form rows of region `i` and transition `i` (paths with their index).
fn indexed_rows() -> Vec<Row> {
    let mut rows = Vec::new();
    for i in 0..MAX_REGIONS {
        let f = [
            crate::settings::choice_docs(
                other(
                    "set_by",
                    "Regions",
                    REGION_SET[i],
                    FieldKind::Choice,
                    &["v_star", "modulus"],
                    "Give the region's V* directly, or the stiffness it should have.",
                ),
                &["V* as given.", "The V* whose foam has this modulus, by the calibration under Stiffness."],
            ),
            when(
                num(
                    "v_star",
                    "Regions",
                    REGION_V[i],
                    "",
                    0.01,
                    10.0,
                    0.01,
                    "Nozzle speed ÷ thread speed: lower lays more coils per mm (denser, stiffer foam); the paper prints 0.15–0.4.",
                ),
                "set_by",
                "v_star",
            ),
            when(
                num(
                    "modulus_kpa",
                    "Regions",
                    REGION_E[i],
                    "kPa",
                    1e-6,
                    1e6,
                    0.1,
                    "Target compressive modulus; weft picks the V* the calibration gives for it (the paper's fit for its TPU: 1.01 to 22.68 kPa).",
                ),
                "set_by",
                "modulus",
            ),
            num("h_star", "Regions", REGION_H[i], "", 0.1, 100.0, 0.5, "Nozzle height in swollen thread diameters: higher gives wider coils."),
        ];
        rows.extend(mount(&format!("job.regions.{i}"), &f));
    }
    for i in 0..MAX_TRANSITIONS {
        let f = [
            num("from", "Transitions", T_FROM[i], "", 1.0, MAX_REGIONS as f64, 1.0, "The region where the weight is 0 (the transition runs from it)."),
            num("to", "Transitions", "to region", "", 1.0, MAX_REGIONS as f64, 1.0, "The region where the weight is 1."),
            num("length_mm", "Transitions", "length", "mm", 0.0, 10000.0, 0.5, "Width of the blend, centred on the shared boundary (0: a sharp step)."),
            crate::settings::choice_docs(
                other(
                    "weighting.kind",
                    "Transitions",
                    "weighting",
                    FieldKind::Choice,
                    &["linear", "cubic", "logarithmic", "cube_root", "sinusoidal", "linear_modulus"],
                    "How V* and H* blend across the transition.",
                ),
                &[
                    "w = x + ½: V* and H* change at a constant rate.",
                    "w = 4(1 − s)x³ + s·x + ½: slope s at the boundary (1.5: smooth ends).",
                    "The paper's fitted inverse: its foam's measured modulus, not V*, changed linearly (it misses the ends a little).",
                    "w = ∛(x/4) + ½: steep at the boundary, flat at the ends.",
                    "w = sin(πx)/2 + ½: smooth at both ends.",
                    "The modulus changes linearly from region to region by the calibration, exact at both ends.",
                ],
            ),
            num(
                "weighting.slope",
                "Transitions",
                "slope",
                "",
                -1000.0,
                1000.0,
                0.01,
                "Cubic: slope at the boundary (0 to 1.5). Logarithmic: slope of the modulus line E(x).",
            ),
            num("weighting.intercept", "Transitions", "intercept", "", -1000.0, 1000.0, 0.01, "Intercept of the modulus line E(x) (the paper's 13.26)."),
            num("weighting.f", "Transitions", "F", "", 1e-6, 1000.0, 0.01, "Factor of the modulus fit E = F·e^(b·u) (the paper's 4.79)."),
            num("weighting.b", "Transitions", "b", "", -100.0, 100.0, 0.01, "Exponent of the modulus fit (the paper's −3.11)."),
        ];
        let mut r = mount(&format!("job.transitions.{i}"), &f);
        // Integers: region numbers.
        for row in r.iter_mut().take(2) {
            row.field.kind = FieldKind::Integer;
        }
        rows.extend(r);
    }
    rows
}

/// The die swell, nozzle and filament of the design with the feed C.
fn process(design: &Design, j: &FoamJob) -> Process {
    Process {
        nozzle_mm: design.printer.nozzle_diameter_mm,
        die_swell: design.material.swell_ratio,
        filament_mm: design.printer.filament_diameter_mm,
        feed_mm_s: j.foam.feed_mm_s,
    }
}

/// How many meshes the design names (None: a built-in model, whose count is its own).
fn mesh_names(j: &FoamJob) -> Vec<String> {
    match &j.meshes {
        Some(Input::File { name, .. }) => vec![name.clone()],
        Some(Input::Files(names)) => names.clone(),
        _ => Vec::new(),
    }
}

/// The number of regions the job's source gives.
fn source_regions(j: &FoamJob) -> Option<usize> {
    match &j.model {
        Some(m) => Some(models::build(m).len()),
        None => j.meshes.as_ref().map(|_| mesh_names(j).len()),
    }
}

/// Each region's pair (V* given, or by the calibration from its modulus).
fn pairs(j: &FoamJob) -> Vec<Pair> {
    j.regions.iter().map(|r| r.pair(&j.foam.calibration)).collect()
}

/// The transitions with regions from 0; a linear-modulus weighting takes the ratio of its
/// regions' moduli by the calibration.
fn transitions(j: &FoamJob) -> Vec<Transition> {
    let pairs = pairs(j);
    let v = |r: usize| pairs.get(r.wrapping_sub(1)).map_or(f64::NAN, |p| p.v_star);
    j.transitions
        .iter()
        .map(|t| {
            let weighting = match t.weighting {
                Weighting::LinearModulus { .. } => Weighting::LinearModulus { ratio: j.foam.calibration.ratio(v(t.from), v(t.to)) },
                w => w,
            };
            Transition { from: t.from.saturating_sub(1), to: t.to.saturating_sub(1), length_mm: t.length_mm, weighting }
        })
        .collect()
}

impl Kind for FoamKind {
    type Settings = FoamJob;
    const NAME: &'static str = "foam";
    const LABEL: &'static str = "Graded foam (VTP)";
    const DOC: &'static str = "A viscous-thread-printed foam whose stiffness is graded between regions, printed as one uninterrupted thread.";
    const SLOTS: &'static [Slot] = SLOTS;
    const STAGES: &'static [StageInfo] = STAGES;
    const VIEWS: &'static [ViewInfo] = VIEWS;

    fn fields() -> Vec<Row> {
        let mut rows = mount(
            "job",
            &[crate::settings::Field {
                default: Some(r#"{"kind":"dogbone","neck_length_mm":60,"neck_width_mm":12,"grip_length_mm":30,"grip_width_mm":25,"thickness_mm":10}"#),
                ..other("model", "Model", "Built-in model", FieldKind::Section, &[], "Use region meshes made by weft instead of loaded files.")
            }],
        );
        rows.extend(mount("job.model", models::FIELDS));
        rows.extend(indexed_rows());
        rows.extend(mount("job.foam", OPTION_FIELDS));
        rows
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
        let p = process(design, j);
        for m in p.problems() {
            out.push(Problem { path: "job.foam.feed_mm_s".into(), message: m });
        }
        if j.model.is_none() && j.meshes.is_none() {
            out.push(Problem {
                path: "job.meshes".into(),
                message: "a foam needs its region meshes: load one file per region, or switch on a built-in model".into(),
            });
        }
        if let Some(m) = &j.model {
            for message in models::problems(m) {
                out.push(Problem { path: "job.model".into(), message });
            }
        }
        if j.regions.len() > MAX_REGIONS {
            out.push(Problem { path: "job.regions".into(), message: format!("{} regions: at most {MAX_REGIONS}", j.regions.len()) });
        }
        if j.transitions.len() > MAX_TRANSITIONS {
            out.push(Problem { path: "job.transitions".into(), message: format!("{} transitions: at most {MAX_TRANSITIONS}", j.transitions.len()) });
        }
        // More pairs than regions is allowed (a region's row waits for its file: loading
        // files one by one never drops a row); fewer is not.
        if let Some(n) = source_regions(j) {
            if n > j.regions.len() {
                out.push(Problem {
                    path: "job.regions".into(),
                    message: format!(
                        "the model has {n} region(s) but the design gives {} V*/H* pair(s): give one pair per region, in the order of the meshes",
                        j.regions.len()
                    ),
                });
            }
        }
        let c = &j.foam.calibration;
        let calibration = c.problems();
        for message in &calibration {
            out.push(Problem { path: "job.foam.calibration".into(), message: message.clone() });
        }
        for (i, r) in j.regions.iter().enumerate() {
            if r.set_by == SetBy::Modulus {
                if let Some(message) = c.modulus_problem(r.modulus_kpa).filter(|_| calibration.is_empty()) {
                    out.push(Problem { path: format!("job.regions.{i}.modulus_kpa"), message: format!("region {}: {message}", i + 1) });
                    continue;
                } else if !calibration.is_empty() {
                    continue;
                }
            }
            for message in p.pair_problems(&format!("region {}", i + 1), r.pair(c), j.foam.layer_height_mm) {
                out.push(Problem { path: format!("job.regions.{i}"), message });
            }
        }
        let n = j.regions.len();
        for (i, t) in j.transitions.iter().enumerate() {
            let path = format!("job.transitions.{i}");
            for (end, r) in [("from", t.from), ("to", t.to)] {
                if r == 0 || r > n {
                    out.push(Problem { path: format!("{path}.{end}"), message: format!("region {r} does not exist: regions are numbered 1 to {n}") });
                }
            }
            if t.from == t.to {
                out.push(Problem {
                    path: format!("{path}.to"),
                    message: format!("a transition joins two different regions (both ends are region {})", t.from),
                });
            }
            if !(t.length_mm.is_finite() && t.length_mm >= 0.0) {
                out.push(Problem { path: format!("{path}.length_mm"), message: format!("{} mm: the length must be 0 (a step) or more", t.length_mm) });
            }
            for message in t.weighting.problems() {
                out.push(Problem { path: format!("{path}.weighting"), message });
            }
            if j.transitions[..i].iter().any(|u| (u.from.min(u.to), u.from.max(u.to)) == (t.from.min(t.to), t.from.max(t.to))) {
                out.push(Problem { path: path.clone(), message: format!("regions {} and {} already have a transition: give one per pair", t.from, t.to) });
            }
        }
        if !(j.foam.piece_mm.is_finite() && j.foam.piece_mm > 0.0) {
            out.push(Problem { path: "job.foam.piece_mm".into(), message: "the piece length must be above 0 mm".into() });
        }
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
        let placed = placed_stage(j, ctx)?;
        let triangles = placed.union.triangles.len();
        let regions = Estimate::new("regions").quantity("triangles", "Triangles", triangles as f64, "").cost(triangles as f64 * 400.0, triangles as f64 * 4e-6);
        let slice_e = slice::estimate(&placed.union, &slice_options(j));
        let b = placed.union.bounds().map(|b| b.max - b.min).unwrap_or_default();
        let layers = (b.z / j.foam.layer_height_mm).ceil().max(1.0);
        let s = j.foam.line_spacing_mm;
        // Upper bounds from the box: every layer full, plus a turn per line.
        let lines = layers * (b.x.max(b.y) / s + 1.0);
        let length = layers * (b.x * b.y / s + b.x + b.y);
        let pieces = length / j.foam.piece_mm + lines;
        let raster = Estimate::new("raster")
            .quantity("lines", "Raster lines", lines, "")
            .cost(lines * 400.0, lines * 5e-6)
            .limit("raster lines", lines, raster::MAX_SCAN_INTERSECTIONS as f64, "", "raise the line spacing or the layer height")
            .budgets("raise the line spacing or the layer height");
        let grade = Estimate::new("grade")
            .quantity("pieces", "Pieces", pieces, "")
            .quantity("segments", "Segments", pieces, "")
            .cost(pieces * 72.0, pieces * 1e-6)
            .limit("pieces", pieces, MAX_PIECES, "", "raise the piece length, the line spacing or the layer height")
            .budgets("raise the piece length, the line spacing or the layer height");
        Ok(vec![regions, slice_e, raster, grade])
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
        match view {
            "boundaries" => {
                let regions = regions_stage(j, ctx)?;
                let count = regions.boundaries.len();
                let index = index.min(count.saturating_sub(1));
                let mut data = Vec::new();
                let mut meta = serde_json::json!({ "regions": regions.names() });
                if let Some(b) = regions.boundaries.get(index) {
                    for t in &b.triangles {
                        for p in t {
                            data.extend_from_slice(&[p.x as f32, p.y as f32, p.z as f32]);
                        }
                    }
                    meta = serde_json::json!({
                        "between": [regions.regions[b.a].name, regions.regions[b.b].name],
                        "area_mm2": b.area_mm2,
                        "legend": { "0": format!("{} | {}", regions.regions[b.a].name, regions.regions[b.b].name) },
                    });
                }
                Ok(Inspection { view: view.into(), shape: Shape::Mesh, index, count, stride: Shape::Mesh.stride(), data, overlay: Vec::new(), meta })
            }
            "layer" => {
                let regions = regions_stage(j, ctx)?;
                let layers = slice_stage(j, ctx, &regions)?;
                let paths = raster_stage(j, ctx, &layers)?;
                let count = paths.len();
                let index = index.min(count.saturating_sub(1));
                let mut data = Vec::new();
                if let (Some(path), Some(layer)) = (paths.get(index), layers.get(index)) {
                    for w in path.points.windows(2) {
                        data.extend_from_slice(&[w[0].x as f32, w[0].y as f32, w[1].x as f32, w[1].y as f32, Feature::Infill.code() as f32]);
                    }
                    for ring in std::iter::once(&layer.polygon.outer).chain(&layer.polygon.holes) {
                        for k in 0..ring.len() {
                            let (a, b) = (ring[k], ring[(k + 1) % ring.len()]);
                            data.extend_from_slice(&[a.x as f32, a.y as f32, b.x as f32, b.y as f32, Feature::ExternalPerimeter.code() as f32]);
                        }
                    }
                }
                let z = layers.get(index).map_or(0.0, |l| l.z);
                let meta = serde_json::json!({ "z_mm": z, "legend": { Feature::Infill.code().to_string(): "path", Feature::ExternalPerimeter.code().to_string(): "outline" } });
                Ok(Inspection { view: view.into(), shape: Shape::Lines2d, index, count, stride: Shape::Lines2d.stride(), data, overlay: Vec::new(), meta })
            }
            _ => Err(Error::UnknownView { view: view.into(), job: Self::NAME }),
        }
    }
}

/// The regions placed together: each region's mesh, moved with the others so that their
/// union stands on the plate, XY centred on 0 (their places relative to each other kept), and
/// that union (all triangles in one mesh: touching outlines merge when sliced).
pub struct Placed {
    /// Region names (their files, or the model's).
    pub names: Vec<String>,
    /// Region meshes, placed.
    pub meshes: Vec<Mesh>,
    /// All of them in one mesh.
    pub union: Mesh,
}

/// The placed regions of the files (each imported and cached on its own) or of the built-in
/// model: made by the estimate, read again by the run.
fn placed_stage(j: &FoamJob, ctx: &mut Ctx) -> Result<Out<Placed>, Error> {
    let mut items: Vec<(String, Out<Mesh>)> = Vec::new();
    if j.model.is_none() {
        let input = j.meshes.as_ref().ok_or_else(|| {
            Error::NoInput("a foam needs its region meshes: load one file per region (--input regions=FILE, repeated), or switch on a built-in model".into())
        })?;
        let inputs: Vec<Input> = match input {
            Input::Files(names) => names.iter().map(|n| Input::File { name: n.clone(), embedded: None }).collect(),
            other => vec![other.clone()],
        };
        // One .zip holds the region files (in name order, as a folder gives them).
        let zipped = matches!(input, Input::File { name, .. } if name.to_ascii_lowercase().ends_with(".zip"));
        if inputs.len() > MAX_REGIONS {
            return Err(Error::NoInput(format!("{} region meshes: a foam takes at most {MAX_REGIONS}", inputs.len())));
        }
        if let Some(Input::File { name, .. }) =
            inputs.iter().find(|i| matches!(i, Input::File { name, .. } if name.to_ascii_lowercase().ends_with(".zip"))).filter(|_| !zipped)
        {
            return Err(Error::NoInput(format!(
                "{name} is a zip among other region files: a zip holds all the region meshes, so load it alone (remove the other region files)"
            )));
        }
        if zipped {
            items = ctx.mesh_items_of_zip(&SLOTS[0], input)?;
        } else {
            for (i, input) in inputs.iter().enumerate() {
                let name = match input {
                    Input::File { name, .. } => name.clone(),
                    _ => format!("region {}", i + 1),
                };
                items.push((name, ctx.mesh_item(&SLOTS[0], i, input)?));
            }
        }
        if items.len() > MAX_REGIONS {
            return Err(Error::NoInput(format!("{} region meshes: a foam takes at most {MAX_REGIONS}", items.len())));
        }
    }
    let keys: Vec<crate::stage::Key> = items.iter().map(|(_, m)| m.key).collect();
    let names: Vec<&str> = items.iter().map(|(n, _)| n.as_str()).collect();
    ctx.stage_kept("place", "place", &(&j.model, &names), &keys, |_| {
        let (names, mut meshes): (Vec<String>, Vec<Mesh>) = match &j.model {
            Some(m) => models::build(m).into_iter().unzip(),
            None => items.iter().map(|(n, m)| (n.clone(), (**m).clone())).unzip(),
        };
        let mut union = Mesh::default();
        for m in &meshes {
            union.append(m);
        }
        if let Some(b) = union.bounds() {
            let shift = DVec3::new(-(b.min.x + b.max.x) / 2.0, -(b.min.y + b.max.y) / 2.0, -b.min.z);
            union.translate(shift);
            for m in &mut meshes {
                m.translate(shift);
            }
        }
        Ok((Placed { names, meshes, union }, None))
    })
}

fn slice_options(j: &FoamJob) -> slice::Options {
    let h = j.foam.layer_height_mm;
    slice::Options { first_layer_height_mm: h, layer_height_mm: h, perimeters: 0, infill_density: 0.0, solid_layers: 0, ..slice::Options::default() }
}

/// The regions' solids and shared boundaries.
fn regions_stage(j: &FoamJob, ctx: &mut Ctx) -> Result<Out<Regions>, Error> {
    let placed = placed_stage(j, ctx)?;
    let options = regions::Options { many_neighbours: j.foam.many_neighbours, ..regions::Options::default() };
    ctx.stage("regions", "regions", &(j.foam.many_neighbours,), &[placed.key], |_| {
        let r =
            regions::regions(placed.names.iter().cloned().zip(placed.meshes.iter().cloned()).collect(), &options).map_err(|e| Error::stage("regions", e))?;
        let shared: f64 = r.boundaries.iter().map(|b| b.area_mm2).sum();
        let report = StageReport::new(
            "regions",
            "Finding shared boundaries",
            &serde_json::json!({ "regions": r.names(), "boundaries": r.boundaries.iter().map(|b| [b.a + 1, b.b + 1]).collect::<Vec<_>>() }),
        )
        .metric("regions", "Regions", r.regions.len() as f64, "", "Region meshes, each with its own V* and H*.")
        .metric("boundaries", "Shared boundaries", r.boundaries.len() as f64, "", "Pairs of regions that share a face; transitions are centred on these.")
        .metric("shared_area", "Shared area", shared, "mm²", "Total area of the shared boundaries.")
        .metric(
            "epsilon",
            "Contact tolerance ε",
            r.epsilon_mm,
            "mm",
            "Faces closer than this count as touching (10⁻⁶ of the model's size, at least 0.1 µm).",
        );
        Ok((r, Some(report)))
    })
}

/// One layer's outline.
pub struct Layer {
    /// Top of the layer, mm.
    pub z: f64,
    /// The union's one outline.
    pub polygon: Polygon,
}

/// The union sliced: one outline per layer, or refused naming the layer and the regions.
fn slice_stage(j: &FoamJob, ctx: &mut Ctx, regions: &Out<Regions>) -> Result<Out<Vec<Layer>>, Error> {
    let placed = placed_stage(j, ctx)?;
    let options = slice_options(j);
    ctx.stage("slice", "slice", &options, &[regions.key, placed.key], |progress| {
        let sliced = slice::slice(&placed.union, &options, &mut |f| progress(f * 0.5)).map_err(|e| Error::stage("slicing", e))?;
        // Each region alone, for the overlap check per layer.
        let mut per_region = Vec::with_capacity(placed.meshes.len());
        for (k, m) in placed.meshes.iter().enumerate() {
            let s = slice::slice(m, &options, &mut |_| {}).map_err(|e| Error::stage("slicing", e))?;
            per_region.push(s.layers);
            progress(0.5 + 0.5 * (k + 1) as f32 / placed.meshes.len() as f32);
        }
        let names: Vec<&str> = placed.names.iter().map(String::as_str).collect();
        let layers = check_layers(&sliced.layers, &per_region, &names).map_err(|e| Error::stage("slicing", e))?;
        let report = super::slice_report(&sliced.report, "Slicing the union").metric(
            "layers",
            "Layers",
            layers.len() as f64,
            "",
            "Layers of the foam, each one outline.",
        );
        Ok((layers, Some(report)))
    })
}

/// Why the union cannot be printed as one thread.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum LayerError {
    /// A layer with several outlines.
    #[error("the layer at z = {z:.2} mm is {count} separate outlines ({regions}); one continuous thread needs one outline per layer: join the parts, or print them as separate foams")]
    Several {
        /// Top of the layer.
        z: f64,
        /// Outlines.
        count: usize,
        /// The regions in the layer.
        regions: String,
    },
    /// An empty layer between two printed ones.
    #[error("nothing to print at z = {z:.2} mm between regions below and above: the regions do not make one connected foam (close the gap)")]
    Gap {
        /// Top of the layer.
        z: f64,
    },
    /// Two regions overlap in a layer.
    #[error("regions {a} and {b} overlap by {area:.2} mm² in the layer at z = {z:.2} mm; regions must only touch (move or trim one of them)")]
    Overlap {
        /// One region.
        a: String,
        /// The other.
        b: String,
        /// The overlap's area.
        area: f64,
        /// Top of the layer.
        z: f64,
    },
    /// Nothing at all.
    #[error("the regions slice to nothing: check that the meshes are closed solids")]
    Empty,
}

fn polygon_area(shapes: &[Polygon]) -> f64 {
    shapes.iter().map(|p| p.area()).sum()
}

fn contours(p: &[Polygon]) -> Vec<Vec<[f64; 2]>> {
    p.iter().flat_map(|p| std::iter::once(&p.outer).chain(&p.holes)).map(|r| r.iter().map(|q| [q.x, q.y]).collect()).collect()
}

/// Area of the intersection of two sets of polygons, mm².
fn overlap_area(a: &[Polygon], b: &[Polygon]) -> f64 {
    use i_overlay::core::fill_rule::FillRule;
    use i_overlay::core::overlay_rule::OverlayRule;
    use i_overlay::float::single::SingleFloatOverlay;
    let shapes = contours(a).overlay(&contours(b), OverlayRule::Intersect, FillRule::NonZero);
    shapes.iter().flatten().map(|r| crate::geom::signed_area(&r.iter().map(|p| DVec2::new(p[0], p[1])).collect::<Vec<_>>())).sum()
}

/// The per-layer rules: one outline per layer, no empty layer inside the stack, no overlap of
/// two regions in a layer (beyond 0.1 % of the layer's area and 0.01 mm²).
fn check_layers(union: &[slice::SlicedLayer], per_region: &[Vec<slice::SlicedLayer>], names: &[&str]) -> Result<Vec<Layer>, LayerError> {
    let first = union.iter().position(|l| !l.regions.is_empty()).ok_or(LayerError::Empty)?;
    let last = union.iter().rposition(|l| !l.regions.is_empty()).unwrap_or(first);
    let mut out = Vec::new();
    for (k, l) in union.iter().enumerate().take(last + 1).skip(first) {
        // Every slicing starts its stack at the plate with the same heights: layer k of a
        // region is layer k of the union (a lower region just has fewer).
        let here: Vec<(usize, &[Polygon])> = per_region
            .iter()
            .enumerate()
            .filter_map(|(r, layers)| layers.get(k).filter(|x| (x.slice_z - l.slice_z).abs() < 1e-9).map(|x| (r, x.regions.as_slice())))
            .filter(|(_, p)| !p.is_empty())
            .collect();
        let listed = || here.iter().map(|(r, _)| names[*r]).collect::<Vec<_>>().join(", ");
        if l.regions.is_empty() {
            return Err(LayerError::Gap { z: l.z });
        }
        let total = polygon_area(&l.regions);
        let sum: f64 = here.iter().map(|(_, p)| polygon_area(p)).sum();
        if sum > total + total * 1e-3 + 0.01 {
            for (x, (ra, pa)) in here.iter().enumerate() {
                for (rb, pb) in &here[x + 1..] {
                    let area = overlap_area(pa, pb);
                    if area > 0.01 {
                        return Err(LayerError::Overlap { a: names[*ra].into(), b: names[*rb].into(), area, z: l.z });
                    }
                }
            }
        }
        if l.regions.len() > 1 {
            return Err(LayerError::Several { z: l.z, count: l.regions.len(), regions: listed() });
        }
        out.push(Layer { z: l.z, polygon: l.regions[0].clone() });
    }
    Ok(out)
}

/// One layer's continuous path, as the raster made it.
pub struct LayerPath {
    /// Points, mm.
    pub points: Vec<DVec2>,
}

/// The raster of every layer, each starting where the last ended.
fn raster_stage(j: &FoamJob, ctx: &mut Ctx, layers: &Out<Vec<Layer>>) -> Result<Out<Vec<LayerPath>>, Error> {
    let o = j.foam;
    ctx.stage("raster", "raster", &(o.line_spacing_mm, o.raster_angle_deg, o.alternate, o.inset), &[layers.key], |progress| {
        let mut out: Vec<LayerPath> = Vec::with_capacity(layers.len());
        let (mut scan, mut boundary, mut retraced, mut cells) = (0.0, 0.0, 0.0, 0usize);
        for (k, layer) in layers.iter().enumerate() {
            let angle = o.raster_angle_deg + if o.alternate && k % 2 == 1 { 90.0 } else { 0.0 };
            let area = inset(&layer.polygon, o.inset * o.line_spacing_mm, layer.z).map_err(|e| Error::stage("raster", e))?;
            let start = out.last().and_then(|p: &LayerPath| p.points.last().copied());
            let r = raster::raster(&area, start, &raster::Options { spacing_mm: o.line_spacing_mm, angle_deg: angle })
                .map_err(|e| Error::stage("raster", RasterAt { z: layer.z, source: e }))?;
            scan += r.raster_mm;
            boundary += r.boundary_mm;
            retraced += r.retraced_mm;
            cells += r.cells;
            out.push(LayerPath { points: r.points });
            progress((k + 1) as f32 / layers.len() as f32);
        }
        let report = StageReport::new("raster", "One continuous path per layer", &serde_json::json!({ "layers": out.len() }))
            .metric("raster", "Raster lines", scan, "mm", "Length of the scan lines of every layer.")
            .metric("turns", "Turns along the outline", boundary, "mm", "Length of the links that run along the outline between lines and cells.")
            .metric(
                "retraced",
                "Lines run twice",
                retraced,
                "mm",
                "Links that cross a part already printed to reach the next cell (printed twice: denser there); 0 for simple outlines.",
            )
            .metric("cells", "Cells", cells as f64, "", "Boustrophedon cells over all layers (each a zig-zag); more where outlines are concave or have holes.");
        Ok((out, Some(report)))
    })
}

/// A raster error with the layer it happened in.
#[derive(Debug, thiserror::Error)]
#[error("layer at z = {z:.2} mm: {source}")]
struct RasterAt {
    z: f64,
    source: raster::Error,
}

/// An outline that cannot be inset for the raster's turns.
#[derive(Debug, thiserror::Error)]
#[error("layer at z = {z:.2} mm: the outline inset by {d:.2} mm {what}; lower the turn inset or the line spacing")]
struct InsetError {
    z: f64,
    d: f64,
    what: &'static str,
}

/// `polygon` shrunk by `d` mm (the raster's turns run there); refused when it vanishes or splits.
fn inset(polygon: &Polygon, d: f64, z: f64) -> Result<Polygon, InsetError> {
    use i_overlay::mesh::float::outline::offset::OutlineOffset;
    use i_overlay::mesh::float::style::OutlineStyle;
    if d <= 0.0 {
        return Ok(polygon.clone());
    }
    let shape = contours(std::slice::from_ref(polygon));
    let out = shape.outline(&OutlineStyle::new(-d));
    let mut polys: Vec<Polygon> = out
        .iter()
        .filter(|s| !s.is_empty())
        .map(|s| {
            let ring = |r: &Vec<[f64; 2]>| r.iter().map(|p| DVec2::new(p[0], p[1])).collect::<Vec<_>>();
            Polygon { outer: ring(&s[0]), holes: s[1..].iter().map(ring).collect() }
        })
        .filter(|p| p.area() > 1e-9)
        .collect();
    match polys.len() {
        0 => Err(InsetError { z, d, what: "vanishes (the part is too thin)" }),
        1 => Ok(polys.remove(0)),
        _ => Err(InsetError { z, d, what: "splits into several parts (a neck narrower than twice the inset)" }),
    }
}

/// The toolpath ([`grade::grade`]: each layer's path cut into pieces, each with the pair of
/// its end) once the design's pairs and transitions are checked against the regions loaded,
/// and the report with its plots.
fn grade(
    j: &FoamJob,
    p: &Process,
    regions: &Regions,
    layers: &[Layer],
    paths: &[LayerPath],
    progress: &mut dyn FnMut(f32),
) -> Result<(Toolpath, Option<StageReport>), Error> {
    let mut pairs = pairs(j);
    let n = regions.regions.len();
    if pairs.len() < n {
        return Err(Error::NoInput(format!("the foam has {n} regions but the design gives {} V*/H* pairs: give one per region", pairs.len())));
    }
    // Rows and transitions beyond the regions given wait for their files, said out loud.
    let mut notes = Vec::new();
    if pairs.len() > n {
        notes.push(format!(
            "the design gives {} V*/H* pairs for {n} region mesh(es): pair(s) {}–{} wait for their files and are not used",
            pairs.len(),
            n + 1,
            pairs.len()
        ));
        pairs.truncate(n);
    }
    let mut transitions = transitions(j);
    let waiting = transitions.iter().filter(|t| t.from >= n || t.to >= n).count();
    if waiting > 0 {
        notes.push(format!("{waiting} transition(s) join a region without its file and are not used"));
        transitions.retain(|t| t.from < n && t.to < n);
    }
    for t in &transitions {
        if regions.boundary(t.from, t.to).is_none() {
            return Err(Error::NoInput(format!(
                "the transition from region {} ({}) to region {} ({}) has no boundary to run across: those regions do not touch (remove it, or pick touching regions)",
                t.from + 1,
                regions.regions[t.from].name,
                t.to + 1,
                regions.regions[t.to].name
            )));
        }
    }
    let field = Field::new(regions, pairs.clone(), &transitions, j.foam.junction);
    let rasters: Vec<grade::LayerRaster> = paths.iter().zip(layers).map(|(path, layer)| grade::LayerRaster { z: layer.z, points: &path.points }).collect();
    let g = grade::grade(&field, p, &rasters, j.foam.layer_height_mm, j.foam.piece_mm, p.die_swell * p.nozzle_mm, progress);
    let (toolpath, pieces, queries, (v_lo, v_hi)) = (g.toolpath, g.pieces, g.queries, g.v_range);
    let mut report = grade_report(j, p, &field, regions, &transitions, pieces, queries, (v_lo, v_hi));
    report.notes.extend(notes);
    Ok((toolpath, Some(report)))
}

#[allow(clippy::too_many_arguments)] // the report of one stage: its numbers
fn grade_report(
    j: &FoamJob,
    p: &Process,
    field: &Field,
    regions: &Regions,
    transitions: &[Transition],
    pieces: usize,
    queries: usize,
    v: (f64, f64),
) -> StageReport {
    let (v_lo, v_hi) = if v.0 <= v.1 { v } else { (0.0, 0.0) };
    let mut r = StageReport::new("grade", "Grading V* and H* along the path", &serde_json::json!({ "pieces": pieces, "queries": queries }))
        .metric("pieces", "Pieces", pieces as f64, "", "Pieces of path, each printed with the V* and H* of its end point.")
        .metric(
            "queries",
            "Exact evaluations",
            queries as f64,
            "",
            "Pieces whose pair needed parry's distance queries; the others were known far from every boundary.",
        )
        .metric("v_star_min", "Lowest V*", v_lo, "", "Densest coils printed.")
        .metric("v_star_max", "Highest V*", v_hi, "", "Sparsest coils printed.")
        .metric(
            "e_per_mm_max",
            "Most filament per mm",
            if v_lo > 0.0 { p.filament_per_mm(v_lo) } else { 0.0 },
            "mm/mm",
            "ΔE per mm of nozzle travel at the lowest V*: A_t / (V*·A_f).",
        )
        .metric(
            "e_per_mm_min",
            "Least filament per mm",
            if v_hi > 0.0 { p.filament_per_mm(v_hi) } else { 0.0 },
            "mm/mm",
            "ΔE per mm of nozzle travel at the highest V*.",
        )
        .metric(
            "thread_speed",
            "Thread speed",
            p.speed_mm_s(1.0),
            "mm/s",
            "Speed of the thread leaving the nozzle, C·A_f/A_t (the nozzle moves V* times as fast).",
        );
    // The weighting functions of the transitions (appendix A), plotted over x = α_i/α_T.
    let xs: Vec<f64> = (0..=120).map(|i| -0.6 + 1.2 * i as f64 / 120.0).collect();
    let mut weights = Plot {
        key: "weighting".into(),
        title: "Weighting functions w(x)".into(),
        kind: PlotKind::Line,
        x: Axis::new("x = α_i / α_T", ""),
        y: Axis::new("w", ""),
        group: None,
        series: Vec::new(),
    };
    let mut seen: Vec<Weighting> = Vec::new();
    for t in transitions {
        if !seen.contains(&t.weighting) {
            seen.push(t.weighting);
        }
    }
    let used = seen.len();
    let linear_modulus = Weighting::LinearModulus { ratio: crate::foam::weight::DEFAULT_MODULUS_RATIO };
    for w in [
        Weighting::Linear,
        Weighting::Cubic { slope: crate::foam::weight::DEFAULT_CUBIC_SLOPE },
        Weighting::logarithmic(),
        Weighting::CubeRoot,
        Weighting::Sinusoidal,
        linear_modulus,
    ] {
        if !seen.iter().any(|s| std::mem::discriminant(s) == std::mem::discriminant(&w)) {
            seen.push(w);
        }
    }
    for (i, w) in seen.iter().enumerate() {
        // Linear-modulus weightings differ by their regions' modulus ratio.
        let ratio = match w {
            Weighting::LinearModulus { ratio } => format!(", E × {ratio:.3}"),
            _ => String::new(),
        };
        let name = format!("{}{ratio}{}", weighting_name(w), if i < used { " (used)" } else { "" });
        weights.series.push(Series::xy(&name, xs.clone(), xs.iter().map(|&x| w.weight(x)).collect()));
    }
    r.plots.push(weights);
    // The probe line through the middle of the part (the paper's Fig. 6).
    let all = regions.regions.iter().map(|x| x.bounds).reduce(|a, b| crate::geom::Aabb { min: a.min.min(b.min), max: a.max.max(b.max) });
    if let Some(b) = all {
        let c = (b.min + b.max) * 0.5;
        let (axis, label) = match j.foam.probe_axis {
            ProbeAxis::X => (DVec3::X, "x"),
            ProbeAxis::Y => (DVec3::Y, "y"),
            ProbeAxis::Z => (DVec3::Z, "z"),
        };
        let (lo, hi) = (b.min.dot(axis), b.max.dot(axis));
        let cal = &j.foam.calibration;
        let (mut s, mut vs, mut hs, mut es, mut ms) = (Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for i in 0..PROBE_SAMPLES {
            let t = lo + (hi - lo) * i as f64 / (PROBE_SAMPLES - 1) as f64;
            let q = c + axis * (t - c.dot(axis));
            let Some(pair) = field.inside(q) else { continue }; // outside the part
            s.push(t);
            vs.push(pair.v_star);
            hs.push(pair.h_star);
            es.push(p.filament_per_mm(pair.v_star));
            ms.push(cal.modulus_kpa(pair.v_star));
        }
        let plot = |key: &str, title: &str, y: &str, unit: &str, values: Vec<f64>| Plot {
            key: key.into(),
            title: format!("{title} along {label} (probe through the middle)"),
            kind: PlotKind::Line,
            x: Axis::new(label, "mm"),
            y: Axis::new(y, unit),
            group: None,
            series: vec![Series::xy(y, s.clone(), values)],
        };
        r.plots.push(plot("probe_v", "V*", "V*", "", vs.clone()));
        r.plots.push(plot("probe_h", "H*", "H*", "", hs));
        r.plots.push(plot("probe_e", "Filament per mm", "ΔE/mm", "mm/mm", es));
        if cal.problems().is_empty() {
            // Outside the calibration's sweep the fit is extrapolated: the title says so.
            let (lo, hi) = (cal.v_star_from.min(cal.v_star_to), cal.v_star_from.max(cal.v_star_to));
            let outside = vs.iter().any(|&v| v < lo * (1.0 - 1e-9) || v > hi * (1.0 + 1e-9));
            // The calibration (by default the paper's own fit) applied to V*: not a measurement,
            // so it cannot confirm the paper's moduli; the title says so.
            let fit = "Modulus by the calibration's fit at each V* (not measured)";
            let title = if outside { format!("{fit}, extrapolated outside V* {lo}–{hi}") } else { fit.to_string() };
            r.plots.push(plot("probe_modulus", &title, "E", "kPa", ms));
        }
    }
    // Regions set by a modulus: the V* weft chose for them.
    for (i, spec) in j.regions.iter().enumerate() {
        if spec.set_by == SetBy::Modulus {
            r.metrics.push(Metric {
                key: "region_v_star".into(),
                label: format!("Region {}: V*", i + 1),
                value: field.pair(i).v_star,
                unit: String::new(),
                hint: format!(
                    "The V* whose foam has {} kPa ({}), by the calibration under Stiffness.",
                    spec.modulus_kpa,
                    regions.regions.get(i).map_or("", |x| x.name.as_str())
                ),
                group_index: None,
            });
        }
    }
    for (i, t) in transitions.iter().enumerate() {
        r.metrics.push(Metric {
            key: "transition_length".into(),
            label: format!("Transition {}: {} → {}", i + 1, regions.regions[t.from].name, regions.regions[t.to].name),
            value: t.length_mm,
            unit: "mm".into(),
            hint: format!("{} blend over this length, centred on the shared boundary.", weighting_name(&t.weighting)),
            group_index: None,
        });
        // A weighting that does not meet its regions' values at its ends (the paper's fitted
        // logarithm) makes V* jump there: said, with the values it jumps to.
        let (a, b) = (field.pair(t.from).v_star, field.pair(t.to).v_star);
        let (w0, w1) = (t.weighting.inside(-0.5), t.weighting.inside(0.5));
        if t.length_mm > 0.0 && (w0.abs() > 1e-6 || (w1 - 1.0).abs() > 1e-6) {
            for (key, label, w) in [("transition_v_start", "starts at V*", w0), ("transition_v_end", "ends at V*", w1)] {
                r.metrics.push(Metric {
                    key: key.into(),
                    label: format!("Transition {} {label}", i + 1),
                    value: a + (b - a) * w,
                    unit: String::new(),
                    hint: "The weighting's own value at this end of the transition: V* jumps there from the region's.".into(),
                    group_index: None,
                });
            }
        }
    }
    r
}

fn weighting_name(w: &Weighting) -> &'static str {
    match w {
        Weighting::Linear => "linear",
        Weighting::Cubic { .. } => "cubic",
        Weighting::Logarithmic { .. } => "logarithmic",
        Weighting::CubeRoot => "cube root",
        Weighting::Sinusoidal => "sinusoidal",
        Weighting::LinearModulus { .. } => "linear modulus",
    }
}

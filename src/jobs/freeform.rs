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

use super::{Inspection, Kind, Product, Shape, Slot, SlotKind, StageInfo, ViewInfo};
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

/// Default beam diameter, mm (the paper's isomalt filaments: 100–200 µm).
pub const DEFAULT_BEAM_DIAMETER_MM: f64 = 0.15;
/// Default print speed along a beam, mm/s (the paper's 400 µm/s).
pub const DEFAULT_SPEED_MM_S: f64 = 0.4;
/// Default dwell at a beam's end joint to fuse it, s.
pub const DEFAULT_DWELL_S: f64 = 0.5;
/// Most beams a design may have (the issue's largest is 50k; the paper's 6,161).
pub const MAX_BEAMS: usize = wireframe::MAX_BEAMS;
/// Rows of the sequence table.
pub const TABLE_ROWS: usize = 200;

/// Which axis of the file points up on the printer.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Up {
    /// As drawn.
    #[default]
    Z,
    /// The file's +X up.
    X,
    /// The file's −X up.
    MinusX,
    /// The file's +Y up.
    Y,
    /// The file's −Y up.
    MinusY,
    /// Upside down.
    MinusZ,
}

impl Up {
    /// The point in printer axes (a proper rotation).
    pub fn turn(self, p: DVec3) -> DVec3 {
        match self {
            Up::Z => p,
            Up::X => DVec3::new(p.y, p.z, p.x),
            Up::MinusX => DVec3::new(p.y, -p.z, -p.x),
            Up::Y => DVec3::new(p.z, p.x, p.y),
            Up::MinusY => DVec3::new(-p.z, p.x, -p.y),
            Up::MinusZ => DVec3::new(p.x, -p.y, -p.z),
        }
    }
}

/// How the design is read.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct DesignOptions {
    /// Which of the file's axes points up.
    pub up: Up,
    /// Where the grounded joints come from.
    pub ground: Ground,
    /// "On the lowest level" within this, mm (grounding the lowest joints).
    pub ground_tolerance_mm: f64,
    /// CSV beam ends closer than this are one joint, mm.
    pub merge_tolerance_mm: f64,
}

impl Default for DesignOptions {
    fn default() -> Self {
        DesignOptions {
            up: Up::Z,
            ground: Ground::File,
            ground_tolerance_mm: wireframe::DEFAULT_GROUND_TOLERANCE_MM,
            merge_tolerance_mm: wireframe::DEFAULT_MERGE_TOLERANCE_MM,
        }
    }
}

/// The nozzle's shape.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct NozzleOptions {
    /// Cone half-angle, degrees.
    pub half_angle_deg: f64,
    /// Body radius above the cone, mm.
    pub radius_mm: f64,
    /// Body (cylinder) height above the cone, mm.
    pub height_mm: f64,
    /// How far the nozzle may tilt from the vertical, degrees (0: a 3-axis machine; more
    /// needs a 5-axis machine).
    pub tilt_deg: f64,
}

impl Default for NozzleOptions {
    fn default() -> Self {
        let n = Nozzle::default();
        NozzleOptions { half_angle_deg: n.half_angle_deg, radius_mm: n.radius_mm, height_mm: n.height_mm, tilt_deg: precedence::DEFAULT_TILT_DEG }
    }
}

/// The beams' section, material and the planning load.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct BeamOptions {
    /// Diameter, mm.
    pub diameter_mm: f64,
    /// Young's modulus, MPa.
    pub e_mpa: f64,
    /// Shear modulus, MPa.
    pub g_mpa: f64,
    /// Load at the free end of the beam being printed, N.
    pub load_n: f64,
}

impl Default for BeamOptions {
    fn default() -> Self {
        BeamOptions { diameter_mm: DEFAULT_BEAM_DIAMETER_MM, e_mpa: DEFAULT_E_MPA, g_mpa: DEFAULT_G_MPA, load_n: DEFAULT_LOAD_N }
    }
}

/// The process constraints (section II.A), each switchable.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ConstraintOptions {
    /// Steep beams only upward.
    pub directionality: bool,
    /// The nozzle never sweeps through a printed beam.
    pub collision: bool,
    /// Each beam starts at a grounded or printed joint.
    pub connection: bool,
    /// One cantilever per joint (strict) or any number (relaxed).
    pub cantilever: Mode,
}

impl Default for ConstraintOptions {
    fn default() -> Self {
        ConstraintOptions { directionality: true, collision: true, connection: true, cantilever: Mode::Strict }
    }
}

/// How the plan is made.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PlannerOptions {
    /// Cost used to choose.
    pub cost: Cost,
    /// Planning budget, s of counted work (past it the exact cost gives way to the heuristic).
    pub budget_s: f64,
    /// Measure both costs along the sequence (the paper's Fig. 8).
    pub compare: bool,
    /// The exact search over every order, on small designs.
    pub exact_search: ExactSearch,
    /// Largest design the exact search takes, beams.
    pub exact_beams: usize,
    /// States the exact search explores at most.
    pub exact_states: usize,
    /// Plan in bands of about this many beams up the design's height (0: whole).
    pub band_beams: usize,
    /// Send the G-code of the first beams ahead once the plan has fixed this many (0: never).
    pub send_ahead_beams: usize,
}

impl Default for PlannerOptions {
    fn default() -> Self {
        PlannerOptions {
            cost: Cost::Exact,
            budget_s: plan::DEFAULT_BUDGET_S,
            compare: true,
            exact_search: ExactSearch::Compare,
            exact_beams: optimal::DEFAULT_MAX_BEAMS,
            exact_states: optimal::DEFAULT_MAX_STATES,
            band_beams: bands::DEFAULT_BAND_BEAMS,
            send_ahead_beams: plan::DEFAULT_SEND_AHEAD_BEAMS,
        }
    }
}

/// What the exact search over every order does on a small design ([`optimal`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ExactSearch {
    /// Prove the planner's largest ε optimal or show the gap; print the planner's sequence
    /// (or the search's, when the planner finds none).
    #[default]
    Compare,
    /// Print the search's sequence when it beats the planner's.
    Print,
    /// Do not search.
    Off,
}

/// Printing.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PrintOptions {
    /// Speed along a beam, mm/s.
    pub speed_mm_s: f64,
    /// Dwell at each beam's end joint, s.
    pub dwell_s: f64,
    /// Clearance over the highest printed beam while deadheading, mm.
    pub clearance_mm: f64,
}

impl Default for PrintOptions {
    fn default() -> Self {
        PrintOptions { speed_mm_s: DEFAULT_SPEED_MM_S, dwell_s: DEFAULT_DWELL_S, clearance_mm: deadhead::DEFAULT_CLEARANCE_MM }
    }
}

/// Settings of a `freeform` job.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FreeformJob {
    /// The wireframe file.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub input: Option<Input>,
    /// A built-in design used instead of a file.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub model: Option<Model>,
    /// Reading the design.
    #[serde(default)]
    pub design: DesignOptions,
    /// The nozzle.
    #[serde(default)]
    pub nozzle: NozzleOptions,
    /// Beams and load.
    #[serde(default)]
    pub beam: BeamOptions,
    /// Process constraints.
    #[serde(default)]
    pub constraints: ConstraintOptions,
    /// Planner.
    #[serde(default)]
    pub planner: PlannerOptions,
    /// Printing.
    #[serde(default)]
    pub print: PrintOptions,
}

impl Default for FreeformJob {
    fn default() -> Self {
        FreeformJob {
            input: None,
            model: Some(Model::default()),
            design: DesignOptions::default(),
            nozzle: NozzleOptions::default(),
            beam: BeamOptions::default(),
            constraints: ConstraintOptions::default(),
            planner: PlannerOptions::default(),
            print: PrintOptions::default(),
        }
    }
}

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

const VIEWS: &[ViewInfo] = &[ViewInfo {
    id: "sequence",
    stage: "order",
    label: "Print sequence",
    shape: Shape::Lines3d,
    index_label: "Step",
    doc: "The wireframe after each step: printed beams, the beam being printed, the cantilevered ones, and those still to print (mm).",
}];

/// Feature codes the sequence view draws with (named by its legend).
const PRINTED: Feature = Feature::Lattice;
const CURRENT: Feature = Feature::ExternalPerimeter;
const CANTILEVER: Feature = Feature::Infill;
const TODO: Feature = Feature::Handle;

const DESIGN_FIELDS: &[Row0] = &[
    crate::settings::choice_docs(
        other(
            "up",
            "Design",
            "Up is the file's",
            FieldKind::Choice,
            &["z", "x", "minus_x", "y", "minus_y", "minus_z"],
            "Turn the design on the plate: which of its axes points up.",
        ),
        &["+Z, as drawn.", "+X.", "−X.", "+Y.", "−Y.", "−Z (upside down)."],
    ),
    crate::settings::choice_docs(
        other("ground", "Design", "Grounded joints", FieldKind::Choice, &["file", "lowest"], "Which joints stand on the substrate."),
        &["As the file marks them (the lowest joints when it marks none).", "Every joint within the tolerance of the lowest one."],
    ),
    num(
        "ground_tolerance_mm",
        "Design",
        "Ground tolerance",
        "mm",
        0.0,
        1000.0,
        0.01,
        "Joints this close above the lowest one count as grounded (when grounding the lowest).",
    ),
    num("merge_tolerance_mm", "Design", "Merge tolerance", "mm", 1e-6, 10.0, 0.001, "CSV beam ends closer than this are one joint."),
];

const NOZZLE_FIELDS: &[Row0] = &[
    num(
        "half_angle_deg",
        "Nozzle",
        "Cone half-angle",
        "°",
        1.0,
        89.0,
        1.0,
        "Half-angle of the nozzle's cone at the tip: beams steeper than this may only be printed upward.",
    ),
    num("radius_mm", "Nozzle", "Body radius", "mm", 0.01, 500.0, 0.1, "Radius of the nozzle body where the cone ends."),
    num(
        "height_mm",
        "Nozzle",
        "Body height",
        "mm",
        0.0,
        1000.0,
        1.0,
        "Height of the body's cylinder above the cone: beams within it are hit when printing below them.",
    ),
    num(
        "tilt_deg",
        "Nozzle",
        "Tilt up to",
        "°",
        0.0,
        precedence::MAX_TILT_DEG,
        5.0,
        "A 5-axis head may tilt the nozzle this far from vertical per beam to miss beams it would hit (0: a 3-axis printer).",
    ),
];

const BEAM_FIELDS: &[Row0] = &[
    num("diameter_mm", "Beams", "Beam diameter", "mm", 0.01, 50.0, 0.01, "Diameter of every beam: sets the extrusion and the stiffness."),
    num("e_mpa", "Beams", "Young's modulus E", "MPa", 1.0, 1e6, 100.0, "Stiffness of the set material (the paper's isomalt: 2600 MPa)."),
    num("g_mpa", "Beams", "Shear modulus G", "MPa", 1.0, 1e6, 100.0, "Twisting stiffness (the paper's isomalt: 1100 MPa)."),
    num(
        "load_n",
        "Beams",
        "Nozzle load",
        "N",
        1e-9,
        100.0,
        1e-5,
        "Force of the nozzle on the free end of the beam being printed, straight down (the paper's 10⁻⁴ N).",
    ),
];

const CONSTRAINT_FIELDS: &[Row0] = &[
    other("directionality", "Constraints", "Directionality", FieldKind::Bool, &[], "A beam steeper than the cone is printed upward, never into the nozzle."),
    other("collision", "Constraints", "Collision", FieldKind::Bool, &[], "The nozzle never sweeps through a printed beam: such beams are printed after."),
    other("connection", "Constraints", "Connection", FieldKind::Bool, &[], "Each beam starts at a grounded joint or a joint already printed."),
    crate::settings::choice_docs(
        other("cantilever", "Constraints", "Cantilevers", FieldKind::Choice, &["strict", "relaxed"], "How many cantilevers a joint may carry while printing."),
        &[
            "One per joint: heating a joint lets a second cantilever pivot (isomalt, glassy materials).",
            "Any number (materials whose joints hold while heated).",
        ],
    ),
];

const PLANNER_FIELDS: &[Row0] = &[
    crate::settings::choice_docs(
        other("cost", "Planner", "Stability cost", FieldKind::Choice, &["exact", "heuristic"], "How the error ε of each printed joint is computed while planning."),
        &["The whole connected frame deflects under the nozzle's load (slower, the paper's exact cost).", "Only the cantilevered beams deflect, the rest is rigid (the paper's fast heuristic)."],
    ),
    num("budget_s", "Planner", "Planning budget", "s", 0.1, 36000.0, 1.0, "Work allowed for the exact cost (counted, the same on every machine); past it the plan goes on with the heuristic."),
    other("compare", "Planner", "Compare the costs", FieldKind::Bool, &[], "Measure both the exact and the heuristic ε of every step (plots of the paper's Fig. 8)."),
    crate::settings::choice_docs(
        other("exact_search", "Planner", "Exact search", FieldKind::Choice, &["compare", "print", "off"], "On small designs, search every order for the least largest ε (exact cost)."),
        &["Prove the planner's sequence optimal or show the gap; print the planner's.", "Print the search's sequence when it beats the planner's.", "Do not search."],
    ),
    crate::settings::int("exact_beams", "Planner", "Exact search up to", 1.0, optimal::MAX_BEAMS as f64, "Designs with at most this many beams are searched exactly (the work grows exponentially with it)."),
    crate::settings::int("exact_states", "Planner", "Exact search states", 1.0, 10_000_000.0, "States the exact search explores before it gives up (about 50 µs and 20 bytes each)."),
    crate::settings::int("band_beams", "Planner", "Plan in bands of", 0.0, MAX_BEAMS as f64, "0 plans the design whole; more cuts a big design into bands of about this many beams up its height, each planned with the bands below rigid (the costs card measures what the joins cost)."),
    crate::settings::int("send_ahead_beams", "Planner", "Send ahead after", 0.0, MAX_BEAMS as f64, "Once the plan has fixed this many beams, their G-code is sent out while planning goes on, so a printer could start (0: never; not when planned in bands or searched exactly)."),
];

const PRINT_FIELDS: &[Row0] = &[
    num("speed_mm_s", "Printing", "Beam speed", "mm/s", 0.01, 200.0, 0.1, "Speed of the nozzle along a beam while extruding (the paper's 0.4 mm/s)."),
    num("dwell_s", "Printing", "Dwell at joints", "s", 0.0, 60.0, 0.1, "Time the nozzle waits at a beam's end joint so it fuses."),
    num("clearance_mm", "Printing", "Deadhead clearance", "mm", 0.0, 100.0, 0.5, "How far above the highest printed beam the nozzle moves between beams."),
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

    fn fields() -> Vec<Row> {
        let mut rows = mount(
            "job",
            &[crate::settings::Field {
                default: Some(r#"{"kind":"tower","cells":2,"levels":4,"cell_mm":3,"level_mm":3,"taper":0.7}"#),
                ..other("model", "Model", "Built-in design", FieldKind::Section, &[], "Use a wireframe made by weft instead of a loaded file.")
            }],
        );
        rows.extend(mount("job.model", models::FIELDS));
        rows.extend(mount("job.design", DESIGN_FIELDS));
        rows.extend(mount("job.constraints", CONSTRAINT_FIELDS));
        rows.extend(mount("job.nozzle", NOZZLE_FIELDS));
        rows.extend(mount("job.beam", BEAM_FIELDS));
        rows.extend(mount("job.planner", PLANNER_FIELDS));
        rows.extend(mount("job.print", PRINT_FIELDS));
        rows
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

    fn slot_filled(slot: &str, mut j: FreeformJob) -> FreeformJob {
        if slot == "frame" {
            j.model = None;
        }
        j
    }

    fn estimate(j: &FreeformJob, ctx: &mut Ctx) -> Result<Vec<Estimate>, Error> {
        let w = import_stage(j, ctx)?;
        let m = w.beams.len() as f64;
        let import = Estimate::new("import").quantity("beams", "Beams", m, "").cost(m * 200.0, m * 1e-6);
        // Measured on weft's towers and the conmech truss (native, 2026): constraints about
        // 0.1 ms a beam, the exact plan and the cost replay about 0.4 ms a beam (compliance
        // updates over the joints still open), the heuristic plan about 0.05 ms. A nozzle
        // that may tilt tests every axis it may take (17 with the default rings): the
        // cantilever truss with tilt took 3.7 s where 0.22 s was stated before this counted.
        let axes = precedence::tilt_axes(j.nozzle.tilt_deg.clamp(0.0, precedence::MAX_TILT_DEG)).len() as f64;
        let constraints = Estimate::new("constraints")
            .quantity("beams", "Beams", m, "")
            .quantity("axes", "Nozzle axes tried", axes, "")
            .cost(m * 400.0, m * 1e-4 * axes)
            .parallel(0.85)
            .budgets("lower the nozzle's radius or height, or its tilt");
        let exact = j.planner.cost == Cost::Exact;
        let plan_s = if exact { (m * 4e-4).min(j.planner.budget_s) } else { m * 5e-5 };
        let plan = Estimate::new("plan")
            .quantity("beams", "Beams", m, "")
            .cost(m * 2000.0, plan_s)
            .budgets("plan with the heuristic cost, or lower the planning budget");
        let searched = exact_runs(j, m as usize);
        let states = if searched { j.planner.exact_states as f64 } else { 0.0 };
        // Measured: about 40 µs a state on a 30-beam dome (the frame's update grows as the
        // square of its joints). The time stated is a typical search's (about 2^(beams/2)
        // states: the dome searched 10 457), the memory the limit's; the worst case at the
        // largest limit, 10⁷ states, is under 10 minutes.
        let per_state = 4e-5 * (m / 30.0).powi(2).max(0.05);
        let typical = states.min(2f64.powf(m / 2.0));
        // Memory: the remembered states, and the frame's compliance on every level of the
        // search's path (its capacity doubles from 16 joints).
        let cap = if searched { (m + 1.0).max(16.0).log2().ceil().exp2() } else { 0.0 };
        let path_bytes = if searched { m * (6.0 * cap).powi(2) * 8.0 } else { 0.0 };
        let optimum = Estimate::new("optimum")
            .quantity("states", "States at most", states, "")
            .cost(states * 24.0 + path_bytes, typical * per_state)
            .budgets("lower the exact search's states, or switch it off");
        let order = Estimate::new("order").quantity("beams", "Beams", m, "").cost(m * 200.0, m * 2e-5);
        let costs = Estimate::new("costs")
            .quantity("beams", "Beams", if j.planner.compare { m } else { 0.0 }, "")
            .quantity("segments", "Segments", 4.0 * m, "")
            // The replay is bounded by the planning budget; in bands the plan's order is replayed too.
            .cost(
                m * 300.0,
                if j.planner.compare {
                    (m * 4e-4).min(j.planner.budget_s) * if j.planner.band_beams > 0 && (j.planner.band_beams as f64) < m { 2.0 } else { 1.0 }
                } else {
                    0.0
                },
            )
            .budgets("switch off the comparison of the costs");
        Ok(vec![import, constraints, plan, optimum, order, costs])
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
        match view {
            "sequence" => {
                let w = import_stage(j, ctx)?;
                let c = constraints_stage(j, ctx, &w)?;
                let p = chosen_plan(j, ctx, &w, &c)?;
                let o = order_stage(j, ctx, &w, &c, &p)?;
                Ok(sequence_view(&w, &o, &c, index))
            }
            _ => Err(Error::UnknownView { view: view.into(), job: Self::NAME }),
        }
    }
}

/// The wireframe read (or built) and placed: its lowest joint on the plate, XY centred.
pub struct Placed {
    /// The design, placed.
    pub wire: Wireframe,
    /// Its name (the file's, or the model's).
    pub name: String,
}

impl std::ops::Deref for Placed {
    type Target = Wireframe;
    fn deref(&self) -> &Wireframe {
        &self.wire
    }
}

fn import_stage(j: &FreeformJob, ctx: &mut Ctx) -> Result<Out<Placed>, Error> {
    let options =
        wireframe::Options { ground: j.design.ground, ground_tolerance_mm: j.design.ground_tolerance_mm, merge_tolerance_mm: j.design.merge_tolerance_mm };
    let parts = (&j.model, j.design);
    let (bytes, name, keys) = match (&j.model, &j.input) {
        (Some(_), _) => (None, "model".to_string(), Vec::new()),
        (None, Some(input)) => {
            let (bytes, key) = ctx.file_bytes("frame", input)?;
            let name = match input {
                Input::File { name, .. } => name.clone(),
                _ => "wireframe".into(),
            };
            (Some(bytes), name, vec![key])
        }
        (None, None) => return Err(Error::NoInput("a freeform job needs a wireframe: load one (--input frame=FILE), or switch on a built-in design".into())),
    };
    let design = ctx.design;
    ctx.stage_kept("import", "import", &(parts, &name), &keys, |_| {
        let mut wire = match (&j.model, bytes) {
            (Some(m), _) => {
                if let Some(p) = models::problems(m).into_iter().next() {
                    return Err(Error::NoInput(format!("the built-in design: {p}")));
                }
                models::build(m)
            }
            (None, Some(b)) => wireframe::read(&name, &b, &options).map_err(|e| Error::stage("reading the wireframe", e))?,
            _ => unreachable!("a model or a file"),
        };
        if j.design.up != Up::Z {
            for p in &mut wire.joints {
                *p = j.design.up.turn(*p);
            }
            if !wire.grounded_by_file {
                // The lowest joints after turning.
                let low = wire.joints.iter().map(|p| p.z).fold(f64::INFINITY, f64::min);
                wire.grounded = wire.joints.iter().map(|p| p.z <= low + j.design.ground_tolerance_mm).collect();
            }
        }
        place(&mut wire);
        wire.grounding = Some(wireframe::grounding(&wire, j.design.ground_tolerance_mm));
        let size = bounds(&wire.joints).map(|(lo, hi)| hi - lo).unwrap_or_default();
        crate::gcode::check_fits([size.x, size.y, size.z], &design.printer).map_err(|e| Error::stage("the wireframe", e))?;
        let lengths: Vec<f64> = (0..wire.beams.len()).map(|b| wire.length(b)).collect();
        let total: f64 = lengths.iter().sum();
        let shortest = lengths.iter().copied().fold(f64::INFINITY, f64::min);
        let longest = lengths.iter().copied().fold(0.0, f64::max);
        let grounded = wire.grounded.iter().filter(|&&g| g).count();
        let mut report = StageReport::new(
            "import",
            "Reading the wireframe",
            &serde_json::json!({ "joints": wire.joints.len(), "beams": wire.beams.len(), "grounded": grounded, "format": wire.format, "grounding": wire.grounding }),
        )
        .metric("joints", "Joints", wire.joints.len() as f64, "", "Points where beams meet.")
        .metric("beams", "Beams", wire.beams.len() as f64, "", "Straight beams, each printed once.")
        .metric(
            "grounded",
            "Grounded joints",
            grounded as f64,
            "",
            if wire.grounded_by_file {
                "Joints on the substrate, as the design marks them."
            } else {
                "Joints on the substrate: the lowest ones (the design marks none)."
            },
        )
        .metric("length", "Beam length", total, "mm", "Total length of all beams.")
        .metric("shortest", "Shortest beam", if shortest.is_finite() { shortest } else { 0.0 }, "mm", "The shortest beam.")
        .metric("longest", "Longest beam", longest, "mm", "The longest beam.")
        .metric("height", "Height", size.z, "mm", "Height of the design on the plate.");
        // Assumptions said out loud: how the file was read, what stands on the plate.
        report.notes.extend(wire.notes.iter().cloned());
        // The grounding is an assumption only when it is not the file's own marks.
        if let Some(g) = wire.grounding.as_ref().filter(|g| !g.by_file) {
            report.notes.push(format!("{}: {}", name, g.statement()));
            report.notes.extend(g.warning().map(|w| format!("{name}: {w}")));
        }
        Ok((Placed { wire, name: name.clone() }, Some(report)))
    })
}

fn bounds(p: &[DVec3]) -> Option<(DVec3, DVec3)> {
    let first = *p.first()?;
    Some(p.iter().fold((first, first), |(lo, hi), q| (lo.min(*q), hi.max(*q))))
}

/// Moves the design so its lowest joint is on the plate and its XY box is centred on 0.
fn place(w: &mut Wireframe) {
    if let Some((lo, hi)) = bounds(&w.joints) {
        let shift = DVec3::new(-(lo.x + hi.x) / 2.0, -(lo.y + hi.y) / 2.0, -lo.z);
        for p in &mut w.joints {
            *p += shift;
        }
    }
}

fn precedence_options(j: &FreeformJob) -> precedence::Options {
    precedence::Options {
        nozzle: Nozzle { half_angle_deg: j.nozzle.half_angle_deg, radius_mm: j.nozzle.radius_mm, height_mm: j.nozzle.height_mm },
        beam_radius_mm: j.beam.diameter_mm / 2.0,
        directionality: j.constraints.directionality,
        collision: j.constraints.collision,
        tilt_deg: j.nozzle.tilt_deg,
    }
}

fn constraints_stage(j: &FreeformJob, ctx: &mut Ctx, w: &Out<Placed>) -> Result<Out<Constraints>, Error> {
    let o = precedence_options(j);
    let parts = (j.nozzle, j.beam.diameter_mm, j.constraints.directionality, j.constraints.collision);
    ctx.stage("constraints", "constraints", &parts, &[w.key], |progress| {
        let started = crate::clock::now_s();
        let c = precedence::constraints(&w.joints, &w.beams, &o, progress).map_err(|e| Error::stage("constraints", e))?;
        let ms = (crate::clock::now_s() - started) * 1000.0;
        let one_way = c.forward.iter().zip(&c.backward).filter(|(f, b)| !(**f && **b)).count();
        let report =
            StageReport::new("constraints", "Directions and collisions", &serde_json::json!({ "pairs": c.pairs(), "one_way": one_way, "tested": c.tested }))
                .metric(
                    "pairs",
                    "Collision precedences",
                    c.pairs() as f64,
                    "",
                    "Pairs (A, B) where the nozzle printing A would sweep through B: A is printed first.",
                )
                .metric("one_way", "Upward only", one_way as f64, "", "Beams steeper than the nozzle's cone: printed from their lower joint.")
                .metric(
                    "tested",
                    "Pairs tested exactly",
                    c.tested as f64,
                    "",
                    "Pairs near enough (by the BVH and the 2D distance) for the exact cone/cylinder test (each axis tried counts).",
                )
                .metric("time", "Time", ms, "ms", "Wall time of this stage on this machine.");
        let report = if o.tilt_deg > 0.0 {
            report
                .metric(
                    "tilted",
                    "Beams tilted",
                    c.tilted as f64,
                    "",
                    "Beams printed with the nozzle tilted: a tilt let them go either way or hit fewer beams.",
                )
                .metric(
                    "vertical_pairs",
                    "Precedences if vertical",
                    c.vertical_pairs as f64,
                    "",
                    "Collision precedences a vertical nozzle would have had (beside the ones left with tilting).",
                )
        } else {
            report
        };
        Ok((c, Some(report)))
    })
}

fn plan_options(j: &FreeformJob) -> plan::Options {
    plan::Options {
        mode: j.constraints.cantilever,
        cost: j.planner.cost,
        connection: j.constraints.connection,
        section: section(j),
        load_n: j.beam.load_n,
        budget_s: j.planner.budget_s,
    }
}

fn section(j: &FreeformJob) -> Section {
    Section { diameter_mm: j.beam.diameter_mm, e_mpa: j.beam.e_mpa, g_mpa: j.beam.g_mpa }
}

/// A design that cannot be printed, in words (beams and joints named as the file names them).
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
struct CannotPrint(String);

fn names(w: &Wireframe, beams: &[usize]) -> String {
    beams.iter().map(|&b| w.beam_names.get(b).cloned().unwrap_or_else(|| format!("beam {b}"))).collect::<Vec<_>>().join(", ")
}

/// The reason a design cannot be printed, in words, with the grounding it holds for (a
/// refusal is only as true as the footing it assumed).
pub fn explain(w: &Wireframe, u: &Unconstructable, mode: Mode) -> String {
    let why = explain_only(w, u, mode);
    match &w.grounding {
        Some(g) => match g.warning() {
            Some(warn) => format!("{why} (with {}; {warn})", g.statement()),
            None => format!("{why} (with {})", g.statement()),
        },
        None => why,
    }
}

fn explain_only(w: &Wireframe, u: &Unconstructable, mode: Mode) -> String {
    let joint = |j: usize| w.joint_names.get(j).cloned().unwrap_or_else(|| format!("joint {j}"));
    match u {
        Unconstructable::Cycle { beams } => format!(
            "cannot be printed in this orientation: {} must each be printed before the next (the nozzle printing one sweeps through the next), and the last before the first; tilt or re-orient the design, or narrow the nozzle",
            names(w, beams)
        ),
        Unconstructable::TwoCantilevers { joint: jt, beams } => format!(
            "cannot be printed with one cantilever per joint: the finished design hangs two cantilevers ({}) on {}; relax the cantilever constraint, or join them to the rest",
            names(w, beams),
            joint(*jt)
        ),
        Unconstructable::HangsDown { beam, joint: jt } => format!(
            "cannot be printed: {} hangs down from {} steeper than the nozzle's cone, so it can only be printed upward from its free end, which touches nothing; support it, or re-orient the design",
            names(w, &[*beam]),
            joint(*jt)
        ),
        Unconstructable::Unreachable { beams, count } => format!(
            "cannot be printed: {count} beam(s) can never start from a printed joint in an allowed direction, or wait on such beams ({}{}); check the grounded joints and the nozzle",
            names(w, beams),
            if *count > beams.len() { ", …" } else { "" }
        ),
        Unconstructable::NoSubassembly { printed, beams, count } => format!(
            "the planner found no consistent subassembly after {printed} beams{}: {count} beam(s) left ({}{}); deciding this is NP-complete under the cantilever constraint and the search here joins at most two paths: relax the cantilever constraint, or add a beam that closes these loops",
            if mode == Mode::Strict { " with one cantilever per joint" } else { "" },
            names(w, beams),
            if *count > beams.len() { ", …" } else { "" }
        ),
        Unconstructable::SearchTooLarge { printed, beams, count } => format!(
            "the search for the next subassembly after {printed} beams needed more than {} steps: {count} beam(s) left ({}{}); relax the cantilever constraint or plan with the heuristic cost",
            plan::MAX_ROUND_EXPANSIONS,
            names(w, beams),
            if *count > beams.len() { ", …" } else { "" }
        ),
    }
}

/// Whether the exact search runs on a design of `beams` beams.
fn exact_runs(j: &FreeformJob, beams: usize) -> bool {
    j.planner.exact_search != ExactSearch::Off && j.constraints.connection && beams <= j.planner.exact_beams.min(optimal::MAX_BEAMS)
}

/// The plan printed: the planner's, or the exact search's (see [`ExactSearch`]).
fn chosen_plan(j: &FreeformJob, ctx: &mut Ctx, w: &Out<Placed>, c: &Out<Constraints>) -> Result<Out<Plan>, Error> {
    let p = plan_stage(j, ctx, w, c)?;
    optimum_stage(j, ctx, w, c, &p)
}

/// The planner's plan, or (on a design the exact search takes) why it found none.
type Planned = Result<Plan, Unconstructable>;

fn plan_stage(j: &FreeformJob, ctx: &mut Ctx, w: &Out<Placed>, c: &Out<Constraints>) -> Result<Out<Planned>, Error> {
    let o = plan_options(j);
    let searched = exact_runs(j, w.beams.len());
    let parts = (j.constraints, j.planner.cost, j.planner.budget_s, j.beam, searched, j.planner.band_beams);
    // A plan made whole only adds to its beginning, so that can be sent ahead; a band may be
    // planned again with the one above it (below: no sending), and the exact search may print
    // another order.
    let send_at = if searched { 0 } else { j.planner.send_ahead_beams };
    let dead = deadhead_options(j, ctx.design);
    let sender = ctx.sender();
    let parts = (parts, send_at);
    // The beams fixed, ordered as the order stage orders them alone (it keeps them first).
    let m = w.beams.len();
    let send = |fixed: &Plan| {
        let ordered = deadhead::order(&w.joints, fixed, c, &dead);
        let label = format!("the first {} of {} beams", fixed.steps.len(), m);
        sender.send("plan", &label, fixed.steps.len(), m, &toolpath(j, w, &ordered, c));
    };
    let sent = std::cell::Cell::new(false);
    let out = ctx.stage("plan", "plan", &parts, &[w.key, c.key], |progress| {
        let a = Assembly { joints: &w.joints, beams: &w.beams, grounded: &w.grounded, constraints: c };
        let started = crate::clock::now_s();
        // A forward planner fixes the sequence's beginning first: printing could start when the
        // first subassembly is fixed. When that and half the beams were fixed.
        let (mut first_ms, mut half_ms, mut sent_ms) = (None, None, None);
        let mut tick = |done: usize, all: usize| {
            if done > 0 && first_ms.is_none() {
                first_ms = Some((crate::clock::now_s() - started) * 1000.0);
            }
            if 2 * done >= all && all > 0 && half_ms.is_none() {
                half_ms = Some((crate::clock::now_s() - started) * 1000.0);
            }
            progress(done as f32 / all.max(1) as f32)
        };
        let mut ahead = |fixed: &Plan| {
            send(fixed);
            sent.set(true);
            sent_ms = Some((crate::clock::now_s() - started) * 1000.0);
        };
        let band_of = bands::assign(&w.joints, &w.beams, c, j.planner.band_beams);
        let planned = if band_of.iter().all(|&k| k == 0) {
            plan::plan_sending(&a, &o, send_at, &mut tick, &mut ahead)
        } else {
            bands::plan(&a, &o, &band_of, &mut tick).map(|(p, _)| p)
        };
        let p = match planned {
            Ok(p) => p,
            // The planner's refusals that are proofs stand; its search's limits the exact
            // search may overcome on a small design.
            Err(u @ (Unconstructable::NoSubassembly { .. } | Unconstructable::SearchTooLarge { .. })) if searched => {
                let report = StageReport::new("plan", "Planning the sequence: no sequence found", &serde_json::json!({ "refused": &u }));
                return Ok((Err(u), Some(report)));
            }
            Err(u) => return Err(Error::stage("planning", CannotPrint(explain(w, &u, o.mode)))),
        };
        let ms = (crate::clock::now_s() - started) * 1000.0;
        let eps: Vec<f64> = p.steps.iter().map(|s| s.cost_mm * 1000.0).collect();
        let max = eps.iter().copied().fold(0.0, f64::max);
        let mean = eps.iter().sum::<f64>() / eps.len().max(1) as f64;
        let multi = p.blocks.iter().filter(|b| b.end - b.start > 1).count();
        let mut report = StageReport::new(
            "plan",
            "Planning the sequence",
            &serde_json::json!({ "steps": p.steps.len(), "blocks": p.blocks.len(), "max_um": max, "expansions": p.expansions, "exact_until": p.exact_until }),
        )
        .metric(
            "max_eps",
            "Largest ε",
            max,
            "µm",
            "The largest error of a joint while printing: the deflection of the beam's free end under the nozzle's load (what the plan minimises).",
        )
        .metric("mean_eps", "Mean ε", mean, "µm", "The mean over all beams (0 for beams that close onto a printed joint).")
        .metric(
            "blocks",
            "Subassemblies",
            p.blocks.len() as f64,
            "",
            "Consistent subassemblies added one after another (paths between stable joints, single closing beams, hanging ends).",
        )
        .metric("paths", "Joined paths", multi as f64, "", "Subassemblies of several beams: cantilevers grown from stable joints until they meet.")
        .metric("expansions", "Search steps", p.expansions as f64, "", "Tree states expanded by the best-first search.")
        .metric("work", "Counted work", p.work / plan::WORK_PER_SECOND, "s", "Work counted against the planning budget (the same on every machine).")
        .metric("time", "Planning time", ms, "ms", "Wall time of the plan on this machine.")
        .metric(
            "first_ms",
            "First beams fixed",
            first_ms.unwrap_or(ms),
            "ms",
            "When the plan's first subassembly was fixed: a printer could start then, while planning goes on (the plan only adds after it).",
        )
        .metric("half_ms", "Half the beams fixed", half_ms.unwrap_or(ms), "ms", "When half of the sequence was fixed.");
        if let Some(t) = sent_ms {
            report = report
                .metric(
                    "sent",
                    "Beams sent ahead",
                    p.sent as f64,
                    "",
                    "Beams whose G-code was sent out while planning went on; the final G-code's moves begin with theirs.",
                )
                .metric("sent_ms", "Sent ahead at", t, "ms", "When they were sent, counted from the plan's start.");
        }
        if !p.bands.is_empty() {
            report = report.metric(
                "bands",
                "Bands",
                p.bands.len() as f64,
                "",
                "Bands planned one after another up the design, each with the bands below printed and rigid.",
            );
        }
        if let Some(k) = p.exact_until {
            report = report.metric(
                "exact_until",
                "Exact cost until step",
                k as f64,
                "",
                "The planning budget ran out here: later steps were chosen by the heuristic cost.",
            );
        }
        if j.planner.cost == Cost::Exact {
            report = report.metric(
                "peak_live",
                "Joints tracked",
                p.peak_live as f64,
                "",
                "Most joints whose compliance the exact cost kept at once (its memory grows as the square).",
            );
            if p.refreshes > 0 {
                report = report
                    .metric(
                        "refreshes",
                        "Sparse checks",
                        p.refreshes as f64,
                        "",
                        "Times the running compliance was checked against a sparse Cholesky factorisation of the printed frame (faer).",
                    )
                    .metric(
                        "drift",
                        "Largest difference",
                        p.drift,
                        "",
                        "The largest difference a check found, relative to the largest compliance: the rounding the running updates have gathered.",
                    );
            }
        }
        Ok((Ok(p), Some(report)))
    })?;
    // A plan made before (the cache: an earlier run, or a view asked for first) is ready at
    // once: its beginning is still sent, so every run delivers it.
    if let (false, Ok(p)) = (sent.get(), &*out) {
        if p.sent > 0 {
            send(&p.prefix(p.sent));
        }
    }
    Ok(out)
}

/// ε (exact, mm) of each step of `steps`, replayed.
fn exact_eps(w: &Wireframe, steps: &[plan::Step], s: &Section, load: f64) -> Vec<f64> {
    cost::costs(&w.joints, &w.beams, &w.grounded, steps, s, load).iter().map(|k| k.exact_mm).collect()
}

/// The exact search over every order ([`optimal`]) on small designs: proves the planner's
/// largest ε optimal or shows the gap, and prints the better sequence when asked (or when the
/// planner found none).
fn optimum_stage(j: &FreeformJob, ctx: &mut Ctx, w: &Out<Placed>, c: &Out<Constraints>, p: &Out<Planned>) -> Result<Out<Plan>, Error> {
    let searched = exact_runs(j, w.beams.len());
    let parts = (j.planner.exact_search, j.planner.exact_beams, j.planner.exact_states, searched);
    let mode = j.constraints.cantilever;
    ctx.stage("optimum", "optimum", &parts, &[w.key, c.key, p.key], |progress| {
        let planned: &Planned = p;
        if !searched {
            // Say why when it was asked for.
            let why = if !j.constraints.connection {
                "it needs the connection constraint".to_string()
            } else {
                format!("{} beams, more than {}", w.beams.len(), j.planner.exact_beams.min(optimal::MAX_BEAMS))
            };
            let note = (j.planner.exact_search != ExactSearch::Off)
                .then(|| StageReport::new("optimum", &format!("Exact search: not run ({why})"), &serde_json::json!({ "skipped": why })));
            return match planned {
                Ok(plan) => Ok((plan.clone(), note)),
                Err(u) => Err(Error::stage("planning", CannotPrint(explain(w, u, mode)))),
            };
        }
        let s = section(j);
        let load = j.beam.load_n;
        let planner_eps = planned.as_ref().ok().map(|plan| exact_eps(w, &plan.steps, &s, load));
        let known = planner_eps.as_ref().map(|e| e.iter().copied().fold(0.0, f64::max));
        let a = Assembly { joints: &w.joints, beams: &w.beams, grounded: &w.grounded, constraints: c };
        let o = optimal::Options { mode, section: s, load_n: load, max_states: j.planner.exact_states, known_mm: known };
        let started = crate::clock::now_s();
        let best = optimal::optimum(&a, &o, &mut |done, all| progress(done as f32 / all.max(1) as f32)).map_err(|e| Error::stage("the exact search", e))?;
        let ms = (crate::clock::now_s() - started) * 1000.0;
        let searched_plan = best.steps.as_ref().map(|steps| sequential_plan(steps.clone(), best.states));
        let printed = match (planned, &searched_plan) {
            (Err(_), Some(sp)) => sp.clone(),
            (Ok(_), Some(sp)) if j.planner.exact_search == ExactSearch::Print => sp.clone(),
            (Ok(plan), _) => plan.clone(),
            (Err(u), None) => {
                let why = explain(w, u, mode);
                let msg = if best.proven {
                    format!(
                        "cannot be printed: the exact search tried every order ({} states) and none meets the constraints{}; the planner said: {why}",
                        best.states,
                        if mode == Mode::Strict { " with one cantilever per joint" } else { "" }
                    )
                } else {
                    format!("{why} (the exact search gave up after {} states: raise its states to decide)", best.states)
                };
                return Err(Error::stage("planning", CannotPrint(msg)));
            }
        };
        Ok((printed, Some(optimum_report(&best, known, planner_eps.as_deref(), ms, j.planner.exact_search))))
    })
}

/// A found sequence as a plan: one step a block, each after the one before (the search's order
/// is what meets the cantilever rule, so the deadhead order keeps it).
fn sequential_plan(steps: Vec<plan::Step>, states: usize) -> Plan {
    let blocks = (0..steps.len())
        .map(|i| plan::Block { start: i, end: i + 1, after: if i == 0 { Vec::new() } else { vec![i - 1] }, chain: vec![usize::MAX], key_mm: steps[i].cost_mm })
        .collect();
    Plan { steps, blocks, expansions: states as u64, ..Plan::default() }
}

fn optimum_report(best: &Optimum, known: Option<f64>, planner_eps: Option<&[f64]>, ms: f64, use_: ExactSearch) -> StageReport {
    let um = |x: f64| x * 1000.0;
    let label = match (best.proven, best.best_mm, &best.steps, known) {
        (true, None, _, _) => "Exact search: no order meets the constraints".to_string(),
        (true, Some(_), None, Some(_)) => "Exact search: the planner's sequence is optimal".to_string(),
        (true, Some(_), Some(_), Some(_)) => format!("Exact search: a better sequence{}", if use_ == ExactSearch::Print { " (printed)" } else { "" }),
        (true, Some(_), _, None) => "Exact search: the optimal sequence (the planner found none)".to_string(),
        (false, _, _, _) => format!("Exact search: gave up after {} states", best.states),
    };
    let mut r = StageReport::new(
        "optimum",
        &label,
        &serde_json::json!({ "proven": best.proven, "best_um": best.best_mm.map(um), "planner_um": known.map(um), "states": best.states, "improvements": best.improvements }),
    );
    if let Some(b) = best.best_mm {
        r = r.metric(
            "best",
            if best.proven { "Least largest ε (proven)" } else { "Least largest ε found" },
            um(b),
            "µm",
            "The smallest largest joint error over every order the constraints allow (exact cost).",
        );
    }
    if let Some(k) = known {
        r = r.metric("planner", "Planner's largest ε (exact)", um(k), "µm", "The planner's sequence measured with the exact cost.");
        if let Some(b) = best.best_mm.filter(|&b| b > 0.0) {
            r = r.metric(
                "gap",
                "Planner's gap",
                (k / b - 1.0) * 100.0,
                "%",
                "How far the planner's largest ε is above the least found (0: the planner's is optimal when proven).",
            );
        }
    }
    r = r
        .metric(
            "states",
            "States searched",
            best.states as f64,
            "",
            "Sets of printed beams the search explored (each a state whatever the order that led to it).",
        )
        .metric(
            "improvements",
            "Better orders found",
            best.improvements as f64,
            "",
            "Sequences the search found one after another, each with a smaller largest ε than the last.",
        )
        .metric("time", "Search time", ms, "ms", "Wall time of the search on this machine.");
    if let (Some(steps), Some(pe)) = (&best.steps, planner_eps) {
        let x: Vec<f64> = (1..=pe.len()).map(|i| i as f64).collect();
        let se: Vec<f64> = steps.iter().map(|s| um(s.cost_mm)).collect();
        r.plots.push(Plot {
            key: "optimum_sequence".into(),
            title: "ε of each step: planner and exact search".into(),
            kind: PlotKind::Line,
            x: Axis::new("step", ""),
            y: Axis::new("ε", "µm"),
            group: None,
            series: vec![Series::xy("planner", x.clone(), pe.iter().map(|&e| um(e)).collect()), Series::xy("exact search", x, se)],
        });
    }
    r
}

fn order_stage(j: &FreeformJob, ctx: &mut Ctx, w: &Out<Placed>, c: &Out<Constraints>, p: &Out<Plan>) -> Result<Out<Ordered>, Error> {
    let o = deadhead_options(j, ctx.design);
    let parts = (o.xy_mm_s, o.z_mm_s, o.clearance_mm, o.beam_radius_mm, j.nozzle);
    let speed = j.print.speed_mm_s;
    let dwell = j.print.dwell_s;
    let nozzle = precedence_options(j).nozzle;
    ctx.stage("order", "order", &parts, &[p.key, c.key], |_| {
        let ordered = deadhead::order(&w.joints, p, c, &o);
        let length: f64 = ordered.steps.iter().map(|s| w.joints[s.from].distance(w.joints[s.to])).sum();
        let print_s = length / speed + dwell * ordered.steps.len() as f64;
        let mut report = StageReport::new("order", "Ordering deadheads", &serde_json::json!({ "deadhead_s": ordered.deadhead_s, "plan_order_deadhead_s": ordered.plan_order_deadhead_s, "sequence": ordered.steps.iter().map(|s| [s.beam, s.from, s.to]).collect::<Vec<_>>() }))
            .metric("deadhead", "Deadhead time", ordered.deadhead_s, "s", "Moves between beams: lift above the highest printed beam, move, lower (axes at full speed).")
            .metric("deadhead_plan", "Deadhead in the plan's order", ordered.plan_order_deadhead_s, "s", "The same moves in the order the planner fixed them, before ordering.")
            .metric("print", "Printing time", print_s, "s", "Extruding along every beam at the beam speed, plus the dwells.");
        // Lifts and descents through printed beams higher than the nozzle body reaches.
        let (blocked, tilted) = deadhead::blocked(&w.joints, &w.beams, &c.axis, &ordered, nozzle.radius_mm, nozzle.top(), o.beam_radius_mm);
        report = report.metric("blocked", "Deadheads through printed beams", blocked.len() as f64, "", "Lifts or descents whose nozzle column above the joint meets a printed beam higher than the nozzle body: make the body's height the whole head's, so those beams become precedences.");
        if tilted > 0 {
            report = report.metric("unchecked", "Deadheads not checked (tilted)", tilted as f64, "", "Deadheads next to a beam printed with the nozzle tilted: the check above is for an upright nozzle.");
        }
        if !blocked.is_empty() {
            report.label = format!("Ordering deadheads: {} pass through printed beams (first at step {})", blocked.len(), blocked[0] + 1);
            report.data["blocked_steps"] = serde_json::json!(blocked.iter().take(50).collect::<Vec<_>>());
        }
        report.tables.push(sequence_table(w, &ordered));
        Ok((ordered, Some(report)))
    })
}

fn deadhead_options(j: &FreeformJob, design: &crate::design::Design) -> deadhead::Options {
    let printer = &design.printer;
    deadhead::Options {
        xy_mm_s: printer.travel_speed_mm_s,
        z_mm_s: printer.z_speed_mm_s,
        clearance_mm: j.print.clearance_mm,
        beam_radius_mm: j.beam.diameter_mm / 2.0,
    }
}

fn costs_stage(j: &FreeformJob, ctx: &mut Ctx, w: &Out<Placed>, p: &Out<Plan>, o: &Out<Ordered>) -> Result<Out<Vec<Costs>>, Error> {
    let parts = (j.planner.compare, j.beam, j.planner.budget_s);
    let s = section(j);
    let load = j.beam.load_n;
    let compare = j.planner.compare;
    let chosen = j.planner.cost;
    let budget = j.planner.budget_s * plan::WORK_PER_SECOND;
    ctx.stage("costs", "costs", &parts, &[o.key, p.key], |_| {
        if !compare {
            return Ok((Vec::new(), Some(planned_report(o))));
        }
        let (c, stopped) = cost::costs_within(&w.joints, &w.beams, &w.grounded, &o.steps, &s, load, budget);
        let mut report = costs_report(&c, load, chosen, stopped);
        if !p.bands.is_empty() {
            // The plan's own order, measured with the whole frame, against what each band saw.
            let (whole, _) = cost::costs_within(&w.joints, &w.beams, &w.grounded, &p.steps, &s, load, budget);
            report = joins_report(report, p, &whole);
        }
        Ok((c.clone(), Some(report)))
    })
}

/// The cost of planning in bands: in each band, in the plan's order, the largest ε its plan
/// saw (the bands below rigid) against the largest measured with the whole frame (`whole`,
/// NaN past the budget), and the largest growth of one step's ε.
fn joins_report(r: StageReport, p: &Plan, whole: &[Costs]) -> StageReport {
    let n = p.steps.len();
    let (mut planned, mut measured) = (Vec::new(), Vec::new());
    for (k, &start) in p.bands.iter().enumerate() {
        let end = p.bands.get(k + 1).copied().unwrap_or(n);
        let range = start.min(n)..end.min(n);
        planned.push(p.steps[range.clone()].iter().map(|s| s.cost_mm * 1000.0).fold(0.0, f64::max));
        measured.push(whole[range].iter().map(|k| k.exact_mm * 1000.0).filter(|e| e.is_finite()).fold(0.0, f64::max));
    }
    let join = p.steps.iter().zip(whole).map(|(s, k)| (k.exact_mm - s.cost_mm) * 1000.0).filter(|e| e.is_finite()).fold(0.0, f64::max);
    let worst_planned = planned.iter().copied().fold(0.0, f64::max);
    let worst = measured.iter().copied().fold(0.0, f64::max);
    let x: Vec<f64> = (1..=planned.len()).map(|i| i as f64).collect();
    let mut r = r
        .metric("band_planned", "Largest ε planned in bands", worst_planned, "µm", "The largest ε the bands' plans saw, each with the bands below rigid.")
        .metric(
            "band_join",
            "Cost of the joins",
            join,
            "µm",
            "The most one step's ε grows when the bands below deflect too (the plan's order measured with the whole frame).",
        )
        .metric("band_measured", "Largest ε measured", worst, "µm", "The largest ε of the joined sequence with the whole frame.");
    r.plots.push(Plot {
        key: "bands".into(),
        title: "Largest ε per band: planned (bands below rigid) and measured (whole frame)".into(),
        kind: PlotKind::Line,
        x: Axis::new("band", ""),
        y: Axis::new("ε", "µm"),
        group: None,
        series: vec![Series::xy("planned", x.clone(), planned), Series::xy("measured", x, measured)],
    });
    r
}

/// ε over the sequence as planned (no comparison asked).
fn planned_report(o: &Ordered) -> StageReport {
    let x: Vec<f64> = (1..=o.steps.len()).map(|i| i as f64).collect();
    let y: Vec<f64> = o.steps.iter().map(|s| s.cost_mm * 1000.0).collect();
    let mut r = StageReport::new("costs", "Joint errors along the sequence", &serde_json::json!({ "compared": false }));
    r.plots.push(Plot {
        key: "eps_sequence".into(),
        title: "ε of each step (as planned)".into(),
        kind: PlotKind::Line,
        x: Axis::new("step", ""),
        y: Axis::new("ε", "µm"),
        group: None,
        series: vec![Series::xy("planned", x, y)],
    });
    r
}

fn costs_report(c: &[Costs], load: f64, chosen: Cost, stopped: Option<usize>) -> StageReport {
    // Past the budget nothing was measured: the measured steps only.
    let c = &c[..stopped.unwrap_or(c.len())];
    let n = c.len();
    let x: Vec<f64> = (1..=n).map(|i| i as f64).collect();
    let exact: Vec<f64> = c.iter().map(|k| k.exact_mm * 1000.0).collect();
    let heur: Vec<f64> = c.iter().map(|k| k.heuristic_mm * 1000.0).collect();
    let max_e = exact.iter().copied().fold(0.0, f64::max);
    let max_h = heur.iter().copied().fold(0.0, f64::max);
    // Steps where the heuristic reads more than the exact cost (the paper's Fig. 8C says never).
    let above = c.iter().filter(|k| k.heuristic_mm > k.exact_mm * (1.0 + 1e-9) + 1e-15).count();
    let data = serde_json::json!({ "compared": true, "max_exact_um": max_e, "max_heuristic_um": max_h, "heuristic_above_exact": above });
    let r = StageReport::new("costs", "Joint errors, exact and heuristic", &data)
        .metric("max_exact", "Largest ε, exact", max_e, "µm", "The largest joint error along this sequence with the whole frame deflecting.")
        .metric("max_heuristic", "Largest ε, heuristic", max_h, "µm", "The same with only the cantilevered beams deflecting (the rest rigid).")
        .metric("ratio", "Heuristic ÷ exact (largest)", if max_e > 0.0 { max_h / max_e } else { 0.0 }, "", "How much of the worst error the heuristic sees.")
        .metric("above", "Steps heuristic > exact", above as f64, "", "Steps where the heuristic reads more than the exact cost (the paper: never).");
    let mut r = match stopped {
        Some(k) => r.metric(
            "measured",
            "Steps measured",
            k as f64,
            "",
            "The planning budget ran out during the measurement: the numbers and plots cover these first steps (raise the budget to measure all).",
        ),
        None => r,
    };
    let chosen_name = match chosen {
        Cost::Exact => "exact (planned with)",
        Cost::Heuristic => "heuristic (planned with)",
    };
    let (e_name, h_name) = if chosen == Cost::Exact { (chosen_name, "heuristic") } else { ("exact", chosen_name) };
    r.plots.push(Plot {
        key: "eps_sequence".into(),
        title: "ε of each step".into(),
        kind: PlotKind::Line,
        x: Axis::new("step", ""),
        y: Axis::new("ε", "µm"),
        group: None,
        series: vec![Series::xy(e_name, x.clone(), exact.clone()), Series::xy(h_name, x, heur.clone())],
    });
    // Fig. 8A: compliances (ε per unit load) of the steps, sorted.
    let mut se: Vec<f64> = c.iter().filter(|k| k.exact_mm > 0.0).map(|k| k.exact_mm / load).collect();
    let mut sh: Vec<f64> = c.iter().filter(|k| k.exact_mm > 0.0).map(|k| k.heuristic_mm / load).collect();
    se.sort_by(f64::total_cmp);
    sh.sort_by(f64::total_cmp);
    let rank: Vec<f64> = (1..=se.len()).map(|i| i as f64).collect();
    r.plots.push(Plot {
        key: "compliance_sorted".into(),
        title: "Compliance of the steps, sorted (Fig. 8A)".into(),
        kind: PlotKind::Line,
        x: Axis::new("rank", ""),
        y: Axis::new("ε ÷ load", "mm/N"),
        group: None,
        series: vec![Series::xy("exact", rank.clone(), se), Series::xy("heuristic", rank, sh)],
    });
    // Fig. 8C: heuristic against exact compliance, one point per step.
    let (xs, ys): (Vec<f64>, Vec<f64>) = c.iter().filter(|k| k.exact_mm > 0.0).map(|k| (k.exact_mm / load, k.heuristic_mm / load)).unzip();
    let top = xs.iter().copied().fold(0.0, f64::max);
    r.plots.push(Plot {
        key: "heuristic_vs_exact".into(),
        title: "Heuristic against exact compliance (Fig. 8C)".into(),
        kind: PlotKind::Scatter,
        x: Axis::new("exact", "mm/N"),
        y: Axis::new("heuristic", "mm/N"),
        group: None,
        series: vec![Series::xy("steps", xs, ys), Series { kind: Some(PlotKind::Line), ..Series::xy("heuristic = exact", vec![0.0, top], vec![0.0, top]) }],
    });
    // The distribution of ε.
    if max_e > 0.0 {
        let bins = 20;
        let edges: Vec<f64> = (0..=bins).map(|i| max_e * i as f64 / bins as f64).collect();
        let mut counts = vec![0.0; bins];
        for &e in &exact {
            let k = ((e / max_e * bins as f64) as usize).min(bins - 1);
            counts[k] += 1.0;
        }
        r.plots.push(Plot {
            key: "eps_histogram".into(),
            title: "Distribution of ε (exact)".into(),
            kind: PlotKind::Histogram,
            x: Axis::new("ε", "µm"),
            y: Axis::new("steps", ""),
            group: None,
            series: vec![Series::xy("steps", edges, counts)],
        });
    }
    r
}

/// The G-code's toolpath: one free pass per beam (3D moves at the beam speed with the
/// extrusion of its section, a dwell at the end joint), reached by a deadhead that lifts above
/// the highest printed beam, moves across and lowers.
fn toolpath(j: &FreeformJob, w: &Placed, o: &Ordered, c: &Constraints) -> Toolpath {
    let d = j.beam.diameter_mm;
    let area = std::f64::consts::PI * d * d / 4.0;
    let mut passes = Vec::with_capacity(o.steps.len());
    let mut last: Option<DVec3> = None;
    for (i, s) in o.steps.iter().enumerate() {
        let (a, b) = (w.joints[s.from], w.joints[s.to]);
        let approach = last.map(|p| {
            let z = o.safe_z[i].max(p.z).max(a.z);
            vec![DVec3::new(p.x, p.y, z), DVec3::new(a.x, a.y, z)]
        });
        // A tilted beam carries its nozzle axis (the writer turns it into rotary words).
        let axis = c.axis.get(s.beam).copied().unwrap_or(DVec3::Z);
        let tool_axis = (axis != DVec3::Z).then(|| vec![axis, axis]);
        let data = PointData {
            flow: Some(PointFlow::AreaMm2(vec![0.0, area])),
            feed_mm_s: Some(vec![0.0, j.print.speed_mm_s]),
            tool_axis,
            dwell_s: Some(vec![0.0, j.print.dwell_s]),
        };
        let path = Path { points: vec![a, b], feature: Feature::Beam, width: d, speed_factor: 1.0, approach, data: Some(Box::new(data)) };
        passes.push(Pass { kind: PassKind::Free, z: a.z.max(b.z), height: d, paths: vec![path] });
        last = Some(b);
    }
    Toolpath { passes }
}

/// The wireframe after step `index`: printed beams, the current one, the cantilevered ones
/// (a printed beam with a joint not yet held by two disjoint paths to the ground), the rest.
fn sequence_view(w: &Placed, o: &Ordered, c: &Constraints, index: usize) -> Inspection {
    let count = o.steps.len();
    let index = index.min(count.saturating_sub(1));
    let mut present = vec![false; w.beams.len()];
    for s in o.steps.iter().take(index + 1) {
        present[s.beam] = true;
    }
    let mut inc: Vec<Vec<usize>> = vec![Vec::new(); w.joints.len()];
    for (b, &[p, q]) in w.beams.iter().enumerate() {
        inc[p].push(b);
        inc[q].push(b);
    }
    let stable = plan::stable_joints(&w.joints, &w.beams, &w.grounded, &inc, &present);
    let current = o.steps.get(index).map(|s| s.beam);
    let mut data = Vec::with_capacity(w.beams.len() * 7);
    let mut cantilevered = 0usize;
    for (b, &[p, q]) in w.beams.iter().enumerate() {
        let f = if Some(b) == current {
            CURRENT
        } else if !present[b] {
            TODO
        } else if !(stable[p] && stable[q]) {
            cantilevered += 1;
            CANTILEVER
        } else {
            PRINTED
        };
        let (a, c) = (w.joints[p], w.joints[q]);
        data.extend_from_slice(&[a.x as f32, a.y as f32, a.z as f32, c.x as f32, c.y as f32, c.z as f32, f.code() as f32]);
    }
    let step = o.steps.get(index);
    let tilt = |b: usize| c.axis.get(b).map_or(0.0, |t| libm::acos(t.z.clamp(-1.0, 1.0)).to_degrees());
    let caption = step
        .map(|s| {
            let t = tilt(s.beam);
            let tilted = if t > 1e-9 { format!(", nozzle tilted {t:.0}°") } else { String::new() };
            format!(
                "{} from {} to {}, ε {:.3} µm{tilted}",
                names(w, &[s.beam]),
                w.joint_names.get(s.from).map_or("", String::as_str),
                w.joint_names.get(s.to).map_or("", String::as_str),
                s.cost_mm * 1000.0
            )
        })
        .unwrap_or_default();
    let meta = serde_json::json!({
        "caption": caption,
        "play": true,
        "cantilevered": cantilevered,
        "legend": {
            PRINTED.code().to_string(): "printed",
            CURRENT.code().to_string(): "printing now",
            CANTILEVER.code().to_string(): "cantilevered",
            TODO.code().to_string(): "still to print",
        },
    });
    Inspection { view: "sequence".into(), shape: Shape::Lines3d, index, count, stride: Shape::Lines3d.stride(), data, overlay: Vec::new(), meta }
}

/// The sequence as a table (first [`TABLE_ROWS`] steps): for `--report` readers and the page.
pub fn sequence_table(w: &Wireframe, o: &Ordered) -> Table {
    let rows = o
        .steps
        .iter()
        .take(TABLE_ROWS)
        .enumerate()
        .map(|(i, s)| TableRow {
            group_index: None,
            cells: vec![
                serde_json::json!(i + 1),
                serde_json::json!(w.beam_names.get(s.beam).cloned().unwrap_or_default()),
                serde_json::json!(w.joint_names.get(s.from).cloned().unwrap_or_default()),
                serde_json::json!(w.joint_names.get(s.to).cloned().unwrap_or_default()),
                serde_json::json!((s.cost_mm * 1e6).round() / 1e3),
            ],
        })
        .collect();
    Table {
        key: "sequence".into(),
        title: format!("Sequence (first {} of {} steps)", o.steps.len().min(TABLE_ROWS), o.steps.len()),
        group: None,
        columns: ["step", "beam", "from", "to", "ε"]
            .iter()
            .zip(["", "", "", "", "µm"])
            .map(|(l, u)| Column { label: l.to_string(), unit: u.to_string() })
            .collect(),
        rows,
    }
}

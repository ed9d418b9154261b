//! The freeform job's settings as the design holds them (design, nozzle, beam, constraints, planner, print), with their defaults.

use super::*;

/// Default beam diameter, mm (the paper's isomalt filaments: 100–200 µm).
pub const DEFAULT_BEAM_DIAMETER_MM: f64 = 0.15;
/// Default print speed along a beam, mm/s (the paper's 400 µm/s).
pub const DEFAULT_SPEED_MM_S: f64 = 0.4;
/// Default dwell at a beam's end joint to fuse it, s.
pub const DEFAULT_DWELL_S: f64 = 0.5;
/// Most beams a design may have (the largest is 50k; the paper's 6,161).
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

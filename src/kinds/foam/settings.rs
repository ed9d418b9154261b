//! The foam job's settings as the design holds them (regions, transitions, the process options), their defaults and what they give the algorithm (`foam::Process`, pairs, transitions).

use super::*;

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

pub(super) fn default_v_star() -> f64 {
    DEFAULT_V_STAR
}

pub(super) fn default_modulus() -> f64 {
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

pub(super) fn default_regions() -> Vec<RegionSpec> {
    vec![RegionSpec::new(0.15, DEFAULT_H_STAR), RegionSpec::new(0.4, DEFAULT_H_STAR)]
}

pub(super) fn default_transitions() -> Vec<TransitionSpec> {
    vec![TransitionSpec { from: 1, to: 2, length_mm: 40.0, weighting: Weighting::Linear }]
}

/// The paper's dogbone with V* 0.15 → 0.4 over a 40 mm linear transition.
impl Default for FoamJob {
    fn default() -> Self {
        FoamJob { meshes: None, model: Some(Model::default()), regions: default_regions(), transitions: default_transitions(), foam: Options::default() }
    }
}

/// The die swell, nozzle and filament of the design with the feed C.
pub(super) fn process(design: &Design, j: &FoamJob) -> Process {
    Process {
        nozzle_mm: design.printer.nozzle_diameter_mm,
        die_swell: design.material.swell_ratio,
        filament_mm: design.printer.filament_diameter_mm,
        feed_mm_s: j.foam.feed_mm_s,
    }
}

/// How many meshes the design names (None: a built-in model, whose count is its own).
pub(super) fn mesh_names(j: &FoamJob) -> Vec<String> {
    match &j.meshes {
        Some(Input::File { name, .. }) => vec![name.clone()],
        Some(Input::Files(names)) => names.clone(),
        _ => Vec::new(),
    }
}

/// The number of regions the job's source gives.
pub(super) fn source_regions(j: &FoamJob) -> Option<usize> {
    match &j.model {
        Some(m) => Some(models::build(m).len()),
        None => j.meshes.as_ref().map(|_| mesh_names(j).len()),
    }
}

/// Each region's pair (V* given, or by the calibration from its modulus).
pub(super) fn pairs(j: &FoamJob) -> Vec<Pair> {
    j.regions.iter().map(|r| r.pair(&j.foam.calibration)).collect()
}

/// The transitions with regions from 0; a linear-modulus weighting takes the ratio of its
/// regions' moduli by the calibration.
pub(super) fn transitions(j: &FoamJob) -> Vec<Transition> {
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

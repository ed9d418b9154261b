//! The graded job's settings as the design holds them (route, density map, alignment, cell sizing, the slicer's options), with their defaults.

use super::*;

/// The paper's contour levels on the slices (Fig. 8): 250, 350 (the bone threshold) and 600 HU.
pub const DEFAULT_CONTOUR_LEVELS_HU: [f64; 3] = [250.0, 350.0, 600.0];
/// The femur case's infill density ρ_s (table 3).
pub const DEFAULT_RHO_S: f64 = 0.47;
/// The femur case's extrusion width, mm (table 3).
pub const DEFAULT_WIDTH_MM: f64 = 0.4;
/// The femur case's perimeters (table 3: 3, 1.2 mm).
pub const DEFAULT_PERIMETERS: u32 = 3;
/// The femur case's movement speed v_sp, mm/s (table 3).
pub const DEFAULT_SPEED_MM_S: f64 = 25.0;
/// E_w,max, mm: equation 3 for the 0.4 mm nozzle (3 φ).
pub const DEFAULT_MAX_WIDTH_MM: f64 = 1.2;
/// E_w,min, mm: equation 2 for 0.2 mm layers (l_h).
pub const DEFAULT_MIN_WIDTH_MM: f64 = 0.2;

/// Which G-code is graded.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Route {
    /// weft slices the surface model and grades its own infill.
    #[default]
    Native,
    /// Another slicer's G-code, its infill E rewritten (the paper's route).
    Edit,
}

/// How the other slicer's G-code is placed over the volume.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum AlignMode {
    /// By the bounding boxes of the surface model and the printed part (XY centres, bottoms).
    #[default]
    Auto,
    /// `translation_mm`: a G-code point minus it is the volume-frame point.
    Manual,
}

/// Alignment of an edited G-code with the volume.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Alignment {
    /// Automatic or manual.
    pub mode: AlignMode,
    /// The paper's v⃗ (equation 5): G-code point = volume-frame point + v⃗, mm.
    pub translation_mm: [f64; 3],
}

/// The density map and the process limits.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct DensitySpec {
    /// HU → porosity through these points (equation 7: −91 HU → 0.95, 1516 HU → 0.10).
    #[serde(flatten)]
    pub calibration: Calibration,
    /// E_w,min, mm (equation 2: the layer height); ρ_min follows from it.
    pub min_width_mm: f64,
    /// E_w,max, mm (equation 3: 3 × the nozzle).
    pub max_width_mm: f64,
    /// Volumetric flow limit Q_max, mm³/s.
    pub q_max_mm3_s: f64,
    /// Over a limit: warn or clamp.
    pub limit: Limit,
    /// Longest infill segment after splitting, mm (0: the smallest voxel spacing).
    pub segment_mm: f64,
    /// Keep the cell (the paper) or re-size it where the bead would leave [E_w,min, E_w,max].
    pub cell_sizing: CellSizing,
    /// Largest ratio of a re-sized cell to L_s, either way.
    pub max_cell_ratio: f64,
}

/// How the infill cell follows the density.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CellSizing {
    /// One cell L_s everywhere; density by the bead width alone (the paper).
    #[default]
    Fixed,
    /// The cell shrinks or grows where the bead would be wider than E_w,max or narrower than
    /// E_w,min ([`scaffold::cells`]; gyroid only).
    Graded,
}

impl Default for DensitySpec {
    fn default() -> Self {
        DensitySpec {
            calibration: Calibration::default(),
            min_width_mm: DEFAULT_MIN_WIDTH_MM,
            max_width_mm: DEFAULT_MAX_WIDTH_MM,
            q_max_mm3_s: gcode_edit::DEFAULT_Q_MAX_MM3_S,
            limit: Limit::Warn,
            segment_mm: 0.0,
            cell_sizing: CellSizing::Fixed,
            max_cell_ratio: scaffold::cells::DEFAULT_MAX_RATIO,
        }
    }
}

/// Settings of a `graded` job.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GradedJob {
    /// The CT (or any scalar) volume: a DICOM series, a `.zip` of one, NRRD or raw voxels.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub volume: Option<Input>,
    /// How to read a `.raw` volume (dimensions, spacing, voxel type).
    #[serde(default)]
    pub raw: volume::RawLayout,
    /// The region of interest (volume frame, mm); absent: the whole volume.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub roi: Option<Roi>,
    /// Iso-contours drawn on the slices, HU.
    #[serde(default = "default_levels")]
    pub contour_levels_hu: [f64; 3],
    /// The surface model: isovalue, cavity fill, smoothing.
    #[serde(default)]
    pub surface: isosurface::Options,
    /// HU → density and the process limits.
    #[serde(default)]
    pub density: DensitySpec,
    /// Native slicing or editing another slicer's G-code.
    #[serde(default)]
    pub route: Route,
    /// Slicing of the surface model (native route): layers, perimeters, infill pattern and ρ_s.
    #[serde(default = "default_slice")]
    pub slice: slice::Options,
    /// The other slicer's G-code (edit route).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gcode: Option<Input>,
    /// The density the other slicer's infill was made with, ρ_s (edit route).
    #[serde(default = "default_rho_s")]
    pub gcode_rho_s: f64,
    /// The other slicer's ;TYPE: names counted as infill (edit route).
    #[serde(default = "default_infill_types")]
    pub gcode_infill_types: Vec<String>,
    /// Where the other slicer's part sits over the volume (edit route).
    #[serde(default)]
    pub alignment: Alignment,
    /// Native route: also grade the same sliced toolpath the paper's way (its G-code written
    /// ungraded, then each infill move's E rewritten by the field at its midpoint) and report
    /// both routes' per-layer error.
    #[serde(default = "default_compare")]
    pub compare_edit: bool,
}

/// Whether the native route compares itself with the edit route by default.
pub const DEFAULT_COMPARE_EDIT: bool = true;

pub(super) fn default_compare() -> bool {
    DEFAULT_COMPARE_EDIT
}

pub(super) fn default_levels() -> [f64; 3] {
    DEFAULT_CONTOUR_LEVELS_HU
}

pub(super) fn default_rho_s() -> f64 {
    DEFAULT_RHO_S
}

pub(super) fn default_infill_types() -> Vec<String> {
    gcode_edit::Options::default().infill_types
}

/// The femur case's slicing (table 3): gyroid at ρ_s 47 %, 0.4 mm, 0.2 mm layers, 3 perimeters.
pub(super) fn default_slice() -> slice::Options {
    slice::Options {
        perimeters: DEFAULT_PERIMETERS,
        line_width_mm: DEFAULT_WIDTH_MM,
        infill_density: DEFAULT_RHO_S,
        infill_pattern: InfillPattern::Gyroid,
        // A scaffold is open: no solid skins hiding the graded lattice.
        solid_layers: 0,
        ..slice::Options::default()
    }
}

impl Default for GradedJob {
    fn default() -> Self {
        GradedJob {
            volume: None,
            raw: volume::RawLayout::default(),
            roi: None,
            contour_levels_hu: DEFAULT_CONTOUR_LEVELS_HU,
            surface: isosurface::Options::default(),
            density: DensitySpec::default(),
            route: Route::Native,
            slice: default_slice(),
            gcode: None,
            gcode_rho_s: DEFAULT_RHO_S,
            gcode_infill_types: default_infill_types(),
            alignment: Alignment::default(),
            compare_edit: DEFAULT_COMPARE_EDIT,
        }
    }
}

//! The `graded` job (Grigolato & Savio 2025): a CT volume drives the density of a scaffold's
//! infill. CT (DICOM series, NRRD or raw voxels) in, graded G-code out, with no CAD package.
//!
//! Stages: `volume` (the series read and placed; HU histogram of the region of interest),
//! `surface` (marching cubes at an isovalue inside the ROI, capped at its faces, cavities
//! optionally filled, optionally smoothed), `density` (the HU → porosity line of equation 7,
//! ρ = 1 − P clamped to [ρ_min, 1], and the calculators of equations 1–4), then either
//! `slice` + `grade` (the **native** route: weft slices the surface model with perimeters and
//! a gyroid / rectilinear / 3D-honeycomb infill whose cell follows equation 1, splits long
//! infill segments to the voxel size and scales each one's extrusion by ρ(midpoint) / ρ_s,
//! equation 6) or `edit` (the paper's route: another slicer's G-code, its infill moves'
//! E rewritten by equation 6, every other byte kept).
//!
//! Frames: the volume frame (mm, first voxel centre at 0, [`crate::volume`]) holds the volume,
//! the ROI and the surface model. The native route places the surface on the plate (XY
//! centred, lowest point at Z = 0) and looks ρ up at `p − offset`; the edit route aligns the
//! other slicer's printed part to the surface model by their bounding boxes (the paper's
//! equation 5: XY centres and bottoms) or by a translation the user gives.

use super::{Inspection, Kind, Product, Shape, Slot, SlotKind, StageInfo, ViewInfo};
use crate::budget::Estimate;
use crate::design::{Design, Input};
use crate::gcode_edit;
use crate::geom::{DVec3, Mesh};
use crate::isosurface;
use crate::report::{Axis, Column, Plot, PlotKind, Row as TableRow, Series, StageReport, Table};
use crate::scaffold::{self, grade, Calibration, Cell, LayerStat, Limit};
use crate::settings::{choice_docs, mount, num, other, percent, points, vec3, when, Field, Kind as FieldKind, Problem, Row};
use crate::slice::{self, InfillPattern};
use crate::source::ByteSource;
use crate::stage::{Ctx, Error, Out};
use crate::volume::{self, Axis as SliceAxis, Roi, Volume};
use serde::{Deserialize, Serialize};
use std::sync::Arc;

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

fn default_compare() -> bool {
    DEFAULT_COMPARE_EDIT
}

fn default_levels() -> [f64; 3] {
    DEFAULT_CONTOUR_LEVELS_HU
}

fn default_rho_s() -> f64 {
    DEFAULT_RHO_S
}

fn default_infill_types() -> Vec<String> {
    gcode_edit::Options::default().infill_types
}

/// The femur case's slicing (table 3): gyroid at ρ_s 47 %, 0.4 mm, 0.2 mm layers, 3 perimeters.
fn default_slice() -> slice::Options {
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

/// The `graded` job kind.
pub struct GradedKind;

const SLOTS: &[Slot] = &[
    Slot {
        name: "volume",
        label: "CT volume",
        kind: SlotKind::Volume,
        path: "job.volume",
        required: true,
        doc: "A CT series: drop its folder, its .dcm files or a .zip of them (or an NRRD, or .raw voxels with their layout below).",
    },
    Slot {
        name: "gcode",
        label: "Another slicer's G-code",
        kind: SlotKind::Gcode,
        path: "job.gcode",
        required: false,
        doc: "Route 'edit': a G-code from PrusaSlicer, Slic3r or Cura of the surface model; its infill's extrusion is rewritten by the density.",
    },
];

const STAGES: &[StageInfo] = &[
    StageInfo { name: "volume", label: "Reading the volume" },
    StageInfo { name: "surface", label: "Extracting the surface model" },
    StageInfo { name: "density", label: "Mapping HU to density" },
    StageInfo { name: "cells", label: "Sizing the cells" },
    StageInfo { name: "slice", label: "Slicing the surface model" },
    StageInfo { name: "grade", label: "Grading the infill" },
    StageInfo { name: "compare", label: "Native against the edit route" },
    StageInfo { name: "edit", label: "Editing the G-code's infill" },
];

const VIEWS: &[ViewInfo] = &[
    ViewInfo {
        id: "axial",
        stage: "volume",
        label: "Axial slices",
        shape: Shape::Image,
        index_label: "Slice",
        doc: "The volume across k (HU), with iso-contours and the region of interest.",
    },
    ViewInfo {
        id: "coronal",
        stage: "volume",
        label: "Coronal slices",
        shape: Shape::Image,
        index_label: "Slice",
        doc: "The volume across j (HU), with iso-contours and the region of interest.",
    },
    ViewInfo {
        id: "sagittal",
        stage: "volume",
        label: "Sagittal slices",
        shape: Shape::Image,
        index_label: "Slice",
        doc: "The volume across i (HU), with iso-contours and the region of interest.",
    },
    ViewInfo {
        id: "density",
        stage: "density",
        label: "Target density",
        shape: Shape::Image,
        index_label: "Slice",
        doc: "The relative density the infill is graded to (1 − P(HU), clamped to [ρ_min, 1]), axial slices of the ROI.",
    },
    ViewInfo {
        id: "surface",
        stage: "surface",
        label: "Surface model",
        shape: Shape::Mesh,
        index_label: "View",
        doc: "The closed mesh marching cubes extracted at the isovalue inside the ROI (volume frame, mm).",
    },
];

const JOB_FIELDS: &[Field] = &[
    choice_docs(
        other(
            "route",
            "Route",
            "Route",
            FieldKind::Choice,
            &["native", "edit"],
            "Who makes the toolpath: weft slices the surface model, or you bring another slicer's G-code.",
        ),
        &[
            "weft slices the surface model and grades its own infill (long segments split to the voxel size).",
            "The paper's route: another slicer's G-code of the same model, its infill's E rewritten (equation 6).",
        ],
    ),
    vec3(
        "contour_levels_hu",
        "Volume",
        "Contours at",
        "HU",
        -5000.0,
        50000.0,
        1.0,
        "Three iso-contour levels drawn on the slices (the paper's Fig. 8: 250, 350, 600 HU).",
    ),
    when(
        percent(num(
            "gcode_rho_s",
            "Route",
            "Its infill density ρ_s",
            "",
            0.01,
            1.0,
            0.01,
            "The infill density the other slicer's file was made with (equation 6 divides by it).",
        )),
        "route",
        "edit",
    ),
    when(
        other(
            "gcode_infill_types",
            "Route",
            "Its infill types",
            FieldKind::Text,
            &[],
            "The ;TYPE: names of infill in that file (PrusaSlicer 'Internal infill', Cura 'FILL'), one per line.",
        ),
        "route",
        "edit",
    ),
    when(
        choice_docs(
            other("alignment.mode", "Route", "Alignment", FieldKind::Choice, &["auto", "manual"], "How the G-code's part is placed over the volume."),
            &[
                "By the bounding boxes: XY centres and bottoms of the surface model and the printed part.",
                "By the translation below (the paper's v⃗, equation 5).",
            ],
        ),
        "route",
        "edit",
    ),
    when(
        other(
            "compare_edit",
            "Route",
            "Compare with the edit route",
            FieldKind::Bool,
            &[],
            "Also grade the same toolpath the paper's way (whole moves, E by the field at their midpoint) and plot both routes' error per layer.",
        ),
        "route",
        "native",
    ),
    when(
        vec3("alignment.translation_mm", "Route", "Translation v⃗", "mm", -100000.0, 100000.0, 0.01, "G-code point = volume point + v⃗ (alignment 'manual')."),
        "alignment.mode",
        "manual",
    ),
];

const ROI_FIELDS: &[Field] = &[
    Field {
        default: Some("{\"min_mm\":[0,0,0],\"max_mm\":[50,50,50]}"),
        ..other(
            "",
            "Region of interest",
            "Crop to a box",
            FieldKind::Section,
            &[],
            "Use only the voxels inside a box (volume frame, mm); off: the whole volume.",
        )
    },
    vec3(
        "min_mm",
        "Region of interest",
        "From",
        "mm",
        -100000.0,
        100000.0,
        0.1,
        "The ROI box's smallest corner in the volume frame (first voxel centre at 0).",
    ),
    vec3("max_mm", "Region of interest", "To", "mm", -100000.0, 100000.0, 0.1, "The ROI box's largest corner in the volume frame."),
];

const DENSITY_FIELDS: &[Field] = &[
    points(
        "points",
        "Density",
        "HU → porosity",
        "",
        -100000.0,
        100000.0,
        64,
        "Calibration points 'HU P', one per line: porosity P at that HU, straight lines between (the femur case: -91 0.95 and 1516 0.10).",
    ),
    num(
        "min_width_mm",
        "Density",
        "E_w,min",
        "mm",
        0.01,
        10.0,
        0.01,
        "Narrowest bead that still holds the layer (equation 2: the layer height); ρ_min follows from it.",
    ),
    num("max_width_mm", "Density", "E_w,max", "mm", 0.05, 20.0, 0.01, "Widest bead that keeps its shape (equation 3: 3 × the nozzle)."),
    num(
        "q_max_mm3_s",
        "Density",
        "Q_max",
        "mm³/s",
        0.1,
        1000.0,
        0.1,
        "Most material the hot end melts per second (the paper measured 19.24 for PLA at 215 °C).",
    ),
    choice_docs(
        other("limit", "Density", "Over a limit", FieldKind::Choice, &["warn", "clamp"], "What to do with a segment over Q_max or E_w,max."),
        &["Count it in the report and print it as graded.", "Count it and reduce its flow to the limit."],
    ),
    num(
        "segment_mm",
        "Density",
        "Grading step",
        "mm",
        0.0,
        100.0,
        0.1,
        "Longest infill segment after splitting (0: the smallest voxel spacing), so the grading resolves the voxels.",
    ),
    choice_docs(
        other(
            "cell_sizing",
            "Density",
            "Cell size",
            FieldKind::Choice,
            &["fixed", "graded"],
            "Keep one gyroid cell everywhere, or re-size it where the bead would leave its printable range.",
        ),
        &[
            "One cell L_s; density by the bead width alone (the paper: beads clamp at E_w,min and E_w,max).",
            "Smaller cells where the bead would be wider than E_w,max, larger where narrower than E_w,min (gyroid).",
        ],
    ),
    when(
        num("max_cell_ratio", "Density", "Cell size range", "×", 1.0, 10.0, 0.1, "A re-sized cell stays within L_s ÷ this and L_s × this."),
        "cell_sizing",
        "graded",
    ),
];

impl Kind for GradedKind {
    type Settings = GradedJob;
    const NAME: &'static str = "graded";
    const LABEL: &'static str = "CT-graded scaffold";
    const DOC: &'static str =
        "A CT volume's density drives the extrusion of a gyroid (or rectilinear, 3D honeycomb) infill: patient-specific graded scaffolds from DICOM.";
    const SLOTS: &'static [Slot] = SLOTS;
    const STAGES: &'static [StageInfo] = STAGES;
    const VIEWS: &'static [ViewInfo] = VIEWS;

    fn fields() -> Vec<Row> {
        let mut rows = mount("job", JOB_FIELDS);
        rows.extend(mount("job.raw", volume::RAW_FIELDS));
        rows.extend(mount("job.roi", ROI_FIELDS));
        rows.extend(mount("job.surface", isosurface::FIELDS));
        rows.extend(mount("job.density", DENSITY_FIELDS));
        rows.extend(mount("job.slice", slice::FIELDS));
        rows
    }

    fn validate(design: &Design, j: &GradedJob, out: &mut Vec<Problem>) {
        out.extend(super::thicker_than_nozzle("job.slice.layer_height_mm", j.slice.layer_height_mm, design.printer.nozzle_diameter_mm));
        for message in j.density.calibration.problems() {
            out.push(Problem { path: "job.density.points".into(), message });
        }
        if j.density.min_width_mm >= j.density.max_width_mm {
            out.push(Problem { path: "job.density.min_width_mm".into(), message: "E_w,min must be narrower than E_w,max".into() });
        }
        if let Some(r) = &j.roi {
            if (0..3).any(|a| !(r.max_mm[a] > r.min_mm[a])) {
                out.push(Problem { path: "job.roi".into(), message: "each 'to' corner value must be larger than its 'from' value".into() });
            }
        }
        if j.density.cell_sizing == CellSizing::Graded && (j.route != Route::Native || j.slice.infill_pattern != InfillPattern::Gyroid) {
            out.push(Problem {
                path: "job.density.cell_sizing".into(),
                message: "a graded cell size needs route 'native' and the gyroid pattern (job.slice.infill_pattern); or set it to 'fixed'".into(),
            });
        }
        if !(j.density.max_cell_ratio >= 1.0 && j.density.max_cell_ratio <= 10.0) {
            out.push(Problem { path: "job.density.max_cell_ratio".into(), message: "the cell size range must be between 1 and 10".into() });
        }
        if j.route == Route::Edit && j.gcode.is_none() {
            out.push(Problem {
                path: "job.gcode".into(),
                message: "route 'edit' rewrites another slicer's G-code: load it (its drop zone, or --input gcode=FILE), or pick route 'native'".into(),
            });
        }
    }

    /// The femur case's printing (table 3): 25 mm/s, 215 °C nozzle, 55 °C bed.
    fn adopted(design: &mut serde_json::Value) {
        if let Some(s) = design.get_mut("speeds").and_then(|s| s.as_object_mut()) {
            for key in ["external_perimeter_mm_s", "perimeter_mm_s", "infill_mm_s", "solid_infill_mm_s"] {
                s.insert(key.into(), DEFAULT_SPEED_MM_S.into());
            }
        }
        if let Some(m) = design.get_mut("material").and_then(|s| s.as_object_mut()) {
            m.insert("nozzle_temp_c".into(), 215.0.into());
            m.insert("first_layer_nozzle_temp_c".into(), 220.0.into());
            m.insert("bed_temp_c".into(), 55.0.into());
        }
    }

    fn slot_filled(slot: &str, mut j: GradedJob) -> GradedJob {
        if slot == "gcode" {
            j.route = Route::Edit;
        }
        j
    }

    fn estimate(j: &GradedJob, ctx: &mut Ctx) -> Result<Vec<Estimate>, Error> {
        let input = volume_input(j)?;
        let mut out = vec![ctx.volume_estimate("volume", input, &volume_options(j))?];
        let vol = volume_stage(j, ctx)?;
        let roi = roi_of(j, &vol);
        let surface_e = isosurface::estimate(&vol, &roi, &j.surface);
        let refused = surface_e.refused.is_some();
        out.push(surface_e);
        if refused {
            return Ok(out);
        }
        // The surface model is bounded by its own estimate, like an imported mesh: made here,
        // kept for the run.
        let surface = surface_stage(j, ctx, &vol)?;
        match j.route {
            Route::Native => {
                let (mesh, _) = placed(&surface.mesh);
                let model = Model::of(j, ctx.design, &vol)?;
                let s = slice::estimate(&mesh, &slice_options(j, &model));
                let infill_mm = surface.report.volume_mm3 * model.cell.k_c * model.cell.m / model.cell_mm / j.slice.layer_height_mm;
                if j.density.cell_sizing == CellSizing::Graded {
                    if let Some(b) = mesh.bounds() {
                        out.push(scaffold::cells::estimate(&b, &cells_options(j, &model)));
                    }
                }
                let sliced_moves = s.get("segments");
                let segments = sliced_moves + infill_mm / model.segment_mm;
                out.push(s);
                out.push(Estimate::new("grade").quantity("segments", "Toolpath segments", segments, "").cost(segments * 120.0, segments * 2e-7).limit(
                    "infill segments after splitting",
                    segments,
                    grade::MAX_SEGMENTS as f64,
                    "",
                    "raise the grading step (job.density.segment_mm)",
                ));
                if j.compare_edit && j.density.cell_sizing == CellSizing::Fixed {
                    // The ungraded G-code (about 30 bytes per move) and its edited copy.
                    let bytes = (sliced_moves * 30.0) as usize;
                    let mut e = gcode_edit::estimate(bytes, &edit_options(j, ctx.design, [0.0; 3], model.segment_mm));
                    e.stage = "compare";
                    if let Some(r) = e.refused.as_mut() {
                        r.fix = "turn off 'Compare with the edit route' (job.compare_edit)".into();
                    }
                    out.push(e);
                }
            }
            Route::Edit => {
                let input =
                    j.gcode.as_ref().ok_or_else(|| Error::NoInput("route 'edit' needs another slicer's G-code: load it, or pass --input gcode=FILE".into()))?;
                let (source, _) = ctx.file_source("gcode", input)?;
                let e = gcode_edit::estimate(source.len(), &edit_options(j, ctx.design, [0.0; 3], 1.0));
                // The analyzer reads about one segment per 30 bytes of G-code.
                let segments = source.len() as f64 / 30.0;
                out.push(e.quantity("segments", "Moves (about)", segments, ""));
            }
        }
        Ok(out)
    }

    fn run(j: &GradedJob, ctx: &mut Ctx) -> Result<Product, Error> {
        let vol = volume_stage(j, ctx)?;
        let surface = surface_stage(j, ctx, &vol)?;
        let model = density_stage(j, ctx, &vol, &surface)?;
        match j.route {
            Route::Native => native(j, ctx, &vol, &surface, &model),
            Route::Edit => edit(j, ctx, &vol, &surface),
        }
    }

    fn inspect(j: &GradedJob, ctx: &mut Ctx, view: &str, index: usize) -> Result<Inspection, Error> {
        let vol = volume_stage(j, ctx)?;
        let roi = roi_of(j, &vol);
        match view {
            "axial" | "coronal" | "sagittal" => {
                let axis = match view {
                    "axial" => SliceAxis::Axial,
                    "coronal" => SliceAxis::Coronal,
                    _ => SliceAxis::Sagittal,
                };
                Ok(slice_view(view, &vol, axis, index, &roi, j))
            }
            "density" => {
                let model = Model::of(j, ctx.design, &vol)?;
                let image = volume::slice_image(&vol, SliceAxis::Axial, index);
                let curve = j.density.calibration.curve();
                let values: Vec<f32> = image.values.iter().map(|&hu| curve.density(hu as f64, model.rho_min) as f32).collect();
                let mut overlay = Vec::new();
                roi_rect(&mut overlay, &image, &roi);
                Ok(Inspection {
                    view: view.into(),
                    shape: Shape::Image,
                    index: image.index,
                    count: image.count,
                    stride: 1,
                    data: values,
                    overlay,
                    meta: serde_json::json!({
                        "width": image.width, "height": image.height, "pixel_mm": image.pixel_mm, "window": [0.0, 1.0], "unit": "ρ",
                        "caption": format!("z = {:.1} mm · ρ_min {:.3}", image.position_mm, model.rho_min),
                        "overlay_legend": [{"code": ROI_CODE, "label": "region of interest", "color": ROI_COLOR}],
                    }),
                })
            }
            "surface" => {
                let surface = surface_stage(j, ctx, &vol)?;
                let m = &surface.mesh;
                let mut data = Vec::with_capacity(m.triangles.len() * 9);
                for t in &m.triangles {
                    for &v in t {
                        data.extend_from_slice(&m.vertices[v as usize]);
                    }
                }
                let r = &surface.report;
                Ok(Inspection {
                    view: view.into(),
                    shape: Shape::Mesh,
                    index: 0,
                    count: 1,
                    stride: 9,
                    data,
                    overlay: Vec::new(),
                    meta: serde_json::json!({ "caption": format!("{} triangles, {:.0} mm³{}", r.triangles, r.volume_mm3, if r.closed { ", closed" } else { ", NOT closed" }), "stl": true }),
                })
            }
            _ => Err(Error::UnknownView { view: view.into(), job: Self::NAME }),
        }
    }
}

/// Overlay code of the ROI rectangle on the slice views.
const ROI_CODE: usize = 10;
const ROI_COLOR: &str = "#4cc38a";
/// The contour colours of the paper's Fig. 8: yellow, red, blue.
const LEVEL_COLORS: [&str; 3] = ["#f5d547", "#e5484d", "#3e8ef7"];

fn volume_input(j: &GradedJob) -> Result<&Input, Error> {
    j.volume.as_ref().ok_or_else(|| {
        Error::NoInput(
            "a graded job needs a CT volume: drop a DICOM series (folder, files or .zip), an NRRD or a .raw file, or pass --input volume=FOLDER".into(),
        )
    })
}

fn volume_options(j: &GradedJob) -> volume::Options {
    volume::Options { raw: j.raw.clone() }
}

fn volume_stage(j: &GradedJob, ctx: &mut Ctx) -> Result<Out<Volume>, Error> {
    let input = volume_input(j)?;
    ctx.volume("volume", input, &volume_options(j))
}

/// The ROI, or the whole grid.
fn roi_of(j: &GradedJob, vol: &Volume) -> Roi {
    j.roi.unwrap_or_else(|| Roi::whole(vol))
}

fn surface_stage(j: &GradedJob, ctx: &mut Ctx, vol: &Out<Volume>) -> Result<Out<isosurface::Surface>, Error> {
    let roi = roi_of(j, vol);
    // Kept: the estimate makes the surface model (to bound the slicing) and the run reads it.
    ctx.stage_kept("surface", "surface", &(&j.surface, &roi), &[vol.key], |progress| {
        let s = isosurface::extract(vol, &roi, &j.surface, progress).map_err(|e| Error::stage("surface model", e))?;
        let r = &s.report;
        let report = StageReport::new("surface", "Extracting the surface model", r)
            .metric("triangles", "Triangles", r.triangles as f64, "", "Facets of the surface model (marching cubes at the isovalue inside the ROI).")
            .metric("volume", "Volume", r.volume_mm3, "mm³", "Volume enclosed by the surface model.")
            .metric("area", "Surface area", r.area_mm2, "mm²", "Area of the surface model.")
            .metric("cavities", "Cavities filled", r.cavities_filled as f64, "", "Closed voids inside the solid (a medullary canal) filled before meshing.")
            .metric("components", "Pieces", r.components as f64, "", "Separate solids found inside the ROI.")
            .metric("closed", "Closed", if r.closed { 1.0 } else { 0.0 }, "", "1: every edge joins exactly two triangles (watertight, slices cleanly).");
        Ok((s, Some(report)))
    })
}

/// The numbers of the paper's model for this design (equations 1–4).
#[derive(Clone, Debug, Serialize)]
struct Model {
    pattern: InfillPattern,
    cell: Cell,
    rho_s: f64,
    nozzle_mm: f64,
    layer_mm: f64,
    /// L_cell from equation 1 at ρ_s, mm.
    cell_mm: f64,
    /// ρ_min: equation 1 at E_w,min.
    rho_min: f64,
    /// The bead at ρ_s (equation 1's 1.25 φ), mm².
    nominal_area_mm2: f64,
    /// L_cell from equation 4 for ρ = 1, mm.
    cell_eq4_mm: f64,
    /// Grading step, mm.
    segment_mm: f64,
    /// The calibration as a line (2 points): slope, intercept.
    line: Option<(f64, f64)>,
}

fn cell_of(p: InfillPattern) -> Cell {
    match p {
        InfillPattern::Gyroid => scaffold::GYROID,
        InfillPattern::Rectilinear => scaffold::RECTILINEAR,
        InfillPattern::Honeycomb3d => scaffold::HONEYCOMB_3D,
    }
}

impl Model {
    fn of(j: &GradedJob, design: &Design, vol: &Volume) -> Result<Model, Error> {
        let (nozzle, layer) = (design.printer.nozzle_diameter_mm, j.slice.layer_height_mm);
        let (pattern, rho_s) = match j.route {
            Route::Native => (j.slice.infill_pattern, j.slice.infill_density),
            Route::Edit => (j.slice.infill_pattern, j.gcode_rho_s),
        };
        if !(rho_s > 0.0 && rho_s <= 1.0) {
            return Err(Error::NoInput(format!("the infill density ρ_s is {rho_s}: set it between 1 % and 100 %")));
        }
        let cell = cell_of(pattern);
        let cell_mm = scaffold::cell_size_for_density(cell, rho_s, nozzle, layer);
        let rho_min = scaffold::density_at_width(cell, cell_mm, j.density.min_width_mm, layer).clamp(0.0, 1.0);
        let segment_mm = grading_step(j, vol);
        Ok(Model {
            pattern,
            cell,
            rho_s,
            nozzle_mm: nozzle,
            layer_mm: layer,
            cell_mm,
            rho_min,
            nominal_area_mm2: scaffold::bead_area(1.25 * nozzle, layer),
            cell_eq4_mm: scaffold::cell_size_for_width(cell, j.density.max_width_mm, 1.0),
            segment_mm,
            line: j.density.calibration.line(),
        })
    }
}

/// The grading step, mm: the design's, else the smallest voxel spacing.
fn grading_step(j: &GradedJob, vol: &Volume) -> f64 {
    let smallest_voxel = vol.spacing_mm.iter().copied().fold(f64::INFINITY, f64::min);
    if j.density.segment_mm > 0.0 {
        j.density.segment_mm
    } else {
        smallest_voxel.clamp(0.05, 100.0)
    }
}

/// The density stage: the model's numbers, the calibration and ρ over the solid voxels.
fn density_stage(j: &GradedJob, ctx: &mut Ctx, vol: &Out<Volume>, surface: &Out<isosurface::Surface>) -> Result<Out<Model>, Error> {
    let model = Model::of(j, ctx.design, vol)?;
    let roi = roi_of(j, vol);
    let parts = (&j.density, model.rho_s, model.cell_mm, roi, j.surface.iso);
    ctx.stage("density", "density", &parts, &[vol.key, surface.key], |_| {
        let report = density_report(j, &model, vol, &roi);
        Ok((model, Some(report)))
    })
}

fn density_report(j: &GradedJob, m: &Model, vol: &Volume, roi: &Roi) -> StageReport {
    let cal = &j.density.calibration;
    let mut r = StageReport::new("density", "Mapping HU to density", m)
        .metric("rho_s", "Infill density ρ_s", m.rho_s, "", "The density the infill is sliced for; each segment's extrusion is scaled by ρ / ρ_s (equation 6).")
        .metric("cell", "Unit cell L_cell", m.cell_mm, "mm", "Cell size from equation 1 at ρ_s (k_c, m of table 1, nozzle φ, layer l_h).")
        .metric("rho_min", "ρ_min", m.rho_min, "", "The least density printed: equation 1 with the bead at E_w,min (thinner beads do not hold the layer).")
        .metric("ew_min", "E_w,min", j.density.min_width_mm, "mm", "Narrowest bead (equation 2: l_h).")
        .metric("ew_max", "E_w,max", j.density.max_width_mm, "mm", "Widest bead (equation 3: 3φ).")
        .metric(
            "cell_eq4",
            "L_cell for ρ = 1 (eq. 4)",
            m.cell_eq4_mm,
            "mm",
            "Equation 4: the cell whose beads at E_w,max make a solid; larger cells cannot reach ρ = 1.",
        )
        .metric("k_c", "k_c", m.cell.k_c, "", "Toolpath length in a unit cell ÷ L_cell for this pattern (table 1).")
        .metric("segment", "Grading step", m.segment_mm, "mm", "Infill segments are split to this length so the grading resolves the voxels.");
    if let Some((slope, intercept)) = m.line {
        r = r.metric("slope", "P slope", slope * 1000.0, "per 1000 HU", "Equation 7: P = slope · HU + intercept (the femur case: −0.529 per 1000 HU).").metric(
            "intercept",
            "P intercept",
            intercept,
            "",
            "Equation 7's constant (the femur case: 0.901867).",
        );
    }
    // The calibration, plotted over the ROI's HU range.
    let h = volume::histogram(vol, roi, 64);
    // The points may be given in any order: the range covers all of them.
    let (lo, hi) = cal.points.iter().fold((h.min, h.max), |(lo, hi), p| (lo.min(p[0]), hi.max(p[0])));
    let curve = cal.curve();
    let xs: Vec<f64> = (0..=40).map(|i| lo + (hi - lo) * i as f64 / 40.0).collect();
    r.plots.push(Plot {
        key: "calibration".into(),
        title: "HU → porosity P and density ρ".into(),
        kind: PlotKind::Line,
        x: Axis::new("CT value", "HU"),
        y: Axis::new("P, ρ", ""),
        group: None,
        series: vec![
            Series::xy("P (equation 7)", xs.clone(), xs.iter().map(|&x| curve.porosity(x)).collect()),
            Series::xy("ρ = 1 − P, clamped", xs.clone(), xs.iter().map(|&x| curve.density(x, m.rho_min)).collect()),
            Series::hline("ρ_min", m.rho_min),
        ],
    });
    let edges = |h: &volume::Histogram| (0..=h.counts.len()).map(|i| h.min + h.bin_width * i as f64).collect::<Vec<_>>();
    r.plots.push(Plot {
        key: "hu_histogram".into(),
        title: "HU in the region of interest".into(),
        kind: PlotKind::Histogram,
        x: Axis::new("CT value", "HU"),
        y: Axis::new("Voxels", ""),
        group: None,
        series: vec![Series::xy("voxels", edges(&h), h.counts.iter().map(|&c| c as f64).collect())],
    });
    // Figure 2: ρ_s against L_cell for the three patterns at this nozzle and layer.
    let ls: Vec<f64> = (0..=40).map(|i| 1.0 + 5.0 * i as f64 / 40.0).collect();
    r.plots.push(Plot {
        key: "rho_s_of_cell".into(),
        title: "Infill density against cell size (equation 1, Fig. 2)".into(),
        kind: PlotKind::Line,
        x: Axis::new("L_cell", "mm"),
        y: Axis::new("ρ_s", ""),
        group: None,
        series: scaffold::coefficients_table()
            .iter()
            .map(|(name, c)| Series::xy(name, ls.clone(), ls.iter().map(|&l| scaffold::infill_density(*c, l, m.nozzle_mm, m.layer_mm)).collect()))
            .collect(),
    });
    r
}

fn slice_options(j: &GradedJob, m: &Model) -> slice::Options {
    slice::Options { infill_pattern: m.pattern, infill_density: m.rho_s, infill_cell_mm: Some(m.cell_mm), ..j.slice.clone() }
}

/// The mesh placed on the plate (XY centred, lowest point at Z = 0) and the offset applied.
fn placed(mesh: &Mesh) -> (Mesh, DVec3) {
    let mut m = mesh.clone();
    let Some(b) = mesh.bounds() else { return (m, DVec3::ZERO) };
    let c = (b.min + b.max) * 0.5;
    let offset = DVec3::new(-c.x, -c.y, -b.min.z);
    m.translate(offset);
    (m, offset)
}

fn native(j: &GradedJob, ctx: &mut Ctx, vol: &Out<Volume>, surface: &Out<isosurface::Surface>, model: &Out<Model>) -> Result<Product, Error> {
    let mut options = slice_options(j, model);
    let (mesh, offset) = placed(&surface.mesh);
    super::part_fits(ctx.design, &mesh)?;
    let field = density_field(j, vol);
    let rho = |p: DVec3| field(p - offset);
    let mut slice_upstream = vec![surface.key];
    let cells = match j.density.cell_sizing {
        CellSizing::Fixed => None,
        CellSizing::Graded => {
            let bounds = mesh.bounds().ok_or_else(|| Error::NoInput("the surface model is empty: lower the isovalue or widen the ROI".into()))?;
            let o = cells_options(j, model);
            let parts = (format!("{o:?}"), &j.density.calibration, offset.to_array());
            let cells = ctx.stage("cells", "cells", &parts, &[surface.key, vol.key], |_| {
                let sized = scaffold::cells::size_cells(&bounds, &rho, &o).map_err(|e| Error::stage("sizing the cells", e))?;
                let report = cells_report(&sized.report, &o);
                Ok((Arc::new(sized.field), Some(report)))
            })?;
            options.infill_cell_field = Some(cells.value.as_ref().clone());
            slice_upstream.push(cells.key);
            Some(cells)
        }
    };
    let sliced = ctx.stage("slice", "slice", &options, &slice_upstream, |progress| {
        let sliced = slice::slice(&mesh, &options, progress).map_err(|e| Error::stage("slicing", e))?;
        let report = super::slice_report(&sliced.report, "Slicing the surface model");
        Ok((sliced.toolpath, Some(report)))
    })?;
    drop(mesh);
    let design = ctx.design;
    let g = grade::Options {
        rho_s: model.rho_s,
        rho_min: model.rho_min,
        nominal_area_mm2: model.nominal_area_mm2,
        segment_mm: model.segment_mm,
        q_max_mm3_s: j.density.q_max_mm3_s,
        width_max_mm: j.density.max_width_mm,
        limit: j.density.limit,
        feed_mm_s: design.speeds.infill_mm_s,
    };
    let parts = (format!("{g:?}"), &j.density.calibration);
    let graded = ctx.stage("grade", "grade", &parts, &[sliced.key, vol.key], |progress| {
        let ratio = cells.as_ref().map(|c| move |p: DVec3| c.at(p) / c.reference_mm);
        let mut out = grade::grade(&sliced, &rho, ratio.as_ref().map(|f| f as &dyn Fn(DVec3) -> f64), &g, progress).map_err(|e| Error::stage("grading", e))?;
        out.report.offset_mm = offset.to_array();
        let report = grade_report(&out.report);
        Ok((out.toolpath, Some(report)))
    })?;
    // The edit route cannot know a re-sized cell: compared only with one cell everywhere.
    if j.compare_edit && cells.is_none() {
        compare(j, ctx, vol, &sliced, model, &g, offset)?;
    }
    Ok(Product::Toolpath(graded))
}

fn cells_options(j: &GradedJob, m: &Model) -> scaffold::cells::Options {
    scaffold::cells::Options {
        cell: m.cell,
        reference_mm: m.cell_mm,
        width_min_mm: j.density.min_width_mm,
        width_max_mm: j.density.max_width_mm,
        layer_mm: m.layer_mm,
        max_ratio: j.density.max_cell_ratio,
    }
}

fn cells_report(r: &scaffold::cells::CellsReport, o: &scaffold::cells::Options) -> StageReport {
    let mut s = StageReport::new("cells", "Sizing the cells", r)
        .metric("nodes", "Cell-size nodes", r.nodes as f64, "", "Nodes of the cell-size grid (one per L_s over the part); the size is trilinear between them.")
        .metric("sampled", "Nodes in the volume", r.sampled as f64, "", "Nodes with CT density around them.")
        .metric(
            "smaller",
            "Cells made smaller",
            r.smaller as f64,
            "",
            "Density above what E_w,max gives at L_s: a smaller cell reaches it with a printable bead.",
        )
        .metric("larger", "Cells made larger", r.larger as f64, "", "Density below what E_w,min gives at L_s: a larger cell reaches it with a bead that holds.")
        .metric(
            "still_out",
            "Still out of range",
            r.still_out_of_range as f64,
            "",
            "Re-sized cells whose bead is outside [E_w,min, E_w,max] even at the size bound (the grading clamps them).",
        )
        .metric("min_cell", "Smallest cell", r.min_cell_mm, "mm", "The smallest cell written.")
        .metric("max_cell", "Largest cell", r.max_cell_mm, "mm", "The largest cell written.")
        .metric("reference", "L_s", o.reference_mm, "mm", "The uniform cell (equation 1 at ρ_s), kept where the bead is printable.");
    let col = |label: &str, unit: &str| Column { label: label.into(), unit: unit.into() };
    s.tables.push(Table {
        key: "resized".into(),
        title: format!("Re-sized cells (the first {} of {})", r.resized.len(), r.smaller + r.larger),
        group: None,
        columns: vec![col("x", "mm"), col("y", "mm"), col("z", "mm"), col("ρ", ""), col("Bead at L_s", "mm"), col("Cell", "mm"), col("Bead", "mm")],
        rows: r
            .resized
            .iter()
            .map(|c| TableRow {
                group_index: None,
                cells: vec![
                    c.centre_mm[0].into(),
                    c.centre_mm[1].into(),
                    c.centre_mm[2].into(),
                    c.rho.into(),
                    c.width_at_reference_mm.into(),
                    c.cell_mm.into(),
                    c.width_mm.into(),
                ],
            })
            .collect(),
    });
    s
}

/// The paper's route on the same toolpath: `sliced` written as G-code without grading, its
/// infill moves' E rewritten by the field at their midpoints ([`gcode_edit`]); both routes'
/// per-layer error, measured the same way ([`scaffold::mean_along`]), in one plot.
fn compare(
    j: &GradedJob,
    ctx: &mut Ctx,
    vol: &Out<Volume>,
    sliced: &Out<crate::geom::Toolpath>,
    model: &Model,
    g: &grade::Options,
    offset: DVec3,
) -> Result<(), Error> {
    let native_layers: Vec<LayerStat> = ctx
        .reports
        .iter()
        .find(|r| r.stage == "grade")
        .and_then(|r| serde_json::from_value::<grade::GradeReport>(r.data.clone()).ok())
        .map(|r| r.layers)
        .unwrap_or_default();
    let design = ctx.design;
    let writer = crate::stage::writer_options(design);
    // G-code point = volume point + placement offset + the bed's origin offset.
    let to_volume = -(offset + crate::gcode::bed_offset(&writer));
    let options = gcode_edit::Options {
        rho_s: model.rho_s,
        rho_min: model.rho_min,
        translation_mm: to_volume.to_array(),
        // The target sampled as the native route's grading samples it (its pieces are one step).
        ..edit_options(j, design, [0.0; 3], model.segment_mm / 4.0)
    };
    let parts = (format!("{g:?}"), format!("{options:?}"), &j.density.calibration, &design.printer, &design.material, &design.speeds);
    ctx.stage("compare", "compare", &parts, &[sliced.key, vol.key], |progress| {
        let written = crate::gcode::write_gcode(sliced, &writer).map_err(|e| Error::stage("writing the comparison's G-code", e))?;
        progress(0.3);
        let rho = density_field(j, vol);
        let edited = gcode_edit::edit("compare.gcode", &written.text.as_bytes(), &rho, &options, &mut |x| progress(0.3 + 0.7 * x))
            .map_err(|e| Error::stage("editing the comparison's G-code", e))?;
        let edit_layers = edited.report.layers;
        let mean = |ls: &[LayerStat]| {
            let n: f64 = ls.iter().map(|l| l.length_mm).sum();
            if n > 0.0 {
                ls.iter().map(|l| l.mean_abs_error * l.length_mm).sum::<f64>() / n
            } else {
                0.0
            }
        };
        let (e_native, e_edit) = (mean(&native_layers), mean(&edit_layers));
        let used = |ls: &[LayerStat]| ls.iter().filter(|l| l.moves > 0).map(|l| (l.z_mm, l.mean_abs_error)).unzip::<f64, f64, Vec<f64>, Vec<f64>>();
        let ((zn, en), (ze, ee)) = (used(&native_layers), used(&edit_layers));
        let mut report = StageReport::new(
            "compare",
            "Native against the edit route",
            &CompareReport { native: native_layers.clone(), edit: edit_layers.clone(), edited_moves: edited.report.edited_moves },
        )
        .metric(
            "native_error",
            "Native: mean |achieved − target| ρ",
            e_native,
            "",
            "weft's own grading: segments split to the grading step, each graded by the field at its midpoint.",
        )
        .metric(
            "edit_error",
            "Edit route: mean |achieved − target| ρ",
            e_edit,
            "",
            "The paper's route on the same toolpath: whole moves, each graded by the field at its midpoint.",
        )
        .metric(
            "error_ratio",
            "Edit ÷ native error",
            if e_native > 0.0 { e_edit / e_native } else { 0.0 },
            "×",
            "How many times further from the field the edit route's infill is (0 when native is exact).",
        )
        .metric(
            "edit_moves",
            "Edited moves",
            edited.report.edited_moves as f64,
            "",
            "Infill moves the edit route rewrote (native splits them into more, shorter segments).",
        );
        report.plots.push(Plot {
            key: "error_per_layer".into(),
            title: "Density error per layer: native against edit".into(),
            kind: PlotKind::Line,
            x: Axis::new("Z", "mm"),
            y: Axis::new("Mean |achieved − target| ρ", ""),
            group: None,
            series: vec![Series::xy("native (split)", zn, en), Series::xy("edit (whole moves)", ze, ee)],
        });
        Ok(((), Some(report)))
    })?;
    Ok(())
}

/// Both routes' per-layer density on one toolpath.
#[derive(Serialize)]
struct CompareReport {
    native: Vec<LayerStat>,
    edit: Vec<LayerStat>,
    edited_moves: usize,
}

fn grade_report(r: &grade::GradeReport) -> StageReport {
    let saved = if r.uniform_mm3 > 0.0 { 1.0 - r.infill_mm3 / r.uniform_mm3 } else { 0.0 };
    let mut s = StageReport::new("grade", "Grading the infill", r)
        .metric("segments", "Infill segments", r.segments as f64, "", "Infill segments written, each with its own extrusion.")
        .metric("split", "Added by splitting", r.split_added as f64, "", "Segments cut so none is longer than the grading step.")
        .metric(
            "clamped_low",
            "Raised to ρ_min",
            r.clamped_low as f64,
            "",
            "Segments whose target was below ρ_min (a bead narrower than E_w,min would not hold).",
        )
        .metric("over_flow", "Over Q_max", r.over_flow as f64, "", "Segments needing more melt per second than the hot end gives at the infill speed.")
        .metric("over_width", "Over E_w,max", r.over_width as f64, "", "Segments whose bead would be wider than E_w,max.")
        .metric("outside", "Outside the volume", r.outside as f64, "", "Segments with no CT value under them, printed at ρ_s.")
        .metric("max_width", "Widest bead", r.max_width_mm, "mm", "The widest infill bead written (stadium bead model).")
        .metric("max_flow", "Highest flow", r.max_flow_mm3_s, "mm³/s", "The largest volumetric flow written, at the infill speed.")
        .metric("infill", "Infill material", r.infill_mm3, "mm³", "Infill volume as graded.")
        .metric("saved", "Material saved", saved * 100.0, "%", "Infill material saved against a uniform infill at ρ_s (negative: more material).");
    layer_plots(&mut s, &r.layers);
    s
}

/// Per-layer target and achieved ρ: a plot along Z and a table.
fn layer_plots(s: &mut StageReport, layers: &[LayerStat]) {
    let used: Vec<&LayerStat> = layers.iter().filter(|l| l.moves > 0).collect();
    let z: Vec<f64> = used.iter().map(|l| l.z_mm).collect();
    let n: f64 = used.iter().map(|l| l.length_mm).sum();
    let err = if n > 0.0 { used.iter().map(|l| l.mean_abs_error * l.length_mm).sum::<f64>() / n } else { 0.0 };
    s.metrics.push(crate::report::Metric {
        key: "mean_abs_error".into(),
        label: "Mean |achieved − target| ρ".into(),
        value: err,
        unit: "".into(),
        hint: "Length-weighted over the infill: how far the written density is from the field's mean along each segment.".into(),
        group_index: None,
    });
    s.plots.push(Plot {
        key: "rho_per_layer".into(),
        title: "Mean density per layer".into(),
        kind: PlotKind::Line,
        x: Axis::new("Z", "mm"),
        y: Axis::new("ρ", ""),
        group: None,
        series: vec![
            Series::xy("target", z.clone(), used.iter().map(|l| l.target_mean).collect()),
            Series::xy("achieved", z.clone(), used.iter().map(|l| l.achieved_mean).collect()),
        ],
    });
    let col = |label: &str, unit: &str| Column { label: label.into(), unit: unit.into() };
    s.tables.push(Table {
        key: "layers".into(),
        title: "Density per layer".into(),
        group: None,
        columns: vec![col("Z", "mm"), col("Segments", ""), col("Length", "mm"), col("Target ρ", ""), col("Achieved ρ", ""), col("Mean |error|", "")],
        rows: used
            .iter()
            .map(|l| TableRow {
                group_index: None,
                cells: vec![l.z_mm.into(), l.moves.into(), l.length_mm.into(), l.target_mean.into(), l.achieved_mean.into(), l.mean_abs_error.into()],
            })
            .collect(),
    });
}

/// The edit route's options; its report samples the target every `target_step_mm` along each move.
fn edit_options(j: &GradedJob, design: &Design, translation: [f64; 3], target_step_mm: f64) -> gcode_edit::Options {
    let cell = cell_of(j.slice.infill_pattern);
    let cell_mm = scaffold::cell_size_for_density(cell, j.gcode_rho_s, design.printer.nozzle_diameter_mm, j.slice.layer_height_mm);
    gcode_edit::Options {
        rho_s: j.gcode_rho_s,
        rho_min: scaffold::density_at_width(cell, cell_mm, j.density.min_width_mm, j.slice.layer_height_mm).clamp(0.0, 1.0),
        rho_max: 1.0,
        limit: j.density.limit,
        q_max_mm3_s: j.density.q_max_mm3_s,
        width_max_mm: j.density.max_width_mm,
        filament_mm: design.printer.filament_diameter_mm,
        translation_mm: translation,
        infill_types: j.gcode_infill_types.clone(),
        target_step_mm,
    }
}

/// The target density ρ(p) of the volume (p in the volume's frame, mm; `None` outside it),
/// trilinear in the calibrated voxels; unclamped below: grading raises targets below ρ_min
/// itself and counts them (the paper's pseudocode).
fn density_field<'v>(j: &GradedJob, vol: &'v Volume) -> impl Fn(DVec3) -> Option<f64> + 'v {
    let curve = j.density.calibration.curve();
    let sampler = volume::Sampler::new(vol, move |hu: f32| curve.density(hu as f64, 0.0));
    move |p| sampler.sample(p)
}

fn edit(j: &GradedJob, ctx: &mut Ctx, vol: &Out<Volume>, surface: &Out<isosurface::Surface>) -> Result<Product, Error> {
    let input = j.gcode.as_ref().ok_or_else(|| Error::NoInput("route 'edit' needs another slicer's G-code: load it, or pass --input gcode=FILE".into()))?;
    // Read line by line (a file the page keeps outside wasm memory is never copied in whole).
    let (bytes, key) = ctx.file_source("gcode", input)?;
    let name = match input {
        Input::File { name, .. } => name.clone(),
        _ => "G-code".into(),
    };
    // v⃗: G-code point = volume point + v⃗; the editor adds `translation` to a G-code point.
    let v = match j.alignment.mode {
        AlignMode::Manual => DVec3::from(j.alignment.translation_mm),
        AlignMode::Auto => {
            let printed = gcode_edit::printed_bounds(&name, &bytes).map_err(|e| Error::stage("editing the G-code", e))?;
            let model = surface.mesh.bounds().ok_or_else(|| Error::NoInput("the surface model is empty: lower the isovalue or widen the ROI".into()))?;
            let (pc, mc) = ((printed.min + printed.max) * 0.5, (model.min + model.max) * 0.5);
            DVec3::new(pc.x - mc.x, pc.y - mc.y, -model.min.z)
        }
    };
    // The target along each whole move sampled once per grading step (a voxel): its mean
    // error is within 4 % of sampling every quarter step (0.00384 against 0.00402 on the
    // benchmark's file), at half the edit's time (BENCHMARKS.md).
    let options = edit_options(j, ctx.design, (-v).to_array(), grading_step(j, vol));
    let parts = (format!("{options:?}"), &j.density.calibration);
    let text = ctx.stage("edit", "edit", &parts, &[key, vol.key], |progress| {
        let rho = density_field(j, vol);
        let out = gcode_edit::edit(&name, &bytes, &rho, &options, progress).map_err(|e| Error::stage("editing the G-code", e))?;
        let r = &out.report;
        let saved = if r.infill_before_mm3 > 0.0 { 1.0 - r.infill_after_mm3 / r.infill_before_mm3 } else { 0.0 };
        let mut report = StageReport::new("edit", "Editing the G-code's infill", r)
            .metric("translation_x", "v⃗ x", v.x, "mm", "Alignment: G-code point = volume point + v⃗ (equation 5).")
            .metric("translation_y", "v⃗ y", v.y, "mm", "Alignment, y.")
            .metric("translation_z", "v⃗ z", v.z, "mm", "Alignment, z.")
            .metric("infill_moves", "Infill moves", r.infill_moves as f64, "", "Extruding moves inside the file's infill sections.")
            .metric("edited", "Moves edited", r.edited_moves as f64, "", "Infill moves whose E was rewritten by equation 6.")
            .metric("outside", "Outside the volume", r.outside_field as f64, "", "Infill moves with no CT value at their midpoint: left as they were.")
            .metric("clamped_low", "Raised to ρ_min", r.clamped_low as f64, "", "Moves whose target was below ρ_min.")
            .metric("over_flow", "Over Q_max", r.over_flow as f64, "", "Moves needing more melt per second than the hot end gives.")
            .metric("over_width", "Over E_w,max", r.over_width as f64, "", "Moves whose bead would be wider than E_w,max.")
            .metric(
                "resets",
                "G92 lines added",
                r.resets_inserted as f64,
                "",
                "Absolute-E files: one 'G92 E…' after each run of edited moves keeps every other line's E valid and unchanged.",
            )
            .metric("saved", "Material saved", saved * 100.0, "%", "Infill material saved against the file as sliced (negative: more material).");
        layer_plots(&mut report, &r.layers);
        let text = String::from_utf8(out.text).map_err(|_| Error::NoInput(format!("{name}: the edited G-code is not UTF-8 text")))?;
        Ok((text, Some(report)))
    })?;
    Ok(Product::Gcode(text))
}

/// A slice view: the image in HU, the iso-contours at the design's levels and the ROI box.
fn slice_view(view: &str, vol: &Volume, axis: SliceAxis, index: usize, roi: &Roi, j: &GradedJob) -> Inspection {
    let image = volume::slice_image(vol, axis, index);
    let mut overlay = Vec::new();
    for s in volume::isolines(&image, &j.contour_levels_hu) {
        overlay.extend_from_slice(&s);
    }
    roi_rect(&mut overlay, &image, roi);
    let mut legend: Vec<serde_json::Value> = j
        .contour_levels_hu
        .iter()
        .zip(LEVEL_COLORS)
        .enumerate()
        .map(|(i, (hu, color))| serde_json::json!({"code": i, "label": format!("{} HU", crate::settings::fmt(*hu)), "color": color}))
        .collect();
    legend.push(serde_json::json!({"code": ROI_CODE, "label": "region of interest", "color": ROI_COLOR}));
    let unit = if vol.info.unit.is_empty() { "" } else { vol.info.unit.as_str() };
    // A bone window by default for CT; the data's range otherwise.
    let window = if unit == "HU" { serde_json::json!([-400.0, 1600.0]) } else { serde_json::Value::Null };
    let axis_name = ["x (i)", "y (j)", "z (k)"][match axis {
        SliceAxis::Axial => 2,
        SliceAxis::Coronal => 1,
        SliceAxis::Sagittal => 0,
    }];
    Inspection {
        view: view.into(),
        shape: Shape::Image,
        index: image.index,
        count: image.count,
        stride: 1,
        data: image.values,
        overlay,
        meta: serde_json::json!({
            "width": image.width, "height": image.height, "pixel_mm": image.pixel_mm, "window": window, "unit": unit,
            "caption": format!("{axis_name} = {:.1} mm", image.position_mm),
            "overlay_legend": legend,
        }),
    }
}

/// The ROI's outline on a slice (when the slice crosses the ROI), in the image's mm frame.
fn roi_rect(out: &mut Vec<f32>, image: &volume::SliceImage, roi: &Roi) {
    // Image x, y and the fixed axis, as volume axes.
    let (ax, ay, fixed) = match image.axis {
        SliceAxis::Axial => (0, 1, 2),
        SliceAxis::Coronal => (0, 2, 1),
        SliceAxis::Sagittal => (1, 2, 0),
    };
    if image.position_mm < roi.min_mm[fixed] - 1e-9 || image.position_mm > roi.max_mm[fixed] + 1e-9 {
        return;
    }
    let (x0, x1, y0, y1) = (roi.min_mm[ax] as f32, roi.max_mm[ax] as f32, roi.min_mm[ay] as f32, roi.max_mm[ay] as f32);
    let c = ROI_CODE as f32;
    out.extend_from_slice(&[x0, y0, x1, y0, c, x1, y0, x1, y1, c, x1, y1, x0, y1, c, x0, y1, x0, y0, c]);
}

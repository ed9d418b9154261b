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

mod beads;
mod checks;
mod form;
mod report;
mod settings;
mod stages;
mod steps;
mod views;
use beads::*;
pub use beads::{infill_widths, width_bin, UNGRADED_CODE, WIDTH_CODES};
use checks::*;
use form::*;
use report::*;
pub use settings::*;
use stages::*;
use views::*;

use super::{Inspection, Kind, Product, Shape, Slot, SlotKind, StageInfo, StepInfo, Teach, ViewInfo};
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
        card: true,
        stage: "volume",
        label: "Axial slices",
        shape: Shape::Image,
        index_label: "Slice",
        doc: "The volume across k (HU), with iso-contours and the region of interest.",
    },
    ViewInfo {
        id: "coronal",
        card: true,
        stage: "volume",
        label: "Coronal slices",
        shape: Shape::Image,
        index_label: "Slice",
        doc: "The volume across j (HU), with iso-contours and the region of interest.",
    },
    ViewInfo {
        id: "sagittal",
        card: true,
        stage: "volume",
        label: "Sagittal slices",
        shape: Shape::Image,
        index_label: "Slice",
        doc: "The volume across i (HU), with iso-contours and the region of interest.",
    },
    ViewInfo {
        id: "density",
        card: true,
        stage: "density",
        label: "Target density",
        shape: Shape::Image,
        index_label: "Slice",
        doc: "The relative density the infill is graded to (1 − P(HU), clamped to [ρ_min, 1]), axial slices of the ROI.",
    },
    ViewInfo {
        id: "surface",
        card: true,
        stage: "surface",
        label: "Surface model",
        shape: Shape::Mesh,
        index_label: "View",
        doc: "The closed mesh marching cubes extracted at the isovalue inside the ROI (volume frame, mm).",
    },
    ViewInfo {
        id: "hu",
        card: false,
        stage: "volume",
        label: "HU in the region of interest",
        shape: Shape::Image,
        index_label: "ROI slice",
        doc: "The axial slices the ROI spans, in HU inside the ROI (windowed to its range), with the iso-contours.",
    },
    ViewInfo {
        id: "beads",
        card: false,
        stage: "grade",
        label: "Bead width along a layer",
        shape: Shape::Lines2d,
        index_label: "Layer",
        doc: "One layer of the graded toolpath (native route), each infill segment coloured by its bead width's bin (mm); perimeters in grey.",
    },
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
    const STEPS: &'static [StepInfo] = steps::STEPS;
    /// Opens coloured by ΔE per mm: the bead's cross-section, which the CT's density scales.
    const TEACH: Teach = Teach { color_by: "e_per_mm", backdrop: None };

    fn fields() -> Vec<Row> {
        rows()
    }

    fn validate(design: &Design, j: &GradedJob, out: &mut Vec<Problem>) {
        validate(design, j, out)
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
        estimate(j, ctx)
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
        inspect(j, ctx, view, index)
    }
}

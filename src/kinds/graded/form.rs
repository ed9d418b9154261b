//! The graded job's form: one row per setting of the job, the region of interest and the density map.

use super::*;

pub(super) const JOB_FIELDS: &[Field] = &[
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

pub(super) const ROI_FIELDS: &[Field] = &[
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

pub(super) const DENSITY_FIELDS: &[Field] = &[
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

/// The form's rows (`Kind::fields`), mounted at their design paths.
pub(super) fn rows() -> Vec<Row> {
    let mut rows = mount("job", JOB_FIELDS);
    rows.extend(mount("job.raw", volume::RAW_FIELDS));
    rows.extend(mount("job.roi", ROI_FIELDS));
    rows.extend(mount("job.surface", isosurface::FIELDS));
    rows.extend(mount("job.density", DENSITY_FIELDS));
    rows.extend(mount("job.slice", slice::FIELDS));
    rows.extend(mount("job.slice", slice::support::FIELDS));
    rows
}

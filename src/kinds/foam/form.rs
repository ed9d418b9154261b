//! The foam job's form: one row per setting, with the indexed rows of each region and transition.

use super::*;

pub(super) const OPTION_FIELDS: &[Row0] = &[
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

pub(super) const REGION_V: [&str; MAX_REGIONS] =
    ["Region 1: V*", "Region 2: V*", "Region 3: V*", "Region 4: V*", "Region 5: V*", "Region 6: V*", "Region 7: V*", "Region 8: V*"];
pub(super) const REGION_SET: [&str; MAX_REGIONS] = [
    "Region 1: set by",
    "Region 2: set by",
    "Region 3: set by",
    "Region 4: set by",
    "Region 5: set by",
    "Region 6: set by",
    "Region 7: set by",
    "Region 8: set by",
];
pub(super) const REGION_E: [&str; MAX_REGIONS] = [
    "Region 1: modulus",
    "Region 2: modulus",
    "Region 3: modulus",
    "Region 4: modulus",
    "Region 5: modulus",
    "Region 6: modulus",
    "Region 7: modulus",
    "Region 8: modulus",
];
pub(super) const REGION_H: [&str; MAX_REGIONS] =
    ["Region 1: H*", "Region 2: H*", "Region 3: H*", "Region 4: H*", "Region 5: H*", "Region 6: H*", "Region 7: H*", "Region 8: H*"];
pub(super) const T_FROM: [&str; MAX_TRANSITIONS] = [
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
pub(super) fn indexed_rows() -> Vec<Row> {
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

/// The form's rows (`Kind::fields`), mounted at their design paths.
pub(super) fn rows() -> Vec<Row> {
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

//! The freeform job's form: one row per setting, in the design's sections.

use super::*;

pub(super) const DESIGN_FIELDS: &[Row0] = &[
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

pub(super) const NOZZLE_FIELDS: &[Row0] = &[
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

pub(super) const BEAM_FIELDS: &[Row0] = &[
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

pub(super) const CONSTRAINT_FIELDS: &[Row0] = &[
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

pub(super) const PLANNER_FIELDS: &[Row0] = &[
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

pub(super) const PRINT_FIELDS: &[Row0] = &[
    num("speed_mm_s", "Printing", "Beam speed", "mm/s", 0.01, 200.0, 0.1, "Speed of the nozzle along a beam while extruding (the paper's 0.4 mm/s)."),
    num("dwell_s", "Printing", "Dwell at joints", "s", 0.0, 60.0, 0.1, "Time the nozzle waits at a beam's end joint so it fuses."),
    num("clearance_mm", "Printing", "Deadhead clearance", "mm", 0.0, 100.0, 0.5, "How far above the highest printed beam the nozzle moves between beams."),
];

/// The form's rows (`Kind::fields`), mounted at their design paths.
pub(super) fn rows() -> Vec<Row> {
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

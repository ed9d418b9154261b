//! The axisymmetric job's form: one row per setting of the platform, the domain and the job.

use super::*;

pub(super) const PLATFORM_FIELDS: &[Field] = &[
    choice_docs(
        other(
            "preset",
            "Build platform",
            "Platform",
            FieldKind::Choice,
            &["barrel", "hourglass", "custom"],
            "The curved surface printed on, revolved about Z.",
        ),
        &[
            "The paper's barrel (table 2): 50 mm tall, radius 25 mm at u = 1.",
            "The paper's hourglass (table 3): 100 mm tall, a 25 mm neck at u = 2.",
            "Your own control polygon (below).",
        ],
    ),
    when(
        points(
            "control_points",
            "Build platform",
            "Control points x z",
            "mm",
            -10000.0,
            10000.0,
            6 * 64 + 1,
            "6·k + 1 points (x = radius, z = height), one pair per line: each 7 make a degree-6 Bézier segment, the next starts at the last.",
        ),
        "preset",
        "custom",
    ),
];

pub(super) const DOMAIN_FIELDS: &[Field] = &[
    choice_docs(
        other(
            "kind",
            "Domain Ω",
            "Domain",
            FieldKind::Choice,
            &["rectangle", "polygon", "part"],
            "The patch of the platform to fill, in the embedded map (u along the profile, θ around the axis).",
        ),
        &[
            "A u × θ rectangle.",
            "An outline of (u, θ) corners, optionally with holes.",
            "Where a loaded part meets the platform (its largest outline and the holes in it).",
        ],
    ),
    when(
        num("u_min", "Domain Ω", "u from", "", 0.0, 64.0, 0.01, "Where the patch starts along the profile (u counts Bézier segments: 0 to their number)."),
        "kind",
        "rectangle",
    ),
    when(num("u_max", "Domain Ω", "u to", "", 0.0, 64.0, 0.01, "Where the patch ends along the profile."), "kind", "rectangle"),
    when(num("theta_min_rad", "Domain Ω", "θ from", "rad", -7.0, 7.0, 0.01, "Where the patch starts around the axis."), "kind", "rectangle"),
    when(
        num(
            "theta_max_rad",
            "Domain Ω",
            "θ to",
            "rad",
            -7.0,
            7.0,
            0.01,
            "Where the patch ends around the axis (at most one turn, 6.283 rad, wider than the start).",
        ),
        "kind",
        "rectangle",
    ),
    when(
        points(
            "polygon",
            "Domain Ω",
            "Polygon u θ",
            "",
            -64.0,
            64.0,
            1000,
            "The outline's corners, one 'u θ' pair per line (θ in rad), in order; concave outlines are fine.",
        ),
        "kind",
        "polygon",
    ),
    when(
        rings(
            "holes",
            "Domain Ω",
            "Holes u θ",
            "",
            -64.0,
            64.0,
            1000,
            "Openings left empty inside the outline: each hole's corners one 'u θ' pair per line, a blank line between holes.",
        ),
        "kind",
        "polygon",
    ),
];

pub(super) const JOB_FIELDS: &[Field] = &[
    num(
        "layer_height_mm",
        "Path",
        "Layer height",
        "mm",
        0.01,
        5.0,
        0.01,
        "How thick the strand is: the nozzle tip rides this far out along the surface normal.",
    ),
    int(
        "layers",
        "Path",
        "Layers",
        1.0,
        MAX_LAYERS as f64,
        "How many layers to stack: each lies one layer height further out along the normal, with its own points and path.",
    ),
];

/// The form's rows (`Kind::fields`), mounted at their design paths.
pub(super) fn rows() -> Vec<Row> {
    let mut rows = mount("job.platform", PLATFORM_FIELDS);
    rows.extend(mount("job.domain", DOMAIN_FIELDS));
    rows.extend(mount("job.points", uniform::FIELDS));
    rows.extend(mount("job.path", tour::FIELDS));
    rows.extend(mount("job", JOB_FIELDS));
    rows.extend(mount("job.tool_axis", dynamics::FIELDS));
    rows
}

//! The field table: one row per editable design field with its unit, range and help.
//! The page builds its form from it ([`schema_json`]) and [`validate`] checks ranges with it,
//! so the two can never disagree.

use super::{Design, Job, Problem};
use serde::Serialize;
use serde_json::Value;

/// How a field is edited.
#[derive(Clone, Copy, Debug, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Kind {
    /// A real number.
    Number,
    /// A whole number.
    Integer,
    /// On/off.
    Bool,
    /// Free text (multi-line for G-code templates).
    Text,
    /// One of `choices`.
    Choice,
    /// Three numbers (X, Y, Z).
    Vec3,
    /// An optional block, present or absent (a checkbox); `default` is its JSON when switched on.
    Section,
}

/// One editable field.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Field {
    /// Dotted path in the design JSON.
    pub path: &'static str,
    /// Form section.
    pub section: &'static str,
    /// Label shown in the form.
    pub label: &'static str,
    /// Unit shown after the input ("" when none).
    pub unit: &'static str,
    /// Editor kind.
    pub kind: Kind,
    /// Smallest allowed value (numbers, each Vec3 component).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub min: Option<f64>,
    /// Largest allowed value.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max: Option<f64>,
    /// Form step.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub step: Option<f64>,
    /// Allowed values of a choice.
    #[serde(skip_serializing_if = "<[_]>::is_empty")]
    pub choices: &'static [&'static str],
    /// Help text.
    pub doc: &'static str,
    /// Only for this job kind.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub job: Option<&'static str>,
    /// JSON value a [`Kind::Section`] takes when switched on.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub default: Option<&'static str>,
    /// Shown only while another field has a given value (e.g. pneumatic settings only for the
    /// pneumatic flavour).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub when: Option<When>,
}

/// A condition on another field's value.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct When {
    /// Dotted path of the other field.
    pub path: &'static str,
    /// The value it must have (as written in JSON).
    pub equals: &'static str,
}

const fn when(mut f: Field, path: &'static str, equals: &'static str) -> Field {
    f.when = Some(When { path, equals });
    f
}

#[allow(clippy::too_many_arguments)] // a table row constructor: one argument per column
const fn num(path: &'static str, section: &'static str, label: &'static str, unit: &'static str, min: f64, max: f64, step: f64, doc: &'static str) -> Field {
    Field { path, section, label, unit, kind: Kind::Number, min: Some(min), max: Some(max), step: Some(step), choices: &[], doc, job: None, default: None, when: None }
}
const fn int(path: &'static str, section: &'static str, label: &'static str, min: f64, max: f64, doc: &'static str) -> Field {
    Field { path, section, label, unit: "", kind: Kind::Integer, min: Some(min), max: Some(max), step: Some(1.0), choices: &[], doc, job: None, default: None, when: None }
}
const fn other(path: &'static str, section: &'static str, label: &'static str, kind: Kind, choices: &'static [&'static str], doc: &'static str) -> Field {
    Field { path, section, label, unit: "", kind, min: None, max: None, step: None, choices, doc, job: None, default: None, when: None }
}
const fn for_job(mut f: Field, job: &'static str) -> Field {
    f.job = Some(job);
    f
}

/// Every editable field, in form order.
pub const FIELDS: &[Field] = &[
    other("name", "Design", "Name", Kind::Text, &[], "Used for the downloaded file name."),
    int("seed", "Design", "Random seed", 0.0, 9.007199254740991e15, "Seeds every random choice: the same seed gives the same G-code."),
    other("printer.name", "Printer", "Profile name", Kind::Text, &[], "Shown in the G-code header."),
    Field { unit: "mm", min: Some(10.0), max: Some(2000.0), step: Some(1.0), ..other("printer.bed_size_mm", "Printer", "Bed size X, Y, Z", Kind::Vec3, &[], "Printable volume.") },
    other("printer.origin", "Printer", "Origin", Kind::Choice, &["corner", "center"], "Where X = Y = 0 is: front-left corner (Cartesian) or bed centre (delta)."),
    num("printer.nozzle_diameter_mm", "Printer", "Nozzle diameter", "mm", 0.05, 3.0, 0.01, "d_n in GIPPO equation 4."),
    num("printer.filament_diameter_mm", "Printer", "Filament diameter", "mm", 0.5, 5.0, 0.01, "f_d in GIPPO equation 4."),
    other("printer.flavor", "Printer", "G-code flavour", Kind::Choice, &["marlin", "pneumatic"], "marlin: FDM G-code; pneumatic: .nc for pneumatic (bio)printers, valve on/off and pressure per path."),
    when(other("printer.pneumatic.valve_on", "Printer", "Valve on (pneumatic)", Kind::Text, &[], "Line(s) that start the flow of each path."), "printer.flavor", "pneumatic"),
    when(other("printer.pneumatic.valve_off", "Printer", "Valve off (pneumatic)", Kind::Text, &[], "Line(s) that stop the flow after each path."), "printer.flavor", "pneumatic"),
    when(other("printer.pneumatic.pressure_template", "Printer", "Pressure code (pneumatic)", Kind::Text, &[], "{pressure_kpa} is replaced; empty: no pressure line."), "printer.flavor", "pneumatic"),
    when(num("printer.pneumatic.pressure_kpa", "Printer", "Pressure (pneumatic)", "kPa", 0.0, 100000.0, 1.0, ""), "printer.flavor", "pneumatic"),
    when(num("printer.pneumatic.short_path_pressure_factor", "Printer", "Short-path pressure (pneumatic)", "×", 0.01, 10.0, 0.05, "Multiplies the pressure of slowed-down short paths."), "printer.flavor", "pneumatic"),
    other("printer.relative_e", "Printer", "Relative extrusion (M83)", Kind::Bool, &[], "Off: absolute E (M82)."),
    num("printer.retraction.length_mm", "Printer", "Retraction length", "mm", 0.0, 20.0, 0.05, "0 disables retraction."),
    num("printer.retraction.speed_mm_s", "Printer", "Retraction speed", "mm/s", 1.0, 200.0, 1.0, ""),
    num("printer.retraction.z_hop_mm", "Printer", "Z-hop", "mm", 0.0, 10.0, 0.05, "Lift during retracted travels."),
    num("printer.retraction.min_travel_mm", "Printer", "Retract only above", "mm", 0.0, 100.0, 0.1, "Shorter travels are not retracted."),
    num("printer.travel_speed_mm_s", "Printer", "Travel speed", "mm/s", 1.0, 1000.0, 1.0, ""),
    num("printer.z_speed_mm_s", "Printer", "Z speed", "mm/s", 0.1, 100.0, 0.1, ""),
    num("printer.acceleration_mm_s2", "Printer", "Acceleration", "mm/s²", 10.0, 50000.0, 10.0, "Used for time estimates."),
    other("printer.start_gcode", "Printer", "Start G-code", Kind::Text, &[], "Placeholders: {nozzle_temp_c} {first_layer_nozzle_temp_c} {bed_temp_c} {bed_x_mm} {bed_y_mm} {fan_pwm} {design_name}."),
    other("printer.end_gcode", "Printer", "End G-code", Kind::Text, &[], "Same placeholders as the start G-code."),
    other("material.name", "Material", "Material", Kind::Text, &[], ""),
    num("material.nozzle_temp_c", "Material", "Nozzle temperature", "°C", 0.0, 500.0, 1.0, ""),
    num("material.first_layer_nozzle_temp_c", "Material", "First-layer nozzle temperature", "°C", 0.0, 500.0, 1.0, ""),
    num("material.bed_temp_c", "Material", "Bed temperature", "°C", 0.0, 150.0, 1.0, ""),
    num("material.fan_percent", "Material", "Fan", "%", 0.0, 100.0, 1.0, ""),
    int("material.fan_start_layer", "Material", "Fan from layer", 0.0, 1000.0, "0-based layer index."),
    num("material.extrusion_multiplier", "Material", "Extrusion multiplier EM", "", 0.1, 3.0, 0.01, "EM in GIPPO equation 4."),
    num("material.k", "Material", "Cross-section correction k", "", 0.1, 3.0, 0.01, "k in GIPPO equation 4 (elliptical rather than rectangular strands)."),
    when(num("material.flow.pre_flow_mm", "Material", "Pre-flow", "mm", 0.0, 50.0, 0.01, "Filament pushed at each path start (Marlin)."), "printer.flavor", "marlin"),
    when(num("material.flow.post_flow_mm", "Material", "Post-flow", "mm", 0.0, 50.0, 0.01, "Filament pushed at each path end (Marlin)."), "printer.flavor", "marlin"),
    when(num("material.flow.pre_flow_s", "Material", "Pre-flow time", "s", 0.0, 60.0, 0.01, "Valve open before moving (pneumatic)."), "printer.flavor", "pneumatic"),
    when(num("material.flow.post_flow_s", "Material", "Post-flow time", "s", 0.0, 60.0, 0.01, "Valve closed this long before the path end (pneumatic)."), "printer.flavor", "pneumatic"),
    num("speeds.external_perimeter_mm_s", "Speeds", "External perimeter", "mm/s", 1.0, 500.0, 1.0, ""),
    num("speeds.perimeter_mm_s", "Speeds", "Perimeters", "mm/s", 1.0, 500.0, 1.0, ""),
    num("speeds.infill_mm_s", "Speeds", "Infill", "mm/s", 1.0, 500.0, 1.0, ""),
    num("speeds.solid_infill_mm_s", "Speeds", "Solid infill", "mm/s", 1.0, 500.0, 1.0, ""),
    num("speeds.lattice_mm_s", "Speeds", "Lattice", "mm/s", 1.0, 500.0, 1.0, ""),
    num("speeds.first_layer_mm_s", "Speeds", "First layer", "mm/s", 1.0, 500.0, 1.0, ""),
    for_job(num("job.slice.first_layer_height_mm", "Slicing", "First layer height", "mm", 0.01, 2.0, 0.01, ""), "slice"),
    for_job(num("job.slice.layer_height_mm", "Slicing", "Layer height", "mm", 0.01, 2.0, 0.01, "LT in GIPPO equation 4."), "slice"),
    for_job(int("job.slice.perimeters", "Slicing", "Perimeters", 0.0, 50.0, "Loops around each region."), "slice"),
    for_job(num("job.slice.line_width_mm", "Slicing", "Line width", "mm", 0.05, 5.0, 0.01, "Width of perimeters and infill."), "slice"),
    for_job(num("job.slice.infill_density", "Slicing", "Infill density", "", 0.0, 1.0, 0.05, "0 = hollow, 1 = solid."), "slice"),
    for_job(num("job.slice.infill_angle_deg", "Slicing", "Infill angle", "°", -360.0, 360.0, 1.0, "Odd layers add 90°."), "slice"),
    for_job(int("job.slice.solid_layers", "Slicing", "Solid layers (top and bottom)", 0.0, 1000.0, ""), "slice"),
    for_job(num("job.slice.gap_closing_mm", "Slicing", "Gap closing", "mm", 0.0, 5.0, 0.01, "Open contour ends closer than this are joined."), "slice"),
    for_job(other("job.domain.kind", "Domain", "Domain", Kind::Choice, &["rectangle", "disc", "tensile_specimen", "solid"], "Where the lattice goes: a built-in shape, or the layers of a loaded solid."), "lattice"),
    for_job(num("job.domain.width_mm", "Domain", "Width", "mm", 0.1, 2000.0, 0.1, ""), "lattice"),
    for_job(num("job.domain.height_mm", "Domain", "Height", "mm", 0.1, 2000.0, 0.1, ""), "lattice"),
    for_job(num("job.domain.diameter_mm", "Domain", "Diameter", "mm", 0.1, 2000.0, 0.1, ""), "lattice"),
    for_job(num("job.domain.length_mm", "Domain", "Lattice length", "mm", 0.1, 2000.0, 0.1, "Between the handles."), "lattice"),
    for_job(num("job.domain.handle_length_mm", "Domain", "Handle length", "mm", 0.1, 1000.0, 0.1, "Solid handle at each end."), "lattice"),
    for_job(other("job.lattice.pattern.kind", "Lattice", "Pattern", Kind::Choice, PATTERNS, "The atlas pattern."), "lattice"),
    for_job(num("job.lattice.pattern.hexagon_radius_mm", "Lattice", "Hexagon radius", "mm", 0.05, 1000.0, 0.05, ""), "lattice"),
    for_job(num("job.lattice.pattern.density_per_mm2", "Lattice", "Seed points", "/mm²", 0.0001, 100.0, 0.01, "Voronoi seed points per mm² (placed by the random seed)."), "lattice"),
    for_job(num("job.lattice.pattern.cell_size_mm", "Lattice", "Cell size", "mm", 0.05, 1000.0, 0.05, ""), "lattice"),
    for_job(num("job.lattice.pattern.cell_width_mm", "Lattice", "Unit-cell width", "mm", 0.05, 1000.0, 0.05, ""), "lattice"),
    for_job(num("job.lattice.pattern.cell_height_mm", "Lattice", "Unit-cell height", "mm", 0.05, 1000.0, 0.05, ""), "lattice"),
    for_job(num("job.lattice.pattern.strand_distance_mm", "Lattice", "Strand distance", "mm", 0.05, 1000.0, 0.05, "Centre to centre."), "lattice"),
    for_job(num("job.lattice.layer_thickness_mm", "Lattice", "Layer thickness", "mm", 0.01, 2.0, 0.001, "LT in GIPPO equation 4."), "lattice"),
    for_job(int("job.lattice.layers", "Lattice", "Layers", 1.0, 10000.0, "Ignored for a solid domain (it has as many as it slices to)."), "lattice"),
    for_job(num("job.lattice.rotation_deg", "Lattice", "Rotation per layer", "°", -360.0, 360.0, 1.0, ""), "lattice"),
    for_job(other("job.lattice.contour", "Lattice", "Add the contour", Kind::Bool, &[], "Print each region's outline, joined into the graph."), "lattice"),
    for_job(other("job.paths.method", "Paths", "Optimiser", Kind::Choice, &["gippo_max", "gippo_min", "euler", "continuous"], "gippo_*: the paper's randomised search; euler: the proven minimum number of paths; continuous: one nozzle path per component."), "lattice"),
    for_job(int("job.paths.iterations", "Paths", "GIPPO iterations", 1.0, 100000.0, "The paper uses 500."), "lattice"),
    for_job(other("job.paths.order", "Paths", "Path order", Kind::Choice, &["longest_first", "min_travel"], "longest_first is the paper's."), "lattice"),
    for_job(num("job.paths.merge_tolerance_mm", "Paths", "Node merge tolerance", "mm", 0.0001, 1.0, 0.001, ""), "lattice"),
    for_job(int("job.paths.short_path_segments", "Paths", "Short path below", 0.0, 1000.0, "Paths with fewer segments are slowed down (the paper: 4)."), "lattice"),
    for_job(num("job.paths.short_path_speed_factor", "Paths", "Short path speed", "×", 0.01, 1.0, 0.05, "The paper: 0.6."), "lattice"),
    Field { default: Some("{\"surface\":{\"kind\":\"sphere\"}}"), ..for_job(other("job.nonplanar", "Non-planar", "Print on a surface", Kind::Section, &[], "Project every layer onto a surface along Z."), "lattice") },
    for_job(other("job.nonplanar.surface.kind", "Non-planar", "Surface", Kind::Choice, &["sphere", "cylinder", "mesh"], "mesh: the loaded surface file."), "lattice"),
    for_job(num("job.nonplanar.surface.radius_mm", "Non-planar", "Radius", "mm", 0.1, 10000.0, 0.1, ""), "lattice"),
    Field { unit: "mm", min: Some(-10000.0), max: Some(10000.0), step: Some(0.1), ..for_job(other("job.nonplanar.surface.center_mm", "Non-planar", "Centre X, Y, Z", Kind::Vec3, &[], ""), "lattice") },
    for_job(num("job.nonplanar.surface.axis_z_mm", "Non-planar", "Axis height", "mm", -10000.0, 10000.0, 0.1, "The cylinder lies along X."), "lattice"),
    for_job(num("job.nonplanar.max_segment_mm", "Non-planar", "Longest segment", "mm", 0.01, 10.0, 0.01, "Segments are split so Z follows the surface."), "lattice"),
    Field { unit: "mm", min: Some(0.01), max: Some(2000.0), step: Some(0.1), ..other("job.input.builtin.size", "Input", "Cube size X, Y, Z", Kind::Vec3, &[], "") },
    Field { unit: "mm", min: Some(0.01), max: Some(1000.0), step: Some(0.1), ..other("job.input.builtin.radius", "Input", "Radius", Kind::Number, &[], "") },
    Field { unit: "mm", min: Some(0.01), max: Some(2000.0), step: Some(0.1), ..other("job.input.builtin.height", "Input", "Height", Kind::Number, &[], "") },
    Field { unit: "mm", min: Some(0.0), max: Some(2000.0), step: Some(0.1), ..other("job.input.builtin.dish_depth", "Input", "Dish depth", Kind::Number, &[], "Depth of the concave top at the centre.") },
    Field { min: Some(8.0), max: Some(512.0), step: Some(1.0), ..other("job.input.builtin.segments", "Input", "Facets around", Kind::Integer, &[], "") },
];

/// Built-in shapes offered in the form.
pub const BUILTIN_SHAPES: &[&str] = &["cube", "sphere", "cylinder", "concave_cylinder"];
/// The lattice atlas.
pub const PATTERNS: &[&str] = &[
    "honeycomb", "voronoi", "penrose", "snub_square", "arrowhead", "reentrant_honeycomb", "rectilinear", "square_grid", "triangle_grid",
];
/// Job kinds.
pub const JOB_KINDS: &[&str] = &["slice", "lattice"];

/// The schema as JSON for the page.
pub fn schema_json() -> String {
    #[derive(Serialize)]
    struct Schema {
        version: u32,
        fields: &'static [Field],
        job_kinds: &'static [&'static str],
        builtin_shapes: &'static [&'static str],
        patterns: &'static [&'static str],
    }
    serde_json::to_string(&Schema { version: super::DESIGN_VERSION, fields: FIELDS, job_kinds: JOB_KINDS, builtin_shapes: BUILTIN_SHAPES, patterns: PATTERNS })
        .unwrap_or_default()
}

fn lookup<'a>(root: &'a Value, path: &str) -> Option<&'a Value> {
    path.split('.').try_fold(root, |v, key| v.get(key))
}

fn fmt(x: f64) -> String {
    if x.abs() >= 1e15 { format!("{x:e}") } else { format!("{x}") }
}

fn check_number(path: &str, v: f64, f: &Field, out: &mut Vec<Problem>) {
    let (lo, hi) = (f.min.unwrap_or(f64::MIN), f.max.unwrap_or(f64::MAX));
    if !v.is_finite() || v < lo || v > hi {
        let unit = if f.unit.is_empty() { String::new() } else { format!(" {}", f.unit) };
        out.push(Problem {
            path: path.to_string(),
            message: format!("{} is out of range: allowed {} to {}{unit}", fmt(v), fmt(lo), fmt(hi)),
        });
    }
}

/// Range checks from [`FIELDS`] plus the rules that tie fields together.
pub fn validate(design: &Design) -> Vec<Problem> {
    let mut out = Vec::new();
    let Ok(root) = serde_json::to_value(design) else { return out };
    let kind = design.job.kind();
    for f in FIELDS {
        if f.job.is_some_and(|j| j != kind) {
            continue;
        }
        let Some(v) = lookup(&root, f.path) else { continue };
        match f.kind {
            Kind::Number | Kind::Integer => {
                if let Some(x) = v.as_f64() {
                    check_number(f.path, x, f, &mut out);
                }
            }
            Kind::Vec3 => {
                if let Some(items) = v.as_array() {
                    for (i, x) in items.iter().enumerate() {
                        if let Some(x) = x.as_f64() {
                            check_number(&format!("{}.{i}", f.path), x, f, &mut out);
                        }
                    }
                }
            }
            _ => {}
        }
    }
    if design.name.trim().is_empty() {
        out.push(Problem { path: "name".into(), message: "is empty: give the design a name".into() });
    }
    let nozzle = design.printer.nozzle_diameter_mm;
    match &design.job {
        Job::Slice(j) => {
            let s = &j.slice;
            for (path, h) in [("job.slice.layer_height_mm", s.layer_height_mm), ("job.slice.first_layer_height_mm", s.first_layer_height_mm)] {
                if h > nozzle {
                    out.push(Problem {
                        path: path.into(),
                        message: format!("{} mm is thicker than the {} mm nozzle: use at most the nozzle diameter", fmt(h), fmt(nozzle)),
                    });
                }
            }
            if let super::Input::File { name, .. } = &j.input {
                if name.trim().is_empty() {
                    out.push(Problem { path: "job.input.file.name".into(), message: "is empty: name the mesh file to slice".into() });
                }
            }
        }
        Job::Lattice(j) => {
            let t = j.lattice.layer_thickness_mm;
            if t > nozzle {
                out.push(Problem {
                    path: "job.lattice.layer_thickness_mm".into(),
                    message: format!("{} mm is thicker than the {} mm nozzle: use at most the nozzle diameter", fmt(t), fmt(nozzle)),
                });
            }
            if j.domain == crate::lattice::Domain::Solid && j.input.is_none() {
                out.push(Problem { path: "job.input".into(), message: "a solid domain needs a solid: load a mesh or set job.input".into() });
            }
            if let Some(np) = &j.nonplanar {
                if np.surface == crate::nonplanar::Surface::Mesh && j.surface_input.is_none() {
                    out.push(Problem { path: "job.surface_input".into(), message: "a mesh surface needs a mesh: load the surface file or set job.surface_input".into() });
                }
            }
            for o in &j.lattice.overrides {
                if o.layer >= j.lattice.layers && j.domain != crate::lattice::Domain::Solid {
                    out.push(Problem {
                        path: "job.lattice.overrides".into(),
                        message: format!("layer {} does not exist (the lattice has {} layers, numbered from 0)", o.layer, j.lattice.layers),
                    });
                }
            }
        }
    }
    out
}

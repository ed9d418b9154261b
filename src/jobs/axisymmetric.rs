//! The `axisymmetric` job (Guzman-Bautista et al. 2025): quasi-uniform infill points on a
//! curved, axisymmetric build platform, joined by one geodesic path, printed by a 5-axis head
//! whose tool axis follows the surface normal.
//!
//! Stages: `platform` (the generatrix checked: C³ at the knots, no cusps or self-intersections,
//! pole clearance; κ, metric and Christoffel symbols plotted along u), `points` (N from the
//! paper's equation 4, a seed by EBNS / ERE / GBNS, geodesic repulsion energy; the validation
//! metrics of section 2.5 for the seed and the result), `path` (nearest neighbour + 2-opt,
//! each segment the geodesic between its points, on the surface offset by the layer height).
//! The writer gets one free pass per layer with a tool axis per point: the printer must be
//! 5-axis (the `five-axis-head` profile), or write the poses CSV flavour.
//!
//! Beyond the paper: the polygon domain may have holes (the points and the path keep out of
//! them), and `layers` > 1 stacks layers: layer k (0-based) spreads its own points on the
//! platform offset by k·h along its normal ([`crate::axisym::offset`], the top of the layer
//! below) with its own domain (the same (u, θ) region, or for a part the contour at that
//! offset), seeded from the design seed and k; its path starts nearest where layer k − 1's
//! ended, and its tip rides (k + 1)·h out along the normal. Layer 0 is exactly the one-layer
//! job (its stage ids, seed and bytes).

use super::{Inspection, Kind, Product, Shape, Slot, SlotKind, StageInfo, ViewInfo};
use crate::axisym::contour;
use crate::axisym::domain::Domain;
use crate::axisym::offset::Offset;
use crate::axisym::platform::{self, Platform, Profile};
use crate::axisym::{dynamics, surface::Surface, tour, uniform};
use crate::design::{Design, Input};
use crate::geom::{DVec3, Feature, Pass, PassKind, Path, PointData, Toolpath};
use crate::report::{Axis, Plot, PlotKind, Series, StageReport};
use crate::settings::{choice_docs, int, mount, num, other, points, rings, when, Field, Kind as FieldKind, Problem, Row};
use crate::stage::{Ctx, Error, Out};
use serde::{Deserialize, Serialize};

/// The printer profile a design switching to this kind gets when its machine cannot tilt.
pub const FIVE_AXIS_PRESET: &str = "five-axis-head";

/// Default layer height: the strand's thickness over the platform, mm (the tip rides this far
/// out along the normal).
pub const DEFAULT_LAYER_HEIGHT_MM: f64 = 0.2;
/// Default number of layers (the paper's single layer).
pub const DEFAULT_LAYERS: usize = 1;
/// Most layers a job may stack (each is a full point spreading and tour).
pub const MAX_LAYERS: usize = 100;

/// Settings of an `axisymmetric` job.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AxisymJob {
    /// The build platform.
    #[serde(default)]
    pub platform: PlatformSpec,
    /// The domain Ω in the embedded map (u, θ).
    #[serde(default)]
    pub domain: DomainSpec,
    /// Uniform points: density, seed, repulsion.
    #[serde(default)]
    pub points: uniform::Options,
    /// The path through the points.
    #[serde(default)]
    pub path: tour::Options,
    /// Strand thickness over the platform, mm.
    #[serde(default = "default_layer_height")]
    pub layer_height_mm: f64,
    /// A part resting on the platform: where it meets the platform is Ω (domain kind `part`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub part: Option<Input>,
    /// Layers stacked along the normal (1: the paper's single layer). Always written, so the
    /// form shows the field.
    #[serde(default = "default_layers")]
    pub layers: usize,
    /// The tool axis: the normal, or smoothed within a tilt for the rotary axes.
    #[serde(default)]
    pub tool_axis: dynamics::Options,
}

fn default_layer_height() -> f64 {
    DEFAULT_LAYER_HEIGHT_MM
}

fn default_layers() -> usize {
    DEFAULT_LAYERS
}

impl Default for AxisymJob {
    fn default() -> Self {
        AxisymJob {
            platform: PlatformSpec::default(),
            domain: DomainSpec::default(),
            points: uniform::Options::default(),
            path: tour::Options::default(),
            layer_height_mm: DEFAULT_LAYER_HEIGHT_MM,
            part: None,
            tool_axis: dynamics::Options::default(),
            layers: DEFAULT_LAYERS,
        }
    }
}

/// Which generatrix.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Preset {
    /// The paper's barrel (table 2): u ∈ [0, 2], radius 25 mm at u = 1.
    #[default]
    Barrel,
    /// The paper's hourglass (table 3): u ∈ [0, 4], a 25 mm neck at u = 2.
    Hourglass,
    /// The control points given.
    Custom,
}

/// The platform: a preset, or a control polygon of 6·k + 1 points (x = radius, z = height, mm).
/// A preset writes its own polygon into `control_points`, so the design shows the points it
/// uses and switching to `custom` starts from them.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(from = "RawPlatform")]
pub struct PlatformSpec {
    /// Barrel, hourglass or custom.
    pub preset: Preset,
    /// The control polygon, mm.
    pub control_points: Vec<[f64; 2]>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawPlatform {
    #[serde(default)]
    preset: Preset,
    #[serde(default)]
    control_points: Vec<[f64; 2]>,
}

impl From<RawPlatform> for PlatformSpec {
    fn from(r: RawPlatform) -> Self {
        let control_points = match r.preset {
            Preset::Barrel => polygon_of(&Platform::barrel()),
            Preset::Hourglass => polygon_of(&Platform::hourglass()),
            Preset::Custom => r.control_points,
        };
        PlatformSpec { preset: r.preset, control_points }
    }
}

impl Default for PlatformSpec {
    fn default() -> Self {
        PlatformSpec::from(RawPlatform { preset: Preset::Barrel, control_points: Vec::new() })
    }
}

/// The flat control polygon of a platform (segments share their end points).
fn polygon_of(p: &Platform) -> Vec<[f64; 2]> {
    let mut out: Vec<[f64; 2]> = Vec::new();
    for s in &p.segments {
        let skip = usize::from(!out.is_empty());
        out.extend_from_slice(&s[skip..]);
    }
    out
}

/// Rectangle or polygon.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DomainKind {
    /// u_min ≤ u ≤ u_max, θ_min ≤ θ ≤ θ_max.
    #[default]
    Rectangle,
    /// The polygon's points (u, θ).
    Polygon,
    /// Where the part (slot `part`) meets the platform: its largest outline and the holes in it.
    Part,
}

/// Ω as the form edits it (flat fields), turned into an [`axisym::domain::Domain`]. A polygon
/// domain without corners starts from the rectangle's (as a preset writes its control points):
/// switching the kind in the form gives a valid design whose outline can then be edited.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(from = "RawDomain")]
pub struct DomainSpec {
    /// Rectangle or polygon.
    pub kind: DomainKind,
    /// Rectangle: lowest u.
    pub u_min: f64,
    /// Rectangle: highest u.
    pub u_max: f64,
    /// Rectangle: lowest θ, rad.
    pub theta_min_rad: f64,
    /// Rectangle: highest θ, rad.
    pub theta_max_rad: f64,
    /// Polygon: its corners (u, θ rad), in order; non-convex allowed.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub polygon: Vec<[f64; 2]>,
    /// Polygon: holes inside it, each a list of corners (u, θ rad).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub holes: Vec<Vec<[f64; 2]>>,
}

impl Default for DomainSpec {
    /// The paper's Ω1 on the barrel.
    fn default() -> Self {
        DomainSpec { kind: DomainKind::Rectangle, u_min: 0.8, u_max: 1.2, theta_min_rad: 0.0, theta_max_rad: 1.0, polygon: Vec::new(), holes: Vec::new() }
    }
}

/// [`DomainSpec`] as read, before an empty polygon takes the rectangle's corners.
#[derive(Deserialize)]
#[serde(deny_unknown_fields, default)]
struct RawDomain {
    kind: DomainKind,
    u_min: f64,
    u_max: f64,
    theta_min_rad: f64,
    theta_max_rad: f64,
    polygon: Vec<[f64; 2]>,
    holes: Vec<Vec<[f64; 2]>>,
}

impl Default for RawDomain {
    fn default() -> Self {
        let d = DomainSpec::default();
        RawDomain {
            kind: d.kind,
            u_min: d.u_min,
            u_max: d.u_max,
            theta_min_rad: d.theta_min_rad,
            theta_max_rad: d.theta_max_rad,
            polygon: d.polygon,
            holes: d.holes,
        }
    }
}

impl From<RawDomain> for DomainSpec {
    fn from(r: RawDomain) -> Self {
        let mut polygon = r.polygon;
        if r.kind == DomainKind::Polygon && polygon.is_empty() {
            polygon = vec![[r.u_min, r.theta_min_rad], [r.u_max, r.theta_min_rad], [r.u_max, r.theta_max_rad], [r.u_min, r.theta_max_rad]];
        }
        DomainSpec { kind: r.kind, u_min: r.u_min, u_max: r.u_max, theta_min_rad: r.theta_min_rad, theta_max_rad: r.theta_max_rad, polygon, holes: r.holes }
    }
}

impl DomainSpec {
    /// The domain the settings state (`None` for [`DomainKind::Part`]: it comes from the mesh).
    pub fn domain(&self) -> Option<Domain> {
        match self.kind {
            DomainKind::Rectangle => Some(Domain::Rectangle { u: [self.u_min, self.u_max], theta: [self.theta_min_rad, self.theta_max_rad] }),
            DomainKind::Polygon => Some(Domain::Polygon { points: self.polygon.clone(), holes: self.holes.clone() }),
            DomainKind::Part => None,
        }
    }
}

/// The `axisymmetric` job kind.
pub struct AxisymKind;

const SLOTS: &[Slot] = &[Slot {
    name: "part",
    label: "Part on the platform",
    kind: SlotKind::Mesh,
    path: "job.part",
    required: false,
    doc: "A solid resting on the curved platform: the outline where it meets the platform becomes the domain Ω.",
}];

const STAGES: &[StageInfo] = &[
    StageInfo { name: "platform", label: "Checking the build platform" },
    StageInfo { name: "domain", label: "Finding the domain Ω" },
    StageInfo { name: "points", label: "Spreading uniform points (geodesic repulsion)" },
    StageInfo { name: "path", label: "Joining the points by geodesics" },
    StageInfo { name: "axes", label: "Tool axis and machine dynamics" },
];

const VIEWS: &[ViewInfo] = &[
    ViewInfo {
        id: "map",
        stage: "points",
        label: "Embedded map (u, θ)",
        shape: Shape::Lines2d,
        index_label: "Step",
        doc: "The domain Ω in the (θ, u) plane: 0 the seed points, 1 after repulsion, 2 the path (x: θ in rad, y: u); with several layers, 3·layer + step.",
    },
    ViewInfo {
        id: "platform3d",
        stage: "path",
        label: "Path on the platform",
        shape: Shape::Lines3d,
        index_label: "View",
        doc: "The revolved platform (meridians and parallels) with the printed path on it, mm.",
    },
];

const PLATFORM_FIELDS: &[Field] = &[
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

const DOMAIN_FIELDS: &[Field] = &[
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

const JOB_FIELDS: &[Field] = &[
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

impl Kind for AxisymKind {
    type Settings = AxisymJob;
    const NAME: &'static str = "axisymmetric";
    const LABEL: &'static str = "Uniform infill on a curved platform";
    const DOC: &'static str =
        "Quasi-uniform infill points on an axisymmetric build platform, joined by geodesics and printed by a 5-axis head along the surface normal.";
    const SLOTS: &'static [Slot] = SLOTS;
    const STAGES: &'static [StageInfo] = STAGES;
    const VIEWS: &'static [ViewInfo] = VIEWS;

    fn fields() -> Vec<Row> {
        let mut rows = mount("job.platform", PLATFORM_FIELDS);
        rows.extend(mount("job.domain", DOMAIN_FIELDS));
        rows.extend(mount("job.points", uniform::FIELDS));
        rows.extend(mount("job.path", tour::FIELDS));
        rows.extend(mount("job", JOB_FIELDS));
        rows.extend(mount("job.tool_axis", dynamics::FIELDS));
        rows
    }

    fn validate(design: &Design, j: &AxisymJob, out: &mut Vec<Problem>) {
        out.extend(super::thicker_than_nozzle("job.layer_height_mm", j.layer_height_mm, design.printer.nozzle_diameter_mm));
        if !design.printer.machine.is_five_axis() && design.printer.flavor != crate::gcode::Flavor::PosesCsv {
            out.push(Problem {
                path: "printer.machine.kind".into(),
                message: "this job tilts the tool along the platform's normal: pick a 5-axis machine (printer profile '5-axis head (B/C)', --printer five-axis-head) or the poses CSV output (printer.flavor = poses_csv)".into(),
            });
        }
        let platform = match Platform::from_polygon(&j.platform.control_points) {
            Ok(p) => p,
            Err(e) => {
                out.push(Problem { path: "job.platform.control_points".into(), message: e.to_string() });
                return;
            }
        };
        if let Err(e) = platform.validate(&platform::Options::default()) {
            out.push(Problem { path: "job.platform.control_points".into(), message: e.to_string() });
            return;
        }
        let path = match j.domain.kind {
            DomainKind::Rectangle => "job.domain",
            DomainKind::Polygon => "job.domain.polygon",
            DomainKind::Part => "job.part",
        };
        match j.domain.domain() {
            Some(d) => {
                let problems = d.problems(&platform);
                for message in &problems {
                    out.push(Problem { path: path.into(), message: message.to_string() });
                }
                // The top layer's surface is the furthest offset: if it neither folds nor nears
                // the axis over Ω, no lower one does.
                if problems.is_empty() && (2..=MAX_LAYERS).contains(&j.layers) && j.layer_height_mm.is_finite() {
                    let k = j.layers - 1;
                    if let Err(e) = layer_offset(&platform, j, k, &d) {
                        out.push(Problem { path: "job.layers".into(), message: e.to_string() });
                    }
                }
            }
            None if j.part.is_none() => out.push(Problem {
                path: path.into(),
                message: "the domain is where a part meets the platform: load the part (its drop zone, or --input part=FILE) or pick a rectangle or polygon"
                    .into(),
            }),
            None => {}
        }
        // A radial grading's centre needs the metric too (the form's range allows the poles).
        if let Err(e) = uniform::check_centre(&platform, &j.points) {
            out.push(Problem { path: "job.points.grading.centre_u".into(), message: e.to_string() });
        }
    }

    /// Switching to this kind on a machine that cannot tilt the tool puts the `five-axis-head`
    /// profile in place (the poses CSV output is kept: it needs no machine).
    fn adopted(design: &mut serde_json::Value) {
        let printer = &design["printer"];
        let five_axis = printer.pointer("/machine/kind").and_then(|k| k.as_str()) == Some("five_axis");
        let poses = printer.get("flavor").and_then(|f| f.as_str()) == Some("poses_csv");
        if !five_axis && !poses {
            if let Ok(p) = crate::gcode::presets::preset(FIVE_AXIS_PRESET) {
                if let Ok(v) = serde_json::to_value(&p.printer) {
                    design["printer"] = v;
                }
            }
        }
    }

    fn slot_filled(slot: &str, mut j: AxisymJob) -> AxisymJob {
        if slot == "part" {
            j.domain.kind = DomainKind::Part;
        }
        j
    }

    fn estimate(j: &AxisymJob, ctx: &mut Ctx) -> Result<Vec<crate::budget::Estimate>, Error> {
        let platform = platform_stage(j, ctx)?;
        let width = line_width(ctx.design);
        check_layers(j)?;
        // A part's outlines are found first (their own estimate bounds that: linear in
        // triangles); every layer states its points, the sums are refused over the budgets.
        let (mut points, mut paths) = (Vec::new(), Vec::new());
        for k in 0..j.layers {
            let domain = domain_stage(j, ctx, &platform, k)?;
            let surface = layer_offset(&platform, j, k, &domain).map_err(|e| Error::stage("points", e))?;
            let e = uniform::estimate(surface.profile(), &domain.value, &j.points, width);
            paths.push(tour::estimate(e.get("points") as usize, &j.path, uniform::largest_spacing(&j.points, width)));
            points.push(e);
        }
        Ok(vec![
            crate::budget::Estimate::new("platform"),
            sum_layers(points, "lower the density, the iterations, cutoff_spacings or the layers"),
            sum_layers(paths, "lower the infill density, the layers or split the domain"),
        ])
    }

    fn run(j: &AxisymJob, ctx: &mut Ctx) -> Result<Product, Error> {
        let platform = platform_stage(j, ctx)?;
        let layers = all_layers(j, ctx, &platform, j.layers, true)?;
        let (h, width) = (j.layer_height_mm, line_width(ctx.design));
        let tours: Vec<&tour::Tour> = layers.iter().filter_map(|l| l.tour.as_deref()).collect();
        let mut keys: Vec<_> = layers.iter().map(|l| l.tour.as_ref().map_or(l.points.key, |t| t.key)).collect();
        let axes = axes_stage(j, ctx, &tours, &keys)?;
        keys.push(axes.key);
        let toolpath = ctx.stage("axes", "toolpath", &(h, width), &keys, |_| Ok((toolpath_of(&tours, &axes, h, width), None)))?;
        // The per-layer table joins the path stage's report (cached or not, it is added here).
        let table = layer_table(&layers, h);
        if let Some(r) = ctx.reports.iter_mut().find(|r| r.stage == "path") {
            r.tables.retain(|t| t.key != "layers");
            r.tables.push(table);
        }
        Ok(Product::Toolpath(toolpath))
    }

    fn inspect(j: &AxisymJob, ctx: &mut Ctx, view: &str, index: usize) -> Result<Inspection, Error> {
        let platform = platform_stage(j, ctx)?;
        check_layers(j)?;
        // The path comes from the stage cache when the run made it (the worker's session).
        match view {
            "map" => {
                let index = index.min(3 * j.layers - 1);
                let (layer, step) = (index / 3, index % 3);
                // The points of a layer do not need the paths below it; its path does.
                let layers = all_layers(j, ctx, &platform, layer + 1, step == 2)?;
                let l = &layers[layer];
                Ok(map_view(&l.domain, &l.points, l.tour.as_deref(), layer, j.layers, step, j.domain.kind == DomainKind::Polygon))
            }
            "platform3d" => {
                let layers = all_layers(j, ctx, &platform, j.layers, true)?;
                let tours: Vec<&tour::Tour> = layers.iter().filter_map(|l| l.tour.as_deref()).collect();
                Ok(platform_view(&platform, &tours, j.layer_height_mm))
            }
            _ => Err(Error::UnknownView { view: view.into(), job: Self::NAME }),
        }
    }
}

/// e of equation 4: the nozzle diameter (the paper: 0.4 mm).
fn line_width(design: &Design) -> f64 {
    design.printer.nozzle_diameter_mm
}

/// Samples per segment of the platform plots.
const PLOT_SAMPLES_PER_SEGMENT: usize = 64;

fn platform_stage(j: &AxisymJob, ctx: &mut Ctx) -> Result<Out<Platform>, Error> {
    ctx.stage("platform", "platform", &j.platform.control_points, &[], |_| {
        let p = Platform::from_polygon(&j.platform.control_points).map_err(|e| Error::stage("platform", e))?;
        let continuity = p.validate(&platform::Options::default()).map_err(|e| Error::stage("platform", e))?;
        let report = platform_report(&p, &continuity);
        Ok((p, Some(report)))
    })
}

/// The layer count within 1..=[`MAX_LAYERS`] (the settings table says so too; a design read
/// without its checks must not loop or index out of range).
fn check_layers(j: &AxisymJob) -> Result<(), Error> {
    if (1..=MAX_LAYERS).contains(&j.layers) {
        Ok(())
    } else {
        Err(Error::stage("points", crate::axisym::Error::BadOption { name: "layers", value: j.layers as f64, hint: "1 to 100 layers" }))
    }
}

/// The stage cache id of `stage` for layer k: the plain name for layer 0 (so a one-layer job
/// keeps its ids, keys and reports), `name@k` above.
fn layer_id(stage: &str, k: usize) -> String {
    if k == 0 {
        stage.to_string()
    } else {
        format!("{stage}@{k}")
    }
}

/// The seed of layer k: the design seed for layer 0, a fixed odd multiple of k mixed in above.
pub fn layer_seed(seed: u64, k: usize) -> u64 {
    seed ^ (k as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
}

/// The surface layer k spreads its points on: the platform itself, or its offset by k·h.
enum LayerSurface<'a> {
    Base(&'a Platform),
    Offset(Offset<'a, Platform>),
}

impl LayerSurface<'_> {
    fn profile(&self) -> &dyn Profile {
        match self {
            LayerSurface::Base(p) => *p,
            LayerSurface::Offset(o) => o,
        }
    }
}

/// Why a layer's surface cannot be used.
#[derive(Debug, thiserror::Error)]
#[error("layer {layer} (on the platform offset by {offset_mm} mm): {source}")]
pub struct LayerError {
    /// Layer, 1-based.
    pub layer: usize,
    /// Its offset, mm.
    pub offset_mm: f64,
    /// The offset's reason.
    pub source: crate::axisym::Error,
}

/// Layer k's surface, checked over the u span of its domain.
fn layer_offset<'a>(p: &'a Platform, j: &AxisymJob, k: usize, domain: &Domain) -> Result<LayerSurface<'a>, LayerError> {
    if k == 0 {
        return Ok(LayerSurface::Base(p));
    }
    let h = k as f64 * j.layer_height_mm;
    let b = domain.bounds();
    Offset::new(p, h, [b[0][0], b[1][0]], platform::DEFAULT_MIN_POLE_RADIUS_MM).map(LayerSurface::Offset).map_err(|source| LayerError {
        layer: k + 1,
        offset_mm: h,
        source,
    })
}

/// Sums per-layer estimates of one stage: counts and times add, the peak memory is the
/// largest layer's, the first layer refused refuses, then the budgets on the totals.
fn sum_layers(layers: Vec<crate::budget::Estimate>, fix: &str) -> crate::budget::Estimate {
    let mut it = layers.into_iter();
    let Some(mut total) = it.next() else { return crate::budget::Estimate::new("axisym_uniform") };
    let mut more = false;
    for e in it {
        more = true;
        for q in e.quantities {
            match total.quantities.iter_mut().find(|t| t.key == q.key) {
                Some(t) => t.value += q.value,
                None => total.quantities.push(q),
            }
        }
        total.bytes = total.bytes.max(e.bytes);
        total.seconds += e.seconds;
        if total.refused.is_none() {
            total.refused = e.refused;
        }
    }
    // One layer: exactly its own estimate.
    if more {
        total.budgets(fix)
    } else {
        total
    }
}

/// One layer's stages.
struct Layer {
    offset_mm: f64,
    domain: Out<Domain>,
    points: Out<uniform::Distribution>,
    tour: Option<Out<tour::Tour>>,
}

/// Layers 0..count: domains and points, and with `paths` each layer's path (layer k + 1's
/// starting nearest where layer k's ended).
fn all_layers(j: &AxisymJob, ctx: &mut Ctx, platform: &Out<Platform>, count: usize, paths: bool) -> Result<Vec<Layer>, Error> {
    check_layers(j)?;
    let mut out: Vec<Layer> = Vec::with_capacity(count);
    for k in 0..count {
        let domain = domain_stage(j, ctx, platform, k)?;
        let points = points_stage(j, ctx, platform, &domain, k)?;
        out.push(Layer { offset_mm: k as f64 * j.layer_height_mm, domain, points, tour: None });
    }
    if paths {
        for k in 0..count {
            let start = if k == 0 {
                None
            } else {
                let prev = &out[k - 1];
                prev.tour.as_ref().and_then(|t| t.order.last()).map(|&i| prev.points.points[i])
            };
            let t = path_stage(j, ctx, platform, &out[k].domain, &out[k].points, k, start)?;
            out[k].tour = Some(t);
        }
    }
    Ok(out)
}

/// Ω of layer k ([`domain_of`]), refused when the layer's nozzle tip, (k + 1)·h out along the
/// normal, would go below the plate: checked here, before the points and path stages spend
/// their time (the writer would refuse the toolpath only at the end).
fn domain_stage(j: &AxisymJob, ctx: &mut Ctx, platform: &Out<Platform>, k: usize) -> Result<Out<Domain>, Error> {
    let domain = domain_of(j, ctx, platform, k)?;
    let [[u_lo, _], [u_hi, _]] = domain.value.bounds();
    below_plate(&*platform.value, u_lo, u_hi, (k + 1) as f64 * j.layer_height_mm).map_err(|e| Error::stage("domain", e))?;
    Ok(domain)
}

/// The nozzle tip would go below the plate.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("the nozzle tip would reach z = {z_mm:.3} mm at u = {u:.4}, below the plate (Z < 0): raise the platform by at least {raise_mm:.3} mm (add it to every control point's z), or keep the domain's u where the platform stands higher")]
pub struct BelowPlate {
    /// Lowest tip height, mm.
    pub z_mm: f64,
    /// Where along the profile.
    pub u: f64,
    /// How far to raise the platform, mm.
    pub raise_mm: f64,
}

/// Samples of the tip height per unit u when looking for its lowest point (then refined).
const PLATE_SAMPLES_PER_U: f64 = 512.0;

/// Checks that the tip, `h` out along the normal, stays at Z ≥ 0 for u ∈ [u_lo, u_hi] (the
/// height depends on u only, and every u of a connected domain's range is in the domain).
fn below_plate(p: &dyn platform::Profile, u_lo: f64, u_hi: f64, h: f64) -> Result<(), BelowPlate> {
    let tip_z = |u: f64| platform::position(p, u, 0.0)[2] + platform::normal(p, u, 0.0)[2] * h;
    let n = (((u_hi - u_lo) * PLATE_SAMPLES_PER_U).ceil() as usize).clamp(1, 1 << 16);
    let at = |i: usize| u_lo + (u_hi - u_lo) * i as f64 / n as f64;
    let k = (0..=n).map(|i| (i, tip_z(at(i)))).min_by(|a, b| a.1.total_cmp(&b.1)).map_or(0, |(i, _)| i);
    // Golden-section refinement in the bracket around the lowest sample.
    let (mut a, mut b) = (at(k.saturating_sub(1)), at((k + 1).min(n)));
    for _ in 0..60 {
        let (c, d) = (b - 0.618_033_988_749_895 * (b - a), a + 0.618_033_988_749_895 * (b - a));
        if tip_z(c) < tip_z(d) {
            b = d
        } else {
            a = c
        }
    }
    let (u, z) = [at(k), 0.5 * (a + b)].into_iter().map(|u| (u, tip_z(u))).min_by(|x, y| x.1.total_cmp(&y.1)).unwrap_or((u_lo, 0.0));
    // The writer's tolerance (1e-6 mm).
    if z < -1e-6 {
        Err(BelowPlate { z_mm: z, u, raise_mm: -z })
    } else {
        Ok(())
    }
}

/// Ω of layer k: the settings' rectangle or polygon (every layer the same (u, θ) region), or
/// the largest outline where the part meets the platform offset by k·h, with the holes in it
/// (smaller outlines are reported, not filled).
fn domain_of(j: &AxisymJob, ctx: &mut Ctx, platform: &Out<Platform>, k: usize) -> Result<Out<Domain>, Error> {
    if let Some(d) = j.domain.domain() {
        return ctx.stage("domain", "domain", &d, &[platform.key], |_| {
            let corners = d.ring().len();
            let mut r = StageReport::new("domain", "Finding the domain Ω", &d).metric(
                "corners",
                "Outline corners",
                corners as f64,
                "",
                "Corners of Ω in the embedded map (a rectangle has 4).",
            );
            if !d.holes().is_empty() {
                r = r.metric(
                    "holes",
                    "Holes kept",
                    d.holes().len() as f64,
                    "",
                    "Openings inside the outline, left unfilled: the points and the path keep out of them.",
                );
            }
            Ok((d.clone(), Some(r)))
        });
    }
    let input = j.part.as_ref().ok_or_else(|| Error::NoInput("a part domain needs the part: load it, or pass --input part=FILE".into()))?;
    // In the file's own coordinates: the platform's axis is Z through the origin.
    let mesh = ctx.mesh_in_place(&SLOTS[0], input)?;
    let offset_mm = k as f64 * j.layer_height_mm;
    ctx.stage("domain", &layer_id("domain", k), &offset_mm, &[platform.key, mesh.key], |_| {
        let c = contour::platform_contours(&mesh.value, &platform.value, &contour::Options { offset_mm, ..contour::Options::default() })
            .map_err(|e| Error::stage("domain", e))?;
        // (A hole always lies in an outline, so an outline exists whenever a loop does.)
        let outline = (0..c.loops.len()).find(|&i| !c.is_hole[i]).ok_or_else(|| {
            Error::NoInput("the part meets the platform in no closed outline (an open mesh?): repair the part or move it onto the platform".into())
        })?;
        let kept: Vec<usize> = (0..c.loops.len()).filter(|&i| c.is_hole[i] && c.parent[i] == Some(outline)).collect();
        let outlines = c.is_hole.iter().filter(|h| !**h).count();
        let d = Domain::Polygon { points: c.loops[outline].clone(), holes: kept.iter().map(|&i| c.loops[i].clone()).collect() };
        let r = StageReport::new("domain", "Finding the domain Ω", &d)
            .metric(
                "corners",
                "Outline corners",
                c.loops[outline].len() as f64,
                "",
                "Points of the outline where the part meets the platform, in the embedded map.",
            )
            .metric("area", "Outline area", c.area_mm2[outline], "mm²", "The area the outline encloses on the platform (its holes not taken off).")
            .metric("holes", "Holes kept", kept.len() as f64, "", "Openings inside the outline, left unfilled: the points and the path keep out of them.")
            .metric(
                "other_outlines",
                "Smaller outlines left out",
                (outlines - 1) as f64,
                "",
                "Other places the part meets the platform; only the largest is filled.",
            )
            .metric(
                "open_chains",
                "Open cuts dropped",
                c.open_chains as f64,
                "",
                "Cuts that did not close because the mesh is open there: repair the mesh if this is not 0.",
            );
        // Only layer 0 reports; the others are in the per-layer table.
        Ok((d, (k == 0).then_some(r)))
    })
}

/// The path of layer k through its points (with its report for layer 0), starting nearest
/// `start` when given (where the layer below ended); the toolpath is made from it by the run.
#[allow(clippy::too_many_arguments)]
fn path_stage(
    j: &AxisymJob,
    ctx: &mut Ctx,
    platform: &Out<Platform>,
    domain: &Out<Domain>,
    distribution: &Out<uniform::Distribution>,
    k: usize,
    start: Option<[f64; 2]>,
) -> Result<Out<tour::Tour>, Error> {
    let mut o = j.path.clone();
    if let Some([u, theta]) = start {
        o.start = tour::Start::Nearest { u, theta };
    }
    let parts = (&o, k as f64 * j.layer_height_mm);
    ctx.stage("path", &layer_id("path", k), &parts, &[platform.key, domain.key, distribution.key], |progress| {
        let surface = layer_offset(&platform.value, j, k, &domain.value).map_err(|e| Error::stage("path", e))?;
        let profile = surface.profile();
        let s = Surface::new(profile);
        let dist = |a: [f64; 2], b: [f64; 2]| s.distance(a, b);
        let d = &*domain.value;
        let crosses = |a: [f64; 2], b: [f64; 2]| d.segment_crosses_hole(a, b);
        let avoid: Option<tour::Avoid> = if d.holes().is_empty() { None } else { Some(&crosses) };
        let t = tour::plan(profile, &distribution.points, &o, &dist, avoid, progress).map_err(|e| Error::stage("path", e))?;
        let report = (k == 0).then(|| path_report(&t, &distribution.value, avoid.is_some()));
        Ok((t, report))
    })
}

/// The tool axes along each layer's tour, one unit axis per pose (the normals, or smoothed within the tilt) and what
/// they ask of the machine at the infill speed, before and after smoothing: the largest speed
/// and acceleration of each axis over the layers (each layer is its own pass).
fn axes_stage(j: &AxisymJob, ctx: &mut Ctx, tours: &[&tour::Tour], keys: &[crate::stage::Key]) -> Result<Out<Vec<Vec<[f64; 3]>>>, Error> {
    let design = ctx.design;
    let (h, feed, machine) = (j.layer_height_mm, design.speeds.infill_mm_s, &design.printer.machine);
    ctx.stage("axes", "axes", &(&j.tool_axis, h, feed, machine), keys, |_| {
        let (mut layers, mut raw_all, mut after_all, mut tilt) = (Vec::new(), Vec::new(), Vec::new(), 0.0f64);
        for t in tours {
            let positions: Vec<[f64; 3]> = t.poses.iter().map(|p| p.position).collect();
            let normals: Vec<[f64; 3]> = t.poses.iter().map(|p| p.normal).collect();
            let tips: Vec<[f64; 3]> = t.poses.iter().map(|p| tip(p, h).to_array()).collect();
            let smoothed = dynamics::smooth_axes(&positions, &normals, &j.tool_axis).map_err(|e| Error::stage("axes", e))?;
            let raw = dynamics::dynamics(&tips, &normals, machine, feed).map_err(|e| Error::stage("axes", e))?;
            // Smoothing off (the default): the axes are the normals, the same dynamics.
            let after = if smoothed.axes == normals {
                raw.clone()
            } else {
                dynamics::dynamics(&tips, &smoothed.axes, machine, feed).map_err(|e| Error::stage("axes", e))?
            };
            raw_all.push(raw);
            after_all.push(after);
            tilt = tilt.max(smoothed.max_tilt_deg);
            layers.push(smoothed.axes);
        }
        // The tool's lean from vertical (what a head must reach), over every pose.
        let from_vertical = layers
            .iter()
            .flatten()
            .map(|a| libm::acos((a[2] / libm::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).max(1e-12)).clamp(-1.0, 1.0)).to_degrees())
            .fold(0.0, f64::max);
        let report = axes_report(&j.tool_axis, tilt, &worst(&raw_all), &worst(&after_all), feed).metric(
            "max_from_vertical",
            "Largest tilt from vertical",
            from_vertical,
            "°",
            "The tool axis's largest lean from +Z over the whole path: how far the head must tilt.",
        );
        Ok((layers, Some(report)))
    })
}

/// The largest speed and acceleration of each axis over several passes, their lengths and
/// times added.
fn worst(all: &[dynamics::Dynamics]) -> dynamics::Dynamics {
    let mut out = all.first().cloned().unwrap_or(dynamics::Dynamics { axes: Vec::new(), path_mm: 0.0, duration_s: 0.0 });
    for d in all.iter().skip(1) {
        for (o, a) in out.axes.iter_mut().zip(&d.axes) {
            o.max_speed_deg_s = o.max_speed_deg_s.max(a.max_speed_deg_s);
            o.max_accel_deg_s2 = o.max_accel_deg_s2.max(a.max_accel_deg_s2);
        }
        out.path_mm += d.path_mm;
        out.duration_s += d.duration_s;
    }
    out
}

/// What the `axes` stage reports.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AxesSummary {
    /// Largest tilt of the tool axis from the normal, degrees (0: the normals).
    pub max_tilt_deg: f64,
    /// Per axis (tool axis first, then the rotary letters): [speed °/s, acceleration °/s²]
    /// before smoothing.
    pub raw: Vec<(String, [f64; 2])>,
    /// The same after smoothing (equal to `raw` when smoothing is off).
    pub smoothed: Vec<(String, [f64; 2])>,
}

fn axes_report(o: &dynamics::Options, max_tilt_deg: f64, raw: &dynamics::Dynamics, after: &dynamics::Dynamics, feed: f64) -> StageReport {
    let pairs = |d: &dynamics::Dynamics| d.axes.iter().map(|a| (a.axis.clone(), [a.max_speed_deg_s, a.max_accel_deg_s2])).collect::<Vec<_>>();
    let summary = AxesSummary { max_tilt_deg, raw: pairs(raw), smoothed: pairs(after) };
    let on = o.max_tilt_deg > 0.0;
    let mut r = StageReport::new("axes", "Tool axis and machine dynamics", &summary)
        .metric("max_tilt", "Largest tilt from the normal", max_tilt_deg, "°", "How far smoothing leans the tool axis (0: the axis is the normal).")
        .metric("feed", "At the infill speed", feed, "mm/s", "Speeds below scale with it, accelerations with its square.")
        .metric("duration", "Path time", after.duration_s, "s", "Every layer's path at the infill speed.");
    // The tool axis as metrics; every axis (rotary ones too) in the table below.
    if let Some(b) = after.axes.first() {
        r = r
            .metric("tool_speed", "Tool-axis turn, fastest", b.max_speed_deg_s, "°/s", "How fast the tool axis turns at the infill speed (smoothed, when on).")
            .metric(
                "tool_accel",
                "Tool-axis acceleration, largest",
                b.max_accel_deg_s2,
                "°/s²",
                "Its hardest change of turning speed: the raster's corners set it.",
            );
    }
    if on {
        for (a, b) in raw.axes.iter().zip(&after.axes) {
            let cut = if a.max_accel_deg_s2 > 0.0 { 100.0 * (1.0 - b.max_accel_deg_s2 / a.max_accel_deg_s2) } else { 0.0 };
            let key = if a.axis == "tool axis" { "tool".to_string() } else { a.axis.to_lowercase() };
            r = r.metric(&format!("{key}_accel_cut"), &format!("Acceleration cut, {}", a.axis), cut, "%", "Against the axis equal to the normal everywhere.");
        }
    }
    r.tables.push(crate::report::Table {
        key: "dynamics".into(),
        title: "Axis speeds and accelerations at the infill speed".into(),
        group: None,
        columns: [("Axis", ""), ("Speed", "°/s"), ("Accel.", "°/s²"), ("Speed, smoothed", "°/s"), ("Accel., smoothed", "°/s²")]
            .iter()
            .map(|(label, unit)| crate::report::Column { label: (*label).into(), unit: (*unit).into() })
            .collect(),
        rows: raw
            .axes
            .iter()
            .zip(&after.axes)
            .map(|(a, b)| crate::report::Row {
                group_index: None,
                cells: vec![
                    a.axis.clone().into(),
                    round(a.max_speed_deg_s).into(),
                    round(a.max_accel_deg_s2).into(),
                    round(b.max_speed_deg_s).into(),
                    round(b.max_accel_deg_s2).into(),
                ],
            })
            .collect(),
    });
    r
}

/// Four significant digits, for table cells.
fn round(v: f64) -> f64 {
    if v == 0.0 || !v.is_finite() {
        return v;
    }
    let scale = libm::pow(10.0, 3.0 - libm::floor(libm::log10(v.abs())));
    libm::round(v * scale) / scale
}

/// Layer k's points on its surface, seeded by [`layer_seed`] (layer 0 reports).
fn points_stage(j: &AxisymJob, ctx: &mut Ctx, platform: &Out<Platform>, domain: &Out<Domain>, k: usize) -> Result<Out<uniform::Distribution>, Error> {
    let design = ctx.design;
    let width = line_width(design);
    let seed = layer_seed(design.seed, k);
    let parts = (&j.points, width, seed, k as f64 * j.layer_height_mm);
    ctx.stage("points", &layer_id("points", k), &parts, &[platform.key, domain.key], |progress| {
        let surface = layer_offset(&platform.value, j, k, &domain.value).map_err(|e| Error::stage("points", e))?;
        let d = uniform::distribute(surface.profile(), &domain.value, &j.points, width, seed, progress).map_err(|e| Error::stage("points", e))?;
        let report = (k == 0).then(|| points_report(&d, &j.points, width));
        Ok((d, report))
    })
}

/// Per layer: its offset, points, spread reduction and path length.
fn layer_table(layers: &[Layer], h: f64) -> crate::report::Table {
    use crate::report::{Column, Row as TableRow, Table};
    let col = |label: &str, unit: &str| Column { label: label.into(), unit: unit.into() };
    let rows = layers
        .iter()
        .enumerate()
        .map(|(k, l)| {
            let (s, m) = (&l.points.seed_metrics, &l.points.metrics);
            // Against the local target spacing (the same ratio as in mm when the density is uniform).
            let reduction = if s.rel_std > 0.0 { 100.0 * (1.0 - m.rel_std / s.rel_std) } else { 0.0 };
            let (length, over) = l.tour.as_ref().map_or((0.0, 0), |t| (t.length_mm, t.hole_crossings));
            TableRow {
                group_index: None,
                cells: vec![
                    (k + 1).into(),
                    l.offset_mm.into(),
                    ((k + 1) as f64 * h).into(),
                    l.points.points.len().into(),
                    reduction.into(),
                    length.into(),
                    over.into(),
                ],
            }
        })
        .collect();
    Table {
        key: "layers".into(),
        title: "Layers: each on the platform offset by the layers below".into(),
        group: None,
        columns: vec![
            col("Layer", ""),
            col("Surface offset", "mm"),
            col("Tip offset", "mm"),
            col("Points", ""),
            col("Spread reduced by", "%"),
            col("Path length", "mm"),
            col("Hops over a hole (not printed)", ""),
        ],
        rows,
    }
}

fn platform_report(p: &Platform, c: &platform::Continuity) -> StageReport {
    let (lo, hi) = (0.0, p.segments.len() as f64);
    let n = p.segments.len() * PLOT_SAMPLES_PER_SEGMENT;
    let clearance = platform::pole_clearance(p, platform::DEFAULT_MIN_POLE_RADIUS_MM);
    let (mut us, mut kappa, mut guu, mut gtt, mut g_uuu, mut g_utt, mut g_tut) = (vec![], vec![], vec![], vec![], vec![], vec![], vec![]);
    let mut max_kappa: f64 = 0.0;
    for i in 0..=n {
        let u = lo + (hi - lo) * i as f64 / n as f64;
        let k = platform::curvature(p, u);
        let m = platform::metric(p, u);
        us.push(u);
        kappa.push(k);
        guu.push(m.g_uu);
        gtt.push(m.g_tt);
        max_kappa = max_kappa.max(k.abs());
        // Γ^θ_uθ = x′/x is unbounded at the poles: plotted only where a domain may go.
        let inside = clearance.is_some_and(|(a, b)| u >= a && u <= b);
        let c = platform::christoffel(p, u);
        g_uuu.push(c.u_uu);
        g_utt.push(c.u_tt);
        g_tut.push(if inside { c.t_ut } else { f64::NAN });
    }
    let line = |key: &str, title: &str, y: &str, unit: &str, series: Vec<Series>| Plot {
        key: key.into(),
        title: title.into(),
        kind: PlotKind::Line,
        x: Axis::new("u", ""),
        y: Axis::new(y, unit),
        group: None,
        series,
    };
    let mut r = StageReport::new("platform", "Checking the build platform", c)
        .metric("segments", "Bézier segments", p.segments.len() as f64, "", "Degree-6 segments of the generatrix; u runs from 0 to this number.")
        .metric(
            "max_jump",
            "Largest C³ jump at a knot",
            c.worst_rel.iter().fold(0.0, |a: f64, b| a.max(*b)),
            "",
            "The largest jump of x, z or their first three derivatives across a knot, relative to their size (0: C³).",
        )
        .metric("max_curvature", "Largest |κ|", max_kappa, "1/mm", "The sharpest bend of the profile: 1/κ is the smallest radius of curvature.");
    if let Some((a, b)) = clearance {
        r = r
            .metric("u_clear_min", "Domain may start at u", a, "", "Closer to the top pole the metric degenerates (g_θθ → 0): keep Ω at or above this u.")
            .metric("u_clear_max", "Domain may end at u", b, "", "Closer to the bottom pole the metric degenerates: keep Ω at or below this u.");
    }
    r.plots.push(line("curvature", "Curvature κ of the generatrix", "κ", "1/mm", vec![Series::xy("κ", us.clone(), kappa)]));
    r.plots.push(line("metric", "Metric components", "g", "mm²", vec![Series::xy("g_uu", us.clone(), guu), Series::xy("g_θθ", us.clone(), gtt)]));
    r.plots.push(line(
        "christoffel",
        "Christoffel symbols of the second kind",
        "Γ",
        "",
        vec![Series::xy("Γ^u_uu", us.clone(), g_uuu), Series::xy("Γ^u_θθ", us.clone(), g_utt), Series::xy("Γ^θ_uθ", us, g_tut)],
    ));
    r
}

/// The `points` stage's typed report (`weft run --report`): the numbers, not the points.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PointsSummary {
    /// True surface area of Ω, mm².
    pub area_mm2: f64,
    /// N of equation 4.
    pub points: usize,
    /// Normalised energy E/E0 after each accepted iteration.
    pub energy: Vec<f64>,
    /// Why the repulsion stopped.
    pub stop: String,
    /// 2n-NN distances of the seed: mean and standard deviation, mm.
    pub seed_mean_mm: f64,
    /// See `seed_mean_mm`.
    pub seed_std_mm: f64,
    /// 2n-NN distances after repulsion: mean and standard deviation, mm.
    pub mean_mm: f64,
    /// See `mean_mm`.
    pub std_mm: f64,
    /// 1 − std / seed std.
    pub std_reduction: f64,
    /// e / mean distance after repulsion.
    pub ratio: f64,
    /// e / mean distance of the seed.
    pub seed_ratio: f64,
    /// 2n-NN distances over each point's target spacing s(q) = n·e/ρ(q): standard deviation
    /// of the seed (uniform: `seed_std_mm` / s).
    #[serde(default)]
    pub seed_rel_std: f64,
    /// The same after repulsion.
    #[serde(default)]
    pub rel_std: f64,
    /// 1 − rel_std / seed_rel_std.
    #[serde(default)]
    pub rel_std_reduction: f64,
    /// Whether the density is graded.
    #[serde(default)]
    pub graded: bool,
}

/// The `path` stage's typed report.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PathSummary {
    /// Points visited (each once).
    pub visited: usize,
    /// Path length along the geodesics, mm.
    pub length_mm: f64,
    /// The nearest-neighbour path's length, mm.
    pub nn_length_mm: f64,
    /// Crossings 2-opt removed and left.
    pub crossings_removed: usize,
    /// See `crossings_removed`.
    pub crossings_left: usize,
    /// Poses written.
    pub poses: usize,
    /// Path segments that cross a hole of Ω (0 without holes).
    #[serde(default)]
    pub hole_crossings: usize,
}

fn points_report(d: &uniform::Distribution, o: &uniform::Options, width: f64) -> StageReport {
    let s = &d.seed_metrics;
    let m = &d.metrics;
    let reduction = if s.nn_std_mm > 0.0 { 100.0 * (1.0 - m.nn_std_mm / s.nn_std_mm) } else { 0.0 };
    let summary = PointsSummary {
        area_mm2: d.area_mm2,
        points: d.points.len(),
        energy: d.iterations.iter().map(|i| i.energy).collect(),
        stop: format!("{:?}", d.stop),
        seed_mean_mm: s.nn_mean_mm,
        seed_std_mm: s.nn_std_mm,
        mean_mm: m.nn_mean_mm,
        std_mm: m.nn_std_mm,
        std_reduction: reduction / 100.0,
        ratio: m.ratio,
        seed_ratio: s.ratio,
        seed_rel_std: s.rel_std,
        rel_std: m.rel_std,
        rel_std_reduction: if s.rel_std > 0.0 { 1.0 - m.rel_std / s.rel_std } else { 0.0 },
        graded: d.graded.is_some(),
    };
    let mut r = StageReport::new("points", "Spreading uniform points (geodesic repulsion)", &summary)
        .metric("area", "Surface area of Ω", d.area_mm2, "mm²", "The true area A_Σ of the patch on the curved platform.")
        .metric("points", "Points N", d.points.len() as f64, "", "Equation 4: N = A_Σ·ρ_c² / (n²·e²), e the nozzle diameter.")
        .metric("iterations", "Repulsion iterations", d.iterations.len() as f64, "", "Geodesic repulsion steps taken before a tolerance or the cap stopped it.")
        .metric("std_seed", "Spacing spread, seed", s.nn_std_mm, "mm", "Standard deviation of the distances to the 2n nearest neighbours before repulsion.")
        .metric("std", "Spacing spread, result", m.nn_std_mm, "mm", "The same after repulsion: lower is more uniform.")
        .metric(
            "std_reduction",
            "Spread reduced by",
            reduction,
            "%",
            if o.grading.is_some() {
                "In mm, which a graded density spreads on purpose: see the spread against the target below."
            } else {
                "How much repulsion evened the spacing, against this run's own seed (the paper: 71.7 % on Ω1, 44 % on Ω3; its Ω2 polygon is not published, so barrel-omega2 is weft's stand-in)."
            },
        )
        .metric("mean", "Mean neighbour distance", m.nn_mean_mm, "mm", "Mean distance to the 2n nearest neighbours after repulsion.")
        .metric(
            "ratio",
            "e / mean distance",
            100.0 * m.ratio,
            "%",
            "Line width over the mean spacing: the density the points give, to compare with the command density.",
        )
        .metric(
            "command",
            "Command density ρ_c",
            100.0 * o.density,
            "%",
            if o.grading.is_some() { "The density asked for at the near end of the grading." } else { "The density asked for." },
        );
    if let (Some(g), Some(gp)) = (&o.grading, &d.graded) {
        r = graded_report(r, d, g, gp);
    }
    let it: Vec<f64> = (0..d.iterations.len()).map(|i| (i + 1) as f64).collect();
    let h = if o.grading.is_some() { "h = 4·s(q) per point".to_string() } else { format!("h = {:.3} mm", 4.0 * o.rasters as f64 * width / o.density) };
    r.plots.push(Plot {
        key: "energy".into(),
        title: "Normalised repulsion energy per iteration".into(),
        kind: PlotKind::Line,
        x: Axis::new("Iteration", ""),
        y: Axis::new("E / E0", ""),
        group: None,
        series: vec![Series::xy("E / E0", it, d.iterations.iter().map(|i| i.energy).collect())],
    });
    let rank = |v: &[f64]| -> Vec<f64> { (0..v.len()).map(|i| i as f64).collect() };
    r.plots.push(Plot {
        key: "kdf".into(),
        title: format!("Kernel density per point, sorted ({h})"),
        kind: PlotKind::Line,
        x: Axis::new("Point (sorted)", ""),
        y: Axis::new("Kernel density", "1/mm²"),
        group: None,
        series: vec![Series::xy("seed", rank(&s.kdf_sorted), s.kdf_sorted.clone()), Series::xy("repulsion", rank(&m.kdf_sorted), m.kdf_sorted.clone())],
    });
    let (edges, seed_counts, counts) = crate::axisym::metrics::shared_histogram(&s.nn_distances_mm, &m.nn_distances_mm, HISTOGRAM_BINS);
    r.plots.push(Plot {
        key: "nn".into(),
        title: format!("Distances to the {} nearest neighbours", 2 * o.rasters),
        kind: PlotKind::Histogram,
        x: Axis::new("Distance", "mm"),
        y: Axis::new("Pairs", ""),
        group: None,
        series: vec![Series::xy("seed", edges.clone(), seed_counts), Series::xy("repulsion", edges, counts)],
    });
    r
}

/// Bins of the neighbour-distance histogram.
const HISTOGRAM_BINS: usize = 30;

/// Mean of `values` per bin of `coord` over `range` (`bins` bins; NaN where a bin is empty).
fn binned_mean(coord: &[f64], values: &[f64], range: [f64; 2], bins: usize) -> Vec<f64> {
    let (mut sum, mut count) = (vec![0.0; bins], vec![0usize; bins]);
    let w = (range[1] - range[0]) / bins as f64;
    for (c, v) in coord.iter().zip(values) {
        let k = if w > 0.0 { (((c - range[0]) / w).max(0.0) as usize).min(bins - 1) } else { 0 };
        sum[k] += v;
        count[k] += 1;
    }
    sum.iter().zip(&count).map(|(s, &c)| if c > 0 { s / c as f64 } else { f64::NAN }).collect()
}

/// The graded run's rows and plots: spread of the distances against the local target, the
/// commanded density against the measured one along the grading coordinate.
fn graded_report(mut r: StageReport, d: &uniform::Distribution, g: &crate::axisym::grading::Grading, gp: &uniform::GradedPoints) -> StageReport {
    let (s, m) = (&d.seed_metrics, &d.metrics);
    let reduction = if s.rel_std > 0.0 { 100.0 * (1.0 - m.rel_std / s.rel_std) } else { 0.0 };
    r = r
        .metric("end_density", "End density", 100.0 * g.density_to, "%", "The density asked for at the far end of the grading.")
        .metric(
            "rel_std_seed",
            "Spread against the target, seed",
            100.0 * s.rel_std,
            "%",
            "Standard deviation of the 2n-nearest-neighbour distances, each over its point's target spacing n·e/ρ(q), before repulsion.",
        )
        .metric(
            "rel_std",
            "Spread against the target, result",
            100.0 * m.rel_std,
            "%",
            "The same after repulsion: lower follows the graded target more evenly.",
        )
        .metric(
            "rel_std_reduction",
            "Spread against the target reduced by",
            reduction,
            "%",
            "How much repulsion evened the spacing relative to the graded target.",
        )
        .metric(
            "rel_mean",
            "Mean distance over target",
            m.rel_mean,
            "",
            "Mean of the neighbour distances over their target spacings: near 1 (a hexagonal packing gives 1.07).",
        );
    let (label, unit) = gp.label;
    let lo = gp.commanded.first().map_or(0.0, |c| c[0]);
    let hi = gp.commanded.last().map_or(0.0, |c| c[0]);
    let bins = gp.commanded.len().saturating_sub(1).max(1);
    let centres: Vec<f64> = (0..bins).map(|k| lo + (hi - lo) * (k as f64 + 0.5) / bins as f64).collect();
    let pct = |v: Vec<f64>| v.into_iter().map(|x| 100.0 * x).collect::<Vec<f64>>();
    r.plots.push(Plot {
        key: "graded_density".into(),
        title: format!("Commanded and measured density along {label}"),
        kind: PlotKind::Line,
        x: Axis::new(label, unit),
        y: Axis::new("Density", "%"),
        group: None,
        series: vec![
            Series::xy("commanded ρ", gp.commanded.iter().map(|c| c[0]).collect(), pct(gp.commanded.iter().map(|c| c[1]).collect())),
            Series::xy("seed (n·e / mean 2n-NN distance)", centres.clone(), pct(binned_mean(&gp.seed, &s.local_density, [lo, hi], bins))),
            Series::xy("repulsion (n·e / mean 2n-NN distance)", centres, pct(binned_mean(&gp.points, &m.local_density, [lo, hi], bins))),
        ],
    });
    let rank = |v: &[f64]| -> Vec<f64> { (0..v.len()).map(|i| i as f64).collect() };
    r.plots.push(Plot {
        key: "kdf_relative".into(),
        title: "Kernel density over the graded target's, sorted".into(),
        kind: PlotKind::Line,
        x: Axis::new("Point (sorted)", ""),
        y: Axis::new("KDF / target", ""),
        group: None,
        series: vec![
            Series::xy("seed", rank(&s.kdf_relative_sorted), s.kdf_relative_sorted.clone()),
            Series::xy("repulsion", rank(&m.kdf_relative_sorted), m.kdf_relative_sorted.clone()),
        ],
    });
    let (edges, seed_counts, counts) = crate::axisym::metrics::shared_histogram(&s.nn_relative, &m.nn_relative, HISTOGRAM_BINS);
    r.plots.push(Plot {
        key: "nn_relative".into(),
        title: "Neighbour distances over the local target spacing".into(),
        kind: PlotKind::Histogram,
        x: Axis::new("Distance / s(q)", ""),
        y: Axis::new("Pairs", ""),
        group: None,
        series: vec![Series::xy("seed", edges.clone(), seed_counts), Series::xy("repulsion", edges, counts)],
    });
    r
}

fn path_report(t: &tour::Tour, d: &uniform::Distribution, holes: bool) -> StageReport {
    let saving = if t.nn_length_mm > 0.0 { 100.0 * (1.0 - t.length_mm / t.nn_length_mm) } else { 0.0 };
    let summary = PathSummary {
        visited: t.order.len(),
        length_mm: t.length_mm,
        nn_length_mm: t.nn_length_mm,
        crossings_removed: t.crossings_removed,
        crossings_left: t.crossings_left,
        poses: t.poses.len(),
        hole_crossings: t.hole_crossings,
    };
    let r = StageReport::new("path", "Joining the points by geodesics", &summary)
        .metric("visited", "Points visited", t.order.len() as f64, "", "Every point once, in one path.")
        .metric("length", "Path length", t.length_mm, "mm", "Along the geodesics on the platform.")
        .metric("nn_length", "Nearest-neighbour length", t.nn_length_mm, "mm", "The path before 2-opt.")
        .metric("saving", "2-opt shortened it by", saving, "%", "What 2-opt removed from the nearest-neighbour path (crossings included).")
        .metric("crossings", "Crossings left", t.crossings_left as f64, "", "Places the path crosses itself in the map: 0 is a clean raster.")
        .metric("poses", "Poses", t.poses.len() as f64, "", "Tool positions with their normal, along the sampled geodesics.")
        .metric("points_in", "Points from the previous stage", d.points.len() as f64, "", "The repulsion's points the path joins.");
    if holes {
        r.metric(
            "hole_crossings",
            "Hops over a hole",
            t.hole_crossings as f64,
            "",
            "Path segments that would cross a hole of Ω: the nozzle travels over them without extruding (0 when the path goes around every hole).",
        )
    } else {
        r
    }
}

/// The nozzle tip of a pose: `h` out along the normal from the layer's surface.
fn tip(p: &tour::Pose, h: f64) -> DVec3 {
    DVec3::from_array(p.position) + DVec3::from_array(p.normal) * h
}

/// The lowest nozzle tip Z over every layer's path, mm (∞ without poses): what must stay on or
/// above the plate (Z ≥ 0).
pub fn lowest_tip_z(tours: &[&tour::Tour], h: f64) -> f64 {
    tours.iter().flat_map(|t| &t.poses).map(|p| tip(p, h).z).fold(f64::INFINITY, f64::min)
}

/// Each layer's tour as one free pass: the tip `h` out along the normal from the layer's
/// surface ((k + 1)·h from the platform), the tool axes `axes[k]` (one per pose: the normals,
/// or smoothed).
fn toolpath_of(tours: &[&tour::Tour], axes: &[Vec<[f64; 3]>], h: f64, width: f64) -> Toolpath {
    let mut passes = Vec::with_capacity(tours.len());
    for (t, axes) in tours.iter().zip(axes) {
        if t.poses.len() < 2 {
            continue;
        }
        // A segment that still crosses a hole is not printed: the path stops at its start and
        // the next one starts at its end, reached along the segment's geodesic without
        // extruding (the writer's approach route), so no strand is laid over the hole.
        let mut cuts: Vec<(usize, usize)> = Vec::with_capacity(t.hole_segments.len());
        let mut start = 0;
        let mut next_hole = t.hole_segments.iter().peekable();
        for (k, seg) in t.samples.iter().enumerate() {
            let end = start + seg.len().saturating_sub(1);
            if next_hole.next_if_eq(&&k).is_some() {
                cuts.push((start, end));
            }
            start = end;
        }
        let mut paths = Vec::with_capacity(cuts.len() + 1);
        let mut from = 0;
        let mut approach = None;
        for (a, b) in cuts.into_iter().chain(std::iter::once((t.poses.len() - 1, t.poses.len() - 1))) {
            if a > from {
                let points: Vec<DVec3> = t.poses[from..=a].iter().map(|p| tip(p, h)).collect();
                let data = PointData { tool_axis: Some(axes[from..=a].iter().map(|a| DVec3::from_array(*a)).collect()), ..PointData::default() };
                paths.push(Path { points, feature: Feature::Infill, width, speed_factor: 1.0, approach: approach.take(), data: Some(Box::new(data)) });
            }
            // The hop's inner samples, at the tip height.
            approach = Some(t.poses[(a + 1).min(b)..b].iter().map(|p| tip(p, h)).collect::<Vec<_>>());
            from = b;
        }
        if !paths.is_empty() {
            passes.push(Pass { kind: PassKind::Free, z: lowest_tip_z(&[t], h), height: h, paths });
        }
    }
    Toolpath { passes }
}

/// Half the size of a point's cross in the map view, in map units.
const CROSS: f32 = 0.004;

/// The map of layer `layer` at `step` (seed, result, path); with `drawable` (a polygon
/// domain) the page offers to draw the outline on it (`meta.draw`: field, pair order).
#[allow(clippy::too_many_arguments)]
fn map_view(domain: &Domain, d: &uniform::Distribution, tour: Option<&tour::Tour>, layer: usize, layers: usize, step: usize, drawable: bool) -> Inspection {
    let index = 3 * layer + step;
    let mut data: Vec<f32> = Vec::new();
    let mut seg = |a: [f64; 2], b: [f64; 2], code: u8| data.extend_from_slice(&[a[1] as f32, a[0] as f32, b[1] as f32, b[0] as f32, code as f32]);
    // Outline of Ω and its holes (x: θ, y: u).
    for ring in std::iter::once(domain.ring()).chain(domain.holes()) {
        for k in 0..ring.len() {
            seg(ring[k], ring[(k + 1) % ring.len()], Feature::Contour.code());
        }
    }
    let pts = if step == 0 { &d.seed_points } else { &d.points };
    if step < 2 {
        for p in pts {
            let (u, t) = (p[0] as f32, p[1] as f32);
            data.extend_from_slice(&[t - CROSS, u, t + CROSS, u, Feature::Lattice.code() as f32]);
            data.extend_from_slice(&[t, u - CROSS, t, u + CROSS, Feature::Lattice.code() as f32]);
        }
    } else if let Some(t) = tour {
        for s in &t.samples {
            for w in s.windows(2) {
                data.extend_from_slice(&[w[0][1] as f32, w[0][0] as f32, w[1][1] as f32, w[1][0] as f32, Feature::Infill.code() as f32]);
            }
        }
    }
    let labels = ["seed points", "after repulsion", "path"];
    // One layer keeps the plain caption; several name the layer.
    let caption = if layers > 1 { format!("layer {} of {layers}: {}", layer + 1, labels[step]) } else { labels[step].to_string() };
    Inspection {
        view: "map".into(),
        shape: Shape::Lines2d,
        index,
        count: 3 * layers,
        stride: Shape::Lines2d.stride(),
        data,
        overlay: Vec::new(),
        meta: serde_json::json!({
            "x_label": "θ (rad)", "y_label": "u", "scale_bar": false, "caption": caption,
            "legend": legend(&[(Feature::Contour, "outline of Ω"), (Feature::Lattice, labels[step.min(1)]), (Feature::Infill, "path (geodesics)")]),
            // x is θ and y is u here; the polygon field holds (u, θ) pairs.
            "draw": if drawable { serde_json::json!({ "path": "job.domain.polygon", "pair": ["y", "x"], "label": "Draw Ω on the map", "min_points": 3 }) } else { serde_json::Value::Null },
        }),
    }
}

/// Meridians and parallels drawn on the platform view.
const MERIDIANS: usize = 24;
const PARALLELS_PER_SEGMENT: usize = 6;
const RING_STEPS: usize = 96;

fn platform_view(p: &Platform, tours: &[&tour::Tour], h: f64) -> Inspection {
    let mut data: Vec<f32> = Vec::new();
    let code = Feature::Contour.code() as f32;
    let k = p.segments.len();
    let steps = k * 32;
    let mut push =
        |a: [f64; 3], b: [f64; 3], c: f32| data.extend_from_slice(&[a[0] as f32, a[1] as f32, a[2] as f32, b[0] as f32, b[1] as f32, b[2] as f32, c]);
    for m in 0..MERIDIANS {
        let th = std::f64::consts::TAU * m as f64 / MERIDIANS as f64;
        for i in 0..steps {
            let (u0, u1) = (k as f64 * i as f64 / steps as f64, k as f64 * (i + 1) as f64 / steps as f64);
            push(platform::position(p, u0, th), platform::position(p, u1, th), code);
        }
    }
    for i in 0..=k * PARALLELS_PER_SEGMENT {
        let u = i as f64 / PARALLELS_PER_SEGMENT as f64;
        for s in 0..RING_STEPS {
            let (a, b) = (std::f64::consts::TAU * s as f64 / RING_STEPS as f64, std::f64::consts::TAU * (s + 1) as f64 / RING_STEPS as f64);
            push(platform::position(p, u, a), platform::position(p, u, b), code);
        }
    }
    // Every layer's path, each tip one layer height out from its layer's surface.
    for t in tours {
        for w in t.poses.windows(2) {
            push(tip(&w[0], h).to_array(), tip(&w[1], h).to_array(), Feature::Infill.code() as f32);
        }
    }
    let meta = serde_json::json!({ "legend": legend(&[(Feature::Contour, "platform (meridians, parallels)"), (Feature::Infill, "path (nozzle tip)")]) });
    Inspection { view: "platform3d".into(), shape: Shape::Lines3d, index: 0, count: 1, stride: Shape::Lines3d.stride(), data, overlay: Vec::new(), meta }
}

/// A view's legend: feature code → what the view draws with it.
fn legend(entries: &[(Feature, &str)]) -> serde_json::Value {
    serde_json::Value::Object(entries.iter().map(|(f, text)| (f.code().to_string(), serde_json::Value::from(*text))).collect())
}

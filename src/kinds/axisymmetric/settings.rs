//! The axisymmetric job's settings as the design holds them (platform, domain Ω, layers), their defaults and the raw forms older designs use.

use super::*;

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

pub(super) fn default_layer_height() -> f64 {
    DEFAULT_LAYER_HEIGHT_MM
}

pub(super) fn default_layers() -> usize {
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
pub(super) struct RawPlatform {
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
pub(super) fn polygon_of(p: &Platform) -> Vec<[f64; 2]> {
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
pub(super) struct RawDomain {
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

/// e of equation 4: the nozzle diameter (the paper: 0.4 mm).
pub(super) fn line_width(design: &Design) -> f64 {
    design.printer.nozzle_diameter_mm
}

use glam::DVec3;
use serde::{Deserialize, Serialize};

/// What a path is, for speeds and for viewers (`;TYPE:` comments).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Feature {
    /// Outermost perimeter loop.
    ExternalPerimeter,
    /// Inner perimeter loops.
    Perimeter,
    /// Sparse infill.
    Infill,
    /// Solid infill (first and top layers).
    SolidInfill,
    /// Lattice struts.
    Lattice,
    /// A contour added around a lattice.
    Contour,
    /// Tensile-specimen handles.
    Handle,
    /// Skirt or brim.
    Skirt,
    /// A wireframe beam printed in free space (freeform jobs).
    Beam,
    /// Support under overhangs (its sparse body).
    Support,
    /// The dense top layers of a support, under the part (and a Z gap).
    SupportInterface,
    /// Straight lines across air, anchored on both sides (round strand, bridge speed, full fan).
    Bridge,
    /// A stretch of perimeter that hangs more than half its width over the layer below
    /// (overhang speed, full fan).
    OverhangPerimeter,
}

impl Feature {
    /// Every feature, in a stable order (its index is the feature's code in preview buffers).
    pub const ALL: [Feature; 13] = [
        Feature::ExternalPerimeter,
        Feature::Perimeter,
        Feature::Infill,
        Feature::SolidInfill,
        Feature::Lattice,
        Feature::Contour,
        Feature::Handle,
        Feature::Skirt,
        Feature::Beam,
        Feature::Support,
        Feature::SupportInterface,
        Feature::Bridge,
        Feature::OverhangPerimeter,
    ];

    /// The name written after `;TYPE:`, as PrusaSlicer's G-code viewer spells it where it has one.
    pub fn gcode_name(self) -> &'static str {
        match self {
            Feature::ExternalPerimeter => "External perimeter",
            Feature::Perimeter => "Perimeter",
            Feature::Infill => "Internal infill",
            Feature::SolidInfill => "Solid infill",
            Feature::Lattice => "Lattice",
            Feature::Contour => "Contour",
            Feature::Handle => "Handle",
            Feature::Skirt => "Skirt/Brim",
            Feature::Beam => "Beam",
            Feature::Support => "Support material",
            Feature::SupportInterface => "Support material interface",
            Feature::Bridge => "Bridge infill",
            Feature::OverhangPerimeter => "Overhang perimeter",
        }
    }

    /// Parses a `;TYPE:` name (PrusaSlicer's, Cura's and weft's); unknown names → `None`.
    pub fn from_gcode_name(name: &str) -> Option<Feature> {
        let n = name.trim();
        Some(match n {
            "External perimeter" | "WALL-OUTER" | "Outer wall" => Feature::ExternalPerimeter,
            "Perimeter" | "WALL-INNER" | "Inner wall" => Feature::Perimeter,
            "Internal infill" | "FILL" | "Sparse infill" => Feature::Infill,
            "Solid infill" | "Top solid infill" | "SKIN" | "Gap fill" => Feature::SolidInfill,
            "Lattice" => Feature::Lattice,
            "Contour" => Feature::Contour,
            "Handle" => Feature::Handle,
            "Skirt/Brim" | "SKIRT" | "Skirt" | "Brim" => Feature::Skirt,
            "Beam" => Feature::Beam,
            "Support material" | "SUPPORT" | "Support" => Feature::Support,
            "Support material interface" | "SUPPORT-INTERFACE" | "Support interface" | "Support transition" => Feature::SupportInterface,
            "Bridge infill" | "Bridge" | "Internal Bridge" => Feature::Bridge,
            "Overhang perimeter" | "Overhang wall" => Feature::OverhangPerimeter,
            _ => return None,
        })
    }

    /// Key as written in JSON (`external_perimeter`).
    pub fn key(self) -> &'static str {
        match self {
            Feature::ExternalPerimeter => "external_perimeter",
            Feature::Perimeter => "perimeter",
            Feature::Infill => "infill",
            Feature::SolidInfill => "solid_infill",
            Feature::Lattice => "lattice",
            Feature::Contour => "contour",
            Feature::Handle => "handle",
            Feature::Skirt => "skirt",
            Feature::Beam => "beam",
            Feature::Support => "support",
            Feature::SupportInterface => "support_interface",
            Feature::Bridge => "bridge",
            Feature::OverhangPerimeter => "overhang_perimeter",
        }
    }

    /// Colour in previews (PrusaSlicer's where it has the feature), `#rrggbb`.
    pub fn color(self) -> &'static str {
        match self {
            Feature::ExternalPerimeter => "#ff7d38",
            Feature::Perimeter => "#ffe64d",
            Feature::Infill => "#b03029",
            Feature::SolidInfill => "#9654cc",
            Feature::Lattice => "#29a3d6",
            Feature::Contour => "#1fb04c",
            Feature::Handle => "#a0a0a0",
            Feature::Skirt => "#00876e",
            Feature::Beam => "#5fb8e0",
            Feature::Support => "#00ff00",
            Feature::SupportInterface => "#008000",
            Feature::Bridge => "#4d80ba",
            Feature::OverhangPerimeter => "#0000ff",
        }
    }

    /// Index in [`Feature::ALL`].
    pub fn code(self) -> u8 {
        Feature::ALL.iter().position(|f| *f == self).unwrap_or(0) as u8
    }
}

/// One continuous extrusion: the nozzle moves through `points` in order, extruding all the way.
/// A closed loop repeats its first point at the end.
#[derive(Clone, Debug, PartialEq)]
pub struct Path {
    /// Points in mm (absolute, model coordinates before the printer's bed offset). At least two.
    pub points: Vec<DVec3>,
    /// What this path is.
    pub feature: Feature,
    /// Extrusion width in mm (takes the place of d_n in GIPPO equation 4).
    pub width: f64,
    /// Multiplies the feature's print speed (1.0 = as configured; GIPPO slows short paths).
    pub speed_factor: f64,
    /// How the nozzle gets here from where the previous path ended. `None`: a free travel
    /// (the writer retracts and hops as configured). `Some(route)`: the nozzle moves through
    /// `route` (intermediate points, may be empty) *without* extruding and without retracting,
    /// e.g. along struts already printed (Chinese-postman "continuous" paths).
    pub approach: Option<Vec<DVec3>>,
    /// Per-point values (flow, feed, tool axis, dwell) for general toolpaths; `None` for the
    /// compact planar form, which writes exactly as before.
    pub data: Option<Box<PointData>>,
}

/// How much material a segment deposits, per point (see [`PointData::flow`]).
#[derive(Clone, Debug, PartialEq)]
pub enum PointFlow {
    /// Extruded cross-section of the segment ending at each point, mm² (entry 0 unused). The
    /// filament fed is `k · EM · length · area / (π f_d² / 4)`; GIPPO equation 4 is the case
    /// `area = LT · w`.
    AreaMm2(Vec<f64>),
    /// Filament fed per mm of the segment ending at each point, mm/mm (entry 0 unused), used
    /// as is (no EM or k applied).
    FilamentPerMm(Vec<f64>),
}

/// Optional per-point values of a [`Path`]. Each vector, when present, has exactly one entry
/// per point of the path. Values that describe a segment (flow, feed) are stored at the
/// segment's *end* point; entry 0 is unused.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PointData {
    /// Material per segment; absent: GIPPO equation 4 with the pass height and path width.
    pub flow: Option<PointFlow>,
    /// Feed of the segment ending at each point, mm/s; absent: the feature's speed × the
    /// path's speed factor.
    pub feed_mm_s: Option<Vec<f64>>,
    /// Tool axis at each point: a unit vector from the nozzle tip towards the head (+Z for a
    /// 3-axis printer). Absent: +Z.
    pub tool_axis: Option<Vec<DVec3>>,
    /// Dwell after reaching each point, s (0: none).
    pub dwell_s: Option<Vec<f64>>,
}

impl PointData {
    /// The problems of `self` for a path of `points` points (lengths, non-finite or negative
    /// values, zero axes), empty when it is usable.
    pub fn problems(&self, points: usize) -> Vec<String> {
        let mut out = Vec::new();
        let mut len = |name: &str, n: usize| {
            if n != points {
                out.push(format!("{name} has {n} values for {points} points"));
            }
        };
        match &self.flow {
            Some(PointFlow::AreaMm2(v)) => len("flow (mm²)", v.len()),
            Some(PointFlow::FilamentPerMm(v)) => len("flow (filament per mm)", v.len()),
            None => {}
        }
        if let Some(v) = &self.feed_mm_s {
            len("feed", v.len());
        }
        if let Some(v) = &self.tool_axis {
            len("tool axis", v.len());
        }
        if let Some(v) = &self.dwell_s {
            len("dwell", v.len());
        }
        let bad = |v: &f64| !v.is_finite() || *v < 0.0;
        match &self.flow {
            Some(PointFlow::AreaMm2(v) | PointFlow::FilamentPerMm(v)) if v.iter().skip(1).any(bad) => {
                out.push("a flow value is negative or not a number".into())
            }
            _ => {}
        }
        if self.feed_mm_s.as_ref().is_some_and(|v| v.iter().skip(1).any(|f| !(f.is_finite() && *f > 0.0))) {
            out.push("a feed is not a positive number".into());
        }
        if self.dwell_s.as_ref().is_some_and(|v| v.iter().any(bad)) {
            out.push("a dwell is negative or not a number".into());
        }
        if self.tool_axis.as_ref().is_some_and(|v| v.iter().any(|a| !a.is_finite() || (a.length() - 1.0).abs() > 1e-6)) {
            out.push("a tool axis is not a unit vector".into());
        }
        out
    }
}

impl Path {
    /// An extrusion at full speed reached by a free travel.
    pub fn new(points: Vec<DVec3>, feature: Feature, width: f64) -> Path {
        Path { points, feature, width, speed_factor: 1.0, approach: None, data: None }
    }

    /// Length in mm.
    pub fn length(&self) -> f64 {
        self.points.windows(2).map(|w| w[0].distance(w[1])).sum()
    }
}

/// What a pass is: it decides which per-layer rules of the writer apply.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PassKind {
    /// A planar layer (slices, lattices, projected lattices). The first such layer gets the
    /// first-layer speed and temperature; the fan starts at `fan_start_layer` counting these.
    #[default]
    Layer,
    /// A free 3D pass (a foam's endless path, a wireframe sequence): no first-layer rules,
    /// its own speeds and flows come from the path's [`PointData`].
    Free,
}

/// One pass of the tool, in print order: a planar layer, or a free 3D pass.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Pass {
    /// What kind of pass this is.
    pub kind: PassKind,
    /// Height of the layer's top in mm (the nominal nozzle Z for planar layers; for a free
    /// pass, its lowest Z).
    pub z: f64,
    /// Layer thickness in mm (LT in GIPPO equation 4).
    pub height: f64,
    /// Paths in print order.
    pub paths: Vec<Path>,
}

impl Pass {
    /// A planar layer.
    pub fn layer(z: f64, height: f64, paths: Vec<Path>) -> Pass {
        Pass { kind: PassKind::Layer, z, height, paths }
    }
}

/// A whole print: passes in print order (planar layers bottom to top).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Toolpath {
    /// Passes in print order.
    pub passes: Vec<Pass>,
}

impl Toolpath {
    /// Total extruded path length in mm.
    pub fn extrusion_length(&self) -> f64 {
        let mut total = 0.0;
        for pass in &self.passes {
            for p in &pass.paths {
                total += p.length();
            }
        }
        total
    }

    /// Points (extruded and on approach routes) of every pass.
    pub fn point_count(&self) -> usize {
        self.passes.iter().flat_map(|l| &l.paths).map(|p| p.points.len() + p.approach.as_ref().map_or(0, Vec::len)).sum()
    }
}

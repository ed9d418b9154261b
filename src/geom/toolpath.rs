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
}

impl Feature {
    /// Every feature, in a stable order (its index is the feature's code in preview buffers).
    pub const ALL: [Feature; 8] = [
        Feature::ExternalPerimeter,
        Feature::Perimeter,
        Feature::Infill,
        Feature::SolidInfill,
        Feature::Lattice,
        Feature::Contour,
        Feature::Handle,
        Feature::Skirt,
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
        }
    }

    /// Parses a `;TYPE:` name (PrusaSlicer's, Cura's and weft's); unknown names → `None`.
    pub fn from_gcode_name(name: &str) -> Option<Feature> {
        let n = name.trim();
        Some(match n {
            "External perimeter" | "WALL-OUTER" | "Outer wall" => Feature::ExternalPerimeter,
            "Perimeter" | "Overhang perimeter" | "WALL-INNER" | "Inner wall" => Feature::Perimeter,
            "Internal infill" | "FILL" | "Sparse infill" => Feature::Infill,
            "Solid infill" | "Top solid infill" | "Bridge infill" | "SKIN" | "Gap fill" => Feature::SolidInfill,
            "Lattice" => Feature::Lattice,
            "Contour" => Feature::Contour,
            "Handle" => Feature::Handle,
            "Skirt/Brim" | "SKIRT" | "Skirt" | "Brim" => Feature::Skirt,
            _ => return None,
        })
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
}

impl Path {
    /// An extrusion at full speed reached by a free travel.
    pub fn new(points: Vec<DVec3>, feature: Feature, width: f64) -> Path {
        Path { points, feature, width, speed_factor: 1.0, approach: None }
    }

    /// Length in mm.
    pub fn length(&self) -> f64 {
        self.points.windows(2).map(|w| w[0].distance(w[1])).sum()
    }
}

/// The paths of one layer, in print order.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ToolpathLayer {
    /// Height of the layer's top in mm (the nominal nozzle Z for planar layers).
    pub z: f64,
    /// Layer thickness in mm (LT in GIPPO equation 4).
    pub height: f64,
    /// Paths in print order.
    pub paths: Vec<Path>,
}

/// A whole print: layers bottom to top.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Toolpath {
    /// Layers bottom to top.
    pub layers: Vec<ToolpathLayer>,
}

impl Toolpath {
    /// Total extruded path length in mm.
    pub fn extrusion_length(&self) -> f64 {
        let mut total = 0.0;
        for layer in &self.layers {
            for p in &layer.paths {
                total += p.length();
            }
        }
        total
    }
}

//! The lattice atlas: 2D patterns generated as polylines, filled over an area larger than each
//! layer's domain (rotated per layer), cropped to the domain, optionally with the domain's
//! contour and tensile handles added. GIPPO paper, "Design generation".
//!
//! Entry: [`generate`]. Output: one [`StrokeLayer`] per layer, for the path optimiser.

use crate::geom::{Polygon, StrokeLayer};
use serde::{Deserialize, Serialize};

/// Default layer thickness, mm (the paper's 0.148 mm).
pub const DEFAULT_LAYER_THICKNESS_MM: f64 = 0.148;
/// Default number of layers.
pub const DEFAULT_LAYERS: u32 = 1;
/// Default rotation between consecutive layers, degrees.
pub const DEFAULT_ROTATION_DEG: f64 = 0.0;

/// A pattern of the atlas with its parameters (mm).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Pattern {
    /// Regular hexagons of circumradius `hexagon_radius_mm`.
    Honeycomb {
        /// Hexagon circumradius, mm. Default 1.
        #[serde(default = "d_hex")]
        hexagon_radius_mm: f64,
    },
    /// Voronoi cells of random seed points (seeded by the design seed).
    Voronoi {
        /// Seed points per mm². Default 0.5.
        #[serde(default = "d_vor")]
        density_per_mm2: f64,
    },
    /// Penrose rhombus (P3) tiling.
    Penrose {
        /// Rhombus edge length, mm. Default 1.
        #[serde(default = "d_cell")]
        cell_size_mm: f64,
    },
    /// Snub-square tiling (3.3.4.3.4).
    SnubSquare {
        /// Edge length, mm. Default 1.
        #[serde(default = "d_cell")]
        cell_size_mm: f64,
    },
    /// Arrowhead auxetic unit cells.
    Arrowhead {
        /// Unit-cell width, mm. Default 2.
        #[serde(default = "d_cell_w")]
        cell_width_mm: f64,
        /// Unit-cell height, mm. Default 2.
        #[serde(default = "d_cell_h")]
        cell_height_mm: f64,
    },
    /// Re-entrant (auxetic) honeycomb.
    ReentrantHoneycomb {
        /// Unit-cell width, mm. Default 2.
        #[serde(default = "d_cell_w")]
        cell_width_mm: f64,
        /// Unit-cell height, mm. Default 2.
        #[serde(default = "d_cell_h")]
        cell_height_mm: f64,
    },
    /// Parallel lines (woodpile when rotated 90° per layer).
    Rectilinear {
        /// Centre-to-centre strand distance, mm. Default 1.
        #[serde(default = "d_cell")]
        strand_distance_mm: f64,
    },
    /// Square grid.
    SquareGrid {
        /// Cell size, mm. Default 1.
        #[serde(default = "d_cell")]
        cell_size_mm: f64,
    },
    /// Equilateral triangle grid.
    TriangleGrid {
        /// Triangle edge, mm. Default 1.
        #[serde(default = "d_cell")]
        cell_size_mm: f64,
    },
}

fn d_hex() -> f64 {
    1.0
}
fn d_vor() -> f64 {
    0.5
}
fn d_cell() -> f64 {
    1.0
}
fn d_cell_w() -> f64 {
    2.0
}
fn d_cell_h() -> f64 {
    2.0
}

impl Default for Pattern {
    fn default() -> Self {
        Pattern::Honeycomb { hexagon_radius_mm: d_hex() }
    }
}

/// A different pattern for one layer (the paper's "different infill per layer").
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LayerOverride {
    /// 0-based layer index.
    pub layer: u32,
    /// Pattern used on that layer.
    pub pattern: Pattern,
}

/// Lattice options (the `lattice` job's `lattice` settings).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Options {
    /// The pattern of every layer (unless overridden).
    pub pattern: Pattern,
    /// Layer thickness (centre-to-centre), mm. Default 0.148.
    pub layer_thickness_mm: f64,
    /// Number of layers (ignored for mesh domains, which have as many as they slice to). Default 1.
    pub layers: u32,
    /// Rotation of the pattern between consecutive layers, degrees. Default 0.
    pub rotation_deg: f64,
    /// Per-layer pattern overrides.
    pub overrides: Vec<LayerOverride>,
    /// Add each region's contour as a path joined into the graph. Default false.
    pub contour: bool,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            pattern: Pattern::default(),
            layer_thickness_mm: DEFAULT_LAYER_THICKNESS_MM,
            layers: DEFAULT_LAYERS,
            rotation_deg: DEFAULT_ROTATION_DEG,
            overrides: Vec::new(),
            contour: false,
        }
    }
}

/// The domain of one layer: where the lattice goes, and where solid handles go.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LayerDomain {
    /// Layer top, mm.
    pub z: f64,
    /// Layer thickness, mm.
    pub height: f64,
    /// Regions filled with the pattern.
    pub regions: Vec<Polygon>,
    /// Regions filled solid with [`crate::geom::Feature::Handle`] lines, joined to the lattice.
    pub handles: Vec<Polygon>,
}

/// What the generator did.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct LatticeReport {
    /// Layers generated.
    pub layers: usize,
    /// Strokes per layer.
    pub strokes_per_layer: Vec<usize>,
    /// Pattern area fraction left open (pores), per layer, with struts `line_width` wide (0–1).
    pub pore_fraction_per_layer: Vec<f64>,
}

/// The generator's output.
#[derive(Clone, Debug, Default)]
pub struct Lattice {
    /// One stroke layer per domain layer.
    pub layers: Vec<StrokeLayer>,
    /// Counts.
    pub report: LatticeReport,
}

/// Why a lattice could not be generated.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum Error {
    /// A pattern parameter is unusable.
    #[error("{field} = {value} is not usable: {fix}")]
    BadParameter {
        /// Parameter name.
        field: &'static str,
        /// Its value.
        value: f64,
        /// Allowed range / remedy.
        fix: String,
    },
    /// The pattern would have too many struts.
    #[error("the lattice would have about {struts} struts on a layer (limit {limit}); use larger cells or a smaller domain")]
    TooDense {
        /// Estimated struts.
        struts: usize,
        /// Limit.
        limit: usize,
    },
    /// Nothing to fill.
    #[error("the domain is empty: there is no area to fill")]
    EmptyDomain,
}

/// Generates the lattice of every layer. `line_width_mm` is the strut width (for pore
/// fractions); `seed` drives every random choice (Voronoi points). `progress` gets 0–1.
pub fn generate(
    domains: &[LayerDomain],
    options: &Options,
    line_width_mm: f64,
    seed: u64,
    progress: &mut dyn FnMut(f32),
) -> Result<Lattice, Error> {
    let _ = (options, line_width_mm, seed, progress);
    if domains.iter().all(|d| d.regions.is_empty() && d.handles.is_empty()) {
        return Err(Error::EmptyDomain);
    }
    Ok(Lattice::default())
}

/// Where the lattice goes (the job's domain). Sizes in mm, centred on X = Y = 0.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Domain {
    /// Rectangle W × H (the paper's 10 × 10 mm grids).
    Rectangle {
        /// Width along X, mm. Default 10.
        #[serde(default = "d_ten")]
        width_mm: f64,
        /// Height along Y, mm. Default 10.
        #[serde(default = "d_ten")]
        height_mm: f64,
    },
    /// Disc (the paper's Ø48 mm ball-burst samples).
    Disc {
        /// Diameter, mm. Default 48.
        #[serde(default = "d_disc")]
        diameter_mm: f64,
    },
    /// Tensile specimen: a lattice `width_mm` × `length_mm` (along X) with a solid handle
    /// `width_mm` × `handle_length_mm` at each end, joined to the lattice.
    TensileSpecimen {
        /// Width (Y), mm. Default 10.
        #[serde(default = "d_ten")]
        width_mm: f64,
        /// Lattice length (X), mm. Default 10.
        #[serde(default = "d_ten")]
        length_mm: f64,
        /// Handle length (X) at each end, mm. Default 3.
        #[serde(default = "d_handle")]
        handle_length_mm: f64,
    },
    /// The layers of the job's input solid, sliced every layer thickness.
    Solid,
}

fn d_ten() -> f64 {
    10.0
}
fn d_disc() -> f64 {
    48.0
}
fn d_handle() -> f64 {
    3.0
}

impl Default for Domain {
    fn default() -> Self {
        Domain::Rectangle { width_mm: 10.0, height_mm: 10.0 }
    }
}

/// The layers of a planar domain (every kind but [`Domain::Solid`], which the pipeline slices):
/// `options.layers` identical layers `options.layer_thickness_mm` apart, the first with its top
/// at one thickness. `None` for [`Domain::Solid`].
pub fn planar_domains(domain: &Domain, options: &Options) -> Option<Vec<LayerDomain>> {
    let _ = (domain, options);
    None
}

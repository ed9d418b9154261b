//! The lattice atlas: 2D patterns generated as polylines, filled over an area larger than each
//! layer's domain (rotated per layer), cropped to the domain, optionally with the domain's
//! contour and tensile handles added. GIPPO paper, "Design generation".
//!
//! Entry: [`generate`]. Output: one [`StrokeLayer`] per layer, for the path optimiser.
//!
//! Geometry of each pattern (all deterministic, identical on native and wasm: only IEEE
//! arithmetic, `sqrt` and `libm` transcendental functions; no hash-map iteration reaches the
//! output):
//! - honeycomb: pointy-top regular hexagons, edge = circumradius, one centred on the origin;
//! - Voronoi: cells of a Poisson point process seeded by the design seed (layer-independent);
//!   edges shorter than [`MIN_PIECE_MM`] are contracted (those nodes get degree 4–5);
//! - Penrose: P3 rhombi by Robinson-triangle deflation of a 10-triangle sun at the origin;
//! - snub square: 3.3.4.3.4, squares turned ±15°;
//! - arrowhead: per `w × h` cell, two chevrons sharing their tips (depths
//!   [`ARROWHEAD_OUTER_DEPTH`]·h and [`ARROWHEAD_INNER_DEPTH`]·h) and a vertical strut;
//! - re-entrant honeycomb: bow-tie hexagons, `w × h` is one period (two bow-ties);
//! - rectilinear: lines along X `strand_distance` apart; square and triangle grids;
//! - wavy honeycomb and wavy square grid: the honeycomb and the square grid with every strut
//!   bent into one sine period of amplitude `amplitude_mm` ([`curved`]), sampled into
//!   `samples_per_strut` segments and output as one curved polyline stroke per strut (one
//!   graph edge each; the printed path is the sampled polyline).
//!
//! Pore fraction = 1 − area of the union of the struts ÷ domain area (each strut a band one
//! strut wide, round joints, a joint counted once). The paper's six patterns default to the
//! sizes that give its Table 1 pore fractions with 0.2 mm struts on a 10 × 10 mm layer
//! (`DEFAULT_*` below; honeycomb 75 %, Voronoi 69 %, Penrose 59 %, snub square 55 %,
//! arrowhead 55 %, re-entrant 63 %); with the default 0.4 mm nozzle the struts are twice as
//! wide and the pores smaller. The grids and the wavy patterns (not in the table) default to
//! 1 mm cells; the wavy struts (amplitude 0.15 mm) are 15 % longer than their chords.

use crate::geom::{DVec2, Feature, Polygon, Stroke, StrokeLayer};
use serde::{Deserialize, Serialize};

mod arrowhead;
mod crop;
mod curved;
mod domain;
mod estimate;
mod graph;
mod grids;
mod honeycomb;
mod penrose;
pub(crate) mod pores;
mod reentrant;
mod snub_square;
mod thumbnail;
mod trim;
mod voronoi;

pub use arrowhead::{INNER_DEPTH as ARROWHEAD_INNER_DEPTH, OUTER_DEPTH as ARROWHEAD_OUTER_DEPTH};
pub use curved::{
    DEFAULT_AMPLITUDE_MM as DEFAULT_WAVE_AMPLITUDE_MM, DEFAULT_SAMPLES_PER_STRUT, MAX_AMPLITUDE_FRACTION, MAX_SAMPLES_PER_STRUT, MIN_SAMPLES_PER_STRUT,
};
pub use domain::{disc_sides, DISC_CHORD_ERROR_MM};
pub use estimate::{estimate, DomainSize, PatternStats};
pub use thumbnail::thumbnail;
pub use trim::{MARGIN_UM as TRIM_MARGIN_UM, MAX_ANGLE_DEG as TRIM_MAX_ANGLE_DEG};
pub use voronoi::VORONOI_SEED_SALT;

use crop::Clipper;
use graph::{Graph, Rect};
use trim::Guard;

/// Most struts one layer may have (generated, before cropping; estimated before generating).
/// A layer's strut graph and its crop take about 120 bytes per strut and the path optimiser
/// about 300 per edge while it works on the layer: 2M struts keep one layer well under half a
/// GiB in the browser worker, and GIPPO's default 500 iterations over them under the time
/// budget (about 3 min on the reference machine).
pub const MAX_STRUTS_PER_LAYER: usize = 2_000_000;
/// Smallest cell size / strand distance, mm.
pub const MIN_CELL_MM: f64 = 0.05;
/// Largest cell size / strand distance, mm.
pub const MAX_CELL_MM: f64 = 1000.0;
/// Largest Voronoi density, points per mm².
pub const MAX_VORONOI_DENSITY: f64 = 100.0;
/// Cropped strut pieces shorter than this (mm) are dropped (slivers the optimiser could not
/// join cleanly).
pub const MIN_PIECE_MM: f64 = 0.01;

/// Default layer thickness, mm (the paper's 0.148 mm).
pub const DEFAULT_LAYER_THICKNESS_MM: f64 = 0.148;
/// Default number of layers.
pub const DEFAULT_LAYERS: u32 = 1;
/// Default rotation between consecutive layers, degrees.
pub const DEFAULT_ROTATION_DEG: f64 = 0.0;

/// Rows of [`Options`] (paths relative to the options, i.e. `job.lattice`): ranges, units,
/// help, shared by the design's form and [`generate`]'s own check. Pattern sizes use
/// [`MIN_CELL_MM`]..[`MAX_CELL_MM`], the range [`validate`] checks override patterns against.
pub const FIELDS: &[crate::settings::Field] = {
    use crate::settings::{int, num, other, Kind};
    &[
        num("pattern.hexagon_radius_mm", "Lattice", "Hexagon radius", "mm", MIN_CELL_MM, MAX_CELL_MM, 0.05, "Distance from a hexagon's centre to its corners."),
        num(
            "pattern.density_per_mm2",
            "Lattice",
            "Seed points",
            "/mm²",
            0.0001,
            MAX_VORONOI_DENSITY,
            0.01,
            "Voronoi seed points per mm² (placed by the random seed).",
        ),
        num("pattern.cell_size_mm", "Lattice", "Cell size", "mm", MIN_CELL_MM, MAX_CELL_MM, 0.05, "Edge length of the tiles: bigger cells, bigger pores."),
        num("pattern.cell_width_mm", "Lattice", "Unit-cell width", "mm", MIN_CELL_MM, MAX_CELL_MM, 0.05, "Width of the repeating cell along X."),
        num("pattern.cell_height_mm", "Lattice", "Unit-cell height", "mm", MIN_CELL_MM, MAX_CELL_MM, 0.05, "Height of the repeating cell along Y."),
        num(
            "pattern.strand_distance_mm",
            "Lattice",
            "Strand distance",
            "mm",
            MIN_CELL_MM,
            MAX_CELL_MM,
            0.05,
            "Distance between neighbouring parallel strands, centre to centre.",
        ),
        num(
            "pattern.amplitude_mm",
            "Lattice",
            "Wave amplitude",
            "mm",
            0.0,
            MAX_CELL_MM * MAX_AMPLITUDE_FRACTION,
            0.01,
            "How far each curved strut swings to either side of the straight line (at most a quarter of the strut).",
        ),
        int(
            "pattern.samples_per_strut",
            "Lattice",
            "Points per curved strut",
            MIN_SAMPLES_PER_STRUT as f64,
            MAX_SAMPLES_PER_STRUT as f64,
            "Straight segments each curved strut is printed as: more is smoother, and a longer G-code.",
        ),
        num("layer_thickness_mm", "Lattice", "Layer thickness", "mm", 0.01, 2.0, 0.001, "Height of each lattice layer (LT of GIPPO equation 4)."),
        int("layers", "Lattice", "Layers", 1.0, 10000.0, "Ignored for a solid domain (it has as many as it slices to)."),
        num("rotation_deg", "Lattice", "Rotation per layer", "°", -360.0, 360.0, 1.0, "Each layer turns the pattern by this much more than the one below."),
        other("contour", "Lattice", "Add the contour", Kind::Bool, &[], "Print each region's outline, joined into the graph."),
    ]
};

/// The atlas, by `kind` name.
pub const PATTERNS: &[&str] = &[
    "honeycomb",
    "voronoi",
    "penrose",
    "snub_square",
    "arrowhead",
    "reentrant_honeycomb",
    "rectilinear",
    "square_grid",
    "triangle_grid",
    "wavy_honeycomb",
    "wavy_square_grid",
];

/// A pattern of the atlas with its parameters (mm).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Pattern {
    /// Regular hexagons of circumradius `hexagon_radius_mm`.
    Honeycomb {
        /// Hexagon circumradius, mm. Default 0.92 (Table 1's 75 % pores with 0.2 mm struts).
        #[serde(default = "d_honeycomb")]
        hexagon_radius_mm: f64,
    },
    /// Voronoi cells of random seed points (seeded by the design seed).
    Voronoi {
        /// Seed points per mm². Default 0.84 (Table 1's 69 % pores with 0.2 mm struts).
        #[serde(default = "d_voronoi")]
        density_per_mm2: f64,
    },
    /// Penrose rhombus (P3) tiling.
    Penrose {
        /// Rhombus edge length, mm. Default 1.05 (Table 1's 59 % pores with 0.2 mm struts).
        #[serde(default = "d_penrose")]
        cell_size_mm: f64,
    },
    /// Snub-square tiling (3.3.4.3.4).
    SnubSquare {
        /// Edge length, mm. Default 1.01 (Table 1's 55 % pores with 0.2 mm struts).
        #[serde(default = "d_snub")]
        cell_size_mm: f64,
    },
    /// Arrowhead auxetic unit cells.
    Arrowhead {
        /// Unit-cell width, mm. Default 1.24 (Table 1's 55 % pores with 0.2 mm struts).
        #[serde(default = "d_arrowhead")]
        cell_width_mm: f64,
        /// Unit-cell height, mm. Default 1.24 (Table 1's 55 % pores with 0.2 mm struts).
        #[serde(default = "d_arrowhead")]
        cell_height_mm: f64,
    },
    /// Re-entrant (auxetic) honeycomb.
    ReentrantHoneycomb {
        /// Unit-cell width, mm. Default 1.73 (Table 1's 63 % pores with 0.2 mm struts).
        #[serde(default = "d_reentrant")]
        cell_width_mm: f64,
        /// Unit-cell height, mm. Default 1.73 (Table 1's 63 % pores with 0.2 mm struts).
        #[serde(default = "d_reentrant")]
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
    /// Honeycomb with sine-curved struts (one strut = one graph edge, printed as a polyline).
    WavyHoneycomb {
        /// Hexagon circumradius (node to node), mm. Default 1.
        #[serde(default = "d_hex")]
        hexagon_radius_mm: f64,
        /// Sine amplitude, mm, at most [`MAX_AMPLITUDE_FRACTION`] × the radius. Default 0.15.
        #[serde(default = "d_amp")]
        amplitude_mm: f64,
        /// Segments per strut, [`MIN_SAMPLES_PER_STRUT`]–[`MAX_SAMPLES_PER_STRUT`]. Default 12.
        #[serde(default = "d_samples")]
        samples_per_strut: u32,
    },
    /// Square grid with sine-curved struts (each grid line a continuous sine wave).
    WavySquareGrid {
        /// Cell size, mm. Default 1.
        #[serde(default = "d_cell")]
        cell_size_mm: f64,
        /// Sine amplitude, mm, at most [`MAX_AMPLITUDE_FRACTION`] × the cell. Default 0.15.
        #[serde(default = "d_amp")]
        amplitude_mm: f64,
        /// Segments per strut, [`MIN_SAMPLES_PER_STRUT`]–[`MAX_SAMPLES_PER_STRUT`]. Default 12.
        #[serde(default = "d_samples")]
        samples_per_strut: u32,
    },
}

fn d_amp() -> f64 {
    DEFAULT_WAVE_AMPLITUDE_MM
}
fn d_samples() -> u32 {
    DEFAULT_SAMPLES_PER_STRUT
}

impl Pattern {
    /// The curve every strut is bent into (curved patterns only).
    pub(crate) fn curve(&self) -> Option<curved::Curve> {
        match *self {
            Pattern::WavyHoneycomb { amplitude_mm, samples_per_strut, .. } | Pattern::WavySquareGrid { amplitude_mm, samples_per_strut, .. } => {
                Some(curved::Curve { amplitude: amplitude_mm, samples: samples_per_strut })
            }
            _ => None,
        }
    }

    /// Printed segments per strut (1 for straight patterns).
    pub fn segments_per_strut(&self) -> u32 {
        self.curve().map_or(1, |c| c.samples.max(1))
    }
}

/// Default sizes of the paper's six patterns: the parameters that give the pore fractions of
/// the paper's Table 1 with its 0.2 mm struts on a 10 × 10 mm layer (pores measured as the
/// union of the struts, [`LatticeReport::pore_fraction_per_layer`]; `tests/it/pore_fraction.rs`).
/// Honeycomb circumradius, mm: 75 % pores.
pub const DEFAULT_HONEYCOMB_RADIUS_MM: f64 = 0.92;
/// Voronoi seed points per mm²: 69 % pores (seed 1; about ±3 points from seed to seed).
pub const DEFAULT_VORONOI_DENSITY_PER_MM2: f64 = 0.84;
/// Penrose rhombus edge, mm: 59 % pores.
pub const DEFAULT_PENROSE_EDGE_MM: f64 = 1.05;
/// Snub-square edge, mm: 55 % pores.
pub const DEFAULT_SNUB_SQUARE_EDGE_MM: f64 = 1.01;
/// Arrowhead unit cell (width = height), mm: 55 % pores.
pub const DEFAULT_ARROWHEAD_CELL_MM: f64 = 1.24;
/// Re-entrant honeycomb unit cell (width = height), mm: 63 % pores.
pub const DEFAULT_REENTRANT_CELL_MM: f64 = 1.73;
/// Cell of the grids and the wavy patterns (not in the paper's table), mm.
pub const DEFAULT_GRID_CELL_MM: f64 = 1.0;

fn d_honeycomb() -> f64 {
    DEFAULT_HONEYCOMB_RADIUS_MM
}
fn d_voronoi() -> f64 {
    DEFAULT_VORONOI_DENSITY_PER_MM2
}
fn d_penrose() -> f64 {
    DEFAULT_PENROSE_EDGE_MM
}
fn d_snub() -> f64 {
    DEFAULT_SNUB_SQUARE_EDGE_MM
}
fn d_arrowhead() -> f64 {
    DEFAULT_ARROWHEAD_CELL_MM
}
fn d_reentrant() -> f64 {
    DEFAULT_REENTRANT_CELL_MM
}
fn d_cell() -> f64 {
    DEFAULT_GRID_CELL_MM
}
fn d_hex() -> f64 {
    DEFAULT_GRID_CELL_MM
}

impl Default for Pattern {
    fn default() -> Self {
        Pattern::Honeycomb { hexagon_radius_mm: d_honeycomb() }
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
#[derive(Clone, Debug, Default, PartialEq, Serialize, serde::Deserialize)]
pub struct LatticeReport {
    /// Layers generated.
    pub layers: usize,
    /// Strokes per layer.
    pub strokes_per_layer: Vec<usize>,
    /// Pattern area fraction left open (pores), per layer, with struts `line_width` wide (0–1):
    /// `1 − area of the union of the struts / region area` (each strut a `line_width`-wide
    /// band with a round joint at every point, overlaps counted once, clipped to the regions;
    /// the paper's "pores area" of Table 1). Contours and handles are not struts.
    pub pore_fraction_per_layer: Vec<f64>,
    /// Lattice struts (cropped pieces) per layer.
    pub struts_per_layer: Vec<usize>,
    /// Cropped pieces shorter than [`MIN_PIECE_MM`] dropped, all layers (including those
    /// trimmed below it at contours and handle outlines; one trimmed away entirely counts once).
    pub dropped_slivers: usize,
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
    /// Options outside the ranges of [`FIELDS`] (the design validator normally reports these
    /// first, with their design paths).
    #[error("{}", crate::settings::describe(problems))]
    BadOptions {
        /// Each value out of range, with the allowed range.
        problems: Vec<crate::settings::Problem>,
    },
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
    /// The work would be over a limit ([`MAX_STRUTS_PER_LAYER`], the shared memory or time
    /// budgets), found by [`estimate`] before generating anything.
    #[error("{0}")]
    OverBudget(#[from] crate::budget::OverBudget),
    /// Nothing to fill.
    #[error("the domain is empty: there is no area to fill")]
    EmptyDomain,
}

/// Generates the lattice of every layer. `line_width_mm` is the strut width (for pore
/// fractions, and the spacing of handle fill lines); `seed` drives every random choice
/// (Voronoi points). `progress` gets 0–1 (once per layer).
///
/// Layer `i` uses its [`LayerOverride`] pattern if there is one (the last one listed wins),
/// else `options.pattern`, turned by `rotation_deg × i` about the origin. The pattern is
/// generated over the layer's regions' bounding box in the pattern's frame (grown by a few
/// cells), cropped to the regions in integer micrometres (boundary included) and output as
/// one two-point [`Feature::Lattice`] stroke per strut piece (µm-rounded points, each
/// geometric edge once). Then, with `options.contour`, each region's loops as closed
/// [`Feature::Contour`] strokes; then each handle's outline and its fill lines along X,
/// `line_width_mm` apart and at least `line_width_mm` in from the outline's X-parallel edges
/// (the outline's bead covers the band next to it), as [`Feature::Handle`] strokes.
///
/// Nothing is printed twice (the analyzer's overlap stays 0): strut pieces and fill lines
/// lose the parts lying within half a line width (plus [`TRIM_MARGIN_UM`]) of a printed loop
/// (contour, handle outline) edge at ≤ [`TRIM_MAX_ANGLE_DEG`] to them, and pieces left
/// shorter than [`MIN_PIECE_MM`] are dropped; struts crossing a loop more steeply still end
/// exactly on it. A loop running in an earlier loop's bead (a region narrower than a line
/// width, a handle against a contour) is likewise opened there into polylines.
pub fn generate(domains: &[LayerDomain], options: &Options, line_width_mm: f64, seed: u64, progress: &mut dyn FnMut(f32)) -> Result<Lattice, Error> {
    if domains.iter().all(|d| d.regions.is_empty() && d.handles.is_empty()) {
        return Err(Error::EmptyDomain);
    }
    if !(line_width_mm.is_finite() && line_width_mm > 0.0 && line_width_mm <= 100.0) {
        return Err(Error::BadParameter { field: "line_width_mm", value: line_width_mm, fix: "use a line width in (0, 100] mm".into() });
    }
    let problems = crate::settings::check(options, FIELDS, "");
    if !problems.is_empty() {
        return Err(Error::BadOptions { problems });
    }
    validate(&options.pattern)?;
    for o in &options.overrides {
        validate(&o.pattern)?;
    }
    estimate(&DomainSize::of_layers(domains), options, line_width_mm).check()?;
    let mut out = Lattice::default();
    let n = domains.len();
    // Identical layers (same regions, pattern and angle) are generated once.
    let mut cache: Vec<(usize, &Pattern, f64)> = Vec::new();
    for (i, d) in domains.iter().enumerate() {
        let pattern = options.overrides.iter().rev().find(|o| o.layer as usize == i).map(|o| &o.pattern).unwrap_or(&options.pattern);
        let angle = (options.rotation_deg * i as f64).rem_euclid(360.0);
        let hit = cache.iter().find(|(k, p, a)| *p == pattern && *a == angle && domains[*k].regions == d.regions && domains[*k].handles == d.handles);
        let (strokes, struts, pore, slivers) = if let Some(&(k, _, _)) = hit {
            let l = &out.layers[k];
            (l.strokes.clone(), out.report.struts_per_layer[k], out.report.pore_fraction_per_layer[k], 0)
        } else {
            let r = layer(d, pattern, angle, options.contour, line_width_mm, seed)?;
            if cache.len() < 16 {
                cache.push((i, pattern, angle));
            }
            r
        };
        out.report.strokes_per_layer.push(strokes.len());
        out.report.struts_per_layer.push(struts);
        out.report.pore_fraction_per_layer.push(pore);
        out.report.dropped_slivers += slivers;
        out.layers.push(StrokeLayer { z: d.z, height: d.height, strokes });
        progress((i + 1) as f32 / n as f32);
    }
    out.report.layers = out.layers.len();
    Ok(out)
}

fn check(field: &'static str, v: f64, lo: f64, hi: f64, lo_open: bool) -> Result<(), Error> {
    let ok = v.is_finite() && v <= hi && if lo_open { v > lo } else { v >= lo };
    if ok {
        Ok(())
    } else {
        let open = if lo_open { "(" } else { "[" };
        Err(Error::BadParameter { field, value: v, fix: format!("use a value in {open}{lo}, {hi}]") })
    }
}

/// Checks a pattern's parameters: cell sizes, radii and strand distances in
/// [[`MIN_CELL_MM`], [`MAX_CELL_MM`]] mm, Voronoi density in (0, [`MAX_VORONOI_DENSITY`]] per mm².
pub fn validate(p: &Pattern) -> Result<(), Error> {
    let c = |f, v| check(f, v, MIN_CELL_MM, MAX_CELL_MM, false);
    match *p {
        Pattern::Honeycomb { hexagon_radius_mm } => c("hexagon_radius_mm", hexagon_radius_mm),
        Pattern::Voronoi { density_per_mm2 } => check("density_per_mm2", density_per_mm2, 0.0, MAX_VORONOI_DENSITY, true),
        Pattern::Penrose { cell_size_mm } | Pattern::SnubSquare { cell_size_mm } => c("cell_size_mm", cell_size_mm),
        Pattern::SquareGrid { cell_size_mm } | Pattern::TriangleGrid { cell_size_mm } => c("cell_size_mm", cell_size_mm),
        Pattern::Arrowhead { cell_width_mm, cell_height_mm } | Pattern::ReentrantHoneycomb { cell_width_mm, cell_height_mm } => {
            c("cell_width_mm", cell_width_mm)?;
            c("cell_height_mm", cell_height_mm)
        }
        Pattern::Rectilinear { strand_distance_mm } => c("strand_distance_mm", strand_distance_mm),
        Pattern::WavyHoneycomb { hexagon_radius_mm: l, amplitude_mm, samples_per_strut }
        | Pattern::WavySquareGrid { cell_size_mm: l, amplitude_mm, samples_per_strut } => {
            c(if matches!(p, Pattern::WavyHoneycomb { .. }) { "hexagon_radius_mm" } else { "cell_size_mm" }, l)?;
            check("amplitude_mm", amplitude_mm, 0.0, MAX_AMPLITUDE_FRACTION * l, false)?;
            let n = samples_per_strut as f64;
            check("samples_per_strut", n, MIN_SAMPLES_PER_STRUT as f64, MAX_SAMPLES_PER_STRUT as f64, false)
        }
    }
}

/// The pattern's characteristic length (a cell's size), mm: the fill area's margin.
fn cell_length(p: &Pattern) -> f64 {
    match *p {
        Pattern::Honeycomb { hexagon_radius_mm } | Pattern::WavyHoneycomb { hexagon_radius_mm, .. } => 2.0 * hexagon_radius_mm,
        Pattern::Voronoi { density_per_mm2 } => 3.0 / density_per_mm2.sqrt(),
        Pattern::Penrose { cell_size_mm }
        | Pattern::SnubSquare { cell_size_mm }
        | Pattern::SquareGrid { cell_size_mm }
        | Pattern::WavySquareGrid { cell_size_mm, .. }
        | Pattern::TriangleGrid { cell_size_mm } => 2.0 * cell_size_mm,
        Pattern::Arrowhead { cell_width_mm, cell_height_mm } | Pattern::ReentrantHoneycomb { cell_width_mm, cell_height_mm } => {
            cell_width_mm.max(cell_height_mm)
        }
        Pattern::Rectilinear { strand_distance_mm } => strand_distance_mm,
    }
}

/// Estimated struts of `p` over `rect` (before cropping).
pub(crate) fn estimate_struts(p: &Pattern, rect: Rect) -> f64 {
    let per_mm2 = match *p {
        Pattern::Honeycomb { hexagon_radius_mm: r } | Pattern::WavyHoneycomb { hexagon_radius_mm: r, .. } => 2.0 / (3f64.sqrt() * r * r),
        Pattern::Voronoi { density_per_mm2 } => 3.0 * density_per_mm2,
        Pattern::Penrose { cell_size_mm: a } => 2.5 / (a * a),
        Pattern::SnubSquare { cell_size_mm: a } => 2.7 / (a * a),
        Pattern::SquareGrid { cell_size_mm: a } | Pattern::WavySquareGrid { cell_size_mm: a, .. } => 2.0 / (a * a),
        Pattern::TriangleGrid { cell_size_mm: a } => 3.5 / (a * a),
        Pattern::Arrowhead { cell_width_mm: w, cell_height_mm: h } => 5.0 / (w * h),
        Pattern::ReentrantHoneycomb { cell_width_mm: w, cell_height_mm: h } => 6.0 / (w * h),
        Pattern::Rectilinear { strand_distance_mm: s } => {
            return (rect.max.y - rect.min.y) / s + 1.0;
        }
    };
    per_mm2 * rect.area()
}

/// The pattern's strut graph over `rect` (pattern frame), after the density guard.
pub(crate) fn pattern_graph(p: &Pattern, rect: Rect, seed: u64) -> Result<Graph, Error> {
    let est = estimate_struts(p, rect);
    let limit = MAX_STRUTS_PER_LAYER as f64;
    if est.is_nan() || est > limit {
        let fix = estimate::denser_fix(p, est, limit);
        return Err(Error::OverBudget(crate::budget::OverBudget { what: "struts on one layer".into(), value: est, limit, unit: "", fix }));
    }
    let mut g = match *p {
        Pattern::Honeycomb { hexagon_radius_mm } => honeycomb::honeycomb(hexagon_radius_mm, rect),
        Pattern::Voronoi { density_per_mm2 } => voronoi::voronoi(density_per_mm2, seed, rect),
        Pattern::Penrose { cell_size_mm } => penrose::penrose(cell_size_mm, rect),
        Pattern::SnubSquare { cell_size_mm } => snub_square::snub_square(cell_size_mm, rect),
        Pattern::Arrowhead { cell_width_mm, cell_height_mm } => arrowhead::arrowhead(cell_width_mm, cell_height_mm, rect),
        Pattern::ReentrantHoneycomb { cell_width_mm, cell_height_mm } => reentrant::reentrant(cell_width_mm, cell_height_mm, rect),
        Pattern::Rectilinear { strand_distance_mm } => grids::rectilinear(strand_distance_mm, rect),
        Pattern::SquareGrid { cell_size_mm } => grids::square(cell_size_mm, rect),
        Pattern::TriangleGrid { cell_size_mm } => grids::triangle(cell_size_mm, rect),
        Pattern::WavyHoneycomb { hexagon_radius_mm, .. } => honeycomb::honeycomb(hexagon_radius_mm, rect),
        Pattern::WavySquareGrid { cell_size_mm, .. } => grids::square(cell_size_mm, rect),
    };
    g.contract_short(MIN_PIECE_MM);
    g.curve = p.curve();
    Ok(g)
}

/// Crops the graph's edges (turned by (cos, sin)) to `clip`, then trims them out of the
/// beads of `guard`'s loops (see [`trim`]); pushes two-point strokes of `feature`. Pieces
/// shorter than [`MIN_PIECE_MM`] are dropped: those left by cropping (of nonzero length), and
/// those left by trimming (a piece trimmed away entirely counts once). Returns (total kept
/// length mm, dropped slivers).
pub(crate) fn crop_graph(g: &Graph, cs: (f64, f64), clip: &Clipper, guard: Option<&Guard>, feature: Feature, out: &mut Vec<Stroke>) -> (f64, usize) {
    if let Some(curve) = g.curve {
        return curved::crop_curved(g, curve, cs, clip, guard, feature, out);
    }
    let (c, s) = cs;
    let um: Vec<DVec2> = g.pts.iter().map(|p| DVec2::new(c * p.x - s * p.y, s * p.x + c * p.y) * crate::geom::tolerance::UNITS_PER_MM).collect();
    let guard = guard.filter(|g| !g.is_empty());
    let mut pieces = Vec::new();
    let mut keep = Vec::new();
    let (mut total, mut slivers) = (0.0, 0);
    for e in &g.edges {
        pieces.clear();
        clip.clip(um[e[0] as usize], um[e[1] as usize], &mut pieces);
        for pc in &pieces {
            let (a, b) = (crop::snap_mm(pc[0]), crop::snap_mm(pc[1]));
            let len = (b - a).length();
            if len < MIN_PIECE_MM {
                if len > 0.0 {
                    slivers += 1;
                }
                continue;
            }
            let Some(guard) = guard else {
                total += len;
                out.push(Stroke { points: vec![a, b], feature, curved: false });
                continue;
            };
            guard.keep(pc[0], pc[1], u32::MAX, &mut keep);
            let d = pc[1] - pc[0];
            let at = |t: f64| {
                if t == 0.0 {
                    a
                } else if t == 1.0 {
                    b
                } else {
                    crop::snap_mm(pc[0] + d * t)
                }
            };
            let (mut kept, mut short) = (false, 0);
            for &(t0, t1) in &keep {
                let (p, q) = (at(t0), at(t1));
                let len = (q - p).length();
                if len < MIN_PIECE_MM {
                    short += usize::from(len > 0.0);
                    continue;
                }
                kept = true;
                total += len;
                out.push(Stroke { points: vec![p, q], feature, curved: false });
            }
            // A piece trimmed away entirely counts as one sliver.
            slivers += if kept || short > 0 { short } else { 1 };
        }
    }
    (total, slivers)
}

/// A ring's points on the µm grid (mm), without repeats or the closing point; None when it
/// has fewer than 3.
fn ring_points(ring: &[DVec2]) -> Option<Vec<DVec2>> {
    let mut pts: Vec<DVec2> = ring.iter().map(|&p| crop::snap_mm(crop::to_um_grid(p))).collect();
    pts.dedup();
    while pts.len() > 1 && pts.first() == pts.last() {
        pts.pop();
    }
    (pts.len() >= 3).then_some(pts)
}

/// Ring `tag` of `guard` (its points `pts`) as strokes of `feature`: one closed loop, or, where
/// it runs within the bead of an earlier ring (a region narrower than a line width, a handle
/// against a contour), the open polylines left after trimming those parts away (see [`trim`]).
fn ring_strokes(pts: &[DVec2], tag: u32, guard: &Guard, feature: Feature, out: &mut Vec<Stroke>) {
    let n = pts.len();
    let um: Vec<DVec2> = pts.iter().map(|&p| crop::to_um_grid(p)).collect();
    let mut keep = Vec::new();
    // Kept pieces in ring order: (edge, t0, t1).
    let mut pieces: Vec<(usize, f64, f64)> = Vec::new();
    for i in 0..n {
        guard.keep(um[i], um[(i + 1) % n], tag, &mut keep);
        pieces.extend(keep.iter().map(|&(t0, t1)| (i, t0, t1)));
    }
    if pieces.len() == n && pieces.iter().all(|&(_, t0, t1)| t0 == 0.0 && t1 == 1.0) {
        let mut points = pts.to_vec();
        points.push(pts[0]);
        out.push(Stroke { points, feature, curved: false });
        return;
    }
    let at = |i: usize, t: f64| {
        if t == 0.0 {
            pts[i]
        } else if t == 1.0 {
            pts[(i + 1) % n]
        } else {
            crop::snap_mm(um[i] + (um[(i + 1) % n] - um[i]) * t)
        }
    };
    let mut lines: Vec<Vec<DVec2>> = Vec::new();
    let mut prev: Option<(usize, f64)> = None;
    for &(i, t0, t1) in &pieces {
        let joined = matches!(prev, Some((j, 1.0)) if j + 1 == i && t0 == 0.0);
        if !joined {
            lines.push(vec![at(i, t0)]);
        }
        lines.last_mut().unwrap().push(at(i, t1));
        prev = Some((i, t1));
    }
    // The piece running through the ring's first point joins the last one to the first.
    if lines.len() > 1 {
        if let (Some(&(i_last, _, 1.0)), Some(&(0, 0.0, _))) = (pieces.last(), pieces.first()) {
            if i_last == n - 1 {
                let first = lines.remove(0);
                lines.last_mut().unwrap().extend_from_slice(&first[1..]);
            }
        }
    }
    for mut line in lines {
        line.dedup();
        // Ends shorter than a sliver go (the path graph could not tell their points apart).
        while line.len() >= 2 && (line[1] - line[0]).length() < MIN_PIECE_MM {
            line.remove(0);
        }
        while line.len() >= 2 && (line[line.len() - 1] - line[line.len() - 2]).length() < MIN_PIECE_MM {
            line.pop();
        }
        if line.len() >= 2 {
            out.push(Stroke { points: line, feature, curved: false });
        }
    }
}

/// One layer: (strokes, lattice struts, pore fraction, dropped slivers).
fn layer(d: &LayerDomain, pattern: &Pattern, angle_deg: f64, contour: bool, line_width: f64, seed: u64) -> Result<(Vec<Stroke>, usize, f64, usize), Error> {
    let mut strokes = Vec::new();
    let mut slivers = 0;
    let rad = angle_deg.to_radians();
    let (c, s) = if angle_deg == 0.0 { (1.0, 0.0) } else { (libm::cos(rad), libm::sin(rad)) };
    // Regions' bounding box in the pattern frame (turned back by the layer angle).
    let back = d.regions.iter().flat_map(|p| p.outer.iter()).map(|p| DVec2::new(c * p.x + s * p.y, -s * p.x + c * p.y));
    let back: Vec<DVec2> = back.collect();
    // The printed loops: contours (when asked for), then handle outlines. Struts and handle
    // fill lines must not run along them, nor a loop along an earlier one.
    let mut rings: Vec<Vec<DVec2>> = Vec::new();
    let mut contour_rings = 0;
    if contour {
        for poly in &d.regions {
            rings.extend(std::iter::once(&poly.outer).chain(poly.holes.iter()).filter_map(|r| ring_points(r)));
        }
        contour_rings = rings.len();
    }
    let mut handle_rings = Vec::new();
    for h in &d.handles {
        let k = rings.len();
        rings.extend(std::iter::once(&h.outer).chain(h.holes.iter()).filter_map(|r| ring_points(r)));
        handle_rings.push(k..rings.len());
    }
    let guard = Guard::new(&rings, line_width);
    if let Some(bb) = Rect::of_points(back.iter()) {
        let rect = bb.grown(cell_length(pattern));
        let g = pattern_graph(pattern, rect, seed)?;
        let clip = Clipper::new(&d.regions);
        (_, slivers) = crop_graph(&g, (c, s), &clip, Some(&guard), Feature::Lattice, &mut strokes);
    }
    let struts = strokes.len();
    for (k, ring) in rings[..contour_rings].iter().enumerate() {
        ring_strokes(ring, k as u32, &guard, Feature::Contour, &mut strokes);
    }
    for (h, ks) in d.handles.iter().zip(handle_rings) {
        for k in ks {
            ring_strokes(&rings[k], k as u32, &guard, Feature::Handle, &mut strokes);
        }
        let Some(bb) = Rect::of_points(h.outer.iter()) else { continue };
        // Fill lines strictly inside: the outline's own bead covers the band next to it, so
        // the first line is one line width in from the outline's X-parallel edges.
        let mut g = Graph::default();
        let k_max = libm::floor((bb.max.y - bb.min.y) / line_width - 2.0 + 1e-9);
        if k_max >= 0.0 {
            for k in 0..=(k_max as i64) {
                let y = bb.min.y + line_width * (1.0 + k as f64);
                g.seg(DVec2::new(bb.min.x - 1.0, y), DVec2::new(bb.max.x + 1.0, y));
            }
        }
        let clip = Clipper::new(std::slice::from_ref(h));
        let (_, sl) = crop_graph(&g, (1.0, 0.0), &clip, Some(&guard), Feature::Handle, &mut strokes);
        slivers += sl;
    }
    let pore = pores::pore_fraction(&d.regions, &strokes[..struts], line_width);
    Ok((strokes, struts, pore, slivers))
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
///
/// Rectangle and disc are centred on the origin (the disc an inscribed polygon with a chord
/// error under [`DISC_CHORD_ERROR_MM`]); the tensile specimen's lattice region is
/// `length × width` centred, with a `handle_length × width` handle abutting each end (sharing
/// the lattice's end edges). Unusable sizes (≤ 0, not finite) give layers with no regions.
pub fn planar_domains(domain: &Domain, options: &Options) -> Option<Vec<LayerDomain>> {
    domain::planar(domain, options)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(h: f64) -> Rect {
        Rect { min: DVec2::splat(-h), max: DVec2::splat(h) }
    }

    fn lengths(g: &Graph) -> Vec<f64> {
        g.edges.iter().map(|e| (g.pts[e[0] as usize] - g.pts[e[1] as usize]).length()).collect()
    }

    fn degrees(g: &Graph) -> Vec<usize> {
        let mut d = vec![0; g.pts.len()];
        for e in &g.edges {
            d[e[0] as usize] += 1;
            d[e[1] as usize] += 1;
        }
        d
    }

    /// Degrees of vertices within `r` of the origin.
    fn inner_degrees(g: &Graph, r: f64) -> Vec<usize> {
        let d = degrees(g);
        (0..g.pts.len()).filter(|&i| g.pts[i].length() < r).map(|i| d[i]).collect()
    }

    #[test]
    fn penrose_edges_are_exactly_the_cell_size() {
        for a in [1.0, 0.37, 5.0] {
            let g = penrose::penrose(a, square(8.0 * a));
            assert!(g.edges.len() > 200);
            for l in lengths(&g) {
                assert!((l - a).abs() < 1e-6 * a.max(1.0), "edge {l} for {a}");
            }
            let d = inner_degrees(&g, 6.0 * a);
            assert!(d.iter().all(|&k| (3..=7).contains(&k)), "{d:?}");
            // The sun: the centre has five edges (the 10 triangles merged into 5 thin rhombi).
            assert!(d.contains(&5));
        }
    }

    #[test]
    fn snub_square_is_3_3_4_3_4() {
        let g = snub_square::snub_square(1.0, square(6.0));
        for l in lengths(&g) {
            assert!((l - 1.0).abs() < 1e-9);
        }
        assert!(inner_degrees(&g, 4.0).iter().all(|&k| k == 5));
        // 10 edges and 4 vertices per period L² = (2 + √3) a².
        let n = g.pts.iter().filter(|p| p.x.abs() < 4.0 && p.y.abs() < 4.0).count() as f64;
        assert!((n / 64.0 - 4.0 / (2.0 + 3f64.sqrt())).abs() < 0.1, "{n}");
    }

    #[test]
    fn voronoi_vertices_are_equidistant_from_three_points() {
        let rect = square(5.0);
        let g = voronoi::voronoi(2.0, 11, rect);
        let pts = voronoi::points(2.0, 11, rect.grown(3.0 / 2f64.sqrt()));
        let mut checked = 0;
        for v in g.pts.iter().filter(|p| p.length() < 3.0) {
            let mut d: Vec<f64> = pts.iter().map(|s| (*s - *v).length()).collect();
            d.sort_by(f64::total_cmp);
            assert!(d[2] - d[0] < 0.011, "vertex {v}: {:?}", &d[..4]);
            checked += 1;
        }
        assert!(checked > 50);
        // No bisector edge crosses another: every edge is at most as long as the box.
        assert!(lengths(&g).iter().all(|&l| l > 0.0 && l < 10.0));
    }

    #[test]
    fn voronoi_points_are_layer_independent() {
        let a = voronoi::points(1.0, 5, square(4.0));
        let b = voronoi::points(1.0, 5, square(6.0));
        let inner: Vec<DVec2> = b.iter().copied().filter(|p| p.x.abs() <= 4.0 && p.y.abs() <= 4.0).collect();
        assert_eq!(a, inner);
        // Poisson density: about 64 points in 64 mm² (± 4 σ).
        assert!((a.len() as f64 - 64.0).abs() < 32.0, "{}", a.len());
    }

    #[test]
    fn honeycomb_and_reentrant_edges() {
        let g = honeycomb::honeycomb(1.0, square(5.0));
        assert!(lengths(&g).iter().all(|l| (l - 1.0).abs() < 1e-12));
        assert!(inner_degrees(&g, 3.0).iter().all(|&k| k == 3));
        let g = reentrant::reentrant(2.0, 2.0, square(5.0));
        assert!(inner_degrees(&g, 3.0).iter().all(|&k| k == 3));
        // Struts per unit cell: 6.
        let n = g.edges.iter().filter(|e| {
            let m = (g.pts[e[0] as usize] + g.pts[e[1] as usize]) * 0.5;
            m.x >= 0.1 && m.x < 2.1 && m.y >= 0.1 && m.y < 2.1
        });
        assert_eq!(n.count(), 6);
        let g = arrowhead::arrowhead(2.0, 2.0, square(5.0));
        let n = g.edges.iter().filter(|e| {
            let m = (g.pts[e[0] as usize] + g.pts[e[1] as usize]) * 0.5;
            m.x >= 0.1 && m.x < 2.1 && m.y >= 0.1 && m.y < 2.1
        });
        assert_eq!(n.count(), 5);
    }

    #[test]
    fn estimates_track_real_counts() {
        let rect = square(10.0);
        for p in [
            Pattern::Honeycomb { hexagon_radius_mm: 1.0 },
            Pattern::Voronoi { density_per_mm2: 1.0 },
            Pattern::Penrose { cell_size_mm: 1.0 },
            Pattern::SnubSquare { cell_size_mm: 1.0 },
            Pattern::Arrowhead { cell_width_mm: 2.0, cell_height_mm: 2.0 },
            Pattern::ReentrantHoneycomb { cell_width_mm: 2.0, cell_height_mm: 2.0 },
            Pattern::SquareGrid { cell_size_mm: 1.0 },
            Pattern::TriangleGrid { cell_size_mm: 1.0 },
        ] {
            let est = estimate_struts(&p, rect);
            let g = pattern_graph(&p, rect, 1).unwrap();
            let inside = g
                .edges
                .iter()
                .filter(|e| {
                    let m = (g.pts[e[0] as usize] + g.pts[e[1] as usize]) * 0.5;
                    m.x.abs() < 10.0 && m.y.abs() < 10.0
                })
                .count() as f64;
            assert!((inside / est - 1.0).abs() < 0.15, "{p:?}: {inside} vs {est}");
        }
    }
}

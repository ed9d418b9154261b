//! The path optimiser's statement of its work (issue 7): graph edges, GIPPO steps, the
//! odd-node matching, the paths and toolpath segments it will make, its peak memory and
//! time, from the size of its input, without building a graph.

use super::{Method, Options, Order};
use crate::budget::Estimate;
use crate::geom::StrokeLayer;

/// Most GIPPO steps (iterations × edges, all layers) one run may take: at the calibrated cost
/// of big layers ([`GIPPO_STEP_LARGE`]) that is the time budget,
/// [`crate::budget::MAX_STAGE_SECONDS`]; refusing on the count names the fix (the
/// iterations that fit).
pub const MAX_GIPPO_STEPS: f64 = 5e9;

// Times on the reference machine (one core, release), calibrated with
// `cargo run --release --example lattice_calibrate paths 40 160`: CPU time of
// [`super::optimise`] on every atlas pattern over 40 mm and 160 mm squares and discs (10k–1M
// edges per layer) with each method; GIPPO per step from 21 − 1 iterations. Most costs per
// item grow with the layer, from a layer in cache (`…_SMALL`, ≤ [`SMALL_EDGES`]) to one in
// memory (`…_LARGE`, ≥ 16× that): see [`by_size`].

/// Per edge: building the layer graph (splitting at crossings, merging nodes), making the
/// paths and their points.
const EDGE_GRAPH_SMALL: f64 = 0.6e-6;
/// See [`EDGE_GRAPH_SMALL`].
const EDGE_GRAPH_LARGE: f64 = 1.0e-6;
/// Per GIPPO step (an edge in an iteration) on a layer of at most [`GIPPO_SMALL_EDGES`] (in
/// cache).
const GIPPO_STEP_SMALL: f64 = 0.05e-6;
/// Per GIPPO step on a layer of 32× [`GIPPO_SMALL_EDGES`] or more, log-interpolated between:
/// every path starts at a random node, a cache miss once the node records outgrow the cache.
/// Measured (honeycomb of 0.2 mm cells): 0.02 µs at 12k edges, 0.06 µs at 330k, 0.15 µs at
/// 740k, 0.18 µs at 1.15M (a 200 mm square); Penrose and snub square 0.16 µs at 330k.
const GIPPO_STEP_LARGE: f64 = 0.18e-6;
/// See [`GIPPO_STEP_LARGE`].
const GIPPO_SMALL_EDGES: f64 = 50_000.0;
/// Per edge of the Euler circuits and the cutting into paths (euler), beyond the graph.
const EULER_EDGE: f64 = 0.15e-6;
/// Per odd node of the Euclidean matching (euler).
const EULER_ODD: f64 = 2.5e-6;
/// Per edge of the continuous walks (Dijkstra searches, circuits), beyond the graph.
const CONTINUOUS_EDGE: f64 = 0.6e-6;
/// Per odd node of the graph-distance matching (continuous).
const CONTINUOUS_ODD: f64 = 4.0e-6;
/// Per path of the travel-minimising order (nearest neighbour and 2-opt).
const ORDER_PATH: f64 = 3.0e-6;
/// Layers of at most this many edges are "small" (in cache).
const SMALL_EDGES: f64 = 20_000.0;

/// The cost per item on a layer of `edges` edges: `small` up to [`SMALL_EDGES`], `large`
/// from 16× that on, log-interpolated between.
fn by_size(small: f64, large: f64, edges: f64) -> f64 {
    let x = ((edges / SMALL_EDGES).max(1.0).ln() / 16f64.ln()).min(1.0);
    small + (large - small) * x
}

/// Peak bytes per graph edge while a layer is optimised: the raw segments and splits, the
/// node merger, the graph (nodes, edges, incidences, components), GIPPO's buffers (or the
/// matching's candidates and the augmented multigraph) and the chains.
const BYTES_PER_EDGE_WORKING: f64 = 320.0;
/// Bytes of one output path (the `Path` and its heap blocks' overhead) and of one point.
const BYTES_PER_PATH: f64 = 112.0;
/// See [`BYTES_PER_PATH`].
const BYTES_PER_POINT: f64 = 24.0;

/// GIPPO paths per odd node pair (the proven minimum): measured over the atlas patterns on
/// 40–160 mm domains, GIPPO (500 iterations) makes 1.0–1.3× the minimum.
const GIPPO_PATHS_PER_BOUND: f64 = 1.15;
/// Travelled (duplicated) struts per odd node of a continuous walk (each pair of odd nodes is
/// joined along the graph, 1–2 struts apart on lattices).
const CONTINUOUS_TRAVEL_PER_ODD: f64 = 0.8;

/// What the path optimiser's estimate needs of its input.
#[derive(Clone, Debug, PartialEq)]
pub struct Work {
    /// Layers.
    pub layers: usize,
    /// Stroke segments, all layers (graph edges before splitting at crossings).
    pub edges: f64,
    /// Stroke segments of the largest layer.
    pub edges_max_layer: f64,
    /// Odd-degree nodes, all layers; `None` when unknown (taken as one per edge, an upper
    /// bound for the costs).
    pub odd_nodes: Option<f64>,
    /// Printed length, mm.
    pub length_mm: f64,
}

impl Work {
    /// The work of actual stroke layers (O(strokes); odd nodes unknown).
    pub fn of_layers(layers: &[StrokeLayer]) -> Work {
        let (mut edges, mut max, mut length) = (0.0, 0.0f64, 0.0);
        for l in layers {
            let mut here = 0.0;
            for s in &l.strokes {
                here += s.points.len().saturating_sub(1) as f64;
                length += s.points.windows(2).map(|w| w[0].distance(w[1])).sum::<f64>();
            }
            edges += here;
            max = max.max(here);
        }
        Work { layers: layers.len(), edges, edges_max_layer: max, odd_nodes: None, length_mm: length }
    }

    /// The work the lattice stage's estimate states (its `layers`, `edges`,
    /// `edges_max_layer`, `odd_nodes` and `length_mm`).
    pub fn of_lattice(e: &Estimate) -> Work {
        Work {
            layers: e.get("layers") as usize,
            edges: e.get("edges"),
            edges_max_layer: e.get("edges_max_layer"),
            odd_nodes: Some(e.get("odd_nodes")),
            length_mm: e.get("length_mm"),
        }
    }
}

/// States the path optimiser's work on `work` with `options` (O(1)): quantities (keys)
/// `layers`, `edges`, `gippo_steps` (GIPPO: iterations × edges), `matched_nodes` (euler,
/// continuous: odd nodes paired), `paths` and `segments` (what the writer gets: extrusion
/// segments, one travel per path and the approach points of continuous walks: a toolpath's
/// [`crate::geom::Toolpath::point_count`]), `length_mm`; refused over [`MAX_GIPPO_STEPS`] or the
/// shared budgets.
pub fn estimate(work: &Work, options: &Options) -> Estimate {
    let edges = work.edges;
    let odd = work.odd_nodes.unwrap_or(edges).min(2.0 * edges);
    let layers = work.layers as f64;
    let mean_layer = if layers > 0.0 { edges / layers } else { 0.0 };
    let iterations = options.iterations as f64;
    // Costs per item at the size of a typical layer.
    let layer = mean_layer.max(work.edges_max_layer.min(edges));
    let mut seconds = edges * by_size(EDGE_GRAPH_SMALL, EDGE_GRAPH_LARGE, layer);
    let (mut steps, mut matched) = (0.0, 0.0);
    let (paths, approach) = match options.method {
        Method::GippoMax | Method::GippoMin => {
            steps = iterations * edges;
            let paths = (odd / 2.0 * GIPPO_PATHS_PER_BOUND).max(layers.min(edges));
            let x = ((layer / GIPPO_SMALL_EDGES).max(1.0).ln() / 32f64.ln()).min(1.0);
            seconds += steps * (GIPPO_STEP_SMALL + (GIPPO_STEP_LARGE - GIPPO_STEP_SMALL) * x);
            (paths, 0.0)
        }
        Method::Euler => {
            matched = odd;
            seconds += odd * EULER_ODD + edges * EULER_EDGE;
            ((odd / 2.0).max(layers.min(edges)), 0.0)
        }
        Method::Continuous => {
            matched = odd;
            seconds += odd * CONTINUOUS_ODD + edges * CONTINUOUS_EDGE;
            // One walk per component, split into paths where it travels: about one path per
            // odd pair; the travelled struts' nodes are approach points.
            ((odd / 2.0).max(layers.min(edges)), odd * CONTINUOUS_TRAVEL_PER_ODD)
        }
    };
    if options.order == Order::MinTravel {
        seconds += paths * ORDER_PATH;
    }
    // Exact pairing (euler, continuous): per layer the estimate of the method the solve will
    // choose (`matching::choose_method`, as if each layer's odd nodes were one component), at
    // most `exact_pairing_seconds`; its tables: the sparse solve's per node, the dense
    // fallback's n² when it fits too.
    let mut exact_bytes = 0.0;
    if matches!(options.method, Method::Euler | Method::Continuous) && layers > 0.0 {
        let per_layer = (odd / layers).round() as usize;
        let layer_edges = mean_layer.round() as usize;
        let (dense, sparse) = if options.method == Method::Euler {
            (super::matching::exact_seconds(per_layer), super::matching::sparse_seconds(per_layer))
        } else {
            (super::postman::exact_seconds(per_layer, layer_edges), super::postman::sparse_seconds(per_layer, layer_edges))
        };
        let (method, one) = super::matching::choose_method(dense, sparse, options.exact_pairing_seconds);
        seconds += layers * one.min(options.exact_pairing_seconds);
        let n = per_layer as f64;
        exact_bytes = match method {
            super::matching::PairingMethod::Sparse { dense_fallback } => {
                n * super::matching::SPARSE_BYTES_PER_NODE + if dense_fallback { n * n * super::matching::EXACT_BYTES_PER_SQUARE } else { 0.0 }
            }
            super::matching::PairingMethod::Dense => n * n * super::matching::EXACT_BYTES_PER_SQUARE,
            super::matching::PairingMethod::Heuristic => 0.0,
        };
    }
    let segments = edges + paths + approach;
    let bytes = work.edges_max_layer.min(edges) * BYTES_PER_EDGE_WORKING + paths * BYTES_PER_PATH + segments * BYTES_PER_POINT + exact_bytes;
    let fewer = match options.method {
        Method::GippoMax | Method::GippoMin => "use fewer GIPPO iterations, larger cells or a smaller domain",
        _ => "use larger cells, fewer layers or a smaller domain",
    };
    Estimate::new("paths")
        .quantity("layers", "Layers", layers, "")
        .quantity("edges", "Struts to print (graph edges)", edges, "")
        .quantity("gippo_steps", "GIPPO steps (iterations × edges)", steps, "")
        .quantity("matched_nodes", "Odd nodes paired", matched, "")
        .quantity("paths", "Paths", paths, "")
        .quantity("segments", "Toolpath segments", segments, "")
        .quantity("length_mm", "Printed length", work.length_mm, "mm")
        .cost(bytes, seconds)
        // Layers are optimised side by side (1.80× natively, 1.98× in the worker, at 2
        // threads on ball-burst-disc's 2 layers): one layer runs on one thread.
        .parallel(if layers >= 2.0 { 0.9 } else { 0.0 })
        .limit("GIPPO steps (iterations × struts)", steps, MAX_GIPPO_STEPS, "", gippo_fix(options.iterations, steps))
        .budgets(fewer)
}

/// "use at most N iterations …" for `steps` over [`MAX_GIPPO_STEPS`].
fn gippo_fix(iterations: u32, steps: f64) -> String {
    let most = (iterations as f64 * MAX_GIPPO_STEPS / steps).floor().max(1.0);
    format!("use at most {} GIPPO iterations, larger cells or a smaller domain", crate::budget::human(most, ""))
}

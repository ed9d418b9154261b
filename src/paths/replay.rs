//! GIPPO's search replayed on one layer, for the "How it works" step: the best-so-far
//! solution each time an iteration improves on it, thinned to at most [`REPLAY_MAX_FRAMES`]
//! frames (the first, the last and evenly spaced ones) and [`REPLAY_MAX_BYTES`].
//!
//! Nothing is recorded in a normal run: a replay runs GIPPO again on the layer with the same
//! graph, iterations and seeded RNG ([`super::layer_seed`]), so it makes the same draws and
//! ends on the same solution as the run ([`gippo::run_observed`] with a [`gippo::Recorder`]).

use super::gippo::{self, Frame, Recorder};
use super::{build_graph, estimate, layer_seed, validate, Error, Graph, Method, Options, Work};
use crate::geom::StrokeLayer;
use rand_core::SeedableRng;
use rand_pcg::Pcg64;

/// Frames a replay keeps at most.
pub const REPLAY_MAX_FRAMES: usize = 64;
/// Bytes a replay's frames hold at most while recording (fewer frames on a big layer, never
/// fewer than 2: then a layer of over a million struts may hold more).
pub const REPLAY_MAX_BYTES: usize = 16 << 20;

/// A GIPPO run on one layer, recorded.
#[derive(Clone, Debug)]
pub struct Replay {
    /// The layer's graph (the frames' edges and nodes index it).
    pub graph: Graph,
    /// The best-so-far solutions kept, in iteration order; the last is the run's solution.
    pub frames: Vec<Frame>,
    /// Iterations run.
    pub iterations: u32,
    /// Times an iteration beat the best so far (the frames are thinned from these).
    pub improvements: usize,
    /// Equation 1 of every iteration.
    pub iteration_scores: Vec<f64>,
    /// Grown towards the farthest neighbour (`gippo_max`); else the nearest.
    pub maximise: bool,
    /// The frame cap used on this layer (at most [`REPLAY_MAX_FRAMES`]).
    pub cap: usize,
    /// Bytes the frames hold.
    pub recorded_bytes: usize,
}

/// The frame cap for a layer of `edges` edges: [`REPLAY_MAX_FRAMES`], fewer when that many
/// would hold more than [`REPLAY_MAX_BYTES`], at least 2.
pub fn frame_cap(edges: usize) -> usize {
    // A frame holds every edge once, and at most one path (start, first node) per edge; the
    // recorder holds one frame more aside while it runs.
    let per_frame = std::mem::size_of::<Frame>() + 4 * 3 * edges.max(1);
    (REPLAY_MAX_BYTES / per_frame).saturating_sub(1).clamp(2, REPLAY_MAX_FRAMES)
}

/// Replays GIPPO on `layer`, layer number `index` of a job seeded with `seed`: the run's own
/// draws (`options.iterations`, growing as `options.method` says; `gippo_max` for a method
/// that is not GIPPO). Options out of range or work over the budgets: an error, nothing run.
pub fn replay(layer: &StrokeLayer, options: &Options, seed: u64, index: usize) -> Result<Replay, Error> {
    validate(options)?;
    estimate(&Work::of_layers(std::slice::from_ref(layer)), options).check()?;
    let graph = build_graph(layer, options.merge_tolerance_mm);
    let maximise = options.method != Method::GippoMin;
    let cap = frame_cap(graph.edges.len());
    let mut rng = Pcg64::seed_from_u64(layer_seed(seed, index));
    let mut recorder = Recorder::new(cap);
    let solution = gippo::run_observed(&graph, options.iterations, maximise, &mut rng, &mut recorder);
    let improvements = recorder.improvements();
    let frames = recorder.finish();
    let recorded_bytes = frames.iter().map(Frame::bytes).sum();
    Ok(Replay { graph, frames, iterations: options.iterations, improvements, iteration_scores: solution.iteration_scores, maximise, cap, recorded_bytes })
}

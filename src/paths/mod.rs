//! Print-path optimisation (GIPPO paper, "Graph-theory-based trajectory optimization"):
//! strokes → graph per layer → paths that print every edge exactly once.
//!
//! Entry: [`optimise`]. Methods: the paper's randomised greedy `gippo_max` / `gippo_min`,
//! the provably minimal `euler` (max(1, odd/2) paths per component) and `continuous`
//! (one nozzle path per component, pairing edges travelled along printed struts).

//!
//! Pipeline per layer: [`graph::build_graph`] → method (`gippo.rs`, `euler.rs` +
//! `matching.rs`, `postman.rs`) → order (`order.rs`) → [`Pass`] + [`LayerPaths`]
//! (`metrics.rs`). Everything is deterministic (same input and seed → identical output on
//! native and wasm): no hash-map iteration order, no platform transcendental functions,
//! GIPPO's RNG is `rand_pcg::Pcg64` seeded per layer.

pub mod blossom;
pub mod graph;
pub mod matching;
pub mod metrics;

mod estimate;
mod euler;
mod gippo;
mod order;
mod postman;
mod replay;

pub use estimate::{estimate, Work, MAX_GIPPO_STEPS};
pub use gippo::Frame as GippoFrame;
pub use graph::{build_graph, Edge, Graph};
pub use replay::{frame_cap, replay, Replay, REPLAY_MAX_BYTES, REPLAY_MAX_FRAMES};

use crate::geom::{DVec2, DVec3, Feature, Pass, Path, StrokeLayer, Toolpath};
use crate::settings::{choice_docs, int, num, other, Field, Kind};
use metrics::Run;
use rand_core::SeedableRng;
use rand_pcg::Pcg64;
use serde::{Deserialize, Serialize};

/// Default GIPPO iterations (the paper's 500).
pub const DEFAULT_ITERATIONS: u32 = 500;
/// Default node-merge tolerance, mm.
pub const DEFAULT_MERGE_TOLERANCE_MM: f64 = 0.005;
/// Paths with fewer segments than this are "short" and slowed down (the paper's 4).
pub const DEFAULT_SHORT_PATH_SEGMENTS: u32 = 4;
/// Speed factor of short paths (the paper's 60 %).
pub const DEFAULT_SHORT_PATH_SPEED_FACTOR: f64 = 0.6;
/// Estimated seconds per layer the exact odd-node pairing (euler, continuous) may take; beyond
/// it a layer's remaining components are paired by the heuristic with a certified gap. Decided
/// from the work estimate (node counts × measured cost), never a clock: same bytes everywhere.
pub const DEFAULT_EXACT_PAIRING_SECONDS: f64 = 1.0;
/// Direction of the `direction` order, degrees from +X, counter-clockwise.
pub const DEFAULT_DIRECTION_DEG: f64 = 0.0;

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
    /// One nozzle path per component (the open Chinese postman: the fewest mm of struts
    /// travelled twice, not printed, by a walk that may start and end anywhere).
    Continuous,
}

/// Order of the paths within a layer.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Order {
    /// Longest to shortest (the paper's).
    LongestFirst,
    /// Travel-minimising: up to 10 paths a layer the least travel of every order and direction
    /// (exactly); beyond, never more travel than [`Order::Circuit`] (the circuit order rotated
    /// to start near the previous layer's end, or a nearest-neighbour tour, improved by 2-opt
    /// and or-opt, the shorter kept). Continuous walks of several pieces also re-choose their
    /// ends for the travel between pieces.
    MinTravel,
    /// As the method emits the paths (for euler / continuous the walk order: each travel is
    /// one pairing edge).
    Circuit,
    /// Along the direction `direction_deg` (the paper's future work: a user-chosen sorting
    /// direction): paths sorted by where they start along it, each printed in that direction.
    Direction,
    /// From the centre of the layer out, each path printed from its end nearer the centre.
    CentreOut,
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
    /// Estimated seconds per layer of exact pairing (euler, continuous). Default 1.
    pub exact_pairing_seconds: f64,
    /// Direction of the `direction` order, degrees from +X. Default 0.
    pub direction_deg: f64,
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
            exact_pairing_seconds: DEFAULT_EXACT_PAIRING_SECONDS,
            direction_deg: DEFAULT_DIRECTION_DEG,
        }
    }
}

/// Numbers for one layer (what the page plots).
#[derive(Clone, Debug, Default, PartialEq, Serialize, serde::Deserialize)]
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
    /// Equation 1 of every GIPPO iteration, in iteration order (empty for euler/continuous and
    /// for layers without edges).
    pub iteration_scores: Vec<f64>,
    /// LTS % (equation 2) of the chosen solution.
    pub lts_percent: f64,
    /// OE % (equation 3) of the chosen solution.
    pub oe_percent: f64,
    /// Paths with more than 15 nodes (the paper's "long").
    pub long_paths: usize,
    /// Paths with 5–15 nodes.
    pub medium_paths: usize,
    /// Paths with < 5 nodes.
    pub short_paths: usize,
    /// Travel of the layer, mm: from the previous layer's last point to the first path
    /// (0 on the first layer), then between paths — straight for free travels, along the
    /// struts for a continuous walk's travelled runs (what the G-code moves).
    pub travel_mm: f64,
    /// The part of `travel_mm` walked along printed struts without extruding (a continuous
    /// walk's deadhead), mm.
    pub strut_travel_mm: f64,
    /// The part of `travel_mm` moved straight through the air: into the layer, between paths
    /// and between pieces, mm.
    pub free_travel_mm: f64,
    /// The same travel with the paths in circuit order (as the method emits them), mm:
    /// `min_travel` is never above it.
    pub circuit_travel_mm: f64,
    /// Continuous with `min_travel` on a layer of several pieces: deadhead above the fewest
    /// possible that the walks' ends accept because it shortens the travel between pieces by
    /// more (`between_saved_mm`), mm; 0 when the ends cost nothing.
    pub deadhead_added_mm: f64,
    /// What choosing the walks' ends for the travel between pieces saved, deadhead added
    /// included, mm.
    pub between_saved_mm: f64,
    /// Retractions the G-code makes in this layer: free travels (no strut route) at least the
    /// printer's `min_travel_mm` long, 0 with retraction off or a pneumatic printer
    /// ([`crate::gcode::retractions_per_pass`]). They depend on the printer, which [`optimise`]
    /// does not know: it leaves 0, and the `lattice` job counts them with the design's printer.
    pub retractions: usize,
    /// Duplicate edges collapsed while building the graph.
    pub duplicates_collapsed: usize,
    /// Total length of the odd-node pairing, mm. euler: the straight lines pairing *every* odd
    /// node of a piece (a closed pairing: the paths' free travels in circuit order, one of
    /// them skipped). continuous: the struts walked without extruding (deadhead), which pair
    /// all but two odd nodes of a piece (its walk's ends) along the struts. 0 for GIPPO.
    pub pairing_mm: f64,
    /// A proven lower bound on the shortest possible `pairing_mm`, mm (the exact optimum where
    /// solved exactly, else a dual bound): euler — the minimum-weight perfect matching of each
    /// piece's odd nodes by straight distance; continuous — the open Chinese postman's
    /// deadhead of each piece (walks that start and end anywhere). 0 for GIPPO.
    pub pairing_lower_bound_mm: f64,
    /// `pairing_mm` is provably the shortest of the problem `pairing_lower_bound_mm` names
    /// (solved exactly, lengths to the nanometre, or at its lower bound).
    pub pairing_optimal: bool,
    /// Certified gap: `pairing_mm ÷ pairing_lower_bound_mm` (≥ 1; 1 when optimal or nothing
    /// to pair): the pairing is at most this factor above the optimum.
    pub pairing_gap: f64,
}

impl LayerPaths {
    fn set_pairing(&mut self, cost: f64, lower_bound: f64, optimal: bool) {
        self.pairing_mm = cost;
        self.pairing_lower_bound_mm = if optimal { cost } else { lower_bound.min(cost) };
        self.pairing_optimal = optimal;
        self.pairing_gap = if optimal || cost <= 0.0 {
            1.0
        } else if self.pairing_lower_bound_mm > 0.0 {
            cost / self.pairing_lower_bound_mm
        } else {
            f64::INFINITY
        };
    }

    /// "optimal" or "within x %" (the certified gap), with the reason when deadhead was
    /// added for the travel between pieces; "" when nothing was paired.
    pub fn pairing_quality(&self) -> String {
        let base = if self.pairing_mm <= 0.0 && self.pairing_lower_bound_mm <= 0.0 {
            String::new()
        } else if self.pairing_optimal {
            "optimal".into()
        } else if self.pairing_gap.is_finite() {
            format!("within {:.1} %", (self.pairing_gap - 1.0) * 100.0)
        } else {
            "no bound".into()
        };
        if self.deadhead_added_mm > 0.0 {
            format!("{base} (+{:.2} mm of struts for {:.2} mm less travel in all)", self.deadhead_added_mm, self.between_saved_mm)
        } else {
            base
        }
    }
}

/// The optimiser's report.
#[derive(Clone, Debug, Default, PartialEq, Serialize, serde::Deserialize)]
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
    /// Options outside the ranges of [`FIELDS`] (every one listed; the design validator
    /// normally reports these first, with their design paths).
    #[error("{}", crate::settings::describe(problems))]
    BadOptions {
        /// Each value out of range, with the allowed range.
        problems: Vec<crate::settings::Problem>,
    },
    /// The work would be over a limit ([`MAX_GIPPO_STEPS`], the shared memory or time
    /// budgets), found by [`estimate`] before building anything.
    #[error("{0}")]
    OverBudget(#[from] crate::budget::OverBudget),
}

/// Optimises every layer. `line_width_mm` is written into the paths; `seed` seeds GIPPO.
///
/// Each stroke layer becomes one toolpath layer (same z and height) whose paths print every
/// graph edge exactly once. `progress` is called after each layer with the fraction done.
/// The work is estimated first ([`Work::of_layers`], [`estimate`]); over a limit:
/// [`Error::OverBudget`], before anything is built.
pub fn optimise(layers: &[StrokeLayer], options: &Options, line_width_mm: f64, seed: u64, progress: &mut dyn FnMut(f32)) -> Result<Optimised, Error> {
    validate(options)?;
    estimate(&Work::of_layers(layers), options).check()?;
    let mut toolpath = Toolpath::default();
    let mut report = PathsReport { method: Some(options.method), layers: Vec::with_capacity(layers.len()) };
    let mut last_end: Option<DVec2> = None;
    // Each layer's graph and chains side by side (its own seed: `layer_seed`), a window of a
    // few layers a thread at a time so only those graphs are held; then, in turn, the order
    // of each layer's paths, which starts where the layer below ended.
    let window = 2 * crate::par::threads().max(1);
    let n = layers.len();
    let mut solved: std::collections::VecDeque<Solved> = std::collections::VecDeque::new();
    for li in 0..n {
        if solved.is_empty() {
            let end = (li + window).min(n);
            solved.extend(crate::par::map(end - li, &mut |_| {}, |k| solve_layer(&layers[li + k], options, seed, li + k)));
        }
        let Some(Solved { graph, chains, mut stats, gippo_score, postman }) = solved.pop_front() else { break };
        let layer = &layers[li];
        let mut chains = chains;
        let ends: Vec<[DVec2; 2]> = chains.iter().map(|c| order::printed_ends(c, &graph)).collect();
        let circuit: Vec<(usize, bool)> = (0..chains.len()).map(|i| (i, false)).collect();
        stats.circuit_travel_mm = order::travel_of(&circuit, &ends, last_end);
        chains = match options.order {
            Order::LongestFirst => {
                order::sort_longest_first(&mut chains, &graph);
                chains
            }
            Order::MinTravel => {
                let corner = graph.nodes.iter().fold(DVec2::splat(f64::INFINITY), |m, p| m.min(*p));
                order::min_travel(chains, &graph, last_end, corner)
            }
            Order::Circuit => chains,
            Order::Direction => {
                let a = options.direction_deg.to_radians();
                order::sort_directional(chains, &graph, Some(DVec2::new(libm::cos(a), libm::sin(a))))
            }
            Order::CentreOut => order::sort_directional(chains, &graph, None),
        };
        if let (Order::MinTravel, Some(first)) = (options.order, &postman) {
            if chains.len() >= 2 {
                chains = replan_ends(&graph, first, chains, last_end, options.exact_pairing_seconds, &mut stats);
            }
        }

        let mut out = Pass::layer(layer.z, layer.height, Vec::new());
        let mut runs = Vec::new();
        for chain in &chains {
            emit_chain(&graph, chain, layer.z, line_width_mm, options, &mut out.paths, &mut runs);
        }
        stats.paths = out.paths.len();
        stats.score = gippo_score.unwrap_or_else(|| metrics::score(&runs));
        stats.lts_percent = metrics::lts_percent(&runs);
        stats.oe_percent = metrics::oe_percent(&runs);
        let (long, medium, short) = metrics::classes(&runs);
        stats.long_paths = long;
        stats.medium_paths = medium;
        stats.short_paths = short;
        let mut cur = last_end;
        let mut walked = 0.0;
        for p in &out.paths {
            let b = p.points[0].truncate();
            match (&p.approach, cur) {
                (Some(route), Some(a)) => {
                    // Along the struts: order-independent, also in the circuit travel.
                    let mut q = a;
                    for r in route.iter().map(|r| r.truncate()).chain(std::iter::once(b)) {
                        walked += q.distance(r);
                        q = r;
                    }
                }
                (_, Some(a)) => stats.free_travel_mm += a.distance(b),
                (_, None) => {}
            }
            cur = Some(p.points.last().expect("path has points").truncate());
        }
        stats.strut_travel_mm = walked;
        stats.travel_mm = stats.free_travel_mm + walked;
        stats.circuit_travel_mm += walked;
        if let Some(p) = out.paths.last() {
            last_end = Some(p.points.last().expect("path has points").truncate());
        }
        toolpath.passes.push(out);
        report.layers.push(stats);
        progress((li + 1) as f32 / layers.len() as f32);
    }
    Ok(Optimised { toolpath, report })
}

/// One layer's graph and paths before ordering.
struct Solved {
    graph: Graph,
    chains: Vec<Chain>,
    stats: LayerPaths,
    gippo_score: Option<f64>,
    /// Continuous: the walks' pairings, for [`replan_ends`].
    postman: Option<postman::PostmanPaths>,
}

/// Continuous walks of a layer of several pieces, in the order `chains` are printed: each piece's
/// walk re-planned with its ends joined to the travel around it ([`postman::replan`]); kept when
/// the deadhead plus the straight travel (from `from`, the previous layer's end, and between the
/// pieces) is shorter, and then said in `stats`.
fn replan_ends(graph: &Graph, first: &postman::PostmanPaths, chains: Vec<Chain>, from: Option<DVec2>, budget: f64, stats: &mut LayerPaths) -> Vec<Chain> {
    let links = |chs: &[Chain]| {
        let ends: Vec<[DVec2; 2]> = chs.iter().map(|c| order::printed_ends(c, graph)).collect();
        let seq: Vec<(usize, bool)> = (0..chs.len()).map(|i| (i, false)).collect();
        order::travel_of(&seq, &ends, from)
    };
    let re = postman::replan(graph, first, &chains, from, budget);
    let (before, after) = (links(&chains), links(&re.chains));
    let saved = first.pairing_mm + before - (re.pairing_mm + after);
    if saved <= order::GAIN_MM {
        return chains;
    }
    stats.deadhead_added_mm = (re.pairing_mm - first.pairing_mm).max(0.0);
    stats.between_saved_mm = saved;
    stats.set_pairing(re.pairing_mm, re.lower_bound_mm, re.optimal);
    re.chains
}

/// Builds layer `li`'s graph and covers its edges with the method's chains (GIPPO seeded from
/// `seed` and the layer's index alone, so layers can be solved in any order).
fn solve_layer(layer: &StrokeLayer, options: &Options, seed: u64, li: usize) -> Solved {
    let graph = build_graph(layer, options.merge_tolerance_mm);
    let mut stats = LayerPaths {
        nodes: graph.nodes.len(),
        edges: graph.edges.len(),
        degenerate_dropped: graph.degenerate_dropped,
        components: graph.components,
        odd_nodes: graph.odd_nodes(),
        lower_bound_paths: graph.lower_bound_paths(),
        duplicates_collapsed: graph.duplicates_collapsed,
        ..LayerPaths::default()
    };
    let mut gippo_score = None;
    let mut postman = None;
    let chains = match options.method {
        Method::GippoMax | Method::GippoMin => {
            let mut rng = Pcg64::seed_from_u64(layer_seed(seed, li));
            let sol = gippo::run(&graph, options.iterations, options.method == Method::GippoMax, &mut rng);
            gippo_score = Some(sol.score);
            stats.iteration_scores = sol.iteration_scores;
            sol.chains
        }
        Method::Euler => {
            let r = euler::run(&graph, options.exact_pairing_seconds);
            stats.set_pairing(r.pairing_mm, r.lower_bound_mm, r.optimal);
            r.chains
        }
        Method::Continuous => {
            let mut r = postman::run(&graph, options.exact_pairing_seconds);
            stats.set_pairing(r.pairing_mm, r.lower_bound_mm, r.optimal);
            let chains = std::mem::take(&mut r.chains);
            postman = Some(r);
            chains
        }
    };
    Solved { graph, chains, stats, gippo_score, postman }
}

/// GIPPO's RNG seed for layer `index`: the job seed mixed with the layer index (SplitMix64
/// finaliser), so layers get independent streams.
pub fn layer_seed(seed: u64, index: usize) -> u64 {
    let mut z = seed ^ (index as u64).wrapping_add(1).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Checks the options against [`FIELDS`], the ranges the design's form shows.
pub fn validate(options: &Options) -> Result<(), Error> {
    let problems = crate::settings::check(options, FIELDS, "");
    if problems.is_empty() {
        Ok(())
    } else {
        Err(Error::BadOptions { problems })
    }
}

/// Rows of [`Options`] (paths relative to the options): ranges, units, help, shared by the
/// design's form and [`optimise`]'s own check.
pub const FIELDS: &[Field] = &[
    choice_docs(
        other("method", "Paths", "Optimiser", Kind::Choice, &["gippo_max", "gippo_min", "euler", "continuous"], "How the struts are joined into nozzle paths."),
        &[
            "The paper's randomised search (GIPPO): grows paths towards the farthest neighbour; keeps the best of its iterations.",
            "GIPPO growing towards the nearest neighbour instead: the paper's comparison case.",
            "The fewest paths possible (one per pair of odd joints): fewest starts and stops.",
            "One continuous nozzle path per connected piece: the nozzle never lifts, some struts are travelled over twice.",
        ],
    ),
    int("iterations", "Paths", "GIPPO iterations", 1.0, 100000.0, "How many randomised tries GIPPO makes; it keeps the best (the paper uses 500)."),
    choice_docs(
        other("order", "Paths", "Path order", Kind::Choice, &["longest_first", "min_travel", "circuit", "direction", "centre_out"], "The order the paths are printed in."),
        &[
            "Longest paths first, as the paper prints them.",
            "Each next path starts near where the last ended, and each layer near where the one below ended: the least travel possible up to 10 paths a layer, never more than the circuit order beyond.",
            "In the order the optimiser walks them (euler and continuous: one pairing edge between paths).",
            "Swept along a direction you choose (the angle below): every path printed that way.",
            "From the centre of each layer outwards.",
        ],
    ),
    num("direction_deg", "Paths", "Print direction", "°", -360.0, 360.0, 1.0, "For the 'direction' order: the way paths are swept, as an angle from +X (90 = towards +Y)."),
    num("merge_tolerance_mm", "Paths", "Node merge tolerance", "mm", 0.0001, 1.0, 0.001, "Strut ends closer than this are one node."),
    int("short_path_segments", "Paths", "Short path below", 0.0, 1000.0, "Paths with fewer struts than this are printed slower, so they stick (the paper: 4)."),
    num("short_path_speed_factor", "Paths", "Short path speed", "×", 0.01, 1.0, 0.05, "Speed of those short paths, as a fraction of the lattice speed (the paper: 0.6)."),
    num("exact_pairing_seconds", "Paths", "Exact pairing time", "s", 0.0, 60.0, 0.1, "Fewest-paths and continuous: join the odd joints provably optimally when that is estimated to take at most this long per layer; otherwise join them quickly and show how far from optimal they can be."),
];

/// A walk through the graph: a GIPPO / Euler path, or a continuous component walk whose
/// `travel` steps are walked without extruding.
#[derive(Clone, Debug, Default)]
pub(crate) struct Chain {
    /// Nodes visited, `edges.len() + 1` of them.
    pub nodes: Vec<usize>,
    /// Graph edge of every step.
    pub edges: Vec<usize>,
    /// Step walked without extruding (a duplicated strut).
    pub travel: Vec<bool>,
}

impl Chain {
    /// Walks it the other way.
    pub fn reverse(&mut self) {
        self.nodes.reverse();
        self.edges.reverse();
        self.travel.reverse();
    }
}

/// Splits a chain into extrusion paths: every maximal printed run is a [`Path`]; the first is
/// reached by a free travel, later ones through the travelled run before them.
fn emit_chain(graph: &Graph, chain: &Chain, z: f64, width: f64, options: &Options, paths: &mut Vec<Path>, runs: &mut Vec<Run>) {
    let at = |v: usize| DVec3::new(graph.nodes[v].x, graph.nodes[v].y, z);
    let mut k = 0;
    let mut first = true;
    let steps = chain.edges.len();
    while k < steps {
        // Travelled run (approach).
        let t0 = k;
        while k < steps && chain.travel[k] {
            k += 1;
        }
        if k == steps {
            break;
        }
        let approach = if first {
            None
        } else {
            // Intermediate nodes strictly between the previous end and this start.
            let mut pts = Vec::new();
            for i in t0..k {
                if i > t0 {
                    pts.push(at(chain.nodes[i]));
                }
                pts.extend(graph.bends_from(chain.edges[i], chain.nodes[i]).map(|p| DVec3::new(p.x, p.y, z)));
            }
            Some(pts)
        };
        let p0 = k;
        let mut by_feature = [0.0f64; Feature::ALL.len()];
        let mut length = 0.0;
        while k < steps && !chain.travel[k] {
            let e = &graph.edges[chain.edges[k]];
            by_feature[e.feature.code() as usize] += e.length;
            length += e.length;
            k += 1;
        }
        let mut feature = 0;
        for (i, &l) in by_feature.iter().enumerate() {
            if l > by_feature[feature] {
                feature = i;
            }
        }
        let segments = k - p0;
        // Nodes, and the bends of curved struts between them (walked in the chain's direction).
        let mut points: Vec<DVec3> = Vec::with_capacity(k - p0 + 1);
        for i in p0..k {
            points.push(at(chain.nodes[i]));
            points.extend(graph.bends_from(chain.edges[i], chain.nodes[i]).map(|p| DVec3::new(p.x, p.y, z)));
        }
        points.push(at(chain.nodes[k]));
        let speed_factor = if (segments as u64) < options.short_path_segments as u64 { options.short_path_speed_factor } else { 1.0 };
        paths.push(Path { points, feature: Feature::ALL[feature], width, speed_factor, approach, data: None });
        runs.push(Run { length, segments });
        first = false;
    }
}

//! Quasi-uniform points on a domain of an axisymmetric platform (the paper's sections 2.2,
//! 2.3): N from equation (4), a seed (EBNS, GBNS or ERE), then geodesic repulsion energy
//! (GRE) minimisation with normalised energy and forces and a step accepted only when the
//! energy does not rise.

use super::domain::{Domain, DomainProblem};
use super::grading::{Along, Field, Grading};
use super::metrics::{graded_metrics, metrics, Metrics};
use super::platform::Profile;
use super::surface::{Node, PairEval, Surface};
use crate::budget::{Estimate, OverBudget};
use rand_core::{Rng, SeedableRng};
use rand_pcg::Pcg64;
use std::collections::BTreeMap;

/// Default command density ρ_c (fraction).
pub const DEFAULT_DENSITY: f64 = 0.5;
/// Default rasters through each point n.
pub const DEFAULT_RASTERS: u32 = 1;
/// Default repulsion exponent m (the paper's 5: close pairs are penalised hard).
pub const DEFAULT_EXPONENT: f64 = 5.0;
/// Default GRE iteration cap (the paper's 50).
pub const DEFAULT_ITERATIONS: usize = 50;
/// Default energy tolerance: stop when the normalised energy changes by less than this
/// (relative) in an iteration; also the rise a step may make and still be accepted.
pub const DEFAULT_ENERGY_TOLERANCE: f64 = 1e-6;
/// Default displacement tolerance: stop when no point moves more than this fraction of the
/// target spacing s = n·e/ρ_c.
pub const DEFAULT_DISPLACEMENT_TOLERANCE: f64 = 1e-4;
/// Default cutoff, in target spacings: pairs farther apart are left out of energy and forces
/// (0 = all pairs, as the paper). With m = 5 a pair at 3 s weighs 3⁻⁵ ≈ 0.4 % of a nearest
/// pair. On barrel-omega2 and hourglass-omega3 the final 2n-NN standard deviation and mean
/// with the cutoff stay within 25 % and 3 % of the all-pairs run (the test
/// `cutoff_barely_changes_the_result`), at a fraction of the pairs.
pub const DEFAULT_CUTOFF_SPACINGS: f64 = 3.0;
/// Most candidate draws for one seed point of a graded density (each kept with probability
/// ρ(q)²/ρ_max², so the seed follows the target's point density ρ²/(n²e²)).
pub const MAX_GRADED_DRAWS: usize = 100_000;
/// Most points a run may place.
pub const MAX_POINTS: usize = 20_000;
/// Most iterations accepted in options.
pub const MAX_ITERATIONS: usize = 10_000;
/// Step halvings tried before an iteration gives up.
pub const MAX_RETRIES: usize = 12;
/// ERE seed iterations (Euclidean repulsion from a random start).
pub const ERE_ITERATIONS: usize = 30;
/// Cost of one pair evaluation (s, native release, with the fast Clairaut solver): the
/// paper's three examples measure 2–4 µs per pair including the seed and the metrics.
pub const SECONDS_PER_PAIR: f64 = 3e-6;

/// The barrel's Ω₂: a non-convex slice polygon (concave notch near u = 0.5, convex elsewhere)
/// on the upper shoulder, true area ≈ 443 mm² (N = 173 at ρ_c = 0.25, n = 1, e = 0.4 mm).
pub const OMEGA2_POLYGON: &[[f64; 2]] = &[
    [0.5, 0.15965],
    [0.7, 0.0],
    [0.9, 0.03193],
    [1.05, 0.19158],
    [1.1, 0.47895],
    [1.05, 0.79825],
    [0.9, 0.98983],
    [0.7, 1.03773],
    [0.5, 0.87808],
    [0.62, 0.52685],
];

/// The stage's form rows (paths relative to [`Options`]).
pub const FIELDS: &[crate::settings::Field] = {
    use crate::settings::{choice_docs, int, num, other, percent, when, Kind};
    &[
        percent(num(
            "density",
            "Infill points",
            "Command density",
            "%",
            0.01,
            1.0,
            0.01,
            "How much of the patch the infill covers: more density, more points closer together.",
        )),
        int(
            "rasters",
            "Infill points",
            "Lines through each point",
            1.0,
            16.0,
            "n of the paper: how many equally angled rasters cross at each point (1 for a single path).",
        ),
        choice_docs(
            other(
                "seed_method",
                "Infill points",
                "Starting points",
                Kind::Choice,
                &["ebns", "ere", "gbns"],
                "How the points are scattered before the repulsion evens them out.",
            ),
            &[
                "Euclidean blue noise: random points kept a straight-line distance apart (fastest).",
                "Euclidean repulsion: random points pushed apart with straight-line distances (suits odd outlines).",
                "Geodesic blue noise: random points kept a distance along the surface apart (closest to the answer).",
            ],
        ),
        num(
            "exponent",
            "Infill points",
            "Repulsion exponent",
            "",
            1.01,
            32.0,
            0.5,
            "m of the pair energy d⁻ᵐ: larger pushes hardest on the closest pairs (the paper uses 5).",
        ),
        int(
            "iterations",
            "Infill points",
            "Repulsion iterations",
            0.0,
            MAX_ITERATIONS as f64,
            "Most steps of the geodesic repulsion (the paper runs 50); it stops earlier once settled.",
        ),
        num("energy_tolerance", "Infill points", "Energy tolerance", "", 0.0, 0.5, 1e-6, "Stop when the energy changes by less than this fraction in a step."),
        num(
            "displacement_tolerance",
            "Infill points",
            "Movement tolerance",
            "spacings",
            0.0,
            0.5,
            1e-4,
            "Stop when no point moves more than this fraction of the target spacing.",
        ),
        num(
            "cutoff_spacings",
            "Infill points",
            "Interaction range",
            "spacings",
            0.0,
            100.0,
            0.5,
            "Pairs farther apart than this many target spacings are ignored (0 = every pair, as the paper; slower).",
        ),
        crate::settings::Field {
            default: Some("{\"along\":\"u\",\"density_to\":0.25,\"centre_u\":1.0,\"centre_theta_rad\":0.5,\"radius_mm\":10.0}"),
            ..other(
                "grading",
                "Infill points",
                "Graded density",
                Kind::Section,
                &[],
                "Let the density change over the patch instead of staying at the command density.",
            )
        },
        choice_docs(
            other(
                "grading.along",
                "Infill points",
                "Grade along",
                Kind::Choice,
                &["u", "theta", "radial"],
                "Which way the density changes, from the command density to the end density.",
            ),
            &[
                "Along the profile: the command density at the patch's lowest u, the end density at its highest.",
                "Around the axis: the command density at the patch's lowest θ, the end density at its highest.",
                "Outwards from a centre: the command density there, the end density at the radius (distance along the surface) and beyond.",
            ],
        ),
        percent(num(
            "grading.density_to",
            "Infill points",
            "End density",
            "%",
            0.01,
            1.0,
            0.01,
            "The density at the far end of the grading (the command density is the near end).",
        )),
        when(
            num("grading.centre_u", "Infill points", "Centre u", "", 0.0, 64.0, 0.01, "Where the radial grading is centred along the profile."),
            "grading.along",
            "radial",
        ),
        when(
            num("grading.centre_theta_rad", "Infill points", "Centre θ", "rad", -7.0, 7.0, 0.01, "Where the radial grading is centred around the axis."),
            "grading.along",
            "radial",
        ),
        when(
            num(
                "grading.radius_mm",
                "Infill points",
                "Grading radius",
                "mm",
                0.1,
                10000.0,
                0.1,
                "Distance along the surface over which the density goes from the command to the end density.",
            ),
            "grading.along",
            "radial",
        ),
    ]
};

/// Initial seed method.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SeedMethod {
    /// Euclidean blue-noise sampling: dart throwing with a minimum chord distance.
    Ebns,
    /// Euclidean repulsion energy from a random start.
    Ere,
    /// Geodesic blue-noise sampling: dart throwing with a minimum geodesic distance.
    Gbns,
}

/// Options of the stage.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Options {
    /// Command density ρ_c, fraction in (0, 1] ([`DEFAULT_DENSITY`]).
    pub density: f64,
    /// Rasters through each point n ([`DEFAULT_RASTERS`]).
    pub rasters: u32,
    /// Seed method ([`SeedMethod::Ebns`]).
    pub seed_method: SeedMethod,
    /// Repulsion exponent m > 1 ([`DEFAULT_EXPONENT`]).
    pub exponent: f64,
    /// GRE iteration cap ([`DEFAULT_ITERATIONS`]).
    pub iterations: usize,
    /// See [`DEFAULT_ENERGY_TOLERANCE`].
    pub energy_tolerance: f64,
    /// See [`DEFAULT_DISPLACEMENT_TOLERANCE`].
    pub displacement_tolerance: f64,
    /// See [`DEFAULT_CUTOFF_SPACINGS`].
    pub cutoff_spacings: f64,
    /// A graded density (absent: uniform at `density`, the paper's method). Left out of the
    /// serialised options when absent, so uniform designs read and hash as before.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub grading: Option<Grading>,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            density: DEFAULT_DENSITY,
            rasters: DEFAULT_RASTERS,
            seed_method: SeedMethod::Ebns,
            exponent: DEFAULT_EXPONENT,
            iterations: DEFAULT_ITERATIONS,
            energy_tolerance: DEFAULT_ENERGY_TOLERANCE,
            displacement_tolerance: DEFAULT_DISPLACEMENT_TOLERANCE,
            cutoff_spacings: DEFAULT_CUTOFF_SPACINGS,
            grading: None,
        }
    }
}

/// Why the stage refused.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum Error {
    /// The platform or a geodesic failed.
    #[error(transparent)]
    Axisym(#[from] super::Error),
    /// The domain is unusable (every problem listed).
    #[error("the domain is not usable:\n{}", .0.iter().map(|p| format!("- {p}")).collect::<Vec<_>>().join("\n"))]
    Domain(Vec<DomainProblem>),
    /// An option is out of range.
    #[error("option {name} = {value} is out of range: {hint}")]
    BadOption {
        /// Option name.
        name: &'static str,
        /// Value given.
        value: f64,
        /// Allowed range.
        hint: &'static str,
    },
    /// Over a count limit or budget.
    #[error(transparent)]
    TooBig(OverBudget),
    /// Dart throwing could not place the points.
    #[error(
        "could not place {wanted} seed points (placed {placed}); the domain may be too thin for the spacing: lower the density or use seed_method \"ere\""
    )]
    SeedFailed {
        /// Points wanted.
        wanted: usize,
        /// Points placed.
        placed: usize,
    },
}

/// Why GRE stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum StopReason {
    /// The iteration cap.
    Iterations,
    /// The energy changed less than the tolerance.
    Energy,
    /// No point moved more than the displacement tolerance.
    Displacement,
    /// No step size lowered the energy (a local minimum within rounding).
    Stalled,
    /// Nothing to optimise (one point).
    Trivial,
}

/// One GRE iteration.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Iteration {
    /// Energy E/E₀ after the step.
    pub energy: f64,
    /// Largest force |F_i|/F₀ after the step (metric length).
    pub max_force: f64,
    /// Largest point displacement, mm.
    pub max_step_mm: f64,
    /// Accepted step size τ, target spacings (the longest move of a point).
    pub step: f64,
}

/// The stage's result.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Distribution {
    /// True surface area of Ω, mm².
    pub area_mm2: f64,
    /// N from equation (4) (graded: ∫ρ² dA/(n²e²)).
    pub target_points: usize,
    /// The seed, (u, θ).
    pub seed_points: Vec<[f64; 2]>,
    /// The optimised points, (u, θ).
    pub points: Vec<[f64; 2]>,
    /// Per GRE iteration.
    pub iterations: Vec<Iteration>,
    /// Why GRE stopped.
    pub stop: StopReason,
    /// Metrics of the seed.
    pub seed_metrics: Metrics,
    /// Metrics of the result.
    pub metrics: Metrics,
    /// A graded density's grading coordinate per point (`None` when uniform).
    pub graded: Option<GradedPoints>,
}

/// Where the points of a graded run lie along the grading coordinate (the report bins the
/// commanded and measured densities by it).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct GradedPoints {
    /// Coordinate name and unit.
    pub label: (&'static str, &'static str),
    /// The coordinate span [command density end, far end].
    pub range: [f64; 2],
    /// Coordinate of each seed point (u, θ rad, or distance from the centre mm).
    pub seed: Vec<f64>,
    /// Coordinate of each optimised point.
    pub points: Vec<f64>,
    /// Commanded ρ at `bins + 1` evenly spaced coordinates over the points' span (a line).
    pub commanded: Vec<[f64; 2]>,
}

fn check_options(o: &Options, line_width_mm: f64) -> Result<(), Error> {
    let bad = |name, value: f64, hint| Err(Error::BadOption { name, value, hint });
    if !(o.density > 0.0 && o.density <= 1.0) {
        return bad("density", o.density, "a fraction in (0, 1]: 0.5 is 50 %");
    }
    if o.rasters == 0 || o.rasters > 16 {
        return bad("rasters", o.rasters as f64, "1 to 16 rasters through each point");
    }
    if !(o.exponent > 1.0 && o.exponent <= 32.0) {
        return bad("exponent", o.exponent, "m in (1, 32]; the paper uses 5");
    }
    if o.iterations > MAX_ITERATIONS {
        return bad("iterations", o.iterations as f64, "at most 10000");
    }
    if !(o.energy_tolerance >= 0.0 && o.energy_tolerance < 1.0) {
        return bad("energy_tolerance", o.energy_tolerance, "in [0, 1); 1e-6 is the default");
    }
    if !(o.displacement_tolerance >= 0.0 && o.displacement_tolerance < 1.0) {
        return bad("displacement_tolerance", o.displacement_tolerance, "in [0, 1) target spacings");
    }
    if !(o.cutoff_spacings == 0.0 || (o.cutoff_spacings >= 1.5 && o.cutoff_spacings.is_finite())) {
        return bad("cutoff_spacings", o.cutoff_spacings, "0 (all pairs) or at least 1.5 target spacings");
    }
    if !(line_width_mm > 0.0 && line_width_mm.is_finite()) {
        return bad("line_width_mm", line_width_mm, "a positive width in mm, e.g. 0.4");
    }
    if let Some(g) = &o.grading {
        if !(g.density_to > 0.0 && g.density_to <= 1.0) {
            return bad("grading.density_to", g.density_to, "a fraction in (0, 1]: 0.25 is 25 %");
        }
        if g.along == Along::Radial {
            if !(g.radius_mm >= 0.1 && g.radius_mm <= 10000.0) {
                return bad("grading.radius_mm", g.radius_mm, "a distance from 0.1 to 10000 mm along the surface");
            }
            if !g.centre_u.is_finite() {
                return bad("grading.centre_u", g.centre_u, "a u inside the platform's range");
            }
            if !(g.centre_theta_rad.is_finite() && g.centre_theta_rad.abs() <= 7.0) {
                return bad("grading.centre_theta_rad", g.centre_theta_rad, "an angle from −7 to 7 rad");
            }
        }
    }
    Ok(())
}

/// The radial centre must lie where the platform's metric is trusted (as a domain must).
pub fn check_centre(p: &dyn Profile, o: &Options) -> Result<(), Error> {
    let Some(g) = o.grading.as_ref().filter(|g| g.along == Along::Radial) else { return Ok(()) };
    let clear = super::platform::pole_clearance(p, super::platform::DEFAULT_MIN_POLE_RADIUS_MM);
    match clear {
        Some((a, b)) if g.centre_u >= a && g.centre_u <= b => Ok(()),
        _ => Err(Error::BadOption {
            name: "grading.centre_u",
            value: g.centre_u,
            hint: "the centre must lie on the platform clear of the poles: pick a u inside the range a domain may use (the platform stage's report states it)",
        }),
    }
}

/// The graded density field of a run (`None` when uniform).
fn field_of(s: &Surface, domain: &Domain, o: &Options, line_width_mm: f64) -> Option<Field> {
    o.grading.as_ref().map(|g| Field::new(s, domain, g, o.density, o.rasters as f64 * line_width_mm))
}

/// N = ∫_Ω ρ² dA/(n²e²) of a graded density, rounded, at least 1 (equation (4) per area
/// element; [`target_points`] when uniform).
pub fn graded_target_points(s: &Surface, domain: &Domain, o: &Options, line_width_mm: f64) -> f64 {
    match field_of(s, domain, o, line_width_mm) {
        None => target_points(domain.area_mm2(s), o, line_width_mm),
        Some(f) => {
            let ne = o.rasters as f64 * line_width_mm;
            (f.integral_rho2(s, domain) / (ne * ne)).round().max(1.0)
        }
    }
}

/// The largest target spacing over Ω, mm: n·e over the smallest density (graded or not).
pub fn largest_spacing(o: &Options, line_width_mm: f64) -> f64 {
    let lo = o.grading.as_ref().map_or(o.density, |g| o.density.min(g.density_to));
    o.rasters as f64 * line_width_mm / lo
}

/// Target spacing s = n·e/ρ_c, mm.
pub fn spacing(o: &Options, line_width_mm: f64) -> f64 {
    o.rasters as f64 * line_width_mm / o.density
}

/// N = A·ρ_c²/(n²·e²) (equation (4)), rounded, at least 1.
pub fn target_points(area_mm2: f64, o: &Options, line_width_mm: f64) -> f64 {
    let s = spacing(o, line_width_mm);
    (area_mm2 / (s * s)).round().max(1.0)
}

fn pairs_per_eval(n: f64, o: &Options) -> f64 {
    if o.cutoff_spacings > 0.0 {
        (n * std::f64::consts::PI * o.cutoff_spacings * o.cutoff_spacings / 2.0).min(n * (n - 1.0) / 2.0)
    } else {
        n * (n - 1.0) / 2.0
    }
}

/// The stage's work before running it.
pub fn estimate(p: &dyn Profile, domain: &Domain, o: &Options, line_width_mm: f64) -> Estimate {
    let ok = check_options(o, line_width_mm).is_ok() && check_centre(p, o).is_ok() && domain.problems(p).is_empty();
    let n = match (ok, &o.grading) {
        (false, _) => 0.0,
        (true, None) => target_points(domain.area_mm2(&Surface::new(p)), o, line_width_mm),
        (true, Some(_)) => graded_target_points(&Surface::new(p), domain, o, line_width_mm),
    };
    let pairs = pairs_per_eval(n, o);
    // About 1.5 energy evaluations per iteration, two metric passes, the seed.
    let evals = 1.5 * o.iterations as f64 + 4.0 + if o.seed_method == SeedMethod::Ere { 1.5 * ERE_ITERATIONS as f64 } else { 0.0 };
    let seconds = pairs * evals * SECONDS_PER_PAIR;
    // Per point: its node, forces, trial and counts; then a window of pairs with their
    // geodesics, twice (the last one held while the next is made, and its runs' overshoot).
    let window = 2.0 * (WINDOW_PAIRS * (8 + std::mem::size_of::<PairEval>())) as f64;
    let bytes = n * (std::mem::size_of::<Node>() as f64 + 256.0) + 64.0 * 1024.0 + window.min(pairs * 64.0);
    Estimate::new("axisym_uniform")
        .quantity("points", "points on the domain", n, "")
        .quantity("pairs", "pairs per energy evaluation", pairs, "")
        .cost(bytes, seconds)
        // Pair windows and trial steps run on every thread, the descent's sums on one:
        // 1.61× natively and 1.35× in the worker at 2 threads (hourglass-omega3).
        .parallel(0.6)
        .limit("points", n, MAX_POINTS as f64, "", "lower the density or the line width, or use a smaller domain")
        .budgets("lower the density, the iterations or cutoff_spacings")
}

/// A 3-D uniform grid over points, cells in a `BTreeMap` (deterministic order).
pub(crate) struct Grid {
    cell: f64,
    map: BTreeMap<[i64; 3], Vec<u32>>,
}

impl Grid {
    pub(crate) fn new(points: impl Iterator<Item = [f64; 3]>, cell: f64) -> Grid {
        let mut g = Grid { cell, map: BTreeMap::new() };
        for (i, p) in points.enumerate() {
            g.insert(p, i as u32);
        }
        g
    }
    fn key(&self, p: [f64; 3]) -> [i64; 3] {
        [(p[0] / self.cell).floor() as i64, (p[1] / self.cell).floor() as i64, (p[2] / self.cell).floor() as i64]
    }
    pub(crate) fn insert(&mut self, p: [f64; 3], i: u32) {
        let k = self.key(p);
        self.map.entry(k).or_default().push(i);
    }
    /// Indices of points in the cells within `r` of p (a superset of the ball).
    pub(crate) fn near(&self, p: [f64; 3], r: f64, out: &mut Vec<u32>) {
        let lo = self.key([p[0] - r, p[1] - r, p[2] - r]);
        let hi = self.key([p[0] + r, p[1] + r, p[2] + r]);
        for x in lo[0]..=hi[0] {
            for y in lo[1]..=hi[1] {
                for z in lo[2]..=hi[2] {
                    if let Some(v) = self.map.get(&[x, y, z]) {
                        out.extend_from_slice(v);
                    }
                }
            }
        }
    }
}

fn unit(rng: &mut Pcg64) -> f64 {
    (rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// Area-uniform candidates: u by the inverse CDF of x·√g_uu over Ω's u range (a table),
/// θ uniform over Ω's θ range, rejected outside Ω.
struct Sampler {
    u0: f64,
    du: f64,
    cdf: Vec<f64>,
    theta: [f64; 2],
}

impl Sampler {
    fn new(s: &Surface, d: &Domain) -> Sampler {
        let b = d.bounds();
        let cells = 4096;
        let du = (b[1][0] - b[0][0]) / cells as f64;
        let mut cdf = vec![0.0];
        for i in 0..cells {
            let j = s.profile().jet(b[0][0] + (i as f64 + 0.5) * du);
            let w = j.x[0] * libm::hypot(j.x[1], j.z[1]);
            cdf.push(cdf[i] + w);
        }
        Sampler { u0: b[0][0], du, cdf, theta: [b[0][1], b[1][1]] }
    }
    fn draw(&self, rng: &mut Pcg64, d: &Domain) -> Option<[f64; 2]> {
        for _ in 0..1000 {
            let t = unit(rng) * self.cdf[self.cdf.len() - 1];
            let i = self.cdf.partition_point(|&c| c <= t).clamp(1, self.cdf.len() - 1) - 1;
            let f = (t - self.cdf[i]) / (self.cdf[i + 1] - self.cdf[i]).max(1e-300);
            let q = [self.u0 + (i as f64 + f.clamp(0.0, 1.0)) * self.du, self.theta[0] + unit(rng) * (self.theta[1] - self.theta[0])];
            if d.contains(q) {
                return Some(q);
            }
        }
        None
    }
}

/// A candidate seed point: area-uniform when uniform; for a graded density kept with
/// probability ρ(q)²/ρ_max² (rejection), so candidates follow the target point density.
fn draw(sampler: &Sampler, s: &Surface, field: Option<&Field>, rng: &mut Pcg64, d: &Domain) -> Option<[f64; 2]> {
    let Some(f) = field else { return sampler.draw(rng, d) };
    let top = f.density_bounds()[1];
    for _ in 0..MAX_GRADED_DRAWS {
        let q = sampler.draw(rng, d)?;
        let rho = f.density(s, &s.node(q));
        if unit(rng) * top * top <= rho * rho {
            return Some(q);
        }
    }
    None
}

/// Consecutive misses after which dart throwing shrinks its radius by 5 %. A constant (not one
/// growing with N) keeps seeding linear in N: with 100 + N the seed stage of a 10× larger
/// domain took 16.6× as long.
const DART_MISS_LIMIT: usize = 300;

/// Pairs a window of the first energy evaluation holds (about 1.8 MB with their terms): enough
/// for every thread to have long runs, few enough to stay in a core's cache share.
const WINDOW_PAIRS: usize = 1 << 15;
/// Pairs an item of the later evaluations holds at most (fewer when an evaluation has fewer
/// than four items a thread): the pool makes items while the calling thread sums the one
/// before, so an item is short (a few milliseconds of geodesics at most)…
const ITEM_PAIRS: usize = 1 << 12;
/// …and at most this many are made ahead of the one being summed: the pairs in flight,
/// `(AHEAD_ITEMS + 1) · ITEM_PAIRS`, are the two windows the estimate counts; enough to keep
/// 16 threads busy.
const AHEAD_ITEMS: usize = 15;

/// Dart throwing with a minimum distance (chord, or geodesic when `geodesic`), the radius
/// shrinking by 5 % after [`DART_MISS_LIMIT`] consecutive misses until N points are in. With a graded
/// `field` the minimum distance of a pair is r·s̄/s, s̄ the mean of the two points' target
/// spacings (the pair scale of the repulsion), candidates drawn as [`draw`].
fn dart_throw(s: &Surface, d: &Domain, n: usize, spacing: f64, geodesic: bool, field: Option<&Field>, rng: &mut Pcg64) -> Result<Vec<[f64; 2]>, Error> {
    let sampler = Sampler::new(s, d);
    let mut r = spacing;
    // Largest pair scale over the spacing (1 when uniform): the grid's cell and query radius.
    let widest = field.map_or(1.0, |f| f.spacing_of(f.density_bounds()[0]) / spacing);
    let local = |q: &Node| field.map_or(spacing, |f| f.spacing_of(f.density(s, q)));
    let mut pts: Vec<[f64; 2]> = Vec::with_capacity(n);
    let mut nodes: Vec<Node> = Vec::with_capacity(n);
    let mut scales: Vec<f64> = Vec::with_capacity(n);
    let mut grid = Grid { cell: spacing * widest, map: BTreeMap::new() };
    let mut misses = 0;
    let mut cand = Vec::new();
    while pts.len() < n {
        let Some(q) = draw(&sampler, s, field, rng, d) else {
            return Err(Error::SeedFailed { wanted: n, placed: pts.len() });
        };
        let node = s.node(q);
        let sq = local(&node);
        cand.clear();
        grid.near(node.p, r * widest, &mut cand);
        let ok = cand.iter().all(|&j| {
            let o = &nodes[j as usize];
            // Uniform: s̄ = s, so the radius is r exactly.
            let rij = r * (0.5 * (sq + scales[j as usize]) / spacing);
            let c = ((o.p[0] - node.p[0]).powi(2) + (o.p[1] - node.p[1]).powi(2) + (o.p[2] - node.p[2]).powi(2)).sqrt();
            // The geodesic is never shorter than the chord: only chords under r need it.
            c >= rij || (geodesic && s.pair(&node, o).0 >= rij)
        });
        if ok {
            grid.insert(node.p, pts.len() as u32);
            pts.push(q);
            nodes.push(node);
            scales.push(sq);
            misses = 0;
        } else {
            misses += 1;
            if misses > DART_MISS_LIMIT {
                r *= 0.95;
                misses = 0;
                if r < 1e-3 * spacing {
                    return Err(Error::SeedFailed { wanted: n, placed: pts.len() });
                }
            }
        }
    }
    Ok(pts)
}

/// Energy and forces of a configuration.
struct Engine<'a, 'b> {
    s: &'a Surface<'b>,
    m: f64,
    /// Cutoff distance, mm (∞ = all pairs).
    rc: f64,
    /// Geodesic (GRE) or chord (ERE) distances.
    geodesic: bool,
    /// A graded density: the pair energy becomes (d/s̄)^−m (see [`Engine::eval_graded`]).
    field: Option<&'a Field>,
    /// Cutoff in pair scales s̄ (∞ = all pairs); graded runs only.
    cutoff_spacings: f64,
    /// Each point's pairs in the last evaluation, to cut the next one's windows.
    pairs_per_point: std::sync::Mutex<Vec<u32>>,
}

impl Engine<'_, '_> {
    /// (E, force covectors F_i = −∇_i E, the nodes given, target spacing per point — empty
    /// when uniform) at the points whose `nodes` are given.
    fn eval(&self, nodes: Vec<Node>) -> (f64, Vec<[f64; 2]>, Vec<Node>, Vec<f64>) {
        match self.field {
            None => {
                let (e, f) = self.eval_uniform(&nodes);
                (e, f, nodes, Vec::new())
            }
            Some(field) => {
                let (e, f, sp) = self.eval_graded(&nodes, field);
                (e, f, nodes, sp)
            }
        }
    }

    /// The points' nodes (metric and position), side by side.
    fn nodes(&self, pts: &[[f64; 2]]) -> Vec<Node> {
        crate::par::map(pts.len(), &mut |_| {}, |k| self.s.node(pts[k]))
    }

    /// Calls `add(i, j, term(i, j, pair))` for the pairs `near(i, …)` lists for each point `i`
    /// in turn, in that order: the neighbour search, the pair's geodesic and its `term` run side
    /// by side on the pool, `add` (the sums) on this thread in pair order, so the sums are the
    /// same bits at any thread count.
    ///
    /// After the first evaluation, points go in items of about [`ITEM_PAIRS`] pairs, cut from
    /// each point's pairs in the evaluation before (points move little between two), and this
    /// thread sums one item while the pool makes the next ones ([`crate::par::ordered`], at most
    /// [`AHEAD_ITEMS`] ahead). The first evaluation has no counts yet: it goes in windows of
    /// about [`WINDOW_PAIRS`] pairs, each made in one parallel round then summed, starting at
    /// one point and growing at most 4× a window, so all-pairs runs stay bounded too.
    fn for_pairs<T: Send>(&self, nodes: &[Node], near: &Near<'_>, term: &(dyn Fn(usize, usize, &PairEval) -> T + Sync), add: &mut dyn FnMut(usize, usize, T)) {
        let n = nodes.len();
        let last = self.pairs_per_point.lock().map(|mut c| std::mem::take(&mut *c)).unwrap_or_default();
        let mut counts = vec![0u32; n];
        // The pairs of points `range`, with their terms.
        let make = |range: std::ops::Range<usize>| -> Vec<(u32, u32, T)> {
            let (mut cand, mut pairs) = (Vec::new(), Vec::new());
            for i in range {
                near(i, &mut cand, &mut pairs);
            }
            pairs
                .iter()
                .map(|&(i, j)| {
                    let (a, b) = (&nodes[i as usize], &nodes[j as usize]);
                    let pe = if self.geodesic { self.s.pair_both(a, b) } else { self.s.chord_pair(a, b) };
                    (i, j, term(i as usize, j as usize, &pe))
                })
                .collect()
        };
        let mut sum = |part: Vec<(u32, u32, T)>, counts: &mut Vec<u32>| {
            let found = part.len();
            for (i, j, t) in part {
                if let Some(c) = counts.get_mut(i as usize) {
                    *c += 1;
                }
                add(i as usize, j as usize, t);
            }
            found
        };
        if last.len() == n {
            // Four items a thread at least, so that a small evaluation keeps every thread busy.
            let total: usize = last.iter().map(|&c| c as usize).sum();
            let item_pairs = (total / (4 * crate::par::threads())).clamp(1, ITEM_PAIRS);
            let mut items = Vec::new();
            let (mut start, mut pairs) = (0usize, 0usize);
            for (i, &c) in last.iter().enumerate() {
                pairs += c as usize;
                if pairs >= item_pairs || i + 1 == n {
                    items.push(start..i + 1);
                    (start, pairs) = (i + 1, 0);
                }
            }
            let _ = crate::par::ordered(
                items.len(),
                AHEAD_ITEMS,
                |k| make(items[k].clone()),
                |_, part| -> Result<(), ()> {
                    sum(part, &mut counts);
                    Ok(())
                },
            );
        } else {
            let runs = 4 * crate::par::threads();
            let (mut start, mut span) = (0usize, 1usize);
            while start < n {
                let span_now = span.min(n - start);
                let parts = crate::par::map_runs(span_now, runs, &mut |_| {}, |range, _| vec![make(start + range.start..start + range.end)]);
                let found: usize = parts.into_iter().map(|part| sum(part, &mut counts)).sum();
                start += span_now;
                let per_point = (found as f64 / span_now as f64).max(1.0);
                span = ((WINDOW_PAIRS as f64 / per_point) as usize).clamp(1, 4 * span_now);
            }
        }
        if let Ok(mut c) = self.pairs_per_point.lock() {
            *c = counts;
        }
    }

    /// The graded energy E = Σ (d_ij/s̄_ij)^−m − c^−m over pairs with d_ij < c·s̄_ij, where
    /// s̄_ij = ½(s_i + s_j) and c the cutoff in spacings (shifted so it is continuous at the
    /// cutoff, as the uniform one). Scale-free: a pair at its local target spacing weighs the
    /// same anywhere, and for N = ∫ρ²/(n²e²) points the minimum has point density ∝ 1/s².
    /// The forces are the exact gradient, ∂s̄/∂q included (ρ(q) is linear in u, θ or the
    /// geodesic distance from the centre), so a small enough step always lowers this E and
    /// the descent's no-rise rule holds as in the uniform case:
    /// F_i = m·x^(−m−1)/s̄·(∇_i d − x·∇_i s̄), x = d/s̄, ∇_i s̄ = −½·s_i/ρ_i·∇ρ_i.
    fn eval_graded(&self, nodes: &[Node], field: &Field) -> (f64, Vec<[f64; 2]>, Vec<f64>) {
        let mut sp = Vec::with_capacity(nodes.len());
        let mut dsp = Vec::with_capacity(nodes.len());
        for n in nodes {
            let (rho, g) = field.density_gradient(self.s, n);
            let s = field.spacing_of(rho);
            sp.push(s);
            dsp.push([-s / rho * g[0], -s / rho * g[1]]);
        }
        let c = self.cutoff_spacings;
        let shift = if c.is_finite() { libm::pow(c, -self.m) } else { 0.0 };
        let mut f = vec![[0.0; 2]; nodes.len()];
        let mut e = 0.0;
        // A pair's energy and its force on each point (made on the pool), summed in pair order.
        let term = |i: usize, j: usize, pe: &PairEval| -> PairTerm {
            let sbar = 0.5 * (sp[i] + sp[j]);
            if !(pe.d < c * sbar) {
                return None;
            }
            let x = pe.d.max(1e-9) / sbar;
            let w = self.m * libm::pow(x, -self.m - 1.0) / sbar;
            let fi = [w * (pe.ga[0] - x * 0.5 * dsp[i][0]), w * (pe.ga[1] - x * 0.5 * dsp[i][1])];
            let fj = [w * (pe.gb[0] - x * 0.5 * dsp[j][0]), w * (pe.gb[1] - x * 0.5 * dsp[j][1])];
            Some((libm::pow(x, -self.m) - shift, [fi[0], fi[1], fj[0], fj[1]]))
        };
        let mut add = |i: usize, j: usize, t: PairTerm| add_term(&mut e, &mut f, i, j, t);
        if c.is_finite() {
            let widest = sp.iter().copied().fold(0.0, f64::max) * c;
            let grid = Grid::new(nodes.iter().map(|n| n.p), widest);
            let near = |i: usize, cand: &mut Vec<u32>, out: &mut Vec<(u32, u32)>| {
                cand.clear();
                grid.near(nodes[i].p, widest, cand);
                for &j in cand.iter() {
                    let j = j as usize;
                    if j > i {
                        let (a, b) = (nodes[i].p, nodes[j].p);
                        let c2 = (a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2);
                        let rc = c * 0.5 * (sp[i] + sp[j]);
                        if c2 < rc * rc {
                            out.push((i as u32, j as u32));
                        }
                    }
                }
            };
            self.for_pairs(nodes, &near, &term, &mut add);
        } else {
            let n = nodes.len();
            let all = |i: usize, _: &mut Vec<u32>, out: &mut Vec<(u32, u32)>| out.extend((i + 1..n).map(|j| (i as u32, j as u32)));
            self.for_pairs(nodes, &all, &term, &mut add);
        }
        (e, f, sp)
    }

    /// (E, force covectors F_i = −∇_i E). The pair energy is shifted by rc^−m so it
    /// is continuous at the cutoff (a truncated, unshifted energy jumps as pairs cross it).
    fn eval_uniform(&self, nodes: &[Node]) -> (f64, Vec<[f64; 2]>) {
        let mut f = vec![[0.0; 2]; nodes.len()];
        let mut e = 0.0;
        let shift = if self.rc.is_finite() { libm::pow(self.rc, -self.m) } else { 0.0 };
        // A pair's energy and its force on each point (made on the pool), summed in pair order.
        let term = |_: usize, _: usize, pe: &PairEval| -> PairTerm {
            if !(pe.d < self.rc) {
                return None;
            }
            let d = pe.d.max(1e-9);
            let w = self.m * libm::pow(d, -self.m - 1.0);
            Some((libm::pow(d, -self.m) - shift, [w * pe.ga[0], w * pe.ga[1], w * pe.gb[0], w * pe.gb[1]]))
        };
        let mut add = |i: usize, j: usize, t: PairTerm| add_term(&mut e, &mut f, i, j, t);
        if self.rc.is_finite() {
            let grid = Grid::new(nodes.iter().map(|n| n.p), self.rc);
            let rc = self.rc;
            let near = |i: usize, cand: &mut Vec<u32>, out: &mut Vec<(u32, u32)>| {
                cand.clear();
                grid.near(nodes[i].p, rc, cand);
                for &j in cand.iter() {
                    let j = j as usize;
                    if j > i {
                        let (a, b) = (nodes[i].p, nodes[j].p);
                        let c2 = (a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2);
                        if c2 < rc * rc {
                            out.push((i as u32, j as u32));
                        }
                    }
                }
            };
            self.for_pairs(nodes, &near, &term, &mut add);
        } else {
            let n = nodes.len();
            let all = |i: usize, _: &mut Vec<u32>, out: &mut Vec<(u32, u32)>| out.extend((i + 1..n).map(|j| (i as u32, j as u32)));
            self.for_pairs(nodes, &all, &term, &mut add);
        }
        (e, f)
    }
}

/// Lists point `i`'s pairs `(i, j)`, j > i, into the last argument (the second is scratch).
type Near<'a> = dyn Fn(usize, &mut Vec<u32>, &mut Vec<(u32, u32)>) + Sync + 'a;

/// A pair's share of the energy and its force covectors on its two points (i's two
/// components, then j's), or `None` beyond the cutoff.
type PairTerm = Option<(f64, [f64; 4])>;

/// Adds a pair's term to the energy `e` and the forces `f`.
fn add_term(e: &mut f64, f: &mut [[f64; 2]], i: usize, j: usize, t: PairTerm) {
    if let Some((et, g)) = t {
        *e += et;
        f[i][0] += g[0];
        f[i][1] += g[1];
        f[j][0] += g[2];
        f[j][1] += g[3];
    }
}

/// Metric length of a covector F at a node, mm per unit.
fn cov_norm(n: &Node, f: [f64; 2]) -> f64 {
    (f[0] * f[0] / n.g[0] + if n.g[1] > 0.0 { f[1] * f[1] / n.g[1] } else { 0.0 }).sqrt()
}

/// The reference force of a step: the 90th percentile of the points' force lengths, so a
/// few stiff pairs (two seed points almost on top of each other, or points pressed against
/// Ω's edge) neither set the pace of all the others nor stall them.
fn reference_force(nodes: &[Node], forces: &[[f64; 2]]) -> f64 {
    let mut f: Vec<f64> = nodes.iter().zip(forces).map(|(n, f)| cov_norm(n, *f)).collect();
    f.sort_by(f64::total_cmp);
    f[((f.len() - 1) as f64 * 0.9) as usize]
}

/// Iterations of the descent run in one stretch on a pool thread ([`crate::par::on_pool`])
/// between two progress reports. Each iteration is a few short parallel rounds (1–3 ms in
/// all on the paper's platforms); from a pool thread they cost no wake-up of the caller.
const ITERATIONS_PER_HOP: usize = 8;

/// What a recorded descent is shown after the seed (iteration 0, E/E₀ = 1) and after each
/// accepted step: (iteration, E/E₀, the points).
type Observer<'a> = dyn FnMut(usize, f64, &[[f64; 2]]) + Send + 'a;

/// Repulsion descent: returns (points, iterations, stop); `observe`, when given, sees the
/// start and every accepted step.
///
/// Energy is reported as E/E₀ and forces as |F|/F₀ (the paper's non-dimensionalisation by
/// the initial values). The step moves point i along its force by τ·s·min(|F_i|/F_ref, 1)
/// (s the target spacing, F_ref from [`reference_force`]): a positive scaling of the
/// steepest-descent direction, so a small enough τ always lowers E. τ grows by half after an
/// accepted step (to at most half a spacing) and halves after a rejected one (E rising by
/// more than the tolerance), so the energy never rises by more than the tolerance.
///
/// The iterations run in stretches of [`ITERATIONS_PER_HOP`] on a pool thread, with
/// `progress` called on this thread between them.
#[allow(clippy::too_many_arguments)]
fn descend(
    eng: &Engine,
    d: &Domain,
    start: Vec<[f64; 2]>,
    iterations: usize,
    e_tol: f64,
    disp_tol_mm: f64,
    spacing: f64,
    progress: &mut dyn FnMut(f32),
    mut observe: Option<&mut Observer<'_>>,
) -> (Vec<[f64; 2]>, Vec<Iteration>, StopReason) {
    if start.len() < 2 {
        return (start, Vec::new(), StopReason::Trivial);
    }
    let mut run = crate::par::on_pool(|| Descent::start(eng, start, e_tol, disp_tol_mm, spacing));
    if let Some(o) = observe.as_deref_mut() {
        o(0, 1.0, &run.pts);
    }
    let mut it = 0;
    while it < iterations && run.stop.is_none() {
        let hop = ITERATIONS_PER_HOP.min(iterations - it);
        crate::par::on_pool(|| {
            for _ in 0..hop {
                if run.stop.is_some() {
                    break;
                }
                let before = run.log.len();
                run.iterate(eng, d);
                // Only a recorded run looks at each accepted step (a normal run passes None).
                if let (Some(o), Some(last)) = (observe.as_deref_mut(), run.log.last().filter(|_| run.log.len() > before)) {
                    o(run.log.len(), last.energy, &run.pts);
                }
            }
        });
        it += hop;
        progress(run.log.len() as f32 / iterations as f32);
    }
    (run.pts, run.log, run.stop.unwrap_or(StopReason::Iterations))
}

/// The descent's state between iterations (see [`descend`]).
struct Descent {
    pts: Vec<[f64; 2]>,
    forces: Vec<[f64; 2]>,
    nodes: Vec<Node>,
    /// Target spacing per point (empty when uniform).
    scales: Vec<f64>,
    e0: f64,
    f0: f64,
    e_prev: f64,
    tau: f64,
    e_tol: f64,
    disp_tol_mm: f64,
    spacing: f64,
    log: Vec<Iteration>,
    /// Why it ended; `None` while it goes on.
    stop: Option<StopReason>,
}

impl Descent {
    /// The energy and forces at `pts`, the start.
    fn start(eng: &Engine, pts: Vec<[f64; 2]>, e_tol: f64, disp_tol_mm: f64, spacing: f64) -> Descent {
        let (e0, forces, nodes, scales) = eng.eval(eng.nodes(&pts));
        let f0 = nodes.iter().zip(&forces).map(|(n, f)| cov_norm(n, *f)).fold(0.0, f64::max);
        let stop = if e0 > 0.0 && f0 > 0.0 { None } else { Some(StopReason::Trivial) };
        Descent { pts, forces, nodes, scales, e0, f0, e_prev: 1.0, tau: 0.25, e_tol, disp_tol_mm, spacing, log: Vec::new(), stop }
    }

    /// One iteration: a step, halved until the energy does not rise by more than the
    /// tolerance; sets `stop` when the descent ends.
    fn iterate(&mut self, eng: &Engine, d: &Domain) {
        let f_ref = reference_force(&self.nodes, &self.forces).max(1e-300);
        let mut accepted = None;
        for _ in 0..=MAX_RETRIES {
            // Each point's move and its node at the new place on its own, side by side (one
            // parallel round); the largest step is a maximum (the same whatever the order).
            let tau = self.tau;
            let (pts, nodes, forces, scales) = (&self.pts, &self.nodes, &self.forces, &self.scales);
            let moves = crate::par::map(pts.len(), &mut |_| {}, |i| {
                let (q, n, f) = (pts[i], &nodes[i], forces[i]);
                // Raise the index (vector = g⁻¹·F), then scale to τ·s·min(|F|/F_ref, 1)
                // (s the point's own target spacing when graded).
                let len = cov_norm(n, f);
                if !(len > 0.0) {
                    return (q, 0.0, *n);
                }
                let s_i = scales.get(i).copied().unwrap_or(self.spacing);
                let k = tau * s_i * (len / f_ref).min(1.0) / len;
                let v = [k * f[0] / n.g[0], if n.g[1] > 0.0 { k * f[1] / n.g[1] } else { 0.0 }];
                let t = d.project_inside(eng.s, [q[0] + v[0], q[1] + v[1]]);
                (t, (n.g[0] * (t[0] - q[0]).powi(2) + n.g[1] * (t[1] - q[1]).powi(2)).sqrt(), eng.s.node(t))
            });
            let max_step = moves.iter().map(|m| m.1).fold(0.0, f64::max);
            let (trial, trial_nodes): (Vec<[f64; 2]>, Vec<Node>) = moves.into_iter().map(|m| (m.0, m.2)).unzip();
            let (e, f, nd, sc) = eng.eval(trial_nodes);
            let en = e / self.e0;
            if en <= self.e_prev + self.e_tol {
                accepted = Some((trial, f, nd, sc, en, max_step));
                break;
            }
            self.tau *= 0.5;
        }
        let Some((trial, f, nd, sc, en, max_step)) = accepted else {
            self.stop = Some(StopReason::Stalled);
            return;
        };
        let max_force = nd.iter().zip(&f).map(|(n, f)| cov_norm(n, *f)).fold(0.0, f64::max) / self.f0;
        self.log.push(Iteration { energy: en, max_force, max_step_mm: max_step, step: self.tau });
        let rel = (self.e_prev - en).abs() / self.e_prev;
        (self.pts, self.forces, self.nodes, self.scales, self.e_prev) = (trial, f, nd, sc, en);
        if max_step < self.disp_tol_mm {
            self.stop = Some(StopReason::Displacement);
        } else if rel < self.e_tol {
            self.stop = Some(StopReason::Energy);
        } else {
            self.tau = (self.tau * 1.5).min(0.5);
        }
    }
}

/// Places N = A·ρ_c²/(n²e²) quasi-uniform points on Ω (graded: N = ∫ρ² dA/(n²e²) points
/// at local spacing s(q) = n·e/ρ(q)) and reports the seed, the result and their metrics.
/// `seed` drives every random choice; `progress` gets the GRE fraction done.
pub fn distribute(p: &dyn Profile, domain: &Domain, o: &Options, line_width_mm: f64, seed: u64, progress: &mut dyn FnMut(f32)) -> Result<Distribution, Error> {
    distribute_observed(p, domain, o, line_width_mm, seed, progress, None)
}

/// One kept frame of a recorded repulsion ([`record`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// Accepted GRE iterations done (0: the seed).
    pub iteration: usize,
    /// E/E₀ after them (1 for the seed).
    pub energy: f64,
    /// The points then, (u, θ).
    pub points: Vec<[f64; 2]>,
}

/// A repulsion replayed with its frames kept ([`record`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Recording {
    /// At most the cap asked for, in iteration order: the seed, evenly spaced iterations
    /// (every `stride`-th) and the last one.
    pub frames: Vec<Frame>,
    /// Accepted iterations of the whole run.
    pub iterations: usize,
    /// Iterations between two kept frames (a power of two; the last frame may be closer).
    pub stride: usize,
    /// The run's result: exactly what [`distribute`] gives for the same inputs.
    pub distribution: Distribution,
}

impl Recording {
    /// Bytes the frames' points take.
    pub fn bytes(&self) -> usize {
        self.frames.iter().map(|f| f.points.len() * std::mem::size_of::<[f64; 2]>() + std::mem::size_of::<Frame>()).sum()
    }
}

/// Replays [`distribute`] (the same deterministic run) keeping at most `max_frames` (≥ 2)
/// frames of the geodesic repulsion: the seed, every `stride`-th iteration (the stride doubles
/// whenever the frames would pass the cap, so memory stays within `max_frames` point sets)
/// and the last iteration, whose points are the result's. A normal run records nothing.
pub fn record(p: &dyn Profile, domain: &Domain, o: &Options, line_width_mm: f64, seed: u64, max_frames: usize) -> Result<Recording, Error> {
    let max_frames = max_frames.max(2);
    let (mut frames, mut stride): (Vec<Frame>, usize) = (Vec::new(), 1);
    let mut keep = |iteration: usize, energy: f64, points: &[[f64; 2]]| {
        if iteration % stride != 0 {
            return;
        }
        frames.push(Frame { iteration, energy, points: points.to_vec() });
        // One slot is kept for the last frame.
        while frames.len() > max_frames - 1 {
            stride *= 2;
            frames.retain(|f| f.iteration % stride == 0);
        }
    };
    let distribution = distribute_observed(p, domain, o, line_width_mm, seed, &mut |_| {}, Some(&mut keep))?;
    let iterations = distribution.iterations.len();
    if frames.last().is_none_or(|f| f.iteration != iterations) {
        let energy = distribution.iterations.last().map_or(1.0, |i| i.energy);
        frames.push(Frame { iteration: iterations, energy, points: distribution.points.clone() });
    }
    Ok(Recording { frames, iterations, stride, distribution })
}

fn distribute_observed(
    p: &dyn Profile,
    domain: &Domain,
    o: &Options,
    line_width_mm: f64,
    seed: u64,
    progress: &mut dyn FnMut(f32),
    observe: Option<&mut Observer<'_>>,
) -> Result<Distribution, Error> {
    check_options(o, line_width_mm)?;
    check_centre(p, o)?;
    let problems = domain.problems(p);
    if !problems.is_empty() {
        return Err(Error::Domain(problems));
    }
    let est = estimate(p, domain, o, line_width_mm);
    est.check().map_err(Error::TooBig)?;
    let s = Surface::new(p);
    let area = domain.area_mm2(&s);
    let field = field_of(&s, domain, o, line_width_mm);
    let n = if field.is_some() { est.get("points") as usize } else { target_points(area, o, line_width_mm) as usize };
    let sp = spacing(o, line_width_mm);
    let rc = if o.cutoff_spacings > 0.0 { o.cutoff_spacings * sp } else { f64::INFINITY };
    let cut = if o.cutoff_spacings > 0.0 { o.cutoff_spacings } else { f64::INFINITY };
    let mut rng = Pcg64::seed_from_u64(seed);
    let seed_points = match o.seed_method {
        SeedMethod::Ebns => dart_throw(&s, domain, n, sp, false, field.as_ref(), &mut rng)?,
        SeedMethod::Gbns => dart_throw(&s, domain, n, sp, true, field.as_ref(), &mut rng)?,
        SeedMethod::Ere => {
            let sampler = Sampler::new(&s, domain);
            let mut start = Vec::with_capacity(n);
            for _ in 0..n {
                start.push(draw(&sampler, &s, field.as_ref(), &mut rng, domain).ok_or(Error::SeedFailed { wanted: n, placed: start.len() })?);
            }
            let eng = Engine { s: &s, m: o.exponent, rc, geodesic: false, field: field.as_ref(), cutoff_spacings: cut, pairs_per_point: Default::default() };
            descend(&eng, domain, start, ERE_ITERATIONS, o.energy_tolerance, o.displacement_tolerance * sp, sp, &mut |_| {}, None).0
        }
    };
    let eng = Engine { s: &s, m: o.exponent, rc, geodesic: true, field: field.as_ref(), cutoff_spacings: cut, pairs_per_point: Default::default() };
    let (points, iterations, stop) =
        descend(&eng, domain, seed_points.clone(), o.iterations, o.energy_tolerance, o.displacement_tolerance * sp, sp, progress, observe);
    let (seed_metrics, m, graded) = match &field {
        None => (metrics(&s, &seed_points, o.rasters, o.density, line_width_mm), metrics(&s, &points, o.rasters, o.density, line_width_mm), None),
        Some(f) => {
            // Per point: the grading coordinate and the target spacing there.
            let at = |v: &[[f64; 2]]| -> (Vec<f64>, Vec<f64>) {
                v.iter().map(|&q| s.node(q)).map(|n| f.coordinate(&s, &n)).map(|c| (c, f.spacing_of(f.density_at(c)))).unzip()
            };
            let (seed_c, seed_s) = at(&seed_points);
            let (pts_c, pts_s) = at(&points);
            let lo = pts_c.iter().chain(&seed_c).copied().fold(f64::INFINITY, f64::min);
            let hi = pts_c.iter().chain(&seed_c).copied().fold(f64::NEG_INFINITY, f64::max);
            let commanded = (0..=GRADED_BINS).map(|k| lo + (hi - lo) * k as f64 / GRADED_BINS as f64).map(|c| [c, f.density_at(c)]).collect();
            let graded = GradedPoints { label: f.coordinate_label(), range: f.range(), seed: seed_c, points: pts_c, commanded };
            (
                graded_metrics(&s, &seed_points, o.rasters, line_width_mm, sp, &seed_s),
                graded_metrics(&s, &points, o.rasters, line_width_mm, sp, &pts_s),
                Some(graded),
            )
        }
    };
    Ok(Distribution { area_mm2: area, target_points: n, seed_points, points, iterations, stop, seed_metrics, metrics: m, graded })
}

/// Bins along the grading coordinate of the commanded-vs-measured density plot.
pub const GRADED_BINS: usize = 10;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::axisym::platform::Platform;

    fn omega(name: &str) -> (Platform, Domain, Options) {
        let base = Options::default();
        match name {
            "barrel-omega1" => {
                (Platform::barrel(), Domain::Rectangle { u: [0.8, 1.2], theta: [0.0, 1.0] }, Options { density: 0.5, seed_method: SeedMethod::Ebns, ..base })
            }
            "barrel-omega2" => (
                Platform::barrel(),
                Domain::Polygon { holes: Vec::new(), points: OMEGA2_POLYGON.to_vec() },
                Options { density: 0.25, seed_method: SeedMethod::Ere, ..base },
            ),
            _ => {
                (Platform::hourglass(), Domain::Rectangle { u: [1.0, 3.0], theta: [0.0, 1.0] }, Options { density: 0.1, seed_method: SeedMethod::Gbns, ..base })
            }
        }
    }

    #[test]
    fn n_matches_equation_4() {
        // Cylinder R = 20 mm, z = 60 − 30u: u ∈ [0.5, 1.5] × θ ∈ [0, 0.8] is 30 × 16 = 480 mm²;
        // at ρ_c = 0.5, n = 1, e = 0.4: N = 480·0.25/0.16 = 750.
        let pts: Vec<[f64; 2]> = (0..13).map(|i| [20.0, 60.0 - 5.0 * i as f64]).collect();
        let cyl = Platform::from_polygon(&pts).unwrap();
        let e = estimate(&cyl, &Domain::Rectangle { u: [0.5, 1.5], theta: [0.0, 0.8] }, &Options::default(), 0.4);
        assert_eq!(e.get("points"), 750.0);
        for (name, paper) in [("barrel-omega1", 538.0), ("barrel-omega2", 173.0), ("hourglass-omega3", 204.0)] {
            let (p, d, o) = omega(name);
            let n = estimate(&p, &d, &o, 0.4).get("points");
            println!("{name}: N = {n} (paper {paper}), area {:.1} mm²", d.area_mm2(&Surface::new(&p)));
            assert!((n - paper).abs() <= 0.04 * paper, "{name}: N = {n}, paper {paper}");
        }
    }

    #[test]
    fn record_replays_the_run_within_its_frame_cap() {
        let (p, d, o) = omega("hourglass-omega3");
        let plain = distribute(&p, &d, &o, 0.4, 1, &mut |_| {}).unwrap();
        for cap in [2, 5, 64] {
            let r = record(&p, &d, &o, 0.4, 1, cap).unwrap();
            assert_eq!(r.distribution, plain, "cap {cap}: the recorded run differs");
            assert!(r.frames.len() <= cap && r.frames.len() >= 2, "cap {cap}: {} frames", r.frames.len());
            let (first, last) = (&r.frames[0], &r.frames[r.frames.len() - 1]);
            assert_eq!((first.iteration, first.energy), (0, 1.0));
            assert_eq!(first.points, plain.seed_points);
            assert_eq!(last.iteration, plain.iterations.len());
            assert_eq!(last.points, plain.points, "cap {cap}: the last frame is not the result");
            assert!(r.frames.windows(2).all(|w| w[0].iteration < w[1].iteration && w[1].energy <= w[0].energy + o.energy_tolerance));
            // Evenly spaced but for the last.
            assert!(r.frames[..r.frames.len() - 1].iter().all(|f| f.iteration % r.stride == 0));
        }
    }

    #[test]
    fn examples_improve_uniformity() {
        for name in ["barrel-omega1", "barrel-omega2", "hourglass-omega3"] {
            let (p, d, o) = omega(name);
            let t = std::time::Instant::now();
            let mut reported = Vec::new();
            let r = distribute(&p, &d, &o, 0.4, 1, &mut |f| reported.push(f)).unwrap();
            let secs = t.elapsed().as_secs_f64();
            let red = 1.0 - r.metrics.nn_std_mm / r.seed_metrics.nn_std_mm;
            println!(
                "{name}: N = {}, {:.3} s, {} iterations ({:?}); 2n-NN mean {:.3} → {:.3} mm, std {:.3} → {:.3} mm ({:.1} % lower); e/mean {:.1} % → {:.1} %",
                r.points.len(),
                secs,
                r.iterations.len(),
                r.stop,
                r.seed_metrics.nn_mean_mm,
                r.metrics.nn_mean_mm,
                r.seed_metrics.nn_std_mm,
                r.metrics.nn_std_mm,
                100.0 * red,
                100.0 * r.seed_metrics.ratio,
                100.0 * r.metrics.ratio
            );
            // Progress after each stretch of iterations, the last one the fraction done.
            let tried = r.iterations.len() + usize::from(r.stop == StopReason::Stalled);
            assert_eq!(reported.len(), tried.div_ceil(ITERATIONS_PER_HOP), "{name}: {reported:?}");
            assert!(reported.windows(2).all(|w| w[0] <= w[1]), "{name}: {reported:?}");
            assert_eq!(reported.last().copied(), Some(r.iterations.len() as f32 / o.iterations as f32));
            assert!(r.metrics.nn_std_mm < r.seed_metrics.nn_std_mm, "{name}: no improvement");
            let mut prev = 1.0;
            for it in &r.iterations {
                assert!(it.energy <= prev + o.energy_tolerance, "{name}: energy rose {prev} → {}", it.energy);
                prev = it.energy;
            }
            assert!(r.points.iter().all(|&q| d.contains(q)), "{name}: a point left Ω");
            assert_eq!(r.points.len(), r.target_points);
        }
    }

    #[test]
    fn cutoff_barely_changes_the_result() {
        for name in ["barrel-omega2", "hourglass-omega3"] {
            let (p, d, mut o) = omega(name);
            // All pairs on Ω₃ is ~20 000 pairs per evaluation: compare after 10 iterations.
            if name == "hourglass-omega3" {
                o.iterations = 10;
            }
            let cut = distribute(&p, &d, &o, 0.4, 1, &mut |_| {}).unwrap();
            let all = distribute(&p, &d, &Options { cutoff_spacings: 0.0, ..o.clone() }, 0.4, 1, &mut |_| {}).unwrap();
            let (a, b) = (cut.metrics.nn_std_mm, all.metrics.nn_std_mm);
            println!(
                "{name}: 2n-NN std {a:.4} mm with the cutoff, {b:.4} mm with all pairs; mean {:.4} vs {:.4} mm",
                cut.metrics.nn_mean_mm, all.metrics.nn_mean_mm
            );
            assert!((a - b).abs() <= 0.25 * b, "{name}: {a} vs {b}");
            assert!((cut.metrics.nn_mean_mm - all.metrics.nn_mean_mm).abs() <= 0.03 * all.metrics.nn_mean_mm);
        }
    }

    #[test]
    fn same_seed_same_points() {
        let (p, d, mut o) = omega("barrel-omega2");
        o.iterations = 5;
        let a = distribute(&p, &d, &o, 0.4, 3, &mut |_| {}).unwrap();
        let b = distribute(&p, &d, &o, 0.4, 3, &mut |_| {}).unwrap();
        let c = distribute(&p, &d, &o, 0.4, 4, &mut |_| {}).unwrap();
        let bits = |v: &[[f64; 2]]| v.iter().flat_map(|q| [q[0].to_bits(), q[1].to_bits()]).collect::<Vec<_>>();
        assert_eq!(bits(&a.points), bits(&b.points));
        assert_ne!(bits(&a.points), bits(&c.points));
    }

    #[test]
    fn bad_input_is_refused_with_typed_errors() {
        let p = Platform::barrel();
        let d = Domain::Rectangle { u: [0.8, 1.2], theta: [0.0, 1.0] };
        for density in [0.0, 1.5, f64::NAN] {
            let o = Options { density, ..Options::default() };
            assert!(matches!(distribute(&p, &d, &o, 0.4, 1, &mut |_| {}), Err(Error::BadOption { name: "density", .. })));
        }
        assert!(matches!(distribute(&p, &d, &Options::default(), f64::NAN, 1, &mut |_| {}), Err(Error::BadOption { .. })));
        let bow = Domain::Polygon { holes: Vec::new(), points: vec![[0.8, 0.0], [1.2, 1.0], [1.2, 0.0], [0.8, 1.0]] };
        assert!(matches!(distribute(&p, &bow, &Options::default(), 0.4, 1, &mut |_| {}), Err(Error::Domain(_))));
        let pole = Domain::Rectangle { u: [0.0, 0.3], theta: [0.0, 1.0] };
        let e = distribute(&p, &pole, &Options::default(), 0.4, 1, &mut |_| {}).unwrap_err();
        assert!(matches!(&e, Error::Domain(v) if v.iter().any(|x| matches!(x, DomainProblem::NearPole { .. }))), "{e}");
        let nan = Domain::Polygon { holes: Vec::new(), points: vec![[0.8, 0.0], [f64::NAN, 1.0], [1.2, 0.0]] };
        assert!(matches!(distribute(&p, &nan, &Options::default(), 0.4, 1, &mut |_| {}), Err(Error::Domain(_))));
        // Too many points: refused before allocating.
        let big = Domain::Rectangle { u: [0.3, 1.7], theta: [0.0, 6.0] };
        let e = distribute(&p, &big, &Options { density: 1.0, ..Options::default() }, 0.1, 1, &mut |_| {}).unwrap_err();
        assert!(matches!(e, Error::TooBig(_)), "{e}");
        println!("{e}");
    }

    /// Barrel Ω1 graded along u from 50 % to 25 %.
    fn graded_omega1(along: Along, seed_method: SeedMethod) -> (Platform, Domain, Options) {
        let (p, d, o) = omega("barrel-omega1");
        let g = Grading { along, density_to: 0.25, centre_u: 1.0, centre_theta_rad: 0.5, radius_mm: 12.0 };
        (p, d, Options { seed_method, grading: Some(g), ..o })
    }

    #[test]
    fn graded_n_is_the_integral_of_rho_squared() {
        // The cylinder of `n_matches_equation_4` (480 mm²), ρ linear in u from 0.6 to 0.3:
        // ∫ρ² dA = 480·(0.36 + 0.18 + 0.09)/3 = 100.8 mm², N = 100.8/0.16 = 630.
        let pts: Vec<[f64; 2]> = (0..13).map(|i| [20.0, 60.0 - 5.0 * i as f64]).collect();
        let cyl = Platform::from_polygon(&pts).unwrap();
        let d = Domain::Rectangle { u: [0.5, 1.5], theta: [0.0, 0.8] };
        let g = Grading { along: Along::U, density_to: 0.3, ..Grading::default() };
        let o = Options { density: 0.6, grading: Some(g.clone()), ..Options::default() };
        assert_eq!(estimate(&cyl, &d, &o, 0.4).get("points"), 630.0);
        // A "grading" to the same density is equation 4: 750 points at 50 %.
        for along in [Along::U, Along::Theta, Along::Radial] {
            let same = Options { grading: Some(Grading { along, density_to: 0.5, ..g.clone() }), ..Options::default() };
            assert_eq!(estimate(&cyl, &d, &same, 0.4).get("points"), 750.0, "{along:?}");
        }
    }

    #[test]
    fn graded_points_follow_the_target() {
        for (along, method) in [(Along::U, SeedMethod::Ebns), (Along::Theta, SeedMethod::Gbns), (Along::Radial, SeedMethod::Ere)] {
            let (p, d, o) = graded_omega1(along, method);
            let t = std::time::Instant::now();
            let r = distribute(&p, &d, &o, 0.4, 1, &mut |_| {}).unwrap();
            let secs = t.elapsed().as_secs_f64();
            let (sm, m) = (&r.seed_metrics, &r.metrics);
            println!(
                "{along:?}/{method:?}: N = {}, {secs:.3} s, {} iterations ({:?}); d/s(q) mean {:.3} → {:.3}, std {:.4} → {:.4} ({:.1} % lower); mm std {:.3} → {:.3}",
                r.points.len(),
                r.iterations.len(),
                r.stop,
                sm.rel_mean,
                m.rel_mean,
                sm.rel_std,
                m.rel_std,
                100.0 * (1.0 - m.rel_std / sm.rel_std),
                sm.nn_std_mm,
                m.nn_std_mm
            );
            assert_eq!(r.points.len(), r.target_points);
            assert!(m.rel_std < sm.rel_std, "{along:?}: no improvement against the graded target");
            let mut prev = 1.0;
            for it in &r.iterations {
                assert!(it.energy <= prev + o.energy_tolerance, "{along:?}: energy rose {prev} → {}", it.energy);
                prev = it.energy;
            }
            assert!(r.points.iter().all(|&q| d.contains(q)), "{along:?}: a point left Ω");
            let g = r.graded.as_ref().unwrap();
            assert_eq!((g.points.len(), g.seed.len()), (r.points.len(), r.seed_points.len()));
            if along == Along::U {
                // Counts in the first and last third of u against ∫ρ² dA over those thirds.
                let s = Surface::new(&p);
                let f = field_of(&s, &d, &o, 0.4).unwrap();
                let third = |k: f64| Domain::Rectangle { u: [0.8 + 0.4 * k / 3.0, 0.8 + 0.4 * (k + 1.0) / 3.0], theta: [0.0, 1.0] };
                let want = f.integral_rho2(&s, &third(0.0)) / f.integral_rho2(&s, &third(2.0));
                let count = |v: &[[f64; 2]], k: f64| v.iter().filter(|q| third(k).contains(**q)).count() as f64;
                for (name, v) in [("seed", &r.seed_points), ("result", &r.points)] {
                    let got = count(v, 0.0) / count(v, 2.0);
                    println!("  {name}: first/last third {} / {} = {got:.3}, ∫ρ² ratio {want:.3}", count(v, 0.0), count(v, 2.0));
                    assert!((got / want - 1.0).abs() < 0.15, "{name}: count ratio {got} against {want}");
                }
            }
        }
    }

    #[test]
    fn uniform_metrics_are_the_graded_ones_at_constant_spacing() {
        // The relative spread of a uniform run is its spread in mm over the spacing.
        let (p, d, mut o) = omega("barrel-omega1");
        o.iterations = 3;
        let r = distribute(&p, &d, &o, 0.4, 1, &mut |_| {}).unwrap();
        let s = spacing(&o, 0.4);
        assert!((r.metrics.rel_std - r.metrics.nn_std_mm / s).abs() < 1e-12);
        assert!(r.graded.is_none());
    }

    #[test]
    fn bad_grading_is_refused_with_its_name() {
        let p = Platform::barrel();
        let d = Domain::Rectangle { u: [0.8, 1.2], theta: [0.0, 1.0] };
        let g = Grading { along: Along::Radial, ..Grading::default() };
        let cases = [
            (Grading { density_to: 0.0, ..g.clone() }, "grading.density_to"),
            (Grading { density_to: f64::NAN, ..g.clone() }, "grading.density_to"),
            (Grading { density_to: 1.5, ..g.clone() }, "grading.density_to"),
            (Grading { radius_mm: 0.0, ..g.clone() }, "grading.radius_mm"),
            (Grading { centre_u: f64::INFINITY, ..g.clone() }, "grading.centre_u"),
            // The barrel's top pole: no metric to measure distances with there.
            (Grading { centre_u: 0.0, ..g.clone() }, "grading.centre_u"),
            (Grading { centre_theta_rad: f64::NAN, ..g.clone() }, "grading.centre_theta_rad"),
        ];
        for (g, want) in cases {
            let o = Options { grading: Some(g.clone()), ..Options::default() };
            let e = distribute(&p, &d, &o, 0.4, 1, &mut |_| {}).unwrap_err();
            assert!(matches!(&e, Error::BadOption { name, .. } if *name == want), "{g:?}: {e}");
            // The estimate refuses nothing but counts no points.
            assert_eq!(estimate(&p, &d, &o, 0.4).get("points"), 0.0);
        }
        // Too many points from the graded integral: refused before allocating.
        let big = Domain::Rectangle { u: [0.3, 1.7], theta: [0.0, 6.0] };
        let o = Options { density: 1.0, grading: Some(Grading { density_to: 0.9, ..Grading::default() }), ..Options::default() };
        assert!(matches!(distribute(&p, &big, &o, 0.1, 1, &mut |_| {}), Err(Error::TooBig(_))));
    }
}

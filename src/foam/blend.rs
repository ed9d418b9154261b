//! A point's pair π from its region and its distances to the shared boundaries (the paper's
//! Algorithm 2, FindVH), once the geometry has answered two questions: which region holds the
//! point, and how far it is from each shared boundary.
//!
//! A transition Ω^j → Ω^k has a length α_T and a weighting function; the signed distance α_i is
//! negative on the Ω^j side and positive on the Ω^k side, so a point in Ω^j at distance d from
//! the shared boundary has α_i = −d and one in Ω^k has α_i = +d (the orientation matters for
//! the weighting functions that are not odd about 0, such as the fitted logarithm). A point
//! takes its region's own pair unless it is within α_T/2 of a boundary its region shares; then
//! `π = π^j·(1 − w(x)) + π^k·w(x)` (equation 1), `x = α_i/α_T`.
//!
//! The paper lets a region share a boundary with one other region only, so at most one
//! transition is in reach. Beyond the paper, where regions meet along lines (three sectors of a
//! disc), a point may be in reach of several transitions of its region; it then takes the
//! average of their blends `π_t` with weights `ψ_t = (1 − 2|x_t|)/|x_t|`: inversely to its
//! relative distance from each boundary, and fading to 0 at the edge of each transition. So
//! π stays continuous where a transition comes into reach (its blend equals the region's own
//! pair there and its weight is 0), on each shared boundary (that boundary's weight dominates,
//! and both sides see the same blend), and where the nearest boundary changes; it may only
//! jump on the lines where boundaries meet. Taking the nearest boundary's blend instead
//! ([`Junction::Nearest`]) jumps along the bisector of two boundaries; `tests/it/foam_model.rs`
//! measures both. With one transition in reach both give exactly the paper's π.

use super::{Pair, Weighting};
use serde::{Deserialize, Serialize};

/// A transition between two regions (indices into the regions' list), from `from` (x < 0) to
/// `to` (x > 0).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Transition {
    /// Region on the negative side (Ω^j).
    pub from: usize,
    /// Region on the positive side (Ω^k).
    pub to: usize,
    /// Length α_T across the shared boundary, mm (0: a step at the boundary).
    pub length_mm: f64,
    /// Weighting function.
    pub weighting: Weighting,
}

/// How a point in reach of several transitions of its region takes its pair.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Junction {
    /// The distance-weighted average of the transitions' blends (continuous; see the module).
    #[default]
    Blend,
    /// The blend of the nearest boundary only (jumps where the nearest changes).
    Nearest,
}

/// The pair at a point inside region `region` whose (unsigned) distance to the shared boundary
/// of `transitions[t]` is `distances[t]` (mm; a transition its region is not part of is
/// skipped). `pairs[r]` is region r's own pair. Several transitions in reach are joined by
/// `junction`.
pub fn pair_at(region: usize, distances: &[f64], transitions: &[Transition], pairs: &[Pair], junction: Junction) -> Pair {
    // (|x|, the transition's blend) of each transition in reach.
    let mut near: Vec<(f64, Pair)> = Vec::new();
    for (t, d) in transitions.iter().zip(distances) {
        let alpha = if t.from == region {
            -d.abs()
        } else if t.to == region {
            d.abs()
        } else {
            continue;
        };
        let x = Weighting::x(alpha, t.length_mm);
        if x.abs() < 0.5 {
            near.push((x.abs(), pairs[t.from].lerp(pairs[t.to], t.weighting.weight(x))));
        }
    }
    match (near.as_slice(), junction) {
        ([], _) => pairs[region],
        ([one], _) => one.1,
        (_, Junction::Nearest) => near.iter().fold(near[0], |b, &c| if c.0 < b.0 { c } else { b }).1,
        (_, Junction::Blend) => blend(&near),
    }
}

/// The ψ-weighted average of blends at relative distances |x| (see the module); those on
/// their boundary (|x| = 0) share the whole weight.
fn blend(items: &[(f64, Pair)]) -> Pair {
    let on = items.iter().filter(|(x, _)| *x == 0.0).count();
    let weight = |x: f64| {
        if on > 0 {
            if x == 0.0 {
                1.0
            } else {
                0.0
            }
        } else {
            (1.0 - 2.0 * x) / x.max(1e-12)
        }
    };
    let (mut sw, mut sv, mut sh) = (0.0, 0.0, 0.0);
    for &(x, p) in items {
        let w = weight(x);
        sw += w;
        sv += w * p.v_star;
        sh += w * p.h_star;
    }
    // Equal values stay exact (a constant H* prints at one height).
    let same = |f: fn(&Pair) -> f64, s: f64| {
        let first = f(&items[0].1);
        if items.iter().all(|(_, p)| f(p) == first) {
            first
        } else {
            s / sw
        }
    };
    Pair { v_star: same(|p| p.v_star, sv), h_star: same(|p| p.h_star, sh) }
}

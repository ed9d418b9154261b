//! A point's pair π from its region and its distances to the shared boundaries (the paper's
//! Algorithm 2, FindVH), once the geometry has answered two questions: which region holds the
//! point, and how far it is from each shared boundary.
//!
//! A transition Ω^j → Ω^k has a length α_T and a weighting function; the signed distance α_i is
//! negative on the Ω^j side and positive on the Ω^k side, so a point in Ω^j at distance d from
//! the shared boundary has α_i = −d and one in Ω^k has α_i = +d (the orientation matters for
//! the weighting functions that are not odd about 0, such as the fitted logarithm). A point
//! takes its region's own pair unless it is within α_T/2 of a boundary its region shares; then
//! `π = π^j·(1 − w(x)) + π^k·w(x)` (equation 1), `x = α_i/α_T`. The paper lets a region share a
//! boundary with one other region only, so at most one transition is in reach; where the
//! geometry gives more, the nearest boundary decides.

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

/// The pair at a point inside region `region` whose (unsigned) distance to the shared boundary
/// of `transitions[t]` is `distances[t]` (mm; a transition its region is not part of is
/// skipped). `pairs[r]` is region r's own pair.
pub fn pair_at(region: usize, distances: &[f64], transitions: &[Transition], pairs: &[Pair]) -> Pair {
    let own = pairs[region];
    let mut best: Option<(f64, Pair)> = None;
    for (t, d) in transitions.iter().zip(distances) {
        let alpha = if t.from == region {
            -d.abs()
        } else if t.to == region {
            d.abs()
        } else {
            continue;
        };
        let x = Weighting::x(alpha, t.length_mm);
        if x.abs() < 0.5 && best.is_none_or(|(b, _)| d.abs() < b) {
            best = Some((d.abs(), pairs[t.from].lerp(pairs[t.to], t.weighting.weight(x))));
        }
    }
    best.map_or(own, |(_, p)| p)
}

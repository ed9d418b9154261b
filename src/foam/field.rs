//! The pair π at any point of the foam (Algorithm 2 over the [`Regions`]), and a walker that
//! answers it along a path with few geometric queries.
//!
//! A path that stays in the union changes region only by crossing a shared boundary, and its
//! distance to a boundary changes by at most the distance walked (1-Lipschitz). So the walker
//! keeps a lower bound of the distance to the current region's boundaries, lowers it by each
//! step, and queries parry only when the bound falls within the region's reach (half its
//! longest transition, at least 0): far from every boundary the pair is the region's own.

use super::blend::{pair_at, Junction, Transition};
use super::regions::Regions;
use super::vtp::Pair;
use crate::geom::DVec3;

/// The regions, their pairs and transitions: π anywhere.
pub struct Field<'a> {
    regions: &'a Regions,
    transitions: Vec<Transition>,
    /// The shared boundary of each transition.
    boundary_of: Vec<usize>,
    pairs: Vec<Pair>,
    /// Per region: half of its longest transition, mm.
    reach: Vec<f64>,
    junction: Junction,
}

impl<'a> Field<'a> {
    /// A field over `regions` with a pair per region and `transitions` between regions that
    /// share a boundary (others are left out: the job refuses them with their names first);
    /// `junction` joins the transitions in reach of one point.
    pub fn new(regions: &'a Regions, pairs: Vec<Pair>, transitions: &[Transition], junction: Junction) -> Field<'a> {
        let mut kept = Vec::new();
        let mut boundary_of = Vec::new();
        let mut reach = vec![0.0f64; regions.regions.len()];
        for t in transitions {
            if let Some(b) = regions.boundary(t.from, t.to) {
                kept.push(*t);
                boundary_of.push(b);
                for r in [t.from, t.to] {
                    reach[r] = reach[r].max(t.length_mm / 2.0);
                }
            }
        }
        Field { regions, transitions: kept, boundary_of, pairs, reach, junction }
    }

    /// π at `p` in region `region` (computed exactly), and the distance to the nearest
    /// boundary of the region (where it may change region).
    fn pair_in(&self, p: DVec3, region: usize) -> (Pair, f64) {
        let bounds = &self.regions.boundaries;
        let at: Vec<f64> = bounds.iter().map(|b| if b.other(region).is_some() { b.distance(p) } else { f64::INFINITY }).collect();
        let nearest = at.iter().copied().fold(f64::INFINITY, f64::min);
        let distances: Vec<f64> = self.boundary_of.iter().map(|&b| at[b]).collect();
        (pair_at(region, &distances, &self.transitions, &self.pairs, self.junction), nearest)
    }

    /// Region `r`'s own pair.
    pub fn pair(&self, r: usize) -> Pair {
        self.pairs[r]
    }

    /// π at `p` when it lies in the foam (within ε of a region), every query made.
    pub fn inside(&self, p: DVec3) -> Option<Pair> {
        let (r, d) = self.regions.locate_signed(p, 0);
        (d <= self.regions.epsilon_mm).then(|| self.pair_in(p, r).0)
    }

    /// A walker along one path (a layer), starting with no knowledge.
    pub fn walker(&self) -> Walker<'_, 'a> {
        Walker { field: self, last: None, region: 0, clear: f64::NEG_INFINITY, queries: 0 }
    }
}

/// Answers π point after point along a path (see the module notes).
pub struct Walker<'f, 'a> {
    field: &'f Field<'a>,
    last: Option<DVec3>,
    region: usize,
    /// Lower bound of the distance from the last point to the region's boundaries, mm.
    clear: f64,
    /// Exact evaluations made.
    pub queries: usize,
}

impl Walker<'_, '_> {
    /// π at `p`, the next point of the path, and its region.
    pub fn next(&mut self, p: DVec3) -> (Pair, usize) {
        if let Some(q) = self.last {
            self.clear -= (p - q).length();
        }
        self.last = Some(p);
        let f = self.field;
        if self.clear > f.reach[self.region] && self.clear > 0.0 {
            return (f.pairs[self.region], self.region);
        }
        self.queries += 1;
        self.region = f.regions.locate(p, self.region);
        let (pair, nearest) = f.pair_in(p, self.region);
        self.clear = nearest;
        (pair, self.region)
    }
}

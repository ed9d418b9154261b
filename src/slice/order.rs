//! Print order within a layer.
//!
//! Regions: nearest neighbour (distance from the current nozzle position to the region's
//! bounding box), starting from where the previous layer ended. Inside a region: perimeters
//! from the innermost level outwards, external perimeter last (inner-first keeps the visible
//! outer wall from being pushed around by later loops), then infill. Loops of one level and
//! infill polylines are each taken nearest-first; a loop starts at its vertex nearest to the
//! nozzle (the seam), a polyline is reversed when its far end is nearer. Ties break on index,
//! so the order is deterministic.

use crate::geom::{DVec2, DVec3, Feature, Path};

/// The material of one region, ready to be ordered.
#[derive(Clone, Debug, Default)]
pub(crate) struct RegionWork {
    /// Bounding box of the region, mm: min, max.
    pub min: DVec2,
    pub max: DVec2,
    /// Perimeter loops by level (0 = external), each loop implicitly closed, mm.
    pub perimeters: Vec<Vec<Vec<DVec2>>>,
    /// Infill polylines, mm.
    pub infill: Vec<(Feature, Vec<DVec2>)>,
}

pub(crate) fn box_dist2(p: DVec2, min: DVec2, max: DVec2) -> f64 {
    let d = (min - p).max(p - max).max(DVec2::ZERO);
    d.length_squared()
}

/// Orders the regions' paths; `pos` is the nozzle position, updated to the last point.
pub(crate) fn order_layer(regions: Vec<RegionWork>, pos: &mut DVec2, z: f64, width: f64) -> Vec<Path> {
    let mut paths = Vec::new();
    let mut left: Vec<Option<RegionWork>> = regions.into_iter().map(Some).collect();
    for _ in 0..left.len() {
        let mut best: Option<(f64, usize)> = None;
        for (i, r) in left.iter().enumerate() {
            if let Some(r) = r {
                let d = box_dist2(*pos, r.min, r.max);
                if best.is_none_or(|(bd, _)| d < bd) {
                    best = Some((d, i));
                }
            }
        }
        let Some((_, i)) = best else { break };
        let r = left[i].take().unwrap_or_default();
        let mk = |pts: Vec<DVec2>, feature: Feature| Path::new(pts.into_iter().map(|p| DVec3::new(p.x, p.y, z)).collect(), feature, width);
        for (level, loops) in r.perimeters.into_iter().enumerate().rev() {
            let feature = if level == 0 { Feature::ExternalPerimeter } else { Feature::Perimeter };
            for pts in order_loops(loops, pos) {
                paths.push(mk(pts, feature));
            }
        }
        for (feature, pts) in order_polylines(r.infill, pos) {
            paths.push(mk(pts, feature));
        }
    }
    paths
}

/// Skirt and brim loops in the order given (outside in), each started at its vertex nearest
/// the nozzle and closed; `pos` ends at the last one's end.
pub(crate) fn order_skirt(loops: Vec<Vec<DVec2>>, pos: &mut DVec2, z: f64, width: f64) -> Vec<Path> {
    let mut paths = Vec::with_capacity(loops.len());
    for l in loops {
        for pts in order_loops(vec![l], pos) {
            paths.push(Path::new(pts.into_iter().map(|p| DVec3::new(p.x, p.y, z)).collect(), Feature::Skirt, width));
        }
    }
    paths
}

/// Support lines before the part: the sparse support, then its interface, each nearest-first
/// (a closed sheath loop is a polyline whose ends meet).
pub(crate) fn order_support(base: Vec<Vec<DVec2>>, interface: Vec<Vec<DVec2>>, pos: &mut DVec2, z: f64, width: f64) -> Vec<Path> {
    let mut paths = Vec::with_capacity(base.len() + interface.len());
    for (feature, lines) in [(Feature::Support, base), (Feature::SupportInterface, interface)] {
        let lines = lines.into_iter().map(|l| (feature, l)).collect();
        for (f, pts) in order_polylines(lines, pos) {
            paths.push(Path::new(pts.into_iter().map(|p| DVec3::new(p.x, p.y, z)).collect(), f, width));
        }
    }
    paths
}

/// Nearest-first loops, each rotated to start at its vertex nearest `pos` and closed.
fn order_loops(loops: Vec<Vec<DVec2>>, pos: &mut DVec2) -> Vec<Vec<DVec2>> {
    let mut left: Vec<Option<Vec<DVec2>>> = loops.into_iter().filter(|l| l.len() >= 2).map(Some).collect();
    let mut out = Vec::with_capacity(left.len());
    for _ in 0..left.len() {
        let mut best: Option<(f64, usize, usize)> = None;
        for (i, l) in left.iter().enumerate() {
            let Some(l) = l else { continue };
            for (j, p) in l.iter().enumerate() {
                let d = p.distance_squared(*pos);
                if best.is_none_or(|(bd, _, _)| d < bd) {
                    best = Some((d, i, j));
                }
            }
        }
        let Some((_, i, j)) = best else { break };
        let mut l = left[i].take().unwrap_or_default();
        l.rotate_left(j);
        l.push(l[0]);
        *pos = l[0];
        out.push(l);
    }
    out
}

/// Nearest-first polylines, reversed when their last point is the nearer end.
fn order_polylines(lines: Vec<(Feature, Vec<DVec2>)>, pos: &mut DVec2) -> Vec<(Feature, Vec<DVec2>)> {
    let mut left: Vec<Option<(Feature, Vec<DVec2>)>> = lines.into_iter().filter(|l| l.1.len() >= 2).map(Some).collect();
    let mut out = Vec::with_capacity(left.len());
    for _ in 0..left.len() {
        let mut best: Option<(f64, usize, bool)> = None;
        for (i, l) in left.iter().enumerate() {
            let Some((_, l)) = l else { continue };
            for (rev, p) in [(false, l[0]), (true, l[l.len() - 1])] {
                let d = p.distance_squared(*pos);
                if best.is_none_or(|(bd, _, _)| d < bd) {
                    best = Some((d, i, rev));
                }
            }
        }
        let Some((_, i, rev)) = best else { break };
        let (f, mut l) = left[i].take().unwrap_or((Feature::Infill, Vec::new()));
        if rev {
            l.reverse();
        }
        *pos = l[l.len() - 1];
        out.push((f, l));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inner_first_seam_near_and_closed() {
        let sq = |s: f64| vec![DVec2::new(-s, -s), DVec2::new(s, -s), DVec2::new(s, s), DVec2::new(-s, s)];
        let r = RegionWork {
            min: DVec2::splat(-5.0),
            max: DVec2::splat(5.0),
            perimeters: vec![vec![sq(5.0)], vec![sq(4.0)]],
            infill: vec![(Feature::SolidInfill, vec![DVec2::new(3.0, 0.0), DVec2::new(-3.0, 0.0)])],
        };
        let mut pos = DVec2::new(10.0, 10.0);
        let paths = order_layer(vec![r], &mut pos, 0.2, 0.4);
        assert_eq!(paths.len(), 3);
        assert_eq!(paths[0].feature, Feature::Perimeter);
        assert_eq!(paths[1].feature, Feature::ExternalPerimeter);
        assert_eq!(paths[0].points[0], DVec3::new(4.0, 4.0, 0.2));
        assert_eq!(paths[0].points.first(), paths[0].points.last());
        assert_eq!(paths[2].points[0].x, 3.0);
        assert_eq!(pos, DVec2::new(-3.0, 0.0));
    }
}

//! The projection proper: split, cast, lift along the normal, check collisions.

use super::collision::collides;
use super::surface::Caster;
use super::{Error, Projected, ProjectionReport};
use crate::geom::{DVec2, DVec3, Pass, Path, Toolpath};

/// Deepest bisection of one planar piece. Where the projection jumps (a ray starts missing
/// the surface) no split helps; the piece stops being split after this many halvings.
const MAX_DEPTH: u32 = 24;

struct Ctx<'a> {
    caster: &'a Caster,
    max_seg: f64,
    /// Lowest surface Z under the toolpath's own points: where missed points are kept.
    floor: f64,
}

impl Ctx<'_> {
    /// The nozzle position over planar `q` at offset `d` along the surface normal.
    fn lift(&self, q: DVec2, d: f64) -> DVec3 {
        match self.caster.cast(q.x, q.y) {
            Some(h) => h.p + h.n * d,
            None => DVec3::new(q.x, q.y, self.floor + d),
        }
    }

    /// Projects the planar polyline through the XY of `points` at offset `d`, splitting so that
    /// no projected segment is longer than `max_seg` (every input point is kept, in order).
    fn polyline(&self, points: &[DVec2], d: f64) -> Vec<DVec3> {
        let mut out = Vec::with_capacity(points.len() * 2);
        let Some(&first) = points.first() else { return out };
        let mut pa = self.lift(first, d);
        out.push(pa);
        for w in points.windows(2) {
            let (a, b) = (w[0], w[1]);
            let k = (a.distance(b) / self.max_seg).ceil().clamp(1.0, 1.0e6) as usize;
            let mut prev = a;
            for j in 1..=k {
                let q = if j == k { b } else { a + (b - a) * (j as f64 / k as f64) };
                let pq = self.lift(q, d);
                self.refine(prev, q, pa, pq, d, 0, &mut out);
                prev = q;
                pa = pq;
            }
        }
        out
    }

    /// Appends the projection of planar `a → b` (excluding `a`), bisecting while the projected
    /// piece is longer than `max_seg`.
    #[allow(clippy::too_many_arguments)]
    fn refine(&self, a: DVec2, b: DVec2, pa: DVec3, pb: DVec3, d: f64, depth: u32, out: &mut Vec<DVec3>) {
        if pa.distance(pb) <= self.max_seg || depth >= MAX_DEPTH || a.distance(b) < 1e-9 {
            out.push(pb);
            return;
        }
        let m = (a + b) * 0.5;
        let pm = self.lift(m, d);
        self.refine(a, m, pa, pm, d, depth + 1, out);
        self.refine(m, b, pm, pb, d, depth + 1, out);
    }
}

fn xy(points: &[DVec3]) -> Vec<DVec2> {
    points.iter().map(|p| p.truncate()).collect()
}

/// See [`super::project`]; options are validated and the caster built.
pub(crate) fn run(toolpath: &Toolpath, caster: &Caster, max_seg: f64) -> Result<Projected, Error> {
    // Pass 1: which input points lie over the surface, and the lowest surface Z among them.
    let mut floor = f64::INFINITY;
    let (mut total, mut missed) = (0usize, 0usize);
    for layer in &toolpath.passes {
        for path in &layer.paths {
            for q in path.points.iter().chain(path.approach.iter().flatten()) {
                total += 1;
                match caster.cast(q.x, q.y) {
                    Some(h) => floor = floor.min(h.p.z),
                    None => missed += 1,
                }
            }
        }
    }
    if total == 0 {
        return Ok(Projected { toolpath: toolpath.clone(), report: ProjectionReport::default() });
    }
    if missed == total {
        return Err(Error::NothingOver);
    }
    let ctx = Ctx { caster, max_seg, floor };

    // Pass 2: project layer by layer; layer i sits the sum of the heights of layers 0..=i
    // above the surface ((i + 1) · h for uniform layers).
    let mut report = ProjectionReport { missed_points: missed, ..Default::default() };
    let (mut zmin, mut zmax) = (f64::INFINITY, f64::NEG_INFINITY);
    let mut d_below = 0.0;
    let mut layers = Vec::with_capacity(toolpath.passes.len());
    for layer in &toolpath.passes {
        let d = d_below + layer.height.max(0.0);
        let mut paths = Vec::with_capacity(layer.paths.len());
        let mut prev_end: Option<DVec2> = None;
        let mut layer_top = f64::NEG_INFINITY;
        let mut count = |pts: &[DVec3], report: &mut ProjectionReport| {
            for w in pts.windows(2) {
                if collides(caster, w[0], w[1], d_below) {
                    report.collisions += 1;
                }
            }
            for p in pts {
                zmin = zmin.min(p.z);
                zmax = zmax.max(p.z);
                layer_top = layer_top.max(p.z);
            }
        };
        for path in &layer.paths {
            let points = ctx.polyline(&xy(&path.points), d);
            count(&points, &mut report);
            let approach = match (&path.approach, path.points.first()) {
                (Some(route), Some(start)) => {
                    // The whole approach leg: previous path end (same layer), route, path start.
                    let mut leg: Vec<DVec2> = prev_end.into_iter().collect();
                    leg.extend(route.iter().map(|p| p.truncate()));
                    leg.push(start.truncate());
                    let proj = ctx.polyline(&leg, d);
                    count(&proj, &mut report);
                    let skip = usize::from(prev_end.is_some());
                    Some(proj[skip..proj.len() - 1].to_vec())
                }
                (route, _) => route.clone(),
            };
            prev_end = path.points.last().map(|p| p.truncate()).or(prev_end);
            paths.push(Path { points, approach, ..path.clone() });
        }
        let z = if layer_top.is_finite() { layer_top } else { floor + d };
        layers.push(Pass::layer(z, layer.height, paths));
        d_below = d;
    }
    report.z_range_mm = if zmin.is_finite() { [zmin, zmax] } else { [0.0, 0.0] };
    Ok(Projected { toolpath: Toolpath { passes: layers }, report })
}

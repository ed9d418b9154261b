//! Grading a sliced toolpath by a density field: equation 6 applied by weft's own slicer.
//!
//! Every infill segment's extruded cross-section becomes `A_s · ρ(midpoint) / ρ_s` (the
//! paper's ΔE_e = ΔE_s · ρ_e / ρ_s), with `A_s` the bead of equation 1 at the sliced density.
//! Unlike editing another slicer's file, weft splits long segments first, so the grading
//! resolves the field (`segment_mm`, by default the smallest voxel spacing). Per segment the
//! volumetric flow (area × feed) and the bead width (stadium model, [`super::width_of_area`])
//! are checked against `q_max_mm3_s` and `width_max_mm`: counted, and with [`Limit::Clamp`]
//! the area is reduced to both limits.
//!
//! The report measures every segment twice: the **target** ρ is the field's mean along the
//! segment (sampled every `segment_mm / 4`), the **achieved** ρ is `ρ_s · A / A_s` as written;
//! their length-weighted difference per layer says how well the G-code follows the field.

use crate::budget::{Estimate, OverBudget};
use crate::geom::{DVec3, Feature, Path, PointData, PointFlow, Toolpath};
use serde::{Deserialize, Serialize};

/// Most infill segments after splitting.
pub const MAX_SEGMENTS: usize = 50_000_000;

pub use super::{LayerStat, Limit};

/// Grading options (all set by the job from the design and the paper's equations).
#[derive(Clone, Debug, PartialEq)]
pub struct Options {
    /// The density the infill was sliced for, ρ_s (0–1].
    pub rho_s: f64,
    /// Floor of the target, ρ_e,min (from E_w,min).
    pub rho_min: f64,
    /// Bead cross-section at ρ_s, mm².
    pub nominal_area_mm2: f64,
    /// Longest infill segment after splitting, mm.
    pub segment_mm: f64,
    /// Volumetric flow limit, mm³/s.
    pub q_max_mm3_s: f64,
    /// Widest bead, mm (E_w,max).
    pub width_max_mm: f64,
    /// Warn or clamp.
    pub limit: Limit,
    /// Infill feed, mm/s (for the flow check).
    pub feed_mm_s: f64,
}

/// What grading did.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct GradeReport {
    /// Infill segments written (after splitting).
    pub segments: usize,
    /// Segments added by splitting.
    pub split_added: usize,
    /// Segments whose midpoint has no density (outside the volume): written at ρ_s.
    pub outside: usize,
    /// Segments raised to ρ_min.
    pub clamped_low: usize,
    /// Segments over the volumetric flow limit.
    pub over_flow: usize,
    /// Segments over the width limit.
    pub over_width: usize,
    /// Infill material as graded, mm³.
    pub infill_mm3: f64,
    /// Infill material at a uniform ρ_s, mm³.
    pub uniform_mm3: f64,
    /// Widest bead written, mm.
    pub max_width_mm: f64,
    /// Largest volumetric flow written, mm³/s.
    pub max_flow_mm3_s: f64,
    /// Per layer.
    pub layers: Vec<LayerStat>,
    /// Where the toolpath's frame sits relative to the field's: toolpath point = field point
    /// + offset, mm (set by the caller; grading only reads `density`).
    pub offset_mm: [f64; 3],
}

/// A graded toolpath.
pub struct Graded {
    /// The toolpath with per-point flow on its infill.
    pub toolpath: Toolpath,
    /// What grading did.
    pub report: GradeReport,
}

/// Why grading failed.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum Error {
    /// An option is out of its range.
    #[error("{0}")]
    BadOption(String),
    /// Over a budget.
    #[error(transparent)]
    TooBig(#[from] OverBudget),
}

/// The work of grading `toolpath`: segments after splitting.
pub fn estimate(toolpath: &Toolpath, options: &Options) -> Estimate {
    let length: f64 = toolpath.passes.iter().flat_map(|p| &p.paths).filter(|p| p.feature == Feature::Infill).map(Path::length).sum();
    let segments = length / options.segment_mm.max(1e-3) + infill_segments(toolpath) as f64;
    Estimate::new("grade")
        .quantity("segments", "Infill segments", segments, "")
        .limit("infill segments after splitting", segments, MAX_SEGMENTS as f64, "", "raise the grading step (job.density.segment_mm)")
        .cost(segments * 120.0, segments * 2e-7)
}

fn infill_segments(t: &Toolpath) -> usize {
    t.passes.iter().flat_map(|p| &p.paths).filter(|p| p.feature == Feature::Infill).map(|p| p.points.len().saturating_sub(1)).sum()
}

/// Grades the infill of `toolpath` by `density` (ρ at a point of the toolpath's frame, `None`
/// outside the field). `cell_ratio`, when the infill's cell varies ([`super::cells`]), is
/// `L(p) / L_s`: the bead then is `A_s · (ρ / ρ_s) · L(p) / L_s` (equation 1 in the local cell)
/// and the floor `ρ_min · L_s / L(p)` (`E_w,min` in that cell).
pub fn grade(
    toolpath: &Toolpath,
    density: &dyn Fn(DVec3) -> Option<f64>,
    cell_ratio: Option<&dyn Fn(DVec3) -> f64>,
    options: &Options,
    progress: &mut dyn FnMut(f32),
) -> Result<Graded, Error> {
    let o = options;
    let ok = |x: f64| x.is_finite() && x > 0.0;
    if !(ok(o.rho_s)
        && o.rho_s <= 1.0
        && o.rho_min.is_finite()
        && (0.0..=1.0).contains(&o.rho_min)
        && ok(o.nominal_area_mm2)
        && ok(o.segment_mm)
        && ok(o.q_max_mm3_s)
        && ok(o.width_max_mm)
        && ok(o.feed_mm_s))
    {
        return Err(Error::BadOption(format!("grading options out of range: {o:?}")));
    }
    let e = estimate(toolpath, o);
    if let Some(r) = e.refused {
        return Err(Error::TooBig(r));
    }
    let mut report = GradeReport::default();
    let mut out = toolpath.clone();
    let n = out.passes.len().max(1);
    for (li, pass) in out.passes.iter_mut().enumerate() {
        let h = pass.height;
        let area_limit = super::max_bead_area(o.q_max_mm3_s, o.feed_mm_s, o.width_max_mm, h);
        let mut stat = LayerStat { z_mm: pass.z, ..Default::default() };
        for path in pass.paths.iter_mut().filter(|p| p.feature == Feature::Infill) {
            let points = split(&path.points, o.segment_mm);
            report.split_added += points.len() - path.points.len();
            let mut areas = vec![0.0; points.len()];
            for i in 1..points.len() {
                let (a, b) = (points[i - 1], points[i]);
                let len = a.distance(b);
                let mid = (a + b) * 0.5;
                let target = match density(mid) {
                    Some(r) => r,
                    None => {
                        report.outside += 1;
                        o.rho_s
                    }
                };
                let ratio = cell_ratio.map_or(1.0, |f| f(mid));
                let rho_min = o.rho_min / ratio;
                let mut rho = target;
                if rho < rho_min {
                    rho = rho_min;
                    report.clamped_low += 1;
                }
                let rho = rho.min(1.0);
                let mut area = o.nominal_area_mm2 * ratio * rho / o.rho_s;
                let width = super::width_of_area(area, h);
                if area * o.feed_mm_s > o.q_max_mm3_s * (1.0 + 1e-12) {
                    report.over_flow += 1;
                }
                if width > o.width_max_mm * (1.0 + 1e-12) {
                    report.over_width += 1;
                }
                if o.limit == Limit::Clamp && area > area_limit {
                    area = area_limit;
                }
                areas[i] = area;
                report.max_width_mm = report.max_width_mm.max(super::width_of_area(area, h));
                report.max_flow_mm3_s = report.max_flow_mm3_s.max(area * o.feed_mm_s);
                report.infill_mm3 += area * len;
                report.uniform_mm3 += o.nominal_area_mm2 * ratio * len;
                // The target along the segment, not only at its midpoint.
                let along = super::mean_along(a, b, o.segment_mm / 4.0, density).unwrap_or(target).max(rho_min).min(1.0);
                let achieved = o.rho_s * area / (o.nominal_area_mm2 * ratio);
                stat.moves += 1;
                stat.length_mm += len;
                stat.target_mean += along * len;
                stat.achieved_mean += achieved * len;
                stat.mean_abs_error += (achieved - along).abs() * len;
            }
            path.points = points;
            let data = path.data.get_or_insert_with(|| Box::new(PointData::default()));
            data.flow = Some(PointFlow::AreaMm2(areas));
            // Per-point vectors must match the new point count; the slicer's paths carry none.
            data.feed_mm_s = None;
            data.tool_axis = None;
            data.dwell_s = None;
        }
        report.segments += stat.moves;
        if stat.length_mm > 0.0 {
            stat.target_mean /= stat.length_mm;
            stat.achieved_mean /= stat.length_mm;
            stat.mean_abs_error /= stat.length_mm;
        }
        report.layers.push(stat);
        progress((li + 1) as f32 / n as f32);
    }
    Ok(Graded { toolpath: out, report })
}

/// `points` with every segment longer than `max` cut into equal pieces no longer than it.
fn split(points: &[DVec3], max: f64) -> Vec<DVec3> {
    let mut out = Vec::with_capacity(points.len());
    if let Some(&first) = points.first() {
        out.push(first);
    }
    for w in points.windows(2) {
        let pieces = libm::ceil(w[0].distance(w[1]) / max).max(1.0) as usize;
        for k in 1..=pieces {
            out.push(w[0].lerp(w[1], k as f64 / pieces as f64));
        }
    }
    out
}

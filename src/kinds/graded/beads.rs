//! The views the "How it works" steps add: a CT slice inside the region of interest in HU, and
//! one layer's toolpath coloured by bead width.

use super::*;
use crate::geom::{Feature, PointFlow};

/// Feature codes of the bead-width bins, narrowest first (blue → red in the schema's colours).
pub const WIDTH_CODES: [Feature; 6] = [Feature::Lattice, Feature::Beam, Feature::Contour, Feature::Perimeter, Feature::ExternalPerimeter, Feature::Infill];
/// The code of paths that are not graded (perimeters, skirt) in the bead-width view.
pub const UNGRADED_CODE: Feature = Feature::Handle;

/// The axial slices the ROI spans (all of them when it spans none).
fn roi_slices(vol: &Volume, roi: &Roi) -> (usize, usize) {
    let (n, dz) = (vol.dims[2], vol.spacing_mm[2]);
    if n == 0 {
        return (0, 0);
    }
    let k0 = libm::ceil(roi.min_mm[2] / dz - 1e-9).max(0.0) as usize;
    let k1 = (libm::floor(roi.max_mm[2] / dz + 1e-9).max(0.0) as usize).min(n - 1);
    if k0 <= k1 {
        (k0, k1)
    } else {
        (0, n - 1)
    }
}

/// Slice `index` of the ROI's axial slices in HU: outside the ROI the image takes the ROI's
/// lowest value, the window is the ROI's range, with the iso-contours and the ROI box.
pub(super) fn hu_view(j: &GradedJob, vol: &Volume, roi: &Roi, index: usize) -> Inspection {
    let (k0, k1) = roi_slices(vol, roi);
    let index = index.min(k1 - k0);
    let mut v = slice_view("hu", vol, SliceAxis::Axial, k0 + index, roi, j);
    let (w, h) = (v.meta["width"].as_u64().unwrap_or(0) as usize, v.meta["height"].as_u64().unwrap_or(0) as usize);
    let [px, py] = [vol.spacing_mm[0], vol.spacing_mm[1]];
    let inside = |x: usize, y: usize| {
        let (a, b) = (x as f64 * px, y as f64 * py);
        a >= roi.min_mm[0] - 1e-9 && a <= roi.max_mm[0] + 1e-9 && b >= roi.min_mm[1] - 1e-9 && b <= roi.max_mm[1] + 1e-9
    };
    let (mut lo, mut hi, mut sum, mut n) = (f32::INFINITY, f32::NEG_INFINITY, 0.0f64, 0usize);
    for y in 0..h {
        for x in 0..w {
            let value = v.data[y * w + x];
            if inside(x, y) && value.is_finite() {
                (lo, hi, sum, n) = (lo.min(value), hi.max(value), sum + value as f64, n + 1);
            }
        }
    }
    if n == 0 {
        (lo, hi) = (0.0, 0.0);
    }
    for y in 0..h {
        for x in 0..w {
            let value = &mut v.data[y * w + x];
            if !inside(x, y) || !value.is_finite() {
                *value = lo;
            }
        }
    }
    let unit = if vol.info.unit.is_empty() { "" } else { vol.info.unit.as_str() };
    let mean = if n > 0 { sum / n as f64 } else { 0.0 };
    v.index = index;
    v.count = k1 - k0 + 1;
    v.meta["window"] = serde_json::json!([lo, if hi > lo { hi } else { lo + 1.0 }]);
    v.meta["caption"] = format!(
        "z = {:.1} mm (ROI slice {} of {}): {lo:.0} to {hi:.0} {unit} in the ROI, mean {mean:.0} {unit}; surface at {} {unit}",
        (k0 + index) as f64 * vol.spacing_mm[2],
        index + 1,
        k1 - k0 + 1,
        crate::settings::fmt(j.surface.iso)
    )
    .into();
    v.meta["roi_range"] = serde_json::json!([lo, hi]);
    v
}

/// Bead width of each infill segment of `pass`, in path order (the segment ending at point i
/// has width `width_of_area(area[i], height)`), mm.
pub fn infill_widths(pass: &crate::geom::Pass) -> Vec<f64> {
    let mut out = Vec::new();
    for p in pass.paths.iter().filter(|p| p.feature == Feature::Infill) {
        if let Some(PointFlow::AreaMm2(a)) = p.data.as_ref().and_then(|d| d.flow.as_ref()) {
            out.extend(a.iter().skip(1).take(p.points.len().saturating_sub(1)).map(|&area| scaffold::width_of_area(area, pass.height)));
        }
    }
    out
}

/// The bin of width `w` over [lo, hi] split into [`WIDTH_CODES`] equal bins.
pub fn width_bin(w: f64, lo: f64, hi: f64) -> usize {
    let n = WIDTH_CODES.len();
    if !(hi > lo) {
        return 0;
    }
    (libm::floor((w - lo) / (hi - lo) * n as f64).max(0.0) as usize).min(n - 1)
}

/// Layer `index` of the graded toolpath (XY, mm): each infill segment coded by its bead width's
/// bin over the job's allowed widths (widened to the layer's own if it passes them), the
/// paths that are not graded in grey.
pub(super) fn beads_view(j: &GradedJob, ctx: &mut Ctx, vol: &Out<Volume>, index: usize) -> Result<Inspection, Error> {
    if j.route != Route::Native {
        return Err(Error::NoInput("the bead-width view shows the native route's graded toolpath: switch the route to native".into()));
    }
    let surface = surface_stage(j, ctx, vol)?;
    let model = density_stage(j, ctx, vol, &surface)?;
    let n = native_stages(j, ctx, vol, &surface, &model)?;
    let passes = &n.graded.passes;
    let count = passes.len();
    let index = index.min(count.saturating_sub(1));
    let Some(pass) = passes.get(index) else {
        return Err(Error::NoInput("the graded toolpath has no layers: widen the ROI or lower the isovalue".into()));
    };
    let widths = infill_widths(pass);
    let (w_lo, w_hi) = widths.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &w| (a.min(w), b.max(w)));
    let (lo, hi) = (j.density.min_width_mm.min(w_lo), j.density.max_width_mm.max(w_hi));
    let mut data = Vec::with_capacity(5 * (widths.len() + 64));
    let mut next = widths.iter();
    for p in pass.paths.iter().filter(|p| p.feature == Feature::Infill) {
        if !matches!(p.data.as_ref().and_then(|d| d.flow.as_ref()), Some(PointFlow::AreaMm2(_))) {
            continue;
        }
        for s in p.points.windows(2) {
            let Some(&w) = next.next() else { break };
            let code = WIDTH_CODES[width_bin(w, lo, hi)].code() as f32;
            data.extend_from_slice(&[s[0].x as f32, s[0].y as f32, s[1].x as f32, s[1].y as f32, code]);
        }
    }
    let graded_items = data.len() / 5;
    for p in pass.paths.iter().filter(|p| p.feature != Feature::Infill || !matches!(p.data.as_ref().and_then(|d| d.flow.as_ref()), Some(PointFlow::AreaMm2(_))))
    {
        for s in p.points.windows(2) {
            data.extend_from_slice(&[s[0].x as f32, s[0].y as f32, s[1].x as f32, s[1].y as f32, UNGRADED_CODE.code() as f32]);
        }
    }
    let step = (hi - lo) / WIDTH_CODES.len() as f64;
    let bins: Vec<serde_json::Value> = WIDTH_CODES
        .iter()
        .enumerate()
        .map(|(i, f)| serde_json::json!({ "code": f.code(), "from_mm": lo + step * i as f64, "to_mm": lo + step * (i + 1) as f64 }))
        .collect();
    let mut legend = serde_json::Map::new();
    for (i, f) in WIDTH_CODES.iter().enumerate() {
        legend.insert(f.code().to_string(), format!("bead {:.2}–{:.2} mm", lo + step * i as f64, lo + step * (i + 1) as f64).into());
    }
    legend.insert(UNGRADED_CODE.code().to_string(), "perimeters (not graded)".into());
    let caption = if widths.is_empty() {
        format!("layer {} of {count} at z = {:.2} mm: no graded infill", index + 1, pass.z)
    } else {
        format!(
            "layer {} of {count} at z = {:.2} mm: bead width {w_lo:.2}–{w_hi:.2} mm over {} infill segments (allowed {:.2}–{:.2} mm)",
            index + 1,
            pass.z,
            widths.len(),
            j.density.min_width_mm,
            j.density.max_width_mm
        )
    };
    let meta = serde_json::json!({
        "caption": caption, "legend": legend, "bins": bins, "z_mm": pass.z, "graded_segments": graded_items,
        "width_min_mm": if widths.is_empty() { serde_json::Value::Null } else { w_lo.into() },
        "width_max_mm": if widths.is_empty() { serde_json::Value::Null } else { w_hi.into() },
        "allowed_mm": [j.density.min_width_mm, j.density.max_width_mm],
    });
    Ok(Inspection { view: "beads".into(), shape: Shape::Lines2d, index, count, stride: Shape::Lines2d.stride(), data, overlay: Vec::new(), meta })
}

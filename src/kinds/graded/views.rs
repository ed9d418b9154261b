//! The graded job's views: an axial, coronal or sagittal CT slice in HU with the region of interest and the contour levels, and the target density.

use super::*;

/// One of the kind's views at `index` (`Kind::inspect`).
pub(super) fn inspect(j: &GradedJob, ctx: &mut Ctx, view: &str, index: usize) -> Result<Inspection, Error> {
    let vol = volume_stage(j, ctx)?;
    let roi = roi_of(j, &vol);
    match view {
        "axial" | "coronal" | "sagittal" => {
            let axis = match view {
                "axial" => SliceAxis::Axial,
                "coronal" => SliceAxis::Coronal,
                _ => SliceAxis::Sagittal,
            };
            Ok(slice_view(view, &vol, axis, index, &roi, j))
        }
        "density" => {
            let model = Model::of(j, ctx.design, &vol)?;
            let image = volume::slice_image(&vol, SliceAxis::Axial, index);
            let curve = j.density.calibration.curve();
            let values: Vec<f32> = image.values.iter().map(|&hu| curve.density(hu as f64, model.rho_min) as f32).collect();
            let mut overlay = Vec::new();
            roi_rect(&mut overlay, &image, &roi);
            Ok(Inspection {
                view: view.into(),
                shape: Shape::Image,
                index: image.index,
                count: image.count,
                stride: 1,
                data: values,
                overlay,
                meta: serde_json::json!({
                    "width": image.width, "height": image.height, "pixel_mm": image.pixel_mm, "window": [0.0, 1.0], "unit": "ρ",
                    "caption": format!("z = {:.1} mm · ρ_min {:.3}", image.position_mm, model.rho_min),
                    "overlay_legend": [{"code": ROI_CODE, "label": "region of interest", "color": ROI_COLOR}],
                }),
            })
        }
        "surface" => {
            let surface = surface_stage(j, ctx, &vol)?;
            let m = &surface.mesh;
            let mut data = Vec::with_capacity(m.triangles.len() * 9);
            for t in &m.triangles {
                for &v in t {
                    data.extend_from_slice(&m.vertices[v as usize]);
                }
            }
            let r = &surface.report;
            Ok(Inspection {
                view: view.into(),
                shape: Shape::Mesh,
                index: 0,
                count: 1,
                stride: 9,
                data,
                overlay: Vec::new(),
                meta: serde_json::json!({ "caption": format!("{} triangles, {:.0} mm³{}", r.triangles, r.volume_mm3, if r.closed { ", closed" } else { ", NOT closed" }), "stl": true }),
            })
        }
        "hu" => Ok(hu_view(j, &vol, &roi, index)),
        "beads" => beads_view(j, ctx, &vol, index),
        _ => Err(Error::UnknownView { view: view.into(), job: GradedKind::NAME }),
    }
}

/// Overlay code of the ROI rectangle on the slice views.
pub(super) const ROI_CODE: usize = 10;
pub(super) const ROI_COLOR: &str = "#4cc38a";
/// The contour colours of the paper's Fig. 8: yellow, red, blue.
pub(super) const LEVEL_COLORS: [&str; 3] = ["#f5d547", "#e5484d", "#3e8ef7"];

/// A slice view: the image in HU, the iso-contours at the design's levels and the ROI box.
pub(super) fn slice_view(view: &str, vol: &Volume, axis: SliceAxis, index: usize, roi: &Roi, j: &GradedJob) -> Inspection {
    let image = volume::slice_image(vol, axis, index);
    let mut overlay = Vec::new();
    for s in volume::isolines(&image, &j.contour_levels_hu) {
        overlay.extend_from_slice(&s);
    }
    roi_rect(&mut overlay, &image, roi);
    let mut legend: Vec<serde_json::Value> = j
        .contour_levels_hu
        .iter()
        .zip(LEVEL_COLORS)
        .enumerate()
        .map(|(i, (hu, color))| serde_json::json!({"code": i, "label": format!("{} HU", crate::settings::fmt(*hu)), "color": color}))
        .collect();
    legend.push(serde_json::json!({"code": ROI_CODE, "label": "region of interest", "color": ROI_COLOR}));
    let unit = if vol.info.unit.is_empty() { "" } else { vol.info.unit.as_str() };
    // A bone window by default for CT; the data's range otherwise.
    let window = if unit == "HU" { serde_json::json!([-400.0, 1600.0]) } else { serde_json::Value::Null };
    let axis_name = ["x (i)", "y (j)", "z (k)"][match axis {
        SliceAxis::Axial => 2,
        SliceAxis::Coronal => 1,
        SliceAxis::Sagittal => 0,
    }];
    Inspection {
        view: view.into(),
        shape: Shape::Image,
        index: image.index,
        count: image.count,
        stride: 1,
        data: image.values,
        overlay,
        meta: serde_json::json!({
            "width": image.width, "height": image.height, "pixel_mm": image.pixel_mm, "window": window, "unit": unit,
            "caption": format!("{axis_name} = {:.1} mm", image.position_mm),
            "overlay_legend": legend,
        }),
    }
}

/// The ROI's outline on a slice (when the slice crosses the ROI), in the image's mm frame.
pub(super) fn roi_rect(out: &mut Vec<f32>, image: &volume::SliceImage, roi: &Roi) {
    // Image x, y and the fixed axis, as volume axes.
    let (ax, ay, fixed) = match image.axis {
        SliceAxis::Axial => (0, 1, 2),
        SliceAxis::Coronal => (0, 2, 1),
        SliceAxis::Sagittal => (1, 2, 0),
    };
    if image.position_mm < roi.min_mm[fixed] - 1e-9 || image.position_mm > roi.max_mm[fixed] + 1e-9 {
        return;
    }
    let (x0, x1, y0, y1) = (roi.min_mm[ax] as f32, roi.max_mm[ax] as f32, roi.min_mm[ay] as f32, roi.max_mm[ay] as f32);
    let c = ROI_CODE as f32;
    out.extend_from_slice(&[x0, y0, x1, y0, c, x1, y0, x1, y1, c, x1, y1, x0, y1, c, x0, y1, x0, y0, c]);
}

//! The foam job's views: a shared boundary between two regions, and a layer's path in its outline.

use super::*;

/// One of the kind's views at `index` (`Kind::inspect`).
pub(super) fn inspect(j: &FoamJob, ctx: &mut Ctx, view: &str, index: usize) -> Result<Inspection, Error> {
    match view {
        "boundaries" => {
            let regions = regions_stage(j, ctx)?;
            let count = regions.boundaries.len();
            let index = index.min(count.saturating_sub(1));
            let mut data = Vec::new();
            let mut meta = serde_json::json!({ "regions": regions.names() });
            if let Some(b) = regions.boundaries.get(index) {
                for t in &b.triangles {
                    for p in t {
                        data.extend_from_slice(&[p.x as f32, p.y as f32, p.z as f32]);
                    }
                }
                meta = serde_json::json!({
                    "caption": format!("boundary {} of {count}: {} | {}, {:.1} mm² shared", index + 1, regions.regions[b.a].name, regions.regions[b.b].name, b.area_mm2),
                    "between": [regions.regions[b.a].name, regions.regions[b.b].name],
                    "area_mm2": b.area_mm2,
                    "legend": { "0": format!("{} | {}", regions.regions[b.a].name, regions.regions[b.b].name) },
                });
            }
            Ok(Inspection { view: view.into(), shape: Shape::Mesh, index, count, stride: Shape::Mesh.stride(), data, overlay: Vec::new(), meta })
        }
        "layer" => {
            let regions = regions_stage(j, ctx)?;
            let layers = slice_stage(j, ctx, &regions)?;
            let paths = raster_stage(j, ctx, &layers)?;
            let count = paths.len();
            let index = index.min(count.saturating_sub(1));
            let mut data = Vec::new();
            if let (Some(path), Some(layer)) = (paths.get(index), layers.get(index)) {
                for w in path.points.windows(2) {
                    data.extend_from_slice(&[w[0].x as f32, w[0].y as f32, w[1].x as f32, w[1].y as f32, Feature::Infill.code() as f32]);
                }
                for ring in std::iter::once(&layer.polygon.outer).chain(&layer.polygon.holes) {
                    for k in 0..ring.len() {
                        let (a, b) = (ring[k], ring[(k + 1) % ring.len()]);
                        data.extend_from_slice(&[a.x as f32, a.y as f32, b.x as f32, b.y as f32, Feature::ExternalPerimeter.code() as f32]);
                    }
                }
            }
            let z = layers.get(index).map_or(0.0, |l| l.z);
            let length: f64 = paths.get(index).map_or(0.0, |p| p.points.windows(2).map(|w| w[0].distance(w[1])).sum());
            let caption = format!("layer {} of {count} at z = {z:.2} mm: {length:.0} mm of continuous path", index + 1);
            let meta = serde_json::json!({ "z_mm": z, "caption": caption, "legend": { Feature::Infill.code().to_string(): "path", Feature::ExternalPerimeter.code().to_string(): "outline" } });
            Ok(Inspection { view: view.into(), shape: Shape::Lines2d, index, count, stride: Shape::Lines2d.stride(), data, overlay: Vec::new(), meta })
        }
        "v_star" | "h_star" => thread_view(j, ctx, view, index),
        _ => Err(Error::UnknownView { view: view.into(), job: FoamKind::NAME }),
    }
}

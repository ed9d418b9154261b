//! The lattice job's view: one layer's strokes and paths in the plane.

use super::*;

/// One of the kind's views at `index` (`Kind::inspect`).
pub(super) fn inspect(j: &LatticeJob, ctx: &mut Ctx, view: &str, index: usize) -> Result<Inspection, Error> {
    match view {
        "layer2d" => {}
        "graph" => return graph_view(j, ctx, index),
        "pairing" => return pairing_view(j, ctx, index),
        "gippo" => return gippo_view(j, ctx, index),
        "trails" => return trails_view(j, ctx, index),
        "order" => return order_view(j, ctx, index),
        "gcode" => return gcode_view(j, ctx, index),
        _ => return Err(Error::UnknownView { view: view.into(), job: LatticeKind::NAME }),
    }
    let strokes = strokes(j, ctx)?;
    let count = strokes.len();
    let index = index.min(count.saturating_sub(1));
    let mut data = Vec::new();
    if let Some(l) = strokes.get(index) {
        for s in &l.strokes {
            for w in s.points.windows(2) {
                data.extend_from_slice(&[w[0].x as f32, w[0].y as f32, w[1].x as f32, w[1].y as f32, s.feature.code() as f32]);
            }
        }
    }
    let z = strokes.get(index).map_or(0.0, |l| l.z);
    let struts: usize = strokes.get(index).map_or(0, |l| l.strokes.iter().map(|s| s.points.len().saturating_sub(1)).sum());
    let caption = format!("layer {} of {count} at z {z:.2} mm: {struts} strut segments", index + 1);
    Ok(Inspection {
        view: view.into(),
        shape: Shape::Lines2d,
        index,
        count,
        stride: Shape::Lines2d.stride(),
        data,
        overlay: Vec::new(),
        meta: serde_json::json!({ "z_mm": z, "caption": caption }),
    })
}

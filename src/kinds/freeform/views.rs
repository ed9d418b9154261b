//! The freeform job's view: the build in order, each step's beams printed, printing, cantilevered and still to print.

use super::*;

/// Feature codes the sequence view draws with (named by its legend).
pub(super) const PRINTED: Feature = Feature::Lattice;
pub(super) const CURRENT: Feature = Feature::ExternalPerimeter;
pub(super) const CANTILEVER: Feature = Feature::Infill;
pub(super) const TODO: Feature = Feature::Handle;

/// One of the kind's views at `index` (`Kind::inspect`).
pub(super) fn inspect(j: &FreeformJob, ctx: &mut Ctx, view: &str, index: usize) -> Result<Inspection, Error> {
    match view {
        "sequence" => {
            let w = import_stage(j, ctx)?;
            let c = constraints_stage(j, ctx, &w)?;
            let p = chosen_plan(j, ctx, &w, &c)?;
            let o = order_stage(j, ctx, &w, &c, &p)?;
            Ok(sequence_view(&w, &o, &c, index))
        }
        _ => Err(Error::UnknownView { view: view.into(), job: FreeformKind::NAME }),
    }
}

/// The wireframe after step `index`: printed beams, the current one, the cantilevered ones
/// (a printed beam with a joint not yet held by two disjoint paths to the ground), the rest.
pub(super) fn sequence_view(w: &Placed, o: &Ordered, c: &Constraints, index: usize) -> Inspection {
    let count = o.steps.len();
    let index = index.min(count.saturating_sub(1));
    let mut present = vec![false; w.beams.len()];
    for s in o.steps.iter().take(index + 1) {
        present[s.beam] = true;
    }
    let mut inc: Vec<Vec<usize>> = vec![Vec::new(); w.joints.len()];
    for (b, &[p, q]) in w.beams.iter().enumerate() {
        inc[p].push(b);
        inc[q].push(b);
    }
    let stable = plan::stable_joints(&w.joints, &w.beams, &w.grounded, &inc, &present);
    let current = o.steps.get(index).map(|s| s.beam);
    let mut data = Vec::with_capacity(w.beams.len() * 7);
    let mut cantilevered = 0usize;
    for (b, &[p, q]) in w.beams.iter().enumerate() {
        let f = if Some(b) == current {
            CURRENT
        } else if !present[b] {
            TODO
        } else if !(stable[p] && stable[q]) {
            cantilevered += 1;
            CANTILEVER
        } else {
            PRINTED
        };
        let (a, c) = (w.joints[p], w.joints[q]);
        data.extend_from_slice(&[a.x as f32, a.y as f32, a.z as f32, c.x as f32, c.y as f32, c.z as f32, f.code() as f32]);
    }
    let step = o.steps.get(index);
    let tilt = |b: usize| c.axis.get(b).map_or(0.0, |t| libm::acos(t.z.clamp(-1.0, 1.0)).to_degrees());
    let caption = step
        .map(|s| {
            let t = tilt(s.beam);
            let tilted = if t > 1e-9 { format!(", nozzle tilted {t:.0}°") } else { String::new() };
            format!(
                "{} from {} to {}, ε {:.3} µm{tilted}",
                names(w, &[s.beam]),
                w.joint_names.get(s.from).map_or("", String::as_str),
                w.joint_names.get(s.to).map_or("", String::as_str),
                s.cost_mm * 1000.0
            )
        })
        .unwrap_or_default();
    let meta = serde_json::json!({
        "caption": caption,
        "play": true,
        "cantilevered": cantilevered,
        "legend": {
            PRINTED.code().to_string(): "printed",
            CURRENT.code().to_string(): "printing now",
            CANTILEVER.code().to_string(): "cantilevered",
            TODO.code().to_string(): "still to print",
        },
    });
    Inspection { view: "sequence".into(), shape: Shape::Lines3d, index, count, stride: Shape::Lines3d.stride(), data, overlay: Vec::new(), meta }
}

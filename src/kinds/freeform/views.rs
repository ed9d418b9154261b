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
        "beams" => {
            let w = import_stage(j, ctx)?;
            Ok(beams_view(&w, j.beam.diameter_mm))
        }
        "precedence" => {
            let w = import_stage(j, ctx)?;
            let c = constraints_stage(j, ctx, &w)?;
            let p = chosen_plan(j, ctx, &w, &c)?;
            Ok(precedence_view(&w, &c, &p, j.beam.diameter_mm))
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
                "step {} of {count}: {} from {} to {}, ε {:.3} µm (its end joint's deflection){tilted}",
                index + 1,
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

/// Feature codes of the beams and precedence views (named by their legends).
pub(super) const BEAM: Feature = Feature::Beam;
pub(super) const STANDING: Feature = Feature::Contour;
pub(super) const GROUND: Feature = Feature::ExternalPerimeter;
pub(super) const COLLISION: Feature = Feature::Infill;
pub(super) const PATH: Feature = Feature::Lattice;

fn seg3(data: &mut Vec<f32>, a: DVec3, b: DVec3, f: Feature) {
    data.extend_from_slice(&[a.x as f32, a.y as f32, a.z as f32, b.x as f32, b.y as f32, b.z as f32, f.code() as f32]);
}

/// The wireframe: beams, beams standing on the substrate, grounded joints marked by a cross.
pub(super) fn beams_view(w: &Placed, diameter_mm: f64) -> Inspection {
    let mut data = Vec::with_capacity(7 * (w.beams.len() + 2 * w.joints.len()));
    let grounded = |j: usize| w.grounded.get(j).copied().unwrap_or(false);
    let mut standing = 0usize;
    for &[p, q] in &w.beams {
        let f = if grounded(p) || grounded(q) {
            standing += 1;
            STANDING
        } else {
            BEAM
        };
        seg3(&mut data, w.joints[p], w.joints[q], f);
    }
    let r = diameter_mm.max(0.1);
    let mut ground = 0usize;
    for (j, &p) in w.joints.iter().enumerate() {
        if grounded(j) {
            ground += 1;
            seg3(&mut data, p - DVec3::new(r, r, 0.0), p + DVec3::new(r, r, 0.0), GROUND);
            seg3(&mut data, p - DVec3::new(r, -r, 0.0), p + DVec3::new(r, -r, 0.0), GROUND);
        }
    }
    let length: f64 = (0..w.beams.len()).map(|b| w.length(b)).sum();
    let height = bounds(&w.joints).map_or(0.0, |(lo, hi)| hi.z - lo.z);
    let caption = format!(
        "{} beams between {} joints, {ground} grounded, {standing} beams standing on the substrate; {length:.1} mm of beam, {height:.1} mm tall",
        w.beams.len(),
        w.joints.len()
    );
    let meta = serde_json::json!({
        "caption": caption,
        "beams": w.beams.len(),
        "joints": w.joints.len(),
        "grounded": ground,
        "legend": {
            BEAM.code().to_string(): "beam",
            STANDING.code().to_string(): "beam standing on the substrate",
            GROUND.code().to_string(): "grounded joint",
        },
    });
    Inspection { view: "beams".into(), shape: Shape::Lines3d, index: 0, count: 1, stride: Shape::Lines3d.stride(), data, overlay: Vec::new(), meta }
}

/// The precedences a plan's order keeps: collision pairs (the nozzle printing A sweeps
/// through B: A first) and each path's beam before the next one from its root, each an arrow
/// from the middle of the earlier beam to the middle of the later one, over the beams.
pub(super) fn precedence_view(w: &Placed, c: &Constraints, p: &Plan, diameter_mm: f64) -> Inspection {
    let mid = |b: usize| (w.joints[w.beams[b][0]] + w.joints[w.beams[b][1]]) / 2.0;
    let mut data = Vec::new();
    for &[a, b] in &w.beams {
        seg3(&mut data, w.joints[a], w.joints[b], TODO);
    }
    let arrow = |data: &mut Vec<f32>, from: usize, to: usize, f: Feature| {
        let (a, b) = (mid(from), mid(to));
        seg3(data, a, b, f);
        let d = b - a;
        let len = d.length();
        if len <= 0.0 || !len.is_finite() {
            return;
        }
        let dir = d / len;
        let side = if dir.cross(DVec3::Z).length() > 1e-6 { dir.cross(DVec3::Z).normalize() } else { dir.cross(DVec3::X).normalize() };
        let head = (0.2 * len).min(2.0 * diameter_mm.max(0.1));
        let base = b - dir * head;
        seg3(data, b, base + side * (0.5 * head), f);
        seg3(data, b, base - side * (0.5 * head), f);
    };
    let m = w.beams.len();
    let mut collision = 0usize;
    for a in 0..m.min(c.succ_start.len().saturating_sub(1)) {
        for &b in c.succs(a) {
            if (b as usize) < m {
                arrow(&mut data, a, b as usize, COLLISION);
                collision += 1;
            }
        }
    }
    let mut path = 0usize;
    for blk in &p.blocks {
        for (i, &before) in blk.chain.iter().enumerate() {
            let (Some(s), Some(t)) = (p.steps.get(before), p.steps.get(blk.start + i)) else { continue };
            arrow(&mut data, s.beam, t.beam, PATH);
            path += 1;
        }
    }
    let length: f64 = (0..m).map(|b| w.length(b)).sum();
    let caption =
        format!("{m} beams, {length:.1} mm: {collision} collision precedences (the nozzle would hit the later beam), {path} along paths from their roots");
    let meta = serde_json::json!({
        "caption": caption,
        "beams": m,
        "collision": collision,
        "path": path,
        "legend": {
            TODO.code().to_string(): "beam",
            COLLISION.code().to_string(): "collision: printed before (arrow to the later beam)",
            PATH.code().to_string(): "path from its root: printed before (arrow to the later beam)",
        },
    });
    Inspection { view: "precedence".into(), shape: Shape::Lines3d, index: 0, count: 1, stride: Shape::Lines3d.stride(), data, overlay: Vec::new(), meta }
}

//! Deadheading (section III, end): the plan fixes which beams may come before which (each
//! subassembly after the components it joins, each path from its root, the collision
//! precedences); within that, the beams are ordered greedily by deadhead time (or kept in the
//! plan's order when that is shorter). A deadhead lifts
//! the nozzle above the highest printed beam, moves across, and lowers onto the next start
//! joint, each axis at its top speed (no acceleration), as the paper times it.

use super::plan::{Plan, Step};
use super::precedence::Constraints;
use glam::DVec3;

/// Default clearance above the highest printed beam's top while deadheading, mm.
pub const DEFAULT_CLEARANCE_MM: f64 = 1.0;

/// How deadheads are timed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Options {
    /// Horizontal speed, mm/s.
    pub xy_mm_s: f64,
    /// Vertical speed, mm/s.
    pub z_mm_s: f64,
    /// Clearance of the nozzle tip over the highest printed beam's top, mm.
    pub clearance_mm: f64,
    /// Beam radius, mm (the top of a beam is its axis plus this).
    pub beam_radius_mm: f64,
}

/// The order of a plan's steps.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct Ordered {
    /// Steps of the plan, in print order.
    pub steps: Vec<Step>,
    /// Safe height (tip) of the deadhead before each step, mm (NaN before the first).
    pub safe_z: Vec<f64>,
    /// Deadhead time of this order, s.
    pub deadhead_s: f64,
    /// Deadhead time of the plan's own order, s.
    pub plan_order_deadhead_s: f64,
}

/// Time of one deadhead from `a` to `b` under the safe height `z`.
pub fn deadhead_time(a: DVec3, b: DVec3, z: f64, o: &Options) -> f64 {
    let up = (z - a.z).max(0.0);
    let down = (z - b.z).max(0.0);
    let across = (b.truncate() - a.truncate()).length();
    (up + down) / o.z_mm_s + across / o.xy_mm_s
}

/// Deadhead time of `steps` in their order.
pub fn total(joints: &[DVec3], steps: &[Step], o: &Options) -> f64 {
    let z = safe_heights(joints, steps, o);
    (1..steps.len()).map(|i| deadhead_time(joints[steps[i - 1].to], joints[steps[i].from], z[i], o)).sum()
}

/// The safe height of the deadhead before each step of `steps` (NaN before the first).
fn safe_heights(joints: &[DVec3], steps: &[Step], o: &Options) -> Vec<f64> {
    let mut top = f64::NEG_INFINITY;
    steps
        .iter()
        .map(|s| {
            let z = if top.is_finite() { top + o.beam_radius_mm + o.clearance_mm } else { f64::NAN };
            top = top.max(joints[s.from].z).max(joints[s.to].z);
            z
        })
        .collect()
}

/// Orders `plan` greedily by deadhead time within its constraints. Steps sent ahead
/// ([`Plan::sent`]) come first, in the order this gives them alone (what was sent).
pub fn order(joints: &[DVec3], plan: &Plan, constraints: &Constraints, o: &Options) -> Ordered {
    let n = plan.steps.len();
    if n == 0 {
        return Ordered::default();
    }
    let head: Vec<usize> = if plan.sent > 0 && plan.sent < n {
        let sent = order(joints, &plan.prefix(plan.sent), constraints, o);
        let mut step_of_beam = vec![usize::MAX; constraints.forward.len()];
        for (i, s) in plan.steps[..plan.sent].iter().enumerate() {
            step_of_beam[s.beam] = i;
        }
        sent.steps.iter().map(|s| step_of_beam[s.beam]).collect()
    } else {
        Vec::new()
    };
    let greedy = greedy(joints, plan, constraints, o, &head);
    // A greedy can lose to the plan's own order (after what was sent): keep the better.
    let mut plan_order: Vec<Step> = head.iter().map(|&i| plan.steps[i]).collect();
    plan_order.extend_from_slice(&plan.steps[head.len()..]);
    let alternative = total(joints, &plan_order, o);
    let plan_order_deadhead_s = if head.is_empty() { alternative } else { total(joints, &plan.steps, o) };
    if alternative < greedy.deadhead_s {
        let safe_z = safe_heights(joints, &plan_order, o);
        return Ordered { steps: plan_order, safe_z, deadhead_s: alternative, plan_order_deadhead_s };
    }
    Ordered { plan_order_deadhead_s, ..greedy }
}

/// The greedy order of `plan`, its first steps `head` (step indices) as given.
fn greedy(joints: &[DVec3], plan: &Plan, constraints: &Constraints, o: &Options, head: &[usize]) -> Ordered {
    let n = plan.steps.len();
    let nb = plan.blocks.len();
    // Step → block and position; waiting counts: blocks before, chain step before, collision
    // predecessors (by beam).
    let mut block_of = vec![0usize; n];
    let mut chain_prev = vec![usize::MAX; n];
    for (b, blk) in plan.blocks.iter().enumerate() {
        for i in blk.start..blk.end {
            block_of[i] = b;
            chain_prev[i] = blk.chain[i - blk.start];
        }
    }
    let mut step_of_beam = vec![usize::MAX; constraints.forward.len()];
    for (i, s) in plan.steps.iter().enumerate() {
        step_of_beam[s.beam] = i;
    }
    let mut block_left: Vec<usize> = plan.blocks.iter().map(|b| b.end - b.start).collect();
    let mut blocks_waiting: Vec<usize> = plan.blocks.iter().map(|b| b.after.len()).collect();
    let mut followers: Vec<Vec<usize>> = vec![Vec::new(); nb];
    for (b, blk) in plan.blocks.iter().enumerate() {
        for &a in &blk.after {
            followers[a].push(b);
        }
    }
    let mut waiting = vec![0usize; n];
    let mut chain_next: Vec<Vec<usize>> = vec![Vec::new(); n];
    for i in 0..n {
        if chain_prev[i] != usize::MAX {
            waiting[i] += 1;
            chain_next[chain_prev[i]].push(i);
        }
        waiting[i] += constraints.preds(plan.steps[i].beam).iter().filter(|&&p| step_of_beam[p as usize] != usize::MAX).count();
    }
    // Bands (a plan made band by band): a band's steps wait for every step of the bands before.
    // (bands[k] is band k's first step: a step's band is the last start at or before it.)
    let band_of: Vec<usize> = (0..n).map(|i| plan.bands.partition_point(|&s| s <= i).saturating_sub(1)).collect();
    let bands = band_of.last().map_or(1, |&k| k + 1);
    let mut band_left = vec![0usize; bands];
    for &k in &band_of {
        band_left[k] += 1;
    }
    let mut current = 0usize;
    let mut done = vec![false; n];
    let mut available: Vec<usize> = Vec::new();
    let is_ready =
        |i: usize, waiting: &[usize], blocks_waiting: &[usize], current: usize| waiting[i] == 0 && blocks_waiting[block_of[i]] == 0 && band_of[i] == current;
    for i in 0..n {
        if is_ready(i, &waiting, &blocks_waiting, current) {
            available.push(i);
        }
    }
    let mut out = Vec::with_capacity(n);
    let mut safe_z = Vec::with_capacity(n);
    let mut top = f64::NEG_INFINITY;
    let mut at: Option<DVec3> = None;
    let mut time = 0.0;
    while out.len() < n {
        // The cheapest available step (ties: the plan's order); the first: the plan's first.
        let pick = match at {
            _ if out.len() < head.len() => Some(head[out.len()]).filter(|i| available.contains(i)),
            None => available.iter().copied().min(),
            Some(a) => {
                let z = top + o.beam_radius_mm + o.clearance_mm;
                available.iter().copied().min_by(|&x, &y| {
                    let tx = deadhead_time(a, joints[plan.steps[x].from], z, o);
                    let ty = deadhead_time(a, joints[plan.steps[y].from], z, o);
                    tx.total_cmp(&ty).then(x.cmp(&y))
                })
            }
        };
        let Some(i) = pick else { break }; // cannot happen: the plan's order is one linear extension
        available.retain(|&x| x != i);
        let s = plan.steps[i];
        let z = top + o.beam_radius_mm + o.clearance_mm;
        match at {
            Some(a) => {
                time += deadhead_time(a, joints[s.from], z, o);
                safe_z.push(z);
            }
            None => safe_z.push(f64::NAN),
        }
        top = top.max(joints[s.from].z).max(joints[s.to].z);
        at = Some(joints[s.to]);
        out.push(s);
        done[i] = true;
        // Release what waited on it.
        let mut fresh: Vec<usize> = Vec::new();
        for &c in &chain_next[i] {
            waiting[c] -= 1;
            fresh.push(c);
        }
        for &succ in constraints.succs(s.beam) {
            let j = step_of_beam[succ as usize];
            if j != usize::MAX {
                waiting[j] -= 1;
                fresh.push(j);
            }
        }
        band_left[band_of[i]] -= 1;
        if band_left[current] == 0 && current + 1 < bands {
            current += 1;
            let start = plan.bands[current];
            let end = plan.bands.get(current + 1).copied().unwrap_or(n);
            fresh.extend(start..end);
        }
        let b = block_of[i];
        block_left[b] -= 1;
        if block_left[b] == 0 {
            for &f in &followers[b] {
                blocks_waiting[f] -= 1;
                if blocks_waiting[f] == 0 {
                    fresh.extend(plan.blocks[f].start..plan.blocks[f].end);
                }
            }
        }
        for c in fresh {
            if !done[c] && is_ready(c, &waiting, &blocks_waiting, current) && !available.contains(&c) {
                available.push(c);
            }
        }
    }
    Ordered { steps: out, safe_z, deadhead_s: time, plan_order_deadhead_s: 0.0 }
}

/// The deadheads of an order that lift or lower the nozzle through a printed beam: the body
/// (radius `nozzle_radius_mm`, `body_top_mm` from the tip to its top) rising from the last
/// beam's end joint to the safe height, or lowered from it onto the next start joint, sweeps
/// the column above that joint. What lies within the body at the joint itself is a collision
/// precedence already (the beam's own sweep); beams higher up the column are not, and a tall
/// design can leave one there. Returns the steps whose deadhead does, ascending. Only a
/// vertical nozzle is checked: a deadhead next to a beam printed tilted (`axis` per beam, +Z
/// when upright) is skipped, and counted in the second number returned.
pub fn blocked(
    joints: &[DVec3],
    beams: &[[usize; 2]],
    axis: &[DVec3],
    ordered: &Ordered,
    nozzle_radius_mm: f64,
    body_top_mm: f64,
    beam_radius_mm: f64,
) -> (Vec<usize>, usize) {
    use parry3d_f64::bounding_volume::Aabb;
    use parry3d_f64::math::Vector;
    use parry3d_f64::partitioning::{Bvh, BvhBuildStrategy};
    let steps = &ordered.steps;
    let n = steps.len();
    if n < 2 {
        return (Vec::new(), 0);
    }
    let upright = |b: usize| axis.get(b).is_none_or(|&t| t == DVec3::Z);
    let mut skipped = 0;
    let r = beam_radius_mm;
    let v = |p: DVec3| Vector::new(p.x, p.y, p.z);
    // The steps' beams as boxes, indexed by their place in the order.
    let boxes: Vec<Aabb> = steps
        .iter()
        .map(|s| {
            let [p, q] = beams[s.beam];
            let (a, b) = (joints[p], joints[q]);
            Aabb::new(v(a.min(b) - DVec3::splat(r)), v(a.max(b) + DVec3::splat(r)))
        })
        .collect();
    let bvh = Bvh::from_leaves(BvhBuildStrategy::Binned, &boxes);
    let reach = nozzle_radius_mm + r;
    // Whether beam (order index) k, printed before step i, lies in the column over `at` from
    // `lo` to `hi`.
    let in_column = |k: usize, at: DVec3, lo: f64, hi: f64| -> bool {
        let [p, q] = beams[steps[k].beam];
        let (a, b) = (joints[p], joints[q]);
        // The part of the beam within the column's heights (its radius added).
        let (za, zb) = (lo - r, hi + r);
        let d = b - a;
        let (mut t0, mut t1) = (0.0f64, 1.0f64);
        if d.z.abs() < 1e-12 {
            if a.z < za || a.z > zb {
                return false;
            }
        } else {
            let (s0, s1) = ((za - a.z) / d.z, (zb - a.z) / d.z);
            t0 = t0.max(s0.min(s1));
            t1 = t1.min(s0.max(s1));
            if t0 > t1 {
                return false;
            }
        }
        let (c0, c1) = ((a + d * t0).truncate(), (a + d * t1).truncate());
        let x = at.truncate();
        let e = c1 - c0;
        let l = e.length_squared();
        let t = if l > 0.0 { ((x - c0).dot(e) / l).clamp(0.0, 1.0) } else { 0.0 };
        (c0 + e * t).distance_squared(x) < reach * reach
    };
    let mut out = Vec::new();
    for i in 1..n {
        let safe = ordered.safe_z[i];
        if !safe.is_finite() {
            continue;
        }
        if !(upright(steps[i - 1].beam) && upright(steps[i].beam)) {
            skipped += 1;
            continue;
        }
        let mut hit = false;
        for at in [joints[steps[i - 1].to], joints[steps[i].from]] {
            // Above the body's reach at the joint, up to the safe height.
            let (lo, hi) = (at.z + body_top_mm, safe);
            if lo >= hi {
                continue;
            }
            let query = Aabb::new(v(DVec3::new(at.x - reach, at.y - reach, lo - r)), v(DVec3::new(at.x + reach, at.y + reach, hi + r)));
            if bvh.intersect_aabb(&query).any(|k| (k as usize) < i && in_column(k as usize, at, lo, hi)) {
                hit = true;
                break;
            }
        }
        if hit {
            out.push(i);
        }
    }
    (out, skipped)
}

//! Planning a design too big to plan as a whole (beyond the paper): cut it into bands of
//! about `band_beams` beams by height, plan each band with the planner while every band below
//! stands printed and rigid, and join the band plans in order. The exact cost of a band sees
//! its own frame only (the bands below clamped at the joints they share), so the plan is cheap
//! where the whole frame's compliance would be wide and slow; what that costs is measured by
//! replaying the joined sequence with the whole frame ([`super::cost`]): the *cost of the
//! joins*, the ε the clamped bands did not see.
//!
//! A beam's band is set by its higher joint (the beams that reach a level come with it, so a
//! cut leaves no beam hanging off a band's top), levels are never split, and a beam that must
//! follow another (a collision precedence) is moved up to the other's band when it would come
//! earlier. A band starts only where the bands below end clean (every printed beam between
//! stable joints, or a cantilever of the finished design with nothing more at its joints): its
//! plan holds the joints below rigid and knows nothing of what hangs there. A band that cannot
//! start so, or whose plan fails, is merged with the band before it and the two are planned
//! again; a design that fails as one band fails as the whole design would.

use super::plan::{self, stable_joints, Assembly, Block, Plan, Unconstructable};
use super::precedence::Constraints;
use glam::DVec3;

/// Default beams a band: 0 plans the design whole.
pub const DEFAULT_BAND_BEAMS: usize = 0;

/// The bands of a design: each beam's band, bands numbered from the bottom.
pub fn assign(joints: &[DVec3], beams: &[[usize; 2]], c: &Constraints, band_beams: usize) -> Vec<usize> {
    let m = beams.len();
    if band_beams == 0 || m <= band_beams {
        return vec![0; m];
    }
    let top = |b: usize| joints[beams[b][0]].z.max(joints[beams[b][1]].z);
    let mut by_height: Vec<usize> = (0..m).collect();
    by_height.sort_by(|&a, &b| top(a).total_cmp(&top(b)).then(a.cmp(&b)));
    let mut band = vec![0usize; m];
    let (mut k, mut count) = (0usize, 0usize);
    let mut last = f64::NEG_INFINITY;
    for &b in &by_height {
        let z = top(b);
        if count >= band_beams && z > last {
            k += 1;
            count = 0;
        }
        band[b] = k;
        count += 1;
        last = z;
    }
    // Precedences: a beam comes no earlier than any beam it must follow (Kahn's order over
    // the precedence graph, acyclic when the design can be printed at all; a cycle leaves its
    // beams where they are, and the planner proves the cycle).
    let mut waiting: Vec<usize> = (0..m).map(|b| c.preds(b).len()).collect();
    let mut ready: Vec<usize> = (0..m).filter(|&b| waiting[b] == 0).collect();
    while let Some(a) = ready.pop() {
        for &s in c.succs(a) {
            let s = s as usize;
            band[s] = band[s].max(band[a]);
            waiting[s] -= 1;
            if waiting[s] == 0 {
                ready.push(s);
            }
        }
    }
    // Number the bands left without gaps.
    let mut used: Vec<usize> = band.clone();
    used.sort_unstable();
    used.dedup();
    band.iter().map(|b| used.binary_search(b).unwrap_or(0)).collect()
}

/// One band's share of a plan.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct Band {
    /// First step of the band in the plan.
    pub start: usize,
    /// Beams.
    pub beams: usize,
    /// Joints of the bands below it clamped for its plan.
    pub clamped: usize,
    /// Largest ε planned in the band (its own frame, the bands below rigid), mm.
    pub planned_mm: f64,
}

/// Plans `d` band by band (see the module's text). `progress(done, all)` counts beams.
pub fn plan(d: &Assembly, o: &plan::Options, band_of: &[usize], progress: &mut dyn FnMut(usize, usize)) -> Result<(Plan, Vec<Band>), Unconstructable> {
    let m = d.beams.len();
    let bands = band_of.iter().copied().max().map_or(0, |k| k + 1);
    if bands <= 1 {
        let p = plan::plan(d, o, progress)?;
        let planned = p.steps.iter().map(|s| s.cost_mm).fold(0.0, f64::max);
        return Ok((p, vec![Band { start: 0, beams: m, clamped: 0, planned_mm: planned }]));
    }
    // What can be proved of the whole design is proved first (a band's own proofs see less).
    plan::prove(d, o.mode, o.connection)?;
    let mut members: Vec<Vec<usize>> = vec![Vec::new(); bands];
    for (b, &k) in band_of.iter().enumerate() {
        members[k].push(b);
    }
    let mut inc: Vec<Vec<usize>> = vec![Vec::new(); d.joints.len()];
    for (b, &[p, q]) in d.beams.iter().enumerate() {
        inc[p].push(b);
        inc[q].push(b);
    }
    // Plans, one per band kept so far; a failed band is merged into the one before it.
    let mut done: Vec<(Vec<usize>, Plan, Band)> = Vec::new();
    let mut printed = vec![false; m];
    let mut k = 0;
    let mut pending: Vec<usize> = Vec::new();
    let mut spent = 0.0;
    while k < bands || !pending.is_empty() {
        if pending.is_empty() {
            pending = std::mem::take(&mut members[k]);
            k += 1;
        }
        let base: usize = done.iter().map(|(b, _, _)| b.len()).sum();
        let budget = (o.budget_s - spent).max(0.0);
        match plan_band(d, o, &inc, &printed, &pending, budget, &mut |i, _| progress(base + i, m)) {
            Ok((p, clamped)) => {
                for &b in &pending {
                    printed[b] = true;
                }
                spent += p.work / plan::WORK_PER_SECOND;
                let planned = p.steps.iter().map(|s| s.cost_mm).fold(0.0, f64::max);
                let band = Band { start: base, beams: pending.len(), clamped, planned_mm: planned };
                done.push((std::mem::take(&mut pending), p, band));
            }
            Err(e) => {
                // Merged with the band below (planned again), or, at the bottom, with the next.
                if let Some((below, _, _)) = done.pop() {
                    for &b in &below {
                        printed[b] = false;
                    }
                    let mut merged = below;
                    merged.append(&mut pending);
                    merged.sort_unstable();
                    pending = merged;
                } else if k < bands {
                    pending.append(&mut members[k]);
                    pending.sort_unstable();
                    k += 1;
                } else {
                    return Err(e);
                }
            }
        }
    }
    // Joined: steps and blocks in band order, indices made global.
    let mut out = Plan::default();
    let mut list = Vec::with_capacity(done.len());
    for (_, p, band) in done {
        let (s0, b0) = (out.steps.len(), out.blocks.len());
        out.steps.extend(p.steps.iter().map(|s| plan::Step { block: s.block + b0, ..*s }));
        out.blocks.extend(p.blocks.iter().map(|b| Block {
            start: b.start + s0,
            end: b.end + s0,
            after: b.after.iter().map(|a| a + b0).collect(),
            chain: b.chain.iter().map(|&c| if c == usize::MAX { c } else { c + s0 }).collect(),
            key_mm: b.key_mm,
        }));
        out.expansions += p.expansions;
        out.work += p.work;
        if out.exact_until.is_none() {
            out.exact_until = p.exact_until.map(|e| e + s0);
        }
        out.peak_live = out.peak_live.max(p.peak_live);
        out.refreshes += p.refreshes;
        out.drift = out.drift.max(p.drift);
        out.bands.push(s0);
        list.push(band);
    }
    Ok((out, list))
}

/// Plans the beams `beams` (global indices) with every `printed` beam standing: the joints
/// they leave stable are clamped (grounded for this plan). Returns the plan in global indices
/// and the number of joints clamped.
fn plan_band(
    d: &Assembly,
    o: &plan::Options,
    inc: &[Vec<usize>],
    printed: &[bool],
    beams: &[usize],
    budget_s: f64,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<(Plan, usize), Unconstructable> {
    let stable = stable_joints(d.joints, d.beams, d.grounded, inc, printed);
    // The bands below must end clean: no printed beam hangs (a joint not yet stable) where a
    // beam is still to come, or this band's plan, which sees those joints clamped, would heat
    // a joint with a cantilever about it or hold a loose tip rigid. Otherwise: merged.
    let open = |j: usize| inc[j].iter().any(|&b| !printed[b]);
    for (b, &[p, q]) in d.beams.iter().enumerate() {
        if printed[b] && !(stable[p] && stable[q]) && (open(p) || open(q)) {
            return Err(Unconstructable::NoSubassembly { printed: printed.iter().filter(|&&x| x).count(), beams: vec![b], count: 1 });
        }
    }
    // Local joints: those the band's beams touch, ascending.
    let mut joints: Vec<usize> = beams.iter().flat_map(|&b| d.beams[b]).collect();
    joints.sort_unstable();
    joints.dedup();
    let local = |j: usize| joints.binary_search(&j).unwrap_or(0);
    let lj: Vec<DVec3> = joints.iter().map(|&j| d.joints[j]).collect();
    let lb: Vec<[usize; 2]> = beams.iter().map(|&b| [local(d.beams[b][0]), local(d.beams[b][1])]).collect();
    let lg: Vec<bool> = joints.iter().map(|&j| d.grounded[j] || stable[j]).collect();
    let clamped = joints.iter().filter(|&&j| !d.grounded[j] && stable[j]).count();
    let lc = d.constraints.restricted(beams);
    let a = Assembly { joints: &lj, beams: &lb, grounded: &lg, constraints: &lc };
    let p = plan::plan(&a, &plan::Options { budget_s, ..*o }, progress)?;
    let steps = p.steps.iter().map(|s| plan::Step { beam: beams[s.beam], from: joints[s.from], to: joints[s.to], ..*s }).collect();
    Ok((Plan { steps, ..p }, clamped))
}

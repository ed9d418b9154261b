//! The freeform job's plan stages: the planner's sequence (whole, or in bands), the exact search for the least largest ε, and the words that explain a frame that cannot be printed.

use super::*;

pub(super) fn plan_options(j: &FreeformJob) -> plan::Options {
    plan::Options {
        mode: j.constraints.cantilever,
        cost: j.planner.cost,
        connection: j.constraints.connection,
        section: section(j),
        load_n: j.beam.load_n,
        budget_s: j.planner.budget_s,
    }
}

pub(super) fn section(j: &FreeformJob) -> Section {
    Section { diameter_mm: j.beam.diameter_mm, e_mpa: j.beam.e_mpa, g_mpa: j.beam.g_mpa }
}

/// A design that cannot be printed, in words (beams and joints named as the file names them).
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub(super) struct CannotPrint(String);

pub(super) fn names(w: &Wireframe, beams: &[usize]) -> String {
    beams.iter().map(|&b| w.beam_names.get(b).cloned().unwrap_or_else(|| format!("beam {b}"))).collect::<Vec<_>>().join(", ")
}

/// The reason a design cannot be printed, in words, with the grounding it holds for (a
/// refusal is only as true as the footing it assumed).
pub fn explain(w: &Wireframe, u: &Unconstructable, mode: Mode) -> String {
    let why = explain_only(w, u, mode);
    match &w.grounding {
        Some(g) => match g.warning() {
            Some(warn) => format!("{why} (with {}; {warn})", g.statement()),
            None => format!("{why} (with {})", g.statement()),
        },
        None => why,
    }
}

pub(super) fn explain_only(w: &Wireframe, u: &Unconstructable, mode: Mode) -> String {
    let joint = |j: usize| w.joint_names.get(j).cloned().unwrap_or_else(|| format!("joint {j}"));
    match u {
        Unconstructable::Cycle { beams } => format!(
            "cannot be printed in this orientation: {} must each be printed before the next (the nozzle printing one sweeps through the next), and the last before the first; tilt or re-orient the design, or narrow the nozzle",
            names(w, beams)
        ),
        Unconstructable::TwoCantilevers { joint: jt, beams } => format!(
            "cannot be printed with one cantilever per joint: the finished design hangs two cantilevers ({}) on {}; relax the cantilever constraint, or join them to the rest",
            names(w, beams),
            joint(*jt)
        ),
        Unconstructable::HangsDown { beam, joint: jt } => format!(
            "cannot be printed: {} hangs down from {} steeper than the nozzle's cone, so it can only be printed upward from its free end, which touches nothing; support it, or re-orient the design",
            names(w, &[*beam]),
            joint(*jt)
        ),
        Unconstructable::Unreachable { beams, count } => format!(
            "cannot be printed: {count} beam(s) can never start from a printed joint in an allowed direction, or wait on such beams ({}{}); check the grounded joints and the nozzle",
            names(w, beams),
            if *count > beams.len() { ", …" } else { "" }
        ),
        Unconstructable::NoSubassembly { printed, beams, count } => format!(
            "the planner found no consistent subassembly after {printed} beams{}: {count} beam(s) left ({}{}); deciding this is NP-complete under the cantilever constraint and the search here joins at most two paths: relax the cantilever constraint, or add a beam that closes these loops",
            if mode == Mode::Strict { " with one cantilever per joint" } else { "" },
            names(w, beams),
            if *count > beams.len() { ", …" } else { "" }
        ),
        Unconstructable::SearchTooLarge { printed, beams, count } => format!(
            "the search for the next subassembly after {printed} beams needed more than {} steps: {count} beam(s) left ({}{}); relax the cantilever constraint or plan with the heuristic cost",
            plan::MAX_ROUND_EXPANSIONS,
            names(w, beams),
            if *count > beams.len() { ", …" } else { "" }
        ),
    }
}

/// Whether the exact search runs on a design of `beams` beams.
pub(super) fn exact_runs(j: &FreeformJob, beams: usize) -> bool {
    j.planner.exact_search != ExactSearch::Off && j.constraints.connection && beams <= j.planner.exact_beams.min(optimal::MAX_BEAMS)
}

/// The plan printed: the planner's, or the exact search's (see [`ExactSearch`]).
pub(super) fn chosen_plan(j: &FreeformJob, ctx: &mut Ctx, w: &Out<Placed>, c: &Out<Constraints>) -> Result<Out<Plan>, Error> {
    let p = plan_stage(j, ctx, w, c)?;
    optimum_stage(j, ctx, w, c, &p)
}

/// The planner's plan, or (on a design the exact search takes) why it found none.
pub(super) type Planned = Result<Plan, Unconstructable>;

pub(super) fn plan_stage(j: &FreeformJob, ctx: &mut Ctx, w: &Out<Placed>, c: &Out<Constraints>) -> Result<Out<Planned>, Error> {
    let o = plan_options(j);
    let searched = exact_runs(j, w.beams.len());
    let parts = (j.constraints, j.planner.cost, j.planner.budget_s, j.beam, searched, j.planner.band_beams);
    // A plan made whole only adds to its beginning, so that can be sent ahead; a band may be
    // planned again with the one above it (below: no sending), and the exact search may print
    // another order.
    let send_at = if searched { 0 } else { j.planner.send_ahead_beams };
    let dead = deadhead_options(j, ctx.design);
    let sender = ctx.sender();
    let parts = (parts, send_at);
    // The beams fixed, ordered as the order stage orders them alone (it keeps them first).
    let m = w.beams.len();
    let send = |fixed: &Plan| {
        let ordered = deadhead::order(&w.joints, fixed, c, &dead);
        let label = format!("the first {} of {} beams", fixed.steps.len(), m);
        sender.send("plan", &label, fixed.steps.len(), m, &toolpath(j, w, &ordered, c));
    };
    let sent = std::cell::Cell::new(false);
    let out = ctx.stage("plan", "plan", &parts, &[w.key, c.key], |progress| {
        let a = Assembly { joints: &w.joints, beams: &w.beams, grounded: &w.grounded, constraints: c };
        let started = crate::clock::now_s();
        // A forward planner fixes the sequence's beginning first: printing could start when the
        // first subassembly is fixed. When that and half the beams were fixed.
        let (mut first_ms, mut half_ms, mut sent_ms) = (None, None, None);
        let mut tick = |done: usize, all: usize| {
            if done > 0 && first_ms.is_none() {
                first_ms = Some((crate::clock::now_s() - started) * 1000.0);
            }
            if 2 * done >= all && all > 0 && half_ms.is_none() {
                half_ms = Some((crate::clock::now_s() - started) * 1000.0);
            }
            progress(done as f32 / all.max(1) as f32)
        };
        let mut ahead = |fixed: &Plan| {
            send(fixed);
            sent.set(true);
            sent_ms = Some((crate::clock::now_s() - started) * 1000.0);
        };
        let band_of = bands::assign(&w.joints, &w.beams, c, j.planner.band_beams);
        let planned = if band_of.iter().all(|&k| k == 0) {
            plan::plan_sending(&a, &o, send_at, &mut tick, &mut ahead)
        } else {
            bands::plan(&a, &o, &band_of, &mut tick).map(|(p, _)| p)
        };
        let p = match planned {
            Ok(p) => p,
            // The planner's refusals that are proofs stand; its search's limits the exact
            // search may overcome on a small design.
            Err(u @ (Unconstructable::NoSubassembly { .. } | Unconstructable::SearchTooLarge { .. })) if searched => {
                let report = StageReport::new("plan", "Planning the sequence: no sequence found", &serde_json::json!({ "refused": &u }));
                return Ok((Err(u), Some(report)));
            }
            Err(u) => return Err(Error::stage("planning", CannotPrint(explain(w, &u, o.mode)))),
        };
        let ms = (crate::clock::now_s() - started) * 1000.0;
        let eps: Vec<f64> = p.steps.iter().map(|s| s.cost_mm * 1000.0).collect();
        let max = eps.iter().copied().fold(0.0, f64::max);
        let mean = eps.iter().sum::<f64>() / eps.len().max(1) as f64;
        let multi = p.blocks.iter().filter(|b| b.end - b.start > 1).count();
        let mut report = StageReport::new(
            "plan",
            "Planning the sequence",
            &serde_json::json!({ "steps": p.steps.len(), "blocks": p.blocks.len(), "max_um": max, "expansions": p.expansions, "exact_until": p.exact_until }),
        )
        .metric(
            "max_eps",
            "Largest ε",
            max,
            "µm",
            "The largest error of a joint while printing: the deflection of the beam's free end under the nozzle's load (what the plan minimises).",
        )
        .metric("mean_eps", "Mean ε", mean, "µm", "The mean over all beams (0 for beams that close onto a printed joint).")
        .metric(
            "blocks",
            "Subassemblies",
            p.blocks.len() as f64,
            "",
            "Consistent subassemblies added one after another (paths between stable joints, single closing beams, hanging ends).",
        )
        .metric("paths", "Joined paths", multi as f64, "", "Subassemblies of several beams: cantilevers grown from stable joints until they meet.")
        .metric("expansions", "Search steps", p.expansions as f64, "", "Tree states expanded by the best-first search.")
        .metric("work", "Counted work", p.work / plan::WORK_PER_SECOND, "s", "Work counted against the planning budget (the same on every machine).")
        .metric("time", "Planning time", ms, "ms", "Wall time of the plan on this machine.")
        .metric(
            "first_ms",
            "First beams fixed",
            first_ms.unwrap_or(ms),
            "ms",
            "When the plan's first subassembly was fixed: a printer could start then, while planning goes on (the plan only adds after it).",
        )
        .metric("half_ms", "Half the beams fixed", half_ms.unwrap_or(ms), "ms", "When half of the sequence was fixed.");
        if let Some(t) = sent_ms {
            report = report
                .metric(
                    "sent",
                    "Beams sent ahead",
                    p.sent as f64,
                    "",
                    "Beams whose G-code was sent out while planning went on; the final G-code's moves begin with theirs.",
                )
                .metric("sent_ms", "Sent ahead at", t, "ms", "When they were sent, counted from the plan's start.");
        }
        if !p.bands.is_empty() {
            report = report.metric(
                "bands",
                "Bands",
                p.bands.len() as f64,
                "",
                "Bands planned one after another up the design, each with the bands below printed and rigid.",
            );
        }
        if let Some(k) = p.exact_until {
            report = report.metric(
                "exact_until",
                "Exact cost until step",
                k as f64,
                "",
                "The planning budget ran out here: later steps were chosen by the heuristic cost.",
            );
        }
        if j.planner.cost == Cost::Exact {
            report = report.metric(
                "peak_live",
                "Joints tracked",
                p.peak_live as f64,
                "",
                "Most joints whose compliance the exact cost kept at once (its memory grows as the square).",
            );
            if p.refreshes > 0 {
                report = report
                    .metric(
                        "refreshes",
                        "Sparse checks",
                        p.refreshes as f64,
                        "",
                        "Times the running compliance was checked against a sparse Cholesky factorisation of the printed frame (faer).",
                    )
                    .metric(
                        "drift",
                        "Largest difference",
                        p.drift,
                        "",
                        "The largest difference a check found, relative to the largest compliance: the rounding the running updates have gathered.",
                    );
            }
        }
        Ok((Ok(p), Some(report)))
    })?;
    // A plan made before (the cache: an earlier run, or a view asked for first) is ready at
    // once: its beginning is still sent, so every run delivers it.
    if let (false, Ok(p)) = (sent.get(), &*out) {
        if p.sent > 0 {
            send(&p.prefix(p.sent));
        }
    }
    Ok(out)
}

/// ε (exact, mm) of each step of `steps`, replayed.
pub(super) fn exact_eps(w: &Wireframe, steps: &[plan::Step], s: &Section, load: f64) -> Vec<f64> {
    cost::costs(&w.joints, &w.beams, &w.grounded, steps, s, load).iter().map(|k| k.exact_mm).collect()
}

/// The exact search over every order ([`optimal`]) on small designs: proves the planner's
/// largest ε optimal or shows the gap, and prints the better sequence when asked (or when the
/// planner found none).
pub(super) fn optimum_stage(j: &FreeformJob, ctx: &mut Ctx, w: &Out<Placed>, c: &Out<Constraints>, p: &Out<Planned>) -> Result<Out<Plan>, Error> {
    let searched = exact_runs(j, w.beams.len());
    let parts = (j.planner.exact_search, j.planner.exact_beams, j.planner.exact_states, searched);
    let mode = j.constraints.cantilever;
    ctx.stage("optimum", "optimum", &parts, &[w.key, c.key, p.key], |progress| {
        let planned: &Planned = p;
        if !searched {
            // Say why when it was asked for.
            let why = if !j.constraints.connection {
                "it needs the connection constraint".to_string()
            } else {
                format!("{} beams, more than {}", w.beams.len(), j.planner.exact_beams.min(optimal::MAX_BEAMS))
            };
            let note = (j.planner.exact_search != ExactSearch::Off)
                .then(|| StageReport::new("optimum", &format!("Exact search: not run ({why})"), &serde_json::json!({ "skipped": why })));
            return match planned {
                Ok(plan) => Ok((plan.clone(), note)),
                Err(u) => Err(Error::stage("planning", CannotPrint(explain(w, u, mode)))),
            };
        }
        let s = section(j);
        let load = j.beam.load_n;
        let planner_eps = planned.as_ref().ok().map(|plan| exact_eps(w, &plan.steps, &s, load));
        let known = planner_eps.as_ref().map(|e| e.iter().copied().fold(0.0, f64::max));
        let a = Assembly { joints: &w.joints, beams: &w.beams, grounded: &w.grounded, constraints: c };
        let o = optimal::Options { mode, section: s, load_n: load, max_states: j.planner.exact_states, known_mm: known };
        let started = crate::clock::now_s();
        let best = optimal::optimum(&a, &o, &mut |done, all| progress(done as f32 / all.max(1) as f32)).map_err(|e| Error::stage("the exact search", e))?;
        let ms = (crate::clock::now_s() - started) * 1000.0;
        let searched_plan = best.steps.as_ref().map(|steps| sequential_plan(steps.clone(), best.states));
        let printed = match (planned, &searched_plan) {
            (Err(_), Some(sp)) => sp.clone(),
            (Ok(_), Some(sp)) if j.planner.exact_search == ExactSearch::Print => sp.clone(),
            (Ok(plan), _) => plan.clone(),
            (Err(u), None) => {
                let why = explain(w, u, mode);
                let msg = if best.proven {
                    format!(
                        "cannot be printed: the exact search tried every order ({} states) and none meets the constraints{}; the planner said: {why}",
                        best.states,
                        if mode == Mode::Strict { " with one cantilever per joint" } else { "" }
                    )
                } else {
                    format!("{why} (the exact search gave up after {} states: raise its states to decide)", best.states)
                };
                return Err(Error::stage("planning", CannotPrint(msg)));
            }
        };
        Ok((printed, Some(optimum_report(&best, known, planner_eps.as_deref(), ms, j.planner.exact_search))))
    })
}

/// A found sequence as a plan: one step a block, each after the one before (the search's order
/// is what meets the cantilever rule, so the deadhead order keeps it).
pub(super) fn sequential_plan(steps: Vec<plan::Step>, states: usize) -> Plan {
    let blocks = (0..steps.len())
        .map(|i| plan::Block { start: i, end: i + 1, after: if i == 0 { Vec::new() } else { vec![i - 1] }, chain: vec![usize::MAX], key_mm: steps[i].cost_mm })
        .collect();
    Plan { steps, blocks, expansions: states as u64, ..Plan::default() }
}

//! The exact planner for small designs: its optimum equals a brute force over every sequence
//! (an independent enumeration, ε from faer's sparse factorisation), every sequence it returns
//! passes the independent checker, it never reads more than the planner, and it proves the
//! planner's gap on weft's small models.

use super::plan::{cantilevers_about, check, constraints, ISOMALT};
use weft::freeform::frame::{self, Pattern};
use weft::freeform::optimal::{self, Optimum};
use weft::freeform::plan::{self, Assembly, Cost, Mode, Unconstructable};
use weft::freeform::precedence::{Constraints, Nozzle};
use weft::freeform::wireframe::{self, Wireframe};
use weft::freeform::{cost, models};
use weft::geom::DVec3;

fn search(w: &Wireframe, c: &Constraints, mode: Mode, known: Option<f64>) -> Optimum {
    let a = Assembly { joints: &w.joints, beams: &w.beams, grounded: &w.grounded, constraints: c };
    let o = optimal::Options { known_mm: known, ..optimal::Options::new(mode, ISOMALT, 1e-4) };
    optimal::optimum(&a, &o, &mut |_, _| {}).unwrap()
}

/// Every sequence, depth first without memory: the least largest ε, or None.
fn brute(w: &Wireframe, c: &Constraints, strict: bool) -> Option<f64> {
    let m = w.beams.len();
    let pattern = Pattern::new(&w.joints, &w.beams, &w.grounded, ISOMALT).unwrap();
    let mut inc: Vec<Vec<usize>> = vec![Vec::new(); w.joints.len()];
    for (b, &[p, q]) in w.beams.iter().enumerate() {
        inc[p].push(b);
        inc[q].push(b);
    }
    // The search's state is its arguments (what is printed and touched, the worst ε so far).
    #[allow(clippy::too_many_arguments)]
    fn go(
        w: &Wireframe,
        c: &Constraints,
        strict: bool,
        pattern: &Pattern,
        inc: &[Vec<usize>],
        printed: &mut Vec<bool>,
        touched: &mut Vec<bool>,
        worst: f64,
        best: &mut Option<f64>,
    ) {
        let m = w.beams.len();
        if printed.iter().all(|&p| p) {
            if best.is_none_or(|b| worst < b) {
                *best = Some(worst);
            }
            return;
        }
        for b in 0..m {
            if printed[b] || c.preds(b).iter().any(|&p| !printed[p as usize]) {
                continue;
            }
            let [p, q] = w.beams[b];
            for (from, to) in [(p, q), (q, p)] {
                let ok_dir = if from == p { c.forward[b] } else { c.backward[b] };
                if !touched[from] || !ok_dir {
                    continue;
                }
                if strict && [from, to].iter().any(|&j| touched[j] && !cantilevers_about(w, inc, printed, j).is_empty()) {
                    continue;
                }
                let e = if touched[to] {
                    0.0
                } else {
                    let f = pattern.factor(printed).unwrap();
                    let cf = f.compliance(from);
                    frame::displacement(&frame::extend(&cf, w.joints[from], w.joints[to], &ISOMALT), DVec3::new(0.0, 0.0, -1e-4)).length()
                };
                printed[b] = true;
                let (tf, tt) = (touched[from], touched[to]);
                touched[from] = true;
                touched[to] = true;
                let fine = !strict || [from, to].iter().all(|&j| cantilevers_about(w, inc, printed, j).len() <= 1);
                if fine {
                    go(w, c, strict, pattern, inc, printed, touched, worst.max(e), best);
                }
                printed[b] = false;
                touched[from] = tf;
                touched[to] = tt;
            }
        }
    }
    let mut best = None;
    go(w, c, strict, &pattern, &inc, &mut vec![false; m], &mut w.grounded.clone(), 0.0, &mut best);
    best
}

/// Small random frames (seeded): a few grounded joints, joints above, beams between near ones.
fn random_frame(seed: u64, free: usize, beams: usize) -> Wireframe {
    let mut s = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
    let mut next = move || {
        s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((s >> 33) as f64) / (1u64 << 31) as f64
    };
    let mut joints = vec![DVec3::new(0.0, 0.0, 0.0), DVec3::new(6.0, 0.0, 0.0), DVec3::new(3.0, 5.0, 0.0)];
    for _ in 0..free {
        joints.push(DVec3::new(next() * 8.0 - 1.0, next() * 7.0 - 1.0, 1.0 + next() * 6.0));
    }
    let n = joints.len();
    let mut list: Vec<[usize; 2]> = Vec::new();
    // Each free joint hangs from an earlier joint (connected), then extra beams.
    for j in 3..n {
        let k = (next() * j as f64) as usize;
        list.push([k.min(j - 1), j]);
    }
    let mut tries = 0;
    while list.len() < beams && tries < 1000 {
        tries += 1;
        let (a, b) = ((next() * n as f64) as usize, (next() * n as f64) as usize);
        let (a, b) = (a.min(n - 1), b.min(n - 1));
        if a == b || (a < 3 && b < 3) || list.iter().any(|&[p, q]| (p, q) == (a, b) || (p, q) == (b, a)) {
            continue;
        }
        list.push([a, b]);
    }
    let names = |k: usize, p: &str| (0..k).map(|i| format!("{p} {i}")).collect::<Vec<_>>();
    let m = list.len();
    Wireframe {
        grounded: (0..n).map(|j| j < 3).collect(),
        joints,
        beams: list,
        grounded_by_file: true,
        format: wireframe::Format::Model,
        joint_names: names(n, "joint"),
        beam_names: names(m, "beam"),
        notes: Vec::new(),
        grounding: None,
    }
}

#[test]
fn the_exact_search_equals_a_brute_force_over_every_sequence() {
    let n = Nozzle { half_angle_deg: 13.0, radius_mm: 0.5, height_mm: 5.0 };
    let (mut compared, mut none, mut strict_none) = (0, 0, 0);
    for seed in 0..40u64 {
        let w = random_frame(seed, 3 + (seed % 2) as usize, 6 + (seed % 2) as usize);
        let c = constraints(&w, &n, 0.075);
        for mode in [Mode::Strict, Mode::Relaxed] {
            let strict = mode == Mode::Strict;
            let b = brute(&w, &c, strict);
            let o = search(&w, &c, mode, None);
            assert!(o.proven, "seed {seed}: {o:?}");
            match (b, o.best_mm) {
                (Some(x), Some(y)) => {
                    assert!((x - y).abs() <= 1e-9 * x.max(1e-12), "seed {seed} {mode:?}: brute force {x} mm, search {y} mm");
                    let steps = o.steps.as_ref().unwrap();
                    check(&w, steps, &n, 0.075, strict, &c, &format!("seed {seed} {mode:?}"));
                    // Its own record of ε is the exact cost measured again.
                    let k = cost::costs(&w.joints, &w.beams, &w.grounded, steps, &ISOMALT, 1e-4);
                    let max = k.iter().map(|k| k.exact_mm).fold(0.0, f64::max);
                    assert!((max - y).abs() <= 1e-9 * y.max(1e-12), "seed {seed}: replayed {max} against {y}");
                    compared += 1;
                }
                (None, None) => {
                    none += 1;
                    strict_none += usize::from(strict);
                }
                other => panic!("seed {seed} {mode:?}: brute force and search disagree {other:?}"),
            }
        }
    }
    assert!(compared >= 40, "{compared} compared, {none} without a sequence");
    assert!(strict_none >= 1, "no random frame was unprintable in strict mode: the proof of none was not exercised");
}

#[test]
fn the_exact_search_proves_or_beats_the_planner_on_small_models() {
    let n = Nozzle { half_angle_deg: 13.0, radius_mm: 0.5, height_mm: 5.0 };
    for m in [
        models::Model::Tower { cells: 1, levels: 2, cell_mm: 3.0, level_mm: 2.5, taper: 0.6 },
        models::Model::Dome { radius_mm: 10.0, rings: 1, segments: 8 },
        models::Model::Dome { radius_mm: 10.0, rings: 2, segments: 5 },
        models::Model::Bridge { span_mm: 30.0, panels: 2, width_mm: 5.0, height_mm: 4.0 },
    ] {
        let w = models::build(&m);
        let c = constraints(&w, &n, 0.075);
        for mode in [Mode::Strict, Mode::Relaxed] {
            for cost_kind in [Cost::Heuristic, Cost::Exact] {
                let a = Assembly { joints: &w.joints, beams: &w.beams, grounded: &w.grounded, constraints: &c };
                let p =
                    plan::plan(&a, &plan::Options { mode, cost: cost_kind, connection: true, section: ISOMALT, load_n: 1e-4, budget_s: 600.0 }, &mut |_, _| {})
                        .unwrap();
                let k = cost::costs(&w.joints, &w.beams, &w.grounded, &p.steps, &ISOMALT, 1e-4);
                let planned = k.iter().map(|k| k.exact_mm).fold(0.0, f64::max);
                let o = search(&w, &c, mode, Some(planned));
                let best = o.best_mm.unwrap();
                eprintln!(
                    "{m:?} {mode:?} {cost_kind:?}: {} beams, planner {:.4} µm, optimum {:.4} µm ({}), {} states, {} better",
                    w.beams.len(),
                    planned * 1e3,
                    best * 1e3,
                    if o.proven { "proven" } else { "not proven" },
                    o.states,
                    o.improvements
                );
                assert!(best <= planned, "{m:?}: optimum above the planner");
                if let Some(steps) = &o.steps {
                    check(&w, steps, &n, 0.075, mode == Mode::Strict, &c, &format!("{m:?} {mode:?}"));
                }
            }
        }
    }
}

#[test]
fn the_search_agrees_with_the_planners_proofs_and_decides_where_its_search_gives_up() {
    // Small random frames in strict mode. Where the planner proves a design unconstructable
    // (a precedence cycle, two cantilevers on a joint, a strut hanging down, beams no order
    // reaches) the exhaustive search finds no order either; where the planner plans, the search
    // proves its largest ε optimal or finds a better one; where the planner's search finds no
    // consistent subassembly (it joins at most two paths), the exact search decides.
    let n = Nozzle { half_angle_deg: 13.0, radius_mm: 0.5, height_mm: 5.0 };
    let (mut planned, mut optimal_too, mut rescued, mut none, mut gaps) = (0, 0, 0, 0, Vec::new());
    for seed in 0..1500u64 {
        let free = 4 + (seed % 4) as usize;
        let w = random_frame(seed, free, free + 3 + (seed % 5) as usize);
        let c = constraints(&w, &n, 0.075);
        let a = Assembly { joints: &w.joints, beams: &w.beams, grounded: &w.grounded, constraints: &c };
        let p = plan::plan(
            &a,
            &plan::Options { mode: Mode::Strict, cost: Cost::Exact, connection: true, section: ISOMALT, load_n: 1e-4, budget_s: 600.0 },
            &mut |_, _| {},
        );
        match p {
            Ok(p) => {
                let k = cost::costs(&w.joints, &w.beams, &w.grounded, &p.steps, &ISOMALT, 1e-4);
                let known = k.iter().map(|k| k.exact_mm).fold(0.0, f64::max);
                let o = search(&w, &c, Mode::Strict, Some(known));
                assert!(o.proven, "seed {seed}");
                let best = o.best_mm.unwrap();
                assert!(best <= known, "seed {seed}");
                if let Some(steps) = &o.steps {
                    check(&w, steps, &n, 0.075, true, &c, &format!("seed {seed}"));
                    gaps.push(known / best - 1.0);
                } else {
                    optimal_too += 1;
                }
                planned += 1;
            }
            Err(u @ (Unconstructable::NoSubassembly { .. } | Unconstructable::SearchTooLarge { .. })) => {
                let o = search(&w, &c, Mode::Strict, None);
                assert!(o.proven, "seed {seed}: {u:?}");
                match &o.steps {
                    Some(steps) => {
                        check(&w, steps, &n, 0.075, true, &c, &format!("seed {seed}"));
                        rescued += 1;
                    }
                    None => none += 1,
                }
            }
            Err(u) => {
                let o = search(&w, &c, Mode::Strict, None);
                assert!(o.proven && o.best_mm.is_none(), "seed {seed}: the planner proved {u:?} but the search found {:?}", o.best_mm);
            }
        }
    }
    gaps.sort_by(f64::total_cmp);
    let worst = gaps.last().copied().unwrap_or(0.0);
    eprintln!("strict, 1500 random frames: {planned} planned ({optimal_too} proven optimal, {} beaten: median gap {:.1} %, worst {:.1} %); planner found no subassembly on {} (the search found an order on {rescued}, proved none on {none})", gaps.len(), gaps.get(gaps.len() / 2).copied().unwrap_or(0.0) * 100.0, worst * 100.0, rescued + none);
    assert!(planned > 300 && optimal_too > planned / 2, "{planned} planned, {optimal_too} optimal");
    assert!(rescued > 10 && none > 10, "the search decided {rescued} + {none} designs the planner left open");
}

#[test]
fn planning_in_bands_checks_keeps_the_bands_in_order_and_fails_only_where_the_whole_fails() {
    use weft::freeform::{bands, deadhead};
    let n = Nozzle { half_angle_deg: 13.0, radius_mm: 0.5, height_mm: 5.0 };
    let w = models::build(&models::Model::Tower { cells: 3, levels: 12, cell_mm: 3.0, level_mm: 2.5, taper: 0.6 });
    let c = constraints(&w, &n, 0.075);
    let a = Assembly { joints: &w.joints, beams: &w.beams, grounded: &w.grounded, constraints: &c };
    let o = plan::Options { mode: Mode::Strict, cost: Cost::Exact, connection: true, section: ISOMALT, load_n: 1e-4, budget_s: 600.0 };
    let band_of = bands::assign(&w.joints, &w.beams, &c, 100);
    let (p, list) = bands::plan(&a, &o, &band_of, &mut |_, _| {}).unwrap();
    assert!(p.bands.len() >= 5 && p.bands.len() == list.len(), "{} bands of {} beams", p.bands.len(), w.beams.len());
    check(&w, &p.steps, &n, 0.075, true, &c, "tower in bands");
    // Each band's beams are the band's, and the deadhead order keeps every band after the last.
    for (k, b) in list.iter().enumerate() {
        assert!(b.beams > 0 && (k == 0 || b.clamped > 0), "band {k}: {b:?}");
    }
    let ordered = deadhead::order(&w.joints, &p, &c, &deadhead::Options { xy_mm_s: 150.0, z_mm_s: 10.0, clearance_mm: 1.0, beam_radius_mm: 0.075 });
    let band_at = |i: usize| p.bands.iter().rposition(|&s| s <= i).unwrap();
    let step_of: std::collections::BTreeMap<usize, usize> = p.steps.iter().enumerate().map(|(i, s)| (s.beam, i)).collect();
    let seq: Vec<usize> = ordered.steps.iter().map(|s| band_at(step_of[&s.beam])).collect();
    assert!(seq.windows(2).all(|x| x[0] <= x[1]), "the deadhead order mixes bands");
    check(&w, &ordered.steps, &n, 0.075, true, &c, "tower in bands, ordered");
    // The whole frame against each band's: every step measured again, the joins cost something.
    let whole = cost::costs(&w.joints, &w.beams, &w.grounded, &p.steps, &ISOMALT, 1e-4);
    let grew = p.steps.iter().zip(&whole).filter(|(s, k)| k.exact_mm > s.cost_mm * (1.0 + 1e-9)).count();
    assert!(grew > 0, "no step felt the bands below");
    // Random frames cut into bands of four beams: a band that cannot be planned is merged with
    // the one below, so the bands plan exactly where the whole design plans.
    let (mut both, mut merged_to_fail) = (0, 0);
    for seed in 0..400u64 {
        let free = 4 + (seed % 4) as usize;
        let w = random_frame(seed, free, free + 3 + (seed % 5) as usize);
        let c = constraints(&w, &n, 0.075);
        let a = Assembly { joints: &w.joints, beams: &w.beams, grounded: &w.grounded, constraints: &c };
        let whole = plan::plan(&a, &o, &mut |_, _| {});
        let band_of = bands::assign(&w.joints, &w.beams, &c, 4);
        let banded = bands::plan(&a, &o, &band_of, &mut |_, _| {});
        match (&whole, &banded) {
            (Ok(_), Ok((p, _))) => {
                check(&w, &p.steps, &n, 0.075, true, &c, &format!("seed {seed} in bands"));
                both += 1;
            }
            (Err(_), Err(_)) => merged_to_fail += 1,
            (Err(_), Ok((p, _))) => {
                check(&w, &p.steps, &n, 0.075, true, &c, &format!("seed {seed} in bands (the whole plan gave up)"));
            }
            (Ok(_), Err(e)) => panic!("seed {seed}: whole plans, bands fail: {e:?}"),
        }
    }
    assert!(both > 100 && merged_to_fail > 50, "{both} planned both ways, {merged_to_fail} neither");
}

//! Freeform planning (issue 13): the frame model against closed forms and hand numbers, the
//! collision precedences against a brute-force scan, and every plan of the real designs of
//! `tests/fixtures/wireframes/` and of weft's own models replayed by an independent checker:
//! each beam exactly once, each from a grounded or printed joint, in an allowed direction, no
//! nozzle sweep through a printed beam (found by sampling, not by the planner's test), and in
//! strict mode no joint ever heated while a beam is cantilevered about it.

use weft::freeform::frame::{self, Flex, Pattern, Section, RIGID};
use weft::freeform::plan::{self, Assembly, Cost, Mode, Plan, Step, Unconstructable};
use weft::freeform::precedence::{self, Constraints, Nozzle};
use weft::freeform::wireframe::{self, Wireframe};
use weft::freeform::{cost, deadhead, models};
use weft::geom::DVec3;

fn fixture(name: &str) -> Wireframe {
    let bytes = std::fs::read(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/wireframes").join(name)).unwrap();
    wireframe::read(name, &bytes, &wireframe::Options::default()).unwrap()
}

/// The robot-scale designs' PLA beams (radius 1.5 mm, as their files state).
const PLA: Section = Section { diameter_mm: 3.0, e_mpa: 3500.0, g_mpa: 2400.0 };
pub const ISOMALT: Section = Section { diameter_mm: 0.15, e_mpa: 2600.0, g_mpa: 1100.0 };

fn nozzle() -> Nozzle {
    Nozzle::default()
}

pub fn constraints(w: &Wireframe, n: &Nozzle, r: f64) -> Constraints {
    precedence::constraints(
        &w.joints,
        &w.beams,
        &precedence::Options { nozzle: *n, beam_radius_mm: r, directionality: true, collision: true, tilt_deg: 0.0 },
        &mut |_| {},
    )
    .unwrap()
}

fn plan_of(w: &Wireframe, c: &Constraints, mode: Mode, cost: Cost, s: Section) -> Result<Plan, Unconstructable> {
    let a = Assembly { joints: &w.joints, beams: &w.beams, grounded: &w.grounded, constraints: c };
    plan::plan(&a, &plan::Options { mode, cost, connection: true, section: s, load_n: 1e-4, budget_s: 600.0 }, &mut |_, _| {})
}

// ---------------------------------------------------------------------------------------
// The independent checker
// ---------------------------------------------------------------------------------------

/// Whether point `p` is inside the nozzle body with its tip at `tip`, shrunk by `shrink` (so a
/// grazing contact the exact test calls a hit is not claimed here: only clear collisions).
fn in_nozzle(n: &Nozzle, tip: DVec3, p: DVec3, inflate: f64) -> bool {
    let d = p - tip;
    let h = n.cone_height() + n.height_mm;
    if d.z <= 0.0 || d.z > h {
        return false;
    }
    let r = (d.z * n.half_angle_deg.to_radians().tan()).min(n.radius_mm);
    d.truncate().length() < r + inflate
}

/// A clear collision of the nozzle swept along `a` with beam `b`, found by sampling both
/// (steps of a tenth of the smaller of the beam radius and the nozzle radius).
fn sampled_hit(n: &Nozzle, a: [DVec3; 2], b: [DVec3; 2], shared: Option<DVec3>, radius: f64) -> bool {
    // Shared joint: B's axis from well off the joint (the planner's test starts closer).
    let (b0, b1, r) = match shared {
        Some(s) => {
            let (f, t) = if b[0].distance(s) <= b[1].distance(s) { (b[0], b[1]) } else { (b[1], b[0]) };
            let len = f.distance(t);
            (f + (t - f) * ((radius * 4.0).max(len * 0.01).min(len * 0.5) / len), t, 0.0)
        }
        None => (b[0], b[1], radius),
    };
    let step = (0.1 * radius.max(0.02).min(n.radius_mm)).max(1e-3);
    let na = (a[0].distance(a[1]) / step).ceil().max(1.0) as usize;
    // The body shrunk by 2 % of its radius: only clear hits.
    let inflate = r * 0.98 - 0.02 * n.radius_mm;
    let (reach, top) = (n.radius_mm + inflate.max(0.0), n.cone_height() + n.height_mm);
    let d = b1 - b0;
    (0..=na).any(|i| {
        let tip = a[0].lerp(a[1], i as f64 / na as f64);
        // Only the part of B inside the body's box over this tip: an interval of B's parameter.
        let (mut lo, mut hi) = (0.0f64, 1.0f64);
        for (p0, dp, min, max) in [(b0.z, d.z, tip.z, tip.z + top), (b0.x, d.x, tip.x - reach, tip.x + reach), (b0.y, d.y, tip.y - reach, tip.y + reach)] {
            if dp.abs() < 1e-12 {
                if p0 < min || p0 > max {
                    return false;
                }
            } else {
                let (t0, t1) = ((min - p0) / dp, (max - p0) / dp);
                lo = lo.max(t0.min(t1));
                hi = hi.min(t0.max(t1));
            }
        }
        if lo > hi {
            return false;
        }
        let nb = ((hi - lo) * b0.distance(b1) / step).ceil().max(1.0) as usize;
        (0..=nb).any(|k| in_nozzle(n, tip, b0.lerp(b1, lo + (hi - lo) * k as f64 / nb as f64), inflate))
    })
}

/// Joints reachable from the ground over `present` beams without passing through `avoid`.
fn reach_without(w: &Wireframe, inc: &[Vec<usize>], present: &[bool], avoid: usize) -> Vec<bool> {
    let mut seen = vec![false; w.joints.len()];
    let mut stack: Vec<usize> = (0..w.joints.len()).filter(|&j| w.grounded[j] && j != avoid).collect();
    for &j in &stack {
        seen[j] = true;
    }
    while let Some(j) = stack.pop() {
        for &b in &inc[j] {
            if !present[b] {
                continue;
            }
            let o = if w.beams[b][0] == j { w.beams[b][1] } else { w.beams[b][0] };
            if o != avoid && !seen[o] {
                seen[o] = true;
                stack.push(o);
            }
        }
    }
    seen
}

/// Beams cantilevered about joint `j`: printed beams (j, x) with x not grounded and cut off
/// from the ground when j is removed.
pub fn cantilevers_about(w: &Wireframe, inc: &[Vec<usize>], present: &[bool], j: usize) -> Vec<usize> {
    let mine: Vec<usize> = inc[j].iter().copied().filter(|&b| present[b]).collect();
    if mine.is_empty() {
        return Vec::new();
    }
    let seen = reach_without(w, inc, present, j);
    mine.into_iter()
        .filter(|&b| {
            let x = if w.beams[b][0] == j { w.beams[b][1] } else { w.beams[b][0] };
            !w.grounded[x] && !seen[x]
        })
        .collect()
}

/// Replays `steps`, asserting every process constraint; returns the collision pairs checked.
pub fn check(w: &Wireframe, steps: &[Step], n: &Nozzle, radius: f64, strict: bool, c: &Constraints, label: &str) -> usize {
    let m = w.beams.len();
    assert_eq!(steps.len(), m, "{label}: every beam, once");
    let mut printed = vec![false; m];
    let mut touched: Vec<bool> = w.grounded.clone();
    let mut inc: Vec<Vec<usize>> = vec![Vec::new(); w.joints.len()];
    for (b, &[p, q]) in w.beams.iter().enumerate() {
        inc[p].push(b);
        inc[q].push(b);
    }
    let cos = n.half_angle_deg.to_radians().cos();
    let top = n.cone_height() + n.height_mm + radius;
    let reach = n.radius_mm + radius;
    let mut pairs = 0;
    for (i, s) in steps.iter().enumerate() {
        assert!(!printed[s.beam], "{label}: beam {} printed twice (step {i})", s.beam);
        let [p, q] = w.beams[s.beam];
        assert!((s.from, s.to) == (p, q) || (s.from, s.to) == (q, p), "{label}: step {i} runs along beam {}", s.beam);
        assert!(touched[s.from], "{label}: step {i} starts at joint {} which is neither grounded nor printed", s.from);
        // The nozzle's axis for this beam (a tilting nozzle): the geometry is turned so that
        // axis is vertical, and the vertical checks apply.
        let axis = c.axis.get(s.beam).copied().unwrap_or(DVec3::Z);
        assert!((axis.length() - 1.0).abs() < 1e-9 && axis.z > 0.0, "{label}: step {i} has nozzle axis {axis:?}");
        let turn = glam::DQuat::from_rotation_arc(axis, DVec3::Z);
        let at = |j: usize| turn * w.joints[j];
        let d = (at(s.to) - at(s.from)).normalize();
        assert!(-d.z <= cos + 1e-9, "{label}: step {i} prints beam {} downward, steeper than the cone", s.beam);
        // The planner's own precedences hold.
        for &pr in c.preds(s.beam) {
            assert!(printed[pr as usize], "{label}: step {i} prints beam {} before its predecessor {pr}", s.beam);
        }
        // No clear collision with any printed beam, by sampling.
        let a = [at(p), at(q)];
        let (lo, hi) = (a[0].min(a[1]), a[0].max(a[1]));
        for (b, &[u, v]) in w.beams.iter().enumerate() {
            if !printed[b] {
                continue;
            }
            let (bu, bv) = (at(u), at(v));
            let (bl, bh) = (bu.min(bv), bu.max(bv));
            if bh.z < lo.z - radius || bl.z > hi.z + top || bh.x < lo.x - reach || bl.x > hi.x + reach || bh.y < lo.y - reach || bl.y > hi.y + reach {
                continue;
            }
            pairs += 1;
            let shared = [p, q].into_iter().find(|&x| x == u || x == v).map(at);
            assert!(!sampled_hit(n, a, [bu, bv], shared, radius), "{label}: step {i} (beam {}) sweeps the nozzle through printed beam {b}", s.beam);
        }
        if strict {
            for j in [s.from, s.to] {
                if touched[j] {
                    let hanging = cantilevers_about(w, &inc, &printed, j);
                    assert!(hanging.is_empty(), "{label}: step {i} heats joint {j} while beam(s) {hanging:?} are cantilevered about it");
                }
            }
        }
        printed[s.beam] = true;
        touched[s.from] = true;
        touched[s.to] = true;
        if strict {
            for j in [s.from, s.to] {
                let k = cantilevers_about(w, &inc, &printed, j);
                assert!(k.len() <= 1, "{label}: after step {i} joint {j} carries cantilevers {k:?}");
            }
        }
    }
    pairs
}

// ---------------------------------------------------------------------------------------
// The frame
// ---------------------------------------------------------------------------------------

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs().max(1e-300)
}

#[test]
fn a_cantilever_deflects_pl3_over_3ei() {
    for (dir, l) in [(DVec3::X, 10.0), (DVec3::new(0.6, 0.8, 0.0), 7.5), (DVec3::new(0.0, 0.6, 0.8), 4.0)] {
        let joints = vec![DVec3::new(1.0, 2.0, 3.0), DVec3::new(1.0, 2.0, 3.0) + dir * l];
        let p = Pattern::new(&joints, &[[0, 1]], &[true, false], ISOMALT).unwrap();
        let f = p.factor(&[true]).unwrap();
        let load = DVec3::new(0.0, 0.0, -1e-4);
        let sparse = f.deflection(1, load);
        let chain = frame::displacement(&frame::extend(&RIGID, joints[0], joints[1], &ISOMALT), load);
        // Bending by the load's part across the beam, stretching by the part along it.
        let across = load - dir * load.dot(dir);
        let expect = across * (l * l * l / (3.0 * ISOMALT.e_mpa * ISOMALT.inertia())) + dir * load.dot(dir) * (l / (ISOMALT.e_mpa * ISOMALT.area()));
        assert!((sparse - expect).length() <= 1e-9 * expect.length(), "sparse {sparse:?} against PL³/3EI {expect:?}");
        assert!((chain - expect).length() <= 1e-9 * expect.length(), "chain {chain:?} against PL³/3EI {expect:?}");
    }
}

#[test]
fn statically_determinate_trusses_match_hand_numbers() {
    // Two bars from (±40, 0, 0) to the apex (0, 0, 30): each 50 mm, sin α = 0.6. A load P down
    // at the apex compresses each by N = P / (2 sin α) and lowers it by δ = P L / (2 E A sin² α)
    // (virtual work); rigid joints add bending of relative size ~(d/L)², far below 0.1 %.
    let s = Section { diameter_mm: 0.5, e_mpa: 2600.0, g_mpa: 1100.0 };
    let p = 1e-4;
    let joints = vec![DVec3::new(-40.0, 0.0, 0.0), DVec3::new(40.0, 0.0, 0.0), DVec3::new(0.0, 0.0, 30.0)];
    let pat = Pattern::new(&joints, &[[0, 2], [1, 2]], &[true, true, false], s).unwrap();
    let d = pat.factor(&[true, true]).unwrap().deflection(2, DVec3::new(0.0, 0.0, -p));
    let hand = p * 50.0 / (2.0 * 2600.0 * s.area() * 0.36);
    assert!(rel(-d.z, hand) < 1e-3 && d.x.abs() < 1e-9 * hand, "two-bar truss: {d:?} against {hand:e} mm");
    // A tripod: three bars of 50 mm from a circle of radius 40 to an apex 30 mm up: δ = P L / (3 E A sin² α).
    let mut joints: Vec<DVec3> = (0..3)
        .map(|k| {
            let a = std::f64::consts::TAU * k as f64 / 3.0;
            DVec3::new(40.0 * a.cos(), 40.0 * a.sin(), 0.0)
        })
        .collect();
    joints.push(DVec3::new(0.0, 0.0, 30.0));
    let pat = Pattern::new(&joints, &[[0, 3], [1, 3], [2, 3]], &[true, true, true, false], s).unwrap();
    let d = pat.factor(&[true; 3]).unwrap().deflection(3, DVec3::new(0.0, 0.0, -p));
    let hand = p * 50.0 / (3.0 * 2600.0 * s.area() * 0.36);
    assert!(rel(-d.z, hand) < 1e-3 && d.truncate().length() < 1e-6 * hand, "tripod: {d:?} against {hand:e} mm");
}

#[test]
fn a_hanging_chain_is_the_sparse_solve_and_the_incremental_frame_is_exact() {
    // A 3D chain: the transfer recursion equals the sparse solve with the root clamped.
    let pts = [DVec3::ZERO, DVec3::new(3.0, 1.0, 2.0), DVec3::new(5.0, -2.0, 4.0), DVec3::new(6.0, 0.0, 7.0), DVec3::new(9.0, 3.0, 6.0)];
    let beams: Vec<[usize; 2]> = (0..4).map(|i| [i, i + 1]).collect();
    let p = Pattern::new(&pts, &beams, &[true, false, false, false, false], ISOMALT).unwrap();
    let sparse = p.factor(&[true; 4]).unwrap().compliance(4);
    let mut c = RIGID;
    for i in 0..4 {
        c = frame::extend(&c, pts[i], pts[i + 1], &ISOMALT);
    }
    for r in 0..6 {
        for k in 0..6 {
            assert!((c[r][k] - sparse[r][k]).abs() <= 1e-9 * sparse[r][r].abs().max(sparse[k][k].abs()), "({r}, {k}): {} against {}", c[r][k], sparse[r][k]);
        }
    }
    // The incremental frame (attach, connect, retire) against a full factorisation after every
    // beam of a growing tower.
    let w = models::build(&models::Model::Tower { cells: 2, levels: 4, cell_mm: 3.0, level_mm: 3.0, taper: 0.8 });
    let pat = Pattern::new(&w.joints, &w.beams, &w.grounded, ISOMALT).unwrap();
    let mut open = vec![0; w.joints.len()];
    for &[a, b] in &w.beams {
        open[a] += 1;
        open[b] += 1;
    }
    let mut flex = Flex::new(w.joints.len());
    let mut in_frame = w.grounded.clone();
    let mut present = vec![false; w.beams.len()];
    let mut worst: f64 = 0.0;
    // Layer by layer (the models list verticals before a level's grid), each beam from a joint
    // in the frame.
    for (b, &[i, j]) in w.beams.iter().enumerate() {
        match (in_frame[i], in_frame[j]) {
            (true, true) => flex.connect(i, j, w.joints[i], w.joints[j], &ISOMALT),
            (true, false) => {
                flex.attach(j, i, w.joints[i], w.joints[j], &ISOMALT);
                in_frame[j] = true;
            }
            (false, true) => {
                flex.attach(i, j, w.joints[j], w.joints[i], &ISOMALT);
                in_frame[i] = true;
            }
            _ => panic!("beam {b} starts nowhere"),
        }
        present[b] = true;
        for x in [i, j] {
            open[x] -= 1;
            if open[x] == 0 {
                flex.retire(x);
            }
        }
        let f = pat.factor(&present).unwrap();
        for x in 0..w.joints.len() {
            if flex.is_live(x) {
                let (a, e) = (flex.get(x), f.compliance(x));
                let scale = (0..6).map(|k| e[k][k].abs()).fold(0.0, f64::max);
                for r in 0..6 {
                    for k in 0..6 {
                        worst = worst.max((a[r][k] - e[r][k]).abs() / scale);
                    }
                }
            }
        }
    }
    assert!(worst < 1e-8, "incremental compliance off by {worst:e} of the largest entry");
}

// ---------------------------------------------------------------------------------------
// Constraints
// ---------------------------------------------------------------------------------------

#[test]
fn the_bvh_finds_every_pair_a_full_scan_finds() {
    for file in ["klein_bottle.json", "duck.json"] {
        let w = fixture(file);
        let n = nozzle();
        let r = 1.5;
        let c = constraints(&w, &n, r);
        let mut full = 0;
        for (a, &[i, j]) in w.beams.iter().enumerate() {
            let mut found: Vec<u32> = Vec::new();
            for (b, &[k, l]) in w.beams.iter().enumerate() {
                if a == b {
                    continue;
                }
                let shared = [i, j].into_iter().find(|&x| x == k || x == l).map(|x| w.joints[x]);
                if precedence::collides(&n, [w.joints[i], w.joints[j]], [w.joints[k], w.joints[l]], shared, r) {
                    found.push(b as u32);
                }
            }
            full += found.len();
            assert_eq!(c.succs(a), found.as_slice(), "{file}: beam {a}");
        }
        assert_eq!(c.pairs(), full);
        assert!(
            c.tested < w.beams.len() * w.beams.len() / 10,
            "{file}: {} exact tests for {} beams: the index should spare most pairs",
            c.tested,
            w.beams.len()
        );
    }
}

#[test]
fn steep_beams_go_up_and_block_each_other() {
    let n = Nozzle { half_angle_deg: 20.0, radius_mm: 1.0, height_mm: 10.0 };
    // Two beams rising at 10° and 15° from the vertical out of one grounded joint: each nozzle
    // sweep meets the other: a cycle.
    let (s10, c10) = (10f64.to_radians().sin(), 10f64.to_radians().cos());
    let (s15, c15) = (15f64.to_radians().sin(), 15f64.to_radians().cos());
    let w = Wireframe {
        joints: vec![DVec3::ZERO, DVec3::new(s10 * 10.0, 0.0, c10 * 10.0), DVec3::new(-s15 * 10.0, 0.0, c15 * 10.0)],
        beams: vec![[0, 1], [2, 0]],
        grounded: vec![true, false, false],
        grounded_by_file: true,
        format: wireframe::Format::Model,
        joint_names: vec!["a".into(), "b".into(), "c".into()],
        beam_names: vec!["up".into(), "down".into()],
        notes: Vec::new(),
        grounding: None,
    };
    let c = constraints(&w, &n, 0.1);
    assert_eq!((c.forward[0], c.backward[0]), (true, false), "a beam steeper than the cone is printed upward only");
    assert_eq!((c.forward[1], c.backward[1]), (false, true), "written downward, it goes from its lower joint");
    assert_eq!((c.succs(0), c.succs(1)), (&[1u32][..], &[0u32][..]));
    match plan_of(&w, &c, Mode::Relaxed, Cost::Heuristic, ISOMALT) {
        Err(Unconstructable::Cycle { beams }) => assert_eq!(beams, vec![0, 1]),
        other => panic!("{other:?}"),
    }
    // One at 30°, outside the cone: only the steep one blocks (print the 30° one first).
    let (s30, c30) = (30f64.to_radians().sin(), 30f64.to_radians().cos());
    let mut w2 = w.clone();
    w2.joints[2] = DVec3::new(-s30 * 10.0, 0.0, c30 * 10.0);
    let c2 = constraints(&w2, &n, 0.1);
    assert_eq!((c2.succs(0), c2.succs(1)), (&[][..], &[0u32][..]));
    let p2 = plan_of(&w2, &c2, Mode::Relaxed, Cost::Heuristic, ISOMALT).unwrap();
    assert_eq!(p2.steps.iter().map(|s| s.beam).collect::<Vec<_>>(), vec![1, 0]);
    // A beam right above another, within the nozzle's body, is printed after it.
    let w3 = Wireframe {
        joints: vec![DVec3::ZERO, DVec3::new(10.0, 0.0, 0.0), DVec3::new(0.0, 0.5, 4.0), DVec3::new(10.0, 0.5, 4.0)],
        beams: vec![[0, 1], [2, 3]],
        grounded: vec![true; 4],
        ..w.clone()
    };
    let c3 = constraints(&w3, &n, 0.1);
    assert_eq!((c3.succs(0), c3.succs(1)), (&[1u32][..], &[][..]), "the lower beam first");
}

// ---------------------------------------------------------------------------------------
// Plans of real designs, checked
// ---------------------------------------------------------------------------------------

#[test]
fn every_real_design_plans_or_is_proved_unconstructable_and_every_plan_checks() {
    let n = nozzle();
    let r = PLA.diameter_mm / 2.0;
    for file in [
        "four-frame.json",
        "semi_sphere.json",
        "klein_bottle.json",
        "voronoi_S1_03-14-2019_w_layer.json",
        "topopt-310_S1_03-14-2019_w_layer.json",
        "duck.json",
        "cantilever_beam_truss.json",
    ] {
        let w = fixture(file);
        let c = constraints(&w, &n, r);
        for mode in [Mode::Strict, Mode::Relaxed] {
            let label = format!("{file} {mode:?}");
            match plan_of(&w, &c, mode, Cost::Heuristic, PLA) {
                Ok(p) => {
                    check(&w, &p.steps, &n, r, mode == Mode::Strict, &c, &label);
                    // The deadhead order keeps every constraint too.
                    let o = deadhead::order(&w.joints, &p, &c, &deadhead::Options { xy_mm_s: 150.0, z_mm_s: 10.0, clearance_mm: 1.0, beam_radius_mm: r });
                    check(&w, &o.steps, &n, r, mode == Mode::Strict, &c, &format!("{label}, deadhead order"));
                    assert!(
                        o.deadhead_s <= o.plan_order_deadhead_s + 1e-9,
                        "{label}: greedy deadhead {} s > the plan's own order {} s",
                        o.deadhead_s,
                        o.plan_order_deadhead_s
                    );
                }
                Err(Unconstructable::Cycle { beams }) => {
                    assert_eq!(file, "cantilever_beam_truss.json", "{label}: unexpected cycle {beams:?}");
                    // The proof holds: each beam's sweep clearly meets the next, by sampling.
                    for k in 0..beams.len() {
                        let (a, b) = (beams[k], beams[(k + 1) % beams.len()]);
                        let [i, j] = w.beams[a];
                        let [u, v] = w.beams[b];
                        let shared = [i, j].into_iter().find(|&x| x == u || x == v).map(|x| w.joints[x]);
                        assert!(sampled_hit(&n, [w.joints[i], w.joints[j]], [w.joints[u], w.joints[v]], shared, r), "{label}: {a} does not meet {b}");
                    }
                }
                Err(Unconstructable::NoSubassembly { count, .. }) => {
                    assert_eq!((file, mode), ("topopt-310_S1_03-14-2019_w_layer.json", Mode::Strict), "{label}: no subassembly ({count} left)");
                }
                Err(e) => panic!("{label}: {e:?}"),
            }
        }
    }
}

#[test]
fn weft_models_plan_strict_and_check() {
    let n = Nozzle { half_angle_deg: 13.0, radius_mm: 0.5, height_mm: 5.0 };
    let r = ISOMALT.diameter_mm / 2.0;
    for m in [
        models::Model::default(),
        models::Model::Tower { cells: 3, levels: 6, cell_mm: 3.0, level_mm: 2.5, taper: 0.6 },
        models::Model::Dome { radius_mm: 10.0, rings: 5, segments: 12 },
        models::Model::Bridge { span_mm: 30.0, panels: 8, width_mm: 5.0, height_mm: 4.0 },
    ] {
        let w = models::build(&m);
        let c = constraints(&w, &n, r);
        for cost in [Cost::Heuristic, Cost::Exact] {
            let p = plan_of(&w, &c, Mode::Strict, cost, ISOMALT).unwrap_or_else(|e| panic!("{m:?}: {e:?}"));
            check(&w, &p.steps, &n, r, true, &c, &format!("{m:?} {cost:?}"));
        }
    }
}

#[test]
fn strict_mode_refuses_two_cantilevers_on_a_joint_and_a_strut_hanging_down() {
    // A square frame on two grounded feet with two struts sticking out of one top corner.
    let joints = vec![
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(10.0, 0.0, 0.0),
        DVec3::new(0.0, 0.0, 10.0),
        DVec3::new(10.0, 0.0, 10.0),
        DVec3::new(15.0, 0.0, 12.0),
        DVec3::new(15.0, 5.0, 12.0),
    ];
    let beams = vec![[0, 2], [1, 3], [2, 3], [3, 4], [3, 5]];
    let names = |k: usize, p: &str| (0..k).map(|i| format!("{p} {i}")).collect::<Vec<_>>();
    let w = Wireframe {
        joints,
        beams,
        grounded: vec![true, true, false, false, false, false],
        grounded_by_file: true,
        format: wireframe::Format::Model,
        joint_names: names(6, "joint"),
        beam_names: names(5, "beam"),
        notes: Vec::new(),
        grounding: None,
    };
    let n = Nozzle { half_angle_deg: 13.0, radius_mm: 0.5, height_mm: 5.0 };
    let c = constraints(&w, &n, 0.1);
    match plan_of(&w, &c, Mode::Strict, Cost::Exact, ISOMALT) {
        Err(Unconstructable::TwoCantilevers { joint, beams }) => assert_eq!((joint, beams), (3, [3, 4])),
        other => panic!("{other:?}"),
    }
    let p = plan_of(&w, &c, Mode::Relaxed, Cost::Exact, ISOMALT).unwrap();
    check(&w, &p.steps, &n, 0.1, false, &c, "relaxed");
    // One strut only, hanging nearly straight down from the middle of the top beam: it could
    // only be printed upward from its free end, which touches nothing.
    let mut w2 = w.clone();
    w2.joints = vec![
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(10.0, 0.0, 0.0),
        DVec3::new(0.0, 0.0, 10.0),
        DVec3::new(10.0, 0.0, 10.0),
        DVec3::new(5.0, 0.0, 10.0),
        DVec3::new(5.0, 0.5, 6.0),
    ];
    w2.beams = vec![[0, 2], [1, 3], [2, 4], [4, 3], [4, 5]];
    let c2 = constraints(&w2, &n, 0.1);
    match plan_of(&w2, &c2, Mode::Strict, Cost::Heuristic, ISOMALT) {
        Err(Unconstructable::HangsDown { beam, joint }) => assert_eq!((beam, joint), (4, 4)),
        other => panic!("{other:?}"),
    }
}

#[test]
fn heuristic_never_reads_more_than_exact_and_the_relaxed_greedy_is_optimal() {
    // Fig. 8C: on every state of real sequences the heuristic reads no more than the exact
    // cost. Along the load this is a theorem (freeing joints only adds compliance) and holds
    // on every state; the norm (the paper's ε) adds sideways deflection, which freeing the
    // root can turn against the chain's own: measured on these designs it holds on all but
    // 1 of 148 (voronoi, strict) and 4 of 121 (topopt) states, by at most 6 %.
    let n = nozzle();
    let r = PLA.diameter_mm / 2.0;
    for file in ["klein_bottle.json", "duck.json", "voronoi_S1_03-14-2019_w_layer.json"] {
        let w = fixture(file);
        let c = constraints(&w, &n, r);
        for mode in [Mode::Strict, Mode::Relaxed] {
            let ph = plan_of(&w, &c, mode, Cost::Heuristic, PLA).unwrap();
            let costs = cost::costs(&w.joints, &w.beams, &w.grounded, &ph.steps, &PLA, 1e-4);
            let (mut nonzero, mut above) = (0, 0);
            for (i, k) in costs.iter().enumerate() {
                assert!(
                    k.heuristic_load_mm <= k.exact_load_mm * (1.0 + 1e-9) + 1e-15,
                    "{file} {mode:?} step {i}: along the load, heuristic {} > exact {}",
                    k.heuristic_load_mm,
                    k.exact_load_mm
                );
                assert!(
                    k.heuristic_mm <= k.exact_mm * 1.1,
                    "{file} {mode:?} step {i}: heuristic ε {} more than 10 % over exact {}",
                    k.heuristic_mm,
                    k.exact_mm
                );
                above += usize::from(k.heuristic_mm > k.exact_mm * (1.0 + 1e-9));
                nonzero += usize::from(k.exact_mm > 0.0);
            }
            assert!(nonzero > w.beams.len() / 4, "{file}: {nonzero} steps with a cost");
            assert!(above * 20 <= nonzero, "{file} {mode:?}: heuristic ε above exact on {above} of {nonzero} states");
            // The plan's own record of ε is the heuristic measured again.
            for (s, k) in ph.steps.iter().zip(&costs) {
                assert!((s.cost_mm - k.heuristic_mm).abs() <= 1e-9 * k.heuristic_mm.max(1e-12), "{file}: planned ε {} against {}", s.cost_mm, k.heuristic_mm);
            }
            // Planned with the exact cost: its record is the exact cost measured again, and in
            // relaxed mode (a bottleneck greedy) its largest ε is the least of any order,
            // in particular at most the heuristic plan's.
            let pe = plan_of(&w, &c, mode, Cost::Exact, PLA).unwrap();
            let ce = cost::costs(&w.joints, &w.beams, &w.grounded, &pe.steps, &PLA, 1e-4);
            for (s, k) in pe.steps.iter().zip(&ce) {
                assert!((s.cost_mm - k.exact_mm).abs() <= 1e-6 * k.exact_mm.max(1e-12), "{file}: exact plan ε {} against {}", s.cost_mm, k.exact_mm);
            }
            let max = |v: &[cost::Costs]| v.iter().map(|k| k.exact_mm).fold(0.0, f64::max);
            if mode == Mode::Relaxed {
                assert!(max(&ce) <= max(&costs) * (1.0 + 1e-9), "{file}: exact greedy {} > heuristic plan's exact {}", max(&ce), max(&costs));
            }
        }
    }
}

#[test]
fn the_same_design_plans_the_same() {
    let w = fixture("duck.json");
    let c = constraints(&w, &nozzle(), 1.5);
    let a = plan_of(&w, &c, Mode::Strict, Cost::Exact, PLA).unwrap();
    let b = plan_of(&w, &c, Mode::Strict, Cost::Exact, PLA).unwrap();
    assert_eq!(a.steps, b.steps);
}

#[test]
fn a_tilting_nozzle_breaks_the_cycle_of_the_truss_and_every_tilted_step_checks() {
    // The conmech truss through the paper's 13° cone (radius 2, height 20): two near-vertical
    // beams at one joint each sweep the nozzle through the other, a cycle, on a 3-axis
    // machine. A head tilting up to 30° prints each of them leaning away from the other.
    let w = fixture("cantilever_beam_truss.json");
    let n = Nozzle { half_angle_deg: 13.0, radius_mm: 2.0, height_mm: 20.0 };
    let o = |tilt: f64| precedence::Options { nozzle: n, beam_radius_mm: 1.5, directionality: true, collision: true, tilt_deg: tilt };
    let vertical = precedence::constraints(&w.joints, &w.beams, &o(0.0), &mut |_| {}).unwrap();
    assert!(matches!(plan_of(&w, &vertical, Mode::Strict, Cost::Heuristic, PLA), Err(Unconstructable::Cycle { .. })));
    assert_eq!(vertical.tilted, 0);
    assert_eq!(vertical.vertical_pairs, vertical.pairs());
    let tilted = precedence::constraints(&w.joints, &w.beams, &o(30.0), &mut |_| {}).unwrap();
    assert!(
        tilted.tilted > 0 && tilted.pairs() < vertical.pairs() / 4,
        "{} beams tilted, {} precedences against {}",
        tilted.tilted,
        tilted.pairs(),
        vertical.pairs()
    );
    assert_eq!(tilted.vertical_pairs, vertical.pairs(), "the vertical count is the 3-axis one");
    // A beam keeps the vertical unless a tilt gains something, and no axis leans past 30°.
    for (b, t) in tilted.axis.iter().enumerate() {
        assert!(t.z >= 30f64.to_radians().cos() - 1e-12, "beam {b}: axis {t:?}");
        if *t == DVec3::Z {
            continue;
        }
        let hits_vertical = vertical.succs(b).len();
        let both_vertical = vertical.forward[b] && vertical.backward[b];
        assert!(tilted.succs(b).len() < hits_vertical || !both_vertical, "beam {b} tilted for nothing");
    }
    let p = plan_of(&w, &tilted, Mode::Strict, Cost::Heuristic, PLA).unwrap();
    let pairs = check(&w, &p.steps, &n, 1.5, true, &tilted, "truss tilted");
    assert!(pairs > 1000, "{pairs} pairs checked by sampling");
}

#[test]
fn a_descent_under_a_printed_roof_is_flagged_and_one_in_the_open_is_not() {
    use weft::freeform::deadhead::{self, Ordered};
    // A post at B with a beam over to above A, then a short post at A: lowering onto A passes
    // the printed beam 45 mm up, higher than the nozzle body (28.7 mm) reaches.
    let joints = vec![
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(10.0, 0.0, 0.0),
        DVec3::new(10.0, 0.0, 45.0),
        DVec3::new(0.0, 0.0, 45.0),
        DVec3::new(0.0, 0.0, 5.0),
        DVec3::new(30.0, 0.0, 0.0),
        DVec3::new(30.0, 0.0, 5.0),
    ];
    let beams = vec![[1, 2], [2, 3], [0, 4], [5, 6]];
    let step = |beam: usize, from: usize, to: usize| Step { beam, from, to, cost_mm: 0.0, block: 0 };
    let n = Nozzle::default();
    let safe = 45.0 + 1.5 + 1.0;
    let under =
        Ordered { steps: vec![step(0, 1, 2), step(1, 2, 3), step(2, 0, 4)], safe_z: vec![f64::NAN, safe, safe], deadhead_s: 0.0, plan_order_deadhead_s: 0.0 };
    assert_eq!(deadhead::blocked(&joints, &beams, &[], &under, n.radius_mm, n.top(), 1.5), (vec![2], 0));
    // The same post printed first, or a post away from the roof: clear.
    let first = Ordered {
        steps: vec![step(2, 0, 4), step(0, 1, 2), step(1, 2, 3)],
        safe_z: vec![f64::NAN, 5.0 + 2.5, safe],
        deadhead_s: 0.0,
        plan_order_deadhead_s: 0.0,
    };
    assert!(deadhead::blocked(&joints, &beams, &[], &first, n.radius_mm, n.top(), 1.5).0.is_empty());
    let away =
        Ordered { steps: vec![step(0, 1, 2), step(1, 2, 3), step(3, 5, 6)], safe_z: vec![f64::NAN, safe, safe], deadhead_s: 0.0, plan_order_deadhead_s: 0.0 };
    assert!(deadhead::blocked(&joints, &beams, &[], &away, n.radius_mm, n.top(), 1.5).0.is_empty());
    // A tilted beam's deadheads are skipped (the column is for an upright nozzle).
    let tilted = vec![DVec3::Z, DVec3::Z, DVec3::new(0.5, 0.0, 0.75f64.sqrt()), DVec3::Z];
    assert_eq!(deadhead::blocked(&joints, &beams, &tilted, &under, n.radius_mm, n.top(), 1.5), (vec![], 1));
}

#[test]
fn a_plan_sends_a_beginning_it_keeps_and_the_deadhead_order_prints_it_first_as_sent() {
    let n = nozzle();
    let r = PLA.diameter_mm / 2.0;
    let dead = deadhead::Options { xy_mm_s: 150.0, z_mm_s: 10.0, clearance_mm: 1.0, beam_radius_mm: r };
    for (file, mode) in [
        ("voronoi_S1_03-14-2019_w_layer.json", Mode::Strict),
        ("klein_bottle.json", Mode::Relaxed),
        ("duck.json", Mode::Strict),
        ("semi_sphere.json", Mode::Relaxed),
    ] {
        let w = fixture(file);
        let c = constraints(&w, &n, r);
        let a = Assembly { joints: &w.joints, beams: &w.beams, grounded: &w.grounded, constraints: &c };
        let o = plan::Options { mode, cost: Cost::Exact, connection: true, section: PLA, load_n: 1e-4, budget_s: 600.0 };
        let whole = plan::plan(&a, &o, &mut |_, _| {}).unwrap();
        let m = w.beams.len();
        for send_at in [1, m / 3, m - 1] {
            let label = format!("{file} {mode:?}, sent at {send_at}");
            let mut sent: Vec<Plan> = Vec::new();
            let p = plan::plan_sending(&a, &o, send_at, &mut |_, _| {}, &mut |s| sent.push(s.clone())).unwrap();
            assert_eq!(sent.len(), 1, "{label}: sent once");
            let head = &sent[0];
            assert!(head.steps.len() >= send_at && head.steps.len() < m, "{label}: {} sent", head.steps.len());
            assert_eq!(p.sent, head.steps.len(), "{label}");
            // Sending changes nothing of the plan: what was sent is its beginning.
            assert_eq!(p.steps, whole.steps, "{label}: the same plan");
            assert_eq!(head.steps[..], p.steps[..p.sent], "{label}");
            // The order prints what was sent first, in the order it was sent, and still checks.
            let alone = deadhead::order(&w.joints, head, &c, &dead);
            let all = deadhead::order(&w.joints, &p, &c, &dead);
            assert_eq!(all.steps[..p.sent], alone.steps[..], "{label}: sent first, as sent");
            assert!(all.safe_z[..p.sent].iter().zip(&alone.safe_z).all(|(a, b)| a.to_bits() == b.to_bits()), "{label}: the same deadheads");
            check(&w, &all.steps, &n, r, mode == Mode::Strict, &c, &label);
        }
    }
}

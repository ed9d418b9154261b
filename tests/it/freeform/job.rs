//! The `freeform` job end to end (issue 13): every freeform example runs, and its G-code, read
//! back by the analyzer, prints every beam exactly once as its own extrusion path along the
//! beam, with the filament of the beam's section per mm, at the beam speed; deadheads rise
//! above everything printed before; the sequence G-code follows is the one the report states;
//! unconstructable designs are refused in words that name the beams; the same design gives the
//! same bytes; a wireframe given as a file gives the bytes of the same file embedded.

use weft::design::{Design, Input};
use weft::geom::DVec3;
use weft::pipeline::{self, Files};

use crate::common::{example, root, run};

/// Reads a run back: each extruding segment matched to a beam of the placed design.
fn read_back(name: &str, d: &Design) {
    let out = run(d, &Files::new()).unwrap_or_else(|e| panic!("{name}: {e}"));
    let pv = out.preview.as_ref().unwrap();
    let order: Vec<[usize; 3]> = serde_json::from_value(out.report.stage_data("order").unwrap()["sequence"].clone()).unwrap();
    let beams = order.len();
    assert_eq!(out.report.analysis.extrusion_paths, beams, "{name}: one extrusion path per beam");
    let job = &d.job.value;
    let diameter = job["beam"]["diameter_mm"].as_f64().unwrap_or(weft::kinds::freeform::DEFAULT_BEAM_DIAMETER_MM);
    let speed = job["print"]["speed_mm_s"].as_f64().unwrap_or(weft::kinds::freeform::DEFAULT_SPEED_MM_S);
    let fd = d.printer.filament_diameter_mm;
    let nominal = diameter * diameter / (fd * fd) * d.material.extrusion_multiplier;
    // Segments by path: every path is one straight beam, printed once, in the stated order.
    let mut paths: Vec<(DVec3, DVec3, f64)> = vec![(DVec3::ZERO, DVec3::ZERO, 0.0); beams];
    let mut first = vec![true; beams];
    for (i, s) in pv.positions.chunks_exact(6).enumerate() {
        let p = pv.path[i] as usize;
        let (a, b) = (DVec3::new(s[0] as f64, s[1] as f64, s[2] as f64), DVec3::new(s[3] as f64, s[4] as f64, s[5] as f64));
        let len = a.distance(b);
        if first[p] {
            paths[p].0 = a;
            first[p] = false;
        }
        paths[p].1 = b;
        paths[p].2 += len;
        if len > 1e-3 {
            let e = pv.e_per_mm[i] as f64;
            assert!((e - nominal).abs() <= 2e-3 * nominal + 1e-6, "{name}: path {p} feeds {e} mm/mm, the section asks {nominal}");
            assert!((pv.speed[i] as f64 - speed).abs() <= 1e-3 * speed + 1e-3, "{name}: path {p} at {} mm/s, not {speed}", pv.speed[i]);
        }
    }
    // The report's joints, placed as the G-code has them (the bed's centre added).
    let (cx, cy) = (d.printer.bed_size_mm[0] / 2.0, d.printer.bed_size_mm[1] / 2.0);
    let joint_of = |q: DVec3| DVec3::new(q.x - cx, q.y - cy, q.z);
    let mut seen = std::collections::BTreeSet::new();
    let mut top = f64::NEG_INFINITY;
    for (k, &(a, b, len)) in paths.iter().enumerate() {
        let [beam, _from, _to] = order[k];
        assert!(seen.insert(beam), "{name}: beam {beam} printed twice");
        assert!((a.distance(b) - len).abs() <= 1e-3 * len.max(1.0), "{name}: path {k} is not one straight beam ({len} mm along, {} apart)", a.distance(b));
        let _ = joint_of(a);
        top = top.max(a.z).max(b.z);
    }
    assert_eq!(seen.len(), beams, "{name}: every beam once");
    // Deadheads: each travel before a beam passes above every beam printed before it.
    let mut printed_top = f64::NEG_INFINITY;
    let mut by_layer = 0;
    for l in 0..pv.layer_z.len() {
        let (t0, t1) = (pv.layer_travel_start[l] as usize, pv.layer_travel_start[l + 1] as usize);
        if l > 0 && t1 > t0 {
            let highest = pv.travel_positions[t0 * 6..t1 * 6].chunks_exact(6).map(|s| s[2].max(s[5]) as f64).fold(f64::NEG_INFINITY, f64::max);
            assert!(
                highest >= printed_top + diameter / 2.0 - 1e-3,
                "{name}: the deadhead before beam {l} peaks at z {highest}, below the printed top {printed_top}"
            );
            by_layer += 1;
        }
        let (s0, s1) = (pv.layer_segment_start[l] as usize, pv.layer_segment_start[l + 1] as usize);
        for s in pv.positions[s0 * 6..s1 * 6].chunks_exact(6) {
            printed_top = printed_top.max(s[2] as f64).max(s[5] as f64);
        }
    }
    assert!(by_layer + 1 >= beams.min(pv.layer_z.len()), "{name}: {by_layer} deadheads for {beams} beams");
    let _ = top;
}

#[test]
fn every_freeform_example_prints_each_beam_once_at_its_section_and_speed() {
    let mut names: Vec<String> = std::fs::read_dir(root().join("examples"))
        .unwrap()
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|n| n.starts_with("freeform-") && n.ends_with(".json"))
        .map(|n| n.trim_end_matches(".json").to_string())
        .collect();
    names.sort();
    assert!(names.len() >= 13, "{names:?}");
    for name in names {
        // The big truss is read back by the CLI test; here the rest, with every constraint.
        if name == "freeform-cantilever-truss" {
            continue;
        }
        read_back(&name, &example(&name));
    }
}

#[test]
fn unconstructable_designs_are_refused_naming_the_beams() {
    // The conmech truss through the default 13° cone: two near-vertical beams at one joint.
    let mut d = example("freeform-cantilever-truss");
    d = d.with_overrides(&[r#"job.nozzle={"half_angle_deg": 13, "radius_mm": 2, "height_mm": 20}"#.to_string()]).unwrap();
    let e = run(&d, &Files::new()).unwrap_err();
    assert!(e.contains("cannot be printed in this orientation") && e.contains("element 827") && e.contains("element 1149"), "{e}");
    // The tower without its grounded joints marked as such: every joint grounded by file → the
    // lowest; a lifted wireframe with a strut that touches nothing printable.
    let csv = "x1,y1,z1,x2,y2,z2\n0,0,0,0,0,5\n0,0,5,5,0,5\n5,0,5,5,0,0\n5,0,5,7,1,5.2\n5,0,5,7,-1,5.2\n";
    let mut files = Files::new();
    files.insert("two-struts.csv".into(), csv.as_bytes().to_vec());
    let d = Design::from_json("t", r#"{"version":1,"name":"two struts","job":{"kind":"freeform","input":{"file":{"name":"two-struts.csv"}}}}"#).unwrap();
    let e = run(&d, &files).unwrap_err();
    assert!(e.contains("two cantilevers") && e.contains("line 5") && e.contains("line 6"), "{e}");
    let relaxed = d.with_overrides(&["job.constraints.cantilever=relaxed".to_string()]).unwrap();
    let out = run(&relaxed, &files).unwrap();
    assert_eq!(out.report.analysis.extrusion_paths, 5);
}

#[test]
fn a_file_gives_the_bytes_of_the_same_file_embedded_and_runs_repeat() {
    let d = example("freeform-four-frame");
    let embedded = run(&d, &Files::new()).unwrap();
    let again = run(&d, &Files::new()).unwrap();
    assert_eq!(embedded.gcode, again.gcode, "the same design gives the same bytes");
    let bytes = std::fs::read(root().join("tests/fixtures/wireframes/four-frame.json")).unwrap();
    let mut files = Files::new();
    files.insert("four-frame.json".into(), bytes);
    let mut loaded = d.clone();
    loaded.job.value["input"] = serde_json::to_value(Input::File { name: "four-frame.json".into(), embedded: None }).unwrap();
    let from_file = run(&loaded, &files).unwrap();
    assert_eq!(embedded.gcode, from_file.gcode);
    // The sequence view scrubs the steps: the current beam, printed ones before it.
    let mut cache = pipeline::Cache::new();
    let reg = weft::kinds::Registry::builtin();
    let v = pipeline::inspect(&reg, &mut cache, &d, &Files::new(), "sequence", 2).unwrap();
    assert_eq!((v.count, v.index), (4, 2));
    let codes: Vec<u32> = v.data.chunks_exact(7).map(|s| s[6] as u32).collect();
    let current = weft::geom::Feature::ExternalPerimeter.code() as u32;
    assert_eq!(codes.iter().filter(|&&c| c == current).count(), 1, "{codes:?}");
    assert_eq!(codes.iter().filter(|&&c| c == weft::geom::Feature::Handle.code() as u32).count(), 1, "one beam still to print: {codes:?}");
}

#[test]
fn the_exact_search_proves_the_least_largest_eps_and_prints_it_when_asked() {
    let d = example("freeform-dome-exact");
    let out = run(&d, &Files::new()).unwrap();
    let stage = |name: &str| out.report.stages.iter().find(|s| s.stage == name).unwrap_or_else(|| panic!("no {name} stage"));
    let metric = |name: &str, key: &str| stage(name).metrics.iter().find(|m| m.key == key).map(|m| m.value).unwrap_or_else(|| panic!("no {name}.{key}"));
    let opt = out.report.stage_data("optimum").unwrap();
    assert_eq!(opt["proven"], true, "{opt}");
    let (best, planner) = (opt["best_um"].as_f64().unwrap(), opt["planner_um"].as_f64().unwrap());
    assert!(best < planner * 0.95, "the heuristic planner's {planner} µm against the optimum {best} µm");
    assert!(stage("optimum").label.contains("better sequence (printed)"), "{}", stage("optimum").label);
    assert!(stage("optimum").plots.iter().any(|p| p.key == "optimum_sequence"));
    // What is printed is the search's sequence: its exact ε, measured again, is the optimum.
    assert!((metric("costs", "max_exact") - best).abs() <= 1e-9 * best, "printed {} µm, optimum {best} µm", metric("costs", "max_exact"));
    // Compared only: the planner's sequence is printed, and measures what the search said.
    let compare = d.with_overrides(&["job.planner.exact_search=compare".to_string()]).unwrap();
    let out2 = run(&compare, &Files::new()).unwrap();
    let printed = out2.report.stages.iter().find(|s| s.stage == "costs").unwrap().metrics.iter().find(|m| m.key == "max_exact").unwrap().value;
    assert!((printed - planner).abs() <= 1e-9 * planner, "{printed} against {planner}");
    assert_ne!(out.gcode, out2.gcode);
    // Off: no search, the planner's bytes.
    let off = d.with_overrides(&["job.planner.exact_search=off".to_string()]).unwrap();
    let out3 = run(&off, &Files::new()).unwrap();
    assert!(out3.report.stage_data("optimum").is_none());
    assert_eq!(out2.gcode, out3.gcode);
    // A design too big for it says so.
    let big = run(&example("freeform-tower"), &Files::new()).unwrap();
    let label = &big.report.stages.iter().find(|s| s.stage == "optimum").unwrap().label;
    assert!(label.contains("not run (116 beams, more than 32)"), "{label}");
}

#[test]
fn where_the_planner_finds_no_subassembly_the_exact_search_decides() {
    // Random frame 22 of the search's tests, written out: the planner's paths cannot close it,
    // an order exists. As a CSV of beams on a freeform job.
    let csv = std::fs::read_to_string(root().join("tests/fixtures/freeform-planner-gives-up.csv")).unwrap();
    let mut files = Files::new();
    files.insert("frame.csv".into(), csv.into_bytes());
    let d = Design::from_json("t", r#"{"version":1,"name":"gives up","job":{"kind":"freeform","input":{"file":{"name":"frame.csv"}},"nozzle":{"half_angle_deg":13,"radius_mm":0.5,"height_mm":5}}}"#).unwrap();
    let out = run(&d, &files).unwrap();
    let label = &out.report.stages.iter().find(|s| s.stage == "optimum").unwrap().label;
    assert!(label.contains("the planner found none"), "{label}");
    let beams = csv_lines(&std::fs::read_to_string(root().join("tests/fixtures/freeform-planner-gives-up.csv")).unwrap());
    assert_eq!(out.report.analysis.extrusion_paths, beams);
    let off = d.with_overrides(&["job.planner.exact_search=off".to_string()]).unwrap();
    let e = run(&off, &files).unwrap_err();
    assert!(e.contains("no consistent subassembly"), "{e}");
}

fn csv_lines(text: &str) -> usize {
    text.lines().skip(1).filter(|l| !l.trim().is_empty()).count()
}

#[test]
fn a_tilting_head_prints_the_truss_a_3_axis_printer_cannot() {
    let d = example("freeform-cantilever-truss-tilt");
    let out = run(&d, &Files::new()).unwrap();
    assert_eq!(out.report.analysis.extrusion_paths, 2197);
    let c = out.report.stages.iter().find(|s| s.stage == "constraints").unwrap();
    let metric = |k: &str| c.metrics.iter().find(|m| m.key == k).unwrap().value;
    assert!(
        metric("tilted") > 1000.0 && metric("pairs") * 4.0 < metric("vertical_pairs"),
        "{} tilted, {} of {} precedences",
        metric("tilted"),
        metric("pairs"),
        metric("vertical_pairs")
    );
    // Tilted beams are written with their rotary words (a head-head B C machine).
    assert!(out.gcode.lines().any(|l| l.starts_with("G1 ") && l.contains(" B30")), "no B30 in the G-code");
    // The sequence view names a tilted step's tilt.
    let mut cache = pipeline::Cache::new();
    let reg = weft::kinds::Registry::builtin();
    let captions: Vec<String> = (0..6)
        .map(|i| pipeline::inspect(&reg, &mut cache, &d, &Files::new(), "sequence", i).unwrap().meta["caption"].as_str().unwrap_or("").to_string())
        .collect();
    assert!(captions.iter().any(|c| c.contains("nozzle tilted")), "{captions:?}");
    // The same nozzle on a 3-axis printer: the tilt is refused where it is set, and without
    // the tilt the design is refused with its cycle.
    let flat = d.with_overrides(&["printer.machine.kind=cartesian".to_string()]);
    let e = match flat {
        Err(e) => e.to_string(),
        Ok(f) => run(&f, &Files::new()).unwrap_err(),
    };
    assert!(e.contains("needs a 5-axis machine"), "{e}");
    let vertical = d.with_overrides(&["job.nozzle.tilt_deg=0".to_string()]).unwrap();
    let e = run(&vertical, &Files::new()).unwrap_err();
    assert!(e.contains("cannot be printed in this orientation"), "{e}");
}

#[test]
fn a_tower_planned_in_bands_reports_the_cost_of_its_joins() {
    let d = example("freeform-tower-bands");
    let out = run(&d, &Files::new()).unwrap();
    let metric = |st: &str, key: &str| out.report.stages.iter().find(|s| s.stage == st).and_then(|s| s.metrics.iter().find(|m| m.key == key)).map(|m| m.value);
    let bands = metric("plan", "bands").unwrap();
    assert!(bands >= 3.0, "{bands} bands");
    let (planned, measured, join) =
        (metric("costs", "band_planned").unwrap(), metric("costs", "band_measured").unwrap(), metric("costs", "band_join").unwrap());
    assert!(planned > 0.0 && measured > 0.0 && join > 0.0, "planned {planned}, measured {measured}, joins {join} µm");
    let costs = out.report.stages.iter().find(|s| s.stage == "costs").unwrap();
    let plot = costs.plots.iter().find(|p| p.key == "bands").unwrap();
    assert_eq!(plot.series[0].y.len() as f64, bands);
    // Whole, the same design plans the same beams (another order).
    let whole = run(&d.with_overrides(&["job.planner.band_beams=0".to_string()]).unwrap(), &Files::new()).unwrap();
    assert_eq!(whole.report.analysis.extrusion_paths, out.report.analysis.extrusion_paths);
    assert!(metric("plan", "bands").is_some() && whole.report.stages.iter().find(|s| s.stage == "plan").unwrap().metrics.iter().all(|m| m.key != "bands"));
}

#[test]
fn the_cost_replay_stops_at_its_budget_and_says_where() {
    use weft::freeform::{cost, frame::Section, models, plan, precedence};
    let w = models::build(&models::Model::Tower { cells: 2, levels: 4, cell_mm: 3.0, level_mm: 3.0, taper: 0.7 });
    let c = precedence::constraints(
        &w.joints,
        &w.beams,
        &precedence::Options {
            nozzle: precedence::Nozzle { half_angle_deg: 13.0, radius_mm: 0.5, height_mm: 5.0 },
            beam_radius_mm: 0.075,
            directionality: true,
            collision: true,
            tilt_deg: 0.0,
        },
        &mut |_| {},
    )
    .unwrap();
    let s = Section { diameter_mm: 0.15, e_mpa: 2600.0, g_mpa: 1100.0 };
    let a = plan::Assembly { joints: &w.joints, beams: &w.beams, grounded: &w.grounded, constraints: &c };
    let p = plan::plan(
        &a,
        &plan::Options { mode: plan::Mode::Strict, cost: plan::Cost::Exact, connection: true, section: s, load_n: 1e-4, budget_s: 60.0 },
        &mut |_, _| {},
    )
    .unwrap();
    let all = cost::costs(&w.joints, &w.beams, &w.grounded, &p.steps, &s, 1e-4);
    let (within, stopped) = cost::costs_within(&w.joints, &w.beams, &w.grounded, &p.steps, &s, 1e-4, f64::INFINITY);
    assert_eq!((within.len(), stopped), (all.len(), None));
    let (cut, stopped) = cost::costs_within(&w.joints, &w.beams, &w.grounded, &p.steps, &s, 1e-4, 20_000.0);
    let k = stopped.expect("a small budget stops the replay");
    assert!(k > 0 && k < all.len(), "stopped at {k}");
    assert!(cut[..k].iter().zip(&all).all(|(a, b)| a.exact_mm.to_bits() == b.exact_mm.to_bits()), "the measured steps are the full replay's");
    assert!(cut[k..].iter().all(|c| c.exact_mm.is_nan() && c.heuristic_mm.is_nan()));
}

#[test]
fn weft_models_deadhead_clear_of_printed_beams_and_the_order_card_counts_those_that_do_not() {
    for name in ["freeform-tower", "freeform-dome", "freeform-bridge"] {
        let out = run(&example(name), &Files::new()).unwrap();
        let order = out.report.stages.iter().find(|s| s.stage == "order").unwrap();
        let blocked = order.metrics.iter().find(|m| m.key == "blocked").unwrap().value;
        assert_eq!(blocked, 0.0, "{name}: {}", order.label);
    }
    // The klein bottle's PLA frame under the default nozzle: some deadheads pass printed
    // beams above the body (the body's height is the fix), and the card says so.
    let out = run(&example("freeform-klein-bottle"), &Files::new()).unwrap();
    let order = out.report.stages.iter().find(|s| s.stage == "order").unwrap();
    let blocked = order.metrics.iter().find(|m| m.key == "blocked").unwrap().value;
    assert!(blocked > 0.0 && order.label.contains("pass through printed beams"), "{blocked}: {}", order.label);
}

/// G-code from its first move (`;LAYER_CHANGE`) on, without the trailer of a file sent ahead.
fn moves(text: &str) -> &str {
    let from = text.find(";LAYER_CHANGE").expect("moves");
    let to = text.rfind("; weft: ").filter(|&i| i > from).unwrap_or(text.len());
    &text[from..to]
}

#[test]
fn the_first_beams_are_sent_ahead_and_the_final_gcode_begins_with_their_moves() {
    use std::cell::RefCell;
    use weft::kinds::Registry;
    use weft::pipeline::{Ahead, Cache, RunOptions};
    for name in ["freeform-voronoi", "freeform-klein-bottle-relaxed", "freeform-cantilever-truss-tilt"] {
        let d = example(name);
        let sent: RefCell<Vec<Ahead>> = RefCell::new(Vec::new());
        let out = pipeline::run_sending(&Registry::builtin(), &mut Cache::disabled(), &d, &Files::new(), &RunOptions::default(), &mut |_, _| {}, &|a| {
            sent.borrow_mut().push(a.clone())
        })
        .unwrap();
        let sent = sent.into_inner();
        assert_eq!(sent.len(), 1, "{name}: sent once");
        let a = &sent[0];
        let beams = out.report.analysis.extrusion_paths;
        assert!(
            a.done >= weft::freeform::plan::DEFAULT_SEND_AHEAD_BEAMS && a.done < beams && a.total == beams,
            "{name}: {} of {} sent, {beams} beams",
            a.done,
            a.total
        );
        let plan = out.report.stages.iter().find(|s| s.stage == "plan").unwrap();
        assert_eq!(plan.metrics.iter().find(|m| m.key == "sent").map(|m| m.value), Some(a.done as f64), "{name}: the plan card says how many");
        // The file sent is G-code of exactly those beams, and the final file's moves begin with its.
        let options = weft::analyze::Options { machine: d.printer.machine.clone(), filament_diameter_mm: d.printer.filament_diameter_mm, ..Default::default() };
        let read = weft::analyze::analyze("ahead.gcode", a.gcode.as_bytes(), &options).unwrap().report;
        assert_eq!(read.extrusion_paths, a.done, "{name}: the beams sent");
        let (head, all) = (moves(&a.gcode), moves(&out.gcode));
        assert!(head.len() > 1000 && all.starts_with(head), "{name}: the final G-code's moves begin with those sent");
        assert!(!a.gcode.contains(d.printer.end_gcode.lines().next().unwrap_or("M84")), "{name}: no end code in a file the plan goes on from");
        // Listening changes nothing: the same bytes as a run nobody listens to.
        assert_eq!(run(&d, &Files::new()).unwrap().gcode, out.gcode, "{name}");
    }
    // A plan taken from the cache (a view asked for first, an earlier run) is sent as well,
    // the same bytes as when it was planned.
    let d = example("freeform-voronoi");
    let mut cache = Cache::new();
    let got: RefCell<Vec<Ahead>> = RefCell::new(Vec::new());
    for _ in 0..2 {
        pipeline::run_sending(&Registry::builtin(), &mut cache, &d, &Files::new(), &RunOptions::default(), &mut |_, _| {}, &|a| {
            got.borrow_mut().push(a.clone())
        })
        .unwrap();
    }
    let got = got.into_inner();
    assert_eq!(got.len(), 2);
    assert_eq!(got[0], got[1], "sent from the cache as when planned");
    // Planned in bands (a band may be planned again) nothing is sent.
    let sent = RefCell::new(0);
    pipeline::run_sending(
        &Registry::builtin(),
        &mut Cache::disabled(),
        &example("freeform-tower-bands"),
        &Files::new(),
        &RunOptions::default(),
        &mut |_, _| {},
        &|_| *sent.borrow_mut() += 1,
    )
    .unwrap();
    assert_eq!(sent.into_inner(), 0);
}

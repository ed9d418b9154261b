//! The lattice and freeform step views draw what they say, checked against the run's own
//! report and against each other: the odd-node marks are the graph's odd nodes, the pairing
//! has half as many lines, the GIPPO replay rises to the run's score within its frame cap,
//! the kept paths are the report's classes, the toolpath extrudes every strut once, and every
//! freeform precedence points from an earlier beam to a later one.

use crate::common::example;
use weft::design::Design;
use weft::kinds::Registry;
use weft::paths::{PathsReport, REPLAY_MAX_BYTES, REPLAY_MAX_FRAMES};
use weft::pipeline::{self, Cache, Files, RunOptions};

/// The feature code a view's legend gives to `words` exactly, else to the words containing them.
fn code(meta: &serde_json::Value, words: &str) -> f32 {
    let legend = meta["legend"].as_object().expect("a legend");
    let text = |v: &serde_json::Value| v.as_str().unwrap_or("").to_string();
    let (k, _) = legend
        .iter()
        .find(|(_, v)| text(v) == words)
        .or_else(|| legend.iter().find(|(_, v)| text(v).contains(words)))
        .unwrap_or_else(|| panic!("no {words:?} in {legend:?}"));
    k.parse().unwrap()
}

/// Items of `data` (stride `stride`, code last) with code `c`.
fn with_code(data: &[f32], stride: usize, c: f32) -> Vec<&[f32]> {
    data.chunks(stride).filter(|s| s[stride - 1] == c).collect()
}

/// A run of `design` into `cache`, and its paths report.
fn run_lattice(design: &Design, cache: &mut Cache) -> PathsReport {
    let out = pipeline::run_in(&Registry::builtin(), cache, design, &Files::new(), &RunOptions::default(), &mut |_, _| {}).unwrap();
    out.report.stage::<PathsReport>("paths").expect("a paths report")
}

fn inspect(cache: &mut Cache, design: &Design, view: &str, index: usize) -> weft::kinds::Inspection {
    pipeline::inspect(&Registry::builtin(), cache, design, &Files::new(), view, index).unwrap_or_else(|e| panic!("{view} at {index}: {e}"))
}

#[test]
fn the_graph_marks_the_odd_nodes_and_the_pairing_joins_them_two_by_two() {
    for name in ["honeycomb-10mm", "voronoi-10mm"] {
        let design = example(name);
        let mut cache = Cache::new();
        let report = run_lattice(&design, &mut cache);
        let layer = &report.layers[0];
        let g = inspect(&mut cache, &design, "graph", 0);
        let odd = with_code(&g.data, 5, code(&g.meta, "odd")).len();
        let even = with_code(&g.data, 5, code(&g.meta, "even")).len();
        // Two strokes a mark.
        assert_eq!(odd, 2 * layer.odd_nodes, "{name}");
        assert_eq!(odd / 2 + even / 2, layer.nodes, "{name}");
        assert_eq!(g.meta["odd_nodes"], layer.odd_nodes);
        assert_eq!(with_code(&g.data, 5, code(&g.meta, "strut")).len(), layer.edges, "{name}: straight struts, one segment each");
        assert!(layer.odd_nodes > 0, "{name}");

        let p = inspect(&mut cache, &design, "pairing", 0);
        let lines = with_code(&p.data, 5, code(&p.meta, "pairing line"));
        assert_eq!(lines.len(), layer.odd_nodes / 2, "{name}");
        assert_eq!(p.meta["pairs"], layer.odd_nodes / 2);
        // Every odd node is the end of exactly one pairing line.
        let mut ends: Vec<(u32, u32)> = lines.iter().flat_map(|s| [(s[0].to_bits(), s[1].to_bits()), (s[2].to_bits(), s[3].to_bits())]).collect();
        ends.sort_unstable();
        let n = ends.len();
        ends.dedup();
        assert_eq!(ends.len(), n, "{name}: a node paired twice");
        let length: f64 = lines.iter().map(|s| ((s[2] - s[0]) as f64).hypot((s[3] - s[1]) as f64)).sum();
        assert!((length - p.meta["pairing_mm"].as_f64().unwrap()).abs() < 1e-3, "{name}: {length}");
        assert_eq!(p.meta["lower_bound_paths"], layer.lower_bound_paths);
        assert!(layer.paths >= layer.lower_bound_paths);
    }
}

#[test]
fn the_gippo_replay_rises_to_the_runs_score_within_its_cap() {
    let design = example("honeycomb-10mm");
    let mut cache = Cache::new();
    let report = run_lattice(&design, &mut cache);
    let first = inspect(&mut cache, &design, "gippo", 0);
    let frames = first.count;
    let cap = first.meta["cap"].as_u64().unwrap() as usize;
    let bytes = first.meta["recorded_bytes"].as_u64().unwrap() as usize;
    eprintln!("honeycomb-10mm GIPPO replay: {frames} frames (cap {cap}), {bytes} bytes, {} improvements", first.meta["improvements"]);
    assert!(frames >= 2 && frames <= cap && cap <= REPLAY_MAX_FRAMES, "{frames} frames, cap {cap}");
    assert_eq!(first.meta["frames"], frames);
    assert!(bytes > 0 && bytes <= REPLAY_MAX_BYTES);
    let li = first.meta["layer"].as_u64().unwrap() as usize;
    let layer = &report.layers[li];
    assert_eq!(first.meta["iteration"], 1, "the first frame is the first iteration");
    let edges = inspect(&mut cache, &design, "graph", li).meta["edges"].as_u64().unwrap() as usize;
    let mut last = f64::NEG_INFINITY;
    for i in 0..frames {
        let f = inspect(&mut cache, &design, "gippo", i);
        let score = f.meta["score"].as_f64().unwrap();
        let iteration = f.meta["iteration"].as_u64().unwrap() as usize;
        assert!(score > last, "frame {i}: {score} after {last}");
        last = score;
        // Each frame is an improvement the run scored: its iteration's score, above all before it.
        assert_eq!(layer.iteration_scores[iteration - 1], score, "frame {i} at iteration {iteration}");
        assert!(layer.iteration_scores[..iteration - 1].iter().all(|&s| s < score), "frame {i}");
        // Every strut once.
        assert_eq!(f.data.len() / 5, edges, "frame {i}");
        assert!(f.meta["caption"].as_str().unwrap().contains(&format!("iteration {iteration} of 500")), "{}", f.meta["caption"]);
    }
    assert_eq!(last, layer.score, "the last frame is the run's solution");
    let paths = inspect(&mut cache, &design, "gippo", frames - 1).meta["paths"].as_u64().unwrap() as usize;
    assert_eq!(paths, layer.paths);
}

#[test]
fn the_kept_paths_the_order_and_the_toolpath_agree_with_the_run() {
    let design = example("honeycomb-10mm");
    let mut cache = Cache::new();
    let report = run_lattice(&design, &mut cache);
    let layer = &report.layers[0];
    let t = inspect(&mut cache, &design, "trails", 0);
    assert_eq!(t.meta["paths"], layer.paths);
    assert_eq!(
        (t.meta["long"].as_u64().unwrap(), t.meta["medium"].as_u64().unwrap(), t.meta["short"].as_u64().unwrap()),
        (layer.long_paths as u64, layer.medium_paths as u64, layer.short_paths as u64)
    );
    assert!((t.meta["score"].as_f64().unwrap() - layer.score).abs() < 1e-9, "{} against {}", t.meta["score"], layer.score);

    // Print order: one frame a path; the last has nothing left to print and the layer's travel.
    let total: usize = report.layers.iter().map(|l| l.paths).sum();
    let o = inspect(&mut cache, &design, "order", 0);
    assert_eq!(o.count, total);
    assert!(!with_code(&o.data, 5, code(&o.meta, "printing now")).is_empty());
    let end = inspect(&mut cache, &design, "order", total - 1);
    assert!(with_code(&end.data, 5, code(&end.meta, "still to print")).is_empty());
    assert!((end.meta["travel_mm"].as_f64().unwrap() - layer.travel_mm).abs() < 1e-6, "{} against {}", end.meta["travel_mm"], layer.travel_mm);

    // The toolpath extrudes every strut once and slows the short paths.
    let g = inspect(&mut cache, &design, "gcode", 0);
    let graph = inspect(&mut cache, &design, "graph", 0);
    let strut = code(&graph.meta, "strut");
    let strut_mm: f64 = with_code(&graph.data, 5, strut).iter().map(|s| ((s[2] - s[0]) as f64).hypot((s[3] - s[1]) as f64)).sum();
    assert!((g.meta["extruded_mm"].as_f64().unwrap() - strut_mm).abs() < 1e-3, "{} against {strut_mm}", g.meta["extruded_mm"]);
    assert_eq!(g.meta["paths"], layer.paths);
    assert!((g.meta["travel_mm"].as_f64().unwrap() - layer.travel_mm).abs() < 1e-6);
    let short = design.job.value["paths"]["short_path_segments"].as_u64().unwrap() as usize;
    assert_eq!(short, 4);
    // The short class is under 5 nodes, i.e. under 4 segments: the paths slowed.
    assert_eq!(g.meta["slowed"], layer.short_paths);
}

#[test]
fn every_freeform_precedence_points_to_a_later_beam() {
    let design = example("freeform-bridge");
    let mut cache = Cache::new();
    let beams = inspect(&mut cache, &design, "beams", 0);
    let m = beams.meta["beams"].as_u64().unwrap() as usize;
    let drawn = with_code(&beams.data, 7, code(&beams.meta, "beam standing")).len() + with_code(&beams.data, 7, code(&beams.meta, "beam")).len();
    assert_eq!(drawn, m);
    assert!(beams.meta["grounded"].as_u64().unwrap() > 0);
    // The build order, from the sequence view: the beam printing now at each step.
    let seq = inspect(&mut cache, &design, "sequence", 0);
    assert_eq!(seq.count, m);
    let mut step_of: Vec<([f32; 3], usize)> = Vec::new();
    for i in 0..m {
        let s = inspect(&mut cache, &design, "sequence", i);
        let now = with_code(&s.data, 7, code(&s.meta, "printing now"));
        assert_eq!(now.len(), 1, "step {i}");
        let b = now[0];
        step_of.push(([(b[0] + b[3]) / 2.0, (b[1] + b[4]) / 2.0, (b[2] + b[5]) / 2.0], i));
        assert!(s.meta["caption"].as_str().unwrap().starts_with(&format!("step {} of {m}: ", i + 1)));
    }
    let step_at = |x: f32, y: f32, z: f32| -> Option<usize> {
        let near: Vec<usize> =
            step_of.iter().filter(|(p, _)| (p[0] - x).abs() < 1e-4 && (p[1] - y).abs() < 1e-4 && (p[2] - z).abs() < 1e-4).map(|(_, s)| *s).collect();
        (near.len() == 1).then(|| near[0])
    };
    let p = inspect(&mut cache, &design, "precedence", 0);
    let arrows = p.meta["collision"].as_u64().unwrap() + p.meta["path"].as_u64().unwrap();
    assert!(arrows > 0, "{}", p.meta["caption"]);
    let mut checked = 0;
    for c in [code(&p.meta, "collision"), code(&p.meta, "path from its root")] {
        for s in with_code(&p.data, 7, c) {
            // Shafts join two beams' middles (the arrowheads do not).
            let (Some(a), Some(b)) = (step_at(s[0], s[1], s[2]), step_at(s[3], s[4], s[5])) else { continue };
            assert!(a < b, "a precedence from step {a} to step {b}");
            checked += 1;
        }
    }
    assert_eq!(checked as u64, arrows);
}

#[test]
fn the_views_refuse_an_unknown_view_and_clamp_their_index() {
    let design = example("honeycomb-10mm");
    let mut cache = Cache::new();
    for view in ["graph", "pairing", "gippo", "trails", "order", "gcode"] {
        let a = inspect(&mut cache, &design, view, 10_000);
        assert_eq!(a.index, a.count - 1, "{view}");
        assert!(!a.data.is_empty() && a.data.iter().all(|x| x.is_finite()), "{view}");
        assert!(a.meta["caption"].as_str().is_some_and(|c| c.contains("mm")), "{view}: {}", a.meta["caption"]);
    }
    assert!(pipeline::inspect(&Registry::builtin(), &mut cache, &design, &Files::new(), "nope", 0).is_err());
}

#[test]
fn the_lattice_and_freeform_steps_are_complete() {
    let reg = Registry::builtin();
    for kind in ["lattice", "freeform"] {
        let k = reg.get(kind).unwrap();
        assert!(k.steps().len() >= 3, "{kind}");
        for s in k.steps() {
            assert!(k.views().iter().any(|v| v.id == s.view), "{kind}: {}", s.view);
            assert!(s.text.len() >= 40 && s.text.ends_with('.') && !s.cite.is_empty(), "{kind}: {}", s.title);
        }
    }
    // Every step's frame says what it shows, with units.
    for (kind, file) in [("lattice", "honeycomb-10mm"), ("freeform", "freeform-bridge")] {
        let design = example(file);
        let mut cache = Cache::new();
        for s in reg.get(kind).unwrap().steps() {
            let a = inspect(&mut cache, &design, s.view, s.index);
            let caption = a.meta["caption"].as_str().unwrap_or("");
            eprintln!("{kind} {}: {caption}", s.view);
            assert!(caption.contains("mm") || caption.contains("µm"), "{kind}: step {:?} caption {caption:?}", s.title);
        }
    }
}

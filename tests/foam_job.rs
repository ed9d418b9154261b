//! The `foam` job end to end: the printed ΔE/mm along the dogbone read back from the G-code
//! follows 1/V* of the chosen transition; every example is one uninterrupted thread; every
//! region rule refuses a crafted input with its message; region files give the same G-code as
//! the built-in model.

use weft::design::{Design, Input};
use weft::foam::models::prisms;
use weft::foam::{Process, Weighting};
use weft::geom::{DVec2, Mesh};
use weft::pipeline::{self, Files, RunOptions};

fn root() -> std::path::PathBuf {
    std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn example(name: &str) -> Design {
    let text = std::fs::read_to_string(root().join(format!("examples/{name}.json"))).unwrap();
    Design::from_json(name, &text).unwrap()
}

fn run(design: &Design, files: &Files) -> Result<pipeline::RunOutput, String> {
    pipeline::run(design, files, &RunOptions { collect_preview: true }, &mut |_, _| {}).map_err(|e| e.to_string())
}

/// The process of a design with its feed C.
fn process(d: &Design) -> Process {
    let c = d.job.value["foam"]["feed_mm_s"].as_f64().unwrap_or(weft::jobs::foam::DEFAULT_FEED_MM_S);
    Process { nozzle_mm: d.printer.nozzle_diameter_mm, die_swell: d.material.swell_ratio, filament_mm: d.printer.filament_diameter_mm, feed_mm_s: c }
}

/// Along the neck (|y| inside it, every piece lying flat in a layer), the filament per mm the
/// analyzer reads from the G-code against A_t/(V*·A_f) at the piece's end, with V* from the
/// transition's weighting at x/40 mm: the largest relative error and the x covered.
fn neck_profile(name: &str, w: Weighting) -> (f64, f64, f64, usize) {
    let d = example(name);
    let out = run(&d, &Files::new()).unwrap();
    let pv = out.preview.as_ref().unwrap();
    let p = process(&d);
    let (mut worst, mut lo, mut hi, mut n) = (0.0f64, f64::INFINITY, f64::NEG_INFINITY, 0);
    // The model is centred on the plate; the G-code adds the bed's centre.
    let (cx, cy) = (d.printer.bed_size_mm[0] / 2.0, d.printer.bed_size_mm[1] / 2.0);
    for (i, s) in pv.positions.chunks_exact(6).enumerate() {
        let (a, b) = ([s[0] as f64, s[1] as f64, s[2] as f64], [s[3] as f64, s[4] as f64, s[5] as f64]);
        let len = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
        if (b[2] - a[2]).abs() > 1e-6 || len < 0.2 {
            continue;
        }
        let (x, y) = (b[0] - cx, b[1] - cy);
        if y.abs() > 5.0 || x.abs() > 29.0 {
            continue;
        }
        let v = 0.15 * (1.0 - w.weight(x / 40.0)) + 0.4 * w.weight(x / 40.0);
        let want = p.filament_per_mm(v);
        let got = pv.e_per_mm[i] as f64;
        worst = worst.max((got - want).abs() / want);
        lo = lo.min(x);
        hi = hi.max(x);
        n += 1;
    }
    (worst, lo, hi, n)
}

#[test]
fn printed_filament_per_mm_follows_one_over_v_star_along_the_dogbone() {
    for (name, w) in [("foam-dogbone-linear", Weighting::Linear), ("foam-dogbone-log", Weighting::logarithmic())] {
        let (worst, lo, hi, n) = neck_profile(name, w);
        assert!(n > 500, "{name}: {n} pieces in the neck");
        assert!(lo < -25.0 && hi > 25.0, "{name}: the neck was covered only from {lo} to {hi}");
        assert!(worst < 0.01, "{name}: ΔE/mm off 1/V* by {:.3} %", worst * 100.0);
    }
}

#[test]
fn the_logarithmic_transition_jumps_to_the_papers_ends() {
    // Just inside the transition the fitted logarithm gives the paper's V* 0.1415 and 0.3795.
    let w = Weighting::logarithmic();
    let v = |x: f64| 0.15 * (1.0 - w.weight(x)) + 0.4 * w.weight(x);
    assert!((v(-0.4999) - 0.1415).abs() < 5e-4, "{}", v(-0.4999));
    assert!((v(0.4999) - 0.3795).abs() < 5e-4, "{}", v(0.4999));
}

#[test]
fn every_example_is_one_uninterrupted_thread() {
    for name in ["foam-dogbone-linear", "foam-dogbone-log", "foam-hinge-cube", "foam-insole"] {
        let d = example(name);
        let out = run(&d, &Files::new()).unwrap();
        let a = &out.report.analysis;
        assert_eq!(a.extrusion_paths, 1, "{name}: extrusion paths");
        assert_eq!(a.retractions, 0, "{name}: retractions");
        assert!(a.layers >= 5, "{name}: {} layers", a.layers);
        // Travel only up to the first point (and the end code's lift after the last): no layer
        // in between moves without extruding.
        for l in &a.per_layer[1..a.per_layer.len() - 1] {
            assert_eq!(l.travel_mm, 0.0, "{name}: travel in the layer at z {}", l.z);
        }
        // With the printer's retraction on, the only one is the printer's own at the very end.
        let mut on = d.clone();
        on.printer.retraction.length_mm = 0.8;
        let a = run(&on, &Files::new()).unwrap().report.analysis;
        assert_eq!(a.extrusion_paths, 1, "{name}");
        assert_eq!(a.per_layer.iter().map(|l| l.retractions).sum::<usize>(), 1, "{name}: retractions inside the print");
    }
}

#[test]
fn the_same_design_gives_the_same_bytes() {
    let d = example("foam-insole");
    let a = run(&d, &Files::new()).unwrap();
    let b = run(&d, &Files::new()).unwrap();
    assert_eq!(a.gcode, b.gcode);
}

/// A box from `min` to `max`.
fn cuboid(min: [f64; 3], max: [f64; 3]) -> Mesh {
    let mut m = prisms(&[vec![DVec2::new(min[0], min[1]), DVec2::new(max[0], min[1]), DVec2::new(max[0], max[1]), DVec2::new(min[0], max[1])]], max[2] - min[2]);
    m.translate(weft::geom::DVec3::new(0.0, 0.0, min[2]));
    m
}

/// `mesh` with Y and Z swapped (an outline in XZ extruded along Y), still facing out.
fn swap_yz(mut mesh: Mesh) -> Mesh {
    for v in &mut mesh.vertices {
        *v = [v[0], v[2], v[1]];
    }
    for t in &mut mesh.triangles {
        t.swap(1, 2);
    }
    mesh
}

/// A foam design over region files `names` (loaded in `files`), with `extra` settings.
fn files_design(regions: &[(&str, Mesh)], extra: serde_json::Value) -> (Design, Files) {
    let mut files = Files::new();
    for (n, m) in regions {
        files.insert(n.to_string(), m.to_stl_binary());
    }
    let mut v: serde_json::Value = serde_json::from_str(&example("foam-dogbone-linear").to_json_pretty()).unwrap();
    v["job"] = serde_json::json!({
        "kind": "foam",
        "meshes": serde_json::to_value(Input::Files(regions.iter().map(|(n, _)| n.to_string()).collect())).unwrap(),
        "regions": regions.iter().map(|_| serde_json::json!({"v_star": 0.2, "h_star": 8.0})).collect::<Vec<_>>(),
        "transitions": [],
    });
    if let (Some(job), Some(extra)) = (v["job"].as_object_mut(), extra.as_object()) {
        for (k, x) in extra {
            job.insert(k.clone(), x.clone());
        }
    }
    (Design::from_json("test", &v.to_string()).unwrap(), files)
}

fn refusal(regions: &[(&str, Mesh)], extra: serde_json::Value) -> String {
    let (d, files) = files_design(regions, extra);
    match run(&d, &files) {
        Ok(_) => panic!("the regions were accepted"),
        Err(e) => e,
    }
}

#[test]
fn every_region_rule_refuses_a_crafted_input_with_its_message() {
    // Overlap: a corner of B inside A.
    let e = refusal(&[("a.stl", cuboid([0.0, 0.0, 0.0], [20.0, 20.0, 10.0])), ("b.stl", cuboid([15.0, 0.0, 0.0], [40.0, 20.0, 10.0]))], serde_json::json!({}));
    assert!(e.contains("regions") && e.contains("overlap") && e.contains("a.stl") && e.contains("b.stl"), "{e}");
    // Overlap with no corner inside the other (a plus sign): found in the layers.
    let e = refusal(&[("long-x.stl", cuboid([-30.0, -5.0, 0.0], [30.0, 5.0, 6.0])), ("long-y.stl", cuboid([-5.0, -30.0, 0.0], [5.0, 30.0, 6.0]))], serde_json::json!({}));
    assert!(e.contains("overlap") && e.contains("long-x.stl") && e.contains("long-y.stl"), "{e}");
    // A region sharing boundaries with two others: refused (the paper's rule), accepted when
    // several neighbours are allowed.
    let row = [("left.stl", cuboid([0.0, 0.0, 0.0], [20.0, 20.0, 6.0])), ("middle.stl", cuboid([20.0, 0.0, 0.0], [40.0, 20.0, 6.0])), ("right.stl", cuboid([40.0, 0.0, 0.0], [60.0, 20.0, 6.0]))];
    let e = refusal(&row, serde_json::json!({}));
    assert!(e.contains("middle.stl shares a boundary with 2 regions (left.stl, right.stl)"), "{e}");
    let (d, files) = files_design(&row, serde_json::json!({"foam": {"many_neighbours": true}}));
    assert!(run(&d, &files).is_ok());
    // Not one connected domain: apart, and touching only along an edge.
    let e = refusal(&[("near.stl", cuboid([0.0, 0.0, 0.0], [20.0, 20.0, 6.0])), ("far.stl", cuboid([30.0, 0.0, 0.0], [50.0, 20.0, 6.0]))], serde_json::json!({}));
    assert!(e.contains("do not make one connected foam") && e.contains("near.stl") && e.contains("far.stl"), "{e}");
    let e = refusal(&[("p.stl", cuboid([0.0, 0.0, 0.0], [20.0, 20.0, 6.0])), ("q.stl", cuboid([20.0, 20.0, 0.0], [40.0, 40.0, 6.0]))], serde_json::json!({}));
    assert!(e.contains("do not make one connected foam"), "{e}");
    // One outline per layer: an arch (a pillar, and a beam with the other pillar) is one
    // domain, but its lower layers are two outlines.
    let pillar = cuboid([0.0, 0.0, 0.0], [10.0, 10.0, 10.0]);
    let l_shape = vec![DVec2::new(0.0, 10.0), DVec2::new(30.0, 10.0), DVec2::new(30.0, 0.0), DVec2::new(40.0, 0.0), DVec2::new(40.0, 12.0), DVec2::new(0.0, 12.0)];
    let beam = swap_yz(prisms(&[l_shape], 10.0));
    let e = refusal(&[("pillar.stl", pillar), ("beam.stl", beam)], serde_json::json!({}));
    assert!(e.contains("separate outlines") && e.contains("pillar.stl") && e.contains("beam.stl"), "{e}");
    // A transition between regions that do not touch.
    let e = refusal(&row, serde_json::json!({"foam": {"many_neighbours": true}, "transitions": [{"from": 1, "to": 3, "length_mm": 5.0}]}));
    assert!(e.contains("left.stl") && e.contains("right.stl") && e.contains("do not touch"), "{e}");
}

#[test]
fn the_shared_boundary_is_the_contact_face() {
    // A small block on the side of a big one: the shared boundary is the small block's face.
    let (d, files) = files_design(&[("big.stl", cuboid([0.0, 0.0, 0.0], [40.0, 40.0, 10.0])), ("small.stl", cuboid([40.0, 10.0, 0.0], [50.0, 22.0, 10.0]))], serde_json::json!({}));
    let out = run(&d, &files).unwrap();
    let regions = out.report.stages.iter().find(|s| s.stage == "regions").unwrap();
    let area = regions.metrics.iter().find(|m| m.key == "shared_area").unwrap().value;
    assert!((area - 120.0).abs() < 120.0 * 0.03, "shared area {area} mm², the contact is 12 × 10 = 120 mm²");
    // The dogbone's halves share the neck's cut: 12 × 10 mm.
    let out = run(&example("foam-dogbone-linear"), &Files::new()).unwrap();
    let regions = out.report.stages.iter().find(|s| s.stage == "regions").unwrap();
    let area = regions.metrics.iter().find(|m| m.key == "shared_area").unwrap().value;
    assert!((area - 120.0).abs() < 1e-3, "dogbone shared area {area}");
}

#[test]
fn region_files_give_the_same_gcode_as_the_built_in_model() {
    let d = example("foam-dogbone-linear");
    let model: weft::foam::models::Model = serde_json::from_value(d.job.value["model"].clone()).unwrap();
    let meshes = weft::foam::models::build(&model);
    let mut files = Files::new();
    let mut v: serde_json::Value = serde_json::from_str(&d.to_json_pretty()).unwrap();
    let names: Vec<String> = meshes.iter().enumerate().map(|(i, _)| format!("half-{i}.stl")).collect();
    for ((_, m), n) in meshes.iter().zip(&names) {
        files.insert(n.clone(), m.to_stl_binary());
    }
    v["job"].as_object_mut().unwrap().remove("model");
    v["job"]["meshes"] = serde_json::to_value(Input::Files(names)).unwrap();
    let from_files = Design::from_json("files", &v.to_string()).unwrap();
    assert_eq!(run(&d, &Files::new()).unwrap().gcode, run(&from_files, &files).unwrap().gcode);
}

//! The `foam` job end to end: the printed ΔE/mm along the dogbone read back from the G-code
//! follows 1/V* of the chosen transition; every example is one uninterrupted thread; every
//! region rule refuses a crafted input with its message; region files give the same G-code as
//! the built-in model.

use weft::design::{Design, Input};
use weft::foam::models::prisms;
use weft::foam::{Process, Weighting};
use weft::geom::{DVec2, Mesh};
use weft::pipeline::Files;

use crate::common;
use common::{example, run};

/// The process of a design with its feed C.
fn process(d: &Design) -> Process {
    let c = d.job.value["foam"]["feed_mm_s"].as_f64().unwrap_or(weft::kinds::foam::DEFAULT_FEED_MM_S);
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
    let modulus = Weighting::LinearModulus { ratio: weft::foam::stiffness::Calibration::default().ratio(0.15, 0.4) };
    for (name, w) in [("foam-dogbone-linear", Weighting::Linear), ("foam-dogbone-log", Weighting::logarithmic()), ("foam-dogbone-modulus", modulus)] {
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
    for name in ["foam-dogbone-linear", "foam-dogbone-log", "foam-dogbone-modulus", "foam-hinge-cube", "foam-insole", "foam-stiffness-sectors"] {
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
    let mut m =
        prisms(&[vec![DVec2::new(min[0], min[1]), DVec2::new(max[0], min[1]), DVec2::new(max[0], max[1]), DVec2::new(min[0], max[1])]], max[2] - min[2]);
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
    let e = refusal(
        &[("long-x.stl", cuboid([-30.0, -5.0, 0.0], [30.0, 5.0, 6.0])), ("long-y.stl", cuboid([-5.0, -30.0, 0.0], [5.0, 30.0, 6.0]))],
        serde_json::json!({}),
    );
    assert!(e.contains("overlap") && e.contains("long-x.stl") && e.contains("long-y.stl"), "{e}");
    // A region sharing boundaries with two others: refused (the paper's rule), accepted when
    // several neighbours are allowed.
    let row = [
        ("left.stl", cuboid([0.0, 0.0, 0.0], [20.0, 20.0, 6.0])),
        ("middle.stl", cuboid([20.0, 0.0, 0.0], [40.0, 20.0, 6.0])),
        ("right.stl", cuboid([40.0, 0.0, 0.0], [60.0, 20.0, 6.0])),
    ];
    let e = refusal(&row, serde_json::json!({}));
    assert!(e.contains("middle.stl shares a boundary with 2 regions (left.stl, right.stl)"), "{e}");
    let (d, files) = files_design(&row, serde_json::json!({"foam": {"many_neighbours": true}}));
    assert!(run(&d, &files).is_ok());
    // Not one connected domain: apart, and touching only along an edge.
    let e =
        refusal(&[("near.stl", cuboid([0.0, 0.0, 0.0], [20.0, 20.0, 6.0])), ("far.stl", cuboid([30.0, 0.0, 0.0], [50.0, 20.0, 6.0]))], serde_json::json!({}));
    assert!(e.contains("do not make one connected foam") && e.contains("near.stl") && e.contains("far.stl"), "{e}");
    let e = refusal(&[("p.stl", cuboid([0.0, 0.0, 0.0], [20.0, 20.0, 6.0])), ("q.stl", cuboid([20.0, 20.0, 0.0], [40.0, 40.0, 6.0]))], serde_json::json!({}));
    assert!(e.contains("do not make one connected foam"), "{e}");
    // One outline per layer: an arch (a pillar, and a beam with the other pillar) is one
    // domain, but its lower layers are two outlines.
    let pillar = cuboid([0.0, 0.0, 0.0], [10.0, 10.0, 10.0]);
    let l_shape =
        vec![DVec2::new(0.0, 10.0), DVec2::new(30.0, 10.0), DVec2::new(30.0, 0.0), DVec2::new(40.0, 0.0), DVec2::new(40.0, 12.0), DVec2::new(0.0, 12.0)];
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
    let (d, files) = files_design(
        &[("big.stl", cuboid([0.0, 0.0, 0.0], [40.0, 40.0, 10.0])), ("small.stl", cuboid([40.0, 10.0, 0.0], [50.0, 22.0, 10.0]))],
        serde_json::json!({}),
    );
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

/// Every printed piece lying flat: its filament per mm, its length, its end point (mm,
/// plate-centred) and whether it follows the previous piece in the same layer. (A 0.5 mm
/// piece's ΔE/mm reads back within about 0.3 %, G-code X and Y having 3 decimals; shorter
/// ones with more error.)
fn printed_pieces(d: &Design) -> Vec<(f64, f64, [f64; 2], bool)> {
    let out = run(d, &Files::new()).unwrap();
    let pv = out.preview.as_ref().unwrap();
    let (cx, cy) = (d.printer.bed_size_mm[0] / 2.0, d.printer.bed_size_mm[1] / 2.0);
    let mut last_z = f64::NAN;
    let mut v = Vec::new();
    for (i, s) in pv.positions.chunks_exact(6).enumerate() {
        let flat = (s[5] - s[2]).abs() < 1e-6;
        let e = pv.e_per_mm[i] as f64;
        if !flat || e <= 0.0 {
            last_z = f64::NAN;
            continue;
        }
        let same = s[5] as f64 == last_z;
        last_z = s[5] as f64;
        let len = ((s[3] as f64 - s[0] as f64).powi(2) + (s[4] as f64 - s[1] as f64).powi(2)).sqrt();
        v.push((e, len, [s[3] as f64 - cx, s[4] as f64 - cy], same));
    }
    v
}

/// V* of a piece printing `e_per_mm` (V* = A_t/(A_f·ΔE/mm)).
fn v_star_of(p: &Process, e_per_mm: f64) -> f64 {
    p.thread_area() / (p.filament_area() * e_per_mm)
}

/// The largest change of V* from one piece to the next along each layer's path, both pieces
/// 0.4 mm long or more and ending farther than `r` mm from the axis.
fn largest_step(p: &Process, v: &[(f64, f64, [f64; 2], bool)], r: f64) -> f64 {
    let far = |q: [f64; 2]| q[0].hypot(q[1]) > r;
    v.windows(2)
        .filter(|w| w[1].3 && w[0].1 >= 0.4 && w[1].1 >= 0.4 && far(w[0].2) && far(w[1].2))
        .map(|w| (v_star_of(p, w[1].0) - v_star_of(p, w[0].0)).abs())
        .fold(0.0, f64::max)
}

#[test]
fn a_stiffness_map_prints_the_asked_moduli_and_blends_without_jumps_where_three_regions_meet() {
    use weft::foam::stiffness::Calibration;
    let d = example("foam-stiffness-sectors");
    let c = Calibration::default();
    let p = process(&d);
    let v = printed_pieces(&d);
    assert!(v.len() > 10_000, "{} pieces", v.len());
    // Deep inside each sector (more than 8 mm, half a transition, from both of its cuts), the
    // filament printed over the length gives back the asked modulus by the calibration.
    let asked = [20.0, 8.0, 2.0];
    let mut seen = [(0.0, 0.0, 0usize); 3];
    for &(e, len, [x, y], _) in &v {
        let (r, a) = ((x * x + y * y).sqrt(), libm::atan2(y, x).to_degrees());
        // Sector k spans 90° + 120°k to 90° + 120°(k + 1); the angle from its cuts, in mm.
        let from_first = (a - 90.0).rem_euclid(360.0);
        let k = (from_first / 120.0) as usize;
        let off = (from_first - 120.0 * k as f64).min(120.0 * (k + 1) as f64 - from_first);
        let to_cut = if off >= 90.0 { r } else { r * off.to_radians().sin() };
        if to_cut > 8.5 {
            seen[k].0 += e * len;
            seen[k].1 += len;
            seen[k].2 += 1;
        }
    }
    for (k, &(e, len, n)) in seen.iter().enumerate() {
        let modulus = c.modulus_kpa(v_star_of(&p, e / len));
        assert!(n > 500 && (modulus - asked[k]).abs() < 1e-3 * asked[k], "sector {}: {modulus} kPa printed for {} over {n} pieces", k + 1, asked[k]);
    }
    // One piece to the next, V* changes only by its slope along the path with the distance
    // blend, against the nearest-boundary rule's jumps where the nearest boundary changes.
    // With linear weights V* has a slope of at most (0.345 − 0.160)/16 mm, 0.006 per 0.5 mm
    // piece, away from the axis. On the axis, where the three boundaries meet, each carries
    // its own blend: around it V* varies by up to (V*₃ − V*₁)/4 at any distance, so the slope
    // grows as 1/r there.
    let mut linear = d.clone();
    for t in 0..3 {
        linear.job.value["transitions"][t]["weighting"] = serde_json::json!({"kind": "linear"});
    }
    let mut nearest = linear.clone();
    nearest.job.value["foam"]["junction"] = serde_json::json!("nearest");
    let (blend, nearest) = (printed_pieces(&linear), printed_pieces(&nearest));
    // Measured: beyond 3 mm of the axis the blend steps by 0.0099 at most, the nearest rule
    // by 0.054; beyond 8 mm both by the slope alone (0.0065 with the read-back's noise).
    for (r, most, jumps) in [(0.0, 0.05, false), (3.0, 0.012, true), (8.0, 0.0075, false)] {
        let (b, n) = (largest_step(&p, &blend, r), largest_step(&p, &nearest, r));
        eprintln!("largest V* step beyond {r} mm of the axis: blend {b:.4}, nearest {n:.4}");
        assert!(b < most, "blend: V* steps by {b} between pieces beyond {r} mm");
        if jumps {
            assert!(n > 3.0 * b, "beyond {r} mm: nearest {n} against blend {b}");
        }
    }
    // The paper's rule refuses the sectors, naming them.
    let mut strict = d.clone();
    strict.job.value["foam"]["many_neighbours"] = serde_json::json!(false);
    let e = run(&strict, &Files::new()).unwrap_err();
    assert!(e.contains("sector 1") && e.contains("shares a boundary with 2 regions") && e.contains("allow several neighbours"), "{e}");
}

#[test]
fn a_modulus_outside_the_calibration_is_refused_with_its_range() {
    let mut d = example("foam-stiffness-sectors");
    d.job.value["regions"][1]["modulus_kpa"] = serde_json::json!(40.0);
    let problems = d.validate();
    let p = problems.iter().find(|p| p.path == "job.regions.1.modulus_kpa").unwrap_or_else(|| panic!("{problems:?}"));
    assert!(p.message.contains("region 2") && p.message.contains("40 kPa") && p.message.contains("1.01 kPa (V* 0.4) to 22.68 kPa (V* 0.15)"), "{}", p.message);
    d.job.value["foam"]["calibration"]["b"] = serde_json::json!(0.0);
    let problems = d.validate();
    assert!(problems.iter().any(|p| p.path == "job.foam.calibration" && p.message.contains("b is 0")), "{problems:?}");
}

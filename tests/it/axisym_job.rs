//! The `axisymmetric` job end to end: the three shipped examples (the paper's Ω1, Ω2, Ω3)
//! through the design, the pipeline, the 5-axis writer and the analyzer.

use weft::design::Design;
use weft::kinds::axisymmetric::{PathSummary, PointsSummary};
use weft::pipeline::{self, Files, RunOptions};

fn example(name: &str) -> Design {
    let path = format!("{}/examples/{name}.json", env!("CARGO_MANIFEST_DIR"));
    Design::from_json(name, &std::fs::read_to_string(path).unwrap()).unwrap()
}

fn run(d: &Design) -> pipeline::RunOutput {
    pipeline::run(d, &Files::default(), &RunOptions { collect_preview: true }, &mut |_, _| {}).unwrap()
}

/// (example, the paper's N, the paper's 2n-NN standard-deviation reduction).
const CASES: &[(&str, Option<usize>, f64)] = &[("barrel-omega1", Some(538), 0.717), ("barrel-omega2", Some(173), 0.716), ("hourglass-omega3", Some(204), 0.44)];

#[test]
fn examples_spread_points_evenly_and_visit_each_once() {
    for &(name, paper_n, paper_reduction) in CASES {
        let d = example(name);
        let out = run(&d);
        let points: PointsSummary = out.report.stage("points").unwrap();
        let path: PathSummary = out.report.stage("path").unwrap();
        if let Some(n) = paper_n {
            // Equation 4 on the true area: within 2 % of the paper's N.
            let rel = (points.points as f64 - n as f64).abs() / n as f64;
            assert!(rel < 0.02, "{name}: N = {} against the paper's {n}", points.points);
        }
        // Repulsion evens the spacing (the paper's table 4).
        assert!(points.std_mm < points.seed_std_mm, "{name}: std {} not below the seed's {}", points.std_mm, points.seed_std_mm);
        eprintln!(
            "{name}: N {} area {:.1} mm², std {:.3} → {:.3} mm ({:.1} % less; paper {:.1} %), e/mean {:.1} % (seed {:.1} %)",
            points.points,
            points.area_mm2,
            points.seed_std_mm,
            points.std_mm,
            100.0 * points.std_reduction,
            100.0 * paper_reduction,
            100.0 * points.ratio,
            100.0 * points.seed_ratio
        );
        // The normalised energy never rises by more than the tolerance.
        let tol = d.job.value["points"]["energy_tolerance"].as_f64().unwrap();
        for w in points.energy.windows(2) {
            assert!(w[1] <= w[0] + tol + 1e-12, "{name}: energy rose {} → {}", w[0], w[1]);
        }
        // The neighbour-distance histogram: n + 1 bin edges per n counts, every distance in.
        let report = serde_json::to_value(&out.report).unwrap();
        let stage = report["stages"].as_array().unwrap().iter().find(|s| s["stage"] == "points").unwrap();
        let nn = stage["plots"].as_array().unwrap().iter().find(|p| p["key"] == "nn").unwrap();
        for series in nn["series"].as_array().unwrap() {
            let (x, y) = (series["x"].as_array().unwrap(), series["y"].as_array().unwrap());
            assert_eq!(x.len(), y.len() + 1, "{name}: histogram edges");
            let total: f64 = y.iter().map(|v| v.as_f64().unwrap()).sum();
            assert_eq!(total as usize, 2 * points.points, "{name}: every point's 2 distances counted");
        }
        assert_eq!(path.visited, points.points, "{name}");
        assert_eq!(path.crossings_left, 0, "{name}");
        assert!(path.length_mm <= path.nn_length_mm + 1e-9, "{name}");

        // The G-code as read back: one extrusion path of the tour's length, tool axes stated.
        let a = &out.report.analysis;
        assert_eq!(a.extrusion_paths, 1, "{name}");
        let preview = out.preview.as_ref().unwrap();
        assert!(!preview.axis.is_empty(), "{name}: the G-code states no tool axis");
        // The tip rides one layer height out along the normal, so the printed length is the
        // surface path's within the layer height's share of the curvature.
        let rel = (a.extruded_mm - path.length_mm).abs() / path.length_mm;
        assert!(rel < 0.02, "{name}: extruded {} mm against a {} mm path", a.extruded_mm, path.length_mm);
    }
}

#[test]
fn same_design_same_bytes() {
    let d = example("hourglass-omega3");
    assert_eq!(run(&d).gcode, run(&d).gcode);
    let mut other = d.clone();
    other.seed += 1;
    assert_ne!(run(&d).gcode, run(&other).gcode);
}

/// Every problem of `d` with `sets` applied (the design refuses an invalid result).
fn problems_with(d: &Design, sets: &[&str]) -> Vec<String> {
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    match d.with_overrides(&sets) {
        Ok(d) => d.validate().into_iter().map(|p| format!("{}: {}", p.path, p.message)).collect(),
        Err(weft::design::Error::Invalid { problems, .. }) => problems.into_iter().map(|p| format!("{}: {}", p.path, p.message)).collect(),
        Err(e) => vec![e.to_string()],
    }
}

#[test]
fn bad_settings_are_named() {
    let d = example("barrel-omega1");
    assert!(problems_with(&d, &[]).is_empty(), "{:?}", problems_with(&d, &[]));

    let p = problems_with(&d, &["printer.machine.kind=cartesian"]);
    assert!(p.iter().any(|m| m.starts_with("printer.machine.kind") && m.contains("5-axis")), "{p:?}");

    // A domain reaching the top pole: the message gives the u range to keep.
    let p = problems_with(&d, &["job.domain.u_min=0.0"]);
    assert!(p.iter().any(|m| m.starts_with("job.domain") && m.contains("pole")), "{p:?}");

    // A custom polygon of the wrong length.
    let p = problems_with(&d, &["job.platform.preset=custom", "job.platform.control_points=[[0,50],[5,50],[10,50]]"]);
    assert!(p.iter().any(|m| m.starts_with("job.platform.control_points") && m.contains("6·k + 1")), "{p:?}");

    // A cusp: two segments meeting at an angle.
    let p = problems_with(
        &d,
        &[
            "job.platform.preset=custom",
            "job.platform.control_points=[[0,50],[5,50],[10,50],[25,50],[25,35],[25,30],[25,25],[30,20],[25,15],[25,0],[10,0],[5,0],[0,0]]",
        ],
    );
    assert!(p.iter().any(|m| m.starts_with("job.platform") && m.contains("jumps")), "{p:?}");
}

#[test]
fn a_preset_writes_its_control_points() {
    let d = example("hourglass-omega3");
    let cp = d.job.value["platform"]["control_points"].as_array().unwrap();
    assert_eq!(cp.len(), 4 * 6 + 1);
    // Switching to custom keeps the points, so editing starts from the preset.
    let custom = d.with_overrides(&["job.platform.preset=custom".to_string()]).unwrap();
    assert_eq!(custom.job.value["platform"]["control_points"], d.job.value["platform"]["control_points"]);
    assert_eq!(run(&custom).gcode, run(&d).gcode);
}

#[test]
fn poses_csv_output_has_one_row_per_pose() {
    let d = example("barrel-omega2").with_overrides(&["printer.flavor=poses_csv".to_string(), "printer.machine.kind=cartesian".to_string()]).unwrap();
    let out = run(&d);
    let path: PathSummary = out.report.stage("path").unwrap();
    let csv = out.gcode.as_str();
    let mut lines = csv.lines().filter(|l| !l.starts_with(';') && !l.is_empty());
    assert_eq!(lines.next(), Some("x,y,z,nx,ny,nz"));
    let rows: Vec<Vec<f64>> = lines.map(|l| l.split(',').map(|f| f.parse().unwrap()).collect()).collect();
    assert_eq!(rows.len(), path.poses, "one row per pose");
    // Every normal is a unit vector.
    for r in &rows {
        assert_eq!(r.len(), 6);
        assert!(((r[3] * r[3] + r[4] * r[4] + r[5] * r[5]).sqrt() - 1.0).abs() < 1e-5, "{r:?}");
    }
}

#[test]
fn a_part_on_the_platform_gives_the_domain() {
    // A ball of radius 8 mm centred on the barrel's equator (radius 25 mm at z = 25 mm): it
    // meets the platform in one near-circular outline around u = 1, θ = 0.
    let mut mesh = weft::geom::shapes::Shape::Sphere { radius: 8.0, segments: 96 }.mesh();
    let zmin = mesh.vertices.iter().map(|v| v[2]).fold(f32::INFINITY, f32::min);
    let zmax = mesh.vertices.iter().map(|v| v[2]).fold(f32::NEG_INFINITY, f32::max);
    for v in &mut mesh.vertices {
        v[0] += 25.0;
        v[2] += 25.0 - 0.5 * (zmin + zmax);
    }
    let mut files = Files::default();
    files.insert("box.stl".into(), mesh.to_stl_binary());
    let d = example("barrel-omega1").with_overrides(&["job.domain.kind=part".to_string(), "job.part={\"file\":{\"name\":\"box.stl\"}}".to_string()]).unwrap();
    let out = pipeline::run(&d, &files, &RunOptions { collect_preview: false }, &mut |_, _| {}).unwrap();
    let points: PointsSummary = out.report.stage("points").unwrap();
    let domain = out.report.stage_data("domain").unwrap();
    assert_eq!(domain["kind"], "polygon");
    let ring = domain["points"].as_array().unwrap();
    assert!(ring.len() > 8, "{domain}");
    // θ within ±asin(8/25) (the ball's radius over the platform's), u around the equator.
    for q in ring {
        let (u, t) = (q[0].as_f64().unwrap(), q[1].as_f64().unwrap());
        assert!((0.6..1.4).contains(&u) && t.abs() <= (8.0f64 / 25.0).asin() + 1e-6, "({u}, {t})");
    }
    // N from the outline's true area (equation 4 at 50 %, e = 0.4 mm: 1.5625 points per mm²).
    let want = points.area_mm2 * 0.25 / 0.16;
    assert!((points.points as f64 - want).abs() <= 1.0, "{} points for {} mm²", points.points, points.area_mm2);
    assert!(points.std_mm < points.seed_std_mm);
    // Without the part, the design names the slot.
    let p = problems_with(&example("barrel-omega1"), &["job.domain.kind=part"]);
    assert!(p.iter().any(|m| m.starts_with("job.part") && m.contains("load the part")), "{p:?}");
}

#[test]
fn switching_to_the_kind_puts_a_five_axis_head_in_place() {
    // The default design (a slice on a Cartesian printer) switched to axisymmetric is valid:
    // the kind puts the five-axis-head profile in place, and runs.
    let d = Design::default().with_overrides(&["job.kind=axisymmetric".to_string()]).unwrap();
    let preset = weft::gcode::presets::preset(weft::kinds::axisymmetric::FIVE_AXIS_PRESET).unwrap();
    assert_eq!(serde_json::to_value(&d.printer).unwrap(), serde_json::to_value(&preset.printer).unwrap());
    // A poses CSV printer is kept (it needs no machine).
    let csv = Design::default().with_overrides(&["printer.flavor=poses_csv".to_string(), "job.kind=axisymmetric".to_string()]).unwrap();
    assert_eq!(csv.printer.flavor, weft::gcode::Flavor::PosesCsv);
    assert!(!csv.printer.machine.is_five_axis());
    // The shipped examples use exactly that profile.
    for name in ["barrel-omega1", "barrel-omega2", "hourglass-omega3"] {
        assert_eq!(serde_json::to_value(&example(name).printer).unwrap(), serde_json::to_value(&preset.printer).unwrap(), "{name}");
    }
}

#[test]
fn a_tip_below_the_plate_is_refused_before_the_points() {
    // Near the barrel's lower pole the normal points down: the tip, one layer height out
    // along it, dips under Z = 0. The domain stage refuses it; no points are spread.
    let d = example("barrel-omega1").with_overrides(&["job.domain.u_min=1.8".into(), "job.domain.u_max=1.96".into()]).unwrap();
    let mut stages = Vec::new();
    let e = pipeline::run(&d, &Files::default(), &RunOptions { collect_preview: false }, &mut |p, _| stages.push(p.to_string())).unwrap_err().to_string();
    assert!(e.starts_with("domain:") && e.contains("below the plate") && e.contains("raise the platform by at least"), "{e}");
    assert!(!stages.iter().any(|s| s == "points"), "the points stage ran: {stages:?}");
    // Raised by the amount the message states (rounded up), the same domain prints.
    let raise: f64 = e.split("at least ").nth(1).unwrap().split(' ').next().unwrap().parse().unwrap();
    let raised: Vec<[f64; 2]> =
        d.job.settings::<weft::kinds::axisymmetric::AxisymJob>().unwrap().platform.control_points.iter().map(|p| [p[0], p[1] + raise + 1e-3]).collect();
    // (The tool points almost straight down there: the head's B limit is opened for it.)
    let d = d
        .with_overrides(&[
            "job.platform.preset=custom".into(),
            format!("job.platform.control_points={}", serde_json::to_string(&raised).unwrap()),
            "printer.machine.rotary_min_deg=[-120,-181,-36000]".into(),
            "printer.machine.rotary_max_deg=[120,181,36000]".into(),
        ])
        .unwrap();
    let out = run(&d);
    assert!(!out.gcode.is_empty());
}

/// X Y Z words of every G1 move.
fn xyz_of(gcode: &str) -> Vec<[String; 3]> {
    gcode
        .lines()
        .filter(|l| l.starts_with("G1 "))
        .map(|l| {
            let word = |c: char| l.split_whitespace().find(|w| w.starts_with(c)).map(|w| w[1..].to_string()).unwrap_or_default();
            [word('X'), word('Y'), word('Z')]
        })
        .collect()
}

#[test]
fn smoothing_the_tool_axis_lowers_every_rotary_acceleration_and_keeps_the_tip() {
    use weft::kinds::axisymmetric::AxesSummary;
    for name in ["barrel-omega1", "hourglass-omega3"] {
        let d = example(name);
        let plain = run(&d);
        let s = d.with_overrides(&["job.tool_axis.max_tilt_deg=10".into(), "job.tool_axis.window_mm=2".into()]).unwrap();
        let smooth = run(&s);
        let a: AxesSummary = smooth.report.stage("axes").unwrap();
        assert!(a.max_tilt_deg > 0.1 && a.max_tilt_deg < 10.0, "{name}: tilt {}", a.max_tilt_deg);
        // Tool axis, B and C on the five-axis head.
        assert_eq!(a.raw.iter().map(|(k, _)| k.as_str()).collect::<Vec<_>>(), ["tool axis", "B", "C"]);
        for ((axis, raw), (_, after)) in a.raw.iter().zip(&a.smoothed) {
            assert!(after[1] < 0.5 * raw[1], "{name} {axis}: acceleration {} → {}", raw[1], after[1]);
            assert!(after[0] <= raw[0] * (1.0 + 1e-9), "{name} {axis}: speed {} → {}", raw[0], after[0]);
        }
        // Off: the report's before and after agree, and the axes are the normals.
        let p: AxesSummary = plain.report.stage("axes").unwrap();
        assert_eq!(p.max_tilt_deg, 0.0);
        assert_eq!(p.raw, p.smoothed);
        // The tip path is the same (pivot 0: machine X Y Z are the tip); only the axis words differ.
        assert_eq!(xyz_of(&plain.gcode), xyz_of(&smooth.gcode), "{name}");
        assert_ne!(plain.gcode, smooth.gcode);
    }
}

#[test]
fn graded_density_follows_its_target() {
    // The graded example: Ω1 with ρ falling along u from 50 % to 25 %.
    let d = example("barrel-graded");
    let out = run(&d);
    let points: PointsSummary = out.report.stage("points").unwrap();
    assert!(points.graded);
    // N = ∫ρ² dA/(n²e²): about the uniform 538 times the mean of ρ² over 0.25 (≈ 0.58).
    assert!((300..330).contains(&points.points), "N = {}", points.points);
    assert!(points.rel_std < points.seed_rel_std, "spread against the target {} not below the seed's {}", points.rel_std, points.seed_rel_std);
    for w in points.energy.windows(2) {
        assert!(w[1] <= w[0] + 1e-6 + 1e-12, "energy rose {} → {}", w[0], w[1]);
    }
    eprintln!(
        "barrel-graded: N {}, 2n-NN distance / s(q) std {:.4} → {:.4} ({:.1} % less), mm std {:.3} → {:.3}",
        points.points,
        points.seed_rel_std,
        points.rel_std,
        100.0 * points.rel_std_reduction,
        points.seed_std_mm,
        points.std_mm
    );
    // The commanded-vs-measured plot: the commanded line runs 50 → 25 %, the measured one
    // falls with it (first bin well above the last, each within 20 % of the command).
    let report = serde_json::to_value(&out.report).unwrap();
    let stage = report["stages"].as_array().unwrap().iter().find(|s| s["stage"] == "points").unwrap();
    let plot = |key: &str| stage["plots"].as_array().unwrap().iter().find(|p| p["key"] == key).unwrap_or_else(|| panic!("no {key} plot")).clone();
    let density = plot("graded_density");
    let series = |name: &str| {
        density["series"].as_array().unwrap().iter().find(|s| s["name"].as_str().unwrap().starts_with(name)).unwrap()["y"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap_or(f64::NAN))
            .collect::<Vec<f64>>()
    };
    let (commanded, measured) = (series("commanded"), series("repulsion"));
    assert!((commanded[0] - 50.0).abs() < 2.0 && (commanded[commanded.len() - 1] - 25.0).abs() < 2.0, "{commanded:?}");
    assert!(measured[0] > 1.5 * measured[measured.len() - 1], "{measured:?}");
    let bins = measured.len();
    for (k, m) in measured.iter().enumerate() {
        // The bin's centre on the commanded line (linear between its ends).
        let c = commanded[0] + (commanded[commanded.len() - 1] - commanded[0]) * (k as f64 + 0.5) / bins as f64;
        assert!((m / c - 1.0).abs() < 0.2, "bin {k}: measured {m:.1} % against {c:.1} %");
    }
    for key in ["kdf_relative", "nn_relative"] {
        plot(key);
    }
    let metrics = stage["metrics"].as_array().unwrap();
    assert!(metrics.iter().any(|m| m["key"] == "rel_std_reduction"), "{metrics:?}");
    // A uniform design gains no graded rows or plots.
    let out = run(&example("barrel-omega1"));
    let report = serde_json::to_value(&out.report).unwrap();
    let stage = report["stages"].as_array().unwrap().iter().find(|s| s["stage"] == "points").unwrap();
    assert!(stage["plots"].as_array().unwrap().iter().all(|p| p["key"] != "graded_density"));
    let points: PointsSummary = out.report.stage("points").unwrap();
    assert!(!points.graded);
}

#[test]
fn bad_grading_is_named() {
    let d = example("barrel-omega1");
    let grading = |json: &str| format!("job.points.grading={json}");
    let cases = [
        (grading(r#"{"along":"u","density_to":1.5}"#), "job.points.grading.density_to"),
        (grading(r#"{"along":"u","density_to":0}"#), "job.points.grading.density_to"),
        (grading(r#"{"along":"radial","radius_mm":0}"#), "job.points.grading.radius_mm"),
        (grading(r#"{"along":"radial","centre_theta_rad":9}"#), "job.points.grading.centre_theta_rad"),
        // Inside the form's range, but at the barrel's top pole: the metric fails there.
        (grading(r#"{"along":"radial","centre_u":0.0}"#), "job.points.grading.centre_u"),
        (grading(r#"{"along":"diagonal"}"#), "job.points.grading"),
    ];
    for (set, path) in cases {
        let p = problems_with(&d, &[set.as_str()]);
        assert!(p.iter().any(|m| m.contains(path)), "{set}: {p:?}");
    }
    // A valid grading is accepted, and switching it off gives the uniform design back.
    assert!(problems_with(&d, &[grading(r#"{"along":"theta","density_to":0.3}"#).as_str()]).is_empty());
    let off = example("barrel-graded").with_overrides(&["job.points.grading=null".to_string()]).unwrap();
    assert_eq!(off.job.value["points"], d.job.value["points"]);
}

/// (u, θ) points of layer `layer` after repulsion, read from the map view (each point is a
/// cross: its horizontal bar is the first of its two segments).
fn map_points(d: &Design, files: &Files, cache: &mut weft::pipeline::Cache, layer: usize) -> (Vec<[f64; 2]>, serde_json::Value, usize) {
    let v = pipeline::inspect(&weft::kinds::Registry::builtin(), cache, d, files, "map", 3 * layer + 1).unwrap();
    let lattice = weft::geom::Feature::Lattice.code() as f32;
    let segs: Vec<&[f32]> = v.data.chunks(v.stride).filter(|s| s[4] == lattice).collect();
    let pts = segs.chunks(2).map(|c| [c[0][1] as f64, 0.5 * (c[0][0] + c[0][2]) as f64]).collect();
    (pts, v.meta, v.count)
}

/// Splits poses CSV rows by layer: the tip lies (k + 1)·h out along the normal from the
/// barrel; returns the layer of each row and the barrel point under it.
fn layer_of_rows(rows: &[Vec<f64>], h: f64, layers: usize) -> Vec<(usize, [f64; 3], [f64; 2])> {
    use weft::axisym::platform::{normal, position, Profile};
    let p = weft::axisym::Platform::barrel();
    rows.iter()
        .map(|r| {
            let theta = r[4].atan2(r[3]);
            // For each layer k, the point (k + 1)·h back along the normal; the barrel's height
            // falls from 50 (u = 0) to 0 (u = 2): bisect u on it, then compare the point
            // there (the CSV has 3 decimals in mm).
            let fit = |k: usize| {
                let b: [f64; 3] = std::array::from_fn(|i| r[i] - r[3 + i] * (k + 1) as f64 * h);
                let (mut lo, mut hi) = (0.0, 2.0);
                for _ in 0..80 {
                    let m = 0.5 * (lo + hi);
                    if p.jet(m).z[0] > b[2] {
                        lo = m
                    } else {
                        hi = m
                    }
                }
                let u = 0.5 * (lo + hi);
                let on = position(&p, u, theta);
                let miss = (0..3).map(|i| (on[i] - b[i]).abs()).fold(0.0, f64::max);
                (miss, on, [u, theta])
            };
            let (k, (miss, b, q)) = (0..layers).map(|k| (k, fit(k))).min_by(|a, b| a.1 .0.total_cmp(&b.1 .0)).unwrap();
            assert!(miss < 2e-3, "row {r:?}: no whole number of layer heights out from the barrel (best layer {k}, {miss} mm off)");
            // The tool axis is the platform's normal there (to the CSV's digits and the u the
            // rounded height gives).
            let n = normal(&p, q[0], theta);
            assert!((0..3).all(|i| (n[i] - r[3 + i]).abs() < 1e-3), "{r:?}: axis {n:?}");
            (k, b, q)
        })
        .collect()
}

#[test]
fn three_layers_stack_along_the_normal() {
    let sets = ["job.layers=3".to_string()];
    let d = example("barrel-omega1").with_overrides(&sets).unwrap();
    let h = d.job.value["layer_height_mm"].as_f64().unwrap_or(0.2);
    // The estimate states every layer's points before running (the sum, refused as a whole).
    let plan = pipeline::estimate(&weft::kinds::Registry::builtin(), &mut weft::pipeline::Cache::disabled(), &d, &Files::default()).unwrap();
    let stated = plan.stages.iter().find(|e| e.stage == "axisym_uniform").unwrap().get("points");
    assert!((stated - 3.0 * 538.0).abs() <= 0.03 * 3.0 * 538.0, "{stated}");
    let many = example("barrel-omega1").with_overrides(&["job.layers=100".to_string(), "job.points.density=1".to_string()]).unwrap();
    let plan = pipeline::estimate(&weft::kinds::Registry::builtin(), &mut weft::pipeline::Cache::disabled(), &many, &Files::default()).unwrap();
    eprintln!("100 layers at 100 %: {:?}", plan.refusal);
    assert!(plan.refusal.is_some());
    // The G-code: three extrusion paths (one pass per layer).
    let out = run(&d);
    assert_eq!(out.report.analysis.extrusion_paths, 3);
    let one: PointsSummary = run(&example("barrel-omega1")).report.stage("points").unwrap();
    let points: PointsSummary = out.report.stage("points").unwrap();
    assert_eq!(points, one, "layer 0 is the one-layer job's");
    let report = serde_json::to_value(&out.report).unwrap();
    let path = report["stages"].as_array().unwrap().iter().find(|s| s["stage"] == "path").unwrap();
    let table = path["tables"].as_array().unwrap().iter().find(|t| t["key"] == "layers").unwrap();
    let rows = table["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 3);
    for (k, r) in rows.iter().enumerate() {
        eprintln!("layer table row {k}: {}", r["cells"]);
        assert_eq!(r["cells"][0], k + 1);
        assert!((r["cells"][1].as_f64().unwrap() - k as f64 * h).abs() < 1e-12);
    }

    // The poses, read back: each layer's tips (k + 1)·h out along the barrel's normal, the
    // layers in order, each inside Ω.
    let csv_sets = ["job.layers=3".to_string(), "printer.flavor=poses_csv".to_string(), "printer.machine.kind=cartesian".to_string()];
    let csv_design = example("barrel-omega1").with_overrides(&csv_sets).unwrap();
    let csv = run(&csv_design).gcode;
    let rows: Vec<Vec<f64>> =
        csv.lines().filter(|l| !l.starts_with(';') && !l.is_empty()).skip(1).map(|l| l.split(',').map(|f| f.parse().unwrap()).collect()).collect();
    let layers = layer_of_rows(&rows, h, 3);
    assert!(layers.windows(2).all(|w| w[1].0 >= w[0].0), "layers out of order");
    for k in 0..3 {
        let n = layers.iter().filter(|l| l.0 == k).count();
        assert!(n > 500, "layer {k}: {n} poses");
    }
    for (_, _, q) in &layers {
        assert!(q[0] > 0.8 - 1e-3 && q[0] < 1.2 + 1e-3 && q[1] > -1e-3 && q[1] < 1.0 + 1e-3, "{q:?} outside Ω");
    }
    // Layer k + 1 starts where layer k ended: the nearest of its points, well under a spacing.
    for k in 0..2 {
        let last = layers.iter().rfind(|l| l.0 == k).unwrap().1;
        let first = layers.iter().find(|l| l.0 == k + 1).unwrap().1;
        let gap = ((last[0] - first[0]).powi(2) + (last[1] - first[1]).powi(2) + (last[2] - first[2]).powi(2)).sqrt();
        eprintln!("layer {k} ends {gap:.3} mm (on the platform) from where layer {} starts", k + 1);
        assert!(gap < 0.8, "{gap}");
    }

    // Each layer's own points (the map view steps through them), inside Ω, N from its area.
    let mut cache = weft::pipeline::Cache::new();
    let files = Files::default();
    let mut seen = Vec::new();
    for k in 0..3 {
        let (pts, meta, count) = map_points(&d, &files, &mut cache, k);
        assert_eq!(count, 9);
        assert_eq!(meta["caption"], format!("layer {} of 3: after repulsion", k + 1));
        assert!(pts.iter().all(|q| q[0] >= 0.8 - 1e-6 && q[0] <= 1.2 + 1e-6 && q[1] >= -1e-6 && q[1] <= 1.0 + 1e-6));
        // The outer layers are a little larger (radius + k·h): never fewer points.
        assert!(pts.len() >= one.points, "layer {k}: {} points", pts.len());
        seen.push(pts);
    }
    assert_ne!(seen[0], seen[1], "layers are seeded apart");
}

/// A square tube along x (radially through the barrel's equator): outer y, z half-width 5 mm,
/// inner 2.5 mm, from x = 15 to 35 mm.
fn square_tube() -> weft::geom::Mesh {
    let (o, i, zc) = (5.0f32, 2.5f32, 25.0f32);
    let mut m = weft::geom::Mesh { vertices: Vec::new(), triangles: Vec::new() };
    // Square rings at each end: outer corners 0..4, inner 4..8 (per end).
    for x in [15.0f32, 35.0] {
        for r in [o, i] {
            for (y, z) in [(-r, -r), (r, -r), (r, r), (-r, r)] {
                m.vertices.push([x, y, zc + z]);
            }
        }
    }
    let mut quad = |a: u32, b: u32, c: u32, d: u32| {
        m.triangles.push([a, b, c]);
        m.triangles.push([a, c, d]);
    };
    for s in 0..4u32 {
        let t = (s + 1) % 4;
        quad(s, t, 8 + t, 8 + s); // outer wall
        quad(4 + s, 12 + s, 12 + t, 4 + t); // inner wall
        quad(s, 4 + s, 4 + t, t); // end x = 15
        quad(8 + s, 8 + t, 12 + t, 12 + s); // end x = 35
    }
    m
}

#[test]
fn a_part_with_a_hole_keeps_it_on_every_layer() {
    let mut files = Files::default();
    files.insert("tube.stl".into(), square_tube().to_stl_binary());
    let sets = ["job.domain.kind=part".to_string(), "job.part={\"file\":{\"name\":\"tube.stl\"}}".to_string(), "job.layers=2".to_string()];
    let d = example("barrel-omega1").with_overrides(&sets).unwrap();
    let out = pipeline::run(&d, &files, &RunOptions { collect_preview: false }, &mut |_, _| {}).unwrap();
    let domain: weft::axisym::domain::Domain = serde_json::from_value(out.report.stage_data("domain").unwrap().clone()).unwrap();
    let holes = domain.holes();
    assert_eq!(holes.len(), 1, "{domain:?}");
    // The hole is the inner square: |θ| ≤ asin(2.5/25), u about the equator.
    for q in &holes[0] {
        // (The cut interpolates along the mesh's edges: a few µrad of slack.)
        assert!(q[1].abs() <= (2.5f64 / 25.0).asin() + 1e-3 && (q[0] - 1.0).abs() < 0.3, "{q:?}");
    }
    let report = serde_json::to_value(&out.report).unwrap();
    let dstage = report["stages"].as_array().unwrap().iter().find(|s| s["stage"] == "domain").unwrap();
    let kept = dstage["metrics"].as_array().unwrap().iter().find(|m| m["key"] == "holes").unwrap();
    assert_eq!(kept["label"], "Holes kept");
    assert_eq!(kept["value"], 1.0);
    let points: PointsSummary = out.report.stage("points").unwrap();
    let path: PathSummary = out.report.stage("path").unwrap();
    // Equation 4 on the area between the outline and the hole (about 100 − 25 mm²).
    let want = points.area_mm2 * 0.25 / 0.16;
    assert!(
        (points.points as f64 - want).abs() <= 1.0 && points.area_mm2 > 60.0 && points.area_mm2 < 90.0,
        "{} points, {} mm²",
        points.points,
        points.area_mm2
    );
    eprintln!("tube: area {:.2} mm², N {}, path {:.1} mm, {} segments over the hole", points.area_mm2, points.points, path.length_mm, path.hole_crossings);
    // Segments still crossing the hole are hops without extrusion: one more printed path each.
    let table = report["stages"].as_array().unwrap().iter().find(|s| s["stage"] == "path").unwrap()["tables"]
        .as_array()
        .unwrap()
        .iter()
        .find(|t| t["key"] == "layers")
        .unwrap()
        .clone();
    let hops: usize = table["rows"].as_array().unwrap().iter().map(|r| r["cells"][6].as_u64().unwrap() as usize).sum();
    assert!(hops >= path.hole_crossings && hops <= 8, "{hops} hops");
    // (A hop at a path's end or two in a row add no path.)
    assert!((2..=2 + hops).contains(&out.report.analysis.extrusion_paths), "{} paths, {hops} hops", out.report.analysis.extrusion_paths);
    // Read back from the toolpath: no printed segment's middle lies in the hole (in the map of
    // the platform: θ from x, y; u from the height, monotone on the barrel).
    // The G-code read back by the analyzer (the five-axis head's origin is the bed centre and
    // its pivot 0: X Y Z are the tip).
    assert_eq!(d.printer.origin, weft::gcode::Origin::Center);
    let preview = pipeline::run(&d, &files, &RunOptions { collect_preview: true }, &mut |_, _| {}).unwrap().preview.unwrap();
    let hole = weft::axisym::domain::Domain::Polygon { points: holes[0].clone(), holes: Vec::new() };
    let barrel = weft::axisym::Platform::barrel();
    let u_of = |z: f64| {
        use weft::axisym::platform::Profile;
        let (mut lo, mut hi) = (0.0, 2.0);
        for _ in 0..60 {
            let m = 0.5 * (lo + hi);
            if barrel.jet(m).z[0] > z {
                lo = m
            } else {
                hi = m
            }
        }
        0.5 * (lo + hi)
    };
    let c = holes[0].iter().fold([0.0, 0.0], |s, v| [s[0] + v[0] / holes[0].len() as f64, s[1] + v[1] / holes[0].len() as f64]);
    let mut printed = 0;
    for seg in preview.positions.chunks(6) {
        let m: Vec<f64> = (0..3).map(|i| 0.5 * (seg[i] + seg[3 + i]) as f64).collect();
        // The tip is 0.2–0.4 mm out along a near-horizontal normal: z is the platform's.
        let q = [u_of(m[2]), m[1].atan2(m[0])];
        // 80 % of the hole: the cut's slack and the tip's offset stay out of the test.
        let q80 = [c[0] + (q[0] - c[0]) / 0.8, c[1] + (q[1] - c[1]) / 0.8];
        assert!(!hole.contains(q80), "a printed segment at (u, θ) = {q:?} lies over the hole");
        printed += 1;
    }
    assert!(printed > 100);
    // No point of either layer in the hole (the second layer's domain is its own contour).
    let mut cache = weft::pipeline::Cache::new();
    for k in 0..2 {
        let (pts, _, _) = map_points(&d, &files, &mut cache, k);
        assert!(!pts.is_empty());
        // Layer 1's hole is a touch narrower in θ (radius 25.2 mm): test the middle 90 %.
        let c = holes[0].iter().fold([0.0, 0.0], |s, q| [s[0] + q[0] / holes[0].len() as f64, s[1] + q[1] / holes[0].len() as f64]);
        let shrunk = holes[0].iter().map(|q| [c[0] + 0.9 * (q[0] - c[0]), c[1] + 0.9 * (q[1] - c[1])]).collect();
        let inner = weft::axisym::domain::Domain::Polygon { points: shrunk, holes: Vec::new() };
        assert!(pts.iter().all(|q| !inner.contains(*q)), "layer {k}: a point in the hole");
    }
}

#[test]
fn switching_the_domain_to_a_polygon_starts_from_the_rectangle() {
    // The form switches the kind alone: the design stays valid, the outline is the rectangle's.
    let d = example("barrel-omega1").with_overrides(&["job.domain.kind=polygon".into()]).unwrap();
    assert!(d.validate().is_empty(), "{:?}", d.validate());
    let j: weft::kinds::axisymmetric::AxisymJob = d.job.settings().unwrap();
    assert_eq!(j.domain.polygon, vec![[0.8, 0.0], [1.2, 0.0], [1.2, 1.0], [0.8, 1.0]]);
    // Same points as the rectangle: the same (u, θ) region.
    let a: PointsSummary = run(&example("barrel-omega1")).report.stage("points").unwrap();
    let b: PointsSummary = run(&d).report.stage("points").unwrap();
    assert_eq!(a.points, b.points);
    assert!(serde_json::from_str::<weft::kinds::axisymmetric::DomainSpec>(r#"{"kind":"polygon","polgon":[]}"#).is_err(), "unknown fields are still refused");
    // The map offers to draw a polygon domain (which field, and that its pairs are (u, θ) =
    // (y, x) of the map), and not a rectangle.
    let mut cache = weft::pipeline::Cache::new();
    let registry = weft::kinds::Registry::builtin();
    let v = pipeline::inspect(&registry, &mut cache, &d, &Files::default(), "map", 1).unwrap();
    assert_eq!(v.meta["draw"]["path"], "job.domain.polygon");
    assert_eq!(v.meta["draw"]["pair"], serde_json::json!(["y", "x"]));
    let v = pipeline::inspect(&registry, &mut cache, &example("barrel-omega1"), &Files::default(), "map", 1).unwrap();
    assert!(v.meta["draw"].is_null());
    assert_eq!(v.meta["legend"][weft::geom::Feature::Contour.code().to_string()], "outline of Ω");
}

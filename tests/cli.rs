//! End-to-end runs of the `weft` binary: designs in, G-code out, read back by the analyzer.

use std::path::{Path, PathBuf};
use std::process::Command;

fn weft() -> Command {
    Command::new(env!("CARGO_BIN_EXE_weft"))
}

fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("weft-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn run_ok(args: &[&str]) -> String {
    let out = weft().args(args).output().unwrap();
    assert!(out.status.success(), "weft {args:?} failed: {}", String::from_utf8_lossy(&out.stderr));
    String::from_utf8(out.stdout).unwrap()
}

fn run_err(args: &[&str]) -> String {
    let out = weft().args(args).output().unwrap();
    assert!(!out.status.success(), "weft {args:?} should fail");
    let err = String::from_utf8(out.stderr).unwrap();
    assert_eq!(err.trim_end().lines().count(), 1, "one-line error expected, got:\n{err}");
    assert!(err.starts_with("weft: error: "), "{err}");
    err
}

fn analyze(path: &Path) -> serde_json::Value {
    serde_json::from_str(&run_ok(&["analyze", path.to_str().unwrap(), "--json"])).unwrap()
}

fn repo(path: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(path).to_str().unwrap().to_string()
}

#[test]
fn every_example_runs_and_reads_back() {
    for entry in std::fs::read_dir(repo("examples")).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().and_then(|e| e.to_str()) != Some("json") {
            continue;
        }
        let stem = path.file_stem().unwrap().to_str().unwrap().to_string();
        let out = tmp(&format!("{stem}.gcode"));
        let report = tmp(&format!("{stem}.report.json"));
        run_ok(&["run", path.to_str().unwrap(), "--out", out.to_str().unwrap(), "--report", report.to_str().unwrap(), "-q"]);
        let a = analyze(&out);
        let r: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
        assert!(a["layers"].as_u64().unwrap() > 0, "{stem}: no layers");
        // The CLI's analysis of the file equals the report written with it.
        assert_eq!(a, r["analysis"], "{stem}: report and re-analysis differ");
        // Extruded length read back from the G-code equals the writer's nominal length.
        let nominal = r["gcode"]["extruded_mm"].as_f64().unwrap();
        let read = a["extruded_mm"].as_f64().unwrap();
        assert!((nominal - read).abs() <= 1e-3 * nominal, "{stem}: extruded {read} vs nominal {nominal}");
        // Nothing is printed twice: prisms exactly 0; the sphere's thin solid rings near its
        // dome stay under 0.01 % of the extruded length (known: connectors on both ring edges).
        let overlap = a["overlap_mm"].as_f64().unwrap();
        if stem.starts_with("sphere") {
            assert!(overlap <= 1e-4 * read, "{stem}: overlap {overlap} mm");
        } else {
            assert_eq!(overlap, 0.0, "{stem}: overlap {overlap} mm");
        }
    }
}

#[test]
fn same_design_same_bytes_and_set_changes_them() {
    let design = repo("examples/cube-20mm.json");
    let (a, b, c) = (tmp("a.gcode"), tmp("b.gcode"), tmp("c.gcode"));
    run_ok(&["run", &design, "--out", a.to_str().unwrap(), "-q"]);
    run_ok(&["run", &design, "--out", b.to_str().unwrap(), "-q"]);
    assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
    run_ok(&["run", &design, "--out", c.to_str().unwrap(), "-q", "--set", "job.slice.layer_height_mm=0.1"]);
    let (la, lc) = (analyze(&a)["layers"].as_u64().unwrap(), analyze(&c)["layers"].as_u64().unwrap());
    assert_eq!(la, 100, "20 mm at 0.2 mm");
    assert_eq!(lc, 1 + 198, "0.2 mm first layer then 0.1 mm layers to 20 mm");
}

#[test]
fn input_replaces_the_design_mesh() {
    let mesh = tmp("slab.stl");
    let m = weft::geom::shapes::Shape::Cube { size: [30.0, 10.0, 2.0] }.mesh();
    std::fs::write(&mesh, m.to_stl_binary()).unwrap();
    let out = tmp("slab.gcode");
    run_ok(&["run", &repo("examples/cube-20mm.json"), "--input", mesh.to_str().unwrap(), "--out", out.to_str().unwrap(), "-q"]);
    assert_eq!(analyze(&out)["layers"].as_u64().unwrap(), 10);
}

#[test]
fn bad_inputs_fail_with_one_line() {
    let e = run_err(&["run", "/nonexistent/design.json"]);
    assert!(e.contains("/nonexistent/design.json"), "{e}");
    let bad = tmp("bad.json");
    std::fs::write(&bad, "{\"version\": 1, \"name\": \"x\", \"job\": {\"kind\": \"slice\", \"input\": {\"builtin\": {\"shape\": \"cube\", \"size\": [1,1,1]}}, \"slice\": {\"infill_density\": 3}}}").unwrap();
    let e = run_err(&["run", bad.to_str().unwrap()]);
    assert!(e.contains("job.slice.infill_density") && e.contains("0 to 1"), "{e}");
    let e = run_err(&["run", &repo("examples/cube-20mm.json"), "--set", "job.slice.bogus=1"]);
    assert!(e.contains("bogus"), "{e}");
    let corrupt = tmp("corrupt.stl");
    std::fs::write(&corrupt, "solid x\nfacet normal 0 0 1\nouter loop\nvertex 1 2\n").unwrap();
    let e = run_err(&["run", &repo("examples/cube-20mm.json"), "--input", corrupt.to_str().unwrap()]);
    assert!(e.contains("corrupt.stl") && e.contains("line"), "{e}");
    let e = run_err(&["analyze", "/nonexistent.gcode"]);
    assert!(e.contains("nonexistent.gcode"), "{e}");
}

#[test]
fn share_fragment_runs_like_the_file() {
    let design = repo("examples/sphere-30mm.json");
    let fragment = run_ok(&["share", &design]).trim().to_string();
    assert!(fragment.starts_with("#d="));
    let (a, b) = (tmp("share-a.gcode"), tmp("share-b.gcode"));
    run_ok(&["run", &design, "--out", a.to_str().unwrap(), "-q"]);
    run_ok(&["run", &fragment, "--out", b.to_str().unwrap(), "-q"]);
    assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
}

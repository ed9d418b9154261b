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
        // The graded phantom's gyroid: 1.3 mm of 56 m where two clipped gyroid pieces touch
        // (known, in the issue-11 note), also under 0.01 %.
        // A foam's one thread reaches the next cell of a layer along the outline or over a line
        // already printed: its overlap lies within those links (the raster stage's "turns" and
        // "lines run twice"), never on the scan lines themselves.
        if stem.starts_with("foam") {
            let raster = r["stages"].as_array().unwrap().iter().find(|s| s["stage"] == "raster").unwrap();
            let metric = |k: &str| raster["metrics"].as_array().unwrap().iter().find(|m| m["key"] == k).unwrap()["value"].as_f64().unwrap();
            assert!(overlap <= metric("turns") + metric("retraced"), "{stem}: overlap {overlap} mm beyond the links");
        } else if stem.starts_with("sphere") || stem.starts_with("graded") {
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

/// A small valid design (a 5 mm cube, fast to slice) named `name`, as JSON.
fn named_design(name: &str) -> String {
    let mut v: serde_json::Value = serde_json::from_str(&weft::Design::default().to_json_pretty()).unwrap();
    v["name"] = name.into();
    v["job"]["input"] = serde_json::json!({"builtin": {"shape": "cube", "size": [5, 5, 2]}});
    v.to_string()
}

/// Every file under `dir`, recursively.
fn files_under(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else {
                out.push(p);
            }
        }
    }
    out
}

#[test]
fn hostile_design_names_write_inside_the_folder() {
    // The sandbox: runs happen in sandbox/a/b/work; an escape would land elsewhere in the sandbox
    // (never outside it: the absolute name points into it too).
    let sandbox = tmp("hostile-names");
    let _ = std::fs::remove_dir_all(&sandbox);
    let work = sandbox.join("a/b/work");
    let outside = sandbox.join("outside");
    std::fs::create_dir_all(&work).unwrap();
    std::fs::create_dir_all(&outside).unwrap();
    let designs = sandbox.join("designs");
    std::fs::create_dir_all(&designs).unwrap();
    let absolute = format!("{}/x", outside.display());
    let long = "L".repeat(250);
    let cases: Vec<(&str, &str)> = vec![
        (&absolute, ""),
        ("../../x", "x.gcode"),
        ("..", "design.gcode"),
        (".bashrc", "bashrc.gcode"),
        ("a\\b", "a_b.gcode"),
        ("C:\\x", "C_x.gcode"),
        ("CON", "_CON.gcode"),
        ("nul.txt", "_nul.txt.gcode"),
        ("Würfel 立方体", "Würfel 立方体.gcode"),
        (&long, ""),
    ];
    for (i, (name, want)) in cases.iter().enumerate() {
        let design = designs.join(format!("{i}.json"));
        std::fs::write(&design, named_design(name)).unwrap();
        let out = weft().current_dir(&work).args(["run", design.to_str().unwrap(), "-q"]).output().unwrap();
        assert!(out.status.success(), "{name:?}: {}", String::from_utf8_lossy(&out.stderr));
        let made: Vec<PathBuf> = files_under(&sandbox).into_iter().filter(|p| !p.starts_with(&designs)).collect();
        assert_eq!(made.len(), 1, "{name:?}: {made:?}");
        assert_eq!(made[0].parent(), Some(work.as_path()), "{name:?} wrote {}", made[0].display());
        let file = made[0].file_name().unwrap().to_str().unwrap().to_string();
        if want.is_empty() {
            assert!(file.len() <= weft::design::MAX_FILE_STEM_BYTES + 6 && file.ends_with("_outside_x.gcode") || file.starts_with("LLL"), "{file}");
        } else {
            assert_eq!(file, *want, "{name:?}");
        }
        std::fs::remove_file(&made[0]).unwrap();
    }
    // Names with control characters (NUL, line breaks) or over the length limit are refused.
    for name in ["a\0b", "x\nG28", &"n".repeat(10_000)] {
        let design = designs.join("refused.json");
        std::fs::write(&design, named_design(name)).unwrap();
        let out = weft().current_dir(&work).args(["run", design.to_str().unwrap(), "-q"]).output().unwrap();
        assert!(!out.status.success(), "{name:?}");
        let err = String::from_utf8(out.stderr).unwrap();
        assert!(err.len() < 500 && err.contains("name: "), "{err}");
        assert!(files_under(&sandbox).iter().all(|p| p.starts_with(&designs)), "{name:?}");
    }
    // --out naming a folder: the file goes in it, named after the design; so does the report.
    let folder = sandbox.join("out");
    std::fs::create_dir_all(&folder).unwrap();
    let design = designs.join("to-folder.json");
    std::fs::write(&design, named_design("../../escape")).unwrap();
    run_ok(&["run", design.to_str().unwrap(), "--out", folder.to_str().unwrap(), "--report", folder.to_str().unwrap(), "-q"]);
    let mut made: Vec<String> = files_under(&folder).iter().map(|p| p.strip_prefix(&folder).unwrap().display().to_string()).collect();
    made.sort();
    assert_eq!(made, ["escape.gcode", "escape.report.json"]);
}

#[test]
fn hostile_designs_fail_with_one_short_line() {
    let dir = tmp("hostile-designs");
    std::fs::create_dir_all(&dir).unwrap();
    let design = repo("examples/cube-20mm.json");
    let short = |e: &str| assert!(e.len() < 1000, "{} bytes: {}", e.len(), &e[..300]);
    // A 1 MB name: refused by length, the name not repeated.
    let long = dir.join("long-name.json");
    std::fs::write(&long, weft::testgen::design::long_name_design(1 << 20)).unwrap();
    let e = run_err(&["run", long.to_str().unwrap(), "--out", dir.join("x.gcode").to_str().unwrap()]);
    short(&e);
    assert!(e.contains("name: ") && e.contains("1048576 bytes") && e.contains("limit of 256"), "{e}");
    // A template bomb: 5 000 × {design_name} with a 256-byte name.
    let bomb = dir.join("bomb.json");
    let mut v: serde_json::Value = serde_json::from_str(&named_design(&"n".repeat(256))).unwrap();
    v["printer"]["start_gcode"] = weft::testgen::design::template_bomb(5000).into();
    std::fs::write(&bomb, v.to_string()).unwrap();
    let e = run_err(&["run", bomb.to_str().unwrap(), "--out", dir.join("bomb.gcode").to_str().unwrap()]);
    short(&e);
    assert!(e.contains("start_gcode") && e.contains("1280250 bytes") && e.contains("1048576"), "{e}");
    // 50 000 nested --set keys (about 100 kB: under the OS limit of one argument).
    let e = run_err(&["run", &design, "--set", &weft::testgen::design::deep_set_path(50_000)]);
    short(&e);
    assert!(e.contains("50000 keys") && e.contains("limit of 32"), "{e}");
    // A design nested 100 000 deep.
    let deep = dir.join("deep.json");
    std::fs::write(&deep, weft::testgen::design::nested_design_json(100_000)).unwrap();
    let e = run_err(&["run", deep.to_str().unwrap()]);
    short(&e);
    assert!(e.contains("nested more than 128 levels deep, the limit"), "{e}");
    // A 3 kB share link whose design inflates to a 350 kB name; a link that inflates past the limit.
    let e = run_err(&["run", &weft::testgen::design::share_bomb_fragment(3000)]);
    short(&e);
    assert!(e.contains("name: ") && e.contains("limit of 256"), "{e}");
    let e = run_err(&["run", &weft::testgen::design::share_bomb_fragment(100_000)]);
    short(&e);
    assert!(e.contains(&format!("more than {} bytes", weft::design::MAX_DESIGN_BYTES)), "{e}");
}

#[test]
fn a_closed_stdout_ends_quietly() {
    use std::io::Read;
    // 20 000 layers: the JSON report (4 MB) is far larger than a pipe holds, so the writer
    // meets the closed pipe.
    let gcode = tmp("many-layers.gcode");
    let mut text = String::from("G90\nM82\n");
    for i in 1..=20_000 {
        text += &format!("G1 Z{:.3} F600\nG1 X10 Y10 E{i}\nG1 X0 Y0\n", 0.2 * i as f64);
    }
    std::fs::write(&gcode, text).unwrap();
    let mut child =
        weft().args(["analyze", gcode.to_str().unwrap(), "--json"]).stdout(std::process::Stdio::piped()).stderr(std::process::Stdio::piped()).spawn().unwrap();
    let mut stdout = child.stdout.take().unwrap();
    let mut first = [0u8; 16];
    stdout.read_exact(&mut first).unwrap();
    assert_eq!(first[0], b'{');
    drop(stdout); // `| head -c 16`
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!err.contains("panicked") && err.is_empty(), "stderr: {err}");
    assert!(out.status.success(), "{:?}", out.status);
}

#[test]
fn file_errors_are_in_words() {
    let e = run_err(&["run", "/nonexistent/design.json"]);
    assert_eq!(e.trim_end(), "weft: error: /nonexistent/design.json: cannot read it: there is no such file or folder");
    let dir = std::env::temp_dir();
    let e = run_err(&["analyze", dir.to_str().unwrap()]);
    assert_eq!(e.trim_end(), format!("weft: error: {}: cannot read it: it is a folder, not a file", dir.display()));
}

#[test]
fn set_errors_name_the_field_and_the_fix() {
    let honeycomb = repo("examples/honeycomb-10mm.json");
    for (set, want) in [
        ("job.paths.method=eulr", "--set: job.paths.method: 'eulr' is not a choice for Optimiser; use one of: gippo_max, gippo_min, euler, continuous"),
        ("job.paths.iterations=2.5", "--set: job.paths.iterations: GIPPO iterations must be a whole number from 1 to 100000 (got 2.5)"),
        ("job.paths.iteratons=5", "--set: job.paths.iteratons: is not a setting (did you mean 'iterations'?); the settings of job.paths are: method, iterations, order, merge_tolerance_mm, short_path_segments, short_path_speed_factor, exact_pairing_seconds, direction_deg"),
        ("printer.relative_e=yes", "--set: printer.relative_e: Relative extrusion (M83) must be true or false (got \"yes\")"),
    ] {
        let e = run_err(&["run", &honeycomb, "--dry-run", "--set", set]);
        assert_eq!(e.trim_end(), format!("weft: error: {want}"), "{set}");
    }
    let junk = tmp("junk.stl");
    std::fs::write(&junk, (0..300u32).map(|i| (i.wrapping_mul(2654435761) >> 13) as u8).collect::<Vec<u8>>()).unwrap();
    let e = run_err(&["run", &honeycomb, "--input", junk.to_str().unwrap(), "--dry-run"]);
    assert_eq!(
        e.trim_end(),
        "weft: error: junk.stl is not an STL file: its size does not fit the triangle count a binary STL states at byte 80, and it does not start with the word \"solid\" as a text STL does; export the mesh again as STL, OBJ or 3MF"
    );
}

/// `weft run` of `design` with `input` (`FILE` or `SLOT=FILE`), under an address-space limit
/// of 400 MB (far below the inputs below): its stderr.
fn run_limited(design: &str, input: &str) -> String {
    let script =
        format!("ulimit -v 400000 && exec '{}' run '{}' --input '{}' -o '{}'", env!("CARGO_BIN_EXE_weft"), repo(design), input, tmp("huge.gcode").display());
    let out = Command::new("sh").args(["-c", &script]).output().unwrap();
    assert!(!out.status.success());
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// A sparse file: `head`, then zeros up to `len` bytes (no disk used).
fn sparse(name: &str, head: &[u8], len: u64) -> PathBuf {
    let path = tmp(name);
    std::fs::write(&path, head).unwrap();
    std::fs::OpenOptions::new().write(true).open(&path).unwrap().set_len(len).unwrap();
    path
}

/// A mesh over the limits is refused from its head and size, before the file is read: under
/// the address-space limit the refusal is the limit's (not "out of memory"). A binary STL
/// over the triangle limit, and any mesh file over the import's memory limit.
#[test]
fn a_huge_mesh_is_refused_before_it_is_read() {
    let n: u32 = 10_000_000;
    let mut head = vec![0u8; 80];
    head.extend_from_slice(&n.to_le_bytes());
    let stl = sparse("huge-10m.stl", &head, 84 + 50 * n as u64);
    let err = run_limited("examples/cube-20mm.json", &stl.display().to_string());
    assert!(err.contains("huge-10m.stl: the mesh has 10,000,000 triangles, limit 5,000,000"), "{err}");
    assert!(err.contains("decimate"), "{err}");
    let obj = sparse("huge-5g.obj", b"v 0 0 0\n", 5 << 30);
    let err = run_limited("examples/cube-20mm.json", &obj.display().to_string());
    assert!(err.contains("huge-5g.obj: the file is 5,120 MiB, more than the 1,024 MiB weft reads a mesh from"), "{err}");
    // A slot of several meshes (a foam's regions) checks each file the same way.
    let err = run_limited("examples/foam-dogbone-linear.json", &format!("regions={}", stl.display()));
    assert!(err.contains("huge-10m.stl: the mesh has 10,000,000 triangles, limit 5,000,000"), "{err}");
    for p in [stl, obj] {
        let _ = std::fs::remove_file(p);
    }
}

/// Volume files, another slicer's G-code and a design over their limits are refused from
/// their size before they are read (under the address-space limit the refusal is the
/// limit's, not "out of memory"); a series' files are refused by their total too.
#[test]
fn huge_volumes_gcode_and_designs_are_refused_before_they_are_read() {
    let raw = sparse("huge-5g.raw", b"", 5 << 30);
    let err = run_limited("examples/graded-phantom.json", &format!("volume={}", raw.display()));
    assert!(err.contains("huge-5g.raw: 5,120 MiB is more than the 1,280 MiB of files a volume is read from (134,217,728 voxels"), "{err}");
    assert!(err.contains("crop or resample"), "{err}");
    // A folder of files each under the limit, over it together.
    let dir = tmp("huge-series");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    for k in 0..3 {
        std::fs::OpenOptions::new().create(true).truncate(true).write(true).open(dir.join(format!("s{k}.dcm"))).unwrap().set_len(600 << 20).unwrap();
    }
    let err = run_limited("examples/graded-phantom.json", &format!("volume={}", dir.display()));
    assert!(err.contains("huge-series (all its files): 1,800 MiB is more than"), "{err}");
    // The same files given one by one: their running total is checked before each is read.
    let args: Vec<String> = (0..3).map(|k| format!("volume={}", dir.join(format!("s{k}.dcm")).display())).collect();
    let err = run_limited("examples/graded-phantom.json", &args.join("' --input '"));
    assert!(err.contains("the files given for 'volume': 1,800 MiB is more than"), "{err}");
    let gcode = sparse("huge-2g.gcode", b"G1 X0\n", 2 << 30);
    let err = run_limited("examples/graded-phantom.json", &format!("gcode={}", gcode.display()));
    assert!(err.contains("huge-2g.gcode:") && err.contains("the G-code to edit"), "{err}");
    // `weft analyze` of G-code over the analyzer's limit: refused from its size, not read.
    let big = sparse("huge-analyze.gcode", b"G1 X0\n", 2 << 30);
    let out =
        Command::new("sh").args(["-c", &format!("ulimit -v 400000 && exec '{}' analyze '{}'", env!("CARGO_BIN_EXE_weft"), big.display())]).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!out.status.success());
    assert!(err.contains("huge-analyze.gcode: the file is 2,048 MiB, more than the 1,024 MiB weft analyses: split it"), "{err}");
    let _ = std::fs::remove_file(big);
    let design = sparse("huge-design.json", b"{", 3 << 30);
    let out =
        Command::new("sh").args(["-c", &format!("ulimit -v 400000 && exec '{}' run '{}'", env!("CARGO_BIN_EXE_weft"), design.display())]).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!out.status.success());
    assert!(err.contains("huge-design.json: the design is 3221225472 bytes, over the limit"), "{err}");
    for p in [raw, gcode, design] {
        let _ = std::fs::remove_file(p);
    }
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn an_output_named_bgcode_is_binary_gcode_of_the_same_text() {
    let (text, binary) = (tmp("cube.gcode"), tmp("cube.bgcode"));
    run_ok(&["run", &repo("examples/cube-20mm.json"), "-q", "-o", text.to_str().unwrap()]);
    run_ok(&["run", &repo("examples/cube-20mm.json"), "-q", "-o", binary.to_str().unwrap()]);
    let (t, b) = (std::fs::read_to_string(&text).unwrap(), std::fs::read(&binary).unwrap());
    assert_eq!(b, weft::gcode::binary::from_text(&t));
    // The printer's setting does it too, into <name>.bgcode; a non-Marlin flavour refuses it.
    let dir = tmp("bg");
    std::fs::create_dir_all(&dir).unwrap();
    run_ok(&["run", &repo("examples/cube-20mm.json"), "-q", "--set", "printer.binary_gcode=true", "-o", dir.to_str().unwrap()]);
    assert_eq!(std::fs::read(dir.join("cube-20mm.bgcode")).unwrap(), b);
    // A name ending in .gcode is text whatever the printer asks; the Prusa MK4 profile writes
    // binary by default into a folder (made when the name ends in /) and text when named .gcode.
    let named = tmp("asked.gcode");
    run_ok(&["run", &repo("examples/cube-20mm.json"), "-q", "--set", "printer.binary_gcode=true", "-o", named.to_str().unwrap()]);
    assert_eq!(std::fs::read_to_string(&named).unwrap(), t);
    let mk4 = format!("{}/", tmp("mk4-new-folder").display());
    let _ = std::fs::remove_dir_all(&mk4);
    run_ok(&["run", &repo("examples/cube-20mm.json"), "-q", "--printer", "prusa-mk4", "-o", &mk4]);
    let mk4_binary = std::fs::read(format!("{mk4}cube-20mm.bgcode")).unwrap();
    run_ok(&["run", &repo("examples/cube-20mm.json"), "-q", "--printer", "prusa-mk4", "-o", &format!("{mk4}text.gcode")]);
    let mk4_text = std::fs::read_to_string(format!("{mk4}text.gcode")).unwrap();
    assert!(mk4_text.contains("; printer_model = MK4\n") && mk4_text.contains("; thumbnail_QOI begin 440x240 "), "MK4 header");
    assert_eq!(mk4_binary, weft::gcode::binary::from_text(&mk4_text));
    let out = weft()
        .args(["run", &repo("examples/cube-20mm.json"), "-q", "--set", "printer.flavor=pneumatic", "-o", tmp("x.bgcode").to_str().unwrap()])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("binary G-code is Marlin G-code"), "{err}");
}

#[test]
fn run_then_send_writes_the_file_first_and_says_why_the_host_did_not_take_it() {
    // A loopback port nothing listens on (bound, then freed).
    let port = std::net::TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port();
    let out = tmp("sent.gcode");
    let _ = std::fs::remove_file(&out);
    let url = format!("http://127.0.0.1:{port}");
    let err = run_err(&["run", &repo("examples/cube-20mm.json"), "-q", "-o", out.to_str().unwrap(), "--send", "moonraker", "--send-url", &url]);
    assert!(err.contains(&format!("Cannot reach 127.0.0.1:{port}")) && err.lines().count() == 1, "{err}");
    // The G-code is written before sending, and is the same bytes as a run without --send.
    let plain = tmp("plain.gcode");
    run_ok(&["run", &repo("examples/cube-20mm.json"), "-q", "-o", plain.to_str().unwrap()]);
    assert_eq!(std::fs::read(&out).unwrap(), std::fs::read(&plain).unwrap());
    // --dry-run writes nothing to send; a URL without a kind is refused by the argument parser.
    let err = run_err(&["run", &repo("examples/cube-20mm.json"), "--dry-run", "--send-to", "octoprint", "--send-url", &url]);
    assert!(err.contains("--dry-run writes none"), "{err}");
    let o = weft().args(["run", &repo("examples/cube-20mm.json"), "--send-url", &url]).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("--send-to <KIND>"), "{err}");
}

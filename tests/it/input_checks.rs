//! Files from other people's tools are never silently misread: a solid slot's open or
//! inside-out mesh is repaired out loud or refused by its hole; inputs given one by one, as a
//! folder or with `--set` in any order make the same design; a wireframe's grounding is stated
//! and an implausible one warned of; wireframes come from triangle meshes too; the writer
//! leaves no dust. Read back from the G-code and the report, through the pipeline and the
//! `weft` binary.

use crate::common::{example, root};
use std::path::{Path, PathBuf};
use std::process::Command;
use weft::design::Input;
use weft::geom::Mesh;
use weft::pipeline::Files;

/// A closed box, triangles facing out; `drop` leaves out the listed triangles (two per face:
/// 0–1 bottom, 2–3 top, 4–5 front y = y0, 6–7 right x = x1, 8–9 back, 10–11 left).
fn box_mesh(lo: [f32; 3], hi: [f32; 3], drop: &[usize]) -> Mesh {
    let [x0, y0, z0] = lo;
    let [x1, y1, z1] = hi;
    let vertices = vec![[x0, y0, z0], [x1, y0, z0], [x1, y1, z0], [x0, y1, z0], [x0, y0, z1], [x1, y0, z1], [x1, y1, z1], [x0, y1, z1]];
    let all = [[0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7], [0, 1, 5], [0, 5, 4], [1, 2, 6], [1, 6, 5], [2, 3, 7], [2, 7, 6], [3, 0, 4], [3, 4, 7]];
    let triangles = all.iter().enumerate().filter(|(i, _)| !drop.contains(i)).map(|(_, t)| *t).collect();
    Mesh { vertices, triangles }
}

fn temp_dir(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("weft-input-checks-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn weft(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_weft")).args(args).output().unwrap()
}

fn run_files(design: &weft::design::Design, files: &[(&str, Vec<u8>)]) -> Result<weft::pipeline::RunOutput, String> {
    let mut f = Files::new();
    for (name, bytes) in files {
        f.insert((*name).into(), bytes.clone());
    }
    crate::common::run(design, &f)
}

fn notes(out: &weft::pipeline::RunOutput) -> Vec<String> {
    out.report.stages.iter().flat_map(|s| s.notes.iter().cloned()).collect()
}

/// A foam of two touching boxes from files, with the dogbone example's pairs and transition.
fn foam_of(names: &[&str]) -> weft::design::Design {
    let d = example("foam-dogbone-linear");
    let input = Input::Files(names.iter().map(|n| n.to_string()).collect());
    d.with_changes_in(&weft::kinds::Registry::builtin(), &[("regions".into(), input)], &[]).unwrap()
}

#[test]
fn an_open_region_is_capped_out_loud_and_prints_the_whole_part() {
    let a = box_mesh([0.0, 0.0, 0.0], [30.0, 10.0, 3.0], &[]).to_stl_binary();
    let b = box_mesh([30.0, 0.0, 0.0], [60.0, 10.0, 3.0], &[]).to_stl_binary();
    // A side wall missing (the paper's dogbone half printed as half of itself before).
    let a_open = box_mesh([0.0, 0.0, 0.0], [30.0, 10.0, 3.0], &[4, 5]).to_stl_binary();
    // The shared face missing: the regions still touch once it is capped.
    let a_no_shared = box_mesh([0.0, 0.0, 0.0], [30.0, 10.0, 3.0], &[6, 7]).to_stl_binary();
    let d = foam_of(&["A.stl", "B.stl"]);
    let closed = run_files(&d, &[("A.stl", a.clone()), ("B.stl", b.clone())]).unwrap();
    assert!(notes(&closed).iter().all(|n| !n.contains("capped")), "{:?}", notes(&closed));
    for (what, open) in [("a side wall", a_open), ("the shared face", a_no_shared)] {
        let out = run_files(&d, &[("A.stl", open), ("B.stl", b.clone())]).unwrap_or_else(|e| panic!("{what}: {e}"));
        assert!(out.gcode == closed.gcode, "{what} missing: the capped region prints as the closed one");
        let said = notes(&out);
        assert!(said.iter().any(|n| n.contains("A.stl: capped 1 flat hole of 4 edges") && n.contains("mm²")), "{what}: {said:?}");
        let import = out.report.stages.iter().find(|s| s.stage == "import" && !s.notes.is_empty()).expect("the import says it");
        let capped = import.metrics.iter().find(|m| m.key == "holes_capped").expect("holes capped metric");
        assert_eq!(capped.value, 1.0);
    }
}

#[test]
fn holes_that_cannot_be_capped_are_refused_by_place_with_the_real_cause() {
    let b = box_mesh([30.0, 0.0, 0.0], [60.0, 10.0, 3.0], &[]).to_stl_binary();
    // The top and a wall missing: one hole whose rim bends over an edge.
    let bent = box_mesh([0.0, 0.0, 0.0], [30.0, 10.0, 3.0], &[2, 3, 6, 7]).to_stl_binary();
    let e = run_files(&foam_of(&["A.stl", "B.stl"]), &[("A.stl", bent.clone()), ("B.stl", b)]).unwrap_err();
    assert!(e.contains("A.stl is not a closed solid") && e.contains("is not flat") && e.contains("mm² around (") && !e.contains("do not touch"), "{e}");
    // The slice job refuses it the same way (one check per slot kind), and so does the CLI.
    let mut d = example("cube-20mm");
    d = d.with_changes_in(&weft::kinds::Registry::builtin(), &[("mesh".into(), Input::File { name: "A.stl".into(), embedded: None })], &[]).unwrap();
    let e = run_files(&d, &[("A.stl", bent.clone())]).unwrap_err();
    assert!(e.contains("A.stl is not a closed solid"), "{e}");
    let dir = temp_dir("refused");
    let path = dir.join("A.stl");
    std::fs::write(&path, &bent).unwrap();
    let o = weft(&[
        "run",
        root().join("examples/cube-20mm.json").to_str().unwrap(),
        "--input",
        path.to_str().unwrap(),
        "--out",
        dir.join("x.gcode").to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && stderr.contains("is not a closed solid") && stderr.contains("is not flat"), "{stderr}");
    assert!(!dir.join("x.gcode").exists(), "nothing written for a refused part");
    // An open sheet is not a solid with a hole.
    let sheet = box_mesh([0.0, 0.0, 0.0], [30.0, 10.0, 3.0], &[2, 3, 4, 5, 6, 7, 8, 9, 10, 11]).to_stl_binary();
    let e = run_files(&d, &[("A.stl", sheet)]).unwrap_err();
    assert!(e.contains("an open surface, not a solid"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn an_inside_out_part_slices_as_the_part_and_says_so() {
    let right = box_mesh([0.0, 0.0, 0.0], [20.0, 20.0, 10.0], &[]);
    let mut inverted = right.clone();
    for t in &mut inverted.triangles {
        t.swap(1, 2);
    }
    let d = example("cube-20mm")
        .with_changes_in(&weft::kinds::Registry::builtin(), &[("mesh".into(), Input::File { name: "part.stl".into(), embedded: None })], &[])
        .unwrap();
    let good = run_files(&d, &[("part.stl", right.to_stl_binary())]).unwrap();
    let turned = run_files(&d, &[("part.stl", inverted.to_stl_binary())]).unwrap();
    assert!(turned.gcode == good.gcode, "the turned part prints as the part");
    assert!(good.report.analysis.extruded_mm > 1000.0);
    assert!(notes(&turned).iter().any(|n| n.contains("turned 12 triangles facing inward")), "{:?}", notes(&turned));
    // A surface slot takes an open mesh as it is: nothing capped, nothing said.
    let registry = weft::kinds::Registry::builtin();
    let surface = registry.slot("surface").unwrap();
    assert_eq!(surface.kind, weft::kinds::SlotKind::Surface);
    assert!(!surface.kind.solid() && registry.slot("mesh").unwrap().kind.solid() && registry.slot("regions").unwrap().kind.solid());
}

/// The G-code and stderr of `weft run` of the foam example with `args`.
fn foam_cli(dir: &Path, tag: &str, args: &[&str]) -> (Vec<u8>, String) {
    let out = dir.join(format!("{tag}.gcode"));
    let mut all = vec!["run", "examples/foam-dogbone-linear.json"];
    all.extend_from_slice(args);
    all.extend_from_slice(&["--out", out.to_str().unwrap(), "-q"]);
    let o = Command::new(env!("CARGO_BIN_EXE_weft")).current_dir(root()).args(&all).output().unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(o.status.success(), "{tag}: {stderr}");
    (std::fs::read(&out).unwrap(), stderr)
}

#[test]
fn inputs_one_by_one_a_folder_and_settings_in_any_order_make_the_same_gcode() {
    let dir = temp_dir("order");
    let folder = dir.join("regions");
    std::fs::create_dir_all(&folder).unwrap();
    std::fs::write(folder.join("A.stl"), box_mesh([0.0, 0.0, 0.0], [30.0, 10.0, 3.0], &[]).to_stl_binary()).unwrap();
    std::fs::write(folder.join("B.stl"), box_mesh([30.0, 0.0, 0.0], [60.0, 10.0, 3.0], &[]).to_stl_binary()).unwrap();
    let (a, b, f) = (folder.join("A.stl"), folder.join("B.stl"), folder.clone());
    let (a, b, f) = (format!("regions={}", a.display()), format!("regions={}", b.display()), format!("regions={}", f.display()));
    let sets = ["--set", "job.regions.1.v_star=0.35", "--set", "job.regions.1.h_star=10"];
    let one_by_one = foam_cli(&dir, "one", &[&["--input", &a, "--input", &b][..], &sets].concat());
    let folder_run = foam_cli(&dir, "folder", &[&["--input", &f][..], &sets].concat());
    let sets_first = foam_cli(&dir, "sets-first", &[&sets[..], &["--input", &a, "--input", &b]].concat());
    // A zip of the folder (with a file that is not a mesh, left out and said).
    let zip_path = dir.join("regions.zip");
    {
        use std::io::Write;
        let mut z = zip::ZipWriter::new(std::fs::File::create(&zip_path).unwrap());
        let stored = zip::write::SimpleFileOptions::default().compression_method(zip::CompressionMethod::Stored);
        for (name, file) in [("regions/B.stl", folder.join("B.stl")), ("regions/A.stl", folder.join("A.stl"))] {
            z.start_file(name, stored).unwrap();
            z.write_all(&std::fs::read(file).unwrap()).unwrap();
        }
        z.start_file("regions/readme.txt", stored).unwrap();
        z.write_all(b"two regions").unwrap();
        z.finish().unwrap();
    }
    let zipped = foam_cli(&dir, "zip", &[&["--input", &format!("regions={}", zip_path.display())][..], &sets].concat());
    assert!(zipped.0 == folder_run.0, "a zip of the files gives the folder's G-code");
    let mixed = weft(&[
        "run",
        root().join("examples/foam-dogbone-linear.json").to_str().unwrap(),
        "--input",
        &a,
        "--input",
        &format!("regions={}", zip_path.display()),
        "--out",
        dir.join("m.gcode").to_str().unwrap(),
    ]);
    assert!(!mixed.status.success() && String::from_utf8_lossy(&mixed.stderr).contains("load it alone"), "{}", String::from_utf8_lossy(&mixed.stderr));
    let o = weft(&[
        "run",
        root().join("examples/foam-dogbone-linear.json").to_str().unwrap(),
        "--input",
        &format!("regions={}", zip_path.display()),
        "--out",
        dir.join("z.gcode").to_str().unwrap(),
    ]);
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("regions.zip: left out 1 file(s) that are not meshes (regions/readme.txt)"),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(one_by_one.0 == folder_run.0 && sets_first.0 == folder_run.0, "the same design however the files come");
    // The second region's V* and H* are in the G-code's report: read back from a run.
    let d = foam_of(&["A.stl", "B.stl"]).with_overrides(&["job.regions.1.v_star=0.35".into(), "job.regions.1.h_star=10".into()]).unwrap();
    let files: Vec<(&str, Vec<u8>)> = vec![("A.stl", std::fs::read(folder.join("A.stl")).unwrap()), ("B.stl", std::fs::read(folder.join("B.stl")).unwrap())];
    let out = run_files(&d, &files).unwrap();
    assert!(out.gcode.as_bytes() == &folder_run.0[..], "the CLI's folder run is the pipeline's run of the design");
    let grade = out.report.stages.iter().find(|s| s.stage == "grade").unwrap();
    let v_max = grade.metrics.iter().find(|m| m.key == "v_star_max").unwrap().value;
    assert!((v_max - 0.35).abs() < 1e-9, "region 2's V* is printed: {v_max}");
    // A page-style load, one file then the other: region 2's row survives the first load.
    let registry = weft::kinds::Registry::builtin();
    let start = example("foam-dogbone-linear").with_overrides(&["job.regions.1.v_star=0.35".into(), "job.regions.1.h_star=10".into()]).unwrap();
    let first = start.with_slot_input(&registry, "regions", Input::File { name: "A.stl".into(), embedded: None }).unwrap();
    let both = first.with_slot_input(&registry, "regions", Input::Files(vec!["A.stl".into(), "B.stl".into()])).unwrap();
    assert_eq!(both.job.value["regions"], d.job.value["regions"], "loading one by one keeps every row");
    assert_eq!(both.job.value["transitions"], d.job.value["transitions"]);
    // With one file of two, the waiting row is said, not silently dropped.
    let one = run_files(&first, &files[..1]).unwrap();
    assert!(notes(&one).iter().any(|n| n.contains("wait for their files")), "{:?}", notes(&one));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_edit_route_takes_its_gcode_from_the_same_command_line() {
    let dir = temp_dir("edit");
    let other = dir.join("other.gcode");
    let o = weft(&["run", root().join("examples/cube-20mm.json").to_str().unwrap(), "--out", other.to_str().unwrap(), "-q"]);
    assert!(o.status.success());
    let out = dir.join("edited.gcode");
    let phantom = root().join("examples/graded-phantom.json");
    let gcode_in = format!("gcode={}", other.display());
    for order in [["--input", &gcode_in, "--set", "job.route=edit"], ["--set", "job.route=edit", "--input", &gcode_in]] {
        let mut args = vec!["run", phantom.to_str().unwrap()];
        args.extend_from_slice(&order);
        args.extend_from_slice(&["--out", out.to_str().unwrap(), "-q"]);
        let o = weft(&args);
        assert!(o.status.success(), "{order:?}: {}", String::from_utf8_lossy(&o.stderr));
        let edited = std::fs::read_to_string(&out).unwrap();
        assert!(edited.lines().filter(|l| l.starts_with("G1")).count() > 1000, "an edited copy of the cube's G-code");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// An OBJ of a UV sphere as triangle faces (no `l` lines), standing on its lower pole.
fn ball_obj(rings: usize, around: usize, radius: f64) -> String {
    let mut s = String::from("# a wireframe exported as a triangle mesh\nv 0 0 0\n");
    for i in 1..rings {
        let th = std::f64::consts::PI * i as f64 / rings as f64;
        for j in 0..around {
            let ph = std::f64::consts::TAU * j as f64 / around as f64;
            s.push_str(&format!("v {:.6} {:.6} {:.6}\n", radius * th.sin() * ph.cos(), radius * th.sin() * ph.sin(), radius * (1.0 - th.cos())));
        }
    }
    s.push_str(&format!("v 0 0 {:.6}\n", 2.0 * radius));
    let at = |i: usize, j: usize| 2 + (i - 1) * around + j % around;
    let top = 2 + (rings - 1) * around;
    for j in 0..around {
        s.push_str(&format!("f 1 {} {}\n", at(1, j + 1), at(1, j)));
        s.push_str(&format!("f {top} {} {}\n", at(rings - 1, j), at(rings - 1, j + 1)));
    }
    for i in 1..rings - 1 {
        for j in 0..around {
            s.push_str(&format!("f {} {} {}\n", at(i, j), at(i, j + 1), at(i + 1, j + 1)));
            s.push_str(&format!("f {} {} {}\n", at(i, j), at(i + 1, j + 1), at(i + 1, j)));
        }
    }
    s
}

#[test]
fn wireframes_come_from_triangle_meshes_with_the_count_stated() {
    use weft::freeform::wireframe::{grounding, read, Options};
    let (rings, around) = (6usize, 10usize);
    let obj = ball_obj(rings, around, 10.0);
    let w = read("ball.obj", obj.as_bytes(), &Options::default()).unwrap();
    // Euler: a closed triangulated sphere has 3V − 6 edges.
    let v = 2 + (rings - 1) * around;
    assert_eq!(w.joints.len(), v);
    assert_eq!(w.beams.len(), 3 * v - 6);
    let faces = 2 * around * (rings - 1);
    assert!(w.notes.iter().any(|n| n.contains(&format!("ball.obj: read {faces} faces as {} beams", 3 * v - 6))), "{:?}", w.notes);
    // The same mesh as STL gives the same beams.
    let mut mesh = Mesh::default();
    for p in &w.joints {
        mesh.vertices.push([p.x as f32, p.y as f32, p.z as f32]);
    }
    for line in obj.lines().filter_map(|l| l.strip_prefix("f ")) {
        let c: Vec<u32> = line.split_whitespace().map(|t| t.parse::<u32>().unwrap() - 1).collect();
        mesh.triangles.push([c[0], c[1], c[2]]);
    }
    let s = read("ball.stl", &mesh.to_stl_binary(), &Options::default()).unwrap();
    assert_eq!(s.beams.len(), w.beams.len());
    assert!(s.notes.iter().any(|n| n.contains(&format!("read {faces} triangles as {} beams", 3 * v - 6))), "{:?}", s.notes);
    // Standing on its pole, one joint is grounded: stated, warned of, a tolerance suggested.
    let g = grounding(&w, 0.01);
    assert_eq!(g.joints, 1);
    assert_eq!(g.statement(), "1 joint grounded, the lowest: z 0.00 ± 0.01 mm");
    let warn = g.warning().expect("one joint under a ball is implausible");
    assert!(warn.contains("only 1 joint touches the plate") && warn.contains("a ground tolerance of"), "{warn}");
    let (tol, joints, share) = g.suggestion.unwrap();
    let ring = 10.0 * (1.0 - (std::f64::consts::PI / rings as f64).cos());
    assert!(tol >= ring && tol <= ring * 1.05 && joints == 1 + around && share >= 0.2, "{tol} {joints} {share}");
    // A file's own marks are trusted: no warning.
    let marked = read("four-frame.json", &std::fs::read(root().join("../shared/wireframes/four-frame.json")).unwrap_or_default(), &Options::default());
    if let Ok(m) = marked {
        let g = grounding(&m, 0.01);
        assert!(g.by_file && g.warning().is_none() && g.statement().ends_with("as the file marks them"), "{}", g.statement());
    }
}

#[test]
fn a_refusal_states_the_grounding_it_assumed() {
    let dir = temp_dir("ground");
    let path = dir.join("ball.obj");
    std::fs::write(&path, ball_obj(6, 10, 10.0)).unwrap();
    let o = weft(&[
        "run",
        root().join("examples/freeform-dome.json").to_str().unwrap(),
        "--input",
        &format!("frame={}", path.display()),
        "--out",
        dir.join("b.gcode").to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    // Printed or refused, the grounding is said; a refusal cites it.
    assert!(stderr.contains("1 joint grounded, the lowest: z 0.00 ± 0.01 mm"), "{stderr}");
    assert!(stderr.contains("only 1 joint touches the plate"), "{stderr}");
    if !o.status.success() {
        assert!(stderr.contains("(with 1 joint grounded"), "{stderr}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn short_moves_are_merged_with_their_filament() {
    use weft::geom::{DVec3, Feature, Pass, PassKind, Path as ToolPath, Toolpath};
    // A 10 mm line cut every 0.004 mm in its middle (a split at voxel faces), and a short last move.
    let mut points = vec![DVec3::new(10.0, 10.0, 0.2), DVec3::new(15.0, 10.0, 0.2)];
    for k in 1..=20 {
        points.push(DVec3::new(15.0 + 0.004 * k as f64, 10.0, 0.2));
    }
    points.push(DVec3::new(20.0, 10.0, 0.2));
    points.push(DVec3::new(20.005, 10.0, 0.2));
    let path = ToolPath { points, feature: Feature::Infill, width: 0.45, speed_factor: 1.0, approach: None, data: None };
    let whole = ToolPath { points: vec![DVec3::new(10.0, 10.0, 0.2), DVec3::new(20.005, 10.0, 0.2)], ..path.clone() };
    let options = weft::gcode::Options::default();
    let write = |p: &ToolPath| {
        weft::gcode::write_gcode(&Toolpath { passes: vec![Pass { kind: PassKind::Layer, z: 0.2, height: 0.2, paths: vec![p.clone()] }] }, &options).unwrap()
    };
    let cut = write(&path);
    let straight = write(&whole);
    assert!((cut.stats.filament_mm - straight.stats.filament_mm).abs() < 1e-4, "{} vs {}", cut.stats.filament_mm, straight.stats.filament_mm);
    // Of the 0.004 mm steps, two of every three join the next move (each written move is
    // at least 0.01 mm: 0.012), and the short last move joins the one before it.
    assert_eq!(cut.stats.merged_moves, 15);
    let moves = cut.text.lines().filter(|l| l.starts_with("G1 X") && l.contains(" E")).count();
    assert_eq!(moves, 8, "{}", cut.text);
    // A sliver path (0.007 mm in all) has no neighbour: left out with its travel, and counted.
    let sliver = ToolPath { points: vec![DVec3::new(30.0, 10.0, 0.2), DVec3::new(30.007, 10.0, 0.2)], ..path.clone() };
    let both =
        weft::gcode::write_gcode(&Toolpath { passes: vec![Pass { kind: PassKind::Layer, z: 0.2, height: 0.2, paths: vec![path.clone(), sliver] }] }, &options)
            .unwrap();
    assert_eq!(both.stats.dropped_paths, 1);
    assert!(both.stats.dropped_filament_mm > 0.0 && both.stats.dropped_filament_mm < 1e-3);
    assert!(!both.text.contains("X30.007"), "the sliver is not written");
    assert_eq!(both.stats.retractions, cut.stats.retractions, "nor its travel's retraction");
}

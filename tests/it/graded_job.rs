//! The `graded` job end to end: a CT phantom written as a DICOM series by weft's own test
//! helpers → surface model → graded G-code, on both routes; the shipped example is the
//! phantom; refusals keep the other inputs; the CLI reads a series folder and writes the
//! surface STL.

use std::path::PathBuf;
use weft::catalog::share;
use weft::design::{Design, Input};
use weft::geom::DVec3;
use weft::pipeline::{self, Files, RunOptions};
use weft::testgen::dicom::{bone_phantom, write_series, zip_files, SeriesOptions};

/// The example's phantom: 48 × 48 × 30 voxels of 1 × 1 × 2 mm.
const DIMS: [usize; 3] = [48, 48, 30];
const SPACING: [f64; 3] = [1.0, 1.0, 2.0];
const EXAMPLE: &str = "examples/graded-phantom.json";

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn series() -> Vec<(String, Vec<u8>)> {
    write_series(&bone_phantom(DIMS, SPACING), &SeriesOptions::default())
}

/// The example design as the generator makes it (the committed file must equal it).
fn example_json() -> String {
    let zip = zip_files(&series());
    let mut d: serde_json::Value = serde_json::from_str(&Design::default().to_json_pretty()).unwrap();
    d["name"] = "graded-phantom".into();
    d["description"] = "A CT bone phantom (cortical shell, graded trabecular core, medullary canal; a 48 × 48 × 30 DICOM series of 1 × 1 × 2 mm voxels written by weft's test helpers) cropped to a 20 mm segment, surface at 350 HU with the canal filled, gyroid infill at ρ_s 47 % graded by the femur case's HU → porosity line (equation 7).".into();
    d["job"] = serde_json::to_value(weft::kinds::graded::GradedJob::default()).unwrap();
    d["job"]["kind"] = "graded".into();
    d["job"]["volume"] = serde_json::json!({"file": {"name": "bone-phantom.zip", "embedded": share::pack(&zip)}});
    d["job"]["roi"] = serde_json::json!({"min_mm": [0.0, 0.0, 20.0], "max_mm": [47.0, 47.0, 40.0]});
    weft::kinds::Registry::builtin().get("graded").unwrap().adopted(&mut d);
    let design = Design::from_json("example", &d.to_string()).unwrap();
    design.to_json_pretty()
}

#[test]
fn the_example_is_the_generated_phantom() {
    let want = example_json();
    let path = root().join(EXAMPLE);
    if std::env::var_os("WEFT_BLESS").is_some() || !path.exists() {
        std::fs::write(&path, &want).unwrap();
    }
    let have = std::fs::read_to_string(&path).unwrap();
    assert!(have == want, "{EXAMPLE} differs from what the generator makes (WEFT_BLESS=1 to rewrite it)");
}

fn run(design: &Design, files: &Files) -> pipeline::RunOutput {
    pipeline::run(design, files, &RunOptions::default(), &mut |_, _| {}).unwrap_or_else(|e| panic!("run failed: {e}"))
}

fn example() -> Design {
    Design::from_json("example", &example_json()).unwrap()
}

/// Every `;TYPE:Internal infill` extrusion of `gcode`: (start, end, E).
fn infill_moves(gcode: &str) -> Vec<(DVec3, DVec3, f64)> {
    // Absolute or relative E, as the file says (M82 / M83), with G92 resets.
    let (mut p, mut infill, mut out, mut relative, mut e_at) = (DVec3::ZERO, false, Vec::new(), false, 0.0);
    for line in gcode.lines() {
        if let Some(t) = line.strip_prefix(";TYPE:") {
            infill = t == "Internal infill";
            continue;
        }
        match line.split(';').next().unwrap().trim() {
            "M82" => relative = false,
            "M83" => relative = true,
            l if l.starts_with("G92") => {
                if let Some(w) = l.split_whitespace().find(|w| w.starts_with('E')) {
                    e_at = w[1..].parse().unwrap();
                }
            }
            _ => {}
        }
        if !(line.starts_with("G1 ") || line.starts_with("G0 ")) {
            continue;
        }
        let mut q = p;
        let mut e = None;
        for w in line.split(';').next().unwrap().split_whitespace().skip(1) {
            let v: f64 = w[1..].parse().unwrap_or(f64::NAN);
            match &w[..1] {
                "X" => q.x = v,
                "Y" => q.y = v,
                "Z" => q.z = v,
                "E" => e = Some(v),
                _ => {}
            }
        }
        let e = e.map(|v| {
            let d = if relative { v } else { v - e_at };
            e_at = if relative { e_at + v } else { v };
            d
        });
        if infill {
            if let Some(e) = e.filter(|e| *e > 0.0) {
                if q.truncate().distance(p.truncate()) > 0.0 {
                    out.push((p, q, e));
                }
            }
        }
        p = q;
    }
    out
}

#[test]
fn native_route_grades_every_infill_segment_by_the_field() {
    let design = example();
    let out = run(&design, &Files::new());
    let stages: Vec<&str> = out.report.stages.iter().map(|s| s.stage.as_str()).collect();
    for s in ["volume", "surface", "density", "slice", "grade"] {
        assert!(stages.contains(&s), "no {s} stage: {stages:?}");
    }
    let surface: serde_json::Value = out.report.stage_data("surface").unwrap().clone();
    assert_eq!(surface["closed"], true, "surface model not closed: {surface}");
    let grade: serde_json::Value = out.report.stage_data("grade").unwrap().clone();
    assert!(grade["segments"].as_u64().unwrap() > 1000, "{grade}");

    // Read the G-code back: E per mm of every infill move against ρ(midpoint)/ρ_s, with ρ
    // computed here from the phantom's own volume and the density stage's numbers.
    let model = out.report.stage_data("density").unwrap().clone();
    let (rho_s, rho_min, area_s) = (model["rho_s"].as_f64().unwrap(), model["rho_min"].as_f64().unwrap(), model["nominal_area_mm2"].as_f64().unwrap());
    // Toolpath point = field point + offset; G-code point = toolpath point + the bed centre
    // (a corner-origin printer).
    let bed = design.printer.bed_size_mm;
    let offset = DVec3::from_array(serde_json::from_value(grade["offset_mm"].clone()).unwrap()) + DVec3::new(bed[0] / 2.0, bed[1] / 2.0, 0.0);
    assert_eq!(serde_json::to_value(design.printer.origin).unwrap(), "corner");
    let volume = bone_phantom(DIMS, SPACING);
    let cal = weft::scaffold::Calibration::default();
    let f = design.printer.filament_diameter_mm;
    let filament_area = std::f64::consts::PI * f * f / 4.0;
    let k = design.material.k * design.material.extrusion_multiplier;
    let moves = infill_moves(&out.gcode);
    assert!(moves.len() > 1000, "{} infill moves", moves.len());
    let (mut worst, mut lo, mut hi) = (0.0f64, f64::INFINITY, 0.0f64);
    let mut long = 0;
    for (a, b, e) in &moves {
        let len = a.distance(*b);
        if len < 0.05 {
            continue; // E is written to 5 decimals: too few digits on tiny moves
        }
        if len > model["segment_mm"].as_f64().unwrap() + 1e-3 {
            long += 1;
        }
        let mid = (*a + *b) * 0.5 - offset;
        let Some(rho) = volume.sample_with(mid, |hu| cal.density(hu as f64, 0.0)) else { continue };
        let rho = rho.max(rho_min);
        let want = k * len * area_s * rho / rho_s / filament_area;
        worst = worst.max((e - want).abs() / want);
        lo = lo.min(e / len);
        hi = hi.max(e / len);
    }
    assert!(worst < 0.02, "E differs from ρ/ρ_s by up to {:.2} %", worst * 100.0);
    assert_eq!(long, 0, "infill moves longer than the grading step");
    assert!(hi > 1.5 * lo, "the infill is not graded: E/mm from {lo} to {hi}");
}

#[test]
fn native_and_edit_routes_are_compared_on_the_same_toolpath() {
    // Rectilinear lines cross the phantom's shell and core in one move: graded whole (the
    // paper's route) their density is the midpoint's all along; split, it follows the field.
    let mut design = example();
    design.job.value["slice"]["infill_pattern"] = "rectilinear".into();
    let out = run(&design, &Files::new());
    let grade: serde_json::Value = out.report.stage_data("grade").unwrap().clone();
    let compare: serde_json::Value = out.report.stage_data("compare").unwrap().clone();
    let metric = |stage: &str, key: &str| out.report.stages.iter().find(|s| s.stage == stage).unwrap().metrics.iter().find(|m| m.key == key).unwrap().value;
    let (native, edit) = (metric("compare", "native_error"), metric("compare", "edit_error"));
    assert_eq!(native, metric("grade", "mean_abs_error"), "the comparison's native error is the grade stage's");
    assert!(native < 0.01, "native error {native}");
    assert!(edit > 5.0 * native, "edit route error {edit} against native {native}");
    // Every infill move of the ungraded toolpath is edited once: the grade stage's segments
    // before splitting.
    let whole = grade["segments"].as_u64().unwrap() - grade["split_added"].as_u64().unwrap();
    assert_eq!(compare["edited_moves"].as_u64().unwrap(), whole, "{compare}");
    // Both routes measured on the same layers.
    let z = |k: &str| {
        compare[k]
            .as_array()
            .unwrap()
            .iter()
            .filter(|l| l["moves"].as_u64().unwrap() > 0)
            .map(|l| (l["z_mm"].as_f64().unwrap() * 1000.0).round() as i64)
            .collect::<Vec<_>>()
    };
    assert_eq!(z("native"), z("edit"));

    // Off: no comparison stage, the same G-code.
    design.job.value["compare_edit"] = false.into();
    let off = run(&design, &Files::new());
    assert!(off.report.stage_data("compare").is_none());
    assert_eq!(off.gcode, out.gcode);
}

#[test]
fn graded_cells_keep_beads_printable_where_the_fixed_cell_clamps() {
    let fixed = example();
    let mut graded = example();
    graded.job.value["density"]["cell_sizing"] = "graded".into();
    let (a, b) = (run(&fixed, &Files::new()), run(&graded, &Files::new()));
    let cells: serde_json::Value = b.report.stage_data("cells").expect("a cells stage").clone();
    assert!(cells["larger"].as_u64().unwrap() > 0, "{cells}");
    assert!(a.report.stage_data("cells").is_none());
    // Fewer segments raised to ρ_min (a bead below E_w,min) with re-sized cells.
    let share = |o: &pipeline::RunOutput| {
        let g = o.report.stage_data("grade").unwrap();
        g["clamped_low"].as_f64().unwrap() / g["segments"].as_f64().unwrap()
    };
    assert!(share(&b) < 0.9 * share(&a), "clamped share {} (graded cells) against {} (fixed)", share(&b), share(&a));
    // Read back: every infill bead of both is within [E_w,min, E_w,max].
    let d = graded.printer.filament_diameter_mm;
    let k = graded.material.k * graded.material.extrusion_multiplier;
    for (name, out) in [("fixed", &a), ("graded", &b)] {
        let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
        for (p, q, e) in infill_moves(&out.gcode) {
            let len = p.distance(q);
            if len < 0.2 {
                continue; // E has 5 decimals
            }
            let area = e / k * std::f64::consts::PI * d * d / 4.0 / len;
            let w = weft::scaffold::width_of_area(area, 0.2);
            (lo, hi) = (lo.min(w), hi.max(w));
        }
        assert!(lo > 0.2 * 0.97 && hi < 1.2 * 1.03, "{name}: beads from {lo} to {hi} mm");
    }
    // The re-sized core has larger cells: less infill path in it.
    assert_ne!(a.gcode, b.gcode);
}

#[test]
fn a_one_shot_run_reads_the_volume_and_extracts_the_surface_once() {
    // The estimate before the run makes both; a disabled cache (the CLI) keeps them for it.
    let mut starts: Vec<String> = Vec::new();
    let mut last = String::new();
    // A stage that runs reports 0 first; one reused from the cache reports only 1.
    pipeline::run(&example(), &Files::new(), &RunOptions::default(), &mut |stage, x| {
        if stage != last && x == 0.0 {
            starts.push(stage.to_string());
        }
        last = stage.to_string();
    })
    .unwrap();
    for s in ["volume", "surface"] {
        assert_eq!(starts.iter().filter(|x| *x == s).count(), 1, "{s} started {:?}", starts);
    }
}

#[test]
fn edit_route_rewrites_only_the_infill_of_another_slicers_gcode() {
    // A PrusaSlicer-style file of a 20 mm block, absolute E (so G92 resets are needed).
    let mut design = example();
    let mut files = Files::new();
    let spec = weft::testgen::foreign::Foreign { layers: 40, relative_e: false, side_mm: 20.0, ..Default::default() };
    let foreign = String::from_utf8(weft::testgen::foreign::generate(&spec).text).unwrap();
    files.insert("part.gcode".into(), foreign.clone().into_bytes());
    // Filling the G-code slot switches the route to `edit`.
    design = design.with_slot_input(&weft::kinds::Registry::builtin(), "gcode", Input::File { name: "part.gcode".into(), embedded: None }).unwrap();
    let out = run(&design, &files);
    let edit: serde_json::Value = out.report.stage_data("edit").unwrap().clone();
    assert!(edit["edited_moves"].as_u64().unwrap() > 100, "{edit}");
    // Every line that is not an infill move is unchanged, in order (inserted G92 resets aside).
    let keep = |t: &str| -> Vec<String> {
        let mut infill = false;
        t.lines()
            .filter(|l| {
                if let Some(ty) = l.strip_prefix(";TYPE:") {
                    infill = ty == "Internal infill";
                }
                !((infill && l.starts_with("G1 ") && l.contains(" E")) || l.starts_with("G92 E"))
            })
            .map(str::to_string)
            .collect()
    };
    assert_eq!(keep(&out.gcode), keep(&foreign), "non-infill lines changed");
    assert_ne!(out.gcode.as_str(), foreign.as_str(), "nothing was edited");
}

/// A loaded file kept outside the core (the page's dropped `File`), read in ranges; reads fail
/// once `gone` is set (the file was deleted after it was dropped).
struct Far {
    bytes: Vec<u8>,
    reads: std::sync::atomic::AtomicUsize,
    gone: std::sync::atomic::AtomicBool,
}

impl weft::source::ByteSource for Far {
    fn len(&self) -> usize {
        self.bytes.len()
    }
    fn read_at(&self, offset: usize, buf: &mut [u8]) -> Result<(), String> {
        use std::sync::atomic::Ordering::Relaxed;
        if self.gone.load(Relaxed) {
            return Err("NotFoundError".into());
        }
        self.reads.fetch_add(1, Relaxed);
        buf.copy_from_slice(&self.bytes[offset..offset + buf.len()]);
        Ok(())
    }
}

#[test]
fn files_kept_outside_give_the_same_gcode_and_a_gone_one_is_named() {
    use std::sync::atomic::Ordering::Relaxed;
    // A G-code over one read piece (4 MiB), so the edit reads it in several.
    let foreign = weft::testgen::foreign::sized(weft::testgen::foreign::Slicer::PrusaSlicer, false, 9 << 20).text;
    let input = Input::File { name: "part.gcode".into(), embedded: None };
    let design = example().with_slot_input(&weft::kinds::Registry::builtin(), "gcode", input).unwrap();
    let names: Vec<String> = series().into_iter().map(|(n, _)| n).collect();
    let design = design.with_slot_input(&weft::kinds::Registry::builtin(), "volume", Input::Files(names)).unwrap();

    let mut inside = Files::new();
    let mut outside = Files::new();
    let mut far = Vec::new();
    for (name, bytes) in series().into_iter().chain([("part.gcode".to_string(), foreign.clone())]) {
        inside.insert(name.clone(), bytes.clone());
        let f = std::sync::Arc::new(Far { bytes, reads: Default::default(), gone: Default::default() });
        outside.insert_source(name, f.clone()).unwrap();
        far.push(f);
    }
    assert!(outside.get("part.gcode").is_none(), "the G-code is not in memory");
    let a = run(&design, &inside);
    let b = run(&design, &outside);
    assert!(a.gcode == b.gcode, "a G-code read in pieces edits differently");
    assert!(far.last().unwrap().reads.load(Relaxed) >= 2 * 3, "hashed and edited in pieces");
    assert_eq!(a.report.stage_data("edit"), b.report.stage_data("edit"));

    // A session re-running the same design reads no slice again: the volume, its estimate and
    // the keys come from the cache and the hashes made on loading.
    let registry = weft::kinds::Registry::builtin();
    let mut cache = weft::pipeline::Cache::new();
    let opts = RunOptions::default();
    pipeline::run_in(&registry, &mut cache, &design, &outside, &opts, &mut |_, _| {}).unwrap();
    let reads = far[3].reads.load(Relaxed);
    pipeline::estimate(&registry, &mut cache, &design, &outside).unwrap();
    pipeline::run_in(&registry, &mut cache, &design, &outside, &opts, &mut |_, _| {}).unwrap();
    assert_eq!(far[3].reads.load(Relaxed), reads, "a cached volume read its slices again");

    // Deleted after loading: the run names the file and says what to do.
    far.last().unwrap().gone.store(true, Relaxed);
    let e = pipeline::run(&design, &outside, &RunOptions::default(), &mut |_, _| {}).expect_err("an unreadable file is refused").to_string();
    assert!(e.contains("part.gcode") && e.contains("load it again"), "{e}");
    far[3].gone.store(true, Relaxed);
    let e = pipeline::run(&design, &outside, &RunOptions::default(), &mut |_, _| {}).expect_err("an unreadable slice is refused").to_string();
    assert!(e.contains(&series()[3].0) && e.contains("load it again"), "{e}");
}

#[test]
fn a_broken_series_is_refused_by_name_and_the_design_keeps_its_inputs() {
    let mut files = Files::new();
    let mut names = Vec::new();
    for (i, (name, mut bytes)) in series().into_iter().enumerate() {
        if i == 7 {
            bytes.truncate(bytes.len() / 2);
        }
        files.insert(name.clone(), bytes);
        names.push(name);
    }
    let design = example().with_slot_input(&weft::kinds::Registry::builtin(), "volume", Input::Files(names.clone())).unwrap();
    let e = pipeline::run(&design, &files, &RunOptions::default(), &mut |_, _| {}).expect_err("a truncated slice must be refused").to_string();
    assert!(e.contains(&names[7]), "the message does not name the file: {e}");
    // The design still names every file (nothing was dropped from it).
    let v: serde_json::Value = serde_json::from_str(&design.to_json_pretty()).unwrap();
    assert_eq!(v["job"]["volume"]["files"].as_array().unwrap().len(), names.len());
}

#[test]
fn cli_reads_a_series_folder_and_writes_the_surface_stl() {
    let dir = std::env::temp_dir().join(format!("weft-graded-{}", std::process::id()));
    let series_dir = dir.join("phantom");
    std::fs::create_dir_all(&series_dir).unwrap();
    for (name, bytes) in series() {
        std::fs::write(series_dir.join(name), bytes).unwrap();
    }
    let weft = env!("CARGO_BIN_EXE_weft");
    let example_path = root().join(EXAMPLE);
    let stl = dir.join("surface.stl");
    let status = std::process::Command::new(weft)
        .args([
            "inspect",
            example_path.to_str().unwrap(),
            "--view",
            "surface",
            "--input",
            &format!("volume={}", series_dir.display()),
            "--out",
            stl.to_str().unwrap(),
        ])
        .status()
        .unwrap();
    assert!(status.success());
    let bytes = std::fs::read(&stl).unwrap();
    let imported = weft::import::read_mesh("surface.stl", &bytes, &weft::import::Options::default()).unwrap();
    assert_eq!(imported.report.open_edges, 0, "the STL is not closed");
    let gcode = dir.join("phantom.gcode");
    let out = std::process::Command::new(weft)
        .args(["run", example_path.to_str().unwrap(), "-q", "--input", &format!("volume={}", series_dir.display()), "--out", gcode.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    // The same series as files or embedded zip: the same G-code.
    let embedded = run(&example(), &Files::new());
    assert_eq!(std::fs::read_to_string(&gcode).unwrap(), *embedded.gcode);
    let _ = std::fs::remove_dir_all(&dir);
}

/// A series whose files are each under the volume limit but over it together is refused from
/// their sizes, before any byte of them is read (the page keeps them in its blob store, where
/// reading them all would not fit the worker's memory).
#[test]
fn a_series_over_the_limit_together_is_refused_before_it_is_read() {
    use std::sync::atomic::Ordering::Relaxed;
    /// A file of `len` zero bytes that holds none of them.
    struct Zeros {
        len: usize,
        reads: std::sync::atomic::AtomicUsize,
    }
    impl weft::source::ByteSource for Zeros {
        fn len(&self) -> usize {
            self.len
        }
        fn read_at(&self, _: usize, buf: &mut [u8]) -> Result<(), String> {
            self.reads.fetch_add(1, Relaxed);
            buf.fill(0);
            Ok(())
        }
    }
    let each = (weft::volume::MAX_INPUT_BYTES / 2 + (1 << 20)) as usize;
    let mut files = Files::new();
    let mut sources = Vec::new();
    for k in 0..2 {
        let z = std::sync::Arc::new(Zeros { len: each, reads: Default::default() });
        files.insert_source(format!("s{k}.dcm"), z.clone()).unwrap();
        sources.push(z);
    }
    let read_on_loading: Vec<usize> = sources.iter().map(|z| z.reads.load(Relaxed)).collect();
    let design = example().with_slot_input(&weft::kinds::Registry::builtin(), "volume", Input::Files(vec!["s0.dcm".into(), "s1.dcm".into()])).unwrap();
    let e = pipeline::run(&design, &files, &RunOptions::default(), &mut |_, _| {}).expect_err("refused").to_string();
    assert!(e.contains("the files given for 'volume':") && e.contains("MiB is more than the") && e.contains("crop or resample"), "{e}");
    let read_later: Vec<usize> = sources.iter().map(|z| z.reads.load(Relaxed)).collect();
    assert_eq!(read_later, read_on_loading, "a file of the series was read before the refusal");
}

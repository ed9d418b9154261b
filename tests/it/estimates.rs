//! Stages state their work before running it: the slicer's and the writer's estimates are
//! checked against what they then make (segments, G-code bytes, extrusion), budgets refuse
//! before any work, and a part too big for the bed or in the wrong units is refused with its
//! real size before slicing.

use weft::budget::{Estimate, MAX_STAGE_BYTES};
use weft::design::Design;
use weft::geom::shapes::Shape;
use weft::geom::Mesh;
use weft::kinds::Registry;
use weft::pipeline::{self, Cache, Files, RunOptions};
use weft::{gcode, slice};

fn shapes() -> Vec<(&'static str, Mesh)> {
    vec![
        ("cube 20", Shape::Cube { size: [20.0, 20.0, 20.0] }.mesh()),
        ("plate 80×60×3", Shape::Cube { size: [80.0, 60.0, 3.0] }.mesh()),
        ("tower 10×10×60", Shape::Cube { size: [10.0, 10.0, 60.0] }.mesh()),
        ("sphere 30", Shape::Sphere { radius: 15.0, segments: 96 }.mesh()),
        ("cylinder", Shape::Cylinder { radius: 12.0, height: 25.0, segments: 64 }.mesh()),
        ("dish", Shape::ConcaveCylinder { radius: 20.0, height: 12.0, dish_depth: 8.0, segments: 64 }.mesh()),
    ]
}

fn options() -> Vec<(&'static str, slice::Options)> {
    let d = slice::Options::default();
    vec![
        ("default", d.clone()),
        ("hollow", slice::Options { infill_density: 0.0, ..d.clone() }),
        ("solid", slice::Options { infill_density: 1.0, ..d.clone() }),
        ("fine", slice::Options { layer_height_mm: 0.1, first_layer_height_mm: 0.1, ..d.clone() }),
        ("thick walls", slice::Options { perimeters: 6, infill_density: 0.4, ..d.clone() }),
        ("no perimeters", slice::Options { perimeters: 0, ..d }),
    ]
}

fn within(what: &str, estimate: f64, actual: f64, lo: f64, hi: f64) -> Option<String> {
    let r = estimate / actual.max(1.0);
    (!(lo..=hi).contains(&r)).then(|| format!("{what}: estimate {estimate:.0}, actual {actual:.0} (×{r:.2})"))
}

/// Segments, G-code bytes and extrusion of the slicer's and the writer's estimates are within
/// 0.45×–2.2× of what slicing then makes, on solids of very different shapes and settings.
#[test]
fn slice_and_writer_estimates_match_what_is_made() {
    let mut wrong = Vec::new();
    let writer = gcode::Options::default();
    for (shape, mesh) in shapes() {
        for (name, o) in options() {
            let e = slice::estimate(&mesh, &o);
            e.check().unwrap_or_else(|r| panic!("{shape}, {name}: refused: {r}"));
            let sliced = slice::slice(&mesh, &o, &mut |_| {}).unwrap();
            let segments = gcode::segments(&sliced.toolpath) as f64;
            let g = gcode::write_gcode(&sliced.toolpath, &writer).unwrap();
            let w = gcode::estimate(e.get("segments"), &writer);
            let case = format!("{shape}, {name}");
            assert_eq!(e.get("layers"), sliced.layers.len() as f64, "{case}: the layer count is exact");
            wrong.extend(within(&format!("{case}: segments"), e.get("segments"), segments, 0.45, 2.2));
            wrong.extend(within(&format!("{case}: G-code bytes"), w.get("gcode_bytes"), g.text.len() as f64, 0.45, 2.2));
            wrong.extend(within(&format!("{case}: extrusion"), e.get("extruded_mm"), sliced.toolpath.extrusion_length(), 0.6, 1.6));
        }
    }
    assert!(wrong.is_empty(), "{} estimates off:\n{}", wrong.len(), wrong.join("\n"));
}

/// A slice whose estimate is over a budget is refused before slicing, naming the number, the
/// limit and the setting to change.
#[test]
fn over_budget_slices_are_refused_before_slicing() {
    let cube = Shape::Cube { size: [200.0, 200.0, 200.0] }.mesh();
    let o = slice::Options { layer_height_mm: 0.01, first_layer_height_mm: 0.01, infill_density: 1.0, ..Default::default() };
    let e = slice::estimate(&cube, &o);
    assert!(e.bytes > MAX_STAGE_BYTES, "a 200 mm solid cube at 0.01 mm is several GiB: {}", e.bytes);
    // Refused before slicing, not after: no progress reported, and what was allocated is a
    // few kB, not the gigabytes the slices would take (counted: the same on any machine).
    let mut progress = 0;
    let (w, err) = crate::work::measure(|| slice::slice(&cube, &o, &mut |_| progress += 1).unwrap_err().to_string());
    assert_eq!(progress, 0, "refused before slicing, not after");
    assert!(w.bytes < 1 << 20, "refused before slicing, not after: {w:?}");
    assert!(err.contains("limit") && err.contains("layer_height_mm"), "{err}");

    // 3 km plate: beyond the integer-micrometre range the regions are computed in.
    let plate = Shape::Cube { size: [3.0e6, 3.0e6, 1.0] }.mesh();
    let err = slice::slice(&plate, &Default::default(), &mut |_| {}).unwrap_err().to_string();
    assert!(err.contains("1500000 mm") || err.contains("1.5M mm"), "names the real reach: {err}");
    assert!(err.contains("3000000 × 3000000 × 1 mm"), "names the real size: {err}");
}

/// A binary STL of `mesh`.
fn stl(mesh: &Mesh) -> Vec<u8> {
    let mut out = vec![0u8; 80];
    out.extend((mesh.triangles.len() as u32).to_le_bytes());
    for t in &mesh.triangles {
        out.extend([0u8; 12]);
        for &i in t {
            for c in mesh.vertices[i as usize] {
                out.extend(c.to_le_bytes());
            }
        }
        out.extend([0u8; 2]);
    }
    out
}

fn design_with(json_edits: &[&str]) -> Design {
    Design::default().with_overrides(&json_edits.iter().map(|s| s.to_string()).collect::<Vec<_>>()).unwrap()
}

/// A part bigger than the bed is refused before slicing with its real size, however big (the
/// saturating micrometre coordinates used to report a 10 km strip as 4294966.89 mm wide).
#[test]
fn parts_larger_than_the_bed_are_refused_with_their_real_size_before_slicing() {
    for (size, says) in [
        ([1.0e7, 20.0, 5.0], "10000000.00 × 20.00 × 5.00 mm"),
        ([3.0e6, 3.0e6, 1.0], "3000000.00 × 3000000.00 × 1.00 mm"),
        ([300.0, 20.0, 5.0], "300.00 × 20.00 × 5.00 mm"),
    ] {
        let bytes = stl(&Shape::Cube { size }.mesh());
        let files = || {
            let mut files = Files::new();
            files.insert("big.stl".into(), bytes.clone());
            files
        };
        let d = design_with(&[r#"job.input={"file":{"name":"big.stl"}}"#]);
        // Refused before slicing: no stage after the import reports progress, and the run
        // allocates a few MB at most (counted, not timed).
        let mut stages = Vec::new();
        let (w, err) = crate::work::measure(|| {
            pipeline::run(&d, &files(), &RunOptions::default(), &mut |stage, _| stages.push(stage.to_string())).unwrap_err().to_string()
        });
        assert!(stages.iter().all(|s| s == "import"), "refused before slicing: {stages:?}");
        assert!(w.bytes < 8 << 20, "refused before slicing: {w:?}");
        assert!(err.contains(says) && err.contains("220 × 220 × 250"), "{err}");
        let plan = pipeline::estimate(&Registry::builtin(), &mut Cache::disabled(), &d, &files());
        assert!(plan.is_err(), "the dry run refuses it too");
    }
    // One that fits runs.
    let d = design_with(&[r#"job.input={"builtin":{"shape":"cube","size":[200,20,5]}}"#]);
    pipeline::run(&d, &Files::new(), &RunOptions::default(), &mut |_, _| {}).unwrap();
}

/// The plan of a run lists the job's stages, then the writer and the analyzer, and its totals
/// add up; a design over a budget is refused by `run` before any stage runs.
#[test]
fn a_run_states_its_plan_and_refuses_over_budget_before_running() {
    let d = Design::default();
    let plan = pipeline::estimate(&Registry::builtin(), &mut Cache::disabled(), &d, &Files::new()).unwrap();
    let stages: Vec<&str> = plan.stages.iter().map(|e| e.stage).collect();
    assert_eq!(stages, ["slice", "gcode", "analyze"]);
    assert!((plan.seconds - plan.stages.iter().map(|e| e.seconds).sum::<f64>()).abs() < 1e-12);
    assert!(plan.refused.is_none() && plan.ask.is_none(), "the default design is small");
    let out = pipeline::run(&d, &Files::new(), &RunOptions::default(), &mut |_, _| {}).unwrap();
    if let Some(m) = within("G-code", plan.gcode_bytes, out.gcode.len() as f64, 0.5, 2.0) {
        panic!("{m}");
    }

    let big = design_with(&[
        r#"job.input={"builtin":{"shape":"cube","size":[200,200,200]}}"#,
        "job.slice.layer_height_mm=0.01",
        "job.slice.first_layer_height_mm=0.01",
        "job.slice.infill_density=1",
    ]);
    let plan = pipeline::estimate(&Registry::builtin(), &mut Cache::disabled(), &big, &Files::new()).unwrap();
    let (stage, _) = plan.refused.clone().expect("refused");
    assert_eq!(stage, "slice");
    let mut stages_run = Vec::new();
    let err = pipeline::run(&big, &Files::new(), &RunOptions::default(), &mut |s, _| stages_run.push(s.to_string())).unwrap_err();
    assert!(matches!(err, pipeline::Error::TooBig { .. }), "{err}");
    assert!(stages_run.iter().all(|s| s == "import"), "no stage but the import (which the estimate needs) ran: {stages_run:?}");
    let medium = design_with(&[r#"job.input={"builtin":{"shape":"cylinder","radius":70,"height":150,"segments":512}}"#, "job.slice.layer_height_mm=0.05"]);
    let plan = pipeline::estimate(&Registry::builtin(), &mut Cache::disabled(), &medium, &Files::new()).unwrap();
    assert!(plan.refused.is_none() && plan.ask.is_some(), "a big but possible job asks first: {plan:?}");
}

#[test]
fn estimates_never_let_a_nan_through() {
    let e = Estimate::new("x").cost(f64::NAN, 0.0).budgets("fix");
    assert!(e.check().is_err());
}

/// A file imported when it is loaded (the page reads a dropped mesh at once), then a plan
/// (the page's question before a big run), then the run: the run's timings count the import
/// once, as work of this run, whatever the plan looked at in between.
#[test]
fn an_import_made_on_loading_is_counted_by_the_run_even_after_a_plan() {
    use weft::design::Input;
    let mut files = Files::new();
    files.insert("part.stl".into(), stl(&Shape::Cylinder { radius: 20.0, height: 10.0, segments: 4096 }.mesh()));
    let d = design_with(&[r#"job.input={"file":{"name":"part.stl"}}"#]);
    let registry = Registry::builtin();
    for plan_first in [false, true] {
        let mut cache = Cache::new();
        let loading = Design::default();
        let mut quiet = |_: &str, _: f32| {};
        let mut ctx = pipeline::Ctx::new(&loading, &files, &mut cache, &mut quiet);
        ctx.mesh(registry.slot("mesh").unwrap(), &Input::File { name: "part.stl".into(), embedded: None }).unwrap();
        let loaded_ms = ctx.timings.iter().find(|t| t.stage == "import").map(|t| t.ms).expect("timed on loading");
        if plan_first {
            pipeline::estimate(&registry, &mut cache, &d, &files).unwrap();
        }
        let out = pipeline::run_in(&registry, &mut cache, &d, &files, &RunOptions::default(), &mut |_, _| {}).unwrap();
        let import = out.report.timings.iter().find(|t| t.stage == "import").expect("the run lists the import");
        assert!(!import.cached && import.ms == loaded_ms, "plan first: {plan_first}: {import:?}, {loaded_ms} ms on loading");
        // Its card says the run reused it (the run did not make it).
        let card = out.report.stages.iter().find(|s| s.stage == "import").expect("the import's card");
        assert!(card.cached, "plan first: {plan_first}: the import's card");
        // A second run reuses it: cached, no time.
        let again = pipeline::run_in(&registry, &mut cache, &d, &files, &RunOptions::default(), &mut |_, _| {}).unwrap();
        let import = again.report.timings.iter().find(|t| t.stage == "import").expect("listed");
        assert!(import.cached && import.ms == 0.0, "{import:?}");
        assert!(again.report.stages.iter().any(|s| s.stage == "import" && s.cached), "the re-run's import card says reused");
    }
}

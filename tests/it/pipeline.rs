//! The whole pipeline on fixture meshes: every run's G-code is read back by the analyzer.

use weft::design::Input;
use weft::import::ImportReport;
use weft::kinds::Registry;
use weft::pipeline::{self, Files, RunOptions};
use weft::slice::SliceReport;
use weft::Design;

fn fixture(name: &str) -> Vec<u8> {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures").join(name);
    std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn run_file(name: &str) -> weft::RunOutput {
    let mut design = Design { name: name.into(), ..Design::default() };
    design = design.with_slot_input(&Registry::builtin(), "mesh", Input::File { name: name.into(), embedded: None }).unwrap();
    let mut files = Files::new();
    files.insert(name.into(), fixture(name));
    let mut stages = Vec::new();
    let out = pipeline::run(&design, &files, &RunOptions { collect_preview: true }, &mut |s, _| {
        if stages.last().map(String::as_str) != Some(s) {
            stages.push(s.to_string())
        }
    })
    .unwrap_or_else(|e| panic!("{name}: {e}"));
    assert_eq!(stages.len(), 4, "{name}: every stage reports progress");
    out
}

#[test]
fn fixtures_slice_end_to_end() {
    for name in ["cube.stl", "cube-ascii.stl", "cube.obj", "cube.3mf", "sphere.stl", "open-box.stl", "overlapping-shells.stl"] {
        let out = run_file(name);
        let a = &out.report.analysis;
        let g = &out.report.gcode;
        assert!(a.layers > 0, "{name}: no layers");
        assert!((a.extruded_mm - g.extruded_mm).abs() <= 1e-3 * g.extruded_mm, "{name}: {} vs {}", a.extruded_mm, g.extruded_mm);
        assert!((a.filament_mm - g.filament_mm).abs() <= 1e-3 * g.filament_mm.max(1.0), "{name}: filament {} vs {}", a.filament_mm, g.filament_mm);
        assert_eq!(a.per_layer.len(), a.layers, "{name}");
        let p = out.preview.as_ref().unwrap();
        assert_eq!(p.layer_segment_start.len(), a.layers + 1, "{name}");
        assert_eq!(p.positions.len(), 6 * p.feature.len(), "{name}");
        assert!(out.report.stage_data("import").is_some(), "{name}");
    }
}

#[test]
fn cube_formats_agree() {
    // The same 20 mm cube as binary STL, ASCII STL, OBJ and 3MF gives the same G-code body.
    let body = |name: &str| {
        let g = run_file(name).gcode;
        g.lines().filter(|l| l.starts_with("G1") || l.starts_with("G0")).collect::<Vec<_>>().join("\n")
    };
    let reference = body("cube.stl");
    for other in ["cube-ascii.stl", "cube.obj", "cube.3mf"] {
        assert_eq!(body(other), reference, "{other} differs from cube.stl");
    }
}

#[test]
fn repairs_are_reported() {
    let open = run_file("open-box.stl");
    assert!(open.report.stage::<ImportReport>("import").unwrap().open_edges > 0);
    let shells = run_file("overlapping-shells.stl");
    assert!(shells.report.stage::<SliceReport>("slice").unwrap().layers_with_overlaps > 0);
    assert_eq!(shells.report.analysis.overlap_mm, 0.0, "unioned shells print each line once");
}

#[test]
fn seed_and_design_determine_the_bytes() {
    let design = Design::default();
    let run = |d: &Design| pipeline::run(d, &Files::new(), &RunOptions::default(), &mut |_, _| {}).unwrap().gcode;
    let a = run(&design);
    assert_eq!(a, run(&design));
    assert_eq!(design.job.kind(), "slice");
    let mut other = design.clone();
    other.material.extrusion_multiplier = 1.1;
    assert_ne!(a, run(&other));
}

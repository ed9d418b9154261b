//! Analyzer: hand-written snippets with every number checked.

use std::f64::consts::PI;
use weft::analyze::{analyze, Error, Options, Report};

fn run(src: &str) -> Report {
    analyze("t.gcode", src.as_bytes(), &Options::default()).unwrap().report
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-9 * (1.0 + b.abs())
}

macro_rules! assert_close {
    ($a:expr, $b:expr) => {{
        let (a, b) = ($a as f64, $b as f64);
        assert!(close(a, b), "{} = {a}, expected {b}", stringify!($a));
    }};
}

#[test]
fn straight_moves_absolute() {
    let r = run("G90\nM82\nG92 E0\nG0 X10 Y10 F6000\nG1 X20 Y10 E1 F1200\nG1 X20 Y20 E2\n");
    assert_close!(r.travel_mm, 200f64.sqrt());
    assert_close!(r.extruded_mm, 20.0);
    assert_close!(r.filament_mm, 2.0);
    assert_eq!(r.extrusion_paths, 1);
    assert_eq!(r.layers, 1);
    assert_eq!(r.retractions, 0);
    assert_close!(r.overlap_mm, 0.0);
    // One path of 2 edges: 20·2 / (20·1) = 2.
    assert_close!(r.gippo_score, 2.0);
    assert_close!(r.per_layer[0].z, 0.0);
}

#[test]
fn g2_quarter_circle_and_r_form_and_helix() {
    // Clockwise quarter circle of radius 10 from (10,0) to (0,-10) about the origin.
    let r = run("G1 X10 Y0 F600\nG2 X0 Y-10 I-10 J0 E1\n");
    assert_close!(r.extruded_mm, 5.0 * PI);
    assert_close!(r.travel_mm, 10.0);
    // Counter-clockwise the same points go the long way: three quarters.
    let r = run("G1 X10 Y0\nG3 X0 Y-10 I-10 J0 E1\n");
    assert_close!(r.extruded_mm, 15.0 * PI);
    // R form: positive R = short arc, negative R = long arc.
    let r = run("G1 X10 Y0\nG2 X0 Y-10 R10 E1\n");
    assert!((r.extruded_mm - 5.0 * PI).abs() < 1e-9, "{}", r.extruded_mm);
    let r = run("G1 X10 Y0\nG2 X0 Y-10 R-10 E1\n");
    assert!((r.extruded_mm - 15.0 * PI).abs() < 1e-9, "{}", r.extruded_mm);
    // Full circle (end = start) with a helical rise of 3 mm.
    let r = run("G1 X10 Y0\nG3 X10 Y0 Z3 I-10 J0 E1\n");
    assert_close!(r.extruded_mm, ((20.0 * PI).powi(2) + 9.0).sqrt());
    // An arc is one edge of its path.
    let r = run("G1 X10 Y0\nG2 X0 Y-10 I-10 J0 E1\nG1 X0 Y-20 E2\n");
    assert_eq!(r.extrusion_paths, 1);
    assert_close!(r.gippo_score, 2.0);
}

#[test]
fn g91_relative_moves_make_e_relative_too() {
    let r = run("G91\nG1 X10 E1\nG1 Y10 E1\nG1 X-10 E0.5\n");
    assert_close!(r.extruded_mm, 30.0);
    assert_close!(r.filament_mm, 2.5);
    // M82 after G91: E absolute again while XYZ stays relative.
    let r = run("G91\nM82\nG1 X10 E1\nG1 X10 E1.5\n");
    assert_close!(r.extruded_mm, 20.0);
    assert_close!(r.filament_mm, 1.5);
    // G90 after M83 resets E to absolute (Marlin).
    let r = run("M83\nG90\nG1 X10 E1\nG1 X20 E1\n");
    assert_close!(r.extruded_mm, 10.0);
    assert_close!(r.filament_mm, 1.0);
    assert_eq!(r.extrusion_paths, 1);
}

#[test]
fn g92_resets_and_m83() {
    let r = run("M82\nG1 X10 E1\nG92 E0\nG1 X20 E1\nG92 X0\nG1 X10 E2\n");
    assert_close!(r.extruded_mm, 30.0);
    assert_close!(r.filament_mm, 3.0);
    assert_eq!(r.extrusion_paths, 1);
    let r = run("M83\nG1 X10 E1\nG1 X20 E1\nG1 E-0.8\nG1 X30\nG1 E0.8\nG1 X40 E1\n");
    assert_close!(r.extruded_mm, 30.0);
    assert_close!(r.travel_mm, 10.0);
    assert_close!(r.filament_mm, 3.0);
    assert_eq!(r.retractions, 1);
    assert_eq!(r.extrusion_paths, 2);
}

#[test]
fn retraction_counting() {
    // E-only retraction, firmware retraction, wipe followed by retraction (counts once),
    // G10 P… (tool setting, not a retraction).
    let src = "M83\nG1 X10 E1\nG1 E-1\nG1 E1\nG1 X20 E1\nG10\nG0 X30\nG11\nG1 X40 E1\nG1 X35 E-0.5\nG1 E-0.3\nG1 X50\nG1 E0.8\nG10 P0 S200\nG1 X60 E1\n";
    let r = run(src);
    assert_eq!(r.retractions, 3);
    assert_eq!(r.extrusion_paths, 4);
    assert_close!(r.extruded_mm, 40.0);
    assert_close!(r.travel_mm, 10.0 + 5.0 + 15.0);
    assert_close!(r.filament_mm, 4.0);
}

#[test]
fn lexical_forms() {
    let src = "N1 g1 x10 y0 e1 f1200*33\r\n\r\n(full-line comment)\nN2 G1 X20 (inline) E2 ; tail\nX30 E3\nT0\nM117 Printing X=1 ; message\nG1X40E4\nM999\n%\n";
    let r = run(src);
    assert_close!(r.extruded_mm, 40.0);
    assert_close!(r.filament_mm, 4.0);
    assert_eq!(r.extrusion_paths, 1);
}

#[test]
fn g28_homes_named_axes() {
    let r = run("G1 X10 Y10 Z5\nG28 X\nG1 X10 E1\nG28\nG1 X1 Y0 Z0 E2\n");
    assert_close!(r.travel_mm, 15.0);
    assert_close!(r.extruded_mm, 10.0 + 1.0);
    assert_eq!(r.extrusion_paths, 2); // homing ends a run
}

#[test]
fn layers_from_comments() {
    let src = "G1 X0 Y0 Z0.3\nG1 X50 E2 ; purge\n;LAYER_CHANGE\n;Z:0.2\n;LAYER:0\nG1 Z0.2\nG1 X0 Y10\nG1 X10 E3\n;LAYER:1\nG1 Z0.4\nG1 X10 Y20 E4\nG1 Z0.5\nG1 X0 Y20 E5\n";
    let r = run(src);
    // The purge line joins the first layer; the Z change inside layer 1 is not a layer.
    assert_eq!(r.layers, 2);
    assert_eq!(r.extrusion_paths, 4);
    assert_close!(r.per_layer[0].z, 0.3);
    assert_eq!(r.per_layer[0].extrusion_paths, 2);
    assert_close!(r.per_layer[0].extruded_mm, 60.0);
    assert_close!(r.per_layer[1].z, 0.4);
    assert_close!(r.per_layer[1].extruded_mm, 20.0);
    // Travels before a layer's first extrusion belong to it.
    assert_close!(r.per_layer[0].travel_mm, 0.3 + 0.1 + (2500.0f64 + 100.0).sqrt());
    assert_close!(r.per_layer[1].travel_mm, 0.2 + 0.1);
}

#[test]
fn layers_from_z_without_comments() {
    let src = "G1 Z0.2\nG1 X10 E1\nG1 Y10 E2\nG1 Z0.4\nG1 X0 E3\nG1 Z1\nG1 X5\nG1 Z0.4\nG1 Y0 E4\n";
    let r = run(src);
    assert_eq!(r.layers, 2);
    assert_eq!(r.extrusion_paths, 3);
    assert_close!(r.per_layer[0].z, 0.2);
    assert_close!(r.per_layer[1].z, 0.4);
    assert_close!(r.per_layer[1].extruded_mm, 20.0);
    assert_close!(r.per_layer[1].travel_mm, 0.2 + 0.6 + 5.0 + 0.6);
}

#[test]
fn gippo_equation_1() {
    // Layer: path A = 3 edges of 10 mm (30 mm), path B = 1 edge of 10 mm.
    // score = (30·3 + 10·1) / (40 · 2) = 1.25.
    let src = "G1 X0 Y0 Z0.2\nG1 X10 E1\nG1 Y10 E2\nG1 X0 E3\nG0 X0 Y20\nG1 X10 E4\n";
    let r = run(src);
    assert_close!(r.per_layer[0].gippo_score, 1.25);
    // Second layer with a single 1-edge path scores 1; the report averages layers.
    let r = run(&format!("{src}G1 Z0.4\nG1 X0 Y20 E5\n"));
    assert_eq!(r.layers, 2);
    assert_close!(r.per_layer[1].gippo_score, 1.0);
    assert_close!(r.gippo_score, 1.125);
}

#[test]
fn overlap_rules() {
    // A strut printed twice (there and back) → its length.
    let r = run("G1 X0 Y0 Z0.2\nG1 X10 E1\nG1 X0 E2\n");
    assert_close!(r.overlap_mm, 10.0);
    // Printed twice in the same direction by two paths, offset by 0.1 mm laterally.
    let r = run("G1 X0 Y0 Z0.2\nG1 X10 E1\nG0 X0 Y0.1\nG1 X10 E2\n");
    assert_close!(r.overlap_mm, 10.0);
    // Half of it re-printed.
    let r = run("G1 X0 Y0 Z0.2\nG1 X10 E1\nG0 X5 Y0\nG1 X15 E2\n");
    assert_close!(r.overlap_mm, 5.0);
    // Adjacent parallel lines one width apart do not overlap.
    let r = run("G1 X0 Y0 Z0.2\nG1 X10 E1\nG0 X0 Y0.4\nG1 X10 E2\n");
    assert_close!(r.overlap_mm, 0.0);
    // A plus-shaped crossing.
    let r = run("G1 X-5 Y0 Z0.2\nG1 X5 E1\nG0 X0 Y-5\nG1 Y5 E2\n");
    assert_close!(r.overlap_mm, 0.0);
    // Two collinear segments touching end to end.
    let r = run("G1 X0 Y0 Z0.2\nG1 X10 E1\nG0 X20\nG1 X10 E2\n");
    assert_close!(r.overlap_mm, 0.0);
    // A T-junction.
    let r = run("G1 X-5 Y0 Z0.2\nG1 X5 E1\nG0 X0 Y5\nG1 Y0 E2\n");
    assert_close!(r.overlap_mm, 0.0);
    // Three passes over the same strut: the third counts once, not twice.
    let r = run("G1 X0 Y0 Z0.2\nG1 X10 E1\nG1 X0 E2\nG1 X10 E3\n");
    assert_close!(r.overlap_mm, 20.0);
    // Other layers do not count.
    let r = run("G1 X0 Y0 Z0.2\nG1 X10 E1\nG1 Z0.4\nG1 X0 E2\n");
    assert_close!(r.overlap_mm, 0.0);
    // A long strut re-printed as many short pieces (grid cells crossed).
    let mut s = String::from("G1 X0 Y0 Z0.2\nG1 X100 Y37 E1\n");
    for k in (0..100).rev() {
        s.push_str(&format!("G1 X{} Y{} E{}\n", k, 0.37 * k as f64, 2 + 100 - k));
    }
    let r = run(&s);
    assert!((r.overlap_mm - (100f64 * 100.0 + 37.0 * 37.0).sqrt()).abs() < 1e-6, "{}", r.overlap_mm);
}

#[test]
fn time_model() {
    // 100 mm at 50 mm/s, a = 1000: 0.05 s accelerating, 0.05 s braking, 97.5 mm cruising.
    let r = run("G1 X100 F3000\n");
    assert_close!(r.estimated_time_s, 0.1 + 97.5 / 50.0);
    // M204 S500 and a 2 s dwell (G4 P2000) plus 0.5 s (G4 S0.5).
    let r = run("M204 S500\nG1 X100 F3000\nG4 P2000\nG4 S0.5\n");
    assert_close!(r.estimated_time_s, 0.2 + 95.0 / 50.0 + 2.5);
    // Straight continuation keeps speed across moves.
    let r = run("G1 X50 F3000\nG1 X100\n");
    assert_close!(r.estimated_time_s, 0.1 + 97.5 / 50.0);
}

#[test]
fn not_text_and_malformed() {
    let e = analyze("b.gcode", b"G1 X1\nG1\0 X2\n", &Options::default()).unwrap_err();
    assert_eq!(e, Error::NotText { file: "b.gcode".into(), offset: 8 });
    let e = analyze("m.gcode", b"G1 X1\n; ok\nG1 X1.2.3 Y2\n", &Options::default()).unwrap_err();
    match e {
        Error::Malformed { file, line, problem } => {
            assert_eq!(file, "m.gcode");
            assert_eq!(line, 3);
            assert!(problem.contains('X'), "{problem}");
        }
        other => panic!("{other:?}"),
    }
    let e = analyze("m.gcode", b"G1 X1\r\nG1 Yabc\r\n", &Options::default()).unwrap_err();
    assert!(matches!(e, Error::Malformed { line: 2, .. }), "{e:?}");
    assert!(e.to_string().contains("m.gcode: line 2"));
    // Unknown commands with odd arguments are fine.
    assert!(analyze("ok.gcode", b"M117 X=abc\nM23 file.gco\nG29.1 X?\n", &Options::default()).is_ok());
}

#[test]
fn empty_and_garbage_never_panic() {
    for src in [
        "",
        "\n\n",
        ";",
        "G1",
        "G2 X1",
        "G3 R0",
        "G2 X0 Y0 I0 J0 E1",
        "G1 X1e308",
        "G1 X99999999999999999999999999 E1",
        "X",
        "*",
        "(",
        "N",
        "G",
        "G4 P-5",
        "G1 X-",
        "\u{feff}G1 X1 E1",
    ] {
        let _ = analyze("f", src.as_bytes(), &Options { collect_preview: true, ..Default::default() });
    }
    let r = run("");
    assert_eq!(r.layers, 0);
    assert_eq!(r.gippo_score, 0.0);
}

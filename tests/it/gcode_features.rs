//! G-code writer: approach routes, pre/post flow, short-path speed, the pneumatic flavour.

use weft::analyze::{analyze, Options as AOptions};
use weft::gcode::{write_gcode, Flavor, Options, Origin, Printer};
use weft::geom::{DVec3, Feature, Pass, Path, Toolpath};

fn p(x: f64, y: f64, z: f64) -> DVec3 {
    DVec3::new(x, y, z)
}

fn path(points: Vec<DVec3>) -> Path {
    Path::new(points, Feature::Lattice, 0.4)
}

fn plain_options() -> Options {
    let mut o = Options::default();
    o.printer.start_gcode = String::new();
    o.printer.end_gcode = String::new();
    o.printer.origin = Origin::Center;
    o.design_name = "t".into();
    // The moves alone: labels and thumbnails have tests of their own (gcode_host).
    o.printer.thumbnails.clear();
    o.printer.object_labels = weft::gcode::ObjectLabels::None;
    o
}

fn eq4(len: f64, lt: f64, w: f64) -> f64 {
    4.0 * len * lt * w / (std::f64::consts::PI * 1.75 * 1.75)
}

fn f5(v: f64) -> String {
    weft::gcode::format::fixed(v, 5)
}

/// Lines from the first `;LAYER:` on, up to the footer.
fn layers_body(text: &str) -> Vec<&str> {
    let lines: Vec<&str> = text.lines().take_while(|l| *l != ";").collect();
    let i = lines.iter().position(|l| l.starts_with(";LAYER:")).unwrap();
    lines[i + 1..].to_vec()
}

fn one_layer(paths: Vec<Path>) -> Toolpath {
    Toolpath { passes: vec![Pass::layer(0.2, 0.2, paths)] }
}

#[test]
fn approach_route_is_dry_g1_without_retraction() {
    let o = plain_options();
    let a = path(vec![p(0.0, 0.0, 0.2), p(10.0, 0.0, 0.2)]);
    let mut b = path(vec![p(10.0, 10.0, 0.2), p(0.0, 10.0, 0.2)]);
    // Back along the printed strut to x = 5, then up to the start of b.
    b.approach = Some(vec![p(5.0, 0.0, 0.2), p(5.0, 10.0, 0.2)]);
    let g = write_gcode(&one_layer(vec![a, b]), &o).unwrap();
    let e = eq4(10.0, 0.2, 0.4);
    assert_eq!(
        layers_body(&g.text),
        [
            "G1 Z0.2 F600".to_string(),
            "G0 X0 Y0 F9000".into(),
            ";TYPE:Lattice".into(),
            ";WIDTH:0.4".into(),
            format!("G1 X10 Y0 E{} F1200", f5(e)),
            "G1 X5 Y0 F9000".into(),
            "G1 X5 Y10".into(),
            "G1 X10 Y10".into(),
            format!("G1 X0 Y10 E{} F1200", f5(2.0 * e)),
            format!("G1 E{} F2100", f5(2.0 * e - 0.8)),
        ]
    );
    // Only the final retraction.
    assert_eq!(g.stats.retractions, 1);
    let a = analyze("a.gcode", g.text.as_bytes(), &AOptions::default()).unwrap().report;
    assert_eq!(a.extrusion_paths, 2);
    assert_eq!(a.retractions, 1);
    // 0.2 mm first Z move + 5 + 10 + 5 mm along the route.
    assert!((a.travel_mm - 20.2).abs() < 1e-9, "{}", a.travel_mm);
    assert_eq!(a.travel_mm, g.stats.travel_mm);
    assert!((a.extruded_mm - 20.0).abs() < 1e-9);
}

#[test]
fn empty_approach_route_and_first_path_approach() {
    let o = plain_options();
    // The first path of the file has an approach: the head position is unknown, so it travels.
    let mut a = path(vec![p(0.0, 0.0, 0.2), p(10.0, 0.0, 0.2)]);
    a.approach = Some(vec![p(3.0, 3.0, 0.2)]);
    let mut b = path(vec![p(10.0, 5.0, 0.2), p(0.0, 5.0, 0.2)]);
    b.approach = Some(Vec::new());
    let g = write_gcode(&one_layer(vec![a, b]), &o).unwrap();
    let body = layers_body(&g.text);
    assert_eq!(body[..2], ["G1 Z0.2 F600", "G0 X0 Y0 F9000"]);
    assert_eq!(body[5], "G1 X10 Y5 F9000");
    assert!(body[6].starts_with("G1 X0 Y5 E"));
    assert_eq!(g.stats.retractions, 1);
}

#[test]
fn approach_across_layers_moves_z_in_the_g1() {
    let o = plain_options();
    let a = path(vec![p(0.0, 0.0, 0.2), p(10.0, 0.0, 0.2)]);
    let mut b = path(vec![p(10.0, 0.0, 0.4), p(0.0, 0.0, 0.4)]);
    b.approach = Some(vec![]);
    let tp = Toolpath { passes: vec![Pass::layer(0.2, 0.2, vec![a]), Pass::layer(0.4, 0.2, vec![b])] };
    let g = write_gcode(&tp, &o).unwrap();
    let body = layers_body(&g.text);
    let i = body.iter().position(|l| *l == ";LAYER:1").unwrap();
    assert_eq!(body[i + 1..i + 4], ["M106 S255", "M104 S210", "G1 X10 Y0 Z0.4 F9000"]);
    assert_eq!(g.stats.retractions, 1);
}

#[test]
fn pre_and_post_flow_marlin_absolute_and_relative() {
    let mut o = plain_options();
    o.material.flow.pre_flow_mm = 0.1;
    o.material.flow.post_flow_mm = 0.05;
    let tp = one_layer(vec![path(vec![p(0.0, 0.0, 0.2), p(10.0, 0.0, 0.2)])]);
    let g = write_gcode(&tp, &o).unwrap();
    let e = eq4(10.0, 0.2, 0.4);
    assert_eq!(
        layers_body(&g.text),
        [
            "G1 Z0.2 F600".to_string(),
            "G0 X0 Y0 F9000".into(),
            ";TYPE:Lattice".into(),
            ";WIDTH:0.4".into(),
            "G1 E0.1 F2100".into(),
            format!("G1 X10 Y0 E{} F1200", f5(0.1 + e)),
            format!("G1 E{} F2100", f5(0.15 + e)),
            format!("G1 E{}", f5(0.15 + e - 0.8)),
        ]
    );
    assert!((g.stats.filament_mm - (0.15 + e)).abs() < 1e-12);
    let a = analyze("a.gcode", g.text.as_bytes(), &AOptions::default()).unwrap().report;
    assert!((a.filament_mm - (0.15 + e)).abs() < 1e-5);
    assert_eq!(a.extrusion_paths, 1);

    o.printer.relative_e = true;
    let g = write_gcode(&tp, &o).unwrap();
    assert_eq!(layers_body(&g.text)[4..], ["G1 E0.1 F2100".to_string(), format!("G1 X10 Y0 E{} F1200", f5(e)), "G1 E0.05 F2100".into(), "G1 E-0.8".into(),]);
}

#[test]
fn short_paths_use_the_speed_factor() {
    let mut o = plain_options();
    o.printer.retraction.length_mm = 0.0;
    let a = path(vec![p(0.0, 0.0, 0.4), p(10.0, 0.0, 0.4)]);
    let mut b = path(vec![p(10.0, 0.0, 0.4), p(10.0, 1.0, 0.4)]);
    b.speed_factor = 0.6;
    let mut c = path(vec![p(10.0, 1.0, 0.4), p(0.0, 1.0, 0.4)]);
    c.feature = Feature::Contour;
    let tp = Toolpath { passes: vec![Pass::layer(0.2, 0.2, vec![path(vec![p(0.0, 0.0, 0.2), p(0.0, 1.0, 0.2)])]), Pass::layer(0.4, 0.2, vec![a, b, c])] };
    o.speeds.lattice_mm_s = 25.0;
    let g = write_gcode(&tp, &o).unwrap();
    let lines: Vec<&str> = g.text.lines().filter(|l| l.starts_with("G1 X")).collect();
    let e = eq4(10.0, 0.2, 0.4);
    let e1 = eq4(1.0, 0.2, 0.4);
    assert_eq!(
        lines,
        [
            format!("G1 X0 Y1 E{} F1200", f5(e1)),                 // first layer speed 20 mm/s
            format!("G1 X10 Y0 E{} F1500", f5(e1 + e)),            // lattice 25 mm/s
            format!("G1 X10 Y1 E{} F900", f5(2.0 * e1 + e)),       // short path: 0.6 × 25 mm/s
            format!("G1 X0 Y1 E{} F1500", f5(2.0 * e1 + 2.0 * e)), // contour at the lattice speed
        ]
    );
}

fn pneumatic_options() -> Options {
    let mut o = plain_options();
    o.printer.flavor = Flavor::Pneumatic;
    o.printer.retraction.z_hop_mm = 1.0;
    o.printer.pneumatic.pressure_template = "M9 P{pressure_kpa}".into();
    o.printer.pneumatic.pressure_kpa = 250.0;
    o.printer.pneumatic.short_path_pressure_factor = 1.2;
    o
}

#[test]
fn pneumatic_exact_lines() {
    let mut o = pneumatic_options();
    o.material.flow.pre_flow_s = 0.25;
    let a = path(vec![p(0.0, 0.0, 0.2), p(10.0, 0.0, 0.2), p(10.0, 10.0, 0.2)]);
    let mut b = path(vec![p(0.0, 10.0, 0.2), p(0.0, 9.0, 0.2)]);
    b.speed_factor = 0.6;
    let mut c = path(vec![p(0.5, 9.0, 0.2), p(0.5, 5.0, 0.2)]);
    c.approach = Some(vec![p(0.5, 9.5, 0.2)]);
    let g = write_gcode(&one_layer(vec![a, b, c]), &o).unwrap();
    assert!(g.text.contains(";FLAVOR:Pneumatic\n"));
    let lines: Vec<&str> = g
        .body()
        .lines()
        .filter(|l| {
            !l.starts_with("; ") && !l.starts_with(";TIME") && !l.starts_with(";Filament") && !l.starts_with(";FLAVOR") && !l.starts_with(";LAYER_COUNT")
        })
        .collect();
    assert_eq!(
        lines,
        [
            "G21 ; millimetres",
            "G90 ; absolute coordinates",
            ";LAYER_CHANGE",
            ";Z:0.2",
            ";HEIGHT:0.2",
            ";LAYER:0",
            "G0 Z0.2 F600",
            "G0 X0 Y0 F9000",
            ";TYPE:Lattice",
            ";WIDTH:0.4",
            "M9 P250",
            "M3",
            "G4 P250 ; pre-flow",
            "G1 X10 Y0 F1200",
            "G1 X10 Y10",
            "M5",
            // 10 mm travel: lifted by z_hop_mm, G0 only.
            "G0 Z1.2 F600",
            "G0 X0 Y10 F9000",
            "G0 Z0.2 F600",
            "M9 P300", // short path: 250 kPa × 1.2
            "M3",
            "G4 P250 ; pre-flow",
            "G1 X0 Y9 F720",
            "M5",
            // Approach route: dry G1 at the travel speed, no lift.
            "G1 X0.5 Y9.5 F9000",
            "G1 X0.5 Y9",
            "M9 P250",
            "M3",
            "G4 P250 ; pre-flow",
            "G1 X0.5 Y5 F1200",
            "M5",
        ]
    );
    // No E anywhere: the analyzer sees only travel (documented: extrusion_paths 0).
    assert!(!g.text.contains(" E"));
    assert_eq!(g.stats.filament_mm, 0.0);
    assert_eq!(g.stats.retractions, 0);
    assert!((g.stats.extruded_mm - 25.0).abs() < 1e-12);
    let a = analyze("a.nc", g.text.as_bytes(), &AOptions::default()).unwrap().report;
    assert_eq!(a.extrusion_paths, 0);
    assert_eq!(a.extruded_mm, 0.0);
    assert_eq!(a.filament_mm, 0.0);
    assert_eq!(a.retractions, 0);
    assert!(a.travel_mm > 25.0);
    assert_eq!(a.travel_mm, g.stats.travel_mm);
    assert!(a.estimated_time_s > 0.75, "dwells count: {}", a.estimated_time_s);
}

#[test]
fn pneumatic_post_flow_closes_the_valve_early() {
    let mut o = pneumatic_options();
    o.printer.pneumatic.pressure_template = String::new();
    o.material.flow.post_flow_s = 0.1; // 0.1 s × 20 mm/s = 2 mm before the end
    let a = path(vec![p(0.0, 0.0, 0.2), p(10.0, 0.0, 0.2), p(10.0, 1.0, 0.2)]);
    let g = write_gcode(&one_layer(vec![a]), &o).unwrap();
    assert_eq!(layers_body(&g.text), ["G0 Z0.2 F600", "G0 X0 Y0 F9000", ";TYPE:Lattice", ";WIDTH:0.4", "M3", "G1 X9 Y0 F1200", "M5", "G1 X10 Y0", "G1 X10 Y1"]);
    // Exactly at a vertex: no zero-length piece.
    o.material.flow.post_flow_s = 0.05;
    let a = path(vec![p(0.0, 0.0, 0.2), p(10.0, 0.0, 0.2), p(10.0, 1.0, 0.2)]);
    let g = write_gcode(&one_layer(vec![a.clone()]), &o).unwrap();
    assert_eq!(layers_body(&g.text)[4..], ["M3", "G1 X10 Y0 F1200", "M5", "G1 X10 Y1"]);
    // Longer than the path: the valve closes right away.
    o.material.flow.post_flow_s = 5.0;
    let g = write_gcode(&one_layer(vec![a]), &o).unwrap();
    assert_eq!(layers_body(&g.text)[4..], ["M3", "M5", "G1 X10 Y0 F1200", "G1 X10 Y1"]);
}

#[test]
fn pneumatic_default_templates_and_extension() {
    let mut o = Options::default();
    o.printer.flavor = Flavor::Pneumatic;
    let tp = one_layer(vec![path(vec![p(0.0, 0.0, 0.2), p(10.0, 0.0, 0.2)])]);
    let g = write_gcode(&tp, &o).unwrap();
    assert!(g.text.contains("\nG28 ; home\nG21 ; millimetres\n"), "{}", g.text);
    assert!(g.text.contains("; pressure 300 kPa\nM3\n"));
    assert!(g.body().ends_with("M5\nG91\nG0 Z5 F600\nG90\nM2 ; end of program\n"), "{}", g.text);
    assert!(!g.text.contains("M104") && !g.text.contains("M106"));
    assert_eq!(Flavor::Pneumatic.file_extension(), "nc");
    assert_eq!(Flavor::Marlin.file_extension(), "gcode");
    // Custom templates are kept as they are.
    o.printer.start_gcode = "G92 X0 Y0 Z0".into();
    let g = write_gcode(&tp, &o).unwrap();
    assert!(!g.text.contains("G28"));
}

#[test]
fn pneumatic_on_layer_comments_and_multi_line_codes() {
    let mut o = pneumatic_options();
    o.printer.pneumatic.valve_on = "M42 P0 S255\nG4 P10\n".into();
    o.printer.pneumatic.valve_off = "M42 P0 S0".into();
    let tp = Toolpath {
        passes: (0..3)
            .map(|i| {
                let z = 0.2 * (i + 1) as f64;
                Pass::layer(z, 0.2, vec![path(vec![p(0.0, 0.0, z), p(5.0, 0.0, z)])])
            })
            .collect(),
    };
    let g = write_gcode(&tp, &o).unwrap();
    assert_eq!(g.text.matches("M42 P0 S255\nG4 P10\nG1 X5 Y0 F1200\n").count(), 3);
    assert_eq!(g.text.matches("\nM42 P0 S0\n").count(), 3);
    assert_eq!(g.text.matches(";LAYER:").count(), 3);
    assert_eq!(g.stats.layers, 3);
    // The pressure is written once: it never changes.
    assert_eq!(g.text.matches("M9 P250").count(), 1);
}

#[test]
fn design_json_without_new_fields_parses() {
    let p: Printer = serde_json::from_str(r#"{"name": "x", "flavor": "marlin"}"#).unwrap();
    assert_eq!(p.pneumatic, Default::default());
    let p: Printer = serde_json::from_str(r#"{"flavor": "pneumatic", "pneumatic": {"valve_on": "M7"}}"#).unwrap();
    assert_eq!(p.flavor, Flavor::Pneumatic);
    assert_eq!(p.pneumatic.valve_on, "M7");
    assert_eq!(p.pneumatic.valve_off, "M5");
    let m: weft::gcode::Material = serde_json::from_str(r#"{"k": 1.1, "flow": {"pre_flow_mm": 0.2}}"#).unwrap();
    assert_eq!(m.flow.pre_flow_mm, 0.2);
    assert_eq!(m.flow.post_flow_s, 0.0);
}

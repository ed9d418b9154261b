//! Analyzer on hand-written slicer-style files (tests/fixtures).

use weft::analyze::{analyze, Options};

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-9 * (1.0 + b.abs())
}

macro_rules! assert_close {
    ($a:expr, $b:expr) => {{
        let (a, b) = ($a as f64, $b as f64);
        assert!(close(a, b), "{} = {a}, expected {b}", stringify!($a));
    }};
}

fn fixture(name: &str) -> Vec<u8> {
    std::fs::read(format!("{}/tests/fixtures/{name}", env!("CARGO_MANIFEST_DIR"))).unwrap()
}

#[test]
fn prusaslicer_style() {
    let a = analyze("prusaslicer-style.gcode", &fixture("prusaslicer-style.gcode"), &Options { collect_preview: true, ..Default::default() }).unwrap();
    let r = &a.report;
    assert_eq!(r.layers, 2);
    // Intro line (2 moves, 100 mm) + perimeter (4 × 20 mm) + infill (18 + 1 + 18 mm) on layer 0,
    // a perimeter with its first side printed twice (5 × 20 mm) on layer 1.
    assert_eq!(r.extrusion_paths, 4);
    assert_close!(r.extruded_mm, 317.0);
    assert_eq!(r.retractions, 3);
    assert_close!(r.overlap_mm, 20.0);
    assert_close!(r.filament_mm, 21.5 + 3.2 + 1.85 + 4.0);
    let travel0 = 0.2 + 3.0 + 8749f64.sqrt() + 2f64.sqrt();
    let travel1 = 0.2 + 5f64.sqrt() + 10.0 + 24200f64.sqrt();
    assert_close!(r.travel_mm, travel0 + travel1);
    let l = &r.per_layer;
    assert_close!(l[0].z, 0.2);
    assert_close!(l[1].z, 0.4);
    assert_eq!((l[0].extrusion_paths, l[1].extrusion_paths), (3, 1));
    assert_close!(l[0].extruded_mm, 217.0);
    assert_close!(l[1].extruded_mm, 100.0);
    assert_close!(l[0].travel_mm, travel0);
    assert_close!(l[1].travel_mm, travel1);
    assert_eq!((l[0].retractions, l[1].retractions), (1, 2));
    assert_close!(l[0].overlap_mm, 0.0);
    assert_close!(l[1].overlap_mm, 20.0);
    assert_close!(l[0].gippo_score, (100.0 * 2.0 + 80.0 * 4.0 + 37.0 * 3.0) / (217.0 * 3.0));
    assert_close!(l[1].gippo_score, 5.0);
    assert_close!(r.gippo_score, (631.0 / 651.0 + 5.0) / 2.0);
    assert!(r.estimated_time_s > 15.0 && r.estimated_time_s < 30.0, "{}", r.estimated_time_s);

    let p = a.preview.unwrap();
    assert_eq!(p.positions.len(), 14 * 6);
    assert_eq!(p.layer_segment_start, [0, 9, 14]);
    assert_eq!(p.layer_travel_start, [0, 4, 8]);
    assert_eq!(p.travel_positions.len(), 8 * 6);
    assert_eq!(p.layer_z, [0.2f32, 0.4]);
    assert_eq!(p.feature, [255, 255, 0, 0, 0, 0, 3, 3, 3, 0, 0, 0, 0, 0]);
    assert_eq!(p.path, [0, 0, 1, 1, 1, 1, 2, 2, 2, 3, 3, 3, 3, 3]);
    assert_eq!(p.width[..3], [0.4f32, 0.4, 0.45]);
    assert_eq!(p.width[6], 0.5f32);
    // Perimeter: 0.8 mm of 1.75 mm filament over 20 mm at 20 mm/s → 0.8·π·1.75²/4 mm³/s.
    let flow = 0.8 * std::f64::consts::PI * 1.75 * 1.75 / 4.0;
    assert!((p.flow[2] as f64 - flow).abs() < 1e-5, "{}", p.flow[2]);
    assert_eq!(p.positions[12..18], [90.0f32, 90.0, 0.2, 110.0, 90.0, 0.2]);
}

#[test]
fn cura_style() {
    let a = analyze("cura-style.gcode", &fixture("cura-style.gcode"), &Options { collect_preview: true, ..Default::default() }).unwrap();
    let r = &a.report;
    let fill = 18.0 * 2f64.sqrt();
    assert_eq!(r.layers, 2);
    assert_eq!(r.extrusion_paths, 5);
    assert_close!(r.extruded_mm, 360.0 + 80.0 + fill + 80.0);
    assert_eq!(r.retractions, 3);
    assert_close!(r.overlap_mm, 0.0);
    assert_close!(r.filament_mm, 35.0);
    let travel0 = 2.0 + 402.9f64.sqrt() + 0.3 + 1.7 + (99.6f64 * 99.6 + 6400.0 + 1.8 * 1.8).sqrt() + 2f64.sqrt();
    let travel1 = 722.04f64.sqrt() + 0.2 + 50f64.sqrt() + 10.0 + (105.0f64 * 105.0 + 115.0 * 115.0).sqrt();
    assert_close!(r.per_layer[0].travel_mm, travel0);
    assert_close!(r.per_layer[1].travel_mm, travel1);
    assert_close!(r.travel_mm, travel0 + travel1);
    assert_close!(r.per_layer[0].z, 0.3); // the purge line opens layer 0
    assert_close!(r.per_layer[1].z, 0.4);
    assert_eq!((r.per_layer[0].retractions, r.per_layer[1].retractions), (1, 2));
    let g0 = (180.0 + 180.0 + 80.0 * 4.0 + fill) / ((440.0 + fill) * 4.0);
    assert_close!(r.per_layer[0].gippo_score, g0);
    assert_close!(r.per_layer[1].gippo_score, 4.0);
    assert_close!(r.gippo_score, (g0 + 4.0) / 2.0);
    let p = a.preview.unwrap();
    assert_eq!(p.feature, [255, 255, 0, 0, 0, 0, 2, 0, 0, 0, 0]);
    assert_eq!(p.layer_segment_start, [0, 7, 11]);
}

#[test]
fn crlf_and_repeated_file_scale() {
    let src = fixture("prusaslicer-style.gcode");
    let crlf: Vec<u8> = src.iter().flat_map(|&b| if b == b'\n' { vec![b'\r', b'\n'] } else { vec![b] }).collect();
    let a = analyze("x", &src, &Options::default()).unwrap().report;
    let b = analyze("x", &crlf, &Options::default()).unwrap().report;
    assert_eq!(a, b);
}

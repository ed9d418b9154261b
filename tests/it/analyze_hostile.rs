//! The analyzer on hostile G-code (issue 7): cost grows linearly with the input (overlap
//! search, arcs), numbers G-code does not have are refused with their line, and memory is
//! estimated and bounded. Inputs come from `weft::testgen::gcode`.

use crate::work::work;
use weft::analyze::{analyze, estimate, Error, Options, MAX_ARC_CHORDS, MAX_LAYER_SEGMENTS, MAX_PEAK_BYTES};
use weft::testgen::gcode as gen;

fn preview() -> Options {
    Options { collect_preview: true, ..Default::default() }
}

/// Counts the work of analysing `make(n)` and `make(8n)` (cells and segments the overlap
/// search visits, allocations, bytes allocated, peak heap: [`crate::work`]) and asserts
/// linear growth (quadratic growth gives 64).
fn assert_linear(name: &str, make: fn(usize) -> Vec<u8>, n: usize, options: &Options) {
    let small = make(n);
    let big = make(8 * n);
    let bytes_ratio = big.len() as f64 / small.len() as f64;
    assert!((7.0..9.0).contains(&bytes_ratio), "{name}: the generator is not linear ({bytes_ratio})");
    let run = |bytes: &[u8]| {
        let a = analyze("scaling.gcode", bytes, options).expect("analysable");
        std::hint::black_box(a.report.overlap_mm);
    };
    crate::work::assert_linear(name, 8.0, work(|| run(&small)), work(|| run(&big)));
}

#[test]
fn normal_print_scales_linearly() {
    assert_linear("perimeter_print", gen::perimeter_print, 50_000, &preview());
}

#[test]
fn repeated_moves_scale_linearly() {
    // Was quadratic: 10,000 moves 3.3 s, 40,000 52 s.
    assert_linear("repeated_moves", gen::repeated_moves, 40_000, &Options::default());
    assert_linear("repeated_moves (preview)", gen::repeated_moves, 40_000, &preview());
}

#[test]
fn long_moves_scale_linearly() {
    // Was worse than quadratic: 250 moves 0.2 s, 1,000 10 s.
    assert_linear("long_moves", gen::long_moves, 40_000, &Options::default());
}

#[test]
fn large_arcs_scale_linearly() {
    // Was quadratic: 250 arcs 8.6 s, 1,000 159 s. 1,000 arcs of 128 chords stay under the
    // layer limit.
    assert_linear("large_arcs", gen::large_arcs, 125, &preview());
}

#[test]
fn overlap_of_hostile_inputs_is_still_measured() {
    // Each move back and forth over the strut lies wholly on the first.
    let r = analyze("r", &gen::repeated_moves(1000), &Options::default()).unwrap().report;
    assert!((r.overlap_mm - 999.0 * 10.0).abs() < 1e-6, "{}", r.overlap_mm);
    assert!((r.extruded_mm - 1000.0 * 10.0).abs() < 1e-6);
    // Long stacked moves: all but the first lie (almost) wholly on earlier ones.
    let r = analyze("l", &gen::long_moves(1000), &Options::default()).unwrap().report;
    assert!(r.overlap_mm > 0.99 * (r.extruded_mm - 425.0) && r.overlap_mm < r.extruded_mm, "{} of {}", r.overlap_mm, r.extruded_mm);
}

#[test]
fn exponents_are_refused_with_their_line() {
    // The generator's header is 7 lines; its first move has an exponent.
    let e = analyze("exp.gcode", &gen::exponent_words(100), &Options::default()).unwrap_err();
    assert!(matches!(&e, Error::Malformed { line: 8, .. }), "{e:?}");
    assert!(e.to_string().contains("exp.gcode: line 8: X1.5e1 has an exponent"), "{e}");
    for (src, what) in [("G1 X10 E1e300\n", "E1e300"), ("G1 X1e10 Y2\n", "X1e10"), ("G1 X2.5e-3 E1\n", "X2.5e-3"), ("G1 Y3e+2\n", "Y3e+2"), ("x1e5\n", "X1e5")]
    {
        let e = analyze("t.gcode", format!("G1 X0 Y0\n{src}").as_bytes(), &Options::default()).unwrap_err();
        let msg = e.to_string();
        assert!(msg.starts_with("t.gcode: line 2: ") && msg.contains(what) && msg.contains("exponent"), "{src}: {msg}");
    }
    // The compact form (an uppercase E right after a number) is X40 then E4, as firmware reads it.
    let r = analyze("c", b"G1X40E4\n", &Options::default()).unwrap().report;
    assert_eq!((r.extruded_mm, r.filament_mm), (40.0, 4.0));
    // A letter twice on a line is ambiguous.
    let e = analyze("t.gcode", b"G1 X1\nG1 X2 E1E300\n", &Options::default()).unwrap_err();
    assert!(e.to_string().contains("line 2: E appears twice"), "{e}");
}

#[test]
fn meaningless_numbers_are_refused_with_their_line() {
    for (src, what) in [
        ("G1 X20000000 E1", "X20000000 is out of range"),
        ("G1 X1 E99999999999999999999999", "E99999999999999999999999 is out of range"),
        ("G2 X0 Y0 I-10000001 E1", "I-10000001 is out of range"),
        ("G1 X1 F0.0000001", "F0.0000001 is slower than"),
        ("M204 S0.000000000000000000000000000001", "is slower than"),
        ("G4 P100000000", "P100000000 is out of range"),
    ] {
        let e = analyze("t.gcode", format!("G1 X0\n{src}\n").as_bytes(), &Options::default()).unwrap_err();
        assert!(matches!(e, Error::Malformed { line: 2, .. }), "{src}: {e:?}");
        assert!(e.to_string().contains(what), "{src}: {e}");
    }
    // The largest values accepted keep every total finite, even summed over many lines.
    let mut s = String::from("G91\nM83\n");
    for _ in 0..10_000 {
        s.push_str("G1 X10000000 Y-10000000 Z10000000 E10000000 F0.001\nM204 S0.001\nG4 P10000000\n");
    }
    let r = analyze("big", s.as_bytes(), &preview()).unwrap().report;
    for v in [r.extruded_mm, r.travel_mm, r.filament_mm, r.estimated_time_s, r.overlap_mm, r.gippo_score] {
        assert!(v.is_finite(), "{r:?}");
    }
}

#[test]
fn huge_arcs_are_bounded() {
    // A full circle of radius 10 km is drawn with MAX_ARC_CHORDS chords (and its length is exact).
    let src = "G1 X0 Y0 F6000\nG2 X0 Y0 I10000000 J0 E1\n";
    let a = analyze("huge", src.as_bytes(), &preview()).unwrap();
    assert_eq!(a.preview.unwrap().feature.len(), MAX_ARC_CHORDS);
    assert!((a.report.extruded_mm - 2.0 * std::f64::consts::PI * 1e7).abs() < 1e-3);
    // A small arc is drawn within the tolerance, with few chords: a quarter circle of 10 mm.
    let a = analyze("small", b"G1 X10 Y0\nG2 X0 Y-10 I-10 J0 E1\n", &preview()).unwrap();
    let n = a.preview.unwrap().feature.len();
    // Chord angle 2·acos(1 − 0.01/10) ≈ 5.1°: 18 chords for 90°.
    assert_eq!(n, 18);
}

#[test]
fn too_many_arcs_are_refused_cleanly() {
    // 100,000 circles of 128 chords in one layer (the tester's case aborted on a 2 GB
    // allocation): refused when the layer passes MAX_LAYER_SEGMENTS, with the line.
    let bytes = gen::large_arcs(100_000);
    for options in [Options::default(), preview()] {
        let e = analyze("arcs.gcode", &bytes, &options).unwrap_err();
        let msg = e.to_string();
        match &e {
            Error::TooLarge { line, .. } => assert!(*line > 16_000 && *line < 17_000, "{msg}"),
            other => panic!("{other:?}"),
        }
        assert!(msg.contains(&MAX_LAYER_SEGMENTS.to_string()), "{msg}");
    }
}

#[test]
fn estimate_counts_moves_layers_and_arcs() {
    let bytes = gen::perimeter_print(10_000);
    let e = estimate(&bytes, &Options::default());
    let r = analyze("p", &bytes, &Options::default()).unwrap().report;
    assert_eq!(e.bytes, bytes.len());
    // Every move line counts: extrusions, travels, Z moves, retractions.
    assert!(e.moves >= 10_000 && e.moves < 11_000, "{e:?}");
    assert_eq!(e.layers, r.layers + 1);
    // A layer is 20 rings of 120 sides, plus its Z move, travels and retractions.
    assert!(e.largest_layer >= 2400 && e.largest_layer < 2500, "{e:?}");
    assert_eq!(e.arcs, 0);
    let with_preview = estimate(&bytes, &preview());
    assert!(with_preview.peak_bytes > e.peak_bytes);
    let e = estimate(&gen::large_arcs(100), &Options::default());
    assert_eq!(e.arcs, 100);
    assert_eq!(e.moves, 2 + 2 * 100 + 1);
    // Without layer comments the largest layer may be every move.
    let e = estimate(b"G1 X1 E1\nG1 X2 E2\nG1 Z1\nG1 X3 E3\n", &Options::default());
    assert_eq!((e.moves, e.layers, e.largest_layer), (4, 2, 4));
}

#[test]
fn too_large_files_are_refused_before_reading() {
    // Eight million of the shortest extruding moves (40 MB): the preview alone would need most
    // of the limit; refused before reading, with the estimate's numbers in the message.
    let mut s = String::from("M83\n");
    for _ in 0..4_000_000 {
        s.push_str("X1E1\nX0E1\n");
    }
    let est = estimate(s.as_bytes(), &preview());
    assert!(est.peak_bytes > MAX_PEAK_BYTES, "{est:?}");
    let e = analyze("huge.gcode", s.as_bytes(), &preview()).unwrap_err();
    assert!(matches!(e, Error::TooLarge { line: 0, .. }), "{e:?}");
    let msg = e.to_string();
    assert!(msg.starts_with("huge.gcode: the analysis needs about 1.") && msg.contains("8.0M segments") && msg.contains("limit 1.0 GB"), "{msg}");
    assert!(msg.contains("without the preview") && msg.contains("command-line tool (`weft analyze`"), "{msg}");
    // Without the preview only the largest layer counts; a layer that size is refused as it
    // is read, when it passes MAX_LAYER_SEGMENTS.
    let e = analyze("huge.gcode", s.as_bytes(), &Options::default()).unwrap_err();
    assert!(matches!(e, Error::TooLarge { line, .. } if line == MAX_LAYER_SEGMENTS + 2), "{e:?}");
}

//! The G-code editor (paper section 2.3.3) on PrusaSlicer-, Slic3r- and Cura-style files in
//! relative and absolute E: every line but the infill moves' E numbers kept byte for byte,
//! each edited E at ρ(mid)/ρ_s of the original to the printed decimals, ρ_min clamping, the
//! absolute-E resets and the filament the analyzer reads back, the identity round trip, the
//! limits, the refusals, a seeded fuzz smoke and a 50 MB file.

use rand_core::{Rng, SeedableRng};
use rand_pcg::Pcg64;
use weft::gcode_edit::{edit, estimate, printed_bounds, EditReport, Edited, Error, Limit, Options, MAX_GCODE_BYTES, MAX_LINE_BYTES};
use weft::geom::DVec3;
use weft::motion::lex::lex_line;
use weft::motion::{Motion, Move, Step};
use weft::testgen::foreign::{generate, sized, Foreign, Generated, Slicer};

const VARIANTS: [(Slicer, bool); 6] =
    [(Slicer::PrusaSlicer, true), (Slicer::PrusaSlicer, false), (Slicer::Slic3r, true), (Slicer::Slic3r, false), (Slicer::Cura, true), (Slicer::Cura, false)];

/// The test part: 30 mm square at (100, 100), x in [85, 115].
fn spec(slicer: Slicer, relative_e: bool) -> Foreign {
    Foreign { slicer, relative_e, layers: 8, side_mm: 30.0, ..Foreign::default() }
}

/// A linear field along x, 0.1 at x = 85 to 0.85 at x = 115 (below ρ_min = 0.235 for
/// x < 90.4), with no value above y = 112.3 (outside the volume).
fn linear(p: DVec3) -> Option<f64> {
    (p.y <= 112.3).then_some(0.1 + 0.025 * (p.x - 85.0))
}

fn run(name: &str, text: &[u8], field: &dyn Fn(DVec3) -> Option<f64>, o: &Options) -> Edited {
    edit(name, &text, field, o, &mut |_| {}).unwrap_or_else(|e| panic!("{name}: {e}"))
}

fn lines(text: &[u8]) -> Vec<&[u8]> {
    let mut v: Vec<&[u8]> = text.split(|&b| b == b'\n').collect();
    if v.last().is_some_and(|l| l.is_empty()) {
        v.pop();
    }
    v
}

/// Each line's move as the shared machine model reads it, and the E position before it.
fn replay(text: &[u8]) -> Vec<(Option<Move>, f64)> {
    let mut m = Motion::default();
    lines(text)
        .into_iter()
        .map(|l| {
            let e = m.e;
            let l = lex_line(l).unwrap();
            match m.line(l.cmd, &l.words, false) {
                Step::Move(mv) => (Some(mv), e),
                _ => (None, e),
            }
        })
        .collect()
}

/// The line without its E number.
fn without_e(line: &[u8]) -> (Vec<u8>, Vec<u8>) {
    let p = line.iter().position(|&b| b == b'E').expect("an E word");
    let n = line[p + 1..].iter().take_while(|b| b.is_ascii_digit() || **b == b'.' || **b == b'-').count();
    (line[..p + 1].to_vec(), line[p + 1 + n..].to_vec())
}

/// Checks an edit of `g` by `field` against the file itself: returns the number of inserted
/// resets and Σ(new − old) E over the infill moves.
fn check(name: &str, g: &Generated, out: &Edited, field: &dyn Fn(DVec3) -> Option<f64>, o: &Options) -> (usize, f64) {
    let input = lines(&g.text);
    let output = lines(&out.text);
    let moves_in = replay(&g.text);
    let moves_out = replay(&out.text);
    let infill: std::collections::BTreeSet<usize> = g.infill.iter().map(|m| m.line).collect();
    let (mut i, mut inserted, mut delta, mut clamped, mut outside) = (0, 0, 0.0, 0, 0);
    for (j, line) in output.iter().enumerate() {
        let reset = line.starts_with(b"G92 E") && input.get(i) != Some(line);
        if !reset && i < input.len() && infill.contains(&i) {
            let (a, b) = (without_e(input[i]), without_e(line));
            assert_eq!(a, b, "{name}: line {} changed outside its E number", i + 1);
            let mv_in = moves_in[i].0.unwrap();
            let mv_out = moves_out[j].0.unwrap();
            let mid = (DVec3::from(mv_in.from) + DVec3::from(mv_in.to)) * 0.5 + DVec3::from(o.translation_mm);
            let expected = match field(mid) {
                Some(t) => {
                    clamped += usize::from(t < o.rho_min);
                    mv_in.de * (t.max(o.rho_min).min(o.rho_max) / o.rho_s)
                }
                None => {
                    outside += 1;
                    assert_eq!(input[i], *line, "{name}: line {} outside the field changed", i + 1);
                    mv_in.de
                }
            };
            assert!((mv_out.de - expected).abs() <= 0.5e-5 + 1e-9, "{name}: line {}: E delta {} for {expected}", i + 1, mv_out.de);
            delta += mv_out.de - mv_in.de;
            i += 1;
        } else if !reset && i < input.len() && input[i] == *line {
            i += 1;
        } else {
            // An inserted reset: the input's E position before its next line, verbatim.
            let text = std::str::from_utf8(line).unwrap();
            let v: f64 =
                text.strip_prefix("G92 E").unwrap_or_else(|| panic!("{name}: output line {} `{text}` is neither input nor a reset", j + 1)).parse().unwrap();
            assert_eq!(v, moves_in[i].1, "{name}: reset at output line {}", j + 1);
            inserted += 1;
        }
    }
    assert_eq!(i, input.len(), "{name}: input lines missing from the output");
    let r = &out.report;
    assert_eq!(r.infill_moves, g.infill.len(), "{name}");
    assert_eq!(r.outside_field, outside, "{name}");
    assert_eq!(r.edited_moves, g.infill.len() - outside, "{name}");
    assert_eq!(r.clamped_low, clamped, "{name}");
    assert_eq!(r.resets_inserted, inserted, "{name}");
    (inserted, delta)
}

#[test]
fn every_non_infill_byte_is_kept_and_every_edit_follows_equation_6() {
    let o = Options::default();
    for (slicer, relative) in VARIANTS {
        let name = format!("{slicer:?}-{}", if relative { "M83" } else { "M82" });
        let g = generate(&spec(slicer, relative));
        let out = run(&name, &g.text, &linear, &o);
        let (inserted, _) = check(&name, &g, &out, &linear, &o);
        let r = &out.report;
        assert!(r.clamped_low > 0 && r.outside_field > 0 && r.edited_moves > r.clamped_low, "{name}: {r:?}");
        assert_eq!(r.extrusion, if relative { "relative" } else { "absolute" }, "{name}");
        assert_eq!(
            r.dialect,
            match slicer {
                Slicer::PrusaSlicer => "PrusaSlicer",
                Slicer::Slic3r => "Slic3r",
                Slicer::Cura => "Cura",
            }
        );
        if relative {
            assert_eq!(inserted, 0, "{name}: relative E needs no reset");
        } else {
            assert!(inserted > 0, "{name}");
        }
        // Slic3r cannot tell solid from sparse infill: its solid layers are edited too.
        assert_eq!(g.infill.iter().any(|m| m.solid), slicer == Slicer::Slic3r);
    }
}

#[test]
fn the_identity_field_gives_the_input_back_byte_for_byte() {
    let o = Options::default();
    for (slicer, relative) in VARIANTS {
        let g = generate(&spec(slicer, relative));
        let out = run("identity", &g.text, &|_| Some(0.47), &o);
        assert!(out.text == g.text, "{slicer:?} relative {relative}: output differs");
        assert_eq!(out.report.edited_moves, g.infill.len());
        assert_eq!(out.report.resets_inserted, 0);
        assert_eq!(out.report.filament_after_mm, out.report.filament_before_mm);
    }
}

#[test]
fn absolute_e_files_feed_the_filament_the_analyzer_reads_back() {
    let o = Options::default();
    for slicer in [Slicer::PrusaSlicer, Slicer::Slic3r, Slicer::Cura] {
        let g = generate(&spec(slicer, false));
        let out = run("abs", &g.text, &linear, &o);
        let (_, delta) = check("abs", &g, &out, &linear, &o);
        let a = weft::analyze::Options::default();
        let before = weft::analyze::analyze("in.gcode", &g.text, &a).unwrap().report.filament_mm;
        let after = weft::analyze::analyze("out.gcode", &out.text, &a).unwrap().report.filament_mm;
        assert!(delta.abs() > 0.5, "{slicer:?}: the field changes the filament ({delta})");
        assert!((after - (before + delta)).abs() < 1e-6, "{slicer:?}: analyzer {after}, expected {}", before + delta);
        assert!((out.report.filament_before_mm - before).abs() < 1e-9);
        assert!((out.report.filament_after_mm - after).abs() < 1e-6, "{} vs {after}", out.report.filament_after_mm);
        let area = std::f64::consts::PI * 1.75 * 1.75 / 4.0;
        assert!((out.report.infill_after_mm3 - out.report.infill_before_mm3 - delta * area).abs() < 1e-6);
    }
}

#[test]
fn an_absolute_run_gets_one_reset_with_the_original_e() {
    let text = b"M82\nG92 E0\nG1 Z0.2\n;TYPE:Perimeter\nG1 X10 Y0 E1.00000\n;TYPE:Internal infill\nG1 X20 Y0 E2.00000\nG1 X30 Y0 E3.00000 ; keep me\n;TYPE:Perimeter\nG1 X40 Y0 E4.00000\r\nG1 X50 Y0 E5.00000\n";
    let o = Options { rho_s: 0.5, rho_min: 0.1, ..Options::default() };
    let out = run("run", text, &|_| Some(0.25), &o);
    let expected = "M82\nG92 E0\nG1 Z0.2\n;TYPE:Perimeter\nG1 X10 Y0 E1.00000\n;TYPE:Internal infill\nG1 X20 Y0 E1.50000\nG1 X30 Y0 E2.00000 ; keep me\n;TYPE:Perimeter\nG92 E3.00000\r\nG1 X40 Y0 E4.00000\r\nG1 X50 Y0 E5.00000\n";
    assert_eq!(String::from_utf8(out.text).unwrap(), expected);
    assert_eq!(out.report.resets_inserted, 1);
    assert_eq!(out.report.filament_before_mm, 5.0);
    assert_eq!(out.report.filament_after_mm, 4.0);
    // The next command resetting E itself needs no inserted line.
    let text = b"M82\nG1 Z0.2\n;TYPE:FILL\nG1 X20 Y0 E2.00000\n;TYPE:SKIN\nG92 E0\nG1 X30 Y0 E1.00000\n";
    let out = run("g92", text, &|_| Some(0.25), &o);
    assert_eq!(String::from_utf8(out.text).unwrap(), "M82\nG1 Z0.2\n;TYPE:FILL\nG1 X20 Y0 E1.00000\n;TYPE:SKIN\nG92 E0\nG1 X30 Y0 E1.00000\n");
    assert_eq!(out.report.resets_inserted, 0);
}

#[test]
fn relative_edits_reset_before_a_switch_to_absolute_e() {
    let text = b"M83\nG1 Z0.2\n;TYPE:FILL\nG1 X20 Y0 E2.0\n;TYPE:SKIN\nM82\nG1 X30 Y0 E3.0\n";
    let o = Options { rho_s: 0.5, rho_min: 0.1, ..Options::default() };
    let out = run("switch", text, &|_| Some(0.25), &o);
    assert_eq!(String::from_utf8(out.text).unwrap(), "M83\nG1 Z0.2\n;TYPE:FILL\nG1 X20 Y0 E1.0\n;TYPE:SKIN\nG92 E2.0\nM82\nG1 X30 Y0 E3.0\n");
    assert_eq!(out.report.extrusion, "mixed");
}

#[test]
fn prusaslicer_number_style_and_inches() {
    // Trimmed numbers keep the file's fifth decimal and drop trailing zeros; leading zeros
    // follow each word.
    let text = b"; generated by PrusaSlicer 2.6.1\nM83\nG1 Z.2\n;TYPE:Internal infill\nG1 X10 Y0 E.02612\nG1 X20 Y0 E.1\nG1 X30 Y0 E1.5\n";
    let o = Options { rho_s: 0.5, rho_min: 0.1, ..Options::default() };
    let out = run("style", text, &|_| Some(0.3), &o);
    assert_eq!(
        String::from_utf8(out.text).unwrap(),
        "; generated by PrusaSlicer 2.6.1\nM83\nG1 Z.2\n;TYPE:Internal infill\nG1 X10 Y0 E.01567\nG1 X20 Y0 E.06\nG1 X30 Y0 E.9\n"
    );
    // Inches: the field is evaluated at millimetres, the E word scales in its own unit.
    let text = b"G20\nM83\nG1 Z0.01\n;TYPE:FILL\nG1 X1 Y0 E0.10000\n";
    let out = run("inch", text, &|p| Some(p.x / 50.8), &o);
    assert_eq!(String::from_utf8(out.text).unwrap(), "G20\nM83\nG1 Z0.01\n;TYPE:FILL\nG1 X1 Y0 E0.05000\n");
}

#[test]
fn targets_are_clamped_to_rho_min_and_rho_max() {
    let g = generate(&spec(Slicer::Cura, true));
    let o = Options { rho_min: 0.3, rho_max: 0.6, ..Options::default() };
    let out = run("clamp", &g.text, &linear, &o);
    check("clamp", &g, &out, &linear, &o);
    let r = &out.report;
    let (lo, hi) = g.infill.iter().fold((0, 0), |(lo, hi), m| match linear(DVec3::from(m.mid)) {
        Some(t) if t < 0.3 => (lo + 1, hi),
        Some(t) if t > 0.6 => (lo, hi + 1),
        _ => (lo, hi),
    });
    assert!(lo > 0 && hi > 0);
    assert_eq!((r.clamped_low, r.clamped_high), (lo, hi));
}

#[test]
fn flow_and_width_limits_warn_or_clamp() {
    // Five times the sliced E: 2.1 mm beads at 50 mm/s, 20.4 mm³/s.
    let g = generate(&spec(Slicer::PrusaSlicer, true));
    let o = Options { rho_s: 0.2, ..Options::default() };
    let warn = run("warn", &g.text, &|_| Some(1.0), &o);
    check("warn", &g, &warn, &|_| Some(1.0), &o);
    let sparse = g.infill.len();
    assert_eq!((warn.report.over_width, warn.report.over_flow), (sparse, sparse));
    let o = Options { limit: Limit::Clamp, ..o };
    let clamp = run("clamp", &g.text, &|_| Some(1.0), &o);
    assert_eq!((clamp.report.over_width, clamp.report.over_flow), (sparse, sparse));
    let area_f = std::f64::consts::PI * 1.75 * 1.75 / 4.0;
    let (moves, out) = (replay(&g.text), replay(&clamp.text));
    let lh = 0.2;
    for m in &g.infill {
        let (Some(a), Some(b)) = (moves[m.line].0, out[m.line].0) else { panic!() };
        assert_eq!(a.to, b.to);
        let area = b.de * area_f / b.len;
        let width = area / lh + (1.0 - std::f64::consts::FRAC_PI_4) * lh;
        // Width binds (1.2 mm) before flow (19.24 mm³/s at 50 mm/s is 0.385 mm²).
        assert!(width <= 1.2 + 1e-3 && width > 1.19, "width {width} at line {}", m.line + 1);
        assert!(area * b.v <= 19.24);
    }
}

#[test]
fn layer_statistics_weigh_by_length() {
    let s = spec(Slicer::PrusaSlicer, true);
    let g = generate(&s);
    let out = run("layers", &g.text, &|_| Some(0.3), &Options::default());
    let r: &EditReport = &out.report;
    assert_eq!(r.layers.len(), s.layers - 2 * s.solid_layers);
    assert_eq!(r.layers.iter().map(|l| l.moves).sum::<usize>(), r.edited_moves);
    let len: f64 = g.infill.iter().map(|m| m.len).sum();
    assert!((r.layers.iter().map(|l| l.length_mm).sum::<f64>() - len).abs() < 1e-4 * len);
    for (k, l) in r.layers.iter().enumerate() {
        assert!((l.z_mm - 0.2 * (k + s.solid_layers + 1) as f64).abs() < 1e-9);
        assert!((l.target_mean - 0.3).abs() < 1e-12);
        // Printed to 5 decimals of E per ~2 mm segment: the achieved density is within 1e-3.
        assert!((l.achieved_mean - 0.3).abs() < 1e-3 && l.mean_abs_error < 1e-3, "{l:?}");
        assert!(l.mean_abs_error >= (l.achieved_mean - l.target_mean).abs() - 1e-15);
    }
}

#[test]
fn translation_moves_the_field_and_bounds_give_the_part() {
    let g = generate(&spec(Slicer::Slic3r, true));
    let b = printed_bounds("bounds", &g.text).unwrap();
    for k in 0..3 {
        assert!((b.min[k] - g.bounds.0[k]).abs() < 1e-3 && (b.max[k] - g.bounds.1[k]).abs() < 1e-3, "{b:?} vs {:?}", g.bounds);
    }
    // A field 100 mm to the left, reached by the translation.
    let shifted = |p: DVec3| linear(p + DVec3::new(100.0, 0.0, 0.0));
    let o = Options { translation_mm: [-100.0, 0.0, 0.0], ..Options::default() };
    let out = run("shift", &g.text, &shifted, &o);
    check("shift", &g, &out, &shifted, &o);
    assert_eq!(out.text, run("plain", &g.text, &linear, &Options::default()).text);
    assert_eq!(out.report.bounds_min, b.min.to_array());
    assert_eq!(out.report.bounds_max, b.max.to_array());
}

#[test]
fn files_without_infill_name_the_types_they_have() {
    let cases: [(Slicer, &[&str]); 3] = [
        (Slicer::PrusaSlicer, &["Custom", "Perimeter", "External perimeter", "Solid infill"]),
        (Slicer::Cura, &["WALL-INNER", "WALL-OUTER", "SKIN"]),
        (Slicer::Slic3r, &["perimeter"]),
    ];
    for (slicer, types) in cases {
        let solid_layers = if slicer == Slicer::Slic3r { 0 } else { 2 };
        let g = generate(&Foreign { rho_s: 0.0, solid_layers, ..spec(slicer, true) });
        match edit("none.gcode", &g.text, &linear, &Options::default(), &mut |_| {}) {
            Err(e @ Error::NoInfill { .. }) => {
                let Error::NoInfill { types_seen, .. } = &e else { unreachable!() };
                assert_eq!(types_seen, &types.iter().map(|s| s.to_string()).collect::<Vec<_>>(), "{slicer:?}");
                assert!(e.to_string().contains("set infill_types"), "{e}");
            }
            other => panic!("{slicer:?}: {:?}", other.map(|o| o.report)),
        }
    }
    // Naming the feature makes it infill.
    let g = generate(&Foreign { rho_s: 0.0, ..spec(Slicer::Cura, true) });
    let o = Options { infill_types: vec!["skin".into()], ..Options::default() };
    assert!(run("skin", &g.text, &linear, &o).report.edited_moves > 0);
}

#[test]
fn refusals_are_typed() {
    let g = generate(&spec(Slicer::PrusaSlicer, true));
    let field = |_: DVec3| Some(0.5);
    let o = Options::default();
    let err = |text: &[u8], o: &Options| edit("bad.gcode", &text, &field, o, &mut |_| {}).err().expect("refused");
    let mut bin = g.text.clone();
    let at = bin.iter().enumerate().filter(|(_, &b)| b == b'\n').nth(4).unwrap().0 + 1;
    bin.insert(at + 2, 0);
    assert_eq!(err(&bin, &o), Error::NotText { file: "bad.gcode".into(), line: 6 });
    let mut long = b"M83\n;".to_vec();
    long.extend(std::iter::repeat_n(b'x', MAX_LINE_BYTES + 1));
    assert!(matches!(err(&long, &o), Error::LineTooLong { line: 2, .. }));
    assert!(matches!(err(b"M83\nG1 X1.2.3 E1\n", &o), Error::Malformed { line: 2, .. }));
    assert!(matches!(err(b"M83\n;TYPE:FILL\nG1 X5 Y1 E0.1*33\n", &o), Error::Checksum { line: 3, .. }));
    for bad in [
        Options { rho_s: 0.0, ..Options::default() },
        Options { rho_min: 0.9, rho_max: 0.5, ..Options::default() },
        Options { q_max_mm3_s: f64::NAN, ..Options::default() },
        Options { translation_mm: [0.0, f64::INFINITY, 0.0], ..Options::default() },
        Options { infill_types: vec![" ".into()], ..Options::default() },
    ] {
        assert!(matches!(err(&g.text, &bad), Error::BadOption { .. }), "{bad:?}");
    }
    let e = estimate(MAX_GCODE_BYTES + 1, &o);
    assert!(e.check().is_err());
    assert_eq!(e.stage, "edit");
    let e = estimate(50 << 20, &o);
    assert!(e.check().is_ok() && e.bytes >= (50 << 20) as f64);
    assert!(matches!(printed_bounds("empty", &&b"G1 X5\n"[..]), Err(Error::NoExtrusion { .. })));
}

#[test]
fn options_read_from_json() {
    let o: Options = serde_json::from_str(r#"{"rho_s":0.3,"limit":"clamp","infill_types":["Sparse infill"]}"#).unwrap();
    assert_eq!((o.rho_s, o.limit, o.rho_min), (0.3, Limit::Clamp, weft::gcode_edit::DEFAULT_RHO_MIN));
    assert!(serde_json::from_str::<Options>(r#"{"rho":0.3}"#).is_err());
    let d = Options::default();
    assert_eq!(serde_json::from_str::<Options>(&serde_json::to_string(&d).unwrap()).unwrap(), d);
    assert_eq!(d.infill_types, ["Internal infill", "FILL", "infill"]);
}

fn rand_below(rng: &mut Pcg64, n: usize) -> usize {
    if n == 0 {
        0
    } else {
        (rng.next_u64() % n as u64) as usize
    }
}

#[test]
fn fuzz_smoke_never_panics() {
    let bases: Vec<Vec<u8>> = VARIANTS.iter().map(|&(s, r)| generate(&Foreign { layers: 5, side_mm: 8.0, ..spec(s, r) }).text).collect();
    let words: [&[u8]; 10] = [b"E", b"E-", b"E1e9", b"G2 X1 Y1 I1 J0 E1\n", b"G91\n", b"M82\n", b"G20\n", b"*12", b";TYPE:FILL\n", b"E9999999"];
    let mut rng = Pcg64::seed_from_u64(11);
    let (mut ok, mut refused) = (0, 0);
    for case in 0..3000 {
        let mut data = bases[case % bases.len()].clone();
        for _ in 0..1 + rand_below(&mut rng, 4) {
            let len = data.len();
            match rng.next_u32() % 5 {
                0 => {
                    let i = rand_below(&mut rng, len);
                    data[i] ^= 1 << (rng.next_u32() % 8);
                }
                1 => data.truncate(rand_below(&mut rng, len + 1)),
                2 => {
                    let at = rand_below(&mut rng, len + 1);
                    let w = words[rand_below(&mut rng, words.len())];
                    data.splice(at..at, w.iter().copied());
                }
                3 => {
                    let at = rand_below(&mut rng, len + 1);
                    let n = 1 + rand_below(&mut rng, 8);
                    let junk: Vec<u8> = (0..n).map(|_| rng.next_u32() as u8).collect();
                    data.splice(at..at, junk);
                }
                _ => {
                    let a = rand_below(&mut rng, len);
                    let n = rand_below(&mut rng, (len - a).min(300));
                    let chunk = data[a..a + n].to_vec();
                    let at = rand_below(&mut rng, len + 1);
                    data.splice(at..at, chunk);
                }
            }
        }
        let rho = 0.05 + 0.9 * (case % 7) as f64 / 7.0;
        let o = Options { limit: if case % 2 == 0 { Limit::Warn } else { Limit::Clamp }, ..Options::default() };
        match edit("fuzz", &data, &|p| (p.x > 95.0).then_some(rho), &o, &mut |_| {}) {
            Ok(out) => {
                ok += 1;
                assert!(out.text.len() <= 2 * data.len() + 64, "case {case}: output grew to {}", out.text.len());
                assert!(out.report.filament_after_mm.is_finite());
            }
            Err(_) => refused += 1,
        }
        let _ = printed_bounds("fuzz", &data);
    }
    println!("fuzz: {ok} edited, {refused} refused");
    assert!(ok > 300 && refused > 300, "{ok} / {refused}");
}

#[test]
fn edits_a_50_mb_file() {
    let g = sized(Slicer::PrusaSlicer, false, 50 << 20);
    let mut calls = 0;
    let (w, out) = crate::work::measure(|| edit("big.gcode", &g.text, &linear, &Options::default(), &mut |_| calls += 1).unwrap());
    println!("edited {:.1} MB ({} infill moves, {} resets): {w:?}", g.text.len() as f64 / 1e6, out.report.edited_moves, out.report.resets_inserted);
    assert_eq!(out.report.infill_moves, g.infill.len());
    assert!(out.text.len() as f64 <= g.text.len() as f64 * 1.02);
    assert!(calls >= 10);

    // The same file read in 4 MiB pieces (as the page reads a dropped file it keeps outside
    // wasm memory): the same bytes out, the same report, the same box.
    let far = Far(&g.text);
    let pieces = edit("big.gcode", &far, &linear, &Options::default(), &mut |_| {}).unwrap();
    assert!(far.reads.get() >= 12, "read in pieces: {}", far.reads.get());
    assert!(pieces.text == out.text, "the edit read in pieces differs");
    assert_eq!(pieces.report, out.report);
    assert_eq!(printed_bounds("big.gcode", &far).unwrap(), printed_bounds("big.gcode", &g.text).unwrap());
}

/// A file not in memory: read in ranges, counting the reads; `gone_after` reads fail after
/// that many (a file deleted after it was dropped).
struct Far<'a> {
    bytes: &'a [u8],
    reads: std::cell::Cell<usize>,
    gone_after: usize,
}

#[allow(non_snake_case)]
fn Far(bytes: &[u8]) -> Far<'_> {
    Far { bytes, reads: Default::default(), gone_after: usize::MAX }
}

impl weft::source::ByteSource for Far<'_> {
    fn len(&self) -> usize {
        self.bytes.len()
    }
    fn read_at(&self, offset: usize, buf: &mut [u8]) -> Result<(), String> {
        self.reads.set(self.reads.get() + 1);
        if self.reads.get() > self.gone_after {
            return Err("NotFoundError: the file was removed".into());
        }
        buf.copy_from_slice(&self.bytes[offset..offset + buf.len()]);
        Ok(())
    }
}

#[test]
fn a_file_that_cannot_be_read_any_more_is_named() {
    let g = generate(&spec(Slicer::PrusaSlicer, false));
    let gone = Far { gone_after: 0, ..Far(&g.text) };
    match edit("moved.gcode", &gone, &linear, &Options::default(), &mut |_| {}) {
        Err(e @ Error::Read { .. }) => assert!(e.to_string().contains("moved.gcode") && e.to_string().contains("load it again"), "{e}"),
        other => panic!("{:?}", other.map(|o| o.report)),
    }
}

//! Every example (and variants that exercise each writer option) gives the G-code recorded in
//! `tests/golden/`, the same bytes at 1, 2 and 4 threads: refactors of the core must not change
//! a byte. The cases run in this process (the pipeline the CLI calls, on pools of 1, 2 and 4
//! threads); a few also run through the `weft` binary, which must give the same bytes.
//!
//! `tests/golden/gcode.sha256` holds each output's SHA-256; `tests/golden/gcode/NAME.blocks`
//! the hash of every block of up to 256 lines of every layer, so a mismatch names the first
//! layer and lines that differ and prints them; small outputs are kept whole as
//! `NAME.gcode.gz`, so the mismatch shows the expected lines beside the new ones. When a change
//! is meant to alter output, regenerate them with
//! `WEFT_BLESS=1 cargo test --release --test it golden_gcode::` and say why in the commit.

use crate::common::root;
use sha2::{Digest, Sha256};
use std::collections::BTreeMap;
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::process::Command;

/// (output name, example, `--set` overrides).
const CASES: &[(&str, &str, &[&str])] = &[
    ("arrowhead-10mm", "arrowhead-10mm", &[]),
    ("ball-burst-disc-48mm", "ball-burst-disc-48mm", &[]),
    ("barrel-omega1", "barrel-omega1", &[]),
    ("barrel-graded", "barrel-graded", &[]),
    ("barrel-omega2", "barrel-omega2", &[]),
    ("foam-dogbone-linear", "foam-dogbone-linear", &[]),
    ("foam-dogbone-log", "foam-dogbone-log", &[]),
    ("foam-dogbone-modulus", "foam-dogbone-modulus", &[]),
    ("foam-hinge-cube", "foam-hinge-cube", &[]),
    ("foam-insole", "foam-insole", &[]),
    ("foam-stiffness-sectors", "foam-stiffness-sectors", &[]),
    ("v-foam-sectors-nearest", "foam-stiffness-sectors", &["job.foam.junction=nearest"]),
    ("freeform-bridge", "freeform-bridge", &[]),
    ("freeform-cantilever-truss", "freeform-cantilever-truss", &[]),
    ("freeform-cantilever-truss-tilt", "freeform-cantilever-truss-tilt", &[]),
    ("freeform-dome", "freeform-dome", &[]),
    ("freeform-dome-exact", "freeform-dome-exact", &[]),
    ("freeform-duck", "freeform-duck", &[]),
    ("freeform-four-frame", "freeform-four-frame", &[]),
    ("freeform-klein-bottle", "freeform-klein-bottle", &[]),
    ("freeform-klein-bottle-relaxed", "freeform-klein-bottle-relaxed", &[]),
    ("freeform-semi-sphere", "freeform-semi-sphere", &[]),
    ("freeform-semi-sphere-relaxed", "freeform-semi-sphere-relaxed", &[]),
    ("freeform-topopt", "freeform-topopt", &[]),
    ("freeform-topopt-relaxed", "freeform-topopt-relaxed", &[]),
    ("freeform-tower", "freeform-tower", &[]),
    ("freeform-tower-bands", "freeform-tower-bands", &[]),
    ("freeform-voronoi", "freeform-voronoi", &[]),
    ("v-freeform-tower-heuristic", "freeform-tower", &["job.planner.cost=heuristic"]),
    ("graded-phantom", "graded-phantom", &[]),
    ("v-graded-honeycomb3d", "graded-phantom", &["job.slice.infill_pattern=honeycomb3d"]),
    ("v-graded-rectilinear-clamp", "graded-phantom", &["job.slice.infill_pattern=rectilinear", "job.density.limit=clamp", "job.density.max_width_mm=0.6"]),
    ("concave-cylinder-honeycomb", "concave-cylinder-honeycomb", &[]),
    ("cube-20mm", "cube-20mm", &[]),
    ("cylinder-dense-infill", "cylinder-dense-infill", &[]),
    ("cylinder-on-sphere", "cylinder-on-sphere", &[]),
    ("honeycomb-10mm", "honeycomb-10mm", &[]),
    ("hourglass-omega3", "hourglass-omega3", &[]),
    ("penrose-10mm", "penrose-10mm", &[]),
    ("reentrant-honeycomb-10mm", "reentrant-honeycomb-10mm", &[]),
    ("snub-square-10mm", "snub-square-10mm", &[]),
    ("sphere-30mm", "sphere-30mm", &[]),
    ("tensile-honeycomb", "tensile-honeycomb", &[]),
    ("thin-layers-cube", "thin-layers-cube", &[]),
    ("voronoi-10mm", "voronoi-10mm", &[]),
    ("v-pneumatic", "honeycomb-10mm", &["printer.flavor=pneumatic", "material.flow.pre_flow_s=0.2", "material.flow.post_flow_s=0.1"]),
    (
        "v-relative-hop",
        "cube-20mm",
        &["printer.relative_e=true", "printer.retraction.z_hop_mm=0.4", "material.flow.pre_flow_mm=0.05", "material.flow.post_flow_mm=0.02"],
    ),
    ("v-continuous", "voronoi-10mm", &["job.paths.method=continuous"]),
    ("v-euler", "voronoi-10mm", &["job.paths.method=euler", "job.paths.order=min_travel"]),
    ("v-center", "cube-20mm", &["printer.origin=center", "printer.bed_size_mm=[200,200,200]"]),
    ("v-poses-csv", "barrel-omega2", &["printer.flavor=poses_csv"]),
    ("v-ijk", "barrel-omega2", &["printer.machine.axis_output=ijk"]),
];

/// Threads each case runs at: the G-code must not depend on the count (`weft::par`).
const THREADS: &[usize] = &[1, 2, 4];

/// Cases also run through the `weft` binary (one of each output flavour and job family): the
/// CLI gives the bytes the pipeline gives.
const THROUGH_CLI: &[&str] = &["honeycomb-10mm", "v-pneumatic", "v-poses-csv", "cube-20mm", "freeform-bridge"];

/// Lines per hashed block within a layer.
const BLOCK_LINES: usize = 256;
/// Outputs whose gzip is at most this size are kept whole beside their blocks.
const KEEP_WHOLE_GZ_BYTES: usize = 32 << 10;
/// Lines shown on each side of a mismatch.
const SHOWN: usize = 6;

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

/// The G-code of `example` with `sets`, made in this process on a pool of `threads` threads.
fn gcode_of(example: &str, sets: &[&str], threads: usize) -> String {
    String::clone(&run_of(example, sets, threads).gcode)
}

/// The run of `example` with `sets` in this process on a pool of `threads` threads.
fn run_of(example: &str, sets: &[&str], threads: usize) -> weft::pipeline::RunOutput {
    let mut d = crate::common::example(example);
    if !sets.is_empty() {
        d = d.with_overrides(&sets.iter().map(|s| s.to_string()).collect::<Vec<_>>()).unwrap();
    }
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
    let out = pool.install(|| weft::pipeline::run(&d, &weft::pipeline::Files::new(), &weft::RunOptions::default(), &mut |_, _| {}));
    out.unwrap_or_else(|e| panic!("{example} {sets:?}: {e}"))
}

/// Extruding moves of a 3-axis G-code shorter than `min` mm (as written: each end rounded to
/// the file's 3 decimals), with their line numbers; none for files with rotary or tool-axis
/// words (their X Y Z are machine coordinates).
fn dust(text: &str, min: f64) -> Vec<(usize, f64)> {
    let (mut pos, mut e, mut relative) = ([0.0f64; 3], 0.0f64, false);
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let code = line.split(';').next().unwrap_or("").trim();
        let mut words = code.split_whitespace();
        let Some(cmd) = words.next() else { continue };
        match cmd {
            "M82" => relative = false,
            "M83" => relative = true,
            "G92" => {
                for w in words {
                    if let Some(v) = w.strip_prefix('E') {
                        e = v.parse().unwrap_or(e);
                    }
                }
            }
            "G0" | "G1" => {
                let mut to = pos;
                let mut de = 0.0;
                for w in words {
                    let (letter, v) = w.split_at(1);
                    let Ok(v) = v.parse::<f64>() else { continue };
                    match letter {
                        "X" => to[0] = v,
                        "Y" => to[1] = v,
                        "Z" => to[2] = v,
                        "E" if relative => de = v,
                        "E" => {
                            de = v - e;
                            e = v;
                        }
                        "A" | "B" | "C" | "I" | "J" | "K" => return Vec::new(),
                        _ => {}
                    }
                }
                let len = ((to[0] - pos[0]).powi(2) + (to[1] - pos[1]).powi(2) + (to[2] - pos[2]).powi(2)).sqrt();
                if de > 0.0 && len > 0.0 && len < min {
                    out.push((i + 1, len));
                }
                pos = to;
            }
            _ => {}
        }
    }
    out
}

/// Numbers a description states with a unit or as a count ("120°", "0.148 mm", "83 beams"),
/// each with its decimals, leaving out names (Ω1, Fig. 7a, equation 7, M3) and list markers.
fn stated_numbers(text: &str) -> Vec<(String, f64, usize)> {
    let chars: Vec<char> = text.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        let prev = if i == 0 { ' ' } else { chars[i - 1] };
        let starts = c.is_ascii_digit() && (prev == 'Ø' || !(prev.is_alphanumeric() || matches!(prev, '_' | '.' | '-' | '/')));
        if !starts {
            i += 1;
            continue;
        }
        let from = i;
        let mut s = String::new();
        loop {
            match chars.get(i) {
                Some(d) if d.is_ascii_digit() || *d == '.' => s.push(*d),
                // "1 620": a thousands gap (a space, then exactly three digits).
                Some(' ')
                    if s.len() <= 3
                        && !s.contains('.')
                        && chars.get(i + 1..i + 4).is_some_and(|t| t.iter().all(|c| c.is_ascii_digit()))
                        && !chars.get(i + 4).is_some_and(|c| c.is_ascii_digit() || *c == '.') => {}
                _ => break,
            }
            i += 1;
        }
        let s = s.trim_end_matches('.').to_string();
        let before: String = chars[from.saturating_sub(10)..from].iter().collect::<String>().trim_end().to_string();
        let after: String = chars[i..(i + 8).min(chars.len())].iter().collect();
        // A range's second end ("Figs. 5–6") is named when its first is.
        let range_of = before.strip_suffix('–').map(|b| b.trim_end_matches(|c: char| c.is_ascii_digit()).trim_end().to_string());
        let names = ["Fig", "Figs", "Fig.", "Figs.", "equation", "Ω", "al."];
        let named =
            names.iter().any(|w| before.ends_with(w) || range_of.as_deref().is_some_and(|b| b.ends_with(w))) || after.starts_with(|c: char| c.is_alphabetic());
        if named {
            continue;
        }
        if let Ok(v) = s.parse::<f64>() {
            let decimals = s.split_once('.').map_or(0, |(_, d)| d.len());
            out.push((format!("{s}{}", after.chars().take(6).collect::<String>()), v, decimals));
        }
    }
    out
}

/// Every number in `v` (a JSON tree), and each as a percentage and in degrees of a radian
/// value, so that "50 %" meets 0.5 and "13°" meets 0.2269 rad.
fn numbers_of(v: &serde_json::Value, out: &mut Vec<f64>) {
    match v {
        serde_json::Value::Number(n) => {
            if let Some(x) = n.as_f64() {
                out.extend([x, x * 100.0, x.to_degrees(), -x]);
            }
        }
        // Short arrays only: long ones are plot data, where any number may be found.
        serde_json::Value::Array(a) if a.len() <= 64 => a.iter().for_each(|x| numbers_of(x, out)),
        serde_json::Value::Object(m) => m.values().for_each(|x| numbers_of(x, out)),
        _ => {}
    }
}

/// The numbers of an example's description that neither its design nor its own run states
/// (to the description's precision).
fn untrue_numbers(example: &str, run: &weft::pipeline::RunOutput) -> Vec<String> {
    let d = crate::common::example(example);
    let text = std::fs::read_to_string(root().join(format!("examples/{example}.json"))).unwrap();
    let json: serde_json::Value = serde_json::from_str(&text).unwrap();
    let description = json.get("description").and_then(|v| v.as_str()).unwrap_or("").to_string();
    let mut known = Vec::new();
    numbers_of(&serde_json::to_value(&d).unwrap(), &mut known);
    numbers_of(&serde_json::to_value(&run.report).unwrap(), &mut known);
    stated_numbers(&description)
        .into_iter()
        .filter(|(_, v, decimals)| {
            let half = 0.5 * 10f64.powi(-(*decimals as i32));
            !known.iter().any(|k| (k - v).abs() <= half * (1.0 + 1e-9) || (v.fract() == 0.0 && *v >= 1000.0 && (k - v).abs() <= 0.005 * v))
        })
        .map(|(s, _, _)| s)
        .collect()
}

/// The G-code of `example` with `sets` from the `weft` binary.
fn gcode_from_cli(example: &str, sets: &[&str], dir: &Path) -> String {
    let out = dir.join(format!("{example}-{}.out", sets.len()));
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_weft"));
    cmd.arg("run").arg(root().join(format!("examples/{example}.json"))).arg("--out").arg(&out).arg("-q");
    for s in sets {
        cmd.arg("--set").arg(s);
    }
    let status = cmd.output().unwrap();
    assert!(status.status.success(), "{example}: {}", String::from_utf8_lossy(&status.stderr));
    std::fs::read_to_string(&out).unwrap()
}

/// One hashed block: the layer (0: before the first `;LAYER_CHANGE`), its first line (1-based
/// in the file), its line count and the first 16 hex digits of its SHA-256.
#[derive(Clone, Debug, PartialEq, Eq)]
struct Block {
    layer: usize,
    first: usize,
    lines: usize,
    hash: String,
}

/// The blocks of `text`: each layer cut in runs of at most [`BLOCK_LINES`] lines.
fn blocks(text: &str) -> Vec<Block> {
    let lines: Vec<&str> = text.split_inclusive('\n').collect();
    let mut out = Vec::new();
    let (mut layer, mut start) = (0, 0);
    let flush = |layer: usize, from: usize, to: usize, out: &mut Vec<Block>| {
        let mut at = from;
        while at < to {
            let end = (at + BLOCK_LINES).min(to);
            let mut h = Sha256::new();
            for l in &lines[at..end] {
                h.update(l.as_bytes());
            }
            out.push(Block { layer, first: at + 1, lines: end - at, hash: hex(&h.finalize())[..16].to_string() });
            at = end;
        }
    };
    for (i, l) in lines.iter().enumerate() {
        if l.starts_with(";LAYER_CHANGE") {
            flush(layer, start, i, &mut out);
            (layer, start) = (layer + 1, i);
        }
    }
    flush(layer, start, lines.len(), &mut out);
    out
}

fn blocks_path(name: &str) -> PathBuf {
    root().join(format!("tests/golden/gcode/{name}.blocks"))
}

fn whole_path(name: &str) -> PathBuf {
    root().join(format!("tests/golden/gcode/{name}.gcode.gz"))
}

fn write_blocks(name: &str, text: &str) -> String {
    let mut s = format!("# {name}: the hash of each block of up to {BLOCK_LINES} lines of each layer (layer first-line lines sha256[..16])\n");
    for b in blocks(text) {
        s.push_str(&format!("{} {} {} {}\n", b.layer, b.first, b.lines, b.hash));
    }
    s
}

fn read_blocks(name: &str) -> Option<Vec<Block>> {
    let text = std::fs::read_to_string(blocks_path(name)).ok()?;
    text.lines()
        .filter(|l| !l.starts_with('#'))
        .map(|l| {
            let f: Vec<&str> = l.split_whitespace().collect();
            Some(Block { layer: f.first()?.parse().ok()?, first: f.get(1)?.parse().ok()?, lines: f.get(2)?.parse().ok()?, hash: f.get(3)?.to_string() })
        })
        .collect()
}

fn gzip(text: &str) -> Vec<u8> {
    let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::best());
    e.write_all(text.as_bytes()).unwrap();
    e.finish().unwrap()
}

fn expected_whole(name: &str) -> Option<String> {
    let bytes = std::fs::read(whole_path(name)).ok()?;
    let mut s = String::new();
    flate2::read::GzDecoder::new(&bytes[..]).read_to_string(&mut s).ok()?;
    Some(s)
}

/// Lines `from..to` (0-based) of `text`, numbered from 1, each behind `mark`.
fn numbered(text: &str, from: usize, to: usize, mark: &str) -> String {
    text.lines().enumerate().skip(from).take(to.saturating_sub(from)).map(|(i, l)| format!("    {mark} {:>7} | {l}\n", i + 1)).collect()
}

/// Why `got` is not the recorded output of `name`: the first layer and lines that differ, the
/// new lines there and, where the expected output is kept whole, the expected ones beside.
fn explain(name: &str, got: &str) -> String {
    let Some(expected) = read_blocks(name) else {
        return format!("{name}: no block hashes recorded (tests/golden/gcode/{name}.blocks); WEFT_BLESS=1 records them\n");
    };
    let new = blocks(got);
    let at = expected.iter().zip(&new).position(|(a, b)| a != b).unwrap_or(expected.len().min(new.len()));
    let mut s = format!("{name}: {} blocks recorded, {} now", expected.len(), new.len());
    let (layer, first) = match (expected.get(at), new.get(at)) {
        (Some(e), _) => (e.layer, e.first),
        (None, Some(n)) => (n.layer, n.first),
        (None, None) => (0, 1),
    };
    let z = got.lines().skip(first.saturating_sub(1)).take(3).find_map(|l| l.strip_prefix(";Z:")).map(|z| format!(" (Z {z})")).unwrap_or_default();
    s.push_str(&format!("; the first that differs: layer {layer}{z}, from line {first}\n"));
    if let Some(whole) = expected_whole(name) {
        let (e, g): (Vec<&str>, Vec<&str>) = (whole.lines().collect(), got.lines().collect());
        let line = (first.saturating_sub(1)..e.len().max(g.len())).find(|&i| e.get(i) != g.get(i)).unwrap_or(first.saturating_sub(1));
        let from = line.saturating_sub(2);
        s.push_str(&format!("  line {} differs; expected (- ) and now (+ ):\n", line + 1));
        s.push_str(&numbered(&whole, from, line + SHOWN, "-"));
        s.push_str(&numbered(got, from, line + SHOWN, "+"));
    } else {
        let from = first.saturating_sub(1);
        s.push_str(&format!(
            "  now (+ ), lines {}–{} (the recorded block's hash is {}; the whole expected file is not kept, it is large):\n",
            from + 1,
            from + 2 * SHOWN,
            expected.get(at).map_or("none", |b| b.hash.as_str())
        ));
        s.push_str(&numbered(got, from, from + 2 * SHOWN, "+"));
    }
    s
}

#[test]
fn examples_give_the_recorded_gcode_at_any_thread_count() {
    let golden_path = root().join("tests/golden/gcode.sha256");
    let golden: BTreeMap<String, String> = std::fs::read_to_string(&golden_path)
        .unwrap()
        .lines()
        .filter_map(|l| l.split_once("  ").map(|(h, n)| (n.trim_end_matches(".gcode").to_string(), h.to_string())))
        .collect();
    let dir = std::env::temp_dir().join(format!("weft-golden-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let bless = std::env::var_os("WEFT_BLESS").is_some();
    let mut got = BTreeMap::new();
    let (mut differ, mut explained) = (Vec::new(), String::new());
    let (mut untrue, mut dusty) = (Vec::new(), Vec::new());
    for (name, example, sets) in CASES {
        let runs: Vec<weft::pipeline::RunOutput> = THREADS.iter().map(|&t| run_of(example, sets, t)).collect();
        let texts: Vec<String> = runs.iter().map(|r| String::clone(&r.gcode)).collect();
        // Examples tell the truth: each number of the description is the design's or the
        // run's own. And the writer leaves no dust.
        if sets.is_empty() {
            let wrong = untrue_numbers(example, &runs[0]);
            if !wrong.is_empty() {
                untrue.push(format!("{example}: {wrong:?}"));
            }
        }
        let short = dust(&texts[0], weft::gcode::MIN_MOVE_MM - 0.0015);
        if !short.is_empty() {
            dusty.push(format!("{name}: {} moves, first at line {} ({:.4} mm)", short.len(), short[0].0, short[0].1));
        }
        let hashes: Vec<String> = texts.iter().map(|t| hex(&Sha256::digest(t.as_bytes()))).collect();
        if hashes.iter().any(|h| h != &hashes[0]) {
            differ.push(format!("{name}: {}", THREADS.iter().zip(&hashes).map(|(t, h)| format!("{t} threads {}", &h[..12])).collect::<Vec<_>>().join(", ")));
        }
        if THROUGH_CLI.contains(name) {
            assert!(gcode_from_cli(example, sets, &dir) == texts[0], "{name}: the weft binary gives other bytes than the pipeline in this process");
        }
        if bless {
            std::fs::create_dir_all(root().join("tests/golden/gcode")).unwrap();
            std::fs::write(blocks_path(name), write_blocks(name, &texts[0])).unwrap();
            let gz = gzip(&texts[0]);
            if gz.len() <= KEEP_WHOLE_GZ_BYTES {
                std::fs::write(whole_path(name), gz).unwrap();
            } else {
                let _ = std::fs::remove_file(whole_path(name));
            }
        } else if golden.get(*name) != Some(&hashes[0]) {
            explained.push_str(&explain(name, &texts[0]));
        }
        got.insert(name.to_string(), hashes[0].clone());
    }
    let _ = std::fs::remove_dir_all(&dir);
    assert!(differ.is_empty(), "G-code depends on the thread count: {differ:?}");
    assert!(untrue.is_empty(), "descriptions state numbers that neither the design nor the run gives:\n{}", untrue.join("\n"));
    assert!(dusty.is_empty(), "extruding moves shorter than {} mm were written:\n{}", weft::gcode::MIN_MOVE_MM, dusty.join("\n"));
    if bless {
        let text: String = got.iter().map(|(n, h)| format!("{h}  {n}.gcode\n")).collect();
        std::fs::write(&golden_path, text).unwrap();
        return;
    }
    let changed: Vec<&String> = got.keys().filter(|n| golden.get(*n) != got.get(*n)).collect();
    assert!(changed.is_empty(), "G-code changed for {changed:?} (WEFT_BLESS=1 to record a deliberate change):\n{explained}");
    assert_eq!(golden.len(), CASES.len(), "every recorded case is still run");
}

#[test]
fn descriptions_and_dust_are_read() {
    // The readers behind the checks above, on made-up text: they can fail.
    let n = stated_numbers("The paper's Ω3 (Fig. 7a, equation 7): tilts up to 120°, a 1 620-beam tower, 0.148 mm layers, 50 % density.");
    let values: Vec<f64> = n.iter().map(|x| x.1).collect();
    assert_eq!(values, vec![120.0, 1620.0, 0.148, 50.0], "{n:?}");
    let g = "M83\nG1 X0 Y0\nG1 X10 Y0 E0.5\nG1 X10.004 Y0 E0.001\nG1 X20 Y0 E0.5\n";
    assert_eq!(dust(g, 0.0085).iter().map(|d| d.0).collect::<Vec<_>>(), vec![4]);
}

#[test]
fn a_changed_line_is_named_by_layer_and_shown() {
    // The explanation of a mismatch, on a recorded case with its whole text kept and on one
    // without: the layer, the line, and the lines themselves.
    let name = "honeycomb-10mm";
    let mut text = gcode_of(name, &[], 1);
    let line = text.lines().position(|l| l.starts_with(";LAYER_CHANGE")).unwrap() + 5;
    let old: String = text.lines().nth(line).unwrap().to_string();
    text = text.replacen(&format!("\n{old}\n"), "\nG1 X0 Y0 ; changed\n", 1);
    let e = explain(name, &text);
    assert!(e.contains("layer 1") && e.contains(&format!("line {} differs", line + 1)), "{e}");
    assert!(e.contains(&format!("- {:>7} | {old}", line + 1)) && e.contains(&format!("+ {:>7} | G1 X0 Y0 ; changed", line + 1)), "{e}");
    let name = "graded-phantom";
    assert!(!whole_path(name).exists(), "a large output is kept as block hashes only");
    let mut text = gcode_of(name, &[], 2);
    let third = text.match_indices(";LAYER_CHANGE\n").nth(2).unwrap().0;
    text.insert_str(third + ";LAYER_CHANGE\n".len(), "M117 changed\n");
    let e = explain(name, &text);
    assert!(e.contains("layer 3") && e.contains("M117 changed"), "{e}");
}

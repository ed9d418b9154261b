//! Parallel loops (`weft::par`, issue 15): the same results in the same order at any thread
//! count, progress that reaches the end, a panic that comes back instead of a hang; and a
//! generated 1M-triangle sphere sliced to the same G-code bytes at 1, 2 and 4 threads (the
//! examples are checked so by the golden test, through `weft run --threads`).

use rayon::ThreadPoolBuilder;
use weft::design::{Design, Input};
use weft::pipeline::{self, Files, RunOptions};

fn pool(n: usize) -> rayon::ThreadPool {
    ThreadPoolBuilder::new().num_threads(n).build().unwrap()
}

#[test]
fn loops_give_the_sequential_result_at_any_thread_count() {
    // Items of very different cost, so runs finish out of order.
    let work = |i: usize| -> u64 { (0..(i % 7) * 2000).fold(i as u64, |a, k| a.wrapping_mul(6364136223846793005).wrapping_add(k as u64)) };
    let expected: Vec<u64> = (0..1000).map(work).collect();
    for threads in [1, 2, 4, 8] {
        let (got, last, runs_got) = pool(threads).install(|| {
            let mut last = 0;
            let got = weft::par::map(1000, &mut |d| last = d, work);
            let runs_got = weft::par::map_runs(1000, 13, &mut |_| {}, |r, tick| {
                r.map(|i| {
                    tick();
                    work(i)
                })
                .collect()
            });
            (got, last, runs_got)
        });
        assert_eq!(got, expected, "{threads} threads");
        assert_eq!(runs_got, expected, "{threads} threads, in runs");
        assert_eq!(last, 1000, "{threads} threads: progress reaches every item");
    }
    assert!(weft::par::map(0, &mut |_| {}, work).is_empty());
}

#[test]
fn an_ordered_pipeline_consumes_every_item_in_order_and_stops_on_an_error() {
    // Items of very different cost, so they are made out of order.
    let work = |i: usize| -> u64 { (0..(i % 7) * 3000).fold(i as u64, |a, k| a.wrapping_mul(6364136223846793005).wrapping_add(k as u64)) };
    let expected: Vec<(usize, u64)> = (0..500).map(|i| (i, work(i))).collect();
    for threads in [1, 2, 4, 8] {
        for ahead in [1, 3, 32] {
            let mut got = Vec::new();
            let r: Result<(), ()> = pool(threads).install(|| {
                weft::par::ordered(500, ahead, work, |k, v| {
                    got.push((k, v));
                    Ok(())
                })
            });
            assert!(r.is_ok());
            assert_eq!(got, expected, "{threads} threads, {ahead} ahead");
            // An error stops it there: nothing after the failing item is consumed.
            let mut seen = 0;
            let r = pool(threads).install(|| {
                weft::par::ordered(500, ahead, work, |k, _| {
                    if k == 123 {
                        Err(k)
                    } else {
                        seen += 1;
                        Ok(())
                    }
                })
            });
            assert_eq!((r, seen), (Err(123), 123), "{threads} threads, {ahead} ahead");
        }
        let r = std::panic::catch_unwind(|| {
            pool(threads).install(|| weft::par::ordered(100, 4, |i| if i == 57 { panic!("item 57") } else { i }, |_, _| Ok::<(), ()>(())))
        });
        assert!(r.is_err(), "{threads} threads: the panic comes back");
    }
    // From a thread outside any pool (the CLI's main thread), on the global pool.
    let mut got = Vec::new();
    weft::par::ordered(500, 4, work, |k, v| {
        got.push((k, v));
        Ok::<(), ()>(())
    })
    .unwrap();
    assert_eq!(got, expected, "outside a pool");
}

#[test]
fn a_panicking_item_comes_back_as_a_panic_not_a_hang() {
    for threads in [1, 3] {
        let r = std::panic::catch_unwind(|| pool(threads).install(|| weft::par::map(100, &mut |_| {}, |i| if i == 57 { panic!("item 57") } else { i })));
        assert!(r.is_err(), "{threads} threads");
    }
}

/// A sphere of several of the importer's chunks of triangles and vertices (300 000 triangles:
/// 4.6 chunks of 65 536 triangles, 2.3 of vertices, so the parallel passes split it and meet
/// at chunk boundaries) and of more layers than threads, sliced at 1, 2 and 4 threads. (It was
/// a million triangles; this size exercises the same splits.)
#[test]
fn a_sphere_of_several_import_chunks_slices_to_the_same_bytes_at_one_two_and_four_threads() {
    let stl = weft::testgen::mesh::binary_stl_sphere(300_000);
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/examples/cube-20mm.json")).unwrap();
    let design = Design::from_json("cube-20mm", &text)
        .unwrap()
        .with_slot_input(&weft::kinds::Registry::builtin(), "mesh", Input::File { name: "sphere.stl".into(), embedded: None })
        .unwrap();
    let mut outputs = Vec::new();
    for threads in [1, 2, 4] {
        let out = pool(threads)
            .install(|| {
                // Files stay on the thread that made them (a browser's may be a blob).
                let mut files = Files::new();
                files.insert("sphere.stl".into(), stl.clone());
                pipeline::run(&design, &files, &RunOptions::default(), &mut |_, _| {})
            })
            .unwrap();
        assert_eq!(out.report.threads, threads);
        assert!(out.report.timings.iter().any(|t| t.stage == "slice" && t.ms > 0.0), "the slice stage's time is reported");
        outputs.push(out);
    }
    let layers = outputs[0].report.analysis.layers;
    assert!(layers > 100, "{layers} layers");
    for (k, o) in outputs.iter().enumerate().skip(1) {
        assert!(o.gcode == outputs[0].gcode, "{} threads: the G-code differs from 1 thread's", [1, 2, 4][k]);
    }
}

/// The analyzer's report, preview and errors at 1, 2 and 4 threads, on files over the size it
/// reads on the pool (blocks lexed ahead, layers measured behind: `src/analyze/pooled.rs`).
#[test]
fn the_analysis_and_its_errors_are_the_same_at_any_thread_count() {
    use weft::analyze::{analyze, Options};
    let fixture = |name: &str| std::fs::read(format!("{}/tests/fixtures/{name}", env!("CARGO_MANIFEST_DIR"))).unwrap();
    let mut files: Vec<(String, Vec<u8>)> = Vec::new();
    // Other slicers' files (arcs, CRLF, layer comments), repeated past a few blocks.
    for name in ["prusaslicer-style.gcode", "cura-style.gcode"] {
        let one = String::from_utf8(fixture(name)).unwrap();
        files.push((name.into(), weft::bench::repeat_to(&one, 3_000_000).into_bytes()));
    }
    // Layers of every size: tiny ones and ones over the pool's per-layer limit (measured on the
    // reading thread), some overlapping themselves; no layer comments (Z starts layers).
    let mut z_layers = String::from("G21\nG90\nM83\n");
    for layer in 0..120 {
        let n = [3, 40, 70, 900, 70_000][layer % 5];
        z_layers.push_str(&format!("G1 Z{:.2} F600\n", 0.2 * (layer + 1) as f64));
        for k in 0..n {
            let x = (k % 200) as f64 * 0.3;
            let y = (k / 200) as f64 * 0.4 + if layer % 3 == 0 { 0.0 } else { 0.1 };
            z_layers.push_str(&format!("G1 X{x:.3} Y{y:.3} E0.02\n"));
        }
        z_layers.push_str("G1 E-0.8\nG0 X0 Y0\nG1 E0.8\n");
    }
    files.push(("z-layers.gcode".into(), z_layers.into_bytes()));
    // A bad number far into the file: the same line at any thread count.
    let mut bad = weft::bench::repeat_to(&String::from_utf8(fixture("prusaslicer-style.gcode")).unwrap(), 2_500_000);
    let bad_line = bad.lines().count() + 1;
    bad.push_str("G1 X1e5 Y2\n");
    bad.push_str(&weft::bench::repeat_to("G1 X1 Y1 E1\n", 600_000));
    files.push(("bad-number.gcode".into(), bad.into_bytes()));
    // A layer over the analyzer's limit, then a bad number in a later block: the earlier
    // refusal wins, as when the file is read on one thread.
    let mut huge = String::from("M83\n;LAYER:0\nG1 X0 Y0 E1\n");
    for k in 0..(weft::analyze::MAX_LAYER_SEGMENTS + 10) {
        huge.push_str(if k % 2 == 0 { "X1E1\n" } else { "X0E1\n" });
    }
    huge.push_str("G1 X1e5\n");
    files.push(("huge-layer.gcode".into(), huge.into_bytes()));

    for (name, bytes) in &files {
        assert!(bytes.len() > 1 << 20, "{name}: {} bytes is over the size read on the pool", bytes.len());
        for preview in [false, true] {
            let options = Options { collect_preview: preview, ..Default::default() };
            let runs: Vec<_> = [1, 2, 4].iter().map(|&t| pool(t).install(|| analyze(name, bytes, &options))).collect();
            for (k, r) in runs.iter().enumerate().skip(1) {
                match (&runs[0], r) {
                    (Ok(a), Ok(b)) => {
                        assert!(a.report == b.report, "{name}: the report differs at {} threads", [1, 2, 4][k]);
                        assert!(a.preview == b.preview, "{name}: the preview differs at {} threads", [1, 2, 4][k]);
                    }
                    (a, b) => assert_eq!(a.as_ref().err(), b.as_ref().err(), "{name}: {} threads", [1, 2, 4][k]),
                }
            }
            match (name.as_str(), &runs[0]) {
                ("bad-number.gcode", Err(weft::analyze::Error::Malformed { line, .. })) => assert_eq!(*line, bad_line),
                ("huge-layer.gcode", Err(weft::analyze::Error::TooLarge { line, .. })) => assert!(*line > 1 << 20, "line {line}"),
                (_, Ok(a)) => assert!(a.report.layers > 0 && a.report.overlap_mm >= 0.0, "{name}"),
                (_, r) => panic!("{name}: {:?}", r.as_ref().err()),
            }
        }
    }
}

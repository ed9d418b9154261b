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
fn a_panicking_item_comes_back_as_a_panic_not_a_hang() {
    for threads in [1, 3] {
        let r = std::panic::catch_unwind(|| pool(threads).install(|| weft::par::map(100, &mut |_| {}, |i| if i == 57 { panic!("item 57") } else { i })));
        assert!(r.is_err(), "{threads} threads");
    }
}

#[test]
fn a_one_million_triangle_sphere_slices_to_the_same_bytes_at_one_two_and_four_threads() {
    let stl = weft::testgen::mesh::binary_stl_sphere(1_000_000);
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/examples/cube-20mm.json")).unwrap();
    let design = Design::from_json("cube-20mm", &text).unwrap().with_slot_input(&weft::jobs::Registry::builtin(), "mesh", Input::File { name: "sphere.stl".into(), embedded: None }).unwrap();
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

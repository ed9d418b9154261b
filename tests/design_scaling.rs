//! Growth of the cost of hostile design inputs: the start/end template expander, long names,
//! deep `--set` paths and share-link bombs. Each case times n and 4n (the thread's CPU time,
//! best of 3, repeated so the small size takes at least 20 ms) and checks the ratio against linear growth, 4^1.2,
//! times a generous noise factor. A quadratic cost gives about 16.

use weft::design::{share, Design};
use weft::gcode::{expand_template, MAX_TEMPLATE_BYTES};
use weft::testgen::design as gen;

/// Linear growth with room for n·log n and noise.
const LIMIT: f64 = 2.0 * 5.278_031_643_091_577; // 2 × 4^1.2

/// Best of 3 times of `reps` runs of `work` on `input`, seconds (one thread's CPU time:
/// `weft::bench::best_of_3_one_thread_seconds`).
fn best_of_3<T: Sync>(input: &T, reps: usize, work: &(dyn Fn(&T) + Sync)) -> f64 {
    weft::bench::best_of_3_one_thread_seconds(&|| (0..reps).for_each(|_| work(input)))
}

/// One measurement at a time: the tests of this file run in parallel threads, and two
/// measurements at once would share the caches.
static ONE_AT_A_TIME: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// time(4n) / time(n) of `work` on `make(n)`, with as many repetitions as make the small
/// size take 20 ms. Sizes are chosen so both sizes stay on the same side of the allocator's
/// and caches' thresholds (glibc maps blocks over 128 KiB afresh, page faults included): the
/// ratio is then the algorithm's growth, not a change of memory regime between n and 4n.
fn ratio<T: Sync>(what: &str, n: usize, make: &dyn Fn(usize) -> T, work: &(dyn Fn(&T) + Sync)) -> f64 {
    let (small, large) = (make(n), make(4 * n));
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let mut reps = 1;
    let mut t1 = best_of_3(&small, reps, work);
    while t1 < 0.02 {
        reps *= 2;
        t1 = best_of_3(&small, reps, work);
    }
    let t4 = best_of_3(&large, reps, work);
    let r = t4 / t1;
    eprintln!("{what}: n = {n}: {:.1} ms, 4n: {:.1} ms ({reps} runs), ratio {r:.2}, exponent {:.2}", t1 * 1e3, t4 * 1e3, r.ln() / 4f64.ln());
    r
}

fn vars(name_len: usize) -> Vec<(&'static str, String)> {
    vec![("bed_temp_c", "60".into()), ("design_name", "n".repeat(name_len))]
}

#[test]
fn unclosed_braces_expand_in_linear_time() {
    let v = vars(20);
    let n = MAX_TEMPLATE_BYTES / 4;
    let r = ratio("unclosed braces", n, &gen::unclosed_braces_template, &|t: &String| {
        let out = expand_template(t, "start_gcode", &v).unwrap();
        assert_eq!(out.len(), t.len());
    });
    assert!(r < LIMIT, "template of unclosed braces: time(4n)/time(n) = {r:.1}, over {LIMIT:.1}: the expander is not linear");
}

#[test]
fn placeholders_expand_in_linear_time() {
    let v = vars(256);
    let r = ratio("template bomb", 1000, &gen::template_bomb, &|t: &String| {
        assert!(expand_template(t, "start_gcode", &v).unwrap().len() >= 256_000);
    });
    assert!(r < LIMIT, "placeholders: time(4n)/time(n) = {r:.1}, over {LIMIT:.1}");
}

#[test]
fn long_names_are_refused_in_linear_time() {
    let r = ratio("long name", 1 << 14, &gen::long_name_design, &|t: &String| {
        assert!(Design::from_json("d", t).is_err());
    });
    assert!(r < LIMIT, "long design name: time(4n)/time(n) = {r:.1}, over {LIMIT:.1}");
}

#[test]
fn deep_set_paths_are_refused_in_linear_time() {
    let d = Design::default();
    let r = ratio("deep --set path", 1 << 16, &|n| vec![gen::deep_set_path(n)], &|set: &Vec<String>| {
        assert!(d.with_overrides(set).is_err());
    });
    assert!(r < LIMIT, "deep --set path: time(4n)/time(n) = {r:.1}, over {LIMIT:.1}");
}

#[test]
fn share_bombs_are_refused_in_linear_time() {
    // 250 characters inflate to about 27 kB, 1 000 to about 110 kB: the design is read and
    // refused for its name.
    let r = ratio("share bomb", 250, &gen::share_bomb_fragment, &|f: &String| {
        let e = share::decode(f).unwrap_err().to_string();
        assert!(e.contains("name"), "{}", &e[..e.len().min(200)]);
    });
    assert!(r < LIMIT, "share-link bomb: time(4n)/time(n) = {r:.1}, over {LIMIT:.1}");
    // Past the limit the inflater stops at it.
    let e = share::decode(&gen::share_bomb_fragment(100_000)).unwrap_err().to_string();
    assert!(e.contains(&format!("more than {} bytes", weft::design::MAX_DESIGN_BYTES)), "{e}");
}

//! Growth of the cost of hostile design inputs: the start/end template expander, long names,
//! deep `--set` paths and share-link bombs. Each case counts the work at n and 4n (bytes
//! scanned, allocations, bytes allocated, peak heap: `crate::work`, the same on any machine)
//! and checks it against linear growth; a quadratic cost gives about 16.

use crate::work::{assert_linear, work};
use weft::catalog::share;
use weft::design::Design;
use weft::gcode::{expand_template, MAX_TEMPLATE_BYTES};
use weft::testgen::design as gen;

/// Checks that the work of `work` on `make(4n)` is within linear growth of its work on
/// `make(n)` (bytes scanned where the code counts them, allocations, bytes allocated, peak
/// heap: [`crate::work`]).
fn check_linear<T: Sync>(what: &str, n: usize, make: &dyn Fn(usize) -> T, run: &(dyn Fn(&T) + Sync)) {
    let (small, large) = (make(n), make(4 * n));
    assert_linear(what, 4.0, work(|| run(&small)), work(|| run(&large)));
}

fn vars(name_len: usize) -> Vec<(&'static str, String)> {
    vec![("bed_temp_c", "60".into()), ("design_name", "n".repeat(name_len))]
}

#[test]
fn unclosed_braces_expand_in_linear_time() {
    let v = vars(20);
    let n = MAX_TEMPLATE_BYTES / 4;
    check_linear("unclosed braces", n, &gen::unclosed_braces_template, &|t: &String| {
        let out = expand_template(t, "start_gcode", &v).unwrap();
        assert_eq!(out.len(), t.len());
    });
}

#[test]
fn placeholders_expand_in_linear_time() {
    let v = vars(256);
    check_linear("template bomb", 1000, &gen::template_bomb, &|t: &String| {
        assert!(expand_template(t, "start_gcode", &v).unwrap().len() >= 256_000);
    });
}

#[test]
fn long_names_are_refused_in_linear_time() {
    check_linear("long name", 1 << 14, &gen::long_name_design, &|t: &String| {
        assert!(Design::from_json("d", t).is_err());
    });
}

#[test]
fn deep_set_paths_are_refused_in_linear_time() {
    let d = Design::default();
    check_linear("deep --set path", 1 << 16, &|n| vec![gen::deep_set_path(n)], &|set: &Vec<String>| {
        assert!(d.with_overrides(set).is_err());
    });
}

#[test]
fn share_bombs_are_refused_in_linear_time() {
    // 250 characters inflate to about 27 kB, 1 000 to about 110 kB: the design is read and
    // refused for its name.
    check_linear("share bomb", 250, &gen::share_bomb_fragment, &|f: &String| {
        let e = share::decode(f).unwrap_err().to_string();
        assert!(e.contains("name"), "{}", &e[..e.len().min(200)]);
    });
    // Past the limit the inflater stops at it.
    let e = share::decode(&gen::share_bomb_fragment(100_000)).unwrap_err().to_string();
    assert!(e.contains(&format!("more than {} bytes", weft::design::MAX_DESIGN_BYTES)), "{e}");
}

//! `weft export-stl` must not make struts touch that the lattice does not join: on
//! honeycomb-10mm no two boxes of struts sharing no node intersect or touch.

use weft::design::Design;
use weft::export::{convex_touch, lattice_stl, strut_boxes};
use weft::pipeline::Files;

fn check(name: &str, json: &str) -> usize {
    let design = Design::from_json("test.json", json).unwrap();
    let w = design.printer.nozzle_diameter_mm;
    let layers = weft::jobs::lattice::lattice_strokes(&design, &Files::new()).unwrap();
    let mut pairs = 0;
    for layer in &layers {
        let g = weft::paths::build_graph(layer, 0.005);
        let boxes = strut_boxes(&g, w);
        for (i, (ei, a)) in boxes.iter().enumerate() {
            for (ej, b) in &boxes[i + 1..] {
                let (x, y) = (&g.edges[*ei], &g.edges[*ej]);
                let share = ei == ej || x.a == y.a || x.a == y.b || x.b == y.a || x.b == y.b;
                if share {
                    continue;
                }
                pairs += 1;
                assert!(!convex_touch(a, b, 1e-6), "{name}: struts {ei} and {ej} share no node but their boxes touch: {a:?} {b:?}");
            }
        }
    }
    let stl = lattice_stl(&design).unwrap();
    assert_eq!(stl.triangles, 12 * layers.iter().map(|l| strut_boxes(&weft::paths::build_graph(l, 0.005), w).len()).sum::<usize>());
    pairs
}

#[test]
fn unconnected_struts_do_not_touch_in_the_stl() {
    assert!(check("honeycomb-10mm", include_str!("../examples/honeycomb-10mm.json")) > 1000);
}

#[test]
fn unconnected_curved_struts_do_not_touch_in_the_stl() {
    let mut v: serde_json::Value = serde_json::from_str(include_str!("../examples/honeycomb-10mm.json")).unwrap();
    v["job"]["lattice"]["pattern"] = serde_json::json!({"kind": "wavy_honeycomb", "hexagon_radius_mm": 0.92});
    check("wavy honeycomb", &v.to_string());
}

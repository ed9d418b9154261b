//! Issue 9: path order and the per-layer travel / retraction numbers, on the shipped lattice
//! examples. `min_travel` never travels more than the circuit order on any layer; the report's
//! retractions are the G-code's, layer by layer.

use crate::common;

use weft::design::Job;
use weft::kinds::lattice::{lattice_strokes, LatticeJob};
use weft::paths::{optimise, Method, Options, Order, PathsReport};
use weft::pipeline::{self, Files, RunOptions};
use weft::Design;

fn example(name: &str) -> Design {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples").join(format!("{name}.json"));
    Design::from_json(name, &std::fs::read_to_string(path).unwrap()).unwrap()
}

use common::PLANAR_LATTICES as PLANAR;

#[test]
fn min_travel_never_travels_more_than_the_circuit_order() {
    for name in PLANAR {
        let d = example(name);
        let strokes = lattice_strokes(&d, &Files::new()).unwrap();
        for method in [Method::Euler, Method::Continuous, Method::GippoMax] {
            let run = |order| {
                let o = Options { method, order, iterations: 5, ..Options::default() };
                optimise(&strokes, &o, 0.4, 1, &mut |_| {}).unwrap().report
            };
            // The circuit order's own travel is what the report calls circuit travel.
            for (li, l) in run(Order::Circuit).layers.iter().enumerate() {
                assert!((l.travel_mm - l.circuit_travel_mm).abs() < 1e-6, "{name} {method:?} layer {li}: {} vs {}", l.travel_mm, l.circuit_travel_mm);
            }
            let min = run(Order::MinTravel);
            for (li, l) in min.layers.iter().enumerate() {
                assert!(
                    l.travel_mm <= l.circuit_travel_mm + 1e-6,
                    "{name} {method:?} layer {li}: min_travel {} > circuit {}",
                    l.travel_mm,
                    l.circuit_travel_mm
                );
            }
            // Every order prints the same paths.
            for order in [Order::LongestFirst, Order::Direction, Order::CentreOut] {
                let r = run(order);
                for (a, b) in r.layers.iter().zip(&min.layers) {
                    assert_eq!(a.paths, b.paths, "{name} {method:?} {order:?}");
                }
            }
        }
    }
}

/// Retractions per `;LAYER_CHANGE` section of Marlin G-code with absolute E: `G1 E…` lines
/// without a move that lower E. The final retraction (after the last path) is dropped.
fn gcode_retractions(gcode: &str) -> Vec<usize> {
    let mut per = Vec::new();
    let mut e = 0.0f64;
    let mut last: Option<usize> = None;
    for line in gcode.lines() {
        if line.starts_with(";LAYER_CHANGE") {
            per.push(0);
            continue;
        }
        let code = line.split(';').next().unwrap();
        let mut words = code.split_whitespace();
        if words.next() != Some("G1") && !code.starts_with("G0") {
            continue;
        }
        let mut moved = false;
        let mut new_e = None;
        for w in code.split_whitespace().skip(1) {
            match w.as_bytes()[0] {
                b'X' | b'Y' | b'Z' => moved = true,
                b'E' => new_e = Some(w[1..].parse::<f64>().unwrap()),
                _ => {}
            }
        }
        if let Some(v) = new_e {
            if !moved && v < e - 1e-9 && !per.is_empty() {
                *per.last_mut().unwrap() += 1;
                last = Some(per.len() - 1);
            }
            e = v;
        }
    }
    // The epilogue's retraction.
    if let Some(k) = last {
        per[k] -= 1;
    }
    per
}

#[test]
fn reported_retractions_are_the_gcodes() {
    for name in ["honeycomb-10mm", "voronoi-10mm", "ball-burst-disc-48mm", "tensile-honeycomb"] {
        for (method, order) in [(Method::GippoMax, Order::LongestFirst), (Method::Euler, Order::MinTravel), (Method::Continuous, Order::MinTravel)] {
            let mut d = example(name);
            let mut j: LatticeJob = d.job.settings().unwrap();
            j.paths.method = method;
            j.paths.order = order;
            j.paths.iterations = 20;
            d.job = Job::new("lattice", &j);
            let out = pipeline::run(&d, &Files::new(), &RunOptions::default(), &mut |_, _| {}).unwrap();
            let report = out.report.stage::<PathsReport>("paths").unwrap();
            let reported: Vec<usize> = report.layers.iter().map(|l| l.retractions).collect();
            assert_eq!(reported, gcode_retractions(&out.gcode), "{name} {method:?} {order:?}");
        }
    }
}

/// `direction` prints paths in order along the chosen direction, each from its end lower along
/// it; `centre_out` from the layer's centre outwards, each from its end nearer the centre.
/// Read back from the optimised toolpath (euler and gippo_max: one printed path per chain).
#[test]
fn directional_orders_sweep_as_asked() {
    for name in ["voronoi-10mm", "ball-burst-disc-48mm"] {
        let d = example(name);
        let strokes = lattice_strokes(&d, &Files::new()).unwrap();
        for method in [Method::Euler, Method::GippoMax] {
            for deg in [0.0, 30.0, 135.0, -90.0] {
                let o = Options { method, order: Order::Direction, direction_deg: deg, iterations: 5, ..Options::default() };
                let t = optimise(&strokes, &o, 0.4, 1, &mut |_| {}).unwrap().toolpath;
                let a = f64::to_radians(deg);
                let key = |p: &weft::geom::DVec3| p.x * a.cos() + p.y * a.sin();
                for pass in &t.passes {
                    let starts: Vec<f64> = pass.paths.iter().map(|p| key(&p.points[0])).collect();
                    assert!(starts.windows(2).all(|w| w[0] <= w[1] + 1e-9), "{name} {method:?} {deg}°: starts not swept in order");
                    for p in &pass.paths {
                        assert!(key(&p.points[0]) <= key(p.points.last().unwrap()) + 1e-9, "{name} {method:?} {deg}°: a path printed against the direction");
                    }
                }
            }
            let o = Options { method, order: Order::CentreOut, iterations: 5, ..Options::default() };
            let t = optimise(&strokes, &o, 0.4, 1, &mut |_| {}).unwrap().toolpath;
            for pass in &t.passes {
                let (mut lo, mut hi) = (weft::geom::DVec3::splat(f64::INFINITY), weft::geom::DVec3::splat(f64::NEG_INFINITY));
                for p in &pass.paths {
                    for q in [p.points[0], *p.points.last().unwrap()] {
                        lo = lo.min(q);
                        hi = hi.max(q);
                    }
                }
                let c = ((lo + hi) * 0.5).truncate();
                let r = |p: &weft::geom::DVec3| p.truncate().distance(c);
                let starts: Vec<f64> = pass.paths.iter().map(|p| r(&p.points[0])).collect();
                assert!(starts.windows(2).all(|w| w[0] <= w[1] + 1e-9), "{name} {method:?}: centre_out starts not outwards");
                for p in &pass.paths {
                    assert!(r(&p.points[0]) <= r(p.points.last().unwrap()) + 1e-9, "{name} {method:?}: a path printed inwards");
                }
            }
        }
    }
}

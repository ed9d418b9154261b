//! Issue 9: curved (wavy) struts — one graph edge per strut, printed once as its sampled sine
//! — and the die swell ratio (predicted width, optional E compensation).

use std::collections::BTreeMap;
use weft::design::Design;
use weft::geom::{DVec2, Feature};
use weft::lattice::{self, Domain, Options, Pattern};
use weft::pipeline::{self, Files, RunOptions};

/// An XY point in whole µm.
type MicronXy = (i64, i64);

const LW: f64 = 0.2;

fn strokes(p: Pattern) -> weft::geom::StrokeLayer {
    let options = Options { pattern: p, ..Options::default() };
    let d = lattice::planar_domains(&Domain::Rectangle { width_mm: 10.0, height_mm: 10.0 }, &options).unwrap();
    lattice::generate(&d, &options, LW, 1, &mut |_| {}).unwrap().layers.remove(0)
}

fn wavy_hc(r: f64, a: f64, n: u32) -> Pattern {
    Pattern::WavyHoneycomb { hexagon_radius_mm: r, amplitude_mm: a, samples_per_strut: n }
}

fn wavy_sq(c: f64, a: f64, n: u32) -> Pattern {
    Pattern::WavySquareGrid { cell_size_mm: c, amplitude_mm: a, samples_per_strut: n }
}

#[test]
fn curved_patterns_have_the_straight_graph() {
    for (wavy, straight) in [
        (wavy_hc(1.0, 0.15, 12), Pattern::Honeycomb { hexagon_radius_mm: 1.0 }),
        (wavy_hc(0.92, 0.2, 16), Pattern::Honeycomb { hexagon_radius_mm: 0.92 }),
        (wavy_sq(1.0, 0.15, 12), Pattern::SquareGrid { cell_size_mm: 1.0 }),
        (wavy_sq(1.3, 0.3, 8), Pattern::SquareGrid { cell_size_mm: 1.3 }),
    ] {
        let (w, s) = (strokes(wavy.clone()), strokes(straight));
        assert!(w.strokes.iter().all(|s| s.curved && s.feature == Feature::Lattice));
        let (gw, gs) = (weft::paths::build_graph(&w, 0.005), weft::paths::build_graph(&s, 0.005));
        // One edge per curved strut piece.
        assert_eq!(gw.edges.len(), w.strokes.len(), "{wavy:?}: one edge per curved strut");
        // Away from the domain's edge (where a wave may leave and re-enter the square, or
        // stay in where the chord leaves) the graphs are the same: the same edges between the
        // same nodes, each curved one longer.
        let inner = |g: &weft::paths::Graph| {
            let mut v: Vec<(MicronXy, MicronXy, f64)> = g
                .edges
                .iter()
                .filter(|e| [e.a, e.b].iter().all(|&n| g.nodes[n].abs().max_element() < 3.5))
                .map(|e| {
                    let k = |p: DVec2| ((p.x * 1000.0).round() as i64, (p.y * 1000.0).round() as i64);
                    let (a, b) = (k(g.nodes[e.a]), k(g.nodes[e.b]));
                    (a.min(b), a.max(b), e.length)
                })
                .collect();
            v.sort_by_key(|x| (x.0, x.1));
            v
        };
        let (iw, is) = (inner(&gw), inner(&gs));
        assert!(is.len() > 30, "{}", is.len());
        assert_eq!(iw.len(), is.len(), "{wavy:?}");
        for (x, y) in iw.iter().zip(&is) {
            assert_eq!((x.0, x.1), (y.0, y.1), "{wavy:?}");
            assert!(x.2 > y.2 * 1.03, "{wavy:?}: a curved strut is longer than its chord");
        }
        // Interior degrees (hence odd nodes and the lower bound away from the edge) agree.
        let deg =
            |g: &weft::paths::Graph| -> Vec<usize> { (0..g.nodes.len()).filter(|&n| g.nodes[n].abs().max_element() < 3.5).map(|n| g.degree(n)).collect() };
        assert_eq!(deg(&gw).len(), deg(&gs).len());
        assert!(gw.total_length() > gs.total_length() * 1.03, "{wavy:?}: curved struts are longer");
    }
}

/// Every bend of an uncut strut lies on a + t·d + A·sin(2πt)·n within the µm rounding.
#[test]
fn path_points_follow_the_sine() {
    for (p, a, n) in [(wavy_hc(1.0, 0.15, 12), 0.15, 12), (wavy_sq(1.0, 0.2, 10), 0.2, 10)] {
        let l = strokes(p);
        let g = weft::paths::build_graph(&l, 0.005);
        let mut checked = 0;
        for e in 0..g.edges.len() {
            let pts = g.edge_points(e);
            if pts.len() != n + 1 {
                continue; // cut by the domain's edge
            }
            let (p0, p1) = (pts[0], pts[n]);
            let d = p1 - p0;
            let nrm = DVec2::new(-d.y, d.x) / d.length();
            for (i, q) in pts.iter().enumerate() {
                let t = i as f64 / n as f64;
                let want = p0 + d * t + nrm * (a * (2.0 * std::f64::consts::PI * t).sin());
                assert!(q.distance(want) < 2e-3, "edge {e} point {i}: {q} vs {want}");
            }
            checked += 1;
        }
        assert!(checked > 50, "{checked}");
    }
}

fn design(pattern: serde_json::Value, edit: impl FnOnce(&mut serde_json::Value)) -> Design {
    let mut v: serde_json::Value = serde_json::from_str(include_str!("../../examples/honeycomb-10mm.json")).unwrap();
    v["job"]["lattice"]["pattern"] = pattern;
    edit(&mut v);
    Design::from_json("test.json", &v.to_string()).unwrap()
}

/// Extruded XY segments of a G-code (µm keys, unordered ends), with their counts.
fn extruded_segments(gcode: &str, offset: DVec2) -> BTreeMap<(MicronXy, MicronXy), usize> {
    let (mut x, mut y, mut e) = (0.0f64, 0.0f64, 0.0f64);
    let mut out = BTreeMap::new();
    for line in gcode.lines() {
        let line = line.split(';').next().unwrap().trim();
        if !(line.starts_with("G1 ") || line.starts_with("G0 ")) {
            if line.starts_with("G92") {
                e = 0.0;
            }
            continue;
        }
        let (mut nx, mut ny, mut ne) = (x, y, e);
        for w in line.split_whitespace().skip(1) {
            let v: f64 = w[1..].parse().unwrap_or(0.0);
            match &w[..1] {
                "X" => nx = v,
                "Y" => ny = v,
                "E" => ne = v,
                _ => {}
            }
        }
        if ne > e && (nx, ny) != (x, y) {
            let k = |a: f64, b: f64, o: DVec2| (((a - o.x) * 1000.0).round() as i64, ((b - o.y) * 1000.0).round() as i64);
            let (p, q) = (k(x, y, offset), k(nx, ny, offset));
            *out.entry((p.min(q), p.max(q))).or_insert(0) += 1;
        }
        (x, y, e) = (nx, ny, ne);
    }
    out
}

#[test]
fn every_curved_strut_is_printed_exactly_once() {
    for (pattern, method) in
        [(serde_json::json!({"kind": "wavy_honeycomb", "hexagon_radius_mm": 0.92}), "gippo_max"), (serde_json::json!({"kind": "wavy_square_grid"}), "euler")]
    {
        let d = design(pattern.clone(), |v| v["job"]["paths"]["method"] = serde_json::json!(method));
        let out = pipeline::run(&d, &Files::new(), &RunOptions::default(), &mut |_, _| {}).unwrap();
        let layer = weft::kinds::lattice::lattice_strokes(&d, &Files::new()).unwrap().remove(0);
        let g = weft::paths::build_graph(&layer, 0.005);
        // The bed centre (corner origin, 220 × 220) is the lattice's origin.
        let printed = extruded_segments(&out.gcode, DVec2::new(110.0, 110.0));
        let key = |p: DVec2| ((p.x * 1000.0).round() as i64, (p.y * 1000.0).round() as i64);
        let mut expected = 0;
        for e in 0..g.edges.len() {
            for w in g.edge_points(e).windows(2) {
                let (p, q) = (key(w[0]), key(w[1]));
                assert_eq!(printed.get(&(p.min(q), p.max(q))), Some(&1), "{pattern}: edge {e} segment {w:?}");
                expected += 1;
            }
        }
        assert_eq!(printed.values().sum::<usize>(), expected, "{pattern}: nothing else is printed");
        let a = &out.report.analysis;
        assert_eq!(a.overlap_mm, 0.0, "{pattern}");
        assert!((a.extruded_mm - g.total_length()).abs() < 1e-3 * g.total_length(), "{pattern}: {} vs {}", a.extruded_mm, g.total_length());
        // Paths never fewer than the proven minimum of the one-edge-per-strut graph.
        assert!(a.extrusion_paths >= g.lower_bound_paths());
        assert!(g.edges.len() < printed.len() / 4, "{pattern}: struts are single edges");
    }
}

#[test]
fn curved_patterns_are_in_the_atlas_with_defaults_and_thumbnails() {
    let p: Pattern = serde_json::from_str(r#"{"kind":"wavy_honeycomb"}"#).unwrap();
    assert_eq!(p, wavy_hc(1.0, lattice::DEFAULT_WAVE_AMPLITUDE_MM, lattice::DEFAULT_SAMPLES_PER_STRUT));
    let p: Pattern = serde_json::from_str(r#"{"kind":"wavy_square_grid"}"#).unwrap();
    assert_eq!(p, wavy_sq(1.0, 0.15, 12));
    assert!(lattice::PATTERNS.contains(&"wavy_honeycomb") && lattice::PATTERNS.contains(&"wavy_square_grid"));
    // The thumbnail draws every sampled segment.
    let t = lattice::thumbnail(&p, 6.0, 1);
    let straight = lattice::thumbnail(&Pattern::SquareGrid { cell_size_mm: 1.0 }, 6.0, 1);
    assert!(t.len() > 8 * straight.len(), "{} vs {}", t.len(), straight.len());
    // Out of range: amplitude over a quarter strut, too few or too many samples.
    for bad in [wavy_hc(1.0, 0.26, 12), wavy_sq(1.0, -0.1, 12), wavy_sq(1.0, 0.1, 2), wavy_hc(1.0, 0.1, 65)] {
        assert!(lattice::validate(&bad).is_err(), "{bad:?}");
    }
    assert!(lattice::validate(&wavy_hc(1.0, 0.0, 4)).is_ok());
}

#[test]
fn estimate_counts_the_extra_points() {
    let size = |o: &Options| lattice::DomainSize::planar(&Domain::Rectangle { width_mm: 10.0, height_mm: 10.0 }, o);
    let q = |p: Pattern, key: &str| {
        let o = Options { pattern: p, ..Options::default() };
        lattice::estimate(&size(&o), &o, LW).get(key)
    };
    let (straight, wavy) = (q(Pattern::Honeycomb { hexagon_radius_mm: 1.0 }, "edges"), q(wavy_hc(1.0, 0.15, 12), "edges"));
    assert!((wavy / straight / 12.0 - 1.0).abs() < 0.05, "{wavy} vs {straight}");
    // The real segment count is within the estimate's usual margin.
    let real: usize = strokes(wavy_hc(1.0, 0.15, 12)).strokes.iter().map(|s| s.points.len() - 1).sum();
    assert!((real as f64 / wavy - 1.0).abs() < 0.25, "{real} vs {wavy}");
    let (ls, lw) = (q(Pattern::Honeycomb { hexagon_radius_mm: 1.0 }, "length_mm"), q(wavy_hc(1.0, 0.15, 12), "length_mm"));
    assert!(lw > 1.1 * ls);
}

fn metric(out: &pipeline::RunOutput, stage: &str, key: &str) -> (f64, String) {
    let s = out.report.stages.iter().find(|s| s.stage == stage).unwrap();
    let m = s.metrics.iter().find(|m| m.key == key).unwrap();
    (m.value, m.unit.clone())
}

#[test]
fn die_swell_predicts_the_width_and_optionally_scales_e() {
    let hc = serde_json::json!({"kind": "honeycomb", "hexagon_radius_mm": 0.92});
    let run = |b: f64, comp: bool| {
        let d = design(hc.clone(), |v| {
            v["material"]["swell_ratio"] = serde_json::json!(b);
            v["material"]["compensate_swell"] = serde_json::json!(comp);
        });
        pipeline::run(&d, &Files::new(), &RunOptions::default(), &mut |_, _| {}).unwrap()
    };
    let base = run(1.0, false);
    assert_eq!(metric(&base, "lattice", "strut_width"), (0.2, "mm".into()));
    assert_eq!(metric(&base, "lattice", "printed_width"), (0.2, "mm".into()));
    let swollen = run(1.25, false);
    assert!((metric(&swollen, "lattice", "printed_width").0 - 0.25).abs() < 1e-12);
    // Prediction only: the G-code is the same bytes.
    assert_eq!(swollen.gcode, base.gcode);
    // Compensation: equation 4 with w = 1.25 × 0.2 mm: 1.25 × the strut filament; pre/post
    // flow and retraction unchanged (honeycomb-10mm has none of the former).
    let comp = run(1.25, true);
    let (eb, ec) = (base.report.gcode.filament_mm, comp.report.gcode.filament_mm);
    assert!((ec / eb - 1.25).abs() < 1e-3, "{ec} vs {eb}");
    // By equation 4 directly: 131.82 mm of struts, LT 0.148, EM = k = 1, f_d 1.75.
    let want = 4.0 * base.report.analysis.extruded_mm * 0.148 * 0.25 / (std::f64::consts::PI * 1.75 * 1.75);
    assert!((ec - want).abs() < 1e-3 * want, "{ec} vs {want}");
    // Ranges: below 1 or above 3 refused.
    for bad in [0.9, 3.5] {
        let mut v: serde_json::Value = serde_json::from_str(include_str!("../../examples/honeycomb-10mm.json")).unwrap();
        v["material"]["swell_ratio"] = serde_json::json!(bad);
        let d = Design::from_json("test.json", &v.to_string());
        assert!(d.is_err() || pipeline::run(&d.unwrap(), &Files::new(), &RunOptions::default(), &mut |_, _| {}).is_err(), "{bad}");
    }
}

//! Print-path optimisation: coverage (every graph edge printed exactly once), path-count
//! bounds, continuous walks, determinism, GIPPO scores, crossing splits and timings.

use std::collections::BTreeSet;
use weft::geom::{DVec2, Feature, Stroke, StrokeLayer, Toolpath};
use weft::paths::{build_graph, optimise, Error, Graph, Method, Optimised, Options, Order};

const TOL: f64 = 0.005;
const METHODS: [Method; 4] = [Method::GippoMax, Method::GippoMin, Method::Euler, Method::Continuous];

fn stroke(points: &[(f64, f64)]) -> Stroke {
    Stroke { points: points.iter().map(|&(x, y)| DVec2::new(x, y)).collect(), feature: Feature::Lattice, curved: false }
}

fn layer(strokes: Vec<Stroke>) -> StrokeLayer {
    StrokeLayer { z: 0.3, height: 0.2, strokes }
}

/// A grid of `nx` × `ny` unit squares drawn as long crossing lines (exercises splitting).
fn grid_lines(nx: usize, ny: usize, s: f64) -> StrokeLayer {
    let mut strokes = Vec::new();
    for j in 0..=ny {
        strokes.push(stroke(&[(0.0, j as f64 * s), (nx as f64 * s, j as f64 * s)]));
    }
    for i in 0..=nx {
        strokes.push(stroke(&[(i as f64 * s, 0.0), (i as f64 * s, ny as f64 * s)]));
    }
    layer(strokes)
}

/// A grid of squares drawn as one stroke per unit edge.
fn grid_segments(nx: usize, ny: usize, s: f64) -> StrokeLayer {
    let mut strokes = Vec::new();
    for j in 0..=ny {
        for i in 0..=nx {
            let (x, y) = (i as f64 * s, j as f64 * s);
            if i < nx {
                strokes.push(stroke(&[(x, y), (x + s, y)]));
            }
            if j < ny {
                strokes.push(stroke(&[(x, y), (x, y + s)]));
            }
        }
    }
    layer(strokes)
}

/// Flat-top hexagons of radius `r` (closed strokes, shared edges drawn twice) whose centres
/// lie in `keep`.
fn honeycomb(r: f64, w: f64, h: f64, keep: &dyn Fn(f64, f64) -> bool) -> StrokeLayer {
    let k = 3f64.sqrt() / 2.0;
    let corners = [(1.0, 0.0), (0.5, k), (-0.5, k), (-1.0, 0.0), (-0.5, -k), (0.5, -k), (1.0, 0.0)];
    let mut strokes = Vec::new();
    let cols = (w / (1.5 * r)).ceil() as i64 + 1;
    let rows = (h / (2.0 * k * r)).ceil() as i64 + 1;
    for i in 0..=cols {
        for j in 0..=rows {
            let cx = 1.5 * r * i as f64;
            let cy = 2.0 * k * r * (j as f64 + if i % 2 == 1 { 0.5 } else { 0.0 });
            if cx > w || cy > h || !keep(cx, cy) {
                continue;
            }
            let pts: Vec<(f64, f64)> = corners.iter().map(|&(a, b)| (cx + r * a, cy + r * b)).collect();
            strokes.push(stroke(&pts));
        }
    }
    layer(strokes)
}

fn honeycomb_10mm() -> StrokeLayer {
    honeycomb(1.0, 10.0, 10.0, &|_, _| true)
}

/// About 300 edges over 10 × 10 mm (radius-1 mm hexagons give only ~150).
fn honeycomb_10mm_dense() -> StrokeLayer {
    honeycomb(0.7, 10.0, 10.0, &|_, _| true)
}

fn honeycomb_disc_48mm() -> StrokeLayer {
    honeycomb(1.0, 48.0, 48.0, &|x, y| (x - 24.0).hypot(y - 24.0) <= 24.0)
}

/// A pentagram (one closed stroke crossing itself five times) plus spokes.
fn star() -> StrokeLayer {
    let p = |k: f64| {
        let a = std::f64::consts::FRAC_PI_2 + k * 2.0 * std::f64::consts::PI / 5.0;
        (10.0 + 5.0 * a.cos(), 10.0 + 5.0 * a.sin())
    };
    let pts: Vec<(f64, f64)> = [0.0, 2.0, 4.0, 1.0, 3.0, 0.0].iter().map(|&k| p(k)).collect();
    let mut strokes = vec![stroke(&pts)];
    for k in 0..5 {
        strokes.push(stroke(&[(10.0, 10.0), p(k as f64 + 0.5)]));
    }
    layer(strokes)
}

/// Random long crossing strokes (deterministic LCG).
fn crossings(n: usize, seed: u64) -> StrokeLayer {
    let mut s = seed;
    let mut rnd = move || {
        s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (s >> 11) as f64 / (1u64 << 53) as f64 * 20.0
    };
    layer((0..n).map(|_| stroke(&[(rnd(), rnd()), (rnd(), rnd()), (rnd(), rnd())])).collect())
}

fn components() -> StrokeLayer {
    layer(vec![
        stroke(&[(0.0, 0.0), (2.0, 0.0), (2.0, 2.0), (0.0, 2.0), (0.0, 0.0)]),
        stroke(&[(1.0, 0.0), (1.0, 2.0)]),
        stroke(&[(10.0, 0.0), (12.0, 0.0), (12.0, 3.0)]),
        stroke(&[(20.0, 5.0), (21.0, 5.0)]),
        stroke(&[(30.0, 0.0), (30.0, 3.0)]),
        stroke(&[(29.0, 1.0), (31.0, 1.0)]),
    ])
}

fn single_edge() -> StrokeLayer {
    layer(vec![stroke(&[(1.0, 1.0), (4.0, 5.0)])])
}

fn closed_loop() -> StrokeLayer {
    layer(vec![stroke(&[(0.0, 0.0), (3.0, 0.0), (3.0, 2.0), (0.0, 2.0), (0.0, 0.0)])])
}

/// Diamonds touching at their corners: every node has degree 2 or 4.
fn eulerian_grid() -> StrokeLayer {
    let mut strokes = Vec::new();
    for i in 0..5 {
        for j in 0..5 {
            let (x, y) = (2.0 * i as f64, 2.0 * j as f64);
            strokes.push(stroke(&[(x + 1.0, y), (x + 2.0, y + 1.0), (x + 1.0, y + 2.0), (x, y + 1.0), (x + 1.0, y)]));
        }
    }
    layer(strokes)
}

fn cases() -> Vec<(&'static str, StrokeLayer)> {
    vec![
        ("grid_lines_6x4", grid_lines(6, 4, 1.5)),
        ("grid_segments_5x5", grid_segments(5, 5, 1.0)),
        ("honeycomb_10mm", honeycomb_10mm()),
        ("honeycomb_10mm_dense", honeycomb_10mm_dense()),
        ("star", star()),
        ("crossings", crossings(12, 7)),
        ("crossings_b", crossings(25, 99)),
        ("components", components()),
        ("single_edge", single_edge()),
        ("closed_loop", closed_loop()),
        ("eulerian_grid", eulerian_grid()),
    ]
}

fn um(v: f64) -> i64 {
    (v * 1000.0).round() as i64
}

type Seg = ((i64, i64), (i64, i64));

fn seg_key(a: (f64, f64), b: (f64, f64)) -> Seg {
    let a = (um(a.0), um(a.1));
    let b = (um(b.0), um(b.1));
    if a <= b {
        (a, b)
    } else {
        (b, a)
    }
}

fn graph_segments(g: &Graph) -> Vec<Seg> {
    let mut v: Vec<Seg> = g.edges.iter().map(|e| seg_key((g.nodes[e.a].x, g.nodes[e.a].y), (g.nodes[e.b].x, g.nodes[e.b].y))).collect();
    v.sort();
    v
}

fn printed_segments(tp: &Toolpath, layer: usize) -> Vec<Seg> {
    let mut v = Vec::new();
    for p in &tp.passes[layer].paths {
        assert!(p.points.len() >= 2);
        for w in p.points.windows(2) {
            v.push(seg_key((w[0].x, w[0].y), (w[1].x, w[1].y)));
        }
    }
    v.sort();
    v
}

fn run(l: &StrokeLayer, method: Method, seed: u64) -> Optimised {
    let options = Options { method, iterations: 60, ..Options::default() };
    optimise(std::slice::from_ref(l), &options, 0.4, seed, &mut |_| {}).expect("optimise")
}

#[test]
fn every_method_prints_every_edge_exactly_once() {
    for (name, l) in cases() {
        let g = build_graph(&l, TOL);
        let want = graph_segments(&g);
        assert!(!want.is_empty(), "{name}");
        for m in METHODS {
            let out = run(&l, m, 1);
            let got = printed_segments(&out.toolpath, 0);
            assert_eq!(got, want, "{name} {m:?}");
            let tl = &out.toolpath.passes[0];
            assert_eq!(tl.z, 0.3);
            assert_eq!(tl.height, 0.2);
            for p in &tl.paths {
                assert_eq!(p.width, 0.4);
                assert!(p.points.iter().all(|q| q.z == 0.3));
                assert_eq!(p.feature, Feature::Lattice);
            }
            let r = &out.report.layers[0];
            assert_eq!(r.edges, g.edges.len(), "{name}");
            assert_eq!(r.nodes, g.nodes.len(), "{name}");
            assert_eq!(r.components, g.components, "{name}");
            assert_eq!(r.lower_bound_paths, g.lower_bound_paths(), "{name}");
            assert_eq!(r.paths, tl.paths.len(), "{name}");
            assert!(r.paths >= r.lower_bound_paths, "{name} {m:?}");
            assert_eq!(r.long_paths + r.medium_paths + r.short_paths, r.paths);
            assert_eq!(out.report.method, Some(m));
        }
    }
}

#[test]
fn euler_reaches_the_lower_bound() {
    let mut all = cases();
    for seed in 0..15 {
        all.push(("random", crossings(4 + seed as usize * 3, seed)));
    }
    all.push(("disc", honeycomb_disc_48mm()));
    all.push(("grid_segments_17x9", grid_segments(17, 9, 0.8)));
    for (name, l) in all {
        let out = run(&l, Method::Euler, 0);
        let r = &out.report.layers[0];
        assert_eq!(r.paths, r.lower_bound_paths, "{name}");
        assert_eq!(printed_segments(&out.toolpath, 0), graph_segments(&build_graph(&l, TOL)), "{name}");
        // Every path after the first is a free travel; the G-code retracts for those at least
        // the default printer's 1 mm long.
        let retractions = weft::gcode::retractions_per_pass(&out.toolpath, &weft::gcode::Printer::default())[0];
        assert!(retractions <= r.paths.saturating_sub(1), "{name}");
        // `optimise` does not know the printer; the lattice job fills the report's count.
        assert_eq!(r.retractions, 0, "{name}");
        if r.odd_nodes > 0 {
            assert!(r.pairing_mm > 0.0, "{name}");
        }
    }
}

#[test]
fn euler_on_a_100x100_square_grid() {
    let l = grid_lines(100, 100, 1.0);
    let g = build_graph(&l, TOL);
    assert_eq!(g.edges.len(), 2 * 100 * 101);
    assert_eq!(g.nodes.len(), 101 * 101);
    // Odd nodes: the boundary nodes except the corners.
    let odd: Vec<usize> = (0..g.nodes.len()).filter(|&v| g.degree(v) % 2 == 1).collect();
    assert_eq!(odd.len(), 4 * 99);
    for &v in &odd {
        let p = g.nodes[v];
        assert!(p.x.abs() < 1e-9 || p.y.abs() < 1e-9 || (p.x - 100.0).abs() < 1e-9 || (p.y - 100.0).abs() < 1e-9);
    }
    let out = run(&l, Method::Euler, 0);
    let r = &out.report.layers[0];
    assert_eq!(r.lower_bound_paths, 198);
    assert_eq!(r.paths, 198);
    assert_eq!(printed_segments(&out.toolpath, 0), graph_segments(&g));
}

#[test]
fn continuous_is_one_chain_per_component_along_struts() {
    let mut routed = 0;
    for (name, l) in cases() {
        let g = build_graph(&l, TOL);
        let edges: BTreeSet<Seg> = graph_segments(&g).into_iter().collect();
        for order in [Order::LongestFirst, Order::MinTravel] {
            let options = Options { method: Method::Continuous, order, ..Options::default() };
            let out = optimise(std::slice::from_ref(&l), &options, 0.4, 3, &mut |_| {}).unwrap();
            let paths = &out.toolpath.passes[0].paths;
            let free = paths.iter().filter(|p| p.approach.is_none()).count();
            assert_eq!(free, g.components, "{name}");
            assert!(paths[0].approach.is_none());
            let retractions = weft::gcode::retractions_per_pass(&out.toolpath, &weft::gcode::Printer::default())[0];
            assert_eq!(retractions, g.components - 1, "{name}");
            for w in paths.windows(2) {
                if let Some(route) = &w[1].approach {
                    routed += 1;
                    let mut pts = vec![*w[0].points.last().unwrap()];
                    pts.extend(route.iter().copied());
                    pts.push(w[1].points[0]);
                    for s in pts.windows(2) {
                        let k = seg_key((s[0].x, s[0].y), (s[1].x, s[1].y));
                        assert!(edges.contains(&k), "{name}: approach leaves the struts at {k:?}");
                    }
                }
            }
            assert_eq!(printed_segments(&out.toolpath, 0), graph_segments(&g), "{name}");
        }
    }
    assert!(routed > 10, "{routed} approach routes");
}

#[test]
fn gippo_is_deterministic_and_seed_dependent() {
    let l = honeycomb_10mm();
    for m in [Method::GippoMax, Method::GippoMin] {
        let a = run(&l, m, 42);
        let b = run(&l, m, 42);
        assert_eq!(a.toolpath, b.toolpath);
        assert_eq!(a.report, b.report);
        let c = run(&l, m, 43);
        assert_ne!(a.report.layers[0].iteration_scores, c.report.layers[0].iteration_scores, "{m:?}");
    }
    // Every method is deterministic, also across multiple layers with min-travel order.
    let layers = vec![honeycomb_10mm(), star(), crossings(10, 5)];
    for m in METHODS {
        let options = Options { method: m, order: Order::MinTravel, iterations: 20, ..Options::default() };
        let a = optimise(&layers, &options, 0.4, 9, &mut |_| {}).unwrap();
        let b = optimise(&layers, &options, 0.4, 9, &mut |_| {}).unwrap();
        assert_eq!(a.toolpath, b.toolpath);
        assert_eq!(a.report, b.report);
        assert_eq!(a.toolpath.passes.len(), 3);
        for (i, l) in layers.iter().enumerate() {
            assert_eq!(printed_segments(&a.toolpath, i), graph_segments(&build_graph(l, TOL)));
        }
    }
}

#[test]
fn gippo_best_score_and_scores() {
    let l = honeycomb_10mm();
    let out = run(&l, Method::GippoMax, 5);
    let r = &out.report.layers[0];
    assert_eq!(r.iteration_scores.len(), 60);
    assert!(r.iteration_scores.iter().all(|&s| s <= r.score));
    assert!(r.iteration_scores.contains(&r.score));
    // Report score is equation 1 over the printed paths.
    let tl = &out.toolpath.passes[0];
    let total: f64 = tl.paths.iter().map(|p| p.length()).sum();
    let eq1: f64 = tl.paths.iter().map(|p| p.length() * (p.points.len() - 1) as f64).sum::<f64>() / (total * tl.paths.len() as f64);
    assert!((eq1 - r.score).abs() < 1e-9 * eq1.max(1.0), "{eq1} vs {}", r.score);
    // Longest first: segments never increase.
    assert!(tl.paths.windows(2).all(|w| w[0].points.len() >= w[1].points.len()));
}

#[test]
fn gippo_scores_match_hand_computed_equation_1() {
    // Star with spokes of 1, 2, 3 mm. gippo_max: starting at the centre, A2 or A3 gives
    // paths {A2-C-A3 (5 mm, 2 edges), C-A1} → (10 + 1)/(6·2) = 11/12; starting at A1 gives
    // {A1-C-A3, C-A2} → (8 + 2)/12 = 10/12.
    let l = layer(vec![stroke(&[(0.0, 0.0), (1.0, 0.0)]), stroke(&[(0.0, 0.0), (0.0, 2.0)]), stroke(&[(0.0, 0.0), (-3.0, 0.0)])]);
    let out = run(&l, Method::GippoMax, 11);
    let r = &out.report.layers[0];
    for &s in &r.iteration_scores {
        assert!((s - 11.0 / 12.0).abs() < 1e-12 || (s - 10.0 / 12.0).abs() < 1e-12, "{s}");
    }
    assert!((r.score - 11.0 / 12.0).abs() < 1e-12);
    // gippo_min: starts at C, A1, A2 → {A2-C-A1, C-A3} = 9/12; start at A3 → {A3-C-A1, C-A2} = 10/12.
    let out = run(&l, Method::GippoMin, 11);
    let r = &out.report.layers[0];
    for &s in &r.iteration_scores {
        assert!((s - 9.0 / 12.0).abs() < 1e-12 || (s - 10.0 / 12.0).abs() < 1e-12, "{s}");
    }
    assert!((r.score - 10.0 / 12.0).abs() < 1e-12);
    assert_eq!(r.paths, 2);
    assert_eq!(r.short_paths, 2);
    assert_eq!(r.lts_percent, 0.0);
}

#[test]
fn crossing_strokes_are_split_and_close_nodes_merge() {
    let x = layer(vec![stroke(&[(0.0, 0.0), (4.0, 4.0)]), stroke(&[(0.0, 4.0), (4.0, 0.0)])]);
    let g = build_graph(&x, TOL);
    assert_eq!(g.edges.len(), 4);
    assert_eq!((0..g.nodes.len()).filter(|&v| g.degree(v) == 4).count(), 1);
    assert_eq!(g.components, 1);
    for m in METHODS {
        let out = run(&x, m, 0);
        assert_eq!(printed_segments(&out.toolpath, 0), graph_segments(&g));
    }
    // Euler: the X's 4 odd leaves → 2 paths.
    assert_eq!(run(&x, Method::Euler, 0).report.layers[0].paths, 2);

    // Ends 3 µm apart merge; a 2 µm segment is dropped.
    let l = layer(vec![stroke(&[(0.0, 0.0), (1.0, 0.0)]), stroke(&[(1.003, 0.0), (2.0, 0.0)]), stroke(&[(5.0, 5.0), (5.002, 5.0)])]);
    let g = build_graph(&l, TOL);
    assert_eq!(g.nodes.len(), 3);
    assert_eq!(g.edges.len(), 2);
    assert_eq!(g.degenerate_dropped, 1);
    let out = run(&l, Method::Euler, 0);
    assert_eq!(out.report.layers[0].paths, 1);
    assert_eq!(out.report.layers[0].degenerate_dropped, 1);

    // Grid drawn as long lines: every crossing becomes a node.
    let g = build_graph(&grid_lines(6, 4, 1.5), TOL);
    assert_eq!(g.nodes.len(), 7 * 5);
    assert_eq!(g.edges.len(), 6 * 5 + 7 * 4);
    // The same strokes twice collapse.
    let mut twice = grid_lines(3, 3, 1.0);
    twice.strokes.extend(grid_lines(3, 3, 1.0).strokes);
    let g = build_graph(&twice, TOL);
    assert_eq!(g.edges.len(), 24);
}

#[test]
fn short_paths_are_slowed() {
    // A 1-edge component and a 6-edge closed loop.
    let l = layer(vec![stroke(&[(0.0, 0.0), (1.0, 0.0)]), stroke(&[(5.0, 0.0), (6.0, 0.0), (7.0, 0.0), (7.0, 1.0), (6.0, 1.0), (5.0, 1.0), (5.0, 0.0)])]);
    for m in METHODS {
        let out = run(&l, m, 0);
        let paths = &out.toolpath.passes[0].paths;
        assert_eq!(paths.len(), 2, "{m:?}");
        for p in paths {
            let segs = p.points.len() - 1;
            let want = if segs < 4 { 0.6 } else { 1.0 };
            assert_eq!(p.speed_factor, want, "{m:?} {segs}");
        }
    }
    let options = Options { short_path_speed_factor: 0.5, short_path_segments: 7, ..Options::default() };
    let out = optimise(&[l], &options, 0.4, 0, &mut |_| {}).unwrap();
    assert!(out.toolpath.passes[0].paths.iter().all(|p| p.speed_factor == 0.5));
}

#[test]
fn majority_feature_and_min_travel_order() {
    let mut l = layer(vec![
        stroke(&[(0.0, 0.0), (5.0, 0.0)]),
        Stroke { points: vec![DVec2::new(5.0, 0.0), DVec2::new(5.0, 1.0)], feature: Feature::Contour, curved: false },
    ]);
    let out = run(&l, Method::Euler, 0);
    assert_eq!(out.toolpath.passes[0].paths.len(), 1);
    assert_eq!(out.toolpath.passes[0].paths[0].feature, Feature::Lattice);
    l.strokes[1].points[1] = DVec2::new(5.0, 9.0);
    assert_eq!(run(&l, Method::Euler, 0).toolpath.passes[0].paths[0].feature, Feature::Contour);

    // Min-travel beats longest-first on scattered single edges.
    let scattered = crossings(1, 1);
    let mut strokes = scattered.strokes;
    for i in 0..40 {
        let x = ((i * 37) % 40) as f64;
        let len = 0.5 + (i % 7) as f64 * 0.3;
        strokes.push(stroke(&[(x, 30.0), (x, 30.0 + len)]));
    }
    let l = layer(strokes);
    let lf = optimise(std::slice::from_ref(&l), &Options { method: Method::Euler, ..Options::default() }, 0.4, 0, &mut |_| {}).unwrap();
    let mt =
        optimise(std::slice::from_ref(&l), &Options { method: Method::Euler, order: Order::MinTravel, ..Options::default() }, 0.4, 0, &mut |_| {}).unwrap();
    let (a, b) = (lf.report.layers[0].travel_mm, mt.report.layers[0].travel_mm);
    assert!(b < a * 0.5, "min travel {b} vs longest first {a}");
    assert_eq!(printed_segments(&mt.toolpath, 0), printed_segments(&lf.toolpath, 0));
}

#[test]
fn options_are_validated_and_progress_reported() {
    let l = vec![single_edge(), closed_loop(), StrokeLayer::default()];
    let bad = [
        Options { iterations: 0, ..Options::default() },
        Options { iterations: 100_001, ..Options::default() },
        Options { merge_tolerance_mm: 0.0, ..Options::default() },
        Options { merge_tolerance_mm: 1.5, ..Options::default() },
        Options { merge_tolerance_mm: f64::NAN, ..Options::default() },
        Options { short_path_speed_factor: 0.0, ..Options::default() },
        Options { short_path_speed_factor: 1.2, ..Options::default() },
    ];
    for o in bad {
        assert!(matches!(optimise(&l, &o, 0.4, 0, &mut |_| {}), Err(Error::BadOptions { .. })), "{o:?}");
    }
    let mut seen = Vec::new();
    let out = optimise(&l, &Options::default(), 0.4, 0, &mut |f| seen.push(f)).unwrap();
    assert_eq!(seen, vec![1.0 / 3.0, 2.0 / 3.0, 1.0]);
    assert_eq!(out.toolpath.passes.len(), 3);
    assert!(out.toolpath.passes[2].paths.is_empty());
    assert_eq!(out.report.layers[2], weft::paths::LayerPaths::default());
    assert_eq!(out.report.layers[1].paths, 1);
    assert_eq!(out.report.layers[1].lower_bound_paths, 1);
    assert_eq!(out.report.layers[0].retractions, 0);
}

/// The counted work of building graphs and optimising paths (`crate::work`), printed (times:
/// `weft bench --lattice`): `cargo test --release --test it paths:: -- --ignored --nocapture timings`
#[test]
#[ignore]
fn timings() {
    let small = honeycomb_10mm();
    let disc = honeycomb_disc_48mm();
    let big = grid_segments(223, 224, 1.0);
    let big_lines = grid_lines(223, 224, 1.0);
    let dense = honeycomb_10mm_dense();
    for (name, l) in [
        ("honeycomb 10 mm r1", &small),
        ("honeycomb 10 mm r0.7", &dense),
        ("honeycomb disc 48 mm", &disc),
        ("grid 100k (segments)", &big),
        ("grid 100k (lines)", &big_lines),
    ] {
        let (t, g): (_, Graph) = crate::work::measure(|| build_graph(l, TOL));
        println!("{name}: {} edges, {} nodes, build_graph {t:?}", g.edges.len(), g.nodes.len());
    }
    for (name, l) in [("honeycomb 10 mm r1", &small), ("honeycomb 10 mm r0.7", &dense), ("honeycomb disc 48 mm", &disc)] {
        for m in [Method::GippoMax, Method::GippoMin] {
            let o = Options { method: m, ..Options::default() };
            let (t, out) = crate::work::measure(|| optimise(std::slice::from_ref(l), &o, 0.4, 1, &mut |_| {}).unwrap());
            let r = &out.report.layers[0];
            println!(
                "{name}: {m:?} 500 iterations {t:?} (incl. graph) — paths {} (lb {}), score {:.3}, LTS {:.1} %, OE {:.1} %",
                r.paths, r.lower_bound_paths, r.score, r.lts_percent, r.oe_percent
            );
        }
    }
    for (name, l) in [("honeycomb disc 48 mm", &disc), ("grid 100k (segments)", &big)] {
        for m in [Method::Euler, Method::Continuous] {
            for order in [Order::LongestFirst, Order::MinTravel] {
                let o = Options { method: m, order, ..Options::default() };
                let (t, out) = crate::work::measure(|| optimise(std::slice::from_ref(l), &o, 0.4, 1, &mut |_| {}).unwrap());
                let r = &out.report.layers[0];
                println!(
                    "{name}: {m:?} {order:?} {t:?} (incl. graph) — paths {} (lb {}), pairing {:.1} mm, travel {:.1} mm",
                    r.paths, r.lower_bound_paths, r.pairing_mm, r.travel_mm
                );
            }
        }
    }
}

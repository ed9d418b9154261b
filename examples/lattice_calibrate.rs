//! Calibrates and checks the lattice job's stage estimates (issue 7): for each pattern and
//! domain size, the estimated counts against the real ones and the measured CPU time per
//! work unit (the constants in `src/lattice/estimate.rs`, `src/paths/estimate.rs`,
//! `src/nonplanar/estimate.rs`).
//!
//! `cargo run --release --example lattice_calibrate [lattice|paths|nonplanar] [side_mm…]`

use weft::lattice::{self, Domain, DomainSize, Options, Pattern};

/// This thread's CPU time, s (wall time where it cannot be read).
fn cpu() -> f64 {
    weft::bench::thread_cpu_seconds().unwrap_or_else(|| std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).unwrap().as_secs_f64())
}

fn patterns(scale: f64) -> Vec<Pattern> {
    vec![
        Pattern::Honeycomb { hexagon_radius_mm: 0.3 * scale },
        Pattern::Voronoi { density_per_mm2: 4.0 / (scale * scale) },
        Pattern::Penrose { cell_size_mm: 0.4 * scale },
        Pattern::SnubSquare { cell_size_mm: 0.4 * scale },
        Pattern::Arrowhead { cell_width_mm: 0.8 * scale, cell_height_mm: 0.8 * scale },
        Pattern::ReentrantHoneycomb { cell_width_mm: 0.8 * scale, cell_height_mm: 0.8 * scale },
        Pattern::Rectilinear { strand_distance_mm: 0.3 * scale },
        Pattern::SquareGrid { cell_size_mm: 0.4 * scale },
        Pattern::TriangleGrid { cell_size_mm: 0.4 * scale },
    ]
}

fn name(p: &Pattern) -> String {
    format!("{p:?}").split(' ').next().unwrap_or("").to_string()
}

/// Estimated against real segments and the time per unit of each path method.
fn paths_row(layers: &[weft::geom::StrokeLayer], lat: &weft::budget::Estimate, side: f64, pattern: &str, contour: bool) {
    use weft::paths::{self, Method, Order, Work};
    let work = Work::of_lattice(lat);
    let mut line = format!("{side:>5} {pattern:<18} {:<5}", if contour { "disc" } else { "rect" });
    let mut t1 = 0.0;
    for (label, method, iterations, order) in [
        ("g1", Method::GippoMax, 1, Order::LongestFirst),
        ("g21", Method::GippoMax, 21, Order::LongestFirst),
        ("g500", Method::GippoMax, 500, Order::LongestFirst),
        ("eu", Method::Euler, 1, Order::LongestFirst),
        ("eu+mt", Method::Euler, 1, Order::MinTravel),
        ("co", Method::Continuous, 1, Order::LongestFirst),
    ] {
        if label == "g500" && std::env::var_os("G500").is_none() {
            continue;
        }
        let o = paths::Options { method, iterations, order, ..paths::Options::default() };
        let est = paths::estimate(&work, &o);
        let t = cpu();
        let out = paths::optimise(layers, &o, 0.2, 1, &mut |_| {}).unwrap();
        let dt = cpu() - t;
        let edges: f64 = out.report.layers.iter().map(|l| l.edges as f64).sum();
        let odd: f64 = out.report.layers.iter().map(|l| l.odd_nodes as f64).sum();
        let segs = out.toolpath.point_count() as f64;
        let per = match label {
            "g1" => {
                t1 = dt;
                dt / edges
            }
            "g21" | "g500" => (dt - t1) / (edges * (iterations - 1) as f64),
            _ => (dt - t1) / odd.max(1.0),
        };
        line += &format!(" | {label} seg {:.2} t {:.3}/{:.3} u {:.2}µs", est.get("segments") / segs, dt, est.seconds, per * 1e6);
    }
    println!("{line}");
}

/// A cone of `n` triangles fanned from its apex (radius `r`, height 0.3 r).
fn cone(r: f64, n: u32) -> weft::geom::Mesh {
    let mut m = weft::geom::Mesh::default();
    m.vertices.push([0.0, 0.0, (0.3 * r) as f32]);
    for k in 0..n {
        let t = 2.0 * std::f64::consts::PI * k as f64 / n as f64;
        m.vertices.push([(r * libm::cos(t)) as f32, (r * libm::sin(t)) as f32, 0.0]);
    }
    for k in 0..n {
        m.triangles.push([0, 1 + k, 1 + (k + 1) % n]);
    }
    m
}

/// Estimated against real points and times of the projection on several surfaces.
fn nonplanar_rows(sides: &[f64]) {
    use weft::nonplanar::{self, Surface, SurfaceSize, Work};
    let mut uv = weft::geom::shapes::uv_sphere(150.0, 256);
    uv.translate(weft::geom::DVec3::new(0.0, 0.0, -150.0));
    let fan = cone(150.0, 20_000);
    for &side in sides {
        for (cell, method) in [(1.0, weft::paths::Method::Euler), (0.5, weft::paths::Method::Continuous)] {
            let o = Options { pattern: Pattern::Honeycomb { hexagon_radius_mm: cell }, layers: 2, contour: true, ..Options::default() };
            let domain = Domain::Disc { diameter_mm: side };
            let g = lattice::generate(&lattice::planar_domains(&domain, &o).unwrap(), &o, 0.2, 1, &mut |_| {}).unwrap();
            let po = weft::paths::Options { method, ..weft::paths::Options::default() };
            let tp = weft::paths::optimise(&g.layers, &po, 0.2, 1, &mut |_| {}).unwrap().toolpath;
            // The chained estimate, as the job composes it.
            let size = DomainSize::planar(&domain, &o);
            let lat = lattice::estimate(&size, &o, 0.2);
            let pe = weft::paths::estimate(&weft::paths::Work::of_lattice(&lat), &po);
            for (label, surface, mesh) in [
                ("sphere20", Surface::Sphere { radius_mm: 20.0, center_mm: [0.0, 0.0, 0.0] }, None),
                ("sphere1000", Surface::Sphere { radius_mm: 1000.0, center_mm: [0.0, 0.0, 0.0] }, None),
                ("cyl30", Surface::Cylinder { radius_mm: 30.0, axis_z_mm: 0.0 }, None),
                ("uvmesh", Surface::Mesh, Some(&uv)),
                ("cone20k", Surface::Mesh, Some(&fan)),
            ] {
                let no = nonplanar::Options { surface, max_segment_mm: 0.25 };
                let work = Work::of_toolpath(&tp);
                let ss = mesh.map(|m| SurfaceSize::of_mesh(m, work.min, work.max));
                let est = nonplanar::estimate(&work, ss.as_ref(), &no);
                let chained = nonplanar::estimate(&Work::of_paths(&pe, size.min, size.max), ss.as_ref(), &no);
                let t = cpu();
                let r = nonplanar::project(&tp, mesh, &no).unwrap();
                let dt = cpu() - t;
                let real = r.toolpath.point_count() as f64;
                println!(
                    "{side:>5} hc{cell} {label:<10} est/real points {:.2} chained {:.2} | {:.3} s est {:.3} ({:.2}×) cand {:.1} | {:.0} MB",
                    est.get("segments") / real,
                    chained.get("segments") / real,
                    dt,
                    est.seconds,
                    est.seconds / dt,
                    est.get("candidates"),
                    est.bytes / 1e6
                );
            }
        }
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let what = args.get(1).map(String::as_str).unwrap_or("lattice");
    if what == "plan" {
        // The plan of a design file (`--set`-style overrides after it), as JSON.
        let text = std::fs::read_to_string(&args[2]).expect("a design file");
        let d = weft::Design::from_json(&args[2], &text).unwrap();
        let sets: Vec<String> = args.iter().skip(3).cloned().collect();
        let d = d.with_overrides(&sets).unwrap();
        let registry = weft::kinds::Registry::builtin();
        let files = weft::pipeline::Files::new();
        let mut cache = weft::pipeline::Cache::new();
        let mut quiet = |_: &str, _: f32| {};
        let mut ctx = weft::pipeline::Ctx::new(&d, &files, &mut cache, &mut quiet);
        let est = registry.get(d.job.kind()).unwrap().estimate(&mut ctx).unwrap();
        println!("{}", serde_json::to_string_pretty(&weft::budget::Plan::new(est)).unwrap());
        return;
    }
    if what == "nonplanar" {
        let sides: Vec<f64> = args.iter().skip(2).filter_map(|s| s.parse().ok()).collect();
        nonplanar_rows(if sides.is_empty() { &[50.0, 100.0, 200.0] } else { &sides });
        return;
    }
    let sides: Vec<f64> = args.iter().skip(2).filter_map(|s| s.parse().ok()).collect();
    let sides = if sides.is_empty() { vec![80.0, 160.0] } else { sides };
    for &side in &sides {
        for p in patterns(1.0) {
            for (domain, contour, layers, rot) in
                [(Domain::Rectangle { width_mm: side, height_mm: side }, false, 1, 0.0), (Domain::Disc { diameter_mm: side }, true, 2, 30.0)]
            {
                let o = Options { pattern: p.clone(), contour, layers, rotation_deg: rot, ..Options::default() };
                let d = lattice::planar_domains(&domain, &o).unwrap();
                let est = lattice::estimate(&DomainSize::planar(&domain, &o), &o, 0.2);
                let t = cpu();
                let g = match lattice::generate(&d, &o, 0.2, 1, &mut |_| {}) {
                    Ok(g) => g,
                    Err(e) => {
                        println!("{side} {} {e}", name(&p));
                        continue;
                    }
                };
                let dt = cpu() - t;
                let struts_max = *g.report.struts_per_layer.iter().max().unwrap_or(&0) as f64;
                let struts_total: f64 = g.report.struts_per_layer.iter().sum::<usize>() as f64;
                let edges: f64 = g.layers.iter().flat_map(|l| &l.strokes).map(|s| s.points.len() as f64 - 1.0).sum();
                let length: f64 = g.layers.iter().flat_map(|l| &l.strokes).map(|s| s.points.windows(2).map(|w| w[0].distance(w[1])).sum::<f64>()).sum();
                let odd: f64 = g.layers.iter().map(|l| weft::paths::build_graph(l, 0.005).odd_nodes() as f64).sum();
                let r = |a: f64, b: f64| if b > 0.0 { a / b } else { f64::NAN };
                let per = if what == "lattice" { dt / est.get("generated_struts") / layers as f64 } else { 0.0 };
                if what == "lattice" {
                    println!(
                    "{side:>5} {:<18} {:<5} est/real struts {:.2} total {:.2} edges {:.2} length {:.2} odd {:.2} | {:.3} s, {:.2} µs/generated strut, est {:.3} s ({:.2}×) bytes {:.0} MB",
                    name(&p),
                    if contour { "disc" } else { "rect" },
                    r(est.get("struts"), struts_max),
                    r(est.get("struts_total"), struts_total),
                    r(est.get("edges"), edges),
                    r(est.get("length_mm"), length),
                    r(est.get("odd_nodes"), odd),
                    dt,
                    per * 1e6,
                    est.seconds,
                    r(est.seconds, dt),
                    est.bytes / 1e6,
                );
                }
                if what == "paths" {
                    paths_row(&g.layers, &est, side, &name(&p), contour);
                }
            }
        }
    }
}

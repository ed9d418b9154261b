//! Issue 7 for the lattice job: every stage (lattice, paths, nonplanar) states its work before
//! doing it, the statement matches what the run makes, hostile inputs are refused before
//! anything big is allocated (naming the number, the limit and the fix), and every stage's
//! cost grows linearly with the domain.

use weft::budget::{Estimate, Plan, MAX_STAGE_BYTES};
use weft::design::Job;
use weft::geom::{DVec2, DVec3, Feature, Mesh, Pass, Path, StrokeLayer, Toolpath};
use weft::kinds::lattice::{lattice_strokes, LatticeJob};
use weft::kinds::{Product, Registry};
use weft::lattice::{self, Domain, DomainSize, Options, Pattern, MAX_STRUTS_PER_LAYER};
use weft::nonplanar::{self, Surface, SurfaceSize};
use weft::paths::{self, Method, Order, MAX_GIPPO_STEPS};
use weft::pipeline::{Cache, Ctx, Files};
use weft::testgen::lattice as gen;
use weft::Design;

/// The stated factor: every estimated count is within 0.5×–2× of the real one.
const FACTOR: f64 = 2.0;

fn example(name: &str) -> Design {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples").join(format!("{name}.json"));
    Design::from_json(name, &std::fs::read_to_string(path).unwrap()).unwrap()
}

fn set(d: &Design, assignments: &[&str]) -> Design {
    let a: Vec<String> = assignments.iter().map(|s| s.to_string()).collect();
    d.with_overrides(&a).unwrap_or_else(|e| panic!("{}: {e}", d.name))
}

/// The job's estimates, and what its run makes: (struts per layer, toolpath segments).
fn estimate_and_run(design: &Design) -> (Vec<Estimate>, Vec<f64>, f64) {
    let registry = Registry::builtin();
    let kind = registry.get("lattice").unwrap();
    let files = Files::new();
    let mut cache = Cache::new();
    let mut quiet = |_: &str, _: f32| {};
    let mut ctx = Ctx::new(design, &files, &mut cache, &mut quiet);
    let est = kind.estimate(&mut ctx).unwrap_or_else(|e| panic!("{}: {e}", design.name));
    let Product::Toolpath(tp) = kind.run(&mut ctx).unwrap_or_else(|e| panic!("{}: {e}", design.name)) else {
        panic!("{}: a lattice job makes a toolpath", design.name)
    };
    let lattice = ctx.reports.iter().find(|r| r.stage == "lattice").expect("a lattice report");
    let struts: Vec<f64> = lattice.data["struts_per_layer"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
    (est, struts, tp.point_count() as f64)
}

fn within(name: &str, what: &str, est: f64, real: f64) {
    let r = est / real;
    assert!((1.0 / FACTOR..=FACTOR).contains(&r), "{name}: {what} estimated {est:.0}, real {real:.0} (×{r:.2}), outside 1/{FACTOR}–{FACTOR}");
}

/// Checks the chained estimates of `design` against its run; returns the ratios printed.
fn check(design: &Design) {
    let (est, struts, segments) = estimate_and_run(design);
    let names: Vec<&str> = est.iter().map(|e| e.stage).collect();
    let j: LatticeJob = design.job.settings().unwrap();
    assert_eq!(names, if j.nonplanar.is_some() { vec!["lattice", "paths", "nonplanar"] } else { vec!["lattice", "paths"] }, "{}", design.name);
    let (lat, last) = (&est[0], est.last().unwrap());
    let total: f64 = struts.iter().sum();
    let max = struts.iter().cloned().fold(0.0, f64::max);
    within(&design.name, "struts (all layers)", lat.get("struts_total"), total);
    within(&design.name, "struts (densest layer)", lat.get("struts"), max);
    within(&design.name, "layers", lat.get("layers"), struts.len() as f64);
    within(&design.name, "toolpath segments", last.get("segments"), segments);
    let plan = Plan::new(est.clone());
    assert!(plan.refused.is_none(), "{}: {:?}", design.name, plan.refused);
    assert_eq!(plan.segments, last.get("segments"));
    println!(
        "{:<32} struts ×{:.2} (densest ×{:.2})  segments ×{:.2}  ({:.0} real)  est {:.2} s {:.0} MB",
        design.name,
        lat.get("struts_total") / total,
        lat.get("struts") / max,
        last.get("segments") / segments,
        segments,
        plan.seconds,
        plan.peak_bytes / 1e6
    );
}

#[test]
fn every_lattice_example_is_estimated_within_the_factor() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples");
    let mut names: Vec<String> =
        std::fs::read_dir(dir).unwrap().filter_map(|e| e.ok()?.file_name().into_string().ok()?.strip_suffix(".json").map(String::from)).collect();
    names.sort();
    let mut checked = 0;
    for name in names {
        let d = example(&name);
        if d.job.kind() != "lattice" {
            continue;
        }
        check(&d);
        checked += 1;
    }
    assert!(checked >= 9, "{checked} lattice examples");
}

#[test]
fn held_out_designs_are_estimated_within_the_factor() {
    let hc = example("honeycomb-10mm");
    for (name, sets) in [
        (
            "voronoi-disc-continuous",
            &[
                "job.lattice.pattern={\"kind\":\"voronoi\",\"density_per_mm2\":1.5}",
                "job.domain={\"kind\":\"disc\",\"diameter_mm\":30}",
                "job.lattice.contour=true",
                "job.paths.method=continuous",
            ][..],
        ),
        (
            "penrose-tensile-euler",
            &[
                "job.lattice.pattern={\"kind\":\"penrose\",\"cell_size_mm\":0.8}",
                "job.domain={\"kind\":\"tensile_specimen\",\"width_mm\":15,\"length_mm\":20,\"handle_length_mm\":4}",
                "job.lattice.layers=3",
                "job.lattice.rotation_deg=30",
                "job.paths.method=euler",
                "job.paths.order=min_travel",
            ],
        ),
        (
            "triangles-woodpile-gippo",
            &[
                "job.lattice.pattern={\"kind\":\"triangle_grid\",\"cell_size_mm\":0.7}",
                "job.domain={\"kind\":\"rectangle\",\"width_mm\":25,\"height_mm\":12}",
                "job.lattice.layers=4",
                "job.lattice.rotation_deg=90",
                "job.paths.iterations=50",
            ],
        ),
        (
            "rectilinear-woodpile",
            &[
                "job.lattice.pattern={\"kind\":\"rectilinear\",\"strand_distance_mm\":0.5}",
                "job.domain.width_mm=20",
                "job.domain.height_mm=20",
                "job.lattice.layers=6",
                "job.lattice.rotation_deg=90",
                "job.paths.method=euler",
            ],
        ),
        (
            "arrowhead-override-disc",
            &[
                "job.lattice.pattern={\"kind\":\"arrowhead\",\"cell_width_mm\":1.5,\"cell_height_mm\":1.2}",
                "job.lattice.overrides=[{\"layer\":1,\"pattern\":{\"kind\":\"square_grid\",\"cell_size_mm\":0.9}}]",
                "job.domain={\"kind\":\"disc\",\"diameter_mm\":20}",
                "job.lattice.layers=2",
                "job.lattice.contour=true",
                "job.paths.iterations=60",
            ],
        ),
        (
            "snub-on-cylinder",
            &[
                "job.lattice.pattern={\"kind\":\"snub_square\",\"cell_size_mm\":0.9}",
                "job.domain.width_mm=20",
                "job.domain.height_mm=20",
                "job.lattice.layers=3",
                "job.paths.method=euler",
                "job.nonplanar={\"surface\":{\"kind\":\"cylinder\",\"radius_mm\":15}}",
            ],
        ),
        (
            "honeycomb-in-a-sphere",
            &[
                "job.domain={\"kind\":\"solid\"}",
                "job.input={\"builtin\":{\"shape\":\"sphere\",\"radius\":5,\"segments\":48}}",
                "job.lattice.pattern.hexagon_radius_mm=0.8",
                "job.lattice.rotation_deg=30",
                "job.lattice.contour=true",
                "job.paths.iterations=30",
            ],
        ),
        (
            "reentrant-on-a-sphere-mesh",
            &[
                "job.lattice.pattern={\"kind\":\"reentrant_honeycomb\",\"cell_width_mm\":1.6,\"cell_height_mm\":1.6}",
                "job.domain={\"kind\":\"disc\",\"diameter_mm\":24}",
                "job.lattice.layers=3",
                "job.paths.method=continuous",
                "job.paths.order=min_travel",
                "job.nonplanar={\"surface\":{\"kind\":\"mesh\"},\"max_segment_mm\":0.4}",
                "job.surface_input={\"builtin\":{\"shape\":\"sphere\",\"radius\":20,\"segments\":64}}",
            ],
        ),
    ] {
        let mut d = set(&hc, sets);
        d.name = name.into();
        check(&d);
    }
}

// ---------------------------------------------------------------------------------------
// Hostile cases: refused by the estimate, before the work allocates anything.

fn lattice_error(domain: Domain, pattern: Pattern, layers: u32, rotation: f64) -> weft::budget::OverBudget {
    let o = Options { pattern, layers, rotation_deg: rotation, ..Options::default() };
    // The planar estimate refuses first (the job checks it before building the layers).
    let planned = lattice::estimate(&DomainSize::planar(&domain, &o), &o, 0.2).check().unwrap_err();
    // generate() refuses the same on the layers (cheap here: one small polygon per layer).
    let layers = lattice::planar_domains(&domain, &o).unwrap();
    match lattice::generate(&layers, &o, 0.2, 1, &mut |_| {}) {
        // The same limit and fix; the number from the actual polygons (a disc's is inscribed).
        Err(lattice::Error::OverBudget(e)) => {
            assert_eq!((&e.what, e.limit, &e.fix), (&planned.what, planned.limit, &planned.fix));
            assert!((e.value / planned.value - 1.0).abs() < 0.01, "{e} / {planned}");
        }
        other => panic!("not refused: {:?}", other.map(|l| l.report)),
    }
    planned
}

/// The number after `marker` in `text` ("use a hexagon radius ≥ 1.6 mm" → 1.6).
fn number_after(text: &str, marker: &str) -> f64 {
    let rest = &text[text.find(marker).unwrap_or_else(|| panic!("no '{marker}' in '{text}'")) + marker.len()..];
    rest.trim_start().split(|c: char| !(c.is_ascii_digit() || c == '.')).next().unwrap().parse().unwrap()
}

#[test]
fn huge_domains_and_tiny_cells_are_refused_with_the_cell_size_that_fits() {
    // A 2 m square of 0.92 mm hexagons: 5.5M struts on the layer.
    let e = lattice_error(Domain::Rectangle { width_mm: 2000.0, height_mm: 2000.0 }, Pattern::Honeycomb { hexagon_radius_mm: 0.92 }, 1, 0.0);
    let msg = e.to_string();
    assert!(msg.starts_with("struts on one layer would be about 5."), "{msg}");
    assert!(msg.contains("limit 2M: use a hexagon radius ≥ "), "{msg}");
    assert_eq!(e.limit, MAX_STRUTS_PER_LAYER as f64);
    let r = number_after(&msg, "radius ≥");
    assert!(r > 0.92 && r < 2.0, "{msg}");
    // The suggested radius fits (and is not far above what fits).
    let fits = |r: f64| {
        let o = Options { pattern: Pattern::Honeycomb { hexagon_radius_mm: r }, ..Options::default() };
        let d = Domain::Rectangle { width_mm: 2000.0, height_mm: 2000.0 };
        lattice::estimate(&DomainSize::planar(&d, &o), &o, 0.2).get("generated_struts") <= MAX_STRUTS_PER_LAYER as f64
    };
    assert!(fits(r) && !fits(r * 0.9), "{r}");

    // The finest allowed cells on a 100 mm disc.
    let e = lattice_error(Domain::Disc { diameter_mm: 100.0 }, Pattern::TriangleGrid { cell_size_mm: 0.05 }, 1, 0.0);
    assert!(e.to_string().contains("use cells ≥ "), "{e}");
    assert!(e.value > 5.0 * e.limit, "{e}");
    // Dense Voronoi on a 200 mm square: the density that fits.
    let e = lattice_error(Domain::Rectangle { width_mm: 200.0, height_mm: 200.0 }, Pattern::Voronoi { density_per_mm2: 100.0 }, 1, 0.0);
    let msg = e.to_string();
    let rho = number_after(&msg, "at most");
    assert!(rho > 10.0 && rho < 20.0, "{msg}");
    // Unit cells of both sizes.
    let e = lattice_error(Domain::Rectangle { width_mm: 500.0, height_mm: 500.0 }, Pattern::Arrowhead { cell_width_mm: 0.2, cell_height_mm: 0.3 }, 1, 0.0);
    assert!(e.to_string().contains("use unit cells ≥ ") && e.to_string().contains(" × "), "{e}");
}

#[test]
fn many_layers_are_refused_on_memory_before_the_layers_are_built() {
    // 4000 turning layers of a 150 mm honeycomb: about 250M struts held at once.
    let e = lattice_error(Domain::Rectangle { width_mm: 150.0, height_mm: 150.0 }, Pattern::Honeycomb { hexagon_radius_mm: 0.5 }, 4000, 7.0);
    let msg = e.to_string();
    assert!(msg.starts_with("its peak memory would be about "), "{msg}");
    assert!(msg.contains("GiB, limit 1.25 GiB: use larger cells, fewer layers or a smaller domain"), "{msg}");
    assert_eq!(e.limit, MAX_STAGE_BYTES);

    // Through the job: refused by the lattice stage before the domains stage builds 4000
    // copies of a 2 m disc (8192 points each, 0.5 GB).
    let d = set(
        &example("ball-burst-disc-48mm"),
        &["job.domain.diameter_mm=2000", "job.lattice.layers=4000", "job.lattice.rotation_deg=1", "job.lattice.pattern.hexagon_radius_mm=30"],
    );
    let registry = Registry::builtin();
    let kind = registry.get("lattice").unwrap();
    let files = Files::new();
    let mut cache = Cache::new();
    let mut quiet = |_: &str, _: f32| {};
    let mut ctx = Ctx::new(&d, &files, &mut cache, &mut quiet);
    let plan = Plan::new(kind.estimate(&mut ctx).unwrap());
    let (stage, why) = plan.refused.clone().expect("refused");
    assert_eq!(stage, "lattice");
    let err = match kind.run(&mut ctx) {
        Err(e) => e.to_string(),
        Ok(_) => panic!("ran"),
    };
    assert!(err.contains(&why.to_string()), "{err} / {why}");
}

#[test]
fn gippo_iterations_over_the_step_limit_are_refused_with_the_iterations_that_fit() {
    let o = Options { pattern: Pattern::Honeycomb { hexagon_radius_mm: 0.3 }, ..Options::default() };
    let d = Domain::Rectangle { width_mm: 120.0, height_mm: 120.0 };
    let strokes = lattice::generate(&lattice::planar_domains(&d, &o).unwrap(), &o, 0.2, 1, &mut |_| {}).unwrap().layers;
    let po = paths::Options { iterations: 100_000, ..paths::Options::default() };
    // 100,000 iterations × about 190k struts: 19G steps.
    let e = match paths::optimise(&strokes, &po, 0.2, 1, &mut |_| {}) {
        Err(paths::Error::OverBudget(e)) => e,
        other => panic!("not refused: {:?}", other.map(|o| o.report.layers.len())),
    };
    let msg = e.to_string();
    assert!(msg.starts_with("GIPPO steps (iterations × struts) would be about "), "{msg}");
    assert!(msg.contains(", limit 5G: use at most "), "{msg}");
    assert_eq!(e.limit, MAX_GIPPO_STEPS);
    let most = number_after(&msg, "use at most");
    assert!((10.0..100_000.0).contains(&most), "{msg}");
    // The job's plan says the same before any stage runs.
    let est = paths::estimate(&paths::Work::of_layers(&strokes), &po);
    assert_eq!(est.check().unwrap_err(), e);
}

/// `layers` layers of `rows` straight paths of `length` mm (a big domain, few points).
fn long_paths(layers: usize, rows: usize, length: f64) -> Toolpath {
    Toolpath {
        passes: (0..layers)
            .map(|i| {
                let z = 0.2 * (i + 1) as f64;
                let paths = (0..rows)
                    .map(|k| {
                        let y = -length / 2.0 + length * k as f64 / rows as f64;
                        Path::new(vec![DVec3::new(-length / 2.0, y, z), DVec3::new(length / 2.0, y, z)], Feature::Lattice, 0.2)
                    })
                    .collect();
                Pass::layer(z, 0.2, paths)
            })
            .collect(),
    }
}

#[test]
fn tiny_segments_on_a_big_domain_are_refused_with_the_segment_that_fits() {
    // 28 layers of 200 mm: 5.6 M mm of lines, 0.01 mm segments: about 900M points.
    let tp = long_paths(28, 1000, 200.0);
    let o = nonplanar::Options { surface: Surface::Sphere { radius_mm: 400.0, center_mm: [0.0, 0.0, -380.0] }, max_segment_mm: 0.01 };
    let e = match nonplanar::project(&tp, None, &o) {
        Err(nonplanar::Error::OverBudget(e)) => e,
        other => panic!("not refused: {:?}", other.map(|p| p.report)),
    };
    let msg = e.to_string();
    assert!(msg.starts_with("its peak memory would be about "), "{msg}");
    assert!(msg.contains("limit 1.25 GiB: use a longest segment (max_segment_mm) ≥ "), "{msg}");
    let s = number_after(&msg, "max_segment_mm) ≥");
    let fits = nonplanar::estimate(&nonplanar::Work::of_toolpath(&tp), None, &nonplanar::Options { max_segment_mm: s, ..o.clone() });
    assert!(fits.check().is_ok(), "{s}: {:?}", fits.refused);
    // The generator's design at 100 × 400 mm² (the tester's 200 mm): refused by the plan.
    let d = Design::from_json("fine", &gen::projected_honeycomb_fine_segments(100)).unwrap();
    let registry = Registry::builtin();
    let files = Files::new();
    let mut cache = Cache::new();
    let mut quiet = |_: &str, _: f32| {};
    let mut ctx = Ctx::new(&d, &files, &mut cache, &mut quiet);
    let plan = Plan::new(registry.get("lattice").unwrap().estimate(&mut ctx).unwrap());
    assert_eq!(plan.refused.as_ref().map(|r| r.0.as_str()), Some("nonplanar"), "{plan:?}");
}

fn cone(n: usize) -> Mesh {
    weft::import::read_mesh("cone.stl", &gen::cone_fan_stl(n), &Default::default()).unwrap().mesh
}

#[test]
fn a_cone_fan_surface_is_bucketed_within_its_budget() {
    // 200k wedges: by bounding box about 10^9 bucket entries (out of memory); by the cells
    // each wedge crosses, within the budget, and the estimate says how many a cast tests.
    let mesh = cone(200_000);
    let s = SurfaceSize::of_mesh(&mesh, DVec2::splat(-20.0), DVec2::splat(20.0));
    assert_eq!(s.triangles, 200_000.0);
    assert!(s.entries <= (32 << 20) as f64, "{s:?}");
    assert!(s.candidates > 100.0, "{s:?}");
    // Projecting a small lattice on it works (and states its work first).
    let tp = long_paths(2, 20, 30.0);
    let o = nonplanar::Options { surface: Surface::Mesh, max_segment_mm: 0.5 };
    let r = nonplanar::project(&tp, Some(&mesh), &o).unwrap();
    assert_eq!(r.report.missed_points, 0);
}

// ---------------------------------------------------------------------------------------
// Scaling: the work at 4× the domain area against the work at 1× (candidates tested, nodes
// and cells visited, allocations, bytes allocated, peak heap: `crate::work`), against linear
// growth (quadratic growth gives 16). Counts, not times: the same verdict on any machine
// under any load.

/// Asserts linear growth of `run(k)` from k = n to k = 4n (inputs prepared by `prepare`,
/// not counted).
fn assert_linear<T: Sync>(name: &str, n: usize, prepare: impl Fn(usize) -> T, run: impl Fn(&T) + Sync) {
    let (small, big) = (prepare(n), prepare(4 * n));
    crate::work::assert_linear_run(name, 4.0, &small, &big, run);
}

/// The strokes of a generator's design.
fn strokes_of(json: &str) -> Vec<StrokeLayer> {
    let d = Design::from_json("scaling", json).unwrap();
    lattice_strokes(&d, &Files::new()).unwrap()
}

fn paths_options(json: &str) -> paths::Options {
    let j: LatticeJob = Design::from_json("scaling", json).unwrap().job.settings().unwrap();
    j.paths
}

#[test]
fn lattice_generation_scales_linearly() {
    assert_linear(
        "lattice (honeycomb 0.2 mm)",
        // 400 → 1 600 mm², 20 layers (identical layers are made once): about 0.11M → 0.45M
        // struts.
        1,
        |n| {
            let d = Design::from_json("s", &gen::fine_honeycomb_design(n)).unwrap();
            let j: LatticeJob = d.job.settings().unwrap();
            (lattice::planar_domains(&j.domain, &j.lattice).unwrap(), j.lattice)
        },
        |(domains, o)| drop(lattice::generate(domains, o, 0.2, 1, &mut |_| {}).unwrap()),
    );
}

#[test]
fn path_methods_scale_linearly() {
    // 400 → 1 600 mm². (In time, GIPPO's steps grow up to 3× dearer from a few 100k struts
    // on, where every path's random start is a cache miss: stated by the estimate, measured
    // by `weft bench --scaling`; the work per step stays the same.)
    for (name, n, make, method, order, iterations) in [
        ("paths gippo_max (20 iterations)", 1, gen::fine_honeycomb_design as fn(usize) -> String, Method::GippoMax, Order::LongestFirst, 20),
        ("paths euler", 1, gen::fine_honeycomb_euler, Method::Euler, Order::LongestFirst, 1),
        ("paths euler + min_travel (nearest neighbour, 2-opt)", 1, gen::fine_honeycomb_euler, Method::Euler, Order::MinTravel, 1),
        ("paths continuous (Voronoi: matching and its 2-opt)", 1, gen::voronoi_continuous_design, Method::Continuous, Order::LongestFirst, 1),
    ] {
        assert_linear(
            name,
            n,
            |n| {
                let json = make(n);
                // The exact pairing is cubic but capped per layer by its estimated time
                // (`exact_pairing_seconds`): the linear part is the heuristic's.
                let o = paths::Options { method, order, iterations, exact_pairing_seconds: 0.0, ..paths_options(&json) };
                (strokes_of(&json), o)
            },
            |(strokes, o)| drop(paths::optimise(strokes, o, 0.2, 1, &mut |_| {}).unwrap()),
        );
    }
}

/// The toolpath of a generator's projected design, before projection, and its options.
fn planar_toolpath(n: usize) -> (Toolpath, nonplanar::Options) {
    let json = gen::projected_honeycomb_design(n);
    let d = Design::from_json("scaling", &json).unwrap();
    let mut j: LatticeJob = d.job.settings().unwrap();
    let o = j.nonplanar.take().unwrap();
    let d = Design { job: Job::new("lattice", &j), ..d };
    let strokes = lattice_strokes(&d, &Files::new()).unwrap();
    (paths::optimise(&strokes, &j.paths, 0.2, 1, &mut |_| {}).unwrap().toolpath, o)
}

#[test]
fn projection_scales_linearly() {
    assert_linear("nonplanar sphere", 2, planar_toolpath, |(tp, o)| drop(nonplanar::project(tp, None, o).unwrap()));
    // A mesh surface under the whole domain: a UV sphere whose triangles grow with the area.
    assert_linear(
        "nonplanar mesh",
        2,
        |n| {
            let (tp, _) = planar_toolpath(n);
            let r = 30.0 * (n as f64).sqrt();
            let mut mesh = weft::geom::shapes::uv_sphere(r, (48.0 * (n as f64).sqrt()) as u32);
            mesh.translate(DVec3::new(0.0, 0.0, -2.0 * r + 5.0));
            (tp, mesh, nonplanar::Options { surface: Surface::Mesh, max_segment_mm: 0.25 })
        },
        |(tp, mesh, o)| drop(nonplanar::project(tp, Some(mesh), o).unwrap()),
    );
    // The cone fan: a fixed lattice on fans of n and 4n wedges (each cast tests the wedges
    // crossing its cell: linear in the wedges). Was 15× in time from 20k to 80k wedges (and
    // out of memory from about 100k).
    let tp = long_paths(2, 40, 40.0);
    assert_linear("nonplanar cone fan", 5_000, cone, |mesh| {
        drop(nonplanar::project(&tp, Some(mesh), &nonplanar::Options { surface: Surface::Mesh, max_segment_mm: 0.5 }).unwrap())
    });
}

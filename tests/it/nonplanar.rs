//! Non-planar projection: spheres, cylinders, meshes.

use weft::geom::shapes::Shape;
use weft::geom::{DVec3, Feature, Mesh, Pass, Path, Toolpath};
use weft::nonplanar::{project, Error, Options, Surface};

const H: f64 = 0.2;

/// `layers` layers of a flat grid: `n` lines along X and `n` along Y over [-half, half]².
fn grid(layers: usize, n: usize, half: f64) -> Toolpath {
    let mut tp = Toolpath::default();
    for i in 0..layers {
        let z = (i + 1) as f64 * H;
        let mut paths = Vec::new();
        for k in 0..n {
            let c = -half + 2.0 * half * k as f64 / (n - 1) as f64;
            if i % 2 == 0 {
                paths.push(Path::new(vec![DVec3::new(-half, c, z), DVec3::new(0.0, c, z), DVec3::new(half, c, z)], Feature::Lattice, 0.4));
            } else {
                paths.push(Path::new(vec![DVec3::new(c, -half, z), DVec3::new(c, half, z)], Feature::Lattice, 0.4));
            }
        }
        tp.passes.push(Pass::layer(z, H, paths));
    }
    tp
}

fn sphere(r: f64, c: [f64; 3]) -> Options {
    Options { surface: Surface::Sphere { radius_mm: r, center_mm: c }, max_segment_mm: 0.25 }
}

fn all_points(tp: &Toolpath) -> impl Iterator<Item = (usize, &DVec3)> {
    tp.passes.iter().enumerate().flat_map(|(i, l)| l.paths.iter().flat_map(move |p| p.points.iter().map(move |q| (i, q))))
}

/// Expected image of planar (x, y) on layer i over an analytic sphere.
fn on_sphere(x: f64, y: f64, i: usize, r: f64, c: DVec3) -> DVec3 {
    let p = DVec3::new(x, y, c.z + (r * r - (x - c.x).powi(2) - (y - c.y).powi(2)).sqrt());
    c + (p - c) / r * (r + (i + 1) as f64 * H)
}

#[test]
fn sphere_points_lie_on_offset_spheres() {
    let c = DVec3::new(1.0, -0.5, -8.0);
    let tp = grid(4, 9, 4.0);
    let out = project(&tp, None, &sphere(10.0, c.to_array())).unwrap();
    assert_eq!(out.report.missed_points, 0);
    assert_eq!(out.report.collisions, 0);
    for (i, q) in all_points(&out.toolpath) {
        let want = 10.0 + (i + 1) as f64 * H;
        assert!(((*q - c).length() - want).abs() < 1e-6, "layer {i}: {q}");
    }
    // Layers, paths and features are kept; heights too; z is the layer's top.
    assert_eq!(out.toolpath.passes.len(), 4);
    for (a, b) in tp.passes.iter().zip(&out.toolpath.passes) {
        assert_eq!(a.paths.len(), b.paths.len());
        assert_eq!(b.height, H);
        let top = b.paths.iter().flat_map(|p| &p.points).map(|p| p.z).fold(f64::NEG_INFINITY, f64::max);
        assert_eq!(b.z, top);
    }
    let [lo, hi] = out.report.z_range_mm;
    assert!((hi - (c.z + 10.0 + 4.0 * H)).abs() < 0.01, "{hi}");
    assert!(lo < hi - 0.5 && lo > c.z, "{lo}");
}

#[test]
fn segments_are_split_and_z_follows_the_surface() {
    let tp = grid(2, 3, 5.0);
    for max in [0.25, 0.1, 1.0] {
        let o = Options { max_segment_mm: max, ..sphere(8.0, [0.0, 0.0, -4.0]) };
        let out = project(&tp, None, &o).unwrap();
        for l in &out.toolpath.passes {
            for p in &l.paths {
                for w in p.points.windows(2) {
                    assert!(w[0].distance(w[1]) <= max + 1e-12, "{} > {max}", w[0].distance(w[1]));
                }
                // A 10 mm line over a sphere: Z rises then falls.
                let zs: Vec<f64> = p.points.iter().map(|q| q.z).collect();
                let top = zs.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
                assert!(top - zs[0] > 0.5 && top - zs[zs.len() - 1] > 0.5);
                assert!(p.points.len() as f64 >= 10.0 / max);
            }
        }
    }
}

#[test]
fn point_order_is_preserved() {
    let c = DVec3::new(0.0, 0.0, -6.0);
    let mut tp = grid(2, 4, 3.0);
    tp.passes[1].paths[2].speed_factor = 0.6;
    let out = project(&tp, None, &sphere(10.0, c.to_array())).unwrap();
    for (i, (a, b)) in tp.passes.iter().zip(&out.toolpath.passes).enumerate() {
        for (pa, pb) in a.paths.iter().zip(&b.paths) {
            assert_eq!(pa.feature, pb.feature);
            assert_eq!(pa.speed_factor, pb.speed_factor);
            assert_eq!(pa.width, pb.width);
            // Every input point appears, in order, as a subsequence of the output.
            let mut k = 0;
            for q in &pa.points {
                let want = on_sphere(q.x, q.y, i, 10.0, c);
                while k < pb.points.len() && pb.points[k].distance(want) > 1e-9 {
                    k += 1;
                }
                assert!(k < pb.points.len(), "point {q} missing or out of order");
            }
            assert!(pb.points[0].distance(on_sphere(pa.points[0].x, pa.points[0].y, i, 10.0, c)) < 1e-9);
            let last = pa.points.last().unwrap();
            assert!(pb.points.last().unwrap().distance(on_sphere(last.x, last.y, i, 10.0, c)) < 1e-9);
        }
    }
}

#[test]
fn cylinder_points_lie_on_offset_cylinders() {
    let tp = grid(3, 7, 4.0);
    let o = Options { surface: Surface::Cylinder { radius_mm: 6.0, axis_z_mm: -3.0 }, max_segment_mm: 0.2 };
    let out = project(&tp, None, &o).unwrap();
    assert_eq!(out.report.missed_points, 0);
    assert_eq!(out.report.collisions, 0);
    for (i, q) in all_points(&out.toolpath) {
        let r = (q.y * q.y + (q.z + 3.0) * (q.z + 3.0)).sqrt();
        assert!((r - (6.0 + (i + 1) as f64 * H)).abs() < 1e-6, "layer {i}: {q}");
    }
    // Lines along X stay at constant Z (the cylinder lies along X); lines along Y do not.
    let l0 = &out.toolpath.passes[0];
    for p in &l0.paths {
        assert!(p.points.iter().all(|q| (q.z - p.points[0].z).abs() < 1e-12));
    }
    let l1 = &out.toolpath.passes[1];
    assert!(l1.paths.iter().all(|p| p.points.iter().any(|q| (q.z - p.points[0].z).abs() > 0.5)));
}

/// A flat square mesh of `n × n` cells over [-s, s]², tilted: z = z0 + slope · x.
fn plane_mesh(s: f64, n: u32, z0: f64, slope: f64) -> Mesh {
    let mut m = Mesh::default();
    for j in 0..=n {
        for i in 0..=n {
            let x = -s + 2.0 * s * i as f64 / n as f64;
            let y = -s + 2.0 * s * j as f64 / n as f64;
            m.vertices.push([x as f32, y as f32, (z0 + slope * x) as f32]);
        }
    }
    let id = |i: u32, j: u32| j * (n + 1) + i;
    for j in 0..n {
        for i in 0..n {
            m.triangles.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            m.triangles.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    m
}

#[test]
fn flat_and_tilted_plane_meshes() {
    let tp = grid(3, 5, 4.0);
    let o = Options { surface: Surface::Mesh, max_segment_mm: 0.25 };
    // Flat plane at z = 1: layers at 1 + (i + 1) h, X and Y unchanged.
    let flat = plane_mesh(6.0, 7, 1.0, 0.0);
    let out = project(&tp, Some(&flat), &o).unwrap();
    assert_eq!(out.report.missed_points, 0);
    for (i, q) in all_points(&out.toolpath) {
        assert!((q.z - (1.0 + (i + 1) as f64 * H)).abs() < 1e-6, "{q}");
    }
    // The input points keep their XY exactly.
    assert_eq!(out.toolpath.passes[0].paths[0].points[0].truncate(), tp.passes[0].paths[0].points[0].truncate());
    // Tilted 30°: every point is (i + 1) h from the plane along its normal.
    let slope = libm::tan(std::f64::consts::PI / 6.0);
    let tilted = plane_mesh(6.0, 7, 0.5, slope);
    let out = project(&tp, Some(&tilted), &o).unwrap();
    assert_eq!(out.report.missed_points, 0);
    assert_eq!(out.report.collisions, 0);
    let n = DVec3::new(-slope, 0.0, 1.0).normalize();
    for (i, q) in all_points(&out.toolpath) {
        let dist = (*q - DVec3::new(0.0, 0.0, 0.5)).dot(n);
        assert!((dist - (i + 1) as f64 * H).abs() < 1e-5, "layer {i}: {q} at {dist}");
    }
    for l in &out.toolpath.passes {
        for p in &l.paths {
            for w in p.points.windows(2) {
                assert!(w[0].distance(w[1]) <= 0.25 + 1e-12);
            }
        }
    }
}

#[test]
fn sphere_mesh_matches_the_analytic_sphere() {
    let r = 10.0;
    let segments = 128;
    let mesh = Shape::Sphere { radius: r, segments }.mesh(); // centred on (0, 0, r)
    let tp = grid(3, 7, 5.0);
    let a = project(&tp, None, &sphere(r, [0.0, 0.0, r])).unwrap();
    let m = project(&tp, Some(&mesh), &Options { surface: Surface::Mesh, max_segment_mm: 0.25 }).unwrap();
    assert_eq!(m.report.missed_points, 0);
    assert_eq!(m.report.collisions, 0);
    // Chord error (sagitta) of the facets, both directions.
    let sagitta = r * (1.0 - libm::cos(std::f64::consts::PI / segments as f64));
    let c = DVec3::new(0.0, 0.0, r);
    let mut worst: f64 = 0.0;
    for (i, q) in all_points(&m.toolpath) {
        let want = r + (i + 1) as f64 * H;
        let err = ((*q - c).length() - want).abs();
        worst = worst.max(err);
        assert!(err <= 2.0 * sagitta + 1e-4, "layer {i}: {q} off by {err} (sagitta {sagitta})");
    }
    assert!(worst > 0.0);
    // The input points map to nearly the same places.
    for (la, lm) in a.toolpath.passes.iter().zip(&m.toolpath.passes) {
        for (pa, pm) in la.paths.iter().zip(&lm.paths) {
            assert!(pa.points[0].distance(pm.points[0]) <= 4.0 * sagitta + 1e-3);
            assert!(pa.points.last().unwrap().distance(*pm.points.last().unwrap()) <= 4.0 * sagitta + 1e-3);
        }
    }
}

#[test]
fn missed_points_are_counted_and_kept_at_the_lowest_hit() {
    // A 10 mm lattice over a 3 mm sphere: the line ends miss.
    let tp = grid(1, 3, 5.0);
    let c = DVec3::new(0.0, 0.0, 0.0);
    let out = project(&tp, None, &sphere(3.0, c.to_array())).unwrap();
    // Points of 3 lines at y = -5, 0, 5: all 6 ends miss, the middles at y = ±5 too.
    assert_eq!(out.report.missed_points, 8);
    let floor = 3.0; // only (0, 0) hits: its surface Z is the lowest hit
    for p in &out.toolpath.passes[0].paths {
        let first = p.points[0];
        assert_eq!(first, DVec3::new(-5.0, first.y, floor + H));
    }
    // Everything missing is an error.
    let far = sphere(1.0, [50.0, 0.0, 0.0]);
    assert_eq!(project(&tp, None, &far).unwrap_err(), Error::NothingOver);
}

#[test]
fn approach_routes_are_projected() {
    let mut tp = grid(1, 2, 3.0);
    // Second line reached along a route over the first one's end.
    tp.passes[0].paths[1].approach = Some(vec![DVec3::new(3.0, 0.0, H)]);
    let c = DVec3::new(0.0, 0.0, -5.0);
    let out = project(&tp, None, &sphere(10.0, c.to_array())).unwrap();
    let p = &out.toolpath.passes[0].paths[1];
    let route = p.approach.as_ref().unwrap();
    // Legs (3,-3) → (3,0) → (-3,3) are split; the interior points form the route.
    assert!(route.len() > 10);
    let mut prev = *out.toolpath.passes[0].paths[0].points.last().unwrap();
    for q in route.iter().chain(std::iter::once(&p.points[0])) {
        assert!(((*q - c).length() - (10.0 + H)).abs() < 1e-6);
        assert!(prev.distance(*q) <= 0.25 + 1e-12);
        prev = *q;
    }
    assert!(route.iter().any(|q| q.distance(on_sphere(3.0, 0.0, 0, 10.0, c)) < 1e-9));
    assert_eq!(out.toolpath.passes[0].paths[0].approach, None);
}

#[test]
fn collisions_are_counted_when_segments_are_long() {
    // A coarse split on a small sphere: chords of layer 0 cut into the sphere.
    let tp = grid(1, 3, 2.5);
    let o = Options { max_segment_mm: 10.0, ..sphere(3.0, [0.0, 0.0, 0.0]) };
    let out = project(&tp, None, &o).unwrap();
    assert!(out.report.collisions > 0);
    let fine = project(&tp, None, &sphere(3.0, [0.0, 0.0, 0.0])).unwrap();
    assert_eq!(fine.report.collisions, 0);
}

#[test]
fn bad_options_and_missing_mesh() {
    let tp = grid(1, 2, 1.0);
    let bad = |o: Options| match project(&tp, None, &o) {
        Err(Error::BadOptions { problems }) => problems[0].path.split(".0").next().unwrap().to_string(),
        other => panic!("{other:?}"),
    };
    assert_eq!(bad(Options { max_segment_mm: 0.001, ..sphere(5.0, [0.0; 3]) }), "max_segment_mm");
    assert_eq!(bad(Options { max_segment_mm: 11.0, ..sphere(5.0, [0.0; 3]) }), "max_segment_mm");
    assert_eq!(bad(Options { max_segment_mm: f64::NAN, ..sphere(5.0, [0.0; 3]) }), "max_segment_mm");
    assert_eq!(bad(sphere(0.0, [0.0; 3])), "surface.radius_mm");
    assert_eq!(bad(sphere(5.0, [f64::INFINITY, 0.0, 0.0])), "surface.center_mm");
    assert_eq!(bad(Options { surface: Surface::Cylinder { radius_mm: -1.0, axis_z_mm: 0.0 }, max_segment_mm: 0.25 }), "surface.radius_mm");
    let o = Options { surface: Surface::Mesh, max_segment_mm: 0.25 };
    assert_eq!(project(&tp, None, &o).unwrap_err(), Error::NoSurfaceMesh);
    assert_eq!(project(&tp, Some(&Mesh::default()), &o).unwrap_err(), Error::NoSurfaceMesh);
    // Options parse with the default segment length.
    let o: Options = serde_json::from_str(r#"{"surface": {"kind": "sphere", "radius_mm": 20, "center_mm": [0, 0, -15]}}"#).unwrap();
    assert_eq!(o.max_segment_mm, weft::nonplanar::DEFAULT_MAX_SEGMENT_MM);
}

#[test]
fn deterministic() {
    let tp = grid(3, 6, 5.0);
    let mesh = Shape::Sphere { radius: 8.0, segments: 48 }.mesh();
    let o = Options { surface: Surface::Mesh, max_segment_mm: 0.3 };
    let a = project(&tp, Some(&mesh), &o).unwrap();
    let b = project(&tp, Some(&mesh), &o).unwrap();
    assert_eq!(a.toolpath, b.toolpath);
    assert_eq!(a.report, b.report);
    let s = project(&tp, None, &sphere(8.0, [0.0, 0.0, 8.0])).unwrap();
    assert_eq!(s.toolpath, project(&tp, None, &sphere(8.0, [0.0, 0.0, 8.0])).unwrap().toolpath);
    // And the result writes as G-code.
    let g = weft::gcode::write_gcode(&a.toolpath, &weft::gcode::Options::default()).unwrap();
    assert_eq!(g.stats.layers, 3);
}

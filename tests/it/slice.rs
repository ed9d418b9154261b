//! Integration tests of `weft::slice` on built-in and hand-made (dirty) meshes.

use std::f64::consts::PI;
use weft::geom::shapes::Shape;
use weft::geom::{DVec2, DVec3, Feature, Mesh, Polygon};
use weft::slice::{self, Error, Options, Sliced};

fn run(mesh: &Mesh, o: &Options) -> Sliced {
    slice::slice(mesh, o, &mut |_| {}).expect("slices")
}

fn cube(size: [f64; 3]) -> Mesh {
    Shape::Cube { size }.mesh()
}

fn moved(mut m: Mesh, d: [f64; 3]) -> Mesh {
    m.translate(DVec3::from_array(d));
    m
}

fn layer_area(p: &[Polygon]) -> f64 {
    p.iter().map(|r| r.area()).sum()
}

/// Every triangle with its own three vertices (an STL-like soup).
fn soup(m: &Mesh) -> Mesh {
    let mut out = Mesh::default();
    for t in &m.triangles {
        let b = out.vertices.len() as u32;
        for &i in t {
            out.vertices.push(m.vertices[i as usize]);
        }
        out.triangles.push([b, b + 1, b + 2]);
    }
    out
}

fn reversed(mut m: Mesh) -> Mesh {
    for t in &mut m.triangles {
        t.swap(1, 2);
    }
    m
}

fn dist_to_segment(p: DVec2, a: DVec2, b: DVec2) -> f64 {
    let ab = b - a;
    let t = if ab.length_squared() > 0.0 { ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0) } else { 0.0 };
    p.distance(a + ab * t)
}

fn inside_or_near(poly: &Polygon, p: DVec2, tol: f64) -> bool {
    let rings = std::iter::once(&poly.outer).chain(poly.holes.iter());
    let mut inside = false;
    let mut near = false;
    for r in rings {
        let n = r.len();
        for i in 0..n {
            let (a, b) = (r[i], r[(i + 1) % n]);
            if (a.y > p.y) != (b.y > p.y) && p.x < a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x) {
                inside = !inside;
            }
            if dist_to_segment(p, a, b) <= tol {
                near = true;
            }
        }
    }
    inside || near
}

#[test]
fn cube_20mm_has_100_square_layers() {
    let s = run(&cube([20.0, 20.0, 20.0]), &Options::default());
    assert_eq!(s.layers.len(), 100);
    assert_eq!(s.report.layers, 100);
    assert_eq!(s.toolpath.passes.len(), 100);
    for (i, l) in s.layers.iter().enumerate() {
        assert_eq!(l.regions.len(), 1, "layer {i}");
        assert!(l.regions[0].holes.is_empty());
        assert!((l.regions[0].area() - 400.0).abs() < 1e-6, "layer {i}: {}", l.regions[0].area());
        assert!((l.z - 0.2 * (i + 1) as f64).abs() < 1e-9);
        assert!((l.slice_z - (l.z - 0.1)).abs() < 1e-9);
        assert!(weft::geom::signed_area(&l.regions[0].outer) > 0.0, "outer CCW");
    }
    assert_eq!(s.report.gaps_closed, 0);
    assert_eq!(s.report.open_contours_dropped, 0);
    assert_eq!(s.report.layers_with_overlaps, 0);
    let tl = &s.toolpath.passes[5];
    assert!((tl.z - 1.2).abs() < 1e-9 && (tl.height - 0.2).abs() < 1e-12);
    for p in &tl.paths {
        assert_eq!(p.width, 0.4);
        assert_eq!(p.speed_factor, 1.0);
        assert!(p.points.iter().all(|q| q.z == tl.z));
    }
}

#[test]
fn first_layer_height_is_honoured() {
    let o = Options { first_layer_height_mm: 0.3, ..Default::default() };
    let s = run(&cube([20.0, 20.0, 10.0]), &o);
    assert!((s.layers[0].z - 0.3).abs() < 1e-12 && (s.layers[0].height - 0.3).abs() < 1e-12);
    assert!((s.layers[1].z - 0.5).abs() < 1e-12 && (s.layers[1].height - 0.2).abs() < 1e-12);
    assert!((s.layers.last().unwrap().z - 9.9).abs() < 1e-9, "{}", s.layers.last().unwrap().z);
}

#[test]
fn sphere_layer_areas_follow_the_circle_formula() {
    let r = 10.0;
    let s = run(&Shape::Sphere { radius: r, segments: 256 }.mesh(), &Options::default());
    assert_eq!(s.layers.len(), 100);
    for l in &s.layers {
        let z = l.slice_z;
        let expect = PI * (r * r - (z - r) * (z - r));
        let got = layer_area(&l.regions);
        assert_eq!(l.regions.len(), 1);
        assert!((got - expect).abs() < 0.01 * expect + 0.3, "z {z}: {got} vs {expect}");
    }
}

#[test]
fn cylinder_gives_one_loop_per_layer() {
    let s = run(&Shape::Cylinder { radius: 8.0, height: 5.0, segments: 64 }.mesh(), &Options::default());
    assert_eq!(s.layers.len(), 25);
    for l in &s.layers {
        assert_eq!(l.regions.len(), 1);
        assert!(l.regions[0].holes.is_empty());
        // 64 facets; the cut through each facet's two triangles leaves a collinear midpoint,
        // removed unless micrometre rounding pushed it more than 1 µm off the line.
        let n = l.regions[0].outer.len();
        assert!((64..=72).contains(&n), "{n}");
    }
}

#[test]
fn open_box_still_slices_closed() {
    let mut m = cube([20.0, 20.0, 20.0]);
    m.triangles.drain(2..4); // the two top triangles
    let s = run(&m, &Options::default());
    assert_eq!(s.layers.len(), 100);
    for l in &s.layers {
        assert_eq!(l.regions.len(), 1);
        assert!((l.regions[0].area() - 400.0).abs() < 1e-6);
    }
    assert_eq!(s.report.open_contours_dropped, 0);
}

#[test]
fn small_gap_is_closed_and_reported() {
    // Move the +X face's two corner vertices at (+x, +y) by 0.02 mm in Y: every cut of the
    // +X face now ends 0.02 mm away from where the +Y face's cut starts.
    let mut m = cube([20.0, 20.0, 20.0]);
    let v2 = m.vertices[2];
    let v6 = m.vertices[6];
    m.vertices.push([v2[0], v2[1] + 0.02, v2[2]]); // 8
    m.vertices.push([v6[0], v6[1] + 0.02, v6[2]]); // 9
    assert_eq!(m.triangles[6], [1, 2, 6]);
    assert_eq!(m.triangles[7], [1, 6, 5]);
    m.triangles[6] = [1, 8, 9];
    m.triangles[7] = [1, 9, 5];
    let s = run(&m, &Options::default());
    assert_eq!(s.report.gaps_closed, 100);
    assert!((s.report.largest_gap_closed_mm - 0.02).abs() < 0.0015, "{}", s.report.largest_gap_closed_mm);
    assert_eq!(s.report.open_contours_dropped, 0);
    for l in &s.layers {
        assert_eq!(l.regions.len(), 1);
        assert!((l.regions[0].area() - 400.0).abs() < 0.5);
    }
    // With gap closing off, the same contours are dropped.
    let o = Options { gap_closing_mm: 0.01, ..Default::default() };
    let s = run(&m, &o);
    assert_eq!(s.report.gaps_closed, 0);
    assert_eq!(s.report.open_contours_dropped, 100);
    assert!(s.layers.iter().all(|l| l.regions.is_empty()));
}

#[test]
fn overlapping_cubes_are_unioned() {
    let mut m = cube([20.0, 20.0, 20.0]);
    m.append(&moved(cube([20.0, 20.0, 20.0]), [10.0, 0.0, 0.0]));
    let s = run(&m, &Options::default());
    assert_eq!(s.report.layers_with_overlaps, 100);
    for l in &s.layers {
        assert_eq!(l.regions.len(), 1);
        assert!((l.regions[0].area() - 600.0).abs() < 1e-6, "{}", l.regions[0].area());
    }
}

#[test]
fn duplicate_triangles_change_nothing() {
    let m = Shape::Sphere { radius: 6.0, segments: 48 }.mesh();
    let mut d = m.clone();
    d.append(&m);
    let mut s2 = soup(&m);
    s2.append(&soup(&m));
    let a = run(&m, &Options::default());
    let b = run(&d, &Options::default());
    let c = run(&s2, &Options::default());
    assert_eq!(a.layers, b.layers);
    assert_eq!(a.toolpath, b.toolpath);
    assert_eq!(a.layers, c.layers);
    assert_eq!(b.report, a.report);
    assert_eq!(b.report.layers_with_overlaps, 0);
}

#[test]
fn tube_has_a_hole() {
    let mut m = Shape::Cylinder { radius: 10.0, height: 4.0, segments: 128 }.mesh();
    m.append(&reversed(Shape::Cylinder { radius: 5.0, height: 4.0, segments: 128 }.mesh()));
    let s = run(&m, &Options::default());
    let ring = |r: f64| 0.5 * 128.0 * r * r * (2.0 * PI / 128.0).sin();
    for l in &s.layers {
        assert_eq!(l.regions.len(), 1);
        assert_eq!(l.regions[0].holes.len(), 1);
        assert!(weft::geom::signed_area(&l.regions[0].holes[0]) < 0.0, "hole CW");
        assert!((l.regions[0].area() - (ring(10.0) - ring(5.0))).abs() < 0.01);
    }
    // No toolpath point falls in the hole.
    for tl in &s.toolpath.passes {
        for p in &tl.paths {
            for q in &p.points {
                assert!(q.truncate().length() > 5.0 - 1e-6, "{q:?} in the hole");
            }
        }
    }
}

#[test]
fn solid_infill_covers_the_inner_area() {
    let o = Options { infill_density: 1.0, ..Default::default() };
    let s = run(&cube([20.0, 20.0, 4.0]), &o);
    let inner = (20.0 - 4.0 * 0.4) * (20.0 - 4.0 * 0.4);
    for tl in &s.toolpath.passes {
        let len: f64 = tl.paths.iter().filter(|p| p.feature == Feature::SolidInfill).map(|p| p.length()).sum();
        assert!((len * 0.4 - inner).abs() < 0.1 * inner, "z {}: {} vs {inner}", tl.z, len * 0.4);
        assert!(tl.paths.iter().all(|p| p.feature != Feature::Infill));
    }
}

#[test]
fn sparse_infill_between_solid_skins() {
    let o = Options::default(); // density 0.2, 3 solid layers
    let s = run(&cube([20.0, 20.0, 4.0]), &o);
    let n = s.toolpath.passes.len();
    assert_eq!(n, 20);
    let count = |i: usize, f: Feature| s.toolpath.passes[i].paths.iter().filter(|p| p.feature == f).count();
    for i in 0..n {
        let solid = i < 3 || i >= n - 3;
        assert_eq!(count(i, Feature::SolidInfill) > 0, solid, "layer {i}");
        assert_eq!(count(i, Feature::Infill) > 0, !solid, "layer {i}");
    }
    // Sparse: about density × inner area, plus the zig-zag connectors along the boundary.
    let len: f64 = s.toolpath.passes[10].paths.iter().filter(|p| p.feature == Feature::Infill).map(|p| p.length()).sum();
    let inner = 18.4 * 18.4;
    assert!(len * 0.4 > 0.2 * inner * 0.95 && len * 0.4 < 0.2 * inner * 1.3, "{}", len * 0.4);
}

#[test]
fn top_skin_of_a_step_is_solid() {
    // A 20 mm square base 2 mm tall with a 10 mm square tower on top, as two touching boxes.
    let mut m = cube([20.0, 20.0, 2.0]);
    m.append(&moved(cube([10.0, 10.0, 4.0]), [0.0, 0.0, 2.0]));
    let s = run(&m, &Options { solid_layers: 2, ..Default::default() });
    // Layer 8 (top at 1.8 mm) is within 2 layers of the base's top: its ring outside the tower
    // is solid, the part under the tower (covered above and below) is sparse.
    let l = &s.toolpath.passes[8];
    let solid: Vec<_> = l.paths.iter().filter(|p| p.feature == Feature::SolidInfill).collect();
    let sparse: Vec<_> = l.paths.iter().filter(|p| p.feature == Feature::Infill).collect();
    assert!(!solid.is_empty() && !sparse.is_empty());
    for p in &sparse {
        for q in &p.points {
            assert!(q.x.abs() <= 5.0 + 1e-6 && q.y.abs() <= 5.0 + 1e-6, "{q:?}");
        }
    }
}

#[test]
fn infill_angle_alternates() {
    let o = Options { infill_density: 1.0, infill_angle_deg: 30.0, ..Default::default() };
    let s = run(&cube([20.0, 20.0, 2.0]), &o);
    let dominant = |i: usize| {
        // Direction of the longest infill segment, in degrees modulo 180.
        let mut best = (0.0, 0.0);
        for p in s.toolpath.passes[i].paths.iter().filter(|p| p.feature == Feature::SolidInfill) {
            for w in p.points.windows(2) {
                let d = w[1] - w[0];
                let len = d.truncate().length();
                if len > best.0 {
                    best = (len, d.y.atan2(d.x).to_degrees().rem_euclid(180.0));
                }
            }
        }
        best.1
    };
    for i in 0..6 {
        let expect: f64 = if i % 2 == 0 { 30.0 } else { 120.0 };
        assert!((dominant(i) - expect).abs() < 0.01, "layer {i}: {}", dominant(i));
    }
}

#[test]
fn perimeter_count_and_order() {
    let o = Options { perimeters: 3, skirt_loops: 0, ..Default::default() };
    let s = run(&Shape::Cylinder { radius: 10.0, height: 2.0, segments: 64 }.mesh(), &o);
    for tl in &s.toolpath.passes {
        let per: Vec<_> = tl.paths.iter().filter(|p| matches!(p.feature, Feature::ExternalPerimeter | Feature::Perimeter)).collect();
        assert_eq!(per.len(), 3);
        assert_eq!(per[0].feature, Feature::Perimeter);
        assert_eq!(per[1].feature, Feature::Perimeter);
        assert_eq!(per[2].feature, Feature::ExternalPerimeter, "external last");
        for p in &per {
            assert_eq!(p.points.first(), p.points.last(), "closed loop");
        }
        // External perimeter centre line is half a width inside the wall.
        let r_ext = per[2].points.iter().map(|q| q.truncate().length()).fold(0.0, f64::max);
        assert!((r_ext - 9.8).abs() < 0.01, "{r_ext}");
        // Perimeters come before infill.
        let first_infill = tl.paths.iter().position(|p| matches!(p.feature, Feature::Infill | Feature::SolidInfill));
        assert!(first_infill.is_none_or(|k| k == 3));
    }
}

#[test]
fn toolpath_stays_inside_regions() {
    let mut m = Shape::Sphere { radius: 8.0, segments: 64 }.mesh();
    m.append(&moved(cube([6.0, 20.0, 5.0]), [6.0, 0.0, 0.0]));
    let s = run(&m, &Options::default());
    for (l, tl) in s.layers.iter().zip(&s.toolpath.passes) {
        // The skirt lies outside the part by design (slice::skirt_and_brim_around_the_first_layer).
        for p in tl.paths.iter().filter(|p| p.feature != Feature::Skirt) {
            for q in &p.points {
                let q2 = q.truncate();
                assert!(l.regions.iter().any(|r| inside_or_near(r, q2, 0.2 + 1e-6)), "layer z {} point {q2:?} outside", l.z);
            }
        }
    }
}

#[test]
fn vertices_exactly_on_cut_planes() {
    // Layer 0.25: cutting planes at 0.125 + 0.25 k, exact in f32 and f64.
    let o = Options { first_layer_height_mm: 0.25, layer_height_mm: 0.25, ..Default::default() };
    // Octahedron whose equator is exactly on the plane 5.125.
    let (a, h) = (6.0f32, 5.125f32);
    let m = Mesh {
        vertices: vec![[a, 0.0, h], [0.0, a, h], [-a, 0.0, h], [0.0, -a, h], [0.0, 0.0, 0.0], [0.0, 0.0, 2.0 * h]],
        triangles: vec![[0, 1, 5], [1, 2, 5], [2, 3, 5], [3, 0, 5], [1, 0, 4], [2, 1, 4], [3, 2, 4], [0, 3, 4]],
    };
    let s = run(&m, &o);
    let eq = s.layers.iter().find(|l| l.slice_z == 5.125).expect("plane at the equator");
    assert_eq!(eq.regions.len(), 1);
    assert!((eq.regions[0].area() - 2.0 * 36.0).abs() < 1e-6);
    assert_eq!(s.report.open_contours_dropped, 0);
    assert_eq!(s.report.gaps_closed, 0);

    // A box whose top is exactly on a plane, with a smaller box standing on it.
    let mut m = cube([20.0, 20.0, 5.125]);
    m.append(&moved(cube([10.0, 10.0, 5.0]), [0.0, 0.0, 5.125]));
    let s = run(&m, &o);
    let l = s.layers.iter().find(|l| l.slice_z == 5.125).unwrap();
    assert_eq!(l.regions.len(), 1);
    assert!((l.regions[0].area() - 400.0).abs() < 1e-6);
    for l in &s.layers {
        let expect = if l.slice_z <= 5.125 { 400.0 } else { 100.0 };
        assert!((layer_area(&l.regions) - expect).abs() < 1e-6, "z {}", l.slice_z);
    }
    assert_eq!(s.report.open_contours_dropped, 0);
    assert_eq!(s.report.gaps_closed, 0);
}

#[test]
fn rotated_copy_gives_the_same_areas() {
    let mut m = cube([20.0, 8.0, 6.0]);
    m.append(&moved(Shape::Cylinder { radius: 5.0, height: 9.0, segments: 40 }.mesh(), [7.0, 3.0, 0.0]));
    let mut r = m.clone();
    for v in &mut r.vertices {
        *v = [-v[1], v[0], v[2]];
    }
    let a = run(&m, &Options::default());
    let b = run(&r, &Options::default());
    assert_eq!(a.layers.len(), b.layers.len());
    for (la, lb) in a.layers.iter().zip(&b.layers) {
        assert_eq!(la.regions.len(), lb.regions.len());
        // Equal up to i_overlay snapping edge crossings to the micrometre grid.
        let (x, y) = (layer_area(&la.regions), layer_area(&lb.regions));
        assert!((x - y).abs() < 1e-3, "z {}: {x} vs {y}", la.z);
    }
    assert_eq!(a.report, b.report);
}

#[test]
fn inside_out_mesh_still_slices() {
    let s = run(&reversed(cube([20.0, 20.0, 2.0])), &Options::default());
    for l in &s.layers {
        assert_eq!(l.regions.len(), 1);
        assert!((l.regions[0].area() - 400.0).abs() < 1e-6);
    }
}

#[test]
fn deterministic_and_progress_reported() {
    let m = Shape::Sphere { radius: 5.0, segments: 40 }.mesh();
    let mut seen = Vec::new();
    let a = slice::slice(&m, &Options::default(), &mut |f| seen.push(f)).unwrap();
    let b = run(&m, &Options::default());
    assert_eq!(a.toolpath, b.toolpath);
    assert_eq!(a.layers, b.layers);
    assert!(seen.len() >= 10);
    assert!(seen.windows(2).all(|w| w[0] <= w[1]));
    assert_eq!(*seen.last().unwrap(), 1.0);
}

#[test]
fn no_infill_when_hollow_and_no_skins() {
    let o = Options { infill_density: 0.0, solid_layers: 0, skirt_loops: 0, ..Default::default() };
    let s = run(&cube([20.0, 20.0, 2.0]), &o);
    for tl in &s.toolpath.passes {
        assert_eq!(tl.paths.len(), 2);
    }
}

#[test]
fn errors() {
    assert_eq!(slice::slice(&Mesh::default(), &Options::default(), &mut |_| {}).unwrap_err(), Error::EmptyMesh);
    let e = slice::slice(&cube([1.0; 3]), &Options { line_width_mm: -1.0, ..Default::default() }, &mut |_| {}).unwrap_err();
    assert!(matches!(e, Error::BadOptions { problems } if problems[0].path == "line_width_mm"));
    let o = Options { layer_height_mm: 0.01, first_layer_height_mm: 0.01, ..Default::default() };
    let e = slice::slice(&cube([1.0, 1.0, 2000.0]), &o, &mut |_| {}).unwrap_err();
    assert!(matches!(&e, Error::TooBig(r) if r.what == "layers" && r.limit == 100_000.0), "{e:?}");
    assert_eq!(e.to_string(), "layers would be about 200k, limit 100k: use thicker layers (job.slice.layer_height_mm) or scale the part down");
}

#[test]
fn inconsistently_oriented_triangles_are_tolerated() {
    // Flip the +X face of a cube, and one triangle of the -Y face.
    let mut m = cube([20.0, 20.0, 4.0]);
    for k in [6, 7, 4] {
        m.triangles[k].swap(1, 2);
    }
    let s = run(&m, &Options::default());
    assert_eq!(s.report.open_contours_dropped, 0);
    for l in &s.layers {
        assert_eq!(l.regions.len(), 1);
        assert!((l.regions[0].area() - 400.0).abs() < 1e-6);
    }
}

#[test]
fn skirt_and_brim_around_the_first_layer() {
    // A 20 mm cube: the default skirt is one loop 3 mm out, printed first, on the first layer only.
    let s = run(&cube([20.0, 20.0, 1.0]), &Options::default());
    let first = &s.toolpath.passes[0].paths;
    assert_eq!(first[0].feature, Feature::Skirt);
    assert_eq!(first.iter().filter(|p| p.feature == Feature::Skirt).count(), 1);
    let reach = |p: &weft::geom::Path| p.points.iter().map(|q| q.x.abs().max(q.y.abs())).fold(0.0, f64::max);
    assert!((reach(&first[0]) - 13.2).abs() < 1e-3, "{}", reach(&first[0]));
    assert!(s.toolpath.passes[1..].iter().all(|l| l.paths.iter().all(|p| p.feature != Feature::Skirt)));
    // A 2 mm brim (5 loops of 0.4 mm, the last at 10.2 mm, touching the part) and the skirt
    // 3 mm beyond it; no skirt: the brim alone.
    let o = Options { brim_width_mm: 2.0, ..Default::default() };
    let s = run(&cube([20.0, 20.0, 1.0]), &o);
    let reaches: Vec<f64> =
        s.toolpath.passes[0].paths.iter().take_while(|p| p.feature == Feature::Skirt).map(|p| (reach(p) * 1000.0).round() / 1000.0).collect();
    assert_eq!(reaches, [15.2, 11.8, 11.4, 11.0, 10.6, 10.2]);
    let o = Options { brim_width_mm: 2.0, skirt_loops: 0, ..Default::default() };
    assert_eq!(run(&cube([20.0, 20.0, 1.0]), &o).toolpath.passes[0].paths.iter().filter(|p| p.feature == Feature::Skirt).count(), 5);
}

use super::*;
use crate::axisym::platform::{normal, position};
use std::collections::BTreeMap;

/// A box [lo, hi] with each face split into n × n quads, vertices welded, outward facing.
fn boxed(lo: [f64; 3], hi: [f64; 3], n: usize) -> Mesh {
    let mut tris: Vec<[[f64; 3]; 3]> = Vec::new();
    for k in 0..3 {
        let (a, b) = ((k + 1) % 3, (k + 2) % 3);
        for side in [lo[k], hi[k]] {
            let pt = |i: usize, j: usize| {
                let mut p = [0.0; 3];
                p[k] = side;
                p[a] = lo[a] + (hi[a] - lo[a]) * i as f64 / n as f64;
                p[b] = lo[b] + (hi[b] - lo[b]) * j as f64 / n as f64;
                p
            };
            for i in 0..n {
                for j in 0..n {
                    let (p00, p10, p11, p01) = (pt(i, j), pt(i + 1, j), pt(i + 1, j + 1), pt(i, j + 1));
                    if side == hi[k] {
                        tris.push([p00, p10, p11]);
                        tris.push([p00, p11, p01]);
                    } else {
                        tris.push([p00, p11, p10]);
                        tris.push([p00, p01, p11]);
                    }
                }
            }
        }
    }
    weld(&tris)
}

fn weld(tris: &[[[f64; 3]; 3]]) -> Mesh {
    let mut m = Mesh::default();
    let mut index: BTreeMap<[u32; 3], u32> = BTreeMap::new();
    for t in tris {
        let mut tri = [0u32; 3];
        for (c, p) in t.iter().enumerate() {
            let v = [p[0] as f32, p[1] as f32, p[2] as f32];
            let key = v.map(f32::to_bits);
            tri[c] = *index.entry(key).or_insert_with(|| {
                m.vertices.push(v);
                (m.vertices.len() - 1) as u32
            });
        }
        m.triangles.push(tri);
    }
    m
}

fn inverted(mut m: Mesh) -> Mesh {
    for t in &mut m.triangles {
        t.swap(1, 2);
    }
    m
}

fn in_box(q: [f64; 3], lo: [f64; 3], hi: [f64; 3], tol: f64) -> bool {
    (0..3).all(|k| q[k] >= lo[k] - tol && q[k] <= hi[k] + tol)
}

fn face_distance(q: [f64; 3], lo: [f64; 3], hi: [f64; 3]) -> f64 {
    (0..3).map(|k| (q[k] - lo[k]).abs().min((q[k] - hi[k]).abs())).fold(f64::INFINITY, f64::min)
}

/// Platform area of {(u, θ): position inside the box}, midpoint rule on a fine grid.
fn numeric_area(p: &Platform, lo: [f64; 3], hi: [f64; 3], ur: (f64, f64), tr: (f64, f64), n: usize) -> f64 {
    let (du, dt) = ((ur.1 - ur.0) / n as f64, (tr.1 - tr.0) / n as f64);
    let mut area = 0.0;
    for i in 0..n {
        let u = ur.0 + (i as f64 + 0.5) * du;
        let j = p.jet(u);
        let w = j.x[0] * j.x[1].hypot(j.z[1]) * du * dt;
        for k in 0..n {
            let t = tr.0 + (k as f64 + 0.5) * dt;
            if in_box(position(p, u, t), lo, hi, 0.0) {
                area += w;
            }
        }
    }
    area
}

fn bbox(l: &[[f64; 2]]) -> ((f64, f64), (f64, f64)) {
    let f = |k: usize| l.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| (a.min(p[k]), b.max(p[k])));
    (f(0), f(1))
}

#[test]
fn the_sign_is_positive_outside_the_barrel() {
    let p = Platform::barrel();
    let g = Generatrix::new(&p, DEFAULT_SAMPLES_PER_SEGMENT);
    let (d, u) = g.signed([30.0, 0.0, 25.0]);
    assert!((d - 5.0).abs() < 1e-6 && (u - 1.0).abs() < 1e-6, "d = {d}, u = {u}");
    let (d, _) = g.signed([0.0, 20.0, 25.0]);
    assert!((d + 5.0).abs() < 1e-6, "inside: d = {d}");
    // Above the top pole, and just under it (the generatrix turns there: z is not monotone in r).
    assert!(g.signed([0.0, 0.0, 55.0]).0 > 4.99);
    assert!(g.signed([1.0, 0.0, 49.0]).0 < 0.0);
}

#[test]
fn a_box_across_the_barrel_side_gives_one_loop_on_the_mesh_with_the_right_area() {
    let p = Platform::barrel();
    let (lo, hi) = ([20.0, -5.0, 20.0], [40.0, 5.0, 30.0]);
    let mesh = boxed(lo, hi, 8);
    let c = platform_contours(&mesh, &p, &Options::default()).unwrap();
    assert_eq!(c.loops.len(), 1, "{c:?}");
    assert_eq!((c.open_chains, c.is_hole[0], c.parent[0]), (0, false, None));
    let l = &c.loops[0];
    assert!(shoelace(l) > 0.0, "outer loop counter-clockwise");
    for &[u, t] in l {
        let q = position(&p, u, t);
        assert!(in_box(q, lo, hi, 1e-6), "{q:?} outside the box");
        assert!(face_distance(q, lo, hi) < 1e-6, "{q:?} is not on the box's surface");
    }
    let (ur, tr) = bbox(l);
    let num = numeric_area(&p, lo, hi, (ur.0 - 0.01, ur.1 + 0.01), (tr.0 - 0.01, tr.1 + 0.01), 1500);
    let rel = (c.area_mm2[0] - num).abs() / num;
    println!("box loop: {} points, area {:.4} mm² (grid {:.4}, rel {:.2e})", l.len(), c.area_mm2[0], num, rel);
    assert!(rel < 0.01, "area {} vs {}", c.area_mm2[0], num);
    // About 10 mm of z × 2·asin(5/25)·25 mm of arc on a near-cylinder.
    assert!((c.area_mm2[0] - 100.0).abs() < 10.0);
}

#[test]
fn a_vertical_cylinder_through_the_barrel_side_closes_on_its_wall() {
    let p = Platform::barrel();
    let mut mesh = crate::geom::shapes::Shape::Cylinder { radius: 10.0, height: 20.0, segments: 96 }.mesh();
    mesh.translate(glam::DVec3::new(25.0, 0.0, 15.0));
    let c = platform_contours(&mesh, &p, &Options::default()).unwrap();
    assert_eq!((c.loops.len(), c.open_chains), (1, 0), "{c:?}");
    for &[u, t] in &c.loops[0] {
        let q = position(&p, u, t);
        let rho = (q[0] - 25.0).hypot(q[1]);
        // On the faceted wall: between the facets' inscribed radius and 10 mm.
        let inner = 10.0 * libm::cos(PI / 96.0);
        let wall = rho > inner - 1e-5 && rho < 10.0 + 1e-5 && q[2] > 15.0 - 1e-6 && q[2] < 35.0 + 1e-6;
        let cap = rho < 10.0 + 1e-5 && ((q[2] - 15.0).abs() < 1e-6 || (q[2] - 35.0).abs() < 1e-6);
        assert!(wall || cap, "{q:?} rho {rho}");
    }
}

#[test]
fn an_offset_surface_cuts_where_the_offset_says() {
    let p = Platform::barrel();
    let (lo, hi) = ([20.0, -5.0, 20.0], [40.0, 5.0, 30.0]);
    let o = Options { offset_mm: 2.0, ..Options::default() };
    let c = platform_contours(&boxed(lo, hi, 4), &p, &o).unwrap();
    assert_eq!(c.loops.len(), 1);
    for &[u, t] in &c.loops[0] {
        let (q, n) = (position(&p, u, t), normal(&p, u, t));
        let q = [q[0] + 2.0 * n[0], q[1] + 2.0 * n[1], q[2] + 2.0 * n[2]];
        assert!(in_box(q, lo, hi, 1e-6) && face_distance(q, lo, hi) < 1e-6, "{q:?}");
    }
}

#[test]
fn a_box_that_misses_says_how_far_it_is() {
    let p = Platform::barrel();
    let e = platform_contours(&boxed([32.0, -5.0, 20.0], [40.0, 5.0, 30.0], 1), &p, &Options::default()).unwrap_err();
    match &e {
        Error::NoContact { distance_mm, side, .. } => {
            assert_eq!(*side, "outside");
            assert!(*distance_mm > 6.0 && *distance_mm < 8.0, "{e}");
        }
        other => panic!("{other:?}"),
    }
    assert!(e.to_string().contains("move the part"), "{e}");
    let e = platform_contours(&boxed([-5.0, -5.0, 20.0], [5.0, 5.0, 30.0], 1), &p, &Options::default()).unwrap_err();
    assert!(matches!(e, Error::NoContact { side: "inside", .. }), "{e}");
}

#[test]
fn a_hollow_box_gives_a_hole_and_two_boxes_two_loops() {
    let p = Platform::barrel();
    let mut m = boxed([15.0, -8.0, 17.0], [40.0, 8.0, 33.0], 4);
    m.append(&inverted(boxed([18.0, -4.0, 21.0], [37.0, 4.0, 29.0], 4)));
    let c = platform_contours(&m, &p, &Options::default()).unwrap();
    assert_eq!(c.loops.len(), 2, "{c:?}");
    assert_eq!(c.parent, vec![None, Some(0)]);
    assert_eq!(c.is_hole, vec![false, true]);
    assert!(shoelace(&c.loops[0]) > 0.0 && shoelace(&c.loops[1]) < 0.0);
    assert!(c.area_mm2[0] > 2.0 * c.area_mm2[1]);

    // Two boxes side by side in θ (one across θ = ±π, to exercise the unwrap): two outer loops.
    let mut m = boxed([20.0, 2.0, 20.0], [40.0, 8.0, 30.0], 2);
    m.append(&boxed([-40.0, -3.0, 20.0], [-20.0, 3.0, 30.0], 2));
    let c = platform_contours(&m, &p, &Options::default()).unwrap();
    assert_eq!(c.loops.len(), 2);
    assert_eq!(c.parent, vec![None, None]);
    assert!(c.area_mm2[0] > c.area_mm2[1], "the 6 mm wide box comes first");
    let (_, tr) = bbox(&c.loops[1]);
    assert!(tr.1 - tr.0 < 0.5, "θ unwrapped across ±π: span {}", tr.1 - tr.0);
}

#[test]
fn a_part_around_the_axis_is_refused_as_winding() {
    let p = Platform::barrel();
    let e = platform_contours(&boxed([-40.0, -40.0, 20.0], [40.0, 40.0, 30.0], 3), &p, &Options::default()).unwrap_err();
    assert!(matches!(e, Error::WindsAroundAxis { turns, .. } if turns.abs() == 1), "{e}");
}

#[test]
fn the_same_mesh_gives_identical_output() {
    let p = Platform::hourglass();
    let mut m = crate::geom::shapes::uv_sphere(8.0, 48);
    m.translate(glam::DVec3::new(25.0, 3.0, 42.0));
    let a = platform_contours(&m, &p, &Options::default()).unwrap();
    let b = platform_contours(&m.clone(), &p, &Options::default()).unwrap();
    assert_eq!(a, b);
    assert_eq!(a.loops.len(), 1);
    assert_eq!(format!("{a:?}"), format!("{b:?}"));
}

#[test]
fn hostile_input_gives_typed_errors_never_a_panic() {
    let p = Platform::barrel();
    let o = Options::default();
    assert_eq!(platform_contours(&Mesh::default(), &p, &o), Err(Error::EmptyMesh));
    let mut m = boxed([20.0, -5.0, 20.0], [40.0, 5.0, 30.0], 1);
    m.vertices[3][1] = f32::NAN;
    assert!(matches!(platform_contours(&m, &p, &o), Err(Error::NonFiniteVertex { index: 3, .. })));
    let mut m = boxed([20.0, -5.0, 20.0], [40.0, 5.0, 30.0], 1);
    m.triangles[5][2] = 99;
    assert!(matches!(platform_contours(&m, &p, &o), Err(Error::BadIndex { triangle: 5, index: 99, .. })));
    // Only degenerate triangles across the surface: nothing to chain, an empty result.
    let m = Mesh { vertices: vec![[20.0, 0.0, 25.0], [30.0, 0.0, 25.0], [30.0, 0.0, 25.0]], triangles: vec![[0, 0, 1], [0, 1, 2], [1, 1, 1]] };
    let c = platform_contours(&m, &p, &o).unwrap();
    assert!(c.loops.is_empty());
    // An open mesh (one face missing): the chain does not close and is counted.
    let mut m = boxed([20.0, -5.0, 20.0], [40.0, 5.0, 30.0], 2);
    let v = m.vertices.clone();
    m.triangles.retain(|t| !t.iter().all(|&i| v[i as usize][1] == 5.0));
    let c = platform_contours(&m, &p, &o).unwrap();
    assert_eq!((c.loops.len(), c.open_chains), (0, 1), "{c:?}");
    // A box only touching the platform (its face x = 25 is tangent along y = 0): distance 0.
    let e = platform_contours(&boxed([25.0, -5.0, 20.0], [40.0, 5.0, 30.0], 2), &p, &o).unwrap_err();
    assert!(matches!(e, Error::NoContact { distance_mm, .. } if distance_mm < 1e-9), "{e}");
    // A vertex exactly on the platform (the equator point (25, 0, 25)) on a crossing face.
    let c = platform_contours(&boxed([20.0, 0.0, 20.0], [40.0, 5.0, 30.0], 4), &p, &o).unwrap();
    assert_eq!((c.loops.len(), c.open_chains), (1, 0), "{c:?}");
    assert!(c.loops[0].windows(2).all(|w| w[0] != w[1]));
    for bad in [
        Options { offset_mm: f64::NAN, ..o.clone() },
        Options { tolerance_mm: 0.0, ..o.clone() },
        Options { merge_mm: -1.0, ..o.clone() },
        Options { samples_per_segment: 0, ..o.clone() },
    ] {
        assert!(matches!(platform_contours(&boxed([20.0, -5.0, 20.0], [40.0, 5.0, 30.0], 1), &p, &bad), Err(Error::BadOption { .. })));
    }
    assert!(estimate(MAX_TRIANGLES + 1).check().is_err());
    assert!(estimate(100_000).check().is_ok());
}

#[test]
fn options_read_with_defaults_and_refuse_unknown_fields() {
    let o: Options = serde_json::from_str(r#"{"offset_mm": 0.4}"#).unwrap();
    assert_eq!(o, Options { offset_mm: 0.4, ..Options::default() });
    assert!(serde_json::from_str::<Options>(r#"{"offset": 0.4}"#).is_err());
}

#[test]
fn timing_on_a_100k_triangle_sphere() {
    let p = Platform::barrel();
    let mut m = crate::geom::shapes::uv_sphere(15.0, 316);
    m.translate(glam::DVec3::new(25.0, 0.0, 10.0));
    let t0 = std::time::Instant::now();
    let c = platform_contours(&m, &p, &Options::default()).unwrap();
    let dt = t0.elapsed().as_secs_f64();
    println!(
        "100k timing: {} triangles, {} vertices: {:.1} ms ({:.3} µs per triangle), {} loop(s), {} points, area {:.2} mm²",
        m.triangles.len(),
        m.vertices.len(),
        dt * 1e3,
        dt * 1e6 / m.triangles.len() as f64,
        c.loops.len(),
        c.loops.iter().map(Vec::len).sum::<usize>(),
        c.area_mm2.first().copied().unwrap_or(0.0)
    );
    assert_eq!((c.loops.len(), c.open_chains), (1, 0));
}

//! Times `weft::slice::slice` on a ~1,000,000-triangle sphere at 0.2 mm layers.
//! `cargo run --release --example slice_bench [segments] [radius_mm]`

use std::time::Instant;
use weft::geom::Mesh;

fn sphere(r: f64, seg: u32) -> Mesh {
    let rings = seg / 2;
    let mut m = Mesh::default();
    m.vertices.push([0.0, 0.0, 0.0]);
    for i in 1..rings {
        let phi = std::f64::consts::PI * i as f64 / rings as f64;
        for j in 0..seg {
            let th = 2.0 * std::f64::consts::PI * j as f64 / seg as f64;
            m.vertices.push([
                (r * libm::sin(phi) * libm::cos(th)) as f32,
                (r * libm::sin(phi) * libm::sin(th)) as f32,
                (r - r * libm::cos(phi)) as f32,
            ]);
        }
    }
    let north = m.vertices.len() as u32;
    m.vertices.push([0.0, 0.0, (2.0 * r) as f32]);
    let ring = |i: u32, j: u32| 1 + (i - 1) * seg + (j % seg);
    for j in 0..seg {
        m.triangles.push([0, ring(1, j + 1), ring(1, j)]);
        m.triangles.push([north, ring(rings - 1, j), ring(rings - 1, j + 1)]);
    }
    for i in 1..rings - 1 {
        for j in 0..seg {
            let (a, b, c, d) = (ring(i, j), ring(i, j + 1), ring(i + 1, j + 1), ring(i + 1, j));
            m.triangles.push([a, b, c]);
            m.triangles.push([a, c, d]);
        }
    }
    m
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let seg: u32 = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(1000);
    let r: f64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(25.0);
    let mesh = sphere(r, seg);
    println!("sphere r = {r} mm, {} triangles", mesh.triangles.len());
    let t = Instant::now();
    let s = weft::slice::slice(&mesh, &Default::default(), &mut |_| {}).expect("slices");
    let dt = t.elapsed();
    let paths: usize = s.toolpath.layers.iter().map(|l| l.paths.len()).sum();
    println!(
        "{} layers, {paths} paths, {:.0} mm extruded, report {:?}",
        s.layers.len(),
        s.toolpath.extrusion_length(),
        s.report
    );
    println!("slice time: {:.3} s", dt.as_secs_f64());
}

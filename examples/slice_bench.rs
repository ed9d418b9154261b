//! Times `weft::slice::slice` on a ~1,000,000-triangle sphere at 0.2 mm layers.
//! `cargo run --release --example slice_bench [segments] [radius_mm]`

use std::time::Instant;
use weft::geom::shapes::uv_sphere;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let seg: u32 = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(1000);
    let r: f64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(25.0);
    let mesh = uv_sphere(r, seg);
    println!("sphere r = {r} mm, {} triangles", mesh.triangles.len());
    let t = Instant::now();
    let s = weft::slice::slice(&mesh, &Default::default(), &mut |_| {}).expect("slices");
    let dt = t.elapsed();
    let paths: usize = s.toolpath.passes.iter().map(|l| l.paths.len()).sum();
    println!(
        "{} layers, {paths} paths, {:.0} mm extruded, report {:?}",
        s.layers.len(),
        s.toolpath.extrusion_length(),
        s.report
    );
    println!("slice time: {:.3} s", dt.as_secs_f64());
}

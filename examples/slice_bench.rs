//! Times the slicer, the writer and the analyzer on built-in solids against their estimates
//! (the calibration of the per-item costs in `slice/estimate.rs`, `gcode::estimate` and
//! `analyze::estimate`).
//! `cargo run --release --example slice_bench [sphere_segments] [radius_mm]`

use std::time::Instant;
use weft::geom::shapes::{uv_sphere, Shape};
use weft::{analyze, gcode, slice};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let seg: u32 = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(1000);
    let r: f64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(25.0);
    let d = slice::Options::default();
    let cases = [
        ("sphere", uv_sphere(r, seg), d.clone()),
        ("cube 100", Shape::Cube { size: [100.0, 100.0, 100.0] }.mesh(), d.clone()),
        ("cube 100 solid", Shape::Cube { size: [100.0, 100.0, 100.0] }.mesh(), slice::Options { infill_density: 1.0, ..d.clone() }),
        ("cube 150 at 0.05", Shape::Cube { size: [150.0, 150.0, 150.0] }.mesh(), slice::Options { layer_height_mm: 0.05, ..d.clone() }),
        ("cylinder hollow", Shape::Cylinder { radius: 50.0, height: 100.0, segments: 512 }.mesh(), slice::Options { infill_density: 0.0, ..d }),
    ];
    let writer = gcode::Options { printer: gcode::Printer { bed_size_mm: [1000.0; 3], ..Default::default() }, ..Default::default() };
    println!("{:<18} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9}", "case", "slice s", "est", "write s", "est", "analyze s", "est");
    for (name, mesh, o) in cases {
        let e = slice::estimate(&mesh, &o);
        let t = Instant::now();
        let s = slice::slice(&mesh, &o, &mut |_| {}).expect("slices");
        let ts = t.elapsed().as_secs_f64();
        let we = gcode::estimate(e.get("segments"), &writer);
        let t = Instant::now();
        let g = gcode::write_gcode(&s.toolpath, &writer).expect("writes");
        let tw = t.elapsed().as_secs_f64();
        let ae = analyze::plan(e.get("segments"), e.get("layers"), &analyze::Options { collect_preview: true, ..Default::default() });
        let t = Instant::now();
        analyze::analyze("bench.gcode", g.text.as_bytes(), &analyze::Options { collect_preview: true, ..Default::default() }).expect("analyses");
        let ta = t.elapsed().as_secs_f64();
        println!("{name:<18} {ts:>9.3} {:>9.3} {tw:>9.3} {:>9.3} {ta:>9.3} {:>9.3}", e.seconds, we.seconds, ae.seconds);
    }
}

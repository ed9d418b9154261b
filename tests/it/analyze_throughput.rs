//! Throughput of the analyzer on ~100 MB of writer output. Run with
//! `cargo test --release --test it analyze_throughput:: -- --ignored --nocapture`.

use std::time::Instant;
use weft::analyze::{analyze, Options as AOptions};
use weft::gcode::{write_gcode, Options};
use weft::geom::{DVec3, Feature, Pass, Path, Toolpath};

fn big_toolpath(layers: usize) -> Toolpath {
    let mut tp = Toolpath::default();
    for i in 0..layers {
        let z = 0.2 * (i + 1) as f64;
        let mut paths = Vec::new();
        // Concentric "perimeters" of 360 chords each (curved walls: many short segments).
        for ring in 0..20 {
            let r = 30.0 + 0.45 * ring as f64;
            let pts: Vec<DVec3> = (0..=360)
                .map(|k| {
                    let t = k as f64 / 360.0 * std::f64::consts::TAU;
                    DVec3::new(r * t.cos(), r * t.sin(), z)
                })
                .collect();
            paths.push(Path { points: pts, feature: Feature::Perimeter, width: 0.45, speed_factor: 1.0, approach: None, data: None });
        }
        // Zig-zag infill inside, 1 mm segments.
        let mut pts = Vec::new();
        for row in 0..100 {
            let y = -25.0 + 0.5 * row as f64;
            for k in 0..=40 {
                let x = if row % 2 == 0 { -20.0 + k as f64 } else { 20.0 - k as f64 };
                pts.push(DVec3::new(x, y, z));
            }
        }
        paths.push(Path { points: pts, feature: Feature::Infill, width: 0.45, speed_factor: 1.0, approach: None, data: None });
        tp.passes.push(Pass::layer(z, 0.2, paths));
    }
    tp
}

/// CPU time of this thread in seconds (Linux; 0 elsewhere), so a busy machine does not skew
/// the figure the way wall time does.
fn thread_cpu_s() -> f64 {
    weft::bench::thread_cpu_seconds().unwrap_or(0.0)
}

#[test]
#[ignore]
fn throughput_100mb() {
    let t = Instant::now();
    let g = write_gcode(&big_toolpath(300), &Options::default()).unwrap();
    let write_s = t.elapsed().as_secs_f64();
    let bytes = g.text.as_bytes();
    let mb = bytes.len() as f64 / 1e6;
    println!("generated {mb:.1} MB in {write_s:.2} s (writer incl. its own analysis pass)");
    for preview in [false, true] {
        let t = Instant::now();
        let c = thread_cpu_s();
        let a = analyze("big.gcode", bytes, &AOptions { collect_preview: preview, ..Default::default() }).unwrap();
        let s = t.elapsed().as_secs_f64();
        let cpu = thread_cpu_s() - c;
        println!(
            "analyze (preview {preview}): wall {s:.3} s = {:.0} MB/s, cpu {cpu:.2} s = {:.0} MB/s; {} layers, {} paths, {:.0} mm extruded, overlap {:.3} mm",
            mb / s,
            mb / cpu,
            a.report.layers,
            a.report.extrusion_paths,
            a.report.extruded_mm,
            a.report.overlap_mm
        );
    }
}

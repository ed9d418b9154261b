//! Benchmark workloads, shared by `weft bench` (native timing) and the browser worker
//! (timed with `performance.now()` in `tests/e2e/bench.mjs`), so both measure the same work.

use crate::design::{Design, Input, Job};
use crate::geom::shapes::uv_sphere;
use crate::geom::Mesh;

/// Radius of the benchmark sphere, mm (500 layers at 0.2 mm).
pub const BENCH_SPHERE_RADIUS_MM: f64 = 50.0;

/// A closed UV sphere with about `triangles` triangles.
pub fn bench_mesh(triangles: usize) -> Mesh {
    let seg = ((triangles as f64).sqrt().round() as u32).max(8);
    uv_sphere(BENCH_SPHERE_RADIUS_MM, seg)
}

/// The slicing benchmark's design: the default printer, 0.2 mm layers, slicing `bench.stl`.
pub fn bench_design() -> Design {
    let mut d = Design { name: "bench".into(), ..Design::default() };
    d.job.set_input(Input::File { name: "bench.stl".into(), embedded: None });
    if let Job::Slice(job) = &mut d.job {
        job.slice.layer_height_mm = 0.2;
        job.slice.first_layer_height_mm = 0.2;
    }
    d
}

/// G-code of at least `bytes` bytes: `seed` repeated.
pub fn repeat_to(seed: &str, bytes: usize) -> String {
    let mut s = String::with_capacity(bytes + seed.len());
    while s.len() < bytes && !seed.is_empty() {
        s.push_str(seed);
    }
    s
}

#[cfg(not(target_arch = "wasm32"))]
pub use native::run_all;

#[cfg(not(target_arch = "wasm32"))]
mod native {
    use super::*;
    use crate::pipeline::{self, Files, RunOptions, Stage};
    use std::time::Instant;

    fn peak_rss_mb() -> Option<f64> {
        let status = std::fs::read_to_string("/proc/self/status").ok()?;
        let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
        let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
        Some(kb / 1024.0)
    }

    /// Runs every benchmark and returns a Markdown report.
    pub fn run_all(triangles: usize, gcode_mb: usize) -> Result<String, String> {
        let mut out = String::new();
        let t0 = Instant::now();
        let mesh = bench_mesh(triangles);
        let stl = mesh.to_stl_binary();
        let gen_s = t0.elapsed().as_secs_f64();
        let stl_mb = stl.len() as f64 / 1e6;
        let mut files = Files::new();
        files.insert("bench.stl".into(), stl);
        let design = bench_design();
        let mut stage_start = Instant::now();
        let mut current = Stage::Import;
        let mut stage_times: Vec<(Stage, f64)> = Vec::new();
        let t = Instant::now();
        let output = pipeline::run(&design, &files, &RunOptions::default(), &mut |stage, _| {
            if stage != current {
                stage_times.push((current, stage_start.elapsed().as_secs_f64()));
                current = stage;
                stage_start = Instant::now();
            }
        })
        .map_err(|e| e.to_string())?;
        stage_times.push((current, stage_start.elapsed().as_secs_f64()));
        let total = t.elapsed().as_secs_f64();
        out.push_str(&format!(
            "## slice: {} triangles ({:.1} MB binary STL, generated in {:.2} s), 0.2 mm layers\n\n",
            mesh.triangles.len(),
            stl_mb,
            gen_s
        ));
        out.push_str("| stage | seconds |\n|---|---|\n");
        for (stage, s) in &stage_times {
            out.push_str(&format!("| {} | {:.3} |\n", stage.name(), s));
        }
        out.push_str(&format!("| **total** | **{total:.3}** |\n\n"));
        out.push_str(&format!(
            "layers {}, G-code {:.1} MB, peak RSS {} MB ({:.1}× the STL)\n\n",
            output.report.analysis.layers,
            output.gcode.len() as f64 / 1e6,
            peak_rss_mb().map_or("?".into(), |m| format!("{m:.0}")),
            peak_rss_mb().unwrap_or(0.0) / stl_mb
        ));
        let big = repeat_to(&output.gcode, gcode_mb * 1_000_000);
        drop(output);
        let t = Instant::now();
        let analysis = crate::analyze::analyze("bench.gcode", big.as_bytes(), &Default::default()).map_err(|e| e.to_string())?;
        let s = t.elapsed().as_secs_f64();
        out.push_str(&format!(
            "## analyze: {:.1} MB of G-code in {:.3} s = **{:.0} MB/s** ({} extrusion paths)\n",
            big.len() as f64 / 1e6,
            s,
            big.len() as f64 / 1e6 / s,
            analysis.report.extrusion_paths
        ));
        Ok(out)
    }
}

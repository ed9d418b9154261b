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
    use crate::pipeline::{self, Files, RunOptions, RunOutput, Stage};
    use std::time::Instant;

    /// Analyzer passes per configuration; the fastest is reported (the machine may be shared).
    const ANALYZE_REPEATS: usize = 3;

    fn status_mb(field: &str) -> Option<f64> {
        let status = std::fs::read_to_string("/proc/self/status").ok()?;
        let line = status.lines().find(|l| l.starts_with(field))?;
        let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
        Some(kb / 1024.0)
    }

    /// Peak resident set size since the start or the last [`reset_peak_rss`], MB (Linux).
    fn peak_rss_mb() -> Option<f64> {
        status_mb("VmHWM:")
    }

    /// Resets the peak RSS to the current RSS (Linux `clear_refs` 5); false when not possible.
    fn reset_peak_rss() -> bool {
        std::fs::write("/proc/self/clear_refs", "5").is_ok()
    }

    /// CPU time of this thread, s (Linux; `None` elsewhere).
    fn thread_cpu_s() -> Option<f64> {
        let stat = std::fs::read_to_string("/proc/thread-self/stat").ok()?;
        let after = &stat[stat.rfind(')')? + 2..];
        let f: Vec<&str> = after.split_whitespace().collect();
        let ticks = f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?;
        Some(ticks / 100.0)
    }

    struct Timed {
        stages: Vec<(Stage, f64)>,
        total: f64,
        peak_mb: Option<f64>,
        peak_is_job: bool,
    }

    fn run_timed(files: &Files, collect_preview: bool) -> Result<(Timed, RunOutput), String> {
        let design = bench_design();
        let peak_is_job = reset_peak_rss();
        let mut stage_start = Instant::now();
        let mut current = Stage::Import;
        let mut stages: Vec<(Stage, f64)> = Vec::new();
        let t = Instant::now();
        let output = pipeline::run(&design, files, &RunOptions { collect_preview }, &mut |stage, _| {
            if stage != current {
                stages.push((current, stage_start.elapsed().as_secs_f64()));
                current = stage;
                stage_start = Instant::now();
            }
        })
        .map_err(|e| e.to_string())?;
        stages.push((current, stage_start.elapsed().as_secs_f64()));
        let total = t.elapsed().as_secs_f64();
        Ok((Timed { stages, total, peak_mb: peak_rss_mb(), peak_is_job }, output))
    }

    /// Fastest of [`ANALYZE_REPEATS`] passes: (wall s, thread CPU s of that pass, paths).
    fn time_analyze(gcode: &[u8], collect_preview: bool) -> Result<(f64, Option<f64>, usize), String> {
        let options = crate::analyze::Options { collect_preview, ..Default::default() };
        let mut best: Option<(f64, Option<f64>, usize)> = None;
        for _ in 0..ANALYZE_REPEATS {
            let c = thread_cpu_s();
            let t = Instant::now();
            let a = crate::analyze::analyze("bench.gcode", gcode, &options).map_err(|e| e.to_string())?;
            let s = t.elapsed().as_secs_f64();
            let cpu = thread_cpu_s().zip(c).map(|(b, a)| b - a);
            let paths = a.report.extrusion_paths;
            drop(a);
            if best.is_none_or(|b| s < b.0) {
                best = Some((s, cpu, paths));
            }
        }
        best.ok_or_else(|| "no analyzer pass".to_string())
    }

    /// Runs every benchmark and returns a Markdown report.
    pub fn run_all(triangles: usize, gcode_mb: usize) -> Result<String, String> {
        let mut out = String::new();
        let t0 = Instant::now();
        let mesh = bench_mesh(triangles);
        let stl = mesh.to_stl_binary();
        let gen_s = t0.elapsed().as_secs_f64();
        let stl_mb = stl.len() as f64 / 1e6;
        let n_triangles = mesh.triangles.len();
        drop(mesh);
        let mut files = Files::new();
        files.insert("bench.stl".into(), stl);

        // The CLI's run (no preview buffers), then the page's (Session.run builds them).
        let (plain, output) = run_timed(&files, false)?;
        let layers = output.report.analysis.layers;
        let gcode = output.gcode;
        let (preview, output) = run_timed(&files, true)?;
        let same = output.gcode == gcode;
        drop(output);

        out.push_str(&format!(
            "## slice: {n_triangles} triangles ({stl_mb:.1} MB binary STL, generated in {gen_s:.2} s), 0.2 mm layers\n\n"
        ));
        out.push_str("| stage | seconds (no preview, CLI) | seconds (with preview, as the page) |\n|---|---|---|\n");
        for ((stage, a), (_, b)) in plain.stages.iter().zip(&preview.stages) {
            out.push_str(&format!("| {} | {a:.3} | {b:.3} |\n", stage.name()));
        }
        out.push_str(&format!("| **total** | **{:.3}** | **{:.3}** |\n\n", plain.total, preview.total));
        let rss = |t: &Timed| match t.peak_mb {
            Some(m) => format!("{m:.0} MB ({:.1}× the STL){}", m / stl_mb, if t.peak_is_job { "" } else { " (process peak)" }),
            None => "?".into(),
        };
        out.push_str(&format!(
            "layers {layers}, G-code {:.1} MB{}, peak RSS during the run {} without preview, {} with preview\n\n",
            gcode.len() as f64 / 1e6,
            if same { "" } else { " (the preview run's G-code DIFFERS)" },
            rss(&plain),
            rss(&preview),
        ));
        drop((plain, preview, files));

        let big = repeat_to(&gcode, gcode_mb * 1_000_000);
        drop(gcode);
        let mb = big.len() as f64 / 1e6;
        for (collect_preview, label) in [(false, "analyze"), (true, "analyze with preview")] {
            let (s, cpu, paths) = time_analyze(big.as_bytes(), collect_preview)?;
            out.push_str(&format!(
                "## {label}: {mb:.1} MB of G-code in {s:.3} s = **{:.0} MB/s** (CPU {}; best of {ANALYZE_REPEATS}; {paths} extrusion paths)\n",
                mb / s,
                cpu.map_or("?".into(), |c| format!("{c:.2} s")),
            ));
        }
        Ok(out)
    }
}

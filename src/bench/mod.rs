//! Benchmark workloads, shared by `weft bench` (native timing) and the browser worker
//! (timed with `performance.now()` in `tests/e2e/bench.mjs`), so both measure the same work.

use crate::design::{Design, Input};
use crate::geom::shapes::uv_sphere;
use crate::geom::Mesh;
use crate::kinds::{lattice::LatticeJob, slice::SliceJob};

/// Radius of the benchmark sphere, mm (500 layers at 0.2 mm).
pub const BENCH_SPHERE_RADIUS_MM: f64 = 50.0;

/// A closed UV sphere with about `triangles` triangles.
pub fn bench_mesh(triangles: usize) -> Mesh {
    let seg = ((triangles as f64).sqrt().round() as u32).max(8);
    uv_sphere(BENCH_SPHERE_RADIUS_MM, seg)
}

/// The slicing benchmark's design: the default printer, 0.2 mm layers, slicing `bench.stl`.
pub fn bench_design() -> Design {
    let mut job = SliceJob { input: Input::File { name: "bench.stl".into(), embedded: None }, ..SliceJob::default() };
    job.slice.layer_height_mm = 0.2;
    job.slice.first_layer_height_mm = 0.2;
    Design { name: "bench".into(), job: crate::design::Job::new("slice", &job), ..Design::default() }
}

/// G-code of at least `bytes` bytes: `seed` repeated.
pub fn repeat_to(seed: &str, bytes: usize) -> String {
    let mut s = String::with_capacity(bytes + seed.len());
    while s.len() < bytes && !seed.is_empty() {
        s.push_str(seed);
    }
    s
}

pub mod designs;
pub mod graded;
pub mod pairing;
#[cfg(not(target_arch = "wasm32"))]
pub mod papers;
pub mod scaling;

/// CPU time of the calling thread, seconds (Linux: the scheduler's count in nanoseconds, so
/// other processes on a busy machine do not inflate it); `None` where it cannot be read. The
/// one clock of the benchmarks and the calibration examples (the tests' growth checks count
/// work instead: `crate::work`).
pub fn thread_cpu_seconds() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    let ns: u64 = s.split_whitespace().next()?.parse().ok()?;
    (ns > 0).then_some(ns as f64 * 1e-9)
}

/// The honeycomb-10mm example (embedded so the wasm build has it).
pub const HONEYCOMB_10MM_JSON: &str = include_str!("../../examples/honeycomb-10mm.json");
/// The ball-burst-disc-48mm example.
pub const DISC_48MM_JSON: &str = include_str!("../../examples/ball-burst-disc-48mm.json");

/// Side of the square honeycomb (r = 0.92 mm) of the euler workload, mm: about 100 000 edges.
pub const EULER_SQUARE_MM: f64 = 270.0;

/// The lattice path-optimisation workloads (`weft bench --lattice`, `BenchLattice` in wasm).
pub const LATTICE_WORKLOADS: [&str; 3] = ["honeycomb-10mm", "disc-48mm", "euler-100k"];

/// One lattice path-optimisation workload: the strokes are prepared (lattice generation is
/// not timed); [`LatticeBench::run`] is the timed part (`paths::optimise` only).
pub struct LatticeBench {
    /// Workload name (one of [`LATTICE_WORKLOADS`]).
    pub name: &'static str,
    /// The strokes of the one layer optimised.
    pub strokes: Vec<crate::geom::StrokeLayer>,
    /// Optimiser options (method, iterations).
    pub options: crate::paths::Options,
    /// Line width, mm.
    pub line_width_mm: f64,
    /// Seed.
    pub seed: u64,
}

/// What one optimise pass produced (to check the passes do the same work).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LatticeRunStats {
    /// Graph edges of the layer.
    pub edges: usize,
    /// Paths produced.
    pub paths: usize,
    /// Equation-1 score.
    pub score: f64,
}

impl LatticeBench {
    /// Prepares a workload by name: builds the design and generates its first layer's strokes.
    pub fn prepare(which: &str) -> Result<LatticeBench, String> {
        use crate::paths::Method;
        let (name, json, euler_square) = match which {
            "honeycomb-10mm" | "honeycomb" => ("honeycomb-10mm", HONEYCOMB_10MM_JSON, None),
            "disc-48mm" | "disc" => ("disc-48mm", DISC_48MM_JSON, None),
            "euler-100k" | "euler" => ("euler-100k", HONEYCOMB_10MM_JSON, Some(EULER_SQUARE_MM)),
            other => return Err(format!("unknown lattice workload '{other}' (one of {})", LATTICE_WORKLOADS.join(", "))),
        };
        let mut design = Design::from_json(name, json).map_err(|e| e.to_string())?;
        let mut job: LatticeJob = design.job.settings().ok_or_else(|| format!("{name}: not a lattice design"))?;
        job.lattice.layers = 1;
        job.paths.iterations = 500;
        job.paths.method = Method::GippoMax;
        if let Some(side) = euler_square {
            job.domain = crate::lattice::Domain::Rectangle { width_mm: side, height_mm: side };
            job.paths.method = Method::Euler;
        }
        let options = job.paths.clone();
        design.job = crate::design::Job::new("lattice", &job);
        let mut strokes = crate::kinds::lattice::lattice_strokes(&design, &Default::default()).map_err(|e| e.to_string())?;
        strokes.truncate(1);
        Ok(LatticeBench { name, strokes, options, line_width_mm: design.printer.nozzle_diameter_mm, seed: design.seed })
    }

    /// The timed part: `paths::optimise` of the prepared layer.
    pub fn run(&self) -> Result<LatticeRunStats, String> {
        let o = crate::paths::optimise(&self.strokes, &self.options, self.line_width_mm, self.seed, &mut |_| {}).map_err(|e| e.to_string())?;
        let l = o.report.layers.first().ok_or("no layer")?;
        Ok(LatticeRunStats { edges: l.edges, paths: l.paths, score: l.score })
    }

    /// The method's name.
    pub fn method(&self) -> &'static str {
        match self.options.method {
            crate::paths::Method::GippoMax => "gippo_max",
            crate::paths::Method::GippoMin => "gippo_min",
            crate::paths::Method::Euler => "euler",
            crate::paths::Method::Continuous => "continuous",
        }
    }

    /// The target of the issue, ms.
    pub fn target_ms(&self) -> f64 {
        match self.name {
            "honeycomb-10mm" => 100.0,
            "disc-48mm" => 2000.0,
            _ => 200.0,
        }
    }
}

#[cfg(not(target_arch = "wasm32"))]
pub use cache_native::run_cache;
#[cfg(not(target_arch = "wasm32"))]
pub use native::{run_all, run_lattice};

#[cfg(not(target_arch = "wasm32"))]
mod native {
    use super::*;
    use crate::pipeline::{self, Files, RunOptions, RunOutput};
    use std::time::Instant;

    /// Analyzer passes per configuration; the fastest is reported (the machine may be shared).
    const ANALYZE_REPEATS: usize = 3;

    fn status_mb(field: &str) -> Option<f64> {
        let status = std::fs::read_to_string("/proc/self/status").ok()?;
        let line = status.lines().find(|l| l.starts_with(field))?;
        let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
        Some(kb / 1024.0)
    }

    /// Peak resident set size since the start or the last [`reset_peak_rss`], MiB (Linux).
    pub(super) fn peak_rss_mb() -> Option<f64> {
        status_mb("VmHWM:")
    }

    /// Resident set size now, MiB (Linux).
    pub(super) fn rss_mb() -> Option<f64> {
        status_mb("VmRSS:")
    }

    /// Resets the peak RSS to the current RSS (Linux `clear_refs` 5); false when not possible.
    pub(super) fn reset_peak_rss() -> bool {
        std::fs::write("/proc/self/clear_refs", "5").is_ok()
    }

    struct Timed {
        stages: Vec<(String, f64)>,
        total: f64,
        peak_mb: Option<f64>,
        peak_is_job: bool,
    }

    fn run_timed(files: &Files, collect_preview: bool) -> Result<(Timed, RunOutput), String> {
        let design = bench_design();
        let peak_is_job = reset_peak_rss();
        let mut stage_start = Instant::now();
        let mut current = String::from("import");
        let mut stages: Vec<(String, f64)> = Vec::new();
        let t = Instant::now();
        let output = pipeline::run(&design, files, &RunOptions { collect_preview }, &mut |stage, _| {
            if stage != current {
                stages.push((std::mem::replace(&mut current, stage.to_string()), stage_start.elapsed().as_secs_f64()));
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
            let c = super::thread_cpu_seconds();
            let t = Instant::now();
            let a = crate::analyze::analyze("bench.gcode", gcode, &options).map_err(|e| e.to_string())?;
            let s = t.elapsed().as_secs_f64();
            let cpu = super::thread_cpu_seconds().zip(c).map(|(b, a)| b - a);
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

        out.push_str(&format!("## slice: {n_triangles} triangles ({stl_mb:.1} MB binary STL, generated in {gen_s:.2} s), 0.2 mm layers\n\n"));
        out.push_str("| stage | seconds (no preview, CLI) | seconds (with preview, as the page) |\n|---|---|---|\n");
        for ((stage, a), (_, b)) in plain.stages.iter().zip(&preview.stages) {
            out.push_str(&format!("| {} | {a:.3} | {b:.3} |\n", stage));
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

    /// Timed optimise passes per lattice workload (best and median reported).
    pub const LATTICE_REPEATS: usize = 3;

    /// The lattice path-optimisation benchmarks as a Markdown table.
    pub fn run_lattice() -> Result<String, String> {
        let mut out = String::new();
        out.push_str(&format!("## lattice path optimisation (`paths::optimise` of one prepared layer; best and median of {LATTICE_REPEATS})\n\n"));
        out.push_str("| workload | method | edges | paths | score | best ms | median ms | target ms |\n|---|---|---|---|---|---|---|---|\n");
        for which in LATTICE_WORKLOADS {
            let b = LatticeBench::prepare(which)?;
            let mut times = Vec::new();
            let mut stats = None;
            for _ in 0..LATTICE_REPEATS {
                let t = Instant::now();
                let s = b.run()?;
                times.push(t.elapsed().as_secs_f64() * 1000.0);
                if stats.is_some_and(|p| p != s) {
                    return Err(format!("{which}: passes differ"));
                }
                stats = Some(s);
            }
            times.sort_by(f64::total_cmp);
            let s = stats.ok_or("no pass")?;
            out.push_str(&format!(
                "| {} | {} | {} | {} | {:.4} | {:.1} | {:.1} | {:.0} |\n",
                b.name,
                b.method(),
                s.edges,
                s.paths,
                s.score,
                times[0],
                times[times.len() / 2],
                b.target_ms()
            ));
        }
        Ok(out)
    }
}

/// `design_json` with `material.bed_temp_c` raised by `delta` (the cache benchmark's edit: it
/// changes only what the `gcode` stage reads).
pub fn bump_bed_temp(design_json: &str, delta: f64) -> Result<String, String> {
    let mut v: serde_json::Value = serde_json::from_str(design_json).map_err(|e| e.to_string())?;
    let t = v.pointer_mut("/material/bed_temp_c").ok_or("the design has no material.bed_temp_c")?;
    *t = serde_json::json!(t.as_f64().ok_or("material.bed_temp_c is not a number")? + delta);
    serde_json::to_string_pretty(&v).map_err(|e| e.to_string())
}

/// Stages of `stages` before `gcode` that were recomputed (not `cached`); empty when every
/// one was reused.
pub fn uncached_before_gcode(stages: &[crate::report::StageReport]) -> Vec<String> {
    stages.iter().take_while(|r| r.stage != "gcode").filter(|r| !r.cached).map(|r| r.stage.clone()).collect()
}

#[cfg(not(target_arch = "wasm32"))]
mod cache_native {
    use super::*;
    use crate::kinds::Registry;
    use crate::pipeline::{self, Cache, Files, RunOptions};
    use std::time::Instant;

    /// One cached workload: first run, then the re-run after `bump_bed_temp(+10)`.
    struct CacheRow {
        name: String,
        add_file_s: Option<f64>,
        first_s: f64,
        second_s: f64,
        stages: Vec<(String, bool)>,
        uncached: Vec<String>,
        same_layers: bool,
    }

    fn run_pair(name: &str, json: &str, files: &Files, mesh_slot: Option<&str>) -> Result<CacheRow, String> {
        let registry = Registry::builtin();
        let mut cache = Cache::new();
        let options = RunOptions { collect_preview: true };
        let design = Design::from_json(name, json).map_err(|e| e.to_string())?;
        // As `Session.addFile` does: the mesh is imported into the cache before the first run.
        let add_file_s = match mesh_slot {
            Some(slot) => {
                let t = Instant::now();
                let plain = Design::default();
                let mut quiet = |_: &str, _: f32| {};
                let mut ctx = pipeline::Ctx::new(&plain, files, &mut cache, &mut quiet);
                let input = crate::design::Input::File { name: "bench.stl".into(), embedded: None };
                let slot = Registry::builtin().slot(slot).ok_or_else(|| format!("no slot {slot}"))?;
                ctx.mesh(slot, &input).map_err(|e| e.to_string())?;
                Some(t.elapsed().as_secs_f64())
            }
            None => None,
        };
        let t = Instant::now();
        let a = pipeline::run_in(&registry, &mut cache, &design, files, &options, &mut |_, _| {}).map_err(|e| e.to_string())?;
        let first_s = t.elapsed().as_secs_f64();
        let layers = a.report.analysis.layers;
        drop(a);
        let edited = Design::from_json(name, &bump_bed_temp(json, 10.0)?).map_err(|e| e.to_string())?;
        let t = Instant::now();
        let b = pipeline::run_in(&registry, &mut cache, &edited, files, &options, &mut |_, _| {}).map_err(|e| e.to_string())?;
        let second_s = t.elapsed().as_secs_f64();
        Ok(CacheRow {
            name: name.into(),
            add_file_s,
            first_s,
            second_s,
            stages: b.report.stages.iter().map(|r| (r.stage.clone(), r.cached)).collect(),
            uncached: uncached_before_gcode(&b.report.stages),
            same_layers: b.report.analysis.layers == layers,
        })
    }

    /// The stage-cache benchmark (`weft bench --cache`): a full run, then a re-run after
    /// `material.bed_temp_c` +10, on the disc-48mm example and on the `triangles` mesh.
    pub fn run_cache(triangles: usize) -> Result<String, String> {
        let stl = bench_mesh(triangles).to_stl_binary();
        let stl_mb = stl.len() as f64 / 1e6;
        let mut files = Files::new();
        files.insert("bench.stl".into(), stl);
        let rows = [
            run_pair("disc-48mm", DISC_48MM_JSON, &Files::new(), None)?,
            run_pair(&format!("mesh-{triangles}"), &bench_design().to_json_pretty(), &files, Some("mesh"))?,
        ];
        let mut out = String::new();
        out.push_str(&format!("## stage cache: full run, then re-run after material.bed_temp_c +10 (native, preview on; mesh: {stl_mb:.1} MB STL)\n\n"));
        out.push_str("| workload | addFile s | first run s | re-run s | re-run / first | stages before gcode cached |\n|---|---|---|---|---|---|\n");
        for r in &rows {
            out.push_str(&format!(
                "| {} | {} | {:.4} | {:.4} | {:.4} | {} |\n",
                r.name,
                r.add_file_s.map_or("-".into(), |s| format!("{s:.3}")),
                r.first_s,
                r.second_s,
                r.second_s / r.first_s,
                if r.uncached.is_empty() { "all".to_string() } else { format!("NOT: {}", r.uncached.join(", ")) },
            ));
        }
        out.push('\n');
        for r in &rows {
            let st: Vec<String> = r.stages.iter().map(|(s, c)| format!("{s}{}", if *c { " (cached)" } else { "" })).collect();
            out.push_str(&format!("re-run stages of {}: {}{}\n", r.name, st.join(", "), if r.same_layers { "" } else { " (layer count DIFFERS)" }));
        }
        Ok(out)
    }
}

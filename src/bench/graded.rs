//! The graded job's benchmark workload (issue 11), shared by `examples/graded_bench.rs`,
//! `weft bench --graded` (native) and `BenchGraded` in the browser worker
//! (`tests/e2e/bench.mjs`), so all of them time the same bytes: weft's bone phantom at the
//! paper's CT size written as a DICOM series, and a PrusaSlicer-style G-code of ~50 MB.
//!
//! Issue 11's targets, in the browser worker: load the series and extract the surface under
//! 3 s; edit the 50 MB G-code under 3 s; peak memory under 3 × the volume's bytes plus the
//! G-code's bytes ([`Workload::memory_target`]).

use crate::design::{Design, Input, Job};
use crate::kinds::graded::{AlignMode, Alignment, GradedJob, Route};
use crate::testgen::dicom::{bone_phantom, write_series, SeriesOptions};
use crate::testgen::foreign::{sized, Slicer};

/// The femur case's CT grid (the paper's table 2), voxels along i, j, k.
pub const SERIES_DIMS: [usize; 3] = [182, 197, 107];
/// Its voxel spacing, mm.
pub const SERIES_SPACING_MM: [f64; 3] = [0.976562, 0.976562, 3.27];
/// Size of the edited G-code, bytes (about; the generator stops at a whole layer).
pub const GCODE_BYTES: usize = 50 << 20;
/// The folder the series' files are named in, as a dropped folder names them on the page.
pub const SERIES_FOLDER: &str = "bone-phantom";
/// Name of the G-code file.
pub const GCODE_NAME: &str = "prusaslicer-50mb.gcode";

/// The bone phantom at `dims` (spacing [`SERIES_SPACING_MM`]) as DICOM files, one per slice.
pub fn series(dims: [usize; 3]) -> Vec<(String, Vec<u8>)> {
    write_series(&bone_phantom(dims, SERIES_SPACING_MM), &SeriesOptions::default())
}

/// A PrusaSlicer-style absolute-E G-code of about `bytes` bytes (a 60 mm square prism centred
/// at X 100, Y 100 with sparse rectilinear infill), and the box of its extruding moves.
pub fn foreign_gcode(bytes: usize) -> (Vec<u8>, ([f64; 3], [f64; 3])) {
    // Only the text and its box: the generator's per-move record is ~100 MB at this size.
    let g = sized(Slicer::PrusaSlicer, false, bytes);
    (g.text, g.bounds)
}

/// The graded workload: inputs as the page's `Session` gets them and the designs that use them.
pub struct Workload {
    /// The series as a dropped folder gives it: (`bone-phantom/slice-0000.dcm`, bytes), …
    pub series: Vec<(String, Vec<u8>)>,
    /// The G-code edited ([`GCODE_NAME`]).
    pub gcode: Vec<u8>,
    /// Bytes of the volume as the reader holds it (`f32` voxels).
    pub volume_bytes: usize,
    /// Route `native`, the whole volume: what a dropped series makes (its surface view).
    pub surface_design: Design,
    /// Route `edit`: the series and the G-code, placed by a manual translation.
    pub edit_design: Design,
}

impl Workload {
    /// The series at `dims` and a G-code of about `gcode_bytes` bytes, with their designs.
    pub fn new(dims: [usize; 3], gcode_bytes: usize) -> Workload {
        let series: Vec<(String, Vec<u8>)> = series(dims).into_iter().map(|(n, b)| (format!("{SERIES_FOLDER}/{n}"), b)).collect();
        let (gcode, (lo, hi)) = foreign_gcode(gcode_bytes);
        let names: Vec<String> = series.iter().map(|(n, _)| n.clone()).collect();
        let graded = GradedJob { volume: Some(Input::Files(names)), ..GradedJob::default() };
        let design = |name: &str, job: &GradedJob| Design { name: name.into(), job: Job::new("graded", job), ..Design::default() };
        // G-code point = volume point + v: the part's XY centre over the volume's centre (the
        // bone's axis) and its middle at the volume's mid-height, so the infill lies in bone.
        let centre = |a: usize| (dims[a].saturating_sub(1)) as f64 * SERIES_SPACING_MM[a] / 2.0;
        let v = [(lo[0] + hi[0]) / 2.0 - centre(0), (lo[1] + hi[1]) / 2.0 - centre(1), lo[2] - (centre(2) - (hi[2] - lo[2]) / 2.0)];
        let edit = GradedJob {
            route: Route::Edit,
            gcode: Some(Input::File { name: GCODE_NAME.into(), embedded: None }),
            alignment: Alignment { mode: AlignMode::Manual, translation_mm: v },
            ..graded.clone()
        };
        Workload {
            series,
            gcode,
            volume_bytes: dims.iter().product::<usize>() * std::mem::size_of::<f32>(),
            surface_design: design("graded-bench-surface", &graded),
            edit_design: design("graded-bench-edit", &edit),
        }
    }

    /// The paper's CT size and a 50 MB G-code.
    pub fn paper() -> Workload {
        Workload::new(SERIES_DIMS, GCODE_BYTES)
    }

    /// Bytes of the series' files.
    pub fn series_bytes(&self) -> usize {
        self.series.iter().map(|(_, b)| b.len()).sum()
    }

    /// The peak-memory target, bytes: 3 × the volume plus the G-code (`with_gcode`).
    pub fn memory_target(&self, with_gcode: bool) -> usize {
        3 * self.volume_bytes + if with_gcode { self.gcode.len() } else { 0 }
    }
}

#[cfg(not(target_arch = "wasm32"))]
pub use native::run_graded;

#[cfg(not(target_arch = "wasm32"))]
mod native {
    use super::*;
    use crate::bench::designs::timed_run;
    use crate::bench::native::{peak_rss_mb, reset_peak_rss, rss_mb};
    use crate::kinds::Registry;
    use crate::pipeline::{self, Cache, Files, RunOptions};
    use std::time::Instant;

    /// Passes per case; the fastest counts (the machine may be shared).
    const REPEATS: usize = 3;

    /// The series (and the G-code) in `Files`, as `Session.addBlob` keeps each dropped file;
    /// with the G-code, its check on loading too (every line read, the printed part's box).
    fn load(w: &Workload, with_gcode: bool) -> Result<Files, String> {
        let mut files = Files::new();
        for (name, bytes) in &w.series {
            files.insert(name.clone(), bytes.clone());
        }
        if with_gcode {
            files.insert(GCODE_NAME.into(), w.gcode.clone());
            crate::gcode_edit::printed_bounds(GCODE_NAME, &w.gcode.as_slice()).map_err(|e| e.to_string())?;
        }
        Ok(files)
    }

    /// Peak RSS during `f` above the RSS before it, MB (Linux; `None` where it cannot be reset).
    fn peak_above<T>(f: impl FnOnce() -> T) -> (T, Option<f64>) {
        let before = rss_mb();
        let reset = reset_peak_rss();
        let out = f();
        let peak = peak_rss_mb();
        (out, before.zip(peak).filter(|_| reset).map(|(b, p)| (p - b) * 1.048576))
    }

    fn row(out: &mut String, case: &str, step: &str, runs: &[f64], best: f64) {
        let all: Vec<String> = runs.iter().map(|s| format!("{s:.3}")).collect();
        out.push_str(&format!("| {case} | {step} | {best:.3} | {} |\n", all.join(", ")));
    }

    /// `weft bench --graded`: the worker's two cases natively, as Markdown.
    pub fn run_graded() -> Result<String, String> {
        let t = Instant::now();
        let w = Workload::paper();
        let gen_s = t.elapsed().as_secs_f64();
        let registry = Registry::builtin();
        let mut out = String::new();
        out.push_str(&format!(
            "## graded (issue 11): bone phantom {} × {} × {} ({} DICOM files, {:.1} MB; f32 volume {:.1} MB), PrusaSlicer-style G-code {:.1} MB (generated in {gen_s:.1} s); native, best of {REPEATS}\n\n",
            SERIES_DIMS[0],
            SERIES_DIMS[1],
            SERIES_DIMS[2],
            w.series.len(),
            w.series_bytes() as f64 / 1e6,
            w.volume_bytes as f64 / 1e6,
            w.gcode.len() as f64 / 1e6,
        ));
        out.push_str("| case | step | s (fastest pass by total) | runs s |\n|---|---|---|---|\n");

        // Case 1, as the page goes after a drop: the series loaded, the run's plan asked
        // (`Session.estimate`: it reads the volume and makes the surface, kept for the run),
        // the surface view; then, from a new cache, the two stages apart (a slice view needs
        // only the volume stage).
        let mut passes: Vec<[f64; 5]> = Vec::new();
        let mut triangles = 0;
        let mut surface_mb = Vec::new();
        for _ in 0..REPEATS {
            let (pass, mb) = peak_above(|| -> Result<[f64; 3], String> {
                let t = Instant::now();
                let files = load(&w, false)?;
                let add = t.elapsed().as_secs_f64();
                let mut cache = Cache::new();
                let t = Instant::now();
                pipeline::estimate(&registry, &mut cache, &w.surface_design, &files).map_err(|e| e.to_string())?;
                let plan = t.elapsed().as_secs_f64();
                let t = Instant::now();
                let s = pipeline::inspect(&registry, &mut cache, &w.surface_design, &files, "surface", 0).map_err(|e| e.to_string())?;
                triangles = s.data.len() / 9;
                Ok([add, plan, t.elapsed().as_secs_f64()])
            });
            let [add, plan, view] = pass?;
            surface_mb.push(mb);
            let files = load(&w, false)?;
            let mut cache = Cache::new();
            let t = Instant::now();
            pipeline::inspect(&registry, &mut cache, &w.surface_design, &files, "axial", 0).map_err(|e| e.to_string())?;
            let vol = t.elapsed().as_secs_f64();
            let t = Instant::now();
            pipeline::inspect(&registry, &mut cache, &w.surface_design, &files, "surface", 0).map_err(|e| e.to_string())?;
            passes.push([add, plan, view, vol, t.elapsed().as_secs_f64()]);
        }
        let totals: Vec<f64> = passes.iter().map(|p| p[0] + p[1] + p[2]).collect();
        let best = (0..passes.len()).min_by(|&a, &b| totals[a].total_cmp(&totals[b])).ok_or("no pass")?;
        let steps = ["addFile", "estimate", "surface view", "volume stage", &format!("surface stage ({triangles} triangles)")];
        for (i, step) in steps.iter().enumerate() {
            row(&mut out, "surface", step, &passes.iter().map(|p| p[i]).collect::<Vec<_>>(), passes[best][i]);
        }
        row(&mut out, "surface", "**addFile + estimate + view**", &totals, totals[best]);

        // Case 2: load the series and the G-code, then the edit route's whole run.
        let mut loads = Vec::new();
        let mut runs = Vec::new();
        let mut edited = None;
        let mut edit_mb = Vec::new();
        for _ in 0..REPEATS {
            let (pass, mb) = peak_above(|| -> Result<_, String> {
                let t = Instant::now();
                let files = load(&w, true)?;
                let add = t.elapsed().as_secs_f64();
                let mut cache = Cache::new();
                let options = RunOptions { collect_preview: true };
                let (total, stages, output) = timed_run(&registry, &mut cache, &w.edit_design, &files, &options)?;
                let moves = output.report.stages.iter().find(|s| s.stage == "edit").and_then(|s| s.metrics.iter().find(|m| m.key == "edited")).map(|m| m.value);
                Ok((add, (total, stages), moves))
            });
            let (add, timing, moves) = pass?;
            loads.push(add);
            runs.push(timing);
            edited = moves;
            edit_mb.push(mb);
        }
        let best = (0..runs.len()).min_by(|&a, &b| (loads[a] + runs[a].0).total_cmp(&(loads[b] + runs[b].0))).ok_or("no pass")?;
        row(&mut out, "edit", "addFile", &loads, loads[best]);
        for (stage, s) in &runs[best].1 {
            let all: Vec<f64> = runs.iter().map(|r| r.1.iter().find(|x| &x.0 == stage).map_or(f64::NAN, |x| x.1)).collect();
            row(&mut out, "edit", stage, &all, *s);
        }
        row(&mut out, "edit", "**run**", &runs.iter().map(|r| r.0).collect::<Vec<_>>(), runs[best].0);
        let whole: Vec<f64> = loads.iter().zip(&runs).map(|(a, r)| a + r.0).collect();
        row(&mut out, "edit", "**addFile + run**", &whole, whole[best]);
        out.push('\n');
        // The largest peak of the passes (each pass starts from the same state).
        let mb = |m: &[Option<f64>]| m.iter().flatten().copied().reduce(f64::max).map_or("?".into(), |m| format!("{m:.1} MB"));
        out.push_str(&format!(
            "surface: {triangles} triangles; edit: {} moves edited. Peak RSS above the start of a pass (inputs copied in included): surface {}, edit {}; targets {:.1} MB and {:.1} MB.\n",
            edited.map_or("?".into(), |m| format!("{m:.0}")),
            mb(&surface_mb),
            mb(&edit_mb),
            w.memory_target(false) as f64 / 1e6,
            w.memory_target(true) as f64 / 1e6,
        ));
        Ok(out)
    }
}

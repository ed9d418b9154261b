//! Whole designs timed stage by stage (`weft bench --design FILE…`; the browser benchmark
//! runs the same designs through `Session.run` in the worker, `BENCH_DESIGNS`): the time
//! from each stage's first progress report to the next stage's, and the total, best of
//! `repeats` runs without a cache. Used for the job kinds whose work is one design (the
//! axisymmetric examples: the paper's Ω1–Ω3).

use crate::design::Design;
use crate::kinds::Registry;
use crate::pipeline::{self, Cache, Files, RunOptions, RunOutput};
use std::time::Instant;

/// One design's best run.
#[derive(Clone, Debug)]
pub struct DesignTiming {
    /// Design name.
    pub name: String,
    /// (stage, seconds) in run order, from the best run.
    pub stages: Vec<(String, f64)>,
    /// Whole run, s (best of the repeats).
    pub total_s: f64,
    /// Every run's total, s.
    pub runs_s: Vec<f64>,
}

/// Each stage's time, s, in run order.
pub type StageTimes = Vec<(String, f64)>;

/// One run of `design` through `cache`: (total s, (stage, s) in run order, the output). A
/// stage's time runs from its first progress report to the next stage's (the last one to the
/// end); a stage reported twice (estimated, then reused from the cache) is summed.
pub fn timed_run(registry: &Registry, cache: &mut Cache, design: &Design, files: &Files, options: &RunOptions) -> Result<(f64, StageTimes, RunOutput), String> {
    let start = Instant::now();
    let mut marks: Vec<(String, f64)> = Vec::new();
    let mut progress = |stage: &str, _: f32| {
        if marks.last().map(|m| m.0.as_str()) != Some(stage) {
            marks.push((stage.to_string(), start.elapsed().as_secs_f64()));
        }
    };
    let output = pipeline::run_in(registry, cache, design, files, options, &mut progress).map_err(|e| format!("{}: {e}", design.name))?;
    let total = start.elapsed().as_secs_f64();
    let mut stages: Vec<(String, f64)> = Vec::new();
    for (i, (name, t)) in marks.iter().enumerate() {
        let end = marks.get(i + 1).map_or(total, |m| m.1);
        match stages.iter_mut().find(|s| &s.0 == name) {
            Some(s) => s.1 += end - t,
            None => stages.push((name.clone(), end - t)),
        }
    }
    Ok((total, stages, output))
}

/// Runs `design` `repeats` times (no cache) and keeps the fastest run's stage times.
pub fn time_design(design: &Design, repeats: usize) -> Result<DesignTiming, String> {
    let files = Files::default();
    let registry = Registry::builtin();
    let mut best: Option<(f64, Vec<(String, f64)>)> = None;
    let mut runs = Vec::new();
    for _ in 0..repeats.max(1) {
        let mut cache = Cache::disabled();
        let (total, stages, _) = timed_run(&registry, &mut cache, design, &files, &RunOptions::default())?;
        runs.push(total);
        if best.as_ref().is_none_or(|b| total < b.0) {
            best = Some((total, stages));
        }
    }
    let (total_s, stages) = best.unwrap_or_default();
    Ok(DesignTiming { name: design.name.clone(), stages, total_s, runs_s: runs })
}

/// [`time_design`] on one thread and on every core, side by side (native only: the wasm build
/// has one thread).
#[cfg(not(target_arch = "wasm32"))]
pub fn time_design_threads(design: &Design, repeats: usize) -> Result<(DesignTiming, DesignTiming), String> {
    let pool = |n: usize| rayon::ThreadPoolBuilder::new().num_threads(n).build().map_err(|e| e.to_string());
    let one = pool(1)?.install(|| time_design(design, repeats))?;
    let all = pool(0)?.install(|| time_design(design, repeats))?;
    Ok((one, all))
}

/// The table of [`time_design_threads`]: each stage at 1 thread and at `threads`, and the ratio.
pub fn threads_table(rows: &[(DesignTiming, DesignTiming)], threads: usize) -> String {
    let mut out = format!("| design | stage | 1 thread s | {threads} threads s | speed-up |\n|---|---|---|---|---|\n");
    for (one, all) in rows {
        for (stage, s1) in &one.stages {
            let sn = all.stages.iter().find(|x| &x.0 == stage).map_or(f64::NAN, |x| x.1);
            out.push_str(&format!("| {} | {stage} | {s1:.3} | {sn:.3} | {:.2}× |\n", one.name, s1 / sn));
        }
        out.push_str(&format!("| {} | **total** | **{:.3}** | **{:.3}** | **{:.2}×** |\n", one.name, one.total_s, all.total_s, one.total_s / all.total_s));
    }
    out
}

/// The table `weft bench --design` prints.
pub fn table(rows: &[DesignTiming]) -> String {
    let mut out = String::from("| design | stage | best s |\n|---|---|---|\n");
    for r in rows {
        for (stage, s) in &r.stages {
            out.push_str(&format!("| {} | {stage} | {s:.3} |\n", r.name));
        }
        let runs: Vec<String> = r.runs_s.iter().map(|s| format!("{s:.3}")).collect();
        out.push_str(&format!("| {} | **total** | **{:.3}** (runs: {}) |\n", r.name, r.total_s, runs.join(", ")));
    }
    out
}

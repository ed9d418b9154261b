//! Runs a [`Design`]: its job kind's stages ([`crate::kinds`]), then G-code and analysis;
//! estimates a run and answers a view's `inspect`. Nothing else here: the stage runtime
//! (files, keys, the cache, [`Ctx`], loaders, errors) is [`crate::stage`], re-exported for
//! callers of the pipeline.
//!
//! The CLI and the wasm binding both call [`run`] (or [`run_in`] with a cache and a
//! registry); nothing else orchestrates stages. A [`Cache`] kept between runs (the page's
//! worker keeps one) recomputes only the stages whose inputs changed — a temperature edit
//! re-runs only G-code and analysis.

use crate::analyze::{self, Preview};
use crate::budget::Plan;
use crate::design::Design;
use crate::gcode::{self, GcodeStats};
use crate::geom::Toolpath;
use crate::kinds::Registry;
use crate::report::StageReport;
pub use crate::stage::{
    meshes_of_zip, writer_options, Ahead, Cache, Ctx, Error, FileSource, Files, Inspection, Key, NamedFiles, Out, Product, Sender, Slot, StageTime,
};
use serde::Serialize;
use std::sync::Arc;

/// Run options that are not part of the design.
#[derive(Clone, Debug, Default)]
pub struct RunOptions {
    /// Build preview buffers.
    pub collect_preview: bool,
}

/// Everything a run reports (`weft run --report`): the stages' reports in run order, the
/// writer's totals and the analyzer's reading of the G-code.
#[derive(Clone, Debug, Serialize)]
pub struct RunReport {
    /// Design name.
    pub name: String,
    /// Job kind.
    pub job: String,
    /// Each stage's report, in run order.
    pub stages: Vec<StageReport>,
    /// Writer totals.
    pub gcode: GcodeStats,
    /// The analyzer's reading of the written G-code.
    pub analysis: analyze::Report,
    /// Threads the run computed on (`weft run --threads`; in the browser the worker's pool, 1 without cross-origin isolation).
    pub threads: usize,
    /// Each stage's wall time, in run order.
    pub timings: Vec<StageTime>,
}

impl RunReport {
    /// The raw typed report of stage `name` (its `data`), if it ran.
    pub fn stage_data(&self, name: &str) -> Option<&serde_json::Value> {
        self.stages.iter().find(|s| s.stage == name).map(|s| &s.data)
    }

    /// The typed report of stage `name`.
    pub fn stage<T: serde::de::DeserializeOwned>(&self, name: &str) -> Option<T> {
        self.stage_data(name).and_then(|v| serde_json::from_value(v.clone()).ok())
    }
}

/// A run's products.
#[derive(Clone, Debug)]
pub struct RunOutput {
    /// The G-code.
    pub gcode: Arc<String>,
    /// The report.
    pub report: RunReport,
    /// Preview buffers, when asked for.
    pub preview: Option<Arc<Preview>>,
    /// The G-code as Prusa binary G-code (`.bgcode`), when the printer asks for it
    /// ([`gcode::Printer::binary_gcode`], Marlin flavour).
    pub bgcode: Option<Arc<Vec<u8>>>,
}

/// Runs the design with the built-in job kinds and no cache. `progress(stage, fraction)` is
/// called as work proceeds.
pub fn run(design: &Design, files: &Files, options: &RunOptions, progress: &mut dyn FnMut(&str, f32)) -> Result<RunOutput, Error> {
    run_in(&Registry::builtin(), &mut Cache::disabled(), design, files, options, progress)
}

/// The G-code written by the writer stage and its totals.
struct Written {
    text: Arc<String>,
    stats: GcodeStats,
}

/// What the analyzer stage keeps.
struct Analysed {
    report: analyze::Report,
    preview: Option<Arc<Preview>>,
}

/// Runs the design with `registry`'s job kinds, reusing `cache`'s outputs whose inputs did
/// not change.
pub fn run_in(
    registry: &Registry,
    cache: &mut Cache,
    design: &Design,
    files: &Files,
    options: &RunOptions,
    progress: &mut dyn FnMut(&str, f32),
) -> Result<RunOutput, Error> {
    run_sending(registry, cache, design, files, options, progress, &crate::stage::send_nowhere)
}

/// [`run_in`], with `ahead` receiving the G-code stages send ahead ([`Ahead`]) while it runs.
pub fn run_sending(
    registry: &Registry,
    cache: &mut Cache,
    design: &Design,
    files: &Files,
    options: &RunOptions,
    progress: &mut dyn FnMut(&str, f32),
    ahead: &dyn Fn(&Ahead),
) -> Result<RunOutput, Error> {
    let kind = registry.get(design.job.kind()).ok_or_else(|| Error::UnknownKind { kind: design.job.kind().into(), known: registry.names().join(", ") })?;
    let mut ctx = Ctx::new(design, files, cache, progress);
    ctx.ahead = ahead;
    ctx.counting = true;
    let plan = plan(kind, &mut ctx)?;
    if let Some((stage, source)) = plan.refused {
        return Err(Error::TooBig { stage, source });
    }
    let (written, finished) = match kind.run(&mut ctx)? {
        Product::Toolpath(toolpath) => (write_stage(&mut ctx, &toolpath)?, false),
        // Finished G-code: no writer; its totals are read back below.
        Product::Gcode(text) => (Out { value: Arc::new(Written { text: text.value.clone(), stats: GcodeStats::default() }), key: text.key }, true),
    };
    let analysed = analyze_stage(&mut ctx, &written, options)?;
    let reports = std::mem::take(&mut ctx.reports);
    let stats = if finished { stats_of(&analysed.report) } else { written.stats.clone() };
    let report = RunReport {
        name: design.name.clone(),
        job: design.job.kind().into(),
        stages: reports,
        gcode: stats,
        analysis: analysed.report.clone(),
        threads: crate::par::threads(),
        timings: std::mem::take(&mut ctx.timings),
    };
    let binary = design.printer.binary_gcode && design.printer.flavor == gcode::Flavor::Marlin;
    let bgcode = if binary { Some(Arc::new(gcode::binary::from_text(&written.text))) } else { None };
    Ok(RunOutput { gcode: written.text.clone(), report, preview: analysed.preview.clone(), bgcode })
}

/// Writer totals of G-code weft did not write (an edited file), as the analyzer measured them.
fn stats_of(a: &analyze::Report) -> GcodeStats {
    GcodeStats {
        layers: a.layers,
        extruded_mm: a.extruded_mm,
        filament_mm: a.filament_mm,
        travel_mm: a.travel_mm,
        retractions: a.retractions,
        estimated_time_s: a.estimated_time_s,
        merged_moves: 0,
        dropped_paths: 0,
        dropped_filament_mm: 0.0,
        arcs: 0,
        arc_bytes_saved: 0,
    }
}

/// The run's plan (`weft run --dry-run`, the page's question before a big run): every
/// stage's estimate in run order, made before running any stage but the imports (which are
/// bounded by their own estimates and kept for the run).
pub fn estimate(registry: &Registry, cache: &mut Cache, design: &Design, files: &Files) -> Result<Plan, Error> {
    let kind = registry.get(design.job.kind()).ok_or_else(|| Error::UnknownKind { kind: design.job.kind().into(), known: registry.names().join(", ") })?;
    let mut quiet = |_: &str, _: f32| {};
    let mut ctx = Ctx::new(design, files, cache, &mut quiet);
    plan(kind, &mut ctx)
}

/// The job's stage estimates, then the writer's and the analyzer's (unless a job stage is
/// already refused).
fn plan(kind: &dyn crate::kinds::JobKind, ctx: &mut Ctx) -> Result<Plan, Error> {
    let mut stages = kind.estimate(ctx)?;
    if stages.iter().all(|e| e.refused.is_none()) {
        let segments = stages.last().map_or(0.0, |e| e.get("segments"));
        let mut writer = gcode::estimate(segments, &writer_options(ctx.design));
        let layers = stages.iter().map(|e| e.get("layers")).fold(0.0, f64::max);
        let mut analyzer = analyze::plan(segments, layers, &analyzer_options(ctx.design, &RunOptions { collect_preview: true }));
        // Their size is the job's toolpath: what shrinks it is the job's own fix.
        if let Some(fix) = stages.last().and_then(|e| e.smaller.clone()) {
            for r in [&mut writer.refused, &mut analyzer.refused].into_iter().flatten() {
                r.fix = fix.clone();
            }
        }
        stages.push(writer);
        stages.push(analyzer);
    }
    Ok(Plan::on_threads(stages, crate::par::threads()))
}

fn write_stage(ctx: &mut Ctx, toolpath: &Out<Toolpath>) -> Result<Out<Written>, Error> {
    let design = ctx.design;
    let parts = (&design.printer, &design.material, &design.speeds, &design.name, &design.date);
    ctx.stage("gcode", "gcode", &parts, &[toolpath.key], |_| {
        let options = writer_options(design);
        let mut g = gcode::write_gcode(toolpath, &options)?;
        if g.stats.arcs > 0 {
            // What the arcs saved: the same file with straight segments only.
            let mut lines = options.clone();
            lines.printer.arc_tolerance_mm = 0.0;
            let plain = gcode::write_gcode(toolpath, &lines)?;
            g.stats.arc_bytes_saved = plain.text.len() as i64 - g.text.len() as i64;
        }
        // Its numbers are the run report's `gcode` totals, which the page shows once, in its
        // overall statistics; the stage report says whether the writer ran.
        let mut report = StageReport::new("gcode", "Writing G-code", &g.stats);
        if g.stats.merged_moves > 0 {
            report = report.note(&format!(
                "joined {} extruding move(s) shorter than {} mm to their neighbours, with their filament (such dust stutters a printer's planner)",
                g.stats.merged_moves,
                gcode::MIN_MOVE_MM
            ));
        }
        if g.stats.arcs > 0 {
            let kb = g.stats.arc_bytes_saved as f64 / 1024.0;
            let pct = 100.0 * g.stats.arc_bytes_saved as f64 / (g.text.len() as f64 + g.stats.arc_bytes_saved as f64);
            report = report.note(&format!(
                "fitted {} arcs (G2/G3) within {} mm of the straight segments: the file is {kb:.1} KB ({pct:.1} %) smaller, with the same filament",
                g.stats.arcs, design.printer.arc_tolerance_mm
            ));
        }
        if g.stats.dropped_paths > 0 {
            report = report.note(&format!(
                "left out {} path(s) shorter than {} mm in all (slivers with no neighbour to join; {:.5} mm of filament), with their travel and retraction",
                g.stats.dropped_paths,
                gcode::MIN_MOVE_MM,
                g.stats.dropped_filament_mm
            ));
        }
        Ok((Written { text: Arc::new(g.text), stats: g.stats }, Some(report)))
    })
}

/// What the analyzer reads of the design.
fn analyzer_options(design: &Design, options: &RunOptions) -> analyze::Options {
    analyze::Options {
        collect_preview: options.collect_preview,
        default_line_width_mm: design.printer.nozzle_diameter_mm,
        filament_diameter_mm: design.printer.filament_diameter_mm,
        machine: design.printer.machine.clone(),
    }
}

fn analyze_stage(ctx: &mut Ctx, written: &Out<Written>, options: &RunOptions) -> Result<Out<Analysed>, Error> {
    let design = ctx.design;
    let a_options = analyzer_options(design, options);
    let parts = (options.collect_preview, a_options.default_line_width_mm, a_options.filament_diameter_mm, &a_options.machine, &design.name);
    ctx.stage("analyze", "analyze", &parts, &[written.key], |_| {
        let a = analyze::analyze(&format!("{}.gcode", design.name), written.text.as_bytes(), &a_options)?;
        // The full reading is the run report's `analysis` (the page's overall statistics).
        let report = StageReport::new("analyze", "Measuring the G-code", &serde_json::Value::Null);
        Ok((Analysed { report: a.report, preview: a.preview.map(Arc::new) }, Some(report)))
    })
}

/// Data of view `view` at `index` of the design's job (the page's extra views), computed
/// through the same cached stages as a run.
pub fn inspect(registry: &Registry, cache: &mut Cache, design: &Design, files: &Files, view: &str, index: usize) -> Result<Inspection, Error> {
    let kind = registry.get(design.job.kind()).ok_or_else(|| Error::UnknownKind { kind: design.job.kind().into(), known: registry.names().join(", ") })?;
    let mut quiet = |_: &str, _: f32| {};
    let mut ctx = Ctx::new(design, files, cache, &mut quiet);
    kind.inspect(&mut ctx, view, index)
}

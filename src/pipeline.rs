//! Runs a [`Design`] end to end: resolve input → import → slice → G-code → analyze.
//!
//! The CLI and the wasm binding both call [`run`]; nothing else orchestrates stages.

use crate::analyze::{self, Preview};
use crate::design::{share, Design, Input, Job};
use crate::gcode::{self, GcodeStats};
use crate::geom::{DVec3, Mesh};
use crate::import::{self, ImportReport};
use crate::slice::{self, SliceReport};
use serde::Serialize;
use std::collections::BTreeMap;

/// Pipeline stages, in order, for progress reports.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Stage {
    /// Reading the input mesh.
    Import,
    /// Slicing and filling layers.
    Slice,
    /// Writing G-code.
    Gcode,
    /// Measuring the G-code (and building the preview).
    Analyze,
}

impl Stage {
    /// Lower-case name shown in progress bars.
    pub fn name(self) -> &'static str {
        match self {
            Stage::Import => "import",
            Stage::Slice => "slice",
            Stage::Gcode => "gcode",
            Stage::Analyze => "analyze",
        }
    }
}

/// Files available to a run, by name (uploaded on the page, `--input` on the CLI).
pub type Files = BTreeMap<String, Vec<u8>>;

/// Run options that are not part of the design.
#[derive(Clone, Debug, Default)]
pub struct RunOptions {
    /// Build preview buffers.
    pub collect_preview: bool,
}

/// Everything a run reports (`weft run --report`).
#[derive(Clone, Debug, Serialize)]
pub struct RunReport {
    /// Design name.
    pub name: String,
    /// Job kind.
    pub job: &'static str,
    /// Import repairs, when the input was a file.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub import: Option<ImportReport>,
    /// Slicer repairs and counts.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub slice: Option<SliceReport>,
    /// Writer totals.
    pub gcode: GcodeStats,
    /// The analyzer's reading of the written G-code.
    pub analysis: analyze::Report,
}

/// A run's products.
#[derive(Clone, Debug)]
pub struct RunOutput {
    /// The G-code.
    pub gcode: String,
    /// The report.
    pub report: RunReport,
    /// Preview buffers, when asked for.
    pub preview: Option<Preview>,
}

/// Why a run failed.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The design names a file that was not given.
    #[error("the design slices '{name}', which is not loaded; load {name} (drop it on the page, or pass --input {name})")]
    MissingInput {
        /// File name.
        name: String,
    },
    /// The embedded mesh in a share link is damaged.
    #[error("the mesh embedded in the design is damaged: {0}")]
    Embedded(share::Error),
    /// Import failed.
    #[error(transparent)]
    Import(#[from] import::Error),
    /// Slicing failed.
    #[error("slicing: {0}")]
    Slice(#[from] slice::Error),
    /// Writing failed.
    #[error("G-code: {0}")]
    Gcode(#[from] gcode::Error),
    /// Reading back failed (a bug: weft's own G-code must always analyse).
    #[error("analysing the written G-code: {0}")]
    Analyze(#[from] analyze::Error),
}

/// Resolves an input to a mesh placed on the plate: XY centred on 0, lowest point at Z = 0.
pub fn load_input(input: &Input, files: &Files) -> Result<(Mesh, Option<ImportReport>), Error> {
    let (mut mesh, report) = match input {
        Input::Builtin(shape) => (shape.mesh(), None),
        Input::File { name, embedded } => {
            let unpacked;
            let bytes: &[u8] = match (files.get(name), embedded) {
                (Some(b), _) => b,
                (None, Some(e)) => {
                    unpacked = share::unpack(e).map_err(Error::Embedded)?;
                    &unpacked
                }
                (None, None) => return Err(Error::MissingInput { name: name.clone() }),
            };
            let imported = import::read_mesh(name, bytes, &import::Options::default())?;
            (imported.mesh, Some(imported.report))
        }
    };
    if let Some(b) = mesh.bounds() {
        let c = (b.min + b.max) * 0.5;
        mesh.translate(DVec3::new(-c.x, -c.y, -b.min.z));
    }
    Ok((mesh, report))
}

/// Runs the design. `progress(stage, fraction_of_stage)` is called as work proceeds.
pub fn run(
    design: &Design,
    files: &Files,
    options: &RunOptions,
    progress: &mut dyn FnMut(Stage, f32),
) -> Result<RunOutput, Error> {
    let (toolpath, import_report, slice_report) = match &design.job {
        Job::Slice(job) => {
            progress(Stage::Import, 0.0);
            let (mesh, import_report) = load_input(&job.input, files)?;
            progress(Stage::Import, 1.0);
            progress(Stage::Slice, 0.0);
            let sliced = slice::slice(&mesh, &job.slice, &mut |f| progress(Stage::Slice, f))?;
            progress(Stage::Slice, 1.0);
            (sliced.toolpath, import_report, Some(sliced.report))
        }
    };
    progress(Stage::Gcode, 0.0);
    let written = gcode::write_gcode(
        &toolpath,
        &gcode::Options {
            printer: design.printer.clone(),
            material: design.material.clone(),
            speeds: design.speeds.clone(),
            design_name: design.name.clone(),
        },
    )?;
    drop(toolpath);
    progress(Stage::Gcode, 1.0);
    progress(Stage::Analyze, 0.0);
    let analysis = analyze::analyze(
        &format!("{}.gcode", design.name),
        written.text.as_bytes(),
        &analyze::Options {
            collect_preview: options.collect_preview,
            default_line_width_mm: design.printer.nozzle_diameter_mm,
            filament_diameter_mm: design.printer.filament_diameter_mm,
        },
    )?;
    progress(Stage::Analyze, 1.0);
    Ok(RunOutput {
        gcode: written.text,
        report: RunReport {
            name: design.name.clone(),
            job: design.job.kind(),
            import: import_report,
            slice: slice_report,
            gcode: written.stats,
            analysis: analysis.report,
        },
        preview: analysis.preview,
    })
}

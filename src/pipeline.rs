//! Runs a [`Design`] end to end: resolve input → import → slice → G-code → analyze.
//!
//! The CLI and the wasm binding both call [`run`]; nothing else orchestrates stages.

use crate::analyze::{self, Preview};
use crate::design::{share, Design, Input, Job, LatticeJob};
use crate::geom::{StrokeLayer, Toolpath};
use crate::lattice::{self, LatticeReport};
use crate::nonplanar::{self, ProjectionReport};
use crate::paths::{self, PathsReport};
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
    /// Generating the lattice of every layer.
    Lattice,
    /// Optimising print paths.
    Paths,
    /// Projecting onto a non-planar surface.
    NonPlanar,
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
            Stage::Lattice => "lattice",
            Stage::Paths => "paths",
            Stage::NonPlanar => "nonplanar",
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
    /// Lattice generation.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lattice: Option<LatticeReport>,
    /// Path optimisation per layer (scores, bounds, classes).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub paths: Option<PathsReport>,
    /// Non-planar projection.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub nonplanar: Option<ProjectionReport>,
    /// Writer totals.
    pub gcode: GcodeStats,
    /// The analyzer's reading of the written G-code.
    pub analysis: analyze::Report,
}

impl RunReport {
    /// An empty report for `design`, filled stage by stage.
    fn new(design: &Design) -> RunReport {
        RunReport {
            name: design.name.clone(),
            job: design.job.kind(),
            import: None,
            slice: None,
            lattice: None,
            paths: None,
            nonplanar: None,
            gcode: GcodeStats::default(),
            analysis: analyze::Report::default(),
        }
    }
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
    /// Lattice generation failed.
    #[error("lattice: {0}")]
    Lattice(#[from] lattice::Error),
    /// Path optimisation failed.
    #[error("paths: {0}")]
    Paths(#[from] paths::Error),
    /// Projection failed.
    #[error("non-planar: {0}")]
    NonPlanar(#[from] nonplanar::Error),
    /// A job that needs an input has none.
    #[error("{0}")]
    NoInput(String),
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
    let mut report = RunReport::new(design);
    let toolpath = match &design.job {
        Job::Slice(job) => {
            progress(Stage::Import, 0.0);
            let (mesh, import_report) = load_input(&job.input, files)?;
            report.import = import_report;
            progress(Stage::Import, 1.0);
            progress(Stage::Slice, 0.0);
            let sliced = slice::slice(&mesh, &job.slice, &mut |f| progress(Stage::Slice, f))?;
            progress(Stage::Slice, 1.0);
            report.slice = Some(sliced.report);
            sliced.toolpath
        }
        Job::Lattice(job) => run_lattice(design, job, files, &mut report, progress)?,
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
            machine: design.printer.machine.clone(),
        },
    )?;
    progress(Stage::Analyze, 1.0);
    report.gcode = written.stats;
    report.analysis = analysis.report;
    Ok(RunOutput { gcode: written.text, report, preview: analysis.preview })
}

/// The strut width of lattices: the nozzle diameter (d_n of equation 4).
fn lattice_line_width(design: &Design) -> f64 {
    design.printer.nozzle_diameter_mm
}

/// The domain of every layer: built-in planar shapes directly, a solid by slicing it every
/// layer thickness (regions only).
fn lattice_domains(
    job: &LatticeJob,
    files: &Files,
    report: &mut RunReport,
    progress: &mut dyn FnMut(Stage, f32),
) -> Result<Vec<lattice::LayerDomain>, Error> {
    if let Some(domains) = lattice::planar_domains(&job.domain, &job.lattice) {
        return Ok(domains);
    }
    let input = job
        .input
        .as_ref()
        .ok_or_else(|| Error::NoInput("a solid lattice domain needs a mesh: load one, or pass --input".into()))?;
    progress(Stage::Import, 0.0);
    let (mesh, import_report) = load_input(input, files)?;
    report.import = import_report;
    progress(Stage::Import, 1.0);
    let t = job.lattice.layer_thickness_mm;
    let options = slice::Options {
        first_layer_height_mm: t,
        layer_height_mm: t,
        perimeters: 0,
        infill_density: 0.0,
        solid_layers: 0,
        ..slice::Options::default()
    };
    progress(Stage::Slice, 0.0);
    let sliced = slice::slice(&mesh, &options, &mut |f| progress(Stage::Slice, f))?;
    progress(Stage::Slice, 1.0);
    report.slice = Some(sliced.report);
    Ok(sliced
        .layers
        .into_iter()
        .map(|l| lattice::LayerDomain { z: l.z, height: l.height, regions: l.regions, handles: Vec::new() })
        .collect())
}

/// Generates the lattice strokes of every layer (the page's 2D preview uses this too).
pub fn lattice_strokes(
    design: &Design,
    files: &Files,
    progress: &mut dyn FnMut(Stage, f32),
) -> Result<(Vec<StrokeLayer>, RunReport), Error> {
    let Job::Lattice(job) = &design.job else {
        return Err(Error::NoInput(format!("a {} job has no lattice", design.job.kind())));
    };
    let mut report = RunReport::new(design);
    let domains = lattice_domains(job, files, &mut report, progress)?;
    progress(Stage::Lattice, 0.0);
    let generated = lattice::generate(&domains, &job.lattice, lattice_line_width(design), design.seed, &mut |f| {
        progress(Stage::Lattice, f)
    })?;
    progress(Stage::Lattice, 1.0);
    report.lattice = Some(generated.report);
    Ok((generated.layers, report))
}

fn run_lattice(
    design: &Design,
    job: &LatticeJob,
    files: &Files,
    report: &mut RunReport,
    progress: &mut dyn FnMut(Stage, f32),
) -> Result<Toolpath, Error> {
    let (strokes, partial) = lattice_strokes(design, files, progress)?;
    report.import = partial.import;
    report.slice = partial.slice;
    report.lattice = partial.lattice;
    progress(Stage::Paths, 0.0);
    let optimised = paths::optimise(&strokes, &job.paths, lattice_line_width(design), design.seed, &mut |f| {
        progress(Stage::Paths, f)
    })?;
    drop(strokes);
    progress(Stage::Paths, 1.0);
    report.paths = Some(optimised.report);
    let Some(np) = &job.nonplanar else { return Ok(optimised.toolpath) };
    progress(Stage::NonPlanar, 0.0);
    let surface = match (&np.surface, &job.surface_input) {
        (nonplanar::Surface::Mesh, Some(input)) => Some(load_input(input, files)?.0),
        _ => None,
    };
    let projected = nonplanar::project(&optimised.toolpath, surface.as_ref(), np)?;
    progress(Stage::NonPlanar, 1.0);
    report.nonplanar = Some(projected.report);
    Ok(projected.toolpath)
}

//! The vocabulary of a job kind: its slots, stages, views, products, and the traits the
//! pipeline runs it through ([`JobKind`], [`Kind`]).

use super::*;

/// What a slot holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SlotKind {
    /// One solid: a closed mesh (STL, OBJ or 3MF); an open or inside-out one is repaired out
    /// loud or refused ([`crate::import::close`]).
    Mesh,
    /// Several solids, each with a label (foam regions), each checked as [`SlotKind::Mesh`].
    Meshes,
    /// One surface mesh, which may be open (a surface to print onto).
    Surface,
    /// A volume: a DICOM series (many files, a folder or a `.zip`), NRRD, raw + header.
    Volume,
    /// Another slicer's G-code, to edit.
    Gcode,
    /// A wireframe: JSON, OBJ `l` lines, CSV.
    Frame,
}

impl SlotKind {
    /// File name extensions a slot of this kind accepts (lower case, with the dot).
    pub fn accept(self) -> &'static [&'static str] {
        match self {
            SlotKind::Mesh | SlotKind::Surface => &[".stl", ".obj", ".3mf"],
            SlotKind::Meshes => &[".stl", ".obj", ".3mf", ".zip"],
            SlotKind::Volume => &[".dcm", ".zip", ".nrrd", ".nhdr", ".raw"],
            SlotKind::Gcode => &[".gcode", ".gco", ".g", ".nc"],
            SlotKind::Frame => &[".json", ".obj", ".csv", ".stl"],
        }
    }

    /// Its meshes must be closed solids.
    pub fn solid(self) -> bool {
        matches!(self, SlotKind::Mesh | SlotKind::Meshes)
    }

    /// Several files at once.
    pub fn multiple(self) -> bool {
        matches!(self, SlotKind::Meshes | SlotKind::Volume)
    }

    /// Refuses a file that a slot of this kind would refuse anyway, from its first bytes
    /// (`head`, up to [`FILE_HEAD_BYTES`]) and its length alone, so a front end refuses it
    /// before reading it into memory or hashing it: a mesh over the import's limits
    /// ([`crate::import::check_head`]), volume files over [`crate::volume::MAX_INPUT_BYTES`],
    /// G-code over the editor's limit, a wireframe over its reader's. `Ok` when the head and
    /// length cannot tell; the reader decides then. A series' files are checked one by one,
    /// and their total with `file` naming the series.
    pub fn check_file(self, file: &str, head: &[u8], len: u64) -> Result<(), String> {
        let len_usize = usize::try_from(len).unwrap_or(usize::MAX);
        match self {
            SlotKind::Mesh | SlotKind::Meshes | SlotKind::Surface => crate::import::check_head(file, head, len).map_err(|e| e.to_string()),
            SlotKind::Volume => crate::volume::check_input_bytes(file, len).map_err(|e| e.to_string()),
            SlotKind::Gcode => match crate::gcode_edit::estimate(len_usize, &crate::gcode_edit::Options::default()).refused {
                Some(r) => Err(format!("{file}: {r}")),
                None => Ok(()),
            },
            SlotKind::Frame if len_usize > crate::freeform::wireframe::MAX_BYTES => {
                Err(crate::freeform::wireframe::Error::TooBig { file: file.into(), bytes: len_usize }.to_string())
            }
            SlotKind::Frame => Ok(()),
        }
    }
}

/// Bytes of a file's head [`SlotKind::check_file`] looks at.
pub const FILE_HEAD_BYTES: usize = crate::import::HEAD_BYTES;

/// A named input of a job kind.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Slot {
    /// Name (`mesh`, `surface`), used by `--input SLOT=FILE`.
    pub name: &'static str,
    /// Label on the page's drop zone.
    pub label: &'static str,
    /// What it holds.
    pub kind: SlotKind,
    /// Dotted design path of the [`crate::design::Input`] it fills.
    pub path: &'static str,
    /// The job cannot run without it (with the current settings, the job's validation says).
    pub required: bool,
    /// One line on what the slot is for.
    pub doc: &'static str,
}

/// A stage of a job kind, in run order (the progress bar's steps).
#[derive(Clone, Copy, Debug, Serialize)]
pub struct StageInfo {
    /// Name reported with progress (`slice`).
    pub name: &'static str,
    /// Label shown to the user.
    pub label: &'static str,
}

/// The shapes of [`Inspection`] data the page has generic viewers for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Shape {
    /// 2D segments: `x0 y0 x1 y1 feature_code` (mm), stride 5.
    Lines2d,
    /// 3D segments: `x0 y0 z0 x1 y1 z1 feature_code` (mm), stride 7.
    Lines3d,
    /// A scalar image, `width × height` values row by row (`meta` gives the size).
    Image,
    /// Triangles: 9 floats each (mm).
    Mesh,
}

impl Shape {
    /// Floats per item.
    pub fn stride(self) -> usize {
        match self {
            Shape::Lines2d => 5,
            Shape::Lines3d => 7,
            Shape::Image => 1,
            Shape::Mesh => 9,
        }
    }
}

/// An extra view of a stage's output (the lattice's 2D layer, a CT slice, …).
#[derive(Clone, Copy, Debug, Serialize)]
pub struct ViewInfo {
    /// Id used in `inspect` requests.
    pub id: &'static str,
    /// The view has a card of its own among the results; false: it is drawn only by a step of
    /// "How it works" (a recording that costs nothing unless the steps are open).
    pub card: bool,
    /// The stage whose output it shows.
    pub stage: &'static str,
    /// Label of the view's card.
    pub label: &'static str,
    /// Data shape.
    pub shape: Shape,
    /// What the index counts (`Layer`).
    pub index_label: &'static str,
    /// One line on what it shows.
    pub doc: &'static str,
}

/// One step of a kind's "How it works" walk through its method: a view of the kind at an
/// index, with one or two plain sentences citing the paper's section or figure.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct StepInfo {
    /// Title of the step ("Pairing").
    pub title: &'static str,
    /// The kind's view drawn ([`ViewInfo::id`]).
    pub view: &'static str,
    /// The view's index shown (the first one when the step scrubs).
    pub index: usize,
    /// The step iterates: a scrubber and Play walk the view's indices (frames).
    pub scrub: bool,
    /// One or two plain sentences on what the step does.
    pub text: &'static str,
    /// Where the paper says it ("GIPPO §2.2, Fig. 3").
    pub cite: &'static str,
}

/// How the page first shows a kind's result, so it shows the method: the preview's colouring
/// (`feature`, `path`, `flow`, `e_per_mm`, `speed`, `width`) and a view drawn behind the
/// toolpath (a platform the path is printed on).
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Teach {
    /// The preview's colour mode on opening a result of this kind.
    pub color_by: &'static str,
    /// A `lines3d` view of the kind (at index 0) drawn faintly behind the toolpath, in the
    /// toolpath's frame (mm); none by default.
    pub backdrop: Option<&'static str>,
}

/// The answer to an `inspect(view, index)` request.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Inspection {
    /// The view.
    pub view: String,
    /// Data shape.
    pub shape: Shape,
    /// The index shown (clamped to `0..count`).
    pub index: usize,
    /// How many indices there are.
    pub count: usize,
    /// Floats per item.
    pub stride: usize,
    /// The data.
    #[serde(skip)]
    pub data: Vec<f32>,
    /// Lines drawn over the data, `x0 y0 x1 y1 code` (stride 5) in the data's mm frame (an
    /// image's iso-contours); `meta.overlay_legend` names each code. Usually empty.
    #[serde(skip)]
    pub overlay: Vec<f32>,
    /// Shape-specific facts (an image's `width` and `height`, value range, …); `legend`, an
    /// object of feature code → words, names what the view draws with each feature colour.
    pub meta: Value,
}

/// What a job produces for the writer.
pub enum Product {
    /// A toolpath (a stage output, with its key), written by the G-code stage.
    Toolpath(Out<Toolpath>),
    /// Finished G-code (another slicer's file, edited): the writer is skipped and the
    /// analyzer reads it as it is; the run's writer totals are the analyzer's.
    Gcode(Out<String>),
}

/// A job kind, as the pipeline, the design and the page see it. Implement [`Kind`] (typed)
/// rather than this.
pub trait JobKind: Sync {
    /// Name written in `job.kind`.
    fn name(&self) -> &'static str;
    /// Label in the page's job menu.
    fn label(&self) -> &'static str;
    /// One line on what the job makes.
    fn doc(&self) -> &'static str;
    /// Form rows of its settings, mounted at their design paths (`job.…`).
    fn fields(&self) -> Vec<Row>;
    /// Input slots.
    fn slots(&self) -> &'static [Slot];
    /// Stages in run order (the pipeline adds `gcode` and `analyze`).
    fn stages(&self) -> &'static [StageInfo];
    /// Extra views.
    fn views(&self) -> &'static [ViewInfo];
    /// The method's steps, in order, each drawn by one of [`JobKind::views`].
    fn steps(&self) -> &'static [StepInfo];
    /// How the page first shows a result of this kind ([`Teach`]).
    fn teach(&self) -> Teach;
    /// The default `job` object (with `kind`).
    fn default_job(&self) -> Value;
    /// The `job` object parsed and written back with every default filled in, or serde's
    /// error with the path of the field (relative to `job`), which the design puts in words.
    fn normalize(&self, job: &Value) -> Result<Value, serde_path_to_error::Error<serde_json::Error>>;
    /// Rules that tie fields together (ranges are checked from [`JobKind::fields`]).
    fn validate(&self, design: &Design, job: &Value, out: &mut Vec<Problem>);
    /// `job` after a file was put in `slot` (a lattice fills a loaded solid).
    fn slot_filled(&self, _slot: &str, job: Value) -> Value {
        job
    }
    /// The whole design (as JSON) when it has just switched to this kind: a kind that only
    /// runs on some machines puts one in place (the axisymmetric job needs a 5-axis head).
    fn adopted(&self, _design: &mut Value) {}
    /// The work of the job's own stages, stated before running them (each stage's
    /// `estimate`), in run order; the last one states `segments`, the toolpath segments the
    /// writer will get. May import meshes (bounded by their own estimate) but runs no stage.
    fn estimate(&self, ctx: &mut Ctx) -> Result<Vec<Estimate>, Error>;
    /// Runs the job's own stages.
    fn run(&self, ctx: &mut Ctx) -> Result<Product, Error>;
    /// Data of view `view` at `index`.
    fn inspect(&self, ctx: &mut Ctx, view: &str, index: usize) -> Result<Inspection, Error>;
}

/// A job kind with typed settings; every `Kind` is a [`JobKind`].
pub trait Kind: Sync {
    /// The settings: the `job` object without `kind`.
    type Settings: Serialize + DeserializeOwned + Default;
    /// Name written in `job.kind`.
    const NAME: &'static str;
    /// Label in the page's job menu.
    const LABEL: &'static str;
    /// One line on what the job makes.
    const DOC: &'static str;
    /// Input slots.
    const SLOTS: &'static [Slot];
    /// Stages in run order.
    const STAGES: &'static [StageInfo];
    /// Extra views.
    const VIEWS: &'static [ViewInfo] = &[];
    /// The method's steps ("How it works"), each naming one of [`Kind::VIEWS`].
    const STEPS: &'static [StepInfo] = &[];
    /// How the page first shows a result: the colouring and backdrop that show the method.
    const TEACH: Teach = Teach { color_by: "feature", backdrop: None };
    /// Form rows (mounted at design paths, e.g. with [`crate::settings::mount`]).
    fn fields() -> Vec<Row>;
    /// Cross-field rules.
    fn validate(_design: &Design, _settings: &Self::Settings, _out: &mut Vec<Problem>) {}
    /// The settings after a file was put in `slot`.
    fn slot_filled(_slot: &str, settings: Self::Settings) -> Self::Settings {
        settings
    }
    /// The design (JSON) after switching to this kind (see [`JobKind::adopted`]).
    fn adopted(_design: &mut Value) {}
    /// The work of its stages, stated before running (see [`JobKind::estimate`]).
    fn estimate(settings: &Self::Settings, ctx: &mut Ctx) -> Result<Vec<Estimate>, Error>;
    /// Runs the job's stages.
    fn run(settings: &Self::Settings, ctx: &mut Ctx) -> Result<Product, Error>;
    /// Data of a view.
    fn inspect(_settings: &Self::Settings, _ctx: &mut Ctx, view: &str, _index: usize) -> Result<Inspection, Error> {
        Err(Error::UnknownView { view: view.into(), job: Self::NAME })
    }
}

/// The typed settings of `job` (a normalised `job` object).
pub fn settings<T: DeserializeOwned>(job: &Value) -> Result<T, Error> {
    crate::design::job_settings(job).map_err(|e| Error::BadJob(e.to_string()))
}

pub use crate::design::with_kind;

impl<K: Kind> JobKind for K {
    fn name(&self) -> &'static str {
        K::NAME
    }
    fn label(&self) -> &'static str {
        K::LABEL
    }
    fn doc(&self) -> &'static str {
        K::DOC
    }
    fn fields(&self) -> Vec<Row> {
        let mut rows = K::fields();
        for r in &mut rows {
            r.job = Some(K::NAME);
        }
        rows
    }
    fn slots(&self) -> &'static [Slot] {
        K::SLOTS
    }
    fn stages(&self) -> &'static [StageInfo] {
        K::STAGES
    }
    fn views(&self) -> &'static [ViewInfo] {
        K::VIEWS
    }
    fn steps(&self) -> &'static [StepInfo] {
        K::STEPS
    }
    fn teach(&self) -> Teach {
        K::TEACH
    }
    fn default_job(&self) -> Value {
        with_kind(K::NAME, &K::Settings::default()).unwrap_or(Value::Null)
    }
    fn normalize(&self, job: &Value) -> Result<Value, serde_path_to_error::Error<serde_json::Error>> {
        let s: K::Settings = serde_path_to_error::deserialize(crate::design::without_kind(job))?;
        // Writing back settings just read cannot fail (string keys only); were it to, the job
        // stays as given.
        Ok(with_kind(K::NAME, &s).unwrap_or_else(|_| job.clone()))
    }
    fn validate(&self, design: &Design, job: &Value, out: &mut Vec<Problem>) {
        if let Ok(s) = settings::<K::Settings>(job) {
            K::validate(design, &s, out);
        }
    }
    fn adopted(&self, design: &mut Value) {
        K::adopted(design)
    }
    fn slot_filled(&self, slot: &str, job: Value) -> Value {
        match settings::<K::Settings>(&job) {
            Ok(s) => with_kind(K::NAME, &K::slot_filled(slot, s)).unwrap_or(job),
            Err(_) => job,
        }
    }
    fn estimate(&self, ctx: &mut Ctx) -> Result<Vec<Estimate>, Error> {
        let s: K::Settings = settings(&ctx.design.job.value)?;
        K::estimate(&s, ctx)
    }
    fn run(&self, ctx: &mut Ctx) -> Result<Product, Error> {
        let s: K::Settings = settings(&ctx.design.job.value)?;
        K::run(&s, ctx)
    }
    fn inspect(&self, ctx: &mut Ctx, view: &str, index: usize) -> Result<Inspection, Error> {
        let s: K::Settings = settings(&ctx.design.job.value)?;
        K::inspect(&s, ctx, view, index)
    }
}

//! The only module that knows about JavaScript (compiled for wasm32 only).
//!
//! Free functions serve the page's cheap synchronous needs (schema, validation, share
//! links); [`Session`] lives in the Web Worker and holds the loaded files, the stage cache
//! (so an edit re-runs only the stages it affects) and the last result. Structured values
//! (schema, reports, inspections) cross as plain JS objects through serde-wasm-bindgen; bulk
//! data leaves as typed arrays copied once out of wasm memory, which the worker then
//! transfers (not copies) to the page.

use crate::analyze::{self, Preview};
use crate::catalog::{schema, share};
use crate::design::{Design, Input};

use crate::gcode_edit;
use crate::import::group;
use crate::kinds::{Registry, SlotKind};
use crate::pipeline::{self, Cache, Files, RunOptions};
use crate::source::ByteSource;
use serde::Serialize;
use std::sync::Arc;
use wasm_bindgen::prelude::*;

#[wasm_bindgen(start)]
fn start() {
    console_error_panic_hook::set_once();
    // The core's wall clock for reports (planning time): the page's Date.now().
    crate::clock::set(|| js_sys::Date::now() / 1000.0);
}

/// The thread pool of the threaded module (`--features wasm-threads`, pkg/threads/).
///
/// rayon's global pool is built here with a spawn handler that only queues each thread's
/// builder; the page starts one web worker per thread with this module and its shared memory
/// (www/pool-worker.js), and each calls [`run_pool_thread`], which takes a builder and runs
/// rayon's loop on that worker for good. The page owns those workers, so Cancel terminates
/// them with the computing worker: a pool spawned by the worker itself (wasm-bindgen-rayon's
/// way) is made of nested workers, which Chromium keeps running after their parent is
/// terminated (measured: the old pool went on slicing for seconds after Cancel), holding the
/// whole memory.
#[cfg(feature = "wasm-threads")]
mod thread_pool {
    use std::sync::{mpsc, Mutex, OnceLock};
    use wasm_bindgen::prelude::*;

    /// The pool's threads go from `startThreadPool` (the sender, taken once) to the pool
    /// workers (the receiver). Two locks, not one: a pool worker that comes before
    /// `startThreadPool` waits in `recv` holding the receiver's, which must not keep
    /// `startThreadPool` from the sender (it would wait for ever).
    static SENDER: Mutex<Option<mpsc::Sender<rayon::ThreadBuilder>>> = Mutex::new(None);
    static RECEIVER: OnceLock<Mutex<mpsc::Receiver<rayon::ThreadBuilder>>> = OnceLock::new();

    fn poisoned<T>(_: T) -> JsError {
        JsError::new("the thread pool's queue is poisoned")
    }

    /// What a pool worker needs to join, and where the page sets Cancel: `[module, memory,
    /// cancel word's byte address]` (the memory is shared; see `par::cancel_flag`). Call
    /// first: the pool workers wait on the queue it makes.
    #[wasm_bindgen(js_name = threadPoolShare)]
    pub fn thread_pool_share() -> Result<js_sys::Array, JsError> {
        let mut made = Ok(());
        RECEIVER.get_or_init(|| {
            let (tx, rx) = mpsc::channel();
            made = SENDER.lock().map(|mut s| *s = Some(tx)).map_err(poisoned);
            Mutex::new(rx)
        });
        made?;
        let cancel_at = crate::par::cancel_flag() as *const std::sync::atomic::AtomicU32 as usize;
        Ok(js_sys::Array::of3(&wasm_bindgen::module(), &wasm_bindgen::memory(), &JsValue::from_f64(cancel_at as f64)))
    }

    /// Builds rayon's global pool of `threads` threads, each handed to a pool worker through
    /// the queue. Blocks until every thread runs (rayon waits for them), so the page must
    /// have started `threads` pool workers.
    #[wasm_bindgen(js_name = startThreadPool)]
    pub fn start_thread_pool(threads: usize) -> Result<(), JsError> {
        let tx = SENDER.lock().map_err(poisoned)?.take().ok_or_else(|| JsError::new("threadPoolShare first, and the pool starts once"))?;
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads.max(1))
            .spawn_handler(move |thread| tx.send(thread).map_err(|_| std::io::Error::other("no pool queue")))
            .build_global()
            .map_err(|e| JsError::new(&format!("the thread pool could not start: {e}")))?;
        // Once every pool thread has run a task, each has its thread-local storage: the
        // allocator's per-thread caches may be used from then on (no thread starts later).
        rayon::broadcast(|_| ());
        crate::thread_cache::enable();
        Ok(())
    }

    /// Runs one of the pool's threads on the calling pool worker: waits for its turn on the
    /// queue, then runs rayon's loop; returns only when the pool ends (never, in the page: the
    /// worker is terminated).
    #[wasm_bindgen(js_name = runPoolThread)]
    pub fn run_pool_thread() -> Result<(), JsError> {
        let rx = RECEIVER.get().ok_or_else(|| JsError::new("threadPoolShare was not called"))?;
        // Held while waiting: the pool workers take their threads one after another.
        let builder = rx.lock().map_err(poisoned)?.recv().map_err(|_| JsError::new("every thread of the pool has its worker"))?;
        builder.run();
        Ok(())
    }
}

fn js_err(e: impl std::fmt::Display) -> JsError {
    JsError::new(&e.to_string())
}

/// A plain JS object (maps as objects, not `Map`s) from a Rust value.
fn to_js<T: Serialize + ?Sized>(value: &T) -> Result<JsValue, JsError> {
    value.serialize(&serde_wasm_bindgen::Serializer::json_compatible()).map_err(js_err)
}

/// A default design (pretty JSON).
#[wasm_bindgen(js_name = defaultDesign)]
pub fn default_design() -> String {
    Design::default().to_json_pretty()
}

/// Everything the page builds its form, menus, progress and colours from (an object).
#[wasm_bindgen(js_name = designSchema)]
pub fn design_schema() -> Result<JsValue, JsError> {
    to_js(&schema::schema(&Registry::builtin()))
}

/// Runs a design that needs no files and draws its result as a small SVG (the example list's
/// thumbnails, made by scripts/build-www.sh).
#[wasm_bindgen(js_name = thumbnailSvg)]
pub fn thumbnail_svg(json: &str, size_px: u32) -> Result<String, JsError> {
    let design = Design::from_json("design", json).map_err(js_err)?;
    let out = pipeline::run(&design, &Files::new(), &RunOptions { collect_preview: true }, &mut |_, _| {}).map_err(js_err)?;
    let preview = out.preview.unwrap_or_default();
    Ok(crate::thumbnail::svg(&preview, &crate::thumbnail::Options { size_px, ..Default::default() }))
}

/// Parses and validates a design; returns it normalised (pretty JSON).
#[wasm_bindgen(js_name = validateDesign)]
pub fn validate_design(json: &str) -> Result<String, JsError> {
    Design::from_json("design", json).map(|d| d.to_json_pretty()).map_err(js_err)
}

/// Sets one field (`path` dotted, `value` JSON or plain text) and returns the new design.
#[wasm_bindgen(js_name = setField)]
pub fn set_field(json: &str, path: &str, value: &str) -> Result<String, JsError> {
    let d = Design::from_json("design", json).map_err(js_err)?;
    d.with_overrides(&[format!("{path}={value}")]).map(|d| d.to_json_pretty()).map_err(|e| match e {
        // The page edits one field at a time: name it, not the CLI's `--set` form.
        crate::design::Error::Override { message, .. } => JsError::new(&format!("{path}: {message}")),
        other => js_err(other),
    })
}

/// Puts a loaded file (or several, for a slot that takes several) in `slot` of the design
/// and applies the job kind's rule for a filled slot; returns the new design (pretty JSON).
#[wasm_bindgen(js_name = fillSlot)]
pub fn fill_slot(json: &str, slot: &str, names: Vec<String>) -> Result<String, JsError> {
    let d = Design::from_json("design", json).map_err(js_err)?;
    let input = match names.as_slice() {
        [one] => Input::File { name: one.clone(), embedded: None },
        _ => Input::Files(names),
    };
    d.with_slot_input(&Registry::builtin(), slot, input).map(|d| d.to_json_pretty()).map_err(js_err)
}

/// A binary STL of a `mesh` view's triangles (9 floats each, mm).
#[wasm_bindgen(js_name = meshStl)]
pub fn mesh_stl(triangles: &[f32], name: &str) -> Vec<u8> {
    crate::isosurface::write_stl(&crate::geom::Mesh::from_triangle_floats(triangles), name)
}

/// A share-link fragment for the design with the given files (`[{slot, name, bytes}]`);
/// returns `{fragment, embedded: [names], missing: [names], note}`.
#[wasm_bindgen(js_name = encodeShare)]
pub fn encode_share(design_json: &str, files: JsValue) -> Result<JsValue, JsError> {
    let d = Design::from_json("design", design_json).map_err(js_err)?;
    let mut owned: Vec<(String, Vec<u8>)> = Vec::new();
    if let Some(list) = files.dyn_ref::<js_sys::Array>() {
        for item in list.iter() {
            let name = js_sys::Reflect::get(&item, &"name".into()).ok().and_then(|v| v.as_string());
            let bytes = js_sys::Reflect::get(&item, &"bytes".into()).ok().filter(|b| b.is_object());
            if let (Some(name), Some(bytes)) = (name, bytes) {
                owned.push((name, js_sys::Uint8Array::new(&bytes).to_vec()));
            }
        }
    }
    let list: Vec<(&str, &[u8])> = owned.iter().map(|(n, b)| (n.as_str(), b.as_slice())).collect();
    to_js(&share::encode(&d, &list))
}

/// The design in a share-link fragment (pretty JSON).
#[wasm_bindgen(js_name = decodeShare)]
pub fn decode_share(fragment: &str) -> Result<String, JsError> {
    share::decode(fragment).map(|d| d.to_json_pretty()).map_err(js_err)
}

/// What `addFile` says about a file.
#[derive(Serialize)]
struct Loaded {
    slot: String,
    name: String,
    kind: SlotKind,
    summary: String,
    report: serde_json::Value,
}

/// A `Blob` read in ranges with `FileReaderSync` (synchronous, which the worker's synchronous
/// calls need; workers only). A dropped file's bytes stay in the browser's blob store.
struct BlobSource {
    blob: web_sys::Blob,
    reader: web_sys::FileReaderSync,
    len: usize,
}

fn js_message(v: JsValue) -> String {
    v.dyn_ref::<js_sys::Error>().map(|e| String::from(e.message())).or_else(|| v.as_string()).unwrap_or_else(|| "the browser refused".into())
}

impl BlobSource {
    fn new(blob: web_sys::Blob) -> Result<BlobSource, JsError> {
        let reader = web_sys::FileReaderSync::new()
            .map_err(|e| JsError::new(&format!("files cannot be read here ({}): weft reads them in its worker", js_message(e))))?;
        let len = blob.size() as usize;
        Ok(BlobSource { blob, reader, len })
    }
}

/// All of `source`, read in pieces ([`crate::source::read_all`]); `name` names it in the error.
fn read_whole(source: &BlobSource, name: &str) -> Result<Vec<u8>, JsError> {
    crate::source::read_all(source).map(std::borrow::Cow::into_owned).map_err(|m| JsError::new(&format!("{name} could not be read ({m}); load it again")))
}

impl ByteSource for BlobSource {
    fn len(&self) -> usize {
        self.len
    }
    fn read_at(&self, offset: usize, buf: &mut [u8]) -> Result<(), String> {
        let part = self.blob.slice_with_f64_and_f64(offset as f64, (offset + buf.len()) as f64).map_err(js_message)?;
        let bytes = js_sys::Uint8Array::new(&self.reader.read_as_array_buffer(&part).map_err(js_message)?.into());
        if bytes.length() as usize != buf.len() {
            return Err(format!("{} bytes came back where {} were asked for", bytes.length(), buf.len()));
        }
        bytes.copy_to(buf);
        Ok(())
    }
}

/// State held by the worker: loaded files, the stage cache and the last result.
#[wasm_bindgen]
pub struct Session {
    registry: Registry,
    files: Files,
    cache: Cache,
    gcode: Arc<String>,
    /// The last run's binary G-code, when its printer asks for it.
    bgcode: Option<Arc<Vec<u8>>>,
    preview: Arc<Preview>,
    bed: [f64; 3],
}

impl Default for Session {
    fn default() -> Self {
        Self::new()
    }
}

fn f32_array(v: &[f32]) -> js_sys::Float32Array {
    js_sys::Float32Array::from(v)
}

fn u32_array(v: &[u32]) -> js_sys::Uint32Array {
    js_sys::Uint32Array::from(v)
}

#[wasm_bindgen]
impl Session {
    /// An empty session.
    #[wasm_bindgen(constructor)]
    pub fn new() -> Session {
        Session {
            registry: Registry::builtin(),
            files: Files::new(),
            cache: Cache::new(),
            gcode: Arc::default(),
            bgcode: None,
            preview: Arc::default(),
            bed: Design::default().printer.bed_size_mm,
        }
    }

    /// Keeps a file for `slot` (its bytes copied into the session) and reads it now with the
    /// slot kind's reader, so a bad file is reported at once (a mesh is imported into the stage
    /// cache: the run does not read it again). Returns `{slot, name, kind, summary, report}`.
    #[wasm_bindgen(js_name = addFile)]
    pub fn add_file(&mut self, slot: &str, name: &str, bytes: Vec<u8>) -> Result<JsValue, JsError> {
        let kind = self.slot_kind(slot)?;
        self.files.insert(name.to_string(), bytes);
        self.check_loaded(slot, name, kind)
    }

    /// Keeps a dropped file (a `Blob`, as the page has it) for `slot`, as
    /// [`Session::add_file`] does. Volumes and G-code stay in the browser's blob store and are
    /// read in pieces when a stage needs them (a 50 MB G-code is edited without a copy of it
    /// in wasm memory); meshes and wireframes are read in now.
    #[wasm_bindgen(js_name = addBlob)]
    pub fn add_blob(&mut self, slot: &str, name: &str, blob: web_sys::Blob) -> Result<JsValue, JsError> {
        let kind = self.slot_kind(slot)?;
        // A file the slot would refuse anyway, refused from its head and its size as the
        // browser states it, before it is copied here or hashed (a file of gigabytes does not
        // fit this memory; hashing it takes seconds).
        let size = blob.size();
        let source = BlobSource::new(blob)?;
        let mut head = vec![0u8; source.len.min(crate::kinds::FILE_HEAD_BYTES)];
        source.read_at(0, &mut head).map_err(|m| JsError::new(&format!("{name} could not be read ({m}); load it again")))?;
        // Every kind's limit is under 4 GiB (a unit test in `kinds` holds it), so `source.len`,
        // a `usize` here, is the file's whole size past this check.
        kind.check_file(name, &head, size as u64).map_err(|m| JsError::new(&m))?;
        match kind {
            SlotKind::Volume | SlotKind::Gcode => {
                self.files
                    .insert_source(name.to_string(), Arc::new(source))
                    .map_err(|m| JsError::new(&format!("{name} could not be read ({m}); load it again")))?;
                self.check_loaded(slot, name, kind)
            }
            SlotKind::Mesh | SlotKind::Meshes | SlotKind::Surface | SlotKind::Frame => {
                let bytes = read_whole(&source, name)?;
                self.add_file(slot, name, bytes)
            }
        }
    }

    fn slot_kind(&self, slot: &str) -> Result<SlotKind, JsError> {
        self.slot(slot).map(|s| s.kind)
    }

    fn slot(&self, slot: &str) -> Result<&'static crate::kinds::Slot, JsError> {
        self.registry.slot(slot).ok_or_else(|| JsError::new(&format!("no job kind has an input slot '{slot}'")))
    }

    /// Reads a just-loaded file with its slot kind's reader; forgets it if it is refused.
    fn check_loaded(&mut self, slot: &str, name: &str, kind: SlotKind) -> Result<JsValue, JsError> {
        let size = self.files.source(name).map_or(0, |s| s.len());
        let (summary, report) = match kind {
            // A zip of region meshes: its mesh files listed now, each read when the job runs.
            SlotKind::Meshes if name.to_ascii_lowercase().ends_with(".zip") => {
                let listed = match self.files.get(name) {
                    Some(bytes) => pipeline::meshes_of_zip(name, bytes),
                    None => Err(format!("{name} could not be read; load it again")),
                };
                match listed {
                    Ok((meshes, _)) => {
                        let names: Vec<&str> = meshes.iter().map(|(n, _)| n.as_str()).collect();
                        (format!("a zip of {} mesh(es): {}", names.len(), names.join(", ")), serde_json::Value::Null)
                    }
                    Err(m) => {
                        self.files.remove(name);
                        return Err(JsError::new(&m));
                    }
                }
            }
            SlotKind::Mesh | SlotKind::Meshes | SlotKind::Surface => {
                let spec = self.slot(slot)?;
                let design = Design::default();
                let mut quiet = |_: &str, _: f32| {};
                let mut ctx = pipeline::Ctx::new(&design, &self.files, &mut self.cache, &mut quiet);
                let input = Input::File { name: name.to_string(), embedded: None };
                match ctx.mesh(spec, &input) {
                    Ok(mesh) => {
                        let report = ctx.reports.first().map(|r| r.data.clone()).unwrap_or_default();
                        let notes = ctx.reports.first().map(|r| r.notes.join("; ")).unwrap_or_default();
                        let size = mesh.bounds().map(|b| b.max - b.min).unwrap_or_default();
                        let tris = mesh.triangles.len();
                        let said = if notes.is_empty() { String::new() } else { format!(" ({notes})") };
                        (format!("{} triangles, {:.1} × {:.1} × {:.1} mm{said}", group(tris as u64), size.x, size.y, size.z), report)
                    }
                    Err(e) => {
                        self.files.remove(name);
                        return Err(js_err(e));
                    }
                }
            }
            SlotKind::Gcode => {
                // Every line read as G-code (in pieces when the file stays outside), the part's box.
                let read = match self.files.source(name) {
                    Some(source) => gcode_edit::printed_bounds(name, &source),
                    None => Err(gcode_edit::Error::Read { file: name.into(), message: "not loaded".into() }),
                };
                match read {
                    Ok(b) => {
                        let d = b.max - b.min;
                        let amount = if size >= 1_000_000 { format!("{:.1} MB", size as f64 / 1e6) } else { format!("{:.1} kB", size as f64 / 1e3) };
                        (format!("{amount} of G-code, printing {:.1} × {:.1} × {:.1} mm", d.x, d.y, d.z), serde_json::Value::Null)
                    }
                    Err(e) => {
                        self.files.remove(name);
                        return Err(js_err(e));
                    }
                }
            }
            // A wireframe is read now, so a file that is not one is refused on loading, naming
            // its problems.
            SlotKind::Frame => {
                let read = match self.files.get(name) {
                    Some(bytes) => crate::freeform::wireframe::read(name, bytes, &crate::freeform::wireframe::Options::default()),
                    None => Err(crate::freeform::wireframe::Error::NotRead { file: name.into(), place: "the file".into(), message: "not loaded".into() }),
                };
                match read {
                    Ok(w) => {
                        let first = w.joints.first().copied().unwrap_or_default();
                        let (lo, hi) = w.joints.iter().fold((first, first), |(a, b), p| (a.min(*p), b.max(*p)));
                        let d = hi - lo;
                        // What reading assumed and what stands on the plate, said on loading.
                        let g = crate::freeform::wireframe::grounding(&w, crate::freeform::wireframe::DEFAULT_GROUND_TOLERANCE_MM);
                        let mut said: Vec<String> = w.notes.clone();
                        said.push(g.statement());
                        said.extend(g.warning());
                        (
                            format!(
                                "{} beams, {} joints, {:.1} × {:.1} × {:.1} mm ({})",
                                group(w.beams.len() as u64),
                                group(w.joints.len() as u64),
                                d.x,
                                d.y,
                                d.z,
                                said.join("; ")
                            ),
                            serde_json::Value::Null,
                        )
                    }
                    Err(e) => {
                        self.files.remove(name);
                        return Err(js_err(e));
                    }
                }
            }
            // Read by the job kinds that use them (volumes), when they run.
            SlotKind::Volume => (format!("{} bytes", group(size as u64)), serde_json::Value::Null),
        };
        to_js(&Loaded { slot: slot.into(), name: name.into(), kind, summary, report })
    }

    /// Drops the recordings the steps of "How it works" made (they were closed); returns how
    /// many.
    #[wasm_bindgen(js_name = dropRecordings)]
    pub fn drop_recordings(&mut self) -> usize {
        self.cache.drop_recordings()
    }

    /// Forgets a file (and the stage outputs made from it at the next run).
    #[wasm_bindgen(js_name = removeFile)]
    pub fn remove_file(&mut self, name: &str) -> bool {
        self.files.remove(name)
    }

    /// Runs a design; `on_progress(stage, fraction)`; `on_ahead({stage, label, done, total},
    /// gcode)` gets the G-code a stage sends ahead while the run goes on (a `Uint8Array` the
    /// caller owns, see [`pipeline::Ahead`]); returns the run report (an object).
    pub fn run(&mut self, design_json: &str, on_progress: &js_sys::Function, on_ahead: Option<js_sys::Function>) -> Result<JsValue, JsError> {
        let design = Design::from_json("design", design_json).map_err(js_err)?;
        let mut progress = |stage: &str, f: f32| {
            // Cancelled by the page (threaded module): leave at once, as a JS exception, so
            // the worker is idle when its terminate() comes (see `par::cancel_flag`).
            if crate::par::cancelled() {
                wasm_bindgen::throw_str("cancelled");
            }
            let _ = on_progress.call2(&JsValue::NULL, &JsValue::from_str(stage), &JsValue::from_f64(f as f64));
        };
        let ahead = |a: &pipeline::Ahead| {
            let Some(f) = &on_ahead else { return };
            let info = serde_json::json!({ "stage": a.stage, "label": a.label, "done": a.done, "total": a.total });
            if let Ok(info) = to_js(&info) {
                let _ = f.call2(&JsValue::NULL, &info, &js_sys::Uint8Array::from(a.gcode.as_bytes()));
            }
        };
        let out = pipeline::run_sending(&self.registry, &mut self.cache, &design, &self.files, &RunOptions { collect_preview: true }, &mut progress, &ahead)
            .map_err(js_err)?;
        self.gcode = out.gcode;
        self.bgcode = out.bgcode;
        self.preview = out.preview.unwrap_or_default();
        self.bed = design.printer.bed_size_mm;
        to_js(&out.report)
    }

    /// The run's plan before running it (every stage's estimate; `ask` when the page should
    /// ask first, `refused` when a budget is exceeded): see [`crate::budget::Plan`].
    pub fn estimate(&mut self, design_json: &str) -> Result<JsValue, JsError> {
        let design = Design::from_json("design", design_json).map_err(js_err)?;
        let plan = pipeline::estimate(&self.registry, &mut self.cache, &design, &self.files).map_err(js_err)?;
        to_js(&plan)
    }

    /// Data of view `view` at `index` of the design's job: `{view, shape, index, count,
    /// stride, data: Float32Array, meta}`.
    pub fn inspect(&mut self, design_json: &str, view: &str, index: usize) -> Result<JsValue, JsError> {
        let design = Design::from_json("design", design_json).map_err(js_err)?;
        let found = pipeline::inspect(&self.registry, &mut self.cache, &design, &self.files, view, index).map_err(js_err)?;
        let obj = to_js(&found)?;
        js_sys::Reflect::set(&obj, &"data".into(), &f32_array(&found.data)).map_err(|_| JsError::new("inspect: cannot build the answer"))?;
        if !found.overlay.is_empty() {
            js_sys::Reflect::set(&obj, &"overlay".into(), &f32_array(&found.overlay)).map_err(|_| JsError::new("inspect: cannot build the answer"))?;
        }
        Ok(obj)
    }

    /// Analyses a G-code file and makes it the current result; returns `{analysis}`.
    #[wasm_bindgen(js_name = analyzeGcode)]
    pub fn analyze_gcode(&mut self, name: &str, bytes: Vec<u8>) -> Result<JsValue, JsError> {
        self.analyze_bytes(name, bytes)
    }

    /// Analyses a dropped G-code file (a `Blob`, as the page has it), as
    /// [`Session::analyze_gcode`] does. A file over [`analyze::MAX_FILE_BYTES`] is refused
    /// from its size before it is read; the rest is read straight into this memory in pieces,
    /// with no whole copy on the JavaScript side.
    #[wasm_bindgen(js_name = analyzeBlob)]
    pub fn analyze_blob(&mut self, name: &str, blob: web_sys::Blob) -> Result<JsValue, JsError> {
        analyze::check_size(name, blob.size() as u64).map_err(js_err)?;
        let source = BlobSource::new(blob)?;
        // The last result's text is let go first: two large files need not fit together.
        self.gcode = Arc::default();
        self.preview = Arc::default();
        let bytes = read_whole(&source, name)?;
        self.analyze_bytes(name, bytes)
    }

    fn analyze_bytes(&mut self, name: &str, bytes: Vec<u8>) -> Result<JsValue, JsError> {
        let options = analyze::Options { collect_preview: true, ..Default::default() };
        let a = analyze::analyze(name, &bytes, &options).map_err(js_err)?;
        // The bytes become the text without a copy (the analysis refused control bytes; any
        // invalid UTF-8 is replaced, as the download would show it).
        self.gcode = Arc::new(String::from_utf8(bytes).unwrap_or_else(|e| String::from_utf8_lossy(e.as_bytes()).into_owned()));
        self.bgcode = None;
        self.preview = Arc::new(a.preview.unwrap_or_default());
        #[derive(Serialize)]
        struct Out<'a> {
            analysis: &'a analyze::Report,
        }
        to_js(&Out { analysis: &a.report })
    }

    /// G-code bytes of the last result.
    pub fn gcode(&self) -> js_sys::Uint8Array {
        js_sys::Uint8Array::from(self.gcode.as_bytes())
    }
    /// Binary G-code (`.bgcode`) of the last run when its printer asks for it, else empty.
    pub fn bgcode(&self) -> js_sys::Uint8Array {
        js_sys::Uint8Array::from(self.bgcode.as_deref().map_or(&[][..], Vec::as_slice))
    }
    /// Extrusion segments, 6 floats each (mm).
    #[wasm_bindgen(js_name = previewPositions)]
    pub fn preview_positions(&self) -> js_sys::Float32Array {
        f32_array(&self.preview.positions)
    }
    /// Feature code per segment.
    #[wasm_bindgen(js_name = previewFeature)]
    pub fn preview_feature(&self) -> js_sys::Uint8Array {
        js_sys::Uint8Array::from(self.preview.feature.as_slice())
    }
    /// Path index per segment.
    #[wasm_bindgen(js_name = previewPath)]
    pub fn preview_path(&self) -> js_sys::Uint32Array {
        u32_array(&self.preview.path)
    }
    /// Volumetric flow per segment, mm³/s.
    #[wasm_bindgen(js_name = previewFlow)]
    pub fn preview_flow(&self) -> js_sys::Float32Array {
        f32_array(&self.preview.flow)
    }
    /// Filament per mm of each segment (ΔE / length), mm/mm.
    #[wasm_bindgen(js_name = previewEPerMm)]
    pub fn preview_e_per_mm(&self) -> js_sys::Float32Array {
        f32_array(&self.preview.e_per_mm)
    }
    /// Feed rate per segment, mm/s.
    #[wasm_bindgen(js_name = previewSpeed)]
    pub fn preview_speed(&self) -> js_sys::Float32Array {
        f32_array(&self.preview.speed)
    }
    /// Width per segment, mm.
    #[wasm_bindgen(js_name = previewWidth)]
    pub fn preview_width(&self) -> js_sys::Float32Array {
        f32_array(&self.preview.width)
    }
    /// First segment of each layer, plus the end.
    #[wasm_bindgen(js_name = previewLayerStart)]
    pub fn preview_layer_start(&self) -> js_sys::Uint32Array {
        u32_array(&self.preview.layer_segment_start)
    }
    /// Travel segments, 6 floats each (mm).
    #[wasm_bindgen(js_name = previewTravel)]
    pub fn preview_travel(&self) -> js_sys::Float32Array {
        f32_array(&self.preview.travel_positions)
    }
    /// First travel segment of each layer, plus the end.
    #[wasm_bindgen(js_name = previewTravelLayerStart)]
    pub fn preview_travel_layer_start(&self) -> js_sys::Uint32Array {
        u32_array(&self.preview.layer_travel_start)
    }
    /// Z of each layer, mm.
    #[wasm_bindgen(js_name = previewLayerZ)]
    pub fn preview_layer_z(&self) -> js_sys::Float32Array {
        f32_array(&self.preview.layer_z)
    }
    /// Tool axis at the end of each extrusion segment (3 floats), empty without tool axes.
    #[wasm_bindgen(js_name = previewAxis)]
    pub fn preview_axis(&self) -> js_sys::Float32Array {
        f32_array(&self.preview.axis)
    }
    /// Per extrusion segment, the index of the G-code move it came from.
    #[wasm_bindgen(js_name = previewSegmentMove)]
    pub fn preview_segment_move(&self) -> js_sys::Uint32Array {
        u32_array(&self.preview.segment_move)
    }
    /// Per travel segment, the index of the G-code move it came from.
    #[wasm_bindgen(js_name = previewTravelMove)]
    pub fn preview_travel_move(&self) -> js_sys::Uint32Array {
        u32_array(&self.preview.travel_move)
    }
    /// Bed size of the last run's printer, mm.
    #[wasm_bindgen(js_name = bedSize)]
    pub fn bed_size(&self) -> Vec<f64> {
        self.bed.to_vec()
    }
}

/// Segments (x0 y0 x1 y1, mm, centred on 0) of `pattern` (JSON, e.g. `{"kind":"voronoi"}`)
/// cropped to a `size_mm` square: the page's pattern thumbnails.
#[wasm_bindgen(js_name = patternThumbnail)]
pub fn pattern_thumbnail(pattern_json: &str, size_mm: f64, seed: u64) -> Result<Vec<f32>, JsError> {
    let pattern: crate::lattice::Pattern = serde_json::from_str(pattern_json).map_err(js_err)?;
    Ok(crate::lattice::thumbnail(&pattern, size_mm, seed).into_iter().flat_map(|s| s.map(|x| x as f32)).collect())
}

/// Benchmark workloads (`benchMeshStl`, `benchDesign`, `benchAnalyze`, `BenchLattice`,
/// `benchScalingCases`, `BenchScaling`, `BenchGraded`), built only with `--features bench` (the benchmark page's wasm), so
/// the production module does not carry them.
#[cfg(feature = "bench")]
mod bench_exports {
    use super::*;

    /// Benchmark workload: binary STL of the benchmark mesh (about `triangles` triangles).
    #[wasm_bindgen(js_name = benchMeshStl)]
    pub fn bench_mesh_stl(triangles: usize) -> Vec<u8> {
        crate::bench::bench_mesh(triangles).to_stl_binary()
    }

    /// Benchmark workload: the slicing benchmark design (JSON).
    #[wasm_bindgen(js_name = benchDesign)]
    pub fn bench_design() -> String {
        crate::bench::bench_design().to_json_pretty()
    }

    /// Benchmark workload: analyses `gcode` without preview; returns the report JSON.
    #[wasm_bindgen(js_name = benchAnalyze)]
    pub fn bench_analyze(gcode: &[u8]) -> Result<String, JsError> {
        let a = analyze::analyze("bench.gcode", gcode, &Default::default()).map_err(js_err)?;
        serde_json::to_string(&a.report).map_err(js_err)
    }

    /// Benchmark workload: one lattice path-optimisation layer (`src/bench.rs`), prepared by
    /// [`BenchLattice::new`] (not timed); [`BenchLattice::run`] is the part timed in the worker.
    #[wasm_bindgen]
    pub struct BenchLattice(crate::bench::LatticeBench);

    #[wasm_bindgen]
    impl BenchLattice {
        /// Prepares `which` (`honeycomb-10mm`, `disc-48mm` or `euler-100k`).
        #[wasm_bindgen(constructor)]
        pub fn new(which: &str) -> Result<BenchLattice, JsError> {
            crate::bench::LatticeBench::prepare(which).map(BenchLattice).map_err(js_err)
        }

        /// Runs `paths::optimise` once; returns `{edges, paths, score}` as JSON.
        pub fn run(&self) -> Result<String, JsError> {
            let s = self.0.run().map_err(js_err)?;
            Ok(format!(r#"{{"edges":{},"paths":{},"score":{}}}"#, s.edges, s.paths, s.score))
        }

        /// The method (`gippo_max` or `euler`).
        pub fn method(&self) -> String {
            self.0.method().into()
        }

        /// The issue's target, ms.
        #[wasm_bindgen(js_name = targetMs)]
        pub fn target_ms(&self) -> f64 {
            self.0.target_ms()
        }
    }

    /// The pairing benchmark's cases (`weft bench --pairing`, `src/bench/pairing.rs`), in order.
    #[wasm_bindgen(js_name = benchPairingCases)]
    pub fn bench_pairing_cases() -> Vec<String> {
        crate::bench::pairing::CASES.iter().map(|c| c.name.to_string()).collect()
    }

    /// Benchmark workload: one pairing case, heuristic only or with the exact budget, prepared
    /// by [`BenchPairing::new`] (not timed); [`BenchPairing::run`] is timed in the worker.
    #[wasm_bindgen]
    pub struct BenchPairing(crate::bench::pairing::PairingBench);

    #[wasm_bindgen]
    impl BenchPairing {
        /// Prepares case `name` (see `benchPairingCases`); `exact`: with the exact budget.
        #[wasm_bindgen(constructor)]
        pub fn new(name: &str, exact: bool) -> Result<BenchPairing, JsError> {
            crate::bench::pairing::PairingBench::prepare(name, exact).map(BenchPairing).map_err(js_err)
        }

        /// Runs `paths::optimise` once; returns the pairing's numbers as JSON.
        pub fn run(&self) -> Result<String, JsError> {
            self.0.run().map(|s| s.to_json()).map_err(js_err)
        }
    }

    /// Benchmark workload of the graded job (`src/bench/graded.rs`, the same as `weft bench
    /// --graded`): the DICOM series and the G-code handed to a `Session` file by file, as the
    /// page does for a dropped folder, and the designs that use them. Made in a worker that is
    /// then terminated, so making it does not count in the timed worker's memory.
    #[wasm_bindgen]
    pub struct BenchGraded(crate::bench::graded::Workload);

    impl Default for BenchGraded {
        fn default() -> Self {
            Self::new()
        }
    }

    #[wasm_bindgen]
    impl BenchGraded {
        /// The paper's CT size (182 × 197 × 107) and a 50 MB PrusaSlicer-style G-code.
        #[wasm_bindgen(constructor)]
        pub fn new() -> BenchGraded {
            BenchGraded(crate::bench::graded::Workload::paper())
        }

        /// The series' file names (`bone-phantom/slice-0000.dcm`, …), in order.
        #[wasm_bindgen(js_name = seriesNames)]
        pub fn series_names(&self) -> Vec<String> {
            self.0.series.iter().map(|(n, _)| n.clone()).collect()
        }

        /// The bytes of series file `i`.
        #[wasm_bindgen(js_name = seriesFile)]
        pub fn series_file(&self, i: usize) -> Result<Vec<u8>, JsError> {
            self.0.series.get(i).map(|(_, b)| b.clone()).ok_or_else(|| JsError::new("no such series file"))
        }

        /// The G-code's file name (the edit design's `job.gcode`).
        #[wasm_bindgen(js_name = gcodeName)]
        pub fn gcode_name(&self) -> String {
            crate::bench::graded::GCODE_NAME.into()
        }

        /// The G-code's bytes.
        pub fn gcode(&self) -> Vec<u8> {
            self.0.gcode.clone()
        }

        /// Route `native` over the whole volume (its `surface` view), JSON.
        #[wasm_bindgen(js_name = surfaceDesign)]
        pub fn surface_design(&self) -> String {
            self.0.surface_design.to_json_pretty()
        }

        /// Route `edit` (series + G-code, manual alignment), JSON.
        #[wasm_bindgen(js_name = editDesign)]
        pub fn edit_design(&self) -> String {
            self.0.edit_design.to_json_pretty()
        }

        /// Bytes of the volume as the reader holds it (f32 voxels).
        #[wasm_bindgen(js_name = volumeBytes)]
        pub fn volume_bytes(&self) -> f64 {
            self.0.volume_bytes as f64
        }
    }

    /// The scaling cases' names (`weft bench --scaling`, `src/bench/scaling.rs`), in order.
    #[wasm_bindgen(js_name = benchScalingCases)]
    pub fn bench_scaling_cases() -> Vec<String> {
        crate::bench::scaling::cases().iter().map(|c| c.name.to_string()).collect()
    }

    /// Benchmark workload: one scaling case at one scale, prepared by [`BenchScaling::new`]
    /// (not timed) with `bench::scaling::prepare`, the same input `weft bench --scaling`
    /// makes; [`BenchScaling::run`] runs it once and is timed in the worker with
    /// `performance.now()` (`std::time::Instant` panics on wasm32-unknown-unknown).
    #[wasm_bindgen]
    pub struct BenchScaling {
        prepared: crate::bench::scaling::Prepared,
        unit: &'static str,
    }

    #[wasm_bindgen]
    impl BenchScaling {
        /// Prepares case `name` (e.g. `paths/gippo`) at `scale` (1, 4 or 16).
        #[wasm_bindgen(constructor)]
        pub fn new(name: &str, scale: usize) -> Result<BenchScaling, JsError> {
            let unit = crate::bench::scaling::cases().iter().find(|c| c.name == name).map(|c| c.unit).unwrap_or("");
            let prepared = crate::bench::scaling::prepare(name, scale).map_err(js_err)?;
            Ok(BenchScaling { prepared, unit })
        }

        /// Runs the case's work once.
        pub fn run(&self) -> Result<(), JsError> {
            (self.prepared.run)().map_err(js_err)
        }

        /// The input's size in the case's unit.
        pub fn size(&self) -> f64 {
            self.prepared.size
        }

        /// What the size counts (`triangles`, `mm²`…).
        pub fn unit(&self) -> String {
            self.unit.into()
        }
    }
}

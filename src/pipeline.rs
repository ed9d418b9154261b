//! Runs a [`Design`]: its job kind's stages ([`crate::jobs`]), then G-code and analysis.
//!
//! The CLI and the wasm binding both call [`run`] (or [`run_in`] with a cache and a
//! registry); nothing else orchestrates stages. Every stage goes through [`Ctx::stage`], which
//! keys its output by a hash of the design parts the stage reads and of its upstream keys: a
//! [`Cache`] kept between runs (the page's worker keeps one) then recomputes only the stages
//! whose inputs changed — a temperature edit re-runs only G-code and analysis.

use crate::analyze::{self, Preview};
use crate::budget::{Estimate, Plan};
use crate::design::{share, Design, Input};
use crate::gcode::{self, GcodeStats};
use crate::geom::{DVec3, Mesh, Toolpath};
use crate::import::{self, ImportReport};
use crate::jobs::{Inspection, Product, Registry, Slot};
use crate::report::StageReport;
use crate::source::ByteSource;
use crate::volume;
use serde::Serialize;
use std::any::Any;
use std::collections::BTreeMap;
use std::sync::Arc;

/// Where a file's bytes are.
#[derive(Clone)]
enum Content {
    /// In memory.
    Bytes(Arc<Vec<u8>>),
    /// Outside the core (the browser's blob store), read in ranges when a stage needs it.
    Far(Arc<dyn ByteSource>),
}

impl std::fmt::Debug for Content {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Content::Bytes(b) => write!(f, "Bytes({} bytes)", b.len()),
            Content::Far(s) => write!(f, "Far({} bytes)", s.len()),
        }
    }
}

/// A loaded file and the hash of its bytes (computed once, for cache keys).
#[derive(Clone, Debug)]
struct FileEntry {
    content: Content,
    hash: Key,
}

/// Files available to a run, by name (uploaded on the page, `--input` on the CLI). Each is
/// stored once and hashed once; stages parse them lazily through [`Ctx::mesh`]. A file may
/// stay outside the core ([`Files::insert_source`]): stages that read line by line stream it
/// ([`Ctx::file_source`]), the others read it whole when they run.
#[derive(Clone, Debug, Default)]
pub struct Files {
    map: BTreeMap<String, FileEntry>,
}

/// A loaded file's bytes for a stage: in memory (borrowed, or unpacked from a share link), or
/// read in ranges from outside the core.
pub enum FileSource<'a> {
    /// In memory.
    Bytes(std::borrow::Cow<'a, [u8]>),
    /// Outside the core.
    Far(Arc<dyn ByteSource>),
}

impl ByteSource for FileSource<'_> {
    fn len(&self) -> usize {
        match self {
            FileSource::Bytes(b) => b.len(),
            FileSource::Far(s) => s.len(),
        }
    }
    fn read_at(&self, offset: usize, buf: &mut [u8]) -> Result<(), String> {
        match self {
            FileSource::Bytes(b) => b.read_at(offset, buf),
            FileSource::Far(s) => s.read_at(offset, buf),
        }
    }
    fn as_slice(&self) -> Option<&[u8]> {
        match self {
            FileSource::Bytes(b) => Some(b),
            FileSource::Far(s) => s.as_slice(),
        }
    }
}

impl Files {
    /// No files.
    pub fn new() -> Files {
        Files::default()
    }

    /// Adds (or replaces) `name`.
    pub fn insert(&mut self, name: String, bytes: Vec<u8>) {
        let hash = Key::of_bytes(&bytes);
        self.map.insert(name, FileEntry { content: Content::Bytes(Arc::new(bytes)), hash });
    }

    /// Adds (or replaces) `name`, whose bytes stay in `source` (read once now, in pieces, to
    /// hash them; the message says why they could not be read).
    pub fn insert_source(&mut self, name: String, source: Arc<dyn ByteSource>) -> Result<(), String> {
        let hash = Key::of_source(&*source)?;
        self.map.insert(name, FileEntry { content: Content::Far(source), hash });
        Ok(())
    }

    /// Removes `name`; whether it was there.
    pub fn remove(&mut self, name: &str) -> bool {
        self.map.remove(name).is_some()
    }

    /// The bytes of `name`, when they are in memory.
    pub fn get(&self, name: &str) -> Option<&[u8]> {
        self.map.get(name).and_then(|e| match &e.content {
            Content::Bytes(b) => Some(b.as_slice()),
            Content::Far(_) => None,
        })
    }

    /// The bytes of `name`, wherever they are.
    pub fn source(&self, name: &str) -> Option<FileSource<'_>> {
        self.map.get(name).map(|e| match &e.content {
            Content::Bytes(b) => FileSource::Bytes(std::borrow::Cow::Borrowed(b.as_slice())),
            Content::Far(s) => FileSource::Far(s.clone()),
        })
    }

    /// All the bytes of `name`: borrowed when in memory, read when not.
    fn whole(&self, name: &str) -> Option<Result<std::borrow::Cow<'_, [u8]>, Error>> {
        self.map.get(name).map(|e| match &e.content {
            Content::Bytes(b) => Ok(std::borrow::Cow::Borrowed(b.as_slice())),
            Content::Far(s) => crate::source::read_all(&**s)
                .map(|b| std::borrow::Cow::Owned(b.into_owned()))
                .map_err(|message| Error::Unreadable { name: name.to_string(), message }),
        })
    }

    /// The size of `name` in bytes, known without reading it.
    pub fn size(&self, name: &str) -> Option<usize> {
        self.map.get(name).map(|e| match &e.content {
            Content::Bytes(b) => b.len(),
            Content::Far(s) => s.len(),
        })
    }

    /// Whether `name` is loaded.
    pub fn contains(&self, name: &str) -> bool {
        self.map.contains_key(name)
    }

    /// Names, sorted.
    pub fn names(&self) -> impl Iterator<Item = &str> {
        self.map.keys().map(String::as_str)
    }

    fn hash(&self, name: &str) -> Option<Key> {
        self.map.get(name).map(|e| e.hash)
    }
}

/// A stage output's identity: a 128-bit hash of what it was computed from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Key(u64, u64);

impl Key {
    /// Hash of `bytes` (two independent 64-bit multiply–rotate streams, 8 bytes at a time;
    /// deterministic on every target, fast enough for 200 MB inputs).
    pub fn of_bytes(bytes: &[u8]) -> Key {
        let mut h = Hasher::new(bytes.len());
        h.words(bytes);
        h.finish(&bytes[bytes.len() / 8 * 8..])
    }

    /// [`Key::of_bytes`] of a source's bytes, read in pieces (the same key as in memory).
    pub fn of_source(source: &dyn ByteSource) -> Result<Key, String> {
        if let Some(all) = source.as_slice() {
            return Ok(Key::of_bytes(all));
        }
        let len = source.len();
        let mut h = Hasher::new(len);
        // A multiple of 8, so every piece but the last is whole words.
        let mut buf = vec![0u8; crate::source::WHOLE_PIECE_BYTES.min(len)];
        let mut offset = 0;
        while offset < len {
            let n = buf.len().min(len - offset);
            source.read_at(offset, &mut buf[..n])?;
            offset += n;
            h.words(&buf[..n]);
            if offset == len {
                return Ok(h.finish(&buf[n / 8 * 8..n]));
            }
        }
        Ok(h.finish(&[]))
    }

    /// Hash of a stage name, its design parts (as JSON) and its upstream keys.
    pub fn of(stage: &str, parts: &impl Serialize, upstream: &[Key]) -> Key {
        let mut bytes = stage.as_bytes().to_vec();
        bytes.push(0);
        bytes.extend(serde_json::to_vec(parts).unwrap_or_default());
        for k in upstream {
            bytes.extend(k.0.to_le_bytes());
            bytes.extend(k.1.to_le_bytes());
        }
        Key::of_bytes(&bytes)
    }
}

/// Two independent 64-bit multiply–rotate streams, 8 bytes at a time.
struct Hasher {
    a: u64,
    b: u64,
}

impl Hasher {
    const K1: u64 = 0x9E37_79B9_7F4A_7C15;
    const K2: u64 = 0xC2B2_AE3D_27D4_EB4F;

    fn new(len: usize) -> Hasher {
        Hasher { a: 0x243F_6A88_85A3_08D3u64 ^ len as u64, b: 0x1319_8A2E_0370_7344u64 }
    }

    /// The whole words of `bytes` (a trailing part of under 8 bytes is left for `finish`).
    fn words(&mut self, bytes: &[u8]) {
        for c in bytes.chunks_exact(8) {
            let w = u64::from_le_bytes([c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]]);
            self.a = (self.a ^ w).wrapping_mul(Self::K1).rotate_left(29);
            self.b = (self.b ^ w.rotate_left(17)).wrapping_mul(Self::K2).rotate_left(31);
        }
    }

    fn finish(mut self, tail: &[u8]) -> Key {
        for &byte in tail {
            self.a = (self.a ^ byte as u64).wrapping_mul(Self::K1).rotate_left(29);
            self.b = (self.b ^ byte as u64).wrapping_mul(Self::K2).rotate_left(31);
        }
        let (a, b) = (self.a, self.b);
        Key(fmix(a ^ b.rotate_left(32)), fmix(b ^ a))
    }
}

fn fmix(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

struct Entry {
    key: Key,
    value: Arc<dyn Any + Send + Sync>,
    report: Option<StageReport>,
    /// Wall time it took, ms, while no run has counted it yet (an import the estimate made
    /// before the run that reads it): the run's timings count it once.
    uncounted_ms: Option<f64>,
}

/// Stage outputs kept between runs: the newest output of each stage (by cache id), with the
/// key it was computed for. A run reuses an entry only when its key matches exactly.
#[derive(Default)]
pub struct Cache {
    entries: BTreeMap<String, Entry>,
    enabled: bool,
}

impl Cache {
    /// A cache that keeps outputs between runs (the page's worker).
    pub fn new() -> Cache {
        Cache { entries: BTreeMap::new(), enabled: true }
    }

    /// No caching: every stage runs once and nothing is kept after the run (the CLI, one run);
    /// only what the estimate makes and the run reads again is kept ([`Ctx::stage_kept`]).
    pub fn disabled() -> Cache {
        Cache::default()
    }

    /// Cache ids held (for tests and diagnostics).
    pub fn ids(&self) -> Vec<String> {
        self.entries.keys().cloned().collect()
    }
}

/// A stage's output with its key (pass the key on as the upstream of the next stage).
pub struct Out<T> {
    /// The output (shared with the cache).
    pub value: Arc<T>,
    /// What it was computed from.
    pub key: Key,
}

impl<T> Clone for Out<T> {
    fn clone(&self) -> Self {
        Out { value: self.value.clone(), key: self.key }
    }
}

impl<T> std::ops::Deref for Out<T> {
    type Target = T;
    fn deref(&self) -> &T {
        &self.value
    }
}

/// G-code a stage sends ahead while the run goes on: the beginning of the run's G-code, fixed
/// already (a freeform plan's first beams), so a printer could start on it. Its moves are the
/// first moves of the final file; its header counts only them and it has no end code.
#[derive(Clone, Debug, PartialEq)]
pub struct Ahead {
    /// The stage sending it.
    pub stage: String,
    /// What it is, in words ("the first 200 of 6 120 beams").
    pub label: String,
    /// Items (beams, paths) it holds, of `total`.
    pub done: usize,
    /// Items in the whole run.
    pub total: usize,
    /// The G-code.
    pub gcode: String,
}

fn send_nowhere(_: &Ahead) {}

/// A job's handle for sending G-code ahead ([`Ahead`]): copied out of the [`Ctx`] so a stage
/// can send while it runs.
#[derive(Clone, Copy)]
pub struct Sender<'a> {
    design: &'a Design,
    to: &'a dyn Fn(&Ahead),
}

impl Sender<'_> {
    /// Writes `toolpath` (the first `done` of `total` items of the run's final toolpath) with
    /// the design's printer and sends its moves. A toolpath the writer refuses is not sent: the
    /// run's own writer will say why.
    pub fn send(&self, stage: &str, label: &str, done: usize, total: usize, toolpath: &Toolpath) {
        let Ok(g) = gcode::write_gcode(toolpath, &writer_options(self.design)) else { return };
        let mut text = g.text;
        text.truncate(g.moves_end);
        text.push_str(&format!("; weft: {label}; the plan goes on, and the final file's moves begin with these\n"));
        (self.to)(&Ahead { stage: stage.into(), label: label.into(), done, total, gcode: text });
    }
}

/// Wall time of one stage in a run (the run report's "where the time went").
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StageTime {
    /// Stage name.
    pub stage: String,
    /// Wall time on this machine, ms (0 when reused from the cache).
    pub ms: f64,
    /// Reused from the cache.
    pub cached: bool,
}

/// What a job kind's run sees: the design, the files, progress, the stage cache and the
/// reports so far.
pub struct Ctx<'a> {
    /// The design being run.
    pub design: &'a Design,
    /// Loaded files.
    pub files: &'a Files,
    cache: &'a mut Cache,
    progress: &'a mut dyn FnMut(&str, f32),
    ahead: &'a dyn Fn(&Ahead),
    /// Stage reports, in run order.
    pub reports: Vec<StageReport>,
    /// Wall time of each stage run, in run order (a stage met twice: summed).
    pub timings: Vec<StageTime>,
    /// A run counts its stages' time; an estimate leaves what it made to be counted by the run.
    counting: bool,
    /// Cache ids whose report is in `reports` (a stage reached twice in one run, e.g. an
    /// import by the estimate and then by the run, reports once).
    reported: Vec<String>,
}

impl<'a> Ctx<'a> {
    /// A context over `design` and `files` with `cache`.
    pub fn new(design: &'a Design, files: &'a Files, cache: &'a mut Cache, progress: &'a mut dyn FnMut(&str, f32)) -> Ctx<'a> {
        Ctx { design, files, cache, progress, ahead: &send_nowhere, reports: Vec::new(), timings: Vec::new(), counting: false, reported: Vec::new() }
    }

    fn time(&mut self, stage: &str, ms: f64, cached: bool) {
        match self.timings.iter_mut().find(|t| t.stage == stage) {
            Some(t) => {
                t.ms += ms;
                t.cached &= cached;
            }
            None => self.timings.push(StageTime { stage: stage.into(), ms, cached }),
        }
    }

    /// Where a stage's output sent ahead goes (see [`Sender`]); it can be kept while stages run.
    pub fn sender(&self) -> Sender<'a> {
        Sender { design: self.design, to: self.ahead }
    }

    /// Runs stage `name` (cache id `id`, usually the name) unless the cache holds its output
    /// for the same key: `parts` are the design parts it reads, `upstream` the keys of the
    /// outputs it reads. `f` gets a progress callback (0..1 within the stage) and returns the
    /// output and its report (pushed to [`Ctx::reports`], marked `cached` when reused).
    pub fn stage<T, P, F>(&mut self, name: &str, id: &str, parts: &P, upstream: &[Key], f: F) -> Result<Out<T>, Error>
    where
        T: Any + Send + Sync,
        P: Serialize + ?Sized,
        F: FnOnce(&mut dyn FnMut(f32)) -> Result<(T, Option<StageReport>), Error>,
    {
        self.run_stage(name, id, parts, upstream, f, false)
    }

    /// [`Ctx::stage`] for an output the job's estimate makes and its run reads again (an
    /// imported mesh, a volume, a surface model): kept even by a disabled cache, so a
    /// one-shot run (the CLI) does not make it twice.
    pub fn stage_kept<T, P, F>(&mut self, name: &str, id: &str, parts: &P, upstream: &[Key], f: F) -> Result<Out<T>, Error>
    where
        T: Any + Send + Sync,
        P: Serialize + ?Sized,
        F: FnOnce(&mut dyn FnMut(f32)) -> Result<(T, Option<StageReport>), Error>,
    {
        self.run_stage(name, id, parts, upstream, f, true)
    }

    fn run_stage<T, P, F>(&mut self, name: &str, id: &str, parts: &P, upstream: &[Key], f: F, keep: bool) -> Result<Out<T>, Error>
    where
        T: Any + Send + Sync,
        P: Serialize + ?Sized,
        F: FnOnce(&mut dyn FnMut(f32)) -> Result<(T, Option<StageReport>), Error>,
    {
        let key = Key::of(id, &parts, upstream);
        if let Some(e) = self.cache.entries.get_mut(id) {
            if e.key == key {
                if let Ok(value) = e.value.clone().downcast::<T>() {
                    // Made before this run (on loading, or by an estimate) and not counted
                    // yet: this run's work. An estimate leaves it for the run.
                    let earlier = if self.counting { e.uncounted_ms.take() } else { None };
                    if let Some(mut r) = e.report.clone() {
                        if !self.reported.iter().any(|i| i == id) {
                            // Its card says reused (this run did not make it), even when
                            // its time is this run's to count.
                            r.cached = true;
                            self.reports.push(r);
                            self.reported.push(id.to_string());
                        }
                    }
                    (self.progress)(name, 1.0);
                    self.time(name, earlier.unwrap_or(0.0), earlier.is_none());
                    return Ok(Out { value, key });
                }
            }
        }
        // Free the stale output first: peak memory is then one copy, not two.
        self.cache.entries.remove(id);
        (self.progress)(name, 0.0);
        let started = crate::clock::now_s();
        let progress = &mut *self.progress;
        let (value, report) = f(&mut |x| progress(name, x))?;
        let ms = (crate::clock::now_s() - started) * 1000.0;
        self.time(name, ms, false);
        (self.progress)(name, 1.0);
        let value = Arc::new(value);
        if let Some(r) = &report {
            self.reports.push(r.clone());
            self.reported.push(id.to_string());
        }
        if self.cache.enabled || keep {
            self.cache.entries.insert(id.to_string(), Entry { key, value: value.clone(), report, uncounted_ms: (!self.counting).then_some(ms) });
        }
        Ok(Out { value, key })
    }

    /// The importer's statement of its work on `input` (a slot's [`Input`]), before parsing it:
    /// refused over the importer's limits. A built-in shape costs nothing worth stating.
    pub fn import_estimate(&self, slot: &str, input: &Input) -> Result<Estimate, Error> {
        let Input::File { name, embedded } = input else { return Ok(Estimate::new("import")) };
        let bytes = match (self.files.whole(name), embedded) {
            (Some(b), _) => b?,
            (None, Some(e)) => std::borrow::Cow::Owned(share::unpack(e).map_err(|source| Error::Embedded { name: name.clone(), source })?),
            (None, None) => return Err(Error::MissingInput { name: name.clone(), slot: slot.into() }),
        };
        let e = import::estimate(name, &bytes)?;
        e.check(name)?;
        // Reading and cleaning on one thread: 0.5 µs per triangle for binary STL and 3MF (0.21–
        // 0.28 s for the 1M-triangle sphere natively, about twice that in the browser
        // worker), 1 µs for text formats; the cleaning runs on every thread (1.69× natively,
        // 1.30× in the worker at 2 threads, the Blob's copy included).
        let per_triangle = if matches!(e.format, import::Format::StlBinary | import::Format::ThreeMf) { 0.5e-6 } else { 1e-6 };
        Ok(Estimate::new("import")
            .quantity("triangles", "Triangles", e.triangles as f64, "")
            .cost(e.peak_bytes as f64, e.triangles as f64 * per_triangle)
            .parallel(0.7))
    }

    /// The mesh of `input` (a slot's [`Input`]), imported once per file content and placed on
    /// the plate: XY centred on 0, lowest point at Z = 0. `slot` names the slot for messages
    /// and for the cache id, and its kind says what the mesh must be: a solid slot's mesh is
    /// closed and oriented by [`import::close::close_solid`] (repairs stated in the report's
    /// notes) or refused.
    pub fn mesh(&mut self, slot: &Slot, input: &Input) -> Result<Out<Mesh>, Error> {
        self.mesh_placed(slot, input, true)
    }

    /// The mesh of `slot` in its file's own coordinates (not moved onto the plate): for jobs
    /// where the part's place relative to something else matters (a part resting on a curved
    /// platform).
    pub fn mesh_in_place(&mut self, slot: &Slot, input: &Input) -> Result<Out<Mesh>, Error> {
        self.mesh_placed(slot, input, false)
    }

    /// Mesh `item` of a slot holding several (foam regions), in its file's own coordinates:
    /// each item is cached on its own.
    pub fn mesh_item(&mut self, slot: &Slot, item: usize, input: &Input) -> Result<Out<Mesh>, Error> {
        self.mesh_placed_as(slot, &format!("import-item:{}:{item}", slot.name), input, false)
    }

    fn mesh_placed(&mut self, slot: &Slot, input: &Input, place: bool) -> Result<Out<Mesh>, Error> {
        let id = if place { format!("import:{}", slot.name) } else { format!("import-in-place:{}", slot.name) };
        self.mesh_placed_as(slot, &id, input, place)
    }

    fn mesh_placed_as(&mut self, slot: &Slot, id: &str, input: &Input, place: bool) -> Result<Out<Mesh>, Error> {
        // A loaded file is keyed by its content; a built-in shape or an embedded file by the
        // input itself. Missing files and several-file inputs are refused by `load_input`.
        let file = match input {
            Input::File { name, .. } => self.files.hash(name).map(|h| (name, h)),
            _ => None,
        };
        let solid = slot.kind.solid();
        let (parts, upstream) = match file {
            Some((name, h)) => (serde_json::json!({ "file": name, "solid": solid }), vec![h]),
            None => (serde_json::json!({ "input": input, "solid": solid }), Vec::new()),
        };
        let files = self.files;
        let keep = place; // the placed mesh is what the estimate and the run both read
        let slot_name = slot.name;
        self.run_stage(
            "import",
            id,
            &parts,
            &upstream,
            |_| {
                let (mesh, report) = load_input(slot_name, input, files, place, solid)?;
                Ok((mesh, report.as_ref().map(import_report)))
            },
            keep,
        )
    }

    /// The meshes of a slot that takes several, given as one `.zip` (`input`): each mesh file
    /// in it (STL, OBJ, 3MF; by name, as a folder lists them), imported and cached on its own
    /// in its file's coordinates, checked as the slot's kind asks. Other files are left out
    /// and said.
    pub fn mesh_items_of_zip(&mut self, slot: &Slot, input: &Input) -> Result<Vec<(String, Out<Mesh>)>, Error> {
        let (bytes, key) = self.file_bytes(slot.name, input)?;
        let zip_name = match input {
            Input::File { name, .. } => name.clone(),
            _ => format!("the {} archive", slot.name),
        };
        let (meshes, left_out) = meshes_of_zip(&zip_name, &bytes).map_err(Error::NoInput)?;
        drop(bytes);
        let solid = slot.kind.solid();
        let mut out = Vec::with_capacity(meshes.len());
        for (i, (name, entry)) in meshes.iter().enumerate() {
            let parts = serde_json::json!({ "zip": zip_name, "entry": name, "solid": solid });
            let id = format!("import-item:{}:{i}", slot.name);
            let said = if i == 0 && !left_out.is_empty() {
                let shown: Vec<String> = left_out.iter().take(4).map(|n| crate::settings::clip(n, 60).into_owned()).collect();
                let more = if left_out.len() > 4 { ", …" } else { "" };
                Some(format!("{zip_name}: left out {} file(s) that are not meshes ({}{more})", left_out.len(), shown.join(", ")))
            } else {
                None
            };
            let mesh = self.run_stage(
                "import",
                &id,
                &parts,
                &[key],
                |_| {
                    let (mesh, report) = read_solid(name, entry, solid)?;
                    let mut stage = import_report(&report);
                    if let Some(s) = &said {
                        stage = stage.note(s);
                    }
                    Ok((mesh, Some(stage)))
                },
                false,
            )?;
            out.push((name.clone(), mesh));
        }
        Ok(out)
    }
}

/// Files as (name, bytes).
pub type NamedFiles = Vec<(String, Vec<u8>)>;

/// The mesh files of a zip (name order) and the names of the other files in it; refused
/// when it holds no mesh. Shared by the run and the page's check on loading.
pub fn meshes_of_zip(zip_name: &str, bytes: &[u8]) -> Result<(NamedFiles, Vec<String>), String> {
    let all = volume::unzip(zip_name, bytes).map_err(|e| e.to_string())?;
    let is_mesh = |n: &str| crate::jobs::SlotKind::Mesh.accept().iter().any(|x| n.to_ascii_lowercase().ends_with(x));
    let (meshes, others): (Vec<_>, Vec<_>) = all.into_iter().partition(|(n, _)| is_mesh(n));
    if meshes.is_empty() {
        return Err(format!("{zip_name} holds no STL, OBJ or 3MF file: zip the mesh files themselves"));
    }
    Ok((meshes, others.into_iter().map(|(n, _)| n).collect()))
}

/// The import stage's card: counts, what closing the solid did, the notes.
fn import_report(r: &ImportReport) -> StageReport {
    let mut s = StageReport::new("import", "Reading the mesh", r)
        .metric("triangles", "Triangles", r.triangles as f64, "", "Facets in the mesh after repairs.")
        .metric("open_edges", "Open edges", r.open_edges as f64, "", "Edges with one facet as read: holes in the surface (0 for a closed, printable mesh).");
    if let Some(c) = &r.closure {
        s = s
            .metric("holes_capped", "Holes capped", c.capped.len() as f64, "", "Flat holes closed with a cap so the part is a whole solid.")
            .metric("capped_area", "Area capped", c.capped_area_mm2(), "mm²", "Surface the caps added.")
            .metric("flipped", "Facets turned", c.flipped as f64, "", "Facets that faced inward, turned to face out.");
    }
    for note in &r.notes {
        s = s.note(note);
    }
    s
}

/// A mesh file's bytes read, and made a closed solid when `solid` (repairs in the notes).
fn read_solid(name: &str, bytes: &[u8], solid: bool) -> Result<(Mesh, ImportReport), Error> {
    let mut imported = import::read_mesh(name, bytes, &import::Options::default())?;
    if solid {
        let closure = import::close::close_solid(name, &mut imported.mesh).map_err(import::Error::Open)?;
        imported.report.notes.extend(closure.notes(name));
        imported.report.triangles = imported.mesh.triangles.len();
        imported.report.closure = Some(closure);
    }
    Ok((imported.mesh, imported.report))
}

impl<'a> Ctx<'a> {
    /// The bytes of a one-file `input` of `slot` (loaded, or embedded in a share link) and
    /// the key of its content.
    pub fn file_bytes(&self, slot: &str, input: &Input) -> Result<(std::borrow::Cow<'a, [u8]>, Key), Error> {
        file_bytes_in(self.files, slot, input)
    }

    /// A one-file `input` of `slot` for a stage that reads it line by line (it may stay
    /// outside the core: nothing is read here), and the key of its content.
    pub fn file_source(&self, slot: &str, input: &Input) -> Result<(FileSource<'a>, Key), Error> {
        let files: &'a Files = self.files;
        if let Input::File { name, .. } = input {
            if let (Some(source), Some(h)) = (files.source(name), files.hash(name)) {
                return Ok((source, h));
            }
        }
        let (bytes, key) = self.file_bytes(slot, input)?;
        Ok((FileSource::Bytes(bytes), key))
    }

    /// The names and content keys of a volume `input`'s files, reading none that is loaded.
    fn volume_keys(&self, slot: &str, input: &Input) -> Result<Vec<(String, Key)>, Error> {
        match input {
            Input::Files(names) => names
                .iter()
                .map(|name| self.files.hash(name).map(|h| (name.clone(), h)).ok_or_else(|| Error::MissingInput { name: name.clone(), slot: slot.into() }))
                .collect(),
            Input::File { name, .. } => match self.files.hash(name) {
                Some(h) => Ok(vec![(name.clone(), h)]),
                None => Ok(vec![(name.clone(), self.file_bytes(slot, input)?.1)]),
            },
            Input::Builtin(_) => Err(Error::NoInput(format!("the {slot} input takes a volume: a DICOM series, a .zip of one, NRRD or raw voxels"))),
        }
    }

    /// A value made from `parts` and `upstream` keys, kept in the cache under `id` without a
    /// stage of its own (no progress, no report): a statement a plan makes again and again
    /// that costs a read of every file (a volume's estimate).
    fn memo<T, P>(&mut self, id: &str, parts: &P, upstream: &[Key], f: impl FnOnce() -> Result<T, Error>) -> Result<T, Error>
    where
        T: Any + Send + Sync + Clone,
        P: Serialize + ?Sized,
    {
        let key = Key::of(id, &parts, upstream);
        if let Some(e) = self.cache.entries.get(id) {
            if e.key == key {
                if let Ok(v) = e.value.clone().downcast::<T>() {
                    return Ok((*v).clone());
                }
            }
        }
        let v = f()?;
        if self.cache.enabled {
            self.cache.entries.insert(id.to_string(), Entry { key, value: Arc::new(v.clone()), report: None, uncounted_ms: None });
        }
        Ok(v)
    }

    /// The volume reader's statement of its work on `input`, before reading it (the files are
    /// read once per content: the statement is kept).
    pub fn volume_estimate(&mut self, slot: &str, input: &Input, options: &volume::Options) -> Result<Estimate, Error> {
        let keys = self.volume_keys(slot, input)?;
        let upstream: Vec<Key> = keys.iter().map(|(_, k)| *k).collect();
        let names: Vec<&str> = keys.iter().map(|(n, _)| n.as_str()).collect();
        let files = self.files;
        let e = self.memo(&format!("volume-estimate:{slot}"), &(&names, options), &upstream, || {
            let files = volume_files(files, slot, input)?;
            let list: Vec<(&str, &[u8])> = files.iter().map(|(n, b, _)| (n.as_str(), b.as_ref())).collect();
            Ok(volume::estimate(&list, options))
        })?;
        if let Some(r) = &e.refused {
            return Err(Error::TooBig { stage: "volume".into(), source: r.clone() });
        }
        Ok(e)
    }

    /// The volume of `input` (a slot's [`Input`]), read once per content and options: the
    /// stage `volume` (cache id `volume:{slot}`), with its report.
    pub fn volume(&mut self, slot: &str, input: &Input, options: &volume::Options) -> Result<Out<volume::Volume>, Error> {
        // Keys first: a file kept outside the core is read only when the volume is made.
        let keys = self.volume_keys(slot, input)?;
        let names: Vec<&str> = keys.iter().map(|(n, _)| n.as_str()).collect();
        let upstream: Vec<Key> = keys.iter().map(|(_, k)| *k).collect();
        let id = format!("volume:{slot}");
        let all = self.files;
        self.stage_kept("volume", &id, &(&names, options), &upstream, |_| {
            let files = volume_files(all, slot, input)?;
            let list: Vec<(&str, &[u8])> = files.iter().map(|(n, b, _)| (n.as_str(), b.as_ref())).collect();
            let imported = volume::read_volume(&list, options).map_err(|e| Error::stage("reading the volume", e))?;
            let (v, r) = (&imported.volume, &imported.report);
            let unit = v.info.unit.as_str();
            let mut report = StageReport::new("volume", "Reading the volume", r)
                .metric("nx", "Columns (i)", v.dims[0] as f64, "", "Voxels along a row.")
                .metric("ny", "Rows (j)", v.dims[1] as f64, "", "Voxels down a column.")
                .metric("nz", "Slices (k)", v.dims[2] as f64, "", "Images in the series, sorted by position along the slice normal.")
                .metric("sx", "Spacing i", v.spacing_mm[0], "mm", "Voxel size along a row (DICOM Pixel Spacing, second value).")
                .metric("sy", "Spacing j", v.spacing_mm[1], "mm", "Voxel size down a column (Pixel Spacing, first value).")
                .metric("sz", "Spacing k", v.spacing_mm[2], "mm", "Distance between slice positions (measured, not Slice Thickness).")
                .metric("min", "Lowest value", r.min as f64, unit, "The volume's smallest value after rescale.")
                .metric("max", "Highest value", r.max as f64, unit, "The volume's largest value after rescale.")
                .metric("files", "Files read", r.files_read as f64, "", "Files that made the volume.");
            if !r.skipped.is_empty() {
                report = report.metric(
                    "skipped",
                    "Files skipped",
                    r.skipped.len() as f64,
                    "",
                    "Files in the drop that are not images of the series (listed in the report's data).",
                );
            }
            Ok((imported.volume, Some(report)))
        })
    }
}

/// [`Ctx::file_bytes`] over `files`.
fn file_bytes_in<'f>(files: &'f Files, slot: &str, input: &Input) -> Result<(std::borrow::Cow<'f, [u8]>, Key), Error> {
    match input {
        Input::File { name, embedded } => match (files.whole(name), files.hash(name), embedded) {
            (Some(b), Some(h), _) => Ok((b?, h)),
            (_, _, Some(e)) => {
                let bytes = share::unpack(e).map_err(|source| Error::Embedded { name: name.clone(), source })?;
                let key = Key::of_bytes(&bytes);
                Ok((std::borrow::Cow::Owned(bytes), key))
            }
            _ => Err(Error::MissingInput { name: name.clone(), slot: slot.into() }),
        },
        Input::Files(_) => Err(Error::NoInput(format!("the {slot} input takes one file, not several"))),
        Input::Builtin(_) => Err(Error::NoInput(format!("the {slot} input takes a file, not a built-in shape"))),
    }
}

/// One file of a volume input: its name, its bytes (borrowed when the store holds them in memory)
/// and the key of its contents.
type VolumeFile<'f> = (String, std::borrow::Cow<'f, [u8]>, Key);

/// The files of a volume `input` (one file: a `.zip`, NRRD, raw or single DICOM; several: a
/// series), read, with the keys of their contents.
fn volume_files<'f>(files: &'f Files, slot: &str, input: &Input) -> Result<Vec<VolumeFile<'f>>, Error> {
    match input {
        Input::Files(names) => {
            // Each file was checked alone as it was loaded; the series together, from the
            // files' sizes, before any is read (in the browser they stay in the page's blob
            // store until now).
            let total = names.iter().filter_map(|n| files.size(n)).fold(0u64, |sum, len| sum.saturating_add(len as u64));
            volume::check_input_bytes(&format!("the files given for '{slot}'"), total).map_err(|e| Error::stage("reading the volume", e))?;
            let mut out = Vec::with_capacity(names.len());
            for name in names {
                match (files.whole(name), files.hash(name)) {
                    (Some(b), Some(h)) => out.push((name.clone(), b?, h)),
                    _ => return Err(Error::MissingInput { name: name.clone(), slot: slot.into() }),
                }
            }
            Ok(out)
        }
        Input::File { name, .. } => {
            let (bytes, key) = file_bytes_in(files, slot, input)?;
            Ok(vec![(name.clone(), bytes, key)])
        }
        Input::Builtin(_) => Err(Error::NoInput(format!("the {slot} input takes a volume: a DICOM series, a .zip of one, NRRD or raw voxels"))),
    }
}

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
}

/// Why a run failed.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The design names a file that was not given.
    #[error("the design's {slot} input is '{name}', which is not loaded; load {name} (drop it on the page, or pass --input {slot}={name})")]
    MissingInput {
        /// File name.
        name: String,
        /// The slot.
        slot: String,
    },
    /// A loaded file kept outside the core could not be read any more.
    #[error("{name} could not be read ({message}); load it again")]
    Unreadable {
        /// The file's name.
        name: String,
        /// Why, as the browser said.
        message: String,
    },
    /// The copy of a file inside the design (put there by a share link) is damaged.
    #[error("the copy of {name} inside the design is damaged (the link it came with was cut short or changed while copying); load {name} itself, or ask for the link again")]
    Embedded {
        /// The file's name.
        name: String,
        /// What [`share::unpack`] said.
        source: share::Error,
    },
    /// Import failed.
    #[error(transparent)]
    Import(#[from] import::Error),
    /// A stage of the job failed (`stage` says which; `source` is the stage's own error).
    #[error("{stage}: {source}")]
    Stage {
        /// Stage name as the user reads it (`slicing`, `lattice`).
        stage: &'static str,
        /// The stage's error.
        source: Box<dyn std::error::Error + Send + Sync>,
    },
    /// A job that needs an input has none.
    #[error("{0}")]
    NoInput(String),
    /// The job settings do not fit the kind (a bug: designs are normalised when read).
    #[error("the job settings cannot be read: {0}")]
    BadJob(String),
    /// The design's job kind is not known to this build.
    #[error("unknown job kind '{kind}'; this weft knows {known}")]
    UnknownKind {
        /// The kind.
        kind: String,
        /// The known ones.
        known: String,
    },
    /// An `inspect` request names a view the job does not have.
    #[error("a {job} job has no view '{view}'")]
    UnknownView {
        /// The view.
        view: String,
        /// The job kind.
        job: &'static str,
    },
    /// Writing failed.
    #[error("G-code: {0}")]
    Gcode(#[from] gcode::Error),
    /// Reading back failed (a bug: weft's own G-code must always analyse).
    #[error("analysing the written G-code: {0}")]
    Analyze(#[from] analyze::Error),
    /// The run's estimate is over a budget or a limit (stated before running anything).
    #[error("{stage}: {source}")]
    TooBig {
        /// The stage whose estimate is over.
        stage: String,
        /// What, the limit and the fix.
        source: crate::budget::OverBudget,
    },
}

impl Error {
    /// Wraps a stage's own error.
    pub fn stage(stage: &'static str, source: impl std::error::Error + Send + Sync + 'static) -> Error {
        Error::Stage { stage, source: Box::new(source) }
    }
}

/// Resolves the mesh input of `slot`: the built-in shape, or the file (loaded, or embedded in
/// a share link) imported; with `place`, placed on the plate: XY centred on 0, lowest point at
/// Z = 0.
fn load_input(slot: &str, input: &Input, files: &Files, place: bool, solid: bool) -> Result<(Mesh, Option<ImportReport>), Error> {
    let (mut mesh, report) = match input {
        Input::Builtin(shape) => (shape.mesh(), None),
        Input::File { name, embedded } => {
            let bytes = match (files.whole(name), embedded) {
                (Some(b), _) => b?,
                (None, Some(e)) => std::borrow::Cow::Owned(share::unpack(e).map_err(|source| Error::Embedded { name: name.clone(), source })?),
                (None, None) => return Err(Error::MissingInput { name: name.clone(), slot: slot.into() }),
            };
            let (mesh, report) = read_solid(name, &bytes, solid)?;
            (mesh, Some(report))
        }
        Input::Files(_) => return Err(Error::NoInput(format!("the {slot} input takes one mesh file, not several"))),
    };
    if let Some(b) = mesh.bounds().filter(|_| place) {
        let c = (b.min + b.max) * 0.5;
        mesh.translate(DVec3::new(-c.x, -c.y, -b.min.z));
    }
    Ok((mesh, report))
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
    run_sending(registry, cache, design, files, options, progress, &send_nowhere)
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
    Ok(RunOutput { gcode: written.text.clone(), report, preview: analysed.preview.clone() })
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
fn plan(kind: &dyn crate::jobs::JobKind, ctx: &mut Ctx) -> Result<Plan, Error> {
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

/// The printer, material, speeds and name: what the writer reads of the design (also for
/// a job that writes a toolpath itself, e.g. to compare routes).
pub fn writer_options(design: &Design) -> gcode::Options {
    gcode::Options { printer: design.printer.clone(), material: design.material.clone(), speeds: design.speeds.clone(), design_name: design.name.clone() }
}

fn write_stage(ctx: &mut Ctx, toolpath: &Out<Toolpath>) -> Result<Out<Written>, Error> {
    let design = ctx.design;
    let parts = (&design.printer, &design.material, &design.speeds, &design.name);
    ctx.stage("gcode", "gcode", &parts, &[toolpath.key], |_| {
        let g = gcode::write_gcode(toolpath, &writer_options(design))?;
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

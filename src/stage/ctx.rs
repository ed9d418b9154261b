//! What a job kind's run sees ([`Ctx`]): the design, the files, progress, the cache, the
//! reports, and G-code sent ahead.

use super::*;

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

/// Sends nowhere: a run that sends nothing ahead.
pub fn send_nowhere(_: &Ahead) {}

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
    pub(super) cache: &'a mut Cache,
    progress: &'a mut dyn FnMut(&str, f32),
    /// Where G-code sent ahead goes (the pipeline sets it for a run).
    pub(crate) ahead: &'a dyn Fn(&Ahead),
    /// Stage reports, in run order.
    pub reports: Vec<StageReport>,
    /// Wall time of each stage run, in run order (a stage met twice: summed).
    pub timings: Vec<StageTime>,
    /// A run counts its stages' time; an estimate leaves what it made to be counted by the run.
    pub(crate) counting: bool,
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
        self.run_stage(name, id, parts, upstream, f, Keep::Cached)
    }

    /// [`Ctx::stage`] for a recording only a step of "How it works" shows (a method's
    /// intermediate states): cached like a stage while the steps are open, dropped by
    /// [`Cache::drop_recordings`] when they close, never made by a run.
    pub fn recording<T, P, F>(&mut self, name: &str, id: &str, parts: &P, upstream: &[Key], f: F) -> Result<Out<T>, Error>
    where
        T: Any + Send + Sync,
        P: Serialize + ?Sized,
        F: FnOnce(&mut dyn FnMut(f32)) -> Result<(T, Option<StageReport>), Error>,
    {
        self.run_stage(name, id, parts, upstream, f, Keep::Recording)
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
        self.run_stage(name, id, parts, upstream, f, Keep::Always)
    }

    fn run_stage<T, P, F>(&mut self, name: &str, id: &str, parts: &P, upstream: &[Key], f: F, keep: Keep) -> Result<Out<T>, Error>
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
        if self.cache.enabled || keep == Keep::Always {
            let recording = keep == Keep::Recording;
            self.cache.entries.insert(id.to_string(), Entry { key, value: value.clone(), report, uncounted_ms: (!self.counting).then_some(ms), recording });
        }
        Ok(Out { value, key })
    }

    /// The importer's statement of its work on `input` (a slot's [`Input`]), before parsing it:
    /// refused over the importer's limits. A built-in shape costs nothing worth stating.
    pub fn import_estimate(&self, slot: &str, input: &Input) -> Result<Estimate, Error> {
        let Input::File { name, embedded } = input else { return Ok(Estimate::new("import")) };
        let bytes = named_bytes(self.files, slot, name, embedded)?;
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
        // The placed mesh is what the estimate and the run both read.
        let keep = if place { Keep::Always } else { Keep::Cached };
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
                Keep::Cached,
            )?;
            out.push((name.clone(), mesh));
        }
        Ok(out)
    }
}

/// The printer, material, speeds and name: what the writer reads of the design (also for
/// a job that writes a toolpath itself, e.g. to compare routes).
pub fn writer_options(design: &Design) -> gcode::Options {
    gcode::Options {
        printer: design.printer.clone(),
        material: design.material.clone(),
        speeds: design.speeds.clone(),
        design_name: design.name.clone(),
        date: design.date.clone(),
    }
}

/// How long a stage's output stays in the cache.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Keep {
    /// While the cache is enabled (the page's worker).
    Cached,
    /// Even by a disabled cache (made by the estimate, read again by the run).
    Always,
    /// While the cache is enabled, until [`Cache::drop_recordings`].
    Recording,
}

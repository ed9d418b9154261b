//! Inputs read for stages: meshes (imported, closed when solid, placed), zips of meshes,
//! files whole or streamed, volumes.

use super::*;

/// Files as (name, bytes).
pub type NamedFiles = Vec<(String, Vec<u8>)>;

/// The mesh files of a zip (name order) and the names of the other files in it; refused
/// when it holds no mesh. Shared by the run and the page's check on loading.
pub fn meshes_of_zip(zip_name: &str, bytes: &[u8]) -> Result<(NamedFiles, Vec<String>), String> {
    let all = volume::unzip(zip_name, bytes).map_err(|e| e.to_string())?;
    let is_mesh = |n: &str| super::SlotKind::Mesh.accept().iter().any(|x| n.to_ascii_lowercase().ends_with(x));
    let (meshes, others): (Vec<_>, Vec<_>) = all.into_iter().partition(|(n, _)| is_mesh(n));
    if meshes.is_empty() {
        return Err(format!("{zip_name} holds no STL, OBJ or 3MF file: zip the mesh files themselves"));
    }
    Ok((meshes, others.into_iter().map(|(n, _)| n).collect()))
}

/// The import stage's card: counts, what closing the solid did, the notes.
pub(super) fn import_report(r: &ImportReport) -> StageReport {
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
pub(super) fn read_solid(name: &str, bytes: &[u8], solid: bool) -> Result<(Mesh, ImportReport), Error> {
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
    pub(super) fn volume_keys(&self, slot: &str, input: &Input) -> Result<Vec<(String, Key)>, Error> {
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
    pub(super) fn memo<T, P>(&mut self, id: &str, parts: &P, upstream: &[Key], f: impl FnOnce() -> Result<T, Error>) -> Result<T, Error>
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
            self.cache.entries.insert(id.to_string(), Entry { key, value: Arc::new(v.clone()), report: None, uncounted_ms: None, recording: false });
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

/// The bytes of the file `name` of `slot`: loaded, or unpacked from the share link it came
/// `embedded` in; the one place an embedded input is decoded.
pub(super) fn named_bytes<'f>(files: &'f Files, slot: &str, name: &str, embedded: &Option<String>) -> Result<std::borrow::Cow<'f, [u8]>, Error> {
    match (files.whole(name), embedded) {
        (Some(b), _) => b,
        (None, Some(e)) => Ok(std::borrow::Cow::Owned(share::unpack(e).map_err(|source| Error::Embedded { name: name.to_string(), source })?)),
        (None, None) => Err(Error::MissingInput { name: name.to_string(), slot: slot.into() }),
    }
}

/// [`Ctx::file_bytes`] over `files`.
pub(super) fn file_bytes_in<'f>(files: &'f Files, slot: &str, input: &Input) -> Result<(std::borrow::Cow<'f, [u8]>, Key), Error> {
    match input {
        Input::File { name, embedded } => {
            let bytes = named_bytes(files, slot, name, embedded)?;
            // A loaded file's hash was taken once, on loading; an embedded one is hashed here.
            let key = files.hash(name).unwrap_or_else(|| Key::of_bytes(&bytes));
            Ok((bytes, key))
        }
        Input::Files(_) => Err(Error::NoInput(format!("the {slot} input takes one file, not several"))),
        Input::Builtin(_) => Err(Error::NoInput(format!("the {slot} input takes a file, not a built-in shape"))),
    }
}

/// One file of a volume input: its name, its bytes (borrowed when the store holds them in memory)
/// and the key of its contents.
pub(super) type VolumeFile<'f> = (String, std::borrow::Cow<'f, [u8]>, Key);

/// The files of a volume `input` (one file: a `.zip`, NRRD, raw or single DICOM; several: a
/// series), read, with the keys of their contents.
pub(super) fn volume_files<'f>(files: &'f Files, slot: &str, input: &Input) -> Result<Vec<VolumeFile<'f>>, Error> {
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

/// Resolves the mesh input of `slot`: the built-in shape, or the file (loaded, or embedded in
/// a share link) imported; with `place`, placed on the plate: XY centred on 0, lowest point at
/// Z = 0.
pub(super) fn load_input(slot: &str, input: &Input, files: &Files, place: bool, solid: bool) -> Result<(Mesh, Option<ImportReport>), Error> {
    let (mut mesh, report) = match input {
        Input::Builtin(shape) => (shape.mesh(), None),
        Input::File { name, embedded } => {
            let bytes = named_bytes(files, slot, name, embedded)?;
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

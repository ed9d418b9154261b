//! 3MF: a zip container holding XML model parts.
//!
//! The model part is found through `_rels/.rels` (falling back to `3D/3dmodel.model`).
//! Read: `<model unit>`, `<object id><mesh><vertices><vertex x y z/>…<triangles><triangle
//! v1 v2 v3/>`, `<components><component objectid transform p:path/>` (recursively, the
//! production extension's `p:path` parts included) and `<build><item objectid transform/>`.
//! Transforms are 3MF's 3×4 row-vector matrices `m00 m01 m02 m10 m11 m12 m20 m21 m22 m30 m31
//! m32`: `x' = x·m00 + y·m10 + z·m20 + m30`, and so on. Everything else (materials, colours,
//! metadata, thumbnails, slicer settings) is ignored.
//!
//! Streaming and linear: each part is inflated in 64 KiB pieces straight into the XML
//! reader (the inflated part is never held whole), and the piece reader counts the lines it
//! hands over, so an element's line costs nothing (counting from the start of the part for
//! every element made large files quadratic). Limits are checked as the XML streams: element
//! depth ([`MAX_XML_DEPTH`]), token length, inflated bytes ([`MAX_MODEL_PART_BYTES`]), the
//! triangles and vertices stored ([`super::MAX_TRIANGLES`]), objects and references; then the
//! build is counted (every item and component placed) and checked before its output is
//! allocated. Objects are found by id through a sorted index, parts through interned names.
//! Entities are never expanded (`&name;` other than XML's five stays literal text, so a
//! billion-laughs or external-entity file is just a bad number).

use super::{clean, clean_n, group, malformed, raw_bytes, Error, RawMesh, MAX_IMPORT_BYTES, MAX_TRIANGLES};
use quick_xml::events::{BytesStart, Event};
use quick_xml::Reader;
use std::borrow::Cow;
use std::collections::{BTreeMap, BTreeSet};
use std::io::{self, BufRead, Cursor, Read};

/// Largest uncompressed model part (and total of all parts read) weft inflates: 512 MiB.
/// Bigger is refused as a likely zip bomb. (Parts stream, so this bounds time, not memory.)
pub const MAX_MODEL_PART_BYTES: u64 = 512 * 1024 * 1024;

/// Deepest XML element nesting read in a 3MF part. A model part nests 6–8 deep
/// (model/resources/object/mesh/triangles/triangle, a few more with extensions); deeper is a
/// damaged or hostile file, refused before the parser's open-element stack grows.
pub const MAX_XML_DEPTH: usize = 64;

/// Longest single XML token (a tag with its attributes, a text run) buffered. Real tokens
/// are under a few KiB; the cap bounds the parser's buffer against a 500 MB attribute.
const MAX_TOKEN_BYTES: u64 = 16 << 20;
/// Most component instances expanded (guards against exponential component graphs); also
/// the most objects and the most components and build items stored.
const MAX_INSTANCES: usize = 1_000_000;
/// Deepest component nesting.
const MAX_DEPTH: usize = 32;
/// Most model parts read through `p:path`.
const MAX_PARTS: usize = 4096;
/// Longest part name (`p:path`, relationship target) looked up; real ones are under 100.
const MAX_PATH_CHARS: usize = 1024;
/// Most zip entries: a 3MF has a handful (a few hundred with many plate thumbnails); the
/// zip reader keeps a few hundred bytes per entry, so a forged directory of millions of
/// entries would cost gigabytes before any model is read.
const MAX_ZIP_ENTRIES: usize = 10_000;
/// Inflate piece size.
const CHUNK: usize = 64 << 10;
const DEFAULT_MODEL: &str = "3D/3dmodel.model";
const REEXPORT: &str = "the 3MF file is damaged; export it again";

type Affine = [f64; 12];
const IDENTITY: Affine = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0];
/// `Ref::xf` of the identity transform (most components have none).
const NO_XF: u32 = u32::MAX;

#[inline]
fn apply(m: &Affine, p: [f64; 3]) -> [f64; 3] {
    [p[0] * m[0] + p[1] * m[3] + p[2] * m[6] + m[9], p[0] * m[1] + p[1] * m[4] + p[2] * m[7] + m[10], p[0] * m[2] + p[1] * m[5] + p[2] * m[8] + m[11]]
}

/// The transform applying `first`, then `then`.
fn compose(first: &Affine, then: &Affine) -> Affine {
    let mut out = [0.0; 12];
    for r in 0..4 {
        for c in 0..3 {
            let mut v = first[r * 3] * then[c] + first[r * 3 + 1] * then[3 + c] + first[r * 3 + 2] * then[6 + c];
            if r == 3 {
                v += then[9 + c];
            }
            out[r * 3 + c] = v;
        }
    }
    out
}

/// A reference to an object (build item or component). `xf` indexes the transforms of the
/// part the reference is written in.
#[derive(Clone, Copy, Debug)]
struct Ref {
    part: u32,
    id: u32,
    xf: u32,
    line: usize,
}

/// An object: its slices of the part's vertex, triangle and component arrays.
#[derive(Debug, Default)]
struct Object {
    id: u32,
    line: usize,
    other: bool,
    v0: usize,
    nv: usize,
    t0: usize,
    nt: usize,
    c0: usize,
    nc: usize,
}

#[derive(Debug, Default)]
struct Part {
    unit: Option<String>,
    unit_line: usize,
    objects: Vec<Object>,
    /// (id, index into `objects`), sorted by id once the part is read.
    by_id: Vec<(u32, u32)>,
    build: Option<Vec<Ref>>,
    /// Vertices and triangles of every object (empty when only counting).
    vertices: Vec<[f64; 3]>,
    triangles: Vec<[u32; 3]>,
    components: Vec<Ref>,
    transforms: Vec<Affine>,
}

impl Part {
    fn object(&self, id: u32) -> Option<&Object> {
        let i = self.by_id.binary_search_by_key(&id, |&(k, _)| k).ok()?;
        let &(_, at) = self.by_id.get(i)?;
        self.objects.get(at as usize)
    }
    fn transform(&self, xf: u32) -> &Affine {
        self.transforms.get(xf as usize).unwrap_or(&IDENTITY)
    }
}

/// What the reader stores, counted as it streams (bytes of the stored arrays).
#[derive(Debug, Default, Clone, Copy)]
struct Stored {
    vertices: u64,
    triangles: u64,
    objects: u64,
    refs: u64,
    transforms: u64,
    name_bytes: u64,
    /// Zip directory entries (the zip reader keeps a few hundred bytes each).
    zip_entries: u64,
    /// Largest XML token buffered (the parser's buffer keeps its size).
    token_bytes: u64,
}

impl Stored {
    fn bytes(&self) -> u64 {
        24 * self.vertices
            + 12 * self.triangles
            + (std::mem::size_of::<Object>() as u64 + 8) * self.objects
            + std::mem::size_of::<Ref>() as u64 * self.refs
            + 96 * self.transforms
            + 2 * self.name_bytes
    }
}

/// Peak bytes (the input excluded) of reading a 3MF that stores `s` and places `v` vertices
/// and `t` triangles: while streaming the arrays grow by doubling (capacity ≤ 2× length,
/// 3× while one moves), then the objects (≤ 2×) and the exactly sized output coexist, then
/// the output is cleaned. Plus the buffers (zip directory, inflate window and pieces, the
/// largest XML token).
fn peak(s: &Stored, v: u64, t: u64) -> u64 {
    let stored = s.bytes();
    let parse = 3 * stored;
    let expand = 2 * stored + raw_bytes(v, t);
    let cleaning = raw_bytes(v, t) + super::repair::extra_peak(v, t);
    parse.max(expand).max(cleaning) + super::FIXED_PEAK_BYTES + 2 * CHUNK as u64 + 2 * s.token_bytes + 512 * s.zip_entries
}

/// Counts of a 3MF for [`super::estimate`].
pub(super) struct Counts {
    pub vertices: u64,
    pub triangles: u64,
    /// Input excluded.
    pub peak_bytes: u64,
}

/// Part names, interned: references carry a number, not a string.
#[derive(Default)]
struct Names {
    list: Vec<String>,
    ids: BTreeMap<String, u32>,
}

impl Names {
    /// The id of `name`, and whether it is new.
    fn intern(&mut self, name: &str) -> (u32, bool) {
        if let Some(&id) = self.ids.get(name) {
            return (id, false);
        }
        let id = self.list.len() as u32;
        self.list.push(name.to_string());
        self.ids.insert(name.to_string(), id);
        (id, true)
    }
    fn get(&self, id: u32) -> &str {
        self.list.get(id as usize).map_or("", |s| s.as_str())
    }
    /// The name for messages.
    fn show(&self, id: u32) -> String {
        clean(self.get(id))
    }
}

/// Shared state of one read.
struct Load<'a> {
    file: &'a str,
    input: u64,
    /// Only count vertices and triangles (for the estimate).
    counting: bool,
    names: Names,
    stored: Stored,
}

impl Load<'_> {
    fn too_large(&self, place: &str, problem: String) -> Error {
        Error::TooLarge {
            file: self.file.to_string(),
            problem: format!("{place}: {problem}"),
            fix: format!(
                "decimate the mesh (e.g. in PrusaSlicer: right-click the object, Simplify model) to under {} triangles, or split it into parts",
                group(MAX_TRIANGLES as u64)
            ),
        }
    }

    /// Checks what is stored so far (called as each vertex, triangle or reference arrives).
    #[inline]
    fn check_stored(&self, cx: &Ctx) -> Result<(), Error> {
        let s = &self.stored;
        if self.counting {
            // Nothing per vertex or triangle is stored; only the object graph is.
            if s.objects > MAX_INSTANCES as u64 || s.refs > MAX_INSTANCES as u64 {
                return Err(self.too_many_refs(cx));
            }
            return Ok(());
        }
        if s.triangles > MAX_TRIANGLES as u64 {
            return Err(self.too_large(&cx.place(), format!("the objects hold more than {} triangles, the limit", group(MAX_TRIANGLES as u64))));
        }
        if s.vertices > 3 * MAX_TRIANGLES as u64 {
            return Err(self.too_large(
                &cx.place(),
                format!(
                    "the objects hold more than {} vertices (3 per triangle of the {} triangle limit)",
                    group(3 * MAX_TRIANGLES as u64),
                    group(MAX_TRIANGLES as u64)
                ),
            ));
        }
        if s.objects > MAX_INSTANCES as u64 || s.refs > MAX_INSTANCES as u64 {
            return Err(self.too_many_refs(cx));
        }
        let need = self.input.saturating_add(3 * s.bytes());
        if need > MAX_IMPORT_BYTES {
            return Err(self.too_large(
                &cx.place(),
                format!("reading the objects so far needs about {} MiB of memory, limit {} MiB", group(need >> 20), group(MAX_IMPORT_BYTES >> 20)),
            ));
        }
        Ok(())
    }

    fn too_many_refs(&self, cx: &Ctx) -> Error {
        malformed(self.file, cx.place(), format!("more than {} objects, components or build items", group(MAX_INSTANCES as u64)), "simplify the assembly")
    }
}

/// Reads a 3MF; returns the raw mesh in mm and the unit scale applied.
pub(super) fn read_3mf(file: &str, bytes: &[u8]) -> Result<(RawMesh, f64), Error> {
    let (loaded, mut ld) = load(file, bytes, false)?;
    let Loaded { parts, root, scale, items } = loaded;
    // Count the placed mesh (all structural errors surface here), check, then place it.
    let mut walk = Walk { file, parts: &parts, names: &ld.names, scale, out: None, instances: 0, stack: Vec::new(), v: 0, t: 0 };
    for item in &items {
        walk.visit(item, &IDENTITY, root, 0)?;
    }
    let (v, t) = (walk.v, walk.t);
    check_build(&mut ld, root, v, t)?;
    let mut out = RawMesh { vertices: Vec::with_capacity(v as usize), triangles: Vec::with_capacity(t as usize) };
    let mut walk = Walk { file, parts: &parts, names: &ld.names, scale, out: Some(&mut out), instances: 0, stack: Vec::new(), v: 0, t: 0 };
    for item in &items {
        walk.visit(item, &IDENTITY, root, 0)?;
    }
    Ok((out, scale))
}

/// Counts a 3MF without storing its meshes (for [`super::estimate`]).
pub(super) fn count_3mf(file: &str, bytes: &[u8]) -> Result<Counts, Error> {
    let (loaded, ld) = load(file, bytes, true)?;
    let mut walk = Walk { file, parts: &loaded.parts, names: &ld.names, scale: loaded.scale, out: None, instances: 0, stack: Vec::new(), v: 0, t: 0 };
    for item in &loaded.items {
        walk.visit(item, &IDENTITY, loaded.root, 0)?;
    }
    // Counting stored nothing per vertex; the real read stores what was counted.
    let mut stored = ld.stored;
    stored.vertices = loaded.parts.iter().flatten().map(|p| p.objects.iter().map(|o| o.nv as u64).sum::<u64>()).sum();
    stored.triangles = loaded.parts.iter().flatten().map(|p| p.objects.iter().map(|o| o.nt as u64).sum::<u64>()).sum();
    Ok(Counts { vertices: walk.v, triangles: walk.t, peak_bytes: peak(&stored, walk.v, walk.t) })
}

/// Refuses a build of `v` vertices and `t` triangles over the limits, before placing it.
fn check_build(ld: &mut Load, root: u32, v: u64, t: u64) -> Result<(), Error> {
    let place = ld.names.show(root);
    if t > MAX_TRIANGLES as u64 {
        return Err(
            ld.too_large(&place, format!("the build places {} triangles (every item and component counted), limit {}", group(t), group(MAX_TRIANGLES as u64)))
        );
    }
    if v > 3 * MAX_TRIANGLES as u64 {
        return Err(ld.too_large(&place, format!("the build places {} vertices, limit {}", group(v), group(3 * MAX_TRIANGLES as u64))));
    }
    let need = ld.input.saturating_add(peak(&ld.stored, v, t));
    if need > MAX_IMPORT_BYTES {
        return Err(ld.too_large(
            &place,
            format!("placing the build ({} triangles) needs about {} MiB of memory, limit {} MiB", group(t), group(need >> 20), group(MAX_IMPORT_BYTES >> 20)),
        ));
    }
    Ok(())
}

struct Loaded {
    /// Indexed by part name id.
    parts: Vec<Option<Part>>,
    root: u32,
    scale: f64,
    items: Vec<Ref>,
}

/// Opens the zip and streams every model part reachable from the root.
fn load<'a>(file: &'a str, bytes: &[u8], counting: bool) -> Result<(Loaded, Load<'a>), Error> {
    let entries = count_central_headers(bytes);
    if entries > MAX_ZIP_ENTRIES {
        return Err(malformed(
            file,
            "the archive",
            format!("it lists {} parts, more than the {} a 3MF may have", group(entries as u64), group(MAX_ZIP_ENTRIES as u64)),
            REEXPORT,
        ));
    }
    // zip's own words ("Could not find EOCD") say nothing to a user: a 3MF is an archive and
    // this one cannot be opened.
    let mut zip = zip::ZipArchive::new(Cursor::new(bytes))
        .map_err(|_| malformed(file, "the archive", "a 3MF is an archive of parts and this one cannot be opened: it was cut short or damaged", REEXPORT))?;
    let mut ld = Load { file, input: bytes.len() as u64, counting, names: Names::default(), stored: Stored::default() };
    ld.stored.zip_entries = zip.len() as u64;
    let mut budget = MAX_MODEL_PART_BYTES;
    let mut lower: Option<BTreeMap<String, usize>> = None;
    let root_name = root_model_path(&mut ld, &mut zip, &mut lower, &mut budget)?;
    let (root, _) = ld.names.intern(&root_name);
    let mut parts: Vec<Option<Part>> = Vec::new();
    let mut pending = vec![root];
    while let Some(id) = pending.pop() {
        if parts.get(id as usize).is_some_and(|p| p.is_some()) {
            continue;
        }
        let name = ld.names.get(id).to_string();
        let Some(index) = find_entry(&mut zip, &mut lower, &name) else {
            let problem = if id == root {
                "the 3MF has no 3D model part".to_string()
            } else {
                "a component refers to this model part, which is not in the file".to_string()
            };
            return Err(malformed(file, ld.names.show(id), problem, REEXPORT));
        };
        let first_new = ld.names.list.len() as u32;
        let shown = ld.names.show(id);
        let part = stream_entry(&mut ld, &mut zip, index, shown, &mut budget, |ld, reader| parse_part(ld, id, reader))?;
        // Parts named for the first time while reading this one are read next.
        pending.extend(first_new..ld.names.list.len() as u32);
        if parts.len() < ld.names.list.len() {
            parts.resize_with(ld.names.list.len(), || None);
        }
        if let Some(slot) = parts.get_mut(id as usize) {
            *slot = Some(part);
        }
    }
    parts.resize_with(ld.names.list.len(), || None);
    let Some(root_part) = parts.get(root as usize).and_then(|p| p.as_ref()) else {
        return Err(malformed(file, ld.names.show(root), "the 3MF has no 3D model part", REEXPORT));
    };
    let scale = match root_part.unit.as_deref() {
        None | Some("millimeter") => 1.0,
        Some("micron") => 0.001,
        Some("centimeter") => 10.0,
        Some("inch") => 25.4,
        Some("foot") => 304.8,
        Some("meter") => 1000.0,
        Some(other) => {
            return Err(malformed(
                file,
                format!("{} line {}", ld.names.show(root), root_part.unit_line),
                format!("unknown unit \"{}\"", super::show(other.as_bytes())),
                "use micron, millimeter, centimeter, inch, foot or meter",
            ))
        }
    };
    let items: Vec<Ref> = match &root_part.build {
        Some(items) if !items.is_empty() => items.clone(),
        // No build: every object that is not a component of another one, in file order.
        _ => {
            let used: BTreeSet<u32> = root_part.components.iter().filter(|c| c.part == root).map(|c| c.id).collect();
            root_part.objects.iter().filter(|o| !used.contains(&o.id)).map(|o| Ref { part: root, id: o.id, xf: NO_XF, line: o.line }).collect()
        }
    };
    Ok((Loaded { parts, root, scale, items }, ld))
}

/// Central directory headers (`PK\x01\x02`) anywhere in `bytes`: at least as many as any
/// directory the zip reader could decode.
fn count_central_headers(bytes: &[u8]) -> usize {
    let mut n = 0;
    let mut i = 0;
    while let Some(p) = bytes.get(i..).and_then(|rest| rest.iter().position(|&b| b == b'P')) {
        i += p + 1;
        if bytes.get(i..i + 3) == Some(b"K\x01\x02") {
            n += 1;
        }
    }
    n
}

/// Walks the build: counts (first pass) or places (second pass, `out` set) every instance.
struct Walk<'a, 'o> {
    file: &'a str,
    parts: &'a [Option<Part>],
    names: &'a Names,
    scale: f64,
    out: Option<&'o mut RawMesh>,
    instances: usize,
    stack: Vec<(u32, u32)>,
    v: u64,
    t: u64,
}

impl Walk<'_, '_> {
    /// Places object `r` (referenced from part `from` at `r.line`) with its transform, then `parent`.
    fn visit(&mut self, r: &Ref, parent: &Affine, from: u32, depth: usize) -> Result<(), Error> {
        let file = self.file;
        let names = self.names;
        let place = || format!("{} line {}", names.show(from), r.line);
        self.instances += 1;
        if self.instances > MAX_INSTANCES {
            return Err(malformed(file, place(), format!("the build expands to more than {MAX_INSTANCES} object instances"), "simplify the assembly"));
        }
        if depth > MAX_DEPTH {
            return Err(malformed(file, place(), format!("components nest deeper than {MAX_DEPTH} levels"), "flatten the assembly and export again"));
        }
        let parts = self.parts;
        let Some(part) = parts.get(r.part as usize).and_then(|p| p.as_ref()) else {
            return Err(malformed(file, place(), format!("refers to model part {}, which is not in the file", names.show(r.part)), REEXPORT));
        };
        let Some(obj) = part.object(r.id) else {
            return Err(malformed(file, place(), format!("refers to object {}, which is not defined in {}", r.id, names.show(r.part)), REEXPORT));
        };
        if self.stack.iter().any(|&(p, id)| p == r.part && id == r.id) {
            return Err(malformed(file, place(), format!("object {} contains itself through its components", r.id), "remove the circular component reference"));
        }
        if obj.other {
            return Ok(());
        }
        let from_part = parts.get(from as usize).and_then(|p| p.as_ref());
        let own = from_part.map_or(&IDENTITY, |p| p.transform(r.xf));
        let xf = compose(own, parent);
        if obj.nt > 0 {
            self.v += obj.nv as u64;
            self.t += obj.nt as u64;
            if let Some(out) = self.out.as_deref_mut() {
                let base = out.vertices.len() as u32;
                let vs = part.vertices.get(obj.v0..obj.v0 + obj.nv).unwrap_or_default();
                for v in vs {
                    let p = apply(&xf, *v);
                    let q = [(p[0] * self.scale) as f32, (p[1] * self.scale) as f32, (p[2] * self.scale) as f32];
                    if !q.iter().all(|c| c.is_finite()) {
                        return Err(malformed(
                            file,
                            place(),
                            format!("placing object {} gives coordinates too large to represent", r.id),
                            "check the unit and the transforms",
                        ));
                    }
                    out.vertices.push(q);
                }
                let ts = part.triangles.get(obj.t0..obj.t0 + obj.nt).unwrap_or_default();
                out.triangles.extend(ts.iter().map(|t| [t[0] + base, t[1] + base, t[2] + base]));
            }
        }
        if obj.nc > 0 {
            self.stack.push((r.part, r.id));
            for c in part.components.get(obj.c0..obj.c0 + obj.nc).unwrap_or_default() {
                self.visit(c, &xf, r.part, depth + 1)?;
            }
            self.stack.pop();
        }
        Ok(())
    }
}

/// Finds a zip entry by exact name, else case-insensitively (one lowercase index built on
/// the first miss, not a scan per lookup).
fn find_entry(zip: &mut zip::ZipArchive<Cursor<&[u8]>>, lower: &mut Option<BTreeMap<String, usize>>, name: &str) -> Option<usize> {
    if let Some(i) = zip.index_for_name(name) {
        return Some(i);
    }
    let index = lower.get_or_insert_with(|| {
        let mut m = BTreeMap::new();
        for (i, n) in zip.file_names().enumerate() {
            if let Ok(n) = n {
                m.entry(n.to_ascii_lowercase()).or_insert(i);
            }
        }
        m
    });
    index.get(&name.to_ascii_lowercase()).copied()
}

/// Why the piece reader stopped the XML reader.
#[derive(Debug, Clone)]
enum Stop {
    Budget,
    Token,
    Inflate,
}

/// The inflating reader under the XML parser: hands over 64 KiB pieces, counts the lines
/// consumed (the line of the token just read, for free), and enforces the inflation budget
/// and the token length.
struct Source<R> {
    inner: R,
    buf: Vec<u8>,
    pos: usize,
    end: usize,
    lines: usize,
    inflated: u64,
    budget: u64,
    /// Bytes consumed since the current token started, and the most for one token.
    token: u64,
    longest: u64,
    stop: Option<Stop>,
}

impl<R: Read> Source<R> {
    fn new(inner: R, budget: u64) -> Self {
        Source { inner, buf: vec![0; CHUNK], pos: 0, end: 0, lines: 0, inflated: 0, budget, token: 0, longest: 0, stop: None }
    }
}

impl<R: Read> Read for Source<R> {
    fn read(&mut self, out: &mut [u8]) -> io::Result<usize> {
        let avail = self.fill_buf()?;
        let n = avail.len().min(out.len());
        if let (Some(dst), Some(src)) = (out.get_mut(..n), avail.get(..n)) {
            dst.copy_from_slice(src);
        }
        self.consume(n);
        Ok(n)
    }
}

impl<R: Read> BufRead for Source<R> {
    fn fill_buf(&mut self) -> io::Result<&[u8]> {
        if self.token > MAX_TOKEN_BYTES {
            self.stop = Some(Stop::Token);
            return Err(io::Error::other("token too long"));
        }
        if self.pos >= self.end {
            let n = match self.inner.read(&mut self.buf) {
                Ok(n) => n,
                Err(e) if e.kind() == io::ErrorKind::Interrupted => 0,
                Err(e) => {
                    self.stop = Some(Stop::Inflate);
                    return Err(e);
                }
            };
            self.inflated += n as u64;
            if self.inflated > self.budget {
                self.stop = Some(Stop::Budget);
                return Err(io::Error::other("inflation budget"));
            }
            self.pos = 0;
            self.end = n;
        }
        Ok(self.buf.get(self.pos..self.end).unwrap_or_default())
    }

    fn consume(&mut self, amt: usize) {
        let amt = amt.min(self.end.saturating_sub(self.pos));
        let taken = self.buf.get(self.pos..self.pos + amt).unwrap_or_default();
        self.lines += taken.iter().filter(|&&b| b == b'\n').count();
        crate::work::add(taken.len());
        self.pos += amt;
        self.token += amt as u64;
    }
}

type Xml<'z, 'b> = Reader<Source<zip::read::ZipFile<'z, Cursor<&'b [u8]>>>>;

fn bomb(file: &str, part: &str) -> Error {
    malformed(
        file,
        part,
        format!("the part inflates to more than {} MiB", MAX_MODEL_PART_BYTES / (1024 * 1024)),
        "this is too large to be a real model (possibly a zip bomb); simplify the mesh or split it",
    )
}

/// Streams zip entry `index` (`shown` in messages) through `parse`, within the inflation budget.
fn stream_entry<'b, T>(
    ld: &mut Load,
    zip: &mut zip::ZipArchive<Cursor<&'b [u8]>>,
    index: usize,
    shown: String,
    budget: &mut u64,
    parse: impl FnOnce(&mut Load, &mut Xml<'_, 'b>) -> Result<T, Error>,
) -> Result<T, Error> {
    let file = ld.file;
    let entry = zip.by_index(index).map_err(|_| malformed(file, shown.as_str(), "the part cannot be read: the archive is damaged", REEXPORT))?;
    if entry.size() > *budget {
        return Err(bomb(file, &shown));
    }
    let mut reader = Reader::from_reader(Source::new(entry, *budget));
    let result = parse(ld, &mut reader);
    *budget = budget.saturating_sub(reader.get_ref().inflated);
    ld.stored.token_bytes = ld.stored.token_bytes.max(reader.get_ref().longest);
    result
}

/// The error for a failed read of the XML, naming the cause the piece reader recorded.
fn xml_error<R>(file: &str, part: &str, reader: &Reader<Source<R>>, e: &quick_xml::Error) -> Error {
    let src = reader.get_ref();
    let line = src.lines + 1;
    match &src.stop {
        Some(Stop::Budget) => bomb(file, part),
        Some(Stop::Token) => malformed(
            file,
            format!("{part} line {line}"),
            format!("an XML tag or text is longer than {} MiB", MAX_TOKEN_BYTES >> 20),
            "this is not a real model (damaged or hostile); export it again",
        ),
        Some(Stop::Inflate) => malformed(file, part, "the part cannot be unpacked: its compressed data is damaged", REEXPORT),
        None => {
            let offset = reader.error_position();
            if matches!(e, quick_xml::Error::Encoding(_)) {
                return malformed(
                    file,
                    format!("{part} line {line}"),
                    format!("byte {offset} is not text: the model was saved in an encoding other than the UTF-8 a 3MF must use"),
                    "export the model again",
                );
            }
            malformed(file, format!("{part} line {line} (byte {offset})"), format!("the XML is malformed ({})", clean_n(&e.to_string(), 160)), REEXPORT)
        }
    }
}

/// Reads the next event, tracking element depth against [`MAX_XML_DEPTH`].
fn next_event<'b, R: Read>(file: &str, part: &str, reader: &mut Reader<Source<R>>, buf: &'b mut Vec<u8>, depth: &mut usize) -> Result<Event<'b>, Error> {
    buf.clear();
    reader.get_mut().token = 0;
    let ev = match reader.read_event_into(buf) {
        Ok(ev) => ev,
        Err(e) => return Err(xml_error(file, part, reader, &e)),
    };
    let src = reader.get_mut();
    src.longest = src.longest.max(src.token);
    match &ev {
        Event::Start(_) => {
            *depth += 1;
            if *depth > MAX_XML_DEPTH {
                return Err(malformed(
                    file,
                    format!("{part} line {}", reader.get_ref().lines + 1),
                    format!("XML elements nest deeper than {MAX_XML_DEPTH} levels (a 3MF model needs under 10)"),
                    "this is not a real model (damaged or hostile); export it again",
                ));
            }
        }
        Event::End(_) => *depth = depth.saturating_sub(1),
        _ => {}
    }
    Ok(ev)
}

/// Finds the model part through `_rels/.rels`, else the default path.
fn root_model_path(
    ld: &mut Load,
    zip: &mut zip::ZipArchive<Cursor<&[u8]>>,
    lower: &mut Option<BTreeMap<String, usize>>,
    budget: &mut u64,
) -> Result<String, Error> {
    let rels_name = "_rels/.rels";
    let Some(index) = find_entry(zip, lower, rels_name) else {
        return Ok(DEFAULT_MODEL.to_string());
    };
    let found = stream_entry(ld, zip, index, rels_name.to_string(), budget, |ld, reader| {
        let file = ld.file;
        let (mut buf, mut depth) = (Vec::new(), 0);
        loop {
            let e = match next_event(file, rels_name, reader, &mut buf, &mut depth)? {
                Event::Start(e) | Event::Empty(e) => e,
                Event::Eof => return Ok(None),
                _ => continue,
            };
            if local(e.name().as_ref()) != "Relationship" {
                continue;
            }
            let cx = Ctx { file, part: rels_name, line: reader.get_ref().lines + 1 };
            let [target, kind] = attrs(&cx, &e, ["Target", "Type"])?;
            if let (Some(t), Some(k)) = (target, kind) {
                if k.trim_end_matches('/').ends_with("/3dmodel") {
                    return Ok(Some(normalize_path(&t)));
                }
            }
        }
    })?;
    Ok(found.unwrap_or_else(|| DEFAULT_MODEL.to_string()))
}

fn normalize_path(p: &str) -> String {
    p.trim().trim_start_matches('/').to_string()
}

/// The name after any namespace prefix.
fn local(name: &str) -> &str {
    match name.rfind(':') {
        Some(i) => name.get(i + 1..).unwrap_or(name),
        None => name,
    }
}

/// The values of the attributes named `keys` (local names; the first of duplicates wins;
/// namespace declarations skipped), unescaped (unknown entities stay literal).
fn attrs<'e, const N: usize>(cx: &Ctx, e: &'e BytesStart<'_>, keys: [&str; N]) -> Result<[Option<Cow<'e, str>>; N], Error> {
    let mut out: [Option<Cow<'e, str>>; N] = std::array::from_fn(|_| None);
    for a in e.attributes().with_checks(false) {
        let a = a.map_err(|err| cx.err(format!("bad attribute ({})", clean_n(&err.to_string(), 160))))?;
        let key = a.key.as_ref();
        if key == "xmlns" || key.starts_with("xmlns:") {
            continue;
        }
        let key = local(key);
        if let Some(slot) = keys.iter().position(|k| *k == key).and_then(|k| out.get_mut(k)) {
            if slot.is_none() {
                let v = a.value;
                *slot = Some(if v.contains('&') {
                    match quick_xml::escape::unescape(&v) {
                        Ok(u) => Cow::Owned(u.into_owned()),
                        Err(_) => v,
                    }
                } else {
                    v
                });
            }
        }
    }
    Ok(out)
}

struct Ctx<'a> {
    file: &'a str,
    part: &'a str,
    line: usize,
}

impl Ctx<'_> {
    fn place(&self) -> String {
        format!("{} line {}", self.part, self.line)
    }
    fn err(&self, problem: String) -> Error {
        malformed(self.file, self.place(), problem, REEXPORT)
    }
    fn float(&self, el: &str, name: &str, v: Option<&str>) -> Result<f64, Error> {
        let v = v.ok_or_else(|| self.err(format!("<{el}> has no {name} attribute")))?;
        v.trim()
            .parse::<f64>()
            .ok()
            .filter(|x| x.is_finite())
            .ok_or_else(|| self.err(format!("<{el}> {name}=\"{}\" is not a finite number", super::show(v.as_bytes()))))
    }
    fn id(&self, el: &str, name: &str, v: Option<&str>) -> Result<u32, Error> {
        let v = v.ok_or_else(|| self.err(format!("<{el}> has no {name} attribute")))?;
        v.trim().parse::<u32>().map_err(|_| self.err(format!("<{el}> {name}=\"{}\" is not a valid index", super::show(v.as_bytes()))))
    }
    fn transform(&self, el: &str, v: Option<&str>) -> Result<Option<Affine>, Error> {
        let Some(v) = v else { return Ok(None) };
        let mut m = [0.0; 12];
        let mut n = 0;
        for t in v.split_ascii_whitespace() {
            let x = t.parse::<f64>().ok().filter(|x| x.is_finite());
            match (x, m.get_mut(n)) {
                (Some(x), Some(slot)) => *slot = x,
                _ => return Err(self.err(format!("<{el}> transform must be 12 finite numbers, found \"{}\"", super::show(v.as_bytes())))),
            }
            n += 1;
        }
        if n != 12 {
            return Err(self.err(format!("<{el}> transform has {n} numbers, needs 12")));
        }
        Ok(Some(m))
    }
    /// The part a `p:path` names (interned), else this part.
    fn target(&self, ld: &mut Load, el: &str, here: u32, path: Option<&str>) -> Result<u32, Error> {
        let Some(path) = path else { return Ok(here) };
        let path = normalize_path(path);
        let chars = path.chars().count();
        if chars > MAX_PATH_CHARS {
            return Err(self.err(format!("<{el}> p:path is {} characters long, more than the {MAX_PATH_CHARS} weft reads", group(chars as u64))));
        }
        let (id, new) = ld.names.intern(&path);
        if new {
            if ld.names.list.len() > MAX_PARTS {
                return Err(malformed(self.file, self.place(), format!("more than {MAX_PARTS} model parts are referenced"), REEXPORT));
            }
            ld.stored.name_bytes += path.len() as u64;
        }
        Ok(id)
    }
}

/// A reference's transform: stored in the part when it is not the identity.
fn push_transform(ld: &mut Load, part: &mut Part, m: Option<Affine>) -> u32 {
    match m {
        Some(m) if m != IDENTITY => {
            part.transforms.push(m);
            ld.stored.transforms += 1;
            (part.transforms.len() - 1) as u32
        }
        _ => NO_XF,
    }
}

/// Streams one model part (name id `id`).
fn parse_part<R: Read>(ld: &mut Load, id: u32, reader: &mut Reader<Source<R>>) -> Result<Part, Error> {
    let file = ld.file;
    let shown = ld.names.show(id);
    let name = shown.as_str();
    let mut part = Part::default();
    let mut current: Option<Object> = None;
    let mut in_build = false;
    let mut saw_model = false;
    let (mut buf, mut depth) = (Vec::new(), 0);
    loop {
        let (e, empty) = match next_event(file, name, reader, &mut buf, &mut depth)? {
            Event::Start(e) => (e, false),
            Event::Empty(e) => (e, true),
            Event::End(e) => {
                match local(e.name().as_ref()) {
                    "object" => {
                        if let Some(o) = current.take() {
                            finish_object(&mut part, o);
                        }
                    }
                    "build" => in_build = false,
                    _ => {}
                }
                continue;
            }
            Event::Eof => break,
            _ => continue,
        };
        let line = reader.get_ref().lines + 1;
        let cx = Ctx { file, part: name, line };
        let tag = e.name();
        match local(tag.as_ref()) {
            "vertex" => {
                if let Some(o) = current.as_mut() {
                    o.nv += 1;
                    ld.stored.vertices += 1;
                    if !ld.counting {
                        let [x, y, z] = attrs(&cx, &e, ["x", "y", "z"])?;
                        let p = [cx.float("vertex", "x", x.as_deref())?, cx.float("vertex", "y", y.as_deref())?, cx.float("vertex", "z", z.as_deref())?];
                        part.vertices.push(p);
                        ld.check_stored(&cx)?;
                    }
                }
            }
            "triangle" => {
                if let Some(o) = current.as_mut() {
                    if !ld.counting {
                        let vs = attrs(&cx, &e, ["v1", "v2", "v3"])?;
                        let mut t = [0u32; 3];
                        for ((key, v), slot) in ["v1", "v2", "v3"].iter().zip(vs).zip(t.iter_mut()) {
                            let v = cx.id("triangle", key, v.as_deref())?;
                            if v as usize >= o.nv {
                                return Err(cx.err(format!("<triangle> {key}=\"{v}\" but object {} has {} vertices (indices start at 0)", o.id, o.nv)));
                            }
                            *slot = v;
                        }
                        part.triangles.push(t);
                    }
                    o.nt += 1;
                    ld.stored.triangles += 1;
                    if !ld.counting {
                        ld.check_stored(&cx)?;
                    }
                }
            }
            "component" => {
                if let Some(o) = current.as_mut() {
                    let [oid, xf, path] = attrs(&cx, &e, ["objectid", "transform", "path"])?;
                    let cid = cx.id("component", "objectid", oid.as_deref())?;
                    let m = cx.transform("component", xf.as_deref())?;
                    let target = cx.target(ld, "component", id, path.as_deref())?;
                    let xf = push_transform(ld, &mut part, m);
                    part.components.push(Ref { part: target, id: cid, xf, line });
                    o.nc += 1;
                    ld.stored.refs += 1;
                    ld.check_stored(&cx)?;
                }
            }
            "object" => {
                if let Some(o) = current.take() {
                    finish_object(&mut part, o);
                }
                let [oid, kind] = attrs(&cx, &e, ["id", "type"])?;
                let oid = cx.id("object", "id", oid.as_deref())?;
                let other = kind.is_some_and(|t| t.trim() == "other");
                let o = Object { id: oid, line, other, v0: part.vertices.len(), t0: part.triangles.len(), c0: part.components.len(), ..Object::default() };
                ld.stored.objects += 1;
                ld.check_stored(&cx)?;
                if empty {
                    finish_object(&mut part, o);
                } else {
                    current = Some(o);
                }
            }
            "model" => {
                saw_model = true;
                let [unit] = attrs(&cx, &e, ["unit"])?;
                // Only known units matter; keep a short prefix of anything else for the message.
                part.unit = unit.map(|u| u.trim().chars().take(64).collect::<String>().to_ascii_lowercase());
                part.unit_line = line;
            }
            "build" => {
                part.build.get_or_insert_with(Vec::new);
                in_build = !empty;
            }
            "item" if in_build => {
                let [oid, xf, path] = attrs(&cx, &e, ["objectid", "transform", "path"])?;
                let oid = cx.id("item", "objectid", oid.as_deref())?;
                let m = cx.transform("item", xf.as_deref())?;
                let target = cx.target(ld, "item", id, path.as_deref())?;
                let xf = push_transform(ld, &mut part, m);
                part.build.get_or_insert_with(Vec::new).push(Ref { part: target, id: oid, xf, line });
                ld.stored.refs += 1;
                ld.check_stored(&cx)?;
            }
            _ => {}
        }
    }
    if let Some(o) = current.take() {
        finish_object(&mut part, o);
    }
    if !saw_model {
        return Err(malformed(file, name, "the part has no <model> element", REEXPORT));
    }
    // Index objects by id; a repeated id is an error at its second definition.
    part.by_id = part.objects.iter().enumerate().map(|(i, o)| (o.id, i as u32)).collect();
    part.by_id.sort_unstable();
    let twice = part.by_id.windows(2).filter(|w| w.first().map(|a| a.0) == w.get(1).map(|b| b.0)).filter_map(|w| w.get(1)).min_by_key(|&&(_, i)| i);
    if let Some(&(oid, i)) = twice {
        let line = part.objects.get(i as usize).map_or(0, |o| o.line);
        return Err(malformed(file, format!("{name} line {line}"), format!("object id {oid} is defined twice"), REEXPORT));
    }
    Ok(part)
}

fn finish_object(part: &mut Part, o: Object) {
    part.objects.push(o);
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use std::io::Write;

    pub(crate) fn zip_of(entries: &[(&str, &str)], deflate: bool) -> Vec<u8> {
        let mut w = zip::ZipWriter::new(Cursor::new(Vec::new()));
        let method = if deflate { zip::CompressionMethod::Deflated } else { zip::CompressionMethod::Stored };
        let opts = zip::write::SimpleFileOptions::default().compression_method(method);
        for (name, body) in entries {
            w.start_file(*name, opts).unwrap();
            w.write_all(body.as_bytes()).unwrap();
        }
        w.finish().unwrap().into_inner()
    }

    const RELS: &str = r#"<?xml version="1.0" encoding="UTF-8"?>
<Relationships xmlns="http://schemas.openxmlformats.org/package/2006/relationships">
<Relationship Target="/3D/model.model" Id="rel0" Type="http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel"/>
</Relationships>"#;

    fn model(unit: &str, resources: &str, build: &str) -> String {
        format!(
            r#"<?xml version="1.0" encoding="UTF-8"?>
<model unit="{unit}" xml:lang="en-US" xmlns="http://schemas.microsoft.com/3dmanufacturing/core/2015/02">
<resources>
{resources}
</resources>
{build}
</model>"#
        )
    }

    const TRI: &str = r#"<object id="1" type="model"><mesh><vertices>
<vertex x="0" y="0" z="0"/><vertex x="1" y="0" z="0"/><vertex x="0" y="1" z="0"/>
</vertices><triangles><triangle v1="0" v2="1" v3="2"/></triangles></mesh></object>"#;

    fn read(entries: &[(&str, &str)]) -> Result<(RawMesh, f64), Error> {
        read_3mf("t.3mf", &zip_of(entries, true))
    }

    #[test]
    fn units_rels_and_transforms() {
        let m = model("inch", TRI, r#"<build><item objectid="1" transform="1 0 0 0 1 0 0 0 1 10 0 0"/></build>"#);
        let (raw, scale) = read(&[("_rels/.rels", RELS), ("3D/model.model", &m)]).unwrap();
        assert_eq!(scale, 25.4);
        assert_eq!(raw.vertices[0], [254.0, 0.0, 0.0]);
        assert_eq!(raw.vertices[1], [279.4, 0.0, 0.0]);
    }

    #[test]
    fn components_compose_and_unreferenced_objects_are_ignored() {
        let res = format!(
            r#"{TRI}
<object id="2"><components><component objectid="1" transform="0 1 0 -1 0 0 0 0 1 0 0 5"/></components></object>
<object id="3"><components><component objectid="2" transform="1 0 0 0 1 0 0 0 1 100 0 0"/></components></object>"#
        );
        let m = model("millimeter", &res, r#"<build><item objectid="3"/></build>"#);
        let (raw, _) = read(&[("3D/3dmodel.model", &m)]).unwrap();
        assert_eq!(raw.triangles.len(), 1);
        // (1,0,0) rotated 90° about Z → (0,1,0), lifted 5, then moved 100 in X.
        assert_eq!(raw.vertices[1], [100.0, 1.0, 5.0]);
        // No build: object 3 is the only one not used as a component.
        let m = model("millimeter", &res, "");
        let (raw, _) = read(&[("3D/3dmodel.model", &m)]).unwrap();
        assert_eq!(raw.triangles.len(), 1);
    }

    #[test]
    fn cycles_and_depth_are_refused() {
        let res = r#"<object id="1"><components><component objectid="2"/></components></object>
<object id="2"><components><component objectid="1"/></components></object>"#;
        let m = model("millimeter", res, r#"<build><item objectid="1"/></build>"#);
        let e = read(&[("3D/3dmodel.model", &m)]).unwrap_err().to_string();
        assert!(e.contains("contains itself") && e.contains("3D/3dmodel.model line"), "{e}");

        let mut res = String::from(TRI);
        for i in 2..40 {
            res.push_str(&format!(r#"<object id="{i}"><components><component objectid="{}"/></components></object>"#, i - 1));
        }
        let m = model("millimeter", &res, r#"<build><item objectid="39"/></build>"#);
        let e = read(&[("3D/3dmodel.model", &m)]).unwrap_err().to_string();
        assert!(e.contains("deeper than 32"), "{e}");

        // Exponential fan-out: 10 copies per level, 10 levels.
        let mut res = String::from(r#"<object id="1"><components></components></object>"#);
        for i in 2..12 {
            res.push_str(&format!(r#"<object id="{i}"><components>"#));
            for _ in 0..10 {
                res.push_str(&format!(r#"<component objectid="{}"/>"#, i - 1));
            }
            res.push_str("</components></object>");
        }
        let m = model("millimeter", &res, r#"<build><item objectid="11"/></build>"#);
        let e = read(&[("3D/3dmodel.model", &m)]).unwrap_err().to_string();
        assert!(e.contains("object instances"), "{e}");
    }

    #[test]
    fn errors_name_part_and_line() {
        let bad = TRI.replace(r#"v3="2""#, r#"v3="7""#);
        let m = model("millimeter", &bad, "");
        let e = read(&[("3D/3dmodel.model", &m)]).unwrap_err().to_string();
        assert!(e.contains("3D/3dmodel.model line 6") && e.contains("v3=\"7\"") && e.contains("3 vertices"), "{e}");

        let bad = TRI.replace(r#"y="1""#, r#"y="nan""#);
        let e = read(&[("3D/3dmodel.model", &model("millimeter", &bad, ""))]).unwrap_err().to_string();
        assert!(e.contains("line 5") && e.contains("finite"), "{e}");

        let e = read(&[("3D/3dmodel.model", &model("parsec", TRI, ""))]).unwrap_err().to_string();
        assert!(e.contains("line 2") && e.contains("parsec"), "{e}");

        let e = read(&[("3D/3dmodel.model", "<model><resources><object id=\"1\"></resources></model>")]).unwrap_err().to_string();
        assert!(e.contains("3D/3dmodel.model line 1") && e.contains("malformed"), "{e}");

        let e = read(&[("other.txt", "x")]).unwrap_err().to_string();
        assert!(e.contains("no 3D model part"), "{e}");

        let e = read(&[("3D/3dmodel.model", &model("millimeter", TRI, r#"<build><item objectid="5"/></build>"#))]).unwrap_err().to_string();
        assert!(e.contains("object 5") && e.contains("line"), "{e}");

        let e = read_3mf("t.3mf", b"PK\x03\x04 not really a zip").unwrap_err().to_string();
        assert_eq!(e, format!("t.3mf: the archive: a 3MF is an archive of parts and this one cannot be opened: it was cut short or damaged; {REEXPORT}"));

        let twice = format!("{TRI}\n{}", TRI.replace("\n", " "));
        let e = read(&[("3D/3dmodel.model", &model("millimeter", &twice, ""))]).unwrap_err().to_string();
        assert!(e.contains("line 7") && e.contains("object id 1 is defined twice"), "{e}");
    }

    #[test]
    fn production_extension_paths() {
        let sub = model("millimeter", TRI, "");
        let root = model(
            "millimeter",
            r#"<object id="9"><components><component p:path="/3D/Objects/obj_1.model" objectid="1" transform="1 0 0 0 1 0 0 0 1 0 0 2"/></components></object>"#,
            r#"<build><item objectid="9"/></build>"#,
        );
        let (raw, _) = read(&[("3D/3dmodel.model", &root), ("3D/Objects/obj_1.model", &sub)]).unwrap();
        assert_eq!(raw.vertices[2], [0.0, 1.0, 2.0]);
        // Part names are matched case-insensitively when the exact name is missing.
        let (raw, _) = read(&[("3D/3dmodel.model", &root), ("3d/objects/OBJ_1.model", &sub)]).unwrap();
        assert_eq!(raw.vertices[2], [0.0, 1.0, 2.0]);
    }

    #[test]
    fn zip_bomb_is_refused() {
        // A model part whose directory entry declares 600 MiB: refused before inflating.
        let m = model("millimeter", TRI, "");
        let mut bytes = zip_of(&[("3D/3dmodel.model", &m)], true);
        let cd = bytes.windows(4).position(|w| w == b"PK\x01\x02").unwrap();
        bytes[cd + 24..cd + 28].copy_from_slice(&(600u32 << 20).to_le_bytes());
        bytes[22..26].copy_from_slice(&(600u32 << 20).to_le_bytes());
        let e = read_3mf("bomb.3mf", &bytes).unwrap_err().to_string();
        assert!(e.contains("512 MiB") && e.contains("zip bomb"), "{e}");
    }

    #[test]
    fn lines_are_counted_across_pieces() {
        // Many lines before the damage: the line must be exact though the XML arrives in pieces.
        let mut res = String::from(TRI);
        for i in 2..3000 {
            res.push_str(&format!("\n<object id=\"{i}\" type=\"model\">\n<mesh/>\n</object>"));
        }
        res.push_str("\n<object id=\"x\"/>");
        let m = model("millimeter", &res, "");
        let want = m.lines().position(|l| l.contains("id=\"x\"")).unwrap() + 1;
        for deflate in [false, true] {
            let e = read_3mf("t.3mf", &zip_of(&[("3D/3dmodel.model", &m)], deflate)).unwrap_err().to_string();
            assert!(e.contains(&format!("line {want}:")) && e.contains("id=\"x\""), "{want}: {e}");
        }
    }

    #[test]
    fn not_utf8_names_the_line() {
        let m = model("millimeter", TRI, "").replace("type=\"model\"", "type=\"mod\u{FFFD}el\"");
        let mut bytes = m.into_bytes();
        let at = bytes.windows(3).position(|w| w == "\u{FFFD}".as_bytes()).unwrap();
        bytes.splice(at..at + 3, [0xFFu8]);
        let e = read_3mf("t.3mf", &zip_of_bytes(&[("3D/3dmodel.model", &bytes)])).unwrap_err().to_string();
        assert!(e.contains("3D/3dmodel.model line 4") && e.contains("is not text: the model was saved in an encoding other than the UTF-8"), "{e}");
    }

    fn zip_of_bytes(entries: &[(&str, &[u8])]) -> Vec<u8> {
        let mut w = zip::ZipWriter::new(Cursor::new(Vec::new()));
        let opts = zip::write::SimpleFileOptions::default();
        for (name, body) in entries {
            w.start_file(*name, opts).unwrap();
            w.write_all(body).unwrap();
        }
        w.finish().unwrap().into_inner()
    }

    #[test]
    fn counting_matches_reading() {
        let res = format!(
            r#"{TRI}
<object id="2"><components><component objectid="1"/><component objectid="1" transform="1 0 0 0 1 0 0 0 1 0 0 5"/></components></object>"#
        );
        let m = model("millimeter", &res, r#"<build><item objectid="2"/><item objectid="1"/></build>"#);
        let bytes = zip_of(&[("3D/3dmodel.model", &m)], true);
        let c = count_3mf("t.3mf", &bytes).unwrap();
        let (raw, _) = read_3mf("t.3mf", &bytes).unwrap();
        assert_eq!((c.vertices, c.triangles), (raw.vertices.len() as u64, raw.triangles.len() as u64));
        assert_eq!(c.triangles, 3);
    }
}

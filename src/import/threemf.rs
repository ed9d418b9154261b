//! 3MF: a zip container holding XML model parts.
//!
//! The model part is found through `_rels/.rels` (falling back to `3D/3dmodel.model`).
//! Read: `<model unit>`, `<object id><mesh><vertices><vertex x y z/>…<triangles><triangle
//! v1 v2 v3/>`, `<components><component objectid transform p:path/>` (recursively, the
//! production extension's `p:path` parts included) and `<build><item objectid transform/>`.
//! Transforms are 3MF's 3×4 row-vector matrices `m00 m01 m02 m10 m11 m12 m20 m21 m22 m30 m31
//! m32`: `x' = x·m00 + y·m10 + z·m20 + m30`, and so on. Everything else (materials, colours,
//! metadata, thumbnails, slicer settings) is ignored.

use super::{malformed, Error, RawMesh};
use quick_xml::events::{BytesStart, Event};
use quick_xml::Reader;
use std::collections::BTreeMap;
use std::io::{Cursor, Read};

/// Largest uncompressed model part (and total of all model parts) weft inflates: 512 MiB.
/// Bigger parts are refused as a likely zip bomb.
pub const MAX_MODEL_PART_BYTES: u64 = 512 * 1024 * 1024;

/// Most triangles a 3MF build may expand to once every item and component is placed.
pub const MAX_TRIANGLES: usize = 20_000_000;

/// Most component instances expanded (guards against exponential component graphs).
const MAX_INSTANCES: usize = 1_000_000;
/// Deepest component nesting.
const MAX_DEPTH: usize = 32;
/// Most model parts read through `p:path`.
const MAX_PARTS: usize = 4096;
const DEFAULT_MODEL: &str = "3D/3dmodel.model";
const REEXPORT: &str = "the 3MF file is damaged; export it again";

type Affine = [f64; 12];
const IDENTITY: Affine = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0];

#[inline]
fn apply(m: &Affine, p: [f64; 3]) -> [f64; 3] {
    [
        p[0] * m[0] + p[1] * m[3] + p[2] * m[6] + m[9],
        p[0] * m[1] + p[1] * m[4] + p[2] * m[7] + m[10],
        p[0] * m[2] + p[1] * m[5] + p[2] * m[8] + m[11],
    ]
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

/// A reference to an object (build item or component).
#[derive(Debug)]
struct Ref {
    part: String,
    id: u32,
    transform: Affine,
    line: usize,
}

#[derive(Debug, Default)]
struct Object {
    id: u32,
    line: usize,
    other: bool,
    vertices: Vec<[f64; 3]>,
    triangles: Vec<[u32; 3]>,
    components: Vec<Ref>,
}

#[derive(Debug, Default)]
struct Part {
    unit: Option<String>,
    unit_line: usize,
    objects: Vec<Object>,
    by_id: BTreeMap<u32, usize>,
    build: Option<Vec<Ref>>,
}

/// Reads a 3MF; returns the raw mesh in mm and the unit scale applied.
pub(super) fn read_3mf(file: &str, bytes: &[u8]) -> Result<(RawMesh, f64), Error> {
    let mut zip = zip::ZipArchive::new(Cursor::new(bytes)).map_err(|e| {
        malformed(file, "zip container", format!("the 3MF container cannot be opened ({e})"), REEXPORT)
    })?;
    let mut budget = MAX_MODEL_PART_BYTES;
    let root = root_model_path(file, &mut zip, &mut budget)?;
    let mut parts: BTreeMap<String, Part> = BTreeMap::new();
    let mut pending = vec![root.clone()];
    while let Some(name) = pending.pop() {
        if parts.contains_key(&name) {
            continue;
        }
        if parts.len() >= MAX_PARTS {
            return Err(malformed(file, name, format!("more than {MAX_PARTS} model parts are referenced"), REEXPORT));
        }
        let Some(data) = read_entry(file, &mut zip, &name, &mut budget)? else {
            let problem = if name == root {
                "the 3MF has no 3D model part".to_string()
            } else {
                "a component refers to this model part, which is not in the file".to_string()
            };
            return Err(malformed(file, name, problem, REEXPORT));
        };
        let part = parse_part(file, &name, &data)?;
        for o in &part.objects {
            pending.extend(o.components.iter().map(|c| c.part.clone()));
        }
        pending.extend(part.build.iter().flatten().map(|i| i.part.clone()));
        parts.insert(name, part);
    }
    let Some(root_part) = parts.get(&root) else {
        return Err(malformed(file, root, "the 3MF has no 3D model part", REEXPORT));
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
                format!("{root} line {}", root_part.unit_line),
                format!("unknown unit \"{}\"", super::show(other.as_bytes())),
                "use micron, millimeter, centimeter, inch, foot or meter",
            ))
        }
    };
    let items: Vec<Ref> = match &root_part.build {
        Some(items) if !items.is_empty() => items.iter().map(|r| Ref { part: r.part.clone(), ..*r }).collect(),
        // No build: every object that is not a component of another one, in file order.
        _ => {
            let used: std::collections::BTreeSet<u32> = root_part
                .objects
                .iter()
                .flat_map(|o| o.components.iter().filter(|c| c.part == root).map(|c| c.id))
                .collect();
            root_part
                .objects
                .iter()
                .filter(|o| !used.contains(&o.id))
                .map(|o| Ref { part: root.clone(), id: o.id, transform: IDENTITY, line: o.line })
                .collect()
        }
    };
    let mut ex = Expander { file, parts: &parts, scale, out: RawMesh::default(), instances: 0, stack: Vec::new() };
    for item in &items {
        ex.emit(item, &IDENTITY, &root, 0)?;
    }
    Ok((ex.out, scale))
}

struct Expander<'a> {
    file: &'a str,
    parts: &'a BTreeMap<String, Part>,
    scale: f64,
    out: RawMesh,
    instances: usize,
    stack: Vec<(&'a str, u32)>,
}

impl<'a> Expander<'a> {
    /// Places object `r` (referenced from `from` at `r.line`) with `r.transform` then `parent`.
    fn emit(&mut self, r: &Ref, parent: &Affine, from: &str, depth: usize) -> Result<(), Error> {
        let file = self.file;
        let place = || format!("{from} line {}", r.line);
        self.instances += 1;
        if self.instances > MAX_INSTANCES {
            return Err(malformed(file, place(), format!("the build expands to more than {MAX_INSTANCES} object instances"), "simplify the assembly"));
        }
        if depth > MAX_DEPTH {
            return Err(malformed(file, place(), format!("components nest deeper than {MAX_DEPTH} levels"), "flatten the assembly and export again"));
        }
        let parts = self.parts;
        let Some((part_name, part)) = parts.get_key_value(&r.part) else {
            return Err(malformed(file, place(), format!("refers to model part {}, which is not in the file", r.part), REEXPORT));
        };
        let Some(obj) = part.by_id.get(&r.id).and_then(|&i| part.objects.get(i)) else {
            return Err(malformed(file, place(), format!("refers to object {}, which is not defined in {}", r.id, r.part), REEXPORT));
        };
        if self.stack.iter().any(|&(p, id)| p == part_name.as_str() && id == r.id) {
            return Err(malformed(file, place(), format!("object {} contains itself through its components", r.id), "remove the circular component reference"));
        }
        if obj.other {
            return Ok(());
        }
        let xf = compose(&r.transform, parent);
        if !obj.triangles.is_empty() {
            let too_many = self.out.triangles.len().saturating_add(obj.triangles.len()) > MAX_TRIANGLES
                || self.out.vertices.len().saturating_add(obj.vertices.len()) > 3 * MAX_TRIANGLES;
            if too_many {
                return Err(malformed(file, place(), format!("the build expands to more than {MAX_TRIANGLES} triangles"), "reduce the number of copies or simplify the mesh"));
            }
            let base = self.out.vertices.len() as u32;
            for v in &obj.vertices {
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
                self.out.vertices.push(q);
            }
            self.out.triangles.extend(obj.triangles.iter().map(|t| [t[0] + base, t[1] + base, t[2] + base]));
        }
        if !obj.components.is_empty() {
            self.stack.push((part_name.as_str(), r.id));
            for c in &obj.components {
                self.emit(c, &xf, part_name, depth + 1)?;
            }
            self.stack.pop();
        }
        Ok(())
    }
}

/// Finds the model part through `_rels/.rels`, else the default path.
fn root_model_path(file: &str, zip: &mut zip::ZipArchive<Cursor<&[u8]>>, budget: &mut u64) -> Result<String, Error> {
    let rels_name = "_rels/.rels";
    let Some(rels) = read_entry(file, zip, rels_name, budget)? else {
        return Ok(DEFAULT_MODEL.to_string());
    };
    let text = decode(file, rels_name, &rels)?;
    let mut reader = Reader::from_str(text);
    loop {
        let ev = reader.read_event().map_err(|e| xml_error(file, rels_name, text, reader.error_position(), &e))?;
        match ev {
            Event::Start(e) | Event::Empty(e) if local(e.name().as_ref()) == "Relationship" => {
                let line = line_at(text, reader.buffer_position());
                let (mut target, mut kind) = (None, None);
                for (k, v) in attrs(file, rels_name, line, &e)? {
                    match k.as_str() {
                        "Target" => target = Some(v),
                        "Type" => kind = Some(v),
                        _ => {}
                    }
                }
                if let (Some(t), Some(k)) = (target, kind) {
                    if k.trim_end_matches('/').ends_with("/3dmodel") {
                        return Ok(normalize_path(&t));
                    }
                }
            }
            Event::Eof => return Ok(DEFAULT_MODEL.to_string()),
            _ => {}
        }
    }
}

fn normalize_path(p: &str) -> String {
    p.trim().trim_start_matches('/').to_string()
}

/// Reads a zip entry (exact name, else case-insensitive) within the inflation budget.
fn read_entry(
    file: &str,
    zip: &mut zip::ZipArchive<Cursor<&[u8]>>,
    name: &str,
    budget: &mut u64,
) -> Result<Option<Vec<u8>>, Error> {
    let index = match zip.index_for_name(name) {
        Some(i) => i,
        None => {
            let found = zip.file_names().position(|n| n.is_ok_and(|n| n.eq_ignore_ascii_case(name)));
            match found {
                Some(i) => i,
                None => return Ok(None),
            }
        }
    };
    let mut entry = zip
        .by_index(index)
        .map_err(|e| malformed(file, name, format!("the part cannot be read ({e})"), REEXPORT))?;
    let bomb = |file: &str| {
        malformed(
            file,
            name,
            format!("the part inflates to more than {} MiB", MAX_MODEL_PART_BYTES / (1024 * 1024)),
            "this is too large to be a real model (possibly a zip bomb); simplify the mesh or split it",
        )
    };
    let limit = *budget;
    if entry.size() > limit {
        return Err(bomb(file));
    }
    let mut data = Vec::with_capacity(entry.size().min(64 << 20) as usize);
    (&mut entry)
        .take(limit.saturating_add(1))
        .read_to_end(&mut data)
        .map_err(|e| malformed(file, name, format!("the part cannot be decompressed ({e})"), REEXPORT))?;
    if data.len() as u64 > limit {
        return Err(bomb(file));
    }
    *budget = limit - data.len() as u64;
    Ok(Some(data))
}

fn decode<'b>(file: &str, part: &str, data: &'b [u8]) -> Result<&'b str, Error> {
    let data = data.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(data);
    std::str::from_utf8(data).map_err(|e| {
        let at = e.valid_up_to();
        let line = data.get(..at).unwrap_or_default().iter().filter(|&&b| b == b'\n').count() + 1;
        malformed(file, format!("{part} line {line}"), format!("the XML is not UTF-8 (byte {at})"), "save the model as UTF-8 and export again")
    })
}

fn line_at(text: &str, offset: u64) -> usize {
    let end = (offset as usize).min(text.len());
    text.as_bytes().get(..end).unwrap_or_default().iter().filter(|&&b| b == b'\n').count() + 1
}

fn xml_error(file: &str, part: &str, text: &str, offset: u64, e: &quick_xml::Error) -> Error {
    malformed(file, format!("{part} line {} (byte {offset})", line_at(text, offset)), format!("the XML is malformed ({e})"), REEXPORT)
}

/// The name after any namespace prefix.
fn local(name: &str) -> &str {
    name.rsplit(':').next().unwrap_or(name)
}

/// Attributes as (local name, raw value) pairs; namespace declarations skipped.
fn attrs(file: &str, part: &str, line: usize, e: &BytesStart<'_>) -> Result<Vec<(String, String)>, Error> {
    let mut out = Vec::new();
    for a in e.attributes().with_checks(false) {
        let a = a.map_err(|err| malformed(file, format!("{part} line {line}"), format!("bad attribute ({err})"), REEXPORT))?;
        let key = a.key.as_ref();
        if key == "xmlns" || key.starts_with("xmlns:") {
            continue;
        }
        let value = quick_xml::escape::unescape(&a.value).map(|v| v.into_owned()).unwrap_or_else(|_| a.value.to_string());
        out.push((local(key).to_string(), value));
    }
    Ok(out)
}

struct Ctx<'a> {
    file: &'a str,
    part: &'a str,
    line: usize,
}

impl Ctx<'_> {
    fn err(&self, problem: String) -> Error {
        malformed(self.file, format!("{} line {}", self.part, self.line), problem, REEXPORT)
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
        v.trim()
            .parse::<u32>()
            .map_err(|_| self.err(format!("<{el}> {name}=\"{}\" is not a valid index", super::show(v.as_bytes()))))
    }
    fn transform(&self, el: &str, v: Option<&str>) -> Result<Affine, Error> {
        let Some(v) = v else { return Ok(IDENTITY) };
        let mut m = [0.0; 12];
        let mut n = 0;
        for t in v.split_ascii_whitespace() {
            let x = t.parse::<f64>().ok().filter(|x| x.is_finite());
            match (x, m.get_mut(n)) {
                (Some(x), Some(slot)) => *slot = x,
                _ => {
                    return Err(self.err(format!(
                        "<{el}> transform must be 12 finite numbers, found \"{}\"",
                        super::show(v.as_bytes())
                    )))
                }
            }
            n += 1;
        }
        if n != 12 {
            return Err(self.err(format!("<{el}> transform has {n} numbers, needs 12")));
        }
        Ok(m)
    }
}

fn get<'v>(attrs: &'v [(String, String)], key: &str) -> Option<&'v str> {
    attrs.iter().find(|(k, _)| k == key).map(|(_, v)| v.as_str())
}

/// Parses one model part.
fn parse_part(file: &str, name: &str, data: &[u8]) -> Result<Part, Error> {
    let text = decode(file, name, data)?;
    let mut reader = Reader::from_str(text);
    let mut part = Part::default();
    let mut current: Option<Object> = None;
    let mut in_build = false;
    let mut saw_model = false;
    loop {
        let ev = reader.read_event().map_err(|e| xml_error(file, name, text, reader.error_position(), &e))?;
        let (e, empty) = match ev {
            Event::Start(e) => (e, false),
            Event::Empty(e) => (e, true),
            Event::End(e) => {
                match local(e.name().as_ref()) {
                    "object" => {
                        if let Some(o) = current.take() {
                            finish_object(file, name, &mut part, o)?;
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
        let line = line_at(text, reader.buffer_position());
        let cx = Ctx { file, part: name, line };
        let tag = e.name();
        let tag = local(tag.as_ref());
        match tag {
            "model" => {
                saw_model = true;
                let a = attrs(file, name, line, &e)?;
                part.unit = get(&a, "unit").map(|u| u.trim().to_ascii_lowercase());
                part.unit_line = line;
            }
            "object" => {
                if let Some(o) = current.take() {
                    finish_object(file, name, &mut part, o)?;
                }
                let a = attrs(file, name, line, &e)?;
                let id = cx.id("object", "id", get(&a, "id"))?;
                let other = get(&a, "type").is_some_and(|t| t.trim() == "other");
                let o = Object { id, line, other, ..Object::default() };
                if empty {
                    finish_object(file, name, &mut part, o)?;
                } else {
                    current = Some(o);
                }
            }
            "vertex" => {
                if let Some(o) = current.as_mut() {
                    let a = attrs(file, name, line, &e)?;
                    let p = [
                        cx.float("vertex", "x", get(&a, "x"))?,
                        cx.float("vertex", "y", get(&a, "y"))?,
                        cx.float("vertex", "z", get(&a, "z"))?,
                    ];
                    if o.vertices.len() >= u32::MAX as usize / 2 {
                        return Err(cx.err("too many vertices".into()));
                    }
                    o.vertices.push(p);
                }
            }
            "triangle" => {
                if let Some(o) = current.as_mut() {
                    let a = attrs(file, name, line, &e)?;
                    let mut t = [0u32; 3];
                    for (k, key) in ["v1", "v2", "v3"].iter().enumerate() {
                        let v = cx.id("triangle", key, get(&a, key))?;
                        if v as usize >= o.vertices.len() {
                            return Err(cx.err(format!(
                                "<triangle> {key}=\"{v}\" but object {} has {} vertices (indices start at 0)",
                                o.id,
                                o.vertices.len()
                            )));
                        }
                        if let Some(slot) = t.get_mut(k) {
                            *slot = v;
                        }
                    }
                    o.triangles.push(t);
                }
            }
            "component" => {
                if let Some(o) = current.as_mut() {
                    let a = attrs(file, name, line, &e)?;
                    let id = cx.id("component", "objectid", get(&a, "objectid"))?;
                    let transform = cx.transform("component", get(&a, "transform"))?;
                    let target = get(&a, "path").map(normalize_path).unwrap_or_else(|| name.to_string());
                    o.components.push(Ref { part: target, id, transform, line });
                }
            }
            "build" => {
                part.build.get_or_insert_with(Vec::new);
                in_build = !empty;
            }
            "item" if in_build => {
                let a = attrs(file, name, line, &e)?;
                let id = cx.id("item", "objectid", get(&a, "objectid"))?;
                let transform = cx.transform("item", get(&a, "transform"))?;
                let target = get(&a, "path").map(normalize_path).unwrap_or_else(|| name.to_string());
                part.build.get_or_insert_with(Vec::new).push(Ref { part: target, id, transform, line });
            }
            _ => {}
        }
    }
    if let Some(o) = current.take() {
        finish_object(file, name, &mut part, o)?;
    }
    if !saw_model {
        return Err(malformed(file, name, "the part has no <model> element", REEXPORT));
    }
    Ok(part)
}

fn finish_object(file: &str, part_name: &str, part: &mut Part, o: Object) -> Result<(), Error> {
    if part.by_id.contains_key(&o.id) {
        return Err(malformed(file, format!("{part_name} line {}", o.line), format!("object id {} is defined twice", o.id), REEXPORT));
    }
    part.by_id.insert(o.id, part.objects.len());
    part.objects.push(o);
    Ok(())
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
        assert!(e.contains("zip container"), "{e}");
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
}

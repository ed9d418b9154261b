//! Reading a wireframe design: joints (points, mm) joined by straight beams, and the joints
//! that stand on the substrate (grounded).
//!
//! Formats, told apart by the file's name and, for JSON, its keys:
//! - `assembly_instances` JSON (`node_list` of `{point: {X, Y, Z}, node_id, is_grounded}`,
//!   `element_list` of `{end_node_ids: [i, j]}`, `unit`, millimetres by default);
//! - `conmech` JSON (`nodes` of `{point: [x, y, z], node_ind, is_grounded}`, `elements` of
//!   `{end_node_inds: [i, j]}`, `supports` of `{node_ind}`, `unit`, metres by default);
//! - OBJ: `v x y z` and `l a b …` (a polyline of several joints is several beams; negative
//!   indices count back from the last `v`), millimetres; an OBJ without `l` lines whose faces
//!   (`f`) are the design (a wireframe exported as a triangle mesh) gives each face's unique
//!   edges as beams, said in [`Wireframe::notes`];
//! - STL (binary or text, read by [`crate::import`]): each triangle's unique edges as beams,
//!   millimetres, said the same way;
//! - CSV: one beam per line, `x1, y1, z1, x2, y2, z2` (mm; commas, semicolons or spaces; a
//!   first line that is not numbers is a header), joints merged within a tolerance.
//!
//! Grounded joints come from the file (`is_grounded`, conmech's `supports`) or, when it marks
//! none or the user asks, are every joint within a tolerance of the lowest one. What was
//! grounded is stated ([`grounding`]), with a warning and the tolerance that grounds the base
//! when the lowest joints alone are an implausible footing (one point, or a small part of the
//! design's footprint).
//!
//! Checked, every problem listed with its place: coordinates that are not finite, beams that
//! name a joint the file lacks, zero-length beams, beams given twice, no grounded joint, and
//! beams not connected to any grounded joint (a part that could not be reached from the
//! substrate). Size is bounded before parsing ([`MAX_BYTES`], and [`MAX_BEAMS`] by a count
//! of the beams the text states) and after ([`MAX_BEAMS`]).

use crate::geom::DVec3;
use serde::{Deserialize, Serialize};
use serde_json::Value;
use std::collections::BTreeMap;

/// Default tolerance of "on the lowest level" when grounding the lowest joints, mm.
pub const DEFAULT_GROUND_TOLERANCE_MM: f64 = 0.01;
/// Default distance within which a CSV's beam ends are one joint, mm.
pub const DEFAULT_MERGE_TOLERANCE_MM: f64 = 1e-3;
/// Largest file read, bytes (a 50k-beam design in the most verbose schema is about 12 MB).
pub const MAX_BYTES: usize = 64 << 20;
/// Most beams a design may have (the largest target is 50k).
pub const MAX_BEAMS: usize = 200_000;
/// Most problems listed one by one (the count of the rest is given).
pub const MAX_LISTED: usize = 12;

/// Where the grounded joints come from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Ground {
    /// The file's own (`is_grounded`, `supports`); the lowest joints when it marks none.
    #[default]
    File,
    /// Every joint within the tolerance of the lowest joint's z.
    Lowest,
}

/// How a wireframe is read.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Options {
    /// Where the grounded joints come from; default [`Ground::File`].
    pub ground: Ground,
    /// "On the lowest level" within this, mm; default [`DEFAULT_GROUND_TOLERANCE_MM`].
    pub ground_tolerance_mm: f64,
    /// CSV beam ends closer than this are one joint, mm; default [`DEFAULT_MERGE_TOLERANCE_MM`].
    pub merge_tolerance_mm: f64,
}

impl Default for Options {
    fn default() -> Self {
        Options { ground: Ground::File, ground_tolerance_mm: DEFAULT_GROUND_TOLERANCE_MM, merge_tolerance_mm: DEFAULT_MERGE_TOLERANCE_MM }
    }
}

/// The file formats read.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Format {
    /// `assembly_instances` JSON.
    AssemblyInstances,
    /// `conmech` JSON.
    Conmech,
    /// OBJ line elements.
    Obj,
    /// A CSV of beams.
    Csv,
    /// A triangle mesh (STL) whose edges are the beams.
    Mesh,
    /// A built-in design ([`super::models`]).
    Model,
}

/// A wireframe design in mm.
#[derive(Clone, Debug, PartialEq)]
pub struct Wireframe {
    /// Joint positions, mm.
    pub joints: Vec<DVec3>,
    /// Beams as pairs of joint indices, in the file's order.
    pub beams: Vec<[usize; 2]>,
    /// Per joint: on the substrate.
    pub grounded: Vec<bool>,
    /// The grounded joints were the file's (false: the lowest ones).
    pub grounded_by_file: bool,
    /// The format read.
    pub format: Format,
    /// How the file names each joint (`node 7`, `vertex 3 (line 5)`), for messages.
    pub joint_names: Vec<String>,
    /// How the file names each beam (`element 12`, `line 40`), for messages.
    pub beam_names: Vec<String>,
    /// What reading assumed, one sentence each (a triangle mesh's edges read as beams).
    pub notes: Vec<String>,
    /// What was grounded, once the design is placed ([`grounding`]); refusals cite it.
    pub grounding: Option<Grounding>,
}

/// Why a design could not be read.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum Error {
    /// Over [`MAX_BYTES`].
    #[error("{file}: {bytes} bytes is more than the {MAX_BYTES}-byte limit of a wireframe design; split the design")]
    TooBig {
        /// File name.
        file: String,
        /// Its size.
        bytes: usize,
    },
    /// Over [`MAX_BEAMS`].
    #[error("{file}: {beams} beams is more than {MAX_BEAMS}; plan the design in parts")]
    TooManyBeams {
        /// File name.
        file: String,
        /// Beams in it.
        beams: usize,
    },
    /// The file is not one of the formats, or a value in it is unusable.
    #[error("{file}, {place}: {message}")]
    NotRead {
        /// File name.
        file: String,
        /// Where (line, or the JSON path).
        place: String,
        /// What is wrong and how to fix it.
        message: String,
    },
    /// The design was read but cannot be planned: every problem.
    #[error("{file}: {}", problems.join("; "))]
    Invalid {
        /// File name.
        file: String,
        /// Each problem with its place.
        problems: Vec<String>,
    },
}

/// Reads the design `bytes` of the file `name`.
pub fn read(name: &str, bytes: &[u8], options: &Options) -> Result<Wireframe, Error> {
    if bytes.len() > MAX_BYTES {
        return Err(Error::TooBig { file: name.into(), bytes: bytes.len() });
    }
    let not_read = |place: &str, message: String| Error::NotRead { file: name.into(), place: place.into(), message };
    if name.to_ascii_lowercase().ends_with(".stl") {
        let raw = stl(name, bytes)?;
        return finish(name, raw, options);
    }
    let text = std::str::from_utf8(bytes)
        .map_err(|e| not_read(&format!("byte {}", e.valid_up_to()), "the file is not text (UTF-8); export the design as JSON, OBJ or CSV".into()))?;
    let lower = name.to_ascii_lowercase();
    // A cheap count first, so a design far over the limit is refused before it is parsed.
    let counted = beams_counted(text, &lower);
    if counted > MAX_BEAMS + 1 {
        return Err(Error::TooManyBeams { file: name.into(), beams: counted });
    }
    let raw = if lower.ends_with(".obj") {
        obj(text).map_err(|(line, m)| not_read(&format!("line {line}"), m))?
    } else if lower.ends_with(".csv") || lower.ends_with(".txt") {
        csv(text, options.merge_tolerance_mm).map_err(|(line, m)| not_read(&format!("line {line}"), m))?
    } else {
        json(text).map_err(|(place, m)| not_read(&place, m))?
    };
    if raw.beams.len() > MAX_BEAMS {
        return Err(Error::TooManyBeams { file: name.into(), beams: raw.beams.len() });
    }
    finish(name, raw, options)
}

/// A design as read, before grounding and checks; places name beams and joints in words.
struct Raw {
    joints: Vec<DVec3>,
    joint_place: Vec<String>,
    beams: Vec<[usize; 2]>,
    beam_place: Vec<String>,
    /// Grounded joints named by the file (None: the format has no such mark).
    grounded: Option<Vec<bool>>,
    format: Format,
    /// Beams naming a joint the file lacks (place, the missing name).
    dangling: Vec<(String, String)>,
    /// What reading assumed.
    notes: Vec<String>,
}

impl Raw {
    fn new(format: Format) -> Raw {
        Raw {
            joints: Vec::new(),
            joint_place: Vec::new(),
            beams: Vec::new(),
            beam_place: Vec::new(),
            grounded: None,
            format,
            dangling: Vec::new(),
            notes: Vec::new(),
        }
    }
}

/// Each face's edges, once each, as beams (in the order first met): `faces` are polygons of
/// joint indices, `place(f)` names face `f`. Returns the notes' sentence.
fn edges_as_beams(raw: &mut Raw, faces: &[(Vec<usize>, String)], what: &str) -> String {
    let mut edges: Vec<((usize, usize), usize, usize)> = Vec::new();
    for (f, (corners, _)) in faces.iter().enumerate() {
        for k in 0..corners.len() {
            let (a, b) = (corners[k], corners[(k + 1) % corners.len()]);
            if a != b {
                edges.push(((a.min(b), a.max(b)), f, edges.len()));
            }
        }
    }
    edges.sort_unstable();
    edges.dedup_by_key(|e| e.0);
    edges.sort_unstable_by_key(|e| e.2);
    for &((a, b), f, _) in &edges {
        raw.beams.push([a, b]);
        raw.beam_place.push(format!("the edge {}–{} of {}", a + 1, b + 1, faces[f].1));
    }
    format!("read {} {what} as {} beams (their unique edges): the file has faces, not line elements", faces.len(), edges.len())
}

/// A triangle mesh (STL) whose edges are the beams.
fn stl(name: &str, bytes: &[u8]) -> Result<Raw, Error> {
    let imported = crate::import::read_mesh(name, bytes, &crate::import::Options::default()).map_err(|e| Error::NotRead {
        file: name.into(),
        place: "the mesh".into(),
        message: e.to_string(),
    })?;
    let mesh = imported.mesh;
    if mesh.triangles.len().saturating_mul(3) / 2 > MAX_BEAMS + 1 {
        return Err(Error::TooManyBeams { file: name.into(), beams: mesh.triangles.len() * 3 / 2 });
    }
    let mut raw = Raw::new(Format::Mesh);
    for (i, v) in mesh.vertices.iter().enumerate() {
        raw.joints.push(DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64));
        raw.joint_place.push(format!("vertex {}", i + 1));
    }
    let faces: Vec<(Vec<usize>, String)> =
        mesh.triangles.iter().enumerate().map(|(t, tri)| (tri.iter().map(|&v| v as usize).collect(), format!("triangle {}", t + 1))).collect();
    let note = edges_as_beams(&mut raw, &faces, "triangles");
    raw.notes.push(note);
    Ok(raw)
}

fn unit_scale(unit: &str) -> Option<f64> {
    match unit.trim().to_ascii_lowercase().as_str() {
        "mm" | "millimeter" | "millimeters" | "millimetre" | "millimetres" => Some(1.0),
        "cm" | "centimeter" | "centimeters" | "centimetre" | "centimetres" => Some(10.0),
        "m" | "meter" | "meters" | "metre" | "metres" => Some(1000.0),
        "in" | "inch" | "inches" => Some(25.4),
        _ => None,
    }
}

fn json(text: &str) -> Result<Raw, (String, String)> {
    let v: Value = serde_json::from_str(text).map_err(|e| {
        (format!("line {}, column {}", e.line(), e.column()), format!("not JSON ({e}); a wireframe design is assembly_instances or conmech JSON, OBJ or CSV"))
    })?;
    let scale = |default: f64| -> Result<f64, (String, String)> {
        match v.get("unit").and_then(Value::as_str) {
            None => Ok(default),
            Some(u) => unit_scale(u).ok_or_else(|| ("unit".into(), format!("unit \"{u}\" is not one weft reads: use millimeter, centimeter, meter or inch"))),
        }
    };
    let num = |x: &Value, place: &str| -> Result<f64, (String, String)> { x.as_f64().ok_or_else(|| (place.to_string(), format!("{x} is not a number"))) };
    let flag = |x: Option<&Value>| x.is_some_and(|g| g.as_bool().unwrap_or(false) || g.as_f64().is_some_and(|f| f != 0.0));
    if let Some(nodes) = v.get("node_list").and_then(Value::as_array) {
        let s = scale(1.0)?;
        let elements = v
            .get("element_list")
            .and_then(Value::as_array)
            .ok_or(("element_list".to_string(), "an assembly_instances design needs its element_list (the beams)".to_string()))?;
        let mut raw = Raw { grounded: Some(Vec::new()), ..Raw::new(Format::AssemblyInstances) };
        let mut by_id = BTreeMap::new();
        for (i, n) in nodes.iter().enumerate() {
            let place = format!("node_list[{i}]");
            let p = n.get("point").ok_or((place.clone(), "a node needs its point {X, Y, Z}".to_string()))?;
            let c = |k: &str| p.get(k).ok_or((format!("{place}.point"), format!("the point has no {k}"))).and_then(|x| num(x, &format!("{place}.point.{k}")));
            let q = DVec3::new(c("X")?, c("Y")?, c("Z")?) * s;
            let id = n.get("node_id").and_then(Value::as_i64).unwrap_or(i as i64);
            if by_id.insert(id, raw.joints.len()).is_some() {
                return Err((place, format!("node_id {id} is given twice")));
            }
            raw.joints.push(q);
            raw.joint_place.push(format!("node {id}"));
            if let Some(g) = raw.grounded.as_mut() {
                g.push(flag(n.get("is_grounded")));
            }
        }
        json_beams(&mut raw, elements, &by_id, ("element_list", "end_node_ids", "element_id", "node id"))?;
        return Ok(raw);
    }
    if let Some(nodes) = v.get("nodes").and_then(Value::as_array) {
        let s = scale(1000.0)?;
        let elements =
            v.get("elements").and_then(Value::as_array).ok_or(("elements".to_string(), "a conmech design needs its elements (the beams)".to_string()))?;
        let mut raw = Raw::new(Format::Conmech);
        let mut by_id = BTreeMap::new();
        let mut grounded = Vec::new();
        for (i, n) in nodes.iter().enumerate() {
            let place = format!("nodes[{i}]");
            let p = n.get("point").and_then(Value::as_array).filter(|a| a.len() == 3).ok_or((place.clone(), "a node needs its point [x, y, z]".to_string()))?;
            let q = DVec3::new(num(&p[0], &place)?, num(&p[1], &place)?, num(&p[2], &place)?) * s;
            let id = n.get("node_ind").and_then(Value::as_i64).unwrap_or(i as i64);
            if by_id.insert(id, raw.joints.len()).is_some() {
                return Err((place, format!("node_ind {id} is given twice")));
            }
            raw.joints.push(q);
            raw.joint_place.push(format!("node {id}"));
            grounded.push(flag(n.get("is_grounded")));
        }
        for (i, sup) in v.get("supports").and_then(Value::as_array).into_iter().flatten().enumerate() {
            let id = sup.get("node_ind").and_then(Value::as_i64).ok_or((format!("supports[{i}]"), "a support needs its node_ind".to_string()))?;
            match by_id.get(&id) {
                Some(&j) => grounded[j] = true,
                None => return Err((format!("supports[{i}]"), format!("node {id} does not exist"))),
            }
        }
        raw.grounded = Some(grounded);
        json_beams(&mut raw, elements, &by_id, ("elements", "end_node_inds", "elem_ind", "node index"))?;
        return Ok(raw);
    }
    Err(("top level".into(), "this JSON is neither an assembly_instances design (node_list, element_list) nor a conmech one (nodes, elements)".into()))
}

/// The beams of a JSON design's element list: `keys` names the list, the two ends' key, the
/// id's key and what an end is called, as the format spells them. Ends naming missing joints
/// are kept as dangling (listed with every other problem).
fn json_beams(
    raw: &mut Raw,
    elements: &[Value],
    by_id: &std::collections::BTreeMap<i64, usize>,
    keys: (&str, &str, &str, &str),
) -> Result<(), (String, String)> {
    let (list, ends_key, id_key, what) = keys;
    for (i, e) in elements.iter().enumerate() {
        let place = format!("{list}[{i}]");
        let ends = e.get(ends_key).and_then(Value::as_array).filter(|a| a.len() == 2).ok_or((place.clone(), format!("a beam needs {ends_key} [i, j]")))?;
        let id = e.get(id_key).and_then(Value::as_i64).unwrap_or(i as i64);
        let bplace = format!("element {id}");
        let mut pair = [0usize; 2];
        let mut ok = true;
        for (k, end) in ends.iter().enumerate() {
            let n = end.as_i64().ok_or((format!("{place}.{ends_key}"), format!("{end} is not a {what}")))?;
            match by_id.get(&n) {
                Some(&j) => pair[k] = j,
                None => {
                    raw.dangling.push((bplace.clone(), format!("node {n}")));
                    ok = false;
                }
            }
        }
        if ok {
            raw.beams.push(pair);
            raw.beam_place.push(bplace);
        }
    }
    Ok(())
}

/// The beams a file states, counted without parsing: CSV lines (a header line left out) that are not comments, OBJ `l` segments, JSON elements' end pairs.
fn beams_counted(text: &str, lower: &str) -> usize {
    if lower.ends_with(".obj") {
        text.lines().filter_map(|l| l.trim_start().strip_prefix("l ")).map(|rest| rest.split_whitespace().count().saturating_sub(1)).sum()
    } else if lower.ends_with(".csv") || lower.ends_with(".txt") {
        let mut lines = text.lines().filter(|l| !l.trim().is_empty() && !l.trim_start().starts_with('#')).peekable();
        let header = lines.peek().is_some_and(|l| l.chars().any(|c| c.is_ascii_alphabetic() && c != 'e' && c != 'E'));
        lines.count() - usize::from(header)
    } else {
        text.matches("end_node_ids").count() + text.matches("end_node_inds").count()
    }
}

/// The numbers of a line (commas, semicolons, tabs or spaces between them).
fn numbers(line: &str) -> Vec<&str> {
    line.split(|c: char| c == ',' || c == ';' || c.is_whitespace()).filter(|t| !t.is_empty()).collect()
}

/// An OBJ element's vertex reference (`7`, `-1`, `7/3/2`: the vertex is the first number) as
/// written and as a 0-based index (negative ones count back from the `count` vertices so far;
/// the index may be out of range, for the caller to list).
fn obj_vertex(token: &str, count: usize) -> Result<(i64, i64), String> {
    let head = token.split('/').next().unwrap_or(token);
    let i: i64 = head.parse().map_err(|_| format!("\"{token}\" is not a vertex number"))?;
    Ok((i, if i > 0 { i - 1 } else { count as i64 + i }))
}

fn obj(text: &str) -> Result<Raw, (usize, String)> {
    let mut raw = Raw::new(Format::Obj);
    // Faces, used as the design only when the file has no line elements.
    let mut faces: Vec<(Vec<usize>, String)> = Vec::new();
    let mut bad_face: Option<(usize, String)> = None;
    let mut face_corners = 0usize;
    for (k, line) in text.lines().enumerate() {
        let n = k + 1;
        let mut it = line.split_whitespace();
        match it.next() {
            Some("v") => {
                let c: Vec<f64> = it.take(3).map(|t| t.parse::<f64>().map_err(|_| (n, format!("\"{t}\" is not a number")))).collect::<Result<_, _>>()?;
                if c.len() < 3 {
                    return Err((n, "a vertex needs x y z".into()));
                }
                raw.joints.push(DVec3::new(c[0], c[1], c[2]));
                raw.joint_place.push(format!("vertex {} (line {n})", raw.joints.len()));
            }
            Some("l") => {
                let mut ids = Vec::new();
                for t in it {
                    ids.push(obj_vertex(t, raw.joints.len()).map_err(|m| (n, m))?);
                }
                if ids.len() < 2 {
                    return Err((n, "a line element needs at least two vertices".into()));
                }
                for w in ids.windows(2) {
                    let place = format!("line {n}");
                    let bad = w.iter().find(|(_, idx)| *idx < 0 || *idx >= raw.joints.len() as i64);
                    match bad {
                        Some((i, _)) => raw.dangling.push((place, format!("vertex {i}"))),
                        None => {
                            raw.beams.push([w[0].1 as usize, w[1].1 as usize]);
                            raw.beam_place.push(place);
                        }
                    }
                }
            }
            Some("f") => {
                let mut corners = Vec::new();
                for t in it {
                    // Bounded as read: the edges of more corners than this would be more
                    // beams than a design may have.
                    face_corners += 1;
                    if face_corners > 3 * MAX_BEAMS {
                        return Err((
                            n,
                            format!(
                                "the faces have more than {} corners, more than the {MAX_BEAMS} beams a design may have; plan the design in parts",
                                3 * MAX_BEAMS
                            ),
                        ));
                    }
                    let (i, idx) = obj_vertex(t, raw.joints.len()).map_err(|m| (n, m))?;
                    if idx < 0 || idx >= raw.joints.len() as i64 {
                        bad_face.get_or_insert((n, format!("vertex {i}")));
                    } else {
                        corners.push(idx as usize);
                    }
                }
                if corners.len() >= 2 {
                    faces.push((corners, format!("the face on line {n}")));
                }
            }
            _ => {}
        }
    }
    if raw.beams.is_empty() && !faces.is_empty() {
        if let Some((line, missing)) = bad_face {
            raw.dangling.push((format!("the face on line {line}"), missing));
        }
        let note = edges_as_beams(&mut raw, &faces, "faces");
        raw.notes.push(note);
    }
    if raw.beams.is_empty() {
        return Err((
            text.lines().count().max(1),
            "no line elements (`l a b`) and no faces: a wireframe OBJ joins its vertices by lines (or faces whose edges are the beams)".into(),
        ));
    }
    Ok(raw)
}

fn csv(text: &str, merge_mm: f64) -> Result<Raw, (usize, String)> {
    let mut raw = Raw::new(Format::Csv);
    // Joints by position on a grid of the merge tolerance (ends within it are one joint; the
    // neighbouring cells are looked at too, so a pair across a cell edge still merges).
    let cell = merge_mm.max(1e-9);
    let mut grid: BTreeMap<[i64; 3], Vec<usize>> = BTreeMap::new();
    let key = |p: DVec3| [(p.x / cell).floor() as i64, (p.y / cell).floor() as i64, (p.z / cell).floor() as i64];
    let mut joint = |p: DVec3, n: usize, raw: &mut Raw| -> usize {
        let k = key(p);
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    if let Some(list) = grid.get(&[k[0] + dx, k[1] + dy, k[2] + dz]) {
                        if let Some(&j) = list.iter().find(|&&j| raw.joints[j].distance(p) <= merge_mm) {
                            return j;
                        }
                    }
                }
            }
        }
        raw.joints.push(p);
        raw.joint_place.push(format!("the joint first on line {n}"));
        grid.entry(k).or_default().push(raw.joints.len() - 1);
        raw.joints.len() - 1
    };
    for (k, line) in text.lines().enumerate() {
        let n = k + 1;
        let t = numbers(line);
        if t.is_empty() || line.trim_start().starts_with('#') {
            continue;
        }
        let parsed: Result<Vec<f64>, _> = t.iter().map(|s| s.parse::<f64>()).collect();
        match parsed {
            Err(_) if raw.beams.is_empty() && raw.joints.is_empty() => continue, // a header
            Err(_) => return Err((n, format!("\"{}\" is not six numbers x1 y1 z1 x2 y2 z2 (mm)", line.trim()))),
            Ok(c) if c.len() != 6 => return Err((n, format!("{} numbers: a beam is six, x1 y1 z1 x2 y2 z2 (mm)", c.len()))),
            Ok(c) => {
                let a = joint(DVec3::new(c[0], c[1], c[2]), n, &mut raw);
                let b = joint(DVec3::new(c[3], c[4], c[5]), n, &mut raw);
                raw.beams.push([a, b]);
                raw.beam_place.push(format!("line {n}"));
            }
        }
        if raw.beams.len() > MAX_BEAMS {
            break;
        }
    }
    if raw.beams.is_empty() {
        return Err((text.lines().count().max(1), "no beams: each line is x1 y1 z1 x2 y2 z2 (mm)".into()));
    }
    Ok(raw)
}

/// Grounds the joints and lists every problem.
fn finish(name: &str, raw: Raw, options: &Options) -> Result<Wireframe, Error> {
    let mut problems: Vec<String> = Vec::new();
    for (place, missing) in &raw.dangling {
        problems.push(format!("{place} names {missing}, which the file does not have"));
    }
    for (j, p) in raw.joints.iter().enumerate() {
        if !p.is_finite() {
            problems.push(format!("{} is at ({}, {}, {}): coordinates must be finite numbers", raw.joint_place[j], p.x, p.y, p.z));
        }
    }
    let mut seen: BTreeMap<(usize, usize), usize> = BTreeMap::new();
    for (b, &[i, j]) in raw.beams.iter().enumerate() {
        let len = raw.joints[i].distance(raw.joints[j]);
        if i == j || len <= options.merge_tolerance_mm {
            problems.push(format!("{} has length {len:.4} mm (from {} to {}): remove it", raw.beam_place[b], raw.joint_place[i], raw.joint_place[j]));
        }
        if let Some(&first) = seen.get(&(i.min(j), i.max(j))) {
            problems.push(format!(
                "{} repeats {} (both join {} and {}): remove one",
                raw.beam_place[b], raw.beam_place[first], raw.joint_place[i], raw.joint_place[j]
            ));
        } else {
            seen.insert((i.min(j), i.max(j)), b);
        }
    }
    // Grounding: the file's marks, or the lowest joints among those beams use.
    let used: Vec<bool> = {
        let mut u = vec![false; raw.joints.len()];
        for &[i, j] in &raw.beams {
            u[i] = true;
            u[j] = true;
        }
        u
    };
    let from_file = raw.grounded.as_ref().filter(|g| options.ground == Ground::File && g.iter().zip(&used).any(|(&g, &u)| g && u)).cloned();
    let grounded_by_file = from_file.is_some();
    let grounded = from_file.unwrap_or_else(|| {
        let low = raw.joints.iter().zip(&used).filter(|(p, &u)| u && p.z.is_finite()).map(|(p, _)| p.z).fold(f64::INFINITY, f64::min);
        raw.joints.iter().zip(&used).map(|(p, &u)| u && p.z <= low + options.ground_tolerance_mm).collect()
    });
    if !grounded.iter().any(|&g| g) {
        problems.push("no joint is grounded: mark the joints on the substrate, or ground the lowest ones".into());
    } else {
        // Beams not connected to any grounded joint (union-find over the beams).
        let mut parent: Vec<usize> = (0..raw.joints.len()).collect();
        fn find(p: &mut [usize], mut x: usize) -> usize {
            while p[x] != x {
                p[x] = p[p[x]];
                x = p[x];
            }
            x
        }
        for &[i, j] in &raw.beams {
            let (a, b) = (find(&mut parent, i), find(&mut parent, j));
            if a != b {
                parent[a.max(b)] = a.min(b);
            }
        }
        let mut reached = vec![false; raw.joints.len()];
        for (j, &g) in grounded.iter().enumerate() {
            if g {
                let r = find(&mut parent, j);
                reached[r] = true;
            }
        }
        // One line per part, in the order of its first beam.
        let mut parts: BTreeMap<usize, (usize, usize)> = BTreeMap::new();
        for (b, &[i, _]) in raw.beams.iter().enumerate() {
            let r = find(&mut parent, i);
            if !reached[r] {
                parts.entry(r).or_insert((b, 0)).1 += 1;
            }
        }
        let mut parts: Vec<(usize, usize)> = parts.into_values().collect();
        parts.sort_unstable();
        for (first, count) in parts {
            problems.push(format!(
                "{count} beam(s) starting with {} are not connected to any grounded joint: join them to the rest, ground one of their joints, or remove them",
                raw.beam_place[first]
            ));
        }
    }
    if !problems.is_empty() {
        let more = problems.len().saturating_sub(MAX_LISTED);
        problems.truncate(MAX_LISTED);
        if more > 0 {
            problems.push(format!("and {more} more problem(s)"));
        }
        return Err(Error::Invalid { file: name.into(), problems });
    }
    Ok(Wireframe {
        joints: raw.joints,
        beams: raw.beams,
        grounded,
        grounded_by_file,
        format: raw.format,
        joint_names: raw.joint_place,
        beam_names: raw.beam_place,
        notes: raw.notes.into_iter().map(|n| format!("{name}: {n}")).collect(),
        grounding: None,
    })
}

/// Grounded joints spanning less than this share of the design's footprint (the diagonals
/// of their boxes seen from above) are an implausible footing when the lowest joints were
/// grounded by tolerance.
pub const PLAUSIBLE_FOOTPRINT_SHARE: f64 = 0.2;
/// A suggested ground tolerance reaches at most this share of the design's height.
pub const SUGGEST_HEIGHT_SHARE: f64 = 0.1;

/// What was grounded and whether it is a plausible footing for the design.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Grounding {
    /// Joints grounded.
    pub joints: usize,
    /// They are the file's marks (false: the joints within the tolerance of the lowest).
    pub by_file: bool,
    /// The design is a built-in one (its grounded joints are its own).
    pub built_in: bool,
    /// The lowest joint's z, mm.
    pub z_mm: f64,
    /// The tolerance used (grounding the lowest), mm.
    pub tolerance_mm: f64,
    /// The grounded joints' span over the design's, seen from above (diagonals of the boxes).
    pub footprint_share: f64,
    /// A tolerance that would ground the base: (tolerance mm, joints, footprint share).
    pub suggestion: Option<(f64, usize, f64)>,
}

impl Grounding {
    /// Grounding the lowest joints gave a footing the design cannot plausibly stand on.
    pub fn implausible(&self) -> bool {
        !self.by_file && self.footprint_share < PLAUSIBLE_FOOTPRINT_SHARE
    }

    /// One clause: what was grounded.
    pub fn statement(&self) -> String {
        let n = self.joints;
        let joints = if n == 1 { "1 joint grounded".to_string() } else { format!("{n} joints grounded") };
        if self.by_file && self.built_in {
            format!("{joints}, the built-in design's feet")
        } else if self.by_file {
            format!("{joints}, as the file marks them")
        } else {
            format!("{joints}, the lowest: z {:.2} ± {} mm", self.z_mm, self.tolerance_mm)
        }
    }

    /// The warning when the footing is implausible, with the tolerance that grounds the base.
    pub fn warning(&self) -> Option<String> {
        if !self.implausible() {
            return None;
        }
        let fix = match self.suggestion {
            Some((tol, joints, share)) => format!(
                "a ground tolerance of {tol} mm grounds {joints} joints spanning {:.0} % of it (set Ground tolerance, job.design.ground_tolerance_mm), or mark the grounded joints in the file",
                share * 100.0
            ),
            None => "mark the grounded joints in the file, or turn the design so its base is lowest".to_string(),
        };
        Some(format!(
            "only {} touch{} the plate, spanning {:.0} % of the design's footprint: the part would stand on {}; {fix}",
            if self.joints == 1 { "1 joint".to_string() } else { format!("{} joints", self.joints) },
            if self.joints == 1 { "es" } else { "" },
            self.footprint_share * 100.0,
            if self.joints == 1 { "one point" } else { "a small part of its base" }
        ))
    }
}

/// XY diagonal of the box of `points`.
fn xy_diagonal(points: impl Iterator<Item = DVec3>) -> f64 {
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    for p in points {
        lo = lo.min(p);
        hi = hi.max(p);
    }
    if lo.x > hi.x {
        return 0.0;
    }
    ((hi.x - lo.x).powi(2) + (hi.y - lo.y).powi(2)).sqrt()
}

/// What `w`'s grounding is (see [`Grounding`]), `tolerance_mm` being the one used when the
/// lowest joints were grounded. The suggestion is the least tolerance, up to
/// [`SUGGEST_HEIGHT_SHARE`] of the height, whose grounded joints are a plausible footing
/// (rounded up to two significant figures).
pub fn grounding(w: &Wireframe, tolerance_mm: f64) -> Grounding {
    let used: Vec<bool> = {
        let mut u = vec![false; w.joints.len()];
        for &[i, j] in &w.beams {
            u[i] = true;
            u[j] = true;
        }
        u
    };
    let joints_used = || w.joints.iter().zip(&used).filter(|(_, &u)| u).map(|(p, _)| *p);
    let footprint = xy_diagonal(joints_used());
    let share = |d: f64| if footprint > 1e-9 { (d / footprint).min(1.0) } else { 1.0 };
    let grounded = w.grounded.iter().filter(|&&g| g).count();
    let low = joints_used().map(|p| p.z).fold(f64::INFINITY, f64::min);
    let high = joints_used().map(|p| p.z).fold(f64::NEG_INFINITY, f64::max);
    let footprint_share = share(xy_diagonal(w.joints.iter().zip(&w.grounded).filter(|(_, &g)| g).map(|(p, _)| *p)));
    let mut g = Grounding {
        joints: grounded,
        by_file: w.grounded_by_file,
        built_in: w.format == Format::Model,
        z_mm: if low.is_finite() { low } else { 0.0 },
        tolerance_mm,
        footprint_share,
        suggestion: None,
    };
    if g.implausible() && low.is_finite() {
        let mut by_z: Vec<DVec3> = joints_used().collect();
        by_z.sort_by(|a, b| a.z.total_cmp(&b.z));
        let reach = low + SUGGEST_HEIGHT_SHARE * (high - low);
        let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        for p in &by_z {
            if p.z > reach {
                break;
            }
            lo = lo.min(*p);
            hi = hi.max(*p);
            let d = ((hi.x - lo.x).powi(2) + (hi.y - lo.y).powi(2)).sqrt();
            if share(d) >= PLAUSIBLE_FOOTPRINT_SHARE {
                let tol = round_up_2(p.z - low).max(tolerance_mm);
                let count = by_z.iter().filter(|q| q.z <= low + tol).count();
                let d = xy_diagonal(by_z.iter().filter(|q| q.z <= low + tol).copied());
                g.suggestion = Some((tol, count, share(d)));
                break;
            }
        }
    }
    g
}

/// `x` rounded up to two significant figures (0.3412 → 0.35).
fn round_up_2(x: f64) -> f64 {
    if !(x.is_finite() && x > 0.0) {
        return 0.0;
    }
    let scale = libm::pow(10.0, libm::floor(libm::log10(x)) - 1.0);
    let v = libm::ceil(x / scale - 1e-9) * scale;
    // Printed cleanly: as many decimals as the scale has.
    let decimals = (-libm::log10(scale)).round().max(0.0) as i32;
    let f = libm::pow(10.0, decimals as f64);
    (v * f).round() / f
}

impl Wireframe {
    /// Length of beam `b`, mm.
    pub fn length(&self, b: usize) -> f64 {
        let [i, j] = self.beams[b];
        self.joints[i].distance(self.joints[j])
    }
}

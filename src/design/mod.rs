//! The Design document: one versioned JSON file that describes a whole job.
//!
//! The page edits it, the share URL carries it (the codec: [`share`]), the CLI runs it. This
//! module is the document as data and knows no job kind: reading it against the kinds
//! (`Design::from_json`, which rejects unknown fields and wrong versions and lists every
//! out-of-range value with its path and range), its changes and the schema are the catalog's
//! (`crate::catalog`, above the kinds).

pub mod share;
pub(crate) mod words;

use crate::gcode::{Material, Printer, Speeds};
use crate::geom::shapes::Shape;
use serde::{Deserialize, Serialize};
use serde_json::Value;

use crate::settings::clip;
pub use crate::settings::Problem;

/// The only version this build reads and writes.
pub const DESIGN_VERSION: u32 = 1;

/// Longest design name, bytes (UTF-8). The name is one line written into the G-code header and
/// each `{design_name}` of the templates, and it names the output file (cut to
/// [`MAX_FILE_STEM_BYTES`] there); 256 bytes is a long title.
pub const MAX_NAME_BYTES: usize = 256;
/// Longest description, bytes (UTF-8): one line on what the design makes.
pub const MAX_DESCRIPTION_BYTES: usize = 512;

/// Largest design JSON read, bytes (4 MiB). A design is settings and names; the largest parts
/// are the templates (2 × [`crate::gcode::MAX_TEMPLATE_BYTES`]), the files embedded by a share
/// link ([`share::MAX_EMBEDDED_CHARS`]) and a slot's file names ([`MAX_INPUT_FILES`] ×
/// typically 20–40 bytes), together under 1.5 MiB; 4 MiB leaves room and bounds what a share
/// link or a pasted file makes the parser and validator read (a few copies of it).
pub const MAX_DESIGN_BYTES: usize = 4 * 1024 * 1024;

/// Most keys in a `--set` path (32). The deepest real design path has 6
/// (`job.lattice.overrides.0.rotation_deg`); a limit keeps `--set a.a.a…` from building an
/// object tree deep enough to overflow the stack when it is read, written or dropped.
pub const MAX_PATH_DEPTH: usize = 32;

/// Deepest JSON nesting a design value may have (128, serde_json's own parsing limit, so a
/// value built in memory obeys the same rule as a parsed one).
pub const MAX_JSON_DEPTH: usize = 128;

/// Longest input file name, bytes (255: the longest file name of common file systems).
pub const MAX_FILE_NAME_BYTES: usize = 255;

/// Most files in one input slot (10 000): a DICOM series has one file per slice, rarely over
/// 2 000; the names travel in share links and are listed in notes.
pub const MAX_INPUT_FILES: usize = 10_000;

/// Longest file stem [`file_stem`] makes, bytes (100): with the extension the file name stays
/// well under the 255-byte name limit of common file systems.
pub const MAX_FILE_STEM_BYTES: usize = 100;

/// Longest quote of a value in an error message, characters.
pub(crate) const MAX_QUOTE_CHARS: usize = 60;

/// A whole job.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Design {
    /// Format version; must be [`DESIGN_VERSION`].
    pub version: u32,
    /// Name, used for the output file (`<name>.gcode`).
    pub name: String,
    /// One line on what the design makes (the page's example list shows it); optional.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub description: String,
    /// When the design was made or last changed, `YYYY-MM-DD HH:MM:SS` in UTC (`weft new` and
    /// the page's edits set it); the G-code header's date, so the same design gives the same
    /// bytes on any day. Optional.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub date: String,
    /// Seed of every random choice (same seed → same G-code).
    #[serde(default)]
    pub seed: u64,
    /// The machine.
    #[serde(default)]
    pub printer: Printer,
    /// The material.
    #[serde(default)]
    pub material: Material,
    /// Print speeds.
    #[serde(default)]
    pub speeds: Speeds,
    /// What to make.
    pub job: Job,
}

/// The job: a `kind` and that kind's settings, as JSON normalised by the kind
/// (the kind's `normalize`: every default filled in, unknown fields refused).
/// Kinds read their typed settings with [`Job::settings`].
#[derive(Clone, Debug, PartialEq)]
pub struct Job {
    /// The `job` object, `kind` first.
    pub value: Value,
}

impl Job {
    /// The kind's name as written in JSON (`slice`, `lattice`).
    pub fn kind(&self) -> &str {
        self.value.get("kind").and_then(Value::as_str).unwrap_or("")
    }

    /// The typed settings of the job, when it is of the kind `T` belongs to.
    pub fn settings<T: serde::de::DeserializeOwned>(&self) -> Option<T> {
        job_settings(&self.value).ok()
    }

    /// A job of kind `kind` with `settings`.
    pub fn new(kind: &str, settings: &impl Serialize) -> Job {
        Job { value: with_kind(kind, settings).unwrap_or(Value::Null) }
    }

    /// The input at the design path `path` (a slot's path, e.g. `job.input`).
    pub fn input_at(&self, path: &str) -> Option<Input> {
        let rel = path.strip_prefix("job.")?;
        let v = rel.split('.').try_fold(&self.value, |v, k| v.get(k))?;
        serde_json::from_value(v.clone()).ok()
    }
}

/// The settings part of a `job` object: everything but `kind`.
pub fn without_kind(job: &Value) -> Value {
    let mut v = job.clone();
    if let Value::Object(m) = &mut v {
        m.remove("kind");
    }
    v
}

/// The typed settings of `job` (a normalised `job` object).
pub fn job_settings<T: serde::de::DeserializeOwned>(job: &Value) -> Result<T, serde_json::Error> {
    serde_json::from_value(without_kind(job))
}

/// The `job` object of kind `name` with `settings`, `kind` first (as people write it).
pub fn with_kind(name: &str, settings: &impl Serialize) -> Result<Value, serde_json::Error> {
    let mut v = serde_json::to_value(settings)?;
    if let Value::Object(m) = &mut v {
        let mut out = serde_json::Map::new();
        out.insert("kind".into(), Value::String(name.into()));
        out.append(m);
        return Ok(Value::Object(out));
    }
    Ok(v)
}

impl Serialize for Job {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        self.value.serialize(s)
    }
}

impl<'de> Deserialize<'de> for Job {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Job, D::Error> {
        let value = Value::deserialize(d)?;
        match value.get("kind") {
            Some(Value::String(_)) => Ok(Job { value }),
            _ => Err(serde::de::Error::custom("needs a \"kind\", the job kind (e.g. \"slice\" or \"lattice\")")),
        }
    }
}

/// Where a mesh comes from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum Input {
    /// A built-in solid.
    Builtin(Shape),
    /// A loaded file, by name; the bytes come with the job (page upload, `--input`), or
    /// embedded in a share link as base64url of its deflated bytes.
    File {
        /// File name, e.g. `part.stl`.
        name: String,
        /// base64url(deflate(bytes)), present only in share links for small meshes.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        embedded: Option<String>,
    },
    /// Several loaded files, by name (a DICOM series, labelled meshes).
    Files(Vec<String>),
}

/// Why a design could not be read.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum Error {
    /// Not JSON, or nested too deeply.
    #[error("{source_name}: {}{message}", at(*line, *column))]
    Syntax {
        /// Where it came from (file name, "share link", ...).
        source_name: String,
        /// 1-based line (0: no place in a text, e.g. a design built by `--set`).
        line: usize,
        /// 1-based column.
        column: usize,
        /// What is wrong, in words.
        message: String,
    },
    /// A version this build cannot read.
    #[error("{source_name}: design version {found} is not supported; this weft reads version {DESIGN_VERSION} (re-save the design with a matching weft)")]
    Version {
        /// Where it came from.
        source_name: String,
        /// The version in the file.
        found: String,
    },
    /// No `version`: not a design (or not a JSON object at all).
    #[error("{source_name}: this is not a weft design: it has no \"version\" (a design starts {{\"version\": {DESIGN_VERSION}, \"name\": …}}; start from an example on the page, or `weft new`)")]
    NotADesign {
        /// Where it came from.
        source_name: String,
    },
    /// Fields with a wrong value: out of range (all of them listed), of the wrong type, unknown
    /// or missing (the first one the reader met), each at its dotted path, in words.
    #[error("{source_name}: {}", problems.iter().map(|p| format!("{}: {}", p.path, p.message)).collect::<Vec<_>>().join("\n"))]
    Invalid {
        /// Where it came from.
        source_name: String,
        /// Every problem.
        problems: Vec<Problem>,
    },
    /// Over [`MAX_DESIGN_BYTES`].
    #[error("{source_name}: the design is {bytes} bytes, over the limit of {MAX_DESIGN_BYTES} bytes; a design holds settings and names (meshes travel as separate files): remove what was pasted into it")]
    TooLarge {
        /// Where it came from.
        source_name: String,
        /// Its size.
        bytes: usize,
    },
    /// A `--set` override could not be applied.
    #[error("--set {assignment}: {message}")]
    Override {
        /// The `path=value` text.
        assignment: String,
        /// Why.
        message: String,
    },
}

/// "line L, column C: ", or nothing for a value without a text.
pub(crate) fn at(line: usize, column: usize) -> String {
    if line == 0 {
        String::new()
    } else {
        format!("line {line}, column {column}: ")
    }
}

/// A file stem made from a design name (or any untrusted string), safe to join to a folder:
/// the file it names is inside that folder on every system. Letters and digits of any script
/// are kept, as are `- _ . + , ( ) [ ] @ = ~`; whitespace becomes one space; anything else
/// (path separators `/` `\\` `:`, control and invisible characters, `* ? " < > | $ %` …)
/// becomes `_`, runs of `.` one `.`; leading dots, dashes, spaces and `_` are removed (no
/// hidden files, `..`, or names read as options), then trailing dots and spaces (Windows drops
/// them); the result is cut to [`MAX_FILE_STEM_BYTES`]. A Windows device name (`CON`, `NUL`,
/// `COM1`, `LPT¹`, … with or without an extension) gets a leading `_`. Nothing left: `design`.
pub fn file_stem(name: &str) -> String {
    let mut s = String::with_capacity(name.len().min(4 * MAX_FILE_STEM_BYTES));
    for c in name.chars() {
        let c = if c.is_alphanumeric() || matches!(c, '-' | '_' | '.' | '+' | ',' | '(' | ')' | '[' | ']' | '@' | '=' | '~') {
            c
        } else if c.is_whitespace() {
            ' '
        } else {
            '_'
        };
        // Collapse runs of the characters we made (and of dots), and skip leading junk.
        let prev = s.chars().next_back();
        if (s.is_empty() && matches!(c, '.' | '-' | ' ' | '_')) || (matches!(c, ' ' | '_' | '.') && prev == Some(c)) {
            continue;
        }
        if s.len() + c.len_utf8() > MAX_FILE_STEM_BYTES {
            break;
        }
        s.push(c);
    }
    let s = s.trim_end_matches(['.', ' ']);
    if s.is_empty() {
        return "design".into();
    }
    let base = s.split('.').next().unwrap_or("").trim_end().to_ascii_uppercase();
    let reserved = matches!(base.as_str(), "CON" | "PRN" | "AUX" | "NUL")
        || ((base.starts_with("COM") || base.starts_with("LPT"))
            && base[3..].chars().count() == 1
            && base[3..].chars().all(|c| c.is_ascii_digit() || matches!(c, '¹' | '²' | '³')));
    if reserved {
        let mut cut = s.len().min(MAX_FILE_STEM_BYTES - 1);
        while !s.is_char_boundary(cut) {
            cut -= 1;
        }
        format!("_{}", s[..cut].trim_end_matches(['.', ' ']))
    } else {
        s.to_string()
    }
}

/// The top-level key of a place in `value` nested deeper than `limit` ("" for the root
/// itself), found without recursion: the value may be far deeper than the stack allows.
pub(crate) fn too_deep(value: &Value, limit: usize) -> Option<String> {
    let mut stack: Vec<(&Value, usize, &str)> = vec![(value, 0, "")];
    while let Some((v, depth, top)) = stack.pop() {
        match v {
            Value::Array(_) | Value::Object(_) if depth >= limit => return Some(top.to_string()),
            Value::Array(items) => stack.extend(items.iter().map(|c| (c, depth + 1, top))),
            Value::Object(map) => stack.extend(map.iter().map(|(k, c)| (c, depth + 1, if depth == 0 { k.as_str() } else { top }))),
            _ => {}
        }
    }
    None
}

/// Drops `value` one level at a time: the default drop recurses once per level and a value
/// refused for its depth may be deeper than the stack.
pub(crate) fn drop_flat(value: Value) {
    let mut stack = vec![value];
    while let Some(mut v) = stack.pop() {
        match &mut v {
            Value::Array(items) => stack.append(items),
            Value::Object(map) => stack.extend(std::mem::take(map).into_iter().map(|(_, c)| c)),
            _ => {}
        }
    }
}

/// Sets a dotted path in a JSON tree, creating objects on the way (unknown names are then
/// rejected by deserialisation, which names them). Paths of more than [`MAX_PATH_DEPTH`] keys
/// are refused before anything is built.
pub(crate) fn set_path(root: &mut Value, path: &str, new: Value) -> Result<(), String> {
    if path.is_empty() {
        return Err("empty field path".into());
    }
    let keys = path.bytes().filter(|&b| b == b'.').count() + 1;
    if keys > MAX_PATH_DEPTH {
        return Err(format!("the path has {keys} keys, over the limit of {MAX_PATH_DEPTH}; design paths are a few keys long, e.g. job.slice.layer_height_mm"));
    }
    let mut cur = root;
    let parts: Vec<&str> = path.split('.').collect();
    for (i, part) in parts.iter().enumerate() {
        let last = i + 1 == parts.len();
        match cur {
            Value::Object(map) => {
                if last {
                    // Changing a tagged variant (`…kind`) starts the new variant from its
                    // defaults instead of keeping the old variant's fields.
                    if *part == "kind" && map.get("kind") != Some(&new) {
                        map.clear();
                    }
                    map.insert((*part).to_string(), new);
                    return Ok(());
                }
                cur = map.entry((*part).to_string()).or_insert_with(|| Value::Object(Default::default()));
            }
            Value::Array(items) => {
                let idx: usize = part.parse().map_err(|_| {
                    let list = clip(&parts[..i].join("."), 200).into_owned();
                    format!("'{list}' is a list; use an index like {list}.0")
                })?;
                let len = items.len();
                let slot = items.get_mut(idx).ok_or_else(|| format!("index {idx} is outside the list of {len}"))?;
                if last {
                    *slot = new;
                    return Ok(());
                }
                cur = slot;
            }
            _ => return Err(format!("'{}' is not an object", clip(&parts[..i].join("."), 200))),
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_round_trips() {
        let d = Design::default();
        let text = d.to_json_pretty();
        assert_eq!(Design::from_json("t", &text).unwrap(), d);
    }

    #[test]
    fn unknown_field_is_named() {
        let mut v = serde_json::to_value(Design::default()).unwrap();
        v["job"]["slice"]["infil_density"] = 0.3.into();
        let e = Design::from_json("d.json", &v.to_string()).unwrap_err().to_string();
        assert!(e.contains("infil_density"), "{e}");
        v = serde_json::to_value(Design::default()).unwrap();
        v["job"]["colour"] = "red".into();
        let e = Design::from_json("d.json", &v.to_string()).unwrap_err().to_string();
        assert!(e.contains("colour"), "{e}");
    }

    /// What the reader says about a wrong value: the field's path and label, what it must be
    /// and the value given; never serde's words (`invalid type`, `u32`, `line 0`).
    #[test]
    fn reading_errors_are_in_words() {
        let lattice = include_str!("../../examples/honeycomb-10mm.json");
        let d = Design::from_json("t", lattice).unwrap();
        let set = |a: &str| d.with_overrides(&[a.to_string()]).unwrap_err().to_string();
        for (assignment, want) in [
            ("job.paths.iterations=2.5", "job.paths.iterations: GIPPO iterations must be a whole number from 1 to 100000 (got 2.5)"),
            ("job.paths.iterations=-1", "job.paths.iterations: GIPPO iterations must be a whole number from 1 to 100000 (got -1)"),
            ("job.paths.iterations=many", "job.paths.iterations: GIPPO iterations must be a whole number from 1 to 100000 (got \"many\")"),
            ("job.paths.method=eulr", "job.paths.method: 'eulr' is not a choice for Optimiser; use one of: gippo_max, gippo_min, euler, continuous"),
            ("job.lattice.layers=99999999999", "job.lattice.layers: Layers must be a whole number from 1 to 10000 (got 99999999999)"),
            ("job.lattice.pattern.kind=hex", "job.lattice.pattern.kind: 'hex' is not a choice for Pattern; use one of: honeycomb, voronoi, penrose, snub_square, arrowhead, reentrant_honeycomb, rectilinear, square_grid, triangle_grid, wavy_honeycomb, wavy_square_grid"),
            ("job.lattice.pattern.hexagon_radius_mm=big", "job.lattice.pattern.hexagon_radius_mm: Hexagon radius must be a number from 0.05 to 1000 mm (got \"big\")"),
            ("job.domain={\"width_mm\":3}", "job.domain.kind: Domain is missing: add it (one of: rectangle, disc, tensile_specimen, solid)"),
            ("job.kind=weave", "job.kind: 'weave' is not a choice for the job kind; use one of: slice, lattice, axisymmetric, graded, foam, freeform"),
            ("printer.flavor=klipper", "printer.flavor: 'klipper' is not a choice for G-code flavour; use one of: marlin, pneumatic, poses_csv"),
            ("printer.bed_size_mm=200", "printer.bed_size_mm: Bed size X, Y, Z must be three numbers [x, y, z], each from 10 to 2000 mm (got 200)"),
            ("printer.bed_size_mm.1=wide", "printer.bed_size_mm.1: Bed size X, Y, Z must be three numbers [x, y, z], each from 10 to 2000 mm (got \"wide\")"),
            ("printer.relative_e=1", "printer.relative_e: Relative extrusion (M83) must be true or false (got 1)"),
            ("name=3", "name: Name must be text in double quotes (got 3)"),
            ("seed=-1", "seed: Random seed must be a whole number from 0 to 9.007199254740991e15 (got -1)"),
            ("colour=red", "colour: is not a setting; the settings of the design are: version, name, description, date, seed, printer, material, speeds, job"),
            ("job.paths.iteratons=5", "job.paths.iteratons: is not a setting (did you mean 'iterations'?); the settings of job.paths are: method, iterations, order, merge_tolerance_mm, short_path_segments, short_path_speed_factor, exact_pairing_seconds, direction_deg"),
            ("job.lattice.overrides=[{\"layer\":\"top\"}]", "job.lattice.overrides.0.layer: must be a whole number from 0 to 4294967295 (got \"top\")"),
            ("job={}", "job: needs a \"kind\", the job kind (e.g. \"slice\" or \"lattice\")"),
            ("job.input={\"bultin\":{}}", "job.input: 'bultin' is not allowed here; use one of: builtin, file, files"),
        ] {
            assert_eq!(set(assignment), format!("--set: {want}"), "{assignment}");
        }
        let cube = Design::default();
        let e = cube.with_overrides(&["job.input={\"builtin\":{\"shape\":\"cube\",\"size\":[1,2]}}".into()]).unwrap_err().to_string();
        assert_eq!(e, "--set: job.input.builtin.size: Cube size X, Y, Z must be three numbers [x, y, z], each from 0.01 to 2000 mm (got a list of 2 values)");
        // From a file: the same words; a JSON syntax error keeps its line and column.
        let mut v = serde_json::to_value(&cube).unwrap();
        v["job"]["slice"]["perimeters"] = 2.5.into();
        assert_eq!(
            Design::from_json("cube.json", &v.to_string()).unwrap_err().to_string(),
            "cube.json: job.slice.perimeters: Perimeters must be a whole number from 0 to 50 (got 2.5)"
        );
        let text = cube.to_json_pretty();
        let cut = &text[..text.len() / 2];
        assert_eq!(
            Design::from_json("cube.json", cut).unwrap_err().to_string().split_once(": not valid JSON: ").map(|(_, m)| m.to_string()).unwrap(),
            "the text ends before the design does: the file was cut short; save or copy it again"
        );
        assert_eq!(
            Design::from_json("d.json", "{\"version\": 1, name: 2}").unwrap_err().to_string(),
            "d.json: line 1, column 16: not valid JSON: field names must be in double quotes"
        );
        assert_eq!(
            Design::from_json("d.json", "{\"version\": 1,}").unwrap_err().to_string(),
            "d.json: line 1, column 15: not valid JSON: there is a ',' before a closing bracket: remove it"
        );
        assert_eq!(Design::from_json("d.json", "{\"version\": 1}").unwrap_err().to_string(), "d.json: name: Name is missing: add it (text in double quotes)");
        assert_eq!(
            Design::from_json("d.json", "{\"version\": 1, \"name\": \"x\"}").unwrap_err().to_string(),
            "d.json: job: is missing: add it (start from a complete design: an example on the page, or `weft new`)"
        );
        assert_eq!(
            Design::from_json("d.json", "{\"name\": \"x\"}").unwrap_err().to_string(),
            "d.json: this is not a weft design: it has no \"version\" (a design starts {\"version\": 1, \"name\": …}; start from an example on the page, or `weft new`)"
        );
        // Nothing of serde's vocabulary is left in any of them.
        for a in ["job.paths.iterations=2.5", "job.paths.method=x", "job.paths.x=1", "job={}", "printer.bed_size_mm=[1]", "seed=\"s\"", "job.lattice.contour=2"]
        {
            let e = set(a);
            for word in ["invalid type", "invalid value", "unknown variant", "unknown field", "missing field", "expected", "u32", "u64", "f64", "line 0", "`"] {
                assert!(!e.contains(word), "{a}: {e}");
            }
        }
    }

    #[test]
    fn wrong_version_says_which() {
        let mut v = serde_json::to_value(Design::default()).unwrap();
        v["version"] = 7.into();
        let e = Design::from_json("d.json", &v.to_string()).unwrap_err();
        assert!(matches!(e, Error::Version { .. }));
        assert!(e.to_string().contains("version 7"));
    }

    #[test]
    fn out_of_range_lists_every_problem() {
        let mut v = serde_json::to_value(Design::default()).unwrap();
        v["job"]["slice"]["infill_density"] = 1.5.into();
        v["printer"]["nozzle_diameter_mm"] = (-1.0).into();
        let e = Design::from_json("d.json", &v.to_string()).unwrap_err();
        let Error::Invalid { problems, .. } = &e else { panic!("{e}") };
        let paths: Vec<&str> = problems.iter().map(|p| p.path.as_str()).collect();
        assert!(paths.contains(&"job.slice.infill_density"), "{paths:?}");
        assert!(paths.contains(&"printer.nozzle_diameter_mm"), "{paths:?}");
        assert!(e.to_string().contains("0 to 1"), "{e}");
    }

    #[test]
    fn overrides_apply_and_validate() {
        let d = Design::default().with_overrides(&["job.slice.layer_height_mm=0.1".into(), "name=part 2".into()]).unwrap();
        let j: crate::kinds::slice::SliceJob = d.job.settings().expect("slice job expected");
        assert_eq!(j.slice.layer_height_mm, 0.1);
        assert_eq!(d.name, "part 2");
        assert!(Design::default().with_overrides(&["job.slice.nonsense=1".into()]).is_err());
        assert!(Design::default().with_overrides(&["job.slice.layer_height_mm=-3".into()]).is_err());
        assert!(Design::default().with_overrides(&["no_equals".into()]).is_err());
        let d = Design::default().with_overrides(&["printer.bed_size_mm.0=300".into()]).unwrap();
        assert_eq!(d.printer.bed_size_mm[0], 300.0);
    }

    #[test]
    fn file_stem_keeps_files_in_their_folder() {
        let long = "x".repeat(10_000);
        let cases: Vec<(&str, &str)> = vec![
            ("cube-20mm", "cube-20mm"),
            ("part 2", "part 2"),
            ("/etc/x", "etc_x"),
            ("../../x", "x"),
            ("..", "design"),
            (".", "design"),
            ("", "design"),
            ("   ", "design"),
            (".bashrc", "bashrc"),
            ("a\\b", "a_b"),
            ("C:\\x", "C_x"),
            ("CON", "_CON"),
            ("nul", "_nul"),
            ("Com1.txt", "_Com1.txt"),
            ("LPT¹", "_LPT¹"),
            ("CONSOLE", "CONSOLE"),
            ("a\0b", "a_b"),
            ("a\nG28\r\nb", "a G28 b"),
            ("-rf", "rf"),
            ("x.", "x"),
            ("a..b", "a.b"),
            ("Würfel 立方体", "Würfel 立方体"),
            ("evil\u{202e}txt", "evil_txt"),
            ("a／b", "a_b"),
            ("~/x", "~_x"),
        ];
        for (name, want) in cases {
            assert_eq!(file_stem(name), want, "{name:?}");
        }
        for name in [long.as_str(), &"é".repeat(5000), &format!("CON.{long}"), &"../".repeat(3000), "\0\0\0", "\u{202e}\u{200b}"] {
            let stem = file_stem(name);
            assert!(!stem.is_empty() && stem.len() <= MAX_FILE_STEM_BYTES, "{} bytes", stem.len());
            assert!(!stem.contains(['/', '\\', ':', '\0']) && !stem.starts_with('.') && stem != "..", "{stem}");
            let joined = std::path::Path::new("folder").join(format!("{stem}.gcode"));
            assert_eq!(joined.parent(), Some(std::path::Path::new("folder")), "{stem}");
            assert!(joined.components().all(|c| matches!(c, std::path::Component::Normal(_))), "{stem}");
        }
    }

    #[test]
    fn every_string_has_a_limit() {
        let base = serde_json::to_value(Design::default()).unwrap();
        let long = |n: usize| "a".repeat(n);
        for (path, limit) in [
            ("name", MAX_NAME_BYTES),
            ("description", MAX_DESCRIPTION_BYTES),
            ("printer.name", crate::settings::MAX_TEXT_BYTES),
            ("material.name", crate::settings::MAX_TEXT_BYTES),
            ("printer.start_gcode", crate::gcode::MAX_TEMPLATE_BYTES),
            ("printer.end_gcode", crate::gcode::MAX_TEMPLATE_BYTES),
            ("printer.pneumatic.valve_on", crate::settings::MAX_TEXT_BYTES),
            ("printer.pneumatic.valve_off", crate::settings::MAX_TEXT_BYTES),
            ("printer.pneumatic.pressure_template", crate::settings::MAX_TEXT_BYTES),
            ("job.input.file.name", MAX_FILE_NAME_BYTES),
            ("job.input.files.0", MAX_FILE_NAME_BYTES),
        ] {
            let mut v = base.clone();
            if path.starts_with("job.input.file.") {
                v["job"]["input"] = serde_json::json!({"file": {"name": "x.stl"}});
            } else if path.starts_with("job.input.files") {
                v["job"]["input"] = serde_json::json!({"files": ["x.stl"]});
            }
            set_path(&mut v, path, long(limit).into()).unwrap();
            Design::from_json("d", &v.to_string()).unwrap_or_else(|e| panic!("{path} at the limit: {e}"));
            set_path(&mut v, path, long(limit + 1).into()).unwrap();
            let e = Design::from_json("d", &v.to_string()).unwrap_err();
            let Error::Invalid { problems, .. } = &e else { panic!("{path}: {e}") };
            assert_eq!(problems.len(), 1, "{path}: {problems:?}");
            assert_eq!(problems[0].path, path);
            let m = &problems[0].message;
            assert!(m.contains(&format!("{} bytes", limit + 1)) && m.contains(&format!("limit of {limit}")), "{path}: {m}");
        }
        // Embedded files: each and in total.
        let mut v = base.clone();
        let big = long(share::MAX_EMBEDDED_CHARS / 2 + 1);
        v["job"]["input"] = serde_json::json!({"file": {"name": "x.stl", "embedded": big}});
        assert!(Design::from_json("d", &v.to_string()).is_ok());
        let mut l = serde_json::to_value(Design::from_json("t", include_str!("../../examples/honeycomb-10mm.json")).unwrap()).unwrap();
        l["job"]["input"] = serde_json::json!({"file": {"name": "a.stl", "embedded": big}});
        l["job"]["surface_input"] = serde_json::json!({"file": {"name": "b.stl", "embedded": big}});
        let e = Design::from_json("d", &l.to_string()).unwrap_err().to_string();
        assert!(e.contains("embedded files total") && e.contains(&share::MAX_EMBEDDED_CHARS.to_string()), "{e}");
        // Too many files.
        v["job"]["input"] = serde_json::json!({"files": vec!["a.dcm"; MAX_INPUT_FILES + 1]});
        let e = Design::from_json("d", &v.to_string()).unwrap_err().to_string();
        assert!(e.contains("job.input.files") && e.contains("10001 files"), "{e}");
        // The whole text.
        let e = Design::from_json("d", &" ".repeat(MAX_DESIGN_BYTES + 1)).unwrap_err();
        assert!(matches!(e, Error::TooLarge { .. }) && e.to_string().contains(&MAX_DESIGN_BYTES.to_string()), "{e}");
    }

    #[test]
    fn names_are_one_line() {
        for (path, bad) in [
            ("name", "x\nG28"),
            ("name", "x\rG28"),
            ("printer.name", "p\u{2028}M84"),
            ("material.name", "m\u{85}"),
            ("name", "tab\there"),
            ("printer.model", "MK4\nG28"),
        ] {
            let mut v = serde_json::to_value(Design::default()).unwrap();
            set_path(&mut v, path, bad.into()).unwrap();
            let e = Design::from_json("d", &v.to_string()).unwrap_err();
            let Error::Invalid { problems, .. } = &e else { panic!("{e}") };
            assert_eq!(problems[0].path, path, "{problems:?}");
            assert!(problems[0].message.contains("control character") && problems[0].message.contains("one line"), "{problems:?}");
        }
        let mut v = serde_json::to_value(Design::default()).unwrap();
        v["job"]["input"] = serde_json::json!({"file": {"name": "a\nb.stl"}});
        assert!(Design::from_json("d", &v.to_string()).unwrap_err().to_string().contains("job.input.file.name"));
    }

    #[test]
    fn messages_quote_hostile_values_short() {
        let huge = "z".repeat(1_000_000);
        let mut v = serde_json::to_value(Design::default()).unwrap();
        v["printer"][huge.as_str()] = 1.into();
        let e = Design::from_json("d", &v.to_string()).unwrap_err().to_string();
        assert!(e.len() < 3000 && e.contains("is not a setting"), "{}", e.len());
        let mut v = serde_json::to_value(Design::default()).unwrap();
        v["printer"]["flavor"] = huge.as_str().into();
        let e = Design::from_json("d", &v.to_string()).unwrap_err().to_string();
        assert!(e.len() < 3000, "{}", e.len());
        v = serde_json::to_value(Design::default()).unwrap();
        v["version"] = huge.as_str().into();
        assert!(Design::from_json("d", &v.to_string()).unwrap_err().to_string().len() < 300);
        v = serde_json::to_value(Design::default()).unwrap();
        v["job"]["kind"] = huge.as_str().into();
        assert!(Design::from_json("d", &v.to_string()).unwrap_err().to_string().len() < 300);
        v = serde_json::to_value(Design::default()).unwrap();
        v["name"] = huge.as_str().into();
        let e = Design::from_json("d", &v.to_string()).unwrap_err().to_string();
        assert!(e.len() < 300 && e.contains("1000000 bytes") && e.contains("limit of 256"), "{e}");
        let e = Design::default().with_overrides(&[format!("{huge}=1")]).unwrap_err().to_string();
        assert!(e.len() < 1000, "{}", e.len());
    }

    #[test]
    fn deep_paths_and_values_are_refused() {
        let e = Design::default().with_overrides(&[crate::testgen::design::deep_set_path(60_000)]).unwrap_err();
        assert!(e.to_string().contains("60000 keys") && e.to_string().contains(&MAX_PATH_DEPTH.to_string()), "{e}");
        // At the limit the path is built, then refused by name.
        let at = crate::testgen::design::deep_set_path(MAX_PATH_DEPTH);
        assert!(Design::default().with_overrides(&[at]).unwrap_err().to_string().contains("is not a setting"));
        // A deep value set by --set is refused cleanly.
        let deep = format!("job.x={}{}", "[".repeat(127), "]".repeat(127));
        assert!(Design::default().with_overrides(&[deep]).is_err());
        let e = Design::from_json("d", &crate::testgen::design::nested_design_json(100_000)).unwrap_err();
        assert!(matches!(e, Error::Syntax { .. }) && e.to_string().contains("nested more than 128 levels deep, the limit"), "{e}");
        // A value built in memory, far deeper than the stack would survive dropping.
        let mut v = Value::Null;
        for _ in 0..1_000_000 {
            v = Value::Array(vec![v]);
        }
        let mut root = serde_json::to_value(Design::default()).unwrap();
        root["job"]["x"] = v;
        let e = Design::from_value("d", root).unwrap_err().to_string();
        assert!(e.contains("job: nested more than 128 levels"), "{e}");
    }
}

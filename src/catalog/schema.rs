//! The schema the page reads: every form row (mounted from the tables the stages own, so form
//! and validators cannot drift apart), the feature table, the job kinds with their stages,
//! slots and views, and the menus' default values. [`validate`] checks a design with the same
//! rows plus each job kind's own rules.

use crate::design::share::MAX_EMBEDDED_CHARS;
use crate::design::{Design, Input, Problem, MAX_DESCRIPTION_BYTES, MAX_FILE_NAME_BYTES, MAX_INPUT_FILES, MAX_NAME_BYTES};
use crate::geom::shapes::Shape;
use crate::geom::Feature;
use crate::kinds::{Registry, Slot, StageInfo, StepInfo, Teach, ViewInfo};
use crate::settings::{self, int, max_len, mount, other, Field, Kind, Row, MAX_TEXT_BYTES};
use serde::Serialize;
use serde_json::Value;

/// Rows of the design's own fields.
pub const DESIGN_FIELDS: &[Field] = &[
    max_len(other("name", "Design", "Name", Kind::Text, &[], "Names the downloaded file and the G-code header."), MAX_NAME_BYTES),
    max_len(other("description", "Design", "Description", Kind::Text, &[], "One line on what the design makes (optional)."), MAX_DESCRIPTION_BYTES),
    other("date", "Design", "Date (UTC)", Kind::Text, &[], "YYYY-MM-DD HH:MM:SS: when the design was made or last changed; the G-code header's date."),
    int("seed", "Design", "Random seed", 0.0, 9.007199254740991e15, "Seeds every random choice: the same seed gives the same G-code."),
];

/// Stages every job ends with (the pipeline's own).
pub const WRITER_STAGES: &[StageInfo] = &[StageInfo { name: "gcode", label: "Writing G-code" }, StageInfo { name: "analyze", label: "Measuring the G-code" }];

/// The rows shared by every job kind (design, printer, material, speeds).
pub fn common_rows() -> Vec<Row> {
    let mut rows = mount("", DESIGN_FIELDS);
    rows.extend(mount("printer", crate::gcode::PRINTER_FIELDS));
    rows.extend(mount("material", crate::gcode::MATERIAL_FIELDS));
    rows.extend(mount("speeds", crate::gcode::SPEED_FIELDS));
    rows
}

/// Every row: the common ones, then each kind's (tagged with the kind).
pub fn rows(registry: &Registry) -> Vec<Row> {
    let mut rows = common_rows();
    for k in registry.kinds() {
        rows.extend(k.fields());
    }
    rows
}

/// A feature as the page shows it.
#[derive(Serialize)]
pub struct FeatureInfo {
    /// Code in preview buffers.
    pub code: u8,
    /// JSON key.
    pub key: &'static str,
    /// `;TYPE:` name.
    pub name: &'static str,
    /// Label.
    pub label: &'static str,
    /// `#rrggbb`.
    pub color: &'static str,
}

/// A job kind as the page shows it.
#[derive(Serialize)]
pub struct JobInfo {
    /// `job.kind`.
    pub name: &'static str,
    /// Label.
    pub label: &'static str,
    /// One line on what it makes.
    pub doc: &'static str,
    /// Stages in run order, the writer's included.
    pub stages: Vec<StageInfo>,
    /// Input slots.
    pub slots: Vec<SlotInfo>,
    /// Extra views.
    pub views: &'static [ViewInfo],
    /// The method's steps ("How it works"), each drawn by one of `views`.
    pub steps: &'static [StepInfo],
    /// How the page first shows a result (colouring, backdrop view).
    pub teach: Teach,
}

/// A slot as the page shows it.
#[derive(Serialize)]
pub struct SlotInfo {
    /// The slot.
    #[serde(flatten)]
    pub slot: Slot,
    /// Accepted extensions.
    pub accept: &'static [&'static str],
    /// Several files at once.
    pub multiple: bool,
}

/// A menu entry with the JSON value it puts in the design.
#[derive(Serialize)]
pub struct Choice {
    /// Name.
    #[serde(rename = "kind")]
    pub name: &'static str,
    /// Label.
    pub label: String,
    /// The value.
    pub value: serde_json::Value,
}

/// Everything the page builds itself from.
#[derive(Serialize)]
pub struct Schema {
    /// Design format version.
    pub version: u32,
    /// Form rows.
    pub fields: Vec<Row>,
    /// Features (index = code).
    pub features: Vec<FeatureInfo>,
    /// Job kinds.
    pub job_kinds: Vec<JobInfo>,
    /// Built-in shapes with their default sizes.
    pub builtin_shapes: Vec<Choice>,
    /// Lattice patterns with their default sizes.
    pub patterns: Vec<Choice>,
    /// Output flavours: `printer.flavor` value → file extension (the download's name).
    pub flavors: Vec<FlavorInfo>,
    /// Printer profiles (the page's printer picker; `weft run --printer ID`).
    pub printer_presets: Vec<crate::gcode::presets::Preset>,
}

/// An output flavour as the page names its downloads.
#[derive(Serialize)]
pub struct FlavorInfo {
    /// `printer.flavor` value.
    pub name: String,
    /// File extension without the dot.
    pub extension: &'static str,
}

/// The schema of `registry`'s job kinds.
pub fn schema(registry: &Registry) -> Schema {
    let features =
        Feature::ALL.iter().map(|f| FeatureInfo { code: f.code(), key: f.key(), name: f.gcode_name(), label: f.gcode_name(), color: f.color() }).collect();
    let job_kinds = registry
        .kinds()
        .iter()
        .map(|k| JobInfo {
            name: k.name(),
            label: k.label(),
            doc: k.doc(),
            stages: k.stages().iter().chain(WRITER_STAGES).copied().collect(),
            slots: k.slots().iter().map(|s| SlotInfo { slot: *s, accept: s.kind.accept(), multiple: s.kind.multiple() }).collect(),
            views: k.views(),
            steps: k.steps(),
            teach: k.teach(),
        })
        .collect();
    let builtin_shapes = Shape::defaults()
        .into_iter()
        .map(|(name, label, shape)| Choice { name, label: label.into(), value: serde_json::to_value(Input::Builtin(shape)).unwrap_or_default() })
        .collect();
    let patterns = crate::lattice::PATTERNS
        .iter()
        .map(|name| Choice {
            name,
            label: name.replace('_', " "),
            value: serde_json::from_value::<crate::lattice::Pattern>(serde_json::json!({ "kind": name }))
                .ok()
                .and_then(|p| serde_json::to_value(p).ok())
                .unwrap_or_default(),
        })
        .collect();
    let flavors = [crate::gcode::Flavor::Marlin, crate::gcode::Flavor::Pneumatic, crate::gcode::Flavor::PosesCsv]
        .into_iter()
        .map(|f| FlavorInfo {
            name: serde_json::to_value(f).ok().and_then(|v| v.as_str().map(String::from)).unwrap_or_default(),
            extension: f.file_extension(),
        })
        .collect();
    let printer_presets = crate::gcode::presets::presets();
    Schema { version: crate::design::DESIGN_VERSION, fields: rows(registry), features, job_kinds, builtin_shapes, patterns, flavors, printer_presets }
}

/// The schema as JSON (the CLI's `weft schema`, tests).
pub fn schema_json() -> String {
    serde_json::to_string(&schema(&Registry::builtin())).unwrap_or_default()
}

/// Range checks from the rows plus the rules that tie fields together (the job kind's own).
pub fn validate(design: &Design, registry: &Registry) -> Vec<Problem> {
    let mut out = Vec::new();
    let Ok(root) = serde_json::to_value(design) else { return out };
    settings::check_rows(&root, &common_rows(), &mut out);
    if design.name.trim().is_empty() {
        out.push(Problem { path: "name".into(), message: "is empty: give the design a name".into() });
    }
    let Some(kind) = registry.get(design.job.kind()) else {
        out.push(Problem { path: "job.kind".into(), message: format!("unknown job kind; use one of {}", registry.names().join(", ")) });
        return out;
    };
    let kind_rows = kind.fields();
    settings::check_rows(&root, &kind_rows, &mut out);
    check_strings(&root, &[common_rows(), kind_rows].concat(), &mut out);
    for path in ["name", "description", "printer.name", "material.name", "printer.model"] {
        // A name over its length limit is refused for that already.
        if let Some(Value::String(s)) = path.split('.').try_fold(&root, |v, k| v.get(k)).filter(|v| v.as_str().is_some_and(|s| s.len() <= MAX_NAME_BYTES)) {
            out.extend(one_line(path, s, "a name"));
        }
    }
    if !design.date.is_empty() && !crate::gcode::is_date(&design.date) {
        out.push(Problem {
            path: "date".into(),
            message: format!("'{}' is not a date YYYY-MM-DD HH:MM:SS (UTC), e.g. 2026-12-06 14:30:00; or leave it empty", design.date.escape_debug()),
        });
    }
    for slot in kind.slots() {
        if let Some(Input::File { name, .. }) = design.job.input_at(slot.path) {
            if name.trim().is_empty() {
                out.push(Problem { path: format!("{}.file.name", slot.path), message: format!("is empty: name the file of the {} input", slot.label) });
            }
        }
    }
    kind.validate(design, &design.job.value, &mut out);
    out
}

/// Every string of the design within its length limit: a text row's own (checked with the rows),
/// file names [`MAX_FILE_NAME_BYTES`] and one line, embedded files [`MAX_EMBEDDED_CHARS`] in
/// total, a slot's file list [`MAX_INPUT_FILES`] long; any other string (kinds, choices, and
/// whatever a job kind adds) [`MAX_TEXT_BYTES`]. Walks the tree with its own stack.
fn check_strings(root: &Value, rows: &[Row], out: &mut Vec<Problem>) {
    let mut stack: Vec<(String, &Value)> = vec![(String::new(), root)];
    let mut embedded = 0usize;
    while let Some((path, v)) = stack.pop() {
        let (parent, key) = match path.rsplit_once('.') {
            Some((p, k)) => (p.rsplit('.').next().unwrap_or(p), k),
            None => ("", path.as_str()),
        };
        match v {
            // Checked with its row.
            Value::String(_) if rows.iter().any(|r| r.path == path) => {}
            Value::String(s) if parent == "file" && key == "embedded" => {
                embedded += s.len();
                out.extend(settings::text_too_long(&path, s, MAX_EMBEDDED_CHARS, "the embedded file"));
            }
            Value::String(s) if (parent == "file" && key == "name") || parent == "files" => {
                match settings::text_too_long(&path, s, MAX_FILE_NAME_BYTES, "the file name") {
                    Some(p) => out.push(p),
                    None => out.extend(one_line(&path, s, "a file name")),
                }
            }
            Value::String(s) => out.extend(settings::text_too_long(&path, s, MAX_TEXT_BYTES, "the text")),
            Value::Array(items) => {
                if key == "files" && items.len() > MAX_INPUT_FILES {
                    out.push(Problem {
                        path: path.clone(),
                        message: format!(
                            "{} files, over the limit of {MAX_INPUT_FILES} in one input: load fewer (e.g. every other slice of a series)",
                            items.len()
                        ),
                    });
                }
                let join = |i: usize| if path.is_empty() { i.to_string() } else { format!("{path}.{i}") };
                stack.extend(items.iter().enumerate().rev().map(|(i, c)| (join(i), c)));
            }
            Value::Object(map) => {
                let join = |k: &str| if path.is_empty() { k.to_string() } else { format!("{path}.{k}") };
                let children: Vec<_> = map.iter().map(|(k, c)| (join(k), c)).collect();
                stack.extend(children.into_iter().rev());
            }
            _ => {}
        }
    }
    if embedded > MAX_EMBEDDED_CHARS {
        out.push(Problem {
            path: "job".into(),
            message: format!(
                "the embedded files total {embedded} characters, over the limit of {MAX_EMBEDDED_CHARS}: a share link carries at most {} KiB of files; load the files instead",
                super::share::MAX_EMBED_BYTES / 1024
            ),
        });
    }
}

/// The problem of a line break or another control character in `s`, a one-line name (it
/// would start a new line in the G-code header or a `{design_name}` placeholder).
fn one_line(path: &str, s: &str, what: &str) -> Option<Problem> {
    let (i, c) = s.chars().enumerate().find(|(_, c)| c.is_control() || matches!(c, '\u{2028}' | '\u{2029}'))?;
    Some(Problem {
        path: path.to_string(),
        message: format!("has a control character (U+{:04X}) at character {}: {what} is one line of text; remove it", c as u32, i + 1),
    })
}

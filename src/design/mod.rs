//! The Design document: one versioned JSON file that describes a whole job.
//!
//! The page edits it, the share URL carries it ([`share`]), the CLI runs it. Parsing rejects
//! unknown fields and wrong versions; [`Design::validate`] lists every out-of-range value
//! with its field path and the allowed range (ranges live in one table, [`schema`]).

pub mod schema;
pub mod share;

use crate::gcode::{Material, Printer, Speeds};
use crate::geom::shapes::Shape;
use serde::{Deserialize, Serialize};
use serde_json::Value;
use crate::jobs::Registry;

pub use crate::settings::Problem;

/// The only version this build reads and writes.
pub const DESIGN_VERSION: u32 = 1;

/// A whole job.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Design {
    /// Format version; must be [`DESIGN_VERSION`].
    pub version: u32,
    /// Name, used for the output file (`<name>.gcode`).
    pub name: String,
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
/// ([`crate::jobs::JobKind::normalize`]: every default filled in, unknown fields refused).
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
        crate::jobs::settings(&self.value).ok()
    }

    /// A job of kind `kind` with `settings`.
    pub fn new(kind: &str, settings: &impl Serialize) -> Job {
        Job { value: crate::jobs::with_kind(kind, settings).unwrap_or(Value::Null) }
    }

    /// The input at the design path `path` (a slot's path, e.g. `job.input`).
    pub fn input_at(&self, path: &str) -> Option<Input> {
        let rel = path.strip_prefix("job.")?;
        let v = rel.split('.').try_fold(&self.value, |v, k| v.get(k))?;
        serde_json::from_value(v.clone()).ok()
    }
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
            _ => Err(serde::de::Error::custom("job needs a \"kind\" (e.g. \"slice\" or \"lattice\")")),
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
    /// Not JSON, or fields of the wrong type / unknown fields.
    #[error("{source_name}: line {line}, column {column}: {message}")]
    Syntax {
        /// Where it came from (file name, "share link", ...).
        source_name: String,
        /// 1-based line.
        line: usize,
        /// 1-based column.
        column: usize,
        /// serde's message (names the field).
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
    /// Values out of range (all of them listed).
    #[error("{source_name}: {}", problems.iter().map(|p| format!("{}: {}", p.path, p.message)).collect::<Vec<_>>().join("\n"))]
    Invalid {
        /// Where it came from.
        source_name: String,
        /// Every problem.
        problems: Vec<Problem>,
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

impl Default for Design {
    fn default() -> Self {
        Design {
            version: DESIGN_VERSION,
            name: "cube-20mm".into(),
            seed: 1,
            printer: Printer::default(),
            material: Material::default(),
            speeds: Speeds::default(),
            job: Job::new("slice", &crate::jobs::slice::SliceJob::default()),
        }
    }
}

impl Design {
    /// Parses and validates a design with the built-in job kinds. `source_name` names it in
    /// messages.
    pub fn from_json(source_name: &str, text: &str) -> Result<Design, Error> {
        Design::from_json_in(&Registry::builtin(), source_name, text)
    }

    /// Parses and validates a design whose job kind is one of `registry`'s.
    pub fn from_json_in(registry: &Registry, source_name: &str, text: &str) -> Result<Design, Error> {
        let syntax = |e: serde_json::Error| Error::Syntax {
            source_name: source_name.into(),
            line: e.line(),
            column: e.column(),
            message: strip_position(&e.to_string()),
        };
        let value: Value = serde_json::from_str(text).map_err(syntax)?;
        check_version(source_name, &value)?;
        let design: Design = serde_json::from_str(text).map_err(syntax)?;
        design.normalized(registry, source_name)?.validated(registry, source_name)
    }

    /// Builds a design from a JSON value (used after overrides).
    pub fn from_value(source_name: &str, value: Value) -> Result<Design, Error> {
        Design::from_value_in(&Registry::builtin(), source_name, value)
    }

    /// [`Design::from_value`] with the job kinds of `registry`.
    pub fn from_value_in(registry: &Registry, source_name: &str, value: Value) -> Result<Design, Error> {
        check_version(source_name, &value)?;
        let design: Design = serde_json::from_value(value).map_err(|e| Error::Syntax {
            source_name: source_name.into(),
            line: 0,
            column: 0,
            message: strip_position(&e.to_string()),
        })?;
        design.normalized(registry, source_name)?.validated(registry, source_name)
    }

    /// The job object rewritten by its kind: defaults filled in, unknown fields refused.
    fn normalized(mut self, registry: &Registry, source_name: &str) -> Result<Design, Error> {
        let syntax = |message: String| Error::Syntax { source_name: source_name.into(), line: 0, column: 0, message };
        let kind = registry.get(self.job.kind()).ok_or_else(|| {
            syntax(format!("job.kind: unknown job kind '{}'; use one of {}", self.job.kind(), registry.names().join(", ")))
        })?;
        self.job.value = kind.normalize(&self.job.value).map_err(|e| syntax(format!("job: {}", strip_position(&e.to_string()))))?;
        Ok(self)
    }

    /// Pretty JSON (the on-disk form).
    pub fn to_json_pretty(&self) -> String {
        serde_json::to_string_pretty(self).unwrap_or_default() + "\n"
    }

    /// Every out-of-range value, empty when the design is valid.
    pub fn validate(&self) -> Vec<Problem> {
        schema::validate(self, &Registry::builtin())
    }

    fn validated(self, registry: &Registry, source_name: &str) -> Result<Design, Error> {
        let problems = schema::validate(&self, registry);
        if problems.is_empty() {
            Ok(self)
        } else {
            Err(Error::Invalid { source_name: source_name.into(), problems })
        }
    }

    /// Applies `path=value` overrides (e.g. `job.slice.infill_density=0.3`). The value is read
    /// as JSON when it parses (numbers, booleans, objects), else as a string.
    pub fn with_overrides(&self, assignments: &[String]) -> Result<Design, Error> {
        self.with_overrides_in(&Registry::builtin(), assignments)
    }

    /// [`Design::with_overrides`] with the job kinds of `registry`.
    pub fn with_overrides_in(&self, registry: &Registry, assignments: &[String]) -> Result<Design, Error> {
        let mut value = serde_json::to_value(self).map_err(|e| Error::Override {
            assignment: String::new(),
            message: e.to_string(),
        })?;
        for a in assignments {
            let (path, raw) = a.split_once('=').ok_or_else(|| Error::Override {
                assignment: a.clone(),
                message: "expected PATH=VALUE, e.g. job.slice.layer_height_mm=0.1".into(),
            })?;
            let new: Value = serde_json::from_str(raw).unwrap_or_else(|_| Value::String(raw.to_string()));
            set_path(&mut value, path.trim(), new)
                .map_err(|message| Error::Override { assignment: a.clone(), message })?;
        }
        Design::from_value_in(registry, "--set", value)
    }

    /// The design with `input` in the slot at design path `slot_path` (e.g. `job.input`),
    /// after the job kind's own rule for a filled slot (a lattice fills a loaded solid).
    pub fn with_slot_input(&self, registry: &Registry, slot: &str, input: Input) -> Result<Design, Error> {
        let kind_name = self.job.kind().to_string();
        let kind = registry.get(&kind_name).ok_or_else(|| Error::Override { assignment: slot.into(), message: format!("unknown job kind '{kind_name}'") })?;
        let spec = kind.slots().iter().find(|s| s.name == slot).ok_or_else(|| Error::Override {
            assignment: slot.into(),
            message: format!(
                "a {kind_name} job has no input slot '{slot}'; its slots are {}",
                if kind.slots().is_empty() { "none".to_string() } else { kind.slots().iter().map(|s| s.name).collect::<Vec<_>>().join(", ") }
            ),
        })?;
        let mut value = serde_json::to_value(self).unwrap_or(Value::Null);
        let new = serde_json::to_value(&input).unwrap_or(Value::Null);
        set_path(&mut value, spec.path, new).map_err(|message| Error::Override { assignment: slot.into(), message })?;
        let job = value.get("job").cloned().unwrap_or(Value::Null);
        value["job"] = kind.slot_filled(slot, job);
        Design::from_value_in(registry, "design", value)
    }
}

fn check_version(source_name: &str, value: &Value) -> Result<(), Error> {
    match value.get("version") {
        Some(v) if v.as_u64() == Some(DESIGN_VERSION as u64) => Ok(()),
        Some(v) => Err(Error::Version { source_name: source_name.into(), found: v.to_string() }),
        None => Err(Error::Version { source_name: source_name.into(), found: "(missing)".into() }),
    }
}

/// serde_json appends " at line L column C"; the error variant carries those separately.
fn strip_position(msg: &str) -> String {
    match msg.rfind(" at line ") {
        Some(i) => msg[..i].to_string(),
        None => msg.to_string(),
    }
}

/// Sets a dotted path in a JSON tree, creating objects on the way (unknown names are then
/// rejected by deserialisation, which names them).
pub(crate) fn set_path(root: &mut Value, path: &str, new: Value) -> Result<(), String> {
    if path.is_empty() {
        return Err("empty field path".into());
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
                let idx: usize = part
                    .parse()
                    .map_err(|_| format!("'{}' is a list; use an index like {}.0", parts[..i].join("."), parts[..i].join(".")))?;
                let len = items.len();
                let slot = items
                    .get_mut(idx)
                    .ok_or_else(|| format!("index {idx} is outside the list of {len}"))?;
                if last {
                    *slot = new;
                    return Ok(());
                }
                cur = slot;
            }
            _ => return Err(format!("'{}' is not an object", parts[..i].join("."))),
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
        let d = Design::default()
            .with_overrides(&["job.slice.layer_height_mm=0.1".into(), "name=part 2".into()])
            .unwrap();
        let j: crate::jobs::slice::SliceJob = d.job.settings().expect("slice job expected");
        assert_eq!(j.slice.layer_height_mm, 0.1);
        assert_eq!(d.name, "part 2");
        assert!(Design::default().with_overrides(&["job.slice.nonsense=1".into()]).is_err());
        assert!(Design::default().with_overrides(&["job.slice.layer_height_mm=-3".into()]).is_err());
        assert!(Design::default().with_overrides(&["no_equals".into()]).is_err());
        let d = Design::default().with_overrides(&["printer.bed_size_mm.0=300".into()]).unwrap();
        assert_eq!(d.printer.bed_size_mm[0], 300.0);
    }
}

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

/// The kinds of job. Each later kind is one more variant with its own settings struct.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Job {
    /// Slice a solid: perimeters plus rectilinear infill.
    Slice(SliceJob),
    /// A lattice from the atlas, printed along optimised paths (GIPPO), optionally non-planar.
    Lattice(LatticeJob),
}

impl Job {
    /// The kind's name as written in JSON.
    pub fn kind(&self) -> &'static str {
        match self {
            Job::Slice(_) => "slice",
            Job::Lattice(_) => "lattice",
        }
    }

    /// The job's main input, if it has one.
    pub fn input(&self) -> Option<&Input> {
        match self {
            Job::Slice(j) => Some(&j.input),
            Job::Lattice(j) => j.input.as_ref(),
        }
    }

    /// Mutable main input.
    pub fn input_mut(&mut self) -> Option<&mut Input> {
        match self {
            Job::Slice(j) => Some(&mut j.input),
            Job::Lattice(j) => j.input.as_mut(),
        }
    }

    /// Replaces the main input (`--input`, a file dropped on the page). A lattice job then fills
    /// the layers of that solid (its domain becomes `solid`).
    pub fn set_input(&mut self, input: Input) {
        match self {
            Job::Slice(j) => j.input = input,
            Job::Lattice(j) => {
                j.input = Some(input);
                j.domain = crate::lattice::Domain::Solid;
            }
        }
    }
}

/// Settings of a `slice` job.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SliceJob {
    /// The solid to slice. Default: a 20 mm cube.
    #[serde(default = "default_slice_input")]
    pub input: Input,
    /// Layer heights, perimeters, infill.
    #[serde(default)]
    pub slice: crate::slice::Options,
}

/// Settings of a `lattice` job.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LatticeJob {
    /// Where the lattice goes: a built-in planar domain, or the layers of `input`.
    #[serde(default)]
    pub domain: crate::lattice::Domain,
    /// The solid whose layers are filled when `domain` is `solid`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub input: Option<Input>,
    /// Pattern, layers, rotation, overrides, contour.
    #[serde(default)]
    pub lattice: crate::lattice::Options,
    /// Path optimisation.
    #[serde(default)]
    pub paths: crate::paths::Options,
    /// Projection onto a non-planar surface (off when absent).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub nonplanar: Option<crate::nonplanar::Options>,
    /// The surface mesh when `nonplanar.surface` is `mesh`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub surface_input: Option<Input>,
}

fn default_slice_input() -> Input {
    Input::Builtin(Shape::Cube { size: [20.0, 20.0, 20.0] })
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
}

/// One problem found in a design.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Problem {
    /// Dotted field path, e.g. `printer.nozzle_diameter_mm`.
    pub path: String,
    /// What is wrong and what is allowed.
    pub message: String,
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
            job: Job::Slice(SliceJob { input: default_slice_input(), slice: Default::default() }),
        }
    }
}

impl Design {
    /// Parses and validates a design. `source_name` names it in messages.
    pub fn from_json(source_name: &str, text: &str) -> Result<Design, Error> {
        let syntax = |e: serde_json::Error| Error::Syntax {
            source_name: source_name.into(),
            line: e.line(),
            column: e.column(),
            message: strip_position(&e.to_string()),
        };
        let value: Value = serde_json::from_str(text).map_err(syntax)?;
        check_version(source_name, &value)?;
        let design: Design = serde_json::from_str(text).map_err(syntax)?;
        design.validated(source_name)
    }

    /// Builds a design from a JSON value (used after overrides).
    pub fn from_value(source_name: &str, value: Value) -> Result<Design, Error> {
        check_version(source_name, &value)?;
        let design: Design = serde_json::from_value(value).map_err(|e| Error::Syntax {
            source_name: source_name.into(),
            line: 0,
            column: 0,
            message: strip_position(&e.to_string()),
        })?;
        design.validated(source_name)
    }

    /// Pretty JSON (the on-disk form).
    pub fn to_json_pretty(&self) -> String {
        serde_json::to_string_pretty(self).unwrap_or_default() + "\n"
    }

    /// Every out-of-range value, empty when the design is valid.
    pub fn validate(&self) -> Vec<Problem> {
        schema::validate(self)
    }

    fn validated(self, source_name: &str) -> Result<Design, Error> {
        let problems = self.validate();
        if problems.is_empty() {
            Ok(self)
        } else {
            Err(Error::Invalid { source_name: source_name.into(), problems })
        }
    }

    /// Applies `path=value` overrides (e.g. `job.slice.infill_density=0.3`). The value is read
    /// as JSON when it parses (numbers, booleans, objects), else as a string.
    pub fn with_overrides(&self, assignments: &[String]) -> Result<Design, Error> {
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
        Design::from_value("--set", value)
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
        let Job::Slice(j) = &d.job else { panic!("slice job expected") };
        assert_eq!(j.slice.layer_height_mm, 0.1);
        assert_eq!(d.name, "part 2");
        assert!(Design::default().with_overrides(&["job.slice.nonsense=1".into()]).is_err());
        assert!(Design::default().with_overrides(&["job.slice.layer_height_mm=-3".into()]).is_err());
        assert!(Design::default().with_overrides(&["no_equals".into()]).is_err());
        let d = Design::default().with_overrides(&["printer.bed_size_mm.0=300".into()]).unwrap();
        assert_eq!(d.printer.bed_size_mm[0], 300.0);
    }
}

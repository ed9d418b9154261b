//! The design document checked against the job kinds ([`crate::kinds::Registry`]): reading
//! (syntax, fields, each kind's settings and rules), changes (`--set`, slot inputs) validated
//! once, and the default design. Methods of [`Design`] live here, above the kinds, so the
//! document itself ([`crate::design`]) knows no kind.

use super::schema;
use crate::design::words;
use crate::design::{drop_flat, set_path, too_deep, Design, Error, Input, Job, Problem, DESIGN_VERSION, MAX_DESIGN_BYTES, MAX_JSON_DEPTH, MAX_QUOTE_CHARS};
use crate::gcode::{Material, Printer, Speeds};
use crate::kinds::Registry;
use crate::settings::clip;
use serde_json::Value;

impl Default for Design {
    fn default() -> Self {
        Design {
            version: DESIGN_VERSION,
            name: "cube-20mm".into(),
            description: String::new(),
            date: String::new(),
            seed: 1,
            printer: Printer::default(),
            material: Material::default(),
            speeds: Speeds::default(),
            job: Job::new("slice", &crate::kinds::slice::SliceJob::default()),
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
        Design::parse(registry, source_name, text, true)
    }

    /// Parses a design (syntax, fields, ranges of single values) without the checks across
    /// fields that its inputs and overrides may still satisfy (a route that edits a G-code
    /// the command line gives): for a front end that applies them with
    /// [`Design::with_changes_in`], which validates the result once.
    pub fn from_json_draft(source_name: &str, text: &str) -> Result<Design, Error> {
        Design::parse(&Registry::builtin(), source_name, text, false)
    }

    fn parse(registry: &Registry, source_name: &str, text: &str, validate: bool) -> Result<Design, Error> {
        if text.len() > MAX_DESIGN_BYTES {
            return Err(Error::TooLarge { source_name: source_name.into(), bytes: text.len() });
        }
        let value: Value = serde_json::from_str(text).map_err(|e| Error::Syntax {
            source_name: source_name.into(),
            line: e.line(),
            column: e.column(),
            message: format!("not valid JSON: {}", words::syntax(&e)),
        })?;
        Design::from_value_checked(registry, source_name, value, validate)
    }

    /// Builds a design from a JSON value (used after overrides).
    pub fn from_value(source_name: &str, value: Value) -> Result<Design, Error> {
        Design::from_value_in(&Registry::builtin(), source_name, value)
    }

    /// [`Design::from_value`] with the job kinds of `registry`.
    pub fn from_value_in(registry: &Registry, source_name: &str, value: Value) -> Result<Design, Error> {
        Design::from_value_checked(registry, source_name, value, true)
    }

    fn from_value_checked(registry: &Registry, source_name: &str, value: Value, validate: bool) -> Result<Design, Error> {
        if let Some(top) = too_deep(&value, MAX_JSON_DEPTH) {
            drop_flat(value);
            let place = if top.is_empty() { "the design".to_string() } else { clip(&top, MAX_QUOTE_CHARS).into_owned() };
            let message = format!("{place}: nested more than {MAX_JSON_DEPTH} levels deep, the limit; a design is only a few levels deep");
            return Err(Error::Syntax { source_name: source_name.into(), line: 0, column: 0, message });
        }
        check_version(source_name, &value)?;
        // The design's and its kind's form rows: a wrong value is named by its field's label.
        let mut rows = schema::common_rows();
        let kind_name = value.get("job").and_then(|j| j.get("kind")).and_then(Value::as_str).unwrap_or("");
        if let Some(kind) = registry.get(kind_name) {
            rows.extend(kind.fields());
        }
        let invalid = |p: Problem| Error::Invalid { source_name: source_name.into(), problems: vec![p] };
        let mut design: Design = serde_path_to_error::deserialize(&value).map_err(|e| invalid(words::problem(&e, "", &value, &rows)))?;
        let kind = registry
            .get(design.job.kind())
            .ok_or_else(|| invalid(Problem { path: "job.kind".into(), message: words::not_a_choice(design.job.kind(), "the job kind", &registry.names()) }))?;
        design.job.value = kind.normalize(&design.job.value).map_err(|e| invalid(words::problem(&e, "job", &value, &rows)))?;
        if validate {
            design.validated(registry, source_name)
        } else {
            Ok(design)
        }
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
        self.with_changes_from(registry, "--set", &[], assignments)
    }

    /// The job kind after `assignments` (a `job.kind=…` among them switches it).
    pub fn kind_after(&self, assignments: &[String]) -> String {
        let set = assignments.iter().rev().find_map(|a| a.split_once('=').filter(|(p, _)| p.trim() == "job.kind").map(|(_, v)| v));
        match set {
            Some(raw) => serde_json::from_str::<String>(raw).unwrap_or_else(|_| raw.to_string()),
            None => self.job.kind().to_string(),
        }
    }

    /// The design with `inputs` (slot name, input) in their slots and `assignments` applied,
    /// validated once at the end, as the page does: a setting that needs a file (a route that
    /// edits a loaded G-code) may come with it, in either order. Assignments are applied
    /// before the inputs (a `job.kind=…` picks the slots) and again after them (so a value
    /// given wins over a slot's rule, and a row that a file adds can be set).
    pub fn with_changes_in(&self, registry: &Registry, inputs: &[(String, Input)], assignments: &[String]) -> Result<Design, Error> {
        let source = if assignments.is_empty() { "design" } else { "--set" };
        self.with_changes_from(registry, source, inputs, assignments)
    }

    /// [`Design::with_changes_in`], problems named after `source_name` (the design's file).
    pub fn with_changes_from(&self, registry: &Registry, source_name: &str, inputs: &[(String, Input)], assignments: &[String]) -> Result<Design, Error> {
        let mut value = serde_json::to_value(self).map_err(|e| Error::Override { assignment: String::new(), message: e.to_string() })?;
        let apply = |value: &mut Value, strict: bool| -> Result<(), Error> {
            for a in assignments {
                let assignment = || clip(a, 200).into_owned();
                let (path, raw) = a
                    .split_once('=')
                    .ok_or_else(|| Error::Override { assignment: assignment(), message: "expected PATH=VALUE, e.g. job.slice.layer_height_mm=0.1".into() })?;
                let new: Value = serde_json::from_str(raw).unwrap_or_else(|_| Value::String(raw.to_string()));
                let before = value.pointer("/job/kind").cloned();
                match set_path(value, path.trim(), new) {
                    Ok(()) => {}
                    Err(message) if strict => return Err(Error::Override { assignment: assignment(), message }),
                    Err(_) => continue,
                }
                // A switch of job kind lets the new kind put what it needs in place.
                let after = value.pointer("/job/kind").cloned();
                if after != before {
                    if let Some(k) = after.as_ref().and_then(Value::as_str).and_then(|k| registry.get(k)) {
                        k.adopted(value);
                    }
                }
            }
            Ok(())
        };
        apply(&mut value, false)?;
        let kind_name = value.pointer("/job/kind").and_then(Value::as_str).unwrap_or("").to_string();
        if let Some((first, _)) = inputs.first() {
            let kind =
                registry.get(&kind_name).ok_or_else(|| Error::Override { assignment: first.clone(), message: format!("unknown job kind '{kind_name}'") })?;
            for (slot, input) in inputs {
                let spec = kind.slots().iter().find(|s| s.name == slot).ok_or_else(|| Error::Override {
                    assignment: slot.clone(),
                    message: format!(
                        "a {kind_name} job has no input slot '{slot}'; its slots are {}",
                        if kind.slots().is_empty() { "none".to_string() } else { kind.slots().iter().map(|s| s.name).collect::<Vec<_>>().join(", ") }
                    ),
                })?;
                let new = serde_json::to_value(input).unwrap_or(Value::Null);
                set_path(&mut value, spec.path, new).map_err(|message| Error::Override { assignment: slot.clone(), message })?;
                let job = value.get("job").cloned().unwrap_or(Value::Null);
                value["job"] = kind.slot_filled(slot, job);
            }
        }
        apply(&mut value, true)?;
        Design::from_value_in(registry, source_name, value)
    }

    /// The design with `input` in the slot at design path `slot_path` (e.g. `job.input`),
    /// after the job kind's own rule for a filled slot (a lattice fills a loaded solid).
    pub fn with_slot_input(&self, registry: &Registry, slot: &str, input: Input) -> Result<Design, Error> {
        self.with_changes_in(registry, &[(slot.to_string(), input)], &[])
    }
}

fn check_version(source_name: &str, value: &Value) -> Result<(), Error> {
    match value.get("version") {
        Some(v) if v.as_u64() == Some(DESIGN_VERSION as u64) => Ok(()),
        Some(v) => Err(Error::Version { source_name: source_name.into(), found: clip(&v.to_string(), MAX_QUOTE_CHARS).into_owned() }),
        None => Err(Error::NotADesign { source_name: source_name.into() }),
    }
}

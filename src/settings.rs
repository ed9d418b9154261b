//! Settings tables: one row per editable field with its unit, range and help.
//!
//! Each stage declares the rows of its own `Options` (paths relative to that struct) next to
//! the struct, and checks its options against them ([`check`]); a job kind mounts its stages'
//! rows under the design paths where their options live ([`mount`]). The page's form, the
//! CLI's `--set` and the stage validators therefore read the same ranges from one place.

use serde::Serialize;
use serde_json::Value;

/// How a field is edited.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Kind {
    /// A real number.
    Number,
    /// A whole number.
    Integer,
    /// On/off.
    Bool,
    /// Free text (multi-line for G-code templates).
    Text,
    /// One of `choices`.
    Choice,
    /// Three numbers (X, Y, Z).
    Vec3,
    /// A list of 2-D points `[[a, b], …]` (a control polygon, a domain outline); `min`/`max`
    /// bound every number, `max_len` the number of points. The page edits it as lines `a b`.
    Points,
    /// Several closed rings of 2-D points `[[[a, b], …], …]` (holes of a domain); `min`/`max`
    /// bound every number, `max_len` the points of all rings together. The page edits it as
    /// lines `a b`, a blank line between rings.
    Rings,
    /// An optional block, present or absent (a checkbox); `default` is its JSON when switched on.
    Section,
}

/// A condition on another field's value (paths relative to the same table).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct When {
    /// Dotted path of the other field.
    pub path: &'static str,
    /// The value it must have (as written in JSON).
    pub equals: &'static str,
}

/// One editable field, as a stage declares it (path relative to its options struct).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Field {
    /// Dotted path, relative to the table's struct (not serialised: a mounted [`Row`] writes
    /// its absolute path).
    #[serde(skip)]
    pub path: &'static str,
    /// Form section.
    pub section: &'static str,
    /// Label shown in the form.
    pub label: &'static str,
    /// Unit shown after the input ("" when none).
    pub unit: &'static str,
    /// Editor kind.
    pub kind: Kind,
    /// Smallest allowed value (numbers, each Vec3 component).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub min: Option<f64>,
    /// Largest allowed value.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max: Option<f64>,
    /// Form step.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub step: Option<f64>,
    /// Allowed values of a choice.
    #[serde(skip_serializing_if = "<[_]>::is_empty")]
    pub choices: &'static [&'static str],
    /// One line of plain words per choice (what picking it gives), in `choices` order; empty
    /// when the field's `doc` says it all.
    #[serde(skip_serializing_if = "<[_]>::is_empty")]
    pub choice_docs: &'static [&'static str],
    /// Shown as a percentage (the design stores the fraction 0–1, as written in it).
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub percent: bool,
    /// Help text: one line of plain words.
    pub doc: &'static str,
    /// JSON value a [`Kind::Section`] takes when switched on.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub default: Option<&'static str>,
    /// Shown only while another field has a given value.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub when: Option<When>,
    /// A special editor the page offers for this field (`pattern_picker`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub widget: Option<&'static str>,
    /// Longest text of a [`Kind::Text`] field, bytes (UTF-8); absent: [`MAX_TEXT_BYTES`]. For a
    /// [`Kind::Points`] field: the most points (absent: [`MAX_POINTS`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_len: Option<usize>,
}

/// Longest string a design may hold where no other limit is stated (a text field without
/// its own `max_len`, a job kind, a choice), bytes. Every string of a design travels in share
/// links and is copied into messages and forms; 256 bytes is a long sentence.
pub const MAX_TEXT_BYTES: usize = 256;

/// Most points a [`Kind::Points`] field may hold where its row states no other limit.
pub const MAX_POINTS: usize = 1000;

/// A real number in `min..=max` with a form `step`.
#[allow(clippy::too_many_arguments)] // a table row constructor: one argument per column
pub const fn num(
    path: &'static str,
    section: &'static str,
    label: &'static str,
    unit: &'static str,
    min: f64,
    max: f64,
    step: f64,
    doc: &'static str,
) -> Field {
    Field {
        path,
        section,
        label,
        unit,
        kind: Kind::Number,
        min: Some(min),
        max: Some(max),
        step: Some(step),
        choices: &[],
        choice_docs: &[],
        percent: false,
        doc,
        default: None,
        when: None,
        widget: None,
        max_len: None,
    }
}
/// A whole number in `min..=max`.
pub const fn int(path: &'static str, section: &'static str, label: &'static str, min: f64, max: f64, doc: &'static str) -> Field {
    Field {
        path,
        section,
        label,
        unit: "",
        kind: Kind::Integer,
        min: Some(min),
        max: Some(max),
        step: Some(1.0),
        choices: &[],
        choice_docs: &[],
        percent: false,
        doc,
        default: None,
        when: None,
        widget: None,
        max_len: None,
    }
}
/// A field without a numeric range (bool, text, choice, section).
pub const fn other(path: &'static str, section: &'static str, label: &'static str, kind: Kind, choices: &'static [&'static str], doc: &'static str) -> Field {
    Field {
        path,
        section,
        label,
        unit: "",
        kind,
        min: None,
        max: None,
        step: None,
        choices,
        choice_docs: &[],
        percent: false,
        doc,
        default: None,
        when: None,
        widget: None,
        max_len: None,
    }
}
/// Three numbers, each in `min..=max`.
#[allow(clippy::too_many_arguments)] // a table row constructor: one argument per column
pub const fn vec3(
    path: &'static str,
    section: &'static str,
    label: &'static str,
    unit: &'static str,
    min: f64,
    max: f64,
    step: f64,
    doc: &'static str,
) -> Field {
    Field {
        path,
        section,
        label,
        unit,
        kind: Kind::Vec3,
        min: Some(min),
        max: Some(max),
        step: Some(step),
        choices: &[],
        choice_docs: &[],
        percent: false,
        doc,
        default: None,
        when: None,
        widget: None,
        max_len: None,
    }
}
/// A list of 2-D points, each number in `min..=max`, at most `max_points` of them.
#[allow(clippy::too_many_arguments)] // a table row constructor: one argument per column
pub const fn points(
    path: &'static str,
    section: &'static str,
    label: &'static str,
    unit: &'static str,
    min: f64,
    max: f64,
    max_points: usize,
    doc: &'static str,
) -> Field {
    Field {
        path,
        section,
        label,
        unit,
        kind: Kind::Points,
        min: Some(min),
        max: Some(max),
        step: None,
        choices: &[],
        choice_docs: &[],
        percent: false,
        doc,
        default: None,
        when: None,
        widget: None,
        max_len: Some(max_points),
    }
}
/// Several rings of 2-D points, each number in `min..=max`, at most `max_points` in all.
#[allow(clippy::too_many_arguments)] // a table row constructor: one argument per column
pub const fn rings(
    path: &'static str,
    section: &'static str,
    label: &'static str,
    unit: &'static str,
    min: f64,
    max: f64,
    max_points: usize,
    doc: &'static str,
) -> Field {
    Field {
        path,
        section,
        label,
        unit,
        kind: Kind::Rings,
        min: Some(min),
        max: Some(max),
        step: None,
        choices: &[],
        choice_docs: &[],
        percent: false,
        doc,
        default: None,
        when: None,
        widget: None,
        max_len: Some(max_points),
    }
}
/// `f` with one line of plain words per choice.
pub const fn choice_docs(mut f: Field, docs: &'static [&'static str]) -> Field {
    f.choice_docs = docs;
    f
}

/// `f` shown as a percentage in the form.
pub const fn percent(mut f: Field) -> Field {
    f.percent = true;
    f
}

/// `f`, edited with the page's `widget`.
pub const fn widget(mut f: Field, widget: &'static str) -> Field {
    f.widget = Some(widget);
    f
}
/// `f` (a text field), at most `bytes` long.
pub const fn max_len(mut f: Field, bytes: usize) -> Field {
    f.max_len = Some(bytes);
    f
}
/// `f`, shown only while `path` equals `equals`.
pub const fn when(mut f: Field, path: &'static str, equals: &'static str) -> Field {
    f.when = Some(When { path, equals });
    f
}

/// A row mounted at its place in the design (absolute dotted path), as the page and the
/// validator see it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Row {
    /// Absolute dotted path in the design.
    pub path: String,
    /// The row.
    #[serde(flatten)]
    pub field: Field,
    /// Absolute path of the `when` condition's field.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub when_path: Option<String>,
    /// Only for this job kind.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub job: Option<&'static str>,
}

/// `fields` mounted under `prefix` (e.g. `job.slice`; empty for the root).
pub fn mount(prefix: &str, fields: &[Field]) -> Vec<Row> {
    let join = |p: &str| {
        if prefix.is_empty() {
            p.to_string()
        } else if p.is_empty() {
            prefix.to_string()
        } else {
            format!("{prefix}.{p}")
        }
    };
    fields
        .iter()
        .map(|f| Row {
            path: join(f.path),
            field: *f,
            // A leading `/` names a field from the design root (a material row that depends on
            // the printer's flavour).
            when_path: f.when.map(|w| w.path.strip_prefix('/').map_or_else(|| join(w.path), str::to_string)),
            job: None,
        })
        .collect()
}

/// One problem found in a design or in a stage's options.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Problem {
    /// Dotted field path, e.g. `printer.nozzle_diameter_mm`.
    pub path: String,
    /// What is wrong and what is allowed.
    pub message: String,
}

/// The problems as one message, one per line (`path: message`).
pub fn describe(problems: &[Problem]) -> String {
    problems.iter().map(|p| if p.path.is_empty() { p.message.clone() } else { format!("{}: {}", p.path, p.message) }).collect::<Vec<_>>().join("\n")
}

/// Formats a limit the way people write it (`0.01`, `2`, `1e20`).
pub fn fmt(x: f64) -> String {
    if x.abs() >= 1e15 {
        format!("{x:e}")
    } else {
        format!("{x}")
    }
}

fn lookup<'a>(root: &'a Value, path: &str) -> Option<&'a Value> {
    if path.is_empty() {
        return Some(root);
    }
    path.split('.').try_fold(root, |v, key| v.get(key))
}

impl Field {
    /// What a value of this field must be, in words: its kind and range with the unit (a
    /// percent field as the fraction the design holds, with the form's percentages). The one
    /// wording of the range checks here and of the design reader's messages (`design::words`).
    pub fn must_be(&self) -> String {
        let unit = if self.unit.is_empty() { String::new() } else { format!(" {}", self.unit) };
        let (lo, hi) = (self.min.map_or_else(String::new, fmt), self.max.map_or_else(String::new, fmt));
        match self.kind {
            // The form shows it in percent; the design (and --set) hold the fraction.
            Kind::Number if self.percent => {
                let pct = |x: Option<f64>| x.map_or_else(String::new, |x| fmt(x * 100.0));
                format!("a fraction from {lo} to {hi} ({} % to {} % in the form)", pct(self.min), pct(self.max))
            }
            Kind::Number => format!("a number from {lo} to {hi}{unit}"),
            Kind::Integer => format!("a whole number from {lo} to {hi}{unit}"),
            Kind::Bool => "true or false".into(),
            Kind::Text => "text in double quotes".into(),
            Kind::Choice => format!("one of: {}", self.choices.join(", ")),
            Kind::Vec3 => format!("three numbers [x, y, z], each from {lo} to {hi}{unit}"),
            Kind::Points => format!("a list of points [[a, b], …] (at most {}), each number from {lo} to {hi}{unit}", self.max_len.unwrap_or(MAX_POINTS)),
            Kind::Rings => {
                format!("a list of rings [[[a, b], …], …] (at most {} points in all), each number from {lo} to {hi}{unit}", self.max_len.unwrap_or(MAX_POINTS))
            }
            Kind::Section => "a group of settings { … }, or left out to switch it off".into(),
        }
    }
}

fn check_number(path: &str, v: f64, f: &Field, out: &mut Vec<Problem>) {
    let (lo, hi) = (f.min.unwrap_or(f64::MIN), f.max.unwrap_or(f64::MAX));
    if !v.is_finite() || v < lo || v > hi {
        // A Vec3 component is one number of the row's range.
        let f =
            Field { kind: if matches!(f.kind, Kind::Vec3 | Kind::Points | Kind::Rings) { Kind::Number } else { f.kind }, min: Some(lo), max: Some(hi), ..*f };
        let message = format!("{} is out of range: {} must be {}", fmt(v), f.label, f.must_be());
        out.push(Problem { path: path.to_string(), message });
    } else if f.kind == Kind::Integer && v.fract() != 0.0 {
        out.push(Problem { path: path.to_string(), message: format!("{} must be a whole number (got {})", f.label, fmt(v)) });
    }
}

/// Range and choice checks of every row against `root` (absolute paths; absent fields are not
/// checked: serde gives them their defaults).
pub fn check_rows(root: &Value, rows: &[Row], out: &mut Vec<Problem>) {
    for r in rows {
        check_one(root, &r.path, &r.field, out);
    }
}

/// Checks `value` (a stage's options serialised) against its own table; `prefix` is prepended
/// to the paths in the problems.
pub fn check<T: Serialize>(value: &T, fields: &[Field], prefix: &str) -> Vec<Problem> {
    let mut out = Vec::new();
    let Ok(root) = serde_json::to_value(value) else { return out };
    for f in fields {
        let Some(_) = lookup(&root, f.path) else { continue };
        let mut local = Vec::new();
        check_one(&root, f.path, f, &mut local);
        for mut p in local {
            if !prefix.is_empty() {
                p.path = format!("{prefix}.{}", p.path);
            }
            out.push(p);
        }
    }
    out
}

fn check_one(root: &Value, path: &str, f: &Field, out: &mut Vec<Problem>) {
    let Some(v) = lookup(root, path) else { return };
    // serde_json writes NaN and infinities as null.
    let not_a_number = |p: String, out: &mut Vec<Problem>| out.push(Problem { path: p, message: format!("{} must be a finite number", f.label) });
    match f.kind {
        Kind::Number | Kind::Integer => match v.as_f64() {
            Some(x) => check_number(path, x, f, out),
            None if v.is_null() => not_a_number(path.to_string(), out),
            None => {}
        },
        Kind::Vec3 => {
            if let Some(items) = v.as_array() {
                for (i, x) in items.iter().enumerate() {
                    match x.as_f64() {
                        Some(x) => check_number(&format!("{path}.{i}"), x, f, out),
                        None if x.is_null() => not_a_number(format!("{path}.{i}"), out),
                        None => {}
                    }
                }
            }
        }
        Kind::Points => {
            let Some(points) = v.as_array() else { return };
            let most = f.max_len.unwrap_or(MAX_POINTS);
            if points.len() > most {
                out.push(Problem { path: path.to_string(), message: format!("{} has {} points; at most {most} are allowed", f.label, points.len()) });
                return;
            }
            check_pairs(path, points, f, "", out);
        }
        Kind::Rings => {
            let Some(rings) = v.as_array() else { return };
            let most = f.max_len.unwrap_or(MAX_POINTS);
            let total: usize = rings.iter().map(|r| r.as_array().map_or(0, Vec::len)).sum();
            if total > most {
                out.push(Problem { path: path.to_string(), message: format!("{} has {total} points in all; at most {most} are allowed", f.label) });
                return;
            }
            for (r, ring) in rings.iter().enumerate() {
                match ring.as_array() {
                    Some(points) => check_pairs(&format!("{path}.{r}"), points, f, &format!(" of ring {}", r + 1), out),
                    None => out
                        .push(Problem {
                            path: format!("{path}.{r}"), message: format!("ring {} of {} must be a list of points [[a, b], …]", r + 1, f.label)
                        }),
                }
            }
        }
        Kind::Choice => {
            if let Some(s) = v.as_str() {
                if !f.choices.is_empty() && !f.choices.contains(&s) {
                    out.push(Problem { path: path.to_string(), message: not_a_choice(s, f.label, f.choices) });
                }
            }
        }
        Kind::Text => {
            if let Some(s) = v.as_str() {
                if let Some(p) = text_too_long(path, s, f.max_len.unwrap_or(MAX_TEXT_BYTES), f.label) {
                    out.push(p);
                }
            }
        }
        _ => {}
    }
}

/// Each of `points` must be two numbers within the row's range (`of` names the ring).
fn check_pairs(path: &str, points: &[Value], f: &Field, of: &str, out: &mut Vec<Problem>) {
    for (i, p) in points.iter().enumerate() {
        match p.as_array() {
            Some(xy) if xy.len() == 2 => {
                for (k, x) in xy.iter().enumerate() {
                    match x.as_f64() {
                        Some(x) => check_number(&format!("{path}.{i}.{k}"), x, f, out),
                        None => out.push(Problem { path: format!("{path}.{i}.{k}"), message: format!("{} must be a finite number", f.label) }),
                    }
                }
            }
            _ => out.push(Problem { path: format!("{path}.{i}"), message: format!("point {}{of} of {} must be two numbers [a, b]", i + 1, f.label) }),
        }
    }
}

/// The message of a choice not in the list: `'given' is not a choice for Label; use one of: a, b`.
pub fn not_a_choice(given: &str, label: &str, choices: &[&str]) -> String {
    format!("'{}' is not a choice for {label}; use one of: {}", clip(given, 40), choices.join(", "))
}

/// The problem of a string `s` at `path` longer than `limit` bytes (`what` names it).
pub fn text_too_long(path: &str, s: &str, limit: usize, what: &str) -> Option<Problem> {
    (s.len() > limit)
        .then(|| Problem { path: path.to_string(), message: format!("{what} is {} bytes long, over the limit of {limit} bytes: shorten it", s.len()) })
}

/// `s` cut to at most `chars` characters (with `…` when cut), to quote a value in a message.
pub fn clip(s: &str, chars: usize) -> std::borrow::Cow<'_, str> {
    match s.char_indices().nth(chars) {
        Some((i, _)) => format!("{}…", &s[..i]).into(),
        None => s.into(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mounted_rows_check_absolute_paths() {
        const F: &[Field] = &[num("a", "S", "A", "mm", 0.0, 1.0, 0.1, ""), int("n", "S", "N", 0.0, 5.0, "")];
        let rows = mount("job.x", F);
        assert_eq!(rows[0].path, "job.x.a");
        let root = serde_json::json!({"job": {"x": {"a": 2.0, "n": 1.5}}});
        let mut out = Vec::new();
        check_rows(&root, &rows, &mut out);
        assert_eq!(out.len(), 2, "{out:?}");
        assert!(out[0].message.contains("0 to 1 mm"), "{}", out[0].message);
        assert!(out[1].message.contains("whole number"), "{}", out[1].message);
        let local = check(&serde_json::json!({"a": -1.0}), F, "job.x");
        assert_eq!(local[0].path, "job.x.a");
    }

    #[test]
    fn rings_are_checked_point_by_point() {
        const F: &[Field] = &[rings("h", "S", "Holes", "", -1.0, 1.0, 5, "")];
        let ok = check(&serde_json::json!({"h": [[[0, 0], [0.5, 0], [0, 0.5]]]}), F, "p");
        assert!(ok.is_empty(), "{ok:?}");
        let out = check(&serde_json::json!({"h": [[[0, 0], [2, 0], [0, 0.5]], [[0, 0, 1]], 3]}), F, "p");
        assert_eq!(out.len(), 3, "{out:?}");
        assert_eq!(out[0].path, "p.h.0.1.0");
        assert!(out[1].message.contains("point 1 of ring 2"), "{}", out[1].message);
        assert!(out[2].message.contains("ring 3"), "{}", out[2].message);
        let many = check(&serde_json::json!({"h": [[[0, 0], [0, 0], [0, 0]], [[0, 0], [0, 0], [0, 0]]]}), F, "p");
        assert!(many[0].message.contains("6 points in all"), "{many:?}");
    }

    #[test]
    fn text_length_is_checked() {
        const F: &[Field] = &[other("t", "S", "T", Kind::Text, &[], ""), max_len(other("u", "S", "U", Kind::Text, &[], ""), 4)];
        let root = serde_json::json!({"t": "x".repeat(MAX_TEXT_BYTES + 1), "u": "héllo"});
        let out = check(&root, F, "p");
        assert_eq!(out.len(), 2, "{out:?}");
        assert_eq!(out[0].path, "p.t");
        assert!(out[0].message.contains(&format!("{} bytes long, over the limit of {MAX_TEXT_BYTES}", MAX_TEXT_BYTES + 1)), "{}", out[0].message);
        assert!(out[1].message.contains("6 bytes long, over the limit of 4"), "{}", out[1].message);
        assert_eq!(clip("abcdef", 3), "abc…");
        assert_eq!(clip("ab", 3), "ab");
    }
}

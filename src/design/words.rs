//! Plain words for what the JSON reader says about a design.
//!
//! serde's messages name Rust types (`invalid type: floating point `2.5`, expected u32`) and
//! no place; a design's reader tracks the field's path ([`serde_path_to_error`]) and this
//! module turns the message into a [`Problem`] at that path, in the words of the field's form
//! row when it has one (its label, what it must be, the value given), else in general words.
//! A JSON syntax error becomes one plain clause ([`syntax`]).

use crate::settings::{clip, Kind, Problem, Row};
use serde_json::Value;

/// Longest quote of a value or name, characters.
const QUOTE: usize = 40;
/// Longest message, characters (lists of allowed names included).
const MAX_MESSAGE_CHARS: usize = 2000;

/// What serde said, taken apart.
#[derive(Debug, PartialEq)]
enum Said<'a> {
    /// `invalid type: GOT, expected WANT` and `invalid value: …`.
    Type { got: &'a str, want: &'a str },
    /// `invalid length N, expected WANT`.
    Length { len: &'a str, want: &'a str },
    /// `unknown variant `NAME`, expected one of `a`, `b``.
    Variant { name: &'a str, allowed: Vec<&'a str> },
    /// `unknown field `NAME`, expected one of …`.
    Field { name: &'a str, allowed: Vec<&'a str> },
    /// `missing field `NAME``.
    Missing { name: &'a str },
    /// `duplicate field `NAME``.
    Duplicate { name: &'a str },
    /// A message of our own (`Error::custom`), already in words.
    Other(&'a str),
}

/// The names between backticks in serde's "expected one of `a`, `b`" (or "expected `a`").
fn names(list: &str) -> Vec<&str> {
    list.split('`').skip(1).step_by(2).collect()
}

/// The name quoted by `head` (e.g. "unknown field `") and the list after it. The name may hold
/// anything (it comes from the design); the list holds identifiers only, so the last
/// "`, expected" (or "`, there are no") ends the name.
fn named<'a>(msg: &'a str, head: &str) -> Option<(&'a str, &'a str)> {
    let rest = msg.strip_prefix(head)?;
    match rest.rfind("`, expected").or_else(|| rest.rfind("`, there are no")) {
        Some(i) => Some((&rest[..i], &rest[i + 3..])),
        None => Some((rest.strip_suffix('`').unwrap_or(rest), "")),
    }
}

fn parse(msg: &str) -> Said<'_> {
    for head in ["invalid type: ", "invalid value: "] {
        if let Some(rest) = msg.strip_prefix(head) {
            if let Some(i) = rest.rfind(", expected ") {
                return Said::Type { got: &rest[..i], want: &rest[i + 11..] };
            }
        }
    }
    if let Some(rest) = msg.strip_prefix("invalid length ") {
        if let Some((len, want)) = rest.split_once(", expected ") {
            return Said::Length { len, want };
        }
    }
    if let Some((name, list)) = named(msg, "unknown variant `") {
        return Said::Variant { name, allowed: names(list) };
    }
    if let Some((name, list)) = named(msg, "unknown field `") {
        return Said::Field { name, allowed: names(list) };
    }
    if let Some((name, _)) = named(msg, "missing field `") {
        return Said::Missing { name };
    }
    if let Some((name, _)) = named(msg, "duplicate field `") {
        return Said::Duplicate { name };
    }
    Said::Other(msg)
}

/// serde's name of what it wanted, in words.
fn wanted(want: &str) -> String {
    let w = want.trim();
    match w {
        "u8" | "u16" | "u32" | "u64" | "u128" | "usize" => {
            let max = match w {
                "u8" => Some(u8::MAX as u64),
                "u16" => Some(u16::MAX as u64),
                "u32" => Some(u32::MAX as u64),
                _ => None,
            };
            match max {
                Some(m) => format!("a whole number from 0 to {m}"),
                None => "a whole number, 0 or more".into(),
            }
        }
        "i8" | "i16" | "i32" | "i64" | "i128" | "isize" => "a whole number".into(),
        "f32" | "f64" => "a number".into(),
        "a boolean" => "true or false".into(),
        "a string" | "a borrowed string" | "a character" | "a char" => "text in double quotes".into(),
        "a sequence" => "a list [ … ]".into(),
        _ => {
            if let Some(n) = w.strip_prefix("an array of length ").or_else(|| w.strip_prefix("a tuple of size ")) {
                format!("a list of {n} values [ … ]")
            } else if w.starts_with("struct ") || w.starts_with("a map") || w == "map" {
                "a group of settings { … }".into()
            } else if w.starts_with("internally tagged enum") {
                "a group of settings with a \"kind\" { \"kind\": … }".into()
            } else if w.starts_with("enum ") || w.contains("variant") {
                "one of the allowed names".into()
            } else {
                "a different kind of value".into()
            }
        }
    }
}

/// serde's description of the value it got (`floating point `2.5``, `string "x"`), as the
/// value itself where it can.
fn got_words(got: &str) -> String {
    let inner = |s: &str| s.split_once('`').and_then(|(_, r)| r.rsplit_once('`')).map(|(v, _)| v.to_string());
    let g = got.trim();
    if let Some(s) = g.strip_prefix("string ") {
        return clip(s, QUOTE + 2).into_owned();
    }
    for head in ["floating point", "integer", "boolean", "character"] {
        if g.starts_with(head) {
            if let Some(v) = inner(g) {
                return v;
            }
        }
    }
    match g {
        "null" | "unit" | "unit value" => "null".into(),
        "map" => "a group of settings { … }".into(),
        "sequence" => "a list [ … ]".into(),
        _ => clip(g, QUOTE).into_owned(),
    }
}

/// A JSON value as a message quotes it.
fn shown(v: &Value) -> String {
    match v {
        Value::Null => "null".into(),
        Value::Bool(b) => b.to_string(),
        Value::Number(n) => n.to_string(),
        Value::String(s) => format!("\"{}\"", clip(s, QUOTE)),
        Value::Array(a) => format!("a list of {} value{}", a.len(), if a.len() == 1 { "" } else { "s" }),
        Value::Object(_) => "a group of settings { … }".into(),
    }
}

fn lookup<'a>(root: &'a Value, path: &str) -> Option<&'a Value> {
    if path.is_empty() {
        return Some(root);
    }
    path.split('.').try_fold(root, |v, k| match v {
        Value::Array(items) => items.get(k.parse::<usize>().ok()?),
        _ => v.get(k),
    })
}

/// The row of `path`: the one whose `when` holds when several share it; a three-number row
/// for one of its numbers (`…size.1`).
fn row_of<'a>(rows: &'a [Row], root: &Value, path: &str) -> Option<&'a Row> {
    let holds = |r: &Row| match (&r.when_path, r.field.when) {
        (Some(p), Some(w)) => lookup(root, p).is_some_and(|v| v.as_str().map_or_else(|| v.to_string(), str::to_string) == w.equals),
        _ => true,
    };
    let mut same = rows.iter().filter(|r| r.path == path);
    let first = same.clone().next();
    if let Some(r) = same.find(|r| holds(r)).or(first) {
        return Some(r);
    }
    let (parent, last) = path.rsplit_once('.')?;
    last.parse::<usize>().ok()?;
    rows.iter().find(|r| r.path == parent && r.field.kind == Kind::Vec3)
}

pub(crate) use crate::settings::not_a_choice;

/// The closest of `names` to `name` when it is a likely typo (at most a third of it differs).
fn closest<'a>(name: &str, names: &[&'a str]) -> Option<&'a str> {
    let distance = |a: &str, b: &str| {
        let b: Vec<char> = b.chars().collect();
        let mut prev: Vec<usize> = (0..=b.len()).collect();
        for (i, ca) in a.chars().enumerate() {
            let mut cur = vec![i + 1];
            for (j, cb) in b.iter().enumerate() {
                cur.push((prev[j] + usize::from(ca != *cb)).min(prev[j + 1] + 1).min(cur[j] + 1));
            }
            prev = cur;
        }
        prev[b.len()]
    };
    if name.chars().count() > 64 {
        return None;
    }
    names.iter().map(|n| (distance(name, n), *n)).filter(|(d, n)| *d > 0 && *d * 3 <= n.chars().count().max(3)).min_by_key(|(d, _)| *d).map(|(_, n)| n)
}

fn join(path: &str, key: &str) -> String {
    if path.is_empty() {
        key.to_string()
    } else {
        format!("{path}.{key}")
    }
}

/// The dotted design path of serde's error (`prefix` first: `job` for a job's settings).
fn dotted(path: &serde_path_to_error::Path, prefix: &str) -> String {
    let mut out = prefix.to_string();
    for seg in path.iter() {
        let key = match seg {
            serde_path_to_error::Segment::Seq { index } => index.to_string(),
            serde_path_to_error::Segment::Map { key } | serde_path_to_error::Segment::Enum { variant: key } => clip(key, QUOTE).into_owned(),
            serde_path_to_error::Segment::Unknown => break,
        };
        out = join(&out, &key);
    }
    out
}

/// A value of the wrong type or size at `path`: what its row (or serde's `want`) needs.
fn wrong_value(rows: &[Row], root: &Value, path: &str, got: String, want: &str) -> String {
    match row_of(rows, root, path) {
        Some(r) if r.field.kind == Kind::Choice && got.starts_with('"') => not_a_choice(got.trim_matches('"'), r.field.label, r.field.choices),
        Some(r) => format!("{} must be {} (got {got})", r.field.label, r.field.must_be()),
        None => format!("must be {} (got {got})", wanted(want)),
    }
}

/// A reading error of a design (or of its `job` object, `prefix` = `job`) as a problem at its
/// field, in words. `root` is the whole design as read; `rows` its form rows.
pub(crate) fn problem(err: &serde_path_to_error::Error<serde_json::Error>, prefix: &str, root: &Value, rows: &[Row]) -> Problem {
    let mut path = dotted(err.path(), prefix);
    let text = err.inner().to_string();
    let msg = match text.rfind(" at line ") {
        Some(i) if err.inner().line() > 0 => &text[..i],
        _ => &text[..],
    };
    let said = parse(msg);
    // Inside a `kind`-tagged group (a pattern, a domain) serde's path stops at the group: find
    // the field by the name or the value it quotes.
    if let Some(Value::Object(map)) = lookup(root, &path) {
        let child = match &said {
            Said::Field { name, .. } if map.contains_key(*name) => Some(name.to_string()),
            Said::Variant { .. } if map.contains_key("kind") && rows.iter().any(|r| r.path == join(&path, "kind")) => Some("kind".into()),
            Said::Length { len, .. } => {
                let hits: Vec<&String> = map.iter().filter(|(_, v)| v.as_array().is_some_and(|a| a.len().to_string() == *len)).map(|(k, _)| k).collect();
                (hits.len() == 1).then(|| hits[0].clone())
            }
            Said::Type { got, .. } => {
                let want = got_words(got);
                let hits: Vec<&String> =
                    map.iter().filter(|(_, v)| !v.is_object() && shown(v).trim_matches('"') == want.trim_matches('"')).map(|(k, _)| k).collect();
                (hits.len() == 1).then(|| hits[0].clone())
            }
            _ => None,
        };
        if let Some(k) = child {
            path = join(&path, &k);
        }
    }
    let given = || lookup(root, &path).filter(|v| !v.is_object()).map(shown);
    let message = match said {
        Said::Type { got, want } => wrong_value(rows, root, &path, given().unwrap_or_else(|| got_words(got)), want),
        Said::Length { len, want } => wrong_value(rows, root, &path, given().unwrap_or_else(|| format!("a list of {len} values")), want),
        Said::Variant { name, allowed } => {
            let name = lookup(root, &path).and_then(Value::as_str).unwrap_or(name);
            match row_of(rows, root, &path).or_else(|| row_of(rows, root, &join(&path, "kind"))) {
                Some(r) if r.field.kind == Kind::Choice => {
                    path = r.path.clone();
                    not_a_choice(name, r.field.label, r.field.choices)
                }
                _ => format!("'{}' is not allowed here; use one of: {}", clip(name, QUOTE), allowed.join(", ")),
            }
        }
        Said::Field { name, allowed } => {
            // serde's path ends at the unknown name (clipped as the path is), or before it.
            let shown = clip(name, QUOTE);
            if path.rsplit('.').next() != Some(&*shown) {
                path = join(&path, &shown);
            }
            let place = path.rsplit_once('.').map_or("the design".to_string(), |(p, _)| p.to_string());
            let hint = closest(name, &allowed).map(|c| format!(" (did you mean '{c}'?)")).unwrap_or_default();
            if allowed.is_empty() {
                format!("is not a setting{hint}; {place} has no settings of its own here: remove it")
            } else {
                format!("is not a setting{hint}; the settings of {place} are: {}", allowed.join(", "))
            }
        }
        Said::Missing { name } => {
            path = join(&path, &clip(name, QUOTE));
            match row_of(rows, root, &path) {
                Some(r) => format!("{} is missing: add it ({})", r.field.label, r.field.must_be()),
                None => "is missing: add it (start from a complete design: an example on the page, or `weft new`)".into(),
            }
        }
        Said::Duplicate { name } => {
            path = join(&path, &clip(name, QUOTE));
            "is given twice: keep one".into()
        }
        Said::Other(m) => m.to_string(),
    };
    Problem { path, message: clip(&message, MAX_MESSAGE_CHARS).into_owned() }
}

/// A JSON syntax error in plain words (the position is kept by the caller).
pub(crate) fn syntax(err: &serde_json::Error) -> String {
    if err.classify() == serde_json::error::Category::Eof {
        return "the text ends before the design does: the file was cut short; save or copy it again".into();
    }
    let text = err.to_string();
    let msg = text.rfind(" at line ").map_or(&text[..], |i| &text[..i]);
    let words = match msg {
        "expected `:`" => "a ':' is missing after a field name",
        "expected `,` or `]`" => "a ',' or ']' is missing in a list",
        "expected `,` or `}`" => "a ',' or '}' is missing between fields",
        "expected ident" => "a word is not understood: write text in double quotes (only true, false and null go without)",
        "expected value" => "a value is missing or not understood here: write text in double quotes",
        "key must be a string" => "field names must be in double quotes",
        "trailing comma" => "there is a ',' before a closing bracket: remove it",
        "trailing characters" => "there is more text after the end of the design: remove it",
        "invalid escape" => "a backslash starts an unknown escape in a text: write \\\\ for a backslash",
        "invalid number" => "a number is written wrongly",
        "number out of range" => "a number is too large",
        "recursion limit exceeded" => "the design is nested more than 128 levels deep, the limit; a design is only a few levels deep",
        m if m.starts_with("control character") => "a text holds a line break or tab: write it as \\n or \\t",
        m if m.contains("unicode") || m.contains("surrogate") || m.contains("hex escape") => "a \\u escape in a text is not a valid character",
        "EOF while parsing a value" => "the text ends before the design does",
        _ => "this is not valid JSON here",
    };
    words.into()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn serde_messages_are_taken_apart() {
        assert_eq!(parse("invalid type: floating point `2.5`, expected u32"), Said::Type { got: "floating point `2.5`", want: "u32" });
        assert_eq!(
            parse("unknown variant `eu, expected`, expected one of `euler`, `continuous`"),
            Said::Variant { name: "eu, expected", allowed: vec!["euler", "continuous"] }
        );
        assert_eq!(parse("unknown field `x`, there are no fields"), Said::Field { name: "x", allowed: vec![] });
        assert_eq!(parse("missing field `job`"), Said::Missing { name: "job" });
        assert_eq!(wanted("u32"), "a whole number from 0 to 4294967295");
        assert_eq!(got_words("string \"abc\""), "\"abc\"");
        assert_eq!(got_words("integer `-1`"), "-1");
        assert_eq!(closest("iteratons", &["method", "iterations"]), Some("iterations"));
        assert_eq!(closest("zzz", &["method", "iterations"]), None);
    }
}

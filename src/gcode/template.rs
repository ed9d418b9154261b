//! Start/end G-code templates: `{name}` placeholders.

use super::Error;

/// Placeholders a template may use, in the order the error message lists them.
pub const PLACEHOLDERS: [&str; 7] = ["nozzle_temp_c", "first_layer_nozzle_temp_c", "bed_temp_c", "bed_x_mm", "bed_y_mm", "fan_pwm", "design_name"];

/// Longest start or end template, bytes (64 KiB). Real start codes are a few dozen lines
/// (well under 4 KiB, even with mesh bed levelling and purge lines); a template is part of the
/// design, so a share link carries it, and the writer also reads it with the analyzer's lexer.
pub const MAX_TEMPLATE_BYTES: usize = 64 * 1024;

/// Largest expanded template, bytes (1 MiB). Placeholders expand to at most
/// [`crate::design::MAX_NAME_BYTES`] bytes each, so a template within
/// [`MAX_TEMPLATE_BYTES`] can still ask for ~20× its size (`{design_name}` repeated); this
/// keeps that well inside the browser worker's memory while leaving 16× room over the
/// largest template a person writes.
pub const MAX_EXPANDED_BYTES: usize = 1024 * 1024;

/// Longest placeholder name quoted in an error message, characters.
const MAX_QUOTED_CHARS: usize = 40;

/// Replaces every `{name}` in `template` by its value in `vars` (pairs of placeholder name and
/// text). An unknown name is an error; a `{` with no closing `}` on the same line is kept as is.
/// `which` names the template in errors (`start_gcode`, `end_gcode`).
///
/// Cost is linear in the template and the output: each byte is looked at once (a `{` with no
/// `}` before the line's end means every `{` up to there is unclosed too, so the scan resumes
/// at the line's end). Refuses a template over [`MAX_TEMPLATE_BYTES`] and an expansion over
/// [`MAX_EXPANDED_BYTES`] (measured without building it).
pub fn expand(template: &str, which: &'static str, vars: &[(&str, String)]) -> Result<String, Error> {
    if template.len() > MAX_TEMPLATE_BYTES {
        return Err(Error::TemplateTooLong { template: which, bytes: template.len(), limit: MAX_TEMPLATE_BYTES });
    }
    let bytes = expanded_len(template, which, vars)?;
    if bytes > MAX_EXPANDED_BYTES {
        return Err(Error::TemplateTooLarge { template: which, bytes, limit: MAX_EXPANDED_BYTES });
    }
    let mut out = String::with_capacity(bytes);
    for piece in pieces(template, vars) {
        out.push_str(piece.map_err(|name| unknown(which, name))?);
    }
    Ok(out)
}

/// Size of the expansion of `template`, bytes, without building it.
fn expanded_len(template: &str, which: &'static str, vars: &[(&str, String)]) -> Result<usize, Error> {
    let mut n = 0usize;
    for piece in pieces(template, vars) {
        n = n.saturating_add(piece.map_err(|name| unknown(which, name))?.len());
    }
    Ok(n)
}

fn unknown(which: &'static str, name: &str) -> Error {
    let name = match name.char_indices().nth(MAX_QUOTED_CHARS) {
        Some((i, _)) => format!("{}…", &name[..i]),
        None => name.to_string(),
    };
    Error::UnknownPlaceholder { template: which, name, known: PLACEHOLDERS.iter().map(|p| format!("{{{p}}}")).collect::<Vec<_>>().join(", ") }
}

/// The expansion as a sequence of text pieces (literal runs and placeholder values); an
/// unknown placeholder yields `Err(name)`.
fn pieces<'a>(template: &'a str, vars: &'a [(&str, String)]) -> impl Iterator<Item = Result<&'a str, &'a str>> + 'a {
    let mut rest = template;
    let mut pending: Option<Result<&'a str, &'a str>> = None;
    std::iter::from_fn(move || {
        if let Some(p) = pending.take() {
            return Some(p);
        }
        if rest.is_empty() {
            return None;
        }
        let Some(open) = rest.find('{') else {
            crate::work::add(rest.len());
            return Some(Ok(std::mem::take(&mut rest)));
        };
        let after = &rest[open + 1..];
        let close = after.find(['}', '\n']);
        // Bytes scanned (the growth checks count them).
        crate::work::add(open + 1 + close.map_or(after.len(), |c| c + 1));
        match close {
            Some(c) if after.as_bytes()[c] == b'}' => {
                let name = &after[..c];
                let literal = &rest[..open];
                rest = &after[c + 1..];
                crate::work::add(vars.len());
                let value = vars.iter().find(|(n, _)| *n == name.trim()).map(|(_, v)| v.as_str()).ok_or(name);
                if literal.is_empty() {
                    Some(value)
                } else {
                    pending = Some(value);
                    Some(Ok(literal))
                }
            }
            // No `}` before the line's end: nor has any later `{` of this line, so the text up
            // to the newline (or the end) is literal.
            Some(c) => {
                let (literal, tail) = rest.split_at(open + 1 + c);
                rest = tail;
                Some(Ok(literal))
            }
            None => Some(Ok(std::mem::take(&mut rest))),
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn vars(name: &str) -> Vec<(&'static str, String)> {
        vec![("bed_temp_c", "60".into()), ("design_name", name.into())]
    }

    #[test]
    fn placeholders_and_literal_braces() {
        let v = vars("cube");
        assert_eq!(expand("M140 S{bed_temp_c}\n; {design_name}\n", "t", &v).unwrap(), "M140 S60\n; cube\n");
        assert_eq!(expand("a { b\n{ bed_temp_c }{", "t", &v).unwrap(), "a { b\n60{");
        assert_eq!(expand("{{{{\n{{x\nend", "t", &v).unwrap(), "{{{{\n{{x\nend");
        assert_eq!(expand("", "t", &v).unwrap(), "");
        assert_eq!(expand("no braces", "t", &v).unwrap(), "no braces");
        let e = expand("ok {bed_temp_c} {nope} {", "start_gcode", &v).unwrap_err().to_string();
        assert!(e.contains("start_gcode") && e.contains("{nope}") && e.contains("{design_name}"), "{e}");
        // Nested: the name runs to the first `}`.
        assert!(matches!(expand("{a{bed_temp_c}", "t", &v), Err(Error::UnknownPlaceholder { .. })));
        // A long unknown name is quoted short.
        let e = expand(&format!("{{{}}}", "x".repeat(10_000)), "t", &v).unwrap_err().to_string();
        assert!(e.len() < 400, "{}", e.len());
    }

    #[test]
    fn limits_name_the_size() {
        let v = vars(&"n".repeat(256));
        let long = "G4\n".repeat(MAX_TEMPLATE_BYTES / 3 + 1);
        let e = expand(&long, "start_gcode", &v).unwrap_err();
        assert!(matches!(e, Error::TemplateTooLong { bytes, .. } if bytes == long.len()), "{e}");
        let bomb = "{design_name}".repeat(5000);
        let e = expand(&bomb, "end_gcode", &v).unwrap_err();
        assert!(matches!(e, Error::TemplateTooLarge { bytes: 1_280_000, .. }), "{e}");
        let msg = e.to_string();
        assert!(msg.contains("end_gcode") && msg.contains("1280000") && msg.contains(&MAX_EXPANDED_BYTES.to_string()), "{msg}");
        // Just under the limit is fine.
        let ok = "{design_name}".repeat(MAX_EXPANDED_BYTES / 256);
        assert_eq!(expand(&ok, "t", &v).unwrap().len(), MAX_EXPANDED_BYTES);
    }
}

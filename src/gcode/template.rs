//! Start/end G-code templates: `{name}` placeholders.

use super::Error;

/// Placeholders a template may use, in the order the error message lists them.
pub const PLACEHOLDERS: [&str; 7] =
    ["nozzle_temp_c", "first_layer_nozzle_temp_c", "bed_temp_c", "bed_x_mm", "bed_y_mm", "fan_pwm", "design_name"];

/// Replaces every `{name}` in `template` by its value in `vars` (pairs of placeholder name and
/// text). An unknown name is an error; a `{` with no closing `}` on the same line is kept as is.
pub fn expand(template: &str, which: &'static str, vars: &[(&str, String)]) -> Result<String, Error> {
    let mut out = String::with_capacity(template.len() + 32);
    let mut rest = template;
    while let Some(open) = rest.find('{') {
        out.push_str(&rest[..open]);
        let after = &rest[open + 1..];
        let close = match after.find(['}', '\n']) {
            Some(c) if after.as_bytes()[c] == b'}' => c,
            _ => {
                out.push('{');
                rest = after;
                continue;
            }
        };
        let name = &after[..close];
        match vars.iter().find(|(n, _)| *n == name.trim()) {
            Some((_, value)) => out.push_str(value),
            None => {
                return Err(Error::UnknownPlaceholder {
                    template: which,
                    name: name.to_string(),
                    known: PLACEHOLDERS.iter().map(|p| format!("{{{p}}}")).collect::<Vec<_>>().join(", "),
                })
            }
        }
        rest = &after[close + 1..];
    }
    out.push_str(rest);
    Ok(out)
}

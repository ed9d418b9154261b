//! The lattice job's form: the domain's rows, the pattern picker, and the pattern's and the paths' own rows.

use super::*;

/// Rows of the domain (paths relative to `job.domain`).
pub(super) const DOMAIN_FIELDS: &[Field] = &[
    other(
        "kind",
        "Domain",
        "Domain",
        FieldKind::Choice,
        &["rectangle", "disc", "tensile_specimen", "solid"],
        "Where the lattice goes: a built-in shape, or the layers of a loaded solid.",
    ),
    crate::settings::num("width_mm", "Domain", "Width", "mm", 0.1, 2000.0, 0.1, "Size of the rectangle along X."),
    crate::settings::num("height_mm", "Domain", "Height", "mm", 0.1, 2000.0, 0.1, "Size of the rectangle along Y."),
    crate::settings::num("diameter_mm", "Domain", "Diameter", "mm", 0.1, 2000.0, 0.1, "Diameter of the disc."),
    crate::settings::num("length_mm", "Domain", "Lattice length", "mm", 0.1, 2000.0, 0.1, "Between the handles."),
    crate::settings::num("handle_length_mm", "Domain", "Handle length", "mm", 0.1, 1000.0, 0.1, "Solid handle at each end."),
];

/// The pattern choice row, edited with the page's pattern picker.
pub(super) const PATTERN_FIELD: &[Field] = &[widget(
    other(
        "pattern.kind",
        "Lattice",
        "Pattern",
        FieldKind::Choice,
        lattice::PATTERNS,
        "The cell shape the lattice repeats (or randomises): pick by its picture.",
    ),
    "pattern_picker",
)];

/// The form's rows (`Kind::fields`), mounted at their design paths.
pub(super) fn rows() -> Vec<Row> {
    let mut rows = mount("job.domain", DOMAIN_FIELDS);
    rows.extend(mount("job.lattice", PATTERN_FIELD));
    rows.extend(mount("job.lattice", lattice::FIELDS));
    rows.extend(mount("job.paths", paths::FIELDS));
    rows.extend(mount("job.nonplanar", nonplanar::FIELDS));
    rows.extend(mount("job.input", shapes::FIELDS));
    rows
}

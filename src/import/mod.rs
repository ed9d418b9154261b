//! Mesh import: binary and ASCII STL, OBJ, 3MF → [`Mesh`] in millimetres.
//!
//! Entry: [`read_mesh`]. Every problem is a typed [`Error`] naming the file, the place in it
//! and the fix; nothing here panics on any input (fuzzed: `fuzz/`, and a seeded mutation
//! smoke test in `tests/it/fuzz_smoke.rs`).
//!
//! Pipeline: detect the format from the content ([`detect_format`]), parse into a raw indexed
//! triangle list (a binary STL's records are checked and read in place), then clean it
//! ([`repair`]): weld close vertices, drop degenerate and duplicate triangles, count open
//! edges. The output order follows the file order, so the same bytes give the same [`Mesh`]
//! on every run and platform, at any thread count (the checks and the cleaning work on every
//! core through `crate::par`).
//!
//! Bounded: every parser and the cleaner are linear in the input (`tests/it/import_hostile.rs`
//! checks the growth of each), and the counts are checked against [`MAX_TRIANGLES`] and
//! [`MAX_IMPORT_BYTES`] before mesh memory is allocated; [`estimate`] gives the same counts
//! and the memory peak without reading. Strings from files reach messages only through
//! [`clean`] (bounded length, no control characters).

mod buckets;
pub mod close;
mod obj;
mod repair;
mod stl;
mod threemf;

use crate::geom::Mesh;
use serde::Serialize;

pub use threemf::{MAX_MODEL_PART_BYTES, MAX_XML_DEPTH};

/// Most triangles [`read_mesh`] accepts (counted before cleaning; a 3MF counts every build
/// instance). Checked before any mesh memory is allocated: from the binary STL header, a
/// token scan of ASCII STL and OBJ, and the 3MF counts as its XML streams and before the
/// build is placed.
///
/// Why 5 M: the browser worker has about 2 GB of wasm memory for a whole run and slicing
/// follows import, so import should peak under about 1 GB ([`MAX_IMPORT_BYTES`]).
/// Measured (`memory_per_triangle` in `tests/it/import_hostile.rs`: resident high-water mark
/// of `read_mesh` in a fresh process, glibc unmapping every freed block, 2 M-triangle
/// spheres), beyond the file's own bytes: binary STL 44 B/triangle (its records are read in
/// place), ASCII STL 72, OBJ 32, 3MF 42, a binary-STL soup where nothing welds 85;
/// [`estimate`] bounds them at 111, 111, 43, 73, 111. So a binary STL at the limit (a 250 MB
/// file) peaks at about 0.4 GB, and at most at its estimate of 718 MiB whatever its geometry,
/// leaving room for slicing. The one-table cleaner before it peaked at 64 B/triangle for STL,
/// 42 for OBJ and 107 for the soup; the importer before that at 102 B/triangle beyond the
/// file (same measurement; 625 MiB of wasm memory for a 4 M-triangle, 200 MB STL; 1.69 GB
/// RSS for 10 M natively), with no bound for soups. Meshes this large are scans or
/// over-tessellated exports, which slice the same once decimated.
pub const MAX_TRIANGLES: usize = 5_000_000;

/// Most memory an import may need by [`estimate`]: the input's own bytes plus the reader's
/// and cleaner's high-water mark. 1 GiB keeps import within half of the browser worker's
/// ~2 GB, leaving the rest for slicing. It binds before [`MAX_TRIANGLES`] only for inputs
/// that are large for their triangle count: ASCII STL (≈190 bytes of text per triangle, so
/// about 3.7 M triangles fit), OBJ or 3MF with many unused vertices or many small objects.
pub const MAX_IMPORT_BYTES: u64 = 1 << 30;

/// Default vertex-weld distance in mm: vertices closer than this become one.
pub const DEFAULT_WELD_TOLERANCE_MM: f64 = 1e-4;

/// Longest string from a file (a name, a unit, a token) shown in a message, in characters.
pub const MAX_SHOWN_CHARS: usize = 80;

/// Import options.
#[derive(Clone, Debug, PartialEq)]
pub struct Options {
    /// Vertices closer than this (mm) are merged. Default [`DEFAULT_WELD_TOLERANCE_MM`].
    /// Zero, negative or NaN merges only vertices at exactly the same position.
    pub weld_tolerance_mm: f64,
}

impl Default for Options {
    fn default() -> Self {
        Options { weld_tolerance_mm: DEFAULT_WELD_TOLERANCE_MM }
    }
}

/// File formats weft reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Format {
    /// Binary STL.
    StlBinary,
    /// ASCII STL.
    StlAscii,
    /// Wavefront OBJ.
    Obj,
    /// 3D Manufacturing Format (zip + XML).
    ThreeMf,
}

/// What the importer found and repaired.
#[derive(Clone, Debug, Default, PartialEq, Serialize, serde::Deserialize)]
pub struct ImportReport {
    /// Detected format.
    pub format: Option<Format>,
    /// Triangles in the file (OBJ polygons count as their fan triangles; 3MF counts every
    /// build instance).
    pub triangles_read: usize,
    /// Triangles kept.
    pub triangles: usize,
    /// Distinct vertices after welding (those used by the kept triangles).
    pub vertices: usize,
    /// Triangles with zero area (or repeated corners) dropped.
    pub degenerate_removed: usize,
    /// Exact duplicate triangles dropped.
    pub duplicates_removed: usize,
    /// Edges used by only one triangle (holes in the surface; the slicer closes small gaps).
    pub open_edges: usize,
    /// Scale applied to reach millimetres (3MF unit attribute; 1 for STL/OBJ).
    pub unit_scale: f64,
    /// What making it a closed solid did (a slot that needs a solid: [`close::close_solid`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub closure: Option<close::Closure>,
    /// Repairs stated in words, one sentence each.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub notes: Vec<String>,
}

/// A mesh and what happened while reading it.
#[derive(Clone, Debug)]
pub struct Imported {
    /// The mesh, in mm.
    pub mesh: Mesh,
    /// What was read and repaired.
    pub report: ImportReport,
}

/// What reading a file will cost, from [`estimate`], before any mesh memory is allocated.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, serde::Deserialize)]
pub struct Estimate {
    /// Detected format.
    pub format: Format,
    /// Upper bound of the triangles read (before cleaning; 3MF: every build instance).
    /// Exact for binary STL, and for ASCII STL, OBJ and 3MF that parse.
    pub triangles: u64,
    /// Vertices read (before welding); same bounds as `triangles`.
    pub vertices: u64,
    /// Upper bound of the memory [`read_mesh`] holds at its peak, in bytes, the input's own
    /// bytes included (in the browser they sit in wasm memory too) and cleaning (weld,
    /// duplicate removal) included.
    pub peak_bytes: u64,
}

impl Estimate {
    /// The error [`read_mesh`] gives for this estimate, if it is over a limit.
    pub fn check(&self, file: &str) -> Result<(), Error> {
        let fix = |tris: u64| {
            format!(
                "decimate the mesh (e.g. in PrusaSlicer: right-click the object, Simplify model) to under {} triangles, or split it into parts",
                group(tris)
            )
        };
        if self.triangles > MAX_TRIANGLES as u64 {
            return Err(Error::TooLarge {
                file: file.to_string(),
                problem: format!("the mesh has {} triangles, limit {}", group(self.triangles), group(MAX_TRIANGLES as u64)),
                fix: fix(MAX_TRIANGLES as u64),
            });
        }
        if self.peak_bytes > MAX_IMPORT_BYTES {
            // Scale the triangle count down to what would fit, for the fix.
            let fits = (self.triangles as f64 * MAX_IMPORT_BYTES as f64 / self.peak_bytes as f64) as u64;
            let text = matches!(self.format, Format::StlAscii | Format::Obj);
            let mut fix = fix(fits.max(1));
            if text {
                fix.push_str("; binary STL or 3MF of the same mesh is 4–10× smaller");
            }
            return Err(Error::TooLarge {
                file: file.to_string(),
                problem: format!(
                    "reading {} triangles from this file needs about {} MiB of memory, limit {} MiB",
                    group(self.triangles),
                    group(self.peak_bytes >> 20),
                    group(MAX_IMPORT_BYTES >> 20)
                ),
                fix,
            });
        }
        Ok(())
    }
}

/// Why a file could not be read. Every message names the file, where, and what to do.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum Error {
    /// The file has no bytes.
    #[error("{file}: the file is empty; export the mesh again")]
    Empty {
        /// File name.
        file: String,
    },
    /// Not a format weft knows.
    #[error("{file}: not an STL, OBJ or 3MF file ({detail}); export as STL, OBJ or 3MF")]
    UnknownFormat {
        /// File name.
        file: String,
        /// What the first bytes looked like.
        detail: String,
    },
    /// A file named `.stl` (or read as one) that is neither binary nor text STL.
    #[error("{file} is not an STL file: {why}; export the mesh again as STL, OBJ or 3MF")]
    NotStl {
        /// File name.
        file: String,
        /// Why, in one clause.
        why: String,
    },
    /// The file is malformed at a known place.
    #[error("{file}: {place}: {problem}; {fix}")]
    Malformed {
        /// File name.
        file: String,
        /// Where: "line 12", "triangle 40 (byte 2014)", "3D/3dmodel.model line 8".
        place: String,
        /// What is wrong.
        problem: String,
        /// How to fix it.
        fix: String,
    },
    /// The file parsed but holds no usable triangle.
    #[error("{file}: no triangles with area were found; check that the file holds a surface mesh, not points or lines")]
    NoTriangles {
        /// File name.
        file: String,
    },
    /// The mesh is over [`MAX_TRIANGLES`] or [`MAX_IMPORT_BYTES`]; refused before its memory
    /// was allocated.
    #[error("{file}: {problem}; {fix}")]
    TooLarge {
        /// File name.
        file: String,
        /// The count or size and the limit.
        problem: String,
        /// What to change.
        fix: String,
    },
    /// A slot needs a closed solid and the mesh has holes that cannot be capped.
    #[error(transparent)]
    Open(close::OpenError),
}

/// Builds an [`Error::Malformed`].
pub(crate) fn malformed(file: &str, place: impl Into<String>, problem: impl Into<String>, fix: impl Into<String>) -> Error {
    Error::Malformed { file: file.to_string(), place: place.into(), problem: problem.into(), fix: fix.into() }
}

/// A parsed, not yet cleaned triangle list. Every index is in range of `vertices`, every
/// coordinate is finite (parsers guarantee both).
#[derive(Debug, Default)]
pub(crate) struct RawMesh {
    pub vertices: Vec<[f32; 3]>,
    pub triangles: Vec<[u32; 3]>,
}

/// Estimates what [`read_mesh`] will need for `bytes` without reading the mesh: the binary
/// STL header, a token scan of ASCII STL and OBJ (no number parsing), a counting pass over a
/// 3MF's XML (inflated in 64 KiB pieces, nothing kept but the object graph). At most one
/// pass over the bytes (the inflated bytes for 3MF); errors are those `read_mesh` gives for
/// the same damage where the scan meets it.
pub fn estimate(file: &str, bytes: &[u8]) -> Result<Estimate, Error> {
    let format = detect_format(file, bytes)?;
    let input = bytes.len() as u64;
    let (vertices, triangles, peak) = match format {
        Format::StlBinary => {
            let (v, t) = stl::binary_counts(bytes);
            (v, t, raw_peak(v, t))
        }
        Format::StlAscii => {
            let (v, t) = stl::scan_ascii(bytes);
            (v, t, raw_peak(v, t))
        }
        Format::Obj => {
            let (v, t) = obj::scan_obj(bytes);
            (v, t, raw_peak(v, t))
        }
        Format::ThreeMf => {
            let c = threemf::count_3mf(file, bytes)?;
            (c.vertices, c.triangles, c.peak_bytes)
        }
    };
    Ok(Estimate { format, triangles, vertices, peak_bytes: input.saturating_add(peak) })
}

/// The refusal [`read_mesh`] would give, from a file's first [`HEAD_BYTES`] bytes and its
/// length alone: a binary STL over the limits (detected as [`detect_format`] does: not a
/// zip, and exactly as long as its header's count says), or any file longer than
/// [`MAX_IMPORT_BYTES`] (its bytes alone are over the import's memory limit). So a front end
/// refuses such a file before reading it: the CLI reads nothing more of a 10 M-triangle STL,
/// and the page does not try to copy a file of gigabytes into its memory. `Ok` when the head
/// cannot tell: read the file, then [`read_mesh`].
pub fn check_head(file: &str, head: &[u8], len: u64) -> Result<(), Error> {
    let binary_stl = !head.starts_with(b"PK\x03\x04") && stl::count(head).is_some_and(|n| stl::binary_len(n) == len);
    if let (true, Some(n)) = (binary_stl, stl::count(head)) {
        let (v, t) = (3 * n as u64, n as u64);
        return Estimate { format: Format::StlBinary, triangles: t, vertices: v, peak_bytes: len.saturating_add(raw_peak(v, t)) }.check(file);
    }
    if len > MAX_IMPORT_BYTES {
        return Err(Error::TooLarge {
            file: file.to_string(),
            problem: format!("the file is {} MiB, more than the {} MiB weft reads a mesh from", group(len >> 20), group(MAX_IMPORT_BYTES >> 20)),
            fix: "decimate the mesh (e.g. in PrusaSlicer: right-click the object, Simplify model), or export it as binary STL or 3MF, which are 4–10× smaller than text".into(),
        });
    }
    Ok(())
}

/// Bytes [`check_head`] reads: a binary STL's header and count.
pub const HEAD_BYTES: usize = 84;

/// Memory an import uses whatever its size: stack, small allocations, parser buffers.
pub(crate) const FIXED_PEAK_BYTES: u64 = 2 << 20;

/// Peak bytes of reading into an exactly reserved [`RawMesh`] of `v` vertices and `t`
/// triangles and cleaning it ([`repair::extra_peak`]).
fn raw_peak(v: u64, t: u64) -> u64 {
    raw_bytes(v, t).saturating_add(repair::extra_peak(v, t)).saturating_add(FIXED_PEAK_BYTES)
}

/// Bytes of a [`RawMesh`] of `v` vertices and `t` triangles.
pub(crate) fn raw_bytes(v: u64, t: u64) -> u64 {
    v.saturating_add(t).saturating_mul(12)
}

/// Reads a mesh from `bytes`; `file` is only used in messages and to hint the format
/// (content decides: "solid" + facets → ASCII STL, zip → 3MF, `v `/`f ` lines → OBJ).
///
/// Before any mesh memory is allocated the counts are checked against [`MAX_TRIANGLES`]
/// and [`MAX_IMPORT_BYTES`] (as [`estimate`] computes them; for 3MF while the XML streams
/// and before build items are placed); over a limit is [`Error::TooLarge`].
///
/// The result is cleaned (see [`ImportReport`]): vertices closer than
/// [`Options::weld_tolerance_mm`] are welded, degenerate and duplicate triangles dropped.
pub fn read_mesh(file: &str, bytes: &[u8], options: &Options) -> Result<Imported, Error> {
    // Reading and cleaning are some twenty short parallel rounds: run from a pool thread, each
    // round's first items stay on it and no caller is woken between rounds (in the browser a
    // wake-up goes through `Atomics.wait`).
    crate::par::on_pool(|| read_mesh_on(file, bytes, options))
}

/// [`read_mesh`], on the calling thread.
fn read_mesh_on(file: &str, bytes: &[u8], options: &Options) -> Result<Imported, Error> {
    let format = detect_format(file, bytes)?;
    let mut unit_scale = 1.0;
    let input = bytes.len() as u64;
    let check = |v: u64, t: u64| Estimate { format, triangles: t, vertices: v, peak_bytes: input.saturating_add(raw_peak(v, t)) }.check(file);
    let tol = options.weld_tolerance_mm;
    let (triangles_read, repaired) = match format {
        Format::StlBinary => {
            let (v, t) = stl::binary_counts(bytes);
            check(v, t)?;
            read_and_repair(stl::read_binary(file, bytes)?, tol)
        }
        Format::StlAscii => {
            let (v, t) = stl::scan_ascii(bytes);
            check(v, t)?;
            read_and_repair(stl::read_ascii(file, bytes, (v, t))?, tol)
        }
        Format::Obj => {
            let (v, t) = obj::scan_obj(bytes);
            check(v, t)?;
            read_and_repair(obj::read_obj(file, bytes, (v, t))?, tol)
        }
        Format::ThreeMf => {
            let (raw, scale) = threemf::read_3mf(file, bytes)?;
            unit_scale = scale;
            read_and_repair(raw, tol)
        }
    };
    if repaired.mesh.triangles.is_empty() {
        return Err(Error::NoTriangles { file: file.to_string() });
    }
    let report = ImportReport {
        format: Some(format),
        triangles_read,
        triangles: repaired.mesh.triangles.len(),
        vertices: repaired.mesh.vertices.len(),
        degenerate_removed: repaired.degenerate_removed,
        duplicates_removed: repaired.duplicates_removed,
        open_edges: repaired.open_edges,
        unit_scale,
        closure: None,
        notes: Vec::new(),
    };
    Ok(Imported { mesh: repaired.mesh, report })
}

/// The triangles `raw` holds, and `raw` cleaned.
fn read_and_repair(raw: impl repair::Soup, tolerance_mm: f64) -> (usize, repair::Repaired) {
    (raw.triangle_count(), repair::repair(raw, tolerance_mm))
}

/// Detects the format of `bytes` from their content; `file`'s extension only breaks ties.
///
/// STL: binary when the length is exactly what the header's triangle count says (84 + 50·n
/// bytes), else ASCII when the start reads as text (no NUL and at most 4 other control
/// bytes in the first KiB) beginning with `solid`. A `.stl` that is neither is read as a damaged binary STL, so the error says where
/// it was cut short and why it is not ASCII (trailing bytes after the promised triangles,
/// which some exporters leave, are ignored).
pub fn detect_format(file: &str, bytes: &[u8]) -> Result<Format, Error> {
    if bytes.is_empty() {
        return Err(Error::Empty { file: file.to_string() });
    }
    if bytes.starts_with(b"PK\x03\x04") {
        return Ok(Format::ThreeMf);
    }
    if stl::binary_count_matches(bytes) {
        return Ok(Format::StlBinary);
    }
    let text = text_problem(bytes).is_none();
    let body = skip_bom_and_space(bytes);
    if text && starts_with_ignore_case(body, b"solid") {
        return Ok(Format::StlAscii);
    }
    if text && obj::looks_like_obj(bytes) {
        return Ok(Format::Obj);
    }
    let hint = extension(file);
    if !text && bytes.len() >= 84 && hint.as_deref() == Some("stl") {
        return Ok(Format::StlBinary);
    }
    if hint.as_deref() == Some("stl") {
        let why = match describe_guess(bytes, text) {
            Some(g) if bytes.len() >= 84 || text => g.to_string(),
            _ => stl::why_not_stl(bytes),
        };
        return Err(Error::NotStl { file: file.to_string(), why });
    }
    if text && hint.as_deref() == Some("obj") {
        return Ok(Format::Obj);
    }
    let mut detail = describe_start(bytes, text);
    if starts_with_ignore_case(body, b"solid") {
        detail.push_str("; ");
        detail.push_str(&stl::why_not_stl(bytes));
    }
    Err(Error::UnknownFormat { file: file.to_string(), detail })
}

fn extension(file: &str) -> Option<String> {
    let (_, ext) = file.rsplit_once('.')?;
    Some(ext.to_ascii_lowercase())
}

/// Control bytes (other than tab, CR, LF, form feed) a text start may hold: exporters leave
/// the odd one in a solid name; binary data has dozens per KiB.
const TEXT_CONTROL_BYTES: usize = 4;

/// `None` when the first KiB reads as text: no NUL byte and at most
/// [`TEXT_CONTROL_BYTES`] other control bytes; else why not, with the byte offset.
pub(crate) fn text_problem(bytes: &[u8]) -> Option<String> {
    let head = bytes.get(..bytes.len().min(1024)).unwrap_or(bytes);
    let is_control = |b: u8| b < 0x20 && !matches!(b, b'\n' | b'\r' | b'\t' | 0x0c);
    if let Some(at) = head.iter().position(|&b| b == 0) {
        return Some(format!("byte {at} is 0x00, which text never holds"));
    }
    let controls = head.iter().filter(|&&b| is_control(b)).count();
    if controls > TEXT_CONTROL_BYTES {
        let first = head.iter().position(|&b| is_control(b)).unwrap_or(0);
        return Some(format!(
            "the first {} bytes hold {controls} control bytes (the first at byte {first}), more than the {TEXT_CONTROL_BYTES} text may hold",
            head.len()
        ));
    }
    None
}

pub(crate) fn skip_bom_and_space(bytes: &[u8]) -> &[u8] {
    let b = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    let start = b.iter().position(|c| !c.is_ascii_whitespace()).unwrap_or(b.len());
    b.get(start..).unwrap_or_default()
}

fn starts_with_ignore_case(bytes: &[u8], prefix: &[u8]) -> bool {
    bytes.len() >= prefix.len() && bytes.iter().zip(prefix).all(|(a, b)| a.eq_ignore_ascii_case(b))
}

/// A short human description of the first bytes, for [`Error::UnknownFormat`].
/// What the file looks like instead, when its start says so.
fn describe_guess(bytes: &[u8], text: bool) -> Option<&'static str> {
    let body = skip_bom_and_space(bytes);
    if starts_with_ignore_case(body, b"ISO-10303-21") {
        Some("it looks like a STEP file; export a mesh from your CAD program")
    } else if starts_with_ignore_case(body, b"<!doctype html") || starts_with_ignore_case(body, b"<html") {
        Some("it looks like a web page, not a download of the file")
    } else if body.first() == Some(&b';') || starts_with_ignore_case(body, b"G28") || starts_with_ignore_case(body, b"G1 ") {
        Some("it looks like G-code; open it in the analyzer instead")
    } else if bytes.starts_with(b"\x89PNG") || bytes.starts_with(b"\xFF\xD8\xFF") || bytes.starts_with(b"GIF8") {
        Some("it looks like an image")
    } else if bytes.len() < 84 && !text {
        Some("too short for a binary STL")
    } else {
        None
    }
}

fn describe_start(bytes: &[u8], text: bool) -> String {
    let body = skip_bom_and_space(bytes);
    let guess = describe_guess(bytes, text);
    let shown = if text {
        let head: String =
            String::from_utf8_lossy(body.get(..body.len().min(24)).unwrap_or(body)).chars().map(|c| if c.is_control() { ' ' } else { c }).collect();
        format!("it starts with \"{}\"", head.trim_end())
    } else {
        let hex: Vec<String> = bytes.iter().take(8).map(|b| format!("{b:02x}")).collect();
        format!("it starts with bytes {}", hex.join(" "))
    };
    match guess {
        Some(g) => format!("{shown}; {g}"),
        None => shown,
    }
}

/// Parses a finite float; `None` for junk, NaN or infinity.
pub(crate) fn parse_finite(token: &[u8]) -> Option<f64> {
    let s = std::str::from_utf8(token).ok()?;
    let v: f64 = s.parse().ok()?;
    v.is_finite().then_some(v)
}

/// A token for messages: at most 32 characters, lossy UTF-8, control characters replaced.
pub(crate) fn show(token: &[u8]) -> String {
    clean_n(&String::from_utf8_lossy(token.get(..token.len().min(4 * 32 + 4)).unwrap_or(token)), 32)
}

/// A string from a file (name, unit, path, parser message) for messages and reports: at
/// most [`MAX_SHOWN_CHARS`] characters ("…" marks the cut), control characters replaced by
/// "�", so a huge or hostile name cannot flood or garble a message.
pub fn clean(s: &str) -> String {
    clean_n(s, MAX_SHOWN_CHARS)
}

fn clean_n(s: &str, max: usize) -> String {
    let mut out = String::with_capacity(s.len().min(4 * max + 3));
    for (i, c) in s.chars().enumerate() {
        if i == max {
            out.push('…');
            break;
        }
        out.push(if c.is_control() { '\u{FFFD}' } else { c });
    }
    out
}

/// `n` with thousands separators: 5,000,000.
pub(crate) fn group(n: u64) -> String {
    let digits = n.to_string();
    let mut out = String::with_capacity(digits.len() + digits.len() / 3);
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i) % 3 == 0 {
            out.push(',');
        }
        out.push(c);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_head_refuses_a_binary_stl_over_the_limits_and_nothing_else() {
        let head = |n: u32| {
            let mut h = vec![0u8; 80];
            h.extend_from_slice(&n.to_le_bytes());
            h
        };
        let over = (MAX_TRIANGLES + 1) as u32;
        let len = |n: u32| 84 + 50 * n as u64;
        let err = check_head("big.stl", &head(over), len(over)).unwrap_err().to_string();
        assert!(err.contains("big.stl") && err.contains("limit 5,000,000") && err.contains("decimate"), "{err}");
        // The same refusal as reading the whole file (its estimate).
        assert!(check_head("ok.stl", &head(1000), len(1000)).is_ok());
        // Not a binary STL by its length, a zip, or too short to tell: read the file first.
        assert!(check_head("big.stl", &head(over), len(over) + 1).is_ok());
        let mut zip = head(over);
        zip[..4].copy_from_slice(b"PK\x03\x04");
        assert!(check_head("big.3mf", &zip, len(over)).is_ok());
        assert!(check_head("a.stl", b"solid", 5).is_ok());
        // Any file longer than the import's memory limit (a 5 GB text mesh), whatever it is.
        let err = check_head("huge.obj", b"v 0 0 0\n", 5 << 30).unwrap_err().to_string();
        assert!(err.contains("huge.obj") && err.contains("5,120 MiB") && err.contains("1,024 MiB"), "{err}");
        assert!(check_head("big.obj", b"v 0 0 0\n", MAX_IMPORT_BYTES).is_ok());
    }

    #[test]
    fn empty_and_unknown() {
        let o = Options::default();
        assert_eq!(read_mesh("a.stl", b"", &o).unwrap_err(), Error::Empty { file: "a.stl".into() });
        let e = read_mesh("a.bin", b"hello world, not a mesh", &o).unwrap_err();
        let msg = e.to_string();
        assert!(matches!(e, Error::UnknownFormat { .. }), "{msg}");
        assert!(msg.contains("\"hello world, not a mesh\""), "{msg}");
        let e = read_mesh("a.step", b"ISO-10303-21;\nHEADER;", &o).unwrap_err().to_string();
        assert!(e.contains("STEP"), "{e}");
        let e = read_mesh("a.png", b"\x89PNG\r\n\x1a\n\0\0\0", &o).unwrap_err().to_string();
        assert!(e.contains("89 50 4e 47"), "{e}");
    }

    #[test]
    fn strings_are_bounded_and_numbers_grouped() {
        assert_eq!(clean("a\u{1b}[2Jb\n"), "a\u{FFFD}[2Jb\u{FFFD}");
        let long = clean(&"é".repeat(1000));
        assert_eq!(long.chars().count(), MAX_SHOWN_CHARS + 1);
        assert!(long.ends_with('…'));
        assert_eq!(show(&[b'x'; 100]).chars().count(), 33);
        assert_eq!((group(0), group(999), group(1000), group(544_761_204)), ("0".into(), "999".into(), "1,000".into(), "544,761,204".into()));
    }

    #[test]
    fn text_rule() {
        assert!(text_problem(b"solid a\x01b\n").is_none());
        assert!(text_problem(b"solid \x01\x02\x03\x04\x05").unwrap().contains("5 control bytes (the first at byte 6)"));
        assert!(text_problem(b"solid a\0").unwrap().contains("byte 7 is 0x00"));
    }

    #[test]
    fn detect() {
        assert_eq!(detect_format("x", b"PK\x03\x04rest").unwrap(), Format::ThreeMf);
        assert_eq!(detect_format("x", b"  solid a\nfacet normal 0 0 0\n").unwrap(), Format::StlAscii);
        assert_eq!(detect_format("x", b"# c\nv 0 0 0\nf 1 1 1\n").unwrap(), Format::Obj);
        let mut bin = vec![b' '; 84];
        bin[..5].copy_from_slice(b"solid");
        bin[80..84].copy_from_slice(&1u32.to_le_bytes());
        bin.extend_from_slice(&[0u8; 50]);
        assert_eq!(detect_format("x", &bin).unwrap(), Format::StlBinary);
    }
}

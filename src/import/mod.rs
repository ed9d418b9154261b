//! Mesh import: binary and ASCII STL, OBJ, 3MF → [`Mesh`] in millimetres.
//!
//! Entry: [`read_mesh`]. Every problem is a typed [`Error`] naming the file, the place in it
//! and the fix; nothing here panics on any input (fuzzed: `fuzz/`, and a seeded mutation
//! smoke test in `tests/fuzz_smoke.rs`).
//!
//! Pipeline: detect the format from the content ([`detect_format`]), parse into a raw indexed
//! triangle list, then clean it ([`repair`]): weld close vertices, drop degenerate and
//! duplicate triangles, count open edges. The output order follows the file order, so the
//! same bytes give the same [`Mesh`] on every run and platform.

mod obj;
mod repair;
mod stl;
mod threemf;

use crate::geom::Mesh;
use serde::Serialize;

pub use threemf::{MAX_MODEL_PART_BYTES, MAX_TRIANGLES};

/// Default vertex-weld distance in mm: vertices closer than this become one.
pub const DEFAULT_WELD_TOLERANCE_MM: f64 = 1e-4;

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
}

/// A mesh and what happened while reading it.
#[derive(Clone, Debug)]
pub struct Imported {
    /// The mesh, in mm.
    pub mesh: Mesh,
    /// What was read and repaired.
    pub report: ImportReport,
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
}

/// Builds an [`Error::Malformed`].
pub(crate) fn malformed(
    file: &str,
    place: impl Into<String>,
    problem: impl Into<String>,
    fix: impl Into<String>,
) -> Error {
    Error::Malformed { file: file.to_string(), place: place.into(), problem: problem.into(), fix: fix.into() }
}

/// A parsed, not yet cleaned triangle list. Every index is in range of `vertices`, every
/// coordinate is finite (parsers guarantee both).
#[derive(Debug, Default)]
pub(crate) struct RawMesh {
    pub vertices: Vec<[f32; 3]>,
    pub triangles: Vec<[u32; 3]>,
}

/// Reads a mesh from `bytes`; `file` is only used in messages and to hint the format
/// (content decides: "solid" + facets → ASCII STL, zip → 3MF, `v `/`f ` lines → OBJ).
///
/// The result is cleaned (see [`ImportReport`]): vertices closer than
/// [`Options::weld_tolerance_mm`] are welded, degenerate and duplicate triangles dropped.
pub fn read_mesh(file: &str, bytes: &[u8], options: &Options) -> Result<Imported, Error> {
    let format = detect_format(file, bytes)?;
    let mut unit_scale = 1.0;
    let raw = match format {
        Format::StlBinary => stl::read_binary(file, bytes)?,
        Format::StlAscii => stl::read_ascii(file, bytes)?,
        Format::Obj => obj::read_obj(file, bytes)?,
        Format::ThreeMf => {
            let (raw, scale) = threemf::read_3mf(file, bytes)?;
            unit_scale = scale;
            raw
        }
    };
    let triangles_read = raw.triangles.len();
    let repaired = repair::repair(raw, options.weld_tolerance_mm);
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
    };
    Ok(Imported { mesh: repaired.mesh, report })
}

/// Detects the format of `bytes` from their content; `file`'s extension only breaks ties
/// (a binary `.stl` whose triangle count disagrees with its length is read as a damaged
/// binary STL, so the error says where it was cut short).
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
    let text = looks_like_text(bytes);
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
    if text && hint.as_deref() == Some("obj") {
        return Ok(Format::Obj);
    }
    Err(Error::UnknownFormat { file: file.to_string(), detail: describe_start(bytes, text) })
}

fn extension(file: &str) -> Option<String> {
    let (_, ext) = file.rsplit_once('.')?;
    Some(ext.to_ascii_lowercase())
}

/// True when the first KiB is text: no NUL and no control bytes other than whitespace.
fn looks_like_text(bytes: &[u8]) -> bool {
    let head = bytes.get(..bytes.len().min(1024)).unwrap_or(bytes);
    head.iter().all(|&b| b >= 0x20 || matches!(b, b'\n' | b'\r' | b'\t' | 0x0c))
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
fn describe_start(bytes: &[u8], text: bool) -> String {
    let body = skip_bom_and_space(bytes);
    let guess = if starts_with_ignore_case(body, b"ISO-10303-21") {
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
    };
    let shown = if text {
        let head: String = String::from_utf8_lossy(body.get(..body.len().min(24)).unwrap_or(body))
            .chars()
            .map(|c| if c.is_control() { ' ' } else { c })
            .collect();
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

/// Cheap deterministic hasher for integer keys (lookups only; never iterated for output).
#[derive(Default, Clone, Copy)]
pub(crate) struct FxHasher(u64);

impl std::hash::Hasher for FxHasher {
    #[inline]
    fn finish(&self) -> u64 {
        // Final avalanche so the low bits (bucket index) depend on every input bit: float
        // bit patterns of round numbers end in long runs of zeros.
        let mut h = self.0;
        h ^= h >> 29;
        h = h.wrapping_mul(0xbf58_476d_1ce4_e5b9);
        h ^ (h >> 32)
    }
    #[inline]
    fn write(&mut self, bytes: &[u8]) {
        let mut chunks = bytes.chunks_exact(8);
        for c in &mut chunks {
            let mut w = [0u8; 8];
            w.copy_from_slice(c);
            self.write_u64(u64::from_le_bytes(w));
        }
        let rest = chunks.remainder();
        if !rest.is_empty() {
            let mut w = [0u8; 8];
            w.get_mut(..rest.len()).unwrap_or_default().copy_from_slice(rest);
            self.write_u64(u64::from_le_bytes(w));
        }
    }
    #[inline]
    fn write_u32(&mut self, i: u32) {
        self.write_u64(i as u64);
    }
    #[inline]
    fn write_u64(&mut self, i: u64) {
        self.0 = (self.0.rotate_left(5) ^ i).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
    #[inline]
    fn write_usize(&mut self, i: usize) {
        self.write_u64(i as u64);
    }
}

pub(crate) type FxBuild = std::hash::BuildHasherDefault<FxHasher>;
pub(crate) type FxHashMap<K, V> = std::collections::HashMap<K, V, FxBuild>;
pub(crate) type FxHashSet<K> = std::collections::HashSet<K, FxBuild>;

/// Parses a finite float; `None` for junk, NaN or infinity.
pub(crate) fn parse_finite(token: &[u8]) -> Option<f64> {
    let s = std::str::from_utf8(token).ok()?;
    let v: f64 = s.parse().ok()?;
    v.is_finite().then_some(v)
}

/// A token for messages: at most 32 characters, lossy UTF-8.
pub(crate) fn show(token: &[u8]) -> String {
    let s = String::from_utf8_lossy(token);
    let mut out: String = s.chars().take(32).collect();
    if s.chars().count() > 32 {
        out.push('…');
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

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

/// PROVISIONAL (replaced by the importer's own estimate when issue 7's import work merges):
/// the importer's work on `bytes`, from their size.
pub fn estimate(_file: &str, bytes: &[u8]) -> Result<crate::budget::Estimate, Error> {
    let n = bytes.len() as f64;
    Ok(crate::budget::Estimate::new("import").quantity("file_bytes", "File", n, "bytes").cost(3.3 * n, n * 2e-8).budgets("simplify the mesh"))
}

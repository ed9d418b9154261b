//! Mesh import: binary and ASCII STL, OBJ, 3MF → [`Mesh`] in millimetres.
//!
//! Entry: [`read_mesh`]. Every problem is a typed [`Error`] naming the file, the place in it
//! and the fix; nothing here panics on any input (fuzzed: `fuzz/`).

use crate::geom::Mesh;
use serde::Serialize;

/// Default vertex-weld distance in mm: vertices closer than this become one.
pub const DEFAULT_WELD_TOLERANCE_MM: f64 = 1e-4;

/// Import options.
#[derive(Clone, Debug, PartialEq)]
pub struct Options {
    /// Vertices closer than this (mm) are merged. Default [`DEFAULT_WELD_TOLERANCE_MM`].
    pub weld_tolerance_mm: f64,
}

impl Default for Options {
    fn default() -> Self {
        Options { weld_tolerance_mm: DEFAULT_WELD_TOLERANCE_MM }
    }
}

/// File formats weft reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
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
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct ImportReport {
    /// Detected format.
    pub format: Option<Format>,
    /// Triangles in the file.
    pub triangles_read: usize,
    /// Triangles kept.
    pub triangles: usize,
    /// Distinct vertices after welding.
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

/// Reads a mesh from `bytes`; `file` is only used in messages and to hint the format
/// (content decides: "solid" + facets → ASCII STL, zip → 3MF, `v `/`f ` lines → OBJ).
pub fn read_mesh(file: &str, bytes: &[u8], options: &Options) -> Result<Imported, Error> {
    let _ = (bytes, options);
    Err(Error::UnknownFormat { file: file.to_string(), detail: "importer not built yet".into() })
}

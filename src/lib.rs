//! # weft — a slicer for architected lattices and research toolpaths
//!
//! The pure-Rust core behind the browser app (through the thin binding `wasm.rs`) and the
//! `weft` CLI. One versioned [`Design`] describes a job; [`run`] turns it into G-code:
//!
//! ```text
//!  Design ──► kinds::Registry::get(job.kind) ──► the kind's stages ──► Toolpath
//!  (JSON,       slice, lattice, axisymmetric,      (cached per stage,     │
//!   versioned)  graded, foam, freeform             stage::Ctx)            ▼
//!                                                     gcode::write_gcode ──► analyze
//! ```
//!
//! The front: [`Design`] (the document), [`run`] / [`estimate`] / [`inspect`] (the pipeline),
//! [`Registry`] (the job kinds), [`Toolpath`] (what a kind makes), [`analyze()`] (any G-code
//! read back). Below them, one module per paper's algorithm (`lattice`, `paths`, `axisym`,
//! `scaffold`, `foam`, `freeform`, …) on the shared vocabulary [`geom`]; ARCHITECTURE.md
//! gives the floors each module may use. Units: millimetres, seconds, degrees Celsius. The
//! same design gives byte-identical G-code on native and wasm builds at any thread count.

#![warn(missing_docs)]

pub use analyze::analyze;
pub use design::Design;
pub use geom::Toolpath;
pub use kinds::Registry;
pub use pipeline::{estimate, inspect, run, RunOptions, RunOutput};

// The document, the pipeline and the job kinds.
pub mod catalog;
pub mod design;
pub mod kinds;
pub mod pipeline;
mod stage;

// The papers' algorithms.
pub mod axisym;
pub mod foam;
pub mod freeform;
pub mod gcode_edit;
pub mod isosurface;
pub mod lattice;
pub mod nonplanar;
pub mod paths;
pub mod scaffold;
pub mod volume;

// The foundation: meshes in, layers, G-code out and read back.
pub mod analyze;
pub mod export;
pub mod gcode;
pub mod import;
pub mod machine;
pub mod motion;
pub mod slice;

// The shared vocabulary and small utilities.
pub mod budget;
mod clock;
pub mod geom;
pub mod par;
pub mod report;
pub mod settings;
pub mod source;
/// The examples' thumbnails: drawn by the browser's binding (`thumbnailSvg`).
#[cfg(any(test, target_arch = "wasm32"))]
mod thumbnail;
pub mod work;

// Tests, benchmarks and the faces' own parts.
/// `weft bench`: the workloads of BENCHMARKS.md (feature `bench`: on for the CLI and the
/// tests, off in the served wasm).
#[cfg(feature = "bench")]
pub mod bench;
/// Generators of test inputs (meshes, designs, DICOM series, foreign G-code): the tests and
/// `weft bench` only.
#[cfg(any(test, feature = "bench"))]
pub mod testgen;
/// The threaded browser module's allocator: compiled there (and for its own unit tests) only.
#[cfg(any(test, all(target_arch = "wasm32", feature = "wasm-threads")))]
mod thread_cache;
#[cfg(target_arch = "wasm32")]
mod wasm;

/// The threaded browser module allocates through per-thread caches (see [`thread_cache`]).
#[cfg(all(target_arch = "wasm32", feature = "wasm-threads"))]
#[global_allocator]
static ALLOCATOR: thread_cache::ThreadCache = thread_cache::ThreadCache;

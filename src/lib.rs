//! # weft — a slicer for architected lattices and research toolpaths
//!
//! The pure-Rust core behind the browser app (through a thin wasm binding) and the `weft` CLI.
//!
//! ```text
//!  Design (JSON, versioned) ──► pipeline::run
//!      │ job = slice
//!      ▼
//!  import::read_mesh ─► slice::slice ─► gcode::write_gcode ─► analyze::analyze
//!   STL/OBJ/3MF          regions,         Marlin text,           report + preview
//!   → Mesh (mm)          perimeters,      equation-4 E           buffers
//!                        infill → Toolpath
//! ```
//!
//! Every stage is a module with one entry function, an `Options` struct with documented
//! defaults, its output type and its own `Error` enum; stages share only the types in
//! [`geom`]. Units: millimetres, seconds, degrees Celsius. Output is deterministic: the same
//! design gives byte-identical G-code on native and wasm builds.

#![warn(missing_docs)]

pub mod analyze;
pub mod axisym;
pub mod budget;
pub mod catalog;
pub mod clock;
pub mod design;
pub mod gcode;
pub mod gcode_edit;
pub mod geom;
pub mod import;
pub mod isosurface;
pub mod jobs;
pub mod lattice;
pub mod machine;
pub mod motion;
pub mod nonplanar;
pub mod par;
pub mod paths;
pub mod pipeline;
pub mod report;
pub mod scaffold;
pub mod settings;
pub mod slice;
pub mod source;
pub mod stage;
pub mod testgen;
/// The threaded browser module's allocator: compiled there (and for its own unit tests) only.
#[cfg(any(test, all(target_arch = "wasm32", feature = "wasm-threads")))]
mod thread_cache;
pub mod thumbnail;
pub mod volume;
pub mod work;

pub use design::Design;
pub use pipeline::{run, RunOptions, RunOutput};
pub mod bench;
pub mod export;
pub mod foam;
pub mod freeform;
#[cfg(target_arch = "wasm32")]
mod wasm;

/// The threaded browser module allocates through per-thread caches (see [`thread_cache`]).
#[cfg(all(target_arch = "wasm32", feature = "wasm-threads"))]
#[global_allocator]
static ALLOCATOR: thread_cache::ThreadCache = thread_cache::ThreadCache;

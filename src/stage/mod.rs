//! The stage runtime, below the job kinds and the pipeline: files ([`Files`]), cache keys
//! ([`Key`]), the stage cache ([`Cache`], [`Out`]), what a kind's run sees ([`Ctx`]), input
//! loaders, errors ([`Error`]) and the vocabulary a kind declares itself in ([`JobKind`],
//! [`Kind`], [`Slot`], …). Every stage goes through [`Ctx::stage`], which keys its output by a
//! hash of the design parts the stage reads and of its upstream keys.

mod cache;
mod ctx;
mod error;
mod files;
mod key;
mod kind;
mod load;

pub use cache::{Cache, Out};
pub use ctx::{send_nowhere, writer_options, Ahead, Ctx, Sender, StageTime};
pub use error::Error;
pub use files::{FileSource, Files};
pub use key::Key;
pub use kind::{settings, with_kind, Inspection, JobKind, Kind, Product, Shape, Slot, SlotKind, StageInfo, StepInfo, Teach, ViewInfo, FILE_HEAD_BYTES};
pub use load::{meshes_of_zip, NamedFiles};

// Shared among the runtime's files (each file takes what it needs of these with `use super::*`).
use cache::Entry;
use load::{import_report, load_input, named_bytes, read_solid};

use crate::analyze;
use crate::budget::Estimate;
use crate::design::{share, Design, Input};
use crate::gcode;
use crate::geom::{DVec3, Mesh, Toolpath};
use crate::import::{self, ImportReport};
use crate::report::StageReport;
use crate::settings::{Problem, Row};
use crate::source::ByteSource;
use crate::volume;
use serde::de::DeserializeOwned;
use serde::Serialize;
use serde_json::Value;
use std::any::Any;
use std::collections::BTreeMap;
use std::sync::Arc;

//! Why a run failed.

use super::*;

/// Why a run failed.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The design names a file that was not given.
    #[error("the design's {slot} input is '{name}', which is not loaded; load {name} (drop it on the page, or pass --input {slot}={name})")]
    MissingInput {
        /// File name.
        name: String,
        /// The slot.
        slot: String,
    },
    /// A loaded file kept outside the core could not be read any more.
    #[error("{name} could not be read ({message}); load it again")]
    Unreadable {
        /// The file's name.
        name: String,
        /// Why, as the browser said.
        message: String,
    },
    /// The copy of a file inside the design (put there by a share link) is damaged.
    #[error("the copy of {name} inside the design is damaged (the link it came with was cut short or changed while copying); load {name} itself, or ask for the link again")]
    Embedded {
        /// The file's name.
        name: String,
        /// What [`share::unpack`] said.
        source: share::Error,
    },
    /// Import failed.
    #[error(transparent)]
    Import(#[from] import::Error),
    /// A stage of the job failed (`stage` says which; `source` is the stage's own error).
    #[error("{stage}: {source}")]
    Stage {
        /// Stage name as the user reads it (`slicing`, `lattice`).
        stage: &'static str,
        /// The stage's error.
        source: Box<dyn std::error::Error + Send + Sync>,
    },
    /// A job that needs an input has none.
    #[error("{0}")]
    NoInput(String),
    /// The job settings do not fit the kind (a bug: designs are normalised when read).
    #[error("the job settings cannot be read: {0}")]
    BadJob(String),
    /// The design's job kind is not known to this build.
    #[error("unknown job kind '{kind}'; this weft knows {known}")]
    UnknownKind {
        /// The kind.
        kind: String,
        /// The known ones.
        known: String,
    },
    /// An `inspect` request names a view the job does not have.
    #[error("a {job} job has no view '{view}'")]
    UnknownView {
        /// The view.
        view: String,
        /// The job kind.
        job: &'static str,
    },
    /// Writing failed.
    #[error("G-code: {0}")]
    Gcode(#[from] gcode::Error),
    /// Reading back failed (a bug: weft's own G-code must always analyse).
    #[error("analysing the written G-code: {0}")]
    Analyze(#[from] analyze::Error),
    /// The run's estimate is over a budget or a limit (stated before running anything).
    #[error("{stage}: {source}")]
    TooBig {
        /// The stage whose estimate is over.
        stage: String,
        /// What, the limit and the fix.
        source: crate::budget::OverBudget,
    },
}

impl Error {
    /// Wraps a stage's own error.
    pub fn stage(stage: &'static str, source: impl std::error::Error + Send + Sync + 'static) -> Error {
        Error::Stage { stage, source: Box::new(source) }
    }
}

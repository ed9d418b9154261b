//! The stage cache kept between runs, and a stage output with its key.

use super::*;

pub(super) struct Entry {
    pub(super) key: Key,
    pub(super) value: Arc<dyn Any + Send + Sync>,
    pub(super) report: Option<StageReport>,
    /// Wall time it took, ms, while no run has counted it yet (an import the estimate made
    /// before the run that reads it): the run's timings count it once.
    pub(super) uncounted_ms: Option<f64>,
    /// A recording for a step of "How it works" ([`Ctx::recording`]).
    pub(super) recording: bool,
}

/// Stage outputs kept between runs: the newest output of each stage (by cache id), with the
/// key it was computed for. A run reuses an entry only when its key matches exactly.
#[derive(Default)]
pub struct Cache {
    pub(super) entries: BTreeMap<String, Entry>,
    pub(super) enabled: bool,
}

impl Cache {
    /// A cache that keeps outputs between runs (the page's worker).
    pub fn new() -> Cache {
        Cache { entries: BTreeMap::new(), enabled: true }
    }

    /// No caching: every stage runs once and nothing is kept after the run (the CLI, one run);
    /// only what the estimate makes and the run reads again is kept ([`Ctx::stage_kept`]).
    pub fn disabled() -> Cache {
        Cache::default()
    }

    /// Drops every recording ([`Ctx::recording`]: the steps of "How it works" were closed),
    /// keeping the stages; returns how many were dropped.
    pub fn drop_recordings(&mut self) -> usize {
        let before = self.entries.len();
        self.entries.retain(|_, e| !e.recording);
        before - self.entries.len()
    }

    /// Cache ids held (for tests and diagnostics).
    pub fn ids(&self) -> Vec<String> {
        self.entries.keys().cloned().collect()
    }
}

/// A stage's output with its key (pass the key on as the upstream of the next stage).
pub struct Out<T> {
    /// The output (shared with the cache).
    pub value: Arc<T>,
    /// What it was computed from.
    pub key: Key,
}

impl<T> Clone for Out<T> {
    fn clone(&self) -> Self {
        Out { value: self.value.clone(), key: self.key }
    }
}

impl<T> std::ops::Deref for Out<T> {
    type Target = T;
    fn deref(&self) -> &T {
        &self.value
    }
}

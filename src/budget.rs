//! Work estimates and budgets: every stage states its work **before** doing it, and refuses
//! over a stated budget before allocating.
//!
//! A stage's `estimate` function turns its input's size and its options into an [`Estimate`]:
//! what it will make (layers, struts, segments, G-code bytes…), the peak memory it will
//! allocate and the time it will take on the reference machine. The stage's entry function
//! calls [`Estimate::check`] first, so the numbers a user is shown (`weft run --dry-run`, the
//! page's question before a big run) and the numbers that refuse a run are the same.
//!
//! Two thresholds:
//! - **Hard budgets** ([`MAX_STAGE_BYTES`], [`MAX_STAGE_SECONDS`], and each stage's own count
//!   limits): a run within them fits the browser worker's memory (wasm32 gets at most 4 GiB and
//!   browsers reliably grant about 2 GiB, shared by every stage output the run holds) and ends
//!   in minutes. Over them the stage returns [`OverBudget`], naming the number, the limit and
//!   the setting to change.
//! - **Ask first** ([`ASK_SECONDS`], [`ASK_SEGMENTS`], [`ASK_GCODE_BYTES`]): a run this big is
//!   legitimate but not what a newcomer expects from a click; the page shows the estimate and
//!   asks, a share link over it opens without running.
//!
//! Times are estimated from per-item costs measured by `weft bench` on the reference machine
//! (see BENCHMARKS.md): they are meant to be right within a factor of about two, which is
//! what a "this will take about a minute" question needs.

use serde::Serialize;

/// Peak memory one stage may allocate, bytes. The browser worker reliably gets about 2 GiB of
/// wasm memory; a stage's peak comes on top of the outputs the run already holds (mesh,
/// previous stage, G-code), so one stage gets 1.25 GiB.
pub const MAX_STAGE_BYTES: f64 = 1.25 * GIB;
/// Longest estimated time of one stage on the reference machine, s. Over this a run is
/// refused: it would hold the browser worker for more than a quarter of an hour.
pub const MAX_STAGE_SECONDS: f64 = 900.0;
/// Runs estimated to take longer than this (s, all stages) are asked about first.
pub const ASK_SECONDS: f64 = 5.0;
/// Runs with more toolpath segments than this are asked about first (the preview and the
/// analyzer handle them, but they are big). A 1M-triangle part sliced at 0.2 mm makes about
/// 1.2M, which the page runs and shows in 2.4 s on 2 threads: such a drop is not asked about.
pub const ASK_SEGMENTS: f64 = 2e6;
/// Runs writing more G-code than this (bytes) are asked about first.
pub const ASK_GCODE_BYTES: f64 = 50e6;

/// 2³⁰ bytes.
pub const GIB: f64 = 1024.0 * 1024.0 * 1024.0;
/// 2²⁰ bytes.
pub const MIB: f64 = 1024.0 * 1024.0;

/// One count a stage states (`layers`, `struts`, `segments`, `gcode_bytes`…).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Quantity {
    /// Key (stable, for scripts and tests).
    pub key: &'static str,
    /// What it counts, in plain words.
    pub label: &'static str,
    /// Estimated value (an upper bound where the stage can give one).
    pub value: f64,
    /// Unit (`mm`, `bytes`; empty for counts).
    pub unit: &'static str,
}

/// A stage's statement of its work, made before it runs.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Estimate {
    /// Stage name (`slice`, `lattice`…).
    pub stage: &'static str,
    /// What it will make.
    pub quantities: Vec<Quantity>,
    /// Peak memory it allocates, bytes.
    pub bytes: f64,
    /// Time on the reference machine, s, on one thread.
    pub seconds: f64,
    /// Share of [`Estimate::seconds`] that runs on every thread of the pool (0: one thread),
    /// as measured at 1 and 2 threads (`weft bench`): the plan's wall time on `n` threads
    /// counts this share divided by `n` (Amdahl).
    pub parallel_share: f64,
    /// Why it would be refused: the first budget or count limit exceeded.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub refused: Option<OverBudget>,
    /// What makes this stage's output smaller, as [`Estimate::budgets`] was told: the plan
    /// gives it to the writer's and the analyzer's refusals of the job's last stage's output,
    /// so they name the job's own settings.
    #[serde(skip)]
    pub smaller: Option<String>,
}

/// A budget or limit a stage would exceed.
#[derive(Clone, Debug, PartialEq, Serialize, thiserror::Error)]
#[error("{what} would be about {}, limit {}: {fix}", human(*value, unit), human(*limit, unit))]
pub struct OverBudget {
    /// What is over (`struts on one layer`, `peak memory`).
    pub what: String,
    /// The estimate.
    pub value: f64,
    /// The limit.
    pub limit: f64,
    /// Unit of both (`bytes`, `s`, or empty for counts).
    pub unit: &'static str,
    /// The setting to change.
    pub fix: String,
}

impl Estimate {
    /// An estimate of `stage` with no work yet.
    pub fn new(stage: &'static str) -> Estimate {
        Estimate { stage, quantities: Vec::new(), bytes: 0.0, seconds: 0.0, parallel_share: 0.0, refused: None, smaller: None }
    }

    /// Adds a count.
    pub fn quantity(mut self, key: &'static str, label: &'static str, value: f64, unit: &'static str) -> Estimate {
        self.quantities.push(Quantity { key, label, value, unit });
        self
    }

    /// Sets the peak memory (bytes) and the time (s).
    pub fn cost(mut self, bytes: f64, seconds: f64) -> Estimate {
        self.bytes = bytes;
        self.seconds = seconds;
        self
    }

    /// Sets the share of the time that runs on every thread (clamped to 0–1).
    pub fn parallel(mut self, share: f64) -> Estimate {
        self.parallel_share = if share.is_finite() { share.clamp(0.0, 1.0) } else { 0.0 };
        self
    }

    /// The time on `threads` threads, s (Amdahl over [`Estimate::parallel_share`]).
    pub fn seconds_on(&self, threads: usize) -> f64 {
        let p = self.parallel_share;
        self.seconds * ((1.0 - p) + p / threads.max(1) as f64)
    }

    /// The value of quantity `key` (0 when the stage did not state it).
    pub fn get(&self, key: &str) -> f64 {
        self.quantities.iter().find(|q| q.key == key).map_or(0.0, |q| q.value)
    }

    /// Refuses when `value` (of `what`, in `unit`) is over `limit` (or not a number), unless an
    /// earlier limit already refused; `fix` names the setting to change.
    pub fn limit(mut self, what: &str, value: f64, limit: f64, unit: &'static str, fix: impl Into<String>) -> Estimate {
        if self.refused.is_none() && !(value <= limit) {
            self.refused = Some(OverBudget { what: what.into(), value, limit, unit, fix: fix.into() });
        }
        self
    }

    /// Applies the shared memory and time budgets (after the stage's own count limits, which
    /// name a more specific fix); `fix` says what makes the stage smaller.
    pub fn budgets(mut self, fix: &str) -> Estimate {
        let (bytes, seconds) = (self.bytes, self.seconds);
        self.smaller = Some(fix.to_string());
        self.limit("its peak memory", bytes, MAX_STAGE_BYTES, "bytes", fix).limit("its time", seconds, MAX_STAGE_SECONDS, "s", fix)
    }

    /// `Err` with the first budget exceeded: call before allocating.
    pub fn check(&self) -> Result<(), OverBudget> {
        match &self.refused {
            Some(r) => Err(r.clone()),
            None => Ok(()),
        }
    }
}

/// `value` in `unit` as a person reads it: `18.5M`, `1.2 GiB`, `3 min`.
pub fn human(value: f64, unit: &str) -> String {
    if !value.is_finite() {
        return "beyond any limit".into();
    }
    match unit {
        "bytes" => {
            let (v, u) = if value >= GIB {
                (value / GIB, "GiB")
            } else if value >= MIB {
                (value / MIB, "MiB")
            } else if value >= 1024.0 {
                (value / 1024.0, "KiB")
            } else {
                (value, "bytes")
            };
            format!("{} {u}", sig(v))
        }
        "s" => {
            if value >= 5400.0 {
                format!("{} h", sig(value / 3600.0))
            } else if value >= 90.0 {
                format!("{} min", sig(value / 60.0))
            } else {
                format!("{} s", sig(value))
            }
        }
        _ => {
            let (v, s) = if value >= 1e9 {
                (value / 1e9, "G")
            } else if value >= 1e6 {
                (value / 1e6, "M")
            } else if value >= 1e4 {
                (value / 1e3, "k")
            } else {
                (value, "")
            };
            let unit = if unit.is_empty() { String::new() } else { format!(" {unit}") };
            format!("{}{s}{unit}", sig(v))
        }
    }
}

/// Three significant figures at most, without trailing zeros.
fn sig(v: f64) -> String {
    let digits = if v >= 100.0 {
        0
    } else if v >= 10.0 {
        1
    } else {
        2
    };
    let s = format!("{v:.digits$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// A whole run's estimate: every stage's, in run order, and the totals the page and
/// `--dry-run` show.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Plan {
    /// Each stage's estimate, in run order.
    pub stages: Vec<Estimate>,
    /// Sum of the stages' times on one thread, s (the budgets are checked on this: a design
    /// is refused or not whatever the machine).
    pub seconds: f64,
    /// Threads the run will use.
    pub threads: usize,
    /// Sum of the stages' times on [`Plan::threads`] threads, s: what the page shows and asks
    /// about.
    pub wall_seconds: f64,
    /// Largest stage peak, bytes.
    pub peak_bytes: f64,
    /// Toolpath segments (the writer's estimate).
    pub segments: f64,
    /// G-code size, bytes (the writer's estimate).
    pub gcode_bytes: f64,
    /// The first refusal, with its stage.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub refused: Option<(String, OverBudget)>,
    /// The refusal as the user reads it (`stage: what would be about …, limit …: fix`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub refusal: Option<String>,
    /// Why the page should ask before running (over a soft threshold), in plain words.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ask: Option<String>,
}

impl Plan {
    /// The plan of `stages` (in run order) on one thread.
    pub fn new(stages: Vec<Estimate>) -> Plan {
        Plan::on_threads(stages, 1)
    }

    /// The plan of `stages` (in run order) for a run on `threads` threads.
    pub fn on_threads(mut stages: Vec<Estimate>, threads: usize) -> Plan {
        // A stage with nothing to state (a built-in shape's import) is left out.
        stages.retain(|e| !e.quantities.is_empty() || e.bytes > 0.0 || e.seconds > 0.0 || e.refused.is_some());
        let threads = threads.max(1);
        let seconds = stages.iter().map(|e| e.seconds).sum::<f64>();
        let wall_seconds = stages.iter().map(|e| e.seconds_on(threads)).sum::<f64>();
        let peak_bytes = stages.iter().map(|e| e.bytes).fold(0.0, f64::max);
        let segments = stages.iter().map(|e| e.get("segments")).fold(0.0, f64::max);
        let gcode_bytes = stages.iter().map(|e| e.get("gcode_bytes")).fold(0.0, f64::max);
        let refused = stages.iter().find_map(|e| e.refused.clone().map(|r| (e.stage.to_string(), r)));
        let mut reasons = Vec::new();
        if wall_seconds > ASK_SECONDS {
            reasons.push(format!("about {}", human(wall_seconds, "s")));
        }
        if segments > ASK_SEGMENTS {
            reasons.push(format!("{} segments", human(segments, "")));
        }
        if gcode_bytes > ASK_GCODE_BYTES {
            reasons.push(format!("{} of G-code", human(gcode_bytes, "bytes")));
        }
        let ask = (!reasons.is_empty()).then(|| format!("a big job: {}", reasons.join(", ")));
        let refusal = refused.as_ref().map(|(stage, r)| format!("{stage}: {r}"));
        Plan { stages, seconds, threads, wall_seconds, peak_bytes, segments, gcode_bytes, refused, refusal, ask }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_first_limit_exceeded_refuses_with_its_fix() {
        let e = Estimate::new("lattice")
            .quantity("struts", "struts on the densest layer", 18.5e6, "")
            .cost(3.0 * GIB, 10.0)
            .limit("struts on one layer", 18.5e6, 2e6, "", "use cells ≥ 0.6 mm or a smaller domain")
            .budgets("a smaller domain");
        let r = e.check().unwrap_err();
        assert_eq!(r.to_string(), "struts on one layer would be about 18.5M, limit 2M: use cells ≥ 0.6 mm or a smaller domain");
        let e = Estimate::new("slice").cost(3.0 * GIB, 10.0).budgets("thicker layers");
        assert_eq!(e.check().unwrap_err().to_string(), "its peak memory would be about 3 GiB, limit 1.25 GiB: thicker layers");
        let e = Estimate::new("slice").cost(f64::NAN, 1.0).budgets("x");
        assert!(e.check().is_err(), "a NaN estimate is refused, never let through");
        assert!(Estimate::new("slice").cost(1e6, 1.0).budgets("x").check().is_ok());
    }

    #[test]
    fn a_plan_asks_over_the_soft_thresholds_only() {
        let small = Plan::new(vec![Estimate::new("slice").cost(1e6, 1.0).quantity("segments", "", 1e5, "")]);
        assert_eq!(small.ask, None);
        let big = Plan::new(vec![Estimate::new("slice").cost(1e6, 1.0), Estimate::new("gcode").cost(1e6, 6.0).quantity("gcode_bytes", "", 60e6, "bytes")]);
        assert_eq!(big.ask.as_deref(), Some("a big job: about 7 s, 57.2 MiB of G-code"));
        assert_eq!(human(150.0, "s"), "2.5 min");
    }

    #[test]
    fn the_wall_time_counts_the_parallel_share_on_each_thread() {
        let stages = || vec![Estimate::new("slice").cost(1e6, 8.0).parallel(0.75), Estimate::new("gcode").cost(1e6, 1.0)];
        let one = Plan::on_threads(stages(), 1);
        assert_eq!((one.seconds, one.wall_seconds), (9.0, 9.0));
        assert!(one.ask.is_some());
        // 8 s × (0.25 + 0.75 / 4) + 1 s = 4.5 s: under the question's threshold on 4 threads.
        let four = Plan::on_threads(stages(), 4);
        assert_eq!((four.seconds, four.wall_seconds, four.threads), (9.0, 4.5, 4));
        assert_eq!(four.ask, None);
        assert_eq!(Estimate::new("x").parallel(f64::NAN).parallel_share, 0.0);
        assert_eq!(Estimate::new("x").parallel(3.0).parallel_share, 1.0);
    }
}

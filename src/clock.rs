//! Wall time for reports (planning time), in seconds from an arbitrary start. Natively
//! `std::time::Instant`; in the browser the host sets the clock, so the core stays free of
//! JavaScript: `wasm.rs` gives it `Date.now()`, to the millisecond (`Instant` panics on
//! wasm32-unknown-unknown, and `performance.now()` counts from each web worker's own start,
//! so the pool's threads would disagree). Never used for a decision: output never depends
//! on it.

use std::sync::OnceLock;

static HOST: OnceLock<fn() -> f64> = OnceLock::new();

/// Sets the clock (once; later calls are ignored): the browser's binding does, natively
/// `Instant` is the clock.
#[cfg(target_arch = "wasm32")]
pub fn set(now_s: fn() -> f64) {
    let _ = HOST.set(now_s);
}

/// Seconds since an arbitrary start; NaN where no clock is known.
pub fn now_s() -> f64 {
    if let Some(f) = HOST.get() {
        return f();
    }
    native()
}

#[cfg(not(target_arch = "wasm32"))]
fn native() -> f64 {
    static START: OnceLock<std::time::Instant> = OnceLock::new();
    START.get_or_init(std::time::Instant::now).elapsed().as_secs_f64()
}

#[cfg(target_arch = "wasm32")]
fn native() -> f64 {
    f64::NAN
}

//! Any bytes must give an analysis or an error, never a panic.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = weft::analyze::analyze("fuzz", data, &Default::default());
});

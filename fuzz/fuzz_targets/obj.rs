//! Any bytes named `.obj` must give `Ok` or `Err`, never a panic.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = weft::import::read_mesh("fuzz.obj", data, &weft::import::Options::default());
});

//! Any share-URL fragment must decode to a design or an error, never a panic.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let s = String::from_utf8_lossy(data);
    let _ = weft::design::share::decode(&s);
});

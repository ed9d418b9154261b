//! Any bytes named `.3mf` must give `Ok` or `Err`, never a panic. Inputs that do not start
//! with the zip magic get it prepended so the fuzzer spends its time inside the 3MF reader.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let options = weft::import::Options::default();
    if data.starts_with(b"PK\x03\x04") {
        let _ = weft::import::read_mesh("fuzz.3mf", data, &options);
    } else {
        let mut v = b"PK\x03\x04".to_vec();
        v.extend_from_slice(data);
        let _ = weft::import::read_mesh("fuzz.3mf", &v, &options);
    }
});

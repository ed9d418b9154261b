//! Any bytes named `.3mf` must give `Ok` or `Err`, never a panic. Inputs that do not start
//! with the zip magic get it prepended so the fuzzer spends its time inside the 3MF reader.
//! The estimate's counting pass must count the triangles a successful read places.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let options = weft::import::Options::default();
    let owned;
    let bytes = if data.starts_with(b"PK\x03\x04") {
        data
    } else {
        owned = [b"PK\x03\x04".as_slice(), data].concat();
        &owned
    };
    let read = weft::import::read_mesh("fuzz.3mf", bytes, &options);
    let estimate = weft::import::estimate("fuzz.3mf", bytes);
    // The counting pass places exactly what a successful read places.
    if let (Ok(im), Ok(est)) = (read, estimate) {
        assert_eq!(est.triangles, im.report.triangles_read as u64);
    }
});

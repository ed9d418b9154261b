//! Any bytes named `.stl` (binary or ASCII) must give `Ok` or `Err`, never a panic, and the
//! estimate must count the triangles a successful read reads.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let read = weft::import::read_mesh("fuzz.stl", data, &weft::import::Options::default());
    let estimate = weft::import::estimate("fuzz.stl", data);
    // The estimate counts exactly what a successful read reads.
    if let (Ok(im), Ok(est)) = (read, estimate) {
        assert_eq!(est.triangles, im.report.triangles_read as u64);
    }
});

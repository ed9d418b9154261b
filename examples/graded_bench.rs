//! Times the graded job's stages on the paper's CT size: a 182 × 197 × 107 series (the femur
//! case's table 2: 0.976562 × 0.976562 × 3.27 mm voxels) of weft's bone phantom read from its
//! DICOM files, the surface model extracted from it, and a 50 MB PrusaSlicer-style G-code
//! edited by its density; the 1× / 4× ratios of each (the same workload the browser worker
//! runs in `tests/e2e/bench.mjs`' graded case, when built with the `bench` feature: both
//! come from `weft::bench::graded`; `weft bench --graded` times that case's pipeline calls).
//! `cargo run --release --example graded_bench`

use std::time::Instant;
use weft::bench::graded::{foreign_gcode, series, SERIES_DIMS};
use weft::geom::DVec3;
use weft::volume::{self, Roi};
use weft::{gcode_edit, isosurface, scaffold};

fn best<T>(n: usize, mut f: impl FnMut() -> T) -> (f64, T) {
    let mut best = f64::INFINITY;
    let mut out = None;
    for _ in 0..n {
        let t = Instant::now();
        let v = f();
        best = best.min(t.elapsed().as_secs_f64());
        out = Some(v);
    }
    (best, out.unwrap())
}

fn main() {
    println!("{:<34} {:>10} {:>10}", "case", "time s", "MB in");
    let mut times = Vec::new();
    let [nx, ny, nz] = SERIES_DIMS;
    for (label, dims) in [("series 182×197×107", SERIES_DIMS), ("series 4× (364×394×107)", [2 * nx, 2 * ny, nz])] {
        let files = series(dims);
        let list: Vec<(&str, &[u8])> = files.iter().map(|(n, b)| (n.as_str(), b.as_slice())).collect();
        let mb = files.iter().map(|(_, b)| b.len()).sum::<usize>() as f64 / 1e6;
        let (tr, imported) = best(3, || volume::read_volume(&list, &volume::Options::default()).expect("reads"));
        let roi = Roi::whole(&imported.volume);
        let (ts, surface) = best(3, || isosurface::extract(&imported.volume, &roi, &isosurface::Options::default(), &mut |_| {}).expect("extracts"));
        println!("{:<34} {:>10.3} {:>10.1}", format!("{label}: read"), tr, mb);
        println!("{:<34} {:>10.3} {:>10}", format!("{label}: surface ({} tri)", surface.report.triangles), ts, "");
        println!("{:<34} {:>10.3} {:>10}", format!("{label}: read + surface"), tr + ts, "");
        times.push(tr + ts);
    }
    println!("4× ÷ 1× (read + surface): {:.2}", times[1] / times[0]);
    let cal = scaffold::Calibration::default();
    let field = |p: DVec3| Some(cal.density(p.x * 10.0 + p.y * 5.0, 0.0));
    let mut edit_times = Vec::new();
    for mb in [50usize, 200] {
        let (text, _) = foreign_gcode(mb << 20);
        let (t, e) = best(3, || gcode_edit::edit("bench.gcode", &text, &field, &gcode_edit::Options::default(), &mut |_| {}).expect("edits"));
        println!("{:<34} {:>10.3} {:>10.1}", format!("edit {mb} MB ({} moves)", e.report.edited_moves), t, text.len() as f64 / 1e6);
        edit_times.push(t);
    }
    println!("200 MB ÷ 50 MB (edit): {:.2}", edit_times[1] / edit_times[0]);
}

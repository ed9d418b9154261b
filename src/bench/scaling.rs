//! `weft bench --scaling`: every parser and stage on inputs of 1×, 4× and 16× a base size,
//! timed (best of three) with its peak memory, and the growth exponent of each (the slope of
//! log time over log size; 1 is linear, 2 quadratic). The issue on bounded work asks for ≤ 1.2.
//!
//! Inputs come from [`crate::testgen`] (the hostile cases the tests reproduce) or from the
//! built-in shapes and lattices; preparing an input is not timed. Peak memory needs a process
//! per measurement: the CLI runs each case in a child (`weft bench --scaling-case NAME
//! --scale K`), which reports its time and its peak resident memory (Linux `VmHWM`).
//!
//! The browser worker runs the same cases through [`prepare`] (`BenchScaling` in
//! `src/wasm.rs`, `tests/e2e/bench.mjs` with `BENCH_SCALING_ONLY=1`) and times
//! the [`Prepared`] work with `performance.now()` (`Instant` panics on wasm32-unknown-unknown).

use crate::geom::shapes::{uv_sphere, Shape};
use crate::geom::{StrokeLayer, Toolpath};
use crate::{analyze, gcode, import, lattice, nonplanar, paths, slice, testgen};
use std::time::Instant;

/// The scales measured.
pub const SCALES: [usize; 3] = [1, 4, 16];
/// Largest growth exponent accepted (time and memory).
pub const MAX_EXPONENT: f64 = 1.2;

/// A prepared measurement: the input's size and the timed work.
pub struct Prepared {
    /// Input size in the case's unit.
    pub size: f64,
    /// The work (run three times; the best time counts).
    pub run: Box<dyn Fn() -> Result<(), String>>,
}

/// One parser or stage.
pub struct Case {
    /// Name (`import/stl-binary`).
    pub name: &'static str,
    /// What the size counts (`triangles`).
    pub unit: &'static str,
    /// Makes the input at a scale (1, 4, 16).
    pub prepare: fn(usize) -> Result<Prepared, String>,
}

fn err(e: impl std::fmt::Display) -> String {
    e.to_string()
}

fn mesh_case(bytes: Vec<u8>, file: &'static str, size: f64) -> Prepared {
    Prepared { size, run: Box::new(move || import::read_mesh(file, &bytes, &Default::default()).map(drop).map_err(err)) }
}

fn analyze_case(text: Vec<u8>, size: f64) -> Prepared {
    let o = analyze::Options { collect_preview: true, ..Default::default() };
    Prepared { size, run: Box::new(move || analyze::analyze("bench.gcode", &text, &o).map(drop).map_err(err)) }
}

/// A honeycomb lattice (r = 1 mm) on a square of `side` mm: its strokes.
fn honeycomb_strokes(side: f64) -> Result<Vec<StrokeLayer>, String> {
    let o = lattice::Options::default();
    let domain = lattice::Domain::Rectangle { width_mm: side, height_mm: side };
    let domains = lattice::planar_domains(&domain, &o).ok_or("no domain")?;
    Ok(lattice::generate(&domains, &o, 0.4, 1, &mut |_| {}).map_err(err)?.layers)
}

fn paths_case(scale: usize, method: paths::Method) -> Result<Prepared, String> {
    let side = 80.0 * (scale as f64).sqrt();
    let strokes = honeycomb_strokes(side)?;
    let o = paths::Options { method, iterations: 20, ..Default::default() };
    Ok(Prepared { size: side * side, run: Box::new(move || paths::optimise(&strokes, &o, 0.4, 1, &mut |_| {}).map(drop).map_err(err)) })
}

/// A slice of a 20 mm-tall box (100 mm square at 1×) whose footprint grows with the scale: its toolpath.
fn box_toolpath(scale: usize) -> Result<(Toolpath, f64), String> {
    let side = 100.0 * (scale as f64).sqrt();
    let mesh = Shape::Cube { size: [side, side, 20.0] }.mesh();
    Ok((slice::slice(&mesh, &Default::default(), &mut |_| {}).map_err(err)?.toolpath, side * side))
}

/// Every case, in the order printed.
pub fn cases() -> Vec<Case> {
    vec![
        Case {
            name: "import/stl-binary",
            unit: "triangles",
            prepare: |k| Ok(mesh_case(testgen::mesh::binary_stl_sphere(50_000 * k), "a.stl", (50_000 * k) as f64)),
        },
        Case { name: "import/stl-ascii", unit: "triangles", prepare: |k| Ok(mesh_case(testgen::mesh::ascii_stl(20_000 * k), "a.stl", (20_000 * k) as f64)) },
        Case { name: "import/obj", unit: "triangles", prepare: |k| Ok(mesh_case(testgen::mesh::obj(20_000 * k), "a.obj", (20_000 * k) as f64)) },
        Case { name: "import/3mf", unit: "triangles", prepare: |k| Ok(mesh_case(testgen::mesh::three_mf(20_000 * k), "a.3mf", (20_000 * k) as f64)) },
        Case {
            name: "import/3mf-objects",
            unit: "objects",
            prepare: |k| Ok(mesh_case(testgen::mesh::three_mf_siblings(2_000 * k), "a.3mf", (2_000 * k) as f64)),
        },
        Case {
            name: "gcode/template",
            unit: "bytes",
            // Templates are at most 64 KiB: 1× is 4 KiB of unclosed braces, expanded 5,000 times.
            prepare: |k| {
                let t = testgen::design::unclosed_braces_template(4096 * k);
                Ok(Prepared {
                    size: (4096 * k) as f64,
                    run: Box::new(move || (0..5000).try_for_each(|_| gcode::expand_template(&t, "start_gcode", &[]).map(drop).map_err(err))),
                })
            },
        },
        Case {
            name: "slice/triangles",
            unit: "triangles",
            prepare: |k| {
                let seg = (200.0 * (k as f64).sqrt()).round() as u32;
                let mesh = uv_sphere(25.0, seg);
                let n = mesh.triangles.len() as f64;
                Ok(Prepared { size: n, run: Box::new(move || slice::slice(&mesh, &Default::default(), &mut |_| {}).map(drop).map_err(err)) })
            },
        },
        Case {
            name: "slice/area",
            unit: "mm²",
            prepare: |k| {
                let side = 100.0 * (k as f64).sqrt();
                let mesh = Shape::Cube { size: [side, side, 20.0] }.mesh();
                Ok(Prepared { size: side * side, run: Box::new(move || slice::slice(&mesh, &Default::default(), &mut |_| {}).map(drop).map_err(err)) })
            },
        },
        Case {
            name: "gcode/write",
            unit: "mm² of layer",
            prepare: |k| {
                let (tp, size) = box_toolpath(k)?;
                let o = gcode::Options { printer: gcode::Printer { bed_size_mm: [1000.0; 3], ..Default::default() }, ..Default::default() };
                Ok(Prepared { size, run: Box::new(move || gcode::write_gcode(&tp, &o).map(drop).map_err(err)) })
            },
        },
        Case { name: "analyze/print", unit: "moves", prepare: |k| Ok(analyze_case(testgen::gcode::perimeter_print(50_000 * k), (50_000 * k) as f64)) },
        Case { name: "analyze/repeated", unit: "moves", prepare: |k| Ok(analyze_case(testgen::gcode::repeated_moves(20_000 * k), (20_000 * k) as f64)) },
        Case { name: "analyze/long-moves", unit: "moves", prepare: |k| Ok(analyze_case(testgen::gcode::long_moves(20_000 * k), (20_000 * k) as f64)) },
        Case { name: "analyze/arcs", unit: "arcs", prepare: |k| Ok(analyze_case(testgen::gcode::large_arcs(100 * k), (100 * k) as f64)) },
        Case {
            name: "lattice/honeycomb",
            unit: "mm²",
            prepare: |k| {
                let side = 100.0 * (k as f64).sqrt();
                Ok(Prepared { size: side * side, run: Box::new(move || honeycomb_strokes(side).map(drop)) })
            },
        },
        Case { name: "paths/gippo", unit: "mm²", prepare: |k| paths_case(k, paths::Method::GippoMax) },
        Case { name: "paths/euler", unit: "mm²", prepare: |k| paths_case(k, paths::Method::Euler) },
        Case { name: "paths/continuous", unit: "mm²", prepare: |k| paths_case(k, paths::Method::Continuous) },
        Case {
            name: "nonplanar/sphere",
            unit: "mm²",
            prepare: |k| {
                let side = 60.0 * (k as f64).sqrt();
                let strokes = honeycomb_strokes(side)?;
                let tp = paths::optimise(&strokes, &paths::Options { method: paths::Method::Euler, ..Default::default() }, 0.4, 1, &mut |_| {})
                    .map_err(err)?
                    .toolpath;
                let o = nonplanar::Options {
                    surface: nonplanar::Surface::Sphere { radius_mm: 200.0, center_mm: [0.0, 0.0, -190.0] },
                    max_segment_mm: nonplanar::DEFAULT_MAX_SEGMENT_MM,
                };
                Ok(Prepared { size: side * side, run: Box::new(move || nonplanar::project(&tp, None, &o).map(drop).map_err(err)) })
            },
        },
    ]
}

/// Prepares case `name` at `scale` (not timed): its input, ready to run. The native run
/// ([`run_case`]) and the browser worker (`BenchScaling` in `src/wasm.rs`, timed in JS) both
/// start here, so they run the same workload.
pub fn prepare(name: &str, scale: usize) -> Result<Prepared, String> {
    let case = cases().into_iter().find(|c| c.name == name).ok_or_else(|| format!("no scaling case '{name}'"))?;
    (case.prepare)(scale)
}

/// Runs case `name` at `scale` in this process: (input size, best of three times in s).
pub fn run_case(name: &str, scale: usize) -> Result<(f64, f64), String> {
    if name == "none" {
        return Ok((0.0, 0.0));
    }
    let prepared = prepare(name, scale)?;
    let mut best = f64::INFINITY;
    for _ in 0..3 {
        let t = Instant::now();
        (prepared.run)()?;
        best = best.min(t.elapsed().as_secs_f64());
    }
    Ok((prepared.size, best))
}

/// The least-squares slope of log y over log x (the growth exponent).
pub fn exponent(points: &[(f64, f64)]) -> f64 {
    let pts: Vec<(f64, f64)> = points.iter().filter(|(x, y)| *x > 0.0 && *y > 0.0).map(|(x, y)| (x.ln(), y.ln())).collect();
    let n = pts.len() as f64;
    if n < 2.0 {
        return f64::NAN;
    }
    let (mx, my) = (pts.iter().map(|p| p.0).sum::<f64>() / n, pts.iter().map(|p| p.1).sum::<f64>() / n);
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    sxy / sxx
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exponent_of_power_laws() {
        let lin: Vec<(f64, f64)> = SCALES.iter().map(|&k| (k as f64, 3.0 * k as f64)).collect();
        assert!((exponent(&lin) - 1.0).abs() < 1e-12);
        let quad: Vec<(f64, f64)> = SCALES.iter().map(|&k| (k as f64, (k * k) as f64)).collect();
        assert!((exponent(&quad) - 2.0).abs() < 1e-12);
    }

    #[test]
    fn case_names_are_unique() {
        let mut names: Vec<&str> = cases().iter().map(|c| c.name).collect();
        names.sort();
        names.dedup();
        assert_eq!(names.len(), cases().len());
    }
}

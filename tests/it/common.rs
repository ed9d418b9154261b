//! Shared by the integration tests that walk the shipped examples.
#![allow(dead_code)]

/// The planar lattice examples (every example lattice that is not projected onto a surface).
pub const PLANAR_LATTICES: &[&str] = &[
    "honeycomb-10mm",
    "voronoi-10mm",
    "penrose-10mm",
    "snub-square-10mm",
    "arrowhead-10mm",
    "reentrant-honeycomb-10mm",
    "tensile-honeycomb",
    "ball-burst-disc-48mm",
    "concave-cylinder-honeycomb",
];

/// The repository's root.
pub fn root() -> std::path::PathBuf {
    std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A shipped example design, `examples/<name>.json`.
pub fn example(name: &str) -> weft::design::Design {
    let text = std::fs::read_to_string(root().join(format!("examples/{name}.json"))).unwrap();
    weft::design::Design::from_json(name, &text).unwrap()
}

/// Runs a design through the pipeline with its preview; the error in words.
pub fn run(design: &weft::design::Design, files: &weft::pipeline::Files) -> Result<weft::pipeline::RunOutput, String> {
    weft::pipeline::run(design, files, &weft::pipeline::RunOptions { collect_preview: true }, &mut |_, _| {}).map_err(|e| e.to_string())
}

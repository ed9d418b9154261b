//! The writer times its own moves (it no longer runs the analyzer): its time and travel must
//! equal, to the bit, what the analyzer measures on the same file, for every example and the
//! writer variants of the golden test.

use weft::pipeline::{self, Files, RunOptions};
use weft::Design;

const VARIANTS: &[(&str, &[&str])] = &[
    ("honeycomb-10mm", &["printer.flavor=pneumatic", "material.flow.pre_flow_s=0.2", "material.flow.post_flow_s=0.1"]),
    ("cube-20mm", &["printer.relative_e=true", "printer.retraction.z_hop_mm=0.4", "material.flow.pre_flow_mm=0.05"]),
    ("voronoi-10mm", &["job.paths.method=continuous"]),
    ("cube-20mm", &["printer.origin=center", "printer.bed_size_mm=[200,200,200]"]),
    // Templates with motion, units and a dwell: read with the shared lexer.
    ("honeycomb-10mm", &["printer.start_gcode=\"G28\\nG1 Z5 F3000\\nG4 P250\\nG1 X10 Y10\\nM204 S500\\n\""]),
    ("honeycomb-10mm", &["printer.end_gcode=\"G91\\nG1 Z10 F600\\nG90\\nG2 X0 Y0 I5 J0\\n\""]),
];

#[test]
fn writer_time_and_travel_equal_the_analyzers() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples");
    let mut cases: Vec<(String, Vec<String>)> = Vec::new();
    for entry in std::fs::read_dir(&root).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "json") {
            cases.push((path.file_stem().unwrap().to_string_lossy().into_owned(), Vec::new()));
        }
    }
    cases.sort();
    for (name, sets) in VARIANTS {
        cases.push((name.to_string(), sets.iter().map(|s| s.to_string()).collect()));
    }
    assert!(cases.len() >= 19);
    for (name, sets) in &cases {
        let text = std::fs::read_to_string(root.join(format!("{name}.json"))).unwrap();
        let design = Design::from_json(name, &text).unwrap().with_overrides(sets).unwrap_or_else(|e| panic!("{name} {sets:?}: {e}"));
        let out = pipeline::run(&design, &Files::new(), &RunOptions { collect_preview: false }, &mut |_, _| {}).unwrap_or_else(|e| panic!("{name}: {e}"));
        let (g, a) = (&out.report.gcode, &out.report.analysis);
        assert!(g.estimated_time_s > 0.0, "{name} {sets:?}");
        assert_eq!(g.estimated_time_s.to_bits(), a.estimated_time_s.to_bits(), "{name} {sets:?}: time {} vs {}", g.estimated_time_s, a.estimated_time_s);
        assert_eq!(g.travel_mm.to_bits(), a.travel_mm.to_bits(), "{name} {sets:?}: travel {} vs {}", g.travel_mm, a.travel_mm);
    }
}

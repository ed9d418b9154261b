//! Every example (and variants that exercise each writer option) gives the G-code recorded in
//! `tests/golden/gcode.sha256`, the same bytes at 1, 2 and 4 threads: refactors of the core
//! must not change a byte. When a change
//! is meant to alter output, regenerate the file with `WEFT_BLESS=1 cargo test --test golden_gcode`
//! and say why in the commit.

use sha2::{Digest, Sha256};
use std::collections::BTreeMap;
use std::path::Path;
use std::process::Command;

/// (output name, example, `--set` overrides).
const CASES: &[(&str, &str, &[&str])] = &[
    ("arrowhead-10mm", "arrowhead-10mm", &[]),
    ("ball-burst-disc-48mm", "ball-burst-disc-48mm", &[]),
    ("barrel-omega1", "barrel-omega1", &[]),
    ("barrel-graded", "barrel-graded", &[]),
    ("barrel-omega2", "barrel-omega2", &[]),
    ("foam-dogbone-linear", "foam-dogbone-linear", &[]),
    ("foam-dogbone-log", "foam-dogbone-log", &[]),
    ("foam-dogbone-modulus", "foam-dogbone-modulus", &[]),
    ("foam-hinge-cube", "foam-hinge-cube", &[]),
    ("foam-insole", "foam-insole", &[]),
    ("foam-stiffness-sectors", "foam-stiffness-sectors", &[]),
    ("v-foam-sectors-nearest", "foam-stiffness-sectors", &["job.foam.junction=nearest"]),
    ("freeform-bridge", "freeform-bridge", &[]),
    ("freeform-cantilever-truss", "freeform-cantilever-truss", &[]),
    ("freeform-cantilever-truss-tilt", "freeform-cantilever-truss-tilt", &[]),
    ("freeform-dome", "freeform-dome", &[]),
    ("freeform-dome-exact", "freeform-dome-exact", &[]),
    ("freeform-duck", "freeform-duck", &[]),
    ("freeform-four-frame", "freeform-four-frame", &[]),
    ("freeform-klein-bottle", "freeform-klein-bottle", &[]),
    ("freeform-klein-bottle-relaxed", "freeform-klein-bottle-relaxed", &[]),
    ("freeform-semi-sphere", "freeform-semi-sphere", &[]),
    ("freeform-semi-sphere-relaxed", "freeform-semi-sphere-relaxed", &[]),
    ("freeform-topopt", "freeform-topopt", &[]),
    ("freeform-topopt-relaxed", "freeform-topopt-relaxed", &[]),
    ("freeform-tower", "freeform-tower", &[]),
    ("freeform-tower-bands", "freeform-tower-bands", &[]),
    ("freeform-voronoi", "freeform-voronoi", &[]),
    ("v-freeform-tower-heuristic", "freeform-tower", &["job.planner.cost=heuristic"]),
    ("graded-phantom", "graded-phantom", &[]),
    ("v-graded-honeycomb3d", "graded-phantom", &["job.slice.infill_pattern=honeycomb3d"]),
    ("v-graded-rectilinear-clamp", "graded-phantom", &["job.slice.infill_pattern=rectilinear", "job.density.limit=clamp", "job.density.max_width_mm=0.6"]),
    ("concave-cylinder-honeycomb", "concave-cylinder-honeycomb", &[]),
    ("cube-20mm", "cube-20mm", &[]),
    ("cylinder-dense-infill", "cylinder-dense-infill", &[]),
    ("cylinder-on-sphere", "cylinder-on-sphere", &[]),
    ("honeycomb-10mm", "honeycomb-10mm", &[]),
    ("hourglass-omega3", "hourglass-omega3", &[]),
    ("penrose-10mm", "penrose-10mm", &[]),
    ("reentrant-honeycomb-10mm", "reentrant-honeycomb-10mm", &[]),
    ("snub-square-10mm", "snub-square-10mm", &[]),
    ("sphere-30mm", "sphere-30mm", &[]),
    ("tensile-honeycomb", "tensile-honeycomb", &[]),
    ("thin-layers-cube", "thin-layers-cube", &[]),
    ("voronoi-10mm", "voronoi-10mm", &[]),
    (
        "v-pneumatic",
        "honeycomb-10mm",
        &["printer.flavor=pneumatic", "material.flow.pre_flow_s=0.2", "material.flow.post_flow_s=0.1"],
    ),
    (
        "v-relative-hop",
        "cube-20mm",
        &["printer.relative_e=true", "printer.retraction.z_hop_mm=0.4", "material.flow.pre_flow_mm=0.05", "material.flow.post_flow_mm=0.02"],
    ),
    ("v-continuous", "voronoi-10mm", &["job.paths.method=continuous"]),
    ("v-euler", "voronoi-10mm", &["job.paths.method=euler", "job.paths.order=min_travel"]),
    ("v-center", "cube-20mm", &["printer.origin=center", "printer.bed_size_mm=[200,200,200]"]),
    ("v-poses-csv", "barrel-omega2", &["printer.flavor=poses_csv"]),
    ("v-ijk", "barrel-omega2", &["printer.machine.axis_output=ijk"]),
];

/// Threads each case runs at: the G-code must not depend on the count (`weft::par`).
const THREADS: &[usize] = &[1, 2, 4];

#[test]
fn examples_give_the_recorded_gcode_at_any_thread_count() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let golden_path = root.join("tests/golden/gcode.sha256");
    let golden: BTreeMap<String, String> = std::fs::read_to_string(&golden_path)
        .unwrap()
        .lines()
        .filter_map(|l| l.split_once("  ").map(|(h, n)| (n.trim_end_matches(".gcode").to_string(), h.to_string())))
        .collect();
    let dir = std::env::temp_dir().join(format!("weft-golden-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut got = BTreeMap::new();
    let mut differ = Vec::new();
    for (name, example, sets) in CASES {
        let mut hashes = Vec::new();
        for &threads in THREADS {
            let out = dir.join(format!("{name}-{threads}.gcode"));
            let mut cmd = Command::new(env!("CARGO_BIN_EXE_weft"));
            cmd.arg("run").arg(root.join(format!("examples/{example}.json"))).arg("--out").arg(&out).arg("-q").arg("--threads").arg(threads.to_string());
            for s in *sets {
                cmd.arg("--set").arg(s);
            }
            let status = cmd.output().unwrap();
            assert!(status.status.success(), "{name}: {}", String::from_utf8_lossy(&status.stderr));
            let hash = Sha256::digest(std::fs::read(&out).unwrap());
            hashes.push(hash.iter().map(|b| format!("{b:02x}")).collect::<String>());
        }
        if hashes.iter().any(|h| h != &hashes[0]) {
            differ.push(format!("{name}: {}", THREADS.iter().zip(&hashes).map(|(t, h)| format!("{t} threads {}", &h[..12])).collect::<Vec<_>>().join(", ")));
        }
        got.insert(name.to_string(), hashes.swap_remove(0));
    }
    assert!(differ.is_empty(), "G-code depends on the thread count: {differ:?}");
    let _ = std::fs::remove_dir_all(&dir);
    if std::env::var_os("WEFT_BLESS").is_some() {
        let text: String = got.iter().map(|(n, h)| format!("{h}  {n}.gcode\n")).collect();
        std::fs::write(&golden_path, text).unwrap();
        return;
    }
    let changed: Vec<&String> = got.keys().filter(|n| golden.get(*n) != got.get(*n)).collect();
    assert!(changed.is_empty(), "G-code changed for {changed:?} (WEFT_BLESS=1 to record a deliberate change)");
    assert_eq!(golden.len(), CASES.len(), "every recorded case is still run");
}

//! "How it works": every kind's steps name one of its views, say what they do and where the
//! paper says it, and each step draws something on the kind's example (data, not a title).

use crate::common::example;
use weft::kinds::Registry;
use weft::pipeline::{self, Cache, Files};

/// The example each kind opens on in the step-through checks.
const EXAMPLES: &[(&str, &str)] = &[
    ("lattice", "honeycomb-10mm"),
    ("axisymmetric", "hourglass-omega3"),
    ("graded", "graded-phantom"),
    ("foam", "foam-dogbone-linear"),
    ("freeform", "freeform-bridge"),
];

#[test]
fn every_step_names_a_view_and_cites_the_paper() {
    let reg = Registry::builtin();
    for (kind, _) in EXAMPLES {
        let k = reg.get(kind).unwrap_or_else(|| panic!("no kind {kind}"));
        assert!(k.steps().len() >= 3, "{kind}: {} steps", k.steps().len());
        for s in k.steps() {
            assert!(k.views().iter().any(|v| v.id == s.view), "{kind}: step {:?} names no view of the kind ({})", s.title, s.view);
            assert!(!s.title.is_empty() && s.text.len() >= 40 && s.text.ends_with('.'), "{kind}: step {:?} needs a sentence", s.title);
            assert!(!s.cite.is_empty(), "{kind}: step {:?} cites nothing", s.title);
        }
    }
}

#[test]
fn every_step_draws_something_on_its_example() {
    let reg = Registry::builtin();
    for (kind, file) in EXAMPLES {
        let design = example(file);
        let k = reg.get(kind).unwrap();
        let mut cache = Cache::new();
        for s in k.steps() {
            let a = pipeline::inspect(&reg, &mut cache, &design, &Files::new(), s.view, s.index).unwrap_or_else(|e| panic!("{kind}: step {:?}: {e}", s.title));
            assert!(!a.data.is_empty(), "{kind}: step {:?} ({} at {}) draws nothing", s.title, s.view, s.index);
            assert!(a.data.iter().all(|x| x.is_finite()), "{kind}: step {:?} has a non-finite value", s.title);
            if s.scrub {
                assert!(a.count >= 2, "{kind}: step {:?} scrubs over {} frame(s)", s.title, a.count);
                let last = pipeline::inspect(&reg, &mut cache, &design, &Files::new(), s.view, a.count - 1).unwrap();
                assert!(!last.data.is_empty(), "{kind}: step {:?}'s last frame draws nothing", s.title);
            }
        }
    }
}

#[test]
fn each_kind_opens_on_a_colouring_the_page_has_and_a_backdrop_it_declares() {
    let reg = Registry::builtin();
    let modes = ["feature", "path", "flow", "e_per_mm", "speed", "width"];
    for k in reg.kinds() {
        let t = k.teach();
        assert!(modes.contains(&t.color_by), "{}: colour by {}", k.name(), t.color_by);
        if let Some(b) = t.backdrop {
            let v = k.views().iter().find(|v| v.id == b).unwrap_or_else(|| panic!("{}: backdrop {b} is not a view", k.name()));
            assert_eq!(v.shape, weft::kinds::Shape::Lines3d, "{}: backdrop {b} is not lines3d", k.name());
        }
    }
    // The graded scaffold opens coloured by ΔE per mm (its density), a foam by speed (V*).
    assert_eq!(reg.get("graded").unwrap().teach().color_by, "e_per_mm");
    assert_eq!(reg.get("foam").unwrap().teach().color_by, "speed");
    assert!(reg.get("axisymmetric").unwrap().teach().backdrop.is_some());
}

/// `weft steps`: the CLI walks the same steps, says what each drew, and writes their views.
#[test]
fn the_cli_prints_and_writes_the_steps() {
    let dir = std::env::temp_dir().join(format!("weft-steps-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let design = crate::common::root().join("examples/honeycomb-10mm.json");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_weft")).arg("steps").arg(&design).arg("--out").arg(&dir).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = String::from_utf8_lossy(&out.stdout);
    let steps = Registry::builtin().get("lattice").unwrap().steps();
    for (n, s) in steps.iter().enumerate() {
        assert!(text.contains(&format!("{}. {}", n + 1, s.title)), "step {} missing from:\n{text}", n + 1);
        let file = dir.join(format!("honeycomb-10mm-step{}-{}.json", n + 1, s.view));
        let v: serde_json::Value = serde_json::from_slice(&std::fs::read(&file).unwrap()).unwrap();
        assert!(v["data"].as_array().is_some_and(|d| !d.is_empty()), "{} is empty", file.display());
        assert_eq!(v["step"]["cite"], s.cite);
        // A step that iterates writes its last frame too: the GIPPO replay ends on the run's score.
        if s.scrub {
            let last: serde_json::Value =
                serde_json::from_slice(&std::fs::read(dir.join(format!("honeycomb-10mm-step{}-{}-last.json", n + 1, s.view))).unwrap()).unwrap();
            assert_eq!(last["index"].as_u64().unwrap() + 1, last["count"].as_u64().unwrap());
        }
    }
    assert_eq!(text.matches("   paper: ").count(), steps.len());
    // A job without steps says which have them, in one line.
    let cube = crate::common::root().join("examples/cube-20mm.json");
    let bad = std::process::Command::new(env!("CARGO_BIN_EXE_weft")).arg("steps").arg(&cube).output().unwrap();
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(!bad.status.success() && err.contains("no steps") && err.lines().count() == 1, "{err}");
}

/// A step's recording lives in the cache only until the steps close: dropping the recordings
/// keeps every stage (the next step or run reuses them), and a run alone records nothing.
#[test]
fn recordings_are_dropped_when_the_steps_close_and_a_run_makes_none() {
    let reg = Registry::builtin();
    for (file, view, id) in [("honeycomb-10mm", "gippo", "gippo_replay"), ("hourglass-omega3", "repulsion", "repulsion_frames")] {
        let design = example(file);
        let mut cache = Cache::new();
        pipeline::run_in(&reg, &mut cache, &design, &Files::new(), &pipeline::RunOptions::default(), &mut |_, _| {}).unwrap();
        assert!(!cache.ids().iter().any(|i| i == id), "{file}: a run recorded {id}");
        let stages = cache.ids();
        pipeline::inspect(&reg, &mut cache, &design, &Files::new(), view, 0).unwrap();
        assert!(cache.ids().iter().any(|i| i == id), "{file}: {view} kept no {id} ({:?})", cache.ids());
        assert_eq!(cache.drop_recordings(), 1, "{file}");
        assert_eq!(cache.ids(), stages, "{file}: dropping the recordings changed the stages");
    }
}

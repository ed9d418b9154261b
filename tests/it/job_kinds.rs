//! Job kinds are plug-ins: a kind defined only here runs through the pipeline, the design and
//! the schema with no edit anywhere else; the stage cache re-runs only what an edit affects.

use serde::{Deserialize, Serialize};
use weft::budget::Estimate;
use weft::catalog::schema;
use weft::design::{Design, Input};
use weft::geom::{DVec3, Feature, Pass, PassKind, Path, PointData, PointFlow, Toolpath};
use weft::kinds::{Inspection, Kind, Product, Registry, Shape, Slot, SlotKind, StageInfo, ViewInfo};
use weft::pipeline::{self, Cache, Ctx, Error, Files, RunOptions};
use weft::report::{Axis, Plot, PlotKind, Series, StageReport};
use weft::settings::{mount, num, Field, Problem, Row};

/// A spiral vase-like single free pass whose flow grows along the path: one slot (a mesh
/// whose height sets the spiral's), one stage, a report with a metric and a plot.
struct Spiral;

#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct SpiralJob {
    #[serde(default = "turns")]
    turns: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    input: Option<Input>,
}

fn turns() -> f64 {
    3.0
}

const FIELDS: &[Field] = &[num("turns", "Spiral", "Turns", "", 1.0, 20.0, 1.0, "How many times round.")];

impl Kind for Spiral {
    type Settings = SpiralJob;
    const NAME: &'static str = "spiral";
    const LABEL: &'static str = "Spiral (test)";
    const DOC: &'static str = "A test kind.";
    const SLOTS: &'static [Slot] = &[Slot { name: "mesh", label: "Height from", kind: SlotKind::Mesh, path: "job.input", required: false, doc: "" }];
    const STAGES: &'static [StageInfo] = &[StageInfo { name: "spiral", label: "Winding" }];
    const VIEWS: &'static [ViewInfo] =
        &[ViewInfo { id: "plan", card: true, stage: "spiral", label: "Plan", shape: Shape::Lines2d, index_label: "Turn", doc: "" }];

    fn fields() -> Vec<Row> {
        mount("job", FIELDS)
    }

    fn validate(_d: &Design, s: &SpiralJob, out: &mut Vec<Problem>) {
        if s.turns.fract() != 0.0 {
            out.push(Problem { path: "job.turns".into(), message: "whole turns only".into() });
        }
    }

    fn estimate(s: &SpiralJob, _ctx: &mut Ctx) -> Result<Vec<Estimate>, Error> {
        let segments = s.turns * 36.0;
        Ok(vec![Estimate::new("spiral").quantity("segments", "Segments", segments, "").cost(segments * 100.0, segments * 1e-6)])
    }

    fn run(s: &SpiralJob, ctx: &mut Ctx) -> Result<Product, Error> {
        let height = match &s.input {
            Some(i) => ctx.mesh(&Self::SLOTS[0], i)?.bounds().map_or(10.0, |b| b.max.z - b.min.z),
            None => 10.0,
        };
        let turns = s.turns;
        let out = ctx.stage("spiral", "spiral", s, &[], |_| {
            let n = (turns * 36.0) as usize;
            let pts: Vec<DVec3> = (0..=n)
                .map(|i| {
                    let a = i as f64 / 36.0 * std::f64::consts::TAU;
                    DVec3::new(10.0 * libm::cos(a), 10.0 * libm::sin(a), 0.2 + height * i as f64 / n as f64)
                })
                .collect();
            let area: Vec<f64> = (0..=n).map(|i| 0.05 + 0.05 * i as f64 / n as f64).collect();
            let mut path = Path::new(pts, Feature::Perimeter, 0.4);
            path.data = Some(Box::new(PointData { flow: Some(PointFlow::AreaMm2(area)), ..Default::default() }));
            let tp = Toolpath { passes: vec![Pass { kind: PassKind::Free, z: 0.2, height: 0.2, paths: vec![path] }] };
            let mut report = StageReport::new("spiral", "Winding", &serde_json::json!({ "points": n + 1 }));
            report = report.metric("length", "Length", tp.extrusion_length(), "mm", "Path length.");
            report.plots.push(Plot {
                key: "radius".into(),
                title: "Radius".into(),
                kind: PlotKind::Line,
                x: Axis::new("Point", ""),
                y: Axis::new("Radius", "mm"),
                group: None,
                series: vec![Series::xy("radius", vec![0.0, 1.0], vec![10.0, 10.0])],
            });
            Ok((tp, Some(report)))
        })?;
        Ok(Product::Toolpath(out))
    }

    fn inspect(s: &SpiralJob, _ctx: &mut Ctx, view: &str, index: usize) -> Result<Inspection, Error> {
        let count = s.turns as usize;
        Ok(Inspection {
            view: view.into(),
            shape: Shape::Lines2d,
            index: index.min(count - 1),
            count,
            stride: 5,
            data: vec![0.0, 0.0, 1.0, 1.0, 1.0],
            overlay: Vec::new(),
            meta: serde_json::Value::Null,
        })
    }
}

static SPIRAL: Spiral = Spiral;

/// (stage, reused) of every stage report of a run, in order.
fn reuse(out: &pipeline::RunOutput) -> Vec<(&str, bool)> {
    out.report.stages.iter().map(|s| (s.stage.as_str(), s.cached)).collect()
}

fn registry() -> Registry {
    Registry::builtin().with(&SPIRAL)
}

#[test]
fn a_kind_defined_in_a_test_runs_through_the_pipeline() {
    let reg = registry();
    let text = serde_json::json!({ "version": 1, "name": "spiral", "job": { "kind": "spiral" } }).to_string();
    let design = Design::from_json_in(&reg, "spiral.json", &text).unwrap();
    // Defaults filled in by the kind; the built-in registry does not know it.
    assert_eq!(design.job.value["turns"], 3.0);
    assert_eq!(
        Design::from_json("spiral.json", &text).unwrap_err().to_string(),
        "spiral.json: job.kind: 'spiral' is not a choice for the job kind; use one of: slice, lattice, axisymmetric, graded, foam, freeform"
    );
    // Its rows are in the schema and check ranges; its own rule runs too.
    let s = schema::schema(&reg);
    let row = s.fields.iter().find(|r| r.path == "job.turns").expect("the kind's row is in the schema");
    assert_eq!((row.field.min, row.field.max, row.job), (Some(1.0), Some(20.0), Some("spiral")));
    assert!(design.with_overrides_in(&reg, &["job.turns=25".into()]).is_err());
    assert!(design.with_overrides_in(&reg, &["job.turns=2.5".into()]).unwrap_err().to_string().contains("whole turns"));
    let info = s.job_kinds.iter().find(|k| k.name == "spiral").unwrap();
    assert_eq!(info.stages.iter().map(|s| s.name).collect::<Vec<_>>(), ["spiral", "gcode", "analyze"]);

    let mut stages = Vec::new();
    let out = pipeline::run_in(&reg, &mut Cache::disabled(), &design, &Files::new(), &RunOptions::default(), &mut |s, _| {
        if stages.last().map(String::as_str) != Some(s) {
            stages.push(s.to_string());
        }
    })
    .unwrap();
    assert_eq!(stages, ["spiral", "gcode", "analyze"]);
    let spiral = &out.report.stages[0];
    assert_eq!((spiral.stage.as_str(), spiral.metrics[0].key.as_str(), spiral.plots[0].key.as_str()), ("spiral", "length", "radius"));
    // A free pass with a per-point flow: the analyzer reads back the nominal length.
    let nominal = spiral.metrics[0].value;
    assert!((out.report.analysis.extruded_mm - nominal).abs() < 0.01 * nominal, "{} vs {nominal}", out.report.analysis.extruded_mm);

    // Its slot works from the CLI's and the page's entry point.
    let mut files = Files::new();
    files.insert("tall.stl".into(), cube_stl(30.0));
    let with_mesh = design.with_slot_input(&reg, "mesh", Input::File { name: "tall.stl".into(), embedded: None }).unwrap();
    let tall = pipeline::run_in(&reg, &mut Cache::disabled(), &with_mesh, &files, &RunOptions::default(), &mut |_, _| {}).unwrap();
    assert_eq!(tall.report.stages[0].stage, "import");
    assert!(tall.report.analysis.extruded_mm > out.report.analysis.extruded_mm);
    let v = pipeline::inspect(&reg, &mut Cache::new(), &design, &files, "plan", 99).unwrap();
    assert_eq!((v.index, v.count), (2, 3));
}

/// A binary STL of a cube of side `s` mm.
fn cube_stl(s: f64) -> Vec<u8> {
    weft::geom::shapes::Shape::Cube { size: [s, s, s] }.mesh().to_stl_binary()
}

#[test]
fn a_temperature_edit_reruns_only_the_writer_and_the_analyzer() {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/examples/voronoi-10mm.json")).unwrap();
    let design = Design::from_json("voronoi", &text).unwrap();
    let reg = Registry::builtin();
    let mut cache = Cache::new();
    let run = |d: &Design, cache: &mut Cache| pipeline::run_in(&reg, cache, d, &Files::new(), &RunOptions { collect_preview: true }, &mut |_, _| {}).unwrap();
    let first = run(&design, &mut cache);
    assert!(first.report.stages.iter().all(|s| !s.cached));
    let hotter = design.with_overrides(&["material.bed_temp_c=70".into()]).unwrap();
    let second = run(&hotter, &mut cache);
    assert_eq!(reuse(&second), [("lattice", true), ("paths", true), ("gcode", false), ("analyze", false)]);
    // Same bytes as a run without a cache, and only the temperature lines differ.
    let fresh = pipeline::run(&hotter, &Files::new(), &RunOptions::default(), &mut |_, _| {}).unwrap();
    assert_eq!(second.gcode, fresh.gcode);
    let diff: Vec<(&str, &str)> = first.gcode.lines().zip(second.gcode.lines()).filter(|(a, b)| a != b).collect();
    assert!(
        !diff.is_empty()
            && diff.iter().all(|(a, _)| a.starts_with("M140")
                || a.starts_with("M190")
                || a.starts_with("; bed_temperature = ")
                || a.starts_with("; first_layer_bed_temperature = ")),
        "{diff:?}"
    );
    // Same design again: everything reused.
    let third = run(&hotter, &mut cache);
    assert!(third.report.stages.iter().all(|s| s.cached));
    // A path setting re-runs paths onward, not the lattice.
    let euler = hotter.with_overrides(&["job.paths.method=euler".into()]).unwrap();
    let fourth = run(&euler, &mut cache);
    assert_eq!(reuse(&fourth), [("lattice", true), ("paths", false), ("gcode", false), ("analyze", false)]);
}

#[test]
fn the_layer_view_reuses_the_lattice_of_the_run() {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/examples/concave-cylinder-honeycomb.json")).unwrap();
    let design = Design::from_json("concave", &text).unwrap();
    let reg = Registry::builtin();
    let mut cache = Cache::new();
    let a = pipeline::inspect(&reg, &mut cache, &design, &Files::new(), "layer2d", 3).unwrap();
    assert!(a.count > 3 && a.data.len() % 5 == 0 && !a.data.is_empty());
    let ids = cache.ids();
    assert!(ids.contains(&"domains".to_string()) && ids.contains(&"lattice".to_string()), "{ids:?}");
    // A run afterwards reuses the sliced solid and the lattice.
    let out = pipeline::run_in(&reg, &mut cache, &design, &Files::new(), &RunOptions::default(), &mut |_, _| {}).unwrap();
    assert_eq!(&reuse(&out)[..2], [("slice", true), ("lattice", true)]);
    assert!(matches!(pipeline::inspect(&reg, &mut cache, &design, &Files::new(), "nope", 0), Err(Error::UnknownView { .. })));
}

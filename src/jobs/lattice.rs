//! The `lattice` job (the GIPPO method): a lattice from the atlas fills a domain layer by
//! layer, each layer becomes a graph printed along optimised paths, optionally projected onto
//! a non-planar surface.
//!
//! Stages: `import` + `slice` (only for a solid domain: its layers are the domains),
//! `lattice`, `paths`, `nonplanar` (when set). The report draws the score of every GIPPO
//! iteration (the paper's Fig. 2(i)), the path classes and a table of paths per layer.

use super::{Inspection, Kind, Product, Shape, Slot, SlotKind, StageInfo, ViewInfo};
use crate::design::{Design, Input};
use crate::geom::shapes;
use crate::geom::StrokeLayer;
use crate::lattice::{self, Domain, LayerDomain};
use crate::nonplanar;
use crate::paths::{self, PathsReport};
use crate::report::{Axis, Column, Plot, PlotKind, Row as TableRow, Series, StageReport, Table};
use crate::settings::{mount, other, widget, Field, Kind as FieldKind, Problem, Row};
use crate::slice;
use crate::stage::{Ctx, Error, Out};
use serde::{Deserialize, Serialize};

/// Settings of a `lattice` job.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LatticeJob {
    /// Where the lattice goes: a built-in planar domain, or the layers of `input`.
    #[serde(default)]
    pub domain: Domain,
    /// The solid whose layers are filled when `domain` is `solid`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub input: Option<Input>,
    /// Pattern, layers, rotation, overrides, contour.
    #[serde(default)]
    pub lattice: lattice::Options,
    /// Path optimisation.
    #[serde(default)]
    pub paths: paths::Options,
    /// Projection onto a non-planar surface (off when absent).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub nonplanar: Option<nonplanar::Options>,
    /// The surface mesh when `nonplanar.surface` is `mesh`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub surface_input: Option<Input>,
}

/// The `lattice` job kind.
pub struct LatticeKind;

const SLOTS: &[Slot] = &[
    Slot {
        name: "mesh",
        label: "Solid to fill",
        kind: SlotKind::Mesh,
        path: "job.input",
        required: false,
        doc: "A solid whose every layer is filled with the lattice (the domain becomes 'solid').",
    },
    Slot {
        name: "surface",
        label: "Surface to print on",
        kind: SlotKind::Surface,
        path: "job.surface_input",
        required: false,
        doc: "A surface mesh the layers are projected onto (non-planar printing on a mesh).",
    },
];

const STAGES: &[StageInfo] = &[
    StageInfo { name: "import", label: "Reading the mesh" },
    StageInfo { name: "slice", label: "Slicing the solid" },
    StageInfo { name: "lattice", label: "Generating the lattice" },
    StageInfo { name: "paths", label: "Optimising print paths" },
    StageInfo { name: "nonplanar", label: "Projecting onto the surface" },
];

const VIEWS: &[ViewInfo] = &[ViewInfo {
    id: "layer2d",
    stage: "lattice",
    label: "Lattice layer",
    shape: Shape::Lines2d,
    index_label: "Layer",
    doc: "The struts of one layer as generated, before path optimisation (mm).",
}];

/// Rows of the domain (paths relative to `job.domain`).
const DOMAIN_FIELDS: &[Field] = &[
    other(
        "kind",
        "Domain",
        "Domain",
        FieldKind::Choice,
        &["rectangle", "disc", "tensile_specimen", "solid"],
        "Where the lattice goes: a built-in shape, or the layers of a loaded solid.",
    ),
    crate::settings::num("width_mm", "Domain", "Width", "mm", 0.1, 2000.0, 0.1, "Size of the rectangle along X."),
    crate::settings::num("height_mm", "Domain", "Height", "mm", 0.1, 2000.0, 0.1, "Size of the rectangle along Y."),
    crate::settings::num("diameter_mm", "Domain", "Diameter", "mm", 0.1, 2000.0, 0.1, "Diameter of the disc."),
    crate::settings::num("length_mm", "Domain", "Lattice length", "mm", 0.1, 2000.0, 0.1, "Between the handles."),
    crate::settings::num("handle_length_mm", "Domain", "Handle length", "mm", 0.1, 1000.0, 0.1, "Solid handle at each end."),
];

/// The pattern choice row, edited with the page's pattern picker.
const PATTERN_FIELD: &[Field] = &[widget(
    other(
        "pattern.kind",
        "Lattice",
        "Pattern",
        FieldKind::Choice,
        lattice::PATTERNS,
        "The cell shape the lattice repeats (or randomises): pick by its picture.",
    ),
    "pattern_picker",
)];

/// The strut width of lattices: the nozzle diameter (d_n of equation 4).
fn line_width(design: &Design) -> f64 {
    design.printer.nozzle_diameter_mm
}

impl Kind for LatticeKind {
    type Settings = LatticeJob;
    const NAME: &'static str = "lattice";
    const LABEL: &'static str = "Lattice (GIPPO)";
    const DOC: &'static str = "A lattice from the atlas, every strut printed once along optimised paths (GIPPO), optionally on a curved surface.";
    const SLOTS: &'static [Slot] = SLOTS;
    const STAGES: &'static [StageInfo] = STAGES;
    const VIEWS: &'static [ViewInfo] = VIEWS;

    fn fields() -> Vec<Row> {
        let mut rows = mount("job.domain", DOMAIN_FIELDS);
        rows.extend(mount("job.lattice", PATTERN_FIELD));
        rows.extend(mount("job.lattice", lattice::FIELDS));
        rows.extend(mount("job.paths", paths::FIELDS));
        rows.extend(mount("job.nonplanar", nonplanar::FIELDS));
        rows.extend(mount("job.input", shapes::FIELDS));
        rows
    }

    fn validate(design: &Design, j: &LatticeJob, out: &mut Vec<Problem>) {
        out.extend(super::thicker_than_nozzle("job.lattice.layer_thickness_mm", j.lattice.layer_thickness_mm, design.printer.nozzle_diameter_mm));
        if j.domain == Domain::Solid && j.input.is_none() {
            out.push(Problem { path: "job.input".into(), message: "a solid domain needs a solid: load a mesh or set job.input".into() });
        }
        if let Some(np) = &j.nonplanar {
            if np.surface == nonplanar::Surface::Mesh && j.surface_input.is_none() {
                out.push(Problem {
                    path: "job.surface_input".into(),
                    message: "a mesh surface needs a mesh: load the surface file or set job.surface_input".into(),
                });
            }
        }
        for o in &j.lattice.overrides {
            if o.layer >= j.lattice.layers && j.domain != Domain::Solid {
                out.push(Problem {
                    path: "job.lattice.overrides".into(),
                    message: format!("layer {} does not exist (the lattice has {} layers, numbered from 0)", o.layer, j.lattice.layers),
                });
            }
        }
    }

    /// A solid loaded into the `mesh` slot is filled: the domain becomes `solid`, and its
    /// paths are printed in travel-minimising order. The paper's longest-first order suits its
    /// one-layer coupons, but on a filled part it sends the nozzle across every layer again and
    /// again (a 30 mm sphere: travel 4.5–5.6× the extrusion, against 0.29–0.46× in
    /// travel-minimising order; BENCHMARKS.md "A lattice filling a solid").
    fn slot_filled(slot: &str, mut j: LatticeJob) -> LatticeJob {
        if slot == "mesh" {
            j.domain = Domain::Solid;
            j.paths.order = paths::Order::MinTravel;
        }
        j
    }

    /// The lattice, paths and (when set) non-planar stages' estimates, chained: each stage's
    /// input is the previous one's estimated output. A solid domain is measured from its mesh
    /// (box, footprint, volume: [`lattice::DomainSize::of_mesh`]), not sliced.
    fn estimate(j: &LatticeJob, ctx: &mut Ctx) -> Result<Vec<crate::budget::Estimate>, Error> {
        let size = match j.domain {
            Domain::Solid => {
                let input =
                    j.input.as_ref().ok_or_else(|| Error::NoInput("a solid lattice domain needs a mesh: load one, or pass --input mesh=FILE".into()))?;
                let mesh = ctx.mesh(&SLOTS[0], input)?;
                lattice::DomainSize::of_mesh(&mesh, j.lattice.layer_thickness_mm)
            }
            _ => lattice::DomainSize::planar(&j.domain, &j.lattice),
        };
        let lat = lattice::estimate(&size, &j.lattice, line_width(ctx.design));
        let optimised = paths::estimate(&paths::Work::of_lattice(&lat), &j.paths);
        let mut out = vec![lat];
        if let Some(np) = &j.nonplanar {
            let surface = match (&np.surface, &j.surface_input) {
                (nonplanar::Surface::Mesh, Some(input)) => Some(nonplanar::SurfaceSize::of_mesh(&*ctx.mesh(&SLOTS[1], input)?, size.min, size.max)),
                _ => None,
            };
            let projected = nonplanar::estimate(&nonplanar::Work::of_paths(&optimised, size.min, size.max), surface.as_ref(), np);
            out.push(optimised);
            out.push(projected);
        } else {
            out.push(optimised);
        }
        Ok(out)
    }

    fn run(j: &LatticeJob, ctx: &mut Ctx) -> Result<Product, Error> {
        let strokes = strokes(j, ctx)?;
        let design = ctx.design;
        // The printer's retraction rule is in the key: the report counts its retractions.
        let key = (&j.paths, line_width(design), design.seed, &design.printer.retraction, design.printer.flavor);
        let optimised = ctx.stage("paths", "paths", &key, &[strokes.key], |progress| {
            let mut o = paths::optimise(&strokes, &j.paths, line_width(design), design.seed, progress).map_err(|e| Error::stage("paths", e))?;
            let counts = crate::gcode::retractions_per_pass(&o.toolpath, &design.printer);
            for (l, n) in o.report.layers.iter_mut().zip(counts) {
                l.retractions = n;
            }
            let report = paths_report(&o.report);
            Ok((o.toolpath, Some(report)))
        })?;
        drop(strokes);
        let Some(np) = &j.nonplanar else { return Ok(Product::Toolpath(optimised)) };
        let surface = match (&np.surface, &j.surface_input) {
            (nonplanar::Surface::Mesh, Some(input)) => Some(ctx.mesh(&SLOTS[1], input)?),
            _ => None,
        };
        let upstream: Vec<_> = std::iter::once(optimised.key).chain(surface.as_ref().map(|s| s.key)).collect();
        let projected = ctx.stage("nonplanar", "nonplanar", np, &upstream, |_| {
            let p = nonplanar::project(&optimised, surface.as_deref(), np).map_err(|e| Error::stage("non-planar", e))?;
            let r = &p.report;
            let report = StageReport::new("nonplanar", "Projecting onto the surface", r)
                .metric(
                    "missed_points",
                    "Points off the surface",
                    r.missed_points as f64,
                    "",
                    "Points with no surface under them (kept at the lowest surface height).",
                )
                .metric("collisions", "Digging segments", r.collisions as f64, "", "Moves that would cut into the layer below; 0 is safe.");
            Ok((p.toolpath, Some(report)))
        })?;
        Ok(Product::Toolpath(projected))
    }

    fn inspect(j: &LatticeJob, ctx: &mut Ctx, view: &str, index: usize) -> Result<Inspection, Error> {
        if view != "layer2d" {
            return Err(Error::UnknownView { view: view.into(), job: Self::NAME });
        }
        let strokes = strokes(j, ctx)?;
        let count = strokes.len();
        let index = index.min(count.saturating_sub(1));
        let mut data = Vec::new();
        if let Some(l) = strokes.get(index) {
            for s in &l.strokes {
                for w in s.points.windows(2) {
                    data.extend_from_slice(&[w[0].x as f32, w[0].y as f32, w[1].x as f32, w[1].y as f32, s.feature.code() as f32]);
                }
            }
        }
        let z = strokes.get(index).map_or(0.0, |l| l.z);
        Ok(Inspection {
            view: view.into(),
            shape: Shape::Lines2d,
            index,
            count,
            stride: Shape::Lines2d.stride(),
            data,
            overlay: Vec::new(),
            meta: serde_json::json!({ "z_mm": z }),
        })
    }
}

/// The lattice strokes of every layer of a lattice design (for `export-stl` and benchmarks):
/// the same stages as a run, without a cache.
pub fn lattice_strokes(design: &Design, files: &crate::stage::Files) -> Result<Vec<StrokeLayer>, Error> {
    let j: LatticeJob = design.job.settings().ok_or_else(|| Error::BadJob(format!("a {} job has no lattice", design.job.kind())))?;
    let mut cache = crate::stage::Cache::disabled();
    let mut quiet = |_: &str, _: f32| {};
    let mut ctx = Ctx::new(design, files, &mut cache, &mut quiet);
    let out = strokes(&j, &mut ctx)?;
    Ok(std::sync::Arc::try_unwrap(out.value).unwrap_or_else(|a| (*a).clone()))
}

/// The domain of every layer (built-in planar shapes directly, a solid by slicing it every
/// layer thickness) and the lattice strokes on them.
fn strokes(j: &LatticeJob, ctx: &mut Ctx) -> Result<Out<Vec<StrokeLayer>>, Error> {
    let design = ctx.design;
    let domains: Out<Vec<LayerDomain>> = match j.domain {
        // Built inside the stage, so a cached run does not build them again.
        Domain::Rectangle { .. } | Domain::Disc { .. } | Domain::TensileSpecimen { .. } => {
            // Refused before the layers' polygons are built (many layers of a big disc are
            // themselves large).
            let size = lattice::DomainSize::planar(&j.domain, &j.lattice);
            lattice::estimate(&size, &j.lattice, line_width(design)).check().map_err(|e| Error::stage("lattice", lattice::Error::OverBudget(e)))?;
            ctx.stage("domains", "domains", &(&j.domain, &j.lattice), &[], |_| Ok((lattice::planar_domains(&j.domain, &j.lattice).unwrap_or_default(), None)))?
        }
        Domain::Solid => {
            let input = j.input.as_ref().ok_or_else(|| Error::NoInput("a solid lattice domain needs a mesh: load one, or pass --input mesh=FILE".into()))?;
            let mesh = ctx.mesh(&SLOTS[0], input)?;
            let t = j.lattice.layer_thickness_mm;
            let options = slice::Options {
                first_layer_height_mm: t,
                layer_height_mm: t,
                perimeters: 0,
                infill_density: 0.0,
                solid_layers: 0,
                ..slice::Options::default()
            };
            ctx.stage("slice", "domains", &options, &[mesh.key], |progress| {
                let sliced = slice::slice(&mesh, &options, progress).map_err(|e| Error::stage("slicing", e))?;
                let report = super::slice_report(&sliced.report, "Slicing the solid");
                let domains = sliced.layers.into_iter().map(|l| LayerDomain { z: l.z, height: l.height, regions: l.regions, handles: Vec::new() }).collect();
                Ok((domains, Some(report)))
            })?
        }
    };
    let parts = (&j.lattice, line_width(design), design.seed, design.material.swell_ratio);
    ctx.stage("lattice", "lattice", &parts, &[domains.key], |progress| {
        let g = lattice::generate(&domains, &j.lattice, line_width(design), design.seed, progress).map_err(|e| Error::stage("lattice", e))?;
        let r = &g.report;
        let struts: usize = r.struts_per_layer.iter().sum();
        let mean_pore =
            if r.pore_fraction_per_layer.is_empty() { 0.0 } else { r.pore_fraction_per_layer.iter().sum::<f64>() / r.pore_fraction_per_layer.len() as f64 };
        let report = StageReport::new("lattice", "Generating the lattice", r)
            .metric("layers", "Layers", r.layers as f64, "", "Lattice layers generated.")
            .metric("struts", "Struts", struts as f64, "", "Strut pieces over all layers (a curved strut counts once), before path optimisation.")
            .metric("pore_fraction", "Pores", 100.0 * mean_pore, "%", "Open area of a layer: the part of the domain no strut covers (mean over layers).")
            .metric("strut_width", "Strut width", line_width(design), "mm", "Nominal strut width: the nozzle diameter, what the paths are planned for.")
            .metric(
                "printed_width",
                "Predicted printed width",
                design.material.swollen_width(line_width(design)),
                "mm",
                "Nominal width × the material's die swell ratio: how wide the struts are expected to come out.",
            );
        Ok((g.layers, Some(report)))
    })
}

/// The optimiser's report as the page draws it: the score of every GIPPO iteration per layer
/// (Fig. 2(i) of the paper) with the best so far and the proven lower bound, the path
/// classes, and a table of paths per layer.
fn paths_report(r: &PathsReport) -> StageReport {
    let total: usize = r.layers.iter().map(|l| l.paths).sum();
    let bound: usize = r.layers.iter().map(|l| l.lower_bound_paths).sum();
    let mut report = StageReport::new("paths", "Optimising print paths", r)
        .metric("paths", "Paths (all layers)", total as f64, "", "Extrusion paths over all layers: fewer means fewer starts and stops.")
        .metric(
            "lower_bound",
            "Lower bound (all layers)",
            bound as f64,
            "",
            "The proven minimum number of paths (half the odd-degree nodes of each connected part, at least one).",
        );
    let continuous = r.method == Some(crate::paths::Method::Continuous);
    // What the pairing is, and the problem its certificate is about.
    let (pairing_label, pairing_hint) = if continuous {
        (
            "Deadhead along struts",
            "Struts walked a second time without extruding. Each piece's walk may start and end anywhere: the fewest possible is the open Chinese postman's optimum.",
        )
    } else {
        ("Pairing", "Straight lines pairing every odd joint of each piece (fewest paths): in circuit order the travel between paths is these lines but one.")
    };
    for (i, l) in r.layers.iter().enumerate() {
        for (key, label, value, unit, hint) in [
            ("score", "Score", l.score, "", "GIPPO equation 1: higher means longer paths and fewer of them."),
            ("lts", "LTS", l.lts_percent, "%", "Equation 2: share of struts printed in long paths (5 nodes or more)."),
            (
                "oe",
                "OE",
                l.oe_percent,
                "%",
                "Equation 3 (optimisation efficiency): length × edges of the long paths over total length × total edges; higher is better.",
            ),
            ("travel", "Travel", l.travel_mm, "mm", "Moves without extruding: into the layer, between paths, and along struts retraced by a continuous walk."),
            (
                "free_travel",
                "Travel through the air",
                l.free_travel_mm,
                "mm",
                "Straight moves without extruding: into the layer, between paths and between pieces.",
            ),
            ("circuit_travel", "Travel in circuit order", l.circuit_travel_mm, "mm", "The same travel with the paths in the order the optimiser walks them."),
            ("pairing", pairing_label, l.pairing_mm, "mm", pairing_hint),
            (
                "travel_per_pairing",
                "Travel ÷ pairing",
                ratio(l.travel_mm, l.pairing_mm),
                "",
                "Travel over pairing length (0 when there is no pairing); continuous, one piece: 1 (the travel is the deadhead).",
            ),
            (
                "retractions",
                "Retractions",
                l.retractions as f64,
                "",
                "Retractions the G-code makes in this layer (free travels at least the printer's minimum length).",
            ),
        ] {
            report.metrics.push(crate::report::Metric {
                key: key.into(),
                label: label.into(),
                value,
                unit: unit.into(),
                hint: hint.into(),
                group_index: Some(i),
            });
        }
        if l.pairing_mm > 0.0 || l.pairing_lower_bound_mm > 0.0 {
            let problem = if continuous {
                "the fewest mm of struts walked twice by open walks that print every strut once (open Chinese postman, per piece)"
            } else {
                "the shortest straight lines pairing every odd joint of each piece (minimum-weight perfect matching)"
            };
            let hint = if l.deadhead_added_mm > 0.0 {
                format!(
                    "Above {problem}, by choice: the walks' ends take {:.2} mm more struts to save {:.2} mm of travel in all (struts and air).",
                    l.deadhead_added_mm, l.between_saved_mm
                )
            } else if l.pairing_optimal {
                format!("0 % means provably {problem}: solved exactly, lengths to the nanometre.")
            } else {
                format!("At most this far above {problem} (÷ a proven lower bound); solved quickly because an exact solve was estimated over the time budget.")
            };
            report.metrics.push(crate::report::Metric {
                key: "pairing_gap".into(),
                label: match (l.pairing_optimal, continuous) {
                    (true, true) => "Deadhead: optimal, gap".into(),
                    (true, false) => "Pairing: optimal, gap".into(),
                    (false, true) => "Deadhead: proven within".into(),
                    (false, false) => "Pairing: proven within".into(),
                },
                value: (l.pairing_gap - 1.0) * 100.0,
                unit: "%".into(),
                hint,
                group_index: Some(i),
            });
        }
    }
    let mut scores = Plot {
        key: "scores".into(),
        title: "GIPPO score per iteration".into(),
        kind: PlotKind::Line,
        x: Axis::new("Iteration", ""),
        y: Axis::new("Score (eq. 1)", ""),
        group: Some("Layer".into()),
        series: Vec::new(),
    };
    for (i, l) in r.layers.iter().enumerate() {
        if l.iteration_scores.is_empty() {
            continue;
        }
        let x: Vec<f64> = (1..=l.iteration_scores.len()).map(|k| k as f64).collect();
        let mut best = Vec::with_capacity(l.iteration_scores.len());
        let mut m = f64::NEG_INFINITY;
        for &s in &l.iteration_scores {
            m = m.max(s);
            best.push(m);
        }
        scores.series.push(Series::xy("score", x.clone(), l.iteration_scores.clone()).in_group(i));
        scores.series.push(Series::xy("best so far", x, best).in_group(i));
        scores.series.push(Series::hline("kept solution", l.score).in_group(i));
    }
    if !scores.series.is_empty() {
        report.plots.push(scores);
    }
    report.plots.push(per_layer_bars(r, "classes", "Path classes", "Class", &["long (> 15 nodes)", "medium (5–15)", "short (< 5)"], |l| {
        vec![l.long_paths as f64, l.medium_paths as f64, l.short_paths as f64]
    }));
    report.plots.push(per_layer_bars(r, "bound", "Paths against the proven minimum", "", &["lower bound", "printed"], |l| {
        vec![l.lower_bound_paths as f64, l.paths as f64]
    }));
    report.tables.push(Table {
        key: "layers".into(),
        title: "Paths per layer".into(),
        group: None,
        columns: [
            "Layer",
            "Struts",
            "Odd nodes",
            "Lower bound",
            "Paths",
            "Score",
            if continuous { "Deadhead" } else { "Pairing" },
            if continuous { "Deadhead quality" } else { "Pairing quality" },
            if continuous { "Deadhead bound" } else { "Pairing bound" },
            "Travel",
            "Through the air",
            "Travel ÷ pairing",
            "Retractions",
        ]
        .iter()
        .zip(["", "", "", "", "", "", "mm", "", "mm", "mm", "mm", "", ""])
        .map(|(label, unit)| Column { label: (*label).into(), unit: unit.into() })
        .collect(),
        rows: r
            .layers
            .iter()
            .enumerate()
            .map(|(i, l)| TableRow {
                group_index: None,
                cells: vec![
                    (i + 1).into(),
                    l.edges.into(),
                    l.odd_nodes.into(),
                    l.lower_bound_paths.into(),
                    l.paths.into(),
                    serde_json::json!((l.score * 1e4).round() / 1e4),
                    serde_json::json!((l.pairing_mm * 100.0).round() / 100.0),
                    l.pairing_quality().into(),
                    serde_json::json!((l.pairing_lower_bound_mm * 100.0).round() / 100.0),
                    serde_json::json!((l.travel_mm * 100.0).round() / 100.0),
                    serde_json::json!((l.free_travel_mm * 100.0).round() / 100.0),
                    serde_json::json!((ratio(l.travel_mm, l.pairing_mm) * 1000.0).round() / 1000.0),
                    l.retractions.into(),
                ],
            })
            .collect(),
    });
    report
}

/// `a / b`, 0 when `b` is 0.
fn ratio(a: f64, b: f64) -> f64 {
    if b > 0.0 {
        a / b
    } else {
        0.0
    }
}

/// A bar plot of path counts with one bar series per layer.
fn per_layer_bars(r: &PathsReport, key: &str, title: &str, x: &str, labels: &[&str], values: impl Fn(&paths::LayerPaths) -> Vec<f64>) -> Plot {
    Plot {
        key: key.into(),
        title: title.into(),
        kind: PlotKind::Bars,
        x: Axis::new(x, ""),
        y: Axis::new("Paths", ""),
        group: Some("Layer".into()),
        series: r.layers.iter().enumerate().map(|(i, l)| Series::bars("paths", labels, values(l)).in_group(i)).collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solid_slot_switches_the_domain() {
        let j = <LatticeKind as Kind>::slot_filled("mesh", LatticeJob::default());
        assert_eq!(j.domain, Domain::Solid);
        let j = <LatticeKind as Kind>::slot_filled("surface", LatticeJob::default());
        assert_ne!(j.domain, Domain::Solid);
    }
}

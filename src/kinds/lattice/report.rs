//! The lattice job's paths report: per-layer travel, deadhead and the pairing's quality, with their plots and the method's own labels.

use super::*;

/// The optimiser's report as the page draws it: the score of every GIPPO iteration per layer
/// (Fig. 2(i) of the paper) with the best so far and the proven lower bound, the path
/// classes, and a table of paths per layer.
pub(super) fn paths_report(r: &PathsReport) -> StageReport {
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
pub(super) fn ratio(a: f64, b: f64) -> f64 {
    if b > 0.0 {
        a / b
    } else {
        0.0
    }
}

/// A bar plot of path counts with one bar series per layer.
pub(super) fn per_layer_bars(r: &PathsReport, key: &str, title: &str, x: &str, labels: &[&str], values: impl Fn(&paths::LayerPaths) -> Vec<f64>) -> Plot {
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

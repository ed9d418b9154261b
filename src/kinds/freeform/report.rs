//! The freeform job's reports: the plan's ε per step, the joins of bands, the exact search against the planner, and the sequence table.

use super::*;

pub(super) fn optimum_report(best: &Optimum, known: Option<f64>, planner_eps: Option<&[f64]>, ms: f64, use_: ExactSearch) -> StageReport {
    let um = |x: f64| x * 1000.0;
    let label = match (best.proven, best.best_mm, &best.steps, known) {
        (true, None, _, _) => "Exact search: no order meets the constraints".to_string(),
        (true, Some(_), None, Some(_)) => "Exact search: the planner's sequence is optimal".to_string(),
        (true, Some(_), Some(_), Some(_)) => format!("Exact search: a better sequence{}", if use_ == ExactSearch::Print { " (printed)" } else { "" }),
        (true, Some(_), _, None) => "Exact search: the optimal sequence (the planner found none)".to_string(),
        (false, _, _, _) => format!("Exact search: gave up after {} states", best.states),
    };
    let mut r = StageReport::new(
        "optimum",
        &label,
        &serde_json::json!({ "proven": best.proven, "best_um": best.best_mm.map(um), "planner_um": known.map(um), "states": best.states, "improvements": best.improvements }),
    );
    if let Some(b) = best.best_mm {
        r = r.metric(
            "best",
            if best.proven { "Least largest ε (proven)" } else { "Least largest ε found" },
            um(b),
            "µm",
            "The smallest largest joint error over every order the constraints allow (exact cost).",
        );
    }
    if let Some(k) = known {
        r = r.metric("planner", "Planner's largest ε (exact)", um(k), "µm", "The planner's sequence measured with the exact cost.");
        if let Some(b) = best.best_mm.filter(|&b| b > 0.0) {
            r = r.metric(
                "gap",
                "Planner's gap",
                (k / b - 1.0) * 100.0,
                "%",
                "How far the planner's largest ε is above the least found (0: the planner's is optimal when proven).",
            );
        }
    }
    r = r
        .metric(
            "states",
            "States searched",
            best.states as f64,
            "",
            "Sets of printed beams the search explored (each a state whatever the order that led to it).",
        )
        .metric(
            "improvements",
            "Better orders found",
            best.improvements as f64,
            "",
            "Sequences the search found one after another, each with a smaller largest ε than the last.",
        )
        .metric("time", "Search time", ms, "ms", "Wall time of the search on this machine.");
    if let (Some(steps), Some(pe)) = (&best.steps, planner_eps) {
        let x: Vec<f64> = (1..=pe.len()).map(|i| i as f64).collect();
        let se: Vec<f64> = steps.iter().map(|s| um(s.cost_mm)).collect();
        r.plots.push(Plot {
            key: "optimum_sequence".into(),
            title: "ε of each step: planner and exact search".into(),
            kind: PlotKind::Line,
            x: Axis::new("step", ""),
            y: Axis::new("ε", "µm"),
            group: None,
            series: vec![Series::xy("planner", x.clone(), pe.iter().map(|&e| um(e)).collect()), Series::xy("exact search", x, se)],
        });
    }
    r
}

/// The cost of planning in bands: in each band, in the plan's order, the largest ε its plan
/// saw (the bands below rigid) against the largest measured with the whole frame (`whole`,
/// NaN past the budget), and the largest growth of one step's ε.
pub(super) fn joins_report(r: StageReport, p: &Plan, whole: &[Costs]) -> StageReport {
    let n = p.steps.len();
    let (mut planned, mut measured) = (Vec::new(), Vec::new());
    for (k, &start) in p.bands.iter().enumerate() {
        let end = p.bands.get(k + 1).copied().unwrap_or(n);
        let range = start.min(n)..end.min(n);
        planned.push(p.steps[range.clone()].iter().map(|s| s.cost_mm * 1000.0).fold(0.0, f64::max));
        measured.push(whole[range].iter().map(|k| k.exact_mm * 1000.0).filter(|e| e.is_finite()).fold(0.0, f64::max));
    }
    let join = p.steps.iter().zip(whole).map(|(s, k)| (k.exact_mm - s.cost_mm) * 1000.0).filter(|e| e.is_finite()).fold(0.0, f64::max);
    let worst_planned = planned.iter().copied().fold(0.0, f64::max);
    let worst = measured.iter().copied().fold(0.0, f64::max);
    let x: Vec<f64> = (1..=planned.len()).map(|i| i as f64).collect();
    let mut r = r
        .metric("band_planned", "Largest ε planned in bands", worst_planned, "µm", "The largest ε the bands' plans saw, each with the bands below rigid.")
        .metric(
            "band_join",
            "Cost of the joins",
            join,
            "µm",
            "The most one step's ε grows when the bands below deflect too (the plan's order measured with the whole frame).",
        )
        .metric("band_measured", "Largest ε measured", worst, "µm", "The largest ε of the joined sequence with the whole frame.");
    r.plots.push(Plot {
        key: "bands".into(),
        title: "Largest ε per band: planned (bands below rigid) and measured (whole frame)".into(),
        kind: PlotKind::Line,
        x: Axis::new("band", ""),
        y: Axis::new("ε", "µm"),
        group: None,
        series: vec![Series::xy("planned", x.clone(), planned), Series::xy("measured", x, measured)],
    });
    r
}

/// ε over the sequence as planned (no comparison asked).
pub(super) fn planned_report(o: &Ordered) -> StageReport {
    let x: Vec<f64> = (1..=o.steps.len()).map(|i| i as f64).collect();
    let y: Vec<f64> = o.steps.iter().map(|s| s.cost_mm * 1000.0).collect();
    let mut r = StageReport::new("costs", "Joint errors along the sequence", &serde_json::json!({ "compared": false }));
    r.plots.push(Plot {
        key: "eps_sequence".into(),
        title: "ε of each step (as planned)".into(),
        kind: PlotKind::Line,
        x: Axis::new("step", ""),
        y: Axis::new("ε", "µm"),
        group: None,
        series: vec![Series::xy("planned", x, y)],
    });
    r
}

pub(super) fn costs_report(c: &[Costs], load: f64, chosen: Cost, stopped: Option<usize>) -> StageReport {
    // Past the budget nothing was measured: the measured steps only.
    let c = &c[..stopped.unwrap_or(c.len())];
    let n = c.len();
    let x: Vec<f64> = (1..=n).map(|i| i as f64).collect();
    let exact: Vec<f64> = c.iter().map(|k| k.exact_mm * 1000.0).collect();
    let heur: Vec<f64> = c.iter().map(|k| k.heuristic_mm * 1000.0).collect();
    let max_e = exact.iter().copied().fold(0.0, f64::max);
    let max_h = heur.iter().copied().fold(0.0, f64::max);
    // Steps where the heuristic reads more than the exact cost (the paper's Fig. 8C says never).
    let above = c.iter().filter(|k| k.heuristic_mm > k.exact_mm * (1.0 + 1e-9) + 1e-15).count();
    let data = serde_json::json!({ "compared": true, "max_exact_um": max_e, "max_heuristic_um": max_h, "heuristic_above_exact": above });
    let r = StageReport::new("costs", "Joint errors, exact and heuristic", &data)
        .metric("max_exact", "Largest ε, exact", max_e, "µm", "The largest joint error along this sequence with the whole frame deflecting.")
        .metric("max_heuristic", "Largest ε, heuristic", max_h, "µm", "The same with only the cantilevered beams deflecting (the rest rigid).")
        .metric("ratio", "Heuristic ÷ exact (largest)", if max_e > 0.0 { max_h / max_e } else { 0.0 }, "", "How much of the worst error the heuristic sees.")
        .metric("above", "Steps heuristic > exact", above as f64, "", "Steps where the heuristic reads more than the exact cost (the paper: never).");
    let mut r = match stopped {
        Some(k) => r.metric(
            "measured",
            "Steps measured",
            k as f64,
            "",
            "The planning budget ran out during the measurement: the numbers and plots cover these first steps (raise the budget to measure all).",
        ),
        None => r,
    };
    let chosen_name = match chosen {
        Cost::Exact => "exact (planned with)",
        Cost::Heuristic => "heuristic (planned with)",
    };
    let (e_name, h_name) = if chosen == Cost::Exact { (chosen_name, "heuristic") } else { ("exact", chosen_name) };
    r.plots.push(Plot {
        key: "eps_sequence".into(),
        title: "ε of each step".into(),
        kind: PlotKind::Line,
        x: Axis::new("step", ""),
        y: Axis::new("ε", "µm"),
        group: None,
        series: vec![Series::xy(e_name, x.clone(), exact.clone()), Series::xy(h_name, x, heur.clone())],
    });
    // Fig. 8A: compliances (ε per unit load) of the steps, sorted.
    let mut se: Vec<f64> = c.iter().filter(|k| k.exact_mm > 0.0).map(|k| k.exact_mm / load).collect();
    let mut sh: Vec<f64> = c.iter().filter(|k| k.exact_mm > 0.0).map(|k| k.heuristic_mm / load).collect();
    se.sort_by(f64::total_cmp);
    sh.sort_by(f64::total_cmp);
    let rank: Vec<f64> = (1..=se.len()).map(|i| i as f64).collect();
    r.plots.push(Plot {
        key: "compliance_sorted".into(),
        title: "Compliance of the steps, sorted (Fig. 8A)".into(),
        kind: PlotKind::Line,
        x: Axis::new("rank", ""),
        y: Axis::new("ε ÷ load", "mm/N"),
        group: None,
        series: vec![Series::xy("exact", rank.clone(), se), Series::xy("heuristic", rank, sh)],
    });
    // Fig. 8C: heuristic against exact compliance, one point per step.
    let (xs, ys): (Vec<f64>, Vec<f64>) = c.iter().filter(|k| k.exact_mm > 0.0).map(|k| (k.exact_mm / load, k.heuristic_mm / load)).unzip();
    let top = xs.iter().copied().fold(0.0, f64::max);
    r.plots.push(Plot {
        key: "heuristic_vs_exact".into(),
        title: "Heuristic against exact compliance (Fig. 8C)".into(),
        kind: PlotKind::Scatter,
        x: Axis::new("exact", "mm/N"),
        y: Axis::new("heuristic", "mm/N"),
        group: None,
        series: vec![Series::xy("steps", xs, ys), Series { kind: Some(PlotKind::Line), ..Series::xy("heuristic = exact", vec![0.0, top], vec![0.0, top]) }],
    });
    // The distribution of ε.
    if max_e > 0.0 {
        let bins = 20;
        let edges: Vec<f64> = (0..=bins).map(|i| max_e * i as f64 / bins as f64).collect();
        let mut counts = vec![0.0; bins];
        for &e in &exact {
            let k = ((e / max_e * bins as f64) as usize).min(bins - 1);
            counts[k] += 1.0;
        }
        r.plots.push(Plot {
            key: "eps_histogram".into(),
            title: "Distribution of ε (exact)".into(),
            kind: PlotKind::Histogram,
            x: Axis::new("ε", "µm"),
            y: Axis::new("steps", ""),
            group: None,
            series: vec![Series::xy("steps", edges, counts)],
        });
    }
    r
}

/// The sequence as a table (first [`TABLE_ROWS`] steps): for `--report` readers and the page.
pub fn sequence_table(w: &Wireframe, o: &Ordered) -> Table {
    let rows = o
        .steps
        .iter()
        .take(TABLE_ROWS)
        .enumerate()
        .map(|(i, s)| TableRow {
            group_index: None,
            cells: vec![
                serde_json::json!(i + 1),
                serde_json::json!(w.beam_names.get(s.beam).cloned().unwrap_or_default()),
                serde_json::json!(w.joint_names.get(s.from).cloned().unwrap_or_default()),
                serde_json::json!(w.joint_names.get(s.to).cloned().unwrap_or_default()),
                serde_json::json!((s.cost_mm * 1e6).round() / 1e3),
            ],
        })
        .collect();
    Table {
        key: "sequence".into(),
        title: format!("Sequence (first {} of {} steps)", o.steps.len().min(TABLE_ROWS), o.steps.len()),
        group: None,
        columns: ["step", "beam", "from", "to", "ε"]
            .iter()
            .zip(["", "", "", "", "µm"])
            .map(|(l, u)| Column { label: l.to_string(), unit: u.to_string() })
            .collect(),
        rows,
    }
}

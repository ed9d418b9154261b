//! The foam job's grading report: the weighting functions and V*, H*, ΔE/mm and the modulus along the probe line (the paper's Fig. 6).

use super::*;

#[allow(clippy::too_many_arguments)] // the report of one stage: its numbers
pub(super) fn grade_report(
    j: &FoamJob,
    p: &Process,
    field: &Field,
    regions: &Regions,
    transitions: &[Transition],
    pieces: usize,
    queries: usize,
    v: (f64, f64),
) -> StageReport {
    let (v_lo, v_hi) = if v.0 <= v.1 { v } else { (0.0, 0.0) };
    let mut r = StageReport::new("grade", "Grading V* and H* along the path", &serde_json::json!({ "pieces": pieces, "queries": queries }))
        .metric("pieces", "Pieces", pieces as f64, "", "Pieces of path, each printed with the V* and H* of its end point.")
        .metric(
            "queries",
            "Exact evaluations",
            queries as f64,
            "",
            "Pieces whose pair needed parry's distance queries; the others were known far from every boundary.",
        )
        .metric("v_star_min", "Lowest V*", v_lo, "", "Densest coils printed.")
        .metric("v_star_max", "Highest V*", v_hi, "", "Sparsest coils printed.")
        .metric(
            "e_per_mm_max",
            "Most filament per mm",
            if v_lo > 0.0 { p.filament_per_mm(v_lo) } else { 0.0 },
            "mm/mm",
            "ΔE per mm of nozzle travel at the lowest V*: A_t / (V*·A_f).",
        )
        .metric(
            "e_per_mm_min",
            "Least filament per mm",
            if v_hi > 0.0 { p.filament_per_mm(v_hi) } else { 0.0 },
            "mm/mm",
            "ΔE per mm of nozzle travel at the highest V*.",
        )
        .metric(
            "thread_speed",
            "Thread speed",
            p.speed_mm_s(1.0),
            "mm/s",
            "Speed of the thread leaving the nozzle, C·A_f/A_t (the nozzle moves V* times as fast).",
        );
    // The weighting functions of the transitions (appendix A), plotted over x = α_i/α_T.
    let xs: Vec<f64> = (0..=120).map(|i| -0.6 + 1.2 * i as f64 / 120.0).collect();
    let mut weights = Plot {
        key: "weighting".into(),
        title: "Weighting functions w(x)".into(),
        kind: PlotKind::Line,
        x: Axis::new("x = α_i / α_T", ""),
        y: Axis::new("w", ""),
        group: None,
        series: Vec::new(),
    };
    let mut seen: Vec<Weighting> = Vec::new();
    for t in transitions {
        if !seen.contains(&t.weighting) {
            seen.push(t.weighting);
        }
    }
    let used = seen.len();
    let linear_modulus = Weighting::LinearModulus { ratio: crate::foam::weight::DEFAULT_MODULUS_RATIO };
    for w in [
        Weighting::Linear,
        Weighting::Cubic { slope: crate::foam::weight::DEFAULT_CUBIC_SLOPE },
        Weighting::logarithmic(),
        Weighting::CubeRoot,
        Weighting::Sinusoidal,
        linear_modulus,
    ] {
        if !seen.iter().any(|s| std::mem::discriminant(s) == std::mem::discriminant(&w)) {
            seen.push(w);
        }
    }
    for (i, w) in seen.iter().enumerate() {
        // Linear-modulus weightings differ by their regions' modulus ratio.
        let ratio = match w {
            Weighting::LinearModulus { ratio } => format!(", E × {ratio:.3}"),
            _ => String::new(),
        };
        let name = format!("{}{ratio}{}", weighting_name(w), if i < used { " (used)" } else { "" });
        weights.series.push(Series::xy(&name, xs.clone(), xs.iter().map(|&x| w.weight(x)).collect()));
    }
    r.plots.push(weights);
    // The probe line through the middle of the part (the paper's Fig. 6).
    let all = regions.regions.iter().map(|x| x.bounds).reduce(|a, b| crate::geom::Aabb { min: a.min.min(b.min), max: a.max.max(b.max) });
    if let Some(b) = all {
        let c = (b.min + b.max) * 0.5;
        let (axis, label) = match j.foam.probe_axis {
            ProbeAxis::X => (DVec3::X, "x"),
            ProbeAxis::Y => (DVec3::Y, "y"),
            ProbeAxis::Z => (DVec3::Z, "z"),
        };
        let (lo, hi) = (b.min.dot(axis), b.max.dot(axis));
        let cal = &j.foam.calibration;
        let (mut s, mut vs, mut hs, mut es, mut ms) = (Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for i in 0..PROBE_SAMPLES {
            let t = lo + (hi - lo) * i as f64 / (PROBE_SAMPLES - 1) as f64;
            let q = c + axis * (t - c.dot(axis));
            let Some(pair) = field.inside(q) else { continue }; // outside the part
            s.push(t);
            vs.push(pair.v_star);
            hs.push(pair.h_star);
            es.push(p.filament_per_mm(pair.v_star));
            ms.push(cal.modulus_kpa(pair.v_star));
        }
        let plot = |key: &str, title: &str, y: &str, unit: &str, values: Vec<f64>| Plot {
            key: key.into(),
            title: format!("{title} along {label} (probe through the middle)"),
            kind: PlotKind::Line,
            x: Axis::new(label, "mm"),
            y: Axis::new(y, unit),
            group: None,
            series: vec![Series::xy(y, s.clone(), values)],
        };
        r.plots.push(plot("probe_v", "V*", "V*", "", vs.clone()));
        r.plots.push(plot("probe_h", "H*", "H*", "", hs));
        r.plots.push(plot("probe_e", "Filament per mm", "ΔE/mm", "mm/mm", es));
        if cal.problems().is_empty() {
            // Outside the calibration's sweep the fit is extrapolated: the title says so.
            let (lo, hi) = (cal.v_star_from.min(cal.v_star_to), cal.v_star_from.max(cal.v_star_to));
            let outside = vs.iter().any(|&v| v < lo * (1.0 - 1e-9) || v > hi * (1.0 + 1e-9));
            // The calibration (by default the paper's own fit) applied to V*: not a measurement,
            // so it cannot confirm the paper's moduli; the title says so.
            let fit = "Modulus by the calibration's fit at each V* (not measured)";
            let title = if outside { format!("{fit}, extrapolated outside V* {lo}–{hi}") } else { fit.to_string() };
            r.plots.push(plot("probe_modulus", &title, "E", "kPa", ms));
        }
    }
    // Regions set by a modulus: the V* weft chose for them.
    for (i, spec) in j.regions.iter().enumerate() {
        if spec.set_by == SetBy::Modulus {
            r.metrics.push(Metric {
                key: "region_v_star".into(),
                label: format!("Region {}: V*", i + 1),
                value: field.pair(i).v_star,
                unit: String::new(),
                hint: format!(
                    "The V* whose foam has {} kPa ({}), by the calibration under Stiffness.",
                    spec.modulus_kpa,
                    regions.regions.get(i).map_or("", |x| x.name.as_str())
                ),
                group_index: None,
            });
        }
    }
    for (i, t) in transitions.iter().enumerate() {
        r.metrics.push(Metric {
            key: "transition_length".into(),
            label: format!("Transition {}: {} → {}", i + 1, regions.regions[t.from].name, regions.regions[t.to].name),
            value: t.length_mm,
            unit: "mm".into(),
            hint: format!("{} blend over this length, centred on the shared boundary.", weighting_name(&t.weighting)),
            group_index: None,
        });
        // A weighting that does not meet its regions' values at its ends (the paper's fitted
        // logarithm) makes V* jump there: said, with the values it jumps to.
        let (a, b) = (field.pair(t.from).v_star, field.pair(t.to).v_star);
        let (w0, w1) = (t.weighting.inside(-0.5), t.weighting.inside(0.5));
        if t.length_mm > 0.0 && (w0.abs() > 1e-6 || (w1 - 1.0).abs() > 1e-6) {
            for (key, label, w) in [("transition_v_start", "starts at V*", w0), ("transition_v_end", "ends at V*", w1)] {
                r.metrics.push(Metric {
                    key: key.into(),
                    label: format!("Transition {} {label}", i + 1),
                    value: a + (b - a) * w,
                    unit: String::new(),
                    hint: "The weighting's own value at this end of the transition: V* jumps there from the region's.".into(),
                    group_index: None,
                });
            }
        }
    }
    r
}

pub(super) fn weighting_name(w: &Weighting) -> &'static str {
    match w {
        Weighting::Linear => "linear",
        Weighting::Cubic { .. } => "cubic",
        Weighting::Logarithmic { .. } => "logarithmic",
        Weighting::CubeRoot => "cube root",
        Weighting::Sinusoidal => "sinusoidal",
        Weighting::LinearModulus { .. } => "linear modulus",
    }
}

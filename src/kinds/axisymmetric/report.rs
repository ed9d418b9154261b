//! The axisymmetric job's reports: the platform, the points (spacing, energy, grading), the path and the tool axes, with their plots and the per-layer table.

use super::*;

/// Samples per segment of the platform plots.
pub(super) const PLOT_SAMPLES_PER_SEGMENT: usize = 64;

/// What the `axes` stage reports.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AxesSummary {
    /// Largest tilt of the tool axis from the normal, degrees (0: the normals).
    pub max_tilt_deg: f64,
    /// Per axis (tool axis first, then the rotary letters): [speed °/s, acceleration °/s²]
    /// before smoothing.
    pub raw: Vec<(String, [f64; 2])>,
    /// The same after smoothing (equal to `raw` when smoothing is off).
    pub smoothed: Vec<(String, [f64; 2])>,
}

pub(super) fn axes_report(o: &dynamics::Options, max_tilt_deg: f64, raw: &dynamics::Dynamics, after: &dynamics::Dynamics, feed: f64) -> StageReport {
    let pairs = |d: &dynamics::Dynamics| d.axes.iter().map(|a| (a.axis.clone(), [a.max_speed_deg_s, a.max_accel_deg_s2])).collect::<Vec<_>>();
    let summary = AxesSummary { max_tilt_deg, raw: pairs(raw), smoothed: pairs(after) };
    let on = o.max_tilt_deg > 0.0;
    let mut r = StageReport::new("axes", "Tool axis and machine dynamics", &summary)
        .metric("max_tilt", "Largest tilt from the normal", max_tilt_deg, "°", "How far smoothing leans the tool axis (0: the axis is the normal).")
        .metric("feed", "At the infill speed", feed, "mm/s", "Speeds below scale with it, accelerations with its square.")
        .metric("duration", "Path time", after.duration_s, "s", "Every layer's path at the infill speed.");
    // The tool axis as metrics; every axis (rotary ones too) in the table below.
    if let Some(b) = after.axes.first() {
        r = r
            .metric("tool_speed", "Tool-axis turn, fastest", b.max_speed_deg_s, "°/s", "How fast the tool axis turns at the infill speed (smoothed, when on).")
            .metric(
                "tool_accel",
                "Tool-axis acceleration, largest",
                b.max_accel_deg_s2,
                "°/s²",
                "Its hardest change of turning speed: the raster's corners set it.",
            );
    }
    if on {
        for (a, b) in raw.axes.iter().zip(&after.axes) {
            let cut = if a.max_accel_deg_s2 > 0.0 { 100.0 * (1.0 - b.max_accel_deg_s2 / a.max_accel_deg_s2) } else { 0.0 };
            let key = if a.axis == "tool axis" { "tool".to_string() } else { a.axis.to_lowercase() };
            r = r.metric(&format!("{key}_accel_cut"), &format!("Acceleration cut, {}", a.axis), cut, "%", "Against the axis equal to the normal everywhere.");
        }
    }
    r.tables.push(crate::report::Table {
        key: "dynamics".into(),
        title: "Axis speeds and accelerations at the infill speed".into(),
        group: None,
        columns: [("Axis", ""), ("Speed", "°/s"), ("Accel.", "°/s²"), ("Speed, smoothed", "°/s"), ("Accel., smoothed", "°/s²")]
            .iter()
            .map(|(label, unit)| crate::report::Column { label: (*label).into(), unit: (*unit).into() })
            .collect(),
        rows: raw
            .axes
            .iter()
            .zip(&after.axes)
            .map(|(a, b)| crate::report::Row {
                group_index: None,
                cells: vec![
                    a.axis.clone().into(),
                    round(a.max_speed_deg_s).into(),
                    round(a.max_accel_deg_s2).into(),
                    round(b.max_speed_deg_s).into(),
                    round(b.max_accel_deg_s2).into(),
                ],
            })
            .collect(),
    });
    r
}

/// Four significant digits, for table cells.
pub(super) fn round(v: f64) -> f64 {
    if v == 0.0 || !v.is_finite() {
        return v;
    }
    let scale = libm::pow(10.0, 3.0 - libm::floor(libm::log10(v.abs())));
    libm::round(v * scale) / scale
}

/// Per layer: its offset, points, spread reduction and path length.
pub(super) fn layer_table(layers: &[Layer], h: f64) -> crate::report::Table {
    use crate::report::{Column, Row as TableRow, Table};
    let col = |label: &str, unit: &str| Column { label: label.into(), unit: unit.into() };
    let rows = layers
        .iter()
        .enumerate()
        .map(|(k, l)| {
            let (s, m) = (&l.points.seed_metrics, &l.points.metrics);
            // Against the local target spacing (the same ratio as in mm when the density is uniform).
            let reduction = if s.rel_std > 0.0 { 100.0 * (1.0 - m.rel_std / s.rel_std) } else { 0.0 };
            let (length, over) = l.tour.as_ref().map_or((0.0, 0), |t| (t.length_mm, t.hole_crossings));
            TableRow {
                group_index: None,
                cells: vec![
                    (k + 1).into(),
                    l.offset_mm.into(),
                    ((k + 1) as f64 * h).into(),
                    l.points.points.len().into(),
                    reduction.into(),
                    length.into(),
                    over.into(),
                ],
            }
        })
        .collect();
    Table {
        key: "layers".into(),
        title: "Layers: each on the platform offset by the layers below".into(),
        group: None,
        columns: vec![
            col("Layer", ""),
            col("Surface offset", "mm"),
            col("Tip offset", "mm"),
            col("Points", ""),
            col("Spread reduced by", "%"),
            col("Path length", "mm"),
            col("Hops over a hole (not printed)", ""),
        ],
        rows,
    }
}

pub(super) fn platform_report(p: &Platform, c: &platform::Continuity) -> StageReport {
    let (lo, hi) = (0.0, p.segments.len() as f64);
    let n = p.segments.len() * PLOT_SAMPLES_PER_SEGMENT;
    let clearance = platform::pole_clearance(p, platform::DEFAULT_MIN_POLE_RADIUS_MM);
    let (mut us, mut kappa, mut guu, mut gtt, mut g_uuu, mut g_utt, mut g_tut) = (vec![], vec![], vec![], vec![], vec![], vec![], vec![]);
    let mut max_kappa: f64 = 0.0;
    for i in 0..=n {
        let u = lo + (hi - lo) * i as f64 / n as f64;
        let k = platform::curvature(p, u);
        let m = platform::metric(p, u);
        us.push(u);
        kappa.push(k);
        guu.push(m.g_uu);
        gtt.push(m.g_tt);
        max_kappa = max_kappa.max(k.abs());
        // Γ^θ_uθ = x′/x is unbounded at the poles: plotted only where a domain may go.
        let inside = clearance.is_some_and(|(a, b)| u >= a && u <= b);
        let c = platform::christoffel(p, u);
        g_uuu.push(c.u_uu);
        g_utt.push(c.u_tt);
        g_tut.push(if inside { c.t_ut } else { f64::NAN });
    }
    let line = |key: &str, title: &str, y: &str, unit: &str, series: Vec<Series>| Plot {
        key: key.into(),
        title: title.into(),
        kind: PlotKind::Line,
        x: Axis::new("u", ""),
        y: Axis::new(y, unit),
        group: None,
        series,
    };
    let mut r = StageReport::new("platform", "Checking the build platform", c)
        .metric("segments", "Bézier segments", p.segments.len() as f64, "", "Degree-6 segments of the generatrix; u runs from 0 to this number.")
        .metric(
            "max_jump",
            "Largest C³ jump at a knot",
            c.worst_rel.iter().fold(0.0, |a: f64, b| a.max(*b)),
            "",
            "The largest jump of x, z or their first three derivatives across a knot, relative to their size (0: C³).",
        )
        .metric("max_curvature", "Largest |κ|", max_kappa, "1/mm", "The sharpest bend of the profile: 1/κ is the smallest radius of curvature.");
    if let Some((a, b)) = clearance {
        r = r
            .metric("u_clear_min", "Domain may start at u", a, "", "Closer to the top pole the metric degenerates (g_θθ → 0): keep Ω at or above this u.")
            .metric("u_clear_max", "Domain may end at u", b, "", "Closer to the bottom pole the metric degenerates: keep Ω at or below this u.");
    }
    r.plots.push(line("curvature", "Curvature κ of the generatrix", "κ", "1/mm", vec![Series::xy("κ", us.clone(), kappa)]));
    r.plots.push(line("metric", "Metric components", "g", "mm²", vec![Series::xy("g_uu", us.clone(), guu), Series::xy("g_θθ", us.clone(), gtt)]));
    r.plots.push(line(
        "christoffel",
        "Christoffel symbols of the second kind",
        "Γ",
        "",
        vec![Series::xy("Γ^u_uu", us.clone(), g_uuu), Series::xy("Γ^u_θθ", us.clone(), g_utt), Series::xy("Γ^θ_uθ", us, g_tut)],
    ));
    r
}

/// The `points` stage's typed report (`weft run --report`): the numbers, not the points.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PointsSummary {
    /// True surface area of Ω, mm².
    pub area_mm2: f64,
    /// N of equation 4.
    pub points: usize,
    /// Normalised energy E/E0 after each accepted iteration.
    pub energy: Vec<f64>,
    /// Why the repulsion stopped.
    pub stop: String,
    /// 2n-NN distances of the seed: mean and standard deviation, mm.
    pub seed_mean_mm: f64,
    /// See `seed_mean_mm`.
    pub seed_std_mm: f64,
    /// 2n-NN distances after repulsion: mean and standard deviation, mm.
    pub mean_mm: f64,
    /// See `mean_mm`.
    pub std_mm: f64,
    /// 1 − std / seed std.
    pub std_reduction: f64,
    /// e / mean distance after repulsion.
    pub ratio: f64,
    /// e / mean distance of the seed.
    pub seed_ratio: f64,
    /// 2n-NN distances over each point's target spacing s(q) = n·e/ρ(q): standard deviation
    /// of the seed (uniform: `seed_std_mm` / s).
    #[serde(default)]
    pub seed_rel_std: f64,
    /// The same after repulsion.
    #[serde(default)]
    pub rel_std: f64,
    /// 1 − rel_std / seed_rel_std.
    #[serde(default)]
    pub rel_std_reduction: f64,
    /// Whether the density is graded.
    #[serde(default)]
    pub graded: bool,
}

/// The `path` stage's typed report.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PathSummary {
    /// Points visited (each once).
    pub visited: usize,
    /// Path length along the geodesics, mm.
    pub length_mm: f64,
    /// The nearest-neighbour path's length, mm.
    pub nn_length_mm: f64,
    /// Crossings 2-opt removed and left.
    pub crossings_removed: usize,
    /// See `crossings_removed`.
    pub crossings_left: usize,
    /// Poses written.
    pub poses: usize,
    /// Path segments that cross a hole of Ω (0 without holes).
    #[serde(default)]
    pub hole_crossings: usize,
}

pub(super) fn points_report(d: &uniform::Distribution, o: &uniform::Options, width: f64) -> StageReport {
    let s = &d.seed_metrics;
    let m = &d.metrics;
    let reduction = if s.nn_std_mm > 0.0 { 100.0 * (1.0 - m.nn_std_mm / s.nn_std_mm) } else { 0.0 };
    let summary = PointsSummary {
        area_mm2: d.area_mm2,
        points: d.points.len(),
        energy: d.iterations.iter().map(|i| i.energy).collect(),
        stop: format!("{:?}", d.stop),
        seed_mean_mm: s.nn_mean_mm,
        seed_std_mm: s.nn_std_mm,
        mean_mm: m.nn_mean_mm,
        std_mm: m.nn_std_mm,
        std_reduction: reduction / 100.0,
        ratio: m.ratio,
        seed_ratio: s.ratio,
        seed_rel_std: s.rel_std,
        rel_std: m.rel_std,
        rel_std_reduction: if s.rel_std > 0.0 { 1.0 - m.rel_std / s.rel_std } else { 0.0 },
        graded: d.graded.is_some(),
    };
    let mut r = StageReport::new("points", "Spreading uniform points (geodesic repulsion)", &summary)
        .metric("area", "Surface area of Ω", d.area_mm2, "mm²", "The true area A_Σ of the patch on the curved platform.")
        .metric("points", "Points N", d.points.len() as f64, "", "Equation 4: N = A_Σ·ρ_c² / (n²·e²), e the nozzle diameter.")
        .metric("iterations", "Repulsion iterations", d.iterations.len() as f64, "", "Geodesic repulsion steps taken before a tolerance or the cap stopped it.")
        .metric("std_seed", "Spacing spread, seed", s.nn_std_mm, "mm", "Standard deviation of the distances to the 2n nearest neighbours before repulsion.")
        .metric("std", "Spacing spread, result", m.nn_std_mm, "mm", "The same after repulsion: lower is more uniform.")
        .metric(
            "std_reduction",
            "Spread reduced by",
            reduction,
            "%",
            if o.grading.is_some() {
                "In mm, which a graded density spreads on purpose: see the spread against the target below."
            } else {
                "How much repulsion evened the spacing, against this run's own seed (the paper: 71.7 % on Ω1, 44 % on Ω3; its Ω2 polygon is not published, so barrel-omega2 is weft's stand-in)."
            },
        )
        .metric("mean", "Mean neighbour distance", m.nn_mean_mm, "mm", "Mean distance to the 2n nearest neighbours after repulsion.")
        .metric(
            "ratio",
            "e / mean distance",
            100.0 * m.ratio,
            "%",
            "Line width over the mean spacing: the density the points give, to compare with the command density.",
        )
        .metric(
            "command",
            "Command density ρ_c",
            100.0 * o.density,
            "%",
            if o.grading.is_some() { "The density asked for at the near end of the grading." } else { "The density asked for." },
        );
    if let (Some(g), Some(gp)) = (&o.grading, &d.graded) {
        r = graded_report(r, d, g, gp);
    }
    let it: Vec<f64> = (0..d.iterations.len()).map(|i| (i + 1) as f64).collect();
    let h = if o.grading.is_some() { "h = 4·s(q) per point".to_string() } else { format!("h = {:.3} mm", 4.0 * o.rasters as f64 * width / o.density) };
    r.plots.push(Plot {
        key: "energy".into(),
        title: "Normalised repulsion energy per iteration".into(),
        kind: PlotKind::Line,
        x: Axis::new("Iteration", ""),
        y: Axis::new("E / E0", ""),
        group: None,
        series: vec![Series::xy("E / E0", it, d.iterations.iter().map(|i| i.energy).collect())],
    });
    let rank = |v: &[f64]| -> Vec<f64> { (0..v.len()).map(|i| i as f64).collect() };
    r.plots.push(Plot {
        key: "kdf".into(),
        title: format!("Kernel density per point, sorted ({h})"),
        kind: PlotKind::Line,
        x: Axis::new("Point (sorted)", ""),
        y: Axis::new("Kernel density", "1/mm²"),
        group: None,
        series: vec![Series::xy("seed", rank(&s.kdf_sorted), s.kdf_sorted.clone()), Series::xy("repulsion", rank(&m.kdf_sorted), m.kdf_sorted.clone())],
    });
    let (edges, seed_counts, counts) = crate::axisym::metrics::shared_histogram(&s.nn_distances_mm, &m.nn_distances_mm, HISTOGRAM_BINS);
    r.plots.push(Plot {
        key: "nn".into(),
        title: format!("Distances to the {} nearest neighbours", 2 * o.rasters),
        kind: PlotKind::Histogram,
        x: Axis::new("Distance", "mm"),
        y: Axis::new("Pairs", ""),
        group: None,
        series: vec![Series::xy("seed", edges.clone(), seed_counts), Series::xy("repulsion", edges, counts)],
    });
    r
}

/// Bins of the neighbour-distance histogram.
pub(super) const HISTOGRAM_BINS: usize = 30;

/// Mean of `values` per bin of `coord` over `range` (`bins` bins; NaN where a bin is empty).
pub(super) fn binned_mean(coord: &[f64], values: &[f64], range: [f64; 2], bins: usize) -> Vec<f64> {
    let (mut sum, mut count) = (vec![0.0; bins], vec![0usize; bins]);
    let w = (range[1] - range[0]) / bins as f64;
    for (c, v) in coord.iter().zip(values) {
        let k = if w > 0.0 { (((c - range[0]) / w).max(0.0) as usize).min(bins - 1) } else { 0 };
        sum[k] += v;
        count[k] += 1;
    }
    sum.iter().zip(&count).map(|(s, &c)| if c > 0 { s / c as f64 } else { f64::NAN }).collect()
}

/// The graded run's rows and plots: spread of the distances against the local target, the
/// commanded density against the measured one along the grading coordinate.
pub(super) fn graded_report(mut r: StageReport, d: &uniform::Distribution, g: &crate::axisym::grading::Grading, gp: &uniform::GradedPoints) -> StageReport {
    let (s, m) = (&d.seed_metrics, &d.metrics);
    let reduction = if s.rel_std > 0.0 { 100.0 * (1.0 - m.rel_std / s.rel_std) } else { 0.0 };
    r = r
        .metric("end_density", "End density", 100.0 * g.density_to, "%", "The density asked for at the far end of the grading.")
        .metric(
            "rel_std_seed",
            "Spread against the target, seed",
            100.0 * s.rel_std,
            "%",
            "Standard deviation of the 2n-nearest-neighbour distances, each over its point's target spacing n·e/ρ(q), before repulsion.",
        )
        .metric(
            "rel_std",
            "Spread against the target, result",
            100.0 * m.rel_std,
            "%",
            "The same after repulsion: lower follows the graded target more evenly.",
        )
        .metric(
            "rel_std_reduction",
            "Spread against the target reduced by",
            reduction,
            "%",
            "How much repulsion evened the spacing relative to the graded target.",
        )
        .metric(
            "rel_mean",
            "Mean distance over target",
            m.rel_mean,
            "",
            "Mean of the neighbour distances over their target spacings: near 1 (a hexagonal packing gives 1.07).",
        );
    let (label, unit) = gp.label;
    let lo = gp.commanded.first().map_or(0.0, |c| c[0]);
    let hi = gp.commanded.last().map_or(0.0, |c| c[0]);
    let bins = gp.commanded.len().saturating_sub(1).max(1);
    let centres: Vec<f64> = (0..bins).map(|k| lo + (hi - lo) * (k as f64 + 0.5) / bins as f64).collect();
    let pct = |v: Vec<f64>| v.into_iter().map(|x| 100.0 * x).collect::<Vec<f64>>();
    r.plots.push(Plot {
        key: "graded_density".into(),
        title: format!("Commanded and measured density along {label}"),
        kind: PlotKind::Line,
        x: Axis::new(label, unit),
        y: Axis::new("Density", "%"),
        group: None,
        series: vec![
            Series::xy("commanded ρ", gp.commanded.iter().map(|c| c[0]).collect(), pct(gp.commanded.iter().map(|c| c[1]).collect())),
            Series::xy("seed (n·e / mean 2n-NN distance)", centres.clone(), pct(binned_mean(&gp.seed, &s.local_density, [lo, hi], bins))),
            Series::xy("repulsion (n·e / mean 2n-NN distance)", centres, pct(binned_mean(&gp.points, &m.local_density, [lo, hi], bins))),
        ],
    });
    let rank = |v: &[f64]| -> Vec<f64> { (0..v.len()).map(|i| i as f64).collect() };
    r.plots.push(Plot {
        key: "kdf_relative".into(),
        title: "Kernel density over the graded target's, sorted".into(),
        kind: PlotKind::Line,
        x: Axis::new("Point (sorted)", ""),
        y: Axis::new("KDF / target", ""),
        group: None,
        series: vec![
            Series::xy("seed", rank(&s.kdf_relative_sorted), s.kdf_relative_sorted.clone()),
            Series::xy("repulsion", rank(&m.kdf_relative_sorted), m.kdf_relative_sorted.clone()),
        ],
    });
    let (edges, seed_counts, counts) = crate::axisym::metrics::shared_histogram(&s.nn_relative, &m.nn_relative, HISTOGRAM_BINS);
    r.plots.push(Plot {
        key: "nn_relative".into(),
        title: "Neighbour distances over the local target spacing".into(),
        kind: PlotKind::Histogram,
        x: Axis::new("Distance / s(q)", ""),
        y: Axis::new("Pairs", ""),
        group: None,
        series: vec![Series::xy("seed", edges.clone(), seed_counts), Series::xy("repulsion", edges, counts)],
    });
    r
}

pub(super) fn path_report(t: &tour::Tour, d: &uniform::Distribution, holes: bool) -> StageReport {
    let saving = if t.nn_length_mm > 0.0 { 100.0 * (1.0 - t.length_mm / t.nn_length_mm) } else { 0.0 };
    let summary = PathSummary {
        visited: t.order.len(),
        length_mm: t.length_mm,
        nn_length_mm: t.nn_length_mm,
        crossings_removed: t.crossings_removed,
        crossings_left: t.crossings_left,
        poses: t.poses.len(),
        hole_crossings: t.hole_crossings,
    };
    let r = StageReport::new("path", "Joining the points by geodesics", &summary)
        .metric("visited", "Points visited", t.order.len() as f64, "", "Every point once, in one path.")
        .metric("length", "Path length", t.length_mm, "mm", "Along the geodesics on the platform.")
        .metric("nn_length", "Nearest-neighbour length", t.nn_length_mm, "mm", "The path before 2-opt.")
        .metric("saving", "2-opt shortened it by", saving, "%", "What 2-opt removed from the nearest-neighbour path (crossings included).")
        .metric("crossings", "Crossings left", t.crossings_left as f64, "", "Places the path crosses itself in the map: 0 is a clean raster.")
        .metric("poses", "Poses", t.poses.len() as f64, "", "Tool positions with their normal, along the sampled geodesics.")
        .metric("points_in", "Points from the previous stage", d.points.len() as f64, "", "The repulsion's points the path joins.");
    if holes {
        r.metric(
            "hole_crossings",
            "Hops over a hole",
            t.hole_crossings as f64,
            "",
            "Path segments that would cross a hole of Ω: the nozzle travels over them without extruding (0 when the path goes around every hole).",
        )
    } else {
        r
    }
}

//! The papers' checkable numbers beside weft's (`weft bench --papers`, BENCHMARKS.md "Papers'
//! numbers"): the shipped examples that reproduce each paper are run and every number is a
//! [`Row`] saying the paper's value, weft's, how weft's was measured (from the G-code through
//! [`crate::analyze`] where the G-code holds it), whether the input is the paper's or a
//! stand-in of weft's, and a [`Status`].
//!
//! A stand-in chosen to give the paper's number (Ω2's polygon, a lattice parameter fitted to
//! Table 1) is "by construction", never "match"; a number computed from the paper's own fit
//! (the foam's modulus) is "circular"; a time beside the paper's is "timing" and its row says
//! what differs (the cutoff, the thread count, the machine).

use crate::analyze;
use crate::design::Design;
use crate::foam::stiffness::Calibration;
use crate::geom::{DVec2, Feature, Polygon, Stroke};
use crate::kinds::axisymmetric::PointsSummary;
use crate::pipeline::{self, Cache, Files, RunOptions, RunOutput};
use crate::report::StageReport;

const GIPPO: &str = "GIPPO lattices";
const AXISYM: &str = "Axisymmetric infill";
const GRADED: &str = "CT-graded scaffolds";
const FOAM: &str = "VTP foams";
const FREEFORM: &str = "Freeform assembly";

/// Where a row's input comes from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Input {
    /// The paper's own input (its domain, its numbers, its formula's constants).
    Paper,
    /// weft's own stand-in, and why (the paper does not publish it, or weft chose it).
    StandIn(String),
}

impl std::fmt::Display for Input {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Input::Paper => f.write_str("paper's"),
            Input::StandIn(why) => write!(f, "weft's stand-in: {why}"),
        }
    }
}

/// What a row's comparison shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Status {
    /// The paper's input gives the paper's number (within the row's stated tolerance).
    Match,
    /// The paper's input gives a different number.
    Differs,
    /// The number was an input of weft's (chosen to give the paper's): no evidence.
    ByConstruction,
    /// weft's input is not the paper's: the numbers are not comparable.
    StandIn,
    /// weft's number comes from the paper's own fit: agreement says nothing.
    Circular,
    /// A time beside the paper's, under conditions the row states.
    Timing,
}

impl std::fmt::Display for Status {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Status::Match => "match",
            Status::Differs => "differs",
            Status::ByConstruction => "by construction",
            Status::StandIn => "stand-in",
            Status::Circular => "circular",
            Status::Timing => "timing",
        })
    }
}

/// One number of one paper.
#[derive(Clone, Debug)]
pub struct Row {
    /// Which paper.
    pub paper: &'static str,
    /// What is compared.
    pub quantity: String,
    /// The paper's value, as it states it.
    pub paper_value: String,
    /// weft's value.
    pub weft_value: String,
    /// How weft's value is measured.
    pub measured_how: String,
    /// Where the input comes from.
    pub input: Input,
    /// What the comparison shows.
    pub status: Status,
}

impl Row {
    /// A row; a stand-in's agreement is never a match (it is demoted to [`Status::StandIn`]).
    fn new(paper: &'static str, quantity: &str, paper_value: &str, weft_value: String, measured_how: &str, input: Input, status: Status) -> Row {
        let status = if status == Status::Match && input != Input::Paper { Status::StandIn } else { status };
        Row { paper, quantity: quantity.into(), paper_value: paper_value.into(), weft_value, measured_how: measured_how.into(), input, status }
    }
}

/// What [`rows`] runs.
#[derive(Clone, Copy, Debug, Default)]
pub struct Options {
    /// Also the rows timed beside the papers' times (Ω3's three seeds with the cutoff and with
    /// all pairs, on one thread; the 6 120-beam tower): about a minute more.
    pub timings: bool,
}

/// Match within a relative tolerance, else differs.
fn compare(paper: f64, weft: f64, rel_tol: f64) -> Status {
    if (weft - paper).abs() <= rel_tol * paper.abs() {
        Status::Match
    } else {
        Status::Differs
    }
}

/// Every row, paper by paper.
pub fn rows(o: &Options) -> Result<Vec<Row>, String> {
    let mut out = Vec::new();
    out.extend(gippo_rows()?);
    out.extend(axisym_rows()?);
    if o.timings {
        out.extend(axisym_timing_rows()?);
    }
    out.extend(graded_rows()?);
    out.extend(foam_rows()?);
    if o.timings {
        out.extend(freeform_timing_rows()?);
    }
    Ok(out)
}

/// The rows as a Markdown table.
pub fn table(rows: &[Row]) -> String {
    let mut t = String::from("| paper | quantity | paper's value | weft's value | how weft's is measured | input | status |\n|---|---|---|---|---|---|---|\n");
    for r in rows {
        let cells = [
            r.paper.to_string(),
            r.quantity.clone(),
            r.paper_value.clone(),
            r.weft_value.clone(),
            r.measured_how.clone(),
            r.input.to_string(),
            r.status.to_string(),
        ];
        let cells: Vec<String> = cells.iter().map(|c| c.replace('|', "/")).collect();
        t.push_str(&format!("| {} |\n", cells.join(" | ")));
    }
    t
}

/// `weft bench --papers`: every row, timings included, as a table.
pub fn run_all() -> Result<String, String> {
    rows(&Options { timings: true }).map(|r| table(&r))
}

// ---------------------------------------------------------------------------------------
// Running examples and reading their G-code

fn example(name: &str, json: &str) -> Result<Design, String> {
    Design::from_json(name, json).map_err(|e| format!("{name}: {e}"))
}

fn with(design: &Design, sets: &[&str]) -> Result<Design, String> {
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    design.with_overrides(&sets).map_err(|e| format!("{}: {e}", design.name))
}

fn run(design: &Design) -> Result<RunOutput, String> {
    pipeline::run(design, &Files::new(), &RunOptions::default(), &mut |_, _| {}).map_err(|e| format!("{}: {e}", design.name))
}

/// weft's analyzer on a run's G-code, with the per-segment buffers.
fn gcode_segments(out: &RunOutput) -> Result<analyze::Analysis, String> {
    let o = analyze::Options { collect_preview: true, ..analyze::Options::default() };
    analyze::analyze("run.gcode", out.gcode.as_bytes(), &o).map_err(|e| e.to_string())
}

/// One extruding segment of the G-code: ends in printer coordinates, feature, ΔE per mm.
struct Segment {
    a: [f64; 3],
    b: [f64; 3],
    feature: u8,
    e_per_mm: f64,
}

fn segments(a: &analyze::Analysis) -> Vec<Segment> {
    let Some(p) = &a.preview else { return Vec::new() };
    p.positions
        .chunks_exact(6)
        .enumerate()
        .map(|(i, s)| Segment {
            a: [s[0] as f64, s[1] as f64, s[2] as f64],
            b: [s[3] as f64, s[4] as f64, s[5] as f64],
            feature: p.feature[i],
            e_per_mm: p.e_per_mm[i] as f64,
        })
        .collect()
}

/// The bounding box (x0, y0, x1, y1) of the segments.
fn bounds(s: &[Segment]) -> [f64; 4] {
    s.iter().fold([f64::INFINITY, f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY], |b, g| {
        [b[0].min(g.a[0]).min(g.b[0]), b[1].min(g.a[1]).min(g.b[1]), b[2].max(g.a[0]).max(g.b[0]), b[3].max(g.a[1]).max(g.b[1])]
    })
}

fn stage<'a>(out: &'a RunOutput, name: &str) -> Result<&'a StageReport, String> {
    out.report.stages.iter().find(|s| s.stage == name).ok_or_else(|| format!("{}: no {name} stage", out.report.name))
}

fn metric(s: &StageReport, key: &str) -> Result<f64, String> {
    s.metrics.iter().find(|m| m.key == key).map(|m| m.value).ok_or_else(|| format!("{}: no metric {key}", s.stage))
}

/// A number with the typographic minus sign, as the papers print it.
fn minus(v: f64, decimals: usize) -> String {
    format!("{v:.decimals$}").replace('-', "−")
}

/// Thousands separated by a space ("6 123.8").
fn grouped(v: f64, decimals: usize) -> String {
    let s = format!("{v:.decimals$}");
    let (int, frac) = s.split_once('.').map_or((s.as_str(), None), |(i, f)| (i, Some(f)));
    let digits: Vec<char> = int.chars().collect();
    let mut g = String::new();
    for (i, c) in digits.iter().enumerate() {
        if i > 0 && (digits.len() - i) % 3 == 0 {
            g.push(' ');
        }
        g.push(*c);
    }
    frac.map_or(g.clone(), |f| format!("{g}.{f}"))
}

// ---------------------------------------------------------------------------------------
// GIPPO lattices: Table 1's pores, the concave cylinder's layers

/// (example, its JSON, Table 1's pores %).
const TABLE_1: [(&str, &str, f64); 6] = [
    ("honeycomb-10mm", include_str!("../../examples/honeycomb-10mm.json"), 75.0),
    ("voronoi-10mm", include_str!("../../examples/voronoi-10mm.json"), 69.0),
    ("penrose-10mm", include_str!("../../examples/penrose-10mm.json"), 59.0),
    ("snub-square-10mm", include_str!("../../examples/snub-square-10mm.json"), 55.0),
    ("arrowhead-10mm", include_str!("../../examples/arrowhead-10mm.json"), 55.0),
    ("reentrant-honeycomb-10mm", include_str!("../../examples/reentrant-honeycomb-10mm.json"), 63.0),
];

const CONCAVE_CYLINDER_JSON: &str = include_str!("../../examples/concave-cylinder-honeycomb.json");

fn gippo_rows() -> Result<Vec<Row>, String> {
    let mut rows = Vec::new();
    for (name, json, table_1) in TABLE_1 {
        rows.push(pore_row(&example(name, json)?, table_1)?);
    }
    rows.push(concave_cylinder_row()?);
    Ok(rows)
}

/// The pattern's parameters as "kind, key value, …".
fn pattern_words(d: &Design) -> String {
    let p = &d.job.value["lattice"]["pattern"];
    let mut words = vec![p["kind"].as_str().unwrap_or("?").to_string()];
    if let Some(map) = p.as_object() {
        words.extend(map.iter().filter(|(k, _)| k.as_str() != "kind").map(|(k, v)| format!("{k} {v}")));
    }
    words.join(", ")
}

/// Pores of the printed layer: 1 − the union of the G-code's extruding moves (each a band of
/// the nozzle's width with round ends) over their bounding box (the 10 × 10 mm domain).
fn printed_pores(out: &RunOutput, width_mm: f64) -> Result<f64, String> {
    let segs = segments(&gcode_segments(out)?);
    let [x0, y0, x1, y1] = bounds(&segs);
    let square = Polygon { outer: vec![DVec2::new(x0, y0), DVec2::new(x1, y0), DVec2::new(x1, y1), DVec2::new(x0, y1)], holes: Vec::new() };
    let struts: Vec<Stroke> = segs
        .iter()
        .map(|s| Stroke { points: vec![DVec2::new(s.a[0], s.a[1]), DVec2::new(s.b[0], s.b[1])], feature: Feature::Lattice, curved: false })
        .collect();
    Ok(crate::lattice::pores::pore_fraction(&[square], &struts, width_mm))
}

fn pore_row(d: &Design, table_1: f64) -> Result<Row, String> {
    let out = run(d)?;
    let pores = 100.0 * printed_pores(&out, d.printer.nozzle_diameter_mm)?;
    let status = if (pores - table_1).abs() <= 1.0 { Status::ByConstruction } else { Status::Differs };
    Ok(Row::new(
        GIPPO,
        &format!("Table 1 pores, {}", d.name),
        &format!("{table_1:.0} %"),
        format!("{pores:.1} %"),
        "1 − area of the G-code's extruding moves (weft::analyze), each a band of the 0.2 mm nozzle with round ends, unioned and clipped to their 10 × 10 mm bounding box",
        Input::StandIn(format!("weft's pattern parameter ({}), chosen to give Table 1's pores; the paper gives none", pattern_words(d))),
        status,
    ))
}

fn concave_cylinder_row() -> Result<Row, String> {
    let d = example("concave-cylinder-honeycomb", CONCAVE_CYLINDER_JSON)?;
    let layers = gcode_segments(&run(&d)?)?.report.layers;
    Ok(Row::new(
        GIPPO,
        "concave cylinder: layers of 0.148 mm",
        "28",
        layers.to_string(),
        "layers with extrusion in the G-code (weft::analyze)",
        Input::StandIn("weft's solid is 4.144 mm tall (the paper: 4 mm) and asks for 28 layers, so the slicing gives 28".into()),
        if layers == 28 { Status::ByConstruction } else { Status::Differs },
    ))
}

// ---------------------------------------------------------------------------------------
// Axisymmetric infill: Ω1–Ω3 (section 3, Table 4), Ω3's times (section 3.3)

const OMEGA1_JSON: &str = include_str!("../../examples/barrel-omega1.json");
const OMEGA2_JSON: &str = include_str!("../../examples/barrel-omega2.json");
const OMEGA3_JSON: &str = include_str!("../../examples/hourglass-omega3.json");

/// One Ω of the paper: its N, its 2n-NN std seed → after GRE, its reduction, its mean.
struct Omega {
    label: &'static str,
    example: &'static str,
    json: &'static str,
    n: usize,
    std: [f64; 2],
    reduction_pct: f64,
    mean_mm: f64,
    ratio_pct: f64,
}

const OMEGAS: [Omega; 3] = [
    Omega { label: "Ω1", example: "barrel-omega1", json: OMEGA1_JSON, n: 538, std: [0.106, 0.030], reduction_pct: 71.7, mean_mm: 0.848, ratio_pct: 47.2 },
    Omega { label: "Ω2", example: "barrel-omega2", json: OMEGA2_JSON, n: 173, std: [0.560, 0.159], reduction_pct: 71.6, mean_mm: 1.693, ratio_pct: 23.6 },
    Omega { label: "Ω3", example: "hourglass-omega3", json: OMEGA3_JSON, n: 204, std: [0.500, 0.278], reduction_pct: 44.0, mean_mm: 4.384, ratio_pct: 9.1 },
];

/// Ω2's input: the paper does not publish its polygon.
fn omega2_input(area_mm2: f64) -> Input {
    Input::StandIn(format!(
        "weft's own polygon (true area {area_mm2:.2} mm², src/axisym/uniform.rs), chosen to give the paper's N = 173; the paper does not publish Ω2's polygon"
    ))
}

fn axisym_rows() -> Result<Vec<Row>, String> {
    let mut rows = Vec::new();
    for o in &OMEGAS {
        let out = run(&example(o.example, o.json)?)?;
        let p: PointsSummary = out.report.stage("points").ok_or_else(|| format!("{}: no points report", o.example))?;
        rows.extend(omega_rows(o, &p));
    }
    Ok(rows)
}

fn omega_rows(o: &Omega, p: &PointsSummary) -> Vec<Row> {
    let stand_in = o.label == "Ω2";
    let input = if stand_in { omega2_input(p.area_mm2) } else { Input::Paper };
    let n_status = if stand_in { Status::ByConstruction } else { compare(o.n as f64, p.points as f64, 0.0) };
    let quality = |s: Status| if stand_in { Status::StandIn } else { s };
    let report = "the run's points report: 2n-NN distances (2n = 2) of the placed points";
    vec![
        Row::new(
            AXISYM,
            &format!("{}: points N (equation 4)", o.label),
            &o.n.to_string(),
            format!("{} (A_Σ {:.2} mm²)", p.points, p.area_mm2),
            "points placed (the run's points report), N = A_Σ·ρ_c²/(n²e²) over the true area A_Σ of Ω on the platform",
            input.clone(),
            n_status,
        ),
        Row::new(
            AXISYM,
            &format!("{}: 2n-NN std, seed → after GRE (reduction)", o.label),
            &format!("{:.3} → {:.3} mm (−{:.1} %)", o.std[0], o.std[1], o.reduction_pct),
            format!("{:.3} → {:.3} mm (−{:.1} %)", p.seed_std_mm, p.std_mm, 100.0 * p.std_reduction),
            report,
            input.clone(),
            quality(compare(o.std[1], p.std_mm, 0.05)),
        ),
        Row::new(
            AXISYM,
            &format!("{}: 2n-NN mean after GRE (e / mean)", o.label),
            &format!("{:.3} mm ({:.1} %)", o.mean_mm, o.ratio_pct),
            format!("{:.3} mm ({:.1} %)", p.mean_mm, 100.0 * p.ratio),
            report,
            input,
            quality(compare(o.mean_mm, p.mean_mm, 0.02)),
        ),
    ]
}

/// Ω3's seeds with the paper's time and final 2n-NN std (section 3.3).
const OMEGA3_SEEDS: [(&str, &str, f64, f64); 3] = [("EBNS", "ebns", 2425.2, 0.340), ("ERE", "ere", 3407.9, 0.284), ("GBNS", "gbns", 6123.8, 0.278)];

/// Best-of-`repeats` points-stage wall time on one thread, and the points report.
fn timed_points(design: &Design, repeats: usize) -> Result<(f64, PointsSummary), String> {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().map_err(|e| e.to_string())?;
    let registry = crate::kinds::Registry::builtin();
    let mut best: Option<(f64, PointsSummary)> = None;
    for _ in 0..repeats.max(1) {
        let (_, stages, out) = pool.install(|| super::designs::timed_run(&registry, &mut Cache::disabled(), design, &Files::new(), &RunOptions::default()))?;
        let t = stages.iter().find(|s| s.0 == "points").map(|s| s.1).ok_or("no points stage")?;
        let p: PointsSummary = out.report.stage("points").ok_or("no points report")?;
        if best.as_ref().is_none_or(|b| t < b.0) {
            best = Some((t, p));
        }
    }
    best.ok_or_else(|| "no run".into())
}

fn axisym_timing_rows() -> Result<Vec<Row>, String> {
    let base = example("hourglass-omega3", OMEGA3_JSON)?;
    let mut rows = Vec::new();
    for (label, method, paper_s, paper_std) in OMEGA3_SEEDS {
        let seeded = with(&base, &[&format!("job.points.seed_method={method}")])?;
        let (cut_s, cut) = timed_points(&seeded, 3)?;
        let (all_s, all) = timed_points(&with(&seeded, &["job.points.cutoff_spacings=0"])?, 1)?;
        rows.push(Row::new(
            AXISYM,
            &format!("Ω3 {label}: time of the seed + 50 GRE iterations"),
            &format!("{} s (MATLAB, the paper's machine)", grouped(paper_s, 1)),
            format!("{cut_s:.2} s with weft's default 3-spacing cutoff (best of 3); {all_s:.1} s with all pairs, as the paper (1 run)"),
            "wall time of the points stage on 1 thread, this machine; the cutoff leaves out pairs farther than 3 target spacings, which the paper does not",
            Input::Paper,
            Status::Timing,
        ));
        rows.push(Row::new(
            AXISYM,
            &format!("Ω3 {label}: final 2n-NN std, cutoff and all pairs"),
            &format!("{paper_std:.3} mm"),
            format!(
                "{:.3} mm (−{:.1} %) with the cutoff; {:.3} mm (−{:.1} %) with all pairs",
                cut.std_mm,
                100.0 * cut.std_reduction,
                all.std_mm,
                100.0 * all.std_reduction
            ),
            "the points report of the two timed runs (reduction against weft's own seed)",
            Input::Paper,
            compare(paper_std, all.std_mm, 0.05),
        ));
    }
    Ok(rows)
}

// ---------------------------------------------------------------------------------------
// CT-graded scaffolds: equation 7, L_cell (equations 1 and 4), the phantom's densities

const GRADED_JSON: &str = include_str!("../../examples/graded-phantom.json");

fn graded_rows() -> Result<Vec<Row>, String> {
    let d = example("graded-phantom", GRADED_JSON)?;
    let out = run(&d)?;
    let density = stage(&out, "density")?;
    let (slope, intercept) = (metric(density, "slope")? / 1000.0, metric(density, "intercept")?);
    let (cell, cell_eq4, rho_s, rho_min) = (metric(density, "cell")?, metric(density, "cell_eq4")?, metric(density, "rho_s")?, metric(density, "rho_min")?);
    let line = "the density stage's line through the design's calibration points (−91 HU → P 0.95, 1516 HU → P 0.10)";
    let (lo, hi) = hu_range(density)?;
    let (rho_lo, rho_hi) = printed_density(&d, &out, rho_s)?;
    let phantom = || Input::StandIn("a CT phantom written by weft's test helpers (48 × 48 × 30 voxels); the paper's knee CT is not in the repository".into());
    Ok(vec![
        Row::new(GRADED, "equation 7: slope of P(HU)", "−0.000529 per HU", format!("{} per HU", minus(slope, 7)), line, Input::Paper, compare(-0.000529, slope, 0.001)),
        Row::new(GRADED, "equation 7: intercept of P(HU)", "0.901867", format!("{intercept:.6}"), line, Input::Paper, compare(0.901867, intercept, 1e-5)),
        Row::new(
            GRADED,
            "L_cell at ρ_s 0.47 (equation 1, gyroid)",
            "2.4 mm",
            format!("{cell:.3} mm"),
            "equation 1 solved for L_cell at ρ_s 0.47, k_c 1.221, m 2, φ 0.4 mm, l_h 0.2 mm (the density stage); at 2.4 mm equation 1 gives ρ_s 0.465, which the paper rounds to 0.47",
            Input::Paper,
            compare(2.4, cell, 0.02),
        ),
        Row::new(
            GRADED,
            "L_cell for ρ = 1 at E_w,max 1.2 mm (equation 4)",
            "2.4 mm",
            format!("{cell_eq4:.3} mm"),
            "equation 4 as printed: E_w,max·m·k_c/ρ (the density stage)",
            Input::Paper,
            compare(2.4, cell_eq4, 0.02),
        ),
        Row::new(GRADED, "CT values in the region of interest", "−91 … 1516 HU (femur)", format!("{} … {} HU", minus(lo, 0), minus(hi, 0)), "the density stage's HU histogram over the ROI", phantom(), Status::StandIn),
        Row::new(
            GRADED,
            "printed relative density ρ of the infill",
            "ρ = 1 − P: 0.05 … 0.90 over −91 … 1516 HU",
            format!("{rho_lo:.2} … {rho_hi:.2} (ρ_min {rho_min:.3})"),
            "every infill move of 0.1 mm or more in the G-code (weft::analyze): ρ = ρ_s · (ΔE/mm) · A_f / A_s, A_s the bead of equation 1 at ρ_s (2 digits: the G-code's rounding moves ΔE/mm by about 1 %)",
            phantom(),
            Status::StandIn,
        ),
    ])
}

/// The lowest and highest CT value of the ROI's histogram.
fn hu_range(density: &StageReport) -> Result<(f64, f64), String> {
    let p = density.plots.iter().find(|p| p.key == "hu_histogram").ok_or("no HU histogram")?;
    match &p.series.first().ok_or("empty HU histogram")?.x {
        crate::report::XValues::Numbers(x) if !x.is_empty() => Ok((x[0], x[x.len() - 1])),
        _ => Err("the HU histogram has no bin edges".into()),
    }
}

/// The lowest and highest ρ of the G-code's infill moves.
fn printed_density(d: &Design, out: &RunOutput, rho_s: f64) -> Result<(f64, f64), String> {
    let layer = d.job.value["slice"]["layer_height_mm"].as_f64().ok_or("no layer height")?;
    let nominal = crate::scaffold::bead_area(1.25 * d.printer.nozzle_diameter_mm, layer);
    let filament = std::f64::consts::PI * d.printer.filament_diameter_mm * d.printer.filament_diameter_mm / 4.0;
    let infill = Feature::Infill.code();
    // Moves under 0.1 mm are left out: the G-code's rounding (0.001 mm, 0.00001 of E) moves
    // their ΔE/mm by several per cent (longer ones by about 1 %: the row prints 2 digits).
    let long = |s: &Segment| (s.b[0] - s.a[0]).hypot(s.b[1] - s.a[1]) >= 0.1;
    let rho: Vec<f64> = segments(&gcode_segments(out)?)
        .iter()
        .filter(|s| s.feature == infill && s.e_per_mm > 0.0 && long(s))
        .map(|s| rho_s * s.e_per_mm * filament / nominal)
        .collect();
    if rho.is_empty() {
        return Err("graded-phantom: no infill in the G-code".into());
    }
    Ok(rho.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &r| (lo.min(r), hi.max(r))))
}

// ---------------------------------------------------------------------------------------
// VTP foams: the dogbone's V* and the fitted logarithm's jumps (section 4.1)

const FOAM_LINEAR_JSON: &str = include_str!("../../examples/foam-dogbone-linear.json");
const FOAM_LOG_JSON: &str = include_str!("../../examples/foam-dogbone-log.json");

/// Half of the transition (40 mm), mm.
const HALF_TRANSITION_MM: f64 = 20.0;

/// (x from the neck's middle, V*) of every flat piece in the neck, V* = A_t/(A_f·ΔE/mm).
fn neck_v_stars(d: &Design, out: &RunOutput) -> Result<Vec<(f64, f64)>, String> {
    let segs = segments(&gcode_segments(out)?);
    let [x0, y0, x1, y1] = bounds(&segs);
    let (cx, cy) = ((x0 + x1) / 2.0, (y0 + y1) / 2.0);
    let p = crate::foam::Process {
        nozzle_mm: d.printer.nozzle_diameter_mm,
        die_swell: d.material.swell_ratio,
        filament_mm: d.printer.filament_diameter_mm,
        feed_mm_s: d.job.value["foam"]["feed_mm_s"].as_f64().unwrap_or(crate::kinds::foam::DEFAULT_FEED_MM_S),
    };
    let flat = |s: &Segment| (s.b[2] - s.a[2]).abs() < 1e-6 && (s.b[0] - s.a[0]).hypot(s.b[1] - s.a[1]) >= 0.2;
    Ok(segs
        .iter()
        .filter(|s| flat(s) && s.e_per_mm > 0.0 && (s.b[1] - cy).abs() < 5.0)
        .map(|s| (s.b[0] - cx, p.thread_area() / (p.filament_area() * s.e_per_mm)))
        .collect())
}

/// Mean V* of the neck's pieces ending between `from` and `to` (x from the middle, mm).
fn mean_v_star(v: &[(f64, f64)], from: f64, to: f64) -> f64 {
    let sel: Vec<f64> = v.iter().filter(|(x, _)| *x >= from && *x <= to).map(|p| p.1).collect();
    sel.iter().sum::<f64>() / sel.len().max(1) as f64
}

fn foam_rows() -> Result<Vec<Row>, String> {
    let linear = example("foam-dogbone-linear", FOAM_LINEAR_JSON)?;
    let v = neck_v_stars(&linear, &run(&linear)?)?;
    let ends = [mean_v_star(&v, -29.0, -HALF_TRANSITION_MM - 0.25), mean_v_star(&v, HALF_TRANSITION_MM + 0.25, 29.0)];
    let cal = Calibration::default();
    let moduli = [cal.modulus_kpa(ends[0]), cal.modulus_kpa(ends[1])];
    let by_fit = [cal.modulus_kpa(0.15), cal.modulus_kpa(0.4)];
    let from_gcode = "V* = A_t/(A_f·ΔE/mm) of the neck's pieces in the G-code (weft::analyze), mean beyond the transition's ends";
    let mut rows = vec![
        Row::new(
            FOAM,
            "linear dogbone: V* at the neck's ends",
            "0.15 / 0.4",
            format!("{:.4} / {:.4}", ends[0], ends[1]),
            from_gcode,
            Input::Paper,
            Status::ByConstruction,
        ),
        Row::new(
            FOAM,
            "linear dogbone: compressive modulus at the neck's ends",
            &format!("{:.1} / {:.2} kPa (its fit E = 4.79·e^(−3.11x) at x = ∓½; kPa is weft's reading)", by_fit[0], by_fit[1]),
            format!("{:.1} / {:.2} kPa", moduli[0], moduli[1]),
            "the paper's fit applied to the V* read from the G-code (row above); weft measures no modulus, so this is not a validation",
            Input::Paper,
            Status::Circular,
        ),
    ];
    rows.push(log_transition_row()?);
    Ok(rows)
}

fn log_transition_row() -> Result<Row, String> {
    let d = example("foam-dogbone-log", FOAM_LOG_JSON)?;
    let out = run(&d)?;
    let grade = stage(&out, "grade")?;
    let (start, end) = (metric(grade, "transition_v_start")?, metric(grade, "transition_v_end")?);
    let v = neck_v_stars(&d, &out)?;
    let inside: Vec<&(f64, f64)> = v.iter().filter(|(x, _)| x.abs() < HALF_TRANSITION_MM - 1e-6).collect();
    let lo = inside.iter().copied().fold((0.0, f64::INFINITY), |a, &p| if p.1 < a.1 { p } else { a });
    let hi = inside.iter().copied().fold((0.0, f64::NEG_INFINITY), |a, &p| if p.1 > a.1 { p } else { a });
    let ok = (start - 0.1415).abs() <= 5e-5 && (end - 0.3795).abs() <= 5e-5;
    Ok(Row::new(
        FOAM,
        "fitted-log transition (40 mm, V* 0.15 → 0.4): V* at its ends",
        "0.1415 / 0.3795",
        format!(
            "{start:.4} / {end:.4}; printed: {:.4} at x = {} mm, {:.4} at x = {} mm",
            lo.1,
            minus(lo.0, 1),
            hi.1,
            minus(hi.0, 1)
        ),
        "the transition's weighting (the paper's appendix formula and constants) at x = ∓½, from the grade stage's report; printed: the extreme V* = A_t/(A_f·ΔE/mm) of the G-code's neck pieces inside the transition (pieces of 0.5 mm, each graded at its end)",
        Input::Paper,
        if ok { Status::Match } else { Status::Differs },
    ))
}

// ---------------------------------------------------------------------------------------
// Freeform assembly: planning beside printing (section 5)

const TOWER_6120_JSON: &str = include_str!("../../tests/fixtures/freeform-tower-6120-exact.json");

fn freeform_timing_rows() -> Result<Vec<Row>, String> {
    let d = example("freeform-tower-6120-exact", TOWER_6120_JSON)?;
    let registry = crate::kinds::Registry::builtin();
    let (_, stages, out) = super::designs::timed_run(&registry, &mut Cache::disabled(), &d, &Files::new(), &RunOptions::default())?;
    let t = |name: &str| stages.iter().find(|s| s.0 == name).map_or(0.0, |s| s.1);
    let a = gcode_segments(&out)?.report;
    Ok(vec![Row::new(
        FREEFORM,
        "planning with the exact cost beside printing, about 6 100 beams",
        "less than the print: 13 h for the 6 161-beam Eiffel tower (Wolfram Language, quad-core 2.8 GHz i7)",
        format!(
            "constraints + plan {:.1} s on {} threads; print {:.1} h estimated for {} beams",
            t("constraints") + t("plan"),
            out.report.threads,
            a.estimated_time_s / 3600.0,
            grouped(a.extrusion_paths as f64, 0)
        ),
        "wall time of the constraints and plan stages, this machine; beams = extrusion paths and print time = the estimate of weft::analyze on the G-code",
        Input::StandIn(
            "weft's own 6 120-beam tower (tests/fixtures/freeform-tower-6120-exact.json); the paper's Orbit, heart and Eiffel tower are not published".into(),
        ),
        Status::Timing,
    )])
}

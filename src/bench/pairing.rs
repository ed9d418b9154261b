//! Exact vs heuristic odd-node pairing (`weft bench --pairing`, `BenchPairing` in the browser
//! worker): one lattice layer optimised by `euler` or `continuous` twice, once with the
//! heuristic only (`exact_pairing_seconds = 0`) and once with the largest exact budget the
//! design allows, so the two costs, the certified gap and the two times come from one run.

use super::{DISC_48MM_JSON, EULER_SQUARE_MM, HONEYCOMB_10MM_JSON};
use crate::design::Design;
use crate::kinds::lattice::LatticeJob;
use crate::paths::Method;

/// Side of the square honeycomb of the 10k-edge case, mm (a tenth of the euler-100k area).
pub const SQUARE_10K_MM: f64 = 85.4;

/// Budget of the exact runs, s per layer: the most `paths.exact_pairing_seconds` accepts.
pub const EXACT_BUDGET_S: f64 = 60.0;

/// One case: a layer and a method.
#[derive(Clone, Copy, Debug)]
pub struct Case {
    /// Name (`weft bench --pairing` rows, `BenchPairing::new`).
    pub name: &'static str,
    /// `None`: the 48 mm disc example's first layer; `Some(side)`: a square honeycomb (the
    /// honeycomb-10mm pattern) of that side, mm.
    pub square_mm: Option<f64>,
    /// `euler` or `continuous`.
    pub method: Method,
}

/// The cases, in order: the 48 mm disc, about 10k and about 100k edges.
pub const CASES: [Case; 6] = [
    Case { name: "disc-48mm/euler", square_mm: None, method: Method::Euler },
    Case { name: "disc-48mm/continuous", square_mm: None, method: Method::Continuous },
    Case { name: "square-10k/euler", square_mm: Some(SQUARE_10K_MM), method: Method::Euler },
    Case { name: "square-10k/continuous", square_mm: Some(SQUARE_10K_MM), method: Method::Continuous },
    Case { name: "square-100k/euler", square_mm: Some(EULER_SQUARE_MM), method: Method::Euler },
    Case { name: "square-100k/continuous", square_mm: Some(EULER_SQUARE_MM), method: Method::Continuous },
];

/// A prepared case (the lattice is generated here, not timed).
pub struct PairingBench {
    /// The case.
    pub case: Case,
    /// Exact budget in use: 0 (heuristic) or [`EXACT_BUDGET_S`].
    pub exact: bool,
    strokes: Vec<crate::geom::StrokeLayer>,
    options: crate::paths::Options,
    line_width_mm: f64,
    seed: u64,
}

/// What one run found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PairingStats {
    /// Graph edges of the layer.
    pub edges: usize,
    /// Odd-degree nodes paired.
    pub odd_nodes: usize,
    /// Paths printed.
    pub paths: usize,
    /// Pairing length, mm.
    pub pairing_mm: f64,
    /// Proven lower bound, mm.
    pub lower_bound_mm: f64,
    /// Provably optimal.
    pub optimal: bool,
    /// Travel of the layer, mm.
    pub travel_mm: f64,
}

impl PairingStats {
    /// "optimal" or "within x %".
    pub fn status(&self) -> String {
        if self.optimal {
            "optimal".into()
        } else if self.lower_bound_mm > 0.0 {
            format!("within {:.1} %", (self.pairing_mm / self.lower_bound_mm - 1.0) * 100.0)
        } else {
            "no bound".into()
        }
    }

    /// As JSON (the worker's answer).
    pub fn to_json(&self) -> String {
        format!(
            r#"{{"edges":{},"oddNodes":{},"paths":{},"pairingMm":{},"lowerBoundMm":{},"optimal":{},"travelMm":{},"status":"{}"}}"#,
            self.edges,
            self.odd_nodes,
            self.paths,
            self.pairing_mm,
            self.lower_bound_mm,
            self.optimal,
            self.travel_mm,
            self.status()
        )
    }
}

impl PairingBench {
    /// Prepares case `name`, heuristic only or with the exact budget.
    pub fn prepare(name: &str, exact: bool) -> Result<PairingBench, String> {
        let case =
            *CASES.iter().find(|c| c.name == name).ok_or_else(|| format!("unknown pairing case '{name}' (one of {})", CASES.map(|c| c.name).join(", ")))?;
        let json = if case.square_mm.is_some() { HONEYCOMB_10MM_JSON } else { DISC_48MM_JSON };
        let mut design = Design::from_json(case.name, json).map_err(|e| e.to_string())?;
        let mut job: LatticeJob = design.job.settings().ok_or("not a lattice design")?;
        job.lattice.layers = 1;
        if let Some(side) = case.square_mm {
            job.domain = crate::lattice::Domain::Rectangle { width_mm: side, height_mm: side };
        }
        job.paths.method = case.method;
        job.paths.order = crate::paths::Order::Circuit;
        job.paths.exact_pairing_seconds = if exact { EXACT_BUDGET_S } else { 0.0 };
        let options = job.paths.clone();
        design.job = crate::design::Job::new("lattice", &job);
        let mut strokes = crate::kinds::lattice::lattice_strokes(&design, &Default::default()).map_err(|e| e.to_string())?;
        strokes.truncate(1);
        Ok(PairingBench { case, exact, strokes, options, line_width_mm: design.printer.nozzle_diameter_mm, seed: design.seed })
    }

    /// The timed part: `paths::optimise` of the layer.
    pub fn run(&self) -> Result<PairingStats, String> {
        let o = crate::paths::optimise(&self.strokes, &self.options, self.line_width_mm, self.seed, &mut |_| {}).map_err(|e| e.to_string())?;
        let l = o.report.layers.first().ok_or("no layer")?;
        Ok(PairingStats {
            edges: l.edges,
            odd_nodes: l.odd_nodes,
            paths: l.paths,
            pairing_mm: l.pairing_mm,
            lower_bound_mm: l.pairing_lower_bound_mm,
            optimal: l.pairing_optimal,
            travel_mm: l.travel_mm,
        })
    }
}

/// `weft bench --pairing`: every case, heuristic then exact, one pass each (the exact solves
/// take seconds), as a Markdown table with the exact ÷ heuristic ratios.
#[cfg(not(target_arch = "wasm32"))]
pub fn run_all() -> Result<String, String> {
    use std::time::Instant;
    let mut out = String::from(
        "## odd-node pairing: heuristic vs exact (`paths::optimise` of one layer, circuit order; one pass each)\n\n\
         | case | edges | odd nodes | heuristic ms | heuristic mm | heuristic status | exact ms | exact mm | exact status | cost exact ÷ heuristic | time exact ÷ heuristic |\n\
         |---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for case in CASES {
        let mut row = Vec::new();
        for exact in [false, true] {
            let b = PairingBench::prepare(case.name, exact)?;
            let t = Instant::now();
            let s = b.run()?;
            row.push((t.elapsed().as_secs_f64() * 1000.0, s));
        }
        let ((th, h), (te, e)) = (row[0], row[1]);
        out.push_str(&format!(
            "| {} | {} | {} | {:.1} | {:.2} | {} | {:.1} | {:.2} | {} | {:.4} | {:.1}× |\n",
            case.name,
            h.edges,
            h.odd_nodes,
            th,
            h.pairing_mm,
            h.status(),
            te,
            e.pairing_mm,
            e.status(),
            if h.pairing_mm > 0.0 { e.pairing_mm / h.pairing_mm } else { 1.0 },
            if th > 0.0 { te / th } else { 0.0 },
        ));
    }
    Ok(out)
}

//! The papers' table (`weft bench --papers`, issue 41 part 3), without its timed rows: every
//! row names where its input comes from, a stand-in chosen to give the paper's number is never
//! a match, a number from the paper's own fit is circular, and the cheap rows' G-code numbers
//! come out the same when the G-code is read here, by a parser of the test's own.

use crate::common::{example, run};
use std::sync::OnceLock;
use weft::bench::papers::{self, Input, Row, Status};
use weft::pipeline::Files;

fn rows() -> &'static [Row] {
    static ROWS: OnceLock<Vec<Row>> = OnceLock::new();
    ROWS.get_or_init(|| papers::rows(&papers::Options { timings: false }).unwrap())
}

fn row(quantity_starts: &str) -> &'static Row {
    rows().iter().find(|r| r.quantity.starts_with(quantity_starts)).unwrap_or_else(|| panic!("no row '{quantity_starts}…'"))
}

/// The numbers of a value such as "0.1500 / 0.4000" or "28".
fn numbers(value: &str) -> Vec<f64> {
    value.split(" / ").map(|w| w.split_whitespace().next().unwrap_or("").replace('−', "-").parse::<f64>().unwrap_or(f64::NAN)).collect()
}

#[test]
fn every_row_names_its_input_and_no_stand_in_is_a_match() {
    let rows = rows();
    for paper in ["GIPPO lattices", "Axisymmetric infill", "CT-graded scaffolds", "VTP foams"] {
        assert!(rows.iter().any(|r| r.paper == paper), "no row of {paper}");
    }
    for r in rows {
        let what = format!("{} / {}", r.paper, r.quantity);
        assert!(!r.paper_value.is_empty() && !r.weft_value.is_empty() && r.measured_how.len() > 20, "{what}: {r:?}");
        match &r.input {
            Input::Paper => assert_eq!(r.input.to_string(), "paper's"),
            Input::StandIn(why) => {
                assert!(why.len() > 20, "{what}: a stand-in says what it is and why: '{why}'");
                assert!(r.input.to_string().starts_with("weft's stand-in: "), "{what}");
                assert_ne!(r.status, Status::Match, "{what}: a stand-in's agreement is not a reproduction");
            }
        }
        assert_ne!(r.status, Status::Timing, "{what}: no timed row without timings");
    }
    // The table: a header, a rule and one line of 7 cells per row.
    let t = papers::table(rows);
    let lines: Vec<&str> = t.lines().collect();
    assert_eq!(lines.len(), rows.len() + 2);
    assert!(lines.iter().all(|l| l.matches('|').count() == 8), "{t}");
    assert!(lines[0].contains("| input | status |"), "{}", lines[0]);
}

#[test]
fn figures_chosen_or_fitted_to_the_papers_are_labelled_so() {
    // Ω2's polygon is weft's own, chosen to give N = 173.
    let n2 = row("Ω2: points N");
    assert!(matches!(&n2.input, Input::StandIn(why) if why.contains("443.06 mm²")), "{n2:?}");
    assert_eq!(n2.status, Status::ByConstruction);
    assert_eq!(numbers(&n2.weft_value)[0], 173.0);
    for r in rows().iter().filter(|r| r.quantity.starts_with("Ω2")) {
        assert!(matches!(r.status, Status::ByConstruction | Status::StandIn), "{r:?}");
    }
    // Ω1 and Ω3 are the paper's domains: N is a real check.
    for q in ["Ω1: points N", "Ω3: points N"] {
        let r = row(q);
        assert_eq!((&r.input, r.status), (&Input::Paper, Status::Match), "{r:?}");
    }
    // Table 1's pores come from parameters fitted to it.
    let pores: Vec<&Row> = rows().iter().filter(|r| r.quantity.starts_with("Table 1 pores")).collect();
    assert_eq!(pores.len(), 6);
    assert!(pores.iter().all(|r| r.status == Status::ByConstruction && r.input != Input::Paper), "{pores:?}");
    // The foam's modulus is the paper's fit applied to weft's V*.
    let m = row("linear dogbone: compressive modulus");
    assert_eq!(m.status, Status::Circular);
    assert!(m.measured_how.contains("paper's fit") && m.measured_how.contains("not a validation"), "{m:?}");
    // The phantom CT is a stand-in wherever it is the input.
    for r in rows().iter().filter(|r| r.paper == "CT-graded scaffolds" && r.quantity.contains("CT values")) {
        assert!(matches!(&r.input, Input::StandIn(why) if why.contains("phantom")), "{r:?}");
    }
}

/// Moves of a G-code, read here: (from, to, ΔE) of every G0/G1 (absolute XYZ and E, G92 resets).
fn moves(gcode: &str) -> Vec<([f64; 3], [f64; 3], f64)> {
    let (mut p, mut e) = ([0.0f64; 3], 0.0f64);
    let mut out = Vec::new();
    for line in gcode.lines() {
        let code = line.split(';').next().unwrap_or("").trim();
        let mut words = code.split_whitespace();
        let cmd = words.next().unwrap_or("");
        let value = |c: char| code.split_whitespace().skip(1).find(|w| w.starts_with(c)).and_then(|w| w[1..].parse::<f64>().ok());
        if cmd == "G92" {
            e = value('E').unwrap_or(e);
        } else if cmd == "G0" || cmd == "G1" {
            let q = [value('X').unwrap_or(p[0]), value('Y').unwrap_or(p[1]), value('Z').unwrap_or(p[2])];
            let ne = value('E').unwrap_or(e);
            out.push((p, q, ne - e));
            (p, e) = (q, ne);
        }
    }
    out
}

/// Extruding moves: E forward while the nozzle moves in XY.
fn extruding(gcode: &str) -> Vec<([f64; 3], [f64; 3], f64)> {
    moves(gcode).into_iter().filter(|(a, b, de)| *de > 0.0 && (b[0] - a[0]).hypot(b[1] - a[1]) > 1e-9).collect()
}

#[test]
fn layer_count_and_foam_v_star_are_recomputed_from_the_gcode() {
    // The concave cylinder's layers: the distinct heights of its extruding moves.
    let out = run(&example("concave-cylinder-honeycomb"), &Files::new()).unwrap();
    let mut zs: Vec<i64> = extruding(&out.gcode).iter().map(|m| (m.1[2] * 1000.0).round() as i64).collect();
    zs.sort_unstable();
    zs.dedup();
    let r = row("concave cylinder: layers");
    assert_eq!(numbers(&r.weft_value), vec![zs.len() as f64], "{r:?}");

    // The linear dogbone's V* beyond the transition's ends: A_t/(A_f·ΔE/mm) of the flat
    // pieces in the neck, x from the middle of the printed part.
    let d = example("foam-dogbone-linear");
    let out = run(&d, &Files::new()).unwrap();
    let pieces = extruding(&out.gcode);
    let (lo, hi) = pieces.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), m| (lo.min(m.0[0]).min(m.1[0]), hi.max(m.0[0]).max(m.1[0])));
    let (ylo, yhi) = pieces.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), m| (lo.min(m.0[1]).min(m.1[1]), hi.max(m.0[1]).max(m.1[1])));
    let (cx, cy) = ((lo + hi) / 2.0, (ylo + yhi) / 2.0);
    let thread = d.printer.nozzle_diameter_mm * d.material.swell_ratio;
    let (a_t, a_f) = (std::f64::consts::PI * thread * thread / 4.0, std::f64::consts::PI * d.printer.filament_diameter_mm.powi(2) / 4.0);
    let mean_between = |from: f64, to: f64| {
        let v: Vec<f64> = pieces
            .iter()
            .filter(|(a, b, _)| (b[2] - a[2]).abs() < 1e-9 && (b[1] - cy).abs() < 5.0 && (b[0] - a[0]).hypot(b[1] - a[1]) >= 0.2)
            .filter(|(_, b, _)| (from..=to).contains(&(b[0] - cx)))
            .map(|(a, b, de)| a_t / (a_f * de / (b[0] - a[0]).hypot(b[1] - a[1])))
            .collect();
        assert!(v.len() > 100, "{} pieces between {from} and {to} mm", v.len());
        v.iter().sum::<f64>() / v.len() as f64
    };
    let mine = [mean_between(-29.0, -20.25), mean_between(20.25, 29.0)];
    let r = row("linear dogbone: V* at the neck's ends");
    let table = numbers(&r.weft_value);
    assert_eq!(table.len(), 2, "{r:?}");
    for (t, m) in table.iter().zip(mine) {
        assert!((t - m).abs() < 1e-3, "table {t}, read from the G-code here {m}");
    }
    assert!((mine[0] - 0.15).abs() < 2e-3 && (mine[1] - 0.4).abs() < 2e-3, "{mine:?}");
}

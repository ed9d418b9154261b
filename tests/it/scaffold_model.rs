//! The paper's scaffold model (equations 1–4, 7, table 1) against the paper's own numbers.

use std::f64::consts::PI;
use weft::scaffold::*;

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol
}

/// Rounds to `d` decimals (how the paper prints its numbers).
fn round(x: f64, d: i32) -> f64 {
    (x * 10f64.powi(d)).round() / 10f64.powi(d)
}

#[test]
fn table_1_coefficients() {
    let t = coefficients_table();
    assert_eq!(t[0], ("gyroid", Cell { k_c: 1.221, m: 2.0 }));
    assert_eq!(t[1], ("rectilinear", Cell { k_c: 0.707, m: 2.0 }));
    assert_eq!(t[2], ("3D honeycomb", Cell { k_c: 1.011, m: 2.0 }));
    assert_eq!([GYROID, RECTILINEAR, HONEYCOMB_3D], [t[0].1, t[1].1, t[2].1]);
}

#[test]
fn femur_case_infill_density_and_cell_size() {
    // Section 3.2: gyroid, L = 2.4 mm, φ = 0.4 mm, l_h = 0.2 mm → ρ_s "set to 0.47".
    let rho_s = infill_density(GYROID, 2.4, 0.4, 0.2);
    let closed = 1.221 * 2.0 / 2.4 * (0.5 + (PI / 4.0 - 1.0) * 0.2);
    assert!(close(rho_s, closed, 1e-15));
    assert!(close(rho_s, 0.465079, 1e-6), "{rho_s}");
    assert_eq!(round(rho_s, 2), 0.47);
    // The other way: ρ_s = 0.47 needs L ≈ 2.375 mm.
    let l = cell_size_for_density(GYROID, 0.47, 0.4, 0.2);
    assert!(close(l, 2.374869, 1e-6), "{l}");
    // Density is inversely proportional to the cell.
    assert!(close(infill_density(RECTILINEAR, 1.2, 0.4, 0.2), 2.0 * infill_density(RECTILINEAR, 2.4, 0.4, 0.2), 1e-15));
}

#[test]
fn extrusion_width_limits_equations_2_and_3() {
    assert_eq!(min_width(0.2), 0.2);
    assert!(close(max_width(0.4), 1.2, 1e-15));
    assert!(close(max_width(0.6), 1.8, 1e-15));
}

#[test]
fn equation_4_cell_size_and_the_papers_2_4_mm() {
    // As printed: L = E_w,max m k_c / ρ with ρ = 1.
    assert!(close(cell_size_for_width(GYROID, 1.2, 1.0), 2.9304, 1e-12));
    assert!(close(cell_size_for_width(RECTILINEAR, 1.2, 1.0), 1.6968, 1e-12));
    assert!(close(cell_size_for_width(HONEYCOMB_3D, 1.2, 1.0), 2.4264, 1e-12));
    assert!(close(cell_size_for_width(GYROID, 1.2, 0.5), 2.0 * 2.9304, 1e-12));
    // The paper's 2.4 mm is E_w,max · m (k_c left out) …
    assert!(close(cell_size_for_width(Cell { k_c: 1.0, m: 2.0 }, 1.2, 1.0), 2.4, 1e-15));
    // … and not the "bead-width" reading of equation 1 either: a 1.2 mm bead fills 2.826 mm cells.
    let l_bead = 1.221 * 2.0 * (1.2 + (PI / 4.0 - 1.0) * 0.2);
    assert!(close(density_at_width(GYROID, l_bead, 1.2, 0.2), 1.0, 1e-12));
    assert!(close(l_bead, 2.825588, 1e-6));
    // At 2.4 mm, solid needs a 1.026 mm bead, within E_w,max: a feasible, conservative cell.
    let w = width_for_density(GYROID, 2.4, 1.0, 0.2);
    assert!(close(w, 1.025721, 1e-6) && w < max_width(0.4));
    assert!(close(density_at_width(GYROID, 2.4, w, 0.2), 1.0, 1e-12));
}

#[test]
fn equation_1_is_the_stadium_bead_at_the_nominal_width() {
    for (cell, l, phi, lh) in [(GYROID, 2.4, 0.4, 0.2), (RECTILINEAR, 3.1, 0.6, 0.3), (HONEYCOMB_3D, 1.7, 0.25, 0.1)] {
        let via_area = cell.k_c * cell.m * bead_area(1.25 * phi, lh) / (l * lh);
        assert!(close(infill_density(cell, l, phi, lh), via_area, 1e-14));
        assert!(close(density_at_width(cell, l, 1.25 * phi, lh), infill_density(cell, l, phi, lh), 1e-15));
    }
    // A bead as wide as it is tall is a disc: π l_h² / 4.
    assert!(close(bead_area(0.2, 0.2), PI * 0.01, 1e-15));
    // ρ_min at E_w,min = l_h: k_c m π l_h / (4 L); femur case 0.1598.
    let rho_min = min_density(GYROID, 2.4, 0.2);
    assert!(close(rho_min, 1.221 * 2.0 * PI * 0.2 / (4.0 * 2.4), 1e-15));
    assert!(close(rho_min, 0.159829, 1e-6));
}

#[test]
fn round_trips() {
    for cell in [GYROID, RECTILINEAR, HONEYCOMB_3D] {
        for l in [0.8, 1.5, 2.4, 5.0, 12.0] {
            for (phi, lh) in [(0.4, 0.2), (0.25, 0.1), (0.8, 0.4), (0.6, 0.15)] {
                let rho = infill_density(cell, l, phi, lh);
                assert!(close(cell_size_for_density(cell, rho, phi, lh), l, 1e-12 * l));
                for w in [lh, 0.5, 1.2, 3.0 * phi] {
                    let r = density_at_width(cell, l, w, lh);
                    assert!(close(width_for_density(cell, l, r, lh), w, 1e-12));
                    assert!(close(width_of_area(bead_area(w, lh), lh), w, 1e-12));
                }
            }
        }
    }
}

#[test]
fn calibration_defaults_are_equation_7() {
    let c = Calibration::default();
    assert_eq!(c.points, DEFAULT_POINTS.to_vec());
    assert!(c.problems().is_empty());
    let (slope, intercept) = c.line().unwrap();
    assert_eq!((round(slope, 6), round(intercept, 6)), (-0.000529, 0.901867));
    assert!(close(slope, -0.85 / 1607.0, 1e-18));
    // Equation 7 applied to every HU, and through the two literature points.
    for hu in [-1000.0, -91.0, 0.0, 350.0, 1516.0, 1562.0] {
        assert!(close(c.porosity(hu), slope * hu + intercept, 1e-12));
    }
    assert!(close(c.porosity(-91.0), 0.95, 1e-15) && close(c.porosity(1516.0), 0.10, 1e-15));
    // ρ = 1 − P, clamped to [ρ_min, 1].
    assert!(close(c.density(350.0, 0.16), 1.0 - (slope * 350.0 + intercept), 1e-12));
    assert_eq!(c.density(-1000.0, 0.16), 0.16);
    assert_eq!(c.density(1562.0, 0.16), 1.0 - c.porosity(1562.0));
    assert_eq!(c.density(3000.0, 0.16), 1.0);
    assert_eq!(c.density(f64::NAN, 0.16), 0.16);
    // Serde: defaults from {}, unknown fields refused.
    assert_eq!(serde_json::from_str::<Calibration>("{}").unwrap(), c);
    assert!(serde_json::from_str::<Calibration>(r#"{"pointz": []}"#).is_err());
    let json = serde_json::to_string(&c).unwrap();
    assert_eq!(json, r#"{"points":[[-91.0,0.95],[1516.0,0.1]]}"#);
}

#[test]
fn multi_point_calibration_is_piecewise_linear_in_any_order() {
    let c = Calibration { points: vec![[1000.0, 0.1], [0.0, 0.9], [500.0, 0.3]] };
    assert!(c.problems().is_empty());
    assert_eq!(c.line(), None, "three points are not one line");
    let expect = |v: f64| -> f64 {
        if v <= 500.0 {
            0.9 + (0.3 - 0.9) * v / 500.0
        } else {
            0.3 + (0.1 - 0.3) * (v - 500.0) / 500.0
        }
    };
    for v in [-100.0, 0.0, 250.0, 499.0, 500.0, 750.0, 1000.0, 1100.0] {
        assert!(close(c.porosity(v), expect(v), 1e-12), "P({v}) = {}", c.porosity(v));
    }
    assert!(close(c.porosity(-100.0), 1.02, 1e-12), "extrapolated with the first slope");
    assert!(close(c.porosity(1100.0), 0.06, 1e-12), "extrapolated with the last slope");
    assert_eq!(c.density(-100.0, 0.1), 0.1);
    // Same points, other order: same curve.
    let d = Calibration { points: vec![[500.0, 0.3], [1000.0, 0.1], [0.0, 0.9]] };
    for v in [-100.0, 250.0, 750.0, 1100.0] {
        assert_eq!(c.porosity(v), d.porosity(v));
    }
}

#[test]
fn calibration_problems_are_each_listed() {
    let bad = |points: Vec<[f64; 2]>| Calibration { points }.problems();
    let p = bad(vec![]);
    assert_eq!(p.len(), 1);
    assert!(p[0].contains("0 point(s)"), "{p:?}");
    let p = bad(vec![[0.0, 0.5]]);
    assert!(p.len() == 1 && p[0].contains("at least 2"), "{p:?}");
    let p = bad(vec![[0.0, 0.5], [f64::NAN, 0.2]]);
    assert!(p.len() == 1 && p[0].contains("points[1]") && p[0].contains("finite"), "{p:?}");
    let p = bad(vec![[0.0, 0.5], [10.0, 1.5], [20.0, -0.1]]);
    assert_eq!(p.len(), 2, "{p:?}");
    assert!(p[0].contains("points[1]") && p[1].contains("points[2]") && p[0].contains("between 0 and 1"));
    let p = bad(vec![[10.0, 0.5], [0.0, 0.4], [10.0, 0.2]]);
    assert!(p.len() == 1 && p[0].contains("[0] and [2]") && p[0].contains("same value 10"), "{p:?}");
    // All at once: one point with a bad porosity and a non-finite value.
    let p = bad(vec![[f64::INFINITY, 2.0]]);
    assert_eq!(p.len(), 2, "{p:?}");
    // A calibration with problems has no line; degenerate ones give NaN, never a panic.
    assert_eq!(Calibration { points: vec![[0.0, 0.5], [0.0, 0.4]] }.line(), None);
    assert!(Calibration { points: vec![[5.0, 0.5], [5.0, 0.4]] }.porosity(7.0).is_nan());
    assert!(Calibration { points: vec![] }.porosity(7.0).is_nan());
    assert_eq!(Calibration { points: vec![[3.0, 0.25]] }.porosity(7.0), 0.25);
}

#[test]
fn cells_are_resized_only_where_the_bead_would_leave_its_range() {
    // A density ramp along x from 0.05 to 1.0 over 60 mm; femur-case gyroid (L_s at ρ_s 0.47).
    let (nozzle, layer) = (0.4, 0.2);
    let reference = cell_size_for_density(GYROID, 0.47, nozzle, layer);
    let o = cells::Options { cell: GYROID, reference_mm: reference, width_min_mm: 0.2, width_max_mm: 0.6, layer_mm: layer, max_ratio: 3.0 };
    let ramp = |p: weft::geom::DVec3| Some(0.05 + 0.95 * (p.x / 60.0).clamp(0.0, 1.0));
    let bounds = weft::geom::Aabb { min: weft::geom::DVec3::ZERO, max: weft::geom::DVec3::new(60.0, 4.0, 4.0) };
    let sized = cells::size_cells(&bounds, &ramp, &o).unwrap();
    let (r, f) = (&sized.report, &sized.field);
    assert!(r.smaller > 0 && r.larger > 0, "{r:?}");
    assert_eq!(r.sampled, r.nodes);
    // Every node: its bead at its cell is in range (up to the size bound), and a node keeps
    // L_s exactly when its bead at L_s is in range.
    let mut kept = 0;
    for (n, &l) in f.cell_mm.iter().enumerate() {
        let i = n % f.dims[0];
        let x = f.origin_mm[0] + i as f64 * f.step_mm;
        // The node's density: the mean of the ramp over its 3 samples in x (the ramp is linear
        // inside [0, 60]).
        let xs = [x - f.step_mm / 3.0, x, x + f.step_mm / 3.0];
        let rho = xs.iter().map(|&x| ramp(weft::geom::DVec3::new(x, 0.0, 0.0)).unwrap()).sum::<f64>() / 3.0;
        let at_ref = width_for_density(GYROID, reference, rho, layer);
        if (0.2..=0.6).contains(&at_ref) {
            assert_eq!(l, reference, "node {n} (ρ {rho}) re-sized although its bead {at_ref} mm is printable");
            kept += 1;
        } else {
            let w = width_for_density(GYROID, l, rho, layer);
            let bounded = close(l, reference * 3.0, 1e-9) || close(l, reference / 3.0, 1e-9);
            assert!(bounded || close(w, 0.2, 1e-9) || close(w, 0.6, 1e-9), "node {n} (ρ {rho}): cell {l} mm gives a {w} mm bead");
            assert!(bounded || (if at_ref > 0.6 { l < reference } else { l > reference }));
        }
    }
    assert!(kept > 0);
    assert_eq!(r.smaller + r.larger + kept, r.nodes);
    // The field is the nodes' values between them.
    assert!(close(f.at(weft::geom::DVec3::new(f.origin_mm[0], 0.0, 0.0)), f.cell_mm[0], 1e-12));
}

#[test]
fn cell_sizing_refuses_a_part_whose_graded_gyroid_is_too_much_work() {
    let o = cells::Options { cell: GYROID, reference_mm: 2.4, width_min_mm: 0.2, width_max_mm: 1.2, layer_mm: 0.05, max_ratio: 10.0 };
    let bounds = weft::geom::Aabb { min: weft::geom::DVec3::ZERO, max: weft::geom::DVec3::new(200.0, 200.0, 300.0) };
    let called = std::cell::Cell::new(0usize);
    let field = |_: weft::geom::DVec3| {
        called.set(called.get() + 1);
        Some(0.5)
    };
    match cells::size_cells(&bounds, &field, &o) {
        Err(cells::Error::TooBig(r)) => assert!(r.fix.contains("max_cell_ratio"), "{r}"),
        other => panic!("not refused: {:?}", other.map(|s| s.report)),
    }
    assert_eq!(called.get(), 0, "the field was sampled before the refusal");
    // The phantom-sized part is well inside.
    let small = weft::geom::Aabb { min: weft::geom::DVec3::ZERO, max: weft::geom::DVec3::new(40.0, 40.0, 20.0) };
    assert!(cells::estimate(&small, &cells::Options { layer_mm: 0.2, max_ratio: 3.0, ..o }).refused.is_none());
}

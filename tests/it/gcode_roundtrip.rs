//! Round trip: write G-code for a hand-built toolpath, analyse it, compare.

use weft::analyze::{analyze, Options as AOptions};
use weft::gcode::{equation4_e, write_gcode, Options};
use weft::geom::{DVec3, Feature, Pass, PassKind, Path, Toolpath};

/// A small lattice-like layer: a zig-zag strut path, a square contour and a diagonal strut.
fn toolpath(layers: usize) -> Toolpath {
    let mut tp = Toolpath::default();
    for i in 0..layers {
        let z = 0.2 + 0.2 * i as f64;
        let zig: Vec<DVec3> = (0..9).map(|k| DVec3::new(-20.0 + 5.0 * k as f64, if k % 2 == 0 { -10.0 } else { 10.0 }, z)).collect();
        let square =
            vec![DVec3::new(-25.0, -15.0, z), DVec3::new(25.0, -15.0, z), DVec3::new(25.0, 15.0, z), DVec3::new(-25.0, 15.0, z), DVec3::new(-25.0, -15.0, z)];
        let diag = vec![DVec3::new(-24.0, 14.0, z), DVec3::new(-21.0, 11.5, z)];
        tp.passes.push(Pass {
            kind: PassKind::Layer,
            z,
            height: 0.2,
            paths: vec![
                Path { points: zig, feature: Feature::Lattice, width: 0.4, speed_factor: 1.0, approach: None, data: None },
                Path { points: square, feature: Feature::Contour, width: 0.45, speed_factor: 1.0, approach: None, data: None },
                Path { points: diag, feature: Feature::Lattice, width: 0.4, speed_factor: 0.6, approach: None, data: None },
            ],
        });
    }
    tp
}

fn sum_eq4(tp: &Toolpath, o: &Options) -> f64 {
    let mut e = 0.0;
    for l in &tp.passes {
        for p in &l.paths {
            for w in p.points.windows(2) {
                e += equation4_e(w[0].distance(w[1]), l.height, p.width, o.material.extrusion_multiplier, o.material.k, o.printer.filament_diameter_mm);
            }
        }
    }
    e
}

fn check(relative_e: bool, z_hop: f64) {
    let tp = toolpath(3);
    let mut o = Options::default();
    o.printer.relative_e = relative_e;
    o.printer.retraction.z_hop_mm = z_hop;
    o.material.k = 1.1;
    o.material.extrusion_multiplier = 0.95;
    let g = write_gcode(&tp, &o).unwrap();
    let a = analyze("rt.gcode", g.text.as_bytes(), &AOptions { collect_preview: true, ..Default::default() }).unwrap();
    let r = &a.report;
    let len = tp.extrusion_length();
    assert!((r.extruded_mm - len).abs() <= 1e-6 * len, "{} vs {len}", r.extruded_mm);
    assert!((g.stats.extruded_mm - len).abs() <= 1e-9 * len);
    let e = sum_eq4(&tp, &o);
    assert!((g.stats.filament_mm - e).abs() < 1e-9);
    // Printed E is rounded to 5 decimals: absolute E never drifts, relative E drifts by ≤ n·5e-6.
    let tol = if relative_e { 5e-6 * 40.0 } else { 5e-6 };
    assert!((r.filament_mm - e).abs() <= tol, "{} vs {e}", r.filament_mm);
    assert_eq!(r.layers, 3);
    assert_eq!(r.extrusion_paths, 9);
    assert_eq!(r.per_layer.iter().map(|l| l.extrusion_paths).collect::<Vec<_>>(), [3, 3, 3]);
    assert_eq!(r.overlap_mm, 0.0);
    assert_eq!(r.retractions, g.stats.retractions);
    assert_eq!(r.retractions, 3 * 3); // before the 2nd and 3rd path of each layer, layer changes, the end
    assert_eq!(r.estimated_time_s, g.stats.estimated_time_s);
    assert_eq!(r.travel_mm, g.stats.travel_mm);
    // GIPPO per layer: (zig 8 edges, square 4, diag 1).
    let zig = 8.0 * (25.0f64 + 400.0).sqrt();
    let sq = 160.0;
    let diag = (9.0f64 + 6.25).sqrt();
    let g1 = (zig * 8.0 + sq * 4.0 + diag) / ((zig + sq + diag) * 3.0);
    assert!((r.gippo_score - g1).abs() < 1e-6, "{} vs {g1}", r.gippo_score);
    for (i, l) in r.per_layer.iter().enumerate() {
        assert!((l.z - (0.2 + 0.2 * i as f64)).abs() < 1e-9);
    }
    let p = a.preview.unwrap();
    assert_eq!(p.layer_segment_start, [0, 13, 26, 39]);
    // Features survive the trip through ;TYPE: comments.
    assert_eq!(p.feature[0], Feature::Lattice.code());
    assert_eq!(p.feature[8], Feature::Contour.code());
    assert_eq!(p.width[8], 0.45);
    // The bed offset puts the part around the bed centre.
    assert_eq!(p.positions[0..3], [90.0f32, 100.0, 0.2]);
}

#[test]
fn round_trip_absolute_e() {
    check(false, 0.0);
}

#[test]
fn round_trip_relative_e_with_z_hop() {
    check(true, 0.6);
}

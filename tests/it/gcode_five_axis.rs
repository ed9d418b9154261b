//! General toolpaths through the writer and back through the analyzer: 5-axis poses (rotary
//! words and I J K), per-point flow, feed and dwell, free passes, machine limits, poses CSV.

use weft::analyze::{analyze, Options as AOptions};
use weft::gcode::{write_gcode, Error, Flavor, Options};
use weft::geom::{DVec3, Feature, Pass, PassKind, Path, PointData, PointFlow, Toolpath};
use weft::machine::{AxisOutput, Kind, Layout, Machine, RotaryAxes};

const R: f64 = 10.0;

/// A spiral over a hemisphere of radius R centred on the plate centre, from the pole down to
/// 75° (the pole is the singular pose of `bc` machines), tool axis = surface normal.
fn hemisphere() -> (Vec<DVec3>, Vec<DVec3>) {
    let (mut pts, mut axes) = (Vec::new(), Vec::new());
    let n = 400;
    for k in 0..=n {
        let f = k as f64 / n as f64;
        let theta = f * 75f64.to_radians();
        let phi = f * 6.0 * std::f64::consts::PI;
        let a = DVec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos());
        pts.push(a * R);
        axes.push(a);
    }
    (pts, axes)
}

fn free_path(points: Vec<DVec3>, data: PointData) -> Path {
    Path { points, feature: Feature::Lattice, width: 0.4, speed_factor: 1.0, approach: None, data: Some(Box::new(data)) }
}

fn hemisphere_toolpath() -> (Toolpath, Vec<DVec3>, Vec<DVec3>) {
    let (pts, axes) = hemisphere();
    let path = free_path(pts.clone(), PointData { tool_axis: Some(axes.clone()), ..Default::default() });
    (Toolpath { passes: vec![Pass { kind: PassKind::Free, z: 0.0, height: 0.2, paths: vec![path] }] }, pts, axes)
}

fn options(machine: Machine) -> Options {
    let mut o = Options::default();
    o.printer.machine = machine;
    o.printer.retraction.length_mm = 0.0;
    o.design_name = "5-axis".into();
    o
}

/// A 5-axis machine. The table's rotary centre is off the hemisphere's centre (with it on the
/// centre every normal pose puts the tip at the same machine point, and nothing would move).
fn five(layout: Layout, rotary_axes: RotaryAxes, axis_output: AxisOutput) -> Machine {
    Machine { kind: Kind::FiveAxis, layout, rotary_axes, axis_output, pivot_mm: 30.0, table_center_mm: [112.0, 108.0, -5.0], ..Machine::default() }
}

fn extrusion_lines(text: &str) -> Vec<&str> {
    text.lines().filter(|l| l.starts_with("G1 ") && l.contains(" E")).collect()
}

fn word(line: &str, letter: char) -> Option<f64> {
    line.split(';').next().unwrap().split_whitespace().find(|w| w.starts_with(letter)).map(|w| w[1..].parse().unwrap())
}

/// Writes, reads back with the same machine, and checks every segment's axis and tip.
fn round_trip(machine: Machine, analyzer_machine: Machine) -> String {
    let (tp, pts, axes) = hemisphere_toolpath();
    let g = write_gcode(&tp, &options(machine.clone())).unwrap_or_else(|e| panic!("{machine:?}: {e}"));
    let a = analyze("5axis.gcode", g.text.as_bytes(), &AOptions { collect_preview: true, machine: analyzer_machine, ..Default::default() }).unwrap();
    let pv = a.preview.unwrap();
    assert_eq!(pv.feature.len(), pts.len() - 1, "{machine:?}: one segment per planned segment");
    assert_eq!(pv.axis.len(), 3 * pv.feature.len());
    let centre = DVec3::new(110.0, 110.0, 0.0);
    for k in 0..pv.feature.len() {
        let got = DVec3::new(pv.axis[3 * k] as f64, pv.axis[3 * k + 1] as f64, pv.axis[3 * k + 2] as f64);
        assert!((got - axes[k + 1]).length() < 1e-6, "{machine:?} segment {k}: axis {got} vs planned {}", axes[k + 1]);
        let tip = DVec3::new(pv.positions[6 * k + 3] as f64, pv.positions[6 * k + 4] as f64, pv.positions[6 * k + 5] as f64);
        assert!((tip - (pts[k + 1] + centre)).length() < 2e-3, "{machine:?} segment {k}: tip {tip} vs {}", pts[k + 1] + centre);
    }
    assert!(pv.segment_move.windows(2).all(|w| w[0] < w[1]), "one move per segment, increasing");
    assert!(a.report.rotary_moves + a.report.ijk_moves > 0);
    g.text
}

#[test]
fn hemisphere_rotary_words_round_trip_on_every_layout() {
    for layout in [Layout::HeadHead, Layout::TableTable] {
        for pair in [RotaryAxes::Ab, RotaryAxes::Bc] {
            let m = five(layout, pair, AxisOutput::Rotary);
            let text = round_trip(m.clone(), m.clone());
            let letters: Vec<char> = m.rotary_letters().iter().map(|&l| l as char).collect();
            assert!(!text.lines().any(|l| l.starts_with('G') && l.contains(" I")) && text.lines().any(|l| l.contains(&format!(" {}", letters[0]))), "{m:?}");
            // Continuity: no rotary word jumps by more than 20° between neighbouring moves
            // (the spiral starts on the pole, the singular pose of bc machines).
            let mut last: [Option<f64>; 2] = [None, None];
            for l in text.lines().filter(|l| l.starts_with("G0 ") || l.starts_with("G1 ")) {
                for (j, c) in letters.iter().enumerate() {
                    if let Some(v) = word(l, *c) {
                        if let Some(p) = last[j] {
                            assert!((v - p).abs() < 20.0, "{m:?}: {c} jumps {p} → {v} at {l}");
                        }
                        last[j] = Some(v);
                    }
                }
            }
        }
    }
}

#[test]
fn hemisphere_ijk_round_trips_on_a_cartesian_reader() {
    let m = five(Layout::HeadHead, RotaryAxes::Bc, AxisOutput::Ijk);
    let text = round_trip(m, Machine::default());
    let first = extrusion_lines(&text)[0];
    assert!(word(first, 'I').is_some() && word(first, 'J').is_some() && word(first, 'K').is_some(), "{first}");
    assert!(!text.lines().any(|l| l.starts_with("G1 ") && word(l, 'C').is_some()));
}

#[test]
fn files_without_axes_keep_an_empty_axis_buffer() {
    let p = Path::new(vec![DVec3::new(0.0, 0.0, 0.2), DVec3::new(10.0, 0.0, 0.2), DVec3::new(10.0, 5.0, 0.2)], Feature::Lattice, 0.4);
    let g = write_gcode(&Toolpath { passes: vec![Pass::layer(0.2, 0.2, vec![p])] }, &Options::default()).unwrap();
    let a = analyze("plain.gcode", g.text.as_bytes(), &AOptions { collect_preview: true, ..Default::default() }).unwrap();
    let pv = a.preview.unwrap();
    assert!(pv.axis.is_empty());
    assert_eq!(pv.segment_move.len(), pv.feature.len());
    assert_eq!(pv.travel_move.len() * 6, pv.travel_positions.len());
    assert!(pv.travel_move[0] < pv.segment_move[0], "the travel to the start comes first");
    assert!(pv.travel_move.windows(2).all(|w| w[0] < w[1]) && pv.segment_move.windows(2).all(|w| w[0] < w[1]));
    assert!(pv.travel_move.iter().all(|t| !pv.segment_move.contains(t)), "a move is either travel or extrusion");
    assert_eq!(a.report.rotary_moves, 0);
    // A cartesian reader counts rotary words but gives no axis.
    let a = analyze("r.gcode", b"G1 X1 Y1 E1 B10 C20\nG1 X2 E2\n", &AOptions { collect_preview: true, ..Default::default() }).unwrap();
    assert_eq!(a.report.rotary_moves, 1);
    assert!(a.preview.unwrap().axis.is_empty());
}

#[test]
fn per_point_flow_gives_the_nominal_filament() {
    let pts: Vec<DVec3> = (0..6).map(|k| DVec3::new(k as f64 * 3.0, (k % 2) as f64, 0.3)).collect();
    let area = vec![0.0, 0.08, 0.12, 0.1, 0.05, 0.2];
    let per_mm = vec![0.0, 0.02, 0.03, 0.01, 0.05, 0.04];
    let fd: f64 = 1.75;
    let lens: Vec<f64> = pts.windows(2).map(|w| w[0].distance(w[1])).collect();
    let em = 0.9;
    let nominal_area: f64 = (1..6).map(|j| 1.0 * em * lens[j - 1] * area[j] / (std::f64::consts::PI * fd * fd / 4.0)).sum();
    let nominal_mm: f64 = (1..6).map(|j| per_mm[j] * lens[j - 1]).sum();
    let a_path = free_path(pts.clone(), PointData { flow: Some(PointFlow::AreaMm2(area)), ..Default::default() });
    let mut m_path = free_path(
        pts.iter().map(|p| *p + DVec3::new(0.0, 10.0, 0.0)).collect(),
        PointData { flow: Some(PointFlow::FilamentPerMm(per_mm)), ..Default::default() },
    );
    m_path.feature = Feature::Contour;
    let tp = Toolpath { passes: vec![Pass::layer(0.3, 0.3, vec![a_path, m_path])] };
    let mut o = options(Machine::default());
    o.material.extrusion_multiplier = em;
    let g = write_gcode(&tp, &o).unwrap();
    let a = analyze("flow.gcode", g.text.as_bytes(), &AOptions::default()).unwrap();
    let nominal = nominal_area + nominal_mm;
    assert!((a.report.filament_mm - nominal).abs() < 1e-4, "{} vs {nominal}", a.report.filament_mm);
    assert!((g.stats.filament_mm - nominal).abs() < 1e-12);
    // Relative E: each segment's E word is its own nominal value.
    let mut o = o.clone();
    o.printer.relative_e = true;
    let g = write_gcode(&tp, &o).unwrap();
    let es: Vec<f64> = extrusion_lines(&g.text).iter().map(|l| word(l, 'E').unwrap()).collect();
    assert_eq!(es.len(), 10);
    let want = 1.0 * em * lens[1] * 0.12 / (std::f64::consts::PI * fd * fd / 4.0);
    assert!((es[1] - want).abs() < 6e-6, "{} vs {want}", es[1]);
    assert!((es[7] - 0.01 * lens[2]).abs() < 6e-6);
}

#[test]
fn feed_and_dwell_land_on_the_expected_lines() {
    let pts = vec![DVec3::new(0.0, 0.0, 0.2), DVec3::new(5.0, 0.0, 0.2), DVec3::new(5.0, 5.0, 0.2), DVec3::new(0.0, 5.0, 0.2)];
    let data = PointData { feed_mm_s: Some(vec![0.0, 5.0, 10.0, 10.0]), dwell_s: Some(vec![0.1, 0.5, 0.0, 0.25]), ..Default::default() };
    let tp = Toolpath { passes: vec![Pass::layer(0.2, 0.2, vec![free_path(pts, data)])] };
    let mut o = options(Machine::default());
    o.printer.start_gcode.clear();
    o.printer.end_gcode.clear();
    let g = write_gcode(&tp, &o).unwrap();
    let lines: Vec<&str> = g.text.lines().collect();
    let at = |prefix: &str| lines.iter().position(|l| l.starts_with(prefix)).unwrap_or_else(|| panic!("no {prefix} in\n{}", g.text));
    let s1 = at("G1 X115 Y110 E");
    assert!(lines[s1].ends_with(" F300"), "{}", lines[s1]);
    assert_eq!(lines[s1 - 1], "G4 P100", "dwell at the first point, before the first segment");
    assert_eq!(lines[s1 + 1], "G4 P500");
    let s2 = at("G1 X115 Y115 E");
    assert_eq!(s2, s1 + 2);
    assert!(lines[s2].ends_with(" F600"), "{}", lines[s2]);
    let s3 = at("G1 X110 Y115 E");
    assert_eq!(s3, s2 + 1, "no dwell of 0 s");
    assert!(!lines[s3].contains(" F"), "the feed is modal: {}", lines[s3]);
    assert_eq!(lines[s3 + 1], "G4 P250");
    // The dwells are in the time (at least 0.85 s more: each also stops the motion), and the
    // writer's time is the analyzer's.
    let mut tp2 = tp.clone();
    tp2.passes[0].paths[0].data.as_mut().unwrap().dwell_s = None;
    let g2 = write_gcode(&tp2, &o).unwrap();
    assert!(g.stats.estimated_time_s - g2.stats.estimated_time_s >= 0.85, "{} vs {}", g.stats.estimated_time_s, g2.stats.estimated_time_s);
    let a = analyze("d.gcode", g.text.as_bytes(), &AOptions::default()).unwrap();
    assert_eq!(a.report.estimated_time_s.to_bits(), g.stats.estimated_time_s.to_bits());
}

#[test]
fn a_free_pass_gets_no_first_layer_speed_or_temperature() {
    let p = |y: f64| Path::new(vec![DVec3::new(0.0, y, 1.0), DVec3::new(10.0, y, 2.0)], Feature::Lattice, 0.4);
    let tp = Toolpath { passes: vec![Pass { kind: PassKind::Free, z: 1.0, height: 0.2, paths: vec![p(0.0)] }, Pass::layer(2.2, 0.2, vec![p(5.0)])] };
    let mut o = options(Machine::default());
    o.speeds.first_layer_mm_s = 7.0;
    o.speeds.lattice_mm_s = 20.0;
    o.material.first_layer_nozzle_temp_c = 230.0;
    o.material.nozzle_temp_c = 205.0;
    o.material.fan_start_layer = 1;
    let g = write_gcode(&tp, &o).unwrap();
    let lines: Vec<&str> = g.text.lines().collect();
    let layer1 = lines.iter().position(|l| *l == ";LAYER:1").unwrap();
    let free: &[&str] = &lines[..layer1];
    let free_ext: Vec<&&str> = free.iter().filter(|l| l.starts_with("G1 ") && l.contains(" E")).collect();
    assert_eq!(free_ext.len(), 1);
    assert!(free_ext[0].ends_with(" F1200"), "lattice speed, not first-layer: {}", free_ext[0]);
    let layer0 = lines.iter().position(|l| *l == ";LAYER:0").unwrap();
    assert!(free[layer0..].contains(&"M104 S205"), "normal temperature before the free pass");
    assert!(free[layer0..].contains(&"M106 S255"), "fan on for the free pass");
    // The planar layer after it is the first planar layer: first-layer speed, no second M104.
    let planar_ext = lines[layer1..].iter().find(|l| l.starts_with("G1 ") && l.contains(" E")).unwrap();
    assert!(planar_ext.ends_with(" F420"), "{planar_ext}");
    assert_eq!(lines.iter().filter(|l| l.starts_with("M104 S205")).count(), 1);
}

#[test]
fn limits_and_axes_are_checked_with_clear_errors() {
    let (tp, _, _) = hemisphere_toolpath();
    // Rotary limit.
    let mut m = five(Layout::HeadHead, RotaryAxes::Bc, AxisOutput::Rotary);
    m.rotary_max_deg[1] = 30.0;
    match write_gcode(&tp, &options(m)) {
        Err(e @ Error::MachineLimit { axis: 'B', above: true, .. }) => {
            let msg = e.to_string();
            assert!(msg.contains("rotary_max_deg") && msg.contains("limit 30"), "{msg}");
        }
        other => panic!("{other:?}"),
    }
    // Travel limit in machine coordinates: the pivot lifts Z by 30 mm.
    let mut m = five(Layout::HeadHead, RotaryAxes::Bc, AxisOutput::Rotary);
    m.travel_max_mm = Some([220.0, 220.0, 35.0]);
    match write_gcode(&tp, &options(m)) {
        Err(e @ Error::MachineLimit { axis: 'Z', .. }) => assert!(e.to_string().contains("travel_max_mm"), "{e}"),
        other => panic!("{other:?}"),
    }
    // The same limit holds for I J K output (checked through the kinematics).
    let mut m = five(Layout::HeadHead, RotaryAxes::Bc, AxisOutput::Ijk);
    m.travel_max_mm = Some([220.0, 220.0, 35.0]);
    assert!(matches!(write_gcode(&tp, &options(m)), Err(Error::MachineLimit { axis: 'Z', .. })));
    // Table-table: a rotary centre far below the part swings it under the plate.
    let mut m = five(Layout::TableTable, RotaryAxes::Bc, AxisOutput::Rotary);
    m.table_center_mm = [110.0, 110.0, -30.0];
    assert!(matches!(write_gcode(&tp, &options(m)), Err(Error::MachineLimit { .. })));
    // A 3-axis printer refuses tilted axes.
    let e = write_gcode(&tp, &options(Machine::default())).unwrap_err();
    assert!(matches!(e, Error::NeedsFiveAxis { pass: 0, path: 0, point: 1, .. }), "{e:?}");
    assert!(e.to_string().contains("pick a 5-axis machine"), "{e}");
    // Bad per-point data names the pass and path.
    let mut bad = tp.clone();
    bad.passes[0].paths[0].data.as_mut().unwrap().feed_mm_s = Some(vec![1.0; 3]);
    let e = write_gcode(&bad, &options(five(Layout::HeadHead, RotaryAxes::Bc, AxisOutput::Rotary))).unwrap_err();
    assert!(matches!(&e, Error::BadPointData { pass: 0, path: 0, .. }), "{e:?}");
    assert!(e.to_string().contains("feed has 3 values for 401 points"), "{e}");
    let mut bad = tp.clone();
    bad.passes[0].paths[0].data.as_mut().unwrap().dwell_s = Some(vec![f64::NAN; 401]);
    assert!(matches!(write_gcode(&bad, &options(Machine::default())), Err(Error::BadPointData { .. })));
}

#[test]
fn poses_csv_parses_back_to_the_planned_poses() {
    let (mut tp, pts, axes) = hemisphere_toolpath();
    let second: Vec<DVec3> = pts.iter().take(5).map(|p| *p + DVec3::new(0.0, 0.0, 1.0)).collect();
    tp.passes[0].paths.push(free_path(second.clone(), PointData { tool_axis: Some(axes[..5].to_vec()), ..Default::default() }));
    let mut o = options(Machine::default());
    o.printer.flavor = Flavor::PosesCsv;
    assert_eq!(o.printer.flavor.file_extension(), "csv");
    let g = write_gcode(&tp, &o).unwrap();
    let mut lines = g.text.lines();
    assert_eq!(lines.next(), Some("x,y,z,nx,ny,nz"));
    let rows: Vec<Vec<f64>> = lines.filter(|l| !l.is_empty()).map(|l| l.split(',').map(|v| v.parse().unwrap()).collect()).collect();
    let planned: Vec<(DVec3, DVec3)> = pts.iter().copied().zip(axes.iter().copied()).chain(second.iter().copied().zip(axes[..5].iter().copied())).collect();
    assert_eq!(rows.len(), planned.len());
    let centre = DVec3::new(110.0, 110.0, 0.0);
    for (r, (p, n)) in rows.iter().zip(&planned) {
        assert_eq!(r.len(), 6);
        assert!((DVec3::new(r[0], r[1], r[2]) - (*p + centre)).abs().max_element() <= 5e-4 + 1e-12);
        assert!((DVec3::new(r[3], r[4], r[5]) - *n).abs().max_element() <= 5e-8 + 1e-15);
    }
    assert_eq!(g.text.matches("\n\n").count(), 1, "a blank line between the two paths");
    // The analyzer reads it back: two paths, their axes in the preview.
    let a = analyze("poses.csv", g.text.as_bytes(), &AOptions { collect_preview: true, ..Default::default() }).unwrap();
    assert_eq!(a.report.extrusion_paths, 2);
    assert!((a.report.extruded_mm - g.stats.extruded_mm).abs() < 1e-2);
    assert_eq!(a.preview.unwrap().axis.len(), 3 * (pts.len() - 1 + 4));
}

#[test]
fn printer_json_without_machine_is_cartesian_and_stays_unchanged() {
    let p: weft::gcode::Printer = serde_json::from_str(r#"{"name": "x"}"#).unwrap();
    assert_eq!(p.machine, Machine::default());
    assert!(!serde_json::to_string(&p).unwrap().contains("machine"), "the default machine is not written");
    let p: weft::gcode::Printer = serde_json::from_str(
        r#"{"machine": {"kind": "five_axis", "layout": "table_table", "rotary_axes": "ab", "axis_output": "ijk", "table_center_mm": [1, 2, 3]}}"#,
    )
    .unwrap();
    assert_eq!(p.machine.layout, Layout::TableTable);
    assert_eq!(p.machine.table_center_mm, [1.0, 2.0, 3.0]);
    assert!(serde_json::from_str::<weft::gcode::Printer>(r#"{"machine": {"kind": "five_axis", "pivot": 3}}"#).is_err(), "unknown fields are rejected");
}

//! Seams and overhang perimeters of the planar slicer, read back from the G-code: where each
//! layer's external perimeter starts for every `seam` choice, and which stretches of which
//! layers are written as `;TYPE:Overhang perimeter` (and at what feed).

use weft::gcode::{write_gcode, Options as GOptions, Origin};
use weft::geom::shapes::Shape;
use weft::geom::{DVec2, DVec3, Feature, Mesh};
use weft::slice::{self, Options, Seam};

fn moved(mut m: Mesh, d: [f64; 3]) -> Mesh {
    m.translate(DVec3::from_array(d));
    m
}

fn cube(size: [f64; 3]) -> Mesh {
    Shape::Cube { size }.mesh()
}

/// A 20-sided prism, 10 mm radius, 5 mm tall.
fn prism20() -> Mesh {
    Shape::Cylinder { radius: 10.0, height: 5.0, segments: 20 }.mesh()
}

/// An L: a 20 × 10 mm bar and a 10 × 10 mm block beside its left half, 5 mm tall; its
/// concave corner is at (0, 5).
fn ell() -> Mesh {
    let mut m = moved(cube([20.0, 10.0, 5.0]), [0.0, 0.0, 0.0]);
    m.append(&moved(cube([10.0, 10.0, 5.0]), [-5.0, 10.0, 0.0]));
    m
}

fn gcode_options() -> GOptions {
    let mut o = GOptions::default();
    o.printer.start_gcode = String::new();
    o.printer.end_gcode = String::new();
    o.printer.origin = Origin::Center;
    o.printer.thumbnails.clear();
    o.printer.object_labels = weft::gcode::ObjectLabels::None;
    o.design_name = "t".into();
    o
}

fn gcode(mesh: &Mesh, o: &Options, g: &GOptions) -> String {
    let s = slice::slice(mesh, o, &mut |_| {}).expect("slices");
    write_gcode(&s.toolpath, g).expect("writes").text
}

/// One extruding stretch of one feature: where the nozzle was before it (the end of the
/// previous extrusion), its points (the first is where it starts) and the feed of each move.
#[derive(Debug, Clone)]
struct Run {
    layer: usize,
    z: f64,
    feature: Feature,
    before: Option<DVec2>,
    points: Vec<DVec2>,
    feeds: Vec<f64>,
}

/// The extruding runs of the G-code, split at `;TYPE:` and at travels.
fn runs(text: &str) -> Vec<Run> {
    let mut out: Vec<Run> = Vec::new();
    let (mut pos, mut z, mut e, mut f) = (DVec2::ZERO, 0.0, 0.0f64, 0.0);
    let mut layer = 0usize;
    let mut seen_layer = false;
    let mut feature: Option<Feature> = None;
    let mut open = false;
    let mut last_end: Option<DVec2> = None;
    for line in text.lines() {
        if line.starts_with(";LAYER_CHANGE") {
            if seen_layer {
                layer += 1;
            }
            seen_layer = true;
            open = false;
            continue;
        }
        if let Some(name) = line.strip_prefix(";TYPE:") {
            feature = Feature::from_gcode_name(name);
            open = false;
            continue;
        }
        let code = line.split(';').next().unwrap_or("").trim();
        let mut words = code.split_whitespace();
        let g = words.next();
        if g != Some("G1") && g != Some("G0") {
            continue;
        }
        let (mut x, mut y, mut ne) = (pos.x, pos.y, None);
        for w in words {
            let v: f64 = w[1..].parse().unwrap();
            match w.as_bytes()[0] {
                b'X' => x = v,
                b'Y' => y = v,
                b'Z' => z = v,
                b'E' => ne = Some(v),
                b'F' => f = v,
                _ => {}
            }
        }
        let to = DVec2::new(x, y);
        let extrudes = ne.is_some_and(|v| v > e + 1e-9) && to != pos;
        if let Some(v) = ne {
            e = v;
        }
        if extrudes {
            let Some(feat) = feature else { panic!("extrusion before any ;TYPE: {line}") };
            if !open {
                out.push(Run { layer, z, feature: feat, before: last_end, points: vec![pos], feeds: Vec::new() });
                open = true;
            }
            let r = out.last_mut().unwrap();
            r.points.push(to);
            r.feeds.push(f);
            last_end = Some(to);
        } else if to != pos {
            open = false;
        }
        pos = to;
    }
    out
}

/// The start of every external perimeter loop (a run of that feature that does not continue
/// another perimeter run), by layer, with the loop's points.
fn external_starts(text: &str) -> Vec<(usize, DVec2, Vec<DVec2>)> {
    runs(text)
        .into_iter()
        .filter(|r| r.feature == Feature::ExternalPerimeter && r.before != Some(r.points[0]))
        .map(|r| (r.layer, r.points[0], r.points))
        .collect()
}

fn spread(starts: &[(usize, DVec2, Vec<DVec2>)]) -> f64 {
    let p0 = starts[0].1;
    starts.iter().map(|s| s.1.distance(p0)).fold(0.0, f64::max)
}

#[test]
fn aligned_seams_line_up_and_sit_in_the_concave_corner() {
    let g = gcode_options();
    for (name, mesh) in [("prism", prism20()), ("cube", cube([20.0, 20.0, 5.0])), ("ell", ell())] {
        let o = Options { seam: Seam::Aligned, ..Options::default() };
        assert_eq!(Options::default().seam, Seam::Aligned, "the default");
        let starts = external_starts(&gcode(&mesh, &o, &g));
        assert_eq!(starts.len(), 25, "{name}: one external loop a layer");
        let s = spread(&starts);
        eprintln!("{name}: aligned seams within {s:.4} mm of layer 0's");
        assert!(s <= 0.5, "{name}: aligned seams {s} mm apart");
        if name == "ell" {
            // The external perimeter's concave corner, 0.2 mm into the material from the
            // outline's (0, 5).
            let d = starts[0].1.distance(DVec2::new(-0.2, 4.8));
            assert!(d < 0.01, "ell: seam at {:?}, {d} mm from the concave corner", starts[0].1);
        }
        // The same prism with `nearest` does not line up: the test can tell.
        if name == "prism" {
            let o = Options { seam: Seam::Nearest, ..Options::default() };
            let s = spread(&external_starts(&gcode(&mesh, &o, &g)));
            eprintln!("{name}: nearest seams spread {s:.3} mm");
            assert!(s > 2.0, "nearest seams spread only {s} mm");
        }
    }
}

#[test]
fn rear_seams_are_at_the_largest_y() {
    let g = gcode_options();
    for (name, mesh) in [("prism", prism20()), ("cube", cube([20.0, 20.0, 5.0])), ("ell", ell())] {
        let o = Options { seam: Seam::Rear, ..Options::default() };
        let starts = external_starts(&gcode(&mesh, &o, &g));
        assert_eq!(starts.len(), 25, "{name}");
        for (layer, p, pts) in &starts {
            let ymax = pts.iter().map(|q| q.y).fold(f64::NEG_INFINITY, f64::max);
            assert!((p.y - ymax).abs() <= 0.01, "{name} layer {layer}: seam y {} but the loop reaches {ymax}", p.y);
        }
        if name == "cube" {
            // A level top edge: its middle (a point inserted on the edge).
            assert!(starts.iter().all(|s| s.1.distance(DVec2::new(0.0, 9.8)) < 0.01), "{:?}", starts[0].1);
        }
    }
}

#[test]
fn random_seams_scatter_and_repeat() {
    let g = gcode_options();
    let o = Options { seam: Seam::Random, ..Options::default() };
    for (name, mesh) in [("prism", prism20()), ("cube", cube([20.0, 20.0, 5.0]))] {
        let a = gcode(&mesh, &o, &g);
        let starts = external_starts(&a);
        assert_eq!(starts.len(), 25, "{name}");
        let mut distinct: Vec<DVec2> = Vec::new();
        for s in &starts {
            if distinct.iter().all(|q| q.distance(s.1) > 1.0) {
                distinct.push(s.1);
            }
        }
        eprintln!("{name}: {} distinct random seams (> 1 mm apart) in 25 layers", distinct.len());
        assert!(distinct.len() >= 15, "{name}: only {} distinct seams", distinct.len());
        assert_eq!(a, gcode(&mesh, &o, &g), "{name}: the same design, the same bytes");
        for threads in [1, 4] {
            let other = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap().install(|| gcode(&mesh, &o, &g));
            assert_eq!(a, other, "{name}: the same bytes on {threads} threads");
        }
    }
}

#[test]
fn nearest_seams_start_at_the_vertex_nearest_the_nozzle() {
    let g = gcode_options();
    let o = Options { seam: Seam::Nearest, ..Options::default() };
    for (name, mesh) in [("prism", prism20()), ("cube", cube([20.0, 20.0, 5.0]))] {
        let starts = runs(&gcode(&mesh, &o, &g));
        let mut checked = 0;
        for r in starts.iter().filter(|r| matches!(r.feature, Feature::ExternalPerimeter | Feature::Perimeter)) {
            let Some(before) = r.before else { continue };
            if before == r.points[0] {
                continue;
            }
            let nearest = r.points.iter().map(|q| q.distance(before)).fold(f64::INFINITY, f64::min);
            assert!(
                r.points[0].distance(before) <= nearest + 1e-3,
                "{name} layer {}: starts {} mm away, a vertex is {nearest}",
                r.layer,
                r.points[0].distance(before)
            );
            checked += 1;
        }
        assert!(checked >= 50, "{name}: {checked} loops");
    }
}

/// A 10 mm cube with a 30 × 10 × 2 mm slab on top (z 8–10): a 10 mm ledge each side.
fn tee() -> Mesh {
    let mut m = cube([10.0, 10.0, 10.0]);
    m.append(&moved(cube([30.0, 10.0, 2.0]), [0.0, 0.0, 8.0]));
    m
}

#[test]
fn overhang_perimeters_only_over_the_ledge() {
    let mut g = gcode_options();
    g.speeds.overhang_mm_s = 7.0;
    let text = gcode(&tee(), &Options::default(), &g);
    let all = runs(&text);
    let over: Vec<&Run> = all.iter().filter(|r| r.feature == Feature::OverhangPerimeter).collect();
    assert!(!over.is_empty(), "no overhang perimeter");
    let mut len = 0.0;
    for r in &over {
        // Only the first slab layer (cut at 8.1 mm, over the cube's 7.9 mm section).
        assert!((r.z - 8.2).abs() < 1e-6, "overhang at z {}", r.z);
        for w in r.points.windows(2) {
            assert!(w[0].x.abs() >= 5.0 - 1e-3 && w[1].x.abs() >= 5.0 - 1e-3, "overhang move over the cube: {:?}", w);
            len += w[0].distance(w[1]);
        }
        // At the overhang feed.
        assert!(r.feeds.iter().all(|&f| f == 420.0), "feeds {:?}", r.feeds);
        // It continues a perimeter (or is continued by one): one extrusion, no travel.
        assert!(
            r.before.is_some_and(|b| b == r.points[0]) || all.iter().any(|q| q.before == r.points.last().copied() && q.points[0] == *r.points.last().unwrap())
        );
    }
    // External loop (±14.8 × ±4.8 mm) and inner loop (±14.4 × ±4.4 mm) beyond x = ±5:
    // 2 × (9.8 + 9.6 + 9.8) + 2 × (9.4 + 8.8 + 9.4) = 113.6 mm.
    eprintln!("overhang perimeter {len:.3} mm in {} runs", over.len());
    assert!((len - 113.6).abs() < 0.5, "overhang length {len}");
    // On the ledge layer the perimeters around the cube part stay ordinary ones.
    let ledge_ext: f64 = all
        .iter()
        .filter(|r| (r.z - 8.2).abs() < 1e-6 && matches!(r.feature, Feature::ExternalPerimeter | Feature::Perimeter))
        .flat_map(|r| r.points.windows(2).map(|w| w[0].distance(w[1])).collect::<Vec<_>>())
        .sum();
    // Both loops' stretches along y = ±4.8 and ±4.4 between x = −5 and 5: 4 × 10 mm.
    assert!((ledge_ext - 40.0).abs() < 0.5, "ordinary perimeter on the ledge layer {ledge_ext}");
    // A plain cube has none.
    let plain = gcode(&cube([20.0, 20.0, 5.0]), &Options::default(), &g);
    assert!(!plain.contains(";TYPE:Overhang perimeter"));
    assert!(text.contains(";TYPE:Overhang perimeter"));
}

#[test]
fn seam_is_read_from_a_design_and_checked() {
    let o: Options = serde_json::from_str(r#"{"seam": "rear"}"#).unwrap();
    assert_eq!(o.seam, Seam::Rear);
    assert!(serde_json::from_str::<Options>(r#"{"seam": "front"}"#).is_err());
    // Written like every setting, so `weft new` shows it.
    assert!(serde_json::to_string(&Options::default()).unwrap().contains(r#""seam":"aligned""#));
    assert!(serde_json::to_string(&Options { seam: Seam::Random, ..Options::default() }).unwrap().contains(r#""seam":"random""#));
    let row = slice::FIELDS.iter().find(|f| f.path == "seam").expect("a form row");
    assert_eq!(row.choices, slice::SEAMS);
    assert_eq!(row.choice_docs.len(), slice::SEAMS.len());
    for (i, s) in [Seam::Aligned, Seam::Rear, Seam::Nearest, Seam::Random].into_iter().enumerate() {
        assert_eq!(s.label(), slice::SEAMS[i]);
    }
}

#[test]
fn aligned_seams_follow_a_sphere_s_meridian() {
    // Every layer's loop is a different size: the seam stays on one meridian (its angle about
    // the axis), where `nearest` wanders round.
    let sphere = moved(Shape::Sphere { radius: 10.0, segments: 48 }.mesh(), [0.0, 0.0, 10.0]);
    let g = gcode_options();
    let angles = |seam: Seam| -> Vec<f64> {
        let o = Options { seam, ..Options::default() };
        external_starts(&gcode(&sphere, &o, &g)).iter().filter(|s| s.1.length() > 3.0).map(|s| s.1.y.atan2(s.1.x).to_degrees()).collect()
    };
    let a = angles(Seam::Aligned);
    assert!(a.len() > 60, "{} layers", a.len());
    let worst = a.iter().map(|x| (x - a[0]).abs()).fold(0.0, f64::max);
    eprintln!("sphere: aligned seams within {worst:.3}° of one meridian over {} layers", a.len());
    assert!(worst < 2.0, "aligned seams {worst}° apart");
    let n = angles(Seam::Nearest);
    let worst = n.iter().map(|x| (x - n[0]).abs()).fold(0.0, f64::max);
    eprintln!("sphere: nearest seams {worst:.1}° apart");
    assert!(worst > 30.0);
}

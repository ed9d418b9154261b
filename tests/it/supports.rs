//! Supports: read back from the G-code, the first layer of an overhang rests on support (the
//! interface, one layer of air below it) or on the part, nowhere on air; support keeps its side
//! gap; on the plate only leaves out support that would stand on the part; a blocker mesh
//! removes support; the tree style holds the same overhang with less material.

use super::bridges::{extrusions, Move};
use weft::gcode::{write_gcode, Options as GOptions, Origin};
use weft::geom::shapes::Shape;
use weft::geom::{DVec2, DVec3, Mesh};
use weft::slice::{self, support, Extra, Options};

fn cube_at(size: [f64; 3], at: [f64; 3]) -> Mesh {
    let mut m = Shape::Cube { size }.mesh();
    m.translate(DVec3::from_array(at));
    m
}

/// A 10 × 10 mm stem 20 mm tall and a 40 × 10 × 5 mm bar on it: 15 mm overhangs each side.
fn t_bracket() -> Mesh {
    let mut m = cube_at([10.0, 10.0, 20.0], [0.0, 0.0, 0.0]);
    m.append(&cube_at([40.0, 10.0, 5.0], [0.0, 0.0, 20.0]));
    m
}

fn moves_of(mesh: &Mesh, o: &Options, extra: &Extra) -> Vec<Move> {
    let sliced = slice::slice_with(mesh, extra, o, &mut |_| {}).expect("slices");
    let mut g = GOptions::default();
    g.printer.origin = Origin::Center;
    g.printer.thumbnails.clear();
    extrusions(&write_gcode(&sliced.toolpath, &g).expect("writes").text)
}

fn with_support(style: support::Style) -> Options {
    Options { skirt_loops: 0, support: support::Options { enabled: true, style, ..Default::default() }, ..Options::default() }
}

fn dist_to_segment(p: DVec2, a: DVec2, b: DVec2) -> f64 {
    let d = b - a;
    let t = if d.length_squared() > 0.0 { ((p - a).dot(d) / d.length_squared()).clamp(0.0, 1.0) } else { 0.0 };
    p.distance(a + d * t)
}

/// Length (mm) of the extrusions at `z` whose points have nothing within one line width on
/// the two layers below (the layer below and the one under the support's Z gap), except
/// stretches of one straight move between two held points (bridges).
fn unheld_mm(moves: &[Move], z: f64) -> f64 {
    let below: Vec<&Move> = moves.iter().filter(|m| m.z < z - 1e-6 && m.z > z - 0.41).collect();
    let mut un = 0.0;
    for m in moves.iter().filter(|m| (m.z - z).abs() < 1e-6) {
        let len = m.from.distance(m.to);
        let k = (len / 0.1).ceil().max(1.0) as usize;
        let held: Vec<bool> = (0..k)
            .map(|i| {
                let p = m.from.lerp(m.to, (i as f64 + 0.5) / k as f64);
                below.iter().any(|b| dist_to_segment(p, b.from, b.to) <= 0.4 + 0.02)
            })
            .collect();
        let (first, last) = (held.iter().position(|&h| h), held.iter().rposition(|&h| h));
        let bridged = |i: usize| matches!((first, last), (Some(f), Some(l)) if i > f && i < l);
        un += (0..k).filter(|&i| !held[i] && !bridged(i)).count() as f64 * len / k as f64;
    }
    un
}

fn support_mm(moves: &[Move]) -> f64 {
    moves.iter().filter(|m| m.kind.starts_with("Support material")).map(|m| m.from.distance(m.to)).sum()
}

#[test]
fn a_t_bracket_rests_on_its_support() {
    let mesh = t_bracket();
    let bare = moves_of(&mesh, &Options { skirt_loops: 0, ..Options::default() }, &Extra::default());
    let none = unheld_mm(&bare, 20.2);
    assert!(none > 100.0, "without support the bar's first layer hangs in air: {none:.1} mm");
    assert_eq!(support_mm(&bare), 0.0, "support is off by default");

    let moves = moves_of(&mesh, &with_support(support::Style::Grid), &Extra::default());
    let un = unheld_mm(&moves, 20.2);
    assert!(un < 1.0, "the bar's first layer rests on support: {un:.2} mm in air");
    let sup: Vec<&Move> = moves.iter().filter(|m| m.kind.starts_with("Support material")).collect();
    assert!(sup.iter().any(|m| m.kind == "Support material interface"), "an interface under the part");
    // The top of the support is one layer (0.2 mm) of air below the bar; none beside the stem.
    let top = sup.iter().map(|m| m.z).fold(0.0f64, f64::max);
    assert!((top - 19.8).abs() < 1e-6, "support top at Z {top}");
    let nearest = sup.iter().flat_map(|m| [m.from.x.abs(), m.to.x.abs()]).fold(f64::INFINITY, f64::min);
    assert!(nearest >= 5.0 + 0.3 + 0.2 - 1e-3, "support centre lines keep the 0.3 mm side gap: {nearest:.3} mm from the axis");
    // Every support layer but the first is held by the one below it.
    let zs: std::collections::BTreeSet<i64> = sup.iter().map(|m| (m.z * 1000.0).round() as i64).collect();
    for z in zs.iter().skip(1) {
        let z = *z as f64 / 1000.0;
        let only: Vec<Move> = moves
            .iter()
            .filter(|m| (m.z - z).abs() < 1e-6 && m.kind.starts_with("Support") || m.z < z - 1e-6 && m.z > z - 0.21)
            .map(|m| Move { z: m.z, kind: m.kind.clone(), from: m.from, to: m.to, feed: m.feed })
            .collect();
        let u = unheld_mm(&only, z);
        assert!(u < 0.5, "support at Z {z} hangs {u:.2} mm in air");
    }
}

#[test]
fn trees_hold_the_same_overhang_with_less_material() {
    let mesh = t_bracket();
    let grid = moves_of(&mesh, &with_support(support::Style::Grid), &Extra::default());
    let tree = moves_of(&mesh, &with_support(support::Style::Tree), &Extra::default());
    let un = unheld_mm(&tree, 20.2);
    assert!(un < 2.0, "the bar rests on the tree's interface: {un:.2} mm in air");
    let (g, t) = (support_mm(&grid), support_mm(&tree));
    assert!(t > 0.0 && t < 0.9 * g, "tree {t:.0} mm of support, grid {g:.0} mm");
}

#[test]
fn on_the_plate_only_and_blockers_leave_support_out() {
    // A bar over a wider base: its overhangs are above the base, so support would stand on it.
    let mut stepped = cube_at([30.0, 10.0, 5.0], [0.0, 0.0, 0.0]);
    stepped.append(&cube_at([10.0, 10.0, 10.0], [0.0, 0.0, 5.0]));
    stepped.append(&cube_at([30.0, 10.0, 2.0], [0.0, 0.0, 15.0]));
    let everywhere = moves_of(&stepped, &with_support(support::Style::Grid), &Extra::default());
    let low = everywhere.iter().filter(|m| m.kind.starts_with("Support")).map(|m| m.z).fold(f64::INFINITY, f64::min);
    assert!((low - 5.2).abs() < 1e-6, "support stands on the base's top (Z 5): lowest at {low}");
    let mut o = with_support(support::Style::Grid);
    o.support.on_plate_only = true;
    assert_eq!(support_mm(&moves_of(&stepped, &o, &Extra::default())), 0.0, "nothing reaches the plate");

    // A blocker over the left arm of the T: support only under the right one.
    let blocker = cube_at([17.0, 12.0, 30.0], [-12.5, 0.0, 0.0]);
    let moves = moves_of(&t_bracket(), &with_support(support::Style::Grid), &Extra { support_blockers: Some(&blocker), ..Extra::default() });
    let sup: Vec<&Move> = moves.iter().filter(|m| m.kind.starts_with("Support")).collect();
    assert!(!sup.is_empty() && sup.iter().all(|m| m.from.x > 0.0 && m.to.x > 0.0), "support only right of the stem");
    assert!(unheld_mm(&moves, 20.2) > 100.0, "the blocked arm hangs in air");
}

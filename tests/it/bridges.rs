//! Bridges in the planar slicer: the solid infill over a gap between two pillars becomes
//! straight `;TYPE:Bridge infill` lines along the span, each one move from pillar to pillar,
//! at the bridge speed; a cantilever and a plain cube get none. Read back from the G-code.

use weft::gcode::{write_gcode, Options as GOptions, Origin};
use weft::geom::shapes::Shape;
use weft::geom::{DVec2, DVec3, Mesh};
use weft::slice::{self, Options};

fn cube_at(size: [f64; 3], at: [f64; 3]) -> Mesh {
    let mut m = Shape::Cube { size }.mesh();
    m.translate(DVec3::from_array(at));
    m
}

/// Two 10 × 10 × 10 mm pillars `gap` mm apart along X (centred on 0) and a 3 mm slab on
/// them, 10 mm wide (Y), from the outer face of one pillar to the other's (Z 10–13).
fn bridge_part(gap: f64) -> Mesh {
    let mut m = cube_at([10.0, 10.0, 10.0], [-(gap / 2.0 + 5.0), 0.0, 0.0]);
    m.append(&cube_at([10.0, 10.0, 10.0], [gap / 2.0 + 5.0, 0.0, 0.0]));
    m.append(&cube_at([gap + 20.0, 10.0, 3.0], [0.0, 0.0, 10.0]));
    m
}

/// One 10 mm pillar (X −10 … 0) and a slab reaching 20 mm beyond it (X −10 … 20).
fn cantilever_part() -> Mesh {
    let mut m = cube_at([10.0, 10.0, 10.0], [-5.0, 0.0, 0.0]);
    m.append(&cube_at([30.0, 10.0, 3.0], [5.0, 0.0, 10.0]));
    m
}

/// An extruding move read back from the G-code.
pub(crate) struct Move {
    pub z: f64,
    pub kind: String,
    pub from: DVec2,
    pub to: DVec2,
    pub feed: f64,
}

fn gcode_of(mesh: &Mesh) -> (String, GOptions) {
    let sliced = slice::slice(mesh, &Options::default(), &mut |_| {}).expect("slices");
    let mut o = GOptions::default();
    o.printer.origin = Origin::Center;
    o.printer.thumbnails.clear();
    let g = write_gcode(&sliced.toolpath, &o).expect("writes");
    (g.text, o)
}

pub(crate) fn extrusions(text: &str) -> Vec<Move> {
    let (mut pos, mut z, mut e, mut f) = (DVec2::ZERO, 0.0, 0.0, 0.0);
    let mut kind = String::new();
    let mut out = Vec::new();
    for line in text.lines() {
        if let Some(t) = line.strip_prefix(";TYPE:") {
            kind = t.to_string();
            continue;
        }
        let code = line.split(';').next().unwrap_or("").trim();
        let mut words = code.split_whitespace();
        let Some(g) = words.next() else { continue };
        if g == "G92" {
            for w in words {
                if let Some(v) = w.strip_prefix('E') {
                    e = v.parse().unwrap();
                }
            }
            continue;
        }
        if g != "G0" && g != "G1" {
            continue;
        }
        let mut to = pos;
        let mut new_e = e;
        for w in words {
            let v: f64 = w[1..].parse().unwrap();
            match &w[..1] {
                "X" => to.x = v,
                "Y" => to.y = v,
                "Z" => z = v,
                "E" => new_e = v,
                "F" => f = v,
                _ => {}
            }
        }
        if new_e > e && to != pos {
            out.push(Move { z, kind: kind.clone(), from: pos, to, feed: f });
        }
        e = new_e;
        pos = to;
    }
    out
}

fn bridge_moves(moves: &[Move]) -> Vec<&Move> {
    moves.iter().filter(|m| m.kind == "Bridge infill").collect()
}

#[test]
fn gap_between_pillars_is_bridged_along_the_span() {
    let gap = 20.0;
    let (text, o) = gcode_of(&bridge_part(gap));
    let moves = extrusions(&text);
    let bridges = bridge_moves(&moves);
    assert!(!bridges.is_empty(), "no bridge lines");
    // The first layer over the gap (its top at 10.2 mm) has them, and no layer below.
    let first = bridges.iter().map(|m| m.z).fold(f64::INFINITY, f64::min);
    assert!((first - 10.2).abs() < 1e-6, "first bridge layer at {first}");
    let layer: Vec<&&Move> = bridges.iter().filter(|m| (m.z - first).abs() < 1e-6).collect();
    let half = gap / 2.0;
    let mut spanning = 0;
    for m in &layer {
        let d = m.to - m.from;
        let (lo, hi) = (m.from.x.min(m.to.x), m.from.x.max(m.to.x));
        let over_gap = hi > -half + 1e-6 && lo < half - 1e-6;
        if !over_gap {
            // A connector on a pillar, between two lines' ends.
            assert!(d.length() < 0.81, "a bridge move off the gap longer than a connector: {:?} → {:?}", m.from, m.to);
            continue;
        }
        // Over the gap: one straight move along X from one pillar onto the other.
        let angle = d.y.atan2(d.x).to_degrees().rem_euclid(180.0);
        assert!(angle.min(180.0 - angle) < 1.0, "{:?} → {:?} is {angle}° from X", m.from, m.to);
        assert!(lo <= -half - 0.4 && lo >= -half - 10.0, "starts {lo} mm: not on the left pillar");
        assert!(hi >= half + 0.4 && hi <= half + 10.0, "ends {hi} mm: not on the right pillar");
        assert!(m.from.y.abs() < 5.0, "{:?}", m.from);
        spanning += 1;
    }
    // The slab's infill area is 8 mm wide (10 less two perimeters and a half width each side).
    assert!(spanning >= 18, "{spanning} lines across the gap");
    // The whole gap: no other infill of that layer crosses it.
    for m in moves.iter().filter(|m| (m.z - first).abs() < 1e-6 && m.kind.contains("infill") && m.kind != "Bridge infill") {
        let (lo, hi) = (m.from.x.min(m.to.x), m.from.x.max(m.to.x));
        assert!(hi <= -half + 0.2 || lo >= half - 0.2, "{} over the gap: {:?} → {:?}", m.kind, m.from, m.to);
    }
    // At the bridge speed.
    let feed = o.speeds.bridge_mm_s * 60.0;
    assert!(o.speeds.bridge_mm_s != o.speeds.solid_infill_mm_s);
    for m in &bridges {
        assert!((m.feed - feed).abs() < 0.5, "bridge move at F{} (bridge_mm_s is F{feed})", m.feed);
    }
    // The layers above are ordinary solid infill again.
    assert!(bridges.iter().all(|m| (m.z - first).abs() < 1e-6), "bridges only on the first layer over the gap");
}

#[test]
fn short_and_long_gaps_are_bridged_too() {
    for gap in [10.0, 40.0] {
        let (text, _) = gcode_of(&bridge_part(gap));
        let moves = extrusions(&text);
        let half = gap / 2.0;
        let across = bridge_moves(&moves)
            .into_iter()
            .filter(|m| m.from.x.min(m.to.x) <= -half - 0.4 && m.from.x.max(m.to.x) >= half + 0.4 && (m.to.y - m.from.y).abs() < 1e-6)
            .count();
        assert!(across >= 18, "gap {gap}: {across} lines across");
    }
}

#[test]
fn a_cantilever_and_a_cube_get_no_bridges() {
    let (text, _) = gcode_of(&cantilever_part());
    let moves = extrusions(&text);
    assert!(bridge_moves(&moves).is_empty(), "a cantilever is not a bridge");
    // Its overhang is still printed (as solid infill, to be supported).
    assert!(moves.iter().any(|m| (m.z - 10.2).abs() < 1e-6 && m.kind == "Solid infill" && m.from.x.max(m.to.x) > 10.0));
    let (text, _) = gcode_of(&Shape::Cube { size: [20.0, 20.0, 20.0] }.mesh());
    let moves = extrusions(&text);
    assert!(!moves.is_empty());
    assert!(bridge_moves(&moves).is_empty(), "a cube has nothing to bridge");
}

#[test]
fn a_box_lid_on_thin_walls_is_bridged_wall_to_wall() {
    // A 20 mm box with 1.2 mm walls (thinner than two perimeters and the infill's inset) and
    // a 1 mm floor, closed by a 2 mm lid at Z 10.
    let mut m = cube_at([19.4, 19.4, 1.0], [0.0, 0.0, 0.0]);
    for s in [-1.0, 1.0] {
        m.append(&cube_at([20.0, 1.2, 10.0], [0.0, s * 9.4, 0.0]));
        m.append(&cube_at([1.2, 19.0, 10.0], [s * 9.4, 0.0, 0.0]));
    }
    m.append(&cube_at([20.0, 20.0, 2.0], [0.0, 0.0, 10.0]));
    let (text, _) = gcode_of(&m);
    let moves = extrusions(&text);
    let bridges = bridge_moves(&moves);
    assert!(bridges.iter().all(|m| (m.z - 10.2).abs() < 1e-6), "bridges only on the lid's first layer");
    let mut across = 0;
    for m in bridges.iter().filter(|m| m.from.distance(m.to) > 1.0) {
        // Along X or Y, from one wall (|coordinate| ≥ 8.8) to the opposite one.
        let d = m.to - m.from;
        let off = d.y.atan2(d.x).to_degrees().rem_euclid(90.0);
        assert!(off.min(90.0 - off) < 1.0, "{:?} → {:?}", m.from, m.to);
        let (a, b) = if d.x.abs() > d.y.abs() { (m.from.x, m.to.x) } else { (m.from.y, m.to.y) };
        assert!(a.abs() >= 8.8 && a.abs() <= 10.0 && b.abs() >= 8.8 && b.abs() <= 10.0 && a * b < 0.0, "{:?} → {:?}", m.from, m.to);
        across += 1;
    }
    assert!(across >= 40, "{across} lines across the box");
}

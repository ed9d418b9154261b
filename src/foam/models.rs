//! Built-in foam models: region meshes made by weft, for the examples, teaching and the
//! benchmark (the paper's dogbone, hinged cube net and insole, and two blocks). Each region is
//! one closed mesh made of upright prisms over simple polygons (ear-clipped caps); a region may
//! hold several prisms that do not touch each other (the cube net's six panels).

use crate::geom::{signed_area, DVec2, Mesh};
use serde::{Deserialize, Serialize};

/// A built-in model (sizes in mm).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Model {
    /// A dogbone (the paper's Figs. 5–6): grips, tapers and a neck, split in two regions at
    /// the middle of the neck.
    Dogbone {
        /// Neck length (the paper's 60 mm).
        neck_length_mm: f64,
        /// Neck width.
        neck_width_mm: f64,
        /// Grip length at each end.
        grip_length_mm: f64,
        /// Grip width.
        grip_width_mm: f64,
        /// Thickness.
        thickness_mm: f64,
    },
    /// The net of a cube (six square panels in a cross) whose panels are one region and the
    /// strips between them (living hinges) another (the paper's Fig. 7a).
    HingeCube {
        /// Panel edge.
        panel_mm: f64,
        /// Hinge strip width.
        hinge_mm: f64,
        /// Thickness.
        thickness_mm: f64,
    },
    /// An insole outline whose heel and ball are one (soft) region and the rest another (the
    /// paper's Fig. 7c).
    Insole {
        /// Length, heel to toe.
        length_mm: f64,
        /// Thickness.
        thickness_mm: f64,
    },
    /// Two blocks side by side along X (the benchmark's foam).
    Blocks {
        /// Size of both together, X Y Z.
        size_mm: [f64; 3],
    },
    /// A disc cut into equal sectors, one region each, all meeting along the axis (beyond the
    /// paper: every region touches two others, and three or more meet along a line).
    Sectors {
        /// Number of sectors, 3 to 8.
        count: usize,
        /// Radius.
        radius_mm: f64,
        /// Thickness.
        thickness_mm: f64,
    },
}

/// Most sectors of [`Model::Sectors`] (the most regions a foam has).
pub const MAX_SECTORS: usize = 8;
/// Segments of the circle of [`Model::Sectors`] (at least; a multiple of the count).
pub const SECTOR_CIRCLE_SEGMENTS: usize = 48;

impl Default for Model {
    fn default() -> Self {
        Model::Dogbone { neck_length_mm: 60.0, neck_width_mm: 12.0, grip_length_mm: 30.0, grip_width_mm: 25.0, thickness_mm: 10.0 }
    }
}

/// Form rows (paths relative to the model).
pub const FIELDS: &[crate::settings::Field] = &[
    crate::settings::choice_docs(
        crate::settings::other(
            "kind",
            "Model",
            "Shape",
            crate::settings::Kind::Choice,
            &["dogbone", "hinge_cube", "insole", "blocks", "sectors"],
            "Region meshes made by weft instead of loaded files.",
        ),
        &[
            "A dogbone split at the middle of its neck: two regions (the paper's test piece).",
            "A cube's net: six stiff panels joined by soft hinge strips (two regions).",
            "An insole: heel and ball in one region, the rest in another.",
            "Two blocks side by side along X (the benchmark's foam).",
            "A disc cut into sectors that all meet at its centre (needs several neighbours).",
        ],
    ),
    crate::settings::num("neck_length_mm", "Model", "Neck length", "mm", 1.0, 1000.0, 1.0, "Length of the dogbone's narrow middle."),
    crate::settings::num("neck_width_mm", "Model", "Neck width", "mm", 1.0, 1000.0, 0.5, "Width of the narrow middle."),
    crate::settings::num("grip_length_mm", "Model", "Grip length", "mm", 1.0, 1000.0, 1.0, "Length of each wide end."),
    crate::settings::num("grip_width_mm", "Model", "Grip width", "mm", 1.0, 1000.0, 0.5, "Width of the wide ends (more than the neck)."),
    crate::settings::num("thickness_mm", "Model", "Thickness", "mm", 0.1, 500.0, 0.5, "Height of the model."),
    crate::settings::num("panel_mm", "Model", "Panel size", "mm", 1.0, 500.0, 1.0, "Edge of each square panel of the cube's net."),
    crate::settings::num("hinge_mm", "Model", "Hinge width", "mm", 0.1, 100.0, 0.5, "Width of the soft strip between two panels."),
    crate::settings::num("length_mm", "Model", "Insole length", "mm", 50.0, 500.0, 1.0, "Heel to toe."),
    crate::settings::int("count", "Model", "Sectors", 3.0, MAX_SECTORS as f64, "How many regions the disc is cut into."),
    crate::settings::num("radius_mm", "Model", "Disc radius", "mm", 1.0, 500.0, 1.0, "Radius of the disc."),
    crate::settings::vec3("size_mm", "Model", "Blocks size", "mm", 0.5, 1000.0, 1.0, "Both blocks together; they meet at the middle of X."),
];

/// Every problem with the sizes (empty when usable).
pub fn problems(model: &Model) -> Vec<String> {
    let mut out = Vec::new();
    let positive = |name: &str, v: f64, out: &mut Vec<String>| {
        if !(v.is_finite() && v > 0.0) {
            out.push(format!("{name} is {v}: it must be above 0 mm"));
        }
    };
    match *model {
        Model::Dogbone { neck_length_mm, neck_width_mm, grip_length_mm, grip_width_mm, thickness_mm } => {
            for (n, v) in [
                ("the neck length", neck_length_mm),
                ("the neck width", neck_width_mm),
                ("the grip length", grip_length_mm),
                ("the grip width", grip_width_mm),
                ("the thickness", thickness_mm),
            ] {
                positive(n, v, &mut out);
            }
            if grip_width_mm < neck_width_mm {
                out.push(format!("the grips ({grip_width_mm} mm) are narrower than the neck ({neck_width_mm} mm): make them at least as wide"));
            }
        }
        Model::HingeCube { panel_mm, hinge_mm, thickness_mm } => {
            for (n, v) in [("the panel size", panel_mm), ("the hinge width", hinge_mm), ("the thickness", thickness_mm)] {
                positive(n, v, &mut out);
            }
        }
        Model::Insole { length_mm, thickness_mm } => {
            positive("the length", length_mm, &mut out);
            positive("the thickness", thickness_mm, &mut out);
        }
        Model::Blocks { size_mm } => {
            for (n, v) in ["X", "Y", "Z"].iter().zip(size_mm) {
                positive(&format!("the size along {n}"), v, &mut out);
            }
        }
        Model::Sectors { count, radius_mm, thickness_mm } => {
            if !(3..=MAX_SECTORS).contains(&count) {
                out.push(format!("{count} sectors: cut the disc into 3 to {MAX_SECTORS}"));
            }
            positive("the radius", radius_mm, &mut out);
            positive("the thickness", thickness_mm, &mut out);
        }
    }
    out
}

/// The regions of `model`: (name, mesh) in order.
pub fn build(model: &Model) -> Vec<(String, Mesh)> {
    match *model {
        Model::Dogbone { neck_length_mm: n, neck_width_mm: w, grip_length_mm: g, grip_width_mm: gw, thickness_mm: t } => {
            // The taper from grip to neck is as long as the width difference (45° shoulders).
            let taper = (gw - w) / 2.0;
            let half = n / 2.0 + taper + g;
            let left = vec![
                DVec2::new(-half, -gw / 2.0),
                DVec2::new(-half + g, -gw / 2.0),
                DVec2::new(-n / 2.0, -w / 2.0),
                DVec2::new(0.0, -w / 2.0),
                DVec2::new(0.0, w / 2.0),
                DVec2::new(-n / 2.0, w / 2.0),
                DVec2::new(-half + g, gw / 2.0),
                DVec2::new(-half, gw / 2.0),
            ];
            let right: Vec<DVec2> = left.iter().rev().map(|p| DVec2::new(-p.x, p.y)).collect();
            vec![("grip A (left half)".into(), prisms(&[left], t)), ("grip B (right half)".into(), prisms(&[right], t))]
        }
        Model::HingeCube { panel_mm: p, hinge_mm: h, thickness_mm: t } => {
            // A cross: a column of four panels (x = 0) and one panel each side of the second.
            let pitch = p + h;
            let cells = [(0, 0), (0, 1), (0, 2), (0, 3), (-1, 1), (1, 1)];
            let square =
                |x0: f64, y0: f64, sx: f64, sy: f64| vec![DVec2::new(x0, y0), DVec2::new(x0 + sx, y0), DVec2::new(x0 + sx, y0 + sy), DVec2::new(x0, y0 + sy)];
            let panels: Vec<Vec<DVec2>> = cells.iter().map(|&(i, j)| square(i as f64 * pitch - p / 2.0, j as f64 * pitch, p, p)).collect();
            let mut hinges = Vec::new();
            for j in 0..3 {
                hinges.push(square(-p / 2.0, j as f64 * pitch + p, p, h));
            }
            hinges.push(square(-p / 2.0 - h, pitch, h, p));
            hinges.push(square(p / 2.0, pitch, h, p));
            vec![("panels".into(), prisms(&panels, t)), ("hinges".into(), prisms(&hinges, t))]
        }
        Model::Insole { length_mm: l, thickness_mm: t } => {
            // A foot outline along X (heel at x = 0), cut across into heel | arch | ball | toes.
            let outline = foot(l);
            let cuts = [0.0, 0.25 * l, 0.55 * l, 0.8 * l, l];
            let band = |a: f64, b: f64| clip_band(&outline, a, b);
            let soft = vec![band(cuts[0], cuts[1]), band(cuts[2], cuts[3])];
            let stiff = vec![band(cuts[1], cuts[2]), band(cuts[3], cuts[4])];
            vec![("heel and ball".into(), prisms(&soft, t)), ("arch and toes".into(), prisms(&stiff, t))]
        }
        Model::Blocks { size_mm: [x, y, z] } => {
            let rect = |x0: f64, x1: f64| vec![DVec2::new(x0, -y / 2.0), DVec2::new(x1, -y / 2.0), DVec2::new(x1, y / 2.0), DVec2::new(x0, y / 2.0)];
            vec![("block A".into(), prisms(&[rect(-x / 2.0, 0.0)], z)), ("block B".into(), prisms(&[rect(0.0, x / 2.0)], z))]
        }
        Model::Sectors { count, radius_mm: r, thickness_mm: t } => {
            // The circle's points are made once, so that neighbours share their cut exactly;
            // the first cut points along +Y.
            let count = count.clamp(1, MAX_SECTORS);
            let per = SECTOR_CIRCLE_SEGMENTS.div_ceil(count).max(2);
            let n = per * count;
            let at = |k: usize| {
                let a = std::f64::consts::FRAC_PI_2 + std::f64::consts::TAU * (k % n) as f64 / n as f64;
                DVec2::new(r * libm::cos(a), r * libm::sin(a))
            };
            (0..count)
                .map(|i| {
                    let mut ring = vec![DVec2::ZERO];
                    ring.extend((i * per..=(i + 1) * per).map(at));
                    (format!("sector {}", i + 1), prisms(&[ring], t))
                })
                .collect()
        }
    }
}

/// A convex foot-like outline along X from 0 (heel) to `l` (toe), counter-clockwise.
fn foot(l: f64) -> Vec<DVec2> {
    // Half-widths along the foot (a smooth egg: narrow heel, wide ball), sampled and mirrored.
    let n = 24;
    let width = |u: f64| {
        let s = libm::sin(std::f64::consts::PI * u);
        l * (0.12 + 0.08 * u) * libm::sqrt(s.max(0.0))
    };
    let mut lower = Vec::with_capacity(n + 1);
    for k in 0..=n {
        let u = k as f64 / n as f64;
        lower.push(DVec2::new(u * l, -width(u)));
    }
    let mut out: Vec<DVec2> = lower.clone();
    for p in lower.iter().rev().skip(1).take(n - 1) {
        out.push(DVec2::new(p.x, -p.y));
    }
    out.dedup_by(|a, b| a.distance(*b) < 1e-9);
    out
}

/// The part of the convex polygon `poly` with `a ≤ x ≤ b` (Sutherland–Hodgman on two lines).
fn clip_band(poly: &[DVec2], a: f64, b: f64) -> Vec<DVec2> {
    let clip = |pts: &[DVec2], keep: &dyn Fn(DVec2) -> f64| -> Vec<DVec2> {
        let mut out = Vec::new();
        for i in 0..pts.len() {
            let (p, q) = (pts[i], pts[(i + 1) % pts.len()]);
            let (dp, dq) = (keep(p), keep(q));
            if dp >= 0.0 {
                out.push(p);
            }
            if (dp >= 0.0) != (dq >= 0.0) {
                let t = dp / (dp - dq);
                out.push(p + (q - p) * t);
            }
        }
        out
    };
    let left = clip(poly, &|p: DVec2| p.x - a);
    let mut out = clip(&left, &|p: DVec2| b - p.x);
    out.dedup_by(|x, y| x.distance(*y) < 1e-9);
    out
}

/// Upright prisms over `outlines` (simple polygons, any orientation) from z = 0 to `height`,
/// as one closed mesh with outward-facing triangles.
pub fn prisms(outlines: &[Vec<DVec2>], height: f64) -> Mesh {
    let mut mesh = Mesh::default();
    for outline in outlines {
        let mut ring = outline.clone();
        if signed_area(&ring) < 0.0 {
            ring.reverse();
        }
        let n = ring.len() as u32;
        let base = mesh.vertices.len() as u32;
        for z in [0.0, height] {
            mesh.vertices.extend(ring.iter().map(|p| [p.x as f32, p.y as f32, z as f32]));
        }
        for t in ear_clip(&ring) {
            // Bottom faces down (clockwise seen from above), top faces up.
            mesh.triangles.push([base + t[0], base + t[2], base + t[1]]);
            mesh.triangles.push([base + n + t[0], base + n + t[1], base + n + t[2]]);
        }
        for i in 0..n {
            let j = (i + 1) % n;
            mesh.triangles.push([base + i, base + j, base + n + j]);
            mesh.triangles.push([base + i, base + n + j, base + n + i]);
        }
    }
    mesh
}

/// Triangles of a simple counter-clockwise polygon by ear clipping (O(n²); the outlines here
/// have tens of points).
fn ear_clip(ring: &[DVec2]) -> Vec<[u32; 3]> {
    let mut idx: Vec<u32> = (0..ring.len() as u32).collect();
    let mut out = Vec::new();
    let cross = |a: DVec2, b: DVec2, c: DVec2| (b - a).perp_dot(c - a);
    let mut guard = 0;
    while idx.len() > 3 && guard < 10 * ring.len() * ring.len() {
        guard += 1;
        let m = idx.len();
        let mut cut = None;
        for k in 0..m {
            let (i0, i1, i2) = (idx[(k + m - 1) % m], idx[k], idx[(k + 1) % m]);
            let (a, b, c) = (ring[i0 as usize], ring[i1 as usize], ring[i2 as usize]);
            if cross(a, b, c) <= 1e-12 {
                continue;
            }
            let inside = idx.iter().any(|&o| {
                if o == i0 || o == i1 || o == i2 {
                    return false;
                }
                let p = ring[o as usize];
                cross(a, b, p) >= 0.0 && cross(b, c, p) >= 0.0 && cross(c, a, p) >= 0.0
            });
            if !inside {
                cut = Some(k);
                out.push([i0, i1, i2]);
                break;
            }
        }
        match cut {
            Some(k) => {
                idx.remove(k);
            }
            None => break,
        }
    }
    if idx.len() == 3 {
        out.push([idx[0], idx[1], idx[2]]);
    }
    out
}

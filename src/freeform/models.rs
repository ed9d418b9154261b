//! Built-in wireframe designs made by weft, for examples, teaching and benchmarks: a lattice
//! tower (tapering like the paper's Eiffel tower), a dome (rings and meridians braced by
//! diagonals), and a truss bridge (two trusses over a span, joined by cross beams). Each stands
//! on its lowest joints (z = 0), which are its grounded joints.

use super::wireframe::{Format, Wireframe};
use glam::DVec3;
use serde::{Deserialize, Serialize};

/// Most beams a built-in design may have.
pub const MAX_MODEL_BEAMS: usize = 200_000;

/// A built-in design (sizes in mm).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Model {
    /// A square lattice tower: a grid of cells × cells bays per level, verticals, one diagonal
    /// per bay side, tapering upward.
    Tower {
        /// Bays per side.
        cells: usize,
        /// Levels.
        levels: usize,
        /// Bay width at the base.
        cell_mm: f64,
        /// Level height.
        level_mm: f64,
        /// Top width ÷ base width (1: straight).
        taper: f64,
    },
    /// A dome: rings of joints from the base circle up to 80° of latitude, each ring turned half
    /// a segment from the one below, joined around and to the two joints below (triangles).
    Dome {
        /// Base radius.
        radius_mm: f64,
        /// Rings above the base.
        rings: usize,
        /// Joints per ring.
        segments: usize,
    },
    /// A truss bridge: two Warren trusses (bottom and top chords, zig-zag diagonals) joined by
    /// cross beams, raised on four legs at its ends (half its height).
    Bridge {
        /// Length.
        span_mm: f64,
        /// Panels along the span.
        panels: usize,
        /// Distance between the trusses.
        width_mm: f64,
        /// Truss height.
        height_mm: f64,
    },
}

impl Default for Model {
    fn default() -> Self {
        Model::Tower { cells: 2, levels: 4, cell_mm: 3.0, level_mm: 3.0, taper: 0.7 }
    }
}

/// Form rows (paths relative to the model).
pub const FIELDS: &[crate::settings::Field] = &[
    crate::settings::choice_docs(
        crate::settings::other(
            "kind",
            "Model",
            "Design",
            crate::settings::Kind::Choice,
            &["tower", "dome", "bridge"],
            "A wireframe made by weft instead of a loaded file.",
        ),
        &[
            "A square lattice tower that narrows upward (like the paper's Eiffel tower).",
            "A dome of triangles: rings of joints, each joined to the two below it.",
            "Two truss girders over a span, joined by cross beams.",
        ],
    ),
    crate::settings::when(crate::settings::int("cells", "Model", "Bays per side", 1.0, 60.0, "Tower: bays along each side of a level."), "kind", "tower"),
    crate::settings::when(crate::settings::int("levels", "Model", "Levels", 1.0, 400.0, "Tower: storeys."), "kind", "tower"),
    crate::settings::when(crate::settings::num("cell_mm", "Model", "Bay width", "mm", 0.1, 1000.0, 0.5, "Tower: width of a bay at the base."), "kind", "tower"),
    crate::settings::when(crate::settings::num("level_mm", "Model", "Level height", "mm", 0.1, 1000.0, 0.5, "Tower: height of a storey."), "kind", "tower"),
    crate::settings::when(
        crate::settings::num("taper", "Model", "Taper", "", 0.1, 1.0, 0.05, "Tower: top width ÷ base width (1: straight sides)."),
        "kind",
        "tower",
    ),
    crate::settings::when(crate::settings::num("radius_mm", "Model", "Radius", "mm", 0.1, 1000.0, 0.5, "Dome: radius of the base circle."), "kind", "dome"),
    crate::settings::when(crate::settings::int("rings", "Model", "Rings", 1.0, 200.0, "Dome: rings of joints above the base."), "kind", "dome"),
    crate::settings::when(crate::settings::int("segments", "Model", "Segments", 3.0, 400.0, "Dome: joints around each ring."), "kind", "dome"),
    crate::settings::when(
        crate::settings::num("span_mm", "Model", "Span", "mm", 0.1, 5000.0, 1.0, "Bridge: length between the ends it stands on."),
        "kind",
        "bridge",
    ),
    crate::settings::when(crate::settings::int("panels", "Model", "Panels", 1.0, 2000.0, "Bridge: triangles along each truss."), "kind", "bridge"),
    crate::settings::when(
        crate::settings::num("width_mm", "Model", "Width", "mm", 0.1, 1000.0, 0.5, "Bridge: distance between the two trusses."),
        "kind",
        "bridge",
    ),
    crate::settings::when(crate::settings::num("height_mm", "Model", "Height", "mm", 0.1, 1000.0, 0.5, "Bridge: height of the trusses."), "kind", "bridge"),
];

/// Beams the model would have (before building it).
pub fn beam_count(m: &Model) -> f64 {
    match *m {
        Model::Tower { cells, levels, .. } => {
            let (c, l) = (cells as f64, levels as f64);
            let per_level = 2.0 * (c + 1.0) * c + (c + 1.0) * (c + 1.0) + 4.0 * c;
            l * per_level
        }
        Model::Dome { rings, segments, .. } => (rings as f64) * 3.0 * segments as f64,
        Model::Bridge { panels, .. } => panels as f64 * 10.0 + 3.0,
    }
}

/// Problems of a model's sizes (empty when it can be built).
pub fn problems(m: &Model) -> Vec<String> {
    let mut out = Vec::new();
    let pos = |x: f64| x.is_finite() && x > 0.0;
    match *m {
        Model::Tower { cells, levels, cell_mm, level_mm, taper } => {
            if cells == 0 || levels == 0 || !pos(cell_mm) || !pos(level_mm) {
                out.push("a tower needs at least one bay and one level, and sizes above 0 mm".into());
            }
            if !(taper.is_finite() && taper > 0.0 && taper <= 1.0) {
                out.push(format!("a taper of {taper} is not between 0 (a point) and 1 (straight)"));
            }
        }
        Model::Dome { radius_mm, rings, segments } => {
            if rings == 0 || segments < 3 || !pos(radius_mm) {
                out.push("a dome needs at least one ring, three segments and a radius above 0 mm".into());
            }
        }
        Model::Bridge { span_mm, panels, width_mm, height_mm } => {
            if panels == 0 || !pos(span_mm) || !pos(width_mm) || !pos(height_mm) {
                out.push("a bridge needs at least one panel and sizes above 0 mm".into());
            }
        }
    }
    if beam_count(m) > MAX_MODEL_BEAMS as f64 {
        out.push(format!("about {:.0} beams is more than {MAX_MODEL_BEAMS}: make it smaller", beam_count(m)));
    }
    out
}

struct Builder {
    joints: Vec<DVec3>,
    beams: Vec<[usize; 2]>,
}

impl Builder {
    fn joint(&mut self, p: DVec3) -> usize {
        self.joints.push(p);
        self.joints.len() - 1
    }
    fn beam(&mut self, a: usize, b: usize) {
        self.beams.push([a, b]);
    }
}

/// Builds the model (its grounded joints: those at z = 0).
pub fn build(m: &Model) -> Wireframe {
    let mut b = Builder { joints: Vec::new(), beams: Vec::new() };
    match *m {
        Model::Tower { cells, levels, cell_mm, level_mm, taper } => {
            let n = cells + 1;
            let id = |i: usize, j: usize, k: usize| (k * n + j) * n + i;
            for k in 0..=levels {
                let w = cell_mm * (1.0 - (1.0 - taper) * k as f64 / levels as f64);
                let half = w * cells as f64 / 2.0;
                for j in 0..n {
                    for i in 0..n {
                        b.joint(DVec3::new(i as f64 * w - half, j as f64 * w - half, k as f64 * level_mm));
                    }
                }
            }
            for k in 1..=levels {
                // Verticals and the level's grid.
                for j in 0..n {
                    for i in 0..n {
                        b.beam(id(i, j, k - 1), id(i, j, k));
                    }
                }
                for j in 0..n {
                    for i in 0..n {
                        if i + 1 < n {
                            b.beam(id(i, j, k), id(i + 1, j, k));
                        }
                        if j + 1 < n {
                            b.beam(id(i, j, k), id(i, j + 1, k));
                        }
                    }
                }
                // One diagonal per bay of each outer face, alternating direction by level.
                let flip = k % 2 == 0;
                for c in 0..cells {
                    let (a0, a1) = if flip { (c + 1, c) } else { (c, c + 1) };
                    b.beam(id(a0, 0, k - 1), id(a1, 0, k));
                    b.beam(id(a0, cells, k - 1), id(a1, cells, k));
                    b.beam(id(0, a0, k - 1), id(0, a1, k));
                    b.beam(id(cells, a0, k - 1), id(cells, a1, k));
                }
            }
        }
        Model::Dome { radius_mm, rings, segments } => {
            let ring = |b: &mut Builder, r: usize| -> Vec<usize> {
                // Latitude from 0 at the base to 80° at the top ring.
                let lat = (80.0f64).to_radians() * r as f64 / rings as f64;
                let (rc, z) = (radius_mm * libm::cos(lat), radius_mm * libm::sin(lat));
                let twist = if r % 2 == 1 { 0.5 } else { 0.0 };
                (0..segments)
                    .map(|s| {
                        let a = std::f64::consts::TAU * (s as f64 + twist) / segments as f64;
                        b.joint(DVec3::new(rc * libm::cos(a), rc * libm::sin(a), z))
                    })
                    .collect()
            };
            // Odd rings turn half a segment: each joint sits between two below it, and the
            // panels are triangles.
            let mut below = ring(&mut b, 0);
            for r in 1..=rings {
                let here = ring(&mut b, r);
                for s in 0..segments {
                    let (l, rr) = if r % 2 == 1 { (s, (s + 1) % segments) } else { ((s + segments - 1) % segments, s) };
                    b.beam(below[l], here[s]);
                    b.beam(below[rr], here[s]);
                    b.beam(here[s], here[(s + 1) % segments]);
                }
                below = here;
            }
        }
        Model::Bridge { span_mm, panels, width_mm, height_mm } => {
            let dx = span_mm / panels as f64;
            let leg = height_mm / 2.0;
            let mut bottom = [Vec::new(), Vec::new()];
            let mut top = [Vec::new(), Vec::new()];
            for (side, y) in [(0usize, -width_mm / 2.0), (1, width_mm / 2.0)] {
                for i in 0..=panels {
                    bottom[side].push(b.joint(DVec3::new(i as f64 * dx - span_mm / 2.0, y, leg)));
                }
                for i in 0..panels {
                    top[side].push(b.joint(DVec3::new((i as f64 + 0.5) * dx - span_mm / 2.0, y, leg + height_mm)));
                }
                for end in [0, panels] {
                    let foot = b.joint(DVec3::new(end as f64 * dx - span_mm / 2.0, y, 0.0));
                    b.beam(foot, bottom[side][end]);
                }
            }
            for side in 0..2 {
                for i in 0..panels {
                    b.beam(bottom[side][i], bottom[side][i + 1]);
                    b.beam(bottom[side][i], top[side][i]);
                    b.beam(top[side][i], bottom[side][i + 1]);
                    if i + 1 < panels {
                        b.beam(top[side][i], top[side][i + 1]);
                    }
                }
            }
            for i in 0..=panels {
                b.beam(bottom[0][i], bottom[1][i]);
            }
            for i in 0..panels {
                b.beam(top[0][i], top[1][i]);
            }
        }
    }
    let grounded: Vec<bool> = b.joints.iter().map(|p| p.z.abs() < 1e-9).collect();
    let joint_names = (0..b.joints.len()).map(|j| format!("joint {j}")).collect();
    let beam_names = (0..b.beams.len()).map(|e| format!("beam {e}")).collect();
    Wireframe {
        joints: b.joints,
        beams: b.beams,
        grounded,
        grounded_by_file: true,
        format: Format::Model,
        joint_names,
        beam_names,
        notes: Vec::new(),
        grounding: None,
    }
}

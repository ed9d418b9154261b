//! Generators of lattice-job inputs (see the module above): designs whose work grows with a
//! domain of `n` × a base area, and a surface mesh that is hostile to ray casting. Each is
//! deterministic; the bytes made grow at most linearly in `n`.

use crate::design::{Design, Job};
use crate::kinds::lattice::LatticeJob;
use crate::lattice::{Domain, Pattern};
use crate::nonplanar;
use crate::paths::Method;

/// A lattice design: `pattern` on a square of `side` mm (one layer), `method` with
/// `iterations` GIPPO iterations, 0.2 mm nozzle.
fn design(name: &str, side: f64, pattern: Pattern, method: Method, iterations: u32) -> Design {
    let mut j = LatticeJob { domain: Domain::Rectangle { width_mm: side, height_mm: side }, ..LatticeJob::default() };
    j.lattice.pattern = pattern;
    j.paths.method = method;
    j.paths.iterations = iterations;
    let mut d = Design { name: name.into(), job: Job::new("lattice", &j), ..Design::default() };
    d.printer.nozzle_diameter_mm = 0.2;
    d
}

/// The side of a square of `n` × 20 × 20 mm.
fn side(n: usize) -> f64 {
    20.0 * (n.max(1) as f64).sqrt()
}

/// The tester's slow case, at `n` × 400 mm²: a honeycomb of radius 0.2 mm (29 struts per
/// mm², under the per-layer limit up to a 200 mm square, n = 100) printed with GIPPO, 20
/// iterations (the paper's 500 multiply the GIPPO part by 25: over a 200 mm square that is
/// about 600M steps, minutes, which the estimate states and asks about).
pub fn fine_honeycomb_design(n: usize) -> String {
    design(&format!("fine-honeycomb-{n}"), side(n), Pattern::Honeycomb { hexagon_radius_mm: 0.2 }, Method::GippoMax, 20).to_json_pretty()
}

/// The same fine honeycomb (radius 0.2 mm, `n` × 400 mm²) for the minimum-path optimiser:
/// every node of a honeycomb is odd, so the matching pairs two thirds of the nodes.
pub fn fine_honeycomb_euler(n: usize) -> String {
    design(&format!("fine-honeycomb-euler-{n}"), side(n), Pattern::Honeycomb { hexagon_radius_mm: 0.2 }, Method::Euler, 1).to_json_pretty()
}

/// A Voronoi lattice (4 seed points per mm², irregular: the matching's 2-opt has the most to
/// do) on `n` × 400 mm², printed as continuous walks (Dijkstra pairing of its odd nodes).
pub fn voronoi_continuous_design(n: usize) -> String {
    design(&format!("voronoi-continuous-{n}"), side(n), Pattern::Voronoi { density_per_mm2: 4.0 }, Method::Continuous, 1).to_json_pretty()
}

/// A honeycomb (radius 1 mm, 28 layers) on `n` × 400 mm² projected onto a wide sphere with
/// the default longest segment (0.25 mm).
pub fn projected_honeycomb_design(n: usize) -> String {
    projected(n, nonplanar::DEFAULT_MAX_SEGMENT_MM)
}

/// The tester's out-of-memory case, at `n` × 400 mm²: the projected honeycomb with segments
/// of at most 0.01 mm (the smallest allowed). Points after splitting go as area × layers /
/// max_segment: about 2M per 400 mm², 200M (8 GB) over a 200 mm square (n = 100), which the
/// estimate refuses.
pub fn projected_honeycomb_fine_segments(n: usize) -> String {
    projected(n, 0.01)
}

fn projected(n: usize, max_segment_mm: f64) -> String {
    let mut d = design(&format!("projected-honeycomb-{n}"), side(n), Pattern::Honeycomb { hexagon_radius_mm: 1.0 }, Method::Euler, 1);
    let mut j: LatticeJob = d.job.settings().expect("a lattice job");
    j.lattice.layers = 28;
    j.nonplanar = Some(nonplanar::Options { surface: nonplanar::Surface::Sphere { radius_mm: 400.0, center_mm: [0.0, 0.0, -380.0] }, max_segment_mm });
    d.job = Job::new("lattice", &j);
    d.to_json_pretty()
}

/// A binary STL: a cone of radius 100 mm and height 30 mm made of `n` (≥ 3) triangles fanned
/// from its apex, and no base (a surface to print on). Hostile for vertical ray casts: every
/// triangle is a long thin wedge from the apex to the rim, so its bounding box covers up to a
/// quarter of the cone (bucketing triangles by box needed billions of entries at n = 100k)
/// and the cells near the apex are crossed by many wedges.
pub fn cone_fan_stl(n: usize) -> Vec<u8> {
    let n = n.max(3);
    let mut out = Vec::with_capacity(84 + 50 * n);
    out.extend_from_slice(&[0u8; 80]);
    out.extend_from_slice(&(n as u32).to_le_bytes());
    let rim = |k: usize| {
        let t = 2.0 * std::f64::consts::PI * (k % n) as f64 / n as f64;
        [(100.0 * libm::cos(t)) as f32, (100.0 * libm::sin(t)) as f32, 0.0f32]
    };
    for k in 0..n {
        out.extend_from_slice(&[0u8; 12]); // normal: recomputed by readers
        for v in [[0.0f32, 0.0, 30.0], rim(k), rim(k + 1)] {
            for c in v {
                out.extend_from_slice(&c.to_le_bytes());
            }
        }
        out.extend_from_slice(&[0u8; 2]);
    }
    out
}

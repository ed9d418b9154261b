//! The projection's statement of its work (issue 7): points after splitting, ray casts, the
//! mesh grid, peak memory and time, from the toolpath's size, the surface and the options,
//! without projecting anything.
//!
//! Points: every planar segment of length `l` is split into about `l · stretch / max_segment`
//! pieces (at least one), where `stretch` is the mean ratio of surface length to planar
//! length under the toolpath (1/cos of the slope: analytic for spheres and cylinders, area
//! over projected area of the upward faces for meshes); bisection makes pieces of 0.5–1
//! `max_segment`, [`PIECES_PER_LENGTH`] on average.

use super::surface::bucket_budget;
use super::{Options, Surface};
use crate::budget::Estimate;
use crate::geom::{DVec2, Mesh, Toolpath};

/// Pieces per `max_segment_mm` of surface length: the uniform split leaves pieces a little
/// under the longest, and the bisection halves those the surface stretches over it.
/// Measured with `cargo run --release --example lattice_calibrate nonplanar`: 1.1–2 on
/// spheres, cylinders and meshes (2 where struts are whole multiples of the longest segment:
/// every piece is split exactly at it, and the slightest slope bisects them all).
const PIECES_PER_LENGTH: f64 = 1.6;

// Times on the reference machine (one core, release), calibrated with
// `cargo run --release --example lattice_calibrate nonplanar` (CPU time of
// [`super::project`] over honeycomb lattices of 50–200 mm on spheres, a cylinder, a UV-sphere
// mesh and a cone fan).

/// Per output point on an analytic surface (a cast to lift it, one for the collision check
/// of the segment ending at it, the copy).
const POINT_ANALYTIC: f64 = 0.1e-6;
/// Per output point on a mesh, plus [`TRIANGLE_TEST`] per candidate triangle of its two casts.
const POINT_MESH: f64 = 0.15e-6;
/// Per candidate triangle tested by a cast (barycentric test).
const TRIANGLE_TEST: f64 = 0.008e-6;
/// Per mesh triangle: welding, normals, buckets.
const MESH_TRIANGLE: f64 = 1.0e-6;

/// Bytes per output point (the point, and the planar copy made per path).
const BYTES_PER_POINT: f64 = 24.0 + 16.0;
/// Bytes per output path (the `Path` and its heap blocks).
const BYTES_PER_PATH: f64 = 112.0;
/// Bytes per mesh triangle in the grid (corners, corner normals, the face records, the
/// vertex-to-face index) and per bucket entry.
const BYTES_PER_TRIANGLE: f64 = 152.0 + 64.0 + 24.0;
/// See [`BYTES_PER_TRIANGLE`].
const BYTES_PER_ENTRY: f64 = 4.0;

/// What the projection's estimate needs of its input toolpath.
#[derive(Clone, Debug, PartialEq)]
pub struct Work {
    /// Layers.
    pub layers: usize,
    /// Points in (paths' and approach routes'): the input's
    /// [`Toolpath::point_count`].
    pub points: f64,
    /// Paths.
    pub paths: f64,
    /// Planar length of every path and approach route, mm.
    pub length_mm: f64,
    /// XY box of the toolpath, mm.
    pub min: DVec2,
    /// See `min`.
    pub max: DVec2,
}

impl Work {
    /// The work of an actual toolpath (O(points)).
    pub fn of_toolpath(tp: &Toolpath) -> Work {
        let (mut length, mut paths) = (0.0, 0.0);
        let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
        for pass in &tp.passes {
            for p in &pass.paths {
                paths += 1.0;
                for w in p.points.windows(2) {
                    length += w[0].truncate().distance(w[1].truncate());
                }
                for q in p.points.iter().chain(p.approach.iter().flatten()) {
                    lo = lo.min(q.truncate());
                    hi = hi.max(q.truncate());
                }
                if let (Some(route), Some(first)) = (&p.approach, p.points.first()) {
                    let mut prev: Option<DVec2> = None;
                    for q in route.iter().chain(std::iter::once(first)) {
                        if let Some(a) = prev {
                            length += a.distance(q.truncate());
                        }
                        prev = Some(q.truncate());
                    }
                }
            }
        }
        if !lo.is_finite() {
            (lo, hi) = (DVec2::ZERO, DVec2::ZERO);
        }
        Work { layers: tp.passes.len(), points: tp.point_count() as f64, paths, length_mm: length, min: lo, max: hi }
    }

    /// The work the path optimiser's estimate states (its `layers`, `segments`, `paths` and
    /// `length_mm`) over a domain whose box is `min`–`max`.
    pub fn of_paths(e: &Estimate, min: DVec2, max: DVec2) -> Work {
        Work { layers: e.get("layers") as usize, points: e.get("segments"), paths: e.get("paths"), length_mm: e.get("length_mm"), min, max }
    }
}

/// What the projection's estimate needs of a mesh surface (O(triangles), nothing allocated).
#[derive(Clone, Debug, PartialEq)]
pub struct SurfaceSize {
    /// Triangles.
    pub triangles: f64,
    /// Mean surface length per planar length under the toolpath (area over projected area of
    /// the faces over its box).
    pub stretch: f64,
    /// Bucket entries of the cast grid (triangle-cell overlaps at the cell size it uses).
    pub entries: f64,
    /// Grid cells.
    pub cells: f64,
    /// Candidate triangles a cast under the toolpath's box tests, on average.
    pub candidates: f64,
}

impl SurfaceSize {
    /// The size of `mesh` as a surface under a toolpath whose box is `min`–`max`: each
    /// triangle's cells from its area and perimeter (a shape of area A and perimeter P meets
    /// about A/c² + 2P/(πc) + 1 cells of side c), the cell size as the grid picks it (coarser
    /// until the entries fit [`bucket_budget`]), the candidates per cast as the entries of the
    /// triangles over the box (each counted for the part of its extent over it) per cell of
    /// the box.
    pub fn of_mesh(mesh: &Mesh, min: DVec2, max: DVec2) -> SurfaceSize {
        let (mut area, mut projected, mut n) = (0.0, 0.0, 0usize);
        let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
        let tri = |t: &[u32; 3]| [mesh.vertex(t[0]), mesh.vertex(t[1]), mesh.vertex(t[2])];
        for t in &mesh.triangles {
            let v = tri(t);
            let c = (v[1] - v[0]).cross(v[2] - v[0]);
            if c.z.is_nan() || c.z.abs() <= 1e-14 {
                continue; // vertical or degenerate: no footprint
            }
            n += 1;
            let (tlo, thi) = (v[0].truncate().min(v[1].truncate()).min(v[2].truncate()), v[0].truncate().max(v[1].truncate()).max(v[2].truncate()));
            if tlo.x <= max.x && thi.x >= min.x && tlo.y <= max.y && thi.y >= min.y {
                area += 0.5 * c.length();
                projected += 0.5 * c.z.abs();
            }
            lo = lo.min(tlo);
            hi = hi.max(thi);
        }
        if n == 0 {
            return SurfaceSize { triangles: 0.0, stretch: 1.0, entries: 0.0, cells: 1.0, candidates: 0.0 };
        }
        let size = (hi - lo).max(DVec2::splat(1e-6));
        let mut cell = ((size.x * size.y / n as f64).sqrt() * 1.5).max(size.x.max(size.y) / 1024.0).max(1e-6);
        let budget = bucket_budget(n) as f64;
        // Cells a triangle meets, and those over the toolpath's box.
        let count = |cell: f64| -> (f64, f64) {
            let (mut all, mut over) = (0.0, 0.0);
            for t in &mesh.triangles {
                let v = tri(t);
                let c = (v[1] - v[0]).cross(v[2] - v[0]);
                if c.z.is_nan() || c.z.abs() <= 1e-14 {
                    continue;
                }
                let a = 0.5 * c.z.abs();
                let p = (v[1] - v[0]).truncate().length() + (v[2] - v[1]).truncate().length() + (v[0] - v[2]).truncate().length();
                let cells = a / (cell * cell) + 2.0 * p / (std::f64::consts::PI * cell) + 1.0;
                all += cells;
                let (tlo, thi) = (v[0].truncate().min(v[1].truncate()).min(v[2].truncate()), v[0].truncate().max(v[1].truncate()).max(v[2].truncate()));
                let ext = (thi - tlo).max(DVec2::splat(1e-9));
                let ov = (thi.min(max) - tlo.max(min)).max(DVec2::ZERO);
                if ov.x > 0.0 || ov.y > 0.0 || (tlo.x <= max.x && thi.x >= min.x && tlo.y <= max.y && thi.y >= min.y) {
                    over += cells * (ov.x / ext.x).max(ov.y / ext.y).clamp(0.0, 1.0).max(1.0 / cells);
                }
            }
            (all, over)
        };
        let (mut entries, mut over) = count(cell);
        while entries > budget && cell < size.max_element() {
            cell *= 1.1;
            (entries, over) = count(cell);
        }
        let nx = (size.x / cell).ceil().clamp(1.0, 1024.0);
        let ny = (size.y / cell).ceil().clamp(1.0, 1024.0);
        let box_cells = (((max.x - min.x) / cell).ceil().max(1.0) * ((max.y - min.y) / cell).ceil().max(1.0)).min(nx * ny);
        SurfaceSize {
            triangles: n as f64,
            stretch: if projected > 0.0 { area / projected } else { 1.0 },
            entries,
            cells: nx * ny,
            candidates: over / box_cells,
        }
    }
}

/// Mean of 1/cos(slope) over the part of a toolpath box `min`–`max` a sphere of radius `r`
/// centred at `(cx, cy)` (or a cylinder along X through Y = 0, `cylinder`) lies under, and 1
/// off it; capped at 3 (the bisection stops at the rim).
fn analytic_stretch(min: DVec2, max: DVec2, r: f64, centre: DVec2, cylinder: bool) -> f64 {
    let size = (max - min).max(DVec2::splat(1e-9));
    if cylinder {
        // Over |y| ≤ a: (R / a) asin(a / R); the band covers 2R of the box's height.
        let a = (size.y / 2.0).min(r);
        let s = if a > 0.0 { r / a * libm::asin((a / r).min(1.0)) } else { 1.0 };
        let f = (2.0 * r / size.y).min(1.0);
        return (f * s + (1.0 - f)).min(3.0);
    }
    // Over a disc of radius a ≤ R: 2R (R − √(R² − a²)) / a²; the disc covers πR² of the box.
    let far = (min - centre).abs().max((max - centre).abs()).length();
    let a = far.min(r);
    let s = if a > 0.0 { 2.0 * r * (r - (r * r - a * a).max(0.0).sqrt()) / (a * a) } else { 1.0 };
    let f = (std::f64::consts::PI * r * r / (size.x * size.y)).min(1.0);
    (f * s + (1.0 - f)).min(3.0)
}

/// States the projection's work (O(1)): quantities (keys) `layers`, `points` (output points
/// of paths and approach routes), `segments` (what the writer gets: the output's
/// [`Toolpath::point_count`]), `casts` (ray casts), `triangles` and `candidates` (meshes:
/// triangles and the candidates a cast tests); refused over the shared budgets with the
/// longest segment that would fit.
pub fn estimate(work: &Work, surface: Option<&SurfaceSize>, options: &Options) -> Estimate {
    let s = options.max_segment_mm;
    let stretch = match (&options.surface, surface) {
        (Surface::Sphere { radius_mm, center_mm }, _) => analytic_stretch(work.min, work.max, *radius_mm, DVec2::new(center_mm[0], center_mm[1]), false),
        (Surface::Cylinder { radius_mm, .. }, _) => analytic_stretch(work.min, work.max, *radius_mm, DVec2::ZERO, true),
        (Surface::Mesh, Some(m)) => m.stretch,
        (Surface::Mesh, None) => 1.0,
    };
    // Input segments (paths' and approach legs') each give at least one piece.
    let segments_in = (work.points - work.paths).max(0.0);
    let pieces = if s > 0.0 { (work.length_mm * stretch / s * PIECES_PER_LENGTH).max(segments_in) } else { f64::INFINITY };
    let points = pieces + work.paths;
    let casts = 2.0 * points + work.points;
    let (mut seconds, mut bytes) = (0.0, points * BYTES_PER_POINT + work.paths * BYTES_PER_PATH);
    let (triangles, candidates) = match (&options.surface, surface) {
        (Surface::Mesh, Some(m)) => {
            seconds += m.triangles * MESH_TRIANGLE + points * POINT_MESH + casts * m.candidates * TRIANGLE_TEST;
            bytes += m.triangles * BYTES_PER_TRIANGLE + m.entries * BYTES_PER_ENTRY + m.cells * 4.0;
            (m.triangles, m.candidates)
        }
        _ => {
            seconds += points * POINT_ANALYTIC;
            (0.0, 0.0)
        }
    };
    // The longest segment that fits: points go as 1 / max_segment.
    let over = (bytes / crate::budget::MAX_STAGE_BYTES).max(seconds / crate::budget::MAX_STAGE_SECONDS);
    let fix = if over > 1.0 && s.is_finite() {
        format!(
            "use a longest segment (max_segment_mm) ≥ {} mm, fewer layers or a smaller domain",
            crate::settings::fmt((s * over * 1.1 * 100.0).ceil() / 100.0)
        )
    } else {
        "use a longer max_segment_mm, fewer layers or a smaller domain".to_string()
    };
    Estimate::new("nonplanar")
        .quantity("layers", "Layers", work.layers as f64, "")
        .quantity("points", "Points after splitting", points, "")
        .quantity("segments", "Toolpath segments", points, "")
        .quantity("casts", "Ray casts", casts, "")
        .quantity("triangles", "Surface triangles", triangles, "")
        .quantity("candidates", "Triangles tested per cast", candidates, "")
        .cost(bytes, seconds)
        .budgets(&fix)
}

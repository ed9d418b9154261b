//! The slicer's statement of its work, from one pass over the mesh (no slicing).
//!
//! Layer count exact; contour segments = the triangles' layer crossings (each crossing is one
//! contour segment); infill from the mesh's volume and the mean chord of its layers (Cauchy:
//! π·area / perimeter), so a hollow or thin part is not charged like its bounding box.
//! Checked against real slices in `tests/it/estimates.rs`.

use super::{layer_stack_len, InfillPattern, Options, MAX_COORD_MM, MAX_LAYERS};
use crate::budget::Estimate;
use crate::geom::Mesh;

/// Time per outline point per polygon operation, s: each layer's outline is cut, stitched and
/// unioned, offset once per perimeter and for the infill area, and intersected with the
/// `solid_layers` layers above and below it (the solid-skin coverage). Measured with
/// `cargo run --release --example slice_bench` on the reference machine, one thread: 0.8 µs
/// on the hollow 100 mm cylinder of 512 facets, 0.3 µs on the 1M-triangle sphere (many short
/// outline segments), 2026-11-29; 1.2 µs was stated before the slicer's parallel rewrite.
const SECONDS_PER_OUTLINE_OP: f64 = 0.6e-6;
/// Outline operations a layer that support adds (see [`estimate`]): the 1M-triangle sphere
/// slices in 2.1× the time with support everywhere (3.47 s against 1.62 s, 2 threads).
const SUPPORT_OUTLINE_OPS: f64 = 10.0;
/// Time per output segment (infill lines, ordering), s (same measurement: 0.3–0.45 µs on
/// 100–150 mm cubes).
const SECONDS_PER_SEGMENT: f64 = 0.4e-6;
/// Peak bytes per contour segment: the sweep's segments, loops, i_overlay shapes of every layer
/// (kept for the solid-layer coverage) and their polygons in mm.
const BYTES_PER_CROSSING: f64 = 120.0;
/// Peak bytes per output segment: a toolpath point (24 bytes) plus path overhead and the
/// infill polylines before ordering.
const BYTES_PER_SEGMENT: f64 = 64.0;
/// Peak bytes per triangle: the sweep's order and per-triangle bounds.
const BYTES_PER_TRIANGLE: f64 = 24.0;
/// Time per segment of a gyroid or 3D honeycomb curve generated over a layer's bounding box
/// and clipped to its infill area, s: i_overlay's string clip dominates. An allowance (the
/// order of the outline operations' cost per point), not yet measured with `slice_bench`.
const SECONDS_PER_CLIPPED_SEGMENT: f64 = 1.0e-6;
/// Peak bytes per segment of one layer's generated curves: the points (8 bytes) and
/// i_overlay's segments, graph and output while clipping.
const BYTES_PER_CLIPPED_SEGMENT: f64 = 160.0;

/// Segments per mm of a sparse pattern's curves at cell size `cell_mm`: the gyroid's
/// bisection (at least 13 chords per cell length, and about `0.8 √(L / tolerance)`; measured
/// for L = 0.5–20 mm in `tests/it/infill_patterns.rs`), the honeycomb's two per grid unit
/// (`L / 2`), rectilinear's none beyond the one per line across the region.
fn segments_per_mm(pattern: InfillPattern, cell_mm: f64) -> f64 {
    match pattern {
        InfillPattern::Rectilinear => 0.0,
        InfillPattern::Gyroid => {
            let tol = super::gyroid::chord_tolerance_um(cell_mm * 1000.0) / 1000.0;
            (0.8 * (cell_mm / tol).sqrt()).max(13.0) / cell_mm
        }
        InfillPattern::Honeycomb3d => 4.0 / cell_mm,
    }
}

/// What a mesh measures for the estimate.
struct MeshStats {
    triangles: usize,
    /// Σ over triangles of the layers its Z span crosses (expected: span / layer height).
    crossings: f64,
    /// Enclosed volume, mm³ (absolute value of the signed sum).
    volume: f64,
    /// Area of the non-horizontal facets weighted by how vertical they are, mm² (the walls
    /// whose layer outlines are the perimeters).
    wall_area: f64,
    /// Horizontal projection of every facet, mm² (top and bottom surfaces: the solid skins).
    flat_area: f64,
    min: [f64; 3],
    max: [f64; 3],
}

/// Triangles a chunk of [`stats`]'s sums (fixed: the sums must not depend on the threads).
const STATS_CHUNK: usize = 1 << 16;

fn stats(mesh: &Mesh, layer_height: f64) -> MeshStats {
    let mut s = MeshStats {
        triangles: mesh.triangles.len(),
        crossings: 0.0,
        volume: 0.0,
        wall_area: 0.0,
        flat_area: 0.0,
        min: [f64::INFINITY; 3],
        max: [f64::NEG_INFINITY; 3],
    };
    for v in &mesh.vertices {
        for k in 0..3 {
            s.min[k] = s.min[k].min(v[k] as f64);
            s.max[k] = s.max[k].max(v[k] as f64);
        }
    }
    let v = |i: u32| mesh.vertices.get(i as usize).map_or([0.0; 3], |p| [p[0] as f64, p[1] as f64, p[2] as f64]);
    // Sums over fixed chunks of triangles, added in order: the same rounding at any thread
    // count (a 1M-triangle mesh is 16 chunks).
    let parts = crate::par::map_chunks(mesh.triangles.len(), STATS_CHUNK, |range| {
        let mut p = [0.0f64; 4]; // crossings, flat area, wall area, volume
        for t in &mesh.triangles[range] {
            let (a, b, c) = (v(t[0]), v(t[1]), v(t[2]));
            let (lo, hi) = (a[2].min(b[2]).min(c[2]), a[2].max(b[2]).max(c[2]));
            // The expected number of planes, spaced `layer_height`, that cut a span of this height.
            p[0] += (hi - lo) / layer_height;
            let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
            let w = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
            let n = [u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]];
            let area2 = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            p[1] += 0.5 * n[2].abs();
            p[2] += 0.5 * (area2 * area2 - n[2] * n[2]).max(0.0).sqrt();
            // Signed volume of the tetrahedron (origin, a, b, c).
            p[3] += (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0])) / 6.0;
        }
        p
    });
    for p in parts {
        s.crossings += p[0];
        s.flat_area += p[1];
        s.wall_area += p[2];
        s.volume += p[3];
    }
    s.volume = s.volume.abs();
    s
}

/// The slicer's work on `mesh` (placed: lowest point at Z = 0) with `options`: layers,
/// contour segments, toolpath segments and G-code bytes, peak memory and time; refused when a
/// coordinate is beyond [`MAX_COORD_MM`], the layers beyond [`MAX_LAYERS`], or the stage over
/// the shared budgets. O(triangles), on every thread; allocates only the partial sums.
pub fn estimate(mesh: &Mesh, options: &Options) -> Estimate {
    let o = options;
    let s = stats(mesh, o.layer_height_mm);
    let e = Estimate::new("slice").quantity("triangles", "Triangles", s.triangles as f64, "");
    if s.triangles == 0 {
        return e;
    }
    let reach = (0..3).map(|k| s.min[k].abs().max(s.max[k].abs())).fold(0.0, f64::max);
    let size = [s.max[0] - s.min[0], s.max[1] - s.min[1], s.max[2] - s.min[2]];
    let e = e.limit(
        "the mesh's farthest point from the plate centre",
        reach,
        MAX_COORD_MM,
        "mm",
        format!(
            "the mesh spans {} × {} × {} mm: check its units (a file in micrometres read as millimetres?) and scale it down",
            crate::settings::fmt(size[0]),
            crate::settings::fmt(size[1]),
            crate::settings::fmt(size[2])
        ),
    );
    if e.refused.is_some() {
        return e;
    }
    let layers = layer_stack_len(o, s.max[2]) as f64;
    let e = e.limit("layers", layers, MAX_LAYERS as f64, "", "use thicker layers (job.slice.layer_height_mm) or scale the part down");
    if e.refused.is_some() || layers == 0.0 {
        return e.quantity("layers", "Layers", layers, "");
    }
    let w = o.line_width_mm;
    let top = s.max[2].max(o.first_layer_height_mm);
    // Mean layer area and outline length, and the mean chord of a layer's region (Cauchy's
    // formula: π · area / perimeter; the bounding box's diagonal at most).
    let area = s.volume / top;
    let outline = s.wall_area / top;
    let diagonal = (size[0] * size[0] + size[1] * size[1]).sqrt().max(w);
    let chord = if outline > 0.0 { (std::f64::consts::PI * area / outline).clamp(w, diagonal) } else { diagonal };
    // Infill length: sparse over every layer's area, solid in the skins under and over every
    // flat surface (`solid_layers` deep) and all of it at density 1.
    let solid_depth = (o.solid_layers as f64 * o.layer_height_mm).min(top);
    let solid_volume = if o.infill_density >= 1.0 { s.volume } else { (s.flat_area * solid_depth).min(s.volume) };
    let sparse_volume = if o.infill_density > 0.0 && o.infill_density < 1.0 { s.volume - solid_volume } else { 0.0 };
    // A given cell size sets the sparse fraction: k_c·m × width / L.
    let pattern = o.infill_pattern;
    let (fraction, cell_mm) = match o.infill_cell_mm {
        Some(l) => ((pattern.length_per_area_factor() * w / l).min(1.0), l),
        None => (o.infill_density, pattern.cell_mm_for(o.infill_density, w)),
    };
    let sparse_mm = sparse_volume * fraction / (o.layer_height_mm * w);
    let infill_mm = solid_volume / (o.layer_height_mm * w) + sparse_mm;
    // Each infill line across the region is one segment and one connector; the connectors
    // follow the infill area's boundary, an outline of the layer's size.
    let infill_segments = if infill_mm > 0.0 { 2.0 * infill_mm / chord + 0.5 * s.crossings } else { 0.0 };
    // Curved patterns: their chords, and the curves generated over each layer's bounding box
    // before clipping (the box's area over the layer's).
    let per_mm = if sparse_mm > 0.0 { segments_per_mm(pattern, cell_mm) } else { 0.0 };
    let box_over_area = if area > 0.0 { (size[0] * size[1] / area).max(1.0) } else { 1.0 };
    let generated = sparse_mm * per_mm * box_over_area;
    // The largest layer's share: the whole bounding box (the curves cover it before clipping).
    let generated_per_layer = if per_mm > 0.0 { size[0] * size[1] * fraction / w * per_mm } else { 0.0 };
    let infill_segments = infill_segments + sparse_mm * per_mm;
    // Triangulated meshes cut two triangles per flat quad; the stitched outline keeps about
    // half of those points (collinear ones merge).
    let contour = 0.5 * s.crossings;
    let perimeter_segments = contour * o.perimeters as f64;
    let segments = perimeter_segments + infill_segments + layers;
    // Support: each layer's outline is offset and cut for its contact, its bridges and the
    // side gap, the carried support unioned, closed and cut, the interface gathered (about
    // SUPPORT_OUTLINE_OPS operations a layer), and the regions of every layer kept.
    let support = if o.support.enabled { 1.0 } else { 0.0 };
    let bytes = s.triangles as f64 * BYTES_PER_TRIANGLE
        + contour * BYTES_PER_CROSSING * (1.0 + 2.0 * support)
        + segments * BYTES_PER_SEGMENT
        + generated_per_layer * BYTES_PER_CLIPPED_SEGMENT;
    let outline_ops = 2.0 + o.perimeters as f64 + 2.0 * o.solid_layers as f64 + support * SUPPORT_OUTLINE_OPS;
    let seconds = contour * outline_ops * SECONDS_PER_OUTLINE_OP + segments * SECONDS_PER_SEGMENT + generated * SECONDS_PER_CLIPPED_SEGMENT;
    e.quantity("layers", "Layers", layers, "")
        .quantity("contour_segments", "Outline segments", contour, "")
        .quantity("extruded_mm", "Extrusion", outline * layers * o.perimeters as f64 + infill_mm, "mm")
        .quantity("segments", "Toolpath segments", segments, "")
        .cost(bytes, seconds)
        // Layers are sliced and filled side by side: 1.85× natively, 1.64× in the worker at
        // 2 threads (the 1M-triangle sphere).
        .parallel(0.85)
        .budgets(if o.infill_pattern == InfillPattern::Rectilinear && o.infill_cell_mm.is_none() {
            "use thicker layers (job.slice.layer_height_mm), less infill (job.slice.infill_density) or a smaller part"
        } else {
            "use thicker layers (job.slice.layer_height_mm), less infill (job.slice.infill_density), a larger infill cell (job.slice.infill_cell_mm) or a smaller part"
        })
}

//! The lattice stage's statement of its work (issue 7): layers, struts, lengths, peak memory
//! and time, from the domain's size and the options, without generating anything.
//!
//! Per-pattern densities come from [`PatternStats`]: the pattern generated on a sample square
//! of a fixed number of cells (a few hundred struts, whatever the cell size), so they follow
//! the generators exactly. The generated (uncropped) strut count per layer, which
//! [`MAX_STRUTS_PER_LAYER`] limits, is [`super::estimate_struts`] over the layer's box turned
//! into the pattern's frame and grown by a cell, as [`super::generate`] fills it.

use super::graph::Rect;
use super::{cell_length, estimate_struts, pattern_graph, Domain, LayerDomain, Options, Pattern, MAX_STRUTS_PER_LAYER};
use crate::budget::Estimate;
use crate::geom::{DVec2, Mesh};

/// Time per generated (uncropped) strut, s, by pattern, on the reference machine (one core,
/// release): generation, welding, cropping and the output strokes. Measured with
/// `cargo run --release --example lattice_calibrate lattice 40 80 160`: the CPU time of
/// [`super::generate`] on square domains of 40, 80 and 160 mm (10k–1M struts) divided by the
/// generated struts, rounded up from the largest (the cost per strut varies ±30 % with the
/// size as the layer outgrows the caches).
fn seconds_per_strut(p: &Pattern) -> f64 {
    match p {
        Pattern::Honeycomb { .. } => 0.5e-6,
        // The straight pattern's cost, plus `SECONDS_PER_CURVE_SEGMENT` per segment.
        Pattern::WavyHoneycomb { .. } => 0.5e-6 + p.segments_per_strut() as f64 * SECONDS_PER_CURVE_SEGMENT,
        Pattern::WavySquareGrid { .. } => 0.3e-6 + p.segments_per_strut() as f64 * SECONDS_PER_CURVE_SEGMENT,
        Pattern::Voronoi { .. } => 1.4e-6,
        Pattern::Penrose { .. } | Pattern::SnubSquare { .. } => 0.4e-6,
        Pattern::Arrowhead { .. } | Pattern::ReentrantHoneycomb { .. } => 0.4e-6,
        Pattern::SquareGrid { .. } | Pattern::TriangleGrid { .. } => 0.3e-6,
        // Lines: per line, plus `SECONDS_PER_LINE_MM` per mm of it.
        Pattern::Rectilinear { .. } => 2.0e-6,
    }
}

/// Time per segment of a curved strut (a sine, the segment's crop and trim, its point), s.
const SECONDS_PER_CURVE_SEGMENT: f64 = 0.15e-6;

/// Extra time per generated strut when printed loops (contours, handle outlines) guard the
/// layer (trimming struts out of their beads), s: measured as the difference between disc
/// domains with a contour and square ones.
const SECONDS_PER_GUARDED_STRUT: f64 = 0.15e-6;
/// Time per mm of a rectilinear line (cropping and trimming it along its length), s.
const SECONDS_PER_LINE_MM: f64 = 0.1e-6;
/// Time per output stroke of a layer copied from an identical earlier one, s.
const SECONDS_PER_COPIED_STROKE: f64 = 0.04e-6;
/// Time per outline point (contours, handle outlines and their trimming), s.
const SECONDS_PER_OUTLINE_POINT: f64 = 0.5e-6;

/// Bytes of one output stroke: the `Stroke` (vector header, feature) and its heap block of
/// two points with the allocator's overhead.
const BYTES_PER_STROKE: f64 = 32.0 + 32.0 + 16.0;
/// Bytes per generated strut while a layer is generated: its share of the points, the edge,
/// the weld index and the edge set (hash tables at most half full) and the cropping buffers.
const BYTES_PER_GENERATED_STRUT: f64 = 120.0;

/// What the lattice estimate needs of its domain (no layer is built).
#[derive(Clone, Debug, PartialEq)]
pub struct DomainSize {
    /// Layers.
    pub layers: usize,
    /// Every layer has the same regions and handles (planar domains): a layer with the same
    /// pattern and angle as an earlier one is copied, not generated.
    pub identical_layers: bool,
    /// Bounding box of every layer's regions together, mm.
    pub min: DVec2,
    /// See `min`.
    pub max: DVec2,
    /// Largest distance of a region point from the origin, mm: the pattern turns about the
    /// origin, so its fill box at any angle lies within ±`radius` (a disc's box does not grow
    /// when the pattern turns).
    pub radius: f64,
    /// Region area of the largest layer, mm².
    pub max_area_mm2: f64,
    /// Region area of all layers, mm².
    pub total_area_mm2: f64,
    /// Region outline length of all layers, mm (where struts are cropped).
    pub outline_mm: f64,
    /// Region outline points of all layers (the contour strokes' points).
    pub outline_points: f64,
    /// Handle area of all layers, mm².
    pub handle_area_mm2: f64,
    /// Handle outline points of all layers.
    pub handle_points: f64,
    /// Handles' heights (Y extents) of all layers, mm: fill lines run along X, a line width
    /// apart.
    pub handle_height_mm: f64,
}

impl DomainSize {
    /// The size of actual layers (O(points)).
    pub fn of_layers(domains: &[LayerDomain]) -> DomainSize {
        let mut s = DomainSize::empty(domains.len());
        s.identical_layers = domains.iter().all(|d| d.regions == domains[0].regions && d.handles == domains[0].handles);
        let mut bbox: Option<Rect> = None;
        for d in domains {
            let mut area = 0.0;
            for p in &d.regions {
                area += p.area();
                for ring in std::iter::once(&p.outer).chain(p.holes.iter()) {
                    s.outline_points += ring.len() as f64;
                    s.outline_mm += ring_length(ring);
                    s.radius = ring.iter().map(|q| q.length()).fold(s.radius, f64::max);
                    if let Some(r) = Rect::of_points(ring.iter()) {
                        bbox = Some(bbox.map_or(r, |b| Rect { min: b.min.min(r.min), max: b.max.max(r.max) }));
                    }
                }
            }
            s.max_area_mm2 = s.max_area_mm2.max(area);
            s.total_area_mm2 += area;
            for h in &d.handles {
                s.handle_area_mm2 += h.area();
                s.handle_points += h.outer.len() as f64 + h.holes.iter().map(|r| r.len() as f64).sum::<f64>();
                if let Some(r) = Rect::of_points(h.outer.iter()) {
                    s.handle_height_mm += r.max.y - r.min.y;
                }
            }
        }
        if let Some(b) = bbox {
            (s.min, s.max) = (b.min, b.max);
        }
        s
    }

    /// The size of a planar domain's layers, from its dimensions.
    pub fn planar(domain: &Domain, options: &Options) -> DomainSize {
        let layers = options.layers as usize;
        let mut s = DomainSize::empty(layers);
        let n = layers as f64;
        let ok = |v: f64| v.is_finite() && v > 0.0;
        let rect = |s: &mut DomainSize, w: f64, h: f64| {
            (s.min, s.max) = (DVec2::new(-w / 2.0, -h / 2.0), DVec2::new(w / 2.0, h / 2.0));
            s.radius = 0.5 * (w * w + h * h).sqrt();
            s.max_area_mm2 = w * h;
            s.outline_mm = n * 2.0 * (w + h);
            s.outline_points = n * 4.0;
        };
        match *domain {
            Domain::Solid => {}
            Domain::Rectangle { width_mm, height_mm } if ok(width_mm) && ok(height_mm) => rect(&mut s, width_mm, height_mm),
            Domain::Disc { diameter_mm } if ok(diameter_mm) => {
                let r = diameter_mm / 2.0;
                (s.min, s.max, s.radius) = (DVec2::splat(-r), DVec2::splat(r), r);
                s.max_area_mm2 = std::f64::consts::PI * r * r;
                s.outline_mm = n * 2.0 * std::f64::consts::PI * r;
                s.outline_points = n * super::disc_sides(r) as f64;
            }
            Domain::TensileSpecimen { width_mm, length_mm, handle_length_mm } if ok(width_mm) && ok(length_mm) => {
                rect(&mut s, length_mm, width_mm);
                if ok(handle_length_mm) {
                    let l = length_mm + 2.0 * handle_length_mm;
                    s.radius = 0.5 * (l * l + width_mm * width_mm).sqrt();
                    s.handle_area_mm2 = n * 2.0 * width_mm * handle_length_mm;
                    s.handle_points = n * 8.0;
                    s.handle_height_mm = n * 2.0 * width_mm;
                }
            }
            _ => {}
        }
        s.total_area_mm2 = n * s.max_area_mm2;
        s
    }

    /// The size of the layers a solid slices into every `layer_thickness_mm`, from the mesh
    /// (O(triangles), nothing sliced): the box; the largest layer's area at most the mesh's
    /// footprint (the area of its upward faces seen from above); the total area its volume
    /// over the thickness (the mean cross-section times the layers); outline length and
    /// points from the faces' slopes and heights (each face is cut by every plane it spans).
    pub fn of_mesh(mesh: &Mesh, layer_thickness_mm: f64) -> DomainSize {
        let t = layer_thickness_mm;
        let Some(b) = mesh.bounds() else { return DomainSize::empty(0) };
        let height = b.size().z;
        let layers = if t > 0.0 && height.is_finite() { libm::floor(height / t + 0.5).max(1.0) } else { 0.0 };
        let mut s = DomainSize::empty(layers.min(u32::MAX as f64) as usize);
        (s.min, s.max) = (b.min.truncate(), b.max.truncate());
        s.radius = s.min.abs().max(s.max.abs()).length();
        let (mut footprint, mut volume, mut cut, mut crossings) = (0.0, 0.0, 0.0, 0.0);
        for tri in &mesh.triangles {
            let [a, bb, c] = [mesh.vertex(tri[0]), mesh.vertex(tri[1]), mesh.vertex(tri[2])];
            let n = (bb - a).cross(c - a);
            volume += a.dot(bb.cross(c)) / 6.0;
            footprint += (0.5 * n.z).max(0.0);
            // Cut length summed over the planes: the face's area times its steepness over t.
            cut += 0.5 * (n.x * n.x + n.y * n.y).sqrt() / t;
            let (zlo, zhi) = (a.z.min(bb.z).min(c.z), a.z.max(bb.z).max(c.z));
            crossings += (zhi - zlo) / t;
        }
        let box_area = (s.max.x - s.min.x) * (s.max.y - s.min.y);
        s.max_area_mm2 = if footprint > 0.0 { footprint.min(box_area) } else { box_area };
        let by_volume = volume.abs() / t;
        s.total_area_mm2 = if by_volume.is_finite() && by_volume > 0.0 { by_volume.min(layers * s.max_area_mm2) } else { layers * s.max_area_mm2 };
        s.outline_mm = cut;
        s.outline_points = crossings;
        s
    }

    fn empty(layers: usize) -> DomainSize {
        DomainSize {
            layers,
            identical_layers: false,
            min: DVec2::ZERO,
            max: DVec2::ZERO,
            radius: 0.0,
            max_area_mm2: 0.0,
            total_area_mm2: 0.0,
            outline_mm: 0.0,
            outline_points: 0.0,
            handle_area_mm2: 0.0,
            handle_points: 0.0,
            handle_height_mm: 0.0,
        }
    }
}

fn ring_length(ring: &[DVec2]) -> f64 {
    let n = ring.len();
    (0..n).map(|i| ring[i].distance(ring[(i + 1) % n])).sum()
}

/// A pattern's densities, per mm² of area (lines per mm of height for rectilinear).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PatternStats {
    /// Struts per mm².
    pub struts_per_mm2: f64,
    /// Strut length per mm², mm.
    pub length_per_mm2: f64,
    /// Odd-degree nodes per mm² (before cropping).
    pub odd_per_mm2: f64,
}

impl PatternStats {
    /// Measured on the pattern generated over a sample square of a fixed number of cells
    /// (Voronoi with seed 1); rectilinear lines analytically.
    pub fn of(p: &Pattern) -> PatternStats {
        if let Pattern::Rectilinear { strand_distance_mm: s } = *p {
            // Per line of length L: one strut, L of strut, two odd ends (per mm² of a square
            // domain of side L: 1 / (s L) struts; the caller adds the line count).
            return PatternStats { struts_per_mm2: 0.0, length_per_mm2: 1.0 / s, odd_per_mm2: 0.0 };
        }
        let c = cell_length(p);
        // 12 cells across, counted in the middle 8 (no edge effects), off-centre.
        let h = 6.0 * c;
        let at = DVec2::new(0.37 * c, 0.21 * c);
        let rect = Rect { min: at - DVec2::splat(h), max: at + DVec2::splat(h) };
        let inner = Rect { min: at - DVec2::splat(4.0 * c), max: at + DVec2::splat(4.0 * c) };
        let Ok(g) = pattern_graph(p, rect, 1) else {
            return PatternStats { struts_per_mm2: 0.0, length_per_mm2: 0.0, odd_per_mm2: 0.0 };
        };
        let inside = |q: DVec2| q.x >= inner.min.x && q.x < inner.max.x && q.y >= inner.min.y && q.y < inner.max.y;
        let mut degree = vec![0u32; g.pts.len()];
        let (mut struts, mut length) = (0.0, 0.0);
        for e in &g.edges {
            let (a, b) = (g.pts[e[0] as usize], g.pts[e[1] as usize]);
            degree[e[0] as usize] += 1;
            degree[e[1] as usize] += 1;
            if inside((a + b) * 0.5) {
                struts += 1.0;
                length += g.curve.map_or_else(|| a.distance(b), |c| c.length(a, b));
            }
        }
        let odd = (0..g.pts.len()).filter(|&v| degree[v] % 2 == 1 && inside(g.pts[v])).count() as f64;
        let area = inner.area();
        PatternStats { struts_per_mm2: struts / area, length_per_mm2: length / area, odd_per_mm2: odd / area }
    }
}

/// The stats of `p`, measured once per pattern.
fn stat<'a>(stats: &mut Vec<(&'a Pattern, PatternStats)>, p: &'a Pattern) -> PatternStats {
    if let Some((_, s)) = stats.iter().find(|(q, _)| *q == p) {
        return *s;
    }
    let s = PatternStats::of(p);
    stats.push((p, s));
    s
}

/// The pattern of layer `i` (its override, the last one listed winning, else the options').
fn layer_pattern(options: &Options, i: usize) -> &Pattern {
    options.overrides.iter().rev().find(|o| o.layer as usize == i).map(|o| &o.pattern).unwrap_or(&options.pattern)
}

/// The regions' box in the frame of a pattern turned by `angle_deg`, grown by a cell (what
/// [`super::generate`] fills), bounded by the box turned and by the ±`radius` square.
fn fill_rect(size: &DomainSize, p: &Pattern, angle_deg: f64) -> Rect {
    let rad = angle_deg.to_radians();
    let (c, s) = if angle_deg == 0.0 { (1.0, 0.0) } else { (libm::cos(rad), libm::sin(rad)) };
    let corners = [size.min, DVec2::new(size.max.x, size.min.y), size.max, DVec2::new(size.min.x, size.max.y)];
    let back = corners.map(|q| DVec2::new(c * q.x + s * q.y, -s * q.x + c * q.y));
    let r = Rect::of_points(back.iter()).unwrap_or(Rect { min: DVec2::ZERO, max: DVec2::ZERO });
    let round = DVec2::splat(size.radius);
    let r = Rect { min: r.min.max(-round), max: r.max.min(round) };
    r.grown(cell_length(p))
}

/// The smallest size parameter of `p` whose struts over the same area fit `limit`, as the
/// change a user makes ("use a hexagon radius ≥ 0.6 mm"); `struts` is the estimate now.
pub(crate) fn denser_fix(p: &Pattern, struts: f64, limit: f64) -> String {
    // Struts go as 1 / size² (1 / size for lines); 5 % over for the margin a cell grows.
    let k = (struts / limit).sqrt() * 1.05;
    let up = |v: f64| {
        // Two significant figures, rounded up.
        let e = libm::pow(10.0, libm::floor(libm::log10(v)) - 1.0);
        crate::settings::fmt(libm::ceil(v / e) * e)
    };
    match *p {
        Pattern::Honeycomb { hexagon_radius_mm } | Pattern::WavyHoneycomb { hexagon_radius_mm, .. } => {
            format!("use a hexagon radius ≥ {} mm or a smaller domain", up(hexagon_radius_mm * k))
        }
        Pattern::Voronoi { density_per_mm2 } => {
            let e = libm::pow(10.0, libm::floor(libm::log10(density_per_mm2 / (k * k))) - 1.0);
            format!("use at most {} seed points per mm² or a smaller domain", crate::settings::fmt(libm::floor(density_per_mm2 / (k * k) / e) * e))
        }
        Pattern::Penrose { cell_size_mm }
        | Pattern::SnubSquare { cell_size_mm }
        | Pattern::SquareGrid { cell_size_mm }
        | Pattern::TriangleGrid { cell_size_mm }
        | Pattern::WavySquareGrid { cell_size_mm, .. } => {
            format!("use cells ≥ {} mm or a smaller domain", up(cell_size_mm * k))
        }
        Pattern::Arrowhead { cell_width_mm, cell_height_mm } | Pattern::ReentrantHoneycomb { cell_width_mm, cell_height_mm } => {
            format!("use unit cells ≥ {} × {} mm or a smaller domain", up(cell_width_mm * k), up(cell_height_mm * k))
        }
        Pattern::Rectilinear { strand_distance_mm } => {
            format!("use a strand distance ≥ {} mm or a smaller domain", up(strand_distance_mm * struts / limit * 1.05))
        }
    }
}

/// States the lattice stage's work on a domain of `size` (O(layers)): what it makes, its peak
/// memory and its time, refused over [`MAX_STRUTS_PER_LAYER`] or the shared budgets.
///
/// Quantities (keys): `layers`; `struts` (cropped struts on the densest layer) and
/// `struts_total` (all layers); `strut_mm` (mean strut length); `generated_struts` (struts
/// generated on the densest layer before cropping: the limited count); `length_mm` (printed
/// length of all layers: struts, contours, handles); `edges` and `edges_max_layer` (stroke
/// segments, all layers and the largest layer: the path optimiser's input; a curved strut
/// counts its `samples_per_strut` segments);
/// `odd_nodes` (odd-degree nodes of all layers' graphs, struts cut at the outline included).
pub fn estimate(size: &DomainSize, options: &Options, line_width_mm: f64) -> Estimate {
    let n = size.layers;
    let mut stats: Vec<(&Pattern, PatternStats)> = Vec::new();
    let mean_area = if n > 0 { size.total_area_mm2 / n as f64 } else { 0.0 };
    let outline_per_layer = if n > 0 { size.outline_mm / n as f64 } else { 0.0 };
    // Layers generated (a planar layer with an earlier layer's pattern and angle is copied:
    // generate() caches the first 16 distinct ones).
    let mut cached: Vec<(&Pattern, f64)> = Vec::new();
    let (mut densest, mut densest_struts, mut densest_pattern) = (0.0f64, 0.0f64, &options.pattern);
    let (mut struts_total, mut length, mut odd, mut seconds, mut copied) = (0.0, 0.0, 0.0, 0.0, 0.0);
    let mut gen_max = 0.0f64;
    // Stroke segments (points beyond each stroke's first) of the lattice struts: one per
    // straight strut, `samples_per_strut` per curved one.
    let (mut strut_segments, mut segments_max_layer) = (0.0f64, 0.0f64);
    for i in 0..n {
        let p = layer_pattern(options, i);
        let angle = (options.rotation_deg * i as f64).rem_euclid(360.0);
        let st = stat(&mut stats, p);
        let fill = fill_rect(size, p, angle);
        let (struts, len, odd_here) = match *p {
            Pattern::Rectilinear { strand_distance_mm: s } => {
                // Lines across the regions' height in the pattern's frame.
                let lines = ((fill.max.y - fill.min.y - 2.0 * cell_length(p)) / s).max(0.0) + 1.0;
                (lines, mean_area / s, 2.0 * lines)
            }
            _ => {
                // Struts cut by the outline: Buffon's 2/π crossings per unit of outline and
                // strut length per area; each leaves a degree-1 end.
                let cut = outline_per_layer * st.length_per_mm2 * 2.0 / std::f64::consts::PI;
                (st.struts_per_mm2 * mean_area + 0.5 * cut, st.length_per_mm2 * mean_area, st.odd_per_mm2 * mean_area + cut)
            }
        };
        let peak_struts = match *p {
            Pattern::Rectilinear { .. } => struts,
            _ => struts * if mean_area > 0.0 { size.max_area_mm2 / mean_area } else { 1.0 },
        };
        if peak_struts > densest_struts {
            densest_struts = peak_struts;
        }
        struts_total += struts;
        let per = p.segments_per_strut() as f64;
        strut_segments += struts * per;
        segments_max_layer = segments_max_layer.max(peak_struts * per);
        length += len;
        odd += odd_here;
        let generated = estimate_struts(p, fill);
        if generated > densest || generated.is_nan() {
            (densest, densest_pattern) = (generated, p);
        }
        let hit = size.identical_layers && cached.iter().any(|(q, a)| *q == p && *a == angle);
        if hit {
            copied += struts;
        } else {
            if size.identical_layers && cached.len() < 16 {
                cached.push((p, angle));
            }
            let guarded = options.contour || size.handle_points > 0.0;
            seconds += generated * (seconds_per_strut(p) + if guarded { SECONDS_PER_GUARDED_STRUT } else { 0.0 });
            if let Pattern::Rectilinear { .. } = p {
                seconds += generated * (size.max.x - size.min.x + size.max.y - size.min.y) * SECONDS_PER_LINE_MM;
            }
            gen_max = gen_max.max(generated);
        }
    }
    // Contours (when asked for) and handles: outline points, and handle fill lines one line
    // width apart (a stroke each).
    let contour_points = if options.contour { size.outline_points } else { 0.0 };
    let handle_lines = if line_width_mm > 0.0 { size.handle_area_mm2 / line_width_mm } else { 0.0 };
    let handle_strokes = if line_width_mm > 0.0 { size.handle_height_mm / line_width_mm } else { 0.0 };
    let extra_edges = contour_points + size.handle_points + handle_strokes;
    let strut_mm = if struts_total > 0.0 { length / struts_total } else { 0.0 };
    if options.contour {
        length += size.outline_mm;
    }
    length += handle_lines;
    let edges = strut_segments + extra_edges;
    let per_layer_extra = if n > 0 { extra_edges / n as f64 } else { 0.0 };
    let strokes = struts_total + handle_strokes + if options.contour { n as f64 } else { 0.0 };
    seconds += copied * SECONDS_PER_COPIED_STROKE
        + (contour_points + size.handle_points) * SECONDS_PER_OUTLINE_POINT
        + handle_strokes * seconds_per_strut(&Pattern::Rectilinear { strand_distance_mm: 1.0 });
    // The output strokes, the contour strokes' points, the domains' polygons and the graph of
    // the largest generated layer.
    // Curved struts hold `samples_per_strut + 1` points instead of two.
    let bytes = strokes * BYTES_PER_STROKE
        + (strut_segments - struts_total).max(0.0) * 16.0
        + (contour_points + size.handle_points) * 16.0
        + (size.outline_points + size.handle_points) * 16.0
        + gen_max * BYTES_PER_GENERATED_STRUT;
    Estimate::new("lattice")
        .quantity("layers", "Layers", n as f64, "")
        .quantity("struts", "Struts on the densest layer", densest_struts, "")
        .quantity("struts_total", "Struts (all layers)", struts_total, "")
        .quantity("strut_mm", "Mean strut length", strut_mm, "mm")
        .quantity("generated_struts", "Struts generated on the densest layer (before cropping)", densest, "")
        .quantity("length_mm", "Printed length (all layers)", length, "mm")
        .quantity("edges", "Stroke segments (all layers)", edges, "")
        .quantity("edges_max_layer", "Stroke segments on the largest layer", segments_max_layer + per_layer_extra, "")
        .quantity("odd_nodes", "Odd-degree nodes (all layers)", odd, "")
        .cost(bytes, seconds)
        .limit("struts on one layer", densest, MAX_STRUTS_PER_LAYER as f64, "", denser_fix(densest_pattern, densest, MAX_STRUTS_PER_LAYER as f64))
        .budgets("use larger cells, fewer layers or a smaller domain")
}

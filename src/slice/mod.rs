//! Planar slicing: mesh → closed regions per layer → perimeters and rectilinear infill.
//!
//! Entry: [`slice`]. Regions are computed in integer micrometres with i_overlay, so
//! overlapping shells union and results are identical on every target.
//!
//! Pipeline (one file per step):
//! - `plane`: a Z sweep over the triangles sorted by lowest Z hands each cutting plane only
//!   the triangles spanning it; each is cut into an oriented segment (solid on the left),
//!   with vertices exactly on the plane treated as slightly above it.
//! - `stitch`: segments → loops by exact micrometre endpoints, then open ends joined across
//!   gaps up to `gap_closing_mm`; what still cannot close is dropped and counted.
//! - `regions`: loops → polygons with holes by a NonZero union (overlapping shells merge).
//! - `perimeters`: inward offsets for the perimeter loops and the infill area.
//! - `infill`: rectilinear lines on a global grid, linked zig-zag along the area boundary.
//! - `bridge`: the solid area's pieces over air, crossed by straight lines anchored on the
//!   layer below at both ends (`Feature::Bridge`); cantilevers are left as they are.
//! - `gyroid`, `honeycomb3d`: the other sparse infill patterns ([`InfillPattern`]), curves
//!   over the area's bounding box clipped to it.
//! - `overhang`: the stretches of perimeter loops that hang over the layer below.
//! - `order`: print order and seams ([`Seam`]).
//!
//! Layers: the first layer's top is at `first_layer_height_mm`, then every `layer_height_mm`;
//! each layer is cut at its middle, and layers are made while that middle is below the top
//! of the mesh.

mod anchor;
pub(crate) mod bridge;
mod estimate;
pub mod gyroid;
pub mod gyroid_graded;
pub mod honeycomb3d;
mod infill;
mod order;
mod overhang;
mod perimeters;
mod plane;
mod regions;
mod skirt;
mod stitch;
pub mod support;

use crate::geom::tolerance::UNITS_PER_MM;
use crate::geom::{DVec2, Feature, Mesh, Pass, Polygon, Toolpath};
use crate::settings::{choice_docs, int, num, other, percent, Field, Kind};
use i_overlay::i_shape::int::shape::{IntShape, IntShapes};
use serde::{Deserialize, Serialize};

pub use estimate::estimate;

/// Most layers a slice may have ([`Error::TooManyLayers`] beyond).
pub const MAX_LAYERS: usize = 100_000;
/// Farthest a mesh point may lie from the plate centre, mm (100 m). Regions are computed in
/// integer micrometres (i32: ±2,147 m) and their offsets and areas multiply coordinates; a
/// mesh beyond this is almost always in the wrong units, and no printer is this big.
pub const MAX_COORD_MM: f64 = 100_000.0;

/// Default first layer height, mm.
pub const DEFAULT_FIRST_LAYER_HEIGHT_MM: f64 = 0.2;
/// Default layer height, mm.
pub const DEFAULT_LAYER_HEIGHT_MM: f64 = 0.2;
/// Default number of perimeter loops.
pub const DEFAULT_PERIMETERS: u32 = 2;
/// Default extrusion width of perimeters and infill, mm (the usual 0.4 mm nozzle).
pub const DEFAULT_LINE_WIDTH_MM: f64 = 0.4;
/// Default sparse infill density (fraction of the area, 0–1).
pub const DEFAULT_INFILL_DENSITY: f64 = 0.2;
/// Default infill angle on even layers, degrees; odd layers add 90°.
pub const DEFAULT_INFILL_ANGLE_DEG: f64 = 45.0;
/// Default distance under which open contour ends are joined, mm.
pub const DEFAULT_GAP_CLOSING_MM: f64 = 0.05;
/// Default skirt loops.
pub const DEFAULT_SKIRT_LOOPS: u32 = 1;
/// Default gap between the skirt and the part (or its brim), mm.
pub const DEFAULT_SKIRT_DISTANCE_MM: f64 = 3.0;
/// Default brim width, mm (none).
pub const DEFAULT_BRIM_WIDTH_MM: f64 = 0.0;
/// Default number of solid layers at the bottom and at the top.
pub const DEFAULT_SOLID_LAYERS: u32 = 3;

/// Largest unit cell of the sparse infill, mm ([`Options::infill_cell_mm`]).
pub const MAX_INFILL_CELL_MM: f64 = 1000.0;
/// Smallest unit cell of the sparse infill, mm.
pub const MIN_INFILL_CELL_MM: f64 = 0.1;

/// The sparse infill's pattern. Solid infill (skins) is always rectilinear.
///
/// Each is modelled as in section 2.2.1 of the CT-graded scaffolds paper: toolpath length per
/// unit layer area `k_c · m / L` for unit cell size `L` ([`InfillPattern::length_per_area_factor`]
/// is this implementation's `k_c · m`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum InfillPattern {
    /// Straight lines, turned 90° every layer (`L` = √2 × the line spacing).
    #[default]
    Rectilinear,
    /// Sections of the gyroid surface: wavy lines that change with height (`L`: its period).
    Gyroid,
    /// Sections of a truncated-octahedron tessellation: zig-zags that change with height, along
    /// X and along Y on alternate layers (`L`: their period across the lines).
    Honeycomb3d,
}

/// Names of the patterns as written in a design, in [`InfillPattern`] order.
pub const INFILL_PATTERNS: &[&str] = &["rectilinear", "gyroid", "honeycomb3d"];

impl InfillPattern {
    /// Name as written in a design (`"gyroid"`).
    pub fn label(self) -> &'static str {
        match self {
            InfillPattern::Rectilinear => INFILL_PATTERNS[0],
            InfillPattern::Gyroid => INFILL_PATTERNS[1],
            InfillPattern::Honeycomb3d => INFILL_PATTERNS[2],
        }
    }

    /// Mean toolpath length per unit layer area times the unit cell size `L`: the paper's
    /// `k_c · m` (table 1) as this implementation draws the pattern, measured in
    /// `tests/it/infill_patterns.rs` (mean over layers for the patterns that change with height).
    /// Rectilinear √2 = 1.4142 (table 1: 0.707 × 2, the same); gyroid 2.4586 (table 1: 2.442,
    /// 0.7 % less); 3D honeycomb 2 + (√2 − 1)/2 = 2.2071 (table 1: 2.022; PrusaSlicer's
    /// geometry with `L` its period across the lines gives 9 % more than the table).
    pub fn length_per_area_factor(self) -> f64 {
        match self {
            InfillPattern::Rectilinear => std::f64::consts::SQRT_2,
            InfillPattern::Gyroid => gyroid::LENGTH_PER_AREA_FACTOR,
            InfillPattern::Honeycomb3d => honeycomb3d::LENGTH_PER_AREA_FACTOR,
        }
    }

    /// The unit cell size, mm, at which lines `line_width_mm` wide fill the fraction `density`
    /// of the area (length × width / area): `k_c · m · width / density`.
    pub fn cell_mm_for(self, density: f64, line_width_mm: f64) -> f64 {
        self.length_per_area_factor() * line_width_mm / density
    }

    fn is_default(&self) -> bool {
        *self == InfillPattern::default()
    }
}

/// Where each perimeter loop starts (and ends): the seam, a small blemish on the wall.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Seam {
    /// The seams of successive layers line up in one vertical line, in a concave corner
    /// where the outline has one (PrusaSlicer's "aligned").
    #[default]
    Aligned,
    /// At the rear-most point of each loop (largest Y).
    Rear,
    /// At the loop's vertex nearest the nozzle (the shortest travel).
    Nearest,
    /// At a point along the loop chosen pseudo-randomly from the layer and the loop (the same
    /// on every run).
    Random,
}

/// Names of the seam positions as written in a design, in [`Seam`] order.
pub const SEAMS: &[&str] = &["aligned", "rear", "nearest", "random"];

impl Seam {
    /// Name as written in a design (`"rear"`).
    pub fn label(self) -> &'static str {
        match self {
            Seam::Aligned => SEAMS[0],
            Seam::Rear => SEAMS[1],
            Seam::Nearest => SEAMS[2],
            Seam::Random => SEAMS[3],
        }
    }
}

/// Slicing options (the `slice` job's settings in a Design).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Options {
    /// Height of the first layer, mm. Default 0.2.
    pub first_layer_height_mm: f64,
    /// Height of every other layer, mm. Default 0.2.
    pub layer_height_mm: f64,
    /// Perimeter loops per region. Default 2.
    pub perimeters: u32,
    /// Extrusion width of perimeters and infill, mm. Default 0.4.
    pub line_width_mm: f64,
    /// Sparse infill density, 0 (hollow) to 1 (solid). Default 0.2.
    pub infill_density: f64,
    /// Infill direction on even layers in degrees; odd layers are rotated 90°. Default 45.
    pub infill_angle_deg: f64,
    /// Solid layers at the bottom and at the top of the part. Default 3.
    pub solid_layers: u32,
    /// Open contour ends closer than this are joined (and reported), mm. Default 0.05.
    pub gap_closing_mm: f64,
    /// Skirt loops around the first layer, printed first to prime the nozzle; 0: none.
    /// Default 1.
    pub skirt_loops: u32,
    /// Gap between the skirt and the part (or its brim), mm. Default 3.
    pub skirt_distance_mm: f64,
    /// Brim: loops of this width around the first layer, touching the part, so it holds to
    /// the bed, mm; 0: none. Default 0.
    pub brim_width_mm: f64,
    /// Support under overhangs (off by default).
    pub support: support::Options,
    /// Pattern of the sparse infill. Default rectilinear (not written then, so designs without
    /// it read and hash as before).
    #[serde(skip_serializing_if = "InfillPattern::is_default")]
    pub infill_pattern: InfillPattern,
    /// Unit cell size `L` of the sparse infill, mm. `None` (the default, not written): from
    /// `infill_density`, `L` = [`InfillPattern::cell_mm_for`] (for rectilinear the line
    /// spacing the density gives). When set it fixes the sparse infill's density at
    /// `k_c·m × line width / L`; `infill_density` still switches sparse infill off at 0 and
    /// makes all infill solid at 1.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub infill_cell_mm: Option<f64>,
    /// A cell size that varies over the part (gyroid only; set by a job, never read from a
    /// design): replaces `infill_cell_mm` where present ([`gyroid_graded`]).
    #[serde(skip)]
    pub infill_cell_field: Option<std::sync::Arc<gyroid_graded::CellField>>,
    /// Where perimeter loops start ([`Seam`]). Default aligned.
    pub seam: Seam,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            first_layer_height_mm: DEFAULT_FIRST_LAYER_HEIGHT_MM,
            layer_height_mm: DEFAULT_LAYER_HEIGHT_MM,
            perimeters: DEFAULT_PERIMETERS,
            line_width_mm: DEFAULT_LINE_WIDTH_MM,
            infill_density: DEFAULT_INFILL_DENSITY,
            infill_angle_deg: DEFAULT_INFILL_ANGLE_DEG,
            solid_layers: DEFAULT_SOLID_LAYERS,
            gap_closing_mm: DEFAULT_GAP_CLOSING_MM,
            skirt_loops: DEFAULT_SKIRT_LOOPS,
            skirt_distance_mm: DEFAULT_SKIRT_DISTANCE_MM,
            brim_width_mm: DEFAULT_BRIM_WIDTH_MM,
            support: support::Options::default(),
            infill_pattern: InfillPattern::Rectilinear,
            infill_cell_mm: None,
            infill_cell_field: None,
            seam: Seam::Aligned,
        }
    }
}

/// The regions of one layer.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SlicedLayer {
    /// Cutting plane height in mm (middle of the layer).
    pub slice_z: f64,
    /// Top of the layer in mm (the nozzle height).
    pub z: f64,
    /// Layer thickness in mm.
    pub height: f64,
    /// Closed regions with holes.
    pub regions: Vec<Polygon>,
}

/// What the slicer found and repaired.
#[derive(Clone, Debug, Default, PartialEq, Serialize, serde::Deserialize)]
pub struct SliceReport {
    /// Layers produced.
    pub layers: usize,
    /// Gaps between open contour ends that were closed (each shorter than `gap_closing_mm`).
    pub gaps_closed: usize,
    /// Largest gap closed, mm.
    pub largest_gap_closed_mm: f64,
    /// Open contour pieces that could not be closed and were dropped.
    pub open_contours_dropped: usize,
    /// Layers whose shells overlapped and were unioned.
    pub layers_with_overlaps: usize,
}

/// Slicer output: regions per layer and the toolpath that fills them.
#[derive(Clone, Debug, Default)]
pub struct Sliced {
    /// Regions per layer, bottom to top.
    pub layers: Vec<SlicedLayer>,
    /// Perimeters and infill, layer by layer in print order.
    pub toolpath: Toolpath,
    /// Repairs and counts.
    pub report: SliceReport,
}

/// Why slicing failed.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum Error {
    /// The mesh has no triangles.
    #[error("the mesh is empty; load a mesh with at least one triangle")]
    EmptyMesh,
    /// Options outside the ranges of [`FIELDS`] (every one listed; the design validator
    /// normally reports these first, with their design paths).
    #[error("{}", crate::settings::describe(problems))]
    BadOptions {
        /// Each value out of range, with the allowed range.
        problems: Vec<crate::settings::Problem>,
    },
    /// Over a budget or a limit (stated by [`estimate`], checked before slicing).
    #[error(transparent)]
    TooBig(#[from] crate::budget::OverBudget),
    /// The mesh lies below the plate or is too tall for the layer count limit.
    #[error("the mesh would need {layers} layers (limit {limit}); raise layer_height_mm or scale the mesh down")]
    TooManyLayers {
        /// Layers needed.
        layers: usize,
        /// Limit.
        limit: usize,
    },
}

/// Checks every option against [`FIELDS`], the ranges the design's form shows.
fn validate(o: &Options) -> Result<(), Error> {
    let mut problems = crate::settings::check(o, FIELDS, "");
    problems.extend(crate::settings::check(o, support::FIELDS, ""));
    if problems.is_empty() {
        Ok(())
    } else {
        Err(Error::BadOptions { problems })
    }
}

/// Rows of [`Options`] (paths relative to the options): ranges, units, help, shared by the
/// design's form and [`slice`]'s own check.
pub const FIELDS: &[Field] = &[
    num("first_layer_height_mm", "Slicing", "First layer height", "mm", 0.01, 2.0, 0.01, "Height of the first layer: a thicker one sticks to the bed better."),
    num(
        "layer_height_mm",
        "Slicing",
        "Layer height",
        "mm",
        0.01,
        2.0,
        0.01,
        "Height of every other layer: thinner is smoother and slower (LT of GIPPO equation 4).",
    ),
    int("perimeters", "Slicing", "Perimeters", 0.0, 50.0, "Walls: closed loops printed around the outline of each layer."),
    num("line_width_mm", "Slicing", "Line width", "mm", 0.05, 5.0, 0.01, "Width of each printed line, usually about the nozzle diameter."),
    percent(num("infill_density", "Slicing", "Infill density", "", 0.0, 1.0, 0.05, "How much of the inside is filled: 0 % hollow, 100 % solid.")),
    num("infill_angle_deg", "Slicing", "Infill angle", "°", -360.0, 360.0, 1.0, "Direction of the infill lines; every other layer turns by 90°."),
    int("solid_layers", "Slicing", "Solid layers (top and bottom)", 0.0, 1000.0, "Fully filled layers that close the part at its top and bottom."),
    num("gap_closing_mm", "Slicing", "Gap closing", "mm", 0.0, 5.0, 0.01, "Repairs small holes in a mesh: outline ends closer than this are joined."),
    int("skirt_loops", "Slicing", "Skirt loops", 0.0, 20.0, "Loops around the first layer, printed first to prime the nozzle; 0: no skirt."),
    num("skirt_distance_mm", "Slicing", "Skirt distance", "mm", 0.0, 50.0, 0.1, "Gap between the skirt and the part (or its brim)."),
    num("brim_width_mm", "Slicing", "Brim width", "mm", 0.0, 50.0, 0.1, "Loops around the first layer that touch the part and hold it to the bed; 0: no brim."),
    choice_docs(
        other(
            "infill_pattern",
            "Slicing",
            "Infill pattern",
            Kind::Choice,
            INFILL_PATTERNS,
            "The shape of the sparse infill inside the part (top and bottom skins stay straight lines).",
        ),
        &[
            "Straight lines, crossing at 90° from layer to layer.",
            "Wavy lines that shift with height, building a gyroid: open, even channels in every direction.",
            "Zig-zags that shift with height, building cells like truncated octahedra.",
        ],
    ),
    num(
        "infill_cell_mm",
        "Slicing",
        "Infill cell size",
        "mm",
        MIN_INFILL_CELL_MM,
        MAX_INFILL_CELL_MM,
        0.1,
        "Size of one repeat of the infill pattern; left out, it follows from the infill density.",
    ),
    choice_docs(
        other("seam", "Slicing", "Seam position", Kind::Choice, SEAMS, "Where each perimeter loop starts and ends, leaving a small mark on the wall."),
        &[
            "Lined up from layer to layer in one vertical line, hidden in a concave corner where there is one.",
            "At the back of each loop (largest Y).",
            "Wherever the nozzle is nearest: the least travel, seams scattered over the part.",
            "At a random point of each loop (the same every time the design is sliced): no visible line.",
        ],
    ),
];

/// Layer tops, heights and cutting heights for a mesh whose top is at `top` mm: layers are
/// made while their middle is below `top`.
/// How many layers [`layer_stack`] makes below `top`, without making them.
fn layer_stack_len(o: &Options, top: f64) -> usize {
    let (f, h) = (o.first_layer_height_mm, o.layer_height_mm);
    if !(f / 2.0 < top) {
        return 0;
    }
    // Layer i ≥ 1 is cut at f + i·h − h/2, which must stay below `top`.
    let more = ((top - f + h / 2.0) / h).ceil() - 1.0;
    1 + more.clamp(0.0, 1e15) as usize
}

fn layer_stack(o: &Options, top: f64) -> Result<Vec<(f64, f64, f64)>, Error> {
    let estimate = ((top - o.first_layer_height_mm) / o.layer_height_mm).max(0.0) + 2.0;
    if estimate > MAX_LAYERS as f64 + 1.0 {
        return Err(Error::TooManyLayers { layers: estimate.min(usize::MAX as f64 / 2.0) as usize - 1, limit: MAX_LAYERS });
    }
    let mut out = Vec::new();
    for i in 0usize.. {
        let (z, h) = if i == 0 {
            (o.first_layer_height_mm, o.first_layer_height_mm)
        } else {
            (o.first_layer_height_mm + i as f64 * o.layer_height_mm, o.layer_height_mm)
        };
        let slice_z = z - h / 2.0;
        if slice_z >= top {
            break;
        }
        out.push((z, h, slice_z));
    }
    if out.len() > MAX_LAYERS {
        return Err(Error::TooManyLayers { layers: out.len(), limit: MAX_LAYERS });
    }
    Ok(out)
}

/// Even–odd point-in-region test (mm point, µm shape).
fn contains(shape: &IntShape<i32>, p: DVec2) -> bool {
    let (x, y) = (p.x * UNITS_PER_MM, p.y * UNITS_PER_MM);
    let mut inside = false;
    for c in shape {
        let n = c.len();
        for i in 0..n {
            let a = c[i];
            let b = c[(i + 1) % n];
            let (ax, ay, bx, by) = (a.x as f64, a.y as f64, b.x as f64, b.y as f64);
            if (ay > y) != (by > y) && x < ax + (y - ay) / (by - ay) * (bx - ax) {
                inside = !inside;
            }
        }
    }
    inside
}

/// Whether `p` (mm) lies in any of `shapes` (µm).
pub(crate) fn contains_any(shapes: &IntShapes<i32>, p: DVec2) -> bool {
    shapes.iter().any(|s| contains(s, p))
}

fn bbox_mm(shape: &IntShape<i32>) -> (DVec2, DVec2) {
    let mut min = DVec2::splat(f64::INFINITY);
    let mut max = DVec2::splat(f64::NEG_INFINITY);
    for p in shape.iter().flat_map(|c| c.iter()) {
        let q = DVec2::new(p.x as f64, p.y as f64) / UNITS_PER_MM;
        min = min.min(q);
        max = max.max(q);
    }
    (min, max)
}

fn to_mm_loop(c: &[i_overlay::i_float::int::point::IntPoint<i32>]) -> Vec<DVec2> {
    c.iter().map(|p| DVec2::new(p.x as f64, p.y as f64) / UNITS_PER_MM).collect()
}

/// Sparse infill of layer `layer` (cut at `slice_z` mm) in `area`: the pattern of `o` with its
/// unit cell (given, or from the density). Rectilinear turns with the layer (`angle`); the 3D
/// patterns keep one orientation, `infill_angle_deg − 45°` (as PrusaSlicer's gyroid: the
/// default 45° puts their axes along X and Y), and are cut at the layer's middle.
fn sparse_lines(o: &Options, area: &IntShapes<i32>, w_um: i32, layer: usize, slice_z: f64, angle: f64, min_len_um: f64) -> Vec<Vec<DVec2>> {
    let pattern = o.infill_pattern;
    let cell_um = match o.infill_cell_mm {
        Some(l) => l * UNITS_PER_MM,
        None => pattern.cell_mm_for(o.infill_density, w_um as f64),
    };
    let turn = o.infill_angle_deg.to_radians() - std::f64::consts::FRAC_PI_4;
    match pattern {
        InfillPattern::Rectilinear => {
            // Without a cell size, exactly the spacing rectilinear always had.
            let spacing = match o.infill_cell_mm {
                None => w_um as f64 / o.infill_density,
                Some(_) => cell_um / std::f64::consts::SQRT_2,
            };
            infill::rectilinear(area, spacing, angle, min_len_um)
        }
        InfillPattern::Gyroid => match &o.infill_cell_field {
            Some(field) => gyroid_graded::gyroid_graded(area, field, slice_z, turn, min_len_um),
            None => gyroid::gyroid(area, cell_um, slice_z, turn, min_len_um),
        },
        InfillPattern::Honeycomb3d => honeycomb3d::honeycomb3d(area, cell_um, slice_z, layer % 2 == 1, turn, min_len_um),
    }
}

/// Slices `mesh` (already placed: its lowest point is the plate, Z = 0) into layers and fills them.
/// `progress` receives the fraction done, 0–1.
///
/// Solid infill (`Feature::SolidInfill`, spacing = line width) is computed per area: the part
/// of a layer's infill area that is not covered by every one of the `solid_layers` layers
/// above and below it (layers outside the part count as empty, so the first and last
/// `solid_layers` layers are entirely solid, and so are the top surfaces of steps and domes).
/// The rest gets sparse infill (`Feature::Infill`, spacing = line width / density); with
/// `infill_density` 0 there is no sparse infill but top and bottom skins are still printed
/// (set `solid_layers` to 0 as well for no infill at all); with density 1 all infill is solid.
pub fn slice(mesh: &Mesh, options: &Options, progress: &mut dyn FnMut(f32)) -> Result<Sliced, Error> {
    slice_with(mesh, &Extra::default(), options, progress)
}

/// Meshes that shape the slice without being printed, in the part's frame.
#[derive(Clone, Copy, Debug, Default)]
pub struct Extra<'a> {
    /// Support is built under every overhang inside these, whatever its angle.
    pub support_enforcers: Option<&'a Mesh>,
    /// No support is built for overhangs inside these.
    pub support_blockers: Option<&'a Mesh>,
}

/// The regions of `mesh` at every cutting height of `stack` (empty layers where it is not).
fn cut_layers(mesh: &Mesh, stack: &[(f64, f64, f64)], gap_um: f64) -> Vec<IntShapes<i32>> {
    let sweep = plane::Sweep::new(mesh);
    if stack.is_empty() || mesh.triangles.is_empty() {
        return vec![Vec::new(); stack.len()];
    }
    let mut cursor = sweep.cursor(stack[0].2);
    let mut segs = Vec::new();
    stack
        .iter()
        .map(|l| {
            cursor.segments(l.2, &mut segs);
            let (loops, _) = stitch::stitch(&mut segs, gap_um);
            regions::union_loops(&loops).0
        })
        .collect()
}

/// [`slice`] with support enforcer and blocker meshes.
pub fn slice_with(mesh: &Mesh, extra: &Extra, options: &Options, progress: &mut dyn FnMut(f32)) -> Result<Sliced, Error> {
    validate(options)?;
    if mesh.triangles.is_empty() {
        return Err(Error::EmptyMesh);
    }
    estimate(mesh, options).check()?;
    let o = options;
    let sweep = plane::Sweep::new(mesh);
    let top = match sweep.top {
        Some(t) if t > 0.0 => t,
        _ => return Ok(Sliced::default()),
    };
    let stack = layer_stack(o, top)?;
    let n = stack.len();
    let mut report = SliceReport { layers: n, ..Default::default() };
    let mut last_progress = -1.0f32;
    let mut tick = |f: f32, progress: &mut dyn FnMut(f32)| {
        if f - last_progress >= 0.02 || f >= 1.0 {
            last_progress = f;
            progress(f.min(1.0));
        }
    };
    tick(0.0, progress);

    // Pass 1: regions of every layer, runs of layers swept side by side (a few runs a thread,
    // so one slow run does not hold the rest; each run's cursor starts with its own scan).
    let gap_um = o.gap_closing_mm * UNITS_PER_MM;
    let runs = if crate::par::threads() > 1 { 4 * crate::par::threads() } else { 1 };
    let cut = crate::par::map_runs(n, runs, &mut |d| tick(0.4 * d as f32 / n.max(1) as f32, progress), |range, done| {
        let mut cursor = sweep.cursor(stack[range.start].2);
        let mut segs = Vec::new();
        range
            .map(|i| {
                cursor.segments(stack[i].2, &mut segs);
                let (loops, st) = stitch::stitch(&mut segs, gap_um);
                let (shapes, overlap) = regions::union_loops(&loops);
                done();
                (shapes, st, overlap)
            })
            .collect()
    });
    let mut layer_shapes: Vec<IntShapes<i32>> = Vec::with_capacity(n);
    for (shapes, st, overlap) in cut {
        report.gaps_closed += st.gaps_closed;
        report.largest_gap_closed_mm = report.largest_gap_closed_mm.max(st.largest_gap_um / UNITS_PER_MM);
        report.open_contours_dropped += st.open_dropped;
        if overlap {
            report.layers_with_overlaps += 1;
        }
        layer_shapes.push(shapes);
    }

    // Support, from the regions of every layer (and the enforcer and blocker meshes).
    let w_um = (o.line_width_mm * UNITS_PER_MM).round() as i32;
    let support = if o.support.enabled {
        let cut = |m: Option<&Mesh>| m.map_or_else(Vec::new, |m| cut_layers(m, &stack, gap_um));
        let input = support::Input {
            part: &layer_shapes,
            heights: stack.iter().map(|l| l.1).collect(),
            // What a bridge will span is not supported (unless asked): found on the whole
            // layer, as fill_layer finds it on the solid area.
            bridged: if o.support.support_bridges {
                Vec::new()
            } else {
                crate::par::map(n, &mut |_| {}, |i| {
                    if i == 0 {
                        return Vec::new();
                    }
                    let found = bridge::detect(&layer_shapes[i], &layer_shapes[i - 1], w_um);
                    let mut all: IntShapes<i32> = Vec::new();
                    for b in found {
                        all = regions::union(&all, &b.over_air);
                    }
                    all
                })
            },
            enforcers: cut(extra.support_enforcers),
            blockers: cut(extra.support_blockers),
            w_um,
            layer_height_mm: o.layer_height_mm,
        };
        support::generate(&o.support, &input, &mut |f| tick(0.4 + 0.1 * f, progress))
    } else {
        Vec::new()
    };

    // Pass 2: perimeters and infill of each layer side by side, then the order of each layer's
    // paths, which starts where the layer below ended (in turn).
    let w = o.line_width_mm;
    let filled = crate::par::map(n, &mut |d| tick(0.5 + 0.4 * d as f32 / n.max(1) as f32, progress), |i| fill_layer(o, &layer_shapes, &stack, i, w_um));
    let filled = trim_infill(o, filled, &support);
    let mut layers = Vec::with_capacity(n);
    let mut toolpath = Toolpath { passes: Vec::with_capacity(n) };
    let mut pos = DVec2::ZERO;
    let mut support = support.into_iter();
    let mut seams = order::Seams::new(o.seam);
    for (i, works) in filled.into_iter().enumerate() {
        let (z, h, slice_z) = stack[i];
        let mut paths = Vec::new();
        if i == 0 {
            // Skirt and brim before the part, the last brim loop ending beside it.
            let um = |mm: f64| (mm * UNITS_PER_MM).round().clamp(0.0, i32::MAX as f64) as i32;
            let loops = skirt::loops(&layer_shapes[0], o.skirt_loops, um(o.skirt_distance_mm), um(o.brim_width_mm), w_um);
            paths.extend(order::order_skirt(loops.iter().map(|l| to_mm_loop(l)).collect(), &mut pos, z, w));
        }
        if let Some(sup) = support.next() {
            paths.extend(order::order_support(sup.base, sup.interface, &mut pos, z, w));
        }
        paths.extend(order::order_layer(works, &mut pos, z, w, &mut seams));
        toolpath.passes.push(Pass::layer(z, h, paths));
        layers.push(SlicedLayer { slice_z, z, height: h, regions: regions::to_polygons(&layer_shapes[i]) });
        tick(0.9 + 0.1 * (i + 1) as f32 / n as f32, progress);
    }
    tick(1.0, progress);
    Ok(Sliced { layers, toolpath, report })
}

/// Infill cut back where it would end in air: a stub past the last line of the layer below,
/// or a connector over a gap in it, is left out (see [`anchor`]): any such stretch of
/// rectilinear sparse infill, and of other infill those no longer than the larger of 3 mm and
/// 1.5 sparse line spacings; lines across the layer below (bridges) and longer stretches stay. Layer `i` is checked against layer `i − 1`'s perimeters, infill and support.
fn trim_infill(o: &Options, filled: Vec<Vec<order::RegionWork>>, support: &[support::LayerSupport]) -> Vec<Vec<order::RegionWork>> {
    let w = o.line_width_mm;
    let reach = 1.05 * w;
    let spacing = if o.infill_density > 0.0 { w / o.infill_density } else { 0.0 };
    let max_cut = (1.5 * spacing).max(3.0);
    let n = filled.len();
    let trimmed = crate::par::map(n, &mut |_| {}, |i| {
        if i == 0 || filled[i].iter().all(|r| r.infill.is_empty()) {
            return None;
        }
        let mut below: Vec<Vec<DVec2>> = Vec::new();
        for r in &filled[i - 1] {
            for l in r.perimeters.iter().flatten() {
                let mut c = l.pts.clone();
                if let Some(&p) = l.pts.first() {
                    c.push(p);
                }
                below.push(c);
            }
            below.extend(r.infill.iter().map(|(_, l)| l.clone()));
        }
        if let Some(sup) = support.get(i - 1) {
            below.extend(sup.base.iter().chain(&sup.interface).cloned());
        }
        let near = anchor::Near::new(below.iter().map(|l| l.as_slice()), reach);
        let held = |p: DVec2| near.holds(p);
        let regions: Vec<order::RegionWork> = filled[i]
            .iter()
            .map(|r| {
                let mut infill = Vec::with_capacity(r.infill.len());
                for (f, l) in &r.infill {
                    let mut pieces = Vec::new();
                    // Sparse straight lines only ever hang over the sparse lines below
                    // (a part's overhangs are solid): everything unheld is a stub.
                    let cut = if *f == Feature::Infill && o.infill_pattern == InfillPattern::Rectilinear { f64::INFINITY } else { max_cut };
                    anchor::held_pieces(l, &held, 0.1 * w.max(0.1) * 2.5, 0.25 * w, cut, &mut pieces);
                    infill.extend(pieces.into_iter().map(|p| (*f, p)));
                }
                order::RegionWork { infill, ..r.clone() }
            })
            .collect();
        Some(regions)
    });
    filled.into_iter().zip(trimmed).map(|(orig, t)| t.unwrap_or(orig)).collect()
}

/// Perimeters and infill of layer `i` (of `stack`, regions `layer_shapes`), by region: what the
/// layer's order starts from. Reads the layers within `solid_layers` for its solid infill.
fn fill_layer(o: &Options, layer_shapes: &[IntShapes<i32>], stack: &[(f64, f64, f64)], i: usize, w_um: i32) -> Vec<order::RegionWork> {
    let n = stack.len();
    let slice_z = stack[i].2;
    // Infill centre lines stay a full half width inside the innermost perimeter's inner edge:
    // lines and their boundary-following connectors then sit side by side with the perimeter
    // (the analyzer's overlap_mm is 0) instead of re-covering half of it.
    let infill_inset = w_um as i64 * o.perimeters as i64 + w_um as i64 / 2;
    let infill_inset = infill_inset.min(i32::MAX as i64) as i32;
    let min_len_um = 0.25 * w_um as f64;
    let base_angle = o.infill_angle_deg.to_radians();
    let s = o.solid_layers as usize;
    let shapes = &layer_shapes[i];
    // Infill area of the whole layer (regions are disjoint, so are their insets).
    let mut works: Vec<order::RegionWork> = Vec::with_capacity(shapes.len());
    let mut area: IntShapes<i32> = Vec::new();
    // Perimeters above the layer below's outline hang over air (none on the first layer).
    let lower = if i > 0 && o.perimeters > 0 { Some(overhang::Lower::new(&layer_shapes[i - 1])) } else { None };
    let w = w_um as f64 / UNITS_PER_MM;
    let mk_loop = |pts: Vec<DVec2>| match &lower {
        Some(lower) => overhang::classify(pts, lower, w),
        None => order::Loop::plain(pts),
    };
    for region in shapes {
        let levels = perimeters::perimeter_levels(region, o.perimeters, w_um);
        let (min, max) = bbox_mm(region);
        works.push(order::RegionWork {
            min,
            max,
            perimeters: levels.iter().map(|l| l.iter().flat_map(|sh| sh.iter()).map(|c| mk_loop(to_mm_loop(c))).collect()).collect(),
            infill: Vec::new(),
        });
        area.extend(perimeters::inset(std::slice::from_ref(region), infill_inset));
    }
    // The whole infill area, where bridges may reach for their anchors.
    let infill_area = if i > 0 { area.clone() } else { Vec::new() };
    let (solid, sparse) = if area.is_empty() {
        (Vec::new(), Vec::new())
    } else if o.infill_density >= 1.0 {
        (area, Vec::new())
    } else if s == 0 {
        (Vec::new(), area)
    } else {
        // Covered by every layer within `s` above and below.
        let mut cov: Option<IntShapes<i32>> = None;
        if i < s || i + s >= n {
            cov = Some(Vec::new());
        } else {
            for (j, other) in layer_shapes.iter().enumerate().take(i + s + 1).skip(i - s) {
                if j == i {
                    continue;
                }
                let next = match &cov {
                    None => other.clone(),
                    Some(c) => regions::intersect(c, other),
                };
                let done = next.is_empty();
                cov = Some(next);
                if done {
                    break;
                }
            }
        }
        let cov = cov.unwrap_or_default();
        if cov.is_empty() {
            (area, Vec::new())
        } else {
            // Solid and sparse lines both follow their area's boundary; keeping the sparse
            // area one line width away from the solid one stops them sharing a boundary
            // (which would print that stretch twice).
            let solid = regions::difference(&area, &cov);
            let sparse = regions::intersect(&area, &cov);
            let sparse = if solid.is_empty() { sparse } else { regions::difference(&sparse, &perimeters::outset(&solid, w_um)) };
            (solid, sparse)
        }
    };
    // Bridges: the solid area over air (layer i − 1's outlines are the material below, sparse
    // infill included), grown into the infill area around it for the lines' anchors. The
    // solid and sparse areas then keep a line width away from the bridges.
    let mut bridge_lines: Vec<Vec<DVec2>> = Vec::new();
    let (solid, sparse) = if i == 0 || solid.is_empty() {
        (solid, sparse)
    } else {
        let below = &layer_shapes[i - 1];
        let air = regions::difference(&solid, below);
        if air.is_empty() {
            (solid, sparse)
        } else {
            let reach = (bridge::ANCHOR_REACH + 1.0) * w_um as f64;
            let room = regions::intersect(&perimeters::outset(&air, reach as i32), &infill_area);
            let bridges = bridge::detect(&regions::union(&solid, &room), below, w_um);
            if bridges.is_empty() {
                (solid, sparse)
            } else {
                let mut taken: IntShapes<i32> = Vec::new();
                for b in &bridges {
                    bridge_lines.extend(bridge::lines(&b.area, below, b.angle, w_um, min_len_um));
                    taken.extend(b.area.iter().cloned());
                }
                let keep_off = perimeters::outset(&taken, w_um);
                (regions::difference(&solid, &keep_off), regions::difference(&sparse, &keep_off))
            }
        }
    };
    let angle = if i % 2 == 0 { base_angle } else { base_angle + std::f64::consts::FRAC_PI_2 };
    let mut lines: Vec<(Feature, Vec<DVec2>)> = bridge_lines.into_iter().map(|l| (Feature::Bridge, l)).collect();
    for l in infill::rectilinear(&solid, w_um as f64, angle, min_len_um) {
        lines.push((Feature::SolidInfill, l));
    }
    if o.infill_density > 0.0 && !sparse.is_empty() {
        for l in sparse_lines(o, &sparse, w_um, i, slice_z, angle, min_len_um) {
            lines.push((Feature::Infill, l));
        }
    }
    // Hand each polyline to the region containing its first point.
    for (f, l) in lines {
        let p = l[0];
        let k = (0..shapes.len())
            .find(|&k| {
                let r = &works[k];
                p.x >= r.min.x && p.x <= r.max.x && p.y >= r.min.y && p.y <= r.max.y && contains(&shapes[k], p)
            })
            .unwrap_or_else(|| {
                (0..works.len())
                    .min_by(|&a, &b| order::box_dist2(p, works[a].min, works[a].max).total_cmp(&order::box_dist2(p, works[b].min, works[b].max)))
                    .unwrap_or(0)
            });
        if let Some(r) = works.get_mut(k) {
            r.infill.push((f, l));
        }
    }
    works
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layer_stack_counts() {
        let o = Options::default();
        let st = layer_stack(&o, 20.0).unwrap();
        assert_eq!(st.len(), 100);
        assert!((st[99].0 - 20.0).abs() < 1e-9);
        assert!((st[0].2 - 0.1).abs() < 1e-12);
        assert_eq!(layer_stack(&o, 0.15).unwrap().len(), 1);
        assert_eq!(layer_stack(&o, 0.05).unwrap().len(), 0, "a plate-thin mesh is never cut");
        assert!(matches!(layer_stack(&o, 1e6), Err(Error::TooManyLayers { .. })));
        for top in [0.05, 0.1, 0.15, 0.2, 0.3, 0.31, 20.0, 20.05, 20.1, 33.333] {
            for (f, h) in [(0.2, 0.2), (0.3, 0.1), (0.1, 0.25)] {
                let o = Options { first_layer_height_mm: f, layer_height_mm: h, ..Options::default() };
                assert_eq!(layer_stack_len(&o, top), layer_stack(&o, top).unwrap().len(), "top {top}, first {f}, height {h}");
            }
        }
    }

    #[test]
    fn bad_options_are_rejected() {
        let o = Options { layer_height_mm: 0.0, ..Default::default() };
        let e = validate(&o).unwrap_err();
        assert!(matches!(&e, Error::BadOptions { problems } if problems[0].path == "layer_height_mm"), "{e}");
        let o = Options { infill_density: f64::NAN, ..Default::default() };
        assert!(validate(&o).is_err());
        assert!(validate(&Options::default()).is_ok());
    }
}

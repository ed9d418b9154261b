//! Isosurface: the surface model of a tissue in a volume (paper §2.1.2) — the closed triangle
//! mesh of the voxels at or above an isovalue inside a region of interest.
//!
//! Entry: [`extract`]; [`estimate`] states the work first; [`write_stl`] exports.
//!
//! Method:
//! 1. **Segment.** The solid is the ROI's voxels (those [`Roi::voxels`] gives) with value ≥
//!    [`Options::iso`] (NaN counts as below). The grid is padded with one layer of empty
//!    voxels all round: everything outside the ROI is below the isovalue, so the surface
//!    closes at the ROI faces (the paper's Boolean intersection with the ROI box, done on the
//!    voxels instead of the mesh, where it cannot fail).
//! 2. **Fill cavities** (optional, [`Options::fill_cavities`]): empty voxels that cannot reach
//!    the ROI's boundary through empty face neighbours are made solid (`cavities.rs`).
//! 3. **Mesh** by marching cubes with a case table built from one face rule, which makes the
//!    surface closed and consistently oriented for any field (`marching_cubes.rs`: why). Each
//!    crossed grid edge is one vertex (an indexed, welded mesh); vertices are placed by linear
//!    interpolation of the voxel values.
//! 4. **Smooth** (optional, [`Options::smoothing_iterations`]): Taubin λ/μ (`smooth.rs`).
//! 5. **Report**: area, volume (divergence theorem), connected components, and closedness
//!    *checked* on the output (every edge in exactly two triangles, in opposite directions).
//!
//! **Caps.** A vertex between a solid boundary voxel and the padding is put on the ROI face
//! plane itself (not interpolated), so a cut solid is closed by flat caps lying exactly on
//! the ROI faces. Two exceptions, both at most a fraction of a voxel: where the ROI reaches
//! beyond the volume, the cap is half a voxel beyond the last voxel centre; where an ROI face
//! passes through voxel centres (within 10⁻³ voxel, e.g. [`Roi::whole`]), the cap is 10⁻³
//! voxel outside them, so cap vertices of two faces never coincide at a box edge. Where two
//! capped faces meet, the box edge is bevelled across the last voxel (the mesh has vertices
//! only on grid edges).
//!
//! **Cavities.** A cavity is a region of below-isovalue voxels that cannot reach any ROI face
//! through face-neighbouring below-isovalue voxels. A bone's medullary canal that runs out
//! through the ROI's end faces reaches them: a tunnel in 3D, not a cavity. So after the 3D
//! fill, the holes of each slice across k (below-isovalue regions enclosed within the slice)
//! are filled too, which closes the canal as the paper does before slicing (its Figure 10b);
//! both count in `cavities_filled` (`ct_phantom_is_closed` in tests/it/isosurface.rs).
//!
//! **Why our own implementation.** The pure-Rust crates found (`mcubes`, `marching-cubes`)
//! polygonise cube by cube with the classic Bourke table: triangle soups, not welded, with the
//! table's inconsistent ambiguous faces (cracks), and no ROI caps. The watertightness
//! guarantee is the point here, and a table derived from a rule is shorter to get right than
//! a typed-in one.
//!
//! Bounded: the ROI's voxel count is checked against the budgets before anything is
//! allocated; then the classified, filled grid (1 byte per voxel) gives the exact triangle
//! count (each boundary cube's, from the case table) and the memory from it, checked against
//! [`MAX_TRIANGLES`] and the budgets before the mesh is allocated. [`estimate`] does the same
//! steps, so it states exactly what [`extract`] makes or refuses.

mod cavities;
mod marching_cubes;
mod smooth;

use crate::budget::{Estimate, OverBudget};
use crate::geom::Mesh;
use crate::settings::{int, num, other, Field, Kind as FieldKind};
use crate::volume::{Roi, Volume};
use marching_cubes::{Grid, Table, EDGE_MARGIN, SOLID};
use serde::{Deserialize, Serialize};

/// Default isovalue, HU: the paper's threshold for bone (its §3, after the literature's HU
/// ranges: cortical and trabecular bone above it, marrow and soft tissue below).
pub const DEFAULT_ISO: f64 = 350.0;
/// Fill internal cavities by default: the solid is what gets a graded lattice, and a void
/// sealed inside it (marrow space) is part of the part to print.
pub const DEFAULT_FILL_CAVITIES: bool = true;
/// Smoothing iterations by default: none (the mesh follows the voxel data; each iteration is
/// one Taubin λ/μ pair).
pub const DEFAULT_SMOOTHING_ITERATIONS: u32 = 0;
/// Most smoothing iterations accepted: Taubin smoothing has removed the voxel staircase
/// after about 10–30; more only costs time (each is two passes over the mesh).
pub const MAX_SMOOTHING_ITERATIONS: u32 = 200;

/// Most triangles a surface may have: the importer's limit ([`crate::import::MAX_TRIANGLES`],
/// 5 M), so every surface made here can be written to STL and read back, and the slicer
/// downstream gets no bigger mesh than it is sized for. At 80 bytes per triangle of peak
/// memory (mesh, closedness check, smoothing graph) that is 400 MB, within the stage budget.
/// A 0.5 mm CT of a whole femur gives about 2–3 M; a noisy field can give far more, which a
/// higher isovalue or smaller ROI brings down.
pub const MAX_TRIANGLES: usize = crate::import::MAX_TRIANGLES;

/// Peak bytes per triangle: the mesh (12 per triangle, reserved exactly; 13 per vertex, at
/// most 0.75 vertices per triangle, grown by doubling: 31 in all) plus the smoothing graph
/// (39) or the closedness check (18), whichever is later.
const BYTES_PER_TRIANGLE: f64 = 80.0;
/// Peak bytes per padded ROI voxel: the classification grid (1) and the flood fill's stack
/// (4, when every voxel is pushed once).
const BYTES_PER_VOXEL: f64 = 5.0;
/// Time per ROI voxel, s (classification, cavity fill, counting, marching): the 182×197×107
/// phantom of `ct_phantom_is_closed` in tests/it/isosurface.rs (3.8 M voxels, 31 k triangles)
/// takes 0.12–0.17 s in a release build (measured on a loaded 2-core machine).
const SECONDS_PER_VOXEL: f64 = 30e-9;
/// Time per triangle, s (vertex placement, triangles, report): `large_surface_timing`'s 3.6 M
/// triangles take 0.8 s including its voxels (same machine).
const SECONDS_PER_TRIANGLE: f64 = 150e-9;
/// Time per triangle and smoothing iteration, s (same test: 10 iterations add 1.4 s).
const SECONDS_PER_SMOOTHING: f64 = 40e-9;

/// Surface options.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Options {
    /// Isovalue in the volume's unit (HU for CT): voxels at or above it are solid. Default
    /// [`DEFAULT_ISO`].
    pub iso: f64,
    /// Make enclosed voids solid before meshing. Default [`DEFAULT_FILL_CAVITIES`].
    pub fill_cavities: bool,
    /// Taubin smoothing iterations, 0 to [`MAX_SMOOTHING_ITERATIONS`]. Default
    /// [`DEFAULT_SMOOTHING_ITERATIONS`].
    pub smoothing_iterations: u32,
}

impl Default for Options {
    fn default() -> Self {
        Options { iso: DEFAULT_ISO, fill_cavities: DEFAULT_FILL_CAVITIES, smoothing_iterations: DEFAULT_SMOOTHING_ITERATIONS }
    }
}

/// What the surface is and what was done to make it.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct SurfaceReport {
    /// Triangles.
    pub triangles: usize,
    /// Vertices.
    pub vertices: usize,
    /// Surface area, mm².
    pub area_mm2: f64,
    /// Enclosed volume, mm³ (divergence theorem; positive for outward-facing triangles).
    pub volume_mm3: f64,
    /// Cavities (enclosed voids) filled.
    pub cavities_filled: usize,
    /// Voxels made solid by filling them.
    pub cavity_voxels: usize,
    /// ROI faces (−x, +x, −y, +y, −z, +z) the solid touches and was closed at.
    pub capped: [bool; 6],
    /// Connected pieces of the surface (bone fragments; an unfilled cavity's wall is one too).
    pub components: usize,
    /// Every edge is shared by exactly two triangles, in opposite directions (checked).
    pub closed: bool,
}

/// The surface model.
#[derive(Clone, Debug)]
pub struct Surface {
    /// The mesh in the volume frame, mm; outward-facing counter-clockwise triangles.
    pub mesh: Mesh,
    /// What it is.
    pub report: SurfaceReport,
}

/// Why no surface was made. Messages say where and what to change.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum Error {
    /// The region of interest holds no voxel centre.
    #[error(
        "surface: the region of interest {} – {} mm holds no voxel centre of the volume, which spans 0 – {} mm; draw the box over the volume",
        mm3(roi_min_mm),
        mm3(roi_max_mm),
        mm3(volume_extent_mm)
    )]
    EmptyRoi {
        /// The ROI's smallest corner, mm.
        roi_min_mm: [f64; 3],
        /// The ROI's largest corner, mm.
        roi_max_mm: [f64; 3],
        /// The volume's extent (last voxel centre), mm.
        volume_extent_mm: [f64; 3],
    },
    /// No voxel of the region reaches the isovalue.
    #[error(
        "surface: no voxel in the region of interest reaches the isovalue {iso} (its values range from {min} to {max}); choose an isovalue in that range (bone ≈ 350 HU)"
    )]
    NothingInside {
        /// The isovalue asked for.
        iso: f64,
        /// Smallest value in the region (NaN when it holds no number).
        min: f64,
        /// Largest value in the region.
        max: f64,
    },
    /// Over a budget or [`MAX_TRIANGLES`] (stated by [`estimate`], checked before allocating).
    #[error("surface: {0}")]
    TooBig(#[from] OverBudget),
    /// An option out of range.
    #[error("surface option {name} = {value}: {fix}")]
    BadOption {
        /// The option.
        name: &'static str,
        /// Its value.
        value: String,
        /// The allowed range.
        fix: String,
    },
}

fn mm3(p: &[f64; 3]) -> String {
    format!("({:.4}, {:.4}, {:.4})", p[0], p[1], p[2]).replace(".0000", "")
}

fn validate(o: &Options) -> Result<(), Error> {
    if !o.iso.is_finite() {
        return Err(Error::BadOption { name: "iso", value: format!("{}", o.iso), fix: "give a finite isovalue in the volume's unit (HU for CT)".into() });
    }
    if o.smoothing_iterations > MAX_SMOOTHING_ITERATIONS {
        return Err(Error::BadOption {
            name: "smoothing_iterations",
            value: o.smoothing_iterations.to_string(),
            fix: format!("use 0 to {MAX_SMOOTHING_ITERATIONS} (10–30 remove the voxel staircase)"),
        });
    }
    Ok(())
}

/// The ROI's voxel counts along i, j, k.
fn counts(r: &[std::ops::Range<usize>; 3]) -> [usize; 3] {
    [r[0].len(), r[1].len(), r[2].len()]
}

/// The classified (and cavity-filled) padded grid of a ROI, and what classifying found.
struct Prepared {
    /// `m` points per axis, `i` fastest: [`SOLID`] or not; the outer layer is padding.
    cells: Vec<u8>,
    m: [usize; 3],
    /// Voxels at or above the isovalue.
    solid: usize,
    /// Smallest and largest finite value in the ROI (∞, −∞ when none).
    min: f64,
    max: f64,
    filled: cavities::Filled,
}

/// Steps 1 and 2 (module doc): classify the ROI's voxels into the padded grid, fill cavities.
fn prepare(volume: &Volume, r: &[std::ops::Range<usize>; 3], options: &Options) -> Prepared {
    let n = counts(r);
    let m = [n[0] + 2, n[1] + 2, n[2] + 2];
    let plane = m[0] * m[1];
    let mut p = Prepared { cells: vec![0u8; plane * m[2]], m, solid: 0, min: f64::INFINITY, max: f64::NEG_INFINITY, filled: Default::default() };
    for k in 0..n[2] {
        for j in 0..n[1] {
            let row = volume.index(r[0].start, r[1].start + j, r[2].start + k);
            let out = (k + 1) * plane + (j + 1) * m[0] + 1;
            for i in 0..n[0] {
                let v = volume.values.get(row + i).copied().unwrap_or(f32::NAN);
                if v.is_finite() {
                    p.min = p.min.min(v as f64);
                    p.max = p.max.max(v as f64);
                }
                if v as f64 >= options.iso {
                    p.cells[out + i] = SOLID;
                    p.solid += 1;
                }
            }
        }
    }
    if options.fill_cavities && p.solid > 0 {
        p.filled = cavities::fill(&mut p.cells, m, [true; 6]);
        let holes = cavities::fill_slice_holes(&mut p.cells, m);
        p.filled.cavities += holes.cavities;
        p.filled.voxels += holes.voxels;
    }
    p
}

const FIX: &str = "draw a smaller region of interest, or raise the isovalue";

/// The estimate from the ROI's size alone: refuses before the grid is allocated.
fn voxel_estimate(r: &[std::ops::Range<usize>; 3]) -> Estimate {
    let n = counts(r);
    let voxels = n.iter().map(|&x| x as f64).product::<f64>();
    let padded = n.iter().map(|&x| x as f64 + 2.0).product::<f64>();
    Estimate::new("surface")
        .quantity("voxels", "voxels in the region of interest", voxels, "")
        .cost(BYTES_PER_VOXEL * padded, SECONDS_PER_VOXEL * voxels)
        .limit("the region of interest's voxels (with a one-voxel border)", padded, u32::MAX as f64, "", FIX)
        .budgets(FIX)
}

/// `e` (from [`voxel_estimate`], not refused) with the surface's triangle count.
fn triangle_estimate(e: Estimate, triangles: u64, options: &Options) -> Estimate {
    let t = triangles as f64;
    let iterations = options.smoothing_iterations.min(MAX_SMOOTHING_ITERATIONS) as f64;
    let (bytes, seconds) = (e.bytes + BYTES_PER_TRIANGLE * t, e.seconds + (SECONDS_PER_TRIANGLE + SECONDS_PER_SMOOTHING * iterations) * t);
    e.quantity("triangles", "surface triangles", t, "").cost(bytes, seconds).limit("surface triangles", t, MAX_TRIANGLES as f64, "", FIX).budgets(FIX)
}

/// States the work of [`extract`]: ROI voxels, surface triangles (exact), peak memory and
/// time; refuses over [`MAX_TRIANGLES`] or the stage budgets. Over the budgets by the ROI's
/// voxel count it refuses without reading the volume; otherwise it classifies and fills the
/// ROI (the padded grid, 1 byte per voxel, within the budget just checked) and counts each
/// boundary cube's triangles from the case table, allocating no mesh.
pub fn estimate(volume: &Volume, roi: &Roi, options: &Options) -> Estimate {
    let Some(r) = roi.voxels(volume) else {
        return Estimate::new("surface");
    };
    let e = voxel_estimate(&r);
    if e.refused.is_some() {
        return e;
    }
    let p = prepare(volume, &r, options);
    let triangles = marching_cubes::count(&p.cells, p.m, &Table::new());
    triangle_estimate(e, triangles, options)
}

/// The cap planes: per axis, the low and high ROI faces (module doc: caps).
fn cap_planes(volume: &Volume, roi: &Roi, r: &[std::ops::Range<usize>; 3]) -> [[f64; 2]; 3] {
    let mut planes = [[0.0; 2]; 3];
    for a in 0..3 {
        let s = volume.spacing_mm[a];
        let (first, last) = (r[a].start as f64 * s, (r[a].end - 1) as f64 * s);
        planes[a][0] = roi.min_mm[a].max(first - 0.5 * s).min(first - EDGE_MARGIN * s);
        planes[a][1] = roi.max_mm[a].min(last + 0.5 * s).max(last + EDGE_MARGIN * s);
    }
    planes
}

/// The closed surface of `volume`'s voxels at or above `options.iso` inside `roi` (module
/// doc). Refuses as [`estimate`] does, before allocating the mesh. `progress` gets 0..1.
pub fn extract(volume: &Volume, roi: &Roi, options: &Options, progress: &mut dyn FnMut(f32)) -> Result<Surface, Error> {
    validate(options)?;
    let Some(r) = roi.voxels(volume) else {
        return Err(Error::EmptyRoi { roi_min_mm: roi.min_mm, roi_max_mm: roi.max_mm, volume_extent_mm: volume.extent_mm().to_array() });
    };
    let e = voxel_estimate(&r);
    e.check()?;
    // 1, 2. Classify, fill.
    let p = prepare(volume, &r, options);
    if p.solid == 0 {
        let (min, max) = if p.min <= p.max { (p.min, p.max) } else { (f64::NAN, f64::NAN) };
        return Err(Error::NothingInside { iso: options.iso, min, max });
    }
    let table = Table::new();
    let triangles = marching_cubes::count(&p.cells, p.m, &table);
    triangle_estimate(e, triangles, options).check()?;
    progress(0.0);
    // 3. Mesh.
    let planes = cap_planes(volume, roi, &r);
    let grid = Grid { volume, start: [r[0].start, r[1].start, r[2].start], n: counts(&r), cells: &p.cells, iso: options.iso, planes };
    let mesh_share = if options.smoothing_iterations > 0 { 0.7 } else { 0.9 };
    let mut out = marching_cubes::extract(&grid, &table, triangles as usize, &mut |f| progress(mesh_share * f));
    debug_assert_eq!(out.mesh.triangles.len() as u64, triangles);
    let filled = p.filled;
    drop(p);
    // 4. Smooth.
    smooth::taubin(&mut out.mesh, &out.on_plane, planes, options.smoothing_iterations, &mut |f| progress(mesh_share + 0.2 * f));
    // 5. Report.
    let mesh = out.mesh;
    let (area_mm2, volume_mm3) = area_and_volume(&mesh);
    let report = SurfaceReport {
        triangles: mesh.triangles.len(),
        vertices: mesh.vertices.len(),
        area_mm2,
        volume_mm3,
        cavities_filled: filled.cavities,
        cavity_voxels: filled.voxels,
        capped: out.capped,
        components: components(&mesh),
        closed: is_closed(&mesh),
    };
    progress(1.0);
    Ok(Surface { mesh, report })
}

/// Area (mm²) and enclosed volume (mm³, divergence theorem: Σ a·(b × c) / 6).
pub fn area_and_volume(mesh: &Mesh) -> (f64, f64) {
    let (mut area, mut volume) = (0.0, 0.0);
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|v| mesh.vertex(v));
        area += 0.5 * (b - a).cross(c - a).length();
        volume += a.dot(b.cross(c)) / 6.0;
    }
    (area, volume)
}

/// Every edge is in exactly two triangles, in opposite directions: each directed edge occurs
/// once and so does its reverse (and no triangle repeats a vertex). Linear: the directed
/// edges are grouped by their first vertex (a few per vertex), sorted, and looked up in
/// those rows.
pub fn is_closed(mesh: &Mesh) -> bool {
    let nv = mesh.vertices.len();
    let mut start = vec![0u32; nv + 1];
    for t in &mesh.triangles {
        if t.iter().any(|&v| v as usize >= nv) || t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
            return false;
        }
        for &v in t {
            start[v as usize + 1] += 1;
        }
    }
    for v in 0..nv {
        start[v + 1] += start[v];
    }
    let mut fill = start.clone();
    let mut to = vec![0u32; start[nv] as usize];
    for t in &mesh.triangles {
        for q in 0..3 {
            let a = t[q] as usize;
            to[fill[a] as usize] = t[(q + 1) % 3];
            fill[a] += 1;
        }
    }
    for v in 0..nv {
        to[start[v] as usize..start[v + 1] as usize].sort_unstable();
    }
    let row = |v: u32| &to[start[v as usize] as usize..start[v as usize + 1] as usize];
    (0..nv as u32).all(|a| row(a).windows(2).all(|w| w[0] != w[1]) && row(a).iter().all(|&b| row(b).binary_search(&a).is_ok()))
}

/// Connected pieces of the mesh (vertices joined by triangle edges; unused vertices ignored).
pub fn components(mesh: &Mesh) -> usize {
    let mut parent: Vec<u32> = (0..mesh.vertices.len() as u32).collect();
    fn root(parent: &mut [u32], mut v: u32) -> u32 {
        while parent[v as usize] != v {
            let up = parent[parent[v as usize] as usize];
            parent[v as usize] = up;
            v = up;
        }
        v
    }
    let mut used = vec![false; mesh.vertices.len()];
    for t in &mesh.triangles {
        for q in 0..3 {
            used[t[q] as usize] = true;
            let (a, b) = (root(&mut parent, t[q]), root(&mut parent, t[(q + 1) % 3]));
            if a != b {
                parent[a.max(b) as usize] = a.min(b);
            }
        }
    }
    (0..mesh.vertices.len() as u32).filter(|&v| used[v as usize] && root(&mut parent, v) == v).count()
}

/// Binary STL of `mesh` (the mesh's own writer, [`Mesh::to_stl_binary`]), with `name` in the
/// header: `weft isosurface <name>`, printable ASCII only, cut at 80 bytes (the header never
/// starts with `solid`, which some readers take for text STL).
pub fn write_stl(mesh: &Mesh, name: &str) -> Vec<u8> {
    let mut out = mesh.to_stl_binary();
    let mut header = [b' '; 80];
    let text: Vec<u8> = format!("weft isosurface {name}").bytes().filter(|b| (0x20..0x7f).contains(b)).take(80).collect();
    header[..text.len()].copy_from_slice(&text);
    out[..80].copy_from_slice(&header);
    out
}

/// Form rows of [`Options`] (paths relative to it).
pub const FIELDS: &[Field] = &[
    num(
        "iso",
        "Surface model",
        "Isovalue",
        "HU",
        -100000.0,
        100000.0,
        1.0,
        "The boundary of the tissue: voxels at or above it are solid (the paper's bone threshold: 350 HU).",
    ),
    other(
        "fill_cavities",
        "Surface model",
        "Fill cavities",
        FieldKind::Bool,
        &[],
        "Close voids inside the solid (the medullary canal) so the part is one solid.",
    ),
    int("smoothing_iterations", "Surface model", "Smoothing", 0.0, 200.0, "Taubin smoothing passes over the mesh (0: the raw marching-cubes surface)."),
];

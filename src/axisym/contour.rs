//! Where a part meets the curved build platform: the paper's domain Ω₂ ("an actual slice
//! polygon", Guzman-Bautista et al. 2025, sections 2.2 and 2.6) as closed polygons in the
//! platform's (u, θ) map.
//!
//! Method:
//! 1. Every vertex gets its signed distance to the platform surface offset outward by
//!    [`Options::offset_mm`], measured in the (r = √(x² + y²), z) half-plane: the closest
//!    generatrix point is found on a dense polyline of samples, then polished by Newton steps
//!    on u (the generatrix may turn back in z, as the barrel does, so no monotone search).
//!    Positive outside (along the outward normal (−z′, x′)/|S′|).
//! 2. Marching triangles: a triangle whose vertices lie on both sides gives one segment
//!    between its two crossed edges. A vertex at distance exactly 0 counts as outside, so a
//!    crossing never sits on a vertex's "both sides" and the topology stays consistent.
//! 3. Each crossed edge's zero is found once (regula falsi on the true distance along the
//!    3-D edge, not a linear guess: the point then lies on both the mesh and the platform) and
//!    mapped to (u, θ) by its closest generatrix point and θ = atan2(y, x).
//! 4. Segments chain through the crossed edges they share, keyed by the mesh edge (min vertex,
//!    max vertex): exact, no tolerance. [`crate::slice::stitch`] is not reused because it chains
//!    rounded micrometre points in a plane with gap closing; here the edge key is exact and θ
//!    wraps, so a few lines of edge-keyed chaining are simpler and cannot merge wrong points.
//!
//! Output convention: u horizontal, θ vertical; outer loops counter-clockwise, holes
//! clockwise; θ unwrapped along each loop (a hole is put on its outer loop's 2π branch).
//!
//! Deterministic: sorting only, no hash maps; transcendentals through `libm`.

use super::platform::{Jet, Platform, Profile};
use crate::budget::{Estimate, OverBudget};
use crate::geom::Mesh;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// Default outward offset of the cutting surface from the platform, mm (0: the platform
/// itself; layer k of a print uses k × layer height).
pub const DEFAULT_OFFSET_MM: f64 = 0.0;
/// Default tolerance on the distance of a crossing point from the cutting surface, mm. The
/// regula falsi stops below it; 1 nm is far below any printer's resolution and costs a few
/// iterations.
pub const DEFAULT_TOLERANCE_MM: f64 = 1e-9;
/// Default distance on the platform under which consecutive loop points merge, mm (the cut
/// through a vertex lying exactly on the surface gives repeated points).
pub const DEFAULT_MERGE_MM: f64 = 1e-6;
/// Default generatrix samples per Bézier segment for the closest-point search. The polyline
/// only picks the branch; Newton polishes u. 64 resolves features down to 1/64 of a segment.
pub const DEFAULT_SAMPLES_PER_SEGMENT: usize = 64;
/// Largest mesh taken, triangles (the per-triangle tables fit the stage budget well below it).
pub const MAX_TRIANGLES: usize = 20_000_000;

// Measured with `cargo test --release --lib axisym::contour -- --nocapture` (see
// `timing_on_a_100k_triangle_sphere`): 0.6–1.15 µs per triangle (99k triangles in 61–114 ms) for
// distances, crossings and chaining together, with other tests running alongside; rounded up.
const SECONDS_PER_TRIANGLE: f64 = 1.5e-6;
// Distance per vertex (8 B), up to one segment (2 × u32) and two incidences per crossing
// triangle, and sort scratch: 48 B per triangle bounds them.
const BYTES_PER_TRIANGLE: f64 = 48.0;

/// Settings of [`platform_contours`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Options {
    /// See [`DEFAULT_OFFSET_MM`]. May be negative (inward) but must stay below the platform's
    /// smallest radius of curvature, where the offset surface would fold.
    pub offset_mm: f64,
    /// See [`DEFAULT_TOLERANCE_MM`].
    pub tolerance_mm: f64,
    /// See [`DEFAULT_MERGE_MM`].
    pub merge_mm: f64,
    /// See [`DEFAULT_SAMPLES_PER_SEGMENT`].
    pub samples_per_segment: usize,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            offset_mm: DEFAULT_OFFSET_MM,
            tolerance_mm: DEFAULT_TOLERANCE_MM,
            merge_mm: DEFAULT_MERGE_MM,
            samples_per_segment: DEFAULT_SAMPLES_PER_SEGMENT,
        }
    }
}

/// The contour of a part on the (offset) platform.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Contours {
    /// Closed polygons of (u, θ) (the last point does not repeat the first), largest platform
    /// area first. Outer loops counter-clockwise with u horizontal and θ vertical, holes
    /// clockwise. A point maps back to 3-D as `position(p, u, θ) + offset_mm · normal(p, u, θ)`.
    pub loops: Vec<Vec<[f64; 2]>>,
    /// Per loop: the smallest loop containing it (`None`: an outer loop).
    pub parent: Vec<Option<usize>>,
    /// Per loop: whether it is a hole (contained in an odd number of loops).
    pub is_hole: Vec<bool>,
    /// Per loop: the area it encloses on the platform, mm² (∫∫ x(u)·√(x′² + z′²) du dθ; an
    /// outer loop's area does not subtract its holes).
    pub area_mm2: Vec<f64>,
    /// Chains that did not close (the mesh is open or non-manifold there); dropped.
    pub open_chains: usize,
    /// Closed loops dropped for having fewer than three distinct points (a tangent touch).
    pub degenerate_loops: usize,
}

/// Why no contour could be made.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum Error {
    /// The mesh has no triangles.
    #[error("axisymmetric contour: the mesh has no triangles; load a part")]
    EmptyMesh,
    /// A vertex is NaN or infinite.
    #[error("axisymmetric contour: vertex {index} is {value:?}, not finite; repair the mesh (its file has a broken vertex)")]
    NonFiniteVertex {
        /// Vertex index.
        index: usize,
        /// Its coordinates.
        value: [f32; 3],
    },
    /// A triangle refers to a vertex that does not exist.
    #[error("axisymmetric contour: triangle {triangle} refers to vertex {index} but the mesh has {vertices} vertices; repair the mesh")]
    BadIndex {
        /// Triangle index.
        triangle: usize,
        /// The index out of range.
        index: u32,
        /// Vertex count.
        vertices: usize,
    },
    /// The part lies wholly on one side of the cutting surface.
    #[error("axisymmetric contour: the part does not meet the platform surface (offset {offset_mm} mm): it lies wholly {side} it, its nearest vertex {distance_mm:.4} mm away at ({:.3}, {:.3}, {:.3}) mm (platform u = {u:.5}); move the part by that much {toward} the platform", at_mm[0], at_mm[1], at_mm[2])]
    NoContact {
        /// Smallest |signed distance| of a vertex, mm.
        distance_mm: f64,
        /// That vertex, mm.
        at_mm: [f64; 3],
        /// Its closest generatrix parameter.
        u: f64,
        /// `outside` or `inside`.
        side: &'static str,
        /// Which way to move the part, in plain words.
        toward: &'static str,
        /// The offset used.
        offset_mm: f64,
    },
    /// A loop goes around the platform's axis: not a patch of the (u, θ) map.
    #[error("axisymmetric contour: a contour loop of {points} points starting at (u, θ) = ({:.5}, {:.5}) winds {turns} time(s) around the platform's axis; the infill domain must be a patch (θ span under 2π): print a part that does not wrap around the platform, or split it", first[0], first[1])]
    WindsAroundAxis {
        /// The loop's first point (u, θ).
        first: [f64; 2],
        /// Its point count.
        points: usize,
        /// Signed turns around the axis.
        turns: i64,
    },
    /// Over a count limit or the stage budgets.
    #[error("axisymmetric contour: {0}")]
    TooBig(#[from] OverBudget),
    /// An option is out of range.
    #[error("axisymmetric contour: option {name} = {value} is out of range: {hint}")]
    BadOption {
        /// Option name.
        name: &'static str,
        /// Value given.
        value: f64,
        /// Allowed range.
        hint: &'static str,
    },
}

/// The work of [`platform_contours`] on a mesh of `triangles` triangles (pass the larger of the
/// triangle and vertex counts): peak memory and time; refused over [`MAX_TRIANGLES`] or the
/// shared budgets.
pub fn estimate(triangles: usize) -> Estimate {
    let t = triangles as f64;
    Estimate::new("axisym_contour")
        .quantity("triangles", "Triangles", t, "")
        .cost(t * BYTES_PER_TRIANGLE, t * SECONDS_PER_TRIANGLE)
        .limit("triangles", t, MAX_TRIANGLES as f64, "", "decimate the mesh (fewer triangles) before cutting it with the platform")
        .budgets("decimate the mesh")
}

/// The contour where the platform surface, offset outward by `o.offset_mm`, cuts `mesh`, as
/// closed (u, θ) polygons. See the module documentation for the method and conventions.
pub fn platform_contours(mesh: &Mesh, platform: &Platform, o: &Options) -> Result<Contours, Error> {
    check_options(o)?;
    if mesh.triangles.is_empty() {
        return Err(Error::EmptyMesh);
    }
    estimate(mesh.triangles.len().max(mesh.vertices.len())).check()?;
    let nv = mesh.vertices.len();
    if let Some(index) = mesh.vertices.iter().position(|v| !v.iter().all(|c| c.is_finite())) {
        return Err(Error::NonFiniteVertex { index, value: mesh.vertices[index] });
    }
    for (triangle, t) in mesh.triangles.iter().enumerate() {
        if let Some(&index) = t.iter().find(|&&i| i as usize >= nv) {
            return Err(Error::BadIndex { triangle, index, vertices: nv });
        }
    }
    let g = Generatrix::new(platform, o.samples_per_segment);
    let p3 = |i: u32| {
        let v = mesh.vertices[i as usize];
        [v[0] as f64, v[1] as f64, v[2] as f64]
    };

    // 1. Signed distances of the vertices the triangles use (others stay NaN, never read);
    // exact near the surface, the polyline's value (sign only) away from it.
    let mut used = vec![false; nv];
    for t in &mesh.triangles {
        for &i in t {
            used[i as usize] = true;
        }
    }
    let mut dist = vec![f64::NAN; nv];
    for i in 0..nv {
        if used[i] {
            dist[i] = g.classify(p3(i as u32), o.offset_mm);
        }
    }
    let inside = |i: u32| dist[i as usize] < 0.0;

    // 2. Segments between crossed edges, keyed (min vertex, max vertex).
    let key = |a: u32, b: u32| if a < b { (a, b) } else { (b, a) };
    let mut seg_keys: Vec<[(u32, u32); 2]> = Vec::new();
    for t in &mesh.triangles {
        let mut ks = [(0u32, 0u32); 3];
        let mut n = 0;
        for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            if inside(a) != inside(b) {
                ks[n] = key(a, b);
                n += 1;
            }
        }
        // A triangle with a repeated vertex crosses the same edge twice: no segment.
        if n == 2 && ks[0] != ks[1] {
            seg_keys.push([ks[0], ks[1]]);
        }
    }
    if seg_keys.is_empty() {
        return no_contact(mesh, &g, &dist, &used, o.offset_mm);
    }
    let mut edges: Vec<(u32, u32)> = seg_keys.iter().flatten().copied().collect();
    edges.sort_unstable();
    edges.dedup();
    let eidx = |k: (u32, u32)| edges.binary_search(&k).unwrap_or(0) as u32;
    let segs: Vec<[u32; 2]> = seg_keys.iter().map(|s| [eidx(s[0]), eidx(s[1])]).collect();
    drop(seg_keys);

    // 3. Each crossed edge's point on the cutting surface, as (u, θ).
    let uv: Vec<[f64; 2]> = edges
        .iter()
        .map(|&(a, b)| {
            let (pa, pb) = (p3(a), p3(b));
            let at = |t: f64| [pa[0] + t * (pb[0] - pa[0]), pa[1] + t * (pb[1] - pa[1]), pa[2] + t * (pb[2] - pa[2])];
            let (t, u) = g.zero_on_edge(&at, dist[a as usize], dist[b as usize], o.offset_mm, o.tolerance_mm);
            let q = at(t);
            [u, libm::atan2(q[1], q[0])]
        })
        .collect();

    // 4. Chains through shared edges: incidence table sorted by edge (CSR), walked in order.
    let mut start = vec![0u32; edges.len() + 1];
    for s in &segs {
        start[s[0] as usize + 1] += 1;
        start[s[1] as usize + 1] += 1;
    }
    for i in 0..edges.len() {
        start[i + 1] += start[i];
    }
    let mut fill = start.clone();
    let mut inc = vec![0u32; 2 * segs.len()];
    for (si, s) in segs.iter().enumerate() {
        for &e in s {
            inc[fill[e as usize] as usize] = si as u32;
            fill[e as usize] += 1;
        }
    }
    drop(fill);
    let mut done = vec![false; segs.len()];
    // The next unused segment at edge e, and the edge at its other end.
    let step = |e: u32, done: &mut Vec<bool>| -> Option<u32> {
        for &si in &inc[start[e as usize] as usize..start[e as usize + 1] as usize] {
            if !done[si as usize] {
                done[si as usize] = true;
                let s = segs[si as usize];
                return Some(if s[0] == e { s[1] } else { s[0] });
            }
        }
        None
    };
    let mut raw_loops: Vec<Vec<u32>> = Vec::new();
    let mut open_chains = 0;
    for first in 0..segs.len() {
        if done[first] {
            continue;
        }
        done[first] = true;
        let [e0, e1] = segs[first];
        let mut chain = vec![e0, e1];
        let mut cur = e1;
        let closed = loop {
            if cur == e0 {
                break true;
            }
            match step(cur, &mut done) {
                Some(next) => {
                    chain.push(next);
                    cur = next;
                }
                None => break false,
            }
        };
        if closed {
            chain.pop();
            raw_loops.push(chain);
        } else {
            // Consume the chain's other half too so it counts once.
            let mut back = e0;
            while let Some(next) = step(back, &mut done) {
                back = next;
            }
            open_chains += 1;
        }
    }

    // 5. (u, θ) loops: unwrap θ, refuse winding loops, merge near-duplicates.
    let area_table = AreaTable::new(&g);
    let mut loops: Vec<(Vec<[f64; 2]>, f64)> = Vec::new();
    let mut degenerate_loops = 0;
    for chain in &raw_loops {
        let mut pts: Vec<[f64; 2]> = Vec::with_capacity(chain.len());
        for &e in chain {
            let [u, t] = uv[e as usize];
            let t = match pts.last() {
                Some(p) => p[1] + wrap(t - p[1]),
                None => t,
            };
            pts.push([u, t]);
        }
        let (lo, hi) = pts.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| (lo.min(p[1]), hi.max(p[1])));
        let (last, first) = (pts[pts.len() - 1][1], pts[0][1]);
        let total = last + wrap(first - last) - first;
        if total.abs() > PI || hi - lo >= 2.0 * PI {
            let turns = libm::round(total / (2.0 * PI)) as i64;
            return Err(Error::WindsAroundAxis { first: pts[0], points: pts.len(), turns });
        }
        merge_close(&mut pts, &g, o.merge_mm);
        if pts.len() < 3 {
            degenerate_loops += 1;
            continue;
        }
        let area = area_table.loop_integral(&pts).abs();
        loops.push((pts, area));
    }
    // Largest first; ties by first point so the order never depends on the walk alone.
    loops.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0[0][0].total_cmp(&b.0[0][0])).then(a.0[0][1].total_cmp(&b.0[0][1])));

    // 6. Nesting: the smallest containing loop is the parent (θ tested on the ±2π branches).
    let n = loops.len();
    let mut parent: Vec<Option<usize>> = vec![None; n];
    let mut depth = vec![0usize; n];
    for i in 0..n {
        let p = loops[i].0[0];
        // A container encloses more area, so it comes earlier; the last one found is the smallest.
        for (j, outer) in loops.iter().enumerate().take(i) {
            if [0.0, 2.0 * PI, -2.0 * PI].into_iter().any(|s| inside_polygon([p[0], p[1] + s], &outer.0)) {
                depth[i] += 1;
                parent[i] = Some(j);
            }
        }
    }
    // Holes onto their outer loop's 2π branch; orientation by depth.
    for i in 0..n {
        if let Some(pi) = parent[i] {
            let p = loops[i].0[0];
            let shift = [0.0, 2.0 * PI, -2.0 * PI].into_iter().find(|&s| inside_polygon([p[0], p[1] + s], &loops[pi].0)).unwrap_or(0.0);
            if shift != 0.0 {
                for q in &mut loops[i].0 {
                    q[1] += shift;
                }
            }
        }
        let hole = depth[i] % 2 == 1;
        if (shoelace(&loops[i].0) > 0.0) == hole {
            loops[i].0.reverse();
        }
    }
    let is_hole = depth.iter().map(|d| d % 2 == 1).collect();
    let area_mm2 = loops.iter().map(|l| l.1).collect();
    Ok(Contours { loops: loops.into_iter().map(|l| l.0).collect(), parent, is_hole, area_mm2, open_chains, degenerate_loops })
}

fn check_options(o: &Options) -> Result<(), Error> {
    if !o.offset_mm.is_finite() || o.offset_mm.abs() > 1e4 {
        return Err(Error::BadOption { name: "offset_mm", value: o.offset_mm, hint: "a finite offset within ±10 000 mm (k × layer height for layer k)" });
    }
    if !(o.tolerance_mm > 0.0 && o.tolerance_mm <= 0.1) {
        return Err(Error::BadOption { name: "tolerance_mm", value: o.tolerance_mm, hint: "between 0 (exclusive) and 0.1 mm; 1e-9 is the default" });
    }
    if !(o.merge_mm >= 0.0 && o.merge_mm <= 0.1) {
        return Err(Error::BadOption { name: "merge_mm", value: o.merge_mm, hint: "between 0 and 0.1 mm; 1e-6 is the default" });
    }
    if !(4..=4096).contains(&o.samples_per_segment) {
        return Err(Error::BadOption { name: "samples_per_segment", value: o.samples_per_segment as f64, hint: "between 4 and 4096; 64 is the default" });
    }
    Ok(())
}

/// The `NoContact` error: the used vertex nearest the cutting surface.
fn no_contact(mesh: &Mesh, g: &Generatrix, dist: &[f64], used: &[bool], offset_mm: f64) -> Result<Contours, Error> {
    let best = (0..dist.len()).filter(|&i| used[i]).min_by(|&a, &b| dist[a].abs().total_cmp(&dist[b].abs()));
    let Some(i) = best else {
        // Only reachable with no used vertex, i.e. no triangle: handled before.
        return Err(Error::EmptyMesh);
    };
    let v = mesh.vertices[i];
    let at = [v[0] as f64, v[1] as f64, v[2] as f64];
    // Every triangle on one side, yet a vertex can sit at exactly 0 (outside by convention):
    // then the part only touches the surface, and says so with distance 0.
    let (d, u) = g.signed(at);
    let d = d - offset_mm;
    let out = d >= 0.0;
    Err(Error::NoContact {
        distance_mm: d.abs(),
        at_mm: at,
        u,
        side: if out { "outside" } else { "inside" },
        toward: if out { "toward (into)" } else { "out of" },
        offset_mm,
    })
}

/// Wraps an angle difference into (−π, π].
fn wrap(d: f64) -> f64 {
    let w = d - 2.0 * PI * libm::round(d / (2.0 * PI));
    if w <= -PI {
        w + 2.0 * PI
    } else {
        w
    }
}

/// Twice the signed area in the (u, θ) plane (positive: counter-clockwise, u horizontal).
fn shoelace(p: &[[f64; 2]]) -> f64 {
    let n = p.len();
    (0..n)
        .map(|i| {
            let (a, b) = (p[i], p[(i + 1) % n]);
            a[0] * b[1] - b[0] * a[1]
        })
        .sum()
}

/// Even-odd point-in-polygon test in (u, θ).
fn inside_polygon(q: [f64; 2], poly: &[[f64; 2]]) -> bool {
    let mut inside = false;
    let n = poly.len();
    let mut j = n - 1;
    for i in 0..n {
        let (a, b) = (poly[i], poly[j]);
        if (a[1] > q[1]) != (b[1] > q[1]) && q[0] < a[0] + (q[1] - a[1]) * (b[0] - a[0]) / (b[1] - a[1]) {
            inside = !inside;
        }
        j = i;
    }
    inside
}

/// Drops points closer than `merge_mm` (on the platform, first-order metric) to the previous
/// kept point, including across the loop's closing edge.
fn merge_close(pts: &mut Vec<[f64; 2]>, g: &Generatrix, merge_mm: f64) {
    let close = |a: [f64; 2], b: [f64; 2]| {
        let j = g.p.jet(0.5 * (a[0] + b[0]));
        let (du, dt) = (b[0] - a[0], b[1] - a[1]);
        let ds2 = (j.x[1] * j.x[1] + j.z[1] * j.z[1]) * du * du + j.x[0] * j.x[0] * dt * dt;
        ds2 <= merge_mm * merge_mm
    };
    let mut out: Vec<[f64; 2]> = Vec::with_capacity(pts.len());
    for &p in pts.iter() {
        if out.last().is_none_or(|&q| !close(q, p)) {
            out.push(p);
        }
    }
    while out.len() > 1 && close(out[out.len() - 1], out[0]) {
        out.pop();
    }
    *pts = out;
}

/// The generatrix as a dense polyline (for choosing the branch) plus the exact profile (for
/// Newton): the closest point in the (r, z) half-plane.
struct Generatrix<'a> {
    p: &'a Platform,
    /// (u, x, z) samples.
    s: Vec<[f64; 3]>,
    lo: f64,
    hi: f64,
    /// Bound on the polyline's distance from the curve (mm, with a safety factor): a point
    /// farther than twice this from the polyline is on the same side of the curve.
    sag: f64,
}

impl<'a> Generatrix<'a> {
    fn new(p: &'a Platform, per_segment: usize) -> Generatrix<'a> {
        let (lo, hi) = p.u_range();
        let n = per_segment * p.segments.len();
        let s = (0..=n)
            .map(|i| {
                let u = lo + (hi - lo) * i as f64 / n as f64;
                let j = p.jet(u);
                [u, j.x[0], j.z[0]]
            })
            .collect::<Vec<[f64; 3]>>();
        // Chord sagitta measured at the quarter points of every interval, doubled.
        let mut sag: f64 = 0.0;
        for w in s.windows(2) {
            let (a, b) = (w[0], w[1]);
            let (dx, dz) = (b[1] - a[1], b[2] - a[2]);
            let l = libm::hypot(dx, dz);
            for f in [0.25, 0.5, 0.75] {
                let j = p.jet(a[0] + f * (b[0] - a[0]));
                let off = if l > 0.0 { ((j.x[0] - a[1]) * dz - (j.z[0] - a[2]) * dx).abs() / l } else { libm::hypot(j.x[0] - a[1], j.z[0] - a[2]) };
                sag = sag.max(off);
            }
        }
        Generatrix { p, s, lo, hi, sag: 2.0 * sag + 1e-9 }
    }

    /// The signed distance minus `offset` where its sign is all that matters: the polyline's
    /// value when it is clearly away from zero (most vertices; no Newton steps), the exact one
    /// otherwise.
    fn classify(&self, q: [f64; 3], offset: f64) -> f64 {
        let r = libm::hypot(q[0], q[1]);
        let (d, _) = self.polyline(r, q[2]);
        if (d - offset).abs() > 2.0 * self.sag {
            return d - offset;
        }
        self.signed_rz(r, q[2]).0 - offset
    }

    /// Signed distance to the sample polyline and the u of its nearest point. A nearest point
    /// at a polyline corner has the right sign with either neighbouring segment's normal.
    fn polyline(&self, r: f64, z: f64) -> (f64, f64) {
        let (mut best, mut u0, mut side) = (f64::INFINITY, self.lo, 0.0);
        for w in self.s.windows(2) {
            let (a, b) = (w[0], w[1]);
            let (dx, dz) = (b[1] - a[1], b[2] - a[2]);
            let l2 = dx * dx + dz * dz;
            let t = if l2 > 0.0 { (((r - a[1]) * dx + (z - a[2]) * dz) / l2).clamp(0.0, 1.0) } else { 0.0 };
            let (px, pz) = (r - a[1] - t * dx, z - a[2] - t * dz);
            let d2 = px * px + pz * pz;
            if d2 < best {
                best = d2;
                u0 = a[0] + t * (b[0] - a[0]);
                side = -px * dz + pz * dx;
            }
        }
        let d = best.sqrt();
        (if side >= 0.0 { d } else { -d }, u0)
    }

    /// Signed distance of a 3-D point to the platform (positive outside) and the closest u.
    fn signed(&self, q: [f64; 3]) -> (f64, f64) {
        let r = libm::hypot(q[0], q[1]);
        self.signed_rz(r, q[2])
    }

    fn signed_rz(&self, r: f64, z: f64) -> (f64, f64) {
        // Nearest point of the polyline: picks the right branch of a generatrix that turns.
        let (_, u0) = self.polyline(r, z);
        // Newton on (S − P)·S′ = 0, steps limited to one sample spacing so it stays on the branch.
        let h = (self.hi - self.lo) / (self.s.len() - 1) as f64;
        let d2_at = |j: &Jet| (j.x[0] - r).powi(2) + (j.z[0] - z).powi(2);
        let mut u = u0;
        let mut j = self.p.jet(u);
        for _ in 0..8 {
            let (ex, ez) = (j.x[0] - r, j.z[0] - z);
            let f = ex * j.x[1] + ez * j.z[1];
            let df = j.x[1] * j.x[1] + j.z[1] * j.z[1] + ex * j.x[2] + ez * j.z[2];
            if df.is_nan() || df <= 0.0 {
                break;
            }
            let du = (-f / df).clamp(-h, h);
            let un = (u + du).clamp(self.lo, self.hi);
            if un == u {
                break;
            }
            u = un;
            j = self.p.jet(u);
            if du.abs() < 1e-13 {
                break;
            }
        }
        let j0 = self.p.jet(u0);
        let (u, j) = if d2_at(&j) <= d2_at(&j0) { (u, j) } else { (u0, j0) };
        let (ex, ez) = (r - j.x[0], z - j.z[0]);
        let d = libm::hypot(ex, ez);
        // Outward normal (−z′, x′): positive when the point lies on its side.
        let side = -ex * j.z[1] + ez * j.x[1];
        (if side >= 0.0 { d } else { -d }, u)
    }

    /// The zero of the signed distance (minus `offset`) on the edge at(t), t ∈ [0, 1], given
    /// its values at the ends (of opposite classes): regula falsi (Illinois), returning t and
    /// the closest u there.
    fn zero_on_edge(&self, at: &dyn Fn(f64) -> [f64; 3], fa: f64, fb: f64, offset: f64, tol: f64) -> (f64, f64) {
        let (mut a, mut b, mut fa, mut fb) = (0.0, 1.0, fa, fb);
        // A vertex at exactly 0 is the crossing itself.
        if fa == 0.0 {
            return (0.0, self.signed(at(0.0)).1);
        }
        if fb == 0.0 {
            return (1.0, self.signed(at(1.0)).1);
        }
        let mut side = 0;
        let (mut t, mut u) = (0.5, self.lo);
        for _ in 0..100 {
            t = if fb != fa { (a * fb - b * fa) / (fb - fa) } else { 0.5 * (a + b) };
            if !(t > a && t < b) {
                t = 0.5 * (a + b);
            }
            let (d, uu) = self.signed(at(t));
            u = uu;
            let f = d - offset;
            if f.abs() <= tol || b - a < 1e-15 {
                break;
            }
            if (f < 0.0) == (fa < 0.0) {
                a = t;
                fa = f;
                if side == -1 {
                    fb *= 0.5;
                }
                side = -1;
            } else {
                b = t;
                fb = f;
                if side == 1 {
                    fa *= 0.5;
                }
                side = 1;
            }
        }
        (t, u)
    }
}

/// F(u) = ∫ x √(x′² + z′²) du from u_min, tabulated with its derivative for cubic Hermite
/// interpolation: the platform area of a (u, θ) loop is ∮ F dθ (Green's theorem).
struct AreaTable<'a> {
    p: &'a Platform,
    lo: f64,
    h: f64,
    f: Vec<f64>,
}

impl<'a> AreaTable<'a> {
    fn new(g: &Generatrix<'a>) -> AreaTable<'a> {
        let n = 256 * g.p.segments.len();
        let h = (g.hi - g.lo) / n as f64;
        let dfa = |u: f64| {
            let j = g.p.jet(u);
            j.x[0] * libm::hypot(j.x[1], j.z[1])
        };
        // 3-point Gauss–Legendre per interval: exact to degree 5, far below the loops' error.
        let (gx, gw) = ([-0.774_596_669_241_483_4, 0.0, 0.774_596_669_241_483_4], [5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0]);
        let mut f = vec![0.0; n + 1];
        for i in 0..n {
            let m = g.lo + (i as f64 + 0.5) * h;
            let s: f64 = (0..3).map(|k| gw[k] * dfa(m + 0.5 * h * gx[k])).sum();
            f[i + 1] = f[i] + 0.5 * h * s;
        }
        AreaTable { p: g.p, lo: g.lo, h, f }
    }

    fn value(&self, u: f64) -> f64 {
        let n = self.f.len() - 1;
        let s = ((u - self.lo) / self.h).clamp(0.0, n as f64);
        let i = (libm::floor(s) as usize).min(n - 1);
        let t = s - i as f64;
        let d = |k: usize| {
            let j = self.p.jet(self.lo + k as f64 * self.h);
            j.x[0] * libm::hypot(j.x[1], j.z[1]) * self.h
        };
        let (h00, h10, h01, h11) = (2.0 * t * t * t - 3.0 * t * t + 1.0, t * t * t - 2.0 * t * t + t, -2.0 * t * t * t + 3.0 * t * t, t * t * t - t * t);
        h00 * self.f[i] + h10 * d(i) + h01 * self.f[i + 1] + h11 * d(i + 1)
    }

    /// ∮ F dθ over the closed polygon (straight edges in (u, θ)), 3-point Gauss per edge.
    fn loop_integral(&self, pts: &[[f64; 2]]) -> f64 {
        let (gx, gw) = ([-0.774_596_669_241_483_4, 0.0, 0.774_596_669_241_483_4], [5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0]);
        let n = pts.len();
        (0..n)
            .map(|i| {
                let (a, b) = (pts[i], pts[(i + 1) % n]);
                let s: f64 = (0..3).map(|k| gw[k] * self.value(a[0] + 0.5 * (1.0 + gx[k]) * (b[0] - a[0]))).sum();
                0.5 * s * (b[1] - a[1])
            })
            .sum()
    }
}

#[cfg(test)]
mod tests;

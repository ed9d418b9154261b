//! A mesh that must be a closed solid, made one out loud or refused.
//!
//! A slot that fills a solid (a part to slice, a lattice's solid, a foam region) cannot use
//! an open or inconsistently oriented surface: the slicer's NonZero union reads a reversed
//! shell as a hole and an open wall as a gap, so the part would print as less than itself.
//! [`close_solid`] does what admesh and PrusaSlicer's repair do, within stated bounds, and
//! says what it did:
//!
//! 1. **Orientation.** Triangles are made consistent with their neighbours across every
//!    shared edge (a walk over each connected shell). A shell that no other shell's box holds
//!    is turned so it encloses a positive volume; a shell inside another keeps the side most
//!    of its triangles had (a cavity stays a cavity).
//! 2. **Holes.** Edges used by one triangle are chained into loops. A loop is capped (ear
//!    clipping in its best-fit plane, the cap oriented like its rim) when it is flat: no point
//!    further than [`FLAT_MM`] or [`FLAT_RATIO`] of its width from its plane, so the cap is
//!    where the missing surface was (a missing wall, a missing triangle, an open tube's end).
//!    A hole that is not flat, longer than [`MAX_CAP_EDGES`], or whose caps would be more
//!    than [`MAX_CAP_SHARE`] of the part's surface (an open sheet, not a solid with a hole)
//!    is refused, naming each hole by its place, edges and area.
//!
//! Deterministic (sorted edge lists, loops in order of their first edge) and bounded: one
//! sort of the 3 edges per triangle, a linear walk over the shells, and ear clipping whose
//! corner tests stop at [`MAX_CLIP_TESTS`] for all holes together (then each corner is found
//! in linear steps). Memory: about 60 bytes a triangle while the edges are grouped (their
//! sorted list and the pairs), freed before the caps; under the import's own high-water mark
//! ([`super::estimate`]).

use crate::geom::{DVec3, Mesh};
use serde::Serialize;

/// A hole is flat when no rim point is further than this from its plane, mm (or within
/// [`FLAT_RATIO`] of the hole's width, whichever is larger).
pub const FLAT_MM: f64 = 0.05;
/// A hole is flat when no rim point is further than this fraction of its width from its plane.
pub const FLAT_RATIO: f64 = 0.01;
/// Longest hole rim capped, edges.
pub const MAX_CAP_EDGES: usize = 4096;
/// Caps may add at most this share of the surface the mesh already has.
pub const MAX_CAP_SHARE: f64 = 0.5;
/// Holes listed one by one in a refusal (the rest are counted).
pub const MAX_LISTED: usize = 6;
/// Corner tests the ear clipping of all holes together may make; past it, each cap takes its
/// most convex corner without testing (still a cap, found in linear steps per corner).
pub const MAX_CLIP_TESTS: u64 = 50_000_000;

/// A hole in the surface: where, how big, how far from flat.
#[derive(Clone, Debug, PartialEq, Serialize, serde::Deserialize)]
pub struct Hole {
    /// Edges around it.
    pub edges: usize,
    /// Area of its cap (the area its rim spans), mm².
    pub area_mm2: f64,
    /// Mean of its rim's corners, mm (the file's coordinates).
    pub centre: [f64; 3],
    /// Furthest rim point from the rim's best-fit plane, mm.
    pub bulge_mm: f64,
}

impl Hole {
    fn place(&self) -> String {
        let c = self.centre;
        format!("{} edges, {:.1} mm² around ({:.2}, {:.2}, {:.2}) mm", self.edges, self.area_mm2, c[0], c[1], c[2])
    }
}

/// What [`close_solid`] did to a mesh that is now closed and consistently oriented.
#[derive(Clone, Debug, Default, PartialEq, Serialize, serde::Deserialize)]
pub struct Closure {
    /// Triangles turned over (their corners reversed).
    pub flipped: usize,
    /// Holes capped, in the order their rims were found.
    pub capped: Vec<Hole>,
    /// Triangles the caps added.
    pub cap_triangles: usize,
    /// Edges shared by more than two triangles (left as they are; the slicer unions them).
    pub nonmanifold_edges: usize,
}

impl Closure {
    /// Nothing was changed.
    pub fn is_clean(&self) -> bool {
        self.flipped == 0 && self.capped.is_empty()
    }

    /// Total area capped, mm².
    pub fn capped_area_mm2(&self) -> f64 {
        self.capped.iter().map(|h| h.area_mm2).sum()
    }

    /// What was repaired, one sentence each (empty when nothing was).
    pub fn notes(&self, file: &str) -> Vec<String> {
        let mut out = Vec::new();
        if !self.capped.is_empty() {
            let largest = self.capped.iter().max_by(|a, b| a.area_mm2.total_cmp(&b.area_mm2)).map(Hole::place).unwrap_or_default();
            let n = self.capped.len();
            out.push(if n == 1 {
                format!("{file}: capped 1 flat hole of {largest}: the mesh was open; check the part is whole")
            } else {
                format!(
                    "{file}: capped {n} flat holes, {:.1} mm² in all (the largest: {largest}): the mesh was open; check the part is whole",
                    self.capped_area_mm2()
                )
            });
        }
        if self.flipped > 0 {
            out.push(format!("{file}: turned {} triangle{} facing inward to face out", self.flipped, if self.flipped == 1 { "" } else { "s" }));
        }
        out
    }
}

/// Why a mesh cannot be used as a solid.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{file} is not a closed solid: {}; close the holes in the program that made it (or repair it with PrusaSlicer's or admesh's hole filling) and load it again", problems.join("; "))]
pub struct OpenError {
    /// File name.
    pub file: String,
    /// Each problem with its place.
    pub problems: Vec<String>,
}

/// Makes `mesh` a closed, consistently oriented solid as the module states, or refuses it.
/// `file` names the mesh in messages.
pub fn close_solid(file: &str, mesh: &mut Mesh) -> Result<Closure, OpenError> {
    let tris = mesh.triangles.len();
    let edges = edge_groups(mesh);
    let mut closure = Closure { nonmanifold_edges: edges.nonmanifold, ..Closure::default() };
    closure.flipped = orient(mesh, &edges);
    // Boundary half-edges in the triangles' (now consistent) directions.
    let mut boundary: Vec<(u32, u32)> = edges
        .single
        .iter()
        .map(|&slot| {
            let (t, k) = (slot as usize / 3, slot as usize % 3);
            let tri = mesh.triangles[t];
            (tri[k], tri[(k + 1) % 3])
        })
        .collect();
    if boundary.is_empty() {
        return Ok(closure);
    }
    boundary.sort_unstable();
    let (loops, broken) = trace_loops(&boundary);
    crate::work::add(boundary.len());
    let surface: f64 = (0..tris).map(|t| triangle_area(mesh, t)).sum();
    let mut problems = Vec::new();
    let mut caps: Vec<(Hole, Vec<[u32; 3]>)> = Vec::new();
    let mut tests = MAX_CLIP_TESTS;
    for rim in &loops {
        let hole = measure(mesh, rim);
        let width = 2.0 * rim.iter().map(|&v| pos(mesh, v).distance(DVec3::from(hole.centre))).fold(0.0, f64::max);
        if rim.len() > MAX_CAP_EDGES {
            problems.push(format!("a hole of {} is more than {MAX_CAP_EDGES} edges around, too large to cap", hole.place()));
        } else if hole.bulge_mm > FLAT_MM.max(FLAT_RATIO * width) {
            problems.push(format!(
                "a hole of {} is not flat (its rim bulges {:.2} mm from its plane), so no cap can stand for the missing surface",
                hole.place(),
                hole.bulge_mm
            ));
        } else {
            let cap = ear_clip(mesh, rim, &mut tests);
            caps.push((hole, cap));
        }
    }
    if broken > 0 {
        problems.push(format!("{broken} open edge(s) do not join into a hole's rim (edges shared by more than two triangles around them)"));
    }
    let cap_area: f64 = caps.iter().map(|(h, _)| h.area_mm2).sum();
    if problems.is_empty() && cap_area > MAX_CAP_SHARE * surface {
        problems.push(format!(
            "its holes span {cap_area:.1} mm², more than half of the {surface:.1} mm² of surface it has: this is an open surface, not a solid with a hole{}",
            caps.first().map(|(h, _)| format!(" (the first hole: {})", h.place())).unwrap_or_default()
        ));
    }
    if !problems.is_empty() {
        let more = problems.len().saturating_sub(MAX_LISTED);
        problems.truncate(MAX_LISTED);
        if more > 0 {
            problems.push(format!("and {more} more hole(s)"));
        }
        return Err(OpenError { file: file.into(), problems });
    }
    for (hole, cap) in caps {
        closure.cap_triangles += cap.len();
        mesh.triangles.extend(cap);
        closure.capped.push(hole);
    }
    Ok(closure)
}

/// The mesh's edges grouped by their two ends: slots (`3 × triangle + corner`) of edges used
/// once, pairs of slots of edges used twice, and a count of edges used more often.
struct EdgeGroups {
    single: Vec<u32>,
    pairs: Vec<(u32, u32)>,
    nonmanifold: usize,
}

fn edge_groups(mesh: &Mesh) -> EdgeGroups {
    let mut all: Vec<(u64, u32)> = Vec::with_capacity(mesh.triangles.len() * 3);
    for (t, tri) in mesh.triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            let key = (u64::from(a.min(b)) << 32) | u64::from(a.max(b));
            all.push((key, (3 * t + k) as u32));
        }
    }
    crate::par::sort_unstable_by(&mut all, |a, b| a.cmp(b));
    crate::work::add(all.len());
    let mut groups = EdgeGroups { single: Vec::new(), pairs: Vec::new(), nonmanifold: 0 };
    for run in all.chunk_by(|a, b| a.0 == b.0) {
        match run {
            [one] => groups.single.push(one.1),
            [a, b] => groups.pairs.push((a.1, b.1)),
            _ => groups.nonmanifold += 1,
        }
    }
    groups
}

/// Makes neighbouring triangles agree (see the module), turning triangles over in `mesh`;
/// returns how many were turned.
fn orient(mesh: &mut Mesh, edges: &EdgeGroups) -> usize {
    let n = mesh.triangles.len();
    // Neighbours across manifold edges, with whether the pair already agrees (the shared
    // edge runs opposite ways in the two).
    let dir = |mesh: &Mesh, slot: u32| {
        let (t, k) = (slot as usize / 3, slot as usize % 3);
        let tri = mesh.triangles[t];
        tri[k] < tri[(k + 1) % 3]
    };
    let mut start = vec![0u32; n + 1];
    for &(a, b) in &edges.pairs {
        start[a as usize / 3 + 1] += 1;
        start[b as usize / 3 + 1] += 1;
    }
    for i in 0..n {
        start[i + 1] += start[i];
    }
    let mut fill = start.clone();
    let mut adj = vec![(0u32, false); start[n] as usize];
    for &(a, b) in &edges.pairs {
        let agree = dir(mesh, a) != dir(mesh, b);
        let (ta, tb) = (a / 3, b / 3);
        adj[fill[ta as usize] as usize] = (tb, agree);
        fill[ta as usize] += 1;
        adj[fill[tb as usize] as usize] = (ta, agree);
        fill[tb as usize] += 1;
    }
    // Shells: each triangle's flip relative to its shell's first triangle.
    const UNSEEN: u32 = u32::MAX;
    let mut shell = vec![UNSEEN; n];
    let mut flip = vec![false; n];
    let mut shells: Vec<Vec<u32>> = Vec::new();
    let mut stack = Vec::new();
    for seed in 0..n {
        if shell[seed] != UNSEEN {
            continue;
        }
        let id = shells.len() as u32;
        let mut members = vec![seed as u32];
        shell[seed] = id;
        stack.push(seed as u32);
        while let Some(t) = stack.pop() {
            let t = t as usize;
            for &(u, agree) in &adj[start[t] as usize..start[t + 1] as usize] {
                let u = u as usize;
                if shell[u] == UNSEEN {
                    shell[u] = id;
                    flip[u] = if agree { flip[t] } else { !flip[t] };
                    members.push(u as u32);
                    stack.push(u as u32);
                }
            }
        }
        crate::work::add(members.len());
        shells.push(members);
    }
    // Each shell's box and signed volume (×6) as made consistent with its first triangle.
    let boxes: Vec<(DVec3, DVec3)> = shells
        .iter()
        .map(|m| {
            m.iter()
                .flat_map(|&t| mesh.triangles[t as usize])
                .map(|v| pos(mesh, v))
                .fold((DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)), |(lo, hi), p| (lo.min(p), hi.max(p)))
        })
        .collect();
    let mut turned = 0usize;
    for (s, members) in shells.iter().enumerate() {
        let (lo, hi) = boxes[s];
        let centre = (lo + hi) * 0.5;
        let volume: f64 = members
            .iter()
            .map(|&t| {
                let [a, b, c] = mesh.triangles[t as usize].map(|v| pos(mesh, v) - centre);
                let v = a.dot(b.cross(c));
                if flip[t as usize] {
                    -v
                } else {
                    v
                }
            })
            .sum();
        let inside = boxes.iter().enumerate().any(|(o, &(olo, ohi))| o != s && olo.cmple(lo).all() && ohi.cmpge(hi).all() && (olo != lo || ohi != hi));
        let flipped_now = members.iter().filter(|&&t| flip[t as usize]).count();
        // Turn the whole shell over when that makes it face out (or, inside another shell,
        // when most of its triangles already faced the other way).
        let turn_all = if inside { 2 * flipped_now > members.len() } else { volume < 0.0 };
        for &t in members {
            let t = t as usize;
            if flip[t] != turn_all {
                let tri = &mut mesh.triangles[t];
                tri.swap(1, 2);
                turned += 1;
            }
        }
    }
    turned
}

/// Chains sorted boundary half-edges into rims (vertex loops in the half-edges' direction).
/// Returns the rims and the count of half-edges left in chains that never closed.
fn trace_loops(boundary: &[(u32, u32)]) -> (Vec<Vec<u32>>, usize) {
    let mut used = vec![false; boundary.len()];
    let mut loops = Vec::new();
    let mut broken = 0usize;
    // The first unused half-edge leaving `v`.
    let next_from = |v: u32, used: &[bool]| -> Option<usize> {
        let first = boundary.partition_point(|&(a, _)| a < v);
        (first..boundary.len()).take_while(|&i| boundary[i].0 == v).find(|&i| !used[i])
    };
    for i in 0..boundary.len() {
        if used[i] {
            continue;
        }
        used[i] = true;
        let (a, mut cur) = boundary[i];
        let mut rim = vec![a];
        let mut chain = vec![i];
        let closed = loop {
            if cur == a {
                break true;
            }
            match next_from(cur, &used) {
                Some(j) => {
                    used[j] = true;
                    chain.push(j);
                    rim.push(cur);
                    cur = boundary[j].1;
                }
                None => break false,
            }
        };
        if closed {
            loops.push(rim);
        } else {
            broken += chain.len();
        }
    }
    (loops, broken)
}

fn pos(mesh: &Mesh, v: u32) -> DVec3 {
    let p = mesh.vertices[v as usize];
    DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64)
}

fn triangle_area(mesh: &Mesh, t: usize) -> f64 {
    let [a, b, c] = mesh.triangles[t].map(|v| pos(mesh, v));
    0.5 * (b - a).cross(c - a).length()
}

/// Area (Newell's vector area), centre and flatness of a rim.
fn measure(mesh: &Mesh, rim: &[u32]) -> Hole {
    let pts: Vec<DVec3> = rim.iter().map(|&v| pos(mesh, v)).collect();
    let centre = pts.iter().copied().sum::<DVec3>() / pts.len().max(1) as f64;
    let mut normal = DVec3::ZERO;
    for (i, p) in pts.iter().enumerate() {
        let q = pts[(i + 1) % pts.len()];
        normal += (*p - centre).cross(q - centre);
    }
    let area = 0.5 * normal.length();
    let unit = normal.normalize_or_zero();
    let bulge = if unit == DVec3::ZERO { 0.0 } else { pts.iter().map(|p| (*p - centre).dot(unit).abs()).fold(0.0, f64::max) };
    Hole { edges: rim.len(), area_mm2: area, centre: centre.to_array(), bulge_mm: bulge }
}

/// Cap triangles for `rim` (a loop in its boundary half-edges' direction): the rim reversed,
/// ear-clipped in its best-fit plane, so each cap edge runs opposite to the rim edge it meets.
fn ear_clip(mesh: &Mesh, rim: &[u32], tests: &mut u64) -> Vec<[u32; 3]> {
    let order: Vec<u32> = rim.iter().rev().copied().collect();
    let pts: Vec<DVec3> = order.iter().map(|&v| pos(mesh, v)).collect();
    let centre = pts.iter().copied().sum::<DVec3>() / pts.len().max(1) as f64;
    let mut normal = DVec3::ZERO;
    for (i, p) in pts.iter().enumerate() {
        normal += (*p - centre).cross(pts[(i + 1) % pts.len()] - centre);
    }
    let n = normal.normalize_or_zero();
    let u = if n == DVec3::ZERO { DVec3::X } else { n.any_orthonormal_vector() };
    let w = n.cross(u);
    // In the (u, w) plane the reversed rim runs counter-clockwise about n.
    let flat: Vec<[f64; 2]> = pts.iter().map(|p| [(*p - centre).dot(u), (*p - centre).dot(w)]).collect();
    let cross = |a: [f64; 2], b: [f64; 2], c: [f64; 2]| (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
    let inside = |p: [f64; 2], a: [f64; 2], b: [f64; 2], c: [f64; 2]| cross(a, b, p) > 0.0 && cross(b, c, p) > 0.0 && cross(c, a, p) > 0.0;
    let mut idx: Vec<usize> = (0..order.len()).collect();
    let mut out = Vec::with_capacity(order.len().saturating_sub(2));
    while idx.len() > 3 {
        let m = idx.len();
        crate::work::add(m);
        let mut ear = None;
        let mut best = (f64::NEG_INFINITY, 0usize);
        for i in 0..m {
            let (a, b, c) = (flat[idx[(i + m - 1) % m]], flat[idx[i]], flat[idx[(i + 1) % m]]);
            let turn = cross(a, b, c);
            if turn > best.0 {
                best = (turn, i);
            }
            if turn <= 0.0 || *tests == 0 {
                continue;
            }
            *tests = tests.saturating_sub(m as u64);
            let blocked = idx.iter().any(|&k| {
                let p = flat[k];
                p != a && p != b && p != c && inside(p, a, b, c)
            });
            if !blocked {
                ear = Some(i);
                break;
            }
        }
        // No clean ear (a rim that crosses itself in projection): the most convex corner.
        let i = ear.unwrap_or(best.1);
        let m = idx.len();
        out.push([order[idx[(i + m - 1) % m]], order[idx[i]], order[idx[(i + 1) % m]]]);
        idx.remove(i);
    }
    if idx.len() == 3 {
        out.push([order[idx[0]], order[idx[1]], order[idx[2]]]);
    }
    // A rim through one vertex twice (two holes touching at a corner) gives caps with a
    // repeated corner: no area, and their two edges cancel; left out.
    out.retain(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2]);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A closed axis-aligned box, triangles facing out.
    fn cube(size: f32) -> Mesh {
        let s = size;
        let vertices = vec![[0.0, 0.0, 0.0], [s, 0.0, 0.0], [s, s, 0.0], [0.0, s, 0.0], [0.0, 0.0, s], [s, 0.0, s], [s, s, s], [0.0, s, s]];
        let triangles = vec![
            [0, 2, 1],
            [0, 3, 2], // bottom
            [4, 5, 6],
            [4, 6, 7], // top
            [0, 1, 5],
            [0, 5, 4], // front (y = 0)
            [1, 2, 6],
            [1, 6, 5], // right (x = s)
            [2, 3, 7],
            [2, 7, 6], // back (y = s)
            [3, 0, 4],
            [3, 4, 7], // left (x = 0)
        ];
        Mesh { vertices, triangles }
    }

    fn volume(mesh: &Mesh) -> f64 {
        mesh.triangles.iter().map(|t| t.map(|v| pos(mesh, v))).map(|[a, b, c]| a.dot(b.cross(c)) / 6.0).sum()
    }

    #[test]
    fn a_closed_cube_is_left_alone() {
        let mut m = cube(10.0);
        let before = m.clone();
        let c = close_solid("cube.stl", &mut m).unwrap();
        assert!(c.is_clean(), "{c:?}");
        assert_eq!(m, before);
        assert!((volume(&m) - 1000.0).abs() < 1e-6);
    }

    #[test]
    fn a_missing_wall_is_capped_and_said() {
        let mut m = cube(10.0);
        m.triangles.drain(6..8); // the right wall
        let c = close_solid("open.stl", &mut m).unwrap();
        assert_eq!(c.capped.len(), 1);
        assert!((c.capped[0].area_mm2 - 100.0).abs() < 1e-6, "{c:?}");
        assert_eq!(c.capped[0].edges, 4);
        assert!((volume(&m) - 1000.0).abs() < 1e-6, "the cap restores the whole cube: {}", volume(&m));
        let notes = c.notes("open.stl");
        assert!(notes[0].contains("capped 1 flat hole of 4 edges, 100.0 mm² around (10.00, 5.00, 5.00) mm"), "{notes:?}");
        // Closed now: a second pass finds nothing.
        assert!(close_solid("open.stl", &mut m).unwrap().is_clean());
    }

    #[test]
    fn an_inside_out_cube_and_a_flipped_triangle_are_turned() {
        let mut m = cube(10.0);
        for t in &mut m.triangles {
            t.swap(1, 2);
        }
        let c = close_solid("inverted.stl", &mut m).unwrap();
        assert_eq!(c.flipped, 12);
        assert!((volume(&m) - 1000.0).abs() < 1e-6);
        let mut m = cube(10.0);
        m.triangles[3].swap(0, 1);
        let c = close_solid("one.stl", &mut m).unwrap();
        assert_eq!(c.flipped, 1);
        assert!((volume(&m) - 1000.0).abs() < 1e-6);
    }

    #[test]
    fn a_cavity_stays_a_cavity() {
        let mut m = cube(10.0);
        let mut inner = cube(2.0);
        for v in &mut inner.vertices {
            for c in v.iter_mut() {
                *c += 4.0;
            }
        }
        for t in &mut inner.triangles {
            t.swap(1, 2); // facing in: a void
        }
        m.append(&inner);
        let c = close_solid("hollow.stl", &mut m).unwrap();
        assert_eq!(c.flipped, 0);
        assert!((volume(&m) - 992.0).abs() < 1e-6);
    }

    #[test]
    fn an_open_sheet_and_a_curved_hole_are_refused_by_place() {
        // Two walls only: an open surface.
        let mut m = cube(10.0);
        m.triangles.truncate(2);
        let e = close_solid("sheet.stl", &mut m).unwrap_err();
        assert!(e.to_string().contains("open surface, not a solid"), "{e}");
        // A rim that is not flat: a cube without its top and one wall.
        let mut m = cube(10.0);
        m.triangles.drain(2..4);
        m.triangles.drain(4..6);
        let e = close_solid("bent.stl", &mut m).unwrap_err();
        let text = e.to_string();
        assert!(text.contains("is not flat") && text.contains("bent.stl is not a closed solid") && text.contains("mm²"), "{text}");
    }
}

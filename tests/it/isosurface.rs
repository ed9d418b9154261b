//! The isosurface stage: closed-form volumes and areas, caps on the ROI planes, cavity fill,
//! watertightness on random noise, smoothing, refusals, and the STL round trip through the
//! importer and the slicer.

use rand_core::{Rng, SeedableRng};
use rand_pcg::Pcg64;
use std::collections::HashMap;
use std::f64::consts::PI;
use weft::geom::{DVec3, Mesh};
use weft::isosurface::{estimate, extract, write_stl, Error, Options, Surface, MAX_TRIANGLES};
use weft::volume::{Roi, Volume};

/// A volume with value `f(x, y, z)` (mm, volume frame) at each voxel centre.
fn field(dims: [usize; 3], spacing_mm: [f64; 3], mut f: impl FnMut(f64, f64, f64) -> f64) -> Volume {
    let mut values = Vec::with_capacity(dims[0] * dims[1] * dims[2]);
    for k in 0..dims[2] {
        for j in 0..dims[1] {
            for i in 0..dims[0] {
                values.push(f(i as f64 * spacing_mm[0], j as f64 * spacing_mm[1], k as f64 * spacing_mm[2]) as f32);
            }
        }
    }
    Volume { dims, spacing_mm, values, ..Default::default() }
}

fn dist(x: f64, y: f64, z: f64, c: f64) -> f64 {
    ((x - c) * (x - c) + (y - c) * (y - c) + (z - c) * (z - c)).sqrt()
}

fn run(v: &Volume, roi: &Roi, o: &Options) -> Surface {
    let mut last = -1.0f32;
    let s = extract(v, roi, o, &mut |f| {
        assert!(f >= last && (0.0..=1.0).contains(&f), "progress goes 0 → 1");
        last = f;
    })
    .unwrap();
    assert_eq!(last, 1.0);
    s
}

fn opts(iso: f64, fill: bool, smoothing: u32) -> Options {
    Options { iso, fill_cavities: fill, smoothing_iterations: smoothing }
}

/// Checks, independently of the stage's own report, that every edge is used by exactly two
/// triangles in opposite directions, that indices are in range and that no two vertices share
/// a position (so an importer's weld cannot merge any). Returns the Euler characteristic.
fn assert_closed_manifold(mesh: &Mesh, what: &str) -> i64 {
    let nv = mesh.vertices.len() as u32;
    let mut directed: HashMap<(u32, u32), u32> = HashMap::new();
    for t in &mesh.triangles {
        assert!(t.iter().all(|&v| v < nv), "{what}: index out of range");
        assert!(t[0] != t[1] && t[1] != t[2] && t[0] != t[2], "{what}: repeated corner {t:?}");
        for q in 0..3 {
            *directed.entry((t[q], t[(q + 1) % 3])).or_default() += 1;
        }
    }
    for (&(a, b), &n) in &directed {
        assert_eq!(n, 1, "{what}: directed edge {a}→{b} used {n} times (inconsistent orientation or non-manifold)");
        assert_eq!(directed.get(&(b, a)), Some(&1), "{what}: edge {a}–{b} has no opposite triangle (open)");
    }
    let mut pos: Vec<[u32; 3]> = mesh.vertices.iter().map(|p| p.map(f32::to_bits)).collect();
    pos.sort_unstable();
    assert!(pos.windows(2).all(|w| w[0] != w[1]), "{what}: two vertices at one position");
    let used = {
        let mut u = vec![false; nv as usize];
        mesh.triangles.iter().flatten().for_each(|&v| u[v as usize] = true);
        u.iter().filter(|&&x| x).count()
    };
    assert_eq!(used, nv as usize, "{what}: unused vertices");
    used as i64 - (directed.len() / 2) as i64 + mesh.triangles.len() as i64
}

/// Signed volume of each connected component (labels by union–find over triangle edges).
fn component_volumes(mesh: &Mesh) -> Vec<f64> {
    let mut parent: Vec<usize> = (0..mesh.vertices.len()).collect();
    fn find(p: &mut [usize], mut v: usize) -> usize {
        while p[v] != v {
            p[v] = p[p[v]];
            v = p[v];
        }
        v
    }
    for t in &mesh.triangles {
        for q in 0..3 {
            let (a, b) = (find(&mut parent, t[q] as usize), find(&mut parent, t[(q + 1) % 3] as usize));
            parent[a] = b;
        }
    }
    let mut vols: HashMap<usize, f64> = HashMap::new();
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|v| mesh.vertex(v));
        *vols.entry(find(&mut parent, t[0] as usize)).or_default() += a.dot(b.cross(c)) / 6.0;
    }
    let mut v: Vec<f64> = vols.into_values().collect();
    v.sort_by(f64::total_cmp);
    v
}

fn unit(rng: &mut Pcg64) -> f64 {
    (rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

#[test]
fn sphere_volume_and_area_match_closed_forms() {
    let (r, c) = (10.0, 11.8);
    let v = field([60, 60, 60], [0.4; 3], |x, y, z| 350.0 + 100.0 * (r - dist(x, y, z, c)));
    let roi = Roi::whole(&v);
    let s = run(&v, &roi, &Options::default());
    let rep = &s.report;
    let (v0, a0) = (4.0 / 3.0 * PI * r * r * r, 4.0 * PI * r * r);
    assert!((rep.volume_mm3 / v0 - 1.0).abs() < 0.01, "volume {} vs {v0}", rep.volume_mm3);
    assert!((rep.area_mm2 / a0 - 1.0).abs() < 0.01, "area {} vs {a0}", rep.area_mm2);
    assert!(rep.closed);
    assert_eq!((rep.components, rep.capped, rep.cavities_filled), (1, [false; 6], 0));
    assert_eq!((rep.triangles, rep.vertices), (s.mesh.triangles.len(), s.mesh.vertices.len()));
    // A sphere: Euler characteristic 2.
    assert_eq!(assert_closed_manifold(&s.mesh, "sphere"), 2);
    // The vertices on grid edges lie on the sphere to interpolation accuracy (h²/8r).
    let worst = s.mesh.vertices.iter().map(|p| (dist(p[0] as f64, p[1] as f64, p[2] as f64, c) - r).abs()).fold(0.0, f64::max);
    assert!(worst < 0.1, "a vertex {worst} mm off the sphere");
    // The estimate states the exact count.
    let e = estimate(&v, &roi, &Options::default());
    assert_eq!((e.get("triangles"), e.get("voxels")), (rep.triangles as f64, 216_000.0));
    assert!(e.refused.is_none() && e.bytes > 80.0 * rep.triangles as f64);
    // Deterministic: the same mesh again.
    assert_eq!(run(&v, &roi, &Options::default()).mesh, s.mesh);
}

/// A 10 mm box of solid (binary field, so MC cuts edges at their midpoints: faces at ±0.5
/// voxel) cut by the ROI's +x and −z faces, which lie between voxel centres.
fn cut_box() -> (Volume, Roi) {
    let inside = |x: f64, y: f64, z: f64| (2.0..=12.0).contains(&x) && (2.0..=12.0).contains(&y) && (2.0..=12.0).contains(&z);
    let v = field([16, 16, 16], [1.0; 3], |x, y, z| if inside(x, y, z) { 1000.0 } else { -1000.0 });
    (v, Roi { min_mm: [0.0, 0.0, 4.6], max_mm: [7.3, 15.0, 15.0] })
}

#[test]
fn a_box_cut_by_the_roi_is_capped_on_the_roi_planes() {
    let (v, roi) = cut_box();
    for smoothing in [0, 15] {
        let s = run(&v, &roi, &opts(0.0, true, smoothing));
        let rep = &s.report;
        assert_eq!(rep.capped, [false, true, false, false, true, false], "smoothing {smoothing}");
        assert!(rep.closed && rep.components == 1);
        assert_closed_manifold(&s.mesh, "cut box");
        // Every vertex inside the ROI box; those beyond the last voxel centres exactly on it.
        let (mut on_x, mut on_z) = (0, 0);
        for p in &s.mesh.vertices {
            assert!(p[0] <= 7.3f32 && p[2] >= 4.6f32, "vertex {p:?} outside the ROI");
            if p[0] > 7.0 {
                assert_eq!(p[0], 7.3f32, "a vertex beyond x = 7 is on the +x cap");
                on_x += 1;
            }
            if p[2] < 5.0 {
                assert_eq!(p[2], 4.6f32, "a vertex below z = 5 is on the −z cap");
                on_z += 1;
            }
        }
        // The caps cover the cut: 11 × 8 voxels on +x (y 2..=12, z 5..=12), 6 × 11 on −z.
        assert!(on_x >= 88 && on_z >= 66, "cap vertices {on_x}, {on_z}");
        // The solid is x 1.5..7.3, y 1.5..12.5, z 4.6..12.5, less bevelled edges (at most
        // 0.125 mm² of section per mm of edge).
        let full = 5.8 * 11.0 * 7.9;
        let bevels = 0.125 * 4.0 * (5.8 + 11.0 + 7.9);
        assert!(rep.volume_mm3 < full && rep.volume_mm3 > full - bevels - 1.0, "volume {} vs {full}", rep.volume_mm3);
    }
}

#[test]
fn roi_faces_on_voxel_centres_cap_just_outside_them() {
    // The whole grid solid: the surface is the ROI box, the caps 10⁻³ voxel outside the
    // outer voxel centres (Roi::whole's faces pass through them).
    let v = field([5, 6, 7], [0.5, 1.0, 2.0], |_, _, _| 500.0);
    let s = run(&v, &Roi::whole(&v), &Options::default());
    assert_eq!(s.report.capped, [true; 6]);
    assert!(s.report.closed);
    assert_closed_manifold(&s.mesh, "whole box");
    let b = s.mesh.bounds().unwrap();
    let ext = v.extent_mm();
    for a in 0..3 {
        let m = 1e-3 * v.spacing_mm[a];
        assert!((b.min[a] + m).abs() < 1e-6 && (b.max[a] - ext[a] - m).abs() < 1e-5, "axis {a}: {b:?}");
    }
    // An ROI reaching past the volume caps half a voxel beyond the outer voxel centres.
    let big = Roi { min_mm: [-3.0; 3], max_mm: [40.0; 3] };
    let b = run(&v, &big, &Options::default()).mesh.bounds().unwrap();
    for a in 0..3 {
        let h = 0.5 * v.spacing_mm[a];
        assert!((b.min[a] + h).abs() < 1e-6 && (b.max[a] - ext[a] - h).abs() < 1e-5, "axis {a}: {b:?}");
    }
    // The box 2 × 5 × 12 mm less its bevelled edges (section ≤ m²/2) and corners.
    let full = (2.0 + 1e-3) * (5.0 + 2e-3) * (12.0 + 4e-3);
    assert!((s.report.volume_mm3 - full).abs() < 2e-4, "volume {} vs {full}", s.report.volume_mm3);
}

#[test]
fn a_hollow_shell_is_filled_or_left_hollow() {
    let (rm, w, c) = (8.0, 2.0, 11.0);
    let v = field([56, 56, 56], [0.4; 3], |x, y, z| 350.0 + 100.0 * (w - (dist(x, y, z, c) - rm).abs()));
    let roi = Roi::whole(&v);
    let enclosed = (0..v.len())
        .filter(|&n| {
            let (i, j, k) = (n % 56, n / 56 % 56, n / 3136);
            v.values[n] < 350.0 && dist(i as f64 * 0.4, j as f64 * 0.4, k as f64 * 0.4, c) < rm
        })
        .count();
    assert!(enclosed > 10_000);
    let (ro, ri) = (rm + w, rm - w);
    let filled = run(&v, &roi, &Options::default());
    let rep = &filled.report;
    assert_eq!((rep.cavities_filled, rep.cavity_voxels, rep.components), (1, enclosed, 1));
    let ball = 4.0 / 3.0 * PI * ro * ro * ro;
    assert!((rep.volume_mm3 / ball - 1.0).abs() < 0.01, "filled volume {} vs {ball}", rep.volume_mm3);
    assert!(rep.closed);
    assert_eq!(assert_closed_manifold(&filled.mesh, "filled shell"), 2);

    let hollow = run(&v, &roi, &opts(350.0, false, 0));
    let rep = &hollow.report;
    assert_eq!((rep.cavities_filled, rep.cavity_voxels, rep.components), (0, 0, 2));
    let shell = 4.0 / 3.0 * PI * (ro * ro * ro - ri * ri * ri);
    assert!((rep.volume_mm3 / shell - 1.0).abs() < 0.015, "shell volume {} vs {shell}", rep.volume_mm3);
    assert!(rep.closed);
    assert_eq!(assert_closed_manifold(&hollow.mesh, "hollow shell"), 4);
    // The outer surface faces out (positive volume), the cavity's wall faces into the void.
    let vols = component_volumes(&hollow.mesh);
    let inner = 4.0 / 3.0 * PI * ri * ri * ri;
    assert!(vols[0] < 0.0 && (vols[0] / -inner - 1.0).abs() < 0.03, "{vols:?}");
    assert!(vols[1] > 0.0 && (vols[1] / ball - 1.0).abs() < 0.01, "{vols:?}");
}

/// The nastiest input: independent random values at every voxel (every ambiguous case,
/// values exactly at the isovalue, NaN), random ROIs and spacings, with and without cavity
/// fill and smoothing.
#[test]
fn random_noise_gives_closed_consistently_oriented_surfaces() {
    let (mut meshes, mut triangles) = (0, 0);
    for seed in 0..400u64 {
        let mut rng = Pcg64::seed_from_u64(seed);
        let dims = [1 + rng.next_u64() as usize % 7, 1 + rng.next_u64() as usize % 7, 1 + rng.next_u64() as usize % 7];
        let spacing = [0.5 + 1.5 * unit(&mut rng), 0.5 + 1.5 * unit(&mut rng), 0.5 + 1.5 * unit(&mut rng)];
        let kind = seed % 3;
        let n = dims.iter().product::<usize>();
        let values: Vec<f32> = (0..n)
            .map(|_| match kind {
                // Integers 0..4 at isovalue 2: many voxels exactly at it.
                0 => (rng.next_u64() % 5) as f32,
                1 => (1000.0 * unit(&mut rng)) as f32,
                _ if rng.next_u64() % 10 == 0 => f32::NAN,
                _ => (1000.0 * unit(&mut rng)) as f32,
            })
            .collect();
        let v = Volume { dims, spacing_mm: spacing, values, ..Default::default() };
        let ext = v.extent_mm();
        let roi = if seed % 2 == 0 {
            Roi::whole(&v)
        } else {
            let mut lo = [0.0; 3];
            let mut hi = [0.0; 3];
            for a in 0..3 {
                let (p, q) = (unit(&mut rng) * 1.4 - 0.2, unit(&mut rng) * 1.4 - 0.2);
                lo[a] = p.min(q) * ext[a] - 0.3;
                hi[a] = p.max(q) * ext[a] + 0.3;
            }
            Roi { min_mm: lo, max_mm: hi }
        };
        let iso = if kind == 0 { 2.0 } else { 500.0 };
        let o = opts(iso, seed % 4 < 2, if seed % 5 == 0 { 3 } else { 0 });
        let s = match extract(&v, &roi, &o, &mut |_| {}) {
            Ok(s) => s,
            Err(Error::EmptyRoi { .. } | Error::NothingInside { .. }) => continue,
            Err(e) => panic!("seed {seed}: {e}"),
        };
        let what = format!("seed {seed}");
        let euler = assert_closed_manifold(&s.mesh, &what);
        assert!(s.report.closed, "{what}: the report says open");
        assert_eq!(euler % 2, 0, "{what}: odd Euler characteristic");
        assert!(s.report.volume_mm3 > 0.0, "{what}: volume {}", s.report.volume_mm3);
        if o.fill_cavities {
            // No cavity is left, so every piece is an outer surface facing out.
            let vols = component_volumes(&s.mesh);
            assert!(vols.iter().all(|&x| x > 0.0), "{what}: a piece faces in with cavities filled: {vols:?}");
            assert_eq!(vols.len(), s.report.components, "{what}");
        }
        assert_eq!(estimate(&v, &roi, &o).get("triangles"), s.report.triangles as f64, "{what}");
        meshes += 1;
        triangles += s.report.triangles;
    }
    assert!(meshes > 300 && triangles > 50_000, "{meshes} meshes, {triangles} triangles");
}

#[test]
fn smoothing_removes_the_staircase_without_shrinking() {
    // A binary sphere on a coarse grid: every vertex at an edge midpoint, a staircase.
    let (r, c) = (6.0, 7.7);
    let v = field([16, 16, 16], [1.0; 3], |x, y, z| if dist(x, y, z, c) <= r { 1000.0 } else { -1000.0 });
    let roi = Roi::whole(&v);
    let dev = |s: &Surface| {
        let d: Vec<f64> = s.mesh.vertices.iter().map(|p| dist(p[0] as f64, p[1] as f64, p[2] as f64, c) - r).collect();
        let rms = (d.iter().map(|x| x * x).sum::<f64>() / d.len() as f64).sqrt();
        let mean = d.iter().sum::<f64>() / d.len() as f64;
        (rms, mean)
    };
    let raw = run(&v, &roi, &opts(0.0, true, 0));
    let smooth = run(&v, &roi, &opts(0.0, true, 20));
    let ((rms0, _), (rms1, mean1)) = (dev(&raw), dev(&smooth));
    assert!(rms1 < 0.55 * rms0, "rms deviation {rms0} → {rms1}");
    assert!(mean1.abs() < 0.02 * r, "mean radius off by {mean1}");
    let ball = 4.0 / 3.0 * PI * r * r * r;
    assert!((smooth.report.volume_mm3 / ball - 1.0).abs() < 0.04, "volume {} vs {ball}", smooth.report.volume_mm3);
    assert!(smooth.report.closed);
    assert_closed_manifold(&smooth.mesh, "smoothed sphere");
    // Same connectivity, only positions moved.
    assert_eq!(smooth.mesh.triangles, raw.mesh.triangles);
}

#[test]
fn refusals_are_typed() {
    let v = field([10, 10, 10], [1.0; 3], |x, _, _| x * 10.0);
    let far = Roi { min_mm: [100.0; 3], max_mm: [110.0; 3] };
    let e = extract(&v, &far, &Options::default(), &mut |_| {}).unwrap_err();
    assert!(matches!(e, Error::EmptyRoi { roi_min_mm: [100.0, 100.0, 100.0], .. }), "{e}");
    assert!(e.to_string().contains("draw the box over the volume"));
    // Values 0..90: nothing reaches 350; the message gives the range in the ROI (x ≤ 4.5).
    let roi = Roi { min_mm: [0.0; 3], max_mm: [4.5, 9.0, 9.0] };
    let e = extract(&v, &roi, &Options::default(), &mut |_| {}).unwrap_err();
    assert_eq!(e, Error::NothingInside { iso: 350.0, min: 0.0, max: 40.0 });
    assert!(e.to_string().contains("range from 0 to 40"), "{e}");
    let e = extract(&v, &roi, &opts(f64::NAN, true, 0), &mut |_| {}).unwrap_err();
    assert!(matches!(e, Error::BadOption { name: "iso", .. }), "{e}");
    let e = extract(&v, &roi, &opts(50.0, true, 100_000), &mut |_| {}).unwrap_err();
    assert!(matches!(e, Error::BadOption { name: "smoothing_iterations", .. }), "{e}");
    // Options from JSON: defaults fill in, unknown fields refused.
    let o: Options = serde_json::from_str(r#"{"iso": 200}"#).unwrap();
    assert_eq!(o, opts(200.0, true, 0));
    assert!(serde_json::from_str::<Options>(r#"{"isovalue": 200}"#).is_err());
}

#[test]
fn over_budget_refuses_before_allocating() {
    // 125 G voxels that do not exist: refused from the voxel count alone, nothing read.
    let huge = Volume { dims: [5000, 5000, 5000], spacing_mm: [1.0; 3], values: Vec::new(), ..Default::default() };
    let e = estimate(&huge, &Roi::whole(&huge), &Options::default());
    assert!(e.refused.is_some());
    assert_eq!(e.get("voxels"), 125e9);
    let err = extract(&huge, &Roi::whole(&huge), &Options::default(), &mut |_| panic!("no work")).unwrap_err();
    assert!(matches!(err, Error::TooBig(_)), "{err}");
    // Noise whose surface would be over MAX_TRIANGLES: refused from the count, before the
    // mesh is allocated.
    let mut rng = Pcg64::seed_from_u64(1);
    let v = field([180, 180, 180], [0.5; 3], |_, _, _| 1000.0 * unit(&mut rng));
    let o = opts(500.0, false, 0);
    let e = estimate(&v, &Roi::whole(&v), &o);
    assert!(e.get("triangles") > MAX_TRIANGLES as f64, "{}", e.get("triangles"));
    match extract(&v, &Roi::whole(&v), &o, &mut |_| panic!("no work")).unwrap_err() {
        Error::TooBig(r) => {
            assert_eq!(r.what, "surface triangles");
            assert_eq!(r.limit, MAX_TRIANGLES as f64);
        }
        other => panic!("{other}"),
    }
    // A smaller ROI of the same noise is fine.
    let small = Roi { min_mm: [0.0; 3], max_mm: [10.0; 3] };
    assert!(estimate(&v, &small, &o).refused.is_none());
    assert!(run(&v, &small, &o).report.closed);
}

fn min_z_to_zero(mesh: &mut Mesh) {
    let b = mesh.bounds().unwrap();
    mesh.translate(DVec3::new(0.0, 0.0, -b.min.z));
}

#[test]
fn stl_reads_back_closed_and_slices_without_open_contours() {
    let (r, c) = (10.0, 11.0);
    let v = field([45, 45, 45], [0.5; 3], |x, y, z| 350.0 + 100.0 * (r - dist(x, y, z, c)));
    let (b, broi) = cut_box();
    for (name, mut s) in [("sphere", run(&v, &Roi::whole(&v), &Options::default())), ("cut box", run(&b, &broi, &opts(0.0, true, 5)))] {
        let stl = write_stl(&s.mesh, name);
        assert!(stl.starts_with(format!("weft isosurface {name}").as_bytes()));
        assert_eq!(stl.len(), 84 + 50 * s.mesh.triangles.len());
        let imported = weft::import::read_mesh("surface.stl", &stl, &Default::default()).unwrap();
        let rep = &imported.report;
        assert_eq!(rep.triangles, s.mesh.triangles.len(), "{name}");
        assert_eq!(rep.vertices, s.mesh.vertices.len(), "{name}: the weld merged vertices");
        assert_eq!((rep.open_edges, rep.degenerate_removed, rep.duplicates_removed), (0, 0, 0), "{name}");
        min_z_to_zero(&mut s.mesh);
        let sliced = weft::slice::slice(&s.mesh, &Default::default(), &mut |_| {}).unwrap();
        let sr = &sliced.report;
        assert!(sr.layers > 30, "{name}: {} layers", sr.layers);
        assert_eq!((sr.open_contours_dropped, sr.gaps_closed, sr.layers_with_overlaps), (0, 0, 0), "{name}");
    }
    // The name is cleaned into the header.
    let stl = write_stl(&Mesh::default(), "femur\n\u{1F9B4} left");
    assert_eq!(&stl[..26], b"weft isosurface femur left");
    assert_eq!(stl.len(), 84);
}

/// A CT-like phantom at the paper's grid (182×197×107 voxels, 0.977 × 0.977 × 3.27 mm): air,
/// a soft-tissue body, a tilted femur-like tube (cortical bone around a marrow canal, closed
/// by bone below z = 60 and above z = 300 mm), noise. Closed and correct; prints the time
/// (not asserted).
#[test]
fn ct_phantom_is_closed() {
    let s = [0.976562, 0.976562, 3.27];
    let mut rng = Pcg64::seed_from_u64(11);
    let (cx, cy) = (90.0, 95.0);
    let v = field([182, 197, 107], s, |x, y, z| {
        let (dx, dy) = (x - cx, y - cy);
        let body = (dx / 80.0).powi(2) + (dy / 85.0).powi(2) <= 1.0;
        let (bx, by) = (dx + 0.1 * (z - 170.0), dy);
        let rr = (bx * bx + by * by).sqrt();
        let noise = 120.0 * (unit(&mut rng) - 0.5);
        let hu = if rr <= 14.0 && (rr >= 9.0 || !(60.0..=300.0).contains(&z)) {
            1200.0 - 40.0 * (rr - 11.5).abs()
        } else if rr < 9.0 {
            -90.0
        } else if body {
            80.0
        } else {
            -1000.0
        };
        hu + noise
    });
    let roi = Roi { min_mm: [50.0, 65.0, 100.0], max_mm: [125.0, 130.0, 340.0] };
    let mut volumes = Vec::new();
    for fill in [true, false] {
        let surf = run(&v, &roi, &opts(350.0, fill, 0));
        eprintln!("phantom ROI (fill {fill}): {:?}", surf.report);
        let rep = &surf.report;
        assert!(rep.closed);
        assert_closed_manifold(&surf.mesh, "phantom");
        // The tube runs out through −z and is closed by bone above z = 300 inside the ROI.
        assert_eq!(rep.capped, [false, false, false, false, true, true]);
        assert_eq!(rep.components, 1);
        // The canal runs out through the ROI's −z face: a tunnel in 3D, closed slice by slice
        // only when filling (each slice's hole counts once).
        if fill {
            assert!(rep.cavities_filled > 0, "the canal was not closed");
        } else {
            assert_eq!(rep.cavities_filled, 0);
        }
        volumes.push(rep.volume_mm3);
    }
    // Closing the canal adds its volume: r < 9 mm over the ROI's z from 100 to 300 mm.
    let canal = std::f64::consts::PI * 81.0 * 200.0;
    assert!((volumes[0] - volumes[1] - canal).abs() < 0.1 * canal, "closing the canal added {} mm³, expected about {canal}", volumes[0] - volumes[1]);
    let whole = run(&v, &Roi::whole(&v), &Options::default());
    eprintln!("phantom whole volume: {:?}", whole.report);
    assert!(whole.report.closed);
    // Closed at both ends within the volume, the canal is a cavity: filled, and its voxels
    // are the marrow's (r < 9 mm, 60 < z ≤ 300).
    assert_eq!(whole.report.cavities_filled, 1);
    let marrow = (0..v.len()).filter(|&n| (-300.0..0.0).contains(&v.values[n])).count();
    assert_eq!(whole.report.cavity_voxels, marrow);
    let est = estimate(&v, &Roi::whole(&v), &Options::default());
    eprintln!("estimate: {} s, {} bytes, {} triangles", est.seconds, est.bytes, est.get("triangles"));
    assert_eq!(est.get("triangles"), whole.report.triangles as f64);
}

/// A gyroid-like field over the paper's whole CT grid: a 3.6 M-triangle surface (near the
/// limit), closed. Prints its counted work (times: `weft bench`): `cargo test --release --test it
/// isosurface::large_surface -- --ignored --nocapture`.
#[test]
#[ignore = "a big surface, about 2 s"]
fn large_surface_timing() {
    let s = [0.976562, 0.976562, 3.27];
    let p = 3.0;
    let v = field([182, 197, 107], s, |x, y, z| {
        let (x, y, z) = (x / p, y / p, z / p);
        350.0 + 500.0 * (x.sin() * y.cos() + y.sin() * z.cos() + z.sin() * x.cos())
    });
    for it in [0, 10] {
        let e = estimate(&v, &Roi::whole(&v), &opts(350.0, true, it));
        let (w, surf) = crate::work::measure(|| run(&v, &Roi::whole(&v), &opts(350.0, true, it)));
        eprintln!("smoothing {it}: the estimate states {:.2} s, {:.0} MB; extracting: {w:?}, {} triangles", e.seconds, e.bytes / 1e6, surf.report.triangles);
        assert!(surf.report.closed);
        assert_eq!(e.get("triangles"), surf.report.triangles as f64);
    }
}

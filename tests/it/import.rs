//! Integration tests for `weft::import` over generated and committed fixtures.
//!
//! The committed files in `tests/fixtures/` are produced by the builders below; the test
//! `committed_fixtures_are_current` checks they still match, and
//! `WEFT_WRITE_FIXTURES=1 cargo test --release --test it import::` rewrites them.

use std::io::{Cursor, Write};
use std::path::PathBuf;
use weft::geom::shapes::Shape;
use weft::geom::Mesh;
use weft::import::{read_mesh, Error, Format, Imported, Options};

// ---------- builders ----------

fn tri_corners(m: &Mesh) -> Vec<[[f32; 3]; 3]> {
    m.triangles.iter().map(|t| [m.vertices[t[0] as usize], m.vertices[t[1] as usize], m.vertices[t[2] as usize]]).collect()
}

fn normal(t: &[[f32; 3]; 3]) -> [f32; 3] {
    let e1 = [t[1][0] - t[0][0], t[1][1] - t[0][1], t[1][2] - t[0][2]];
    let e2 = [t[2][0] - t[0][0], t[2][1] - t[0][1], t[2][2] - t[0][2]];
    let n = [e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]];
    let l = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    if l > 0.0 {
        [n[0] / l, n[1] / l, n[2] / l]
    } else {
        [0.0; 3]
    }
}

/// Binary STL with an 80-byte header that starts with "solid" (as many exporters write).
fn binary_stl(tris: &[[[f32; 3]; 3]]) -> Vec<u8> {
    let mut b = Vec::with_capacity(84 + 50 * tris.len());
    let mut header = [b' '; 80];
    header[..24].copy_from_slice(b"solid weft test fixture ");
    b.extend_from_slice(&header);
    b.extend_from_slice(&(tris.len() as u32).to_le_bytes());
    for t in tris {
        for c in normal(t) {
            b.extend_from_slice(&c.to_le_bytes());
        }
        for v in t {
            for c in v {
                b.extend_from_slice(&c.to_le_bytes());
            }
        }
        b.extend_from_slice(&[0, 0]);
    }
    b
}

fn ascii_stl(name: &str, tris: &[[[f32; 3]; 3]]) -> String {
    let mut s = format!("solid {name}\n");
    for t in tris {
        let n = normal(t);
        s.push_str(&format!("  facet normal {:e} {:e} {:e}\n    outer loop\n", n[0], n[1], n[2]));
        for v in t {
            s.push_str(&format!("      vertex {} {} {}\n", v[0], v[1], v[2]));
        }
        s.push_str("    endloop\n  endfacet\n");
    }
    s.push_str(&format!("endsolid {name}\n"));
    s
}

/// OBJ using every face syntax: plain, v/vt, v//vn, v/vt/vn and negative indices.
fn obj_text(m: &Mesh) -> String {
    let mut s = String::from("# weft test fixture\nmtllib none.mtl\no cube\n");
    for v in &m.vertices {
        s.push_str(&format!("v {} {} {}\n", v[0], v[1], v[2]));
    }
    s.push_str("vt 0 0\nvn 0 0 1\ng all\nusemtl none\ns off\n");
    let n = m.vertices.len() as i64;
    for (i, t) in m.triangles.iter().enumerate() {
        let [a, b, c] = t.map(|x| x as i64 + 1);
        let line = match i % 5 {
            0 => format!("f {a} {b} {c}"),
            1 => format!("f {a}/1 {b}/1 {c}/1"),
            2 => format!("f {a}//1 {b}//1 {c}//1"),
            3 => format!("f {a}/1/1 {b}/1/1 {c}/1/1"),
            _ => format!("f {} {} {}", a - n - 1, b - n - 1, c - n - 1),
        };
        s.push_str(&line);
        s.push('\n');
    }
    s
}

use weft::testgen::mesh::{CONTENT_TYPES, RELS};

fn model_xml(unit: &str, m: &Mesh, item_transform: Option<&str>) -> String {
    let mut s = format!(
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<model unit=\"{unit}\" xml:lang=\"en-US\" \
         xmlns=\"http://schemas.microsoft.com/3dmanufacturing/core/2015/02\">\n <resources>\n  \
         <object id=\"1\" type=\"model\">\n   <mesh>\n    <vertices>\n"
    );
    for v in &m.vertices {
        s.push_str(&format!("     <vertex x=\"{}\" y=\"{}\" z=\"{}\" />\n", v[0], v[1], v[2]));
    }
    s.push_str("    </vertices>\n    <triangles>\n");
    for t in &m.triangles {
        s.push_str(&format!("     <triangle v1=\"{}\" v2=\"{}\" v3=\"{}\" />\n", t[0], t[1], t[2]));
    }
    s.push_str("    </triangles>\n   </mesh>\n  </object>\n </resources>\n <build>\n");
    match item_transform {
        Some(t) => s.push_str(&format!("  <item objectid=\"1\" transform=\"{t}\" />\n")),
        None => s.push_str("  <item objectid=\"1\" />\n"),
    }
    s.push_str(" </build>\n</model>\n");
    s
}

fn zip_entries(entries: &[(&str, &str)], deflate: bool) -> Vec<u8> {
    let mut w = zip::ZipWriter::new(Cursor::new(Vec::new()));
    let method = if deflate { zip::CompressionMethod::Deflated } else { zip::CompressionMethod::Stored };
    let opts = zip::write::SimpleFileOptions::default().compression_method(method).last_modified_time(zip::DateTime::default());
    for (name, body) in entries {
        w.start_file(*name, opts).unwrap();
        w.write_all(body.as_bytes()).unwrap();
    }
    w.finish().unwrap().into_inner()
}

fn three_mf(unit: &str, m: &Mesh, item_transform: Option<&str>, deflate: bool) -> Vec<u8> {
    let model = model_xml(unit, m, item_transform);
    zip_entries(&[("[Content_Types].xml", CONTENT_TYPES), ("_rels/.rels", RELS), ("3D/3dmodel.model", &model)], deflate)
}

fn cube20() -> Mesh {
    Shape::Cube { size: [20.0, 20.0, 20.0] }.mesh()
}

/// 1 inch cube placed 2 inch along X and rotated 90° about Z by the build item.
const INCH_TRANSFORM: &str = "0 1 0 -1 0 0 0 0 1 2 0 0";

fn fixtures() -> Vec<(&'static str, Vec<u8>)> {
    let cube = cube20();
    let mut open = cube.clone();
    open.triangles.retain(|t| !(t.iter().all(|&i| i >= 4))); // the top face uses only vertices 4..8
    let mut shells = cube.clone();
    let mut second = cube.clone();
    second.translate(weft::geom::DVec3::new(10.0, 10.0, 10.0));
    shells.append(&second);
    let sphere = Shape::Sphere { radius: 10.0, segments: 48 }.mesh();
    let inch = Shape::Cube { size: [1.0, 1.0, 1.0] }.mesh();
    vec![
        ("cube.stl", binary_stl(&tri_corners(&cube))),
        ("cube-ascii.stl", ascii_stl("cube", &tri_corners(&cube)).into_bytes()),
        ("cube.obj", obj_text(&cube).into_bytes()),
        ("cube.3mf", three_mf("millimeter", &cube, None, true)),
        ("cube-inch.3mf", three_mf("inch", &inch, Some(INCH_TRANSFORM), true)),
        ("open-box.stl", binary_stl(&tri_corners(&open))),
        ("overlapping-shells.stl", binary_stl(&tri_corners(&shells))),
        ("sphere.stl", binary_stl(&tri_corners(&sphere))),
    ]
}

fn fixture_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures")
}

fn read_fixture(name: &str) -> Imported {
    let bytes = std::fs::read(fixture_dir().join(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
    read_mesh(name, &bytes, &Options::default()).unwrap_or_else(|e| panic!("{e}"))
}

fn assert_bounds(m: &Mesh, min: [f64; 3], max: [f64; 3]) {
    let b = m.bounds().unwrap();
    for k in 0..3 {
        assert!((b.min[k] - min[k]).abs() < 1e-4, "min {:?} vs {min:?}", b.min);
        assert!((b.max[k] - max[k]).abs() < 1e-4, "max {:?} vs {max:?}", b.max);
    }
}

// ---------- committed fixtures ----------

#[test]
fn committed_fixtures_are_current() {
    let write = std::env::var_os("WEFT_WRITE_FIXTURES").is_some();
    for (name, bytes) in fixtures() {
        assert!(bytes.len() < 200 * 1024, "{name} is {} bytes", bytes.len());
        let path = fixture_dir().join(name);
        if write {
            std::fs::create_dir_all(fixture_dir()).unwrap();
            std::fs::write(&path, &bytes).unwrap();
        }
        let on_disk = std::fs::read(&path).unwrap_or_default();
        assert!(on_disk == bytes, "{name} differs from its builder; run WEFT_WRITE_FIXTURES=1 cargo test --release --test it import::");
    }
}

#[test]
fn cube_in_every_format() {
    for (name, format) in [("cube.stl", Format::StlBinary), ("cube-ascii.stl", Format::StlAscii), ("cube.obj", Format::Obj), ("cube.3mf", Format::ThreeMf)] {
        let im = read_fixture(name);
        let r = &im.report;
        assert_eq!(r.format, Some(format), "{name}");
        assert_eq!(r.triangles_read, 12, "{name}");
        assert_eq!(r.triangles, 12, "{name}");
        assert_eq!(r.vertices, 8, "{name}");
        assert_eq!((r.degenerate_removed, r.duplicates_removed, r.open_edges), (0, 0, 0), "{name}");
        assert_eq!(r.unit_scale, 1.0, "{name}");
        assert_bounds(&im.mesh, [-10.0, -10.0, 0.0], [10.0, 10.0, 20.0]);
    }
    // Same content, same result: both STLs weld to the identical mesh, and so do OBJ and 3MF
    // (which list the vertices in the same order).
    assert_eq!(read_fixture("cube.stl").mesh, read_fixture("cube-ascii.stl").mesh);
    assert_eq!(read_fixture("cube.obj").mesh, read_fixture("cube.3mf").mesh);
    assert_eq!(read_fixture("cube.3mf").mesh, cube20());
}

#[test]
fn inch_3mf_is_scaled_and_placed() {
    let im = read_fixture("cube-inch.3mf");
    assert_eq!(im.report.unit_scale, 25.4);
    assert_eq!(im.report.triangles, 12);
    // 1 inch cube centred on x = y = 0, rotated 90° about Z (still ±0.5), then moved 2 inch in X.
    assert_bounds(&im.mesh, [1.5 * 25.4, -0.5 * 25.4, 0.0], [2.5 * 25.4, 0.5 * 25.4, 25.4]);
}

#[test]
fn open_box_reports_the_hole() {
    let im = read_fixture("open-box.stl");
    assert_eq!(im.report.triangles, 10);
    assert_eq!(im.report.vertices, 8);
    // The square hole's rim: the 4 top edges (the removed diagonal was shared by both).
    assert_eq!(im.report.open_edges, 4);
}

#[test]
fn overlapping_shells_stay_two_closed_shells() {
    let im = read_fixture("overlapping-shells.stl");
    assert_eq!(im.report.triangles, 24);
    assert_eq!(im.report.vertices, 16);
    assert_eq!(im.report.open_edges, 0);
    assert_bounds(&im.mesh, [-10.0, -10.0, 0.0], [20.0, 20.0, 30.0]);
}

#[test]
fn sphere_is_closed() {
    let im = read_fixture("sphere.stl");
    let r = &im.report;
    assert_eq!(r.triangles_read, 2208);
    assert_eq!(r.triangles, 2208);
    assert_eq!(r.vertices, 2 + 23 * 48);
    assert_eq!((r.degenerate_removed, r.duplicates_removed, r.open_edges), (0, 0, 0));
    let b = im.mesh.bounds().unwrap();
    assert!((b.max.z - 20.0).abs() < 1e-4 && b.min.z.abs() < 1e-6);
    assert!((b.size().x - 20.0).abs() < 0.01, "{:?}", b.size());
}

// ---------- generated cases ----------

#[test]
fn duplicates_and_degenerates_are_counted() {
    let mut tris = tri_corners(&cube20());
    let t0 = tris[0];
    let t5 = tris[5];
    tris.push(t0); // exact copy
    tris.push([t5[1], t5[2], t5[0]]); // same triangle, rotated corners
    tris.push([t5[0], t5[2], t5[1]]); // opposite orientation: same vertex set, also dropped
    tris.push([t0[0], t0[0], t0[1]]); // repeated corner
    tris.push([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]]); // collinear
    let im = read_mesh("dups.stl", &binary_stl(&tris), &Options::default()).unwrap();
    let r = &im.report;
    assert_eq!(r.triangles_read, 17);
    assert_eq!(r.triangles, 12);
    assert_eq!(r.duplicates_removed, 3);
    assert_eq!(r.degenerate_removed, 2);
    assert_eq!(r.vertices, 8, "vertices only used by dropped triangles are dropped too");
    assert_eq!(r.open_edges, 0);
}

#[test]
fn welding_follows_the_tolerance() {
    // Jitter every corner copy by up to 20 µm: the default 0.1 µm weld keeps them apart,
    // a 0.05 mm weld joins them into the 8 cube corners.
    let mut tris = tri_corners(&cube20());
    for (i, t) in tris.iter_mut().enumerate() {
        for (k, v) in t.iter_mut().enumerate() {
            v[0] += ((i * 3 + k) % 5) as f32 * 0.005;
        }
    }
    let bytes = binary_stl(&tris);
    let loose = read_mesh("j.stl", &bytes, &Options { weld_tolerance_mm: 0.05 }).unwrap();
    assert_eq!(loose.report.vertices, 8);
    assert_eq!(loose.report.open_edges, 0);
    let tight = read_mesh("j.stl", &bytes, &Options::default()).unwrap();
    assert!(tight.report.vertices > 8);
    assert!(tight.report.open_edges > 0);
    let exact = read_mesh("j.stl", &bytes, &Options { weld_tolerance_mm: 0.0 }).unwrap();
    assert_eq!(exact.report.vertices, tight.report.vertices);
}

#[test]
fn stored_and_deflated_3mf_read_the_same() {
    let sphere = Shape::Sphere { radius: 5.0, segments: 16 }.mesh();
    let stored = three_mf("millimeter", &sphere, None, false);
    let deflated = three_mf("millimeter", &sphere, None, true);
    assert!(deflated.len() < stored.len());
    let a = read_mesh("s.3mf", &stored, &Options::default()).unwrap();
    let b = read_mesh("d.3mf", &deflated, &Options::default()).unwrap();
    assert_eq!(a.mesh, b.mesh);
    assert_eq!(a.report, b.report);
    assert_eq!(a.report.triangles, sphere.triangles.len());
}

#[test]
fn micron_3mf_without_rels_uses_the_default_part() {
    let cube = Shape::Cube { size: [2000.0, 2000.0, 1000.0] }.mesh();
    let model = model_xml("micron", &cube, None);
    let bytes = zip_entries(&[("3D/3dmodel.model", &model)], true);
    let im = read_mesh("m.3mf", &bytes, &Options::default()).unwrap();
    assert_eq!(im.report.unit_scale, 0.001);
    assert_bounds(&im.mesh, [-1.0, -1.0, 0.0], [1.0, 1.0, 1.0]);
}

#[test]
fn reading_is_deterministic() {
    for (name, bytes) in fixtures() {
        let a = read_mesh(name, &bytes, &Options::default()).unwrap();
        let b = read_mesh(name, &bytes, &Options::default()).unwrap();
        assert_eq!(a.mesh, b.mesh, "{name}");
        assert_eq!(a.report, b.report, "{name}");
    }
}

#[test]
fn errors_name_the_place_and_the_fix() {
    let cube = std::fs::read(fixture_dir().join("cube.stl")).unwrap();
    let e = read_mesh("cut.stl", &cube[..cube.len() - 70], &Options::default()).unwrap_err();
    let msg = e.to_string();
    assert!(matches!(e, Error::Malformed { .. }));
    assert!(msg.starts_with("cut.stl: triangle 11 (byte 584)"), "{msg}");
    assert!(msg.contains("export it again"), "{msg}");

    let ascii = String::from_utf8(std::fs::read(fixture_dir().join("cube-ascii.stl")).unwrap()).unwrap();
    let broken = ascii.replacen("endloop", "endlop", 2);
    let msg = read_mesh("b.stl", broken.as_bytes(), &Options::default()).unwrap_err().to_string();
    assert!(msg.contains("line 7") && msg.contains("\"endlop\""), "{msg}");

    let msg = read_mesh("b.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", &Options::default()).unwrap_err().to_string();
    assert!(msg.contains("line 4") && msg.contains("vertex 4"), "{msg}");

    let e = read_mesh("pts.obj", b"v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n", &Options::default()).unwrap_err();
    assert_eq!(e, Error::NoTriangles { file: "pts.obj".into() });

    let e = read_mesh("e.stl", b"solid empty\nendsolid empty\n", &Options::default()).unwrap_err();
    assert_eq!(e, Error::NoTriangles { file: "e.stl".into() });
}

#[test]
fn crlf_and_multiple_solids() {
    let tris = tri_corners(&cube20());
    let text = format!("{}{}", ascii_stl("a", &tris[..6]), ascii_stl("b", &tris[6..])).replace('\n', "\r\n");
    let im = read_mesh("two.stl", text.as_bytes(), &Options::default()).unwrap();
    assert_eq!(im.report.format, Some(Format::StlAscii));
    assert_eq!(im.mesh, read_fixture("cube.stl").mesh);
}

/// `cargo test --release --test it import::million -- --ignored --nocapture`
#[test]
#[ignore = "a 50 MB input; run in release"]
fn million_triangle_binary_stl_is_fast() {
    let sphere = Shape::Sphere { radius: 50.0, segments: 512 }.mesh(); // 261 632 triangles
    let mut tris = Vec::new();
    for k in 0..4 {
        let mut m = sphere.clone();
        m.translate(weft::geom::DVec3::new(k as f64 * 120.0, 0.0, 0.0));
        tris.extend(tri_corners(&m));
    }
    tris.truncate(1_000_000);
    let bytes = binary_stl(&tris);
    // The work, printed, and the peak heap within the estimate (times: `weft bench`).
    let (w, im) = crate::work::measure(|| read_mesh("big.stl", &bytes, &Options::default()).unwrap());
    println!("{} triangles, {} MB: {w:?} ({:?})", im.report.triangles, bytes.len() >> 20, im.report);
    assert!(w.peak <= weft::import::estimate("big.stl", &bytes).unwrap().peak_bytes, "{w:?}");
}

#[test]
fn binary_stl_length_mismatch_uses_the_extension_hint() {
    let mut cube = std::fs::read(fixture_dir().join("cube.stl")).unwrap();
    cube.extend_from_slice(&[0u8; 10]); // trailing junk some exporters leave
    let im = read_mesh("junk.stl", &cube, &Options::default()).unwrap();
    assert_eq!(im.report.format, Some(Format::StlBinary));
    assert_eq!(im.report.triangles, 12);
    // Without the .stl name, a binary blob whose count disagrees with its length is unknown.
    let e = read_mesh("junk.bin", &cube, &Options::default()).unwrap_err();
    assert!(matches!(e, Error::UnknownFormat { .. }), "{e}");
    assert!(e.to_string().contains("starts with bytes 73 6f 6c 69 64"), "{e}");
}

//! Generators of mesh files (STL, OBJ, 3MF) at a size `n`, plain and hostile.
//!
//! Every generator is deterministic (same `n`, same bytes on every platform: `libm` for the
//! trigonometry, Rust's shortest round-trip float printing) and linear in `n`. Sizes are in
//! triangles unless a doc comment says otherwise.

use std::io::{Cursor, Write};

/// Indexed closed UV sphere of radius 50 mm with about `n` triangles (at least 8):
/// `2·s·(r−1)` triangles for `r` latitude bands and `s = 2r` segments.
fn sphere(n: usize) -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
    // 4r(r−1) ≈ n.
    let r = ((1.0 + libm::sqrt(1.0 + n as f64)) / 2.0).round().max(2.0) as usize;
    let s = 2 * r;
    let radius = 50.0;
    let mut v = Vec::with_capacity(2 + s * (r - 1));
    v.push([0.0, 0.0, -radius as f32]);
    for band in 1..r {
        let theta = std::f64::consts::PI * band as f64 / r as f64;
        let (z, ring) = (-radius * libm::cos(theta), radius * libm::sin(theta));
        for k in 0..s {
            let phi = 2.0 * std::f64::consts::PI * k as f64 / s as f64;
            v.push([(ring * libm::cos(phi)) as f32, (ring * libm::sin(phi)) as f32, z as f32]);
        }
    }
    v.push([0.0, 0.0, radius as f32]);
    let top = (v.len() - 1) as u32;
    let at = |band: usize, k: usize| (1 + (band - 1) * s + k % s) as u32;
    let mut t = Vec::with_capacity(2 * s * (r - 1));
    for k in 0..s {
        t.push([0, at(1, k + 1), at(1, k)]);
        t.push([top, at(r - 1, k), at(r - 1, k + 1)]);
    }
    for band in 1..r - 1 {
        for k in 0..s {
            let (a, b, c, d) = (at(band, k), at(band, k + 1), at(band + 1, k), at(band + 1, k + 1));
            t.push([a, b, d]);
            t.push([a, d, c]);
        }
    }
    (v, t)
}

fn corners(v: &[[f32; 3]], t: &[u32; 3]) -> [[f32; 3]; 3] {
    t.map(|i| v.get(i as usize).copied().unwrap_or_default())
}

/// Binary STL of a closed sphere with about `n` triangles (the size/count rule detects it).
/// The header starts with "solid", as many exporters write, so the count must decide.
pub fn binary_stl_sphere(n: usize) -> Vec<u8> {
    let (v, t) = sphere(n);
    let mut b = Vec::with_capacity(84 + 50 * t.len());
    let mut header = [b' '; 80];
    header[..18].copy_from_slice(b"solid weft testgen");
    b.extend_from_slice(&header);
    b.extend_from_slice(&(t.len() as u32).to_le_bytes());
    for tri in &t {
        b.extend_from_slice(&[0u8; 12]); // normal: recomputed by readers
        for p in corners(&v, tri) {
            for c in p {
                b.extend_from_slice(&c.to_le_bytes());
            }
        }
        b.extend_from_slice(&[0, 0]);
    }
    b
}

fn ascii_stl_named(n: usize, name: &str) -> Vec<u8> {
    let (v, t) = sphere(n);
    let mut s = String::with_capacity(40 + 200 * t.len());
    s.push_str(&format!("solid {name}\n"));
    for tri in &t {
        s.push_str("  facet normal 0 0 0\n    outer loop\n");
        for p in corners(&v, tri) {
            s.push_str(&format!("      vertex {} {} {}\n", p[0], p[1], p[2]));
        }
        s.push_str("    endloop\n  endfacet\n");
    }
    s.push_str(&format!("endsolid {name}\n"));
    s.into_bytes()
}

/// ASCII STL of a closed sphere with about `n` triangles.
pub fn ascii_stl(n: usize) -> Vec<u8> {
    ascii_stl_named(n, "weft testgen")
}

/// ASCII STL (about `n` triangles) whose solid name holds one control byte (0x01) within
/// the first KiB: a text sniffer that wants pure text takes it for binary, and bytes 80–83
/// then read as an absurd binary triangle count. Must read as ASCII.
pub fn ascii_stl_control_byte(n: usize) -> Vec<u8> {
    ascii_stl_named(n, "weft\u{1}testgen")
}

/// Wavefront OBJ of a closed sphere with about `n` triangles (shared vertices, `o`/`g` names).
pub fn obj(n: usize) -> Vec<u8> {
    let (v, t) = sphere(n);
    let mut s = String::with_capacity(40 + 60 * t.len());
    s.push_str("# weft testgen\no sphere\ng all\n");
    for p in &v {
        s.push_str(&format!("v {} {} {}\n", p[0], p[1], p[2]));
    }
    for tri in &t {
        s.push_str(&format!("f {} {} {}\n", tri[0] + 1, tri[1] + 1, tri[2] + 1));
    }
    s.into_bytes()
}

/// The package relationships part of a 3MF: the model is `/3D/3dmodel.model`.
pub const RELS: &str = r#"<?xml version="1.0" encoding="UTF-8"?>
<Relationships xmlns="http://schemas.openxmlformats.org/package/2006/relationships">
 <Relationship Target="/3D/3dmodel.model" Id="rel0" Type="http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel"/>
</Relationships>
"#;

/// The content types part of a 3MF.
pub const CONTENT_TYPES: &str = r#"<?xml version="1.0" encoding="UTF-8"?>
<Types xmlns="http://schemas.openxmlformats.org/package/2006/content-types">
 <Default Extension="rels" ContentType="application/vnd.openxmlformats-package.relationships+xml"/>
 <Default Extension="model" ContentType="application/vnd.ms-package.3dmanufacturing-3dmodel+xml"/>
</Types>
"#;

const MODEL_HEAD: &str = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<model unit=\"millimeter\" xml:lang=\"en-US\" \
     xmlns=\"http://schemas.microsoft.com/3dmanufacturing/core/2015/02\">\n";

/// A deflated 3MF package around one model part (deflate keeps test inputs small; the
/// reader's cost is in the inflated XML).
fn package(model: &str) -> Vec<u8> {
    let mut w = zip::ZipWriter::new(Cursor::new(Vec::new()));
    let opts = zip::write::SimpleFileOptions::default().compression_method(zip::CompressionMethod::Deflated).last_modified_time(zip::DateTime::default());
    for (name, body) in [("[Content_Types].xml", CONTENT_TYPES), ("_rels/.rels", RELS), ("3D/3dmodel.model", model)] {
        // Writing into a Vec cannot fail.
        let _ = w.start_file(name, opts);
        let _ = w.write_all(body.as_bytes());
    }
    w.finish().map(|c| c.into_inner()).unwrap_or_default()
}

fn push_mesh(s: &mut String, v: &[[f32; 3]], t: &[[u32; 3]]) {
    s.push_str("   <mesh>\n    <vertices>\n");
    for p in v {
        s.push_str(&format!("     <vertex x=\"{}\" y=\"{}\" z=\"{}\"/>\n", p[0], p[1], p[2]));
    }
    s.push_str("    </vertices>\n    <triangles>\n");
    for tri in t {
        s.push_str(&format!("     <triangle v1=\"{}\" v2=\"{}\" v3=\"{}\"/>\n", tri[0], tri[1], tri[2]));
    }
    s.push_str("    </triangles>\n   </mesh>\n");
}

/// 3MF with one object, a closed sphere of about `n` triangles, one per line as slicers
/// write them (a reader that finds each element's line by counting from the start of the
/// part is quadratic here).
pub fn three_mf(n: usize) -> Vec<u8> {
    let (v, t) = sphere(n);
    let mut s = String::with_capacity(200 + 80 * t.len());
    s.push_str(MODEL_HEAD);
    s.push_str(" <resources>\n  <object id=\"1\" type=\"model\" name=\"sphere\">\n");
    push_mesh(&mut s, &v, &t);
    s.push_str("  </object>\n </resources>\n <build>\n  <item objectid=\"1\"/>\n </build>\n</model>\n");
    package(&s)
}

/// 3MF with `n` sibling objects (each a tetrahedron, 4 triangles) and `n` build items placing
/// them on a grid 10 mm apart: per-object and per-item lookups must not be linear scans.
pub fn three_mf_siblings(n: usize) -> Vec<u8> {
    let tet_v: [[f32; 3]; 4] = [[0.0, 0.0, 0.0], [5.0, 0.0, 0.0], [0.0, 5.0, 0.0], [0.0, 0.0, 5.0]];
    let tet_t: [[u32; 3]; 4] = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
    let mut s = String::with_capacity(300 + 700 * n);
    s.push_str(MODEL_HEAD);
    s.push_str(" <resources>\n");
    for i in 0..n {
        s.push_str(&format!("  <object id=\"{}\" type=\"model\" name=\"part {i}\">\n", i + 1));
        push_mesh(&mut s, &tet_v, &tet_t);
        s.push_str("  </object>\n");
    }
    s.push_str(" </resources>\n <build>\n");
    let side = (libm::sqrt(n as f64).ceil() as usize).max(1);
    for i in 0..n {
        let (x, y) = ((i % side) * 10, (i / side) * 10);
        s.push_str(&format!("  <item objectid=\"{}\" transform=\"1 0 0 0 1 0 0 0 1 {x} {y} 0\"/>\n", i + 1));
    }
    s.push_str(" </build>\n</model>\n");
    package(&s)
}

/// 3MF whose model part holds a valid one-triangle object, then foreign elements nested `n`
/// deep (`<w:nest>` inside `<w:nest>`…). Readers must refuse past their depth limit without
/// recursion or quadratic work.
pub fn three_mf_nested(n: usize) -> Vec<u8> {
    let mut s = String::with_capacity(400 + 20 * n);
    s.push_str(MODEL_HEAD.trim_end_matches(">\n"));
    s.push_str(" xmlns:w=\"urn:weft:testgen\">\n <resources>\n  <object id=\"1\" type=\"model\">\n");
    push_mesh(&mut s, &[[0.0, 0.0, 0.0], [10.0, 0.0, 0.0], [0.0, 10.0, 0.0]], &[[0, 1, 2]]);
    s.push_str("  </object>\n </resources>\n <build>\n  <item objectid=\"1\"/>\n </build>\n");
    for _ in 0..n {
        s.push_str("<w:nest>");
    }
    for _ in 0..n {
        s.push_str("</w:nest>");
    }
    s.push_str("\n</model>\n");
    package(&s)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_follow_n() {
        for n in [8, 100, 10_000] {
            let (_, t) = sphere(n);
            assert!(t.len() >= n / 2 && t.len() <= 2 * n.max(8), "{n}: {}", t.len());
            let b = binary_stl_sphere(n);
            assert_eq!(b.len(), 84 + 50 * t.len());
        }
        assert_eq!(binary_stl_sphere(1000), binary_stl_sphere(1000));
        assert!(ascii_stl_control_byte(100)[..1024].contains(&1));
        assert_eq!(three_mf_siblings(10), three_mf_siblings(10));
    }
}

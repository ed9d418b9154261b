//! Wavefront OBJ: `v x y z [w]` and `f` lines (`v`, `v/vt`, `v//vn`, `v/vt/vn`, negative
//! indices relative to the vertices so far). Polygons are fan-triangulated; every other
//! statement (vt, vn, g, o, usemtl, mtllib, s, l, comments, …) is ignored.

use super::{malformed, parse_finite, show, Error, RawMesh};

const FIX: &str = "the file is not valid OBJ; export it again";

/// True when some line starts with a `v` or `f` statement.
pub(super) fn looks_like_obj(bytes: &[u8]) -> bool {
    bytes.split(|&b| b == b'\n').any(|line| {
        let mut it = line.split(|b| b.is_ascii_whitespace()).filter(|t| !t.is_empty());
        matches!(it.next(), Some(b"v") | Some(b"f")) && it.next().is_some()
    })
}

/// (vertices, triangles) of an OBJ from a scan of statement names and face corner counts,
/// no number parsing: exact for a file that reads (a face of k corners is k − 2 triangles).
pub(super) fn scan_obj(bytes: &[u8]) -> (u64, u64) {
    let (mut v, mut t) = (0u64, 0u64);
    for line in bytes.split(|&b| b == b'\n') {
        let line = match line.iter().position(|&b| b == b'#') {
            Some(c) => line.get(..c).unwrap_or_default(),
            None => line,
        };
        let mut tokens = line.split(|b| b.is_ascii_whitespace()).filter(|t| !t.is_empty());
        match tokens.next() {
            Some(b"v") => v += 1,
            Some(b"f") => t += (tokens.count() as u64).saturating_sub(2),
            _ => {}
        }
    }
    (v, t)
}

/// Reads an OBJ file; `(vertices, triangles)` from [`scan_obj`] (already checked against
/// the limits) size the arrays once.
pub(super) fn read_obj(file: &str, bytes: &[u8], (v, t): (u64, u64)) -> Result<RawMesh, Error> {
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    let mut mesh = RawMesh { vertices: Vec::with_capacity(v as usize), triangles: Vec::with_capacity(t as usize) };
    let mut poly: Vec<u32> = Vec::with_capacity(8);
    for (i, line) in bytes.split(|&b| b == b'\n').enumerate() {
        let n = i + 1;
        let line = match line.iter().position(|&b| b == b'#') {
            Some(c) => line.get(..c).unwrap_or_default(),
            None => line,
        };
        let mut tokens = line.split(|b| b.is_ascii_whitespace()).filter(|t| !t.is_empty());
        match tokens.next() {
            Some(b"v") => {
                let mut p = [0f32; 3];
                for (axis, slot) in p.iter_mut().enumerate() {
                    let t = tokens.next();
                    let v = t.and_then(parse_finite).map(|v| v as f32).filter(|v| v.is_finite());
                    *slot = v.ok_or_else(|| {
                        let found = t.map_or("the end of the line".to_string(), |t| format!("\"{}\"", show(t)));
                        malformed(
                            file,
                            format!("line {n}"),
                            format!("expected the {} coordinate of a vertex (a finite number), found {found}", ["x", "y", "z"][axis]),
                            FIX,
                        )
                    })?;
                }
                if mesh.vertices.len() >= u32::MAX as usize {
                    return Err(malformed(file, format!("line {n}"), "more vertices than weft can index", "split the model into smaller files"));
                }
                mesh.vertices.push(p);
            }
            Some(b"f") => {
                poly.clear();
                for t in tokens {
                    poly.push(face_index(file, n, t, mesh.vertices.len())?);
                }
                if poly.len() < 3 {
                    return Err(malformed(file, format!("line {n}"), format!("a face has {} vertices, needs at least 3", poly.len()), FIX));
                }
                let first = poly.first().copied().unwrap_or(0);
                for w in poly.get(1..).unwrap_or_default().windows(2) {
                    if let [b, c] = *w {
                        mesh.triangles.push([first, b, c]);
                    }
                }
            }
            _ => {}
        }
    }
    Ok(mesh)
}

/// Resolves one `f` corner (`v`, `v/vt`, `v//vn`, `v/vt/vn`) to a 0-based vertex index.
fn face_index(file: &str, line: usize, token: &[u8], defined: usize) -> Result<u32, Error> {
    let v = token.split(|&b| b == b'/').next().unwrap_or_default();
    let place = || format!("line {line}");
    let idx: i64 = std::str::from_utf8(v)
        .ok()
        .and_then(|s| s.parse().ok())
        .ok_or_else(|| malformed(file, place(), format!("expected a vertex index in the face, found \"{}\"", show(token)), FIX))?;
    let resolved = if idx > 0 {
        (idx - 1) as u64
    } else if idx < 0 {
        (defined as u64).checked_sub(idx.unsigned_abs()).unwrap_or(u64::MAX)
    } else {
        return Err(malformed(file, place(), "a face refers to vertex 0; OBJ indices start at 1", FIX));
    };
    if resolved >= defined as u64 {
        return Err(malformed(file, place(), format!("a face refers to vertex {idx} but only {defined} vertices are defined before this line"), FIX));
    }
    Ok(resolved as u32)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read_obj_(file: &str, bytes: &[u8]) -> Result<RawMesh, Error> {
        read_obj(file, bytes, scan_obj(bytes))
    }

    #[test]
    fn reads_all_face_forms() {
        let s = "# comment\nmtllib x.mtl\no thing\nv 0 0 0 1\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\ng grp\nusemtl m\ns off\n\
                 f 1 2 3\r\nf 1/1 3/1 4/1\nf 1//1 2//1 3//1\nf 1/1/1 2/1/1 3/1/1\nf -4 -3 -2 -1\nl 1 2\n";
        let m = read_obj("a.obj", s.as_bytes(), (0, 0)).unwrap();
        assert_eq!(m.vertices.len(), 4);
        assert_eq!(m.triangles.len(), 6);
        assert_eq!(m.triangles[4], [0, 1, 2]);
        assert_eq!(m.triangles[5], [0, 2, 3]);
    }

    #[test]
    fn errors_name_the_line() {
        let s = "v 0 0 0\nv 1 0 0\nv 1 1 0\n\n\n\nf 1 2 9\n";
        let e = read_obj("a.obj", s.as_bytes(), (0, 0)).unwrap_err().to_string();
        assert!(e.contains("line 7") && e.contains("vertex 9") && e.contains("only 3"), "{e}");
        let e = read_obj_("a.obj", b"v 0 0 0\nf -1 -2 -3\n").unwrap_err().to_string();
        assert!(e.contains("line 2") && e.contains("vertex -2"), "{e}");
        let e = read_obj_("a.obj", b"v 0 0\n").unwrap_err().to_string();
        assert!(e.contains("line 1") && e.contains("z coordinate") && e.contains("end of the line"), "{e}");
        let e = read_obj_("a.obj", b"v 0 0 0\nf 0 1 1\n").unwrap_err().to_string();
        assert!(e.contains("line 2") && e.contains("start at 1"), "{e}");
        let e = read_obj_("a.obj", b"v 0 0 0\nf 1 1\n").unwrap_err().to_string();
        assert!(e.contains("line 2") && e.contains("2 vertices"), "{e}");
        let e = read_obj_("a.obj", b"v 0 0 0\nf 1 x 1\n").unwrap_err().to_string();
        assert!(e.contains("\"x\""), "{e}");
        let e = read_obj_("a.obj", b"v 0 0 0\nf 1 -9223372036854775808 1\n").unwrap_err().to_string();
        assert!(e.contains("line 2"), "{e}");
    }

    #[test]
    fn detection() {
        assert!(looks_like_obj(b"# x\nv 1 2 3\n"));
        assert!(!looks_like_obj(b"vertex 1 2 3\n"));
    }
}

//! STL, binary and ASCII.
//!
//! Binary: 80-byte header, little-endian u32 triangle count, then 50 bytes per triangle
//! (normal, three vertices, 2 attribute bytes). The header may start with "solid"; the count
//! agreeing with the length decides. ASCII: `solid … facet normal … outer loop vertex ×3
//! endloop endfacet … endsolid`, any case and whitespace, several solids per file. Normals
//! are ignored (recomputed from the winding).

use super::buckets::{map_chunks, Words};
use super::repair::{Corners, Soup};
use super::{malformed, parse_finite, show, Error, RawMesh};

const HEADER: usize = 84;
const RECORD: usize = 50;
const REEXPORT: &str = "the file was cut short; export it again";

pub(super) fn count(bytes: &[u8]) -> Option<u32> {
    let c: [u8; 4] = bytes.get(80..84)?.try_into().ok()?;
    Some(u32::from_le_bytes(c))
}

/// The length of a binary STL of `n` triangles.
pub(super) fn binary_len(n: u32) -> u64 {
    HEADER as u64 + RECORD as u64 * n as u64
}

/// True when the file is exactly as long as its binary-STL triangle count says.
pub(super) fn binary_count_matches(bytes: &[u8]) -> bool {
    count(bytes).is_some_and(|n| binary_len(n) == bytes.len() as u64)
}

/// (vertices, triangles) a binary STL read gives: the header's count, capped by the
/// records the file actually holds (a forged count cannot make us allocate more).
pub(super) fn binary_counts(bytes: &[u8]) -> (u64, u64) {
    let n = count(bytes).map_or(0, |n| n as u64);
    let held = (bytes.len().saturating_sub(HEADER) / RECORD) as u64;
    let n = n.min(held);
    (3 * n, n)
}

/// Why `bytes` is neither binary nor text STL, in one plain clause (for a file named `.stl`
/// that is not one, and for unknown formats).
pub(super) fn why_not_stl(bytes: &[u8]) -> String {
    let solid = super::starts_with_ignore_case(super::skip_bom_and_space(bytes), b"solid");
    let binary = match count(bytes) {
        None => format!("it is {} bytes, shorter than any binary STL (84 bytes)", bytes.len()),
        Some(_) => "its size does not fit the triangle count a binary STL states at byte 80".to_string(),
    };
    match super::text_problem(bytes) {
        Some(why) if solid => format!("it starts with \"solid\" like a text STL but is not text ({why}), and {binary}"),
        None if !solid => "it is text, but not a text STL: that starts with the word \"solid\"".to_string(),
        _ => format!("{binary}, and it does not start with the word \"solid\" as a text STL does"),
    }
}

/// A binary file cut short keeps most of what its header promises; a file whose header
/// promises over this many times its size is not a binary STL at all (a random header
/// promises about 10¹¹ bytes).
const MAX_CUT_RATIO: u64 = 1000;

/// Checks a binary STL and gives its records to read in place. Bytes after the promised
/// triangles are ignored.
pub(super) fn read_binary<'a>(file: &str, bytes: &'a [u8]) -> Result<BinaryStl<'a>, Error> {
    let Some(n) = count(bytes) else {
        return Err(malformed(
            file,
            format!("byte {}", bytes.len()),
            format!("the file is {} bytes, shorter than the 84-byte binary STL header", bytes.len()),
            REEXPORT,
        ));
    };
    let n = n as u64;
    let expected = HEADER as u64 + RECORD as u64 * n;
    let len = bytes.len() as u64;
    if expected > len {
        if expected / MAX_CUT_RATIO > len {
            return Err(Error::NotStl { file: file.to_string(), why: why_not_stl(bytes) });
        }
        let i = (len - HEADER as u64) / RECORD as u64;
        return Err(malformed(
            file,
            format!("triangle {} (byte {})", i + 1, HEADER as u64 + RECORD as u64 * i),
            format!(
                "the file ends after {} bytes but its header says it holds {} triangles ({} bytes)",
                super::group(len),
                super::group(n),
                super::group(expected)
            ),
            REEXPORT,
        ));
    }
    // n ≤ len / 50 here, so the allocation is bounded by the file size.
    let n = n as usize;
    if n.checked_mul(3).is_none_or(|v| v > u32::MAX as usize) {
        return Err(malformed(file, "header", format!("{n} triangles are more than weft can index"), "split the model into smaller files"));
    }
    let body = bytes.get(HEADER..HEADER + n * RECORD).unwrap_or_default();
    // Every coordinate finite, checked in chunks on every core; the first bad one in the file
    // is the one named.
    let bad = map_chunks(n, |range| range.into_iter().find_map(|i| non_finite(body, i).map(|k| (i, k))));
    if let Some((i, k)) = bad.into_iter().flatten().next() {
        let c = coordinate(body, i, k);
        let what = if c.is_nan() { "not a number (NaN)" } else { "infinite" };
        return Err(malformed(
            file,
            format!("triangle {} (byte {})", i + 1, HEADER + RECORD * i),
            format!("vertex {} has a coordinate that is {what}", k / 3 + 1),
            "repair the mesh in your modelling program and export it again",
        ));
    }
    Ok(BinaryStl { body })
}

/// Coordinate `k` (0..9: x, y, z of the three vertices) of record `i`.
#[inline]
fn coordinate(body: &[u8], i: usize, k: usize) -> f32 {
    let o = RECORD * i + 12 + 4 * k;
    let b: [u8; 4] = body.get(o..o + 4).and_then(|s| s.try_into().ok()).unwrap_or_default();
    f32::from_le_bytes(b)
}

/// The first coordinate of record `i` that is not finite.
fn non_finite(body: &[u8], i: usize) -> Option<usize> {
    (0..9).find(|&k| !coordinate(body, i, k).is_finite())
}

/// A binary STL's triangle records, checked (every coordinate finite), read in place: the
/// cleaner reads vertex `3i + k` as record `i`'s corner `k` and needs no copy of them.
#[derive(Debug)]
pub(super) struct BinaryStl<'a> {
    body: &'a [u8],
}

impl Soup for BinaryStl<'_> {
    const HELD: bool = false;

    fn vertex_count(&self) -> usize {
        3 * self.triangle_count()
    }

    #[inline]
    fn vertex(&self, i: usize) -> [f32; 3] {
        let o = RECORD * (i / 3) + 12 + 12 * (i % 3);
        let b: [u8; 12] = self.body.get(o..o + 12).and_then(|s| s.try_into().ok()).unwrap_or_default();
        let f = |k: usize| f32::from_le_bytes([b[k], b[k + 1], b[k + 2], b[k + 3]]);
        [f(0), f(4), f(8)]
    }

    fn triangle_count(&self) -> usize {
        self.body.len() / RECORD
    }

    fn into_corners(self, map: Words) -> Corners {
        Corners::Map(map)
    }
}

/// Whitespace tokenizer over bytes that knows the line of each token.
struct Lexer<'a> {
    bytes: &'a [u8],
    pos: usize,
    line: usize,
}

impl<'a> Lexer<'a> {
    fn new(bytes: &'a [u8]) -> Self {
        let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
        Lexer { bytes, pos: 0, line: 1 }
    }

    /// The next token and its line, or `None` at the end.
    fn next(&mut self) -> Option<(&'a [u8], usize)> {
        while let Some(&b) = self.bytes.get(self.pos) {
            if b == b'\n' {
                self.line += 1;
            } else if !b.is_ascii_whitespace() {
                break;
            }
            self.pos += 1;
        }
        let start = self.pos;
        while let Some(&b) = self.bytes.get(self.pos) {
            if b.is_ascii_whitespace() {
                break;
            }
            self.pos += 1;
        }
        if start == self.pos {
            return None;
        }
        Some((self.bytes.get(start..self.pos)?, self.line))
    }

    /// Skips to the end of the current line (names after `solid` / `endsolid`).
    fn skip_line(&mut self) {
        while let Some(&b) = self.bytes.get(self.pos) {
            if b == b'\n' {
                return;
            }
            self.pos += 1;
        }
    }
}

fn is(token: &[u8], word: &str) -> bool {
    token.eq_ignore_ascii_case(word.as_bytes())
}

/// (vertices, triangles) of an ASCII STL from a token scan without number parsing, the same
/// grammar as [`read_ascii`]: exact for a file that reads (a loop of k vertices is k − 2
/// triangles), and the reader fails before passing it otherwise.
pub(super) fn scan_ascii(bytes: &[u8]) -> (u64, u64) {
    let mut lx = Lexer::new(bytes);
    let (mut v, mut t, mut k) = (0u64, 0u64, 0u64);
    while let Some((tok, _)) = lx.next() {
        if is(tok, "solid") || is(tok, "endsolid") {
            lx.skip_line();
        } else if is(tok, "normal") || is(tok, "vertex") {
            k += u64::from(is(tok, "vertex"));
            for _ in 0..3 {
                lx.next();
            }
        } else if is(tok, "endloop") {
            v += k;
            t += k.saturating_sub(2);
            k = 0;
        }
    }
    (v, t)
}

/// Reads an ASCII STL; `(vertices, triangles)` from [`scan_ascii`] (already checked against
/// the limits) size the arrays once.
pub(super) fn read_ascii(file: &str, bytes: &[u8], (v, t): (u64, u64)) -> Result<RawMesh, Error> {
    let mut lx = Lexer::new(bytes);
    let mut mesh = RawMesh { vertices: Vec::with_capacity(v as usize), triangles: Vec::with_capacity(t as usize) };
    let fix = "the file is not valid ASCII STL; export it again (binary STL is smaller and safer)";
    let expected = |what: &str, got: Option<(&[u8], usize)>, line_at_end: usize| -> Error {
        match got {
            Some((t, line)) => malformed(file, format!("line {line}"), format!("expected {what}, found \"{}\"", show(t)), fix),
            None => malformed(file, format!("line {line_at_end}"), format!("the file ends where {what} was expected"), REEXPORT),
        }
    };
    let mut loop_pts: Vec<[f32; 3]> = Vec::with_capacity(3);
    'solids: loop {
        match lx.next() {
            None => break,
            Some((t, _)) if is(t, "solid") => lx.skip_line(),
            got => return Err(expected("\"solid\"", got, lx.line)),
        }
        loop {
            let got = lx.next();
            match got {
                // A missing `endsolid` at the very end is tolerated.
                None => break 'solids,
                Some((t, _)) if is(t, "endsolid") => {
                    lx.skip_line();
                    continue 'solids;
                }
                Some((t, _)) if is(t, "facet") => {}
                got => return Err(expected("\"facet\" or \"endsolid\"", got, lx.line)),
            }
            let mut got = lx.next();
            if matches!(got, Some((t, _)) if is(t, "normal")) {
                // Normals are recomputed; their values (sometimes "nan") are not checked.
                for _ in 0..3 {
                    if lx.next().is_none() {
                        return Err(expected("a normal component", None, lx.line));
                    }
                }
                got = lx.next();
            }
            if matches!(got, Some((t, _)) if is(t, "outer")) {
                got = lx.next();
            }
            match got {
                Some((t, _)) if is(t, "loop") => {}
                got => return Err(expected("\"outer loop\"", got, lx.line)),
            }
            loop_pts.clear();
            loop {
                match lx.next() {
                    Some((t, _)) if is(t, "vertex") => {
                        let mut p = [0f32; 3];
                        for (axis, slot) in p.iter_mut().enumerate() {
                            let got = lx.next();
                            let v = got.and_then(|(t, _)| parse_finite(t)).map(|v| v as f32).filter(|v| v.is_finite());
                            match v {
                                Some(v) => *slot = v,
                                None => return Err(expected(&format!("the {} coordinate of a vertex (a finite number)", ["x", "y", "z"][axis]), got, lx.line)),
                            }
                        }
                        loop_pts.push(p);
                    }
                    Some((t, line)) if is(t, "endloop") => {
                        if loop_pts.len() < 3 {
                            return Err(malformed(file, format!("line {line}"), format!("a facet has {} vertices, needs 3", loop_pts.len()), fix));
                        }
                        break;
                    }
                    got => return Err(expected("\"vertex\" or \"endloop\"", got, lx.line)),
                }
            }
            match lx.next() {
                Some((t, _)) if is(t, "endfacet") => {}
                got => return Err(expected("\"endfacet\"", got, lx.line)),
            }
            push_fan(file, &mut mesh, &loop_pts, lx.line)?;
        }
    }
    Ok(mesh)
}

/// Appends a polygon as a fan of triangles with fresh vertices.
fn push_fan(file: &str, mesh: &mut RawMesh, pts: &[[f32; 3]], line: usize) -> Result<(), Error> {
    let base = mesh.vertices.len();
    if base.saturating_add(pts.len()) > u32::MAX as usize {
        return Err(malformed(file, format!("line {line}"), "more vertices than weft can index", "split the model into smaller files"));
    }
    mesh.vertices.extend_from_slice(pts);
    let base = base as u32;
    for k in 1..pts.len().saturating_sub(1) {
        let k = k as u32;
        mesh.triangles.push([base, base + k, base + k + 1]);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    pub(crate) fn binary(tris: &[[[f32; 3]; 3]]) -> Vec<u8> {
        let mut b = vec![0u8; 80];
        b[..5].copy_from_slice(b"solid");
        b.extend_from_slice(&(tris.len() as u32).to_le_bytes());
        for t in tris {
            b.extend_from_slice(&[0u8; 12]);
            for v in t {
                for c in v {
                    b.extend_from_slice(&c.to_le_bytes());
                }
            }
            b.extend_from_slice(&[0, 0]);
        }
        b
    }

    const T: [[f32; 3]; 3] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];

    #[test]
    fn binary_reads_and_validates() {
        let b = binary(&[T, T]);
        assert!(binary_count_matches(&b));
        let m = read_binary("a.stl", &b).unwrap();
        assert_eq!(m.triangle_count(), 2);
        assert_eq!(m.vertex(1), [1.0, 0.0, 0.0]);

        let cut = &b[..b.len() - 10];
        assert!(!binary_count_matches(cut));
        let e = read_binary("a.stl", cut).unwrap_err().to_string();
        assert!(e.contains("triangle 2 (byte 134)"), "{e}");
        assert!(e.contains("cut short"), "{e}");

        let mut nan = binary(&[T, T]);
        let o = 84 + 50 + 12 + 4 * 4; // triangle 2, vertex 2, y
        nan[o..o + 4].copy_from_slice(&f32::NAN.to_le_bytes());
        let e = read_binary("a.stl", &nan).unwrap_err().to_string();
        assert!(e.contains("triangle 2 (byte 134)") && e.contains("vertex 2") && e.contains("NaN"), "{e}");

        let e = read_binary("a.stl", &[0u8; 40]).unwrap_err().to_string();
        assert!(e.contains("shorter than the 84-byte"), "{e}");
    }

    #[test]
    fn huge_count_does_not_allocate() {
        let mut b = vec![0u8; 84];
        b[80..84].copy_from_slice(&u32::MAX.to_le_bytes());
        assert!(read_binary("a.stl", &b).is_err());
    }

    #[test]
    fn ascii_tolerant() {
        let s = "SOLID cube\r\n  Facet Normal 0 0 nan\r\n outer loop\r\n vertex 0 0 0\r\n VERTEX 1 0 0\r\n vertex 0 1 0\r\n endloop\r\n endfacet\r\nendsolid cube\r\n\
                 solid second one\n facet normal 0 0 1 outer loop vertex 0 0 1 vertex 1 0 1 vertex 1 1 1 vertex 0 1 1 endloop endfacet\n";
        let m = read_ascii("a.stl", s.as_bytes(), (0, 0)).unwrap();
        assert_eq!(m.triangles.len(), 3, "quad facet becomes a fan of two");
        assert_eq!(m.vertices.len(), 7);
    }

    #[test]
    fn ascii_errors_name_the_line() {
        let s = "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 one 0\nendloop\nendfacet\nendsolid\n";
        let e = read_ascii("a.stl", s.as_bytes(), (0, 0)).unwrap_err().to_string();
        assert!(e.contains("line 6") && e.contains("y coordinate") && e.contains("\"one\""), "{e}");

        let s = "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfct\n";
        let e = read_ascii("a.stl", s.as_bytes(), (0, 0)).unwrap_err().to_string();
        assert!(e.contains("line 8") && e.contains("\"endfacet\""), "{e}");

        let s = "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n";
        let e = read_ascii("a.stl", s.as_bytes(), (0, 0)).unwrap_err().to_string();
        assert!(e.contains("line 5") && e.contains("ends"), "{e}");

        let s = "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 inf\n";
        let e = read_ascii("a.stl", s.as_bytes(), (0, 0)).unwrap_err().to_string();
        assert!(e.contains("line 4") && e.contains("finite"), "{e}");

        let s = "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 0 0 1\nendloop\nendfacet\n";
        let e = read_ascii("a.stl", s.as_bytes(), (0, 0)).unwrap_err().to_string();
        assert!(e.contains("line 6") && e.contains("2 vertices"), "{e}");
    }
}

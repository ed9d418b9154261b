//! DICOM series → volume.
//!
//! A small reader of its own rather than the dicom-rs crates: weft needs about twenty
//! attributes and the native pixel data, and dicom-object alone added 740 KB (281 KB
//! gzipped) to the wasm module (with dicom-pixeldata 1.1 MB / 370 KB), while its parser
//! sizes some value buffers from the length a file claims before checking that the file
//! holds it. Here every element is a borrowed slice of the file, checked against the bytes
//! left before it is used, so nothing is allocated from a claimed length.
//!
//! Method:
//! 1. Each file: optional 128-byte preamble + `DICM`, the File Meta group (always Explicit
//!    VR Little Endian) with the Transfer Syntax UID, then the data set in that syntax
//!    (Implicit VR LE, Explicit VR LE / BE, Deflated Explicit VR LE: inflated, bounded by
//!    what the header says the pixel data need). Files without meta are read as Implicit
//!    (or, when the VR letters say so, Explicit) VR LE. Elements are walked up to the
//!    Pixel Data (7FE0,0010); sequences are entered (depth ≤ [`MAX_DEPTH`]) only to find
//!    the multi-frame functional groups.
//! 2. The series: same study and series, same Rows/Columns, Pixel Spacing and orientation;
//!    slices are sorted by their Image Position (Patient) projected on the slice normal
//!    (row direction × column direction), not by file name or Instance Number; positions
//!    must differ, lie on one line along the normal and be evenly spaced (within
//!    [`GAP_TOLERANCE`] of the median gap; the mean gap becomes the spacing along k).
//! 3. Pixels: Bits Allocated 8/16/32, Bits Stored / High Bit masking, Pixel Representation
//!    sign extension, then `stored · Rescale Slope + Rescale Intercept` (per slice).
//!
//! The volume frame: `i` along a row (Pixel Spacing's second value), `j` down the columns
//! (its first value), `k` along the normal; the placement's origin is the first sorted
//! slice's position. Compressed (encapsulated) transfer syntaxes are refused, naming them.

use super::read::{base_name, clean, Error, ImportReport, Imported, Scan, HEAD_BYTES, MAX_VOXELS};
use super::{Placement, Volume, VolumeInfo};
use std::io::Read;

/// Deepest sequence nesting walked (real files nest 3–4 deep).
pub const MAX_DEPTH: usize = 16;
/// Largest relative difference between a slice gap and the median gap.
pub const GAP_TOLERANCE: f64 = 0.01;
/// Positions closer than this along the normal are the same position, mm.
pub const DUPLICATE_MM: f64 = 1e-3;
/// Largest header (everything before the pixel data) read from a deflated data set, bytes.
const MAX_DEFLATED_HEADER: usize = 64 << 20;

const TAG_PIXEL_DATA: u32 = 0x7FE0_0010;
const ITEM: u32 = 0xFFFE_E000;
const ITEM_END: u32 = 0xFFFE_E00D;
const SEQ_END: u32 = 0xFFFE_E0DD;
const SHARED_GROUPS: u32 = 0x5200_9229;
const PER_FRAME_GROUPS: u32 = 0x5200_9230;
/// Sequences Implicit VR files may hold with a defined length that must be entered.
const KNOWN_SEQUENCES: [u32; 5] = [SHARED_GROUPS, PER_FRAME_GROUPS, 0x0020_9113, 0x0020_9116, 0x0028_9110];
const DICOMDIR_CLASS: &str = "1.2.840.10008.1.3.10";

/// A transfer syntax weft knows.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Syntax {
    pub uid: &'static str,
    pub name: &'static str,
    pub explicit: bool,
    pub big: bool,
    pub deflated: bool,
    pub encapsulated: bool,
}

const fn ts(uid: &'static str, name: &'static str, explicit: bool, big: bool, deflated: bool, encapsulated: bool) -> Syntax {
    Syntax { uid, name, explicit, big, deflated, encapsulated }
}

/// Transfer syntaxes by UID (DICOM PS3.6 names).
const SYNTAXES: &[Syntax] = &[
    ts("1.2.840.10008.1.2", "Implicit VR Little Endian", false, false, false, false),
    ts("1.2.840.10008.1.2.1", "Explicit VR Little Endian", true, false, false, false),
    ts("1.2.840.10008.1.2.1.99", "Deflated Explicit VR Little Endian", true, false, true, false),
    ts("1.2.840.10008.1.2.2", "Explicit VR Big Endian", true, true, false, false),
    ts("1.2.840.10008.1.2.4.50", "JPEG Baseline (Process 1)", true, false, false, true),
    ts("1.2.840.10008.1.2.4.51", "JPEG Extended (Process 2 & 4)", true, false, false, true),
    ts("1.2.840.10008.1.2.4.57", "JPEG Lossless, Non-Hierarchical (Process 14)", true, false, false, true),
    ts("1.2.840.10008.1.2.4.70", "JPEG Lossless, Non-Hierarchical, First-Order Prediction (Process 14 [Selection Value 1])", true, false, false, true),
    ts("1.2.840.10008.1.2.4.80", "JPEG-LS Lossless Image Compression", true, false, false, true),
    ts("1.2.840.10008.1.2.4.81", "JPEG-LS Lossy (Near-Lossless) Image Compression", true, false, false, true),
    ts("1.2.840.10008.1.2.4.90", "JPEG 2000 Image Compression (Lossless Only)", true, false, false, true),
    ts("1.2.840.10008.1.2.4.91", "JPEG 2000 Image Compression", true, false, false, true),
    ts("1.2.840.10008.1.2.4.92", "JPEG 2000 Part 2 Multi-component Image Compression (Lossless Only)", true, false, false, true),
    ts("1.2.840.10008.1.2.4.93", "JPEG 2000 Part 2 Multi-component Image Compression", true, false, false, true),
    ts("1.2.840.10008.1.2.4.201", "High-Throughput JPEG 2000 Image Compression (Lossless Only)", true, false, false, true),
    ts("1.2.840.10008.1.2.4.202", "High-Throughput JPEG 2000 with RPCL Options Image Compression (Lossless Only)", true, false, false, true),
    ts("1.2.840.10008.1.2.4.203", "High-Throughput JPEG 2000 Image Compression", true, false, false, true),
    ts("1.2.840.10008.1.2.4.110", "JPEG XL Lossless", true, false, false, true),
    ts("1.2.840.10008.1.2.4.111", "JPEG XL JPEG Recompression", true, false, false, true),
    ts("1.2.840.10008.1.2.4.112", "JPEG XL", true, false, false, true),
    ts("1.2.840.10008.1.2.5", "RLE Lossless", true, false, false, true),
];

/// The syntax of `uid` (trailing NUL/space padding ignored).
pub(crate) fn syntax(uid: &str) -> Option<Syntax> {
    SYNTAXES.iter().copied().find(|s| s.uid == uid)
}

/// Whether `name` ends with a compressed-video or other encapsulated UID family not listed.
fn encapsulated_family(uid: &str) -> bool {
    uid.starts_with("1.2.840.10008.1.2.4.") || uid.starts_with("1.2.840.10008.1.2.8")
}

/// Everything read from one file's header.
#[derive(Clone, Debug, Default)]
pub(crate) struct Header {
    pub syntax: Option<Syntax>,
    pub syntax_uid: String,
    pub media_class: String,
    pub study: String,
    pub series: String,
    pub modality: String,
    pub rescale_type: Option<String>,
    pub rows: usize,
    pub cols: usize,
    pub frames: usize,
    pub samples: u16,
    pub bits_alloc: u16,
    pub bits_stored: u16,
    pub high_bit: Option<u16>,
    pub signed: bool,
    pub spacing: Option<[f64; 2]>,
    pub thickness: Option<f64>,
    pub position: Option<[f64; 3]>,
    pub orientation: Option<[f64; 6]>,
    pub slope: Option<f64>,
    pub intercept: Option<f64>,
    pub frame_positions: Vec<Option<[f64; 3]>>,
    pub float_pixels: bool,
    pub directory: bool,
    /// Start of the data set in the file (after the meta group).
    pub dataset_start: usize,
    /// Pixel data: offset in the data set bytes (the inflated ones when deflated), length
    /// (`None`: encapsulated).
    pub pixel: Option<(usize, Option<usize>)>,
}

/// Why a walk stopped early.
enum Stop {
    /// The bytes end inside an element (position of the element).
    Truncated(usize, String),
    /// Something no DICOM writer makes.
    Bad(String),
}

/// A cursor over a data set.
struct Cur<'a> {
    b: &'a [u8],
    pos: usize,
    explicit: bool,
    big: bool,
}

/// VRs whose explicit-VR header has 2 reserved bytes and a 4-byte length.
fn long_vr(vr: [u8; 2]) -> bool {
    matches!(&vr, b"OB" | b"OD" | b"OF" | b"OL" | b"OV" | b"OW" | b"SQ" | b"SV" | b"UC" | b"UN" | b"UR" | b"UT" | b"UV")
}

fn valid_vr(vr: [u8; 2]) -> bool {
    const ALL: [&[u8; 2]; 34] = [
        b"AE", b"AS", b"AT", b"CS", b"DA", b"DS", b"DT", b"FL", b"FD", b"IS", b"LO", b"LT", b"OB", b"OD", b"OF", b"OL", b"OV", b"OW", b"PN", b"SH", b"SL",
        b"SQ", b"SS", b"ST", b"SV", b"TM", b"UC", b"UI", b"UL", b"UN", b"UR", b"US", b"UT", b"UV",
    ];
    ALL.contains(&&vr)
}

const UNDEFINED: u32 = 0xFFFF_FFFF;

impl<'a> Cur<'a> {
    fn u16_at(&self, p: usize) -> Option<u16> {
        let b = self.b.get(p..p + 2)?;
        Some(if self.big { u16::from_be_bytes([b[0], b[1]]) } else { u16::from_le_bytes([b[0], b[1]]) })
    }
    fn u32_at(&self, p: usize) -> Option<u32> {
        let b = self.b.get(p..p + 4)?;
        let a = [b[0], b[1], b[2], b[3]];
        Some(if self.big { u32::from_be_bytes(a) } else { u32::from_le_bytes(a) })
    }
    fn tag_at(&self, p: usize) -> Option<u32> {
        Some(((self.u16_at(p)? as u32) << 16) | self.u16_at(p + 2)? as u32)
    }

    /// Reads an element header: (tag, VR, length) with `pos` moved to the value.
    fn header(&mut self) -> Result<(u32, [u8; 2], u32), Stop> {
        let at = self.pos;
        let cut = || Stop::Truncated(at, "an element header".into());
        let tag = self.tag_at(at).ok_or_else(cut)?;
        // Item and delimiter tags have no VR in any syntax.
        if tag >> 16 == 0xFFFE || !self.explicit {
            let len = self.u32_at(at + 4).ok_or_else(cut)?;
            self.pos = at + 8;
            return Ok((tag, *b"UN", len));
        }
        let vr_b = self.b.get(at + 4..at + 6).ok_or_else(cut)?;
        let vr = [vr_b[0], vr_b[1]];
        if long_vr(vr) {
            let len = self.u32_at(at + 8).ok_or_else(cut)?;
            self.pos = at + 12;
            Ok((tag, vr, len))
        } else if valid_vr(vr) {
            let len = self.u16_at(at + 6).ok_or_else(cut)? as u32;
            self.pos = at + 8;
            Ok((tag, vr, len))
        } else {
            Err(Stop::Bad(format!("element ({:04X},{:04X}) at byte {at} has no valid VR", tag >> 16, tag & 0xFFFF)))
        }
    }

    /// The `len` bytes of a value at `pos`, moving past them.
    fn value(&mut self, tag: u32, len: usize) -> Result<&'a [u8], Stop> {
        let at = self.pos;
        let v = self.b.get(at..at.saturating_add(len)).ok_or_else(|| {
            Stop::Truncated(at, format!("element ({:04X},{:04X}) needs {len} bytes, {} are left", tag >> 16, tag & 0xFFFF, self.b.len().saturating_sub(at)))
        })?;
        self.pos = at + len;
        Ok(v)
    }
}

/// Text of a value: lossy UTF-8, NUL and space padding trimmed.
fn text(v: &[u8]) -> String {
    String::from_utf8_lossy(v).trim_matches(|c: char| c == '\0' || c == ' ').to_string()
}

/// Decimal strings (DS/IS) separated by `\`.
fn numbers(v: &[u8]) -> Option<Vec<f64>> {
    let t = std::str::from_utf8(v).ok()?;
    t.split('\\').map(|p| p.trim_matches(|c: char| c == '\0' || c.is_ascii_whitespace()).parse::<f64>().ok().filter(|x| x.is_finite())).collect()
}

fn number(v: &[u8]) -> Option<f64> {
    numbers(v).and_then(|n| n.first().copied())
}

/// What the walk collects.
struct Visit<'h> {
    h: &'h mut Header,
}

impl Visit<'_> {
    fn element(&mut self, c: &Cur, path: &[(u32, usize)], tag: u32, value: &[u8]) {
        let h = &mut *self.h;
        let us = || if value.len() >= 2 { Some(c.u16_at(c.pos - value.len()).unwrap_or(0)) } else { None };
        match path {
            [] => match tag {
                0x0004_1220 => h.directory = true,
                0x0008_0060 => h.modality = clean(&text(value)),
                0x0020_000D => h.study = clean(&text(value)),
                0x0020_000E => h.series = clean(&text(value)),
                0x0018_0050 => h.thickness = h.thickness.or(number(value)),
                0x0020_0032 => h.position = h.position.or(vec3(value)),
                0x0020_0037 => h.orientation = h.orientation.or(vec6(value)),
                0x0028_0002 => h.samples = us().unwrap_or(0),
                0x0028_0008 => h.frames = number(value).filter(|f| *f >= 1.0 && *f <= 1e9).map_or(1, |f| f as usize),
                0x0028_0010 => h.rows = us().unwrap_or(0) as usize,
                0x0028_0011 => h.cols = us().unwrap_or(0) as usize,
                0x0028_0030 => h.spacing = h.spacing.or(vec2(value)),
                0x0028_0100 => h.bits_alloc = us().unwrap_or(0),
                0x0028_0101 => h.bits_stored = us().unwrap_or(0),
                0x0028_0102 => h.high_bit = us(),
                0x0028_0103 => h.signed = us() == Some(1),
                0x0028_1052 => h.intercept = h.intercept.or(number(value)),
                0x0028_1053 => h.slope = h.slope.or(number(value)),
                0x0028_1054 => h.rescale_type = h.rescale_type.take().or(Some(clean(&text(value)))),
                0x7FE0_0008 | 0x7FE0_0009 => h.float_pixels = true,
                _ => {}
            },
            // Multi-frame functional groups: shared first (its tag is smaller), then frame 0's
            // for what the shared group lacks.
            [(g, item), (_, _)] if *g == SHARED_GROUPS || (*g == PER_FRAME_GROUPS && *item == 0) => match tag {
                0x0020_0037 => h.orientation = h.orientation.or(vec6(value)),
                0x0028_0030 => h.spacing = h.spacing.or(vec2(value)),
                0x0018_0050 => h.thickness = h.thickness.or(number(value)),
                0x0028_1052 => h.intercept = h.intercept.or(number(value)),
                0x0028_1053 => h.slope = h.slope.or(number(value)),
                0x0028_1054 => h.rescale_type = h.rescale_type.take().or(Some(clean(&text(value)))),
                0x0020_0032 if *g == PER_FRAME_GROUPS => self.frame_position(0, value),
                _ => {}
            },
            [(g, item), (0x0020_9113, _)] if *g == PER_FRAME_GROUPS && tag == 0x0020_0032 => self.frame_position(*item, value),
            _ => {}
        }
    }

    fn frame_position(&mut self, item: usize, value: &[u8]) {
        let fp = &mut self.h.frame_positions;
        // Items arrive in order; a gap or a repeat is left to the series checks.
        if item == fp.len() {
            fp.push(vec3(value));
        }
    }
}

fn vec2(v: &[u8]) -> Option<[f64; 2]> {
    numbers(v).filter(|n| n.len() >= 2).map(|n| [n[0], n[1]])
}
fn vec3(v: &[u8]) -> Option<[f64; 3]> {
    numbers(v).filter(|n| n.len() >= 3).map(|n| [n[0], n[1], n[2]])
}
fn vec6(v: &[u8]) -> Option<[f64; 6]> {
    numbers(v).filter(|n| n.len() >= 6).map(|n| [n[0], n[1], n[2], n[3], n[4], n[5]])
}

/// Walks elements until `end` (or an item delimiter when `in_item`), entering sequences.
/// At the top level it stops at the Pixel Data, recording it. `Ok(true)`: pixel data found.
fn walk(c: &mut Cur, end: usize, in_item: bool, path: &mut Vec<(u32, usize)>, v: &mut Visit) -> Result<bool, Stop> {
    while c.pos < end {
        let at = c.pos;
        let (tag, vr, len) = c.header()?;
        if tag == ITEM_END && in_item {
            return Ok(false);
        }
        if path.is_empty() && tag == TAG_PIXEL_DATA {
            v.h.pixel = Some((c.pos, (len != UNDEFINED).then_some(len as usize)));
            return Ok(true);
        }
        if tag >> 16 == 0xFFFE {
            return Err(Stop::Bad(format!("an item tag ({:04X},{:04X}) stands outside a sequence at byte {at}", tag >> 16, tag & 0xFFFF)));
        }
        let is_seq = vr == *b"SQ"
            || (!c.explicit && KNOWN_SEQUENCES.contains(&tag) && len != UNDEFINED)
            || (len == UNDEFINED && !matches!(&vr, b"OB" | b"OW") && tag != TAG_PIXEL_DATA);
        if is_seq {
            if path.len() >= MAX_DEPTH {
                return Err(Stop::Bad(format!("sequences nest more than {MAX_DEPTH} deep at byte {at}")));
            }
            // A UN sequence of undefined length is encoded in Implicit VR LE.
            let saved = (c.explicit, c.big);
            if vr == *b"UN" && c.explicit {
                c.explicit = false;
                c.big = false;
            }
            let r = sequence(c, tag, len, end, path, v);
            (c.explicit, c.big) = saved;
            r?;
        } else if len == UNDEFINED {
            // Encapsulated data (an icon's pixel data): items of raw bytes up to the delimiter.
            skip_fragments(c, end)?;
        } else {
            let value = c.value(tag, len as usize)?;
            v.element(c, path, tag, value);
        }
    }
    if c.pos > end {
        return Err(Stop::Bad(format!("an element runs past the end of its item at byte {}", end)));
    }
    Ok(false)
}

/// Walks the items of a sequence.
fn sequence(c: &mut Cur, tag: u32, len: u32, outer_end: usize, path: &mut Vec<(u32, usize)>, v: &mut Visit) -> Result<(), Stop> {
    let end = if len == UNDEFINED {
        outer_end
    } else {
        c.pos
            .checked_add(len as usize)
            .filter(|&e| e <= outer_end)
            .ok_or_else(|| Stop::Truncated(c.pos, format!("sequence ({:04X},{:04X}) needs {len} bytes", tag >> 16, tag & 0xFFFF)))?
    };
    let mut item = 0usize;
    while c.pos < end {
        let at = c.pos;
        let (t, _, ilen) = c.header()?;
        match t {
            SEQ_END if len == UNDEFINED => return Ok(()),
            ITEM => {
                path.push((tag, item));
                let r = if ilen == UNDEFINED {
                    walk(c, end, true, path, v).map(|_| ())
                } else {
                    let iend =
                        c.pos.checked_add(ilen as usize).filter(|&e| e <= end).ok_or_else(|| Stop::Truncated(c.pos, format!("an item needs {ilen} bytes")))?;
                    let r = walk(c, iend, false, path, v).map(|_| ());
                    c.pos = iend;
                    r
                };
                path.pop();
                r?;
                item += 1;
            }
            _ => return Err(Stop::Bad(format!("sequence ({:04X},{:04X}) holds a non-item at byte {at}", tag >> 16, tag & 0xFFFF))),
        }
    }
    if len == UNDEFINED {
        return Err(Stop::Truncated(c.pos, format!("sequence ({:04X},{:04X}) has no end", tag >> 16, tag & 0xFFFF)));
    }
    Ok(())
}

fn skip_fragments(c: &mut Cur, end: usize) -> Result<(), Stop> {
    while c.pos < end {
        let at = c.pos;
        let tag = c.tag_at(at).ok_or(Stop::Truncated(at, "an item header".into()))?;
        let len = c.u32_at(at + 4).ok_or(Stop::Truncated(at, "an item header".into()))?;
        c.pos = at + 8;
        match tag {
            SEQ_END => return Ok(()),
            ITEM if len != UNDEFINED => {
                c.value(tag, len as usize)?;
            }
            _ => return Err(Stop::Bad(format!("encapsulated data hold a non-item at byte {at}"))),
        }
    }
    Err(Stop::Truncated(c.pos, "encapsulated data have no end".into()))
}

/// Whether `bytes` look like a DICOM file (preamble + `DICM`, or a meta group or a data set
/// starting at byte 0).
pub(crate) fn sniff(bytes: &[u8]) -> bool {
    if bytes.get(128..132) == Some(b"DICM") {
        return true;
    }
    let (Some(g), Some(e)) = (bytes.get(0..2), bytes.get(2..4)) else { return false };
    let group = u16::from_le_bytes([g[0], g[1]]);
    let elem = u16::from_le_bytes([e[0], e[1]]);
    let vr_ok = bytes.get(4..6).is_some_and(|v| valid_vr([v[0], v[1]]));
    match group {
        0x0002 => vr_ok,
        0x0008 => {
            let implicit_ok = bytes.get(4..8).is_some_and(|l| (u32::from_le_bytes([l[0], l[1], l[2], l[3]]) as usize) < bytes.len());
            elem < 0x0100 && (vr_ok || implicit_ok)
        }
        _ => false,
    }
}

fn dicom_err(file: &str, message: String) -> Error {
    Error::Dicom { file: clean(file), message }
}

fn stop_err(file: &str, s: Stop) -> Error {
    match s {
        Stop::Truncated(at, what) => Error::Truncated { file: clean(file), detail: format!("{what} at byte {at}") },
        Stop::Bad(m) => dicom_err(file, m),
    }
}

/// Reads the meta group; returns the header with `syntax`, `media_class`, `dataset_start`.
fn meta(file: &str, bytes: &[u8]) -> Result<Header, Error> {
    let mut h = Header { frames: 1, ..Default::default() };
    let start = if bytes.get(128..132) == Some(b"DICM") { 132 } else { 0 };
    let mut c = Cur { b: bytes, pos: start, explicit: true, big: false };
    let mut has_meta = false;
    while c.u16_at(c.pos) == Some(0x0002) {
        has_meta = true;
        let (tag, _, len) = c.header().map_err(|s| stop_err(file, s))?;
        if len == UNDEFINED {
            return Err(dicom_err(file, "a File Meta element has an undefined length".into()));
        }
        let value = c.value(tag, len as usize).map_err(|s| stop_err(file, s))?;
        match tag {
            0x0002_0002 => h.media_class = text(value),
            0x0002_0010 => h.syntax_uid = text(value),
            _ => {}
        }
    }
    h.dataset_start = c.pos;
    if !has_meta || h.syntax_uid.is_empty() {
        // No meta: Implicit VR LE (the default syntax), unless the VR letters say Explicit.
        let explicit = bytes.get(c.pos + 4..c.pos + 6).is_some_and(|v| valid_vr([v[0], v[1]]));
        h.syntax_uid = if explicit { "1.2.840.10008.1.2.1" } else { "1.2.840.10008.1.2" }.into();
    }
    h.syntax = syntax(&h.syntax_uid);
    Ok(h)
}

/// Inflates a deflated data set, at most `limit` bytes; `(bytes, complete)`.
fn inflate(file: &str, data: &[u8], limit: usize, prefix: bool) -> Result<(Vec<u8>, bool), Error> {
    let mut out = Vec::new();
    let r = flate2::read::DeflateDecoder::new(data).take(limit as u64 + 1).read_to_end(&mut out);
    match r {
        Ok(_) => {
            let complete = out.len() <= limit;
            out.truncate(limit);
            Ok((out, complete))
        }
        // A prefix of a stream (a zip entry's head) ends mid-stream: keep what came out.
        Err(_) if prefix => Ok((out, false)),
        Err(_) => Err(dicom_err(file, "the deflated data set cannot be inflated: it is damaged".into())),
    }
}

/// Parses one file's header. `complete`: `bytes` is the whole file (else a prefix: running
/// out of bytes ends the scan without an error). Deflated data sets are inflated up to
/// [`HEAD_BYTES`], then (when the pixel data were not reached) up to 64 MiB.
pub(crate) fn header(file: &str, bytes: &[u8], complete: bool) -> Result<Header, Error> {
    let mut h = meta(file, bytes)?;
    let Some(s) = h.syntax else {
        if encapsulated_family(&h.syntax_uid) {
            return Err(Error::Compressed { file: clean(file), syntax_name: format!("transfer syntax {}", clean(&h.syntax_uid)) });
        }
        return Err(Error::Unsupported {
            file: clean(file),
            what: format!("transfer syntax {} is not one weft reads; convert the series to Explicit VR Little Endian", clean(&h.syntax_uid)),
        });
    };
    let data = bytes.get(h.dataset_start..).unwrap_or_default();
    if s.deflated {
        let (head, done) = inflate(file, data, HEAD_BYTES, !complete)?;
        walk_header(file, &head, s, done || !complete, &mut h)?;
        if h.pixel.is_none() && !done && complete {
            let (all, done) = inflate(file, data, MAX_DEFLATED_HEADER, false)?;
            walk_header(file, &all, s, done, &mut h)?;
            if h.pixel.is_none() && !done {
                return Err(Error::Unsupported {
                    file: clean(file),
                    what: format!("the header is over {} MiB before the pixel data", MAX_DEFLATED_HEADER >> 20),
                });
            }
        }
    } else {
        walk_header(file, data, s, complete, &mut h)?;
    }
    Ok(h)
}

fn walk_header(file: &str, data: &[u8], s: Syntax, complete: bool, h: &mut Header) -> Result<(), Error> {
    let keep = (h.syntax, h.syntax_uid.clone(), h.media_class.clone(), h.dataset_start);
    *h = Header { frames: 1, ..Default::default() };
    (h.syntax, h.syntax_uid, h.media_class, h.dataset_start) = keep;
    let mut c = Cur { b: data, pos: 0, explicit: s.explicit, big: s.big };
    let r = walk(&mut c, data.len(), false, &mut Vec::new(), &mut Visit { h });
    match r {
        Ok(_) => {}
        Err(Stop::Truncated(..)) if !complete => return Ok(()),
        Err(e) => return Err(stop_err(file, e)),
    }
    if let (Some((at, Some(len))), true) = (h.pixel, complete) {
        if at.saturating_add(len) > data.len() {
            return Err(Error::Truncated {
                file: clean(file),
                detail: format!("the pixel data need {len} bytes from byte {}, {} are left", at + h.dataset_start, data.len().saturating_sub(at)),
            });
        }
    }
    Ok(())
}

/// A file's role in the drop.
enum Role {
    Image(Box<Header>),
    Skipped(String),
}

fn classify(name: &str, bytes: &[u8], complete: bool) -> Result<Role, Error> {
    if base_name(name).eq_ignore_ascii_case("DICOMDIR") {
        return Ok(Role::Skipped("DICOMDIR, a directory index, not an image".into()));
    }
    if !sniff(bytes) {
        return Ok(Role::Skipped("not a DICOM file".into()));
    }
    let h = header(name, bytes, complete)?;
    if h.media_class == DICOMDIR_CLASS || h.directory {
        return Ok(Role::Skipped("DICOMDIR, a directory index, not an image".into()));
    }
    if h.pixel.is_none() && h.rows == 0 && !h.float_pixels {
        return Ok(Role::Skipped(format!("a DICOM file without an image (SOP class {})", clean(&h.media_class))));
    }
    if h.pixel.is_none() && complete && !h.float_pixels {
        return Err(Error::NoPixelData { file: clean(name) });
    }
    Ok(Role::Image(Box::new(h)))
}

/// The header scan: voxels of every image file (rows × columns × frames).
pub(crate) fn scan(files: &[(&str, &[u8])], partial: bool) -> Result<Scan, Error> {
    let mut s = Scan::default();
    for (name, bytes) in files {
        let h = match classify(name, bytes, !partial) {
            Ok(Role::Image(h)) => h,
            Ok(Role::Skipped(_)) => continue,
            Err(_) if partial => continue,
            Err(e) => return Err(e),
        };
        let voxels = (h.rows as u64).saturating_mul(h.cols as u64).saturating_mul(h.frames as u64);
        s.voxels = s.voxels.saturating_add(voxels);
        if h.syntax.is_some_and(|s| s.deflated) {
            s.inflated = s.inflated.saturating_add(voxels.saturating_mul((h.bits_alloc as u64 / 8).max(1)));
        }
        s.files += 1;
    }
    Ok(s)
}

/// One slice: file, frame, position along the normal.
struct Slice {
    file: usize,
    frame: usize,
    position: [f64; 3],
    along: f64,
}

fn label(name: &str, frames: usize, frame: usize) -> String {
    if frames > 1 {
        format!("{} (frame {})", clean(name), frame + 1)
    } else {
        clean(name)
    }
}

fn close(a: &[f64], b: &[f64], tol: f64) -> bool {
    a.iter().zip(b).all(|(x, y)| (x - y).abs() <= tol * x.abs().max(y.abs()).max(1.0))
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}
fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}

fn fmt2(v: [f64; 2]) -> String {
    format!("{}\\{} mm", v[0], v[1])
}

/// Checks one image header on its own.
fn check_image(name: &str, h: &Header) -> Result<(), Error> {
    let file = clean(name);
    let s = h.syntax.expect("header() refuses unknown syntaxes");
    if s.encapsulated {
        return Err(Error::Compressed { file, syntax_name: s.name.to_string() });
    }
    if h.float_pixels {
        return Err(Error::Unsupported { file, what: "float pixel data (7FE0,0008) are not read; export integer pixel data with a rescale".into() });
    }
    if h.samples > 1 {
        return Err(Error::Unsupported {
            file,
            what: format!("a colour image ({} samples per pixel) is not a CT/MR volume; drop a greyscale series", h.samples),
        });
    }
    if !matches!(h.bits_alloc, 8 | 16 | 32) {
        return Err(Error::Unsupported { file, what: format!("Bits Allocated {} is not read (8, 16 or 32 are)", h.bits_alloc) });
    }
    if h.bits_stored > h.bits_alloc || h.high_bit.is_some_and(|hb| hb >= h.bits_alloc || hb + 1 < h.bits_stored) {
        return Err(dicom_err(name, format!("Bits Stored {} / High Bit {:?} do not fit Bits Allocated {}", h.bits_stored, h.high_bit, h.bits_alloc)));
    }
    if h.rows == 0 || h.cols == 0 {
        return Err(dicom_err(name, "Rows or Columns (0028,0010/0011) is missing or 0".into()));
    }
    let need = h.rows.saturating_mul(h.cols).saturating_mul(h.frames).saturating_mul(h.bits_alloc as usize / 8);
    if let Some((_, Some(len))) = h.pixel {
        if len < need {
            return Err(Error::SizeMismatch {
                file,
                expected: format!("Rows × Columns × frames ({}×{}×{}) of {} bits need {need} bytes", h.rows, h.cols, h.frames, h.bits_alloc),
                found: format!("the pixel data hold {len} bytes"),
            });
        }
    }
    if h.slope.is_some_and(|m| m == 0.0) {
        return Err(dicom_err(name, "Rescale Slope (0028,1053) is 0".into()));
    }
    Ok(())
}

/// Reads the series in `files` (headers first, then pixels slice by slice).
pub(crate) fn read(files: &[(&str, &[u8])]) -> Result<Imported, Error> {
    let mut skipped = Vec::new();
    let mut images: Vec<(usize, Box<Header>)> = Vec::new();
    for (i, (name, bytes)) in files.iter().enumerate() {
        match classify(name, bytes, true)? {
            Role::Image(h) => images.push((i, h)),
            Role::Skipped(why) => skipped.push(format!("{}: {why}", clean(name))),
        }
    }
    let Some((first_i, first)) = images.first() else {
        let why = if files.len() == 1 {
            "not a DICOM image, NRRD (.nrrd/.nhdr) or raw volume (.raw); drop a DICOM series (its files or a .zip), an NRRD or a raw file"
        } else {
            "none of the files is a DICOM image; drop the files of a DICOM series (or its folder zipped), an NRRD or a raw file"
        };
        return Err(Error::NotAVolume { file: clean(files[0].0), why: why.into() });
    };
    let name_of = |i: usize| files[i].0;
    let first_name = name_of(*first_i);
    // Same study, series; each image readable; same size, spacing, orientation.
    for (i, h) in &images {
        if h.study != first.study {
            return Err(Error::MixedSeries { what: "studies", file_a: clean(first_name), file_b: clean(name_of(*i)) });
        }
        if h.series != first.series {
            return Err(Error::MixedSeries { what: "series", file_a: clean(first_name), file_b: clean(name_of(*i)) });
        }
    }
    for (i, h) in &images {
        check_image(name_of(*i), h)?;
        if (h.rows, h.cols) != (first.rows, first.cols) {
            return Err(Error::SizeMismatch {
                file: clean(name_of(*i)),
                expected: format!("{} has Rows × Columns {} × {}", clean(first_name), first.rows, first.cols),
                found: format!("Rows × Columns is {} × {}", h.rows, h.cols),
            });
        }
        if (h.bits_alloc, h.signed) != (first.bits_alloc, first.signed) {
            return Err(Error::SizeMismatch {
                file: clean(name_of(*i)),
                expected: format!("{} has {}-bit {} pixels", clean(first_name), first.bits_alloc, if first.signed { "signed" } else { "unsigned" }),
                found: format!("it has {}-bit {} pixels", h.bits_alloc, if h.signed { "signed" } else { "unsigned" }),
            });
        }
        let Some(sp) = h.spacing.filter(|s| s.iter().all(|v| *v > 0.0)) else {
            return Err(Error::Unsupported {
                file: clean(name_of(*i)),
                what: "no valid Pixel Spacing (0028,0030): the image is not measured in mm (a screenshot or secondary capture?); drop the original series"
                    .into(),
            });
        };
        if !close(&sp, &first.spacing.unwrap_or(sp), 1e-4) {
            return Err(Error::SpacingMismatch { file: clean(name_of(*i)), expected: fmt2(first.spacing.unwrap_or(sp)), found: fmt2(sp) });
        }
        let Some(o) = h.orientation else {
            return Err(Error::Unsupported {
                file: clean(name_of(*i)),
                what: "no Image Orientation (Patient) (0020,0037): the slices cannot be placed; drop the original series".into(),
            });
        };
        if !close(&o, &first.orientation.unwrap_or(o), 1e-4) {
            return Err(Error::OrientationMismatch { file_a: clean(first_name), file_b: clean(name_of(*i)) });
        }
    }
    let o = first.orientation.unwrap_or_default();
    let (row, col) = ([o[0], o[1], o[2]], [o[3], o[4], o[5]]);
    let (nr, nc) = (norm(row), norm(col));
    if !((nr - 1.0).abs() < 1e-2 && (nc - 1.0).abs() < 1e-2 && dot(row, col).abs() < 1e-2) {
        return Err(dicom_err(first_name, "Image Orientation (Patient) is not two perpendicular unit directions".into()));
    }
    let row = row.map(|x| x / nr);
    let col = col.map(|x| x / nc);
    let n = cross(row, col);
    let n = n.map(|x| x / norm(n));

    // The slices: one per file, or one per frame of a single multi-frame file.
    let mut slices = Vec::new();
    if images.iter().any(|(_, h)| h.frames > 1) {
        if images.len() > 1 {
            let (i, h) = images.iter().find(|(_, h)| h.frames > 1).expect("found");
            return Err(Error::Unsupported {
                file: clean(name_of(*i)),
                what: format!("a multi-frame file ({} frames) among other images; drop that file alone", h.frames),
            });
        }
        let h = first;
        if h.frame_positions.len() != h.frames || h.frame_positions.iter().any(|p| p.is_none()) {
            return Err(Error::Unsupported {
                file: clean(first_name),
                what: format!(
                    "a multi-frame file ({} frames) without a Plane Position (0020,9113) for every frame; export the series as single-frame files",
                    h.frames
                ),
            });
        }
        for (f, p) in h.frame_positions.iter().enumerate() {
            let p = p.unwrap_or_default();
            slices.push(Slice { file: 0, frame: f, position: p, along: dot(p, n) });
        }
    } else {
        for (idx, (i, h)) in images.iter().enumerate() {
            let Some(p) = h.position else {
                return Err(Error::Unsupported {
                    file: clean(name_of(*i)),
                    what: "no Image Position (Patient) (0020,0032): the slice cannot be placed; drop the original series".into(),
                });
            };
            slices.push(Slice { file: idx, frame: 0, position: p, along: dot(p, n) });
        }
    }
    let frames_of = |s: &Slice| images[s.file].1.frames;
    let slice_name = |s: &Slice| label(name_of(images[s.file].0), frames_of(s), s.frame);
    if slices.len() < 2 {
        return Err(Error::NotAVolume {
            file: clean(first_name),
            why: "a single 2D image, not a volume; drop all the files of the series (or its folder zipped)".into(),
        });
    }
    slices.sort_by(|a, b| a.along.total_cmp(&b.along).then_with(|| name_of(images[a.file].0).cmp(name_of(images[b.file].0))));
    for w in slices.windows(2) {
        if (w[1].along - w[0].along).abs() < DUPLICATE_MM {
            return Err(Error::DuplicatePosition { file_a: slice_name(&w[0]), file_b: slice_name(&w[1]), position: w[1].position });
        }
    }
    let count = slices.len();
    let span = slices[count - 1].along - slices[0].along;
    let gap = span / (count - 1) as f64;
    // Each gap against the median gap (a missing slice makes one gap double; the mean would
    // shift and blame the wrong pair), the worst one reported.
    let mut gaps: Vec<f64> = slices.windows(2).map(|w| w[1].along - w[0].along).collect();
    gaps.sort_by(f64::total_cmp);
    let median = gaps[gaps.len() / 2];
    let worst = slices.windows(2).max_by(|a, b| {
        let da = ((a[1].along - a[0].along) - median).abs();
        let db = ((b[1].along - b[0].along) - median).abs();
        da.total_cmp(&db)
    });
    if let Some(w) = worst {
        let g = w[1].along - w[0].along;
        if (g - median).abs() > GAP_TOLERANCE * median {
            return Err(Error::UnevenSlices { file_a: slice_name(&w[0]), file_b: slice_name(&w[1]), gap_mm: g, expected_mm: median });
        }
    }
    let p0 = slices[0].position;
    for s in &slices {
        let d = [s.position[0] - p0[0], s.position[1] - p0[1], s.position[2] - p0[2]];
        let a = s.along - slices[0].along;
        let off = norm([d[0] - a * n[0], d[1] - a * n[1], d[2] - a * n[2]]);
        if off > GAP_TOLERANCE * gap + 1e-3 {
            return Err(Error::Unsupported {
                file: slice_name(s),
                what: format!("the slice is shifted {off:.3} mm sideways from the line of the others (gantry tilt or a sheared stack); resample the series to an orthogonal grid"),
            });
        }
    }

    // Allocate (the voxel count was checked by the scan; re-checked for direct callers).
    let plane = first.rows * first.cols;
    let voxels = plane.checked_mul(count).filter(|&v| v <= MAX_VOXELS).ok_or_else(|| {
        Error::TooBig(crate::budget::OverBudget {
            what: "voxels".into(),
            value: plane as f64 * count as f64,
            limit: MAX_VOXELS as f64,
            unit: "",
            fix: "crop or resample the series".into(),
        })
    })?;
    let mut values = vec![0f32; voxels];
    let bpp = first.bits_alloc as usize / 8;
    let frame_bytes = plane * bpp;
    // A deflated file is inflated once, up to the end of its pixel data.
    let mut inflated: Option<(usize, Vec<u8>)> = None;
    for (k, s) in slices.iter().enumerate() {
        let (fi, h) = &images[s.file];
        let (name, bytes) = files[*fi];
        let syn = h.syntax.expect("checked");
        let Some((at, _)) = h.pixel else { return Err(Error::NoPixelData { file: clean(name) }) };
        let start = at + s.frame * frame_bytes;
        let dataset = &bytes[h.dataset_start.min(bytes.len())..];
        let data: &[u8] = if syn.deflated {
            if inflated.as_ref().is_none_or(|(f, _)| *f != s.file) {
                let (d, _) = inflate(name, dataset, at + h.frames * frame_bytes, false)?;
                inflated = Some((s.file, d));
            }
            inflated.as_ref().map_or(&[], |(_, d)| d.as_slice())
        } else {
            dataset
        };
        let px = data.get(start..start + frame_bytes).ok_or_else(|| Error::Truncated { file: clean(name), detail: "the pixel data end early".into() })?;
        decode(px, h, syn.big, &mut values[k * plane..(k + 1) * plane]);
    }

    let modality = first.modality.clone();
    let unit = match &first.rescale_type {
        Some(t) if !t.is_empty() => t.clone(),
        _ if modality == "CT" => "HU".into(),
        _ => String::new(),
    };
    let syntax_name = first.syntax.map_or("", |s| s.name).to_string();
    let mut notes = Vec::new();
    if let Some(t) = first.thickness.filter(|t| (t - gap).abs() > GAP_TOLERANCE * gap) {
        notes.push(format!("Slice Thickness {t} mm differs from the {gap:.4} mm gap between slice positions; the gap is the spacing along k"));
    }
    let sp = first.spacing.unwrap_or([1.0, 1.0]);
    let volume = Volume {
        dims: [first.cols, first.rows, count],
        // Pixel Spacing is row spacing (along j) then column spacing (along i).
        spacing_mm: [sp[1], sp[0], gap],
        values,
        placement: Placement { origin_mm: slices[0].position, axes: [row, col, n] },
        info: VolumeInfo {
            format: "DICOM".into(),
            files: images.len(),
            transfer_syntax: syntax_name,
            modality,
            unit,
            study_uid: first.study.clone(),
            series_uid: first.series.clone(),
        },
    };
    skipped.truncate(1000);
    let report = ImportReport { format: "DICOM".into(), files_read: images.len(), skipped, slice_gap_mm: gap, notes, ..Default::default() };
    Ok(Imported { volume, report })
}

/// Stored samples → rescaled values.
fn decode(px: &[u8], h: &Header, big: bool, out: &mut [f32]) {
    let alloc = h.bits_alloc as u32;
    let stored = if h.bits_stored == 0 { alloc } else { h.bits_stored as u32 };
    let high = h.high_bit.map_or(stored - 1, |b| b as u32);
    let shift = (high + 1).saturating_sub(stored);
    let mask: u64 = (1u64 << stored) - 1;
    let (slope, intercept) = (h.slope.unwrap_or(1.0), h.intercept.unwrap_or(0.0));
    let size = alloc as usize / 8;
    for (o, c) in out.iter_mut().zip(px.chunks_exact(size)) {
        let raw: u64 = match (size, big) {
            (1, _) => c[0] as u64,
            (2, false) => u16::from_le_bytes([c[0], c[1]]) as u64,
            (2, true) => u16::from_be_bytes([c[0], c[1]]) as u64,
            (_, false) => u32::from_le_bytes([c[0], c[1], c[2], c[3]]) as u64,
            (_, true) => u32::from_be_bytes([c[0], c[1], c[2], c[3]]) as u64,
        };
        let v = (raw >> shift) & mask;
        let s = if h.signed && (v >> (stored - 1)) & 1 == 1 { v as i64 - (1i64 << stored) } else { v as i64 };
        *o = (s as f64 * slope + intercept) as f32;
    }
}

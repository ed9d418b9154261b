//! NRRD volumes: `.nrrd` (header and data in one file, split at the first blank line) or
//! `.nhdr` (header only; `data file:` names the data file, which must be among the files
//! given, found by its base name: a name from a file never becomes a path).
//!
//! Read: `dimension: 3`, `type` (every 8/16/32-bit integer and float spelling, `double`),
//! `sizes`, `endian`, `encoding` (`raw`, `gzip`), `spacings` or `space directions` (with
//! `space origin` and `space`: RAS-type spaces are turned into DICOM's LPS by negating x and
//! y), `byte skip` (`-1`: the data sit at the end), `line skip`. The first axis is `i`
//! (fastest). Values are stored samples (NRRD has no rescale). Other fields (`kinds`,
//! `units`, `centers`, key/value pairs) are ignored. The header is bounded
//! ([`MAX_HEADER_BYTES`]) and gzip data are inflated one byte past what `sizes` need, so a
//! hostile header or stream costs no more than the volume it claims.

use super::raw::convert;
use super::read::{base_name, clean, extension, Error, ImportReport, Imported, Scan, VoxelType};
use super::{Placement, Volume, VolumeInfo};
use std::io::Read;

/// Longest NRRD header read, bytes (real headers are under 2 KiB).
pub const MAX_HEADER_BYTES: usize = 1 << 20;

fn err(file: &str, line: usize, message: impl Into<String>) -> Error {
    Error::Nrrd { file: clean(file), line, message: message.into() }
}

#[derive(Clone, Copy, PartialEq, Debug)]
enum Encoding {
    Raw,
    Gzip,
}

#[derive(Debug)]
struct Header {
    /// Header file.
    file: String,
    voxel: VoxelType,
    sizes: [usize; 3],
    voxels: usize,
    big_endian: bool,
    encoding: Encoding,
    spacing: [f64; 3],
    placement: Placement,
    byte_skip: i64,
    line_skip: usize,
    /// Detached data file's name.
    data_file: Option<String>,
    /// Attached data start in the header file.
    data_start: usize,
    /// Line of `sizes:`, for size messages.
    sizes_line: usize,
    notes: Vec<String>,
}

fn voxel_type(s: &str) -> Option<VoxelType> {
    Some(match s {
        "signed char" | "int8" | "int8_t" => VoxelType::I8,
        "uchar" | "unsigned char" | "uint8" | "uint8_t" => VoxelType::U8,
        "short" | "short int" | "signed short" | "signed short int" | "int16" | "int16_t" => VoxelType::I16,
        "ushort" | "unsigned short" | "unsigned short int" | "uint16" | "uint16_t" => VoxelType::U16,
        "int" | "signed int" | "int32" | "int32_t" => VoxelType::I32,
        "uint" | "unsigned int" | "uint32" | "uint32_t" => VoxelType::U32,
        "float" => VoxelType::F32,
        "double" => VoxelType::F64,
        _ => return None,
    })
}

fn parse_vector(s: &str) -> Option<[f64; 3]> {
    let inner = s.trim().strip_prefix('(')?.strip_suffix(')')?;
    let mut out = [0.0; 3];
    let mut n = 0;
    for part in inner.split(',') {
        let v: f64 = part.trim().parse().ok()?;
        if n == 3 || !v.is_finite() {
            return None;
        }
        out[n] = v;
        n += 1;
    }
    (n == 3).then_some(out)
}

/// Splits `space directions: (a,b,c) (d,e,f) (g,h,i)` into its vectors.
fn parse_directions(s: &str) -> Option<[[f64; 3]; 3]> {
    let mut out = [[0.0; 3]; 3];
    let mut n = 0;
    let mut rest = s.trim();
    while !rest.is_empty() {
        if n == 3 {
            return None;
        }
        let end = rest.find(')')?;
        out[n] = parse_vector(&rest[..=end])?;
        n += 1;
        rest = rest[end + 1..].trim_start();
    }
    (n == 3).then_some(out)
}

fn parse_header(file: &str, bytes: &[u8]) -> Result<Header, Error> {
    if !bytes.starts_with(b"NRRD000") {
        return Err(err(file, 1, "an NRRD file starts with NRRD0001…NRRD0005; this is not an NRRD header"));
    }
    let detached = extension(file) == "nhdr";
    let window = &bytes[..bytes.len().min(MAX_HEADER_BYTES)];
    // Header end: the first empty line (attached data follow it) or the end of an .nhdr.
    let (text_end, data_start) = match find_blank_line(window) {
        Some((end, start)) => (end, start),
        None if detached && bytes.len() <= MAX_HEADER_BYTES => (bytes.len(), bytes.len()),
        None => {
            return Err(err(
                file,
                0,
                format!("no empty line ends the header within its first {} KiB; an attached NRRD needs one before the data", MAX_HEADER_BYTES >> 10),
            ))
        }
    };
    let text = std::str::from_utf8(&bytes[..text_end]).map_err(|e| {
        let line = bytes[..e.valid_up_to()].iter().filter(|&&b| b == b'\n').count() + 1;
        err(file, line, "the header is not text (UTF-8/ASCII)")
    })?;
    let mut h = Header {
        file: file.to_string(),
        voxel: VoxelType::U8,
        sizes: [0; 3],
        voxels: 0,
        big_endian: false,
        encoding: Encoding::Raw,
        spacing: [1.0; 3],
        placement: Placement::default(),
        byte_skip: 0,
        line_skip: 0,
        data_file: None,
        data_start,
        sizes_line: 1,
        notes: Vec::new(),
    };
    let (mut have_type, mut have_dim, mut have_sizes, mut have_endian, mut have_spacing) = (false, false, false, false, false);
    let mut directions: Option<([[f64; 3]; 3], usize)> = None;
    let mut origin = [0.0; 3];
    let mut flip = false;
    for (n, raw_line) in text.lines().enumerate().skip(1) {
        let line = n + 1;
        let l = raw_line.trim_end_matches('\r');
        if l.starts_with('#') || l.trim().is_empty() || l.contains(":=") {
            continue;
        }
        let Some((key, value)) = l.split_once(':') else {
            return Err(err(file, line, format!("\"{}\" is not a \"field: value\" line", clean(l))));
        };
        let key = key.trim().to_ascii_lowercase();
        let value = value.trim();
        let bad = |what: &str| err(file, line, format!("{what} (found \"{}\")", clean(value)));
        match key.as_str() {
            "dimension" => {
                if value != "3" {
                    return Err(bad("weft reads 3D volumes only: dimension must be 3"));
                }
                have_dim = true;
            }
            "type" => {
                h.voxel = voxel_type(value).ok_or_else(|| bad("unknown or unsupported type: use an 8/16/32-bit integer, float or double"))?;
                have_type = true;
            }
            "sizes" => {
                let v: Vec<&str> = value.split_whitespace().collect();
                let parsed: Option<Vec<usize>> = v.iter().map(|s| s.parse().ok().filter(|&x: &usize| x > 0)).collect();
                match parsed {
                    Some(p) if p.len() == 3 => h.sizes = [p[0], p[1], p[2]],
                    _ => return Err(bad("sizes must be three positive whole numbers")),
                }
                h.sizes_line = line;
                have_sizes = true;
            }
            "endian" => {
                h.big_endian = match value {
                    "little" => false,
                    "big" => true,
                    _ => return Err(bad("endian must be little or big")),
                };
                have_endian = true;
            }
            "encoding" => {
                h.encoding = match value {
                    "raw" => Encoding::Raw,
                    "gzip" | "gz" => Encoding::Gzip,
                    _ => return Err(bad("weft reads raw and gzip encodings; save the NRRD as raw or gzip")),
                };
            }
            "spacings" => {
                let p: Option<Vec<f64>> = value.split_whitespace().map(|s| s.parse().ok().filter(|x: &f64| x.is_finite() && *x > 0.0)).collect();
                match p {
                    Some(p) if p.len() == 3 => h.spacing = [p[0], p[1], p[2]],
                    _ => return Err(bad("spacings must be three positive numbers (mm)")),
                }
                have_spacing = true;
            }
            "space directions" => {
                let d = parse_directions(value)
                    .ok_or_else(|| bad("space directions must be three vectors (x,y,z) (none is not allowed: every axis must be spatial)"))?;
                directions = Some((d, line));
            }
            "space origin" => origin = parse_vector(value).ok_or_else(|| bad("space origin must be a vector (x,y,z)"))?,
            "space" => {
                let v = value.to_ascii_lowercase();
                flip = matches!(v.as_str(), "right-anterior-superior" | "ras" | "right-anterior-superior-time" | "ras-time");
            }
            "byte skip" => h.byte_skip = value.parse().ok().filter(|&b: &i64| b >= -1).ok_or_else(|| bad("byte skip must be -1 or a whole number ≥ 0"))?,
            "line skip" => h.line_skip = value.parse().map_err(|_| bad("line skip must be a whole number ≥ 0"))?,
            "data file" | "datafile" => {
                if value.starts_with("LIST") || value.contains('%') {
                    return Err(bad("a data file list or pattern is not read; save the volume as one data file"));
                }
                h.data_file = Some(value.to_string());
            }
            _ => {}
        }
    }
    if !have_dim {
        return Err(err(file, 1, "the header has no \"dimension: 3\" field"));
    }
    if !have_type {
        return Err(err(file, 1, "the header has no \"type:\" field"));
    }
    if !have_sizes {
        return Err(err(file, 1, "the header has no \"sizes:\" field"));
    }
    if !have_endian && h.voxel.size() > 1 {
        return Err(err(file, 1, "the header has no \"endian:\" field, which a multi-byte type needs"));
    }
    if h.byte_skip == -1 && h.encoding != Encoding::Raw {
        return Err(err(file, 1, "byte skip -1 is only allowed with raw encoding"));
    }
    if h.encoding == Encoding::Gzip && h.byte_skip > MAX_HEADER_BYTES as i64 {
        // Skipped bytes are inflated too: bound them like a header.
        return Err(err(file, 1, format!("byte skip {} is more than the {} KiB weft skips in gzip data", h.byte_skip, MAX_HEADER_BYTES >> 10)));
    }
    if let Some((d, line)) = directions {
        let mut axes = [[0.0; 3]; 3];
        for a in 0..3 {
            let n = (d[a][0] * d[a][0] + d[a][1] * d[a][1] + d[a][2] * d[a][2]).sqrt();
            if n.is_nan() || n <= 0.0 {
                return Err(err(file, line, format!("space direction {} has zero length", a + 1)));
            }
            h.spacing[a] = n;
            axes[a] = [d[a][0] / n, d[a][1] / n, d[a][2] / n];
        }
        for (a, b) in [(0, 1), (0, 2), (1, 2)] {
            let dot = axes[a][0] * axes[b][0] + axes[a][1] * axes[b][1] + axes[a][2] * axes[b][2];
            if dot.abs() > 1e-3 {
                return Err(err(file, line, "the space directions are not perpendicular (a sheared grid); resample the volume onto a rectilinear grid"));
            }
        }
        if have_spacing {
            h.notes.push("both spacings and space directions are given; the space directions' lengths are used".into());
        }
        h.placement.axes = axes;
    } else if !have_spacing {
        h.notes.push("the NRRD header gives no spacing; 1 mm voxels are assumed".into());
    }
    h.placement.origin_mm = origin;
    if flip {
        // RAS → LPS (DICOM patient coordinates): x and y change sign.
        for v in h.placement.axes.iter_mut().chain(std::iter::once(&mut h.placement.origin_mm)) {
            v[0] = -v[0];
            v[1] = -v[1];
        }
    }
    h.voxels = h
        .sizes
        .iter()
        .try_fold(1usize, |a, &d| a.checked_mul(d))
        .filter(|v| v.checked_mul(8).is_some())
        .ok_or_else(|| err(file, h.sizes_line, "sizes multiply to more voxels than any memory holds"))?;
    Ok(h)
}

/// `(end of header text, start of data)` at the first empty line.
fn find_blank_line(b: &[u8]) -> Option<(usize, usize)> {
    let mut i = 0;
    while let Some(p) = b[i..].iter().position(|&c| c == b'\n') {
        let nl = i + p;
        let next = nl + 1;
        if b.get(next) == Some(&b'\n') {
            return Some((nl, next + 1));
        }
        if b.get(next..next + 2) == Some(b"\r\n") {
            return Some((nl, next + 2));
        }
        i = next;
    }
    None
}

/// The header file (`.nrrd` / `.nhdr`) among `files`; other files than it and its data file
/// are reported as skipped.
fn header_file<'a>(files: &[(&'a str, &'a [u8])]) -> Result<(&'a str, &'a [u8]), Error> {
    let headers: Vec<_> = files.iter().filter(|(n, _)| matches!(extension(n).as_str(), "nrrd" | "nhdr")).collect();
    match headers.as_slice() {
        [one] => Ok(**one),
        _ => Err(Error::NotAVolume {
            file: clean(headers.first().map_or("", |h| h.0)),
            why: format!("{} NRRD headers were given; drop one volume at a time", headers.len()),
        }),
    }
}

/// The detached data file among `files`, by base name.
fn data_file<'a>(h: &Header, name: &str, files: &[(&'a str, &'a [u8])]) -> Result<(&'a str, &'a [u8]), Error> {
    let want = base_name(name);
    files.iter().find(|(n, _)| base_name(n) == want).or_else(|| files.iter().find(|(n, _)| base_name(n).eq_ignore_ascii_case(want))).copied().ok_or_else(|| {
        err(&h.file, 0, format!("the data file \"{}\" the header names is not among the files given; drop it together with the header", clean(want)))
    })
}

pub(crate) fn scan(files: &[(&str, &[u8])]) -> Result<Scan, Error> {
    let (name, bytes) = header_file(files)?;
    let h = parse_header(name, bytes)?;
    let inflated = if h.encoding == Encoding::Gzip { (h.voxels * h.voxel.size()) as u64 } else { 0 };
    Ok(Scan { voxels: h.voxels as u64, inflated, files: 1 + h.data_file.is_some() as usize })
}

pub(crate) fn read(files: &[(&str, &[u8])]) -> Result<Imported, Error> {
    let (name, bytes) = header_file(files)?;
    let h = parse_header(name, bytes)?;
    let (data_name, mut data) = match &h.data_file {
        Some(d) => data_file(&h, d, files)?,
        None => (name, &bytes[h.data_start.min(bytes.len())..]),
    };
    for _ in 0..h.line_skip {
        match data.iter().position(|&b| b == b'\n') {
            Some(p) => data = &data[p + 1..],
            None => return Err(err(&h.file, 0, format!("{}: fewer lines than line skip {}", clean(data_name), h.line_skip))),
        }
    }
    let need = h.voxels * h.voxel.size();
    let size_err = |found: usize| Error::SizeMismatch {
        file: clean(data_name),
        expected: format!("the NRRD sizes {}×{}×{} of {} need {need} bytes", h.sizes[0], h.sizes[1], h.sizes[2], h.voxel.name()),
        found: format!("the data hold {found} bytes"),
    };
    let inflated;
    let samples: &[u8] = match h.encoding {
        Encoding::Raw => {
            let skip = if h.byte_skip == -1 { data.len().saturating_sub(need) } else { h.byte_skip as usize };
            let d = data.get(skip..).unwrap_or_default();
            if d.len() != need {
                return Err(size_err(d.len()));
            }
            d
        }
        Encoding::Gzip => {
            let skip = h.byte_skip as u64;
            let mut out = Vec::with_capacity(need);
            let mut dec = flate2::read::MultiGzDecoder::new(data).take(skip + need as u64 + 1);
            std::io::copy(&mut (&mut dec).take(skip), &mut std::io::sink())
                .and_then(|_| dec.read_to_end(&mut out))
                .map_err(|_| err(&h.file, 0, format!("{}: the gzip data are damaged or cut short; save the volume again", clean(data_name))))?;
            if out.len() != need {
                return Err(size_err(out.len()));
            }
            inflated = out;
            &inflated
        }
    };
    let mut values = vec![0f32; h.voxels];
    convert(samples, h.voxel, h.big_endian, 1.0, 0.0, &mut values);
    let files_read = 1 + h.data_file.is_some() as usize;
    let skipped = files
        .iter()
        .filter(|(n, _)| *n != name && (h.data_file.is_none() || *n != data_name))
        .map(|(n, _)| format!("{}: not used by the NRRD header", clean(n)))
        .collect();
    let volume = Volume {
        dims: h.sizes,
        spacing_mm: h.spacing,
        values,
        placement: h.placement,
        info: VolumeInfo { format: "NRRD".into(), files: files_read, ..Default::default() },
    };
    let report = ImportReport { format: "NRRD".into(), files_read, skipped, slice_gap_mm: h.spacing[2], notes: h.notes, ..Default::default() };
    Ok(Imported { volume, report })
}

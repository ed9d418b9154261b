//! DICOM series, zips and a CT bone phantom for the volume import tests.
//!
//! The files are written by hand (a few dozen lines of element encoding) rather than with a
//! DICOM library: weft does not depend on one (see `volume::dicom`), and writing the bytes
//! ourselves lets the tests cover each transfer syntax exactly: Implicit VR LE, Explicit VR
//! LE, Explicit VR BE (tags, lengths and 16-bit pixels big-endian) and Deflated Explicit VR
//! LE (the data set after the meta group raw-deflated).
//!
//! Each file is a CT Image Storage instance: preamble, `DICM`, File Meta (group 0002,
//! Explicit VR LE, with its group length), then the data set in ascending tag order with
//! SOP class/instance, Modality `CT`, Slice Thickness, study/series UIDs, Instance Number,
//! Image Position / Orientation (Patient), the image pixel module (Rows = `dims[1]`, Columns
//! = `dims[0]`, Pixel Spacing = `spacing[1]\spacing[0]`, 16 bits allocated), Rescale
//! Intercept / Slope / Type `HU`, and the pixel data (OW).

use crate::volume::{Placement, Volume, VolumeInfo};
use std::io::{Cursor, Write};

/// Transfer syntax of the files written.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Syntax {
    /// Implicit VR Little Endian (1.2.840.10008.1.2).
    ImplicitLe,
    /// Explicit VR Little Endian (1.2.840.10008.1.2.1).
    #[default]
    ExplicitLe,
    /// Explicit VR Big Endian (1.2.840.10008.1.2.2, retired but still met).
    ExplicitBe,
    /// Deflated Explicit VR Little Endian (1.2.840.10008.1.2.1.99).
    DeflatedLe,
}

impl Syntax {
    /// The transfer syntax UID.
    pub fn uid(self) -> &'static str {
        match self {
            Syntax::ImplicitLe => "1.2.840.10008.1.2",
            Syntax::ExplicitLe => "1.2.840.10008.1.2.1",
            Syntax::ExplicitBe => "1.2.840.10008.1.2.2",
            Syntax::DeflatedLe => "1.2.840.10008.1.2.1.99",
        }
    }
}

/// Default Study Instance UID of [`SeriesOptions`].
pub const DEFAULT_STUDY_UID: &str = "1.2.826.0.1.3680043.10.1141.1";
/// Default Series Instance UID of [`SeriesOptions`].
pub const DEFAULT_SERIES_UID: &str = "1.2.826.0.1.3680043.10.1141.1.2";

/// How [`write_series`] encodes a volume.
#[derive(Clone, Debug, PartialEq)]
pub struct SeriesOptions {
    /// Transfer syntax. Default Explicit VR LE.
    pub syntax: Syntax,
    /// Study Instance UID. Default [`DEFAULT_STUDY_UID`].
    pub study_uid: String,
    /// Series Instance UID. Default [`DEFAULT_SERIES_UID`].
    pub series_uid: String,
    /// Rescale Slope: stored = round((value − intercept) / slope). Default 1.
    pub slope: f64,
    /// Rescale Intercept. Default −1024 (the usual for unsigned CT).
    pub intercept: f64,
    /// Signed 16-bit samples (Pixel Representation 1) instead of unsigned. Default false.
    pub signed: bool,
    /// Slice Thickness written, mm; `None` (the default) writes the gap (`spacing_mm[2]`).
    pub thickness_mm: Option<f64>,
    /// Bits Stored (≤ 16; High Bit = Bits Stored − 1). Below 16 the unused high bits of each
    /// sample are filled with junk (`0b1010…`), which a reader must mask away. Default 16.
    pub bits_stored: u16,
}

impl Default for SeriesOptions {
    fn default() -> Self {
        SeriesOptions {
            syntax: Syntax::ExplicitLe,
            study_uid: DEFAULT_STUDY_UID.into(),
            series_uid: DEFAULT_SERIES_UID.into(),
            slope: 1.0,
            intercept: -1024.0,
            signed: false,
            thickness_mm: None,
            bits_stored: 16,
        }
    }
}

/// The stored sample [`write_series`] writes for `value` (before the junk high bits):
/// `round((value − intercept) / slope)` clamped to the sample range.
pub fn stored_sample(value: f32, options: &SeriesOptions) -> i64 {
    let bits = options.bits_stored.clamp(1, 16) as u32;
    let (lo, hi) = if options.signed { (-(1i64 << (bits - 1)), (1i64 << (bits - 1)) - 1) } else { (0, (1i64 << bits) - 1) };
    let s = libm::round((value as f64 - options.intercept) / options.slope);
    (s as i64).clamp(lo, hi)
}

/// The value a reader should get back for `value`: `stored_sample · slope + intercept`.
pub fn read_back(value: f32, options: &SeriesOptions) -> f32 {
    (stored_sample(value, options) as f64 * options.slope + options.intercept) as f32
}

/// Element writer.
struct W {
    out: Vec<u8>,
    explicit: bool,
    big: bool,
}

impl W {
    fn u16(&mut self, v: u16) {
        self.out.extend_from_slice(&if self.big { v.to_be_bytes() } else { v.to_le_bytes() });
    }
    fn u32(&mut self, v: u32) {
        self.out.extend_from_slice(&if self.big { v.to_be_bytes() } else { v.to_le_bytes() });
    }
    /// One element; `value` is padded to even length with `pad`.
    fn elem(&mut self, tag: u32, vr: &[u8; 2], value: &[u8], pad: u8) {
        let len = value.len() + value.len() % 2;
        self.u16((tag >> 16) as u16);
        self.u16(tag as u16);
        if self.explicit {
            self.out.extend_from_slice(vr);
            if matches!(vr, b"OB" | b"OW" | b"SQ" | b"UN" | b"UT") {
                self.out.extend_from_slice(&[0, 0]);
                self.u32(len as u32);
            } else {
                self.u16(len as u16);
            }
        } else {
            self.u32(len as u32);
        }
        self.out.extend_from_slice(value);
        if value.len() % 2 == 1 {
            self.out.push(pad);
        }
    }
    fn text(&mut self, tag: u32, vr: &[u8; 2], s: &str) {
        self.elem(tag, vr, s.as_bytes(), if vr == b"UI" { 0 } else { b' ' });
    }
    fn us(&mut self, tag: u32, v: u16) {
        let b = if self.big { v.to_be_bytes() } else { v.to_le_bytes() };
        self.elem(tag, b"US", &b, 0);
    }
}

/// A decimal string of at most 16 characters (DICOM's DS limit).
pub fn ds(v: f64) -> String {
    let s = format!("{v}");
    if s.len() <= 16 {
        return s;
    }
    for prec in (0..=15).rev() {
        let s = format!("{v:.prec$}");
        let s = if s.contains('.') { s.trim_end_matches('0').trim_end_matches('.').to_string() } else { s };
        if s.len() <= 16 {
            return s;
        }
    }
    format!("{v:.0}")
}

fn ds_list(v: &[f64]) -> String {
    v.iter().map(|x| ds(*x)).collect::<Vec<_>>().join("\\")
}

/// Writes `volume` as one file per k-slice (`slice-0000.dcm`, …): slice k at
/// `origin + k·spacing_mm[2]·axes[2]`, rows along `axes[0]`, columns down `axes[1]` (so the
/// reader's normal `axes[0] × axes[1]` must be `axes[2]` for the slices to come back in
/// order). Values are stored as [`stored_sample`] gives.
pub fn write_series(volume: &Volume, options: &SeriesOptions) -> Vec<(String, Vec<u8>)> {
    let [nx, ny, nz] = volume.dims;
    let p = &volume.placement;
    let gap = volume.spacing_mm[2];
    let mut files = Vec::with_capacity(nz);
    let sop_class = "1.2.840.10008.5.1.4.1.1.2";
    for k in 0..nz {
        let sop_instance = format!("{}.{}", options.series_uid, k + 1);
        let pos: Vec<f64> = (0..3).map(|a| p.origin_mm[a] + k as f64 * gap * p.axes[2][a]).collect();
        let big = options.syntax == Syntax::ExplicitBe;
        let mut d = W { out: Vec::new(), explicit: options.syntax != Syntax::ImplicitLe, big };
        d.text(0x0008_0016, b"UI", sop_class);
        d.text(0x0008_0018, b"UI", &sop_instance);
        d.text(0x0008_0060, b"CS", "CT");
        d.text(0x0018_0050, b"DS", &ds(options.thickness_mm.unwrap_or(gap)));
        d.text(0x0020_000D, b"UI", &options.study_uid);
        d.text(0x0020_000E, b"UI", &options.series_uid);
        d.text(0x0020_0013, b"IS", &(k + 1).to_string());
        d.text(0x0020_0032, b"DS", &ds_list(&pos));
        d.text(0x0020_0037, b"DS", &ds_list(&[p.axes[0][0], p.axes[0][1], p.axes[0][2], p.axes[1][0], p.axes[1][1], p.axes[1][2]]));
        d.us(0x0028_0002, 1);
        d.text(0x0028_0004, b"CS", "MONOCHROME2");
        d.us(0x0028_0010, ny as u16);
        d.us(0x0028_0011, nx as u16);
        d.text(0x0028_0030, b"DS", &ds_list(&[volume.spacing_mm[1], volume.spacing_mm[0]]));
        let bits = options.bits_stored.clamp(1, 16);
        d.us(0x0028_0100, 16);
        d.us(0x0028_0101, bits);
        d.us(0x0028_0102, bits - 1);
        d.us(0x0028_0103, options.signed as u16);
        d.text(0x0028_1052, b"DS", &ds(options.intercept));
        d.text(0x0028_1053, b"DS", &ds(options.slope));
        d.text(0x0028_1054, b"LO", "HU");
        let mask: u16 = if bits == 16 { 0xFFFF } else { (1u16 << bits) - 1 };
        let mut px = Vec::with_capacity(nx * ny * 2);
        for j in 0..ny {
            for i in 0..nx {
                let s = stored_sample(volume.at(i, j, k), options) as u16;
                let s = (s & mask) | (0xAAAA & !mask);
                px.extend_from_slice(&if big { s.to_be_bytes() } else { s.to_le_bytes() });
            }
        }
        d.elem(0x7FE0_0010, b"OW", &px, 0);
        let dataset = if options.syntax == Syntax::DeflatedLe { deflate(&d.out) } else { d.out };
        let mut out = meta(sop_class, &sop_instance, options.syntax.uid());
        out.extend_from_slice(&dataset);
        files.push((format!("slice-{k:04}.dcm"), out));
    }
    files
}

/// Preamble, `DICM` and the File Meta group (Explicit VR LE, with its group length).
pub fn meta(sop_class: &str, sop_instance: &str, syntax_uid: &str) -> Vec<u8> {
    let mut m = W { out: Vec::new(), explicit: true, big: false };
    m.elem(0x0002_0001, b"OB", &[0, 1], 0);
    m.text(0x0002_0002, b"UI", sop_class);
    m.text(0x0002_0003, b"UI", sop_instance);
    m.text(0x0002_0010, b"UI", syntax_uid);
    m.text(0x0002_0012, b"UI", "1.2.826.0.1.3680043.10.1141");
    let mut out = vec![0u8; 128];
    out.extend_from_slice(b"DICM");
    let mut g = W { out, explicit: true, big: false };
    g.elem(0x0002_0000, b"UL", &(m.out.len() as u32).to_le_bytes(), 0);
    g.out.extend_from_slice(&m.out);
    g.out
}

fn deflate(bytes: &[u8]) -> Vec<u8> {
    let mut e = flate2::write::DeflateEncoder::new(Vec::new(), flate2::Compression::default());
    // Writing into a Vec cannot fail.
    let _ = e.write_all(bytes);
    e.finish().unwrap_or_default()
}

/// A deflated zip of `files` (names kept).
pub fn zip_files(files: &[(String, Vec<u8>)]) -> Vec<u8> {
    let mut w = zip::ZipWriter::new(Cursor::new(Vec::new()));
    let opts = zip::write::SimpleFileOptions::default().compression_method(zip::CompressionMethod::Deflated).last_modified_time(zip::DateTime::default());
    for (name, body) in files {
        // Writing into a Vec cannot fail.
        let _ = w.start_file(name.as_str(), opts);
        let _ = w.write_all(body);
    }
    w.finish().map(|c| c.into_inner()).unwrap_or_default()
}

/// The HU of [`bone_phantom`] at voxel `(i, j, k)` of a grid of `dims` and `spacing_mm`.
///
/// With `W = min((nx−1)·sx, (ny−1)·sy)` (the smaller in-plane extent), `r` the distance of
/// the voxel centre from the axis through the middle of the i–j plane (along k), and
/// `t = k / (nz − 1)` (0 when `nz = 1`), the height fraction:
/// - `r > 0.45·W`: air, −1000;
/// - `0.25·W < r ≤ 0.45·W`: soft tissue, 40;
/// - cortical shell, `R_i < r ≤ 0.25·W` with `R_i = 0.25·W − W·(0.04 + 0.04·sin(π·t))`
///   (thicker at mid-height): `1200 + 300·sin(π·t)`;
/// - medullary canal, `r ≤ 0.10·W` while `0.3 ≤ t ≤ 0.7`: 0;
/// - trabecular core (the rest, `r ≤ R_i`): `150 + 350·max(r / R_i, |2t − 1|)`, graded
///   from 150 at the axis at mid-height to 500 next to the shell and at the ends;
///
/// rounded to a whole HU (`libm::round`), so a slope-1 DICOM stores it exactly.
pub fn bone_phantom_hu(dims: [usize; 3], spacing_mm: [f64; 3], i: usize, j: usize, k: usize) -> f32 {
    let w = ((dims[0].saturating_sub(1)) as f64 * spacing_mm[0]).min((dims[1].saturating_sub(1)) as f64 * spacing_mm[1]);
    let cx = (dims[0].saturating_sub(1)) as f64 * spacing_mm[0] / 2.0;
    let cy = (dims[1].saturating_sub(1)) as f64 * spacing_mm[1] / 2.0;
    let (x, y) = (i as f64 * spacing_mm[0] - cx, j as f64 * spacing_mm[1] - cy);
    let r = (x * x + y * y).sqrt();
    let t = if dims[2] > 1 { k as f64 / (dims[2] - 1) as f64 } else { 0.0 };
    let s = libm::sin(std::f64::consts::PI * t);
    let r_o = 0.25 * w;
    let r_i = r_o - w * (0.04 + 0.04 * s);
    let hu = if r > 0.45 * w {
        -1000.0
    } else if r > r_o {
        40.0
    } else if r > r_i {
        1200.0 + 300.0 * s
    } else if r <= 0.10 * w && (0.3..=0.7).contains(&t) {
        0.0
    } else {
        150.0 + 350.0 * (r / r_i).max((2.0 * t - 1.0).abs())
    };
    libm::round(hu) as f32
}

/// A deterministic CT phantom in HU (see [`bone_phantom_hu`] for the exact formula): air
/// around a soft-tissue cylinder holding a bone along k (cortical shell, graded trabecular
/// core, a medullary canal over the middle 40 % of the length). Placement: identity at the
/// origin; info: CT in HU.
pub fn bone_phantom(dims: [usize; 3], spacing_mm: [f64; 3]) -> Volume {
    let mut values = Vec::with_capacity(dims[0] * dims[1] * dims[2]);
    for k in 0..dims[2] {
        for j in 0..dims[1] {
            for i in 0..dims[0] {
                values.push(bone_phantom_hu(dims, spacing_mm, i, j, k));
            }
        }
    }
    Volume {
        dims,
        spacing_mm,
        values,
        placement: Placement::default(),
        info: VolumeInfo { format: "phantom".into(), modality: "CT".into(), unit: "HU".into(), ..Default::default() },
    }
}

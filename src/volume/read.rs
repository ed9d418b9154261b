//! Volume import: the entry [`read_volume`], format dispatch, options, errors and the
//! header-only [`estimate`].
//!
//! Dispatch, from names and content (never from paths: names only label files and match a
//! detached NRRD's data file among the files given):
//! - one `.zip` (or one file starting `PK\3\4`): its entries become the file list
//!   ([`super::zip`]: counts and sizes bounded before inflating);
//! - a `.nrrd` / `.nhdr` header among the files: NRRD ([`super::nrrd`]);
//! - one `.raw`: raw voxels laid out by [`Options::raw`] ([`super::raw`]);
//! - anything else: a DICOM series ([`super::dicom`]); non-DICOM files and DICOMDIR in a
//!   multi-file drop are skipped and listed in [`ImportReport::skipped`].
//!
//! Bounded: [`estimate`] scans headers only (a zip's entries are inflated only up to
//! [`HEAD_BYTES`] each) and states the voxels and the peak memory; [`read_volume`] runs the
//! same scan first and refuses over [`MAX_VOXELS`] or the stage memory budget before the
//! volume (or a zip's contents) is allocated.

use super::{dicom, nrrd, raw, zip, Volume};
use crate::budget::{Estimate, OverBudget};
use crate::settings::{num, other, vec3, Field, Kind as FieldKind};
use serde::{Deserialize, Serialize};

/// Most voxels a volume may have: 512³ = 134,217,728 (a full 512×512 CT series of 512
/// slices). Values are kept as `f32`, so the volume alone is 512 MiB; with the input bytes
/// (16-bit samples: 256 MiB more) the import peaks at about 0.75 GiB, within the 1.25 GiB a
/// stage may use of the browser worker's ~2 GB ([`crate::budget::MAX_STAGE_BYTES`]) and
/// leaving room for the stages that follow. Crop the series (or resample it) to go bigger.
pub const MAX_VOXELS: usize = 512 * 512 * 512;

/// Most files in a series (and most entries in a zip): 4096 slices is more than any CT
/// series of the body region a scaffold comes from (0.5 mm slices over 2 m); each file costs
/// a parsed header, so the bound keeps the header scan small.
pub const MAX_FILES: usize = 4096;

/// Most bytes a zip may inflate to (all entries, as the archive declares them and as they
/// really inflate): 1 GiB. Larger is refused before inflating (a zip bomb or a series too
/// big to import anyway: [`MAX_VOXELS`] of 16-bit samples is 256 MiB).
pub const MAX_UNZIPPED_BYTES: u64 = 1 << 30;

/// Most bytes of a volume's files together (one file, or all the files of a series): the
/// largest volume weft reads ([`MAX_VOXELS`] of 8-byte samples) is 1 GiB, and 256 MiB more
/// leaves room for headers and zip records. A front end checks each file's size, and a
/// series' total, with [`check_input_bytes`] before it reads or hashes any of it.
pub const MAX_INPUT_BYTES: u64 = MAX_VOXELS as u64 * 8 + (256 << 20);

/// Refuses volume input of `bytes` bytes over [`MAX_INPUT_BYTES`] (`file`: the file, or the
/// series, named in the message), before any of it is read.
pub fn check_input_bytes(file: &str, bytes: u64) -> Result<(), Error> {
    if bytes <= MAX_INPUT_BYTES {
        return Ok(());
    }
    Err(Error::TooMuchInput { file: file.to_string(), mib: bytes >> 20 })
}

/// Bytes of each zip entry (or of a deflated DICOM data set) inflated by the header scan of
/// [`estimate`]: headers sit before the pixel data and are a few KiB.
pub const HEAD_BYTES: usize = 64 << 10;

/// Default raw voxel spacing, mm.
pub const DEFAULT_RAW_SPACING_MM: f64 = 1.0;
/// Default raw rescale slope (value = stored · slope + intercept).
pub const DEFAULT_RAW_SLOPE: f64 = 1.0;
/// Default raw rescale intercept, in the volume's unit (HU for CT).
pub const DEFAULT_RAW_INTERCEPT: f64 = 0.0;

/// Sample type of raw (and NRRD) voxels.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum VoxelType {
    /// Unsigned 8-bit.
    U8,
    /// Signed 8-bit.
    I8,
    /// Unsigned 16-bit.
    U16,
    /// Signed 16-bit (the usual CT export; the default).
    #[default]
    I16,
    /// Unsigned 32-bit.
    U32,
    /// Signed 32-bit.
    I32,
    /// IEEE 32-bit float.
    F32,
    /// IEEE 64-bit float.
    F64,
}

impl VoxelType {
    /// Bytes per sample.
    pub fn size(self) -> usize {
        match self {
            VoxelType::U8 | VoxelType::I8 => 1,
            VoxelType::U16 | VoxelType::I16 => 2,
            VoxelType::U32 | VoxelType::I32 | VoxelType::F32 => 4,
            VoxelType::F64 => 8,
        }
    }

    /// The name used in options (`u8`, `i16`, …).
    pub fn name(self) -> &'static str {
        match self {
            VoxelType::U8 => "u8",
            VoxelType::I8 => "i8",
            VoxelType::U16 => "u16",
            VoxelType::I16 => "i16",
            VoxelType::U32 => "u32",
            VoxelType::I32 => "i32",
            VoxelType::F32 => "f32",
            VoxelType::F64 => "f64",
        }
    }
}

/// How a headerless `.raw` file is laid out (a raw file says nothing about itself).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RawLayout {
    /// Voxels along i (fastest), j, k. `[0, 0, 0]` (the default) = unset: a `.raw` is refused.
    pub dims: [usize; 3],
    /// Voxel spacing along i, j, k, mm. Default [`DEFAULT_RAW_SPACING_MM`] each.
    pub spacing_mm: [f64; 3],
    /// Sample type. Default `i16`.
    pub voxel: VoxelType,
    /// Samples are big-endian (default little-endian).
    pub big_endian: bool,
    /// value = stored · slope + intercept. Default [`DEFAULT_RAW_SLOPE`].
    pub slope: f64,
    /// Default [`DEFAULT_RAW_INTERCEPT`].
    pub intercept: f64,
}

impl Default for RawLayout {
    fn default() -> Self {
        RawLayout {
            dims: [0; 3],
            spacing_mm: [DEFAULT_RAW_SPACING_MM; 3],
            voxel: VoxelType::default(),
            big_endian: false,
            slope: DEFAULT_RAW_SLOPE,
            intercept: DEFAULT_RAW_INTERCEPT,
        }
    }
}

/// Volume import options.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Options {
    /// Layout of a `.raw` file (unused for DICOM and NRRD, which describe themselves).
    pub raw: RawLayout,
}

/// What the importer read.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct ImportReport {
    /// `DICOM`, `NRRD`, `raw` (with ` in zip` when the files came from a zip).
    pub format: String,
    /// Files read into the volume (DICOM: one per slice; NRRD: header and data file).
    pub files_read: usize,
    /// Files given but not used, as `name: reason` (DICOMDIR, non-DICOM files, zip metadata).
    pub skipped: Vec<String>,
    /// Smallest value after rescale.
    pub min: f32,
    /// Largest value after rescale.
    pub max: f32,
    /// Spacing along k as measured (DICOM: the mean gap between sorted slice positions), mm.
    pub slice_gap_mm: f64,
    /// Things worth knowing that did not stop the import (DICOM Slice Thickness ≠ gap).
    pub notes: Vec<String>,
}

/// A volume and what happened while reading it.
#[derive(Clone, Debug)]
pub struct Imported {
    /// The volume.
    pub volume: Volume,
    /// What was read.
    pub report: ImportReport,
}

/// Why a volume could not be read. Every message names the file and says what to do.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum Error {
    /// Nothing was given.
    #[error("no files were given; drop a DICOM series (its files or a .zip of its folder), a .nrrd/.nhdr or a .raw")]
    NoFiles,
    /// A file ends before what its header promises.
    #[error("{file}: the file is cut short ({detail}); copy or export it again")]
    Truncated {
        /// File name.
        file: String,
        /// What was cut.
        detail: String,
    },
    /// A DICOM image without pixel data.
    #[error("{file}: the DICOM file has no pixel data (7FE0,0010); export the series again with its images")]
    NoPixelData {
        /// File name.
        file: String,
    },
    /// A slice (or a data block) whose size differs from the others (or from its header).
    #[error("{file}: {found}, but {expected}; drop only the files of one series")]
    SizeMismatch {
        /// File name.
        file: String,
        /// What the others (or the header) have.
        expected: String,
        /// What this file has.
        found: String,
    },
    /// A slice with a different pixel spacing.
    #[error("{file}: Pixel Spacing is {found}, but {expected} in the other slices; drop only the files of one series")]
    SpacingMismatch {
        /// File name.
        file: String,
        /// The first slice's spacing (row\column, mm).
        expected: String,
        /// This file's.
        found: String,
    },
    /// A slice with a different orientation.
    #[error("{file_b}: Image Orientation (Patient) differs from {file_a}'s; drop only the files of one series (a localizer or a reformat may be mixed in)")]
    OrientationMismatch {
        /// First file.
        file_a: String,
        /// The file that differs.
        file_b: String,
    },
    /// Gaps between sorted slice positions that are not all equal.
    #[error("the gap between {file_a} and {file_b} is {gap_mm:.4} mm, but the other slices are {expected_mm:.4} mm apart; a slice may be missing, or two series are mixed")]
    UnevenSlices {
        /// Slice before the gap.
        file_a: String,
        /// Slice after the gap.
        file_b: String,
        /// The gap, mm.
        gap_mm: f64,
        /// The usual (median) gap, mm.
        expected_mm: f64,
    },
    /// Two slices at the same position.
    #[error("{file_a} and {file_b} are both at position ({:.3}, {:.3}, {:.3}) mm; a slice is duplicated or two series are mixed: drop only one series, each slice once", position[0], position[1], position[2])]
    DuplicatePosition {
        /// First file.
        file_a: String,
        /// Second file.
        file_b: String,
        /// Image Position (Patient), mm.
        position: [f64; 3],
    },
    /// Files of different studies or series.
    #[error("{file_a} and {file_b} belong to different {what}; drop the files of one series only")]
    MixedSeries {
        /// `studies` or `series`.
        what: &'static str,
        /// First file.
        file_a: String,
        /// A file of another study/series.
        file_b: String,
    },
    /// Pixel data in a compressed transfer syntax weft does not decode.
    #[error("{file}: the pixel data is compressed ({syntax_name}), which weft does not decode; convert the series to uncompressed DICOM (e.g. `gdcmconv --raw` or `dcmdjpeg`)")]
    Compressed {
        /// File name.
        file: String,
        /// Transfer syntax name.
        syntax_name: String,
    },
    /// Something weft does not read (colour images, float pixel data, multi-frame…).
    #[error("{file}: {what}")]
    Unsupported {
        /// File name.
        file: String,
        /// What, and what to do.
        what: String,
    },
    /// Not a volume: no readable image, or a single 2D slice.
    #[error("{file}: {why}")]
    NotAVolume {
        /// File name.
        file: String,
        /// Why, and what to drop instead.
        why: String,
    },
    /// A DICOM file that is damaged.
    #[error("{file}: the DICOM file is damaged: {message}; copy or export it again")]
    Dicom {
        /// File name.
        file: String,
        /// What is wrong, where.
        message: String,
    },
    /// Files over [`MAX_INPUT_BYTES`] together; refused before they are read.
    #[error("{file}: {} MiB is more than the {} MiB of files a volume is read from ({} voxels of 8-byte samples, with headers); crop or resample the series, or export it with 16-bit samples", crate::import::group(*mib), crate::import::group(MAX_INPUT_BYTES >> 20), crate::import::group(MAX_VOXELS as u64))]
    TooMuchInput {
        /// The file, or the series.
        file: String,
        /// Its size, MiB.
        mib: u64,
    },
    /// Over [`MAX_VOXELS`], [`MAX_FILES`] or the memory budget; refused before allocating.
    #[error("the volume is too big: {0}")]
    TooBig(OverBudget),
    /// A zip that cannot be read (or is a likely zip bomb).
    #[error("{file}: {message}")]
    Zip {
        /// File name.
        file: String,
        /// What is wrong and what to do.
        message: String,
    },
    /// An NRRD header that cannot be read.
    #[error("{file} line {line}: {message}")]
    Nrrd {
        /// Header file name.
        file: String,
        /// Line of the header (1-based; 0 = the data).
        line: usize,
        /// What is wrong and what to do.
        message: String,
    },
    /// A raw file that does not match [`Options::raw`].
    #[error("{file}: {message}")]
    Raw {
        /// File name.
        file: String,
        /// What is wrong and which option to set.
        message: String,
    },
}

/// A file's lower-case extension.
pub(crate) fn extension(name: &str) -> String {
    let base = base_name(name);
    match base.rsplit_once('.') {
        Some((_, e)) => e.to_ascii_lowercase(),
        None => String::new(),
    }
}

/// The part of a name after its last `/` or `\` (zip entries and browser drops carry folders).
pub(crate) fn base_name(name: &str) -> &str {
    name.rsplit(['/', '\\']).next().unwrap_or(name)
}

/// A name or string from a file, for messages and reports (bounded, no control characters).
pub(crate) fn clean(s: &str) -> String {
    crate::import::clean(s)
}

/// What the header scan found, before any volume memory is allocated.
#[derive(Clone, Debug, Default)]
pub(crate) struct Scan {
    /// Voxels of the volume (upper bound).
    pub voxels: u64,
    /// Bytes inflated and held (zip entries, deflated data).
    pub inflated: u64,
    /// Files that will be read.
    pub files: usize,
}

/// Seconds per voxel converted (measured order: parse + convert + min/max), and per byte
/// inflated, on the reference machine.
const SECONDS_PER_VOXEL: f64 = 4e-9;
const SECONDS_PER_INFLATED_BYTE: f64 = 4e-9;

/// The estimate of reading `files`: stage `volume`, quantities `voxels`, `files`,
/// `input_bytes`, `inflated_bytes`; peak bytes = input + inflated + 4 bytes per voxel (the
/// `f32` values). Refused over [`MAX_VOXELS`], [`MAX_FILES`] or the stage budgets. Cheap:
/// headers only (a zip's entries inflated up to [`HEAD_BYTES`] each). Inputs that cannot be
/// scanned get an estimate of their input bytes only; [`read_volume`] then says what is
/// wrong.
pub fn estimate(files: &[(&str, &[u8])], options: &Options) -> Estimate {
    let input: u64 = files.iter().map(|(_, b)| b.len() as u64).sum();
    let scan = scan(files, options, true).unwrap_or_default();
    build_estimate(files.len(), input, &scan)
}

fn build_estimate(n_files: usize, input: u64, scan: &Scan) -> Estimate {
    let voxels = scan.voxels as f64;
    let bytes = input as f64 + scan.inflated as f64 + 4.0 * voxels + (1 << 20) as f64;
    let seconds = voxels * SECONDS_PER_VOXEL + scan.inflated as f64 * SECONDS_PER_INFLATED_BYTE;
    Estimate::new("volume")
        .quantity("voxels", "voxels in the volume", voxels, "")
        .quantity("files", "files read", scan.files.max(n_files) as f64, "")
        .quantity("input_bytes", "bytes given", input as f64, "bytes")
        .quantity("inflated_bytes", "bytes unpacked (zip, deflate)", scan.inflated as f64, "bytes")
        .cost(bytes, seconds)
        .limit("files", n_files.max(scan.files) as f64, MAX_FILES as f64, "", "drop one series (at most 4096 slices)")
        .limit("voxels", voxels, MAX_VOXELS as f64, "", "crop or resample the series (e.g. every second slice, or a smaller field of view)")
        .budgets("crop or resample the series")
}

/// The header scan shared by [`estimate`] and [`read_volume`]: dispatch, counts, no volume.
/// `for_estimate` lets a zip's entries be inflated only up to [`HEAD_BYTES`].
pub(crate) fn scan(files: &[(&str, &[u8])], options: &Options, for_estimate: bool) -> Result<Scan, Error> {
    if files.is_empty() {
        return Err(Error::NoFiles);
    }
    if let Some((name, bytes)) = single_zip(files) {
        let entries = zip::list(name, bytes)?;
        let heads = zip::inflate(name, bytes, &entries, if for_estimate { Some(HEAD_BYTES) } else { None })?;
        let refs: Vec<(&str, &[u8])> = heads.iter().map(|(n, b)| (n.as_str(), b.as_slice())).collect();
        let total: u64 = entries.iter().map(|e| e.size).sum();
        let mut s = scan_files(&refs, options, for_estimate)?;
        s.inflated = s.inflated.saturating_add(total);
        return Ok(s);
    }
    scan_files(files, options, for_estimate)
}

fn scan_files(files: &[(&str, &[u8])], options: &Options, partial: bool) -> Result<Scan, Error> {
    match kind(files) {
        Kind::Nrrd => nrrd::scan(files),
        Kind::Raw => raw::scan(files, &options.raw),
        Kind::Dicom => dicom::scan(files, partial),
    }
}

enum Kind {
    Nrrd,
    Raw,
    Dicom,
}

fn kind(files: &[(&str, &[u8])]) -> Kind {
    if files.iter().any(|(n, _)| matches!(extension(n).as_str(), "nrrd" | "nhdr")) {
        Kind::Nrrd
    } else if files.len() == 1 && extension(files[0].0) == "raw" {
        Kind::Raw
    } else {
        Kind::Dicom
    }
}

fn single_zip<'a>(files: &[(&'a str, &'a [u8])]) -> Option<(&'a str, &'a [u8])> {
    match files {
        [(name, bytes)] if extension(name) == "zip" || bytes.starts_with(b"PK\x03\x04") => Some((name, bytes)),
        _ => None,
    }
}

/// Reads a volume from `files` (name, bytes): a DICOM series (its files, or one `.zip`), an
/// NRRD (`.nrrd`, or `.nhdr` with its data file among `files`), or one `.raw` laid out by
/// [`Options::raw`]. See the module doc for the dispatch.
///
/// Runs the header scan of [`estimate`] first and returns [`Error::TooBig`] over
/// [`MAX_VOXELS`], [`MAX_FILES`] or the memory budget before allocating the volume.
pub fn read_volume(files: &[(&str, &[u8])], options: &Options) -> Result<Imported, Error> {
    if files.is_empty() {
        return Err(Error::NoFiles);
    }
    if files.len() > MAX_FILES {
        let e = build_estimate(files.len(), 0, &Scan::default());
        return Err(Error::TooBig(e.check().err().unwrap_or_else(|| over_files(files.len()))));
    }
    let input: u64 = files.iter().map(|(_, b)| b.len() as u64).sum();
    if let Some((name, bytes)) = single_zip(files) {
        let entries = zip::list(name, bytes)?;
        // The heads first: the voxel count and the budget are checked before the whole
        // archive is inflated.
        let heads = zip::inflate(name, bytes, &entries, Some(HEAD_BYTES))?;
        let refs: Vec<(&str, &[u8])> = heads.iter().map(|(n, b)| (n.as_str(), b.as_slice())).collect();
        if let Ok(mut s) = scan_files(&refs, options, true) {
            s.inflated = s.inflated.saturating_add(entries.iter().map(|e| e.size).sum());
            build_estimate(1, input, &s).check().map_err(Error::TooBig)?;
        }
        drop(heads);
        let inflated = zip::inflate(name, bytes, &entries, None)?;
        let refs: Vec<(&str, &[u8])> = inflated.iter().map(|(n, b)| (n.as_str(), b.as_slice())).collect();
        let input = input.saturating_add(entries.iter().map(|e| e.size).sum());
        let mut imported = read_files(&refs, options, input)?;
        imported.report.format.push_str(" in zip");
        let mut skipped = zip::skipped(bytes);
        skipped.append(&mut imported.report.skipped);
        imported.report.skipped = skipped;
        return Ok(imported);
    }
    read_files(files, options, input)
}

fn over_files(n: usize) -> OverBudget {
    OverBudget { what: "files".into(), value: n as f64, limit: MAX_FILES as f64, unit: "", fix: "drop one series".into() }
}

fn read_files(files: &[(&str, &[u8])], options: &Options, input: u64) -> Result<Imported, Error> {
    let s = scan_files(files, options, false)?;
    build_estimate(files.len(), input, &s).check().map_err(Error::TooBig)?;
    let mut imported = match kind(files) {
        Kind::Nrrd => nrrd::read(files)?,
        Kind::Raw => raw::read(files, &options.raw)?,
        Kind::Dicom => dicom::read(files)?,
    };
    finish(files[0].0, &mut imported)?;
    Ok(imported)
}

/// Fills min/max and refuses values that are not finite (a float volume with NaN masks).
fn finish(file: &str, imported: &mut Imported) -> Result<(), Error> {
    let v = &imported.volume;
    let (mut lo, mut hi, mut bad) = (f32::INFINITY, f32::NEG_INFINITY, 0usize);
    for &x in &v.values {
        if x.is_finite() {
            lo = lo.min(x);
            hi = hi.max(x);
        } else {
            bad += 1;
        }
    }
    if bad > 0 {
        return Err(Error::Unsupported {
            file: clean(file),
            what: format!(
                "{bad} voxels are not finite numbers (NaN or infinite) after rescaling; replace them (e.g. by the background value) before importing"
            ),
        });
    }
    imported.report.min = if lo.is_finite() { lo } else { 0.0 };
    imported.report.max = if hi.is_finite() { hi } else { 0.0 };
    imported.report.slice_gap_mm = if imported.report.slice_gap_mm > 0.0 { imported.report.slice_gap_mm } else { v.spacing_mm[2] };
    Ok(())
}

/// Form rows of [`RawLayout`] (paths relative to it): how to read `.raw` voxels.
pub const RAW_FIELDS: &[Field] = &[
    vec3("dims", "Raw volume", "Voxels", "", 0.0, 100000.0, 1.0, "A .raw file's size in voxels along i, j, k (0 0 0 when no .raw file is used)."),
    vec3("spacing_mm", "Raw volume", "Voxel size", "mm", 0.0, 1000.0, 0.001, "A .raw file's voxel spacing along i, j, k."),
    other(
        "voxel",
        "Raw volume",
        "Voxel type",
        FieldKind::Choice,
        &["u8", "i8", "u16", "i16", "u32", "i32", "f32", "f64"],
        "How each voxel of a .raw file is stored.",
    ),
    other("big_endian", "Raw volume", "Big-endian", FieldKind::Bool, &[], "The .raw file stores the most significant byte first."),
    num("slope", "Raw volume", "Rescale slope", "", -1e9, 1e9, 0.001, "Value = stored × slope + intercept (1 and 0 keep the stored values)."),
    num("intercept", "Raw volume", "Rescale intercept", "", -1e9, 1e9, 1.0, "Added after the slope (e.g. −1024 for CT stored as unsigned)."),
];

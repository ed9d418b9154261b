//! Volumes: a 3D scalar field on a regular grid (a CT series in Hounsfield units, an MRI, any
//! scalar volume), read from DICOM series (many files or a `.zip`), NRRD, or raw voxels.
//!
//! Entry: [`read_volume`]. The grid is kept in its own frame, the **volume frame**: voxel
//! `(i, j, k)`'s centre is at `(i·sx, j·sy, k·sz)` mm (`i` along a row = DICOM columns, `j`
//! down the rows, `k` across slices, sorted by position along the slice normal). Where the
//! volume sits in the scanner ([`Placement`]: the first voxel's position and the three axis
//! directions, from Image Position / Orientation (Patient)) is kept for reports and
//! round trips; the job works in the volume frame.

mod dicom;
mod nrrd;
mod raw;
mod read;
mod zip;

pub use dicom::{DUPLICATE_MM, GAP_TOLERANCE, MAX_DEPTH};
pub use nrrd::MAX_HEADER_BYTES;
pub use read::*;

/// The files of a zip archive (`file` names it in messages), bounded as a series' zip is
/// (entry count, total unpacked bytes, each entry's declared size), sorted by name, with
/// folders, macOS metadata and dot-files left out: for a slot that takes several files (a
/// foam's region meshes) as one archive.
pub fn unzip(file: &str, bytes: &[u8]) -> Result<Vec<(String, Vec<u8>)>, Error> {
    let entries = zip::list(file, bytes)?;
    let mut files = zip::inflate(file, bytes, &entries, None)?;
    files.sort_by(|a, b| a.0.cmp(&b.0));
    Ok(files)
}

use crate::geom::DVec3;
use serde::Serialize;

/// Where a volume sits in patient (scanner) coordinates, mm.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Placement {
    /// Centre of the first voxel transmitted (DICOM Image Position (Patient) of the first slice).
    pub origin_mm: [f64; 3],
    /// Unit direction of increasing `i` (along a row), then `j` (down a column), then `k`
    /// (slice to slice).
    pub axes: [[f64; 3]; 3],
}

impl Default for Placement {
    fn default() -> Self {
        Placement { origin_mm: [0.0; 3], axes: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]] }
    }
}

/// Facts about where a volume came from (shown in reports; strings already cleaned).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct VolumeInfo {
    /// `DICOM`, `NRRD`, `raw`.
    pub format: String,
    /// Files read (DICOM: one per slice).
    pub files: usize,
    /// DICOM transfer syntax name (`Explicit VR Little Endian`), empty otherwise.
    pub transfer_syntax: String,
    /// DICOM Modality (`CT`, `MR`), empty when unknown.
    pub modality: String,
    /// Unit of the values after rescaling: `HU` for CT Rescale Type HU (or CT without a type),
    /// otherwise the Rescale Type or empty.
    pub unit: String,
    /// DICOM Study Instance UID, empty when absent.
    pub study_uid: String,
    /// DICOM Series Instance UID, empty when absent.
    pub series_uid: String,
}

/// A scalar volume on a regular grid.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Volume {
    /// Voxels along i, j, k.
    pub dims: [usize; 3],
    /// Voxel spacing along i, j, k, mm (all > 0).
    pub spacing_mm: [f64; 3],
    /// Values after rescale (HU for CT), `i` fastest then `j` then `k`: index `i + nx·(j + ny·k)`.
    pub values: Vec<f32>,
    /// Where it sits in the scanner.
    pub placement: Placement,
    /// Where it came from.
    pub info: VolumeInfo,
}

impl Volume {
    /// Number of voxels.
    pub fn len(&self) -> usize {
        self.dims[0] * self.dims[1] * self.dims[2]
    }

    /// No voxels.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Index of voxel `(i, j, k)` in [`Volume::values`].
    #[inline]
    pub fn index(&self, i: usize, j: usize, k: usize) -> usize {
        i + self.dims[0] * (j + self.dims[1] * k)
    }

    /// Value of voxel `(i, j, k)`.
    #[inline]
    pub fn at(&self, i: usize, j: usize, k: usize) -> f32 {
        self.values[self.index(i, j, k)]
    }

    /// Extent of the grid in the volume frame: first to last voxel centre, mm.
    pub fn extent_mm(&self) -> DVec3 {
        DVec3::new(
            self.dims[0].saturating_sub(1) as f64 * self.spacing_mm[0],
            self.dims[1].saturating_sub(1) as f64 * self.spacing_mm[1],
            self.dims[2].saturating_sub(1) as f64 * self.spacing_mm[2],
        )
    }

    /// Patient coordinates (mm) of a point given in the volume frame (mm).
    pub fn to_patient(&self, p: DVec3) -> DVec3 {
        let o = DVec3::from(self.placement.origin_mm);
        let [a, b, c] = self.placement.axes.map(DVec3::from);
        o + a * p.x + b * p.y + c * p.z
    }
}

/// A region of interest: a box in the volume frame, mm (voxel centres inside it, faces
/// included, are in the region).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Roi {
    /// Smallest corner, mm.
    pub min_mm: [f64; 3],
    /// Largest corner, mm.
    pub max_mm: [f64; 3],
}

impl Roi {
    /// The whole grid of `volume`.
    pub fn whole(volume: &Volume) -> Roi {
        Roi { min_mm: [0.0; 3], max_mm: volume.extent_mm().to_array() }
    }

    /// The voxel index ranges `[start, end)` along i, j, k of the voxel centres inside the box,
    /// `None` when none is (or the box is not finite).
    pub fn voxels(&self, volume: &Volume) -> Option<[std::ops::Range<usize>; 3]> {
        let mut out = [0..0, 0..0, 0..0];
        for a in 0..3 {
            let (lo, hi, s, n) = (self.min_mm[a], self.max_mm[a], volume.spacing_mm[a], volume.dims[a]);
            if !(lo.is_finite() && hi.is_finite() && s > 0.0) || n == 0 || hi < lo {
                return None;
            }
            let start = libm::ceil(lo / s - 1e-9).max(0.0);
            let end = (libm::floor(hi / s + 1e-9) + 1.0).min(n as f64);
            if !(end > start) {
                return None;
            }
            out[a] = start as usize..end as usize;
        }
        Some(out)
    }
}

mod histogram;
mod isolines;
mod sample;
mod view;
pub use histogram::*;
pub use isolines::*;
pub use sample::*;
pub use view::*;

//! Headerless raw voxels (`.raw`), laid out by [`RawLayout`], and the sample conversion
//! shared with NRRD: each sample is decoded from its bytes (type and endianness) and
//! rescaled (`stored · slope + intercept`, in `f64`, then stored as `f32`).

use super::read::{clean, Error, ImportReport, Imported, RawLayout, Scan, VoxelType};
use super::{Placement, Volume, VolumeInfo};

/// Decodes `out.len()` samples of `voxel` from `bytes` (which hold at least that many) and
/// rescales them.
pub(crate) fn convert(bytes: &[u8], voxel: VoxelType, big_endian: bool, slope: f64, intercept: f64, out: &mut [f32]) {
    let size = voxel.size();
    for (o, c) in out.iter_mut().zip(bytes.chunks_exact(size)) {
        let mut b = [0u8; 8];
        b[..size].copy_from_slice(c);
        if big_endian {
            b[..size].reverse();
        }
        let v = match voxel {
            VoxelType::U8 => b[0] as f64,
            VoxelType::I8 => b[0] as i8 as f64,
            VoxelType::U16 => u16::from_le_bytes([b[0], b[1]]) as f64,
            VoxelType::I16 => i16::from_le_bytes([b[0], b[1]]) as f64,
            VoxelType::U32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            VoxelType::I32 => i32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            VoxelType::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            VoxelType::F64 => f64::from_le_bytes(b),
        };
        *o = (v * slope + intercept) as f32;
    }
}

fn raw_err(file: &str, message: String) -> Error {
    Error::Raw { file: clean(file), message }
}

const FIELDS: &str = "set the raw layout: raw.dims [nx, ny, nz] (voxels; x fastest), raw.voxel (u8, i8, u16, i16, u32, i32, f32, f64), raw.big_endian, raw.spacing_mm [sx, sy, sz]";

/// Checks the layout against the file; returns the voxel count.
fn check(file: &str, len: usize, l: &RawLayout) -> Result<usize, Error> {
    if l.dims.contains(&0) {
        return Err(raw_err(file, format!("a raw file has no header, so its layout must be given ({} bytes here); {FIELDS}", len)));
    }
    if !l.spacing_mm.iter().all(|s| s.is_finite() && *s > 0.0) {
        return Err(raw_err(file, "raw.spacing_mm must be three positive sizes in mm".into()));
    }
    if !(l.slope.is_finite() && l.intercept.is_finite() && l.slope != 0.0) {
        return Err(raw_err(file, "raw.slope must be a non-zero number and raw.intercept a number".into()));
    }
    let voxels = l.dims.iter().try_fold(1usize, |a, &d| a.checked_mul(d));
    let need = voxels.and_then(|v| v.checked_mul(l.voxel.size()));
    match (voxels, need) {
        (Some(v), Some(n)) if n == len => Ok(v),
        _ => Err(raw_err(
            file,
            format!(
                "the file holds {len} bytes, but raw.dims {}×{}×{} of {} ({} bytes each) need {}; {FIELDS}",
                l.dims[0],
                l.dims[1],
                l.dims[2],
                l.voxel.name(),
                l.voxel.size(),
                need.map_or("more than memory holds".to_string(), |n| n.to_string())
            ),
        )),
    }
}

pub(crate) fn scan(files: &[(&str, &[u8])], layout: &RawLayout) -> Result<Scan, Error> {
    let (name, bytes) = files[0];
    let voxels = check(name, bytes.len(), layout)?;
    Ok(Scan { voxels: voxels as u64, inflated: 0, files: 1 })
}

pub(crate) fn read(files: &[(&str, &[u8])], layout: &RawLayout) -> Result<Imported, Error> {
    let (name, bytes) = files[0];
    let voxels = check(name, bytes.len(), layout)?;
    let mut values = vec![0f32; voxels];
    convert(bytes, layout.voxel, layout.big_endian, layout.slope, layout.intercept, &mut values);
    let volume = Volume {
        dims: layout.dims,
        spacing_mm: layout.spacing_mm,
        values,
        placement: Placement::default(),
        info: VolumeInfo { format: "raw".into(), files: 1, ..Default::default() },
    };
    let report = ImportReport { format: "raw".into(), files_read: 1, slice_gap_mm: layout.spacing_mm[2], ..Default::default() };
    Ok(Imported { volume, report })
}

//! Orthogonal slices of a volume as 2D images (the viewer's axial, coronal and sagittal panes).
//!
//! A slice fixes one voxel index and copies the voxels of that plane row by row. Axes follow
//! the volume frame (`i`, `j`, `k`; see [`super`]): axial fixes `k` (image x = `i`, y = `j`),
//! coronal fixes `j` (x = `i`, y = `k`), sagittal fixes `i` (x = `j`, y = `k`). The names are
//! the usual ones for an axial CT series (slices across the body); for other acquisitions they
//! are just the three grid planes. Row 0 of the image is y index 0: no flip is applied, the
//! viewer decides how to draw it.

use super::Volume;
use serde::{Deserialize, Serialize};

/// Which grid plane a slice image shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Axis {
    /// `k` fixed; image x = `i`, y = `j`.
    Axial,
    /// `j` fixed; image x = `i`, y = `k`.
    Coronal,
    /// `i` fixed; image x = `j`, y = `k`.
    Sagittal,
}

impl Axis {
    /// The volume-frame axes (0 = i, 1 = j, 2 = k) of image x, image y and the fixed index.
    pub fn axes(self) -> [usize; 3] {
        match self {
            Axis::Axial => [0, 1, 2],
            Axis::Coronal => [0, 2, 1],
            Axis::Sagittal => [1, 2, 0],
        }
    }
}

/// One slice of a volume as an image.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SliceImage {
    /// Plane shown.
    pub axis: Axis,
    /// Index of the slice along the fixed axis (after clamping).
    pub index: usize,
    /// Slices along the fixed axis.
    pub count: usize,
    /// Pixels per row.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Pixel size along image x and image y, mm (the voxel spacing along those axes).
    pub pixel_mm: [f64; 2],
    /// Position of the slice along the fixed axis, volume frame, mm (`index · spacing`).
    pub position_mm: f64,
    /// Values row by row, `width × height`, row 0 = y index 0.
    pub values: Vec<f32>,
}

impl SliceImage {
    /// Value at column `x`, row `y` (panics out of range, like slice indexing).
    #[inline]
    pub fn at(&self, x: usize, y: usize) -> f32 {
        self.values[x + self.width * y]
    }
}

/// The slice `index` (clamped to `count − 1`) of `volume` along `axis`. An empty volume (or one
/// whose values do not match its dims) gives a 0×0 image.
pub fn slice_image(volume: &Volume, axis: Axis, index: usize) -> SliceImage {
    let [ax, ay, af] = axis.axes();
    let count = volume.dims[af];
    let s = volume.spacing_mm;
    if volume.is_empty() || volume.values.len() < volume.len() {
        return SliceImage { axis, index: 0, count, width: 0, height: 0, pixel_mm: [s[ax], s[ay]], position_mm: 0.0, values: Vec::new() };
    }
    let index = index.min(count - 1);
    let (width, height) = (volume.dims[ax], volume.dims[ay]);
    // At most the volume's own size: no budget check needed beyond the volume's.
    let mut values = Vec::with_capacity(width * height);
    let mut ijk = [0usize; 3];
    ijk[af] = index;
    for y in 0..height {
        ijk[ay] = y;
        for x in 0..width {
            ijk[ax] = x;
            values.push(volume.at(ijk[0], ijk[1], ijk[2]));
        }
    }
    SliceImage { axis, index, count, width, height, pixel_mm: [s[ax], s[ay]], position_mm: index as f64 * s[af], values }
}

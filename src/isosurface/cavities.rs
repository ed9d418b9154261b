//! Cavity fill: empty voxels that cannot reach the outside of the region of interest through
//! empty voxels are made solid.
//!
//! A flood fill (6-connectivity: face neighbours, the connectivity the mesher's face rule
//! gives the empty side) from every empty voxel on the ROI's boundary layer marks what is
//! outside; every empty voxel left is in a cavity. Each cavity is then flood-filled once
//! more, to count it and make it solid. Both fills use one explicit stack of voxel indices
//! (a voxel is pushed once at most, so it never holds more than the ROI's voxels) and no
//! recursion, so a long thin cavity cannot overflow the call stack.

use super::marching_cubes::SOLID;

/// Marks empty voxels reached from outside.
const OUTSIDE: u8 = 2;
/// Marks the padding while filling, so the flood never enters it: a voxel's six neighbours are
/// then plain index offsets, with no coordinates to compute or bounds to check.
const PAD: u8 = 3;

/// What [`fill`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(super) struct Filled {
    /// Cavities (connected components of enclosed empty voxels) filled.
    pub cavities: usize,
    /// Voxels made solid.
    pub voxels: usize,
}

/// Fills the cavities of the padded grid `cells` (`m` points per axis, `i` fastest, the
/// outer layer is padding and stays empty). `open[2·axis + side]`: the ROI face (−x, +x, −y,
/// +y, −z, +z) counts as outside; empty voxels reaching only closed faces are filled too.
/// Voxels left empty are marked [`OUTSIDE`] (not [`SOLID`], which is all the mesher asks).
pub(super) fn fill(cells: &mut [u8], m: [usize; 3], open: [bool; 6]) -> Filled {
    let stride = [1, m[0], m[0] * m[1]];
    // Every voxel of the layer `layer` across `axis`, by index.
    let layer = |axis: usize, layer: usize| {
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        (0..m[v]).flat_map(move |b| (0..m[u]).map(move |a| layer * stride[axis] + a * stride[u] + b * stride[v]))
    };
    for (axis, &len) in m.iter().enumerate() {
        for l in [0, len - 1] {
            layer(axis, l).for_each(|idx| cells[idx] = PAD);
        }
    }
    let mut stack: Vec<u32> = Vec::new();
    // Seed: empty voxels in the boundary layer of an open face.
    for axis in 0..3 {
        for side in 0..2 {
            if open[2 * axis + side] && m[axis] > 2 {
                for idx in layer(axis, if side == 0 { 1 } else { m[axis] - 2 }) {
                    if cells[idx] == 0 {
                        cells[idx] = OUTSIDE;
                        stack.push(idx as u32);
                    }
                }
            }
        }
    }
    flood(cells, stride, &mut stack, OUTSIDE);
    let mut filled = Filled::default();
    for idx in 0..cells.len() {
        if cells[idx] == 0 {
            cells[idx] = SOLID;
            stack.push(idx as u32);
            filled.cavities += 1;
            filled.voxels += 1 + flood(cells, stride, &mut stack, SOLID);
        }
    }
    for (axis, &len) in m.iter().enumerate() {
        for l in [0, len - 1] {
            layer(axis, l).for_each(|idx| cells[idx] = 0);
        }
    }
    filled
}

/// Spreads `mark` from the voxels on `stack` to every face-connected voxel still 0 (the
/// padding is not 0, so the flood stays inside); returns how many it marked.
fn flood(cells: &mut [u8], steps: [usize; 3], stack: &mut Vec<u32>, mark: u8) -> usize {
    let mut marked = 0;
    while let Some(idx) = stack.pop() {
        let idx = idx as usize;
        for n in [idx - steps[0], idx + steps[0], idx - steps[1], idx + steps[1], idx - steps[2], idx + steps[2]] {
            if cells[n] == 0 {
                cells[n] = mark;
                marked += 1;
                stack.push(n as u32);
            }
        }
    }
    marked
}

/// Fills the holes of each slice across k (z) of the padded grid `cells`: empty voxels that
/// cannot reach the slice's outer ring through empty voxels of the same slice (4-connectivity).
/// This closes a medullary canal that runs out through the ROI's end faces (a tunnel in 3D,
/// so [`fill`] leaves it), as the paper closes it before slicing. Each hole region of a slice
/// counts as one cavity.
pub(super) fn fill_slice_holes(cells: &mut [u8], m: [usize; 3]) -> Filled {
    let (nx, ny) = (m[0], m[1]);
    let plane = nx * ny;
    let mut reached = vec![false; plane];
    let mut stack: Vec<u32> = Vec::new();
    let mut filled = Filled::default();
    for z in 1..m[2].saturating_sub(1) {
        let layer = &mut cells[z * plane..(z + 1) * plane];
        reached.iter_mut().for_each(|r| *r = false);
        // The outer ring is padding, empty by construction: everything empty it reaches is
        // outside.
        let ring = (0..nx).chain(plane - nx..plane).chain((0..ny).map(|j| j * nx)).chain((0..ny).map(|j| j * nx + nx - 1));
        for idx in ring {
            if !reached[idx] && layer[idx] != SOLID {
                reached[idx] = true;
                stack.push(idx as u32);
            }
        }
        flood_plane(layer, nx, &mut reached, &mut stack, false);
        for idx in 0..plane {
            if !reached[idx] && layer[idx] != SOLID {
                reached[idx] = true;
                stack.push(idx as u32);
                filled.cavities += 1;
                filled.voxels += flood_plane(layer, nx, &mut reached, &mut stack, true);
            }
        }
    }
    filled
}

/// Spreads through the empty voxels of one slice (4-connectivity) from `stack`, marking
/// `reached`; with `make_solid`, each voxel reached becomes [`SOLID`]. Returns how many.
fn flood_plane(layer: &mut [u8], nx: usize, reached: &mut [bool], stack: &mut Vec<u32>, make_solid: bool) -> usize {
    let n = layer.len();
    let mut count = 0;
    while let Some(idx) = stack.pop() {
        let idx = idx as usize;
        count += 1;
        let (i, j) = (idx % nx, idx / nx);
        let neighbours = [(i > 0).then(|| idx - 1), (i + 1 < nx).then(|| idx + 1), (j > 0).then(|| idx - nx), (idx + nx < n).then(|| idx + nx)];
        for k in neighbours.into_iter().flatten() {
            if !reached[k] && layer[k] != SOLID {
                reached[k] = true;
                stack.push(k as u32);
            }
        }
        if make_solid {
            layer[idx] = SOLID;
        }
    }
    count
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_enclosed_voxel_is_filled_and_an_open_one_is_not() {
        // 5×5×5 ROI (7³ padded): a solid 3³ shell around the centre voxel.
        let m = [7, 7, 7];
        let mut cells = vec![0u8; 343];
        let at = |i: usize, j: usize, k: usize| k * 49 + j * 7 + i;
        for k in 2..=4 {
            for j in 2..=4 {
                for i in 2..=4 {
                    if (i, j, k) != (3, 3, 3) {
                        cells[at(i, j, k)] = SOLID;
                    }
                }
            }
        }
        let mut closed_z = cells.clone();
        let f = fill(&mut cells, m, [true; 6]);
        assert_eq!(f, Filled { cavities: 1, voxels: 1 });
        assert_eq!(cells[at(3, 3, 3)], SOLID);
        assert_eq!(cells[at(1, 1, 1)], OUTSIDE);
        // With every face closed, the whole empty region is one "cavity".
        let f = fill(&mut closed_z, m, [false; 6]);
        assert_eq!(f, Filled { cavities: 2, voxels: 125 - 26 });
    }
}

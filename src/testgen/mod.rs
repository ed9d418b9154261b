//! Generators of large and hostile inputs, shared by the tests (which reproduce each hostile
//! case at a size that shows its growth) and `weft bench --scaling` (1×, 4×, 16× inputs).
//! Nothing here is committed as a big file: every input is made from a size parameter `n`,
//! and the bytes made grow linearly in `n`.

pub mod design;
pub mod dicom;
pub mod foreign;
pub mod gcode;
pub mod lattice;
pub mod mesh;

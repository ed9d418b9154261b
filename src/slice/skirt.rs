//! Skirt and brim of the first layer ([`super::Options::skirt_loops`],
//! [`super::Options::brim_width_mm`]): loops around the part's first-layer outline, printed
//! before it. The brim is `brim_width_mm / line width` loops touching the part (its first loop's
//! inner edge on the part's outline), printed from the outside in so the last one joins the
//! part; the skirt is `skirt_loops` loops `skirt_distance_mm` beyond the part and its brim
//! (the gap between the edges), printed from the outside in, to prime the nozzle. Only outer
//! outlines get loops (not a part's holes). Offsets are i_overlay's integer ones, so the loops
//! are the same bytes everywhere.

use super::perimeters::outset;
use i_overlay::i_shape::int::shape::IntShapes;

/// Most brim loops (a 50 mm brim of 0.1 mm lines).
pub const MAX_BRIM_LOOPS: usize = 500;

/// The skirt's and the brim's loops around `first` (the first layer's regions, µm), each a
/// closed outline in µm, in print order: skirt loops outermost first, then brim loops
/// outermost first.
pub(crate) fn loops(
    first: &IntShapes<i32>,
    skirt_loops: u32,
    skirt_distance_um: i32,
    brim_um: i32,
    w_um: i32,
) -> Vec<Vec<i_overlay::i_float::int::point::IntPoint<i32>>> {
    if first.is_empty() || w_um <= 0 {
        return Vec::new();
    }
    let outer = |d: i64| -> Vec<Vec<i_overlay::i_float::int::point::IntPoint<i32>>> {
        outset(first, d.clamp(1, i32::MAX as i64) as i32).into_iter().filter_map(|s| s.into_iter().next()).collect()
    };
    let w = w_um as i64;
    let brim_loops = ((brim_um.max(0) as i64 + w / 2) / w).min(MAX_BRIM_LOOPS as i64);
    let brim_edge = brim_loops * w;
    let mut out = Vec::new();
    for k in (0..skirt_loops as i64).rev() {
        out.extend(outer(brim_edge + skirt_distance_um.max(0) as i64 + w / 2 + k * w));
    }
    for k in (0..brim_loops).rev() {
        out.extend(outer(w / 2 + k * w));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use i_overlay::i_float::int::point::IntPoint;

    fn square(s: i32) -> IntShapes<i32> {
        vec![vec![vec![IntPoint::new(-s, -s), IntPoint::new(s, -s), IntPoint::new(s, s), IntPoint::new(-s, s)]]]
    }

    fn half_side(l: &[IntPoint<i32>]) -> i32 {
        l.iter().map(|p| p.x).max().unwrap()
    }

    #[test]
    fn a_skirt_at_its_distance_and_a_brim_touching_the_part() {
        // A 20 mm square, 0.4 mm lines: one skirt loop 3 mm out (centre 3.2 mm), no brim.
        let l = loops(&square(10_000), 1, 3_000, 0, 400);
        assert_eq!(l.iter().map(|l| half_side(l)).collect::<Vec<_>>(), [13_200]);
        // A 2 mm brim is 5 loops from 10.2 to 11.8 mm, printed outside in; two skirt loops 3 mm
        // beyond the brim's edge (12 mm), outside in.
        let l = loops(&square(10_000), 2, 3_000, 2_000, 400);
        assert_eq!(l.iter().map(|l| half_side(l)).collect::<Vec<_>>(), [15_600, 15_200, 11_800, 11_400, 11_000, 10_600, 10_200]);
        assert!(loops(&Vec::new(), 1, 3_000, 0, 400).is_empty());
        assert!(loops(&square(10_000), 0, 3_000, 0, 400).is_empty());
    }

    #[test]
    fn parts_close_together_share_one_skirt() {
        let mut two = square(5_000);
        two.extend(square(5_000).into_iter().map(|s| s.into_iter().map(|c| c.into_iter().map(|p| IntPoint::new(p.x + 12_000, p.y)).collect()).collect()));
        // 2 mm apart: one skirt loop 3 mm out goes round both.
        assert_eq!(loops(&two, 1, 3_000, 0, 400).len(), 1);
    }
}

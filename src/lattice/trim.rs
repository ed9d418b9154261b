//! Trimming struts out of the beads of printed loops (contours, handle outlines).
//!
//! The G-code analyzer counts as overlap any extrusion lying on an earlier one of the same
//! layer: nearly parallel (≤ 10°) and within half a line width laterally. A strut cropped at a
//! contour it meets nearly tangentially runs inside the contour's bead for part of its length
//! (in either print order). So each strut piece loses the part lying within half a line width
//! (plus [`MARGIN_UM`]) of any guarded edge that makes an angle ≤ [`MAX_ANGLE_DEG`] with it:
//! the part inside the edge's capsule (the band along it and the discs at its ends). Removing
//! it leaves no point of the strut within reach of the edge's line over the edge, nor any
//! point of the edge within reach of the strut's line over the strut. Pieces crossing an edge
//! more steeply are left alone (they still end exactly on it).
//!
//! All in integer-micrometre units (edges on the µm grid, as the loops are printed); only IEEE
//! arithmetic and `sqrt`, so identical on every platform.

use crate::geom::tolerance::UNITS_PER_MM;
use crate::geom::DVec2;

/// Largest angle between a strut and a guarded edge for which the strut is trimmed, degrees
/// (the analyzer's limit is 10°).
pub const MAX_ANGLE_DEG: f64 = 12.0;
/// sin([`MAX_ANGLE_DEG`]).
const SIN_MAX_ANGLE: f64 = 0.207_911_690_817_759_34;
/// Extra clearance beyond half a line width, µm (covers rounding of the printed points).
pub const MARGIN_UM: f64 = 1.0;

#[inline]
fn cross(a: DVec2, b: DVec2) -> f64 {
    a.x * b.y - a.y * b.x
}

/// Edges of printed loops, in µm, bucketed in horizontal bands; each edge tagged with its
/// loop's index.
pub(crate) struct Guard {
    edges: Vec<[DVec2; 2]>,
    tags: Vec<u32>,
    /// Clearance radius, µm.
    r: f64,
    y0: f64,
    band_h: f64,
    bands: Vec<Vec<u32>>,
}

impl Guard {
    /// Guards the closed `rings` (mm, each on the µm grid, without the closing point repeated;
    /// ring `i` tagged `i`) with clearance `line_width_mm / 2` + [`MARGIN_UM`].
    pub fn new(rings: &[Vec<DVec2>], line_width_mm: f64) -> Guard {
        let (mut edges, mut tags) = (Vec::new(), Vec::new());
        for (tag, ring) in rings.iter().enumerate() {
            if ring.len() < 2 {
                continue;
            }
            for edge in super::crop::ring_edges(ring) {
                edges.push(edge);
                tags.push(tag as u32);
            }
        }
        let r = 0.5 * line_width_mm * UNITS_PER_MM + MARGIN_UM;
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for e in &edges {
            lo = lo.min(e[0].y.min(e[1].y));
            hi = hi.max(e[0].y.max(e[1].y));
        }
        let nb = (edges.len() / 2).clamp(1, 4096);
        let (y0, band_h) = if edges.is_empty() { (0.0, 1.0) } else { (lo - r - 2.0, ((hi - lo + 2.0 * r + 4.0) / nb as f64).max(1.0)) };
        let mut bands = vec![Vec::new(); nb];
        for (k, e) in edges.iter().enumerate() {
            let b0 = Self::band_of(y0, band_h, nb, e[0].y.min(e[1].y) - r - 1.0);
            let b1 = Self::band_of(y0, band_h, nb, e[0].y.max(e[1].y) + r + 1.0);
            for band in &mut bands[b0..=b1] {
                band.push(k as u32);
            }
        }
        Guard { edges, tags, r, y0, band_h, bands }
    }

    /// Whether there is nothing to guard.
    pub fn is_empty(&self) -> bool {
        self.edges.is_empty()
    }

    fn band_of(y0: f64, band_h: f64, nb: usize, y: f64) -> usize {
        let b = libm::floor((y - y0) / band_h);
        if b.is_nan() || b < 0.0 {
            0
        } else {
            (b as usize).min(nb - 1)
        }
    }

    /// The parts of segment `a`–`b` (µm) to keep, as parameter intervals `[t0, t1]` of it in
    /// increasing order (`[0, 1]` when nothing is trimmed; empty when all of it is), against
    /// the edges of the loops tagged below `before`.
    pub fn keep(&self, a: DVec2, b: DVec2, before: u32, out: &mut Vec<(f64, f64)>) {
        out.clear();
        let d = b - a;
        let dl2 = d.length_squared();
        if self.edges.is_empty() || dl2.is_nan() || dl2 <= 0.0 {
            out.push((0.0, 1.0));
            return;
        }
        let r = self.r;
        let (lo, hi) = (a.min(b) - DVec2::splat(r + 1.0), a.max(b) + DVec2::splat(r + 1.0));
        let nb = self.bands.len();
        let b0 = Self::band_of(self.y0, self.band_h, nb, lo.y);
        let b1 = Self::band_of(self.y0, self.band_h, nb, hi.y);
        let mut cand: Vec<u32> = Vec::new();
        for band in &self.bands[b0..=b1] {
            cand.extend_from_slice(band);
        }
        if b1 > b0 {
            cand.sort_unstable();
            cand.dedup();
        }
        let mut cut: Vec<(f64, f64)> = Vec::new();
        for &k in &cand {
            if self.tags[k as usize] >= before {
                continue;
            }
            let [p, q] = self.edges[k as usize];
            let (elo, ehi) = (p.min(q), p.max(q));
            if ehi.x < lo.x || elo.x > hi.x || ehi.y < lo.y || elo.y > hi.y {
                continue;
            }
            let e = q - p;
            let el2 = e.length_squared();
            let c = cross(d, e);
            if c * c > SIN_MAX_ANGLE * SIN_MAX_ANGLE * dl2 * el2 {
                continue;
            }
            if let Some((t0, t1)) = capsule(a, d, dl2, p, e, el2, r) {
                let (t0, t1) = (t0.max(0.0), t1.min(1.0));
                if t1 > t0 {
                    cut.push((t0, t1));
                }
            }
        }
        if cut.is_empty() {
            out.push((0.0, 1.0));
            return;
        }
        cut.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.total_cmp(&y.1)));
        let mut t = 0.0;
        for (c0, c1) in cut {
            if c0 > t {
                out.push((t, c0));
            }
            t = t.max(c1);
        }
        if t < 1.0 {
            out.push((t, 1.0));
        }
    }
}

/// Where `a + t·d` lies within `r` of segment `p`–`p + e` (a convex capsule): `[t0, t1]`
/// over all real `t`, or None.
fn capsule(a: DVec2, d: DVec2, dl2: f64, p: DVec2, e: DVec2, el2: f64, r: f64) -> Option<(f64, f64)> {
    let mut acc: Option<(f64, f64)> = None;
    let mut add = |iv: Option<(f64, f64)>| {
        if let Some((l, h)) = iv {
            acc = Some(match acc {
                Some((al, ah)) => (al.min(l), ah.max(h)),
                None => (l, h),
            });
        }
    };
    // The band: lateral distance within r, projection inside the edge.
    if el2 > 0.0 {
        let el = el2.sqrt();
        let u = e / el;
        let n = DVec2::new(-u.y, u.x);
        let ap = a - p;
        let mut iv = Some((f64::NEG_INFINITY, f64::INFINITY));
        iv = iv.and_then(|iv| slab(iv, ap.dot(n), d.dot(n), -r, r));
        iv = iv.and_then(|iv| slab(iv, ap.dot(u), d.dot(u), 0.0, el));
        add(iv);
    }
    // The end discs.
    for c in [p, p + e] {
        let ac = a - c;
        let bq = d.dot(ac);
        let cq = ac.length_squared() - r * r;
        let disc = bq * bq - dl2 * cq;
        if disc >= 0.0 {
            let s = disc.sqrt();
            add(Some(((-bq - s) / dl2, (-bq + s) / dl2)));
        }
    }
    acc
}

/// Narrows `iv` to where `v0 + t·dv` lies in `[min, max]`.
fn slab(iv: (f64, f64), v0: f64, dv: f64, min: f64, max: f64) -> Option<(f64, f64)> {
    if dv == 0.0 {
        return if v0 >= min && v0 <= max { Some(iv) } else { None };
    }
    let (mut t0, mut t1) = ((min - v0) / dv, (max - v0) / dv);
    if t0 > t1 {
        std::mem::swap(&mut t0, &mut t1);
    }
    let (lo, hi) = (iv.0.max(t0), iv.1.min(t1));
    if hi >= lo {
        Some((lo, hi))
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square5() -> Guard {
        let h = 5.0;
        Guard::new(&[vec![DVec2::new(-h, -h), DVec2::new(h, -h), DVec2::new(h, h), DVec2::new(-h, h)]], 0.2)
    }

    #[test]
    fn sin_max_angle_is_twelve_degrees() {
        assert!((SIN_MAX_ANGLE - libm::sin(MAX_ANGLE_DEG.to_radians())).abs() < 1e-15);
    }

    #[test]
    fn trims_parallel_struts_and_leaves_steep_ones() {
        let g = square5();
        let mut out = Vec::new();
        // Perpendicular to the bottom edge: untouched.
        g.keep(DVec2::new(0.0, -5000.0), DVec2::new(0.0, 0.0), u32::MAX, &mut out);
        assert_eq!(out, vec![(0.0, 1.0)]);
        // Along the bottom edge, 50 µm inside: all of it goes.
        g.keep(DVec2::new(-1000.0, -4950.0), DVec2::new(1000.0, -4950.0), u32::MAX, &mut out);
        assert!(out.is_empty(), "{out:?}");
        // 5° to the bottom edge from it: the first 101 µm / sin 5° go.
        let (s, c) = (libm::sin(5f64.to_radians()), libm::cos(5f64.to_radians()));
        let (a, b) = (DVec2::new(0.0, -5000.0), DVec2::new(3000.0 * c, -5000.0 + 3000.0 * s));
        g.keep(a, b, u32::MAX, &mut out);
        assert_eq!(out.len(), 1);
        let p = a + (b - a) * out[0].0;
        assert!((p.y + 5000.0 - 101.0).abs() < 1e-6, "{p}");
        assert_eq!(out[0].1, 1.0);
        // 20°: untouched.
        let (s, c) = (libm::sin(20f64.to_radians()), libm::cos(20f64.to_radians()));
        g.keep(DVec2::new(0.0, -5000.0), DVec2::new(3000.0 * c, -5000.0 + 3000.0 * s), u32::MAX, &mut out);
        assert_eq!(out, vec![(0.0, 1.0)]);
    }

    #[test]
    fn trims_shallow_pieces_to_the_bead_edge() {
        let g = square5();
        let mut out = Vec::new();
        // Nearly along the edge: all of it goes; rising 300 µm over 4 mm: trimmed to 101 µm off it.
        g.keep(DVec2::new(-4000.0, -5000.0), DVec2::new(4000.0, -5000.0 + 1.0), u32::MAX, &mut out);
        assert!(out.is_empty());
        g.keep(DVec2::new(-2000.0, -5000.0), DVec2::new(2000.0, -4700.0), u32::MAX, &mut out);
        assert_eq!(out.len(), 1);
        assert!(out[0].0 > 0.3 && out[0].0 < 0.4 && out[0].1 == 1.0, "{out:?}");
    }
}

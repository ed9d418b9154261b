//! Cropping segments to regions (polygons with holes) in micrometre units.
//!
//! Region vertices are snapped to the integer micrometre grid; each segment is split at every
//! crossing with a region edge (and at the ends of edges it runs along), and the pieces whose
//! middle is inside, or which run along a region edge (within half a micrometre: boundary
//! counts as inside), are kept. Adjacent kept pieces are merged. Output points are rounded to whole micrometres.

use crate::geom::tolerance::UNITS_PER_MM;
use crate::geom::{DVec2, Polygon};

/// Within this distance (µm) of a region edge a point is on the boundary (inside).
const ON_EDGE_UM: f64 = 0.5;

/// A region set prepared for clipping: its edges in µm, bucketed in horizontal bands.
pub(crate) struct Clipper {
    edges: Vec<[DVec2; 2]>,
    y0: f64,
    band_h: f64,
    bands: Vec<Vec<u32>>,
    min: DVec2,
    max: DVec2,
}

/// Rounds a µm coordinate to the grid and returns mm.
#[inline]
pub(crate) fn snap_mm(p_um: DVec2) -> DVec2 {
    DVec2::new(libm::round(p_um.x) / UNITS_PER_MM, libm::round(p_um.y) / UNITS_PER_MM)
}

/// mm → µm grid point (rounded), as f64.
#[inline]
pub(crate) fn to_um_grid(p: DVec2) -> DVec2 {
    DVec2::new(libm::round(p.x * UNITS_PER_MM), libm::round(p.y * UNITS_PER_MM))
}

#[inline]
fn cross(a: DVec2, b: DVec2) -> f64 {
    a.x * b.y - a.y * b.x
}

fn dist2_to_segment(p: DVec2, a: DVec2, b: DVec2) -> f64 {
    let d = b - a;
    let l2 = d.length_squared();
    let t = if l2 > 0.0 { ((p - a).dot(d) / l2).clamp(0.0, 1.0) } else { 0.0 };
    (a + d * t - p).length_squared()
}

/// The edges of closed `ring` (mm) snapped to the µm grid, zero-length ones skipped.
pub(crate) fn ring_edges(ring: &[DVec2]) -> impl Iterator<Item = [DVec2; 2]> + '_ {
    let n = ring.len();
    (0..n).filter_map(move |i| {
        let (a, b) = (to_um_grid(ring[i]), to_um_grid(ring[(i + 1) % n]));
        (a != b).then_some([a, b])
    })
}

impl Clipper {
    /// Prepares `regions` (mm) for clipping.
    pub fn new(regions: &[Polygon]) -> Clipper {
        let mut edges = Vec::new();
        for poly in regions {
            for ring in std::iter::once(&poly.outer).chain(poly.holes.iter()) {
                if ring.len() >= 3 {
                    edges.extend(ring_edges(ring));
                }
            }
        }
        let all = edges.iter().flat_map(|e| e.iter());
        let (min, max) = match super::graph::Rect::of_points(all) {
            Some(r) => (r.min, r.max),
            None => (DVec2::ZERO, DVec2::ZERO),
        };
        let nb = (edges.len() / 2).clamp(1, 4096);
        let y0 = min.y - 2.0;
        let band_h = ((max.y - min.y + 4.0) / nb as f64).max(1.0);
        let mut bands = vec![Vec::new(); nb];
        for (k, e) in edges.iter().enumerate() {
            let lo = e[0].y.min(e[1].y) - 1.0;
            let hi = e[0].y.max(e[1].y) + 1.0;
            let (b0, b1) = (Self::band_of(y0, band_h, nb, lo), Self::band_of(y0, band_h, nb, hi));
            for band in &mut bands[b0..=b1] {
                band.push(k as u32);
            }
        }
        Clipper { edges, y0, band_h, bands, min, max }
    }

    fn band_of(y0: f64, band_h: f64, nb: usize, y: f64) -> usize {
        let b = libm::floor((y - y0) / band_h);
        if b < 0.0 {
            0
        } else {
            (b as usize).min(nb - 1)
        }
    }

    fn band(&self, y: f64) -> Option<&[u32]> {
        if self.edges.is_empty() || y < self.min.y - 1.0 || y > self.max.y + 1.0 {
            return None;
        }
        Some(&self.bands[Self::band_of(self.y0, self.band_h, self.bands.len(), y)])
    }

    /// Whether `p` (µm) is inside the regions (even-odd; undecided on the boundary).
    pub fn inside(&self, p: DVec2) -> bool {
        let Some(band) = self.band(p.y) else { return false };
        // Edges tested (the growth checks count them).
        crate::work::add(band.len());
        let mut inside = false;
        for &k in band {
            let [a, b] = self.edges[k as usize];
            if (a.y > p.y) != (b.y > p.y) {
                let x = a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x);
                if x > p.x {
                    inside = !inside;
                }
            }
        }
        inside
    }

    /// The parts of segment `a`–`b` (µm) inside the regions, as (start, end) µm pairs
    /// (unrounded), appended to `out`.
    pub fn clip(&self, a: DVec2, b: DVec2, out: &mut Vec<[DVec2; 2]>) {
        if self.edges.is_empty() {
            return;
        }
        let (lo, hi) = (a.min(b), a.max(b));
        if hi.x < self.min.x - 1.0 || lo.x > self.max.x + 1.0 || hi.y < self.min.y - 1.0 || lo.y > self.max.y + 1.0 {
            return;
        }
        let d = b - a;
        let dl2 = d.length_squared();
        if dl2 == 0.0 {
            return;
        }
        let nb = self.bands.len();
        let b0 = Self::band_of(self.y0, self.band_h, nb, lo.y - 1.0);
        let b1 = Self::band_of(self.y0, self.band_h, nb, hi.y + 1.0);
        let mut cand: Vec<u32> = Vec::new();
        for band in &self.bands[b0..=b1] {
            cand.extend_from_slice(band);
        }
        if b1 > b0 {
            cand.sort_unstable();
            cand.dedup();
        }
        crate::work::add(cand.len());
        let mut ts = vec![0.0, 1.0];
        let mut along: Vec<u32> = Vec::new();
        let dl = dl2.sqrt();
        for &k in &cand {
            let [p, q] = self.edges[k as usize];
            let (elo, ehi) = (p.min(q), p.max(q));
            if ehi.x < lo.x - 1.0 || elo.x > hi.x + 1.0 || ehi.y < lo.y - 1.0 || elo.y > hi.y + 1.0 {
                continue;
            }
            let e = q - p;
            let denom = cross(d, e);
            let el = e.length();
            if denom.abs() > 1e-12 * dl * el {
                let ap = p - a;
                let t = cross(ap, e) / denom;
                let u = cross(ap, d) / denom;
                let eps_t = 1e-9;
                let eps_u = 1e-9;
                if t >= -eps_t && t <= 1.0 + eps_t && u >= -eps_u && u <= 1.0 + eps_u {
                    ts.push(t.clamp(0.0, 1.0));
                }
            } else if (cross(d, p - a) / dl).abs() <= ON_EDGE_UM {
                // Running along the edge: split where the edge starts and ends.
                along.push(k);
                for r in [p, q] {
                    let t = (r - a).dot(d) / dl2;
                    if t > 0.0 && t < 1.0 {
                        ts.push(t);
                    }
                }
            }
        }
        ts.sort_by(|x, y| x.total_cmp(y));
        let mut run: Option<(f64, f64)> = None;
        for w in ts.windows(2) {
            let (t0, t1) = (w[0], w[1]);
            if t1 <= t0 {
                continue;
            }
            let mid = a + d * ((t0 + t1) * 0.5);
            let on_edge = along.iter().any(|&k| {
                let [p, q] = self.edges[k as usize];
                dist2_to_segment(mid, p, q) <= ON_EDGE_UM * ON_EDGE_UM
            });
            if on_edge || self.inside(mid) {
                run = Some(match run {
                    Some((s, _)) => (s, t1),
                    None => (t0, t1),
                });
            } else if let Some((s, e)) = run.take() {
                out.push([a + d * s, a + d * e]);
            }
        }
        if let Some((s, e)) = run {
            out.push([a + d * s, a + d * e]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(h: f64) -> Polygon {
        Polygon { outer: vec![DVec2::new(-h, -h), DVec2::new(h, -h), DVec2::new(h, h), DVec2::new(-h, h)], holes: vec![] }
    }

    #[test]
    fn clips_through_a_square_with_a_hole() {
        let mut p = square(5.0);
        p.holes.push(vec![DVec2::new(-1.0, -1.0), DVec2::new(-1.0, 1.0), DVec2::new(1.0, 1.0), DVec2::new(1.0, -1.0)]);
        let c = Clipper::new(&[p]);
        let mut out = Vec::new();
        c.clip(DVec2::new(-8000.0, 0.0), DVec2::new(8000.0, 0.0), &mut out);
        let got: Vec<[DVec2; 2]> = out.iter().map(|s| [snap_mm(s[0]), snap_mm(s[1])]).collect();
        assert_eq!(got, vec![[DVec2::new(-5.0, 0.0), DVec2::new(-1.0, 0.0)], [DVec2::new(1.0, 0.0), DVec2::new(5.0, 0.0)]]);
    }

    #[test]
    fn drops_lines_grazing_a_disc_from_outside() {
        let c = Clipper::new(&[crate::lattice::domain::disc_polygon(10.0)]);
        let mut out = Vec::new();
        // Tangent to the circle (outside the inscribed polygon by 0.05 µm) at 45°.
        let (a, b) = (DVec2::new(-707.107, -14849.242), DVec2::new(14849.242, 707.107));
        c.clip(a, b, &mut out);
        assert!(out.is_empty(), "{out:?}");
    }

    #[test]
    fn keeps_segments_on_the_boundary() {
        let c = Clipper::new(&[square(5.0)]);
        let mut out = Vec::new();
        c.clip(DVec2::new(-6000.0, 5000.0), DVec2::new(6000.0, 5000.0), &mut out);
        assert_eq!(out.len(), 1);
        assert_eq!(snap_mm(out[0][0]), DVec2::new(-5.0, 5.0));
        assert_eq!(snap_mm(out[0][1]), DVec2::new(5.0, 5.0));
        out.clear();
        c.clip(DVec2::new(5000.0, 5000.0), DVec2::new(6000.0, 5000.0), &mut out);
        assert!(out.iter().all(|s| (s[1] - s[0]).length() < 1e-6));
    }
}

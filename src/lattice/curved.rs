//! Curved struts (the GIPPO paper's future work: "spline-based geometries"): every strut of a
//! straight pattern bent into one full sine period across it,
//!
//! `p(t) = a + t·(b − a) + A·sin(2πt)·n`, t ∈ [0, 1], `n` the unit normal (b − a turned +90°),
//!
//! sampled at `samples` equal steps of t (`libm::sin`, so native and wasm agree). One full
//! period keeps the nodes where they were and makes the curve the same whichever way the
//! strut is stored (swapping a and b flips both t and n); every strut leaves every node turned
//! the same way (a pinwheel), so struts meeting at a node do not cross for
//! `A ≤ MAX_AMPLITUDE_FRACTION × strut length`.
//!
//! A curved strut is cropped segment by segment and the kept pieces rejoined into one
//! polyline [`Stroke`] marked `curved` (the path graph keeps it as one edge: one strut).

use super::crop::{self, Clipper};
use super::graph::Graph;
use super::trim::Guard;
use super::MIN_PIECE_MM;
use crate::geom::{DVec2, Feature, Stroke};

/// Largest wave amplitude as a fraction of the strut (chord) length.
pub const MAX_AMPLITUDE_FRACTION: f64 = 0.25;
/// Default wave amplitude, mm.
pub const DEFAULT_AMPLITUDE_MM: f64 = 0.15;
/// Default segments per curved strut.
pub const DEFAULT_SAMPLES_PER_STRUT: u32 = 12;
/// Fewest segments per curved strut (the sine's two extremes and the middle node).
pub const MIN_SAMPLES_PER_STRUT: u32 = 4;
/// Most segments per curved strut.
pub const MAX_SAMPLES_PER_STRUT: u32 = 64;

/// How a pattern's struts are bent.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Curve {
    /// Amplitude, mm.
    pub amplitude: f64,
    /// Segments per strut.
    pub samples: u32,
}

impl Curve {
    /// The strut from `a` to `b` as `samples + 1` points (exactly `a` and `b` at the ends).
    pub fn points(&self, a: DVec2, b: DVec2) -> Vec<DVec2> {
        let d = b - a;
        let len = d.length();
        let n = if len > 0.0 { DVec2::new(-d.y, d.x) / len } else { DVec2::ZERO };
        let k = self.samples.max(1);
        let mut out = Vec::with_capacity(k as usize + 1);
        out.push(a);
        for i in 1..k {
            let t = i as f64 / k as f64;
            let s = libm::sin(2.0 * std::f64::consts::PI * t);
            out.push(a + d * t + n * (self.amplitude * s));
        }
        out.push(b);
        out
    }

    /// Length of the sampled strut, mm.
    pub fn length(&self, a: DVec2, b: DVec2) -> f64 {
        self.points(a, b).windows(2).map(|w| w[0].distance(w[1])).sum()
    }
}

/// [`super::crop_graph`] for a curved pattern: each strut sampled (in the pattern frame, then
/// turned by (cos, sin)), its segments cropped to `clip` and trimmed by `guard`, consecutive
/// kept parts joined into one polyline (µm-rounded points, repeats removed, inner points
/// closer than [`MIN_PIECE_MM`] to the previous one dropped). Pieces shorter than
/// [`MIN_PIECE_MM`] in all are dropped (slivers). Returns (kept length mm, dropped slivers).
pub(crate) fn crop_curved(
    g: &Graph,
    curve: Curve,
    cs: (f64, f64),
    clip: &Clipper,
    guard: Option<&Guard>,
    feature: Feature,
    out: &mut Vec<Stroke>,
) -> (f64, usize) {
    let (c, s) = cs;
    let guard = guard.filter(|g| !g.is_empty());
    let to_um = |p: DVec2| DVec2::new(c * p.x - s * p.y, s * p.x + c * p.y) * crate::geom::tolerance::UNITS_PER_MM;
    let (mut total, mut slivers) = (0.0, 0);
    let (mut pieces, mut keep) = (Vec::new(), Vec::new());
    let mut lines: Vec<Vec<DVec2>> = Vec::new();
    for e in &g.edges {
        let pts: Vec<DVec2> = curve.points(g.pts[e[0] as usize], g.pts[e[1] as usize]).into_iter().map(to_um).collect();
        lines.clear();
        // The kept parts of every segment, in order along the strut (mm, µm-rounded).
        let push = |p: DVec2, q: DVec2, lines: &mut Vec<Vec<DVec2>>| {
            let (p, q) = (crop::snap_mm(p), crop::snap_mm(q));
            match lines.last_mut() {
                Some(l) if *l.last().unwrap() == p => l.push(q),
                _ => lines.push(vec![p, q]),
            }
        };
        for w in pts.windows(2) {
            pieces.clear();
            clip.clip(w[0], w[1], &mut pieces);
            for pc in &pieces {
                match guard {
                    None => push(pc[0], pc[1], &mut lines),
                    Some(guard) => {
                        guard.keep(pc[0], pc[1], u32::MAX, &mut keep);
                        let d = pc[1] - pc[0];
                        for &(t0, t1) in &keep {
                            let at = |t: f64| {
                                if t == 0.0 {
                                    pc[0]
                                } else if t == 1.0 {
                                    pc[1]
                                } else {
                                    pc[0] + d * t
                                }
                            };
                            push(at(t0), at(t1), &mut lines);
                        }
                    }
                }
            }
        }
        for line in lines.drain(..) {
            let mut pts: Vec<DVec2> = Vec::with_capacity(line.len());
            let last = *line.last().unwrap();
            for p in line {
                if pts.last().is_none_or(|q: &DVec2| q.distance(p) >= MIN_PIECE_MM) {
                    pts.push(p);
                }
            }
            // The end point is kept exactly (it may meet other struts): it replaces the last
            // inner point when that one is too close.
            if *pts.last().unwrap() != last {
                if pts.len() > 1 {
                    pts.pop();
                }
                pts.push(last);
            }
            let len: f64 = pts.windows(2).map(|w| w[0].distance(w[1])).sum();
            if pts.len() < 2 || len < MIN_PIECE_MM {
                slivers += usize::from(len > 0.0 || pts.len() >= 2);
                continue;
            }
            total += len;
            out.push(Stroke { points: pts, feature, curved: true });
        }
    }
    (total, slivers)
}

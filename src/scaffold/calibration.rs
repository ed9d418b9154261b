//! CT value → porosity → relative density (the paper's section 2.3.2 and equation 7).
//!
//! The paper maps HU to porosity with the line through two points, `(HU_min, P_max)` and
//! `(HU_max, P_min)` (femur: `(−91 HU, 0.95)` and `(1516 HU, 0.10)`, giving equation 7,
//! `P = −0.000529 HU + 0.901867`), then `ρ = 1 − P`, floored at the minimum density a
//! stable part allows. This generalises the line to a piecewise-linear curve through any
//! number (≥ 2) of points, in any order: between points it interpolates, beyond the end points
//! it extrapolates with the end segments' slopes (so two points are exactly equation 7 applied
//! to every value). The density is then clamped to `[rho_min, 1]`, which also bounds the
//! extrapolation.
//!
//! Evaluation scans the points (no sorting, no allocation per voxel): the segment is the one
//! between the nearest point at or below the value and the nearest above it, or the two
//! lowest / two highest points outside their span.

use serde::{Deserialize, Serialize};

/// Default calibration points `(HU, porosity)`: the paper's femur section (section 3.2).
pub const DEFAULT_POINTS: [[f64; 2]; 2] = [[-91.0, 0.95], [1516.0, 0.10]];

/// A piecewise-linear map from a scalar (HU for CT) to porosity `P`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Calibration {
    /// `(value, porosity)` points, at least 2, distinct values, porosity in `[0, 1]`; any
    /// order. Default [`DEFAULT_POINTS`].
    pub points: Vec<[f64; 2]>,
}

impl Default for Calibration {
    fn default() -> Self {
        Calibration { points: DEFAULT_POINTS.to_vec() }
    }
}

impl Calibration {
    /// Every problem with the points, each saying how to fix it (empty when usable): fewer
    /// than 2 points, non-finite numbers, the same value twice, porosity outside `[0, 1]`.
    pub fn problems(&self) -> Vec<String> {
        let mut out = Vec::new();
        if self.points.len() < 2 {
            out.push(format!(
                "calibration.points has {} point(s): give at least 2 (value, porosity) pairs, e.g. [[-91, 0.95], [1516, 0.10]]",
                self.points.len()
            ));
        }
        for (n, &[v, p]) in self.points.iter().enumerate() {
            if !(v.is_finite() && p.is_finite()) {
                out.push(format!("calibration.points[{n}] = [{v}, {p}] is not a pair of finite numbers: give a value and a porosity"));
            } else if !(0.0..=1.0).contains(&p) {
                out.push(format!("calibration.points[{n}] has porosity {p}: porosity is a fraction, between 0 and 1"));
            }
        }
        let mut values: Vec<(f64, usize)> = self.points.iter().enumerate().filter(|(_, p)| p[0].is_finite()).map(|(n, p)| (p[0], n)).collect();
        values.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        for pair in values.windows(2) {
            if pair[0].0 == pair[1].0 {
                out.push(format!(
                    "calibration.points[{}] and [{}] have the same value {}: values must be distinct; remove one",
                    pair[0].1, pair[1].1, pair[0].0
                ));
            }
        }
        out
    }

    /// Porosity at `value`: piecewise linear through the points, extrapolated beyond them
    /// with the end segments' slopes. One point gives its porosity everywhere; no points, a
    /// non-finite value or a segment of two equal values give NaN (see [`Calibration::problems`]).
    /// For many values, make the [`Curve`] once.
    pub fn porosity(&self, value: f64) -> f64 {
        self.curve().porosity(value)
    }

    /// Relative density `1 − P(value)` clamped to `[rho_min, 1]` (`rho_min` above 1 gives 1; a
    /// NaN porosity gives `rho_min`, the safe printable minimum).
    pub fn density(&self, value: f64, rho_min: f64) -> f64 {
        self.curve().density(value, rho_min)
    }

    /// The map prepared for millions of calls (a volume's voxels, a G-code's moves): the points
    /// sorted once.
    pub fn curve(&self) -> Curve {
        let mut pts = self.points.clone();
        // By value (stable: of equal values the first given is kept, whatever the order).
        pts.sort_by(|a, b| a[0].total_cmp(&b[0]));
        pts.dedup_by(|later, first| later[0] == first[0]);
        Curve { pts, single: (self.points.len() == 1).then(|| self.points[0][1]) }
    }

    /// `(slope, intercept)` of `P = slope · value + intercept` when there are exactly 2 usable
    /// points (equation 7: `−0.000529, 0.901867` for the defaults, to the paper's digits).
    pub fn line(&self) -> Option<(f64, f64)> {
        if self.points.len() != 2 || !self.problems().is_empty() {
            return None;
        }
        let (mut a, mut b) = (self.points[0], self.points[1]);
        if a[0] > b[0] {
            std::mem::swap(&mut a, &mut b);
        }
        let slope = (b[1] - a[1]) / (b[0] - a[0]);
        Some((slope, a[1] - slope * a[0]))
    }
}

/// A [`Calibration`] ready for evaluation: its points sorted by value, one per value.
#[derive(Clone, Debug)]
pub struct Curve {
    pts: Vec<[f64; 2]>,
    /// The porosity of a one-point calibration (everywhere).
    single: Option<f64>,
}

impl Curve {
    /// See [`Calibration::porosity`].
    #[inline]
    pub fn porosity(&self, value: f64) -> f64 {
        if let Some(p) = self.single {
            return p;
        }
        let pts = self.pts.as_slice();
        if pts.len() < 2 || !value.is_finite() {
            return f64::NAN;
        }
        // The segment around the value; beyond the ends, the end segment (two points, the
        // usual case, have one).
        let i = if pts.len() == 2 { 1 } else { pts.partition_point(|p| p[0] <= value).clamp(1, pts.len() - 1) };
        let (a, b) = (pts[i - 1], pts[i]);
        a[1] + (b[1] - a[1]) * (value - a[0]) / (b[0] - a[0])
    }

    /// See [`Calibration::density`].
    #[inline]
    pub fn density(&self, value: f64, rho_min: f64) -> f64 {
        (1.0 - self.porosity(value)).max(rho_min).min(1.0)
    }
}

//! The foam's compressive modulus as a function of V* and its inverse (beyond the paper, from
//! its section 4.1): a user asks for a stiffness and gets the V* that prints it.
//!
//! The paper printed a linear V* sweep from 0.15 to 0.4 along the dogbone's 40 mm transition,
//! measured the modulus every 5 mm and fitted `E = F·e^{b·u}` (F = 4.79, b = −3.11, R² 0.987)
//! with `u = x/α_T` the position across the transition, −½ at the V* 0.15 end. Along a linear
//! sweep u is linear in V*, so the fit is a calibration of the modulus against V*:
//!
//! `E(V*) = F·exp(b·((V* − V₀)/(V₁ − V₀) − ½))`, inverted `V*(E) = V₀ + (V₁ − V₀)·(ln(E/F)/b + ½)`,
//!
//! with `V₀ → V₁` the calibration sweep. It holds for the material, nozzle and H* it was
//! measured with (the paper's TPU), and only inside the sweep: a modulus outside the range it
//! covers is refused rather than extrapolated. The paper does not print the unit of Fig. 6;
//! weft states the moduli in kPa, the unit of the foams the paper compares with.
//!
//! A transition whose modulus falls linearly between two regions (what the paper's fitted
//! logarithm aims at, [`crate::foam::Weighting::LinearModulus`]) needs only the ratio of the
//! two moduli, [`Calibration::ratio`].

use serde::{Deserialize, Serialize};

/// The paper's F of the modulus fit, kPa.
pub const DEFAULT_F_KPA: f64 = 4.79;
/// The paper's b of the modulus fit (the modulus falls e^{3.11} ≈ 22× over the sweep).
pub const DEFAULT_B: f64 = -3.11;
/// V* at the start of the paper's calibration sweep.
pub const DEFAULT_V_STAR_FROM: f64 = 0.15;
/// V* at the end of the paper's calibration sweep.
pub const DEFAULT_V_STAR_TO: f64 = 0.4;

/// The modulus fit along a linear V* sweep: `E = F·e^{b·u}`, u from −½ (V* `v_star_from`)
/// to ½ (V* `v_star_to`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Calibration {
    /// F, kPa; default [`DEFAULT_F_KPA`].
    pub f_kpa: f64,
    /// b; default [`DEFAULT_B`].
    pub b: f64,
    /// V* where the sweep started (u = −½); default [`DEFAULT_V_STAR_FROM`].
    pub v_star_from: f64,
    /// V* where the sweep ended (u = ½); default [`DEFAULT_V_STAR_TO`].
    pub v_star_to: f64,
}

impl Default for Calibration {
    fn default() -> Self {
        Calibration { f_kpa: DEFAULT_F_KPA, b: DEFAULT_B, v_star_from: DEFAULT_V_STAR_FROM, v_star_to: DEFAULT_V_STAR_TO }
    }
}

impl Calibration {
    /// Modulus at `v_star`, kPa.
    pub fn modulus_kpa(&self, v_star: f64) -> f64 {
        let u = (v_star - self.v_star_from) / (self.v_star_to - self.v_star_from) - 0.5;
        self.f_kpa * libm::exp(self.b * u)
    }

    /// The V* that prints `modulus_kpa` (the inverse of [`Calibration::modulus_kpa`]).
    pub fn v_star(&self, modulus_kpa: f64) -> f64 {
        self.v_star_from + (self.v_star_to - self.v_star_from) * (libm::log(modulus_kpa / self.f_kpa) / self.b + 0.5)
    }

    /// The moduli the sweep covers, least first, kPa.
    pub fn range_kpa(&self) -> (f64, f64) {
        let (a, b) = (self.modulus_kpa(self.v_star_from), self.modulus_kpa(self.v_star_to));
        (a.min(b), a.max(b))
    }

    /// `E(v_to) / E(v_from)`: what a transition from V* `v_from` to `v_to` multiplies the
    /// modulus by.
    pub fn ratio(&self, v_from: f64, v_to: f64) -> f64 {
        libm::exp(self.b * (v_to - v_from) / (self.v_star_to - self.v_star_from))
    }

    /// Every problem with the calibration, each saying how to fix it (empty when usable).
    pub fn problems(&self) -> Vec<String> {
        let mut out = Vec::new();
        if !(self.f_kpa.is_finite() && self.f_kpa > 0.0) {
            out.push(format!("the modulus fit's F is {} kPa: it must be above 0 (the paper's is {DEFAULT_F_KPA})", self.f_kpa));
        }
        if !(self.b.is_finite() && self.b != 0.0) {
            out.push(format!("the modulus fit's b is {}: it must be a number other than 0 (the paper's is {DEFAULT_B})", self.b));
        }
        let (a, b) = (self.v_star_from, self.v_star_to);
        if !(a.is_finite() && b.is_finite() && a > 0.0 && b > 0.0 && a != b) {
            out.push(format!("the calibration sweep runs from V* {a} to {b}: give two different V* above 0 (the paper swept 0.15 to 0.4)"));
        }
        out
    }

    /// Why `modulus_kpa` cannot be asked of this calibration (None when it can; the
    /// calibration itself must be usable).
    pub fn modulus_problem(&self, modulus_kpa: f64) -> Option<String> {
        let (lo, hi) = self.range_kpa();
        if !modulus_kpa.is_finite() || modulus_kpa < lo * (1.0 - 1e-9) || modulus_kpa > hi * (1.0 + 1e-9) {
            let (v_soft, v_stiff) = if self.modulus_kpa(self.v_star_from) < self.modulus_kpa(self.v_star_to) {
                (self.v_star_from, self.v_star_to)
            } else {
                (self.v_star_to, self.v_star_from)
            };
            return Some(format!(
                "a modulus of {modulus_kpa} kPa is outside the calibration, which covers {lo:.2} kPa (V* {v_soft}) to {hi:.2} kPa (V* {v_stiff}); ask for a modulus in that range, or measure a wider V* sweep and enter its fit"
            ));
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_inverse_gives_back_v_star_and_the_sweep_ends_are_the_papers() {
        let c = Calibration::default();
        for v in [0.15, 0.2, 0.275, 0.33, 0.4] {
            assert!((c.v_star(c.modulus_kpa(v)) - v).abs() < 1e-12, "{v}");
        }
        // The paper's fit at the ends of its sweep: F·e^{∓b/2}.
        let (lo, hi) = c.range_kpa();
        assert!((hi - 4.79 * libm::exp(1.555)).abs() < 1e-9 && (lo - 4.79 * libm::exp(-1.555)).abs() < 1e-9, "{lo} {hi}");
        assert!((c.ratio(0.15, 0.4) - libm::exp(-3.11)).abs() < 1e-12);
        assert!(c.modulus_problem(10.0).is_none());
        let m = c.modulus_problem(50.0).unwrap();
        assert!(m.contains("50 kPa") && m.contains("22.68") && m.contains("1.01"), "{m}");
        assert!(c.modulus_problem(f64::NAN).is_some());
        let bad = Calibration { f_kpa: 0.0, b: 0.0, v_star_from: 0.2, v_star_to: 0.2 };
        assert_eq!(bad.problems().len(), 3, "{:?}", bad.problems());
    }
}

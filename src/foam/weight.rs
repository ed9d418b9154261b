//! Weighting functions of a transition between two regions (the paper's appendix A).
//!
//! A point at signed distance α_i from the boundary shared by Ω^j and Ω^k (negative on the Ω^j
//! side) in a transition of length α_T has `x = α_i / α_T`; its pair is
//! `π = π^j·(1 − w(x)) + π^k·w(x)` (equation 1), with `w = 0` for `x ≤ −½` and `w = 1` for
//! `x ≥ ½`. Inside, the functions below (equations 2–6, written out cleanly: the paper's text
//! of equations 5 and 6 is garbled). All but the logarithmic one meet 0 and 1 at the ends, pass
//! ½ at 0 and rise monotonically; the cubic only for a slope `s` in `[0, 3/2]`.
//!
//! The logarithmic function inverts the paper's fit of the modulus measured along a linear V*
//! sweep, so that the modulus falls linearly across the transition (section 4.1, Fig. 6). Its fit
//! measures position from the Ω^k end (the modulus line `E(x) = 23.91x + 13.26` rises towards
//! the stiff, low-V* end), so with x running from Ω^j to Ω^k it is `w(x) = ln(E(−x)/F)/b + ½`.
//! Being a fit, it misses the ends: w(−½⁺) = −0.034 and w(½⁻) = 0.918, which with V* 0.15 → 0.4
//! are the paper's V* 0.1415 and 0.3795 just inside the transition.

use serde::{Deserialize, Serialize};

/// Default slope at 0 of the cubic: 3/2, which also makes its ends C¹ (the paper's special case).
pub const DEFAULT_CUBIC_SLOPE: f64 = 1.5;
/// The logarithmic function's modulus line `E(x) = slope·x + intercept`: the paper's slope.
pub const DEFAULT_LOG_SLOPE: f64 = 23.91;
/// The paper's intercept of the modulus line.
pub const DEFAULT_LOG_INTERCEPT: f64 = 13.26;
/// The paper's F of the exponential fit `E = F·e^{b·u}` of the modulus along a linear V* sweep.
pub const DEFAULT_LOG_F: f64 = 4.79;
/// The paper's b of that fit.
pub const DEFAULT_LOG_B: f64 = -3.11;

/// A transition's weighting function `w(x)`, `x = α_i / α_T`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Weighting {
    /// `w = x + ½` (equation 2).
    #[default]
    Linear,
    /// `w = 4(1 − s)x³ + s·x + ½` (equation 3): `s` is the slope at 0.
    Cubic {
        /// Slope at x = 0, in `[0, 3/2]` (monotone); default [`DEFAULT_CUBIC_SLOPE`].
        slope: f64,
    },
    /// `w = ln(E(−x)/F)/b + ½`, `E(x) = slope·x + intercept` (equation 4; see the module notes).
    Logarithmic {
        /// Slope of the modulus line; default [`DEFAULT_LOG_SLOPE`].
        slope: f64,
        /// Intercept of the modulus line; default [`DEFAULT_LOG_INTERCEPT`].
        intercept: f64,
        /// F of the modulus fit; default [`DEFAULT_LOG_F`].
        f: f64,
        /// b of the modulus fit; default [`DEFAULT_LOG_B`].
        b: f64,
    },
    /// `w = ∛(x/4) + ½` (equation 5): steep at the boundary, flat at the ends.
    CubeRoot,
    /// `w = sin(πx)/2 + ½` (equation 6): C¹ at the ends.
    Sinusoidal,
    /// Beyond the paper: `w = ln(1 + (r − 1)(x + ½)) / ln r`, the weight at which the modulus
    /// (by a [`crate::foam::stiffness::Calibration`]) falls or rises linearly from one region's
    /// to the other's, r being their ratio. What the fitted logarithm aims at, but exact at both
    /// ends (w = 0 and 1) for any two regions; linear when r = 1.
    LinearModulus {
        /// `E(to) / E(from)`, set by the job from the regions' V* and the calibration (not part
        /// of the design); default [`DEFAULT_MODULUS_RATIO`].
        #[serde(skip)]
        ratio: f64,
    },
}

/// The modulus ratio of the paper's sweep, V* 0.15 → 0.4: `e^{−3.11}`.
pub const DEFAULT_MODULUS_RATIO: f64 = 0.044_600_955_340_274_535;

/// The design's form of a weighting: `{"kind": …}` with the kind's own parameters only (a
/// parameter of another kind is refused rather than ignored: serde's tagged enums would drop it
/// silently for the kinds without parameters).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Raw {
    kind: String,
    slope: Option<f64>,
    intercept: Option<f64>,
    f: Option<f64>,
    b: Option<f64>,
}

impl<'de> Deserialize<'de> for Weighting {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        use serde::de::Error;
        let r = Raw::deserialize(d)?;
        let given = |names: &[&str]| -> Vec<&'static str> {
            [("slope", r.slope), ("intercept", r.intercept), ("f", r.f), ("b", r.b)]
                .into_iter()
                .filter(|(n, v)| v.is_some() && !names.contains(n))
                .map(|(n, _)| n)
                .collect()
        };
        let (w, allowed): (Weighting, &[&str]) = match r.kind.as_str() {
            "linear" => (Weighting::Linear, &[]),
            "cubic" => (Weighting::Cubic { slope: r.slope.unwrap_or(DEFAULT_CUBIC_SLOPE) }, &["slope"]),
            "logarithmic" => (
                Weighting::Logarithmic {
                    slope: r.slope.unwrap_or(DEFAULT_LOG_SLOPE),
                    intercept: r.intercept.unwrap_or(DEFAULT_LOG_INTERCEPT),
                    f: r.f.unwrap_or(DEFAULT_LOG_F),
                    b: r.b.unwrap_or(DEFAULT_LOG_B),
                },
                &["slope", "intercept", "f", "b"],
            ),
            "cube_root" => (Weighting::CubeRoot, &[]),
            "sinusoidal" => (Weighting::Sinusoidal, &[]),
            "linear_modulus" => (Weighting::LinearModulus { ratio: DEFAULT_MODULUS_RATIO }, &[]),
            other => return Err(D::Error::unknown_variant(other, &["linear", "cubic", "logarithmic", "cube_root", "sinusoidal", "linear_modulus"])),
        };
        match given(allowed).as_slice() {
            [] => Ok(w),
            extra => Err(D::Error::custom(format!(
                "a {} weighting takes no {} (remove it{})",
                r.kind,
                extra.join(", "),
                if allowed.is_empty() { "" } else { ", or choose another kind" }
            ))),
        }
    }
}

impl Weighting {
    /// The paper's logarithmic function.
    pub fn logarithmic() -> Weighting {
        Weighting::Logarithmic { slope: DEFAULT_LOG_SLOPE, intercept: DEFAULT_LOG_INTERCEPT, f: DEFAULT_LOG_F, b: DEFAULT_LOG_B }
    }

    /// `w(x)`: 0 for `x ≤ −½`, 1 for `x ≥ ½`, [`Weighting::inside`] between (NaN stays NaN).
    pub fn weight(&self, x: f64) -> f64 {
        if x <= -0.5 {
            0.0
        } else if x >= 0.5 {
            1.0
        } else {
            self.inside(x)
        }
    }

    /// The function's formula at `x` (meant for `−½ < x < ½`), without the ends' clamping.
    pub fn inside(&self, x: f64) -> f64 {
        match *self {
            Weighting::Linear => x + 0.5,
            Weighting::Cubic { slope } => 4.0 * (1.0 - slope) * x * x * x + slope * x + 0.5,
            Weighting::Logarithmic { slope, intercept, f, b } => libm::log((intercept - slope * x) / f) / b + 0.5,
            Weighting::CubeRoot => libm::cbrt(x / 4.0) + 0.5,
            Weighting::Sinusoidal => libm::sin(std::f64::consts::PI * x) / 2.0 + 0.5,
            Weighting::LinearModulus { ratio } => {
                if (ratio - 1.0).abs() < 1e-9 {
                    x + 0.5
                } else {
                    libm::log1p((ratio - 1.0) * (x + 0.5)) / libm::log(ratio)
                }
            }
        }
    }

    /// Every problem with the parameters, each saying how to fix it (empty when usable).
    pub fn problems(&self) -> Vec<String> {
        let mut out = Vec::new();
        match *self {
            Weighting::Cubic { slope } if !(0.0..=1.5).contains(&slope) => out.push(format!(
                "the cubic's slope at the boundary is {slope}: use 0 to 1.5 (outside that range the weight is not monotone; 1.5 also makes the ends smooth)"
            )),
            Weighting::Logarithmic { slope, intercept, f, b } => {
                if ![slope, intercept, f, b].iter().all(|v| v.is_finite()) {
                    out.push("the logarithmic function's numbers must be finite".into());
                } else {
                    if f <= 0.0 {
                        out.push(format!("F is {f}: it is the modulus fit's factor and must be above 0 (the paper's is {DEFAULT_LOG_F})"));
                    }
                    if b == 0.0 {
                        out.push(format!("b is 0: it is the modulus fit's exponent and must not be 0 (the paper's is {DEFAULT_LOG_B})"));
                    }
                    let lo = intercept - slope.abs() / 2.0;
                    if lo <= 0.0 {
                        out.push(format!("the modulus line {slope}·x + {intercept} reaches {lo:.3} within the transition: it must stay above 0 over x in [−½, ½] (raise the intercept above {:.3})", slope.abs() / 2.0));
                    }
                }
            }
            Weighting::LinearModulus { ratio } if !(ratio.is_finite() && ratio > 0.0) => {
                out.push(format!("the ratio of the two regions' moduli is {ratio}: check the modulus calibration (its F and b)"))
            }
            _ => {}
        }
        out
    }

    /// `x = α_i / α_T` of a point at signed distance `alpha_i` in a transition of length
    /// `alpha_t` (mm); a zero-length transition is a step (`±∞` off the boundary, 0 on it).
    pub fn x(alpha_i: f64, alpha_t: f64) -> f64 {
        if alpha_t > 0.0 {
            alpha_i / alpha_t
        } else if alpha_i < 0.0 {
            f64::NEG_INFINITY
        } else if alpha_i > 0.0 {
            f64::INFINITY
        } else {
            0.0
        }
    }
}

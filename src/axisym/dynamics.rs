//! Tool-axis smoothing and rotary-axis dynamics of a posed path (issue 10, "rasters smoothed
//! for machine dynamics").
//!
//! With the tool axis equal to the surface normal, the rotary axes follow the normal's turn
//! along the path: smooth along a geodesic, but at every point where the raster changes
//! direction the turning rate jumps within one sample, so the angular acceleration there is
//! about Δrate·feed/step: large, and larger the finer the sampling. [`smooth_axes`] lets the
//! axis lag the normal by at most a stated tilt: a zero-phase exponential filter over arc
//! length (forward, then backward, so the result does not shift along the path) with time
//! constant `window_mm / 2`, each filtered axis's tilt φ from its normal then mapped to
//! L·tanh(φ/L), L = `max_tilt_deg`: nearly unchanged when small, never beyond L, and smooth
//! (a hard clamp would put a kink back wherever it binds). O(n), one pass each way; deterministic (`libm`).
//!
//! [`dynamics`] measures what the machine must do at a feed: the tool axis's rate of turn and,
//! on a 5-axis machine, each rotary axis's speed and acceleration through the machine's
//! inverse kinematics (continuous branch), by finite differences on the samples.

use crate::machine::Machine;
use serde::{Deserialize, Serialize};

/// Default largest tilt of the tool axis away from the surface normal, degrees: 0 = off (the
/// axis is the normal, the paper's rule).
pub const DEFAULT_MAX_TILT_DEG: f64 = 0.0;
/// Largest accepted tilt, degrees: beyond this the nozzle's side drags through the strand.
pub const MAX_TILT_DEG: f64 = 30.0;
/// Default smoothing length along the path, mm: about five nozzle widths, so a corner's turn
/// is spread over a few millimetres.
pub const DEFAULT_WINDOW_MM: f64 = 2.0;
/// Accepted smoothing lengths, mm.
pub const WINDOW_RANGE_MM: [f64; 2] = [0.01, 1000.0];

/// Smoothing settings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Options {
    /// See [`DEFAULT_MAX_TILT_DEG`]; within [0, [`MAX_TILT_DEG`]].
    pub max_tilt_deg: f64,
    /// See [`DEFAULT_WINDOW_MM`]; within [`WINDOW_RANGE_MM`].
    pub window_mm: f64,
}

impl Default for Options {
    fn default() -> Self {
        Options { max_tilt_deg: DEFAULT_MAX_TILT_DEG, window_mm: DEFAULT_WINDOW_MM }
    }
}

/// The settings' form rows (mounted by the job).
pub const FIELDS: &[crate::settings::Field] = {
    use crate::settings::num;
    &[
        num("max_tilt_deg", "Tool axis", "Smoothing: most tilt", "°", 0.0, MAX_TILT_DEG, 0.5, "Lets the tool axis lean up to this far from the surface normal so the rotary axes turn corners gently (0 = always the normal; 10° with a 2 mm length halves the corner accelerations on the examples)."),
        num("window_mm", "Tool axis", "Smoothing length", "mm", WINDOW_RANGE_MM[0], WINDOW_RANGE_MM[1], 0.5, "Along how much path a corner's turn of the tool axis is spread."),
    ]
};

/// Why smoothing or the dynamics could not be computed.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum Error {
    /// An option out of range.
    #[error("option {name} = {value} is out of range: {hint}")]
    BadOption {
        /// Option name.
        name: &'static str,
        /// Value given.
        value: f64,
        /// Allowed range.
        hint: &'static str,
    },
    /// Positions and axes differ in number.
    #[error("{positions} positions but {axes} tool axes: give one axis per position")]
    Mismatch {
        /// Positions given.
        positions: usize,
        /// Axes given.
        axes: usize,
    },
    /// A normal that is not a unit vector.
    #[error("the normal of pose {index} is not a unit vector; the poses must come from the platform")]
    BadNormal {
        /// Pose index.
        index: usize,
    },
}

/// Smoothed tool axes.
#[derive(Clone, Debug, PartialEq)]
pub struct Smoothed {
    /// One unit axis per pose.
    pub axes: Vec<[f64; 3]>,
    /// Largest angle between an axis and its normal, degrees.
    pub max_tilt_deg: f64,
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}
fn chord(a: [f64; 3], b: [f64; 3]) -> f64 {
    libm::hypot(libm::hypot(a[0] - b[0], a[1] - b[1]), a[2] - b[2])
}
/// Angle between unit vectors, radians (atan2 keeps tiny angles accurate).
fn angle(a: [f64; 3], b: [f64; 3]) -> f64 {
    let c = [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
    libm::atan2(norm(c), dot(a, b))
}

fn check(o: &Options) -> Result<(), Error> {
    if !(0.0..=MAX_TILT_DEG).contains(&o.max_tilt_deg) {
        return Err(Error::BadOption { name: "max_tilt_deg", value: o.max_tilt_deg, hint: "give a tilt from 0 to 30°" });
    }
    if !(WINDOW_RANGE_MM[0]..=WINDOW_RANGE_MM[1]).contains(&o.window_mm) {
        return Err(Error::BadOption { name: "window_mm", value: o.window_mm, hint: "give a length from 0.01 to 1000 mm" });
    }
    Ok(())
}

/// Tool axes for the path through `positions` whose surface normals are `normals`: the normals
/// themselves when `max_tilt_deg` is 0, else filtered and kept within the tilt (module notes).
pub fn smooth_axes(positions: &[[f64; 3]], normals: &[[f64; 3]], o: &Options) -> Result<Smoothed, Error> {
    check(o)?;
    if positions.len() != normals.len() {
        return Err(Error::Mismatch { positions: positions.len(), axes: normals.len() });
    }
    if let Some(index) = normals.iter().position(|n| !((norm(*n) - 1.0).abs() < 1e-6)) {
        return Err(Error::BadNormal { index });
    }
    if o.max_tilt_deg == 0.0 || normals.len() < 2 {
        return Ok(Smoothed { axes: normals.to_vec(), max_tilt_deg: 0.0 });
    }
    let tau = 0.5 * o.window_mm;
    // Weight of the previous filtered value across step i (from i − 1 to i).
    let keep: Vec<f64> = (0..positions.len()).map(|i| if i == 0 { 0.0 } else { libm::exp(-chord(positions[i - 1], positions[i]) / tau) }).collect();
    let mix = |prev: [f64; 3], cur: [f64; 3], a: f64| [a * prev[0] + (1.0 - a) * cur[0], a * prev[1] + (1.0 - a) * cur[1], a * prev[2] + (1.0 - a) * cur[2]];
    let mut f = normals.to_vec();
    for i in 1..f.len() {
        f[i] = mix(f[i - 1], normals[i], keep[i]);
    }
    for i in (0..f.len() - 1).rev() {
        f[i] = mix(f[i + 1], f[i], keep[i + 1]);
    }
    let limit = o.max_tilt_deg.to_radians();
    let mut max_tilt = 0.0f64;
    let axes = f
        .iter()
        .zip(normals)
        .map(|(&s, &n)| {
            let l = norm(s);
            // A filtered vector that cancelled out (normals turning by ~180° within the
            // window) has no direction: keep the normal.
            if !(l > 1e-9) {
                return n;
            }
            let s = [s[0] / l, s[1] / l, s[2] / l];
            let phi = angle(n, s);
            // Soft limit: the tilt becomes L·tanh(φ/L), ≈ φ when small and always below L.
            // A hard clamp at L would put back a kink wherever it binds, and kinks are what
            // the filter removes.
            let a = if phi > 1e-12 {
                let t = limit * libm::tanh(phi / limit) / phi;
                let (w0, w1) = (libm::sin((1.0 - t) * phi) / libm::sin(phi), libm::sin(t * phi) / libm::sin(phi));
                let v = [w0 * n[0] + w1 * s[0], w0 * n[1] + w1 * s[1], w0 * n[2] + w1 * s[2]];
                let l = norm(v);
                [v[0] / l, v[1] / l, v[2] / l]
            } else {
                s
            };
            max_tilt = max_tilt.max(angle(n, a));
            a
        })
        .collect();
    Ok(Smoothed { axes, max_tilt_deg: max_tilt.to_degrees() })
}

/// Speed and acceleration of one axis along the path.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct AxisRate {
    /// "tool axis" (its angle of turn), or a rotary axis letter ("A", "B", "C").
    pub axis: String,
    /// Largest speed, °/s.
    pub max_speed_deg_s: f64,
    /// Largest acceleration, °/s² (finite differences of the per-step speeds).
    pub max_accel_deg_s2: f64,
}

/// Motion along a posed path at constant feed.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Dynamics {
    /// The tool axis first, then each rotary axis of a 5-axis machine (letter order).
    pub axes: Vec<AxisRate>,
    /// Path length, mm.
    pub path_mm: f64,
    /// Time at the feed, s.
    pub duration_s: f64,
}

/// Largest |rate| and |Δrate/Δt| of a quantity sampled per step: (step time, change).
struct Rates {
    last: Option<(f64, f64)>,
    max_speed: f64,
    max_accel: f64,
}

impl Rates {
    fn new() -> Rates {
        Rates { last: None, max_speed: 0.0, max_accel: 0.0 }
    }
    /// A step of `change` (degrees) taking `dt` seconds, centred at time `mid`.
    fn step(&mut self, mid: f64, dt: f64, change: f64) {
        let rate = change / dt;
        self.max_speed = self.max_speed.max(rate.abs());
        if let Some((tp, rp)) = self.last {
            self.max_accel = self.max_accel.max((rate - rp).abs() / (mid - tp));
        }
        self.last = Some((mid, rate));
    }
}

/// Speeds and accelerations along the tool path `tips` with tool `axes` at `feed_mm_s`: the
/// tool axis's turn, and each rotary axis of `machine` when it has them (angles continuous
/// from pose to pose, as the writer emits them). Steps of zero length are skipped.
pub fn dynamics(tips: &[[f64; 3]], axes: &[[f64; 3]], machine: &Machine, feed_mm_s: f64) -> Result<Dynamics, Error> {
    if !(feed_mm_s > 0.0 && feed_mm_s.is_finite()) {
        return Err(Error::BadOption { name: "feed_mm_s", value: feed_mm_s, hint: "give a feed > 0 mm/s" });
    }
    if tips.len() != axes.len() {
        return Err(Error::Mismatch { positions: tips.len(), axes: axes.len() });
    }
    let rotary = machine.is_five_axis();
    let angles: Vec<[f64; 2]> = if rotary {
        let mut prev = None;
        axes.iter()
            .map(|a| {
                let r = machine.inverse(crate::geom::DVec3::from_array(*a), prev);
                prev = Some(r);
                r
            })
            .collect()
    } else {
        Vec::new()
    };
    let mut tool = Rates::new();
    let mut each = [Rates::new(), Rates::new()];
    let (mut t, mut path) = (0.0, 0.0);
    for i in 1..tips.len() {
        let l = chord(tips[i - 1], tips[i]);
        if !(l > 0.0) {
            continue;
        }
        let dt = l / feed_mm_s;
        let mid = t + 0.5 * dt;
        tool.step(mid, dt, angle(axes[i - 1], axes[i]).to_degrees());
        if rotary {
            for (k, r) in each.iter_mut().enumerate() {
                r.step(mid, dt, angles[i][k] - angles[i - 1][k]);
            }
        }
        t += dt;
        path += l;
    }
    let mut out = vec![AxisRate { axis: "tool axis".into(), max_speed_deg_s: tool.max_speed, max_accel_deg_s2: tool.max_accel }];
    if rotary {
        for (k, r) in each.iter().enumerate() {
            out.push(AxisRate { axis: (machine.rotary_letters()[k] as char).to_string(), max_speed_deg_s: r.max_speed, max_accel_deg_s2: r.max_accel });
        }
    }
    Ok(Dynamics { axes: out, path_mm: path, duration_s: t })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::axisym::platform::{normal, position, Platform};
    use crate::machine::Kind;

    fn equator(n: usize, dt: f64) -> (Vec<[f64; 3]>, Vec<[f64; 3]>) {
        let p = Platform::barrel();
        (0..=n).map(|i| (position(&p, 1.0, i as f64 * dt), normal(&p, 1.0, i as f64 * dt))).unzip()
    }

    #[test]
    fn equator_turns_at_feed_over_radius() {
        // Around the barrel's equator (radius 25 mm) the normal turns at v/R rad/s; a B/C head
        // turns C at that rate and holds B.
        let (tips, normals) = equator(100, 0.01);
        let m = Machine { kind: Kind::FiveAxis, ..Machine::default() };
        let d = dynamics(&tips, &normals, &m, 50.0).unwrap();
        let want = (50.0f64 / 25.0).to_degrees();
        assert_eq!(d.axes.iter().map(|a| a.axis.as_str()).collect::<Vec<_>>(), ["tool axis", "B", "C"]);
        assert!((d.axes[0].max_speed_deg_s - want).abs() < 1e-3 * want, "{d:?}");
        assert!((d.axes[2].max_speed_deg_s - want).abs() < 1e-3 * want, "{d:?}");
        assert!(d.axes[1].max_speed_deg_s < 1e-6, "B holds: {d:?}");
        assert!(d.axes.iter().all(|a| a.max_accel_deg_s2 < 1e-2 * want), "constant rate: {d:?}");
        // A 3-axis machine (poses CSV) reports the tool axis only.
        assert_eq!(dynamics(&tips, &normals, &Machine::default(), 50.0).unwrap().axes.len(), 1);
        assert!(dynamics(&tips, &normals, &m, 0.0).is_err());
        assert!(dynamics(&tips, &normals[1..], &m, 1.0).is_err());
    }

    #[test]
    fn off_keeps_the_normals_bit_for_bit() {
        let (tips, normals) = equator(20, 0.05);
        let s = smooth_axes(&tips, &normals, &Options::default()).unwrap();
        assert_eq!(s.axes, normals);
        assert_eq!(s.max_tilt_deg, 0.0);
    }

    #[test]
    fn a_corner_is_rounded_within_the_tilt() {
        // Along the equator, then straight up a meridian: the normal's turn stops abruptly at
        // the corner (the meridian of the barrel at u = 1 curves slowly). Smoothing spreads it.
        let p = Platform::barrel();
        let mut tips = Vec::new();
        let mut normals = Vec::new();
        for i in 0..=200 {
            let t = 0.4 * i as f64 / 200.0;
            tips.push(position(&p, 1.0, t));
            normals.push(normal(&p, 1.0, t));
        }
        for i in 1..=200 {
            let u = 1.0 - 0.3 * i as f64 / 200.0;
            tips.push(position(&p, u, 0.4));
            normals.push(normal(&p, u, 0.4));
        }
        let m = Machine { kind: Kind::FiveAxis, ..Machine::default() };
        let raw = dynamics(&tips, &normals, &m, 30.0).unwrap();
        let o = Options { max_tilt_deg: 5.0, window_mm: 4.0 };
        let s = smooth_axes(&tips, &normals, &o).unwrap();
        assert!(s.max_tilt_deg <= 5.0 + 1e-9 && s.max_tilt_deg > 0.1, "{}", s.max_tilt_deg);
        for (a, n) in s.axes.iter().zip(&normals) {
            assert!((norm(*a) - 1.0).abs() < 1e-12);
            assert!(angle(*a, *n).to_degrees() <= 5.0 + 1e-9);
        }
        let smooth = dynamics(&tips, &s.axes, &m, 30.0).unwrap();
        for (r, q) in raw.axes.iter().zip(&smooth.axes) {
            println!(
                "{}: speed {:.1} → {:.1} °/s, accel {:.0} → {:.0} °/s²",
                r.axis, r.max_speed_deg_s, q.max_speed_deg_s, r.max_accel_deg_s2, q.max_accel_deg_s2
            );
        }
        // The tool axis's acceleration at the corner drops by more than half.
        assert!(smooth.axes[0].max_accel_deg_s2 < 0.5 * raw.axes[0].max_accel_deg_s2, "{raw:?} → {smooth:?}");
        assert!(smooth.axes[0].max_speed_deg_s <= raw.axes[0].max_speed_deg_s * (1.0 + 1e-9));
    }

    #[test]
    fn bad_options_are_named() {
        let (tips, normals) = equator(3, 0.1);
        for o in [
            Options { max_tilt_deg: -1.0, ..Options::default() },
            Options { max_tilt_deg: 31.0, ..Options::default() },
            Options { max_tilt_deg: 5.0, window_mm: 0.0 },
            Options { max_tilt_deg: f64::NAN, ..Options::default() },
        ] {
            assert!(matches!(smooth_axes(&tips, &normals, &o), Err(Error::BadOption { .. })), "{o:?}");
        }
        let mut bad = normals.clone();
        bad[2] = [0.0, 0.0, 2.0];
        assert_eq!(smooth_axes(&tips, &bad, &Options { max_tilt_deg: 5.0, ..Options::default() }), Err(Error::BadNormal { index: 2 }));
    }
}

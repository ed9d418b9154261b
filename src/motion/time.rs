//! Print-time model, shared by the analyzer and the writer (which times its own moves).
//!
//! Each move is a trapezoidal velocity profile: accelerate at `a` from the entry speed to the
//! commanded feed rate, cruise, decelerate to the exit speed (a triangle when the move is too
//! short to reach the feed rate). Junction speeds between consecutive moves follow Marlin's
//! junction-deviation rule, `v² = a · δ · sin(θ/2) / (1 − sin(θ/2))` with δ = 0.013 mm and θ
//! the angle between the reversed incoming and the outgoing direction (straight continuation
//! keeps full speed, a reversal stops), capped by both feed rates and by what the previous
//! move can reach. Planning is forward-only with one move of look-ahead (no backward pass),
//! so runs of very short moves ending in a sharp corner are slightly optimistic. Moves with
//! no XYZ motion (E-only retractions) start and end at rest and use the E distance. Dwells
//! (`G4`) add their time. There are no per-axis speed or acceleration limits.

/// Marlin's default junction deviation, mm.
pub const JUNCTION_DEVIATION_MM: f64 = 0.013;

/// Time of one move of `len` mm at cruise speed `v`, acceleration `a`, entering at `v_in`
/// and leaving at `v_out` (mm/s). Speeds above `v` are clamped; infeasible profiles (entry
/// too fast to slow down to the exit within `len`) use the mean speed.
pub fn trapezoid_time(len: f64, v: f64, a: f64, v_in: f64, v_out: f64) -> f64 {
    if len.is_nan() || len <= 0.0 || v.is_nan() || v <= 0.0 {
        return 0.0;
    }
    if a.is_nan() || a <= 0.0 || !a.is_finite() {
        return len / v;
    }
    let v_in = v_in.clamp(0.0, v);
    let v_out = v_out.clamp(0.0, v);
    let d_acc = (v * v - v_in * v_in) / (2.0 * a);
    let d_dec = (v * v - v_out * v_out) / (2.0 * a);
    if d_acc + d_dec <= len {
        return (v - v_in) / a + (v - v_out) / a + (len - d_acc - d_dec) / v;
    }
    let peak2 = (2.0 * a * len + v_in * v_in + v_out * v_out) / 2.0;
    let peak = peak2.sqrt();
    if peak < v_in.max(v_out) {
        return 2.0 * len / (v_in + v_out).max(1e-9);
    }
    (peak - v_in) / a + (peak - v_out) / a
}

#[derive(Clone, Copy, Debug)]
struct Pending {
    len: f64,
    v: f64,
    a: f64,
    v_in: f64,
    dir: [f64; 3],
}

/// Accumulates move times with one move of look-ahead.
#[derive(Clone, Debug, Default)]
pub struct MotionTimer {
    pending: Option<Pending>,
    total: f64,
}

impl MotionTimer {
    /// A move of `len` mm entering along unit vector `dir_in` and leaving along `dir_out`
    /// (equal for straight moves) at feed `v` mm/s with acceleration `a` mm/s².
    pub fn push(&mut self, len: f64, dir_in: [f64; 3], dir_out: [f64; 3], v: f64, a: f64) {
        if len.is_nan() || len <= 0.0 || v.is_nan() || v <= 0.0 {
            return;
        }
        let mut v_in = 0.0;
        if let Some(p) = self.pending.take() {
            let cos_theta = -(p.dir[0] * dir_in[0] + p.dir[1] * dir_in[1] + p.dir[2] * dir_in[2]);
            let a_j = p.a.min(a);
            let sin_half = (0.5 * (1.0 - cos_theta.clamp(-1.0, 1.0))).sqrt();
            // Squared junction speed: both feed rates, the junction deviation limit and what
            // the previous move can reach from its own entry speed.
            let mut vj2 = (p.v * p.v).min(v * v).min(p.v_in * p.v_in + 2.0 * p.a.max(0.0) * p.len);
            if sin_half < 0.999_999 {
                vj2 = vj2.min(a_j * JUNCTION_DEVIATION_MM * sin_half / (1.0 - sin_half));
            }
            let vj = if vj2 > 0.0 && vj2.is_finite() { vj2.sqrt() } else { 0.0 };
            self.total += trapezoid_time(p.len, p.v, p.a, p.v_in, vj);
            v_in = vj;
        }
        self.pending = Some(Pending { len, v, a, v_in, dir: dir_out });
    }

    /// Ends the current chain: the last move decelerates to rest.
    pub fn stop(&mut self) {
        if let Some(p) = self.pending.take() {
            self.total += trapezoid_time(p.len, p.v, p.a, p.v_in, 0.0);
        }
    }

    /// A move that starts and ends at rest (E-only moves).
    pub fn push_isolated(&mut self, len: f64, v: f64, a: f64) {
        self.stop();
        self.total += trapezoid_time(len, v, a, 0.0, 0.0);
    }

    /// A dwell of `s` seconds.
    pub fn dwell(&mut self, s: f64) {
        self.stop();
        if s.is_finite() && s > 0.0 {
            self.total += s;
        }
    }

    /// Total time so far, s (call [`MotionTimer::stop`] first for the final figure).
    pub fn total(&self) -> f64 {
        self.total
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn trapezoids() {
        // 100 mm at 50 mm/s, a = 1000: 0.05 s up, 0.05 s down, 1.25 mm each, 97.5 mm cruise.
        let t = trapezoid_time(100.0, 50.0, 1000.0, 0.0, 0.0);
        assert!((t - (0.1 + 97.5 / 50.0)).abs() < 1e-12);
        // Triangle: 1 mm, peak sqrt(1000) mm/s.
        let t = trapezoid_time(1.0, 100.0, 1000.0, 0.0, 0.0);
        assert!((t - 2.0 * 1000f64.sqrt() / 1000.0).abs() < 1e-12);
        // Constant speed when entering and leaving at the feed rate.
        assert!((trapezoid_time(10.0, 20.0, 1000.0, 20.0, 20.0) - 0.5).abs() < 1e-12);
    }

    #[test]
    fn straight_continuation_keeps_speed() {
        let mut m = MotionTimer::default();
        for _ in 0..10 {
            m.push(10.0, [1.0, 0.0, 0.0], [1.0, 0.0, 0.0], 50.0, 1000.0);
        }
        m.stop();
        let single = trapezoid_time(100.0, 50.0, 1000.0, 0.0, 0.0);
        assert!((m.total() - single).abs() < 1e-9, "{} vs {single}", m.total());
    }
}

//! Machine kinematics: which axes a printer has and how a tool pose (nozzle tip position and
//! tool axis) maps to machine coordinates (X Y Z and two rotary axes) and back.
//!
//! Conventions (documented once, used by the writer and the analyzer):
//! - angles are degrees; a positive angle turns the physical axis by the right-hand rule about
//!   +X (A), +Y (B) or +Z (C) of the machine;
//! - the tool axis is a unit vector from the nozzle tip towards the head (+Z on a 3-axis
//!   printer), in printer coordinates (the frame of the part on the bed at zero angles);
//! - **head-head**: the head turns, the bed does not. `ab`: A (outer, on the Z carriage)
//!   carries B; `bc`: C (outer) carries B. Tool axis `n = R_outer(θo) · R_inner(θi) · ẑ`.
//!   Machine X Y Z is the pivot point `tip + pivot_mm · n` (`pivot_mm` = 0: the tip itself, as
//!   for a controller with tool-centre-point control);
//! - **table-table**: the table turns, the tool stays vertical. `ab`: A (outer cradle) carries
//!   B; `bc`: B (outer cradle) carries C (the turntable). The table rotation is
//!   `M = R_outer(θo) · R_inner(θi)`; it turns the planned axis to vertical (`M · n = ẑ`), and
//!   a tip at `p` is at `M · (p − O) + O` in machine coordinates, `O` = `table_center_mm`
//!   (where both rotary axes cross; axes that do not cross are not modelled);
//! - inverse kinematics picks, among the two solutions, the one closest to the previous pose
//!   (each angle may also move by whole turns), so neighbouring points never flip by 180° or
//!   360°; the first pose takes the canonical solution (inner tilt in −90°…90° for `ab`,
//!   0°…180° for head `bc`); where an angle is undefined (C with a vertical axis on `bc`
//!   machines; A or B with the axis along the other rotary axis on `ab` machines) its previous
//!   value is kept.
//!
//! Transcendentals come from `libm`, so native and wasm builds agree to the bit.

use crate::geom::DVec3;
use serde::{Deserialize, Serialize};

/// How many axes the machine has.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Kind {
    /// X Y Z only; every tool axis must be +Z.
    #[default]
    Cartesian,
    /// X Y Z plus two rotary axes (see [`Layout`] and [`RotaryAxes`]).
    FiveAxis,
}

/// Which part turns on a 5-axis machine.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Layout {
    /// Both rotary axes turn the head.
    #[default]
    HeadHead,
    /// Both rotary axes turn the table.
    TableTable,
}

/// The rotary axis pair, as the G-code letters.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RotaryAxes {
    /// A (about X) and B (about Y).
    Ab,
    /// B (about Y) and C (about Z).
    #[default]
    Bc,
}

/// How the writer states the tool axis.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum AxisOutput {
    /// Rotary words (`A B` or `B C`) through the inverse kinematics; X Y Z are machine
    /// coordinates.
    #[default]
    Rotary,
    /// `I J K` tool vectors after the tip's X Y Z (for controllers that do the kinematics
    /// themselves).
    Ijk,
}

/// Default pivot length of a head-head machine, mm.
pub const DEFAULT_PIVOT_MM: f64 = 0.0;
/// Default rotary centre of a table-table machine, printer coordinates, mm (the middle of the
/// default 220 × 220 bed, on its surface).
pub const DEFAULT_TABLE_CENTER_MM: [f64; 3] = [110.0, 110.0, 0.0];
/// Default lower rotary limits A, B, C, degrees (C turns freely).
pub const DEFAULT_ROTARY_MIN_DEG: [f64; 3] = [-120.0, -120.0, -36000.0];
/// Default upper rotary limits A, B, C, degrees.
pub const DEFAULT_ROTARY_MAX_DEG: [f64; 3] = [120.0, 120.0, 36000.0];

/// A machine: kinematics and limits (`printer.machine` in a design).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Machine {
    /// Cartesian (3-axis) or five-axis. Default cartesian.
    pub kind: Kind,
    /// 5-axis: what turns, head or table. Default head_head.
    pub layout: Layout,
    /// 5-axis: the rotary pair. Default bc.
    pub rotary_axes: RotaryAxes,
    /// 5-axis: rotary words or `I J K` vectors. Default rotary.
    pub axis_output: AxisOutput,
    /// Head-head: distance from the nozzle tip to the point where the rotary axes cross,
    /// along the tool axis, mm. Default 0 (the controller compensates, or the pivot is at the
    /// tip).
    pub pivot_mm: f64,
    /// Table-table: where the rotary axes cross, printer coordinates, mm. Default 110, 110, 0.
    pub table_center_mm: [f64; 3],
    /// Lower limits of A, B, C, degrees. Default −120, −120, −36000.
    pub rotary_min_deg: [f64; 3],
    /// Upper limits of A, B, C, degrees. Default 120, 120, 36000.
    pub rotary_max_deg: [f64; 3],
    /// Lower travel limits X, Y, Z in machine coordinates, mm. Absent: the bed's volume.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub travel_min_mm: Option<[f64; 3]>,
    /// Upper travel limits X, Y, Z in machine coordinates, mm. Absent: the bed's volume.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub travel_max_mm: Option<[f64; 3]>,
}

impl Default for Machine {
    fn default() -> Self {
        Machine {
            kind: Kind::Cartesian,
            layout: Layout::HeadHead,
            rotary_axes: RotaryAxes::Bc,
            axis_output: AxisOutput::Rotary,
            pivot_mm: DEFAULT_PIVOT_MM,
            table_center_mm: DEFAULT_TABLE_CENTER_MM,
            rotary_min_deg: DEFAULT_ROTARY_MIN_DEG,
            rotary_max_deg: DEFAULT_ROTARY_MAX_DEG,
            travel_min_mm: None,
            travel_max_mm: None,
        }
    }
}

/// A coordinate axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Ax {
    X,
    Y,
    Z,
}

/// Rotation of `v` by `deg` about `axis` (right-hand rule).
fn rot(axis: Ax, deg: f64, v: DVec3) -> DVec3 {
    let r = deg.to_radians();
    let (s, c) = (libm::sin(r), libm::cos(r));
    match axis {
        Ax::X => DVec3::new(v.x, c * v.y - s * v.z, s * v.y + c * v.z),
        Ax::Y => DVec3::new(c * v.x + s * v.z, v.y, -s * v.x + c * v.z),
        Ax::Z => DVec3::new(c * v.x - s * v.y, s * v.x + c * v.y, v.z),
    }
}

/// `a + 360·k` closest to `near`.
fn unwrap_near(a: f64, near: f64) -> f64 {
    let k = ((near - a) / 360.0).round();
    if k.is_finite() {
        a + 360.0 * k
    } else {
        a
    }
}

impl Machine {
    /// Whether the machine has rotary axes.
    pub fn is_five_axis(&self) -> bool {
        self.kind == Kind::FiveAxis
    }

    /// G-code letters of the two rotary angles, in the order of [`Machine::inverse`]'s result.
    pub fn rotary_letters(&self) -> [u8; 2] {
        match self.rotary_axes {
            RotaryAxes::Ab => [b'A', b'B'],
            RotaryAxes::Bc => [b'B', b'C'],
        }
    }

    /// Index (A = 0, B = 1, C = 2) of each rotary angle.
    pub fn rotary_indices(&self) -> [usize; 2] {
        self.rotary_letters().map(|l| (l - b'A') as usize)
    }

    /// (outer axis, inner axis, outer angle index in the letter pair).
    fn chain(&self) -> (Ax, Ax, usize) {
        match (self.layout, self.rotary_axes) {
            (Layout::HeadHead, RotaryAxes::Ab) => (Ax::X, Ax::Y, 0),
            (Layout::HeadHead, RotaryAxes::Bc) => (Ax::Z, Ax::Y, 1),
            (Layout::TableTable, RotaryAxes::Ab) => (Ax::X, Ax::Y, 0),
            (Layout::TableTable, RotaryAxes::Bc) => (Ax::Y, Ax::Z, 0),
        }
    }

    /// (outer, inner) angles from the letter-ordered pair.
    fn outer_inner(&self, angles: [f64; 2]) -> (f64, f64) {
        let (_, _, o) = self.chain();
        (angles[o], angles[1 - o])
    }

    /// The letter-ordered pair from (outer, inner).
    fn letters_order(&self, outer: f64, inner: f64) -> [f64; 2] {
        let (_, _, o) = self.chain();
        if o == 0 {
            [outer, inner]
        } else {
            [inner, outer]
        }
    }

    /// Rotation the machine applies at `angles`: the head's orientation (head-head) or the
    /// table's (table-table).
    fn apply(&self, angles: [f64; 2], v: DVec3) -> DVec3 {
        let (ao, ai, _) = self.chain();
        let (o, i) = self.outer_inner(angles);
        rot(ao, o, rot(ai, i, v))
    }

    /// Inverse of [`Machine::apply`].
    fn unapply(&self, angles: [f64; 2], v: DVec3) -> DVec3 {
        let (ao, ai, _) = self.chain();
        let (o, i) = self.outer_inner(angles);
        rot(ai, -i, rot(ao, -o, v))
    }

    /// Forward kinematics: the tool axis (printer frame) at rotary `angles` (letter order).
    /// Cartesian: +Z.
    pub fn tool_axis(&self, angles: [f64; 2]) -> DVec3 {
        if !self.is_five_axis() {
            return DVec3::Z;
        }
        match self.layout {
            Layout::HeadHead => self.apply(angles, DVec3::Z),
            Layout::TableTable => self.unapply(angles, DVec3::Z),
        }
    }

    /// Machine X Y Z of a tip at `tip` (printer coordinates) with the rotary axes at `angles`.
    pub fn to_machine(&self, tip: DVec3, angles: [f64; 2]) -> DVec3 {
        if !self.is_five_axis() {
            return tip;
        }
        match self.layout {
            Layout::HeadHead => tip + self.pivot_mm * self.tool_axis(angles),
            Layout::TableTable => {
                let o = DVec3::from_array(self.table_center_mm);
                self.apply(angles, tip - o) + o
            }
        }
    }

    /// Forward kinematics of the position: the tip (printer coordinates) for machine X Y Z
    /// `xyz` at `angles`.
    pub fn to_tip(&self, xyz: DVec3, angles: [f64; 2]) -> DVec3 {
        if !self.is_five_axis() {
            return xyz;
        }
        match self.layout {
            Layout::HeadHead => xyz - self.pivot_mm * self.tool_axis(angles),
            Layout::TableTable => {
                let o = DVec3::from_array(self.table_center_mm);
                self.unapply(angles, xyz - o) + o
            }
        }
    }

    /// Inverse kinematics: rotary angles (letter order, degrees) that give tool axis `n`
    /// (unit), continuous with `previous` (see the module notes for the branch rule).
    pub fn inverse(&self, n: DVec3, previous: Option<[f64; 2]>) -> [f64; 2] {
        let (ao, ai, _) = self.chain();
        // The vector the outer rotation must bring onto `inner(θi)·ẑ`: n itself for a head; for
        // a table `M n = ẑ` ⇔ `n = R_i(−θi) R_o(−θo) ẑ`, solved as the head form with the
        // roles of the axes swapped and the angles negated.
        let (a1, a2, sign, swap) = match self.layout {
            Layout::HeadHead => (ao, ai, 1.0, false),
            Layout::TableTable => (ai, ao, -1.0, true),
        };
        // Normalised form n = R_a1(α) R_a2(β) ẑ; previous angles in that form.
        let prev = previous.map(|p| {
            let (o, i) = self.outer_inner(p);
            if swap {
                (sign * i, sign * o)
            } else {
                (sign * o, sign * i)
            }
        });
        // α makes the a1-perpendicular part of n lie in the plane R_a2(β)ẑ sweeps.
        let (u, w) = match (a1, a2) {
            (Ax::X, Ax::Y) => (-n.y, n.z),
            (Ax::Z, Ax::Y) => (n.y, n.x),
            (Ax::Y, Ax::X) => (n.x, n.z),
            // No layout chains other pairs.
            _ => (0.0, 1.0),
        };
        let singular = (u * u + w * w).sqrt() < 1e-9;
        let alpha0 = libm::atan2(u, w).to_degrees();
        let near = prev.map_or(0.0, |p| p.0);
        let both = [unwrap_near(alpha0, near), unwrap_near(alpha0 + 180.0, near)];
        let candidates: &[f64] = if singular { std::slice::from_ref(&near) } else { &both };
        let mut best: Option<((f64, f64), f64)> = None;
        for &alpha in candidates {
            let v = rot(a1, -alpha, n);
            // v = R_a2(β) ẑ.
            let beta = match a2 {
                Ax::Y => libm::atan2(v.x, v.z),
                Ax::X => libm::atan2(-v.y, v.z),
                Ax::Z => 0.0,
            }
            .to_degrees();
            let beta = prev.map_or(beta, |p| unwrap_near(beta, p.1));
            let cost = prev.map_or(0.0, |p| (alpha - p.0).abs() + (beta - p.1).abs());
            if best.is_none_or(|(_, c)| cost < c - 1e-12) {
                best = Some(((alpha, beta), cost));
            }
        }
        let ((alpha, beta), _) = best.unwrap_or(((0.0, 0.0), 0.0));
        let (o, i) = if swap { (sign * beta, sign * alpha) } else { (sign * alpha, sign * beta) };
        self.letters_order(o, i)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn machines() -> Vec<Machine> {
        let mut out = Vec::new();
        for layout in [Layout::HeadHead, Layout::TableTable] {
            for rotary_axes in [RotaryAxes::Ab, RotaryAxes::Bc] {
                out.push(Machine { kind: Kind::FiveAxis, layout, rotary_axes, pivot_mm: 40.0, ..Machine::default() });
            }
        }
        out
    }

    #[test]
    fn inverse_then_forward_gives_the_axis() {
        for m in machines() {
            let mut prev = None;
            for k in 0..200 {
                let t = k as f64 * 0.05;
                let n = DVec3::new(libm::sin(t) * 0.7, libm::cos(3.0 * t) * 0.5, 1.0).normalize();
                let a = m.inverse(n, prev);
                let back = m.tool_axis(a);
                assert!((back - n).length() < 1e-12, "{m:?} {n} {a:?} {back}");
                let p = DVec3::new(3.0, -2.0, 7.0);
                assert!((m.to_tip(m.to_machine(p, a), a) - p).length() < 1e-12);
                if let Some(q) = prev {
                    let q: [f64; 2] = q;
                    assert!((a[0] - q[0]).abs() < 20.0 && (a[1] - q[1]).abs() < 20.0, "{m:?} jump {q:?} → {a:?}");
                }
                prev = Some(a);
            }
        }
    }

    #[test]
    fn table_turns_the_axis_to_vertical() {
        for m in machines().into_iter().filter(|m| m.layout == Layout::TableTable) {
            let n = DVec3::new(0.3, -0.4, 0.5).normalize();
            let a = m.inverse(n, None);
            assert!((m.apply(a, n) - DVec3::Z).length() < 1e-12);
        }
    }

    #[test]
    fn vertical_axis_keeps_the_previous_outer_angle() {
        let m = Machine { kind: Kind::FiveAxis, ..Machine::default() }; // head-head BC
        let a = m.inverse(DVec3::new(0.0, 0.5, 0.5).normalize(), None);
        assert!((a[1] - 90.0).abs() < 1e-9, "{a:?}");
        let b = m.inverse(DVec3::Z, Some(a));
        assert_eq!(b[1], a[1], "C kept at the singularity");
        assert!(b[0].abs() < 1e-12);
        // Passing over the pole: B changes sign rather than C turning half a turn.
        let c = m.inverse(DVec3::new(0.0, -0.1, 1.0).normalize(), Some(b));
        assert!((c[1] - 90.0).abs() < 1e-9 && c[0] < 0.0, "{c:?}");
    }
}

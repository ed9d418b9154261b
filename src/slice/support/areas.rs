//! Where support goes: contacts, their projection down to the plate (or onto the part), and
//! the interface under each contact.

use super::{gap_layers, Input, Options};
use crate::geom::tolerance::UNITS_PER_MM;
use crate::slice::perimeters::{inset, outset};
use crate::slice::regions::{difference, intersect, union};
use i_overlay::i_shape::int::shape::IntShapes;

/// Support regions per layer, µm.
pub(crate) struct Areas {
    /// Where each layer needs support under it: the part of the layer that hangs over air.
    pub contact: Vec<IntShapes<i32>>,
    /// The support printed on each layer (interface included).
    pub support: Vec<IntShapes<i32>>,
    /// The dense top layers of the support (within `support`).
    pub interface: Vec<IntShapes<i32>>,
}

pub(crate) fn um(mm: f64) -> i32 {
    (mm * UNITS_PER_MM).round().clamp(0.0, i32::MAX as f64 / 4.0) as i32
}

/// The part of layer `i` that needs support: more than `h · tan(threshold)` beyond the layer
/// below (threads of air narrower than a tenth of a line are dropped), with enforcers added,
/// blockers and bridges taken away.
fn contact(o: &Options, input: &Input, i: usize) -> IntShapes<i32> {
    if i == 0 || input.part[i].is_empty() {
        return Vec::new();
    }
    let w = input.w_um;
    let part = &input.part[i];
    let below = &input.part[i - 1];
    let t = o.threshold_deg.clamp(0.0, 90.0);
    let mut over = if t >= 90.0 {
        Vec::new()
    } else {
        let reach = um(input.heights[i] * libm::tan(t.to_radians())).min(w.saturating_mul(20));
        difference(part, &outset(below, reach))
    };
    if let Some(enf) = input.enforcers.get(i).filter(|e| !e.is_empty()) {
        let forced = intersect(&difference(part, &outset(below, w / 4)), enf);
        over = if over.is_empty() { forced } else { union(&over, &forced) };
    }
    if over.is_empty() {
        return over;
    }
    if let Some(b) = input.blockers.get(i).filter(|b| !b.is_empty()) {
        over = difference(&over, b);
    }
    if !o.support_bridges {
        if let Some(b) = input.bridged.get(i).filter(|b| !b.is_empty()) {
            over = difference(&over, b);
        }
    }
    // Open by a twentieth of a line: slivers that thin are held by the layer below.
    let r = (w / 20).max(1);
    outset(&inset(&over, r), r)
}

/// Contacts, support and interface of every layer.
pub(crate) fn areas(o: &Options, input: &Input) -> Areas {
    let n = input.part.len();
    let contact: Vec<IntShapes<i32>> = crate::par::map(n, &mut |_| {}, |i| contact(o, input, i));
    let g = gap_layers(o, input.layer_height_mm);
    let xy = um(o.xy_gap_mm);
    let close = input.w_um.max(1);
    let keep_out: Vec<IntShapes<i32>> = crate::par::map(n, &mut |_| {}, |j| outset(&input.part[j], xy));
    // Top down: what layer j + 1 carries, plus the contacts resting on layer j, less the part.
    let mut support: Vec<IntShapes<i32>> = vec![Vec::new(); n];
    let mut carry: IntShapes<i32> = Vec::new();
    for j in (0..n).rev() {
        let above = j + 1 + g;
        if above < n && !contact[above].is_empty() {
            carry = if carry.is_empty() { contact[above].clone() } else { union(&carry, &contact[above]) };
            // Closed by a line width: the thin rings a dome's successive layers need merge
            // into one area a line can fill.
            carry = inset(&outset(&carry, close), close);
        }
        if carry.is_empty() {
            continue;
        }
        carry = if keep_out[j].is_empty() { carry } else { difference(&carry, &keep_out[j]) };
        support[j] = carry.clone();
    }
    if o.on_plate_only {
        // Bottom up: nothing above any part of the part below.
        let mut blocked: IntShapes<i32> = Vec::new();
        for j in 0..n {
            if !keep_out[j].is_empty() {
                blocked = if blocked.is_empty() { keep_out[j].clone() } else { union(&blocked, &keep_out[j]) };
            }
            if !support[j].is_empty() && !blocked.is_empty() {
                support[j] = difference(&support[j], &blocked);
            }
        }
    }
    // Interface: under the contacts of the `interface_layers` layers above the gap, grown by
    // one support spacing so lines cut back to their anchors still cover the contact.
    let m = o.interface_layers as usize;
    let grow = um(o.spacing_mm);
    let interface: Vec<IntShapes<i32>> = crate::par::map(n, &mut |_| {}, |j| {
        if m == 0 || support[j].is_empty() {
            return Vec::new();
        }
        let mut under: IntShapes<i32> = Vec::new();
        for c in contact.iter().take((j + g + m + 1).min(n)).skip(j + 1 + g) {
            if !c.is_empty() {
                under = if under.is_empty() { c.clone() } else { union(&under, c) };
            }
        }
        if under.is_empty() {
            return Vec::new();
        }
        intersect(&support[j], &outset(&under, grow))
    });
    Areas { contact, support, interface }
}

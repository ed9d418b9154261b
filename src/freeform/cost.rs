//! Both costs of every step of a sequence (the paper's Fig. 8): the exact ε (the whole
//! connected frame, [`Flex`]) and the heuristic ε (the cantilevered path alone: every stable
//! joint held rigid), each the deflection of the beam's free end under the nominal load; 0 for a
//! beam that ends on a joint already printed.

use super::frame::{self, Flex, Section, M6, RIGID};
use super::plan::{stable_joints, Step};
use glam::DVec3;

/// The two costs of one step, mm: ε (the norm of the free end's x, y, z deflection, the
/// paper's), and its part along the load. Holding joints rigid can only lower the deflection
/// along the load (the frame's compliance only grows when joints are freed), so
/// `heuristic_load_mm ≤ exact_load_mm` always; the norm adds sideways deflection, which freeing
/// the root can turn either way, so it almost always but not provably keeps that order.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct Costs {
    /// Whole frame.
    pub exact_mm: f64,
    /// Cantilevered path only.
    pub heuristic_mm: f64,
    /// Whole frame, along the load.
    pub exact_load_mm: f64,
    /// Cantilevered path only, along the load.
    pub heuristic_load_mm: f64,
}

/// Replays `steps` over the design and measures both costs of each.
pub fn costs(joints: &[DVec3], beams: &[[usize; 2]], grounded: &[bool], steps: &[Step], section: &Section, load_n: f64) -> Vec<Costs> {
    let n = joints.len();
    let mut open = vec![0u32; n];
    for &[a, b] in beams {
        open[a] += 1;
        open[b] += 1;
    }
    let mut inc: Vec<Vec<usize>> = vec![Vec::new(); n];
    for (b, &[p, q]) in beams.iter().enumerate() {
        inc[p].push(b);
        inc[q].push(b);
    }
    let mut flex = Flex::new(n);
    let mut in_frame: Vec<bool> = grounded.to_vec();
    let mut stable: Vec<bool> = grounded.to_vec();
    let mut chain: Vec<M6> = vec![RIGID; n];
    let mut present = vec![false; beams.len()];
    let f = DVec3::new(0.0, 0.0, -load_n);
    let mut out = Vec::with_capacity(steps.len());
    for s in steps {
        let (a, b) = (joints[s.from], joints[s.to]);
        let closing = in_frame[s.to];
        if closing {
            out.push(Costs::default());
            flex.connect(s.from, s.to, a, b, section);
        } else {
            let exact = frame::extend(&flex.get(s.from), a, b, section);
            let root = if stable[s.from] { RIGID } else { chain[s.from] };
            let heur = frame::extend(&root, a, b, section);
            let (ue, uh) = (frame::displacement(&exact, f), frame::displacement(&heur, f));
            let along = f.normalize_or_zero();
            out.push(Costs { exact_mm: ue.length(), heuristic_mm: uh.length(), exact_load_mm: ue.dot(along), heuristic_load_mm: uh.dot(along) });
            flex.attach(s.to, s.from, a, b, section);
            chain[s.to] = heur;
            in_frame[s.to] = true;
        }
        present[s.beam] = true;
        for j in [s.from, s.to] {
            open[j] -= 1;
            if open[j] == 0 {
                flex.retire(j);
            }
        }
        if closing {
            // A loop closed: joints may have become stable.
            let st = stable_joints(joints, beams, grounded, &inc, &present);
            for (x, y) in stable.iter_mut().zip(st) {
                *x |= y;
            }
        }
    }
    out
}

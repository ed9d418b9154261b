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
    costs_within(joints, beams, grounded, steps, section, load_n, f64::INFINITY).0
}

/// [`costs`] within `budget_work` units of counted work ([`super::plan::WORK_PER_SECOND`] a
/// second: the exact cost's compliance updates and the stability searches): past it nothing
/// more is measured (NaN from the step returned on). A wide frame's compliance grows as the
/// square of its open joints, so this bounds the replay.
pub fn costs_within(
    joints: &[DVec3],
    beams: &[[usize; 2]],
    grounded: &[bool],
    steps: &[Step],
    section: &Section,
    load_n: f64,
    budget_work: f64,
) -> (Vec<Costs>, Option<usize>) {
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
    let mut work = 0.0;
    for (i, s) in steps.iter().enumerate() {
        let (a, b) = (joints[s.from], joints[s.to]);
        let closing = in_frame[s.to];
        if work > budget_work {
            // Past the budget nothing more is measured.
            let none = Costs { exact_mm: f64::NAN, heuristic_mm: f64::NAN, exact_load_mm: f64::NAN, heuristic_load_mm: f64::NAN };
            out.resize(steps.len(), none);
            return (out, Some(i));
        }
        if closing {
            out.push(Costs::default());
            let dofs = 6.0 * flex.live() as f64;
            // The update, and the stability search after it.
            work += 3.0 * dofs * dofs + 4.0 * (joints.len() + beams.len()) as f64;
            flex.connect(s.from, s.to, a, b, section);
        } else {
            let root = if stable[s.from] { RIGID } else { chain[s.from] };
            let heur = frame::extend(&root, a, b, section);
            let uh = frame::displacement(&heur, f);
            let along = f.normalize_or_zero();
            let exact = frame::extend(&flex.get(s.from), a, b, section);
            let ue = frame::displacement(&exact, f);
            out.push(Costs { exact_mm: ue.length(), heuristic_mm: uh.length(), exact_load_mm: ue.dot(along), heuristic_load_mm: uh.dot(along) });
            work += 36.0 * 6.0 * flex.live() as f64;
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
    (out, None)
}

//! The freeform job's method as steps ("How it works"), each drawn by one of its views, each
//! citing Gelber, Hurst and Bhargava, *Freeform Assembly Planning*
//! (`../shared/papers/freeform-assembly-planning.txt`).

use super::StepInfo;

/// The steps, in the method's order.
pub(super) const STEPS: &[StepInfo] = &[
    StepInfo {
        title: "Beams",
        view: "beams",
        index: 0,
        scrub: false,
        text: "The design is joints joined by straight beams, each printed once in free space. The joints on the substrate are grounded; every other joint is held up only by beams printed before it.",
        cite: "Freeform Assembly Planning, §II (Definitions 2.1-2.2), §VI.A; Fig. 1",
    },
    StepInfo {
        title: "Precedences",
        view: "precedence",
        index: 0,
        scrub: false,
        text: "If the nozzle printing beam A would sweep through beam B, A must come first, and a beam waits for the beam that holds its start joint on the path from its root. Every arrow points from a beam to one printed later.",
        cite: "Freeform Assembly Planning, §II.A (collision and connection constraints), Fig. 1; §III, Fig. 6",
    },
    StepInfo {
        title: "Build in order",
        view: "sequence",
        index: 0,
        scrub: true,
        text: "The planner adds the consistent subassembly of least cost at each step, so the largest joint error ε (how far a beam's end joint is pushed by the nozzle's load, from the elastic frame) stays as small as possible. Play prints the beams in order with each step's ε.",
        cite: "Freeform Assembly Planning, §II.B (ε_q, Figs. 4-5); §III (Definition 3.1, Algorithm 2, Fig. 6)",
    },
];

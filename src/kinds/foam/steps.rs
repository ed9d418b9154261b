//! The foam job's method, step by step ("How it works").

use super::StepInfo;

/// Regions, raster, V* and H* along the thread (Nakura et al.).
pub(super) const STEPS: &[StepInfo] = &[
    StepInfo {
        title: "Regions and their shared boundary",
        view: "boundaries",
        index: 0,
        scrub: false,
        text: "The part is split into touching, non-overlapping regions, each with its own V* and H* pair. The face two regions share is where a transition between their pairs is centred.",
        cite: "§3, §3.1.1; Algorithm 1",
    },
    StepInfo {
        title: "One continuous raster",
        view: "layer",
        index: 5,
        scrub: false,
        text: "The union is sliced into layers of one outline each, and every layer is filled by one uninterrupted zig-zag path. Each layer starts where the one below ended, so the thread never stops.",
        cite: "§3.2, §3.2.2 (toolpath refinement)",
    },
    StepInfo {
        title: "V* along the thread",
        view: "v_star",
        index: 5,
        scrub: false,
        text: "The path is cut into short pieces and each takes the V* of its end: its region's own, or a weighted mix across a transition. V* sets the filament per mm and the speed, so a higher V* coils more sparsely.",
        cite: "§3.1.2 equation (1), Algorithm 2, §3.2.4; Fig. 2, Fig. 4",
    },
    StepInfo {
        title: "H* along the thread",
        view: "h_star",
        index: 5,
        scrub: false,
        text: "H* sets how high above the layer the nozzle rides, which changes how the thread coils. It is interpolated between regions just like V*.",
        cite: "§3.1.2 equation (1), §3.2.4 (z offset)",
    },
];

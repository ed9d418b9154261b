//! The axisymmetric job's method, step by step ("How it works").

use super::StepInfo;

/// Platform, Ω, seed, repulsion, path, tool axes (Guzman-Bautista et al. 2025).
pub(super) const STEPS: &[StepInfo] = &[
    StepInfo {
        title: "The build platform",
        view: "axes3d",
        index: 0,
        scrub: false,
        text: "A generatrix of degree-6 Bézier segments is revolved about the Z axis into the curved platform. It must be C³ at the knots, free of cusps and clear of the poles so geodesics are well defined.",
        cite: "§2.1; Fig. 3a (hourglass generatrix), Fig. 4",
    },
    StepInfo {
        title: "Ω on the map",
        view: "omega",
        index: 0,
        scrub: false,
        text: "The region to fill is a domain Ω in the embedded map (θ across, u along the generatrix). Its true area on the surface sets how many points the infill needs.",
        cite: "§2.2, §2.6; Fig. 3b (domain Ω₃)",
    },
    StepInfo {
        title: "Seed points",
        view: "map",
        index: 0,
        scrub: false,
        text: "N = A·ρ_c²/(n²e²) points are scattered over Ω by blue-noise sampling or Euclidean repulsion. The seed is uneven where the platform curves.",
        cite: "§2.2 equation (4), §2.3; Fig. 9 top row",
    },
    StepInfo {
        title: "Geodesic repulsion",
        view: "repulsion",
        index: 0,
        scrub: true,
        text: "Every pair of points repels with energy d⁻ᵐ, d measured along the surface, and each step moves the points down the force until the energy stops falling. Play walks the recorded iterations.",
        cite: "§2.2 equations (1)–(3), §2.3; Fig. 7, Fig. 9 bottom row",
    },
    StepInfo {
        title: "One geodesic path",
        view: "map",
        index: 2,
        scrub: false,
        text: "Nearest neighbour and 2-opt join the points into one path without crossings. Each segment is the geodesic between its two points, so it follows the curved surface.",
        cite: "§2.4, §3.4; Fig. 12",
    },
    StepInfo {
        title: "Tool axes",
        view: "axes3d",
        index: 1,
        scrub: false,
        text: "The path is printed one layer height out from the platform with the tool along the surface normal. The strokes show the axis a 5-axis head or robot must hold at each point.",
        cite: "§1 (robot-based NPAM), §2.4; Fig. 12",
    },
];

//! The graded job's method, step by step ("How it works").

use super::StepInfo;

/// CT slice, HU, ρ, bead width (Grigolato & Savio 2025).
pub(super) const STEPS: &[StepInfo] = &[
    StepInfo {
        title: "A CT slice",
        view: "axial",
        index: 15,
        scrub: false,
        text: "The DICOM series is read into a voxel grid with its spacing and rescale, and any slice of it can be shown. The box is the region of interest the scaffold is cut from.",
        cite: "§2.1.1 (volumetric models)",
    },
    StepInfo {
        title: "Hounsfield units",
        view: "hu",
        index: 5,
        scrub: false,
        text: "Inside the region of interest each voxel holds a Hounsfield unit value. The iso-contours mark the levels, and the surface model is extracted at the isovalue by marching cubes.",
        cite: "§1.1, §2.1.2; Fig. 8 (isocurves at 250, 350, 600 HU), Fig. 9",
    },
    StepInfo {
        title: "Target density ρ",
        view: "density",
        index: 15,
        scrub: false,
        text: "A straight line maps HU to porosity P and the target relative density is ρ = 1 − P. It is clamped below at the density the narrowest bead can print.",
        cite: "§2.3.2, Fig. 6, equation (7)",
    },
    StepInfo {
        title: "Bead width along a layer",
        view: "beads",
        index: 50,
        scrub: false,
        text: "Each infill segment's extrusion is scaled by ρ at its midpoint over the sliced density ρ_s, so the bead widens where the bone is denser. Colours bin the bead width between the allowed narrowest and widest beads.",
        cite: "§2.2.1 equations (1)–(4), Fig. 4; §2.3.3 equation (6)",
    },
];

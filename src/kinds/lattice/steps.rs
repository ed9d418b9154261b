//! The lattice job's method as steps ("How it works"), each drawn by one of its views, each
//! citing the GIPPO paper (`../shared/papers/gippo-lattice-print-paths.txt`; its sections are
//! named, not numbered).

use super::StepInfo;

/// The steps, in the method's order.
pub(super) const STEPS: &[StepInfo] = &[
    StepInfo {
        title: "Pattern",
        view: "layer2d",
        index: 0,
        scrub: false,
        text: "A lattice from the atlas fills the layer's domain with straight struts, one layer at a time.",
        cite: "GIPPO, Materials and Methods, \"Design generation\"; Fig. 1, Table 1",
    },
    StepInfo {
        title: "Graph",
        view: "graph",
        index: 0,
        scrub: false,
        text: "The layer becomes a graph: strut ends are nodes and struts are edges weighted by their length. A node with an odd number of struts is where some path has to start or end.",
        cite: "GIPPO, Materials and Methods, \"Design generation\" (node labels, Fig. 1) and \"Graph-theory-based trajectory optimization\" (graph G)",
    },
    StepInfo {
        title: "Pairing",
        view: "pairing",
        index: 0,
        scrub: false,
        text: "Pairing the odd nodes with the shortest lines shows the fewest paths any method can reach: half the odd nodes of each piece. This lower bound is weft's yardstick, beyond the paper.",
        cite: "Beyond the paper (weft's proven minimum); GIPPO, Discussion, on merging paths that share an end",
    },
    StepInfo {
        title: "GIPPO search",
        view: "gippo",
        index: 0,
        scrub: true,
        text: "Each iteration grows paths from a random unfinished node, always extending towards the farthest unused neighbour, and scores the set by equation 1. Play shows the best set so far each time an iteration beats it.",
        cite: "GIPPO, Algorithm 1 and Equation 1; Fig. 2(i)",
    },
    StepInfo {
        title: "Kept paths",
        view: "trails",
        index: 0,
        scrub: false,
        text: "The best-scoring set is kept and its paths sorted from longest to shortest. The colours split them into long, medium and short paths as the paper counts them.",
        cite: "GIPPO, Algorithm 1 (lines 15-16); Results, \"Algorithm robustness and paths construction\", Fig. 2(ii)",
    },
    StepInfo {
        title: "Print order",
        view: "order",
        index: 0,
        scrub: true,
        text: "The paths are printed one after another, with a travel move from the end of one to the start of the next. Play walks them in print order.",
        cite: "GIPPO, \"Graph-theory-based trajectory optimization\" (paths sorted longest to shortest) and \"Post-processing and 3D printing file generation\"",
    },
    StepInfo {
        title: "G-code",
        view: "gcode",
        index: 0,
        scrub: false,
        text: "The writer turns every path into extruding moves, with the extrusion of equation 4, and prints the short paths slower so they stick.",
        cite: "GIPPO, \"Post-processing and 3D printing file generation\", Equation 4; Discussion (short segments at 60 % speed)",
    },
];

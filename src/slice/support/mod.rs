//! Support under overhangs, for the planar slicer.
//!
//! One file per step:
//! - `areas`: where support goes. A layer's *contact* is the part of it that reaches more
//!   than `h · tan(threshold)` beyond the layer below (less what its bridges span, what a
//!   blocker mesh covers, plus what an enforcer mesh asks for). Contacts are projected down,
//!   `z_gap` below the part, kept `xy_gap` away from it, to the plate or (everywhere) onto
//!   the part; the top `interface_layers` under each contact are the *interface*.
//! - `grid`: the grid style: each support island is walled by one loop (a sheath) and filled
//!   with straight lines on a fixed grid, the same every layer so they stack; the interface
//!   is denser lines that cross the ones below.
//! - `tree`: the tree style: branches from points under each contact that lean towards each
//!   other and merge on their way down, so less material is used than a grid.
//! - `anchor`: every support line is checked against what the layer below printed: a stretch
//!   over air that is not a straight span between two held ends is left out, so support
//!   never prints into air itself.
//!
//! Everything is integer micrometres for areas (i_overlay) and fixed grids for lines, so the
//! same design gives the same support on every target and thread count.

mod anchor;
mod areas;
mod grid;
mod tree;

use crate::geom::DVec2;
use crate::settings::{choice_docs, int, num, other, when, Field, Kind};
use i_overlay::i_shape::int::shape::IntShapes;
use serde::{Deserialize, Serialize};

/// How support is built.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Style {
    /// Straight lines on a fixed grid inside a loop, under the whole overhang.
    #[default]
    Grid,
    /// Branches that merge on their way down (less material, smaller scars).
    Tree,
}

/// Names of the styles as written in a design, in [`Style`] order.
pub const STYLES: &[&str] = &["grid", "tree"];

/// Support settings (`job.slice.support` in a design).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Options {
    /// Generate support. Default false.
    pub enabled: bool,
    /// Grid or tree. Default grid.
    pub style: Style,
    /// Overhangs steeper than this from vertical get support, degrees. Default 55.
    pub threshold_deg: f64,
    /// Only support that stands on the plate (none on top of the part). Default false.
    pub on_plate_only: bool,
    /// Distance between the support's lines, mm. Default 5 (a loop around each island holds the interface's ends, so the lines between can be sparse).
    pub spacing_mm: f64,
    /// Dense layers at the top of the support, under the part. Default 2.
    pub interface_layers: u32,
    /// Gap between the interface's lines, mm. Default 0.2.
    pub interface_spacing_mm: f64,
    /// Air between the top of the support and the part, mm (rounded down to whole layers).
    /// Default 0.2.
    pub z_gap_mm: f64,
    /// Air between the support and the part's sides, mm. Default 0.3.
    pub xy_gap_mm: f64,
    /// Also support overhangs that can be bridged (anchored on two sides). Default false.
    pub support_bridges: bool,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            enabled: false,
            style: Style::Grid,
            threshold_deg: 55.0,
            on_plate_only: false,
            spacing_mm: 5.0,
            interface_layers: 2,
            interface_spacing_mm: 0.2,
            z_gap_mm: 0.2,
            xy_gap_mm: 0.3,
            support_bridges: false,
        }
    }
}

const ON: &str = "support.enabled";

/// Rows of [`Options`] (paths relative to the slice options).
pub const FIELDS: &[Field] = &[
    other("support.enabled", "Support", "Supports", Kind::Bool, &[], "Print support under overhangs so they are not printed into air."),
    when(
        choice_docs(
            other("support.style", "Support", "Support style", Kind::Choice, STYLES, "How the support is built."),
            &[
                "Straight lines inside a loop under the whole overhang: sturdy, easy to predict.",
                "Branches that merge on their way down: less material, smaller marks on the part.",
            ],
        ),
        ON,
        "true",
    ),
    when(
        num(
            "support.threshold_deg",
            "Support",
            "Overhang threshold",
            "°",
            0.0,
            90.0,
            1.0,
            "Overhangs steeper than this from vertical get support (0: every overhang; 90: none but enforced).",
        ),
        ON,
        "true",
    ),
    when(
        other(
            "support.on_plate_only",
            "Support",
            "On the plate only",
            Kind::Bool,
            &[],
            "Only support that stands on the plate: none is built on top of the part.",
        ),
        ON,
        "true",
    ),
    when(
        num("support.spacing_mm", "Support", "Support line spacing", "mm", 0.5, 20.0, 0.1, "Distance between the support's lines: wider uses less material."),
        ON,
        "true",
    ),
    when(
        int("support.interface_layers", "Support", "Interface layers", 0.0, 20.0, "Dense layers at the top of the support that the part rests on."),
        ON,
        "true",
    ),
    when(num("support.interface_spacing_mm", "Support", "Interface gap", "mm", 0.0, 2.0, 0.05, "Gap between the interface's lines: 0 is solid."), ON, "true"),
    when(
        num(
            "support.z_gap_mm",
            "Support",
            "Top gap (Z)",
            "mm",
            0.0,
            2.0,
            0.05,
            "Air between the support's top and the part, so it comes off (rounded down to whole layers).",
        ),
        ON,
        "true",
    ),
    when(num("support.xy_gap_mm", "Support", "Side gap (XY)", "mm", 0.0, 5.0, 0.05, "Air between the support and the part's sides."), ON, "true"),
    when(
        other(
            "support.support_bridges",
            "Support",
            "Support bridges",
            Kind::Bool,
            &[],
            "Also support overhangs held on two sides, which print as bridges without it.",
        ),
        ON,
        "true",
    ),
];

/// The support of one layer, mm polylines in print order within each kind.
#[derive(Clone, Debug, Default)]
pub(crate) struct LayerSupport {
    /// Sparse support (sheaths, lines, branches).
    pub base: Vec<Vec<DVec2>>,
    /// Dense interface lines under the part.
    pub interface: Vec<Vec<DVec2>>,
}

/// What the support generator needs from the slicer, per layer (bottom to top).
pub(crate) struct Input<'a> {
    /// The part's regions, µm.
    pub part: &'a [IntShapes<i32>],
    /// Layer heights, mm.
    pub heights: Vec<f64>,
    /// Areas a bridge spans, per layer (removed from contacts unless `support_bridges`).
    pub bridged: Vec<IntShapes<i32>>,
    /// Regions of enforcer meshes, per layer (empty when none).
    pub enforcers: Vec<IntShapes<i32>>,
    /// Regions of blocker meshes, per layer (empty when none).
    pub blockers: Vec<IntShapes<i32>>,
    /// Line width, µm.
    pub w_um: i32,
    /// Layer height, mm (for the Z gap in layers).
    pub layer_height_mm: f64,
}

/// How many whole layers of air the Z gap leaves.
pub(crate) fn gap_layers(o: &Options, layer_height_mm: f64) -> usize {
    let g = (o.z_gap_mm / layer_height_mm + 1e-6).floor();
    if g.is_finite() && g > 0.0 {
        (g as usize).min(1000)
    } else {
        0
    }
}

/// The support of every layer (empty when support is off or nothing needs it).
pub(crate) fn generate(o: &Options, input: &Input, progress: &mut dyn FnMut(f32)) -> Vec<LayerSupport> {
    let n = input.part.len();
    if !o.enabled || n < 2 {
        return vec![LayerSupport::default(); n];
    }
    let areas = areas::areas(o, input);
    progress(0.4);
    let raw = match o.style {
        Style::Grid => grid::paths(o, input, &areas),
        Style::Tree => tree::paths(o, input, &areas),
    };
    progress(0.8);
    let out = anchor::anchor(input, raw);
    progress(1.0);
    out
}

//! G-code writer: [`Toolpath`] + printer, material and speeds → G-code text.
//!
//! Entry: [`write_gcode`]. Extrusion per segment follows GIPPO equation 4:
//! `E = k · 4 · length · LT · EM · w / (π · f_d²)`, where `w` is the path's width
//! (the nozzle diameter d_n for GIPPO lattices), LT the layer thickness, EM the extrusion
//! multiplier, k the cross-section correction and f_d the filament diameter.

use crate::geom::Toolpath;
use serde::{Deserialize, Serialize};

mod flavor;
pub mod format;
mod template;
mod writer;

pub use template::PLACEHOLDERS;
pub use writer::equation4_e;

/// G-code dialects.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Flavor {
    /// Marlin (and Klipper/RepRapFirmware, which read the same subset).
    Marlin,
}

/// Where the printer's X = Y = 0 is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Origin {
    /// Front-left corner of the bed (Cartesian printers): parts are centred on the bed.
    Corner,
    /// Centre of the bed (delta printers): parts are centred on 0, 0.
    Center,
}

/// Retraction settings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Retraction {
    /// Filament pulled back before a travel, mm. 0 disables retraction. Default 0.8.
    pub length_mm: f64,
    /// Retract and unretract speed, mm/s. Default 35.
    pub speed_mm_s: f64,
    /// Nozzle lift during retracted travels, mm. Default 0.
    pub z_hop_mm: f64,
    /// Travels shorter than this are not retracted, mm. Default 1.
    pub min_travel_mm: f64,
}

impl Default for Retraction {
    fn default() -> Self {
        Retraction { length_mm: 0.8, speed_mm_s: 35.0, z_hop_mm: 0.0, min_travel_mm: 1.0 }
    }
}

/// The machine.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Printer {
    /// Profile name, shown in the G-code header.
    pub name: String,
    /// Printable volume X, Y, Z in mm. Default 220 × 220 × 250.
    pub bed_size_mm: [f64; 3],
    /// Where X = Y = 0 is. Default corner.
    pub origin: Origin,
    /// Nozzle diameter d_n, mm. Default 0.4.
    pub nozzle_diameter_mm: f64,
    /// Filament diameter f_d, mm. Default 1.75.
    pub filament_diameter_mm: f64,
    /// G-code dialect. Default marlin.
    pub flavor: Flavor,
    /// Relative extrusion (M83) instead of absolute (M82). Default false.
    pub relative_e: bool,
    /// Retraction.
    pub retraction: Retraction,
    /// Travel speed, mm/s. Default 150.
    pub travel_speed_mm_s: f64,
    /// Z move speed, mm/s. Default 10.
    pub z_speed_mm_s: f64,
    /// Acceleration used for time estimates, mm/s². Default 1000.
    pub acceleration_mm_s2: f64,
    /// Start G-code. Placeholders: {nozzle_temp_c} {first_layer_nozzle_temp_c} {bed_temp_c}
    /// {bed_x_mm} {bed_y_mm} {fan_pwm} {design_name}.
    pub start_gcode: String,
    /// End G-code, same placeholders.
    pub end_gcode: String,
}

/// Default start G-code (Marlin).
pub const DEFAULT_START_GCODE: &str = "M140 S{bed_temp_c} ; bed\nM104 S{first_layer_nozzle_temp_c} ; nozzle\nG28 ; home\nM190 S{bed_temp_c}\nM109 S{first_layer_nozzle_temp_c}\nG92 E0\n";
/// Default end G-code (Marlin).
pub const DEFAULT_END_GCODE: &str = "M107 ; fan off\nM104 S0\nM140 S0\nG91\nG1 Z5 F600\nG90\nM84 ; motors off\n";

impl Default for Printer {
    fn default() -> Self {
        Printer {
            name: "Generic Marlin 220 × 220".into(),
            bed_size_mm: [220.0, 220.0, 250.0],
            origin: Origin::Corner,
            nozzle_diameter_mm: 0.4,
            filament_diameter_mm: 1.75,
            flavor: Flavor::Marlin,
            relative_e: false,
            retraction: Retraction::default(),
            travel_speed_mm_s: 150.0,
            z_speed_mm_s: 10.0,
            acceleration_mm_s2: 1000.0,
            start_gcode: DEFAULT_START_GCODE.into(),
            end_gcode: DEFAULT_END_GCODE.into(),
        }
    }
}

/// The material and its extrusion factors.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Material {
    /// Material name.
    pub name: String,
    /// Nozzle temperature, °C. Default 210.
    pub nozzle_temp_c: f64,
    /// First-layer nozzle temperature, °C. Default 215.
    pub first_layer_nozzle_temp_c: f64,
    /// Bed temperature, °C. Default 60.
    pub bed_temp_c: f64,
    /// Part fan, percent, from `fan_start_layer` on. Default 100.
    pub fan_percent: f64,
    /// First layer (0-based) with the fan on. Default 1.
    pub fan_start_layer: u32,
    /// Extrusion multiplier EM (equation 4). Default 1.
    pub extrusion_multiplier: f64,
    /// Cross-section correction k (equation 4). Default 1.
    pub k: f64,
}

impl Default for Material {
    fn default() -> Self {
        Material {
            name: "PLA".into(),
            nozzle_temp_c: 210.0,
            first_layer_nozzle_temp_c: 215.0,
            bed_temp_c: 60.0,
            fan_percent: 100.0,
            fan_start_layer: 1,
            extrusion_multiplier: 1.0,
            k: 1.0,
        }
    }
}

/// Print speeds per feature, mm/s.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Speeds {
    /// Outer perimeter. Default 30.
    pub external_perimeter_mm_s: f64,
    /// Inner perimeters. Default 45.
    pub perimeter_mm_s: f64,
    /// Sparse infill. Default 60.
    pub infill_mm_s: f64,
    /// Solid infill. Default 45.
    pub solid_infill_mm_s: f64,
    /// Lattice struts, contours and handles. Default 20.
    pub lattice_mm_s: f64,
    /// Every feature on the first layer. Default 20.
    pub first_layer_mm_s: f64,
}

impl Default for Speeds {
    fn default() -> Self {
        Speeds {
            external_perimeter_mm_s: 30.0,
            perimeter_mm_s: 45.0,
            infill_mm_s: 60.0,
            solid_infill_mm_s: 45.0,
            lattice_mm_s: 20.0,
            first_layer_mm_s: 20.0,
        }
    }
}

/// Everything the writer needs.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Options {
    /// The machine.
    pub printer: Printer,
    /// The material.
    pub material: Material,
    /// Speeds.
    pub speeds: Speeds,
    /// Design name, written into the header.
    pub design_name: String,
}

/// What the writer produced.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct GcodeStats {
    /// Layers written.
    pub layers: usize,
    /// Extruded path length, mm.
    pub extruded_mm: f64,
    /// Filament used, mm.
    pub filament_mm: f64,
    /// Travel length, mm.
    pub travel_mm: f64,
    /// Retractions.
    pub retractions: usize,
    /// Estimated print time, s.
    pub estimated_time_s: f64,
}

/// The G-code and its statistics.
#[derive(Clone, Debug, Default)]
pub struct Gcode {
    /// The file's text.
    pub text: String,
    /// Totals, also written in the header.
    pub stats: GcodeStats,
}

/// Why no G-code could be written.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum Error {
    /// Part does not fit the printer.
    #[error("the part spans {size_mm:?} mm but the bed is {bed_mm:?} mm; scale it down or pick a larger printer")]
    OutsideBed {
        /// Part size X, Y, Z.
        size_mm: [f64; 3],
        /// Bed size X, Y, Z.
        bed_mm: [f64; 3],
    },
    /// A template names a placeholder the writer does not know.
    #[error("{template}: unknown placeholder {{{name}}}; use one of {known}")]
    UnknownPlaceholder {
        /// start_gcode or end_gcode.
        template: &'static str,
        /// The placeholder.
        name: String,
        /// The known ones.
        known: String,
    },
    /// Nothing to print.
    #[error("the toolpath is empty: nothing to print; check that the part is not below the first layer height")]
    Empty,
}

/// Writes `toolpath` as G-code.
///
/// Layout: a comment header with totals (PrusaSlicer and Cura styles), the start template,
/// `G90`, `M82`/`M83` (after `G90`, which resets the E mode in Marlin), `G92 E0`,
/// `M204 S<acceleration>`, then per layer `;LAYER_CHANGE`, `;Z:`, `;HEIGHT:`, `;LAYER:<n>`
/// (0-based, counting only layers with paths), the fan (`M106`) on `fan_start_layer` and
/// `M104 S<nozzle_temp>` on layer 1. Each path: a travel to its first point (retracting when
/// the XY travel is at least `min_travel_mm`, with optional z-hop; no travel when the path
/// starts where the previous one ended), `;TYPE:` and `;WIDTH:` when they change within the
/// layer (both are repeated on every layer), then one `G1 X Y [Z] E [F]` per segment
/// (zero-length segments are skipped; F only when it changes). E follows equation 4 with
/// the layer's height as LT and the path's width as d_n; in absolute mode the printed E is
/// the exact running sum rounded to 5 decimals, so rounding never drifts. A final retraction
/// precedes the end template. Coordinates are in printer space: with [`Origin::Corner`] the
/// model (centred on 0, 0) is shifted to the bed centre.
///
/// [`GcodeStats::extruded_mm`] and [`GcodeStats::filament_mm`] are the writer's exact sums;
/// `travel_mm` and `estimated_time_s` come from running [`crate::analyze::analyze`] on the
/// produced text (so they include moves of the start and end templates and agree with
/// `weft analyze`).
///
/// Numbers are formatted with integer arithmetic (X/Y/Z 3 decimals, E 5, F whole mm/min,
/// trailing zeros trimmed, never `-0`), so output is byte-identical on native and wasm.
/// Options are expected to be physically sensible (positive diameters, speeds and heights);
/// a non-finite number would be written as `0`.
pub fn write_gcode(toolpath: &Toolpath, options: &Options) -> Result<Gcode, Error> {
    writer::write(toolpath, options)
}

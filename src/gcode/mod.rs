//! G-code writer: [`Toolpath`] + printer, material and speeds → G-code text.
//!
//! Entry: [`write_gcode`]. Extrusion per segment follows GIPPO equation 4:
//! `E = k · 4 · length · LT · EM · w / (π · f_d²)`, where `w` is the path's width
//! (the nozzle diameter d_n for GIPPO lattices), LT the layer thickness, EM the extrusion
//! multiplier, k the cross-section correction and f_d the filament diameter.

use crate::geom::Toolpath;
use crate::machine::Machine;
use crate::settings::{self, int, max_len, num, other, points, vec3, when, Field, Kind};
use serde::{Deserialize, Serialize};

pub mod arcs;
pub mod bgcode;
pub mod binary;
mod flavor;
pub mod format;
pub mod meta;
pub mod objects;
mod out;
mod poses;
pub mod presets;
mod template;
pub mod thumbs;
mod writer;
pub use writer::MIN_MOVE_MM;

pub use meta::{is_date, utc_date};
pub use poses::POSES_CSV_HEADER;
pub use template::{expand as expand_template, MAX_EXPANDED_BYTES, MAX_TEMPLATE_BYTES, PLACEHOLDERS};
pub use writer::{bed_offset, equation4_e};

/// G-code dialects.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Flavor {
    /// Marlin (and Klipper/RepRapFirmware, which read the same subset).
    Marlin,
    /// Pneumatic extrusion (`.nc` files for CNC-style bioprinters such as the GIPPO paper's
    /// Bioscaffolder): no E axis; each path opens a valve ([`Pneumatic::valve_on`]) and closes
    /// it ([`Pneumatic::valve_off`]); the pressure is set per path
    /// ([`Pneumatic::pressure_template`]). Set [`Printer::pneumatic`] to your machine's codes.
    Pneumatic,
    /// Not G-code: a CSV of tool poses for a robot or another CAM (`.csv`). A header line
    /// `x,y,z,nx,ny,nz`, then one row per point of every path in print order: the nozzle tip
    /// in printer coordinates (mm, 3 decimals) and the unit tool axis (7 decimals); a blank
    /// line separates paths (CSV readers skip it). It is a flavour rather than a machine
    /// output because it replaces the whole file and needs no kinematics: poses are written
    /// as planned, whatever [`Printer::machine`] says (no 3-axis check, no machine limits).
    PosesCsv,
}

impl Flavor {
    /// File name extension of the output, without the dot: `gcode` (Marlin), `nc`
    /// (pneumatic) or `csv` (poses).
    pub fn file_extension(self) -> &'static str {
        match self {
            Flavor::Marlin => "gcode",
            Flavor::Pneumatic => "nc",
            Flavor::PosesCsv => "csv",
        }
    }

    /// Name written in the `;FLAVOR:` header line.
    pub fn name(self) -> &'static str {
        match self {
            Flavor::Marlin => "Marlin",
            Flavor::Pneumatic => "Pneumatic",
            Flavor::PosesCsv => "PosesCSV",
        }
    }
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
    /// Valve and pressure codes of the pneumatic flavour (ignored by Marlin).
    pub pneumatic: Pneumatic,
    /// Kinematics and limits: cartesian (default; left out of the JSON when default, so
    /// existing designs read and write as before) or five-axis. JSON:
    /// `{"kind": "five_axis", "layout": "head_head" | "table_table", "rotary_axes": "ab" | "bc",
    /// "axis_output": "rotary" | "ijk", "pivot_mm": 0, "table_center_mm": [110, 110, 0],
    /// "rotary_min_deg": [-120, -120, -36000], "rotary_max_deg": [120, 120, 36000],
    /// "travel_min_mm": [x, y, z], "travel_max_mm": [x, y, z]}` (every field optional; see
    /// [`crate::machine`] for the conventions).
    #[serde(skip_serializing_if = "is_default_machine")]
    pub machine: Machine,
    /// Printer model as the printer's firmware names it (`MK4`, `MK4S`, `XL`, `MINI`), written
    /// as `printer_model` so a Prusa printer can warn about a file sliced for another machine;
    /// empty: not written. Default empty.
    pub model: String,
    /// PNG thumbnails written into the file, width × height px each (PrusaSlicer's
    /// `; thumbnail begin` blocks, which Moonraker, OctoPrint and printer screens show); none:
    /// no thumbnail. Marlin flavour only. Default 32 × 32 and 300 × 300 (Klipper screens).
    pub thumbnails: Vec<[u32; 2]>,
    /// QOI thumbnails, width × height px each (`; thumbnail_QOI begin` blocks): the format
    /// Prusa's xBuddy screens (MK4, XL, MINI, firmware 5.1 on) read; hosts show the PNG ones.
    /// Marlin flavour only. Default none.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub thumbnails_qoi: Vec<[u32; 2]>,
    /// Object labels, so a failed part can be cancelled mid-print. Marlin flavour only.
    /// Default m486.
    pub object_labels: ObjectLabels,
    /// Arc fitting: perimeters and curved paths within this distance of circular arcs are
    /// written as `G2`/`G3`, mm; 0: straight segments only. Default 0 (off).
    pub arc_tolerance_mm: f64,
    /// Write Prusa binary G-code (`.bgcode`) instead of text: the page's download and send,
    /// `weft run` without `--out`. Default false.
    pub binary_gcode: bool,
    /// The print host the page's Send offers first (the address and key stay in the
    /// browser). Default none.
    pub host: HostKind,
}

/// How objects are labelled in the G-code ([`Printer::object_labels`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ObjectLabels {
    /// No labels.
    None,
    /// Marlin and Prusa firmware, RepRapFirmware: `M486 T<count>`, `M486 S<i> A"name"`,
    /// `M486 S-1`.
    #[default]
    M486,
    /// Klipper: `EXCLUDE_OBJECT_DEFINE NAME= CENTER= POLYGON=`, `EXCLUDE_OBJECT_START`,
    /// `EXCLUDE_OBJECT_END`.
    ExcludeObject,
}

/// A print host kind ([`Printer::host`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum HostKind {
    /// None chosen.
    #[default]
    None,
    /// Moonraker (Klipper; Mainsail and Fluidd talk to it).
    Moonraker,
    /// OctoPrint.
    Octoprint,
}

/// Default thumbnail sizes, px.
pub const DEFAULT_THUMBNAILS: [[u32; 2]; 2] = [[32, 32], [300, 300]];
/// Largest thumbnail side, px.
pub const MAX_THUMBNAIL_PX: u32 = 800;
/// Most thumbnails a printer writes.
pub const MAX_THUMBNAILS: usize = 4;

fn is_default_machine(m: &Machine) -> bool {
    *m == Machine::default()
}

/// Machine codes of the pneumatic flavour ([`Flavor::Pneumatic`]). Controllers differ: these
/// defaults are placeholders in the style of CNC controllers; set the codes of your machine.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Pneumatic {
    /// Line(s) written before the first move of each path to start the flow. Default `M3`
    /// (spindle on: the output CNC controllers usually switch a dispenser relay with).
    pub valve_on: String,
    /// Line(s) written after each path to stop the flow. Default `M5` (spindle off).
    pub valve_off: String,
    /// Line written before a path whose pressure differs from the last one written;
    /// `{pressure_kpa}` is replaced by the pressure in kPa (up to 3 decimals). Empty: no
    /// pressure line. Default `; pressure {pressure_kpa} kPa` (a comment: put your machine's
    /// pressure code here, e.g. `M9 P{pressure_kpa}`).
    pub pressure_template: String,
    /// Extrusion pressure, kPa. Default 300.
    pub pressure_kpa: f64,
    /// Multiplies the pressure of short paths (those the optimiser slowed down: speed factor
    /// below 1). Default 1.
    pub short_path_pressure_factor: f64,
}

impl Default for Pneumatic {
    fn default() -> Self {
        Pneumatic {
            valve_on: "M3".into(),
            valve_off: "M5".into(),
            pressure_template: "; pressure {pressure_kpa} kPa".into(),
            pressure_kpa: 300.0,
            short_path_pressure_factor: 1.0,
        }
    }
}

/// Extra material at path ends (GIPPO's "pre-flow" and "post-flow"). All default to 0, which
/// writes nothing.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Flow {
    /// Marlin: filament pushed at the start of every path, after the travel (and unretract),
    /// before the first move: `G1 E<+pre_flow_mm>` at the retraction speed, mm. Default 0.
    pub pre_flow_mm: f64,
    /// Marlin: filament pushed at the end of every path, without motion, before the next
    /// retraction: `G1 E<+post_flow_mm>` at the retraction speed, mm. Default 0.
    pub post_flow_mm: f64,
    /// Pneumatic: dwell after opening the valve, before the first move (`G4 P<ms>`), so the
    /// flow is established when the nozzle starts moving, s. Default 0.
    pub pre_flow_s: f64,
    /// Pneumatic: the valve closes this long (at the path's speed) before the path's end and
    /// the nozzle finishes the path with the valve closed (the residual pressure keeps the
    /// material flowing, so the end does not blob), s. Longer than the path: the valve closes
    /// right after the pre-flow. Default 0.
    pub post_flow_s: f64,
}

/// Default start G-code (Marlin).
pub const DEFAULT_START_GCODE: &str =
    "M140 S{bed_temp_c} ; bed\nM104 S{first_layer_nozzle_temp_c} ; nozzle\nG28 ; home\nM190 S{bed_temp_c}\nM109 S{first_layer_nozzle_temp_c}\nG92 E0\n";
/// Default end G-code (Marlin).
pub const DEFAULT_END_GCODE: &str = "M107 ; fan off\nM104 S0\nM140 S0\nG91\nG1 Z5 F600\nG90\nM84 ; motors off\n";
/// Start code of the pneumatic flavour, written instead of [`DEFAULT_START_GCODE`] when the
/// flavour is pneumatic and `start_gcode` is left at the Marlin default.
pub const DEFAULT_PNEUMATIC_START_GCODE: &str = "G28 ; home\n";
/// End code of the pneumatic flavour, written instead of [`DEFAULT_END_GCODE`] when the
/// flavour is pneumatic and `end_gcode` is left at the Marlin default.
pub const DEFAULT_PNEUMATIC_END_GCODE: &str = "G91\nG0 Z5 F600\nG90\nM2 ; end of program\n";

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
            pneumatic: Pneumatic::default(),
            machine: Machine::default(),
            model: String::new(),
            thumbnails: DEFAULT_THUMBNAILS.to_vec(),
            thumbnails_qoi: Vec::new(),
            object_labels: ObjectLabels::default(),
            arc_tolerance_mm: 0.0,
            binary_gcode: false,
            host: HostKind::None,
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
    /// Pre-flow and post-flow (default: none).
    pub flow: Flow,
    /// Density, g/cm³, for the filament weight hosts show. Default 1.24 (PLA).
    pub density_g_cm3: f64,
    /// Part fan on bridges and overhanging perimeters, percent (0: as the rest). Default 100.
    pub bridge_fan_percent: f64,
    /// Multiplies a bridge's filament: a round strand of the line width. Default 1.
    pub bridge_flow: f64,
    /// Expected die swell ratio B = D_extrudate / D_nozzle: the strand leaving the nozzle
    /// swells by elastic recovery of the melt (GIPPO, Discussion), so a strut prints about
    /// B × the nominal width. A user-entered number, [`MIN_SWELL_RATIO`]–[`MAX_SWELL_RATIO`];
    /// default [`DEFAULT_SWELL_RATIO`] (no swell). Typical values: 1.13 for a Newtonian
    /// liquid leaving a long capillary (Tanner 1970, GIPPO ref. 30); viscoelastic melts swell
    /// more, elastic ones (TPU) more than stiff ones, growing with shear rate (Colon et al.
    /// 2023, GIPPO ref. 31, estimate it from printing parameters and rheology). Shown as the
    /// lattice report's predicted strut width; changes the G-code only with `compensate_swell`.
    pub swell_ratio: f64,
    /// Use the predicted width in equation 4: with it on, every extruding segment without
    /// per-point flow gets `E = k·4·L·LT·EM·(B·w) / (π f_d²)`, i.e. B × the nominal E (w is
    /// the path's width, the nozzle diameter for lattices); travel, retraction, pre/post-flow,
    /// per-point flow and the `;WIDTH` comments do not change. Default false.
    pub compensate_swell: bool,
}

/// Default die swell ratio (none).
pub const DEFAULT_SWELL_RATIO: f64 = 1.0;
/// Smallest die swell ratio (a strand narrower than the nozzle is not swell).
pub const MIN_SWELL_RATIO: f64 = 1.0;
/// Largest die swell ratio (polymer melts rarely exceed 2–3).
pub const MAX_SWELL_RATIO: f64 = 3.0;
/// Default for [`Material::compensate_swell`].
pub const DEFAULT_COMPENSATE_SWELL: bool = false;

impl Material {
    /// The printed strand width predicted from a nominal width `w` mm: B × w.
    pub fn swollen_width(&self, w: f64) -> f64 {
        self.swell_ratio * w
    }
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
            flow: Flow::default(),
            density_g_cm3: 1.24,
            bridge_fan_percent: 100.0,
            bridge_flow: 1.0,
            swell_ratio: DEFAULT_SWELL_RATIO,
            compensate_swell: DEFAULT_COMPENSATE_SWELL,
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
    /// Support and its interface. Default 50.
    pub support_mm_s: f64,
    /// Bridges (lines across air). Default 25.
    pub bridge_mm_s: f64,
    /// Perimeters overhanging more than half their width. Default 15.
    pub overhang_mm_s: f64,
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
            support_mm_s: 50.0,
            bridge_mm_s: 25.0,
            overhang_mm_s: 15.0,
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
    /// When the design was made, `YYYY-MM-DD HH:MM:SS` (UTC), written into the header's
    /// `; generated by` line (hosts read the slicer from it); empty: `1970-01-01 00:00:00`.
    pub date: String,
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
    /// Extruding moves shorter than [`MIN_MOVE_MM`] merged into their neighbours.
    pub merged_moves: usize,
    /// Whole paths shorter than [`MIN_MOVE_MM`] left out (with their travel and retraction).
    pub dropped_paths: usize,
    /// The filament those paths would have used, mm.
    pub dropped_filament_mm: f64,
    /// Arc moves (`G2`/`G3`) written ([`Printer::arc_tolerance_mm`]).
    pub arcs: usize,
    /// Bytes the arcs saved against the same file with straight segments only (set by the
    /// pipeline, which writes both; 0 without arcs).
    pub arc_bytes_saved: i64,
}

/// The G-code and its statistics.
#[derive(Clone, Debug, Default)]
pub struct Gcode {
    /// The file's text.
    pub text: String,
    /// Totals, also written in the header.
    pub stats: GcodeStats,
    /// Bytes of the header (totals, flavour): `text[header_len..]` is the same for any two
    /// toolpaths up to where their passes differ.
    pub header_len: usize,
    /// Where the moves end and the dialect's epilogue and the end template begin:
    /// `text[..moves_end]` is a file a printer can start on while more moves are made.
    pub moves_end: usize,
    /// Bytes of the footer (the `; key = value` lines hosts read) at the end of `text`.
    pub footer_len: usize,
}

impl Gcode {
    /// The file without its footer: header, start code, moves and end code.
    pub fn body(&self) -> &str {
        &self.text[..self.text.len() - self.footer_len]
    }
}

/// Why no G-code could be written.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum Error {
    /// Part does not fit the printer.
    #[error("{}", outside_bed_message(size_mm, bed_mm, *below_plate_mm))]
    OutsideBed {
        /// Part size X, Y, Z.
        size_mm: [f64; 3],
        /// Bed size X, Y, Z.
        bed_mm: [f64; 3],
        /// How far the lowest point is below the plate (Z < 0), mm; 0 when it is not.
        below_plate_mm: f64,
    },
    /// The G-code would be too big (stated before writing).
    #[error(transparent)]
    TooBig(#[from] crate::budget::OverBudget),
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
    /// A start or end template over [`MAX_TEMPLATE_BYTES`].
    #[error(
        "printer.{template}: the template is {bytes} bytes, over the limit of {limit} bytes; shorten it (start and end codes are normally a few dozen lines)"
    )]
    TemplateTooLong {
        /// start_gcode or end_gcode.
        template: &'static str,
        /// Its length.
        bytes: usize,
        /// [`MAX_TEMPLATE_BYTES`].
        limit: usize,
    },
    /// A template whose placeholders expand beyond [`MAX_EXPANDED_BYTES`].
    #[error("printer.{template}: the template expands to {bytes} bytes, over the limit of {limit} bytes; use fewer placeholders (each {{design_name}} writes the whole design name) or a shorter design name")]
    TemplateTooLarge {
        /// start_gcode or end_gcode.
        template: &'static str,
        /// Size of the expansion.
        bytes: usize,
        /// [`MAX_EXPANDED_BYTES`].
        limit: usize,
    },
    /// Nothing to print.
    #[error("the toolpath is empty: nothing to print; check that the part is not below the first layer height")]
    Empty,
    /// A path's per-point data cannot be written.
    #[error("pass {pass}, path {path}: per-point data is unusable: {}; the toolpath generator must give one finite, non-negative value per point (positive feeds, unit tool axes)", problems.join("; "))]
    BadPointData {
        /// Pass index (0-based, in the toolpath).
        pass: usize,
        /// Path index within the pass.
        path: usize,
        /// What is wrong ([`crate::geom::PointData::problems`]).
        problems: Vec<String>,
    },
    /// A tilted tool axis on a 3-axis printer.
    #[error("pass {pass}, path {path}, point {point}: the tool axis ({:.4}, {:.4}, {:.4}) is not vertical, but this printer is 3-axis (printer.machine.kind = cartesian); pick a 5-axis machine (printer.machine.kind = five_axis) or plan vertical tool axes", axis[0], axis[1], axis[2])]
    NeedsFiveAxis {
        /// Pass index.
        pass: usize,
        /// Path index within the pass.
        path: usize,
        /// Point index within the path.
        point: usize,
        /// The tool axis.
        axis: [f64; 3],
    },
    /// A machine axis would leave its travel or rotary range.
    #[error("pass {pass}, path {path}, point {point}: machine axis {axis} would reach {value:.3} {unit}, beyond its {} limit {limit} {unit} ({setting}); {fix}", if *above { "upper" } else { "lower" })]
    MachineLimit {
        /// Pass index.
        pass: usize,
        /// Path index within the pass.
        path: usize,
        /// Point index within the path (approach-route points count after the path's points).
        point: usize,
        /// The axis letter (`X` … `C`).
        axis: char,
        /// The value it would reach, machine coordinates (mm or degrees).
        value: f64,
        /// The limit.
        limit: f64,
        /// Whether the upper limit is exceeded (else the lower).
        above: bool,
        /// `mm` or `°`.
        unit: &'static str,
        /// The setting holding the limit.
        setting: &'static str,
        /// What to change.
        fix: &'static str,
    },
}

fn outside_bed_message(size: &[f64; 3], bed: &[f64; 3], below: f64) -> String {
    if below > 0.0 {
        return format!(
            "the print reaches {below:.2} mm below the plate (Z < 0); raise it (for a non-planar surface, move the surface up so its printed part lies above Z = 0)"
        );
    }
    format!(
        "the print spans {:.2} × {:.2} × {:.2} mm but the printer reaches {:.0} × {:.0} × {:.0} mm; scale it down or pick a larger printer",
        size[0], size[1], size[2], bed[0], bed[1], bed[2]
    )
}

/// Largest G-code file the writer makes, bytes (256 MiB). The text is held in memory twice
/// on the page (wasm and the download's copy) and read back by the analyzer, whose own
/// memory grows with it; PrusaSlicer's largest everyday files are around 100 MB.
pub const MAX_GCODE_BYTES: f64 = 256.0 * crate::budget::MIB;
/// G-code bytes per toolpath segment: a `G1 X… Y… E…` line (about 27 bytes) plus each
/// segment's share of travels, retractions and layer comments (measured on the examples:
/// 24–33).
pub(crate) const GCODE_BYTES_PER_SEGMENT: f64 = 30.0;
/// Writer time per segment on the reference machine, s (`cargo run --release --example
/// slice_bench`: 0.11 µs on the 1M-triangle sphere, 0.3–0.4 µs on solid cubes).
const SECONDS_PER_SEGMENT: f64 = 0.3e-6;

/// The writer's work for a toolpath of `segments` segments (extrusions, travels and approach
/// points): G-code bytes, peak memory (the text, grown by doubling) and time; refused over
/// [`MAX_GCODE_BYTES`].
pub fn estimate(segments: f64, options: &Options) -> crate::budget::Estimate {
    let templates = (options.printer.start_gcode.len() + options.printer.end_gcode.len()) as f64;
    let gcode = segments * GCODE_BYTES_PER_SEGMENT + templates + 2048.0;
    crate::budget::Estimate::new("gcode")
        .quantity("segments", "Toolpath segments", segments, "")
        .quantity("gcode_bytes", "G-code", gcode, "bytes")
        .cost(2.0 * gcode, segments * SECONDS_PER_SEGMENT)
        .limit("the G-code", gcode, MAX_GCODE_BYTES, "bytes", "print fewer or thicker layers, less infill, or a smaller part")
        .budgets("print fewer or thicker layers, less infill, or a smaller part")
}

/// Segments the writer gets from `toolpath`: path segments plus approach points (travels).
pub fn segments(toolpath: &Toolpath) -> usize {
    toolpath.passes.iter().flat_map(|l| &l.paths).map(|p| p.points.len().saturating_sub(1) + p.approach.as_ref().map_or(0, Vec::len) + 1).sum()
}

/// Checks that a part of `size_mm` (X, Y, Z), centred on the plate and standing on it, fits
/// `printer`'s bed: jobs call it before slicing, so a part too big is refused with its real
/// size before any work (the writer checks the toolpath itself again).
pub fn check_fits(size_mm: [f64; 3], printer: &Printer) -> Result<(), Error> {
    let bed = printer.bed_size_mm;
    let eps = 1e-6;
    let fits = size_mm.iter().all(|v| v.is_finite()) && (0..3).all(|k| size_mm[k] <= bed[k] + eps);
    if fits {
        Ok(())
    } else {
        Err(Error::OutsideBed { size_mm, bed_mm: bed, below_plate_mm: 0.0 })
    }
}

/// Retractions the writer makes for each pass of `toolpath` on `printer` (the same rule as
/// [`write_gcode`]: a path reached by a free travel — no strut route, or the very first path
/// — retracts when the travel's XY length is at least `retraction.min_travel_mm`, never on
/// the first travel of the file, never with `retraction.length_mm` 0, never for the
/// pneumatic and poses flavours; measured on the tool tip; slivers the writer leaves out are
/// left out here too). The final retraction before the end template is not counted in any
/// pass.
pub fn retractions_per_pass(toolpath: &Toolpath, printer: &Printer) -> Vec<usize> {
    let r = &printer.retraction;
    let on = r.length_mm > 0.0 && printer.flavor == Flavor::Marlin;
    let mut pos: Option<crate::geom::DVec3> = None;
    toolpath
        .passes
        .iter()
        .map(|pass| {
            let mut n = 0;
            for path in pass.paths.iter().filter(|p| p.points.len() >= 2 && !writer::is_sliver(p)) {
                let to = path.points[0];
                if let Some(from) = pos {
                    let dxy = ((to.x - from.x) * (to.x - from.x) + (to.y - from.y) * (to.y - from.y)).sqrt();
                    if on && path.approach.is_none() && dxy > 1e-9 && dxy >= r.min_travel_mm {
                        n += 1;
                    }
                }
                pos = Some(*path.points.last().expect("two points"));
            }
            n
        })
        .collect()
}

/// Writes `toolpath` as G-code.
///
/// Layout: a comment header with totals (PrusaSlicer and Cura styles), the start template,
/// `G90`, `M82`/`M83` (after `G90`, which resets the E mode in Marlin), `G92 E0`,
/// `M204 S<acceleration>`, then per layer `;LAYER_CHANGE`, `;Z:`, `;HEIGHT:`, `;LAYER:<n>`
/// (0-based, counting only layers with paths), the fan (`M106`) on `fan_start_layer` and
/// `M104 S<nozzle_temp>` on layer 1. Each path: a travel to its first point (retracting when
/// the XY travel is at least `min_travel_mm`, with optional z-hop; no travel when the path
/// starts where the previous one ended) or, when the path has an
/// [`approach`](crate::geom::Path::approach) route, `G1 X Y [Z] F<travel>` moves without E
/// through the route to its first point (no retraction, no hop; the analyzer counts them as
/// travel), `;TYPE:` and `;WIDTH:` when they change within the
/// layer (both are repeated on every layer), the pre-flow (`G1 E`, see [`Flow`]), then one
/// `G1 X Y [Z] E [F]` per segment at the feature's speed times the path's `speed_factor`
/// (zero-length segments are skipped; F only when it changes), then the post-flow. E follows equation 4 with
/// the layer's height as LT and the path's width as d_n; in absolute mode the printed E is
/// the exact running sum rounded to 5 decimals, so rounding never drifts. A final retraction
/// precedes the end template. Coordinates are in printer space: with [`Origin::Corner`] the
/// model (centred on 0, 0) is shifted to the bed centre.
///
/// [`GcodeStats::extruded_mm`] and [`GcodeStats::filament_mm`] are the writer's exact sums;
/// `travel_mm` and `estimated_time_s` are the writer's own moves (numbers as printed) and the
/// start/end templates (read with the analyzer's lexer) timed with the model it shares with
/// the analyzer ([`crate::motion`]), so they equal `weft analyze` to the bit (0 when a user
/// code makes the file unreadable to the analyzer).
///
/// Passes: first-layer speed and temperature and the fan's `fan_start_layer` count only
/// [`PassKind::Layer`](crate::geom::PassKind) passes; a free pass never gets first-layer
/// rules (`M104 S<nozzle_temp>` and the fan come before the first free pass if not yet
/// written). Per-point data ([`crate::geom::PointData`]): flow per segment as
/// `k · EM · length · area / (π f_d² / 4)` (area) or `value · length` (filament per mm), a
/// per-segment feed instead of the feature speed × speed factor, `G4 P<ms>` after a point with
/// a dwell (after reaching the first point for entry 0); unusable data →
/// [`Error::BadPointData`]. Tool axes: a cartesian machine accepts only +Z
/// ([`Error::NeedsFiveAxis`]); a 5-axis machine ([`Printer::machine`]) writes rotary words
/// (5 decimals, X Y Z in machine coordinates) or `I J K` (7 decimals, X Y Z of the tip) on
/// every motion line where they change, after checking travel and rotary limits in machine
/// coordinates ([`Error::MachineLimit`]). [`Flavor::PosesCsv`] writes a CSV instead.
///
/// [`Flavor::Pneumatic`] writes the same layout without E: `G21`/`G90` instead of the E
/// modes, `G0` travels (lifted by `z_hop_mm` when at least `min_travel_mm` long, no
/// retraction), and per path the pressure line (when it changes), the valve-on code, the
/// pre-flow dwell `G4 P<ms>`, `G1 X Y [Z] [F]` moves and the valve-off code (written
/// `post_flow_s` before the path's end; the rest of the path follows with the valve closed).
/// With the default (Marlin) start/end templates it writes [`DEFAULT_PNEUMATIC_START_GCODE`]
/// and [`DEFAULT_PNEUMATIC_END_GCODE`] instead. The analyzer sees no extrusion in such a file
/// (it counts a move as extruding only when E increases): it reports 0 extrusion paths and
/// every move as travel.
///
/// Numbers are formatted with integer arithmetic (X/Y/Z 3 decimals, E 5, F whole mm/min,
/// trailing zeros trimmed, never `-0`), so output is byte-identical on native and wasm.
/// Options are expected to be physically sensible (positive diameters, speeds and heights);
/// a non-finite number would be written as `0`.
pub fn write_gcode(toolpath: &Toolpath, options: &Options) -> Result<Gcode, Error> {
    estimate(segments(toolpath) as f64, options).check()?;
    writer::write(toolpath, options)
}

/// Rows of [`Printer`] (paths relative to `printer`): ranges, units, help. The writer's options
/// are checked against them ([`check_options`]) and the page's form is built from them.
pub const PRINTER_FIELDS: &[Field] = &[
    other("name", "Printer", "Profile name", Kind::Text, &[], "Shown in the G-code header."),
    vec3("bed_size_mm", "Printer", "Bed size X, Y, Z", "mm", 10.0, 2000.0, 1.0, "Printable volume."),
    other("origin", "Printer", "Origin", Kind::Choice, &["corner", "center"], "Where X = Y = 0 is: front-left corner (Cartesian) or bed centre (delta)."),
    num("nozzle_diameter_mm", "Printer", "Nozzle diameter", "mm", 0.05, 3.0, 0.01, "d_n in GIPPO equation 4."),
    num("filament_diameter_mm", "Printer", "Filament diameter", "mm", 0.5, 5.0, 0.01, "f_d in GIPPO equation 4."),
    other("flavor", "Printer", "G-code flavour", Kind::Choice, &["marlin", "pneumatic", "poses_csv"], "marlin: FDM G-code; pneumatic: .nc for pneumatic (bio)printers, valve on/off and pressure per path; poses_csv: a .csv of tip positions and tool axes (x,y,z,nx,ny,nz) for a robot or other CAM."),
    when(other("pneumatic.valve_on", "Printer", "Valve on (pneumatic)", Kind::Text, &[], "Line(s) that start the flow of each path."), "flavor", "pneumatic"),
    when(other("pneumatic.valve_off", "Printer", "Valve off (pneumatic)", Kind::Text, &[], "Line(s) that stop the flow after each path."), "flavor", "pneumatic"),
    when(other("pneumatic.pressure_template", "Printer", "Pressure code (pneumatic)", Kind::Text, &[], "{pressure_kpa} is replaced; empty: no pressure line."), "flavor", "pneumatic"),
    when(num("pneumatic.pressure_kpa", "Printer", "Pressure (pneumatic)", "kPa", 0.0, 100000.0, 1.0, ""), "flavor", "pneumatic"),
    when(num("pneumatic.short_path_pressure_factor", "Printer", "Short-path pressure (pneumatic)", "×", 0.01, 10.0, 0.05, "Multiplies the pressure of slowed-down short paths."), "flavor", "pneumatic"),
    other("relative_e", "Printer", "Relative extrusion (M83)", Kind::Bool, &[], "Off: absolute E (M82)."),
    num("retraction.length_mm", "Printer", "Retraction length", "mm", 0.0, 20.0, 0.05, "0 disables retraction."),
    num("retraction.speed_mm_s", "Printer", "Retraction speed", "mm/s", 1.0, 200.0, 1.0, ""),
    num("retraction.z_hop_mm", "Printer", "Z-hop", "mm", 0.0, 10.0, 0.05, "Lift during retracted travels."),
    num("retraction.min_travel_mm", "Printer", "Retract only above", "mm", 0.0, 100.0, 0.1, "Shorter travels are not retracted."),
    num("travel_speed_mm_s", "Printer", "Travel speed", "mm/s", 1.0, 1000.0, 1.0, ""),
    num("z_speed_mm_s", "Printer", "Z speed", "mm/s", 0.1, 100.0, 0.1, ""),
    num("acceleration_mm_s2", "Printer", "Acceleration", "mm/s²", 10.0, 50000.0, 10.0, "Used for time estimates."),
    other("machine.kind", "Printer", "Machine", Kind::Choice, &["cartesian", "five_axis"], "cartesian: X Y Z, the tool always vertical; five_axis: two rotary axes tilt the tool (toolpaths with tool axes)."),
    when(other("machine.layout", "Printer", "5-axis layout", Kind::Choice, &["head_head", "table_table"], "What the rotary axes turn: the head, or the table with the part."), "machine.kind", "five_axis"),
    when(other("machine.rotary_axes", "Printer", "Rotary axes", Kind::Choice, &["ab", "bc"], "ab: A about X carrying B about Y; bc: C about Z with B about Y (head: C outer; table: B cradle, C turntable)."), "machine.kind", "five_axis"),
    when(other("machine.axis_output", "Printer", "Tool axis as", Kind::Choice, &["rotary", "ijk"], "rotary: angle words through the inverse kinematics, X Y Z in machine coordinates; ijk: tip X Y Z with I J K tool vectors (the controller does the kinematics)."), "machine.kind", "five_axis"),
    when(num("machine.pivot_mm", "Printer", "Pivot length (head-head)", "mm", 0.0, 1000.0, 0.1, "Nozzle tip to where the rotary axes cross, along the tool axis; 0: the controller compensates."), "machine.layout", "head_head"),
    when(vec3("machine.table_center_mm", "Printer", "Rotary centre (table-table)", "mm", -10000.0, 10000.0, 0.1, "Where the table's rotary axes cross, printer coordinates."), "machine.layout", "table_table"),
    when(vec3("machine.rotary_min_deg", "Printer", "Rotary lower limits A, B, C", "°", -1.0e6, 1.0e6, 1.0, "Checked in machine coordinates before writing."), "machine.kind", "five_axis"),
    when(vec3("machine.rotary_max_deg", "Printer", "Rotary upper limits A, B, C", "°", -1.0e6, 1.0e6, 1.0, "Checked in machine coordinates before writing."), "machine.kind", "five_axis"),
    when(vec3("machine.travel_min_mm", "Printer", "Travel lower limits X, Y, Z", "mm", -10000.0, 10000.0, 1.0, "Machine coordinates; absent: the bed's volume."), "machine.kind", "five_axis"),
    when(vec3("machine.travel_max_mm", "Printer", "Travel upper limits X, Y, Z", "mm", -10000.0, 10000.0, 1.0, "Machine coordinates; absent: the bed's volume."), "machine.kind", "five_axis"),
    other("model", "Printer", "Printer model", Kind::Text, &[], "As the firmware names it (MK4, XL, MINI): a Prusa printer warns about a file for another model; empty: not written."),
    points("thumbnails", "Printer", "Thumbnails", "px", 8.0, MAX_THUMBNAIL_PX as f64, MAX_THUMBNAILS, "PNG pictures of the print written into the file, width height each (hosts and printer screens show them); none: no thumbnail."),
    points("thumbnails_qoi", "Printer", "QOI thumbnails", "px", 8.0, MAX_THUMBNAIL_PX as f64, MAX_THUMBNAILS, "QOI pictures, width height each: what Prusa MK4, XL and MINI screens show (firmware 5.1 on); none: no QOI thumbnail."),
    other("object_labels", "Printer", "Object labels", Kind::Choice, &["none", "m486", "exclude_object"], "So a failed part can be cancelled mid-print: m486 for Marlin, Prusa and RepRapFirmware; exclude_object for Klipper."),
    num("arc_tolerance_mm", "Printer", "Arc fitting tolerance", "mm", 0.0, 0.5, 0.005, "Curved paths within this distance of an arc are written as G2/G3 (smaller files); 0: off."),
    other("binary_gcode", "Printer", "Binary G-code (.bgcode)", Kind::Bool, &[], "Prusa MK4, XL and MINI read binary G-code: smaller files that carry their thumbnails and metadata."),
    other("host", "Printer", "Print host", Kind::Choice, &["none", "moonraker", "octoprint"], "What the page's Send offers first: Moonraker (Klipper) or OctoPrint. Its address and key stay in this browser."),
    max_len(other("start_gcode", "Printer", "Start G-code", Kind::Text, &[], "Placeholders: {nozzle_temp_c} {first_layer_nozzle_temp_c} {bed_temp_c} {bed_x_mm} {bed_y_mm} {fan_pwm} {design_name}."), MAX_TEMPLATE_BYTES),
    max_len(other("end_gcode", "Printer", "End G-code", Kind::Text, &[], "Same placeholders as the start G-code."), MAX_TEMPLATE_BYTES),
];

/// Rows of [`Material`] (paths relative to `material`).
pub const MATERIAL_FIELDS: &[Field] = &[
    other("name", "Material", "Material", Kind::Text, &[], ""),
    num("nozzle_temp_c", "Material", "Nozzle temperature", "°C", 0.0, 500.0, 1.0, ""),
    num("first_layer_nozzle_temp_c", "Material", "First-layer nozzle temperature", "°C", 0.0, 500.0, 1.0, ""),
    num("bed_temp_c", "Material", "Bed temperature", "°C", 0.0, 150.0, 1.0, ""),
    num("fan_percent", "Material", "Fan", "%", 0.0, 100.0, 1.0, ""),
    int("fan_start_layer", "Material", "Fan from layer", 0.0, 1000.0, "0-based layer index."),
    num("extrusion_multiplier", "Material", "Extrusion multiplier EM", "", 0.1, 3.0, 0.01, "EM in GIPPO equation 4."),
    num(
        "bridge_fan_percent",
        "Material",
        "Fan on bridges and overhangs",
        "%",
        0.0,
        100.0,
        1.0,
        "Cools lines printed over air so they set before they sag; 0: the usual fan.",
    ),
    num(
        "bridge_flow",
        "Material",
        "Bridge flow",
        "",
        0.5,
        2.0,
        0.01,
        "Multiplies the filament of a bridge, which is laid as a round strand of the line width.",
    ),
    num("density_g_cm3", "Material", "Density", "g/cm³", 0.1, 25.0, 0.01, "For the filament weight print hosts show (PLA 1.24, PETG 1.27, ABS 1.04)."),
    num("k", "Material", "Cross-section correction k", "", 0.1, 3.0, 0.01, "k in GIPPO equation 4 (elliptical rather than rectangular strands)."),
    num(
        "swell_ratio",
        "Material",
        "Die swell ratio",
        "×",
        MIN_SWELL_RATIO,
        MAX_SWELL_RATIO,
        0.01,
        "How much wider than the nozzle the strand comes out (1 = none; elastic TPU swells more than PLA).",
    ),
    other(
        "compensate_swell",
        "Material",
        "Extrude for the swollen width",
        Kind::Bool,
        &[],
        "Feed filament for the predicted (swollen) width instead of the nozzle width.",
    ),
    when(num("flow.pre_flow_mm", "Material", "Pre-flow", "mm", 0.0, 50.0, 0.01, "Filament pushed at each path start (Marlin)."), "/printer.flavor", "marlin"),
    when(num("flow.post_flow_mm", "Material", "Post-flow", "mm", 0.0, 50.0, 0.01, "Filament pushed at each path end (Marlin)."), "/printer.flavor", "marlin"),
    when(num("flow.pre_flow_s", "Material", "Pre-flow time", "s", 0.0, 60.0, 0.01, "Valve open before moving (pneumatic)."), "/printer.flavor", "pneumatic"),
    when(
        num("flow.post_flow_s", "Material", "Post-flow time", "s", 0.0, 60.0, 0.01, "Valve closed this long before the path end (pneumatic)."),
        "/printer.flavor",
        "pneumatic",
    ),
];

/// Rows of [`Speeds`] (paths relative to `speeds`).
pub const SPEED_FIELDS: &[Field] = &[
    num("external_perimeter_mm_s", "Speeds", "External perimeter", "mm/s", 1.0, 500.0, 1.0, ""),
    num("perimeter_mm_s", "Speeds", "Perimeters", "mm/s", 1.0, 500.0, 1.0, ""),
    num("infill_mm_s", "Speeds", "Infill", "mm/s", 1.0, 500.0, 1.0, ""),
    num("solid_infill_mm_s", "Speeds", "Solid infill", "mm/s", 1.0, 500.0, 1.0, ""),
    num("lattice_mm_s", "Speeds", "Lattice", "mm/s", 1.0, 500.0, 1.0, ""),
    num("first_layer_mm_s", "Speeds", "First layer", "mm/s", 1.0, 500.0, 1.0, ""),
    num("support_mm_s", "Speeds", "Support", "mm/s", 1.0, 500.0, 1.0, "Support and its interface layers."),
    num("bridge_mm_s", "Speeds", "Bridges", "mm/s", 1.0, 500.0, 1.0, "Lines printed across air between two anchors; slower sags less."),
    num("overhang_mm_s", "Speeds", "Overhangs", "mm/s", 1.0, 500.0, 1.0, "Perimeters that hang more than half their width over the layer below."),
];

/// Every out-of-range value of the writer's options, with paths from the design root
/// (`printer.…`, `material.…`, `speeds.…`).
pub fn check_options(options: &Options) -> Vec<settings::Problem> {
    let mut out = settings::check(&options.printer, PRINTER_FIELDS, "printer");
    out.extend(settings::check(&options.material, MATERIAL_FIELDS, "material"));
    out.extend(settings::check(&options.speeds, SPEED_FIELDS, "speeds"));
    out
}

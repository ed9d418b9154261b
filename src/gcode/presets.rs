//! Printer profiles a newcomer picks from instead of typing a machine in (the page's printer
//! picker, `weft run --printer ID`). Each is a whole [`Printer`]: picking one replaces the
//! design's printer section, which stays editable (the picker then reads "custom").
//!
//! Values are the machines' published specifications (build volume, nozzle, direct drive or
//! Bowden retraction); start and end code are kept minimal (no purge line) so the G-code holds
//! only what the design prints.

use super::{Flavor, HostKind, Origin, Printer, Retraction, DEFAULT_PNEUMATIC_END_GCODE, DEFAULT_PNEUMATIC_START_GCODE};
use serde::Serialize;

/// One printer profile.
#[derive(Clone, Debug, Serialize)]
pub struct Preset {
    /// Stable id (`--printer ID`).
    pub id: &'static str,
    /// What the picker shows.
    pub label: &'static str,
    /// One line on who it is for.
    pub doc: &'static str,
    /// The printer section it sets.
    pub printer: Printer,
}

/// Every profile, the generic one first.
pub fn presets() -> Vec<Preset> {
    vec![
        Preset {
            id: "generic-220",
            label: "Generic 220 mm (Marlin)",
            doc: "Any Marlin printer with a 220 × 220 mm bed: weft's default.",
            printer: Printer::default(),
        },
        Preset {
            id: "prusa-mk3",
            label: "Prusa MK3S class",
            doc: "250 × 210 × 210 mm, 0.4 mm nozzle, direct drive (short retraction), relative extrusion, text G-code (often behind OctoPrint).",
            printer: Printer {
                thumbnails: vec![[16, 16], [160, 120]],
                ..prusa("Prusa MK3S class 250 × 210", "MK3S", [250.0, 210.0, 210.0], false, HostKind::Octoprint)
            },
        },
        Preset {
            id: "prusa-mk4",
            label: "Prusa MK4 / MK4S",
            doc: "250 × 210 × 220 mm, 0.4 mm nozzle, direct drive, relative extrusion; Prusa binary G-code (.bgcode) with the QOI thumbnails its screen shows (firmware 5.1 on).",
            printer: xbuddy(prusa("Prusa MK4 250 × 210", "MK4", [250.0, 210.0, 220.0], true, HostKind::None), &[[16, 16], [313, 173], [440, 240], [480, 240]]),
        },
        Preset {
            id: "prusa-mini",
            label: "Prusa MINI / MINI+",
            doc: "180 × 180 × 180 mm, 0.4 mm nozzle, Bowden extruder (longer retraction); Prusa binary G-code (.bgcode) with its screen's QOI thumbnails.",
            printer: Printer {
                retraction: Retraction { length_mm: 3.2, speed_mm_s: 70.0, z_hop_mm: 0.2, min_travel_mm: 1.5 },
                acceleration_mm_s2: 1250.0,
                ..xbuddy(prusa("Prusa MINI 180 × 180", "MINI", [180.0, 180.0, 180.0], true, HostKind::None), &[[16, 16], [480, 240]])
            },
        },
        Preset {
            id: "prusa-xl",
            label: "Prusa XL (one tool)",
            doc: "360 × 360 × 360 mm, 0.4 mm nozzle, direct drive, one tool; Prusa binary G-code (.bgcode) with its screen's QOI thumbnails.",
            printer: Printer {
                acceleration_mm_s2: 2500.0,
                ..xbuddy(prusa("Prusa XL 360 × 360", "XL", [360.0, 360.0, 360.0], true, HostKind::None), &[[16, 16], [313, 173], [440, 240], [480, 240]])
            },
        },
        Preset {
            id: "klipper-220",
            label: "Klipper (Moonraker) 220 mm",
            doc: "Any Klipper printer with a 220 × 220 mm bed behind Moonraker (Mainsail, Fluidd): Klipper's object labels, thumbnails for its screens, Send to Moonraker.",
            printer: Printer {
                name: "Klipper 220 × 220".into(),
                object_labels: super::ObjectLabels::ExcludeObject,
                host: HostKind::Moonraker,
                acceleration_mm_s2: 3000.0,
                ..Printer::default()
            },
        },
        Preset {
            id: "ender-3",
            label: "Ender-3 class",
            doc: "220 × 220 × 250 mm, 0.4 mm nozzle, Bowden extruder (long retraction), absolute extrusion.",
            printer: Printer {
                name: "Ender-3 class 220 × 220".into(),
                retraction: Retraction { length_mm: 5.0, speed_mm_s: 40.0, z_hop_mm: 0.0, min_travel_mm: 1.5 },
                travel_speed_mm_s: 150.0,
                acceleration_mm_s2: 500.0,
                ..Printer::default()
            },
        },
        Preset {
            id: "five-axis-head",
            label: "5-axis head (B/C)",
            doc: "A head that tilts (B about Y, ±150°) and turns (C about Z), 300 × 300 × 300 mm around the centre, for non-planar jobs whose tool follows the surface normal (an hourglass's flare tilts it past 90°).",
            printer: Printer {
                name: "5-axis B/C head 300 × 300".into(),
                bed_size_mm: [300.0, 300.0, 300.0],
                origin: Origin::Center,
                machine: crate::machine::Machine {
                    kind: crate::machine::Kind::FiveAxis,
                    rotary_min_deg: [-150.0, -150.0, -36000.0],
                    rotary_max_deg: [150.0, 150.0, 36000.0],
                    ..crate::machine::Machine::default()
                },
                retraction: Retraction { length_mm: 0.8, speed_mm_s: 35.0, z_hop_mm: 0.0, min_travel_mm: 1.0 },
                travel_speed_mm_s: 100.0,
                z_speed_mm_s: 10.0,
                acceleration_mm_s2: 1000.0,
                ..Printer::default()
            },
        },
        Preset {
            id: "bioprinter-pneumatic",
            label: "Pneumatic bioprinter",
            doc: "Air-pressure dispenser with a valve (22G needle, 0.41 mm), 130 × 90 × 60 mm, slow moves, no retraction.",
            printer: Printer {
                name: "Pneumatic bioprinter 130 × 90".into(),
                bed_size_mm: [130.0, 90.0, 60.0],
                origin: Origin::Corner,
                nozzle_diameter_mm: 0.41,
                flavor: Flavor::Pneumatic,
                retraction: Retraction { length_mm: 0.0, speed_mm_s: 35.0, z_hop_mm: 0.0, min_travel_mm: 1.0 },
                travel_speed_mm_s: 20.0,
                z_speed_mm_s: 5.0,
                acceleration_mm_s2: 500.0,
                start_gcode: DEFAULT_PNEUMATIC_START_GCODE.into(),
                end_gcode: DEFAULT_PNEUMATIC_END_GCODE.into(),
                ..Printer::default()
            },
        },
    ]
}

/// A Prusa printer: direct-drive retraction, relative extrusion, `printer_model` written so the
/// firmware can warn about a file sliced for another machine.
fn prusa(name: &str, model: &str, bed_size_mm: [f64; 3], binary_gcode: bool, host: HostKind) -> Printer {
    Printer {
        name: name.into(),
        model: model.into(),
        bed_size_mm,
        relative_e: true,
        retraction: Retraction { length_mm: 0.7, speed_mm_s: 35.0, z_hop_mm: 0.2, min_travel_mm: 1.5 },
        travel_speed_mm_s: 180.0,
        z_speed_mm_s: 12.0,
        acceleration_mm_s2: 2000.0,
        binary_gcode,
        host,
        ..Printer::default()
    }
}

/// A printer with Prusa's xBuddy board (MK4, XL, MINI): its screens read QOI thumbnails of
/// `screens` sizes (the file list's icon, the preview), PrusaLink and Prusa Connect a PNG.
fn xbuddy(p: Printer, screens: &[[u32; 2]]) -> Printer {
    Printer { thumbnails: vec![[380, 285]], thumbnails_qoi: screens.to_vec(), ..p }
}

/// The profile `id`, or the list of ids as the error.
pub fn preset(id: &str) -> Result<Preset, String> {
    let all = presets();
    let ids: Vec<&str> = all.iter().map(|p| p.id).collect();
    all.into_iter().find(|p| p.id == id).ok_or_else(|| format!("no printer profile '{id}'; use one of: {}", ids.join(", ")))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ids_are_unique_and_found() {
        let all = presets();
        for (i, p) in all.iter().enumerate() {
            assert!(all[i + 1..].iter().all(|q| q.id != p.id), "{} twice", p.id);
            assert_eq!(preset(p.id).map(|q| q.printer), Ok(p.printer.clone()));
        }
        let err = preset("mk5").unwrap_err();
        assert!(err.contains("prusa-mk4") && err.contains("bioprinter-pneumatic"), "{err}");
    }

    #[test]
    fn every_profile_differs_from_the_others() {
        let all = presets();
        for (i, p) in all.iter().enumerate() {
            for q in &all[i + 1..] {
                assert_ne!(p.printer, q.printer, "{} and {} are the same printer", p.id, q.id);
            }
        }
    }
}

//! G-code dialects. The layer loop in `writer.rs` talks to a [`Dialect`] only; a new flavour
//! (e.g. a pneumatic `.nc` dialect that opens a valve per path instead of pushing E) is one
//! more impl of this trait plus one arm in [`dialect`].

use super::format::push_fixed;
use super::writer::Out;
use super::{Flavor, Options};
use crate::geom::DVec3;

/// What a flavour decides: how to set up, travel, extrude and finish.
pub(crate) trait Dialect {
    /// Lines after the start template (positioning and extrusion modes, acceleration).
    fn prologue(&mut self, out: &mut Out, options: &Options);
    /// Moves without extruding from the current position to `to`, the start of the next path.
    fn travel(&mut self, out: &mut Out, to: DVec3, options: &Options);
    /// Before the first segment of a path.
    fn path_begin(&mut self, _out: &mut Out) {}
    /// One extruding segment to `to`, feeding `e` mm of filament, at `feed` mm/min.
    fn segment(&mut self, out: &mut Out, to: DVec3, e: f64, feed: u64);
    /// After the last segment of a path.
    fn path_end(&mut self, _out: &mut Out) {}
    /// Before the end template.
    fn epilogue(&mut self, out: &mut Out, options: &Options);
}

/// The dialect object for `flavor`.
pub(crate) fn dialect(flavor: Flavor) -> Box<dyn Dialect> {
    match flavor {
        Flavor::Marlin => Box::new(Marlin),
    }
}

/// Marlin (and Klipper / RepRapFirmware): E axis, `G0` travels, retraction with optional z-hop.
struct Marlin;

/// mm/s → integer mm/min.
pub(crate) fn feed_mm_min(mm_s: f64) -> u64 {
    let f = (mm_s * 60.0).round();
    if f.is_finite() && f >= 1.0 {
        f.min(1.0e9) as u64
    } else {
        1
    }
}

impl Marlin {
    fn retract(out: &mut Out, options: &Options) {
        let r = &options.printer.retraction;
        let mut line = String::from("G1 E");
        if out.relative_e {
            push_fixed(&mut line, -r.length_mm, 5);
        } else {
            push_fixed(&mut line, out.e_total - r.length_mm, 5);
        }
        out.push_feed(&mut line, feed_mm_min(r.speed_mm_s));
        out.line(&line);
        out.retracted = true;
        out.retractions += 1;
    }

    fn unretract(out: &mut Out, options: &Options) {
        let r = &options.printer.retraction;
        let mut line = String::from("G1 E");
        if out.relative_e {
            push_fixed(&mut line, r.length_mm, 5);
        } else {
            push_fixed(&mut line, out.e_total, 5);
        }
        out.push_feed(&mut line, feed_mm_min(r.speed_mm_s));
        out.line(&line);
        out.retracted = false;
    }
}

impl Dialect for Marlin {
    fn prologue(&mut self, out: &mut Out, options: &Options) {
        // G90 first: in Marlin G90/G91 also reset the E mode, so M82/M83 must come after.
        out.line("G90 ; absolute coordinates");
        out.line(if out.relative_e { "M83 ; relative extrusion" } else { "M82 ; absolute extrusion" });
        out.line("G92 E0");
        let mut line = String::from("M204 S");
        push_fixed(&mut line, options.printer.acceleration_mm_s2, 0);
        line.push_str(" ; acceleration");
        out.line(&line);
    }

    fn travel(&mut self, out: &mut Out, to: DVec3, options: &Options) {
        let p = &options.printer;
        let z_feed = feed_mm_min(p.z_speed_mm_s);
        let xy_feed = feed_mm_min(p.travel_speed_mm_s);
        let Some(from) = out.pos else {
            // First move of the file: where the start G-code left the head is unknown.
            out.move_z(to.z, z_feed);
            out.move_xy(to, xy_feed);
            return;
        };
        let dxy = ((to.x - from.x) * (to.x - from.x) + (to.y - from.y) * (to.y - from.y)).sqrt();
        let xy_moves = dxy > 1e-9;
        if !xy_moves && (to.z - from.z).abs() <= 1e-9 {
            return;
        }
        let r = &p.retraction;
        let retract = r.length_mm > 0.0 && xy_moves && dxy >= r.min_travel_mm && !out.retracted;
        if retract {
            Self::retract(out, options);
        }
        let hop = if retract && r.z_hop_mm > 0.0 { r.z_hop_mm } else { 0.0 };
        let lift = (from.z + hop).max(to.z);
        out.move_z(lift, z_feed);
        if xy_moves {
            out.move_xy(to, xy_feed);
        }
        out.move_z(to.z, z_feed);
        if out.retracted {
            Self::unretract(out, options);
        }
    }

    fn segment(&mut self, out: &mut Out, to: DVec3, e: f64, feed: u64) {
        let mut line = String::with_capacity(48);
        line.push_str("G1 X");
        push_fixed(&mut line, to.x, 3);
        line.push_str(" Y");
        push_fixed(&mut line, to.y, 3);
        out.push_z_if_changed(&mut line, to.z);
        line.push_str(" E");
        out.e_total += e;
        if out.relative_e {
            push_fixed(&mut line, e, 5);
        } else {
            push_fixed(&mut line, out.e_total, 5);
        }
        out.push_feed(&mut line, feed);
        out.line(&line);
        out.pos = Some(to);
    }

    fn epilogue(&mut self, out: &mut Out, options: &Options) {
        if options.printer.retraction.length_mm > 0.0 && !out.retracted {
            Self::retract(out, options);
        }
    }
}

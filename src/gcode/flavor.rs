//! G-code dialects. The layer loop in `writer.rs` talks to a [`Dialect`] only: Marlin (E axis,
//! retraction, pre/post flow as `G1 E`) and the pneumatic `.nc` dialect (a valve per path, no
//! E). A new flavour is one more impl of this trait plus one arm in [`dialect`].

use super::format::{fixed, push_fixed};
use super::out::Out;
use super::{Flavor, Options};
use crate::geom::DVec3;

/// What the dialect needs to know about the path being written.
pub(crate) struct PathCtx {
    /// The path's speed factor (below 1: a short path the optimiser slowed down).
    pub speed_factor: f64,
    /// The path's print speed (feature speed × speed factor), mm/s.
    pub speed_mm_s: f64,
}

/// What a flavour decides: how to set up, travel, extrude and finish.
pub(crate) trait Dialect {
    /// Lines after the start template (positioning and extrusion modes, acceleration).
    fn prologue(&mut self, out: &mut Out, options: &Options);
    /// Moves without extruding from the current position to `to`, the start of the next path.
    fn travel(&mut self, out: &mut Out, to: DVec3, options: &Options);
    /// Moves without extruding through `route` then to `to` with `G1` at the travel speed,
    /// never retracting or hopping (an approach route along printed struts).
    fn approach(&mut self, out: &mut Out, route: &[DVec3], to: DVec3, options: &Options) {
        dry_route(out, route, to, options);
    }
    /// Before the first segment of a path.
    fn path_begin(&mut self, _out: &mut Out, _options: &Options, _path: &PathCtx) {}
    /// How far before the end of the path [`Dialect::path_end`] is called, mm; the rest of
    /// the path is written with [`Dialect::coast`].
    fn end_lead_mm(&self, _options: &Options, _path: &PathCtx) -> f64 {
        0.0
    }
    /// One extruding segment to `to`, feeding `e` mm of filament, at `feed` mm/min.
    fn segment(&mut self, out: &mut Out, to: DVec3, e: f64, feed: u64);
    /// A move along the path after [`Dialect::path_end`] (no material fed).
    fn coast(&mut self, out: &mut Out, to: DVec3, feed: u64) {
        out.dry_move(to, feed);
    }
    /// After the last extruding segment of a path.
    fn path_end(&mut self, _out: &mut Out, _options: &Options) {}
    /// Before the end template.
    fn epilogue(&mut self, out: &mut Out, options: &Options);
}

/// `G1` moves without E through `route` then to `to` at the travel speed (zero-length moves
/// skipped).
fn dry_route(out: &mut Out, route: &[DVec3], to: DVec3, options: &Options) {
    let feed = feed_mm_min(options.printer.travel_speed_mm_s);
    for &p in route.iter().chain(std::iter::once(&to)) {
        if out.pos.is_none_or(|q| q.distance(p) > 1e-9) {
            out.dry_move(p, feed);
        }
    }
}

/// The dialect object for `flavor`.
pub(crate) fn dialect(flavor: Flavor) -> Box<dyn Dialect> {
    match flavor {
        // The poses CSV has its own writer (`poses.rs`) and never reaches the layer loop.
        Flavor::Marlin | Flavor::PosesCsv => Box::new(Marlin),
        Flavor::Pneumatic => Box::new(PneumaticDialect { pressure_written: None }),
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
        let e = if out.relative_e { -r.length_mm } else { out.e_total - r.length_mm };
        out.e_only(e, feed_mm_min(r.speed_mm_s));
        out.retracted = true;
        out.retractions += 1;
    }

    fn unretract(out: &mut Out, options: &Options) {
        let r = &options.printer.retraction;
        let e = if out.relative_e { r.length_mm } else { out.e_total };
        out.e_only(e, feed_mm_min(r.speed_mm_s));
        out.retracted = false;
    }

    /// `G1 E` feeding `e` mm without motion at the retraction speed (pre- and post-flow);
    /// nothing when `e` is not positive.
    fn push_e(out: &mut Out, e: f64, options: &Options) {
        if !(e > 0.0 && e.is_finite()) {
            return;
        }
        out.e_total += e;
        let word = if out.relative_e { e } else { out.e_total };
        out.e_only(word, feed_mm_min(options.printer.retraction.speed_mm_s));
    }
}

impl Dialect for Marlin {
    fn prologue(&mut self, out: &mut Out, options: &Options) {
        // G90 first: in Marlin G90/G91 also reset the E mode, so M82/M83 must come after.
        out.code("G90 ; absolute coordinates");
        out.code(if out.relative_e { "M83 ; relative extrusion" } else { "M82 ; absolute extrusion" });
        out.code("G92 E0");
        let mut line = String::from("M204 S");
        push_fixed(&mut line, options.printer.acceleration_mm_s2, 0);
        line.push_str(" ; acceleration");
        out.code(&line);
    }

    fn travel(&mut self, out: &mut Out, to: DVec3, options: &Options) {
        let p = &options.printer;
        let Some(Leg { from, dxy, xy_moves, z_feed, xy_feed }) = travel_leg(out, to, options, 1) else { return };
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

    fn approach(&mut self, out: &mut Out, route: &[DVec3], to: DVec3, options: &Options) {
        if out.retracted {
            Self::unretract(out, options);
        }
        dry_route(out, route, to, options);
    }

    fn path_begin(&mut self, out: &mut Out, options: &Options, _path: &PathCtx) {
        Self::push_e(out, options.material.flow.pre_flow_mm, options);
    }

    fn path_end(&mut self, out: &mut Out, options: &Options) {
        Self::push_e(out, options.material.flow.post_flow_mm, options);
    }

    fn segment(&mut self, out: &mut Out, to: DVec3, e: f64, feed: u64) {
        out.extrude_move(to, e, feed);
    }

    fn epilogue(&mut self, out: &mut Out, options: &Options) {
        if options.printer.retraction.length_mm > 0.0 && !out.retracted {
            Self::retract(out, options);
        }
    }
}

/// Pneumatic extrusion (`.nc`): no E axis. Travels are `G0` (lifted by the retraction's
/// `z_hop_mm` when at least `min_travel_mm` long; there is no filament to retract); a path is
/// the pressure line (when the pressure changes), the valve-on code, the pre-flow dwell,
/// `G1 X Y [Z] [F]` moves, the valve-off code (early by the post-flow time, see
/// [`super::Flow::post_flow_s`]).
struct PneumaticDialect {
    /// Last pressure written, in Pa (rounded).
    pressure_written: Option<i64>,
}

/// Appends `code` (one or more lines) unless it is blank.
fn push_code(out: &mut Out, code: &str) {
    let code = code.trim_end_matches(['\n', '\r']);
    if !code.trim().is_empty() {
        out.code(code);
    }
}

/// A travel both dialects make, once the trivial cases are handled.
struct Leg {
    from: DVec3,
    dxy: f64,
    xy_moves: bool,
    z_feed: u64,
    xy_feed: u64,
}

/// Common start of a travel to `to`: the file's first move goes straight there (where the start
/// G-code left the head is unknown: Z first with `G<z_g>`, then XY) and a move to where the head
/// already is does nothing; both return `None`. Otherwise the leg to plan.
fn travel_leg(out: &mut Out, to: DVec3, options: &Options, z_g: u32) -> Option<Leg> {
    let p = &options.printer;
    let z_feed = feed_mm_min(p.z_speed_mm_s);
    let xy_feed = feed_mm_min(p.travel_speed_mm_s);
    let Some(from) = out.pos else {
        out.move_z_with(z_g, to.z, z_feed);
        out.move_xy(to, xy_feed);
        return None;
    };
    let dxy = ((to.x - from.x) * (to.x - from.x) + (to.y - from.y) * (to.y - from.y)).sqrt();
    let xy_moves = dxy > 1e-9;
    if !xy_moves && (to.z - from.z).abs() <= 1e-9 {
        return None;
    }
    Some(Leg { from, dxy, xy_moves, z_feed, xy_feed })
}

impl Dialect for PneumaticDialect {
    fn prologue(&mut self, out: &mut Out, _options: &Options) {
        out.code("G21 ; millimetres");
        out.code("G90 ; absolute coordinates");
    }

    fn travel(&mut self, out: &mut Out, to: DVec3, options: &Options) {
        let p = &options.printer;
        let Some(Leg { from, dxy, xy_moves, z_feed, xy_feed }) = travel_leg(out, to, options, 0) else { return };
        let r = &p.retraction;
        let hop = if xy_moves && dxy >= r.min_travel_mm && r.z_hop_mm > 0.0 { r.z_hop_mm } else { 0.0 };
        out.move_z_with(0, (from.z + hop).max(to.z), z_feed);
        if xy_moves {
            out.move_xy(to, xy_feed);
        }
        out.move_z_with(0, to.z, z_feed);
    }

    fn path_begin(&mut self, out: &mut Out, options: &Options, path: &PathCtx) {
        let pn = &options.printer.pneumatic;
        let mut kpa = pn.pressure_kpa;
        if path.speed_factor < 1.0 {
            kpa *= pn.short_path_pressure_factor;
        }
        let pa = (kpa * 1000.0).round() as i64;
        if !pn.pressure_template.trim().is_empty() && self.pressure_written != Some(pa) {
            let line = pn.pressure_template.replace("{pressure_kpa}", &fixed(kpa, 3));
            push_code(out, &line);
            self.pressure_written = Some(pa);
        }
        push_code(out, &pn.valve_on);
        out.dwell(options.material.flow.pre_flow_s, "pre-flow");
    }

    fn end_lead_mm(&self, options: &Options, path: &PathCtx) -> f64 {
        let lead = options.material.flow.post_flow_s * path.speed_mm_s;
        if lead.is_finite() && lead > 0.0 {
            lead
        } else {
            0.0
        }
    }

    fn segment(&mut self, out: &mut Out, to: DVec3, _e: f64, feed: u64) {
        out.dry_move(to, feed);
    }

    fn path_end(&mut self, out: &mut Out, options: &Options) {
        push_code(out, &options.printer.pneumatic.valve_off);
    }

    fn epilogue(&mut self, _out: &mut Out, _options: &Options) {}
}

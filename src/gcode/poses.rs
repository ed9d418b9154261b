//! The poses CSV ([`super::Flavor::PosesCsv`]): tip positions and tool axes, no G-code.

use super::format::push_fixed;
use super::writer::{axis_at, segment_e};
use super::{Gcode, GcodeStats, Options};
use crate::geom::{DVec3, Toolpath};

/// Header line of the poses CSV.
pub const POSES_CSV_HEADER: &str = "x,y,z,nx,ny,nz";

/// Writes the CSV: header, one row per point (printer coordinates, 3 decimals; unit axis,
/// 7 decimals), a blank line between paths. Stats: layers (passes with paths), extruded
/// length and filament as the G-code would feed them, travel as straight lines between paths;
/// no time (there are no feeds in the file) and no retractions.
pub(crate) fn write(toolpath: &Toolpath, options: &Options, offset: DVec3) -> Gcode {
    let mut text = String::with_capacity(1 << 16);
    text.push_str(POSES_CSV_HEADER);
    text.push('\n');
    let mut stats = GcodeStats::default();
    let mut last: Option<DVec3> = None;
    let mut first_path = true;
    for pass in &toolpath.passes {
        if pass.paths.iter().all(|p| p.points.len() < 2) {
            continue;
        }
        stats.layers += 1;
        for path in &pass.paths {
            if path.points.len() < 2 {
                continue;
            }
            if !first_path {
                text.push('\n');
            }
            first_path = false;
            if let Some(l) = last {
                stats.travel_mm += l.distance(path.points[0] + offset);
            }
            for (k, p) in path.points.iter().enumerate() {
                let q = *p + offset;
                let n = axis_at(path, k);
                for (i, v) in [q.x, q.y, q.z].into_iter().enumerate() {
                    if i > 0 {
                        text.push(',');
                    }
                    push_fixed(&mut text, v, 3);
                }
                for v in [n.x, n.y, n.z] {
                    text.push(',');
                    push_fixed(&mut text, v, 7);
                }
                text.push('\n');
                if k > 0 {
                    let len = path.points[k - 1].distance(*p);
                    if len > 0.0 {
                        stats.extruded_mm += len;
                        stats.filament_mm += segment_e(options, path, pass.height, k, len);
                    }
                }
            }
            last = path.points.last().map(|p| *p + offset);
        }
    }
    let moves_end = text.len();
    Gcode { text, stats, header_len: 0, moves_end, footer_len: 0 }
}

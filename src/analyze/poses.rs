//! A poses CSV (`x,y,z,nx,ny,nz`, written by the `poses_csv` flavour) read back: every row is
//! a point, a blank line ends a path; consecutive points of a path are extrusion segments,
//! the jumps between paths travels. There are no feeds, so no time and no filament.

use super::machine::push6;
use super::{Analysis, Error, LayerReport, Options, Preview, Report};

/// Whether `bytes` is a poses CSV (its first line is the header).
pub(crate) fn is_poses(bytes: &[u8]) -> bool {
    let first = bytes.split(|&b| b == b'\n').next().unwrap_or(&[]);
    first.strip_suffix(b"\r").unwrap_or(first) == crate::gcode::POSES_CSV_HEADER.as_bytes()
}

/// Reads the CSV.
pub(crate) fn run(file: &str, bytes: &[u8], options: &Options) -> Result<Analysis, Error> {
    let text = std::str::from_utf8(bytes).map_err(|e| Error::NotText { file: file.into(), offset: e.valid_up_to() })?;
    let mut report = Report::default();
    let mut pv = Preview::default();
    let mut prev: Option<[f64; 3]> = None;
    let mut in_path = false;
    let mut paths: Vec<(f64, u32)> = Vec::new();
    let mut row = 0u32;
    let mut z: Option<f64> = None;
    for (i, line) in text.lines().enumerate().skip(1) {
        let line = line.trim();
        if line.is_empty() {
            in_path = false;
            continue;
        }
        let malformed = |problem: &str| Error::Malformed { file: file.into(), line: i + 1, problem: problem.into() };
        let mut vals = [0.0f64; 6];
        let mut n = 0;
        for v in line.split(',') {
            let v = v.trim().parse::<f64>().map_err(|_| malformed("a poses row needs six numbers x,y,z,nx,ny,nz"))?;
            if let Some(slot) = vals.get_mut(n) {
                *slot = v;
            }
            n += 1;
        }
        if n != 6 || vals.iter().any(|v| !v.is_finite()) {
            return Err(malformed("a poses row needs six finite numbers x,y,z,nx,ny,nz"));
        }
        let p = [vals[0], vals[1], vals[2]];
        z.get_or_insert(p[2]);
        if let Some(a) = prev {
            let len = ((p[0] - a[0]).powi(2) + (p[1] - a[1]).powi(2) + (p[2] - a[2]).powi(2)).sqrt();
            if in_path {
                report.extruded_mm += len;
                if let Some(last) = paths.last_mut() {
                    last.0 += len;
                    last.1 += 1;
                }
                if options.collect_preview {
                    push6(&mut pv.positions, a, p);
                    pv.feature.push(255);
                    pv.path.push(paths.len().saturating_sub(1) as u32);
                    pv.flow.push(0.0);
                    pv.e_per_mm.push(0.0);
                    pv.speed.push(0.0);
                    pv.width.push(options.default_line_width_mm as f32);
                    pv.axis.extend_from_slice(&[vals[3] as f32, vals[4] as f32, vals[5] as f32]);
                    pv.segment_move.push(row);
                }
            } else {
                report.travel_mm += len;
                if options.collect_preview {
                    push6(&mut pv.travel_positions, a, p);
                    pv.travel_move.push(row);
                }
            }
        }
        if !in_path {
            paths.push((0.0, 0));
            in_path = true;
        }
        prev = Some(p);
        row = row.saturating_add(1);
    }
    let paths: Vec<(f64, u32)> = paths.into_iter().filter(|p| p.1 > 0).collect();
    report.extrusion_paths = paths.len();
    if !paths.is_empty() {
        report.layers = 1;
        report.gippo_score = super::gippo_score(&paths);
        report.per_layer.push(LayerReport {
            z: z.unwrap_or(0.0),
            extrusion_paths: paths.len(),
            extruded_mm: report.extruded_mm,
            travel_mm: report.travel_mm,
            retractions: 0,
            overlap_mm: 0.0,
            gippo_score: report.gippo_score,
        });
        pv.layer_segment_start = vec![0, pv.feature.len() as u32];
        pv.layer_travel_start = vec![0, pv.travel_move.len() as u32];
        pv.layer_z = vec![z.unwrap_or(0.0) as f32];
    }
    Ok(Analysis { report, preview: options.collect_preview.then_some(pv) })
}

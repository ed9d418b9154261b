//! The foam job's checks of a design: every problem listed with its path and its fix.

use super::*;

/// Every problem of the design for this kind (`Kind::validate`), each with its path.
pub(super) fn validate(design: &Design, j: &FoamJob, out: &mut Vec<Problem>) {
    let p = process(design, j);
    for m in p.problems() {
        out.push(Problem { path: "job.foam.feed_mm_s".into(), message: m });
    }
    if j.model.is_none() && j.meshes.is_none() {
        out.push(Problem {
            path: "job.meshes".into(),
            message: "a foam needs its region meshes: load one file per region, or switch on a built-in model".into(),
        });
    }
    if let Some(m) = &j.model {
        for message in models::problems(m) {
            out.push(Problem { path: "job.model".into(), message });
        }
    }
    if j.regions.len() > MAX_REGIONS {
        out.push(Problem { path: "job.regions".into(), message: format!("{} regions: at most {MAX_REGIONS}", j.regions.len()) });
    }
    if j.transitions.len() > MAX_TRANSITIONS {
        out.push(Problem { path: "job.transitions".into(), message: format!("{} transitions: at most {MAX_TRANSITIONS}", j.transitions.len()) });
    }
    // More pairs than regions is allowed (a region's row waits for its file: loading
    // files one by one never drops a row); fewer is not.
    if let Some(n) = source_regions(j) {
        if n > j.regions.len() {
            out.push(Problem {
                path: "job.regions".into(),
                message: format!(
                    "the model has {n} region(s) but the design gives {} V*/H* pair(s): give one pair per region, in the order of the meshes",
                    j.regions.len()
                ),
            });
        }
    }
    let c = &j.foam.calibration;
    let calibration = c.problems();
    for message in &calibration {
        out.push(Problem { path: "job.foam.calibration".into(), message: message.clone() });
    }
    for (i, r) in j.regions.iter().enumerate() {
        if r.set_by == SetBy::Modulus {
            if let Some(message) = c.modulus_problem(r.modulus_kpa).filter(|_| calibration.is_empty()) {
                out.push(Problem { path: format!("job.regions.{i}.modulus_kpa"), message: format!("region {}: {message}", i + 1) });
                continue;
            } else if !calibration.is_empty() {
                continue;
            }
        }
        for message in p.pair_problems(&format!("region {}", i + 1), r.pair(c), j.foam.layer_height_mm) {
            out.push(Problem { path: format!("job.regions.{i}"), message });
        }
    }
    let n = j.regions.len();
    for (i, t) in j.transitions.iter().enumerate() {
        let path = format!("job.transitions.{i}");
        for (end, r) in [("from", t.from), ("to", t.to)] {
            if r == 0 || r > n {
                out.push(Problem { path: format!("{path}.{end}"), message: format!("region {r} does not exist: regions are numbered 1 to {n}") });
            }
        }
        if t.from == t.to {
            out.push(Problem { path: format!("{path}.to"), message: format!("a transition joins two different regions (both ends are region {})", t.from) });
        }
        if !(t.length_mm.is_finite() && t.length_mm >= 0.0) {
            out.push(Problem { path: format!("{path}.length_mm"), message: format!("{} mm: the length must be 0 (a step) or more", t.length_mm) });
        }
        for message in t.weighting.problems() {
            out.push(Problem { path: format!("{path}.weighting"), message });
        }
        if j.transitions[..i].iter().any(|u| (u.from.min(u.to), u.from.max(u.to)) == (t.from.min(t.to), t.from.max(t.to))) {
            out.push(Problem { path: path.clone(), message: format!("regions {} and {} already have a transition: give one per pair", t.from, t.to) });
        }
    }
    if !(j.foam.piece_mm.is_finite() && j.foam.piece_mm > 0.0) {
        out.push(Problem { path: "job.foam.piece_mm".into(), message: "the piece length must be above 0 mm".into() });
    }
}

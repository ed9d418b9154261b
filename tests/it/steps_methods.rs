//! "How it works", the methods' own frames: the axisymmetric repulsion replayed (energy falling,
//! within its frame cap, ending on the run's points), the graded bead widths (within the job's
//! allowed widths, as the written toolpath has them), the foam's V* bins (covering the run's V*).

use crate::common::{example, run};
use weft::kinds::Registry;
use weft::pipeline::{self, Cache, Files};

fn inspect(reg: &Registry, cache: &mut Cache, design: &weft::design::Design, view: &str, index: usize) -> weft::kinds::Inspection {
    pipeline::inspect(reg, cache, design, &Files::new(), view, index).unwrap_or_else(|e| panic!("{view} {index}: {e}"))
}

#[test]
fn repulsion_frames_fall_in_energy_and_end_on_the_runs_points() {
    let reg = Registry::builtin();
    let design = example("hourglass-omega3");
    let mut cache = Cache::new();
    let first = inspect(&reg, &mut cache, &design, "repulsion", 0);
    let count = first.count;
    let seed = inspect(&reg, &mut cache, &design, "map", 0);
    let result = inspect(&reg, &mut cache, &design, "map", 1);
    let strokes = result.data.len() / 5;
    let cap = first.meta["cap"].as_u64().unwrap() as usize;
    assert!(count >= 2 && count <= cap && cap <= weft::kinds::axisymmetric::REPULSION_FRAMES, "{count} frames, cap {cap}");
    println!(
        "hourglass-omega3: {count} frames of {} iterations, cap {cap}, {} recorded bytes ({} strokes)",
        first.meta["iterations"], first.meta["recorded_bytes"], strokes
    );
    assert!(first.meta["recorded_bytes"].as_u64().unwrap() > 0);
    assert_eq!(first.data, seed.data, "frame 0 is not the seed");
    let (mut energies, mut iterations) = (Vec::new(), Vec::new());
    for i in 0..count {
        let f = if i == 0 { first.clone() } else { inspect(&reg, &mut cache, &design, "repulsion", i) };
        assert_eq!(f.meta["frames"].as_u64(), Some(count as u64));
        assert!(f.meta["caption"].as_str().unwrap().starts_with("repulsion iteration "), "{}", f.meta["caption"]);
        energies.push(f.meta["energy"].as_f64().unwrap());
        iterations.push(f.meta["iteration"].as_u64().unwrap());
        if i + 1 == count {
            assert_eq!(f.data, result.data, "the last frame is not the run's points");
            assert_eq!(f.meta["iteration"], f.meta["iterations"]);
        }
    }
    assert_eq!(energies[0], 1.0);
    assert!(iterations.windows(2).all(|w| w[0] < w[1]), "{iterations:?}");
    // The descent accepts a step only when E/E₀ rises by at most the tolerance (1e-6).
    assert!(energies.windows(2).all(|w| w[1] <= w[0] + 1e-6), "{energies:?}");
    assert!(energies[count - 1] < 0.9 * energies[0], "the energy did not fall: {energies:?}");
}

#[test]
fn bead_widths_lie_in_the_allowed_range_and_match_the_written_toolpath() {
    let reg = Registry::builtin();
    let design = example("graded-phantom");
    let allowed = |k: &str| design.job.value["density"][k].as_f64().unwrap();
    let (lo, hi) = (allowed("min_width_mm"), allowed("max_width_mm"));
    let layer_mm = design.job.value["slice"]["layer_height_mm"].as_f64().unwrap();
    let out = run(&design, &Files::new()).unwrap();
    let preview = out.preview.expect("a preview");
    let mut cache = Cache::new();
    let first = inspect(&reg, &mut cache, &design, "beads", 0);
    assert_eq!(first.count + 1, preview.layer_segment_start.len(), "layers: view {} vs written {}", first.count, preview.layer_z.len());
    let codes: Vec<f32> = weft::kinds::graded::WIDTH_CODES.iter().map(|f| f.code() as f32).collect();
    let mut checked = 0;
    for layer in [first.count / 4, first.count / 2, 3 * first.count / 4] {
        let v = inspect(&reg, &mut cache, &design, "beads", layer);
        let (Some(w_lo), Some(w_hi)) = (v.meta["width_min_mm"].as_f64(), v.meta["width_max_mm"].as_f64()) else { continue };
        assert!(w_lo >= lo - 1e-9 && w_hi <= hi + 1e-9, "layer {layer}: widths {w_lo}–{w_hi} mm outside {lo}–{hi} mm");
        assert!(v.meta["caption"].as_str().unwrap().contains(" mm"), "{}", v.meta["caption"]);
        let graded = v.meta["graded_segments"].as_u64().unwrap() as usize;
        assert!(v.data.chunks(5).take(graded).all(|s| codes.contains(&s[4])));
        // Each graded segment's code is the bin of its width, the bins span the widths.
        let bins = v.meta["bins"].as_array().unwrap();
        assert!(bins[0]["from_mm"].as_f64().unwrap() <= w_lo && bins[bins.len() - 1]["to_mm"].as_f64().unwrap() >= w_hi);
        // The written G-code's infill beads on that layer: the analyser's flow over its speed
        // is the bead's area, its width by the same stadium model (segments of at least
        // 0.2 mm, where E's five decimals are fine enough).
        let (a, b) = (preview.layer_segment_start[layer] as usize, preview.layer_segment_start[layer + 1] as usize);
        let infill = weft::geom::Feature::Infill.code();
        let length = |i: usize| {
            let p = &preview.positions[6 * i..6 * i + 6];
            ((p[3] - p[0]).powi(2) + (p[4] - p[1]).powi(2) + (p[5] - p[2]).powi(2)).sqrt()
        };
        let written: Vec<f64> = (a..b)
            .filter(|&i| preview.feature[i] == infill && length(i) >= 0.2 && preview.speed[i] > 0.0)
            .map(|i| weft::scaffold::width_of_area(preview.flow[i] as f64 / preview.speed[i] as f64, layer_mm))
            .collect();
        assert!(!written.is_empty(), "layer {layer}: no infill written");
        let (g_lo, g_hi) = written.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(x, y), &w| (x.min(w), y.max(w)));
        println!("layer {layer}: view {w_lo:.4}–{w_hi:.4} mm, written {g_lo:.4}–{g_hi:.4} mm, {graded} segments ({} written)", written.len());
        assert!((g_lo - w_lo).abs() < 0.005 && (g_hi - w_hi).abs() < 0.005, "layer {layer}: view {w_lo}–{w_hi} mm, written {g_lo}–{g_hi} mm");
        checked += 1;
    }
    assert!(checked >= 2, "too few graded layers checked");
}

#[test]
fn v_star_bins_cover_the_values_the_run_prints() {
    let reg = Registry::builtin();
    let design = example("foam-dogbone-linear");
    let out = run(&design, &Files::new()).unwrap();
    let grade = out.report.stages.iter().find(|r| r.stage == "grade").expect("a grade report");
    let metric = |k: &str| grade.metrics.iter().find(|m| m.key == k).unwrap_or_else(|| panic!("no {k}")).value;
    let (v_lo, v_hi) = (metric("v_star_min"), metric("v_star_max"));
    let mut cache = Cache::new();
    let count = inspect(&reg, &mut cache, &design, "v_star", 0).count;
    let (mut seen_lo, mut seen_hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for layer in 0..count {
        let v = inspect(&reg, &mut cache, &design, "v_star", layer);
        let (lo, hi) = (v.meta["min"].as_f64().unwrap(), v.meta["max"].as_f64().unwrap());
        let bins = v.meta["bins"].as_array().unwrap();
        let (b_lo, b_hi) = (bins[0]["from"].as_f64().unwrap(), bins[bins.len() - 1]["to"].as_f64().unwrap());
        assert!(b_lo <= lo && b_hi >= hi && b_lo <= v_lo && b_hi >= v_hi, "layer {layer}: bins {b_lo}–{b_hi}, layer {lo}–{hi}, run {v_lo}–{v_hi}");
        let codes: Vec<f32> = bins.iter().map(|b| b["code"].as_u64().unwrap() as f32).collect();
        assert!(v.data.chunks(5).all(|s| codes.contains(&s[4])), "layer {layer}: a piece outside the bins");
        // Each piece's code is its bin: the lowest and highest bins are used where V* is extreme.
        assert!(v.meta["legend"].as_object().unwrap().len() == bins.len());
        (seen_lo, seen_hi) = (seen_lo.min(lo), seen_hi.max(hi));
    }
    // The view walks the pieces as the run prints them: the same extremes.
    assert!((seen_lo - v_lo).abs() < 1e-12 && (seen_hi - v_hi).abs() < 1e-12, "view {seen_lo}–{seen_hi}, run {v_lo}–{v_hi}");
    assert!(v_hi > v_lo, "the dogbone grades V*");
    let h = inspect(&reg, &mut cache, &design, "h_star", count / 2);
    assert!(!h.data.is_empty() && h.meta["caption"].as_str().unwrap().contains("H*"));
}

#[test]
fn the_three_methods_steps_name_their_views_and_cite_the_papers() {
    let reg = Registry::builtin();
    for kind in ["axisymmetric", "graded", "foam"] {
        let k = reg.get(kind).unwrap();
        assert!(k.steps().len() >= 4, "{kind}: {} steps", k.steps().len());
        for s in k.steps() {
            assert!(k.views().iter().any(|v| v.id == s.view), "{kind}: {} names no view", s.title);
            assert!(s.text.len() >= 40 && s.text.ends_with('.') && !s.cite.is_empty(), "{kind}: {}", s.title);
        }
        assert_eq!(k.steps().iter().filter(|s| s.scrub).count(), usize::from(kind == "axisymmetric"), "{kind}: scrub steps");
    }
}

//! The graded job's reports: the density model, the cells, the grading per layer and the comparison with an edited file.

use super::*;

pub(super) fn density_report(j: &GradedJob, m: &Model, vol: &Volume, roi: &Roi) -> StageReport {
    let cal = &j.density.calibration;
    let mut r = StageReport::new("density", "Mapping HU to density", m)
        .metric("rho_s", "Infill density ρ_s", m.rho_s, "", "The density the infill is sliced for; each segment's extrusion is scaled by ρ / ρ_s (equation 6).")
        .metric("cell", "Unit cell L_cell", m.cell_mm, "mm", "Cell size from equation 1 at ρ_s (k_c, m of table 1, nozzle φ, layer l_h).")
        .metric("rho_min", "ρ_min", m.rho_min, "", "The least density printed: equation 1 with the bead at E_w,min (thinner beads do not hold the layer).")
        .metric("ew_min", "E_w,min", j.density.min_width_mm, "mm", "Narrowest bead (equation 2: l_h).")
        .metric("ew_max", "E_w,max", j.density.max_width_mm, "mm", "Widest bead (equation 3: 3φ).")
        .metric(
            "cell_eq4",
            "L_cell for ρ = 1 (eq. 4)",
            m.cell_eq4_mm,
            "mm",
            "Equation 4: the cell whose beads at E_w,max make a solid; larger cells cannot reach ρ = 1.",
        )
        .metric("k_c", "k_c", m.cell.k_c, "", "Toolpath length in a unit cell ÷ L_cell for this pattern (table 1).")
        .metric("segment", "Grading step", m.segment_mm, "mm", "Infill segments are split to this length so the grading resolves the voxels.");
    if let Some((slope, intercept)) = m.line {
        r = r.metric("slope", "P slope", slope * 1000.0, "per 1000 HU", "Equation 7: P = slope · HU + intercept (the femur case: −0.529 per 1000 HU).").metric(
            "intercept",
            "P intercept",
            intercept,
            "",
            "Equation 7's constant (the femur case: 0.901867).",
        );
    }
    // The calibration, plotted over the ROI's HU range.
    let h = volume::histogram(vol, roi, 64);
    // The points may be given in any order: the range covers all of them.
    let (lo, hi) = cal.points.iter().fold((h.min, h.max), |(lo, hi), p| (lo.min(p[0]), hi.max(p[0])));
    let curve = cal.curve();
    let xs: Vec<f64> = (0..=40).map(|i| lo + (hi - lo) * i as f64 / 40.0).collect();
    r.plots.push(Plot {
        key: "calibration".into(),
        title: "HU → porosity P and density ρ".into(),
        kind: PlotKind::Line,
        x: Axis::new("CT value", "HU"),
        y: Axis::new("P, ρ", ""),
        group: None,
        series: vec![
            Series::xy("P (equation 7)", xs.clone(), xs.iter().map(|&x| curve.porosity(x)).collect()),
            Series::xy("ρ = 1 − P, clamped", xs.clone(), xs.iter().map(|&x| curve.density(x, m.rho_min)).collect()),
            Series::hline("ρ_min", m.rho_min),
        ],
    });
    let edges = |h: &volume::Histogram| (0..=h.counts.len()).map(|i| h.min + h.bin_width * i as f64).collect::<Vec<_>>();
    r.plots.push(Plot {
        key: "hu_histogram".into(),
        title: "HU in the region of interest".into(),
        kind: PlotKind::Histogram,
        x: Axis::new("CT value", "HU"),
        y: Axis::new("Voxels", ""),
        group: None,
        series: vec![Series::xy("voxels", edges(&h), h.counts.iter().map(|&c| c as f64).collect())],
    });
    // Figure 2: ρ_s against L_cell for the three patterns at this nozzle and layer.
    let ls: Vec<f64> = (0..=40).map(|i| 1.0 + 5.0 * i as f64 / 40.0).collect();
    r.plots.push(Plot {
        key: "rho_s_of_cell".into(),
        title: "Infill density against cell size (equation 1, Fig. 2)".into(),
        kind: PlotKind::Line,
        x: Axis::new("L_cell", "mm"),
        y: Axis::new("ρ_s", ""),
        group: None,
        series: scaffold::coefficients_table()
            .iter()
            .map(|(name, c)| Series::xy(name, ls.clone(), ls.iter().map(|&l| scaffold::infill_density(*c, l, m.nozzle_mm, m.layer_mm)).collect()))
            .collect(),
    });
    r
}

pub(super) fn cells_report(r: &scaffold::cells::CellsReport, o: &scaffold::cells::Options) -> StageReport {
    let mut s = StageReport::new("cells", "Sizing the cells", r)
        .metric("nodes", "Cell-size nodes", r.nodes as f64, "", "Nodes of the cell-size grid (one per L_s over the part); the size is trilinear between them.")
        .metric("sampled", "Nodes in the volume", r.sampled as f64, "", "Nodes with CT density around them.")
        .metric(
            "smaller",
            "Cells made smaller",
            r.smaller as f64,
            "",
            "Density above what E_w,max gives at L_s: a smaller cell reaches it with a printable bead.",
        )
        .metric("larger", "Cells made larger", r.larger as f64, "", "Density below what E_w,min gives at L_s: a larger cell reaches it with a bead that holds.")
        .metric(
            "still_out",
            "Still out of range",
            r.still_out_of_range as f64,
            "",
            "Re-sized cells whose bead is outside [E_w,min, E_w,max] even at the size bound (the grading clamps them).",
        )
        .metric("min_cell", "Smallest cell", r.min_cell_mm, "mm", "The smallest cell written.")
        .metric("max_cell", "Largest cell", r.max_cell_mm, "mm", "The largest cell written.")
        .metric("reference", "L_s", o.reference_mm, "mm", "The uniform cell (equation 1 at ρ_s), kept where the bead is printable.");
    let col = |label: &str, unit: &str| Column { label: label.into(), unit: unit.into() };
    s.tables.push(Table {
        key: "resized".into(),
        title: format!("Re-sized cells (the first {} of {})", r.resized.len(), r.smaller + r.larger),
        group: None,
        columns: vec![col("x", "mm"), col("y", "mm"), col("z", "mm"), col("ρ", ""), col("Bead at L_s", "mm"), col("Cell", "mm"), col("Bead", "mm")],
        rows: r
            .resized
            .iter()
            .map(|c| TableRow {
                group_index: None,
                cells: vec![
                    c.centre_mm[0].into(),
                    c.centre_mm[1].into(),
                    c.centre_mm[2].into(),
                    c.rho.into(),
                    c.width_at_reference_mm.into(),
                    c.cell_mm.into(),
                    c.width_mm.into(),
                ],
            })
            .collect(),
    });
    s
}

/// Both routes' per-layer density on one toolpath.
#[derive(Serialize)]
pub(super) struct CompareReport {
    pub(super) native: Vec<LayerStat>,
    pub(super) edit: Vec<LayerStat>,
    pub(super) edited_moves: usize,
}

pub(super) fn grade_report(r: &grade::GradeReport) -> StageReport {
    let saved = if r.uniform_mm3 > 0.0 { 1.0 - r.infill_mm3 / r.uniform_mm3 } else { 0.0 };
    let mut s = StageReport::new("grade", "Grading the infill", r)
        .metric("segments", "Infill segments", r.segments as f64, "", "Infill segments written, each with its own extrusion.")
        .metric("split", "Added by splitting", r.split_added as f64, "", "Segments cut so none is longer than the grading step.")
        .metric(
            "clamped_low",
            "Raised to ρ_min",
            r.clamped_low as f64,
            "",
            "Segments whose target was below ρ_min (a bead narrower than E_w,min would not hold).",
        )
        .metric("over_flow", "Over Q_max", r.over_flow as f64, "", "Segments needing more melt per second than the hot end gives at the infill speed.")
        .metric("over_width", "Over E_w,max", r.over_width as f64, "", "Segments whose bead would be wider than E_w,max.")
        .metric("outside", "Outside the volume", r.outside as f64, "", "Segments with no CT value under them, printed at ρ_s.")
        .metric("max_width", "Widest bead", r.max_width_mm, "mm", "The widest infill bead written (stadium bead model).")
        .metric("max_flow", "Highest flow", r.max_flow_mm3_s, "mm³/s", "The largest volumetric flow written, at the infill speed.")
        .metric("infill", "Infill material", r.infill_mm3, "mm³", "Infill volume as graded.")
        .metric("saved", "Material saved", saved * 100.0, "%", "Infill material saved against a uniform infill at ρ_s (negative: more material).");
    layer_plots(&mut s, &r.layers);
    s
}

/// Per-layer target and achieved ρ: a plot along Z and a table.
pub(super) fn layer_plots(s: &mut StageReport, layers: &[LayerStat]) {
    let used: Vec<&LayerStat> = layers.iter().filter(|l| l.moves > 0).collect();
    let z: Vec<f64> = used.iter().map(|l| l.z_mm).collect();
    let n: f64 = used.iter().map(|l| l.length_mm).sum();
    let err = if n > 0.0 { used.iter().map(|l| l.mean_abs_error * l.length_mm).sum::<f64>() / n } else { 0.0 };
    s.metrics.push(crate::report::Metric {
        key: "mean_abs_error".into(),
        label: "Mean |achieved − target| ρ".into(),
        value: err,
        unit: "".into(),
        hint: "Length-weighted over the infill: how far the written density is from the field's mean along each segment.".into(),
        group_index: None,
    });
    s.plots.push(Plot {
        key: "rho_per_layer".into(),
        title: "Mean density per layer".into(),
        kind: PlotKind::Line,
        x: Axis::new("Z", "mm"),
        y: Axis::new("ρ", ""),
        group: None,
        series: vec![
            Series::xy("target", z.clone(), used.iter().map(|l| l.target_mean).collect()),
            Series::xy("achieved", z.clone(), used.iter().map(|l| l.achieved_mean).collect()),
        ],
    });
    let col = |label: &str, unit: &str| Column { label: label.into(), unit: unit.into() };
    s.tables.push(Table {
        key: "layers".into(),
        title: "Density per layer".into(),
        group: None,
        columns: vec![col("Z", "mm"), col("Segments", ""), col("Length", "mm"), col("Target ρ", ""), col("Achieved ρ", ""), col("Mean |error|", "")],
        rows: used
            .iter()
            .map(|l| TableRow {
                group_index: None,
                cells: vec![l.z_mm.into(), l.moves.into(), l.length_mm.into(), l.target_mean.into(), l.achieved_mean.into(), l.mean_abs_error.into()],
            })
            .collect(),
    });
}

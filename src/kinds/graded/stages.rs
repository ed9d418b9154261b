//! The graded job's stages: the CT volume, the bone surface, the density model; then the native route (cells, slice, grade, compare) or the edit of another slicer's G-code; the work each will do.

use super::*;

/// The work each stage will do (`Kind::estimate`), refused over a budget before any is done.
pub(super) fn estimate(j: &GradedJob, ctx: &mut Ctx) -> Result<Vec<Estimate>, Error> {
    let input = volume_input(j)?;
    let mut out = vec![ctx.volume_estimate("volume", input, &volume_options(j))?];
    let vol = volume_stage(j, ctx)?;
    let roi = roi_of(j, &vol);
    let surface_e = isosurface::estimate(&vol, &roi, &j.surface);
    let refused = surface_e.refused.is_some();
    out.push(surface_e);
    if refused {
        return Ok(out);
    }
    // The surface model is bounded by its own estimate, like an imported mesh: made here,
    // kept for the run.
    let surface = surface_stage(j, ctx, &vol)?;
    match j.route {
        Route::Native => {
            let (mesh, _) = placed(&surface.mesh);
            let model = Model::of(j, ctx.design, &vol)?;
            let s = slice::estimate(&mesh, &slice_options(j, &model));
            let infill_mm = surface.report.volume_mm3 * model.cell.k_c * model.cell.m / model.cell_mm / j.slice.layer_height_mm;
            if j.density.cell_sizing == CellSizing::Graded {
                if let Some(b) = mesh.bounds() {
                    out.push(scaffold::cells::estimate(&b, &cells_options(j, &model)));
                }
            }
            let sliced_moves = s.get("segments");
            let segments = sliced_moves + infill_mm / model.segment_mm;
            out.push(s);
            out.push(Estimate::new("grade").quantity("segments", "Toolpath segments", segments, "").cost(segments * 120.0, segments * 2e-7).limit(
                "infill segments after splitting",
                segments,
                grade::MAX_SEGMENTS as f64,
                "",
                "raise the grading step (job.density.segment_mm)",
            ));
            if j.compare_edit && j.density.cell_sizing == CellSizing::Fixed {
                // The ungraded G-code (about 30 bytes per move) and its edited copy.
                let bytes = (sliced_moves * 30.0) as usize;
                let mut e = gcode_edit::estimate(bytes, &edit_options(j, ctx.design, [0.0; 3], model.segment_mm));
                e.stage = "compare";
                if let Some(r) = e.refused.as_mut() {
                    r.fix = "turn off 'Compare with the edit route' (job.compare_edit)".into();
                }
                out.push(e);
            }
        }
        Route::Edit => {
            let input =
                j.gcode.as_ref().ok_or_else(|| Error::NoInput("route 'edit' needs another slicer's G-code: load it, or pass --input gcode=FILE".into()))?;
            let (source, _) = ctx.file_source("gcode", input)?;
            let e = gcode_edit::estimate(source.len(), &edit_options(j, ctx.design, [0.0; 3], 1.0));
            // The analyzer reads about one segment per 30 bytes of G-code.
            let segments = source.len() as f64 / 30.0;
            out.push(e.quantity("segments", "Moves (about)", segments, ""));
        }
    }
    Ok(out)
}

pub(super) fn volume_input(j: &GradedJob) -> Result<&Input, Error> {
    j.volume.as_ref().ok_or_else(|| {
        Error::NoInput(
            "a graded job needs a CT volume: drop a DICOM series (folder, files or .zip), an NRRD or a .raw file, or pass --input volume=FOLDER".into(),
        )
    })
}

pub(super) fn volume_options(j: &GradedJob) -> volume::Options {
    volume::Options { raw: j.raw.clone() }
}

pub(super) fn volume_stage(j: &GradedJob, ctx: &mut Ctx) -> Result<Out<Volume>, Error> {
    let input = volume_input(j)?;
    ctx.volume("volume", input, &volume_options(j))
}

/// The ROI, or the whole grid.
pub(super) fn roi_of(j: &GradedJob, vol: &Volume) -> Roi {
    j.roi.unwrap_or_else(|| Roi::whole(vol))
}

pub(super) fn surface_stage(j: &GradedJob, ctx: &mut Ctx, vol: &Out<Volume>) -> Result<Out<isosurface::Surface>, Error> {
    let roi = roi_of(j, vol);
    // Kept: the estimate makes the surface model (to bound the slicing) and the run reads it.
    ctx.stage_kept("surface", "surface", &(&j.surface, &roi), &[vol.key], |progress| {
        let s = isosurface::extract(vol, &roi, &j.surface, progress).map_err(|e| Error::stage("surface model", e))?;
        let r = &s.report;
        let report = StageReport::new("surface", "Extracting the surface model", r)
            .metric("triangles", "Triangles", r.triangles as f64, "", "Facets of the surface model (marching cubes at the isovalue inside the ROI).")
            .metric("volume", "Volume", r.volume_mm3, "mm³", "Volume enclosed by the surface model.")
            .metric("area", "Surface area", r.area_mm2, "mm²", "Area of the surface model.")
            .metric("cavities", "Cavities filled", r.cavities_filled as f64, "", "Closed voids inside the solid (a medullary canal) filled before meshing.")
            .metric("components", "Pieces", r.components as f64, "", "Separate solids found inside the ROI.")
            .metric("closed", "Closed", if r.closed { 1.0 } else { 0.0 }, "", "1: every edge joins exactly two triangles (watertight, slices cleanly).");
        Ok((s, Some(report)))
    })
}

/// The numbers of the paper's model for this design (equations 1–4).
#[derive(Clone, Debug, Serialize)]
pub(super) struct Model {
    pub(super) pattern: InfillPattern,
    pub(super) cell: Cell,
    pub(super) rho_s: f64,
    pub(super) nozzle_mm: f64,
    pub(super) layer_mm: f64,
    /// L_cell from equation 1 at ρ_s, mm.
    pub(super) cell_mm: f64,
    /// ρ_min: equation 1 at E_w,min.
    pub(super) rho_min: f64,
    /// The bead at ρ_s (equation 1's 1.25 φ), mm².
    pub(super) nominal_area_mm2: f64,
    /// L_cell from equation 4 for ρ = 1, mm.
    pub(super) cell_eq4_mm: f64,
    /// Grading step, mm.
    pub(super) segment_mm: f64,
    /// The calibration as a line (2 points): slope, intercept.
    pub(super) line: Option<(f64, f64)>,
}

pub(super) fn cell_of(p: InfillPattern) -> Cell {
    match p {
        InfillPattern::Gyroid => scaffold::GYROID,
        InfillPattern::Rectilinear => scaffold::RECTILINEAR,
        InfillPattern::Honeycomb3d => scaffold::HONEYCOMB_3D,
    }
}

impl Model {
    pub(super) fn of(j: &GradedJob, design: &Design, vol: &Volume) -> Result<Model, Error> {
        let (nozzle, layer) = (design.printer.nozzle_diameter_mm, j.slice.layer_height_mm);
        let (pattern, rho_s) = match j.route {
            Route::Native => (j.slice.infill_pattern, j.slice.infill_density),
            Route::Edit => (j.slice.infill_pattern, j.gcode_rho_s),
        };
        if !(rho_s > 0.0 && rho_s <= 1.0) {
            return Err(Error::NoInput(format!("the infill density ρ_s is {rho_s}: set it between 1 % and 100 %")));
        }
        let cell = cell_of(pattern);
        let cell_mm = scaffold::cell_size_for_density(cell, rho_s, nozzle, layer);
        let rho_min = scaffold::density_at_width(cell, cell_mm, j.density.min_width_mm, layer).clamp(0.0, 1.0);
        let segment_mm = grading_step(j, vol);
        Ok(Model {
            pattern,
            cell,
            rho_s,
            nozzle_mm: nozzle,
            layer_mm: layer,
            cell_mm,
            rho_min,
            nominal_area_mm2: scaffold::bead_area(1.25 * nozzle, layer),
            cell_eq4_mm: scaffold::cell_size_for_width(cell, j.density.max_width_mm, 1.0),
            segment_mm,
            line: j.density.calibration.line(),
        })
    }
}

/// The grading step, mm: the design's, else the smallest voxel spacing.
pub(super) fn grading_step(j: &GradedJob, vol: &Volume) -> f64 {
    let smallest_voxel = vol.spacing_mm.iter().copied().fold(f64::INFINITY, f64::min);
    if j.density.segment_mm > 0.0 {
        j.density.segment_mm
    } else {
        smallest_voxel.clamp(0.05, 100.0)
    }
}

/// The density stage: the model's numbers, the calibration and ρ over the solid voxels.
pub(super) fn density_stage(j: &GradedJob, ctx: &mut Ctx, vol: &Out<Volume>, surface: &Out<isosurface::Surface>) -> Result<Out<Model>, Error> {
    let model = Model::of(j, ctx.design, vol)?;
    let roi = roi_of(j, vol);
    let parts = (&j.density, model.rho_s, model.cell_mm, roi, j.surface.iso);
    ctx.stage("density", "density", &parts, &[vol.key, surface.key], |_| {
        let report = density_report(j, &model, vol, &roi);
        Ok((model, Some(report)))
    })
}

pub(super) fn slice_options(j: &GradedJob, m: &Model) -> slice::Options {
    slice::Options { infill_pattern: m.pattern, infill_density: m.rho_s, infill_cell_mm: Some(m.cell_mm), ..j.slice.clone() }
}

/// The mesh placed on the plate (XY centred, lowest point at Z = 0) and the offset applied.
pub(super) fn placed(mesh: &Mesh) -> (Mesh, DVec3) {
    let mut m = mesh.clone();
    let Some(b) = mesh.bounds() else { return (m, DVec3::ZERO) };
    let c = (b.min + b.max) * 0.5;
    let offset = DVec3::new(-c.x, -c.y, -b.min.z);
    m.translate(offset);
    (m, offset)
}

pub(super) fn native(j: &GradedJob, ctx: &mut Ctx, vol: &Out<Volume>, surface: &Out<isosurface::Surface>, model: &Out<Model>) -> Result<Product, Error> {
    let n = native_stages(j, ctx, vol, surface, model)?;
    // The edit route cannot know a re-sized cell: compared only with one cell everywhere.
    if j.compare_edit && !n.cells {
        compare(j, ctx, vol, &n.sliced, model, &n.grade, n.offset)?;
    }
    Ok(Product::Toolpath(n.graded))
}

/// The native route's stages up to the graded toolpath.
pub(super) struct Native {
    /// The toolpath as sliced.
    pub(super) sliced: Out<crate::geom::Toolpath>,
    /// The graded toolpath.
    pub(super) graded: Out<crate::geom::Toolpath>,
    /// The grading options.
    pub(super) grade: grade::Options,
    /// The placement offset (toolpath point = volume point + offset).
    pub(super) offset: DVec3,
    /// The cell was re-sized (graded cell sizing).
    pub(super) cells: bool,
}

/// Slices the placed surface model and grades its infill (the native route without the
/// comparison with the edit route).
pub(super) fn native_stages(j: &GradedJob, ctx: &mut Ctx, vol: &Out<Volume>, surface: &Out<isosurface::Surface>, model: &Out<Model>) -> Result<Native, Error> {
    let mut options = slice_options(j, model);
    let (mesh, offset) = placed(&surface.mesh);
    crate::kinds::part_fits(ctx.design, &mesh)?;
    let field = density_field(j, vol);
    let rho = |p: DVec3| field(p - offset);
    let mut slice_upstream = vec![surface.key];
    let cells = match j.density.cell_sizing {
        CellSizing::Fixed => None,
        CellSizing::Graded => {
            let bounds = mesh.bounds().ok_or_else(|| Error::NoInput("the surface model is empty: lower the isovalue or widen the ROI".into()))?;
            let o = cells_options(j, model);
            let parts = (format!("{o:?}"), &j.density.calibration, offset.to_array());
            let cells = ctx.stage("cells", "cells", &parts, &[surface.key, vol.key], |_| {
                let sized = scaffold::cells::size_cells(&bounds, &rho, &o).map_err(|e| Error::stage("sizing the cells", e))?;
                let report = cells_report(&sized.report, &o);
                Ok((Arc::new(sized.field), Some(report)))
            })?;
            options.infill_cell_field = Some(cells.value.as_ref().clone());
            slice_upstream.push(cells.key);
            Some(cells)
        }
    };
    let sliced = ctx.stage("slice", "slice", &options, &slice_upstream, |progress| {
        let sliced = slice::slice(&mesh, &options, progress).map_err(|e| Error::stage("slicing", e))?;
        let report = crate::kinds::slice_report(&sliced.report, "Slicing the surface model");
        Ok((sliced.toolpath, Some(report)))
    })?;
    drop(mesh);
    let design = ctx.design;
    let g = grade::Options {
        rho_s: model.rho_s,
        rho_min: model.rho_min,
        nominal_area_mm2: model.nominal_area_mm2,
        segment_mm: model.segment_mm,
        q_max_mm3_s: j.density.q_max_mm3_s,
        width_max_mm: j.density.max_width_mm,
        limit: j.density.limit,
        feed_mm_s: design.speeds.infill_mm_s,
    };
    let parts = (format!("{g:?}"), &j.density.calibration);
    let graded = ctx.stage("grade", "grade", &parts, &[sliced.key, vol.key], |progress| {
        let ratio = cells.as_ref().map(|c| move |p: DVec3| c.at(p) / c.reference_mm);
        let mut out = grade::grade(&sliced, &rho, ratio.as_ref().map(|f| f as &dyn Fn(DVec3) -> f64), &g, progress).map_err(|e| Error::stage("grading", e))?;
        out.report.offset_mm = offset.to_array();
        let report = grade_report(&out.report);
        Ok((out.toolpath, Some(report)))
    })?;
    Ok(Native { sliced, graded, grade: g, offset, cells: cells.is_some() })
}

pub(super) fn cells_options(j: &GradedJob, m: &Model) -> scaffold::cells::Options {
    scaffold::cells::Options {
        cell: m.cell,
        reference_mm: m.cell_mm,
        width_min_mm: j.density.min_width_mm,
        width_max_mm: j.density.max_width_mm,
        layer_mm: m.layer_mm,
        max_ratio: j.density.max_cell_ratio,
    }
}

/// The paper's route on the same toolpath: `sliced` written as G-code without grading, its
/// infill moves' E rewritten by the field at their midpoints ([`gcode_edit`]); both routes'
/// per-layer error, measured the same way ([`scaffold::mean_along`]), in one plot.
pub(super) fn compare(
    j: &GradedJob,
    ctx: &mut Ctx,
    vol: &Out<Volume>,
    sliced: &Out<crate::geom::Toolpath>,
    model: &Model,
    g: &grade::Options,
    offset: DVec3,
) -> Result<(), Error> {
    let native_layers: Vec<LayerStat> = ctx
        .reports
        .iter()
        .find(|r| r.stage == "grade")
        .and_then(|r| serde_json::from_value::<grade::GradeReport>(r.data.clone()).ok())
        .map(|r| r.layers)
        .unwrap_or_default();
    let design = ctx.design;
    let writer = crate::stage::writer_options(design);
    // G-code point = volume point + placement offset + the bed's origin offset.
    let to_volume = -(offset + crate::gcode::bed_offset(&writer));
    let options = gcode_edit::Options {
        rho_s: model.rho_s,
        rho_min: model.rho_min,
        translation_mm: to_volume.to_array(),
        // The target sampled as the native route's grading samples it (its pieces are one step).
        ..edit_options(j, design, [0.0; 3], model.segment_mm / 4.0)
    };
    let parts = (format!("{g:?}"), format!("{options:?}"), &j.density.calibration, &design.printer, &design.material, &design.speeds);
    ctx.stage("compare", "compare", &parts, &[sliced.key, vol.key], |progress| {
        let written = crate::gcode::write_gcode(sliced, &writer).map_err(|e| Error::stage("writing the comparison's G-code", e))?;
        progress(0.3);
        let rho = density_field(j, vol);
        let edited = gcode_edit::edit("compare.gcode", &written.text.as_bytes(), &rho, &options, &mut |x| progress(0.3 + 0.7 * x))
            .map_err(|e| Error::stage("editing the comparison's G-code", e))?;
        let edit_layers = edited.report.layers;
        let mean = |ls: &[LayerStat]| {
            let n: f64 = ls.iter().map(|l| l.length_mm).sum();
            if n > 0.0 {
                ls.iter().map(|l| l.mean_abs_error * l.length_mm).sum::<f64>() / n
            } else {
                0.0
            }
        };
        let (e_native, e_edit) = (mean(&native_layers), mean(&edit_layers));
        let used = |ls: &[LayerStat]| ls.iter().filter(|l| l.moves > 0).map(|l| (l.z_mm, l.mean_abs_error)).unzip::<f64, f64, Vec<f64>, Vec<f64>>();
        let ((zn, en), (ze, ee)) = (used(&native_layers), used(&edit_layers));
        let mut report = StageReport::new(
            "compare",
            "Native against the edit route",
            &CompareReport { native: native_layers.clone(), edit: edit_layers.clone(), edited_moves: edited.report.edited_moves },
        )
        .metric(
            "native_error",
            "Native: mean |achieved − target| ρ",
            e_native,
            "",
            "weft's own grading: segments split to the grading step, each graded by the field at its midpoint.",
        )
        .metric(
            "edit_error",
            "Edit route: mean |achieved − target| ρ",
            e_edit,
            "",
            "The paper's route on the same toolpath: whole moves, each graded by the field at its midpoint.",
        )
        .metric(
            "error_ratio",
            "Edit ÷ native error",
            if e_native > 0.0 { e_edit / e_native } else { 0.0 },
            "×",
            "How many times further from the field the edit route's infill is (0 when native is exact).",
        )
        .metric(
            "edit_moves",
            "Edited moves",
            edited.report.edited_moves as f64,
            "",
            "Infill moves the edit route rewrote (native splits them into more, shorter segments).",
        );
        report.plots.push(Plot {
            key: "error_per_layer".into(),
            title: "Density error per layer: native against edit".into(),
            kind: PlotKind::Line,
            x: Axis::new("Z", "mm"),
            y: Axis::new("Mean |achieved − target| ρ", ""),
            group: None,
            series: vec![Series::xy("native (split)", zn, en), Series::xy("edit (whole moves)", ze, ee)],
        });
        Ok(((), Some(report)))
    })?;
    Ok(())
}

/// The edit route's options; its report samples the target every `target_step_mm` along each move.
pub(super) fn edit_options(j: &GradedJob, design: &Design, translation: [f64; 3], target_step_mm: f64) -> gcode_edit::Options {
    let cell = cell_of(j.slice.infill_pattern);
    let cell_mm = scaffold::cell_size_for_density(cell, j.gcode_rho_s, design.printer.nozzle_diameter_mm, j.slice.layer_height_mm);
    gcode_edit::Options {
        rho_s: j.gcode_rho_s,
        rho_min: scaffold::density_at_width(cell, cell_mm, j.density.min_width_mm, j.slice.layer_height_mm).clamp(0.0, 1.0),
        rho_max: 1.0,
        limit: j.density.limit,
        q_max_mm3_s: j.density.q_max_mm3_s,
        width_max_mm: j.density.max_width_mm,
        filament_mm: design.printer.filament_diameter_mm,
        translation_mm: translation,
        infill_types: j.gcode_infill_types.clone(),
        target_step_mm,
    }
}

/// The target density ρ(p) of the volume (p in the volume's frame, mm; `None` outside it),
/// trilinear in the calibrated voxels; unclamped below: grading raises targets below ρ_min
/// itself and counts them (the paper's pseudocode).
pub(super) fn density_field<'v>(j: &GradedJob, vol: &'v Volume) -> impl Fn(DVec3) -> Option<f64> + 'v {
    let curve = j.density.calibration.curve();
    let sampler = volume::Sampler::new(vol, move |hu: f32| curve.density(hu as f64, 0.0));
    move |p| sampler.sample(p)
}

pub(super) fn edit(j: &GradedJob, ctx: &mut Ctx, vol: &Out<Volume>, surface: &Out<isosurface::Surface>) -> Result<Product, Error> {
    let input = j.gcode.as_ref().ok_or_else(|| Error::NoInput("route 'edit' needs another slicer's G-code: load it, or pass --input gcode=FILE".into()))?;
    // Read line by line (a file the page keeps outside wasm memory is never copied in whole).
    let (bytes, key) = ctx.file_source("gcode", input)?;
    let name = match input {
        Input::File { name, .. } => name.clone(),
        _ => "G-code".into(),
    };
    // v⃗: G-code point = volume point + v⃗; the editor adds `translation` to a G-code point.
    let v = match j.alignment.mode {
        AlignMode::Manual => DVec3::from(j.alignment.translation_mm),
        AlignMode::Auto => {
            let printed = gcode_edit::printed_bounds(&name, &bytes).map_err(|e| Error::stage("editing the G-code", e))?;
            let model = surface.mesh.bounds().ok_or_else(|| Error::NoInput("the surface model is empty: lower the isovalue or widen the ROI".into()))?;
            let (pc, mc) = ((printed.min + printed.max) * 0.5, (model.min + model.max) * 0.5);
            DVec3::new(pc.x - mc.x, pc.y - mc.y, -model.min.z)
        }
    };
    // The target along each whole move sampled once per grading step (a voxel): its mean
    // error is within 4 % of sampling every quarter step (0.00384 against 0.00402 on the
    // benchmark's file), at half the edit's time (BENCHMARKS.md).
    let options = edit_options(j, ctx.design, (-v).to_array(), grading_step(j, vol));
    let parts = (format!("{options:?}"), &j.density.calibration);
    let text = ctx.stage("edit", "edit", &parts, &[key, vol.key], |progress| {
        let rho = density_field(j, vol);
        let out = gcode_edit::edit(&name, &bytes, &rho, &options, progress).map_err(|e| Error::stage("editing the G-code", e))?;
        let r = &out.report;
        let saved = if r.infill_before_mm3 > 0.0 { 1.0 - r.infill_after_mm3 / r.infill_before_mm3 } else { 0.0 };
        let mut report = StageReport::new("edit", "Editing the G-code's infill", r)
            .metric("translation_x", "v⃗ x", v.x, "mm", "Alignment: G-code point = volume point + v⃗ (equation 5).")
            .metric("translation_y", "v⃗ y", v.y, "mm", "Alignment, y.")
            .metric("translation_z", "v⃗ z", v.z, "mm", "Alignment, z.")
            .metric("infill_moves", "Infill moves", r.infill_moves as f64, "", "Extruding moves inside the file's infill sections.")
            .metric("edited", "Moves edited", r.edited_moves as f64, "", "Infill moves whose E was rewritten by equation 6.")
            .metric("outside", "Outside the volume", r.outside_field as f64, "", "Infill moves with no CT value at their midpoint: left as they were.")
            .metric("clamped_low", "Raised to ρ_min", r.clamped_low as f64, "", "Moves whose target was below ρ_min.")
            .metric("over_flow", "Over Q_max", r.over_flow as f64, "", "Moves needing more melt per second than the hot end gives.")
            .metric("over_width", "Over E_w,max", r.over_width as f64, "", "Moves whose bead would be wider than E_w,max.")
            .metric(
                "resets",
                "G92 lines added",
                r.resets_inserted as f64,
                "",
                "Absolute-E files: one 'G92 E…' after each run of edited moves keeps every other line's E valid and unchanged.",
            )
            .metric("saved", "Material saved", saved * 100.0, "%", "Infill material saved against the file as sliced (negative: more material).");
        layer_plots(&mut report, &r.layers);
        let text = String::from_utf8(out.text).map_err(|_| Error::NoInput(format!("{name}: the edited G-code is not UTF-8 text")))?;
        Ok((text, Some(report)))
    })?;
    Ok(Product::Gcode(text))
}

//! The lattice job's stages: the pattern clipped to each layer's outline (or projected onto a surface) as strokes, then the paths; the work each will do.

use super::*;

/// The work each stage will do (`Kind::estimate`), refused over a budget before any is done.
pub(super) fn estimate(j: &LatticeJob, ctx: &mut Ctx) -> Result<Vec<crate::budget::Estimate>, Error> {
    let size = match j.domain {
        Domain::Solid => {
            let input = j.input.as_ref().ok_or_else(|| Error::NoInput("a solid lattice domain needs a mesh: load one, or pass --input mesh=FILE".into()))?;
            let mesh = ctx.mesh(&SLOTS[0], input)?;
            lattice::DomainSize::of_mesh(&mesh, j.lattice.layer_thickness_mm)
        }
        _ => lattice::DomainSize::planar(&j.domain, &j.lattice),
    };
    let lat = lattice::estimate(&size, &j.lattice, line_width(ctx.design));
    let optimised = paths::estimate(&paths::Work::of_lattice(&lat), &j.paths);
    let mut out = vec![lat];
    if let Some(np) = &j.nonplanar {
        let surface = match (&np.surface, &j.surface_input) {
            (nonplanar::Surface::Mesh, Some(input)) => Some(nonplanar::SurfaceSize::of_mesh(&*ctx.mesh(&SLOTS[1], input)?, size.min, size.max)),
            _ => None,
        };
        let projected = nonplanar::estimate(&nonplanar::Work::of_paths(&optimised, size.min, size.max), surface.as_ref(), np);
        out.push(optimised);
        out.push(projected);
    } else {
        out.push(optimised);
    }
    Ok(out)
}

/// The lattice strokes of every layer of a lattice design (for `export-stl` and benchmarks):
/// the same stages as a run, without a cache.
pub fn lattice_strokes(design: &Design, files: &crate::stage::Files) -> Result<Vec<StrokeLayer>, Error> {
    let j: LatticeJob = design.job.settings().ok_or_else(|| Error::BadJob(format!("a {} job has no lattice", design.job.kind())))?;
    let mut cache = crate::stage::Cache::disabled();
    let mut quiet = |_: &str, _: f32| {};
    let mut ctx = Ctx::new(design, files, &mut cache, &mut quiet);
    let out = strokes(&j, &mut ctx)?;
    Ok(std::sync::Arc::try_unwrap(out.value).unwrap_or_else(|a| (*a).clone()))
}

/// The domain of every layer (built-in planar shapes directly, a solid by slicing it every
/// layer thickness) and the lattice strokes on them.
pub(super) fn strokes(j: &LatticeJob, ctx: &mut Ctx) -> Result<Out<Vec<StrokeLayer>>, Error> {
    let design = ctx.design;
    let domains: Out<Vec<LayerDomain>> = match j.domain {
        // Built inside the stage, so a cached run does not build them again.
        Domain::Rectangle { .. } | Domain::Disc { .. } | Domain::TensileSpecimen { .. } => {
            // Refused before the layers' polygons are built (many layers of a big disc are
            // themselves large).
            let size = lattice::DomainSize::planar(&j.domain, &j.lattice);
            lattice::estimate(&size, &j.lattice, line_width(design)).check().map_err(|e| Error::stage("lattice", lattice::Error::OverBudget(e)))?;
            ctx.stage("domains", "domains", &(&j.domain, &j.lattice), &[], |_| Ok((lattice::planar_domains(&j.domain, &j.lattice).unwrap_or_default(), None)))?
        }
        Domain::Solid => {
            let input = j.input.as_ref().ok_or_else(|| Error::NoInput("a solid lattice domain needs a mesh: load one, or pass --input mesh=FILE".into()))?;
            let mesh = ctx.mesh(&SLOTS[0], input)?;
            let t = j.lattice.layer_thickness_mm;
            let options = slice::Options {
                first_layer_height_mm: t,
                layer_height_mm: t,
                perimeters: 0,
                infill_density: 0.0,
                solid_layers: 0,
                ..slice::Options::default()
            };
            ctx.stage("slice", "domains", &options, &[mesh.key], |progress| {
                let sliced = slice::slice(&mesh, &options, progress).map_err(|e| Error::stage("slicing", e))?;
                let report = crate::kinds::slice_report(&sliced.report, "Slicing the solid");
                let domains = sliced.layers.into_iter().map(|l| LayerDomain { z: l.z, height: l.height, regions: l.regions, handles: Vec::new() }).collect();
                Ok((domains, Some(report)))
            })?
        }
    };
    let parts = (&j.lattice, line_width(design), design.seed, design.material.swell_ratio);
    ctx.stage("lattice", "lattice", &parts, &[domains.key], |progress| {
        let g = lattice::generate(&domains, &j.lattice, line_width(design), design.seed, progress).map_err(|e| Error::stage("lattice", e))?;
        let r = &g.report;
        let struts: usize = r.struts_per_layer.iter().sum();
        let mean_pore =
            if r.pore_fraction_per_layer.is_empty() { 0.0 } else { r.pore_fraction_per_layer.iter().sum::<f64>() / r.pore_fraction_per_layer.len() as f64 };
        let report = StageReport::new("lattice", "Generating the lattice", r)
            .metric("layers", "Layers", r.layers as f64, "", "Lattice layers generated.")
            .metric("struts", "Struts", struts as f64, "", "Strut pieces over all layers (a curved strut counts once), before path optimisation.")
            .metric("pore_fraction", "Pores", 100.0 * mean_pore, "%", "Open area of a layer: the part of the domain no strut covers (mean over layers).")
            .metric("strut_width", "Strut width", line_width(design), "mm", "Nominal strut width: the nozzle diameter, what the paths are planned for.")
            .metric(
                "printed_width",
                "Predicted printed width",
                design.material.swollen_width(line_width(design)),
                "mm",
                "Nominal width × the material's die swell ratio: how wide the struts are expected to come out.",
            );
        Ok((g.layers, Some(report)))
    })
}

/// The optimised paths of every layer (the `paths` stage), from the layers' strokes.
pub(super) fn paths_stage(j: &LatticeJob, ctx: &mut Ctx, strokes: &Out<Vec<StrokeLayer>>) -> Result<Out<crate::geom::Toolpath>, Error> {
    let design = ctx.design;
    // The printer's retraction rule is in the key: the report counts its retractions.
    let key = (&j.paths, line_width(design), design.seed, &design.printer.retraction, design.printer.flavor);
    ctx.stage("paths", "paths", &key, &[strokes.key], |progress| {
        let mut o = paths::optimise(strokes, &j.paths, line_width(design), design.seed, progress).map_err(|e| Error::stage("paths", e))?;
        let counts = crate::gcode::retractions_per_pass(&o.toolpath, &design.printer);
        for (l, n) in o.report.layers.iter_mut().zip(counts) {
            l.retractions = n;
        }
        let report = paths_report(&o.report);
        Ok((o.toolpath, Some(report)))
    })
}

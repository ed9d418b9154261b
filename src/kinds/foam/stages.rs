//! The foam job's stages: the regions placed, their solids and boundaries, the layers, one raster path per layer, the grading into pieces; and the work each will do.

use super::*;

/// The work each stage will do (`Kind::estimate`), refused over a budget before any is done.
pub(super) fn estimate(j: &FoamJob, ctx: &mut Ctx) -> Result<Vec<Estimate>, Error> {
    let placed = placed_stage(j, ctx)?;
    let triangles = placed.union.triangles.len();
    let regions = Estimate::new("regions").quantity("triangles", "Triangles", triangles as f64, "").cost(triangles as f64 * 400.0, triangles as f64 * 4e-6);
    let slice_e = slice::estimate(&placed.union, &slice_options(j));
    let b = placed.union.bounds().map(|b| b.max - b.min).unwrap_or_default();
    let layers = (b.z / j.foam.layer_height_mm).ceil().max(1.0);
    let s = j.foam.line_spacing_mm;
    // Upper bounds from the box: every layer full, plus a turn per line.
    let lines = layers * (b.x.max(b.y) / s + 1.0);
    let length = layers * (b.x * b.y / s + b.x + b.y);
    let pieces = length / j.foam.piece_mm + lines;
    let raster = Estimate::new("raster")
        .quantity("lines", "Raster lines", lines, "")
        .cost(lines * 400.0, lines * 5e-6)
        .limit("raster lines", lines, raster::MAX_SCAN_INTERSECTIONS as f64, "", "raise the line spacing or the layer height")
        .budgets("raise the line spacing or the layer height");
    let grade = Estimate::new("grade")
        .quantity("pieces", "Pieces", pieces, "")
        .quantity("segments", "Segments", pieces, "")
        .cost(pieces * 72.0, pieces * 1e-6)
        .limit("pieces", pieces, MAX_PIECES, "", "raise the piece length, the line spacing or the layer height")
        .budgets("raise the piece length, the line spacing or the layer height");
    Ok(vec![regions, slice_e, raster, grade])
}

/// The regions placed together: each region's mesh, moved with the others so that their
/// union stands on the plate, XY centred on 0 (their places relative to each other kept), and
/// that union (all triangles in one mesh: touching outlines merge when sliced).
pub struct Placed {
    /// Region names (their files, or the model's).
    pub names: Vec<String>,
    /// Region meshes, placed.
    pub meshes: Vec<Mesh>,
    /// All of them in one mesh.
    pub union: Mesh,
}

/// The placed regions of the files (each imported and cached on its own) or of the built-in
/// model: made by the estimate, read again by the run.
pub(super) fn placed_stage(j: &FoamJob, ctx: &mut Ctx) -> Result<Out<Placed>, Error> {
    let mut items: Vec<(String, Out<Mesh>)> = Vec::new();
    if j.model.is_none() {
        let input = j.meshes.as_ref().ok_or_else(|| {
            Error::NoInput("a foam needs its region meshes: load one file per region (--input regions=FILE, repeated), or switch on a built-in model".into())
        })?;
        let inputs: Vec<Input> = match input {
            Input::Files(names) => names.iter().map(|n| Input::File { name: n.clone(), embedded: None }).collect(),
            other => vec![other.clone()],
        };
        // One .zip holds the region files (in name order, as a folder gives them).
        let zipped = matches!(input, Input::File { name, .. } if name.to_ascii_lowercase().ends_with(".zip"));
        if inputs.len() > MAX_REGIONS {
            return Err(Error::NoInput(format!("{} region meshes: a foam takes at most {MAX_REGIONS}", inputs.len())));
        }
        if let Some(Input::File { name, .. }) =
            inputs.iter().find(|i| matches!(i, Input::File { name, .. } if name.to_ascii_lowercase().ends_with(".zip"))).filter(|_| !zipped)
        {
            return Err(Error::NoInput(format!(
                "{name} is a zip among other region files: a zip holds all the region meshes, so load it alone (remove the other region files)"
            )));
        }
        if zipped {
            items = ctx.mesh_items_of_zip(&SLOTS[0], input)?;
        } else {
            for (i, input) in inputs.iter().enumerate() {
                let name = match input {
                    Input::File { name, .. } => name.clone(),
                    _ => format!("region {}", i + 1),
                };
                items.push((name, ctx.mesh_item(&SLOTS[0], i, input)?));
            }
        }
        if items.len() > MAX_REGIONS {
            return Err(Error::NoInput(format!("{} region meshes: a foam takes at most {MAX_REGIONS}", items.len())));
        }
    }
    let keys: Vec<crate::stage::Key> = items.iter().map(|(_, m)| m.key).collect();
    let names: Vec<&str> = items.iter().map(|(n, _)| n.as_str()).collect();
    ctx.stage_kept("place", "place", &(&j.model, &names), &keys, |_| {
        let (names, mut meshes): (Vec<String>, Vec<Mesh>) = match &j.model {
            Some(m) => models::build(m).into_iter().unzip(),
            None => items.iter().map(|(n, m)| (n.clone(), (**m).clone())).unzip(),
        };
        let mut union = Mesh::default();
        for m in &meshes {
            union.append(m);
        }
        if let Some(b) = union.bounds() {
            let shift = DVec3::new(-(b.min.x + b.max.x) / 2.0, -(b.min.y + b.max.y) / 2.0, -b.min.z);
            union.translate(shift);
            for m in &mut meshes {
                m.translate(shift);
            }
        }
        Ok((Placed { names, meshes, union }, None))
    })
}

pub(super) fn slice_options(j: &FoamJob) -> slice::Options {
    let h = j.foam.layer_height_mm;
    slice::Options { first_layer_height_mm: h, layer_height_mm: h, perimeters: 0, infill_density: 0.0, solid_layers: 0, ..slice::Options::default() }
}

/// The regions' solids and shared boundaries.
pub(super) fn regions_stage(j: &FoamJob, ctx: &mut Ctx) -> Result<Out<Regions>, Error> {
    let placed = placed_stage(j, ctx)?;
    let options = regions::Options { many_neighbours: j.foam.many_neighbours, ..regions::Options::default() };
    ctx.stage("regions", "regions", &(j.foam.many_neighbours,), &[placed.key], |_| {
        let r =
            regions::regions(placed.names.iter().cloned().zip(placed.meshes.iter().cloned()).collect(), &options).map_err(|e| Error::stage("regions", e))?;
        let shared: f64 = r.boundaries.iter().map(|b| b.area_mm2).sum();
        let report = StageReport::new(
            "regions",
            "Finding shared boundaries",
            &serde_json::json!({ "regions": r.names(), "boundaries": r.boundaries.iter().map(|b| [b.a + 1, b.b + 1]).collect::<Vec<_>>() }),
        )
        .metric("regions", "Regions", r.regions.len() as f64, "", "Region meshes, each with its own V* and H*.")
        .metric("boundaries", "Shared boundaries", r.boundaries.len() as f64, "", "Pairs of regions that share a face; transitions are centred on these.")
        .metric("shared_area", "Shared area", shared, "mm²", "Total area of the shared boundaries.")
        .metric(
            "epsilon",
            "Contact tolerance ε",
            r.epsilon_mm,
            "mm",
            "Faces closer than this count as touching (10⁻⁶ of the model's size, at least 0.1 µm).",
        );
        Ok((r, Some(report)))
    })
}

/// The union sliced: one outline per layer, or refused naming the layer and the regions.
pub(super) fn slice_stage(j: &FoamJob, ctx: &mut Ctx, regions: &Out<Regions>) -> Result<Out<Vec<Layer>>, Error> {
    let placed = placed_stage(j, ctx)?;
    let options = slice_options(j);
    ctx.stage("slice", "slice", &options, &[regions.key, placed.key], |progress| {
        let sliced = slice::slice(&placed.union, &options, &mut |f| progress(f * 0.5)).map_err(|e| Error::stage("slicing", e))?;
        // Each region alone, for the overlap check per layer.
        let mut per_region = Vec::with_capacity(placed.meshes.len());
        for (k, m) in placed.meshes.iter().enumerate() {
            let s = slice::slice(m, &options, &mut |_| {}).map_err(|e| Error::stage("slicing", e))?;
            per_region.push(s.layers);
            progress(0.5 + 0.5 * (k + 1) as f32 / placed.meshes.len() as f32);
        }
        let names: Vec<&str> = placed.names.iter().map(String::as_str).collect();
        let per_region: Vec<Vec<Cut>> = per_region.iter().map(|l| cuts(l)).collect();
        let layers = check_layers(&cuts(&sliced.layers), &per_region, &names).map_err(|e| Error::stage("slicing", e))?;
        let report = crate::kinds::slice_report(&sliced.report, "Slicing the union").metric(
            "layers",
            "Layers",
            layers.len() as f64,
            "",
            "Layers of the foam, each one outline.",
        );
        Ok((layers, Some(report)))
    })
}

/// The slicer's layers as the foam's layer checks read them.
fn cuts(layers: &[slice::SlicedLayer]) -> Vec<Cut<'_>> {
    layers.iter().map(|l| Cut { z: l.z, slice_z: l.slice_z, regions: &l.regions }).collect()
}

/// One layer's continuous path, as the raster made it.
pub struct LayerPath {
    /// Points, mm.
    pub points: Vec<DVec2>,
}

/// The raster of every layer, each starting where the last ended.
pub(super) fn raster_stage(j: &FoamJob, ctx: &mut Ctx, layers: &Out<Vec<Layer>>) -> Result<Out<Vec<LayerPath>>, Error> {
    let o = j.foam;
    ctx.stage("raster", "raster", &(o.line_spacing_mm, o.raster_angle_deg, o.alternate, o.inset), &[layers.key], |progress| {
        let mut out: Vec<LayerPath> = Vec::with_capacity(layers.len());
        let (mut scan, mut boundary, mut retraced, mut cells) = (0.0, 0.0, 0.0, 0usize);
        for (k, layer) in layers.iter().enumerate() {
            let angle = o.raster_angle_deg + if o.alternate && k % 2 == 1 { 90.0 } else { 0.0 };
            let area = inset(&layer.polygon, o.inset * o.line_spacing_mm, layer.z).map_err(|e| Error::stage("raster", e))?;
            let start = out.last().and_then(|p: &LayerPath| p.points.last().copied());
            let r = raster::raster(&area, start, &raster::Options { spacing_mm: o.line_spacing_mm, angle_deg: angle })
                .map_err(|e| Error::stage("raster", RasterAt { z: layer.z, source: e }))?;
            scan += r.raster_mm;
            boundary += r.boundary_mm;
            retraced += r.retraced_mm;
            cells += r.cells;
            out.push(LayerPath { points: r.points });
            progress((k + 1) as f32 / layers.len() as f32);
        }
        let report = StageReport::new("raster", "One continuous path per layer", &serde_json::json!({ "layers": out.len() }))
            .metric("raster", "Raster lines", scan, "mm", "Length of the scan lines of every layer.")
            .metric("turns", "Turns along the outline", boundary, "mm", "Length of the links that run along the outline between lines and cells.")
            .metric(
                "retraced",
                "Lines run twice",
                retraced,
                "mm",
                "Links that cross a part already printed to reach the next cell (printed twice: denser there); 0 for simple outlines.",
            )
            .metric("cells", "Cells", cells as f64, "", "Boustrophedon cells over all layers (each a zig-zag); more where outlines are concave or have holes.");
        Ok((out, Some(report)))
    })
}

/// A raster error with the layer it happened in.
#[derive(Debug, thiserror::Error)]
#[error("layer at z = {z:.2} mm: {source}")]
pub(super) struct RasterAt {
    z: f64,
    source: raster::Error,
}

/// The toolpath ([`grade::grade`]: each layer's path cut into pieces, each with the pair of
/// its end) once the design's pairs and transitions are checked against the regions loaded,
/// and the report with its plots.
pub(super) fn grade(
    j: &FoamJob,
    p: &Process,
    regions: &Regions,
    layers: &[Layer],
    paths: &[LayerPath],
    progress: &mut dyn FnMut(f32),
) -> Result<(Toolpath, Option<StageReport>), Error> {
    let (pairs, transitions, notes) = field_inputs(j, regions)?;
    let field = Field::new(regions, pairs.clone(), &transitions, j.foam.junction);
    let rasters: Vec<grade::LayerRaster> = paths.iter().zip(layers).map(|(path, layer)| grade::LayerRaster { z: layer.z, points: &path.points }).collect();
    let g = grade::grade(&field, p, &rasters, j.foam.layer_height_mm, j.foam.piece_mm, p.die_swell * p.nozzle_mm, progress);
    let (toolpath, pieces, queries, (v_lo, v_hi)) = (g.toolpath, g.pieces, g.queries, g.v_range);
    let mut report = grade_report(j, p, &field, regions, &transitions, pieces, queries, (v_lo, v_hi));
    report.notes.extend(notes);
    Ok((toolpath, Some(report)))
}

/// The pairs, the transitions and the notes on rows left waiting ([`field_inputs`]).
pub(super) type FieldInputs = (Vec<crate::foam::Pair>, Vec<crate::foam::Transition>, Vec<String>);

/// The pairs and transitions of the regions loaded, checked: one pair per region (rows
/// beyond them wait, said in the notes), every transition between touching regions.
pub(super) fn field_inputs(j: &FoamJob, regions: &Regions) -> Result<FieldInputs, Error> {
    let mut pairs = pairs(j);
    let n = regions.regions.len();
    if pairs.len() < n {
        return Err(Error::NoInput(format!("the foam has {n} regions but the design gives {} V*/H* pairs: give one per region", pairs.len())));
    }
    // Rows and transitions beyond the regions given wait for their files, said out loud.
    let mut notes = Vec::new();
    if pairs.len() > n {
        notes.push(format!(
            "the design gives {} V*/H* pairs for {n} region mesh(es): pair(s) {}–{} wait for their files and are not used",
            pairs.len(),
            n + 1,
            pairs.len()
        ));
        pairs.truncate(n);
    }
    let mut transitions = transitions(j);
    let waiting = transitions.iter().filter(|t| t.from >= n || t.to >= n).count();
    if waiting > 0 {
        notes.push(format!("{waiting} transition(s) join a region without its file and are not used"));
        transitions.retain(|t| t.from < n && t.to < n);
    }
    for t in &transitions {
        if regions.boundary(t.from, t.to).is_none() {
            return Err(Error::NoInput(format!(
                "the transition from region {} ({}) to region {} ({}) has no boundary to run across: those regions do not touch (remove it, or pick touching regions)",
                t.from + 1,
                regions.regions[t.from].name,
                t.to + 1,
                regions.regions[t.to].name
            )));
        }
    }
    Ok((pairs, transitions, notes))
}

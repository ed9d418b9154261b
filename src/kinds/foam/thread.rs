//! The views the "How it works" steps add: a layer's path coloured by V* or by H* along the
//! thread, each piece with the pair of its end as the grade stage prints it.

use super::*;
use crate::foam::Pair;

/// Feature codes of the value bins, lowest first (blue → red in the schema's colours).
pub const VALUE_CODES: [Feature; 6] = [Feature::Lattice, Feature::Beam, Feature::Contour, Feature::Perimeter, Feature::ExternalPerimeter, Feature::Infill];

/// The bin of `v` over [lo, hi] split into [`VALUE_CODES`] equal bins (0 when lo = hi).
pub fn value_bin(v: f64, lo: f64, hi: f64) -> usize {
    let n = VALUE_CODES.len();
    if !(hi > lo) {
        return 0;
    }
    (libm::floor((v - lo) / (hi - lo) * n as f64).max(0.0) as usize).min(n - 1)
}

/// One layer's pieces along the thread.
struct Pieces {
    /// Each piece `from → to` with the pair of its end.
    pieces: Vec<(DVec2, DVec2, Pair)>,
    /// The regions' own pairs.
    pairs: Vec<Pair>,
    /// The layer shown (clamped) and the layer count.
    index: usize,
    count: usize,
    /// The layer's top, mm.
    z: f64,
}

/// Layer `index`'s pieces, each `[from, to]` with the pair of its end, walked as
/// [`crate::foam::grade::grade`] walks them (pieces at most `piece_mm`, the field queried at
/// mid-layer); the layer's z and the layer count.
fn pieces(j: &FoamJob, ctx: &mut Ctx, index: usize) -> Result<Pieces, Error> {
    let regions = regions_stage(j, ctx)?;
    let layers = slice_stage(j, ctx, &regions)?;
    let paths = raster_stage(j, ctx, &layers)?;
    let (pairs, transitions, _) = field_inputs(j, &regions)?;
    let field = Field::new(&regions, pairs.clone(), &transitions, j.foam.junction);
    let count = paths.len().min(layers.len());
    let index = index.min(count.saturating_sub(1));
    let (h, piece) = (j.foam.layer_height_mm, j.foam.piece_mm);
    let mut out = Vec::new();
    let (Some(path), Some(layer)) = (paths.get(index), layers.get(index)) else { return Ok(Pieces { pieces: out, pairs, index: 0, count: 0, z: 0.0 }) };
    if !(piece > 0.0 && piece.is_finite()) {
        return Err(Error::NoInput(format!("the piece length is {piece} mm: set a positive length")));
    }
    let mut walker = field.walker();
    let at = |q: DVec2| DVec3::new(q.x, q.y, layer.z - h / 2.0);
    if let Some(&first) = path.points.first() {
        walker.next(at(first));
    }
    for w in path.points.windows(2) {
        let n = libm::ceil(w[0].distance(w[1]) / piece).max(1.0) as usize;
        let mut from = w[0];
        for i in 1..=n {
            let to = w[0].lerp(w[1], i as f64 / n as f64);
            out.push((from, to, walker.next(at(to)).0));
            from = to;
        }
    }
    Ok(Pieces { pieces: out, pairs, index, count, z: layer.z })
}

/// Layer `index`'s path coloured by V* (`v_star`) or H*, binned over the regions' range of
/// that value (widened to the layer's own if it passes it).
pub(super) fn thread_view(j: &FoamJob, ctx: &mut Ctx, view: &str, index: usize) -> Result<Inspection, Error> {
    let Pieces { pieces, pairs, index, count, z } = pieces(j, ctx, index)?;
    let (name, of): (&str, fn(&Pair) -> f64) = if view == "v_star" { ("V*", |p| p.v_star) } else { ("H*", |p| p.h_star) };
    let span = |it: &mut dyn Iterator<Item = f64>| it.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(v), b.max(v)));
    let (v_lo, v_hi) = span(&mut pieces.iter().map(|p| of(&p.2)));
    let (r_lo, r_hi) = span(&mut pairs.iter().map(of));
    let (lo, hi) = (r_lo.min(v_lo), r_hi.max(v_hi));
    let mut data = Vec::with_capacity(pieces.len() * 5);
    for (a, b, p) in &pieces {
        data.extend_from_slice(&[a.x as f32, a.y as f32, b.x as f32, b.y as f32, VALUE_CODES[value_bin(of(p), lo, hi)].code() as f32]);
    }
    let bins = if hi > lo { VALUE_CODES.len() } else { 1 };
    let step = if hi > lo { (hi - lo) / bins as f64 } else { 0.0 };
    let mut legend = serde_json::Map::new();
    let mut edges = Vec::new();
    for (i, f) in VALUE_CODES.iter().take(bins).enumerate() {
        let (a, b) = (lo + step * i as f64, if i + 1 == bins { hi } else { lo + step * (i + 1) as f64 });
        let words = if hi > lo { format!("{name} {a:.3}–{b:.3}") } else { format!("{name} {a:.3}") };
        legend.insert(f.code().to_string(), words.into());
        edges.push(serde_json::json!({ "code": f.code(), "from": a, "to": b }));
    }
    let caption = if pieces.is_empty() {
        format!("layer {} of {count} at z = {z:.2} mm: no path", index + 1)
    } else {
        let values = if v_hi > v_lo { format!("{v_lo:.3}–{v_hi:.3}") } else { format!("{v_lo:.3} throughout") };
        format!("layer {} of {count} at z = {z:.2} mm: {name} {values} along {} pieces of ≤ {} mm", index + 1, pieces.len(), j.foam.piece_mm)
    };
    let meta = serde_json::json!({
        "caption": caption, "legend": legend, "bins": edges, "z_mm": z,
        "min": if pieces.is_empty() { serde_json::Value::Null } else { v_lo.into() },
        "max": if pieces.is_empty() { serde_json::Value::Null } else { v_hi.into() },
    });
    Ok(Inspection { view: view.into(), shape: Shape::Lines2d, index, count, stride: Shape::Lines2d.stride(), data, overlay: Vec::new(), meta })
}

//! The lattice job's step views ("How it works"): one layer as a graph, its odd nodes paired,
//! GIPPO's search replayed, the paths kept, their print order and the toolpath the writer gets.
//! Each reuses the run's stages (strokes, paths); the GIPPO replay is made only when inspected
//! and kept in the cache like a stage ([`paths::replay`]).

use super::*;
use crate::geom::{DVec2, Toolpath};
use crate::paths::matching::{choose_method, exact_seconds, pair_points, sparse_seconds};
use crate::paths::metrics::{CLASS_LONG_ABOVE_NODES, CLASS_MEDIUM_MIN_NODES};
use crate::paths::{build_graph, Graph};
use std::collections::BTreeSet;

/// Struts in the graph and pairing views.
pub(super) const STRUT: Feature = Feature::Lattice;
/// Struts drawn under something else (pairing, print order: still to print).
pub(super) const DIM: Feature = Feature::Handle;
/// Even-degree nodes.
pub(super) const EVEN: Feature = Feature::Contour;
/// Odd-degree nodes.
pub(super) const ODD: Feature = Feature::ExternalPerimeter;
/// Lines pairing odd nodes.
pub(super) const PAIR: Feature = Feature::Infill;
/// Long paths (over 15 nodes).
pub(super) const LONG: Feature = Feature::Lattice;
/// Medium paths (5 to 15 nodes).
pub(super) const MEDIUM: Feature = Feature::SolidInfill;
/// Short paths (under 5 nodes).
pub(super) const SHORT: Feature = Feature::ExternalPerimeter;
/// Print order: printed paths.
pub(super) const PRINTED: Feature = Feature::Lattice;
/// Print order: the path being printed.
pub(super) const CURRENT: Feature = Feature::ExternalPerimeter;
/// Travel through the air.
pub(super) const TRAVEL: Feature = Feature::Infill;
/// Travel along printed struts (no extrusion).
pub(super) const STRUT_TRAVEL: Feature = Feature::Skirt;
/// Toolpath: a short path printed slower.
pub(super) const SLOWED: Feature = Feature::Perimeter;

use crate::geom::Feature;

/// A view's legend: feature code → what the view draws with it.
fn legend(entries: &[(Feature, &str)]) -> serde_json::Value {
    let mut m = serde_json::Map::new();
    for (f, words) in entries {
        m.insert(f.code().to_string(), serde_json::Value::String((*words).into()));
    }
    serde_json::Value::Object(m)
}

fn seg(data: &mut Vec<f32>, a: DVec2, b: DVec2, f: Feature) {
    data.extend_from_slice(&[a.x as f32, a.y as f32, b.x as f32, b.y as f32, f.code() as f32]);
}

/// A polyline's segments.
fn polyline(data: &mut Vec<f32>, points: impl IntoIterator<Item = DVec2>, f: Feature) {
    let mut prev: Option<DVec2> = None;
    for p in points {
        if let Some(a) = prev {
            seg(data, a, p, f);
        }
        prev = Some(p);
    }
}

/// A mark at `p`: an × (two diagonals) of half-size `r`, or a + when `upright`.
fn mark(data: &mut Vec<f32>, p: DVec2, r: f64, upright: bool, f: Feature) {
    let (a, b) = if upright { (DVec2::new(r, 0.0), DVec2::new(0.0, r)) } else { (DVec2::new(r, r), DVec2::new(r, -r)) };
    seg(data, p - a, p + a, f);
    seg(data, p - b, p + b, f);
}

/// Every strut of `graph` (through its bends).
fn struts(data: &mut Vec<f32>, graph: &Graph, f: Feature) {
    for e in 0..graph.edges.len() {
        polyline(data, graph.edge_points(e), f);
    }
}

/// The class code of a path of `nodes` nodes, as the paper's Fig. 2 counts them.
fn class(nodes: usize) -> Feature {
    if nodes > CLASS_LONG_ABOVE_NODES {
        LONG
    } else if nodes >= CLASS_MEDIUM_MIN_NODES {
        MEDIUM
    } else {
        SHORT
    }
}

fn class_legend() -> serde_json::Value {
    legend(&[(LONG, "long path (over 15 nodes)"), (MEDIUM, "medium path (5 to 15 nodes)"), (SHORT, "short path (under 5 nodes)")])
}

fn lines2d(view: &str, index: usize, count: usize, data: Vec<f32>, meta: serde_json::Value) -> Inspection {
    Inspection { view: view.into(), shape: Shape::Lines2d, index, count, stride: Shape::Lines2d.stride(), data, overlay: Vec::new(), meta }
}

/// The layer at `index` (clamped) and its graph, with the layer count.
fn layer_graph(j: &LatticeJob, ctx: &mut Ctx, index: usize) -> Result<(usize, usize, f64, Graph), Error> {
    let strokes = strokes(j, ctx)?;
    let count = strokes.len();
    let index = index.min(count.saturating_sub(1));
    let (z, graph) = match strokes.get(index) {
        Some(l) => (l.z, build_graph(l, j.paths.merge_tolerance_mm)),
        None => (0.0, Graph::default()),
    };
    Ok((index, count, z, graph))
}

/// Size of the node marks, mm: three quarters of the strut width.
fn mark_size(ctx: &Ctx) -> f64 {
    0.75 * line_width(ctx.design)
}

/// The graph of a layer: struts, even nodes (+), odd nodes (×).
pub(super) fn graph_view(j: &LatticeJob, ctx: &mut Ctx, index: usize) -> Result<Inspection, Error> {
    let (index, count, z, g) = layer_graph(j, ctx, index)?;
    let r = mark_size(ctx);
    let mut data = Vec::with_capacity(5 * (g.edges.len() + 2 * g.nodes.len()));
    struts(&mut data, &g, STRUT);
    let mut odd = 0usize;
    for v in 0..g.nodes.len() {
        if g.degree(v) % 2 == 1 {
            odd += 1;
            mark(&mut data, g.nodes[v], r, false, ODD);
        } else {
            mark(&mut data, g.nodes[v], 0.5 * r, true, EVEN);
        }
    }
    let caption = format!("layer {} at z {z:.2} mm: {} nodes, {odd} odd, {} struts in {} piece(s)", index + 1, g.nodes.len(), g.edges.len(), g.components);
    let meta = serde_json::json!({
        "caption": caption,
        "z_mm": z,
        "nodes": g.nodes.len(),
        "odd_nodes": odd,
        "edges": g.edges.len(),
        "components": g.components,
        "legend": legend(&[(STRUT, "strut (edge)"), (EVEN, "node of even degree"), (ODD, "node of odd degree: a path must start or end here")]),
    });
    Ok(lines2d("graph", index, count, data, meta))
}

/// The odd nodes of each piece paired by the shortest straight lines (the `euler` method's
/// pairing, exact within the paths' exact-pairing time), over the struts.
pub(super) fn pairing_view(j: &LatticeJob, ctx: &mut Ctx, index: usize) -> Result<Inspection, Error> {
    let (index, count, z, g) = layer_graph(j, ctx, index)?;
    let r = mark_size(ctx);
    let mut data = Vec::new();
    struts(&mut data, &g, DIM);
    let mut odd: Vec<Vec<usize>> = vec![Vec::new(); g.components];
    for v in 0..g.nodes.len() {
        if g.degree(v) % 2 == 1 {
            if let Some(c) = odd.get_mut(g.component[v]) {
                c.push(v);
            }
        }
    }
    let (mut pairs, mut total, mut optimal) = (0usize, 0.0, true);
    let mut left = j.paths.exact_pairing_seconds;
    for nodes in odd.iter().filter(|o| !o.is_empty()) {
        let pts: Vec<DVec2> = nodes.iter().map(|&v| g.nodes[v]).collect();
        let n = pts.len();
        let (method, cost) = choose_method(exact_seconds(n), sparse_seconds(n), left);
        left -= cost;
        let p = pair_points(&pts, method);
        for &(a, b) in &p.pairs {
            seg(&mut data, pts[a], pts[b], PAIR);
        }
        pairs += p.pairs.len();
        total += p.total;
        optimal &= p.optimal;
    }
    let odd_count: usize = odd.iter().map(Vec::len).sum();
    for v in odd.iter().flatten() {
        mark(&mut data, g.nodes[*v], r, false, ODD);
    }
    let quality = if optimal { "shortest possible" } else { "near the shortest" };
    let caption = format!(
        "layer {} at z {z:.2} mm: {pairs} lines pair {odd_count} odd nodes, {total:.2} mm ({quality}); at least {} paths",
        index + 1,
        g.lower_bound_paths()
    );
    let meta = serde_json::json!({
        "caption": caption,
        "z_mm": z,
        "odd_nodes": odd_count,
        "pairs": pairs,
        "pairing_mm": total,
        "optimal": optimal,
        "lower_bound_paths": g.lower_bound_paths(),
        "legend": legend(&[(DIM, "strut"), (ODD, "odd-degree node"), (PAIR, "pairing line (a travel between two paths)")]),
    });
    Ok(lines2d("pairing", index, count, data, meta))
}

/// The replayed layer: the first one with struts (else the first).
fn replay_layer(layers: &[StrokeLayer]) -> usize {
    layers.iter().position(|l| l.strokes.iter().any(|s| s.points.len() >= 2)).unwrap_or(0)
}

/// GIPPO's search replayed: frame `index` is the best solution so far at one improvement.
pub(super) fn gippo_view(j: &LatticeJob, ctx: &mut Ctx, index: usize) -> Result<Inspection, Error> {
    let strokes = strokes(j, ctx)?;
    let li = replay_layer(&strokes);
    let seed = ctx.design.seed;
    let replay: Out<Option<paths::Replay>> =
        ctx.recording("gippo_replay", "gippo_replay", &(&j.paths, seed, li), &[strokes.key], |_| match strokes.get(li) {
            Some(layer) => Ok((Some(paths::replay(layer, &j.paths, seed, li).map_err(|e| Error::stage("paths", e))?), None)),
            None => Ok((None, None)),
        })?;
    let Some(r) = replay.as_ref() else {
        return Ok(lines2d("gippo", 0, 0, Vec::new(), serde_json::json!({ "caption": "no layers", "frames": 0, "recorded_bytes": 0 })));
    };
    let count = r.frames.len();
    let index = index.min(count.saturating_sub(1));
    let mut data = Vec::new();
    let mut paths_drawn = 0usize;
    if let Some(f) = r.frames.get(index) {
        for (first, edges) in f.paths() {
            let f = class(edges.len() + 1);
            let mut v = first;
            let mut pts = vec![r.graph.nodes[v]];
            for &e in edges {
                let e = e as usize;
                pts.extend(r.graph.bends_from(e, v));
                v = r.graph.other(e, v);
                pts.push(r.graph.nodes[v]);
            }
            polyline(&mut data, pts, f);
            paths_drawn += 1;
        }
    }
    let frame = r.frames.get(index);
    let (iteration, score) = frame.map_or((0, 0.0), |f| (f.iteration as usize + 1, f.score));
    let z = strokes.get(li).map_or(0.0, |l| l.z);
    let grown = if r.maximise { "farthest" } else { "nearest" };
    let note = match j.paths.method {
        paths::Method::GippoMax | paths::Method::GippoMin => String::new(),
        m => format!(
            " (this design prints with {}; GIPPO shown for comparison)",
            serde_json::to_value(m).ok().and_then(|v| v.as_str().map(String::from)).unwrap_or_default()
        ),
    };
    let caption = format!(
        "layer {} at z {z:.2} mm, iteration {iteration} of {}: score {score:.4}, {paths_drawn} paths (best so far, frame {} of {count}){note}",
        li + 1,
        r.iterations,
        index + 1
    );
    let meta = serde_json::json!({
        "caption": caption,
        "play": true,
        "layer": li,
        "z_mm": z,
        "iteration": iteration,
        "iterations": r.iterations,
        "score": score,
        "paths": paths_drawn,
        "grown_towards": grown,
        "improvements": r.improvements,
        "frames": count,
        "cap": r.cap,
        "max_frames": paths::REPLAY_MAX_FRAMES,
        "recorded_bytes": r.recorded_bytes,
        "scores": r.frames.iter().map(|f| f.score).collect::<Vec<_>>(),
        "legend": class_legend(),
    });
    Ok(lines2d("gippo", index, count, data, meta))
}

/// The optimised paths (the `paths` stage's toolpath, before any projection).
fn optimised(j: &LatticeJob, ctx: &mut Ctx) -> Result<(Out<Vec<StrokeLayer>>, Out<Toolpath>), Error> {
    let strokes = strokes(j, ctx)?;
    let t = paths_stage(j, ctx, &strokes)?;
    Ok((strokes, t))
}

/// Nodes of `graph` as exact coordinates (the paths' points at nodes are the nodes' own).
fn node_set(graph: &Graph) -> BTreeSet<(u64, u64)> {
    graph.nodes.iter().map(|p| (p.x.to_bits(), p.y.to_bits())).collect()
}

/// The kept paths of a layer coloured by class.
pub(super) fn trails_view(j: &LatticeJob, ctx: &mut Ctx, index: usize) -> Result<Inspection, Error> {
    let (strokes, t) = optimised(j, ctx)?;
    let count = t.passes.len();
    let index = index.min(count.saturating_sub(1));
    let graph = strokes.get(index).map(|l| build_graph(l, j.paths.merge_tolerance_mm)).unwrap_or_default();
    let nodes = node_set(&graph);
    let mut data = Vec::new();
    let (mut classes, mut weighted, mut total, mut n) = ([0usize; 3], 0.0, 0.0, 0usize);
    let z = t.passes.get(index).map_or(0.0, |p| p.z);
    for p in t.passes.get(index).map_or(&[][..], |p| &p.paths[..]) {
        let at_nodes = p.points.iter().filter(|q| nodes.contains(&(q.x.to_bits(), q.y.to_bits()))).count().max(2);
        let f = class(at_nodes);
        classes[[LONG, MEDIUM, SHORT].iter().position(|&c| c == f).unwrap_or(2)] += 1;
        polyline(&mut data, p.points.iter().map(|q| q.truncate()), f);
        let length: f64 = p.points.windows(2).map(|w| w[0].truncate().distance(w[1].truncate())).sum();
        weighted += length * (at_nodes - 1) as f64;
        total += length;
        n += 1;
    }
    // Equation 1 of the paths kept.
    let score = if n > 0 && total > 0.0 { weighted / (total * n as f64) } else { 0.0 };
    let caption = format!("layer {} at z {z:.2} mm: {n} paths, {} long, {} medium, {} short; score {score:.4}", index + 1, classes[0], classes[1], classes[2]);
    let meta = serde_json::json!({
        "caption": caption,
        "z_mm": z,
        "paths": n,
        "long": classes[0],
        "medium": classes[1],
        "short": classes[2],
        "score": score,
        "legend": class_legend(),
    });
    Ok(lines2d("trails", index, count, data, meta))
}

/// Draws the move from `from` into path `p` (along its approach route when it has one).
fn travel_into(data: &mut Vec<f32>, from: Option<DVec2>, p: &crate::geom::Path) -> f64 {
    let Some(a) = from else { return 0.0 };
    let b = p.points[0].truncate();
    let (pts, f): (Vec<DVec2>, Feature) = match &p.approach {
        Some(route) => (std::iter::once(a).chain(route.iter().map(|q| q.truncate())).chain(std::iter::once(b)).collect(), STRUT_TRAVEL),
        None => (vec![a, b], TRAVEL),
    };
    let length = pts.windows(2).map(|w| w[0].distance(w[1])).sum();
    polyline(data, pts, f);
    length
}

/// Print order: frame `index` counts the paths of all layers in print order; it draws that
/// path's layer with the paths before it printed, it printing and the rest still to print,
/// and the travel moves so far.
pub(super) fn order_view(j: &LatticeJob, ctx: &mut Ctx, index: usize) -> Result<Inspection, Error> {
    let (_, t) = optimised(j, ctx)?;
    let count: usize = t.passes.iter().map(|p| p.paths.len()).sum();
    let index = index.min(count.saturating_sub(1));
    let mut data = Vec::new();
    // The layer of path `index`, and the path within it.
    let (mut li, mut k) = (0usize, index);
    while li < t.passes.len() && k >= t.passes[li].paths.len() {
        k -= t.passes[li].paths.len();
        li += 1;
    }
    let mut caption = "no paths".to_string();
    let mut travel_total = 0.0;
    if let Some(pass) = t.passes.get(li) {
        // Where the layer below ended.
        let mut at = t.passes[..li].iter().rev().find_map(|p| p.paths.last()).and_then(|p| p.points.last()).map(|q| q.truncate());
        let mut travel_before = 0.0;
        for (i, p) in pass.paths.iter().enumerate() {
            let pts = p.points.iter().map(|q| q.truncate());
            if i > k {
                polyline(&mut data, pts, DIM);
                continue;
            }
            let moved = travel_into(&mut data, at, p);
            travel_total += moved;
            if i == k {
                travel_before = moved;
            }
            polyline(&mut data, pts, if i == k { CURRENT } else { PRINTED });
            at = p.points.last().map(|q| q.truncate());
        }
        let p = &pass.paths[k];
        let length: f64 = p.points.windows(2).map(|w| w[0].distance(w[1])).sum();
        caption = format!(
            "layer {} at z {:.2} mm: path {} of {}, {length:.2} mm long, {travel_before:.2} mm of travel before it ({travel_total:.2} mm in the layer so far)",
            li + 1,
            pass.z,
            k + 1,
            pass.paths.len()
        );
    }
    let meta = serde_json::json!({
        "caption": caption,
        "play": true,
        "layer": li,
        "path": k,
        "travel_mm": travel_total,
        "legend": legend(&[(PRINTED, "printed"), (CURRENT, "printing now"), (DIM, "still to print"), (TRAVEL, "travel through the air"), (STRUT_TRAVEL, "travel along struts")]),
    });
    Ok(lines2d("order", index, count, data, meta))
}

/// One layer of the job's final toolpath (projected when the design is), as the writer gets it.
pub(super) fn gcode_view(j: &LatticeJob, ctx: &mut Ctx, index: usize) -> Result<Inspection, Error> {
    let t = match <LatticeKind as Kind>::run(j, ctx)? {
        Product::Toolpath(t) => t,
        Product::Gcode(_) => return Err(Error::UnknownView { view: "gcode".into(), job: LatticeKind::NAME }),
    };
    let count = t.passes.len();
    let index = index.min(count.saturating_sub(1));
    let mut data = Vec::new();
    let (mut extruded, mut travel, mut slowed, mut n) = (0.0, 0.0, 0usize, 0usize);
    let mut features: Vec<Feature> = Vec::new();
    let mut at = t.passes[..index].iter().rev().find_map(|p| p.paths.last()).and_then(|p| p.points.last()).map(|q| q.truncate());
    let z = t.passes.get(index).map_or(0.0, |p| p.z);
    for p in t.passes.get(index).map_or(&[][..], |p| &p.paths[..]) {
        travel += travel_into(&mut data, at, p);
        let f = if p.speed_factor < 1.0 {
            slowed += 1;
            SLOWED
        } else {
            if !features.contains(&p.feature) {
                features.push(p.feature);
            }
            p.feature
        };
        polyline(&mut data, p.points.iter().map(|q| q.truncate()), f);
        extruded += p.points.windows(2).map(|w| w[0].distance(w[1])).sum::<f64>();
        at = p.points.last().map(|q| q.truncate());
        n += 1;
    }
    let percent = (100.0 * j.paths.short_path_speed_factor).round();
    let slow_words = format!("short path, slowed to {percent} %");
    let mut entries: Vec<(Feature, &str)> = features.iter().map(|f| (*f, f.gcode_name())).collect();
    entries.extend([(SLOWED, slow_words.as_str()), (TRAVEL, "travel through the air"), (STRUT_TRAVEL, "travel along struts")]);
    let caption =
        format!("layer {} at z {z:.2} mm: {n} paths ({slowed} slowed to {percent} %), {extruded:.1} mm extruded, {travel:.1} mm of travel", index + 1);
    let meta = serde_json::json!({
        "caption": caption,
        "z_mm": z,
        "paths": n,
        "slowed": slowed,
        "extruded_mm": extruded,
        "travel_mm": travel,
        "legend": legend(&entries),
    });
    Ok(lines2d("gcode", index, count, data, meta))
}

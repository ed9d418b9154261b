//! The freeform job's stages around the plan: the wireframe read and placed, its precedence constraints, the print order, the per-step costs; the work each will do, and the toolpath.

use super::*;

/// The work each stage will do (`Kind::estimate`), refused over a budget before any is done.
pub(super) fn estimate(j: &FreeformJob, ctx: &mut Ctx) -> Result<Vec<Estimate>, Error> {
    let w = import_stage(j, ctx)?;
    let m = w.beams.len() as f64;
    let import = Estimate::new("import").quantity("beams", "Beams", m, "").cost(m * 200.0, m * 1e-6);
    // Measured on weft's towers and the conmech truss (native, 2026): constraints about
    // 0.1 ms a beam, the exact plan and the cost replay about 0.4 ms a beam (compliance
    // updates over the joints still open), the heuristic plan about 0.05 ms. A nozzle
    // that may tilt tests every axis it may take (17 with the default rings): the
    // cantilever truss with tilt took 3.7 s where 0.22 s was stated before this counted.
    let axes = precedence::tilt_axes(j.nozzle.tilt_deg.clamp(0.0, precedence::MAX_TILT_DEG)).len() as f64;
    let constraints = Estimate::new("constraints")
        .quantity("beams", "Beams", m, "")
        .quantity("axes", "Nozzle axes tried", axes, "")
        .cost(m * 400.0, m * 1e-4 * axes)
        .parallel(0.85)
        .budgets("lower the nozzle's radius or height, or its tilt");
    let exact = j.planner.cost == Cost::Exact;
    let plan_s = if exact { (m * 4e-4).min(j.planner.budget_s) } else { m * 5e-5 };
    let plan =
        Estimate::new("plan").quantity("beams", "Beams", m, "").cost(m * 2000.0, plan_s).budgets("plan with the heuristic cost, or lower the planning budget");
    let searched = exact_runs(j, m as usize);
    let states = if searched { j.planner.exact_states as f64 } else { 0.0 };
    // Measured: about 40 µs a state on a 30-beam dome (the frame's update grows as the
    // square of its joints). The time stated is a typical search's (about 2^(beams/2)
    // states: the dome searched 10 457), the memory the limit's; the worst case at the
    // largest limit, 10⁷ states, is under 10 minutes.
    let per_state = 4e-5 * (m / 30.0).powi(2).max(0.05);
    let typical = states.min(2f64.powf(m / 2.0));
    // Memory: the remembered states, and the frame's compliance on every level of the
    // search's path (its capacity doubles from 16 joints).
    let cap = if searched { (m + 1.0).max(16.0).log2().ceil().exp2() } else { 0.0 };
    let path_bytes = if searched { m * (6.0 * cap).powi(2) * 8.0 } else { 0.0 };
    let optimum = Estimate::new("optimum")
        .quantity("states", "States at most", states, "")
        .cost(states * 24.0 + path_bytes, typical * per_state)
        .budgets("lower the exact search's states, or switch it off");
    let order = Estimate::new("order").quantity("beams", "Beams", m, "").cost(m * 200.0, m * 2e-5);
    let costs = Estimate::new("costs")
        .quantity("beams", "Beams", if j.planner.compare { m } else { 0.0 }, "")
        .quantity("segments", "Segments", 4.0 * m, "")
        // The replay is bounded by the planning budget; in bands the plan's order is replayed too.
        .cost(
            m * 300.0,
            if j.planner.compare {
                (m * 4e-4).min(j.planner.budget_s) * if j.planner.band_beams > 0 && (j.planner.band_beams as f64) < m { 2.0 } else { 1.0 }
            } else {
                0.0
            },
        )
        .budgets("switch off the comparison of the costs");
    Ok(vec![import, constraints, plan, optimum, order, costs])
}

/// The wireframe read (or built) and placed: its lowest joint on the plate, XY centred.
pub struct Placed {
    /// The design, placed.
    pub wire: Wireframe,
    /// Its name (the file's, or the model's).
    pub name: String,
}

impl std::ops::Deref for Placed {
    type Target = Wireframe;
    fn deref(&self) -> &Wireframe {
        &self.wire
    }
}

pub(super) fn import_stage(j: &FreeformJob, ctx: &mut Ctx) -> Result<Out<Placed>, Error> {
    let options =
        wireframe::Options { ground: j.design.ground, ground_tolerance_mm: j.design.ground_tolerance_mm, merge_tolerance_mm: j.design.merge_tolerance_mm };
    let parts = (&j.model, j.design);
    let (bytes, name, keys) = match (&j.model, &j.input) {
        (Some(_), _) => (None, "model".to_string(), Vec::new()),
        (None, Some(input)) => {
            let (bytes, key) = ctx.file_bytes("frame", input)?;
            let name = match input {
                Input::File { name, .. } => name.clone(),
                _ => "wireframe".into(),
            };
            (Some(bytes), name, vec![key])
        }
        (None, None) => return Err(Error::NoInput("a freeform job needs a wireframe: load one (--input frame=FILE), or switch on a built-in design".into())),
    };
    let design = ctx.design;
    ctx.stage_kept("import", "import", &(parts, &name), &keys, |_| {
        let mut wire = match (&j.model, bytes) {
            (Some(m), _) => {
                if let Some(p) = models::problems(m).into_iter().next() {
                    return Err(Error::NoInput(format!("the built-in design: {p}")));
                }
                models::build(m)
            }
            (None, Some(b)) => wireframe::read(&name, &b, &options).map_err(|e| Error::stage("reading the wireframe", e))?,
            _ => unreachable!("a model or a file"),
        };
        if j.design.up != Up::Z {
            for p in &mut wire.joints {
                *p = j.design.up.turn(*p);
            }
            if !wire.grounded_by_file {
                // The lowest joints after turning.
                let low = wire.joints.iter().map(|p| p.z).fold(f64::INFINITY, f64::min);
                wire.grounded = wire.joints.iter().map(|p| p.z <= low + j.design.ground_tolerance_mm).collect();
            }
        }
        place(&mut wire);
        wire.grounding = Some(wireframe::grounding(&wire, j.design.ground_tolerance_mm));
        let size = bounds(&wire.joints).map(|(lo, hi)| hi - lo).unwrap_or_default();
        crate::gcode::check_fits([size.x, size.y, size.z], &design.printer).map_err(|e| Error::stage("the wireframe", e))?;
        let lengths: Vec<f64> = (0..wire.beams.len()).map(|b| wire.length(b)).collect();
        let total: f64 = lengths.iter().sum();
        let shortest = lengths.iter().copied().fold(f64::INFINITY, f64::min);
        let longest = lengths.iter().copied().fold(0.0, f64::max);
        let grounded = wire.grounded.iter().filter(|&&g| g).count();
        let mut report = StageReport::new(
            "import",
            "Reading the wireframe",
            &serde_json::json!({ "joints": wire.joints.len(), "beams": wire.beams.len(), "grounded": grounded, "format": wire.format, "grounding": wire.grounding }),
        )
        .metric("joints", "Joints", wire.joints.len() as f64, "", "Points where beams meet.")
        .metric("beams", "Beams", wire.beams.len() as f64, "", "Straight beams, each printed once.")
        .metric(
            "grounded",
            "Grounded joints",
            grounded as f64,
            "",
            if wire.grounded_by_file {
                "Joints on the substrate, as the design marks them."
            } else {
                "Joints on the substrate: the lowest ones (the design marks none)."
            },
        )
        .metric("length", "Beam length", total, "mm", "Total length of all beams.")
        .metric("shortest", "Shortest beam", if shortest.is_finite() { shortest } else { 0.0 }, "mm", "The shortest beam.")
        .metric("longest", "Longest beam", longest, "mm", "The longest beam.")
        .metric("height", "Height", size.z, "mm", "Height of the design on the plate.");
        // Assumptions said out loud: how the file was read, what stands on the plate.
        report.notes.extend(wire.notes.iter().cloned());
        // The grounding is an assumption only when it is not the file's own marks.
        if let Some(g) = wire.grounding.as_ref().filter(|g| !g.by_file) {
            report.notes.push(format!("{}: {}", name, g.statement()));
            report.notes.extend(g.warning().map(|w| format!("{name}: {w}")));
        }
        Ok((Placed { wire, name: name.clone() }, Some(report)))
    })
}

pub(super) fn bounds(p: &[DVec3]) -> Option<(DVec3, DVec3)> {
    let first = *p.first()?;
    Some(p.iter().fold((first, first), |(lo, hi), q| (lo.min(*q), hi.max(*q))))
}

/// Moves the design so its lowest joint is on the plate and its XY box is centred on 0.
pub(super) fn place(w: &mut Wireframe) {
    if let Some((lo, hi)) = bounds(&w.joints) {
        let shift = DVec3::new(-(lo.x + hi.x) / 2.0, -(lo.y + hi.y) / 2.0, -lo.z);
        for p in &mut w.joints {
            *p += shift;
        }
    }
}

pub(super) fn precedence_options(j: &FreeformJob) -> precedence::Options {
    precedence::Options {
        nozzle: Nozzle { half_angle_deg: j.nozzle.half_angle_deg, radius_mm: j.nozzle.radius_mm, height_mm: j.nozzle.height_mm },
        beam_radius_mm: j.beam.diameter_mm / 2.0,
        directionality: j.constraints.directionality,
        collision: j.constraints.collision,
        tilt_deg: j.nozzle.tilt_deg,
    }
}

pub(super) fn constraints_stage(j: &FreeformJob, ctx: &mut Ctx, w: &Out<Placed>) -> Result<Out<Constraints>, Error> {
    let o = precedence_options(j);
    let parts = (j.nozzle, j.beam.diameter_mm, j.constraints.directionality, j.constraints.collision);
    ctx.stage("constraints", "constraints", &parts, &[w.key], |progress| {
        let started = crate::clock::now_s();
        let c = precedence::constraints(&w.joints, &w.beams, &o, progress).map_err(|e| Error::stage("constraints", e))?;
        let ms = (crate::clock::now_s() - started) * 1000.0;
        let one_way = c.forward.iter().zip(&c.backward).filter(|(f, b)| !(**f && **b)).count();
        let report =
            StageReport::new("constraints", "Directions and collisions", &serde_json::json!({ "pairs": c.pairs(), "one_way": one_way, "tested": c.tested }))
                .metric(
                    "pairs",
                    "Collision precedences",
                    c.pairs() as f64,
                    "",
                    "Pairs (A, B) where the nozzle printing A would sweep through B: A is printed first.",
                )
                .metric("one_way", "Upward only", one_way as f64, "", "Beams steeper than the nozzle's cone: printed from their lower joint.")
                .metric(
                    "tested",
                    "Pairs tested exactly",
                    c.tested as f64,
                    "",
                    "Pairs near enough (by the BVH and the 2D distance) for the exact cone/cylinder test (each axis tried counts).",
                )
                .metric("time", "Time", ms, "ms", "Wall time of this stage on this machine.");
        let report = if o.tilt_deg > 0.0 {
            report
                .metric(
                    "tilted",
                    "Beams tilted",
                    c.tilted as f64,
                    "",
                    "Beams printed with the nozzle tilted: a tilt let them go either way or hit fewer beams.",
                )
                .metric(
                    "vertical_pairs",
                    "Precedences if vertical",
                    c.vertical_pairs as f64,
                    "",
                    "Collision precedences a vertical nozzle would have had (beside the ones left with tilting).",
                )
        } else {
            report
        };
        Ok((c, Some(report)))
    })
}

pub(super) fn order_stage(j: &FreeformJob, ctx: &mut Ctx, w: &Out<Placed>, c: &Out<Constraints>, p: &Out<Plan>) -> Result<Out<Ordered>, Error> {
    let o = deadhead_options(j, ctx.design);
    let parts = (o.xy_mm_s, o.z_mm_s, o.clearance_mm, o.beam_radius_mm, j.nozzle);
    let speed = j.print.speed_mm_s;
    let dwell = j.print.dwell_s;
    let nozzle = precedence_options(j).nozzle;
    ctx.stage("order", "order", &parts, &[p.key, c.key], |_| {
        let ordered = deadhead::order(&w.joints, p, c, &o);
        let length: f64 = ordered.steps.iter().map(|s| w.joints[s.from].distance(w.joints[s.to])).sum();
        let print_s = length / speed + dwell * ordered.steps.len() as f64;
        let mut report = StageReport::new("order", "Ordering deadheads", &serde_json::json!({ "deadhead_s": ordered.deadhead_s, "plan_order_deadhead_s": ordered.plan_order_deadhead_s, "sequence": ordered.steps.iter().map(|s| [s.beam, s.from, s.to]).collect::<Vec<_>>() }))
            .metric("deadhead", "Deadhead time", ordered.deadhead_s, "s", "Moves between beams: lift above the highest printed beam, move, lower (axes at full speed).")
            .metric("deadhead_plan", "Deadhead in the plan's order", ordered.plan_order_deadhead_s, "s", "The same moves in the order the planner fixed them, before ordering.")
            .metric("print", "Printing time", print_s, "s", "Extruding along every beam at the beam speed, plus the dwells.");
        // Lifts and descents through printed beams higher than the nozzle body reaches.
        let (blocked, tilted) = deadhead::blocked(&w.joints, &w.beams, &c.axis, &ordered, nozzle.radius_mm, nozzle.top(), o.beam_radius_mm);
        report = report.metric("blocked", "Deadheads through printed beams", blocked.len() as f64, "", "Lifts or descents whose nozzle column above the joint meets a printed beam higher than the nozzle body: make the body's height the whole head's, so those beams become precedences.");
        if tilted > 0 {
            report = report.metric("unchecked", "Deadheads not checked (tilted)", tilted as f64, "", "Deadheads next to a beam printed with the nozzle tilted: the check above is for an upright nozzle.");
        }
        if !blocked.is_empty() {
            report.label = format!("Ordering deadheads: {} pass through printed beams (first at step {})", blocked.len(), blocked[0] + 1);
            report.data["blocked_steps"] = serde_json::json!(blocked.iter().take(50).collect::<Vec<_>>());
        }
        report.tables.push(sequence_table(w, &ordered));
        Ok((ordered, Some(report)))
    })
}

pub(super) fn deadhead_options(j: &FreeformJob, design: &crate::design::Design) -> deadhead::Options {
    let printer = &design.printer;
    deadhead::Options {
        xy_mm_s: printer.travel_speed_mm_s,
        z_mm_s: printer.z_speed_mm_s,
        clearance_mm: j.print.clearance_mm,
        beam_radius_mm: j.beam.diameter_mm / 2.0,
    }
}

pub(super) fn costs_stage(j: &FreeformJob, ctx: &mut Ctx, w: &Out<Placed>, p: &Out<Plan>, o: &Out<Ordered>) -> Result<Out<Vec<Costs>>, Error> {
    let parts = (j.planner.compare, j.beam, j.planner.budget_s);
    let s = section(j);
    let load = j.beam.load_n;
    let compare = j.planner.compare;
    let chosen = j.planner.cost;
    let budget = j.planner.budget_s * plan::WORK_PER_SECOND;
    ctx.stage("costs", "costs", &parts, &[o.key, p.key], |_| {
        if !compare {
            return Ok((Vec::new(), Some(planned_report(o))));
        }
        let (c, stopped) = cost::costs_within(&w.joints, &w.beams, &w.grounded, &o.steps, &s, load, budget);
        let mut report = costs_report(&c, load, chosen, stopped);
        if !p.bands.is_empty() {
            // The plan's own order, measured with the whole frame, against what each band saw.
            let (whole, _) = cost::costs_within(&w.joints, &w.beams, &w.grounded, &p.steps, &s, load, budget);
            report = joins_report(report, p, &whole);
        }
        Ok((c.clone(), Some(report)))
    })
}

/// The G-code's toolpath: one free pass per beam (3D moves at the beam speed with the
/// extrusion of its section, a dwell at the end joint), reached by a deadhead that lifts above
/// the highest printed beam, moves across and lowers.
pub(super) fn toolpath(j: &FreeformJob, w: &Placed, o: &Ordered, c: &Constraints) -> Toolpath {
    let d = j.beam.diameter_mm;
    let area = std::f64::consts::PI * d * d / 4.0;
    let mut passes = Vec::with_capacity(o.steps.len());
    let mut last: Option<DVec3> = None;
    for (i, s) in o.steps.iter().enumerate() {
        let (a, b) = (w.joints[s.from], w.joints[s.to]);
        let approach = last.map(|p| {
            let z = o.safe_z[i].max(p.z).max(a.z);
            vec![DVec3::new(p.x, p.y, z), DVec3::new(a.x, a.y, z)]
        });
        // A tilted beam carries its nozzle axis (the writer turns it into rotary words).
        let axis = c.axis.get(s.beam).copied().unwrap_or(DVec3::Z);
        let tool_axis = (axis != DVec3::Z).then(|| vec![axis, axis]);
        let data = PointData {
            flow: Some(PointFlow::AreaMm2(vec![0.0, area])),
            feed_mm_s: Some(vec![0.0, j.print.speed_mm_s]),
            tool_axis,
            dwell_s: Some(vec![0.0, j.print.dwell_s]),
        };
        let path = Path { points: vec![a, b], feature: Feature::Beam, width: d, speed_factor: 1.0, approach, data: Some(Box::new(data)) };
        passes.push(Pass { kind: PassKind::Free, z: a.z.max(b.z), height: d, paths: vec![path] });
        last = Some(b);
    }
    Toolpath { passes }
}

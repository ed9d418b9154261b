//! The `slice` job: a solid sliced into planar layers of perimeters and rectilinear infill.

use super::{Kind, Product, Slot, SlotKind, StageInfo};
use crate::budget::Estimate;
use crate::design::Input;
use crate::geom::shapes::{self, Shape};
use crate::settings::{mount, Row};
use crate::slice;
use crate::stage::{Ctx, Error};
use serde::{Deserialize, Serialize};

/// Settings of a `slice` job.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SliceJob {
    /// The solid to slice. Default: a 20 mm cube.
    #[serde(default = "default_input")]
    pub input: Input,
    /// Layer heights, perimeters, infill, support.
    #[serde(default)]
    pub slice: slice::Options,
    /// A mesh inside which every overhang gets support (in the part's file coordinates).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub support_enforcer: Option<Input>,
    /// A mesh inside which no support is built (in the part's file coordinates).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub support_blocker: Option<Input>,
}

impl Default for SliceJob {
    fn default() -> Self {
        SliceJob { input: default_input(), slice: slice::Options::default(), support_enforcer: None, support_blocker: None }
    }
}

fn default_input() -> Input {
    Input::Builtin(Shape::Cube { size: [20.0, 20.0, 20.0] })
}

/// The `slice` job kind.
pub struct SliceKind;

const SLOTS: &[Slot] = &[
    Slot {
        name: "mesh",
        label: "Part",
        kind: SlotKind::Mesh,
        path: "job.input",
        required: false,
        doc: "The solid to slice (STL, OBJ or 3MF); without one, the built-in shape is sliced.",
    },
    Slot {
        name: "support_enforcer",
        label: "Support enforcer",
        kind: SlotKind::Mesh,
        path: "job.support_enforcer",
        required: false,
        doc: "A closed mesh in the part's coordinates: every overhang inside it gets support, whatever its angle (with supports on).",
    },
    Slot {
        name: "support_blocker",
        label: "Support blocker",
        kind: SlotKind::Mesh,
        path: "job.support_blocker",
        required: false,
        doc: "A closed mesh in the part's coordinates: no support is built inside it.",
    },
];

const STAGES: &[StageInfo] = &[StageInfo { name: "import", label: "Reading the mesh" }, StageInfo { name: "slice", label: "Slicing layers" }];

impl Kind for SliceKind {
    type Settings = SliceJob;
    const NAME: &'static str = "slice";
    const LABEL: &'static str = "Slice a part";
    const DOC: &'static str = "Planar layers of perimeters and rectilinear infill, like any slicer.";
    const SLOTS: &'static [Slot] = SLOTS;
    const STAGES: &'static [StageInfo] = STAGES;

    fn fields() -> Vec<Row> {
        let mut rows = mount("job.slice", slice::FIELDS);
        rows.extend(mount("job.slice", slice::support::FIELDS));
        rows.extend(mount("job.input", shapes::FIELDS));
        rows
    }

    fn validate(design: &crate::design::Design, s: &SliceJob, out: &mut Vec<crate::settings::Problem>) {
        let nozzle = design.printer.nozzle_diameter_mm;
        for (path, h) in [("job.slice.layer_height_mm", s.slice.layer_height_mm), ("job.slice.first_layer_height_mm", s.slice.first_layer_height_mm)] {
            out.extend(super::thicker_than_nozzle(path, h, nozzle));
        }
    }

    fn estimate(s: &SliceJob, ctx: &mut Ctx) -> Result<Vec<Estimate>, Error> {
        let import = ctx.import_estimate("mesh", &s.input)?;
        if import.refused.is_some() {
            return Ok(vec![import]);
        }
        let mesh = ctx.mesh(&SLOTS[0], &s.input)?;
        super::part_fits(ctx.design, &mesh)?;
        Ok(vec![import, slice::estimate(&mesh, &s.slice)])
    }

    fn run(s: &SliceJob, ctx: &mut Ctx) -> Result<Product, Error> {
        let mesh = ctx.mesh(&SLOTS[0], &s.input)?;
        super::part_fits(ctx.design, &mesh)?;
        // Enforcer and blocker meshes share the part's file coordinates: moved as the part was
        // moved onto the plate.
        let mut keys = vec![mesh.key];
        let mut helpers: [Option<crate::geom::Mesh>; 2] = [None, None];
        if s.support_enforcer.is_some() || s.support_blocker.is_some() {
            let raw = ctx.mesh_in_place(&SLOTS[0], &s.input)?;
            let offset = raw.value.bounds().map_or(glam::DVec3::ZERO, |b| {
                let c = (b.min + b.max) * 0.5;
                glam::DVec3::new(-c.x, -c.y, -b.min.z)
            });
            for (k, input) in [&s.support_enforcer, &s.support_blocker].into_iter().enumerate() {
                if let Some(input) = input {
                    let m = ctx.mesh_in_place(&SLOTS[k + 1], input)?;
                    keys.push(m.key);
                    let mut m = (*m.value).clone();
                    m.translate(offset);
                    helpers[k] = Some(m);
                }
            }
        }
        let sliced = ctx.stage("slice", "slice", &s.slice, &keys, |progress| {
            let extra = slice::Extra { support_enforcers: helpers[0].as_ref(), support_blockers: helpers[1].as_ref() };
            let sliced = slice::slice_with(&mesh, &extra, &s.slice, progress).map_err(|e| Error::stage("slicing", e))?;
            let report = super::slice_report(&sliced.report, "Slicing layers");
            Ok((sliced.toolpath, Some(report)))
        })?;
        Ok(Product::Toolpath(sliced))
    }
}

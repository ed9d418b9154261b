//! Ranges live in one table per stage: the page's form (the schema), the CLI's `--set` and the
//! stage's own validator accept and refuse exactly the same values.

use serde_json::Value;
use weft::catalog::schema;
use weft::design::Design;
use weft::kinds::Registry;
use weft::settings::{Field, Kind};

fn example(name: &str) -> Design {
    let text = std::fs::read_to_string(format!("{}/examples/{name}.json", env!("CARGO_MANIFEST_DIR"))).unwrap();
    Design::from_json(name, &text).unwrap()
}

fn get<'a>(v: &'a Value, path: &str) -> Option<&'a Value> {
    path.split('.').try_fold(v, |v, k| v.get(k))
}

/// Values just outside and just at the limits of a numeric row.
fn probes(f: &Field) -> Vec<(f64, bool)> {
    let (lo, hi) = (f.min.unwrap(), f.max.unwrap());
    let step = if f.kind == Kind::Integer { 1.0 } else { (hi - lo).abs().max(1.0) * 1e-3 };
    let mut out = vec![(hi, true), (hi + step, false), (lo, true)];
    if lo - step >= 0.0 || f.kind != Kind::Integer {
        out.push((lo - step, false));
    }
    out
}

/// Checks every numeric row of `fields` mounted at `prefix` in `design`: the schema shows
/// the table's limits, `--set` refuses outside values, and `stage_ok(options JSON)` (the
/// stage's own validator on its options) agrees on every probe.
fn agree(design: &Design, prefix: &str, fields: &[Field], stage_ok: &dyn Fn(&Value) -> bool) -> usize {
    let schema = schema::schema(&Registry::builtin());
    let root = serde_json::to_value(design).unwrap();
    let options = get(&root, prefix).unwrap().clone();
    let mut checked = 0;
    for f in fields.iter().filter(|f| matches!(f.kind, Kind::Number | Kind::Integer)) {
        if get(&options, f.path).is_none() {
            continue; // a variant's field the design does not use (another pattern, surface)
        }
        let path = format!("{prefix}.{}", f.path);
        let row = schema.fields.iter().find(|r| r.path == path).unwrap_or_else(|| panic!("{path} is not in the form"));
        assert_eq!((row.field.min, row.field.max), (f.min, f.max), "{path}: the form shows other limits");
        for (v, inside) in probes(f) {
            let v = if f.kind == Kind::Integer { v.round() } else { v };
            let json = if f.kind == Kind::Integer { format!("{}", v as i64) } else { format!("{v}") };
            let cli = design.with_overrides(&[format!("{path}={json}")]);
            let mut opts = options.clone();
            let mut slot = &mut opts;
            for k in f.path.split('.') {
                slot = slot.get_mut(k).unwrap();
            }
            *slot = serde_json::from_str(&json).unwrap();
            let stage = stage_ok(&opts);
            // Cross-field rules (a layer thicker than the nozzle) may refuse an in-range value
            // in the design; never the other way round.
            if inside {
                assert!(stage, "{path}={json}: the stage refuses a value the form allows");
            } else {
                assert!(cli.is_err(), "{path}={json}: --set accepts a value outside the form's range");
                assert!(cli.unwrap_err().to_string().contains(&path), "{path}: the message names the field");
                assert!(!stage, "{path}={json}: the stage accepts a value outside the form's range");
            }
            checked += 1;
        }
    }
    checked
}

#[test]
fn form_cli_and_stages_share_one_range_table() {
    let mesh = weft::geom::shapes::Shape::Cube { size: [2.0, 2.0, 2.0] }.mesh();
    let cube = example("cube-20mm");
    let n = agree(&cube, "job.slice", weft::slice::FIELDS, &|o| {
        let o: weft::slice::Options = serde_json::from_value(o.clone()).unwrap();
        !matches!(weft::slice::slice(&mesh, &o, &mut |_| {}), Err(weft::slice::Error::BadOptions { .. }))
    });
    assert!(n >= 24, "slice rows checked: {n}");

    let honeycomb = example("honeycomb-10mm");
    let n = agree(&honeycomb, "job.paths", weft::paths::FIELDS, &|o| weft::paths::validate(&serde_json::from_value(o.clone()).unwrap()).is_ok());
    assert!(n >= 12, "paths rows checked: {n}");
    let n = agree(&honeycomb, "job.lattice", weft::lattice::FIELDS, &|o| {
        let o: weft::lattice::Options = serde_json::from_value(o.clone()).unwrap();
        let d = weft::lattice::planar_domains(
            &weft::lattice::Domain::Rectangle { width_mm: 5.0, height_mm: 5.0 },
            &weft::lattice::Options { layers: 1, ..o.clone() },
        )
        .unwrap();
        !matches!(
            weft::lattice::generate(&d, &o, 0.4, 1, &mut |_| {}),
            Err(weft::lattice::Error::BadOptions { .. } | weft::lattice::Error::BadParameter { .. })
        )
    });
    assert!(n >= 12, "lattice rows checked: {n}");

    let dome = example("cylinder-on-sphere");
    let tp = weft::geom::Toolpath {
        passes: vec![weft::geom::Pass::layer(
            0.2,
            0.2,
            vec![weft::geom::Path::new(vec![weft::geom::DVec3::new(0.0, 0.0, 0.2), weft::geom::DVec3::new(1.0, 0.0, 0.2)], weft::geom::Feature::Lattice, 0.4)],
        )],
    };
    let n = agree(&dome, "job.nonplanar", weft::nonplanar::FIELDS, &|o| {
        let o: weft::nonplanar::Options = serde_json::from_value(o.clone()).unwrap();
        !matches!(weft::nonplanar::project(&tp, None, &o), Err(weft::nonplanar::Error::BadOptions { .. }))
    });
    assert!(n >= 8, "non-planar rows checked: {n}");

    for (prefix, fields) in [("printer", weft::gcode::PRINTER_FIELDS), ("material", weft::gcode::MATERIAL_FIELDS), ("speeds", weft::gcode::SPEED_FIELDS)] {
        let n = agree(&cube, prefix, fields, &|o| {
            let mut options = weft::gcode::Options::default();
            match prefix {
                "printer" => options.printer = serde_json::from_value(o.clone()).unwrap(),
                "material" => options.material = serde_json::from_value(o.clone()).unwrap(),
                _ => options.speeds = serde_json::from_value(o.clone()).unwrap(),
            }
            weft::gcode::check_options(&options).is_empty()
        });
        assert!(n >= 12, "{prefix} rows checked: {n}");
    }
}

//! Hostile strings in what the G-code writer is given: names cannot start a G-code line,
//! templates cannot blow up. A design refuses such names already (`catalog::schema`); the writer
//! is also called with options built in code, so it keeps names on one line itself.

use weft::gcode::{write_gcode, Error, Options, MAX_EXPANDED_BYTES, MAX_TEMPLATE_BYTES};
use weft::geom::{DVec3, Feature, Pass, Path, Toolpath};
use weft::testgen::design as gen;

fn one_square() -> Toolpath {
    let p = |x: f64, y: f64| DVec3::new(x, y, 0.2);
    let path = Path {
        points: vec![p(-5.0, -5.0), p(5.0, -5.0), p(5.0, 5.0), p(-5.0, 5.0), p(-5.0, -5.0)],
        feature: Feature::Lattice,
        width: 0.4,
        speed_factor: 1.0,
        approach: None,
        data: None,
    };
    Toolpath { passes: vec![Pass::layer(0.2, 0.2, vec![path])] }
}

#[test]
fn names_cannot_start_a_gcode_line() {
    let mut o = Options { design_name: "x\nG28 X9 ; home\r\nM84 S77\u{85}M104 S300\u{2028}M140 S120\u{0}G1 Z-5".into(), ..Options::default() };
    o.printer.name = "p\nM502".into();
    o.material.name = "m\rM500".into();
    o.printer.start_gcode = "M117 {design_name}\n; {design_name}\n".into();
    let g = write_gcode(&one_square(), &o).unwrap().text;
    for line in g.lines() {
        // Every injected code stays inside the line of the name that carried it.
        for code in ["G28 X9", "M84 S77", "M104 S300", "M140 S120", "G1 Z-5", "M502", "M500"] {
            if line.contains(code) {
                assert!(
                    line.starts_with("; design: ")
                        || line.starts_with("; printer: ")
                        || line.starts_with("; material: ")
                        || line.starts_with("; filament_type = ")
                        || line.starts_with("M117 x")
                        || line.starts_with("; x"),
                    "{line:?}"
                );
            }
        }
    }
    assert!(g.contains("; design: x G28 X9 ; home  M84 S77 M104 S300 M140 S120 G1 Z-5\n"), "{}", &g[..400]);
    assert!(g.contains("\nM117 x G28 X9 ; home  M84 S77 M104 S300 M140 S120 G1 Z-5\n"));
    assert!(g.contains("; printer: p M502\n") && g.contains("; material: m M500\n"));
}

#[test]
fn templates_are_bounded() {
    let mut o = Options { design_name: "n".repeat(256), ..Options::default() };
    o.printer.start_gcode = gen::template_bomb(5000);
    let e = write_gcode(&one_square(), &o).unwrap_err();
    assert!(matches!(e, Error::TemplateTooLarge { template: "start_gcode", limit: MAX_EXPANDED_BYTES, .. }), "{e}");
    let m = e.to_string();
    assert!(m.contains("1280250 bytes") && m.contains(&MAX_EXPANDED_BYTES.to_string()) && m.contains("fewer placeholders"), "{m}");
    o.printer.start_gcode = String::new();
    o.printer.end_gcode = gen::unclosed_braces_template(MAX_TEMPLATE_BYTES + 1);
    let e = write_gcode(&one_square(), &o).unwrap_err();
    assert!(matches!(e, Error::TemplateTooLong { template: "end_gcode", .. }), "{e}");
    // At the limit, unclosed braces are written as they are.
    o.printer.end_gcode = gen::unclosed_braces_template(MAX_TEMPLATE_BYTES);
    let g = write_gcode(&one_square(), &o).unwrap().text;
    assert!(g.contains(&o.printer.end_gcode));
}

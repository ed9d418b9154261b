//! Generators of G-code inputs for the analyzer (see the module above). Each is deterministic
//! and makes about `n` moves in bytes linear in `n`.

use std::fmt::Write;

/// Common start: absolute XYZ, relative E, first layer height.
const HEADER: &str = "G21\nG90\nM83\nG1 Z0.2 F600\n;LAYER:0\n;TYPE:Perimeter\n;WIDTH:0.45\n";

/// Hostile for the overlap search: `n` extruding moves back and forth over the same 10 mm
/// strut (every move lies exactly on all earlier ones, so a pairwise search is quadratic).
pub fn repeated_moves(n: usize) -> Vec<u8> {
    let mut s = String::with_capacity(HEADER.len() + 24 * n);
    s.push_str(HEADER);
    s.push_str("G0 X10 Y10 F6000\nG1 F1800\n");
    for k in 0..n {
        s.push_str(if k % 2 == 0 { "G1 X20 Y10 E0.4\n" } else { "G1 X10 Y10 E0.4\n" });
    }
    s.into_bytes()
}

/// Hostile for the overlap search: `n` extruding moves that each cross a 300 mm bed along its
/// diagonal, back and forth, shifted sideways by up to 0.3 mm (so they are stacked, nearly but
/// not exactly on each other, and each crosses hundreds of grid cells).
pub fn long_moves(n: usize) -> Vec<u8> {
    let mut s = String::with_capacity(HEADER.len() + 32 * n);
    s.push_str(HEADER);
    s.push_str("G0 X0 Y0 F6000\nG1 F1800\n");
    for k in 0..n {
        let shift = 0.02 * (k % 16) as f64;
        let (x, y) = if k % 2 == 0 { (300.0, 300.0 - shift) } else { (0.0, shift) };
        let _ = writeln!(s, "G1 X{x:.3} Y{y:.3} E12");
    }
    s.into_bytes()
}

/// Hostile for arc expansion: `n` extruding full circles (`G2` with `I`) of radius 100 mm
/// around the bed centre, radius growing by 0.01 mm per arc (each becomes many chords, all
/// stacked on each other).
pub fn large_arcs(n: usize) -> Vec<u8> {
    let mut s = String::with_capacity(HEADER.len() + 36 * n);
    s.push_str(HEADER);
    s.push_str("G0 X50 Y150 F6000\nG1 F1800\n");
    for k in 0..n {
        let r = 100.0 + 0.01 * (k % 64) as f64;
        let _ = writeln!(s, "G0 X{:.3} Y150\nG2 X{:.3} Y150 I{r:.3} J0 E20", 150.0 - r, 150.0 - r);
    }
    s.into_bytes()
}

/// A normal print of about `n` moves: layers of 20 concentric 120-gon perimeters (0.45 mm
/// apart, chords of about 1 mm) with a retraction and travel between rings, `;LAYER:` comments,
/// absolute E. The linear baseline for the scaling tests.
pub fn perimeter_print(n: usize) -> Vec<u8> {
    const SIDES: usize = 120;
    const RINGS: usize = 20;
    let mut s = String::with_capacity(64 * n + 256);
    s.push_str("G21\nG90\nM82\nG92 E0\n");
    let mut e = 0.0f64;
    let mut moves = 0usize;
    let mut layer = 0usize;
    while moves < n {
        let z = 0.2 * (layer + 1) as f64;
        let _ = writeln!(s, ";LAYER:{layer}\nG1 Z{z:.3} F600\n;TYPE:Perimeter\n;WIDTH:0.45");
        'rings: for ring in 0..RINGS {
            let r = 20.0 + 0.45 * ring as f64;
            let _ = writeln!(s, "G0 X{:.3} Y100.000 F6000", 100.0 + r);
            s.push_str("G1 E");
            e += 0.8;
            let _ = writeln!(s, "{e:.5} F2400");
            for k in 1..=SIDES {
                let t = k as f64 / SIDES as f64 * std::f64::consts::TAU;
                let (x, y) = (100.0 + r * libm::cos(t), 100.0 + r * libm::sin(t));
                e += 0.035;
                let _ = writeln!(s, "G1 X{x:.3} Y{y:.3} E{e:.5} F1800");
                moves += 1;
                if moves >= n {
                    break 'rings;
                }
            }
            e -= 0.8;
            let _ = writeln!(s, "G1 E{e:.5} F2400");
        }
        layer += 1;
    }
    s.into_bytes()
}

/// Hostile for the lexer: `n` moves whose numbers are written with exponents (`X1.5e1`,
/// `E1e300`, `Y2E-3`…), which G-code does not have; the analyzer must refuse the first with
/// its line number instead of misreading `e300` as a separate E word.
pub fn exponent_words(n: usize) -> Vec<u8> {
    const FORMS: [&str; 6] = ["X1.5e1 Y10 E0.1", "X10 Y1e10 E0.1", "X12 Y10 E1e300", "X1e-3 Y10 E0.1", "X5 Y5 E2.5e-2", "X3 Y3e+2 E0.1"];
    let mut s = String::with_capacity(HEADER.len() + 24 * n);
    s.push_str(HEADER);
    for k in 0..n {
        let _ = writeln!(s, "G1 {}", FORMS[k % FORMS.len()]);
    }
    s.into_bytes()
}

//! The analyzer never panics: mutated fixtures and random G-code-ish bytes, with exponents,
//! huge numbers and arcs among the mutations. Whatever it accepts has finite totals.

use weft::analyze::{analyze, Options, MAX_ARC_CHORDS};

struct XorShift(u64);
impl XorShift {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}

const ALPHABET: &[u8] = b"GMXYZEFIJRPSTN0123456789.-+ ;()*\n\r\tgxyze%";

/// Multi-byte insertions: exponents (refused), numbers at and past the magnitude limit, tiny
/// feeds, arcs (huge, degenerate, helical).
const SNIPPETS: &[&str] = &[
    "e5",
    "e-3",
    "e+300",
    "E1e300",
    "X1e10",
    "9999999",
    "10000001",
    "F0.0001",
    "\nG2 X10 Y10 I10000000 J0 E1\n",
    "\nG3 X0 Y0 I-9999999 J0 E5\n",
    "\nG2 X5 Y5 R-9999999 E1\n",
    "\nG2 X1 Y0 R0.0000001 E1\n",
    "\nG3 X0 Y0 Z9999999 I1 J1 E1\n",
    "\nG91\nG2 X0 Y0 I0.001 E1\n",
];

fn check(bytes: &[u8]) {
    let opts = Options { collect_preview: true, ..Default::default() };
    if let Ok(a) = analyze("fuzz", bytes, &opts) {
        let r = &a.report;
        assert_eq!(r.per_layer.len(), r.layers);
        assert_eq!(r.per_layer.iter().map(|l| l.extrusion_paths).sum::<usize>(), r.extrusion_paths);
        let p = a.preview.unwrap();
        let n = p.positions.len() / 6;
        assert_eq!(p.positions.len() % 6, 0);
        assert_eq!(p.feature.len(), n);
        assert_eq!(p.path.len(), n);
        assert_eq!(p.flow.len(), n);
        assert_eq!(p.width.len(), n);
        assert_eq!(p.layer_segment_start.len(), r.layers + 1);
        assert_eq!(p.layer_travel_start.len(), r.layers + 1);
        assert_eq!(p.layer_z.len(), r.layers);
        assert_eq!(*p.layer_segment_start.last().unwrap() as usize, n);
        assert!(p.layer_segment_start.windows(2).all(|w| w[0] <= w[1]));
        assert!(p.layer_travel_start.windows(2).all(|w| w[0] <= w[1]));
        assert!(r.overlap_mm <= r.extruded_mm * (1.0 + 1e-9) + 1e-9);
        for v in [r.extruded_mm, r.travel_mm, r.filament_mm, r.estimated_time_s, r.overlap_mm, r.gippo_score] {
            assert!(v.is_finite(), "{r:?}");
        }
        // Every move gives at most MAX_ARC_CHORDS segments.
        let moves = bytes.iter().filter(|&&b| b == b'\n').count() + 1;
        assert!(n + p.travel_positions.len() / 6 <= moves * MAX_ARC_CHORDS);
    }
}

#[test]
fn mutated_fixtures_never_panic() {
    let base = [
        std::fs::read(format!("{}/tests/fixtures/prusaslicer-style.gcode", env!("CARGO_MANIFEST_DIR"))).unwrap(),
        std::fs::read(format!("{}/tests/fixtures/cura-style.gcode", env!("CARGO_MANIFEST_DIR"))).unwrap(),
    ];
    let mut rng = XorShift(0x9E37_79B9_7F4A_7C15);
    for round in 0..3000 {
        let mut b = base[round % 2].clone();
        for _ in 0..1 + rng.below(20) {
            let i = rng.below(b.len());
            match rng.below(4) {
                0 => b[i] = ALPHABET[rng.below(ALPHABET.len())],
                1 => b.insert(i, ALPHABET[rng.below(ALPHABET.len())]),
                2 if rng.below(4) == 0 => {
                    let snippet = SNIPPETS[rng.below(SNIPPETS.len())].as_bytes();
                    b.splice(i..i, snippet.iter().copied());
                }
                _ => {
                    b.remove(i);
                }
            }
        }
        if round % 97 == 0 {
            let i = rng.below(b.len());
            b[i] = rng.below(256) as u8;
        }
        check(&b);
    }
}

#[test]
fn random_gcode_words_never_panic() {
    let mut rng = XorShift(12345);
    for _ in 0..3000 {
        let mut s = String::new();
        for _ in 0..rng.below(30) {
            let cmd =
                ["G0", "G1", "G2", "G3", "G4", "G10", "G11", "G28", "G90", "G91", "G92", "M82", "M83", "M204", "", ";LAYER:1", ";TYPE:FILL", ";WIDTH:0.5"]
                    [rng.below(18)];
            s.push_str(cmd);
            for _ in 0..rng.below(5) {
                let letter = b"XYZEFIJRPS"[rng.below(10)] as char;
                let v = match rng.below(10) {
                    0 => "0".to_string(),
                    1 => format!("{}", rng.below(200) as f64 / 7.0),
                    2 => format!("-{}", rng.below(50)),
                    3 => "1e400".to_string(),
                    4 => "99999999999999999999999".to_string(),
                    5 => format!("{}e{}", rng.below(10), rng.below(400) as i64 - 200),
                    6 => "9999999.999".to_string(),
                    7 => "-10000000".to_string(),
                    8 => format!("0.{:0>12}", rng.below(1000)),
                    _ => format!(".{}", rng.below(1000)),
                };
                s.push(' ');
                s.push(letter);
                s.push_str(&v);
            }
            s.push('\n');
        }
        check(s.as_bytes());
    }
}

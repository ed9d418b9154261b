//! Generators of other slicers' G-code for the G-code editor ([`crate::gcode_edit`]): files
//! shaped like PrusaSlicer 2.6, Slic3r 1.3 (`--gcode-comments`) and Cura 5 output, with each
//! slicer's header, number style, feature comments, retractions and E resets, in absolute
//! (`M82`) or relative (`M83`) E. Each file records its infill moves (line, midpoint, E delta
//! as printed) so tests can check every edit against the file itself.
//!
//! The part: a square prism centred at (100, 100) with two perimeters, solid bottom and top
//! layers and rectilinear sparse infill at spacing width/ρ_s in between, its lines split into
//! segments of at most [`Foreign::segment_mm`] (as gyroid infill is), directions alternating
//! by layer. Bytes are linear in layers × side².

/// Which slicer's output to imitate.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Slicer {
    /// PrusaSlicer 2.6: `;TYPE:` markers, `;LAYER_CHANGE`/`;Z:`/`;HEIGHT:`, trimmed numbers
    /// (`E.02612`), `G92 E0` every layer, wipes with negative E.
    PrusaSlicer,
    /// Slic3r 1.3 with verbose G-code: per-line `; infill` comments, fixed decimals
    /// (`E1.23456`), `G92 E0 ; reset extrusion distance` after each retraction in absolute E.
    Slic3r,
    /// Cura 5: `;TYPE:FILL`/`SKIN`/`WALL-OUTER`, `;LAYER:n`, `G0` travels, absolute E
    /// without resets.
    Cura,
}

/// What to generate.
#[derive(Clone, Debug, PartialEq)]
pub struct Foreign {
    /// The slicer imitated.
    pub slicer: Slicer,
    /// Layers (0.2 mm).
    pub layers: usize,
    /// Relative E (`M83`) instead of absolute (`M82`).
    pub relative_e: bool,
    /// Side of the square part, mm.
    pub side_mm: f64,
    /// Sliced infill density (0 writes no sparse infill at all).
    pub rho_s: f64,
    /// Longest infill segment, mm.
    pub segment_mm: f64,
    /// Solid layers at the bottom and at the top.
    pub solid_layers: usize,
    /// Sparse infill feed, mm/min.
    pub infill_feed: f64,
}

impl Default for Foreign {
    fn default() -> Self {
        Foreign { slicer: Slicer::PrusaSlicer, layers: 10, relative_e: true, side_mm: 20.0, rho_s: 0.47, segment_mm: 2.0, solid_layers: 2, infill_feed: 3000.0 }
    }
}

/// One infill move of a generated file.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InfillMove {
    /// 0-based line.
    pub line: usize,
    /// Midpoint, mm.
    pub mid: [f64; 3],
    /// Length, mm.
    pub len: f64,
    /// E delta as printed, mm.
    pub de: f64,
    /// Solid infill (only Slic3r's solid infill is marked as infill).
    pub solid: bool,
}

/// A generated file.
#[derive(Clone, Debug, PartialEq)]
pub struct Generated {
    /// The G-code.
    pub text: Vec<u8>,
    /// The moves the editor must treat as infill, in file order.
    pub infill: Vec<InfillMove>,
    /// Box of the extruding moves, mm (min, max).
    pub bounds: ([f64; 3], [f64; 3]),
}

/// Bead width, mm.
const WIDTH: f64 = 0.45;
/// Layer height, mm.
const HEIGHT: f64 = 0.2;
/// Filament diameter, mm.
const FILAMENT: f64 = 1.75;
/// Retraction, mm.
const RETRACT: f64 = 0.8;

#[derive(Clone, Copy, PartialEq, Eq)]
enum Kind {
    External,
    Perimeter,
    Solid,
    Infill,
}

struct Writer {
    s: String,
    slicer: Slicer,
    relative: bool,
    /// E position as printed (absolute mode).
    e: f64,
    pos: [f64; 3],
    line: usize,
    infill: Vec<InfillMove>,
    kind: Option<Kind>,
    lo: [f64; 3],
    hi: [f64; 3],
    epm: f64,
}

/// `v` with `d` decimals, trailing zeros and a leading zero dropped (PrusaSlicer's style).
fn trimmed(v: f64, d: usize) -> String {
    let mut t = format!("{v:.d$}");
    if t.contains('.') {
        while t.ends_with('0') {
            t.pop();
        }
        if t.ends_with('.') {
            t.pop();
        }
    }
    if t == "-0" {
        t = "0".into();
    }
    if let Some(rest) = t.strip_prefix("0.") {
        t = format!(".{rest}");
    } else if let Some(rest) = t.strip_prefix("-0.") {
        t = format!("-.{rest}");
    }
    t
}

impl Writer {
    fn push(&mut self, text: &str) {
        self.s.push_str(text);
        self.s.push('\n');
        self.line += 1;
    }

    /// XY (or Z) coordinate in the slicer's style.
    fn xy(&self, v: f64) -> String {
        match self.slicer {
            Slicer::Slic3r => format!("{v:.3}"),
            _ => trimmed(v, 3),
        }
    }

    /// The E word for a delta `de` (updates the absolute position); returns the word and the
    /// delta as printed.
    fn e_word(&mut self, de: f64) -> (String, f64) {
        let v = if self.relative { de } else { self.e + de };
        let text = match self.slicer {
            Slicer::PrusaSlicer => trimmed(v, 5),
            _ => format!("{v:.5}"),
        };
        let printed: f64 = text.parse().unwrap_or(0.0);
        if self.relative {
            (text, printed)
        } else {
            let d = printed - self.e;
            self.e = printed;
            (text, d)
        }
    }

    fn set_kind(&mut self, k: Kind) {
        if self.kind == Some(k) {
            return;
        }
        self.kind = Some(k);
        let name = match (self.slicer, k) {
            (Slicer::PrusaSlicer, Kind::External) => "External perimeter",
            (Slicer::PrusaSlicer, Kind::Perimeter) => "Perimeter",
            (Slicer::PrusaSlicer, Kind::Solid) => "Solid infill",
            (Slicer::PrusaSlicer, Kind::Infill) => "Internal infill",
            (Slicer::Cura, Kind::External) => "WALL-OUTER",
            (Slicer::Cura, Kind::Perimeter) => "WALL-INNER",
            (Slicer::Cura, Kind::Solid) => "SKIN",
            (Slicer::Cura, Kind::Infill) => "FILL",
            (Slicer::Slic3r, _) => return,
        };
        self.push(&format!(";TYPE:{name}"));
        if self.slicer == Slicer::PrusaSlicer {
            self.push(&format!(";WIDTH:{WIDTH}"));
        }
    }

    fn travel(&mut self, x: f64, y: f64, what: &str) {
        let t = match self.slicer {
            Slicer::PrusaSlicer => format!("G1 X{} Y{} F9000", self.xy(x), self.xy(y)),
            Slicer::Slic3r => format!("G1 X{} Y{} F7800.000 ; move to first {what} point", self.xy(x), self.xy(y)),
            Slicer::Cura => format!("G0 F6000 X{} Y{}", self.xy(x), self.xy(y)),
        };
        self.push(&t);
        self.pos[0] = x;
        self.pos[1] = y;
    }

    fn retract(&mut self) {
        let (w, _) = self.e_word(-RETRACT);
        let t = match self.slicer {
            Slicer::PrusaSlicer => format!("G1 E{w} F2100"),
            Slicer::Slic3r => format!("G1 E{w} F2400.00000 ; retract"),
            Slicer::Cura => format!("G1 F2700 E{w}"),
        };
        self.push(&t);
        if self.slicer == Slicer::Slic3r && !self.relative {
            self.push("G92 E0 ; reset extrusion distance");
            self.e = 0.0;
        }
    }

    fn unretract(&mut self) {
        let (w, _) = self.e_word(RETRACT);
        let t = match self.slicer {
            Slicer::PrusaSlicer => format!("G1 E{w} F2100"),
            Slicer::Slic3r => format!("G1 E{w} F2400.00000 ; unretract"),
            Slicer::Cura => format!("G1 F2700 E{w}"),
        };
        self.push(&t);
    }

    /// An extruding move to (x, y) of feature `k`.
    fn extrude(&mut self, x: f64, y: f64, k: Kind) {
        let p = self.pos;
        let len = ((x - p[0]).powi(2) + (y - p[1]).powi(2)).sqrt();
        let (w, de) = self.e_word(len * self.epm);
        let comment = match (self.slicer, k) {
            (Slicer::Slic3r, Kind::Infill | Kind::Solid) => " ; infill",
            (Slicer::Slic3r, _) => " ; perimeter",
            _ => "",
        };
        let line = self.line;
        let t = format!("G1 X{} Y{} E{w}{comment}", self.xy(x), self.xy(y));
        self.push(&t);
        let edited = k == Kind::Infill || (self.slicer == Slicer::Slic3r && k == Kind::Solid);
        if edited {
            self.infill.push(InfillMove { line, mid: [(p[0] + x) / 2.0, (p[1] + y) / 2.0, p[2]], len, de, solid: k == Kind::Solid });
        }
        for (k, v) in [p[0], p[1], p[2], x, y, p[2]].into_iter().enumerate() {
            self.lo[k % 3] = self.lo[k % 3].min(v);
            self.hi[k % 3] = self.hi[k % 3].max(v);
        }
        self.pos[0] = x;
        self.pos[1] = y;
    }

    fn feed(&mut self, f: f64) {
        let t = match self.slicer {
            Slicer::Slic3r => format!("G1 F{f:.3}"),
            _ => format!("G1 F{f}"),
        };
        self.push(&t);
    }

    fn header(&mut self, spec: &Foreign) {
        match self.slicer {
            Slicer::PrusaSlicer => {
                self.push("; generated by PrusaSlicer 2.6.1+linux-x64 on 2024-05-01 at 10:00:00 UTC");
                self.push("");
                self.push("; external perimeters extrusion width = 0.45mm");
                self.push(";");
                self.push("M73 P0 R12");
                self.push("M201 X1000 Y1000 Z200 E5000 ; sets maximum accelerations, mm/sec^2");
                self.push("M107");
                self.push(";TYPE:Custom");
                self.push("G90 ; use absolute coordinates");
                self.push(if spec.relative_e { "M83 ; extruder relative mode" } else { "M82 ; extruder absolute mode" });
                self.push("M104 S215 ; set extruder temp");
                self.push("G28 W ; home all without mesh bed level");
                self.push("G21 ; set units to millimeters");
                self.push("G92 E0");
            }
            Slicer::Slic3r => {
                self.push("; generated by Slic3r 1.3.0 on 2020-01-14 at 10:00:00");
                self.push("");
                self.push("; perimeters extrusion width = 0.45mm");
                self.push("; infill extrusion width = 0.45mm");
                self.push("");
                self.push("M107");
                self.push("M104 S215 ; set temperature");
                self.push("G28 ; home all axes");
                self.push("G1 Z5 F5000 ; lift nozzle");
                self.push("M109 S215 ; set temperature and wait for it to be reached");
                self.push("G21 ; set units to millimeters");
                self.push("G90 ; use absolute coordinates");
                self.push(if spec.relative_e { "M83 ; use relative distances for extrusion" } else { "M82 ; use absolute distances for extrusion" });
                self.push("G92 E0");
            }
            Slicer::Cura => {
                self.push(";FLAVOR:Marlin");
                self.push(";TIME:1234");
                self.push(";Filament used: 1.23456m");
                self.push(&format!(";Layer height: {HEIGHT}"));
                self.push(";Generated with Cura_SteamEngine 5.4.0");
                self.push("M140 S60");
                self.push("M104 S215");
                self.push("M109 S215");
                self.push(if spec.relative_e { "M83 ;relative extrusion mode" } else { "M82 ;absolute extrusion mode" });
                self.push("G28 ;Home");
                self.push("G92 E0");
                self.push(&format!(";LAYER_COUNT:{}", spec.layers));
            }
        }
    }

    fn layer_change(&mut self, k: usize, z: f64) {
        match self.slicer {
            Slicer::PrusaSlicer => {
                self.push(";LAYER_CHANGE");
                self.push(&format!(";Z:{}", trimmed(z, 3)));
                self.push(&format!(";HEIGHT:{HEIGHT}"));
                self.push(";BEFORE_LAYER_CHANGE");
                self.push("G92 E0");
                self.e = 0.0;
                self.push(&format!(";{}", trimmed(z, 3)));
                self.push(&format!("G1 Z{} F720", trimmed(z, 3)));
                self.push(";AFTER_LAYER_CHANGE");
            }
            Slicer::Slic3r => self.push(&format!("G1 Z{z:.3} F7800.000 ; move to next layer ({k})")),
            Slicer::Cura => {
                self.push(&format!(";LAYER:{k}"));
                self.push("M107");
                self.push(&format!("G0 F6000 Z{}", self.xy(z)));
            }
        }
        self.pos[2] = z;
    }
}

/// Generates the file `spec` describes.
pub fn generate(spec: &Foreign) -> Generated {
    let area = (WIDTH - HEIGHT) * HEIGHT + std::f64::consts::PI * HEIGHT * HEIGHT / 4.0;
    let epm = area / (std::f64::consts::PI * FILAMENT * FILAMENT / 4.0);
    let mut w = Writer {
        s: String::new(),
        slicer: spec.slicer,
        relative: spec.relative_e,
        e: 0.0,
        pos: [0.0; 3],
        line: 0,
        infill: Vec::new(),
        kind: None,
        lo: [f64::INFINITY; 3],
        hi: [f64::NEG_INFINITY; 3],
        epm,
    };
    w.header(spec);
    let (cx, cy) = (100.0, 100.0);
    let half = spec.side_mm / 2.0;
    for k in 0..spec.layers {
        let z = HEIGHT * (k + 1) as f64;
        w.layer_change(k, z);
        // Perimeters, inner first as PrusaSlicer and Cura print them.
        for ring in (0..2).rev() {
            let h = half - WIDTH * (ring as f64 + 0.5);
            w.travel(cx - h, cy - h, "perimeter");
            w.unretract();
            w.set_kind(if ring == 0 { Kind::External } else { Kind::Perimeter });
            w.feed(if ring == 0 { 1500.0 } else { 2400.0 });
            for (x, y) in [(cx + h, cy - h), (cx + h, cy + h), (cx - h, cy + h), (cx - h, cy - h)] {
                w.extrude(x, y, if ring == 0 { Kind::External } else { Kind::Perimeter });
            }
            w.retract();
        }
        // Infill inside the inner perimeter.
        let solid = k < spec.solid_layers || k + spec.solid_layers >= spec.layers;
        if !solid && spec.rho_s <= 0.0 {
            continue;
        }
        let kind = if solid { Kind::Solid } else { Kind::Infill };
        let spacing = if solid { WIDTH } else { WIDTH / spec.rho_s };
        let h = half - 2.0 * WIDTH - WIDTH / 2.0;
        let lines = ((2.0 * h) / spacing).floor() as usize + 1;
        let along_x = k % 2 == 0;
        let at = |u: f64, v: f64| if along_x { (u, v) } else { (v, u) };
        let (x0, y0) = at(cx - h, cy - h);
        w.travel(x0, y0, "infill");
        w.unretract();
        w.set_kind(kind);
        w.feed(if solid { 2400.0 } else { spec.infill_feed });
        for i in 0..lines {
            let v = cy - h + i as f64 * spacing;
            let (u0, u1) = if i % 2 == 0 { (cx - h, cx + h) } else { (cx + h, cx - h) };
            if i > 0 {
                // The connection from the previous line's end.
                let (x, y) = at(u0, v);
                w.extrude(x, y, kind);
            }
            let n = ((2.0 * h) / spec.segment_mm).ceil().max(1.0) as usize;
            for s in 1..=n {
                let u = u0 + (u1 - u0) * s as f64 / n as f64;
                let (x, y) = at(u, v);
                w.extrude(x, y, kind);
            }
        }
        if w.slicer == Slicer::PrusaSlicer {
            // A wipe: retracting while moving back along the last line.
            w.push(";WIPE_START");
            w.push("G1 F8640");
            let (x, y) = (w.pos[0], w.pos[1]);
            let (xb, yb) = if along_x { (x + if x > cx { -1.0 } else { 1.0 }, y) } else { (x, y + if y > cy { -1.0 } else { 1.0 }) };
            let (e, _) = w.e_word(-0.5);
            let t = format!("G1 X{} Y{} E{e}", w.xy(xb), w.xy(yb));
            w.push(&t);
            w.pos[0] = xb;
            w.pos[1] = yb;
            w.push(";WIPE_END");
            let (e, _) = w.e_word(-(RETRACT - 0.5));
            w.push(&format!("G1 E{e} F2100"));
        } else {
            w.retract();
        }
        if w.slicer == Slicer::Cura {
            w.push(&format!(";TIME_ELAPSED:{:.6}", 10.0 * (k + 1) as f64));
        }
    }
    // End: the final retract and lift.
    match spec.slicer {
        Slicer::PrusaSlicer => {
            w.push("G1 Z5 F720");
            w.push("M104 S0 ; turn off temperature");
            w.push("M84 ; disable motors");
            w.push("; filament used [mm] = 1234.56");
            w.push(&format!("; fill_density = {}%", (spec.rho_s * 100.0).round()));
            w.push("; layer_height = 0.2");
        }
        Slicer::Slic3r => {
            w.push("M104 S0 ; turn off temperature");
            w.push("G28 X0  ; home X axis");
            w.push("M84     ; disable motors");
            w.push("; filament used = 1234.5mm (8.9cm3)");
        }
        Slicer::Cura => {
            w.push("M140 S0");
            w.push("M84");
            w.push(";End of Gcode");
        }
    }
    Generated { text: w.s.into_bytes(), infill: w.infill, bounds: (w.lo, w.hi) }
}

/// A file of about `bytes` bytes (at least 10 layers) of `slicer`'s style: a 60 mm part, as
/// many layers as it takes (the size of a sparse layer measured from two small files).
pub fn sized(slicer: Slicer, relative_e: bool, bytes: usize) -> Generated {
    let probe = Foreign { slicer, relative_e, layers: 10, side_mm: 60.0, ..Foreign::default() };
    let ten = generate(&probe).text.len();
    let twenty = generate(&Foreign { layers: 20, ..probe.clone() }).text.len();
    let per_layer = ((twenty - ten) / 10).max(1);
    let layers = 10 + bytes.saturating_sub(ten) / per_layer;
    generate(&Foreign { layers, ..probe })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_in_prusaslicer_style() {
        assert_eq!(trimmed(0.0261, 5), ".0261");
        assert_eq!(trimmed(-0.8, 5), "-.8");
        assert_eq!(trimmed(100.0, 3), "100");
        assert_eq!(trimmed(0.0, 5), "0");
    }

    #[test]
    fn files_record_their_infill() {
        for slicer in [Slicer::PrusaSlicer, Slicer::Slic3r, Slicer::Cura] {
            let g = generate(&Foreign { slicer, ..Foreign::default() });
            let text = String::from_utf8(g.text).unwrap();
            let lines: Vec<&str> = text.lines().collect();
            assert!(!g.infill.is_empty());
            for m in &g.infill {
                assert!(lines[m.line].starts_with("G1 X"), "{slicer:?}: {}", lines[m.line]);
                assert!(m.de > 0.0);
            }
        }
    }
}

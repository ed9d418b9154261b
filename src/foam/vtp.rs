//! The viscous-thread-printing numbers of one piece of toolpath (the paper's section 3.2.4).
//!
//! A thread of section `A_t = π(α·d_n/2)²` (α the die swell, d_n the nozzle) leaves the nozzle at
//! `C·A_f/A_t` (filament of section `A_f = π(f_d/2)²` fed at C). The nozzle moves V* times as fast
//! (`V* = F/C` in the paper's dimensionless form), at a height `H = α·d_n·H*` above the layer:
//! - nozzle height above the layer's sliced z: `z_offset = α·d_n·H* − l_h`;
//! - filament over a piece of length L: `ΔE = L·A_t / (V*·A_f)`;
//! - feed: `f = V*·C·A_f / A_t` (mm/s; ×60 in G-code).
//!
//! Lower V* lays more thread per mm (denser coils, a stiffer foam); the extrusion rate `C` is
//! the same everywhere: VTP is a constant-extrusion process.

use serde::{Deserialize, Serialize};

/// A region's dimensionless pair π = (V*, H*).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Pair {
    /// V* = nozzle speed ÷ speed of the thread leaving the nozzle.
    pub v_star: f64,
    /// H* = nozzle height ÷ (die swell α · nozzle diameter).
    pub h_star: f64,
}

impl Pair {
    /// `self·(1 − w) + other·w` (equation 1).
    pub fn lerp(self, other: Pair, w: f64) -> Pair {
        // Equal ends stay exact (a constant H* prints at one height, not 1 ulp off).
        let mix = |a: f64, b: f64| if a == b { a } else { a * (1.0 - w) + b * w };
        Pair { v_star: mix(self.v_star, other.v_star), h_star: mix(self.h_star, other.h_star) }
    }
}

/// The process: nozzle, material and extrusion rate (mm, mm/s).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Process {
    /// Nozzle diameter d_n, mm.
    pub nozzle_mm: f64,
    /// Die swell α: the thread's diameter ÷ the nozzle's (measured for the material).
    pub die_swell: f64,
    /// Filament diameter f_d, mm.
    pub filament_mm: f64,
    /// Filament feed speed C, mm/s (constant over the print).
    pub feed_mm_s: f64,
}

/// What one piece prints with.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Piece {
    /// Filament over the piece, mm.
    pub e_mm: f64,
    /// Nozzle speed, mm/s.
    pub speed_mm_s: f64,
    /// Nozzle height above the layer's sliced z, mm.
    pub z_offset_mm: f64,
}

impl Process {
    /// Section of the thread leaving the nozzle (with die swell), mm².
    pub fn thread_area(&self) -> f64 {
        let d = self.die_swell * self.nozzle_mm;
        std::f64::consts::PI * d * d / 4.0
    }

    /// Section of the filament, mm².
    pub fn filament_area(&self) -> f64 {
        std::f64::consts::PI * self.filament_mm * self.filament_mm / 4.0
    }

    /// Filament per mm of nozzle travel at `v_star`: `A_t / (V*·A_f)`.
    pub fn filament_per_mm(&self, v_star: f64) -> f64 {
        self.thread_area() / (v_star * self.filament_area())
    }

    /// Nozzle speed at `v_star`, mm/s: `V*·C·A_f / A_t`.
    pub fn speed_mm_s(&self, v_star: f64) -> f64 {
        v_star * self.feed_mm_s * self.filament_area() / self.thread_area()
    }

    /// Nozzle height above the layer at `h_star` for layers of `layer_mm`: `α·d_n·H* − l_h`.
    pub fn z_offset_mm(&self, h_star: f64, layer_mm: f64) -> f64 {
        self.die_swell * self.nozzle_mm * h_star - layer_mm
    }

    /// The numbers of a piece `len_mm` long printed with `pair` on layers of `layer_mm`.
    pub fn piece(&self, pair: Pair, len_mm: f64, layer_mm: f64) -> Piece {
        Piece {
            e_mm: len_mm * self.filament_per_mm(pair.v_star),
            speed_mm_s: self.speed_mm_s(pair.v_star),
            z_offset_mm: self.z_offset_mm(pair.h_star, layer_mm),
        }
    }

    /// Every problem with the process, each saying how to fix it (empty when usable).
    pub fn problems(&self) -> Vec<String> {
        let mut out = Vec::new();
        for (name, v, fix) in [
            ("the nozzle diameter", self.nozzle_mm, "set printer.nozzle_diameter_mm"),
            ("the die swell", self.die_swell, "measure the thread's diameter ÷ the nozzle's (1 for none)"),
            ("the filament diameter", self.filament_mm, "set printer.filament_diameter_mm"),
            ("the filament feed speed C", self.feed_mm_s, "give the extruder's feed, mm/s"),
        ] {
            if !(v.is_finite() && v > 0.0) {
                out.push(format!("{name} is {v}: it must be above 0 ({fix})"));
            }
        }
        out
    }

    /// Every problem with a region's `pair` on layers of `layer_mm` (named `region`).
    pub fn pair_problems(&self, region: &str, pair: Pair, layer_mm: f64) -> Vec<String> {
        let mut out = Vec::new();
        if !(pair.v_star.is_finite() && pair.v_star > 0.0) {
            out.push(format!("{region}: V* is {}; it must be above 0 (the paper prints 0.15 to 0.4)", pair.v_star));
        }
        if !(pair.h_star.is_finite() && pair.h_star > 0.0) {
            out.push(format!("{region}: H* is {}; it must be above 0", pair.h_star));
        } else if self.problems().is_empty() && self.z_offset_mm(pair.h_star, layer_mm) < 0.0 {
            let least = layer_mm / (self.die_swell * self.nozzle_mm);
            out.push(format!("{region}: H* {} puts the nozzle {:.3} mm high, below the {layer_mm} mm layer it prints on; raise H* to at least {least:.3} or use thinner layers", pair.h_star, self.die_swell * self.nozzle_mm * pair.h_star));
        }
        out
    }
}

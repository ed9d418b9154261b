//! The analyzer's memory estimate: a quick scan of the file (line starts only, no numbers
//! read) bounds its moves and layers; [`peak_bytes`] turns counts into bytes. The analyzer
//! checks it before reading, and again with the real counts while it reads (arcs expand into
//! chords, known only once their line is read).

use super::overlap;
use super::{LayerReport, Options, MAX_LAYER_SEGMENTS};
use crate::motion::lex::parse_number;
use std::mem::size_of;

/// What [`super::estimate`] found and what it expects the analysis to need.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Estimate {
    /// Size of the file, bytes.
    pub bytes: usize,
    /// Lines.
    pub lines: usize,
    /// Lines that may be moves (`G0`–`G3`, or parameters repeating one): an upper bound.
    pub moves: usize,
    /// Of those, arcs (`G2`/`G3`); each becomes up to [`crate::motion::MAX_ARC_CHORDS`]
    /// chords, counted as one here (the analyzer counts their chords as it reads them).
    pub arcs: usize,
    /// Layers at most (layer comments, or lines that may change Z, plus one).
    pub layers: usize,
    /// Moves in the largest layer: the most between two layer comments when the file has
    /// them (not above [`MAX_LAYER_SEGMENTS`]); otherwise all moves, up to that limit.
    pub largest_layer: usize,
    /// Peak memory of the analysis (preview buffers when asked for, the largest layer's
    /// working set, per-layer records), bytes, with arcs as one chord each. The analyzer
    /// checks it again with the layers and arcs it actually reads.
    pub peak_bytes: usize,
}

/// Preview bytes per segment: the largest kind (an extrusion segment with a tool axis: 6
/// positions, feature, path, flow, ΔE per mm, speed, width, move index, 3 axis floats), twice
/// over because the buffers grow by doubling.
const PREVIEW_SEGMENT_BYTES: usize = 2 * (6 * 4 + 1 + 4 + 4 + 4 + 4 + 4 + 4 + 3 * 4);
/// Bytes per layer: its record while reading (about 56 bytes, doubled) and its report, plus the
/// preview's three per-layer entries (doubled).
const LAYER_BYTES: usize = 2 * 56 + size_of::<LayerReport>() + 2 * 12;
/// Builds with threads (native, the browser's threaded module) measure overlap on a second
/// thread: layers in flight to it (at most 10, each of at most `PARALLEL_LAYER_SEGMENTS`
/// segments and of at most the largest layer's, in vectors up to twice their length) and its
/// own working set on one of them.
#[cfg(any(not(target_arch = "wasm32"), feature = "wasm-threads"))]
fn parallel_bytes(largest_layer: usize) -> usize {
    let layer = largest_layer.min(super::machine::PARALLEL_LAYER_SEGMENTS);
    10 * layer * 2 * size_of::<overlap::Seg>() + overlap::layer_bytes(layer)
}

/// Peak bytes of an analysis making `segments` segments (extrusion and travel, arcs by their
/// chords) in `layers` layers, the largest holding `largest_layer` extrusion segments.
pub fn peak_bytes(segments: usize, layers: usize, largest_layer: usize, preview: bool) -> usize {
    let preview_bytes = if preview { segments.saturating_mul(PREVIEW_SEGMENT_BYTES) } else { 0 };
    #[cfg(any(not(target_arch = "wasm32"), feature = "wasm-threads"))]
    let parallel = parallel_bytes(largest_layer);
    #[cfg(all(target_arch = "wasm32", not(feature = "wasm-threads")))]
    let parallel = 0;
    preview_bytes
        .saturating_add(layers.saturating_mul(LAYER_BYTES))
        .saturating_add(overlap::layer_bytes(largest_layer))
        .saturating_add(parallel)
}

/// Scans `bytes` (see [`super::estimate`]).
pub(crate) fn scan(bytes: &[u8], options: &Options) -> Estimate {
    let mut e = Estimate { bytes: bytes.len(), ..Default::default() };
    if super::poses::is_poses(bytes) {
        // Every row is a point: at most one segment each, one layer.
        e.lines = bytes.split(|&b| b == b'\n').count();
        e.moves = e.lines;
        e.layers = 1;
        e.largest_layer = e.moves;
    } else {
        let comment_mode = crate::motion::lex::has_layer_comments(bytes);
        let mut arc_mode = false;
        let (mut layer_comments, mut z_lines) = (0usize, 0usize);
        // Moves since the last layer comment; whether the first layer is still open (comments
        // before its first extrusion do not start a layer) and a line that may extrude was seen.
        let (mut chunk, mut first_open, mut may_extrude) = (0usize, true, false);
        let mut start = 0;
        while start < bytes.len() {
            let end = super::machine::find_newline(&bytes[start..]).map_or(bytes.len(), |p| start + p);
            let line = &bytes[start..end];
            start = end + 1;
            e.lines += 1;
            let code_end = comment_start(line);
            let code = &line[..code_end];
            let is_move = match first_command(code) {
                First::Motion(arc) => {
                    arc_mode = arc;
                    e.arcs += usize::from(arc);
                    true
                }
                First::Modal => {
                    e.arcs += usize::from(arc_mode);
                    true
                }
                First::Home => {
                    z_lines += 1;
                    false
                }
                First::Other => false,
            };
            if is_move {
                e.moves += 1;
                chunk += 1;
                if first_open && layer_comments > 0 && !may_extrude {
                    may_extrude = code.iter().any(|&b| b == b'E' || b == b'e');
                }
            }
            if !comment_mode && code.iter().any(|&b| b == b'Z' || b == b'z') {
                z_lines += 1;
            }
            if code_end < line.len() {
                let c = crate::motion::lex::trim_start(&line[code_end + 1..]);
                if c.starts_with(b"LAYER:") || c.starts_with(b"LAYER_CHANGE") {
                    layer_comments += 1;
                    // The first layer takes everything up to the first comment after its first
                    // extrusion; every later comment starts a layer.
                    if !first_open || may_extrude {
                        e.largest_layer = e.largest_layer.max(chunk);
                        chunk = 0;
                        first_open = false;
                    }
                }
            }
        }
        e.largest_layer = e.largest_layer.max(chunk);
        if comment_mode {
            e.layers = 1 + layer_comments.min(e.moves);
        } else {
            // Each layer after the first starts at a Z change.
            e.layers = 1 + z_lines.min(e.moves);
            e.largest_layer = e.moves;
        }
        e.largest_layer = e.largest_layer.min(MAX_LAYER_SEGMENTS);
    }
    e.peak_bytes = peak_bytes(e.moves, e.layers, e.largest_layer, options.collect_preview);
    e
}

/// Where a line's comment starts (its `;` outside parentheses), or its length.
fn comment_start(s: &[u8]) -> usize {
    let mut i = 0;
    while i < s.len() {
        match s[i] {
            b';' => return i,
            b'(' => i = s[i..].iter().position(|&b| b == b')').map_or(s.len(), |p| i + p + 1),
            _ => i += 1,
        }
    }
    s.len()
}

/// The first command of a line, as far as the estimate cares.
enum First {
    /// `G0`–`G3` (true for arcs).
    Motion(bool),
    /// Parameters without a command: repeats the last motion command.
    Modal,
    /// `G28` (homing may change Z).
    Home,
    /// Anything else.
    Other,
}

/// Reads the command word of a line's code part the way [`crate::motion::lex::lex_line`] does.
fn first_command(s: &[u8]) -> First {
    let mut i = 0;
    while i < s.len() {
        match s[i] {
            b' ' | b'\t' | b'\r' | 0x0b | 0x0c | b'%' => i += 1,
            b'(' => i = s[i..].iter().position(|&b| b == b')').map_or(s.len(), |p| i + p + 1),
            b'*' => {
                i += 1;
                while i < s.len() && s[i].is_ascii_digit() {
                    i += 1;
                }
            }
            b'N' | b'n' => {
                i += 1 + parse_number(&s[i + 1..]).map_or(0, |(_, n)| n);
            }
            b'G' | b'g' => {
                let Some((code, _)) = parse_number(&s[i + 1..]) else { return First::Other };
                if !(0.0..=1.0e6).contains(&code) {
                    return First::Other;
                }
                let whole = code as u32;
                let sub = ((code - whole as f64) * 10.0 + 0.5) as u32;
                return match (whole, sub) {
                    (0..=3, 0) => First::Motion(whole >= 2),
                    (28, 0) => First::Home,
                    _ => First::Other,
                };
            }
            b if b.is_ascii_alphabetic() && !matches!(b, b'M' | b'm' | b'T' | b't') => return First::Modal,
            _ => return First::Other,
        }
    }
    First::Other
}

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
    /// Whether the file has layer-change comments (`;LAYER:`, `;LAYER_CHANGE`): layers are
    /// then read from them, else from Z. Found once here, for the analyzer too (a file
    /// without them is read to its end to know).
    pub layer_comments: bool,
}

/// Preview bytes per segment: the largest kind (an extrusion segment with a tool axis: 6
/// positions, feature, path, flow, ΔE per mm, speed, width, move index, 3 axis floats), twice
/// over because the buffers grow by doubling.
const PREVIEW_SEGMENT_BYTES: usize = 2 * (6 * 4 + 1 + 4 + 4 + 4 + 4 + 4 + 4 + 3 * 4);
/// Bytes per layer: its record while reading (about 56 bytes, doubled) and its report, plus the
/// preview's three per-layer entries (doubled).
const LAYER_BYTES: usize = 2 * 56 + size_of::<LayerReport>() + 2 * 12;
/// Peak bytes of an analysis of `text_bytes` bytes of G-code making `segments` segments
/// (extrusion and travel, arcs by their chords) in `layers` layers, the largest holding
/// `largest_layer` extrusion segments. Builds with threads (native, the browser's threaded
/// module) count what the pool holds in flight too (lexed blocks, layers being measured: a
/// bound that does not depend on the thread count, see [`super::pooled`]).
pub fn peak_bytes(text_bytes: usize, segments: usize, layers: usize, largest_layer: usize, preview: bool) -> usize {
    let preview_bytes = if preview { segments.saturating_mul(PREVIEW_SEGMENT_BYTES) } else { 0 };
    #[cfg(any(not(target_arch = "wasm32"), feature = "wasm-threads"))]
    let parallel = super::pooled::in_flight_bytes(text_bytes, segments);
    #[cfg(all(target_arch = "wasm32", not(feature = "wasm-threads")))]
    let _ = text_bytes;
    #[cfg(all(target_arch = "wasm32", not(feature = "wasm-threads")))]
    let parallel = 0;
    preview_bytes.saturating_add(layers.saturating_mul(LAYER_BYTES)).saturating_add(overlap::layer_bytes(largest_layer)).saturating_add(parallel)
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
        lines_of(bytes, &mut e, SCAN_BLOCK_BYTES);
    }
    e.peak_bytes = peak_bytes(e.bytes, e.moves, e.layers, e.largest_layer, options.collect_preview);
    e
}

/// Text per block of the scan, bytes: the blocks are counted side by side ([`crate::par`]).
const SCAN_BLOCK_BYTES: usize = 1 << 20;

/// What the scan counts over a run of whole lines, told apart so that runs counted side by
/// side add up to the count of the whole (see [`lines_of`]).
#[derive(Clone, Copy, Debug, Default)]
struct Tally {
    lines: usize,
    moves: usize,
    /// Arcs: motion lines that are arcs, and parameter lines after a motion line of the run
    /// that left arc mode on.
    arcs: usize,
    /// Parameter lines before the run's first motion line: arcs if the mode carried in is.
    lead_modal: usize,
    /// The motion mode the run leaves (`None`: it has no motion line).
    last_arc: Option<bool>,
    /// Lines that may change Z (homing; any Z word when the file has no layer comments).
    z_lines: usize,
    /// Layer comments.
    comments: usize,
    /// Moves before the first layer comment, the most between two of them, after the last.
    prefix: usize,
    interior: usize,
    suffix: usize,
}

impl Tally {
    /// Counts one line; returns whether it is a move, whether it has a layer comment, and its
    /// code (the part before the comment).
    fn line<'a>(&mut self, line: &'a [u8], comment_mode: bool) -> (bool, bool, &'a [u8]) {
        self.lines += 1;
        let code_end = comment_start(line);
        let code = &line[..code_end];
        let is_move = match first_command(code) {
            First::Motion(arc) => {
                self.last_arc = Some(arc);
                self.arcs += usize::from(arc);
                true
            }
            First::Modal => {
                match self.last_arc {
                    Some(arc) => self.arcs += usize::from(arc),
                    None => self.lead_modal += 1,
                }
                true
            }
            First::Home => {
                self.z_lines += 1;
                false
            }
            First::Other => false,
        };
        self.moves += usize::from(is_move);
        if !comment_mode && code.iter().any(|&b| b == b'Z' || b == b'z') {
            self.z_lines += 1;
        }
        let layer_comment = code_end < line.len() && {
            let c = crate::motion::lex::trim_start(&line[code_end + 1..]);
            c.starts_with(b"LAYER:") || c.starts_with(b"LAYER_CHANGE")
        };
        (is_move, layer_comment, code)
    }
}

/// Calls `f` on each line of `text` (without its newline) until it returns false; returns
/// the offset after the last line it was called on.
fn each_line(text: &[u8], mut f: impl FnMut(&[u8]) -> bool) -> usize {
    let mut start = 0;
    while start < text.len() {
        let end = super::machine::find_newline(&text[start..]).map_or(text.len(), |p| start + p);
        let go_on = f(&text[start..end]);
        start = (end + 1).min(text.len());
        if !go_on {
            break;
        }
    }
    start
}

/// A block of whole lines, counted as if the first layer were closed before it.
fn tally_block(text: &[u8], comment_mode: bool) -> Tally {
    let mut t = Tally::default();
    let mut chunk = 0;
    each_line(text, |line| {
        let (is_move, layer_comment, _) = t.line(line, comment_mode);
        chunk += usize::from(is_move);
        if layer_comment {
            if t.comments == 0 {
                t.prefix = chunk;
            } else {
                t.interior = t.interior.max(chunk);
            }
            t.comments += 1;
            chunk = 0;
        }
        true
    });
    if t.comments == 0 {
        t.prefix = chunk;
    } else {
        t.suffix = chunk;
    }
    t
}

/// Counts the lines, moves, arcs and layers of G-code `bytes` into `e`. The first layer is
/// read line by line: it takes everything up to the first layer comment after its first
/// extrusion, a rule that needs the lines in order. From there each later comment starts a
/// layer, so the rest is counted in blocks of `block_bytes` side by side, whose tallies add up.
fn lines_of(bytes: &[u8], e: &mut Estimate, block_bytes: usize) {
    let comment_mode = crate::motion::lex::has_layer_comments(bytes);
    e.layer_comments = comment_mode;
    let mut head = Tally::default();
    let (mut layer_comments, mut chunk, mut largest) = (0usize, 0usize, 0usize);
    // Whether a move that may extrude has come after the first layer comment.
    let mut may_extrude = false;
    let mut first_open = comment_mode;
    let head_end = if first_open {
        each_line(bytes, |line| {
            let (is_move, layer_comment, code) = head.line(line, comment_mode);
            if is_move {
                chunk += 1;
                if layer_comments > 0 && !may_extrude {
                    may_extrude = code.iter().any(|&b| b == b'E' || b == b'e');
                }
            }
            if layer_comment {
                layer_comments += 1;
                if may_extrude {
                    largest = largest.max(chunk);
                    chunk = 0;
                    first_open = false;
                }
            }
            first_open
        })
    } else {
        0
    };
    let rest = &bytes[head_end..];
    let cuts = super::machine::cut_lines(rest, block_bytes);
    let blocks = crate::par::map(cuts.len(), &mut |_| {}, |k| tally_block(&rest[cuts[k].clone()], comment_mode));
    let (mut lines, mut moves, mut arcs, mut z_lines) = (head.lines, head.moves, head.arcs, head.z_lines);
    let mut arc_mode = head.last_arc.unwrap_or(false);
    for b in &blocks {
        lines += b.lines;
        moves += b.moves;
        arcs += b.arcs + if arc_mode { b.lead_modal } else { 0 };
        arc_mode = b.last_arc.unwrap_or(arc_mode);
        z_lines += b.z_lines;
        layer_comments += b.comments;
        if b.comments == 0 {
            chunk += b.prefix;
        } else {
            largest = largest.max(chunk + b.prefix).max(b.interior);
            chunk = b.suffix;
        }
    }
    largest = largest.max(chunk);
    e.lines = lines;
    e.moves = moves;
    e.arcs = arcs;
    if comment_mode {
        e.layers = 1 + layer_comments.min(moves);
        e.largest_layer = largest;
    } else {
        // Each layer after the first starts at a Z change.
        e.layers = 1 + z_lines.min(moves);
        e.largest_layer = moves;
    }
    e.largest_layer = e.largest_layer.min(MAX_LAYER_SEGMENTS);
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The scan as one sequential pass (the definition the blocks must add up to).
    fn reference(bytes: &[u8]) -> (usize, usize, usize, usize, usize) {
        let comment_mode = crate::motion::lex::has_layer_comments(bytes);
        let (mut lines, mut moves, mut arcs, mut largest) = (0, 0, 0, 0);
        let mut arc_mode = false;
        let (mut layer_comments, mut z_lines) = (0usize, 0usize);
        let (mut chunk, mut first_open, mut may_extrude) = (0usize, true, false);
        let mut all: Vec<&[u8]> = bytes.split(|&b| b == b'\n').collect();
        if bytes.is_empty() || bytes.last() == Some(&b'\n') {
            all.pop();
        }
        for line in all {
            lines += 1;
            let code_end = comment_start(line);
            let code = &line[..code_end];
            let is_move = match first_command(code) {
                First::Motion(arc) => {
                    arc_mode = arc;
                    arcs += usize::from(arc);
                    true
                }
                First::Modal => {
                    arcs += usize::from(arc_mode);
                    true
                }
                First::Home => {
                    z_lines += 1;
                    false
                }
                First::Other => false,
            };
            if is_move {
                moves += 1;
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
                    if !first_open || may_extrude {
                        largest = largest.max(chunk);
                        chunk = 0;
                        first_open = false;
                    }
                }
            }
        }
        largest = largest.max(chunk);
        let layers = if comment_mode { 1 + layer_comments.min(moves) } else { 1 + z_lines.min(moves) };
        if !comment_mode {
            largest = moves;
        }
        (lines, moves, arcs, layers, largest.min(MAX_LAYER_SEGMENTS))
    }

    #[test]
    fn blocks_counted_side_by_side_add_up_to_one_pass() {
        let mut cases: Vec<Vec<u8>> = vec![
            b"".to_vec(),
            b"G1 X1\n".to_vec(),
            b"G1 X1".to_vec(),
            // Comments before the first extrusion do not start a layer; arcs go on modally
            // across blocks; CRLF; a move and a layer comment on one line.
            b";LAYER:0\nG0 X1 Z0.2\n;LAYER:1\nG1 X2 E1\nG2 X3 I1 J0 E2\nX4 E3\r\nY5 E4 ;LAYER:2\nX6\nG1 X7 E5\n; LAYER_CHANGE\nX8 E6\nG28\n".to_vec(),
            // No layer comments: Z changes and homing count.
            b"G28\nG1 Z0.2\nG1 X1 E1\nG1 X2 Z0.4 E2\nG3 X1 Y1 R1 E3\nX2\nG1 X3\n".to_vec(),
            // Layer comments that never meet an extrusion.
            b";LAYER:0\nG0 X1\n;LAYER:1\nG0 X2\n;LAYER:2\n".to_vec(),
        ];
        let mut big = Vec::new();
        for layer in 0..300 {
            big.extend_from_slice(format!(";LAYER:{layer}\nG0 X0 Y0 Z{}\n", layer as f64 * 0.2).as_bytes());
            for k in 0..(layer % 17) * 3 {
                let cmd = if k % 5 == 0 {
                    "G2"
                } else if k % 3 == 0 {
                    ""
                } else {
                    "G1"
                };
                big.extend_from_slice(format!("{cmd} X{k} Y{layer} I1 J1 E{k}.5 ; k\n").as_bytes());
            }
        }
        cases.push(big);
        for (i, text) in cases.iter().enumerate() {
            let want = reference(text);
            for block in [1, 2, 7, 64, 4096, 1 << 20] {
                let mut e = Estimate::default();
                lines_of(text, &mut e, block);
                assert_eq!((e.lines, e.moves, e.arcs, e.layers, e.largest_layer), want, "case {i}, blocks of {block} bytes");
            }
        }
    }
}

//! The analyzer on every thread (builds with threads): the interpreter reads the file in order
//! on one of the pool's threads, the pool lexes the blocks ahead of it and measures the
//! overlap of the layers behind it.
//!
//! Why this shape: each move of a G-code file depends on the state every earlier line left
//! (positions, modes, the time model's planner), so the interpreter ([`Machine`]) is
//! sequential. Its two costly neighbours are per item: a line's words depend on that line
//! alone, and a layer's overlap on that layer alone. On the 1M-triangle sphere's G-code (one
//! thread) the overlap is about half of the time, lexing a fifth, the interpreter a quarter.
//! The previous shape (overlap on one side thread) could not pass two threads.
//!
//! Same report at any thread count: blocks are interpreted in file order, a line's lexing is
//! the same wherever it runs, and each layer's overlap comes back by its index. Errors too:
//! a block's lexing stops at its first bad line, and the interpreter meets it in order, after
//! every earlier line (a refusal of an earlier line wins, as it does on one thread).
//!
//! Memory in flight (counted by [`super::peak_bytes`] through [`in_flight_bytes`]): at most
//! [`AHEAD_BLOCKS`] lexed blocks ahead of the one being read, and layers of at most
//! [`IN_FLIGHT_SEGMENTS`] segments with their working sets; the caller waits for results
//! beyond that.

use super::machine::{cut_lines, find_newline, Machine};
use super::overlap::{Overlap, Seg};
use super::{Analysis, Error};
use crate::motion::lex::{lex_line, Command, Line, Words};
use crate::par::Reply;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::channel;

/// Files of at least this many bytes are analysed on the pool; smaller ones on the calling
/// thread alone (a few milliseconds, less than handing blocks over would save).
pub(super) const MIN_BYTES: usize = 1 << 20;
/// Text per lexed block, bytes (cut after a newline): about 4000 lines of a slicer's G-code,
/// 0.1–0.2 ms of lexing, long beside the microseconds a spawn costs.
pub(super) const BLOCK_BYTES: usize = 1 << 17;
/// Blocks lexed ahead of the one being interpreted, at most: enough to keep 8 threads busy.
pub(super) const AHEAD_BLOCKS: usize = 8;
/// A lexed line takes at most this many bytes per byte of its text: a 40-byte record for a
/// line of two bytes (`X\n`, `;\n`); the values (8 bytes) need at least 2 bytes each (`X1`).
pub(super) const LEXED_BYTES_PER_BYTE: usize = 20;
/// Layers go to the pool in batches of at least this many segments (the last may be smaller):
/// a task's set-up (its buffers) is then small beside its work.
pub(super) const BATCH_SEGMENTS: usize = 1 << 13;
/// Segments of the layers handed to the pool and not yet measured, at most (a batch being
/// filled and the one layer that tops it off come on top).
pub(super) const IN_FLIGHT_SEGMENTS: usize = 1 << 17;

/// Bytes in flight for a file of `text_bytes` bytes and `segments` segments: lexed blocks and
/// the layers handed over with their working sets (see the module's notes). 0 for files the
/// calling thread analyses alone.
pub(super) fn in_flight_bytes(text_bytes: usize, segments: usize) -> usize {
    if text_bytes < MIN_BYTES {
        return 0;
    }
    let lexed = text_bytes.min((AHEAD_BLOCKS + 1) * (BLOCK_BYTES + 1)).saturating_mul(LEXED_BYTES_PER_BYTE);
    let layers = segments.min(IN_FLIGHT_SEGMENTS + BATCH_SEGMENTS + super::machine::PARALLEL_LAYER_SEGMENTS);
    lexed.saturating_add(super::overlap::layer_bytes(layers))
}

/// One line worth interpreting (blank and comment-free ignored commands are left out).
struct Rec<'a> {
    /// 0-based line in its block.
    line: u32,
    cmd: Command,
    mask: u32,
    flags: u32,
    comment: Option<&'a [u8]>,
    args: Option<&'a [u8]>,
}

/// A block's lines, lexed.
#[derive(Default)]
struct Lexed<'a> {
    recs: Vec<Rec<'a>>,
    /// The words' values, line by line in letter order (as many as a line's mask has bits).
    vals: Vec<f64>,
    /// Lines in the block (up to and with the bad one, when there is one).
    lines: usize,
    /// The first line that does not lex (0-based in the block) and what is wrong with it.
    error: Option<(usize, String)>,
}

/// Lexes `text` (whole lines), stopping at the first bad one.
fn lex_block(text: &[u8]) -> Lexed<'_> {
    // A slicer's line is about 30 bytes with 3 values: room for that, grown if need be.
    let mut out = Lexed { recs: Vec::with_capacity(text.len() / 24), vals: Vec::with_capacity(text.len() / 8), ..Default::default() };
    let mut start = 0;
    while start < text.len() {
        let end = find_newline(&text[start..]).map_or(text.len(), |p| start + p);
        let mut line = &text[start..end];
        if let Some((&b'\r', rest)) = line.split_last() {
            line = rest;
        }
        let n = out.lines;
        out.lines += 1;
        match lex_line(line) {
            // The interpreter does nothing with these (no words read, no comment).
            Ok(l) if matches!(l.cmd, Command::None | Command::Other) && l.comment.is_none() && l.args.is_none() => {}
            Ok(l) => {
                let mut mask = l.words.mask;
                while mask != 0 {
                    out.vals.push(l.words.vals[mask.trailing_zeros() as usize]);
                    mask &= mask - 1;
                }
                out.recs.push(Rec { line: n as u32, cmd: l.cmd, mask: l.words.mask, flags: l.words.flags, comment: l.comment, args: l.args });
            }
            Err(problem) => {
                out.error = Some((n, problem));
                return out;
            }
        }
        start = end + 1;
    }
    out
}

/// A batch's overlaps: (layer index, overlap) for each of its layers, and its segments.
type Measured = (Vec<(usize, f64)>, usize);

/// Gives a batch's overlaps to `m` and takes its segments off `in_flight`; false when the
/// batch has no result (see [`crate::par::Reply`]).
fn settle(reply: Option<(usize, Option<Measured>)>, m: &mut Machine<'_>, in_flight: &mut usize) -> bool {
    let Some((_, Some((done, segments)))) = reply else { return false };
    *in_flight -= segments;
    done.into_iter().for_each(|(i, v)| m.set_overlap(i, v));
    true
}

/// Analyses `bytes` with `m` (see the module's notes); `width` is the options' default line
/// width. Called on one of the pool's threads ([`crate::par::on_pool`]).
pub(super) fn run(file: &str, bytes: &[u8], m: Machine<'_>, width: f64) -> Result<Analysis, Error> {
    let mut m = m;
    let bounds = cut_lines(bytes, BLOCK_BYTES);
    m.handed = Some(Vec::new());
    let stop = AtomicBool::new(false);
    let stop = &stop;
    let (lex_tx, lex_rx) = channel::<(usize, Option<Lexed<'_>>)>();
    let (ov_tx, ov_rx) = channel::<(usize, Option<Measured>)>();
    let skip = move || stop.load(Ordering::Relaxed) || crate::par::cancelled();
    let result = rayon::in_place_scope(|s| -> Result<(), Error> {
        let spawn_lex = |k: usize| {
            let reply = Reply::new(&lex_tx, k);
            let text = &bytes[bounds[k].clone()];
            s.spawn(move |_| {
                if !skip() {
                    reply.send(lex_block(text));
                }
            });
        };
        let mut batches = 0usize;
        let spawn_batch = |batch: Vec<(usize, Vec<Seg>)>, batches: &mut usize| {
            let reply = Reply::new(&ov_tx, *batches);
            *batches += 1;
            s.spawn(move |_| {
                if !skip() {
                    let mut overlap = Overlap::default();
                    let n = batch.iter().map(|(_, segs)| segs.len()).sum();
                    reply.send((batch.iter().map(|(i, segs)| (*i, overlap.layer(segs, width))).collect(), n));
                }
            });
        };
        // A missing result: the page cancelled (sleep until it ends this worker, as par::map
        // does), or a task panicked (return; the scope raises the panic again).
        let missing = || -> Result<(), Error> {
            stop.store(true, Ordering::Relaxed);
            while crate::par::cancelled() {
                std::thread::park();
            }
            Ok(())
        };
        let mut lexed: Vec<Option<Lexed<'_>>> = (0..bounds.len()).map(|_| None).collect();
        let mut spawned = 0;
        let (mut batch, mut batch_segs, mut in_flight) = (Vec::new(), 0usize, 0usize);
        let mut line_base = 0usize;
        let mut line = Line { cmd: Command::None, words: Words::default(), comment: None, args: None };
        for k in 0..bounds.len() {
            while spawned < bounds.len() && spawned <= k + AHEAD_BLOCKS {
                spawn_lex(spawned);
                spawned += 1;
            }
            while lexed[k].is_none() {
                match crate::par::recv(&lex_rx) {
                    Some((j, Some(block))) => lexed[j] = Some(block),
                    _ => return missing(),
                }
            }
            let block = lexed[k].take().unwrap_or_default();
            let mut vals = block.vals.iter();
            for r in &block.recs {
                // Only the letters in the mask are read, so the others' old values may stay.
                line.cmd = r.cmd;
                line.comment = r.comment;
                line.args = r.args;
                line.words.mask = r.mask;
                line.words.flags = r.flags;
                let mut mask = r.mask;
                while mask != 0 {
                    line.words.vals[mask.trailing_zeros() as usize] = vals.next().copied().unwrap_or(0.0);
                    mask &= mask - 1;
                }
                if let Err(problem) = m.line(&line) {
                    stop.store(true, Ordering::Relaxed);
                    return Err(Error::TooLarge { file: file.to_string(), line: line_base + r.line as usize + 1, problem });
                }
            }
            if let Some((n, problem)) = block.error {
                stop.store(true, Ordering::Relaxed);
                return Err(Error::Malformed { file: file.to_string(), line: line_base + n + 1, problem });
            }
            line_base += block.lines;
            if k + 1 == bounds.len() {
                m.close();
            }
            // Hand the finished layers over in batches, within the bound on layers in flight
            // (the last batch when the file ends, `None`).
            let handed = m.handed.as_mut().map(std::mem::take).unwrap_or_default();
            for layer in handed.into_iter().map(Some).chain((k + 1 == bounds.len()).then_some(None)) {
                let end = layer.is_none();
                if let Some((index, segs)) = layer {
                    batch_segs += segs.len();
                    batch.push((index, segs));
                }
                if batch_segs >= BATCH_SEGMENTS || (end && !batch.is_empty()) {
                    while in_flight > 0 && in_flight + batch_segs > IN_FLIGHT_SEGMENTS {
                        if !settle(crate::par::recv(&ov_rx), &mut m, &mut in_flight) {
                            return missing();
                        }
                    }
                    in_flight += batch_segs;
                    spawn_batch(std::mem::take(&mut batch), &mut batches);
                    batch_segs = 0;
                }
            }
            while let Ok(r) = ov_rx.try_recv() {
                if !settle(Some(r), &mut m, &mut in_flight) {
                    return missing();
                }
            }
        }
        // The batches still measuring.
        while in_flight > 0 {
            if !settle(crate::par::recv(&ov_rx), &mut m, &mut in_flight) {
                return missing();
            }
        }
        Ok(())
    });
    result?;
    Ok(m.finish())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn blocks(text: &[u8]) -> Vec<std::ops::Range<usize>> {
        cut_lines(text, BLOCK_BYTES)
    }

    #[test]
    fn blocks_end_after_newlines_and_cover_the_text() {
        let mut text = Vec::new();
        for i in 0..100_000 {
            text.extend_from_slice(format!("G1 X{i} Y1 E0.1 ; move {i}\n").as_bytes());
        }
        text.extend_from_slice(b"G1 X1"); // no newline at the end
        let b = blocks(&text);
        assert!(b.len() > 10, "{} blocks", b.len());
        assert_eq!(b[0].start, 0);
        assert_eq!(b.last().unwrap().end, text.len());
        for w in b.windows(2) {
            assert_eq!(w[0].end, w[1].start);
            assert_eq!(text[w[0].end - 1], b'\n');
        }
        assert!(blocks(b"").is_empty());
        assert_eq!(blocks(&vec![b'G'; 3 * BLOCK_BYTES]), vec![0..3 * BLOCK_BYTES], "one line, one block");
    }

    #[test]
    fn a_block_keeps_every_line_the_interpreter_reads_and_stops_at_a_bad_one() {
        let l = lex_block(b"\n; LAYER:1\nG1 X1 Y2 E3\r\nM104 S200\nT0\nX4\nG1 X1e5\nG1 X2\n");
        // Blank line and T0 are left out; the bad line ends the block.
        assert_eq!(l.recs.iter().map(|r| r.line).collect::<Vec<_>>(), vec![1, 2, 3, 5]);
        assert_eq!(l.vals, vec![3.0, 1.0, 2.0, 4.0], "values in letter order, line by line (M104's are not read)");
        assert_eq!(l.lines, 7);
        assert_eq!(l.error.as_ref().map(|e| e.0), Some(6));
    }
}

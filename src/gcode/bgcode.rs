//! Prusa binary G-code (`.bgcode`, "binary G-code" of PrusaSlicer 2.7+ and the Prusa MK4/XL/MINI firmware).
//!
//! Entry: [`encode`]. The output follows the format of libbgcode (version 1) and the configuration
//! PrusaSlicer writes by default, which is also what the printer firmware reads:
//!
//! * file header `GCDE`, version 1, CRC32 checksums;
//! * blocks in the order file metadata (only when given), printer metadata, thumbnails (PNG), print
//!   metadata, slicer metadata, G-code; each block is a header (type, compression, uncompressed size, and
//!   the compressed size when compressed), its parameters, its data and the CRC32 of all three;
//! * metadata as INI text (`key=value\n`); file, printer and print metadata uncompressed (the firmware
//!   refuses compressed printer metadata), slicer metadata Deflate (zlib-wrapped);
//! * thumbnails uncompressed;
//! * G-code cut at line ends into blocks of at most 65536 bytes of text, each block MeatPack-encoded
//!   ("MeatPack with comments") and then Heatshrink-compressed (window 2^12, lookahead 2^4). Every block
//!   starts a fresh MeatPack and Heatshrink state, so a reader can start at any block.
//!
//! MeatPack is not byte-exact for all text; after a round trip through libbgcode's reader (or the
//! firmware) the G-code reads the same to a printer, but:
//!
//! * whole-line comments (first character `;`) are kept byte for byte;
//! * comments after a command (`G28 ; home`) are dropped, as are empty and blank lines;
//! * command lines lose leading and trailing spaces and tabs;
//! * in G lines (`G` followed by a digit) spaces and tabs are dropped and `e`, `x`, `g` upper-cased; the
//!   reader puts one space back before each parameter letter, so `G1 X10.5 Y-3 E.1234` comes back as is;
//! * other lines (`M104 S200`, lower-case `g1 x1`, `T0`) keep their inner spaces.
//!
//! Differences from libbgcode's encoder, all on text PrusaSlicer never writes: a G line is one whose first
//! character is `G` (libbgcode looks at the first `G` anywhere, so it would mangle `M117 G1 done`); tabs in G
//! lines go like spaces; trailing blanks of other lines go even without a comment; a `*` checksum is kept as
//! written (libbgcode deletes each `*`, gluing the old checksum onto the last number, and appends a new one);
//! NUL is sent as a full byte (libbgcode packs it as the "full byte follows" code, corrupting the stream); a
//! line longer than 65536 bytes gets a block of its own and a last line without `\n` is encoded as if it had
//! one (libbgcode refuses both files).
//!
//! The output is a pure function of the input: no clock, no randomness, no hash-map order. Encoding never
//! panics; keys with `=` or line breaks and values with line breaks are repaired (see [`Input`]).

/// The image format of a thumbnail block (libbgcode's numbers).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ThumbnailFormat {
    /// PNG (hosts and web pages show it).
    Png = 0,
    /// QOI (what Prusa's xBuddy screens read since firmware 5.1).
    Qoi = 2,
}

/// One preview image, stored as a thumbnail block.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Thumbnail {
    /// Image width in pixels (as the image says); a thumbnail with width 0 is skipped.
    pub width: u16,
    /// Image height in pixels; a thumbnail with height 0 is skipped.
    pub height: u16,
    /// The image's format.
    pub format: ThumbnailFormat,
    /// The image file's bytes, stored as they are; an empty image is skipped.
    pub image: Vec<u8>,
}

/// Everything that goes into one `.bgcode` file.
///
/// Metadata are `(key, value)` pairs written in the given order. A key may not hold `=`, CR or LF and a
/// value may not hold CR or LF (libbgcode's reader loops forever on a metadata line without `=`), so each
/// such character is written as `_` in a key and as a space in a value.
#[derive(Clone, Copy, Debug)]
pub struct Input<'a> {
    /// File metadata, e.g. `("Producer", "weft 0.1.0")`; the block is left out when empty.
    pub file_metadata: &'a [(String, String)],
    /// Metadata the printer reads before printing: `printer_model`, `filament_type`, `nozzle_diameter`,
    /// `bed_temperature`, `temperature`, `brim_width`, `fill_density`, `layer_height`, `ironing`,
    /// `support_material`, `max_layer_z`, `extruder_colour`, `filament used [mm]`, `filament used [g]`,
    /// `estimated printing time (normal mode)`, ...
    pub printer_metadata: &'a [(String, String)],
    /// Preview images, written in this order.
    pub thumbnails: &'a [Thumbnail],
    /// Print metadata (PrusaSlicer repeats the filament and time estimates here).
    pub print_metadata: &'a [(String, String)],
    /// Slicer metadata (PrusaSlicer writes its whole configuration here).
    pub slicer_metadata: &'a [(String, String)],
    /// The G-code text.
    pub gcode: &'a str,
    /// More G-code text after `gcode`, cut into blocks on its own (so the caller need not join
    /// the two: a header rewritten in a copy, the body borrowed). `gcode` should end at a line
    /// end.
    pub gcode_more: &'a str,
}

/// Encodes `input` as a binary G-code file (the bytes of a `.bgcode` file).
#[must_use]
pub fn encode(input: &Input) -> Vec<u8> {
    let thumbs: usize = input.thumbnails.iter().map(|t| t.image.len() + 24).sum();
    let mut out = Vec::with_capacity(input.gcode.len() / 3 + thumbs + 4096);
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&VERSION.to_le_bytes());
    out.extend_from_slice(&CHECKSUM_CRC32.to_le_bytes());

    if !input.file_metadata.is_empty() {
        write_metadata(&mut out, BLOCK_FILE_METADATA, input.file_metadata, false);
    }
    write_metadata(&mut out, BLOCK_PRINTER_METADATA, input.printer_metadata, false);
    for t in input.thumbnails {
        if t.width == 0 || t.height == 0 || t.image.is_empty() {
            continue;
        }
        let mut params = [0u8; 6];
        params[0..2].copy_from_slice(&(t.format as u16).to_le_bytes());
        params[2..4].copy_from_slice(&t.width.to_le_bytes());
        params[4..6].copy_from_slice(&t.height.to_le_bytes());
        write_block(&mut out, BLOCK_THUMBNAIL, COMPRESSION_NONE, t.image.len(), &params, &t.image);
    }
    write_metadata(&mut out, BLOCK_PRINT_METADATA, input.print_metadata, false);
    write_metadata(&mut out, BLOCK_SLICER_METADATA, input.slicer_metadata, true);

    // Readers (libbgcode's converter among them) expect at least one G-code block, so empty G-code still
    // gets one, holding only MeatPack's opening commands.
    let mut chunks = gcode_chunks(input.gcode.as_bytes());
    chunks.extend(gcode_chunks(input.gcode_more.as_bytes()));
    let empty: [&[u8]; 1] = [&[]];
    let chunks: &[&[u8]] = if chunks.is_empty() { &empty } else { &chunks };
    let params = GCODE_MEATPACK_COMMENTS.to_le_bytes();
    for chunk in chunks {
        let packed = meatpack(chunk);
        let compressed = heatshrink(&packed);
        // Every G-code block keeps the same compression: the firmware stops at a block whose compression
        // or encoding differs from the first one's.
        write_block(&mut out, BLOCK_GCODE, COMPRESSION_HEATSHRINK_12_4, packed.len(), &params, &compressed);
    }
    out
}

/// Most G-code text bytes in one block (libbgcode's default G-code cache, which PrusaSlicer keeps).
const GCODE_BLOCK_BYTES: usize = 65_536;

const MAGIC: &[u8; 4] = b"GCDE";
const VERSION: u32 = 1;
const CHECKSUM_CRC32: u16 = 1;

const BLOCK_FILE_METADATA: u16 = 0;
const BLOCK_GCODE: u16 = 1;
const BLOCK_SLICER_METADATA: u16 = 2;
const BLOCK_PRINTER_METADATA: u16 = 3;
const BLOCK_PRINT_METADATA: u16 = 4;
const BLOCK_THUMBNAIL: u16 = 5;

const COMPRESSION_NONE: u16 = 0;
const COMPRESSION_DEFLATE: u16 = 1;
const COMPRESSION_HEATSHRINK_12_4: u16 = 3;

const METADATA_INI: u16 = 0;
const GCODE_MEATPACK_COMMENTS: u16 = 2;

/// zlib level of the slicer metadata (zlib's default, as libbgcode uses).
const DEFLATE_LEVEL: u8 = 6;

/// Sizes in the file are u32; clamps what cannot happen in practice (over 4 GiB in one block).
fn size_u32(n: usize) -> u32 {
    u32::try_from(n).unwrap_or(u32::MAX)
}

/// Appends one block: header, parameters, data and the CRC32 of the three.
fn write_block(out: &mut Vec<u8>, block_type: u16, compression: u16, uncompressed: usize, params: &[u8], data: &[u8]) {
    let start = out.len();
    out.extend_from_slice(&block_type.to_le_bytes());
    out.extend_from_slice(&compression.to_le_bytes());
    out.extend_from_slice(&size_u32(uncompressed).to_le_bytes());
    if compression != COMPRESSION_NONE {
        out.extend_from_slice(&size_u32(data.len()).to_le_bytes());
    }
    out.extend_from_slice(params);
    out.extend_from_slice(data);
    let crc = crc32fast::hash(&out[start..]);
    out.extend_from_slice(&crc.to_le_bytes());
}

/// Appends a metadata block (INI encoding). `deflate` compresses it unless it is empty: libbgcode's
/// reader cannot inflate an empty Deflate payload.
fn write_metadata(out: &mut Vec<u8>, block_type: u16, pairs: &[(String, String)], deflate: bool) {
    let mut ini = Vec::new();
    for (key, value) in pairs {
        ini.extend(key.bytes().map(|b| if matches!(b, b'=' | b'\n' | b'\r') { b'_' } else { b }));
        ini.push(b'=');
        ini.extend(value.bytes().map(|b| if matches!(b, b'\n' | b'\r') { b' ' } else { b }));
        ini.push(b'\n');
    }
    let params = METADATA_INI.to_le_bytes();
    if deflate && !ini.is_empty() {
        let compressed = miniz_oxide::deflate::compress_to_vec_zlib(&ini, DEFLATE_LEVEL);
        write_block(out, block_type, COMPRESSION_DEFLATE, ini.len(), &params, &compressed);
    } else {
        write_block(out, block_type, COMPRESSION_NONE, ini.len(), &params, &ini);
    }
}

/// Cuts G-code at line ends into chunks of at most [`GCODE_BLOCK_BYTES`]; a longer line is a chunk alone.
fn gcode_chunks(text: &[u8]) -> Vec<&[u8]> {
    let mut chunks = Vec::new();
    let (mut start, mut end) = (0, 0);
    while end < text.len() {
        let line_end = text[end..].iter().position(|&b| b == b'\n').map_or(text.len(), |p| end + p + 1);
        if line_end - start > GCODE_BLOCK_BYTES && end > start {
            chunks.push(&text[start..end]);
            start = end;
        }
        end = line_end;
    }
    if end > start {
        chunks.push(&text[start..end]);
    }
    chunks
}

// ---------------------------------------------------------------------------------------------------
// MeatPack
//
// A packed byte holds two characters of the set 0-9 . E \n G X, first one in the low nibble; nibble 0xF
// says "this character follows as a full byte" (0xFF: both follow, in order). The pair ends a line that
// has an odd length with a padding '\n', which the reader drops. 0xFF 0xFF <command> switches modes; in
// "no spaces" mode nibble 0xB means 'E' instead of ' '. Comment lines go out with packing disabled,
// byte for byte.
// ---------------------------------------------------------------------------------------------------

const MP_SIGNAL: u8 = 0xFF;
const MP_ENABLE_PACKING: u8 = 251;
const MP_DISABLE_PACKING: u8 = 250;
const MP_ENABLE_NO_SPACES: u8 = 247;

/// The 4-bit code of a packable character (no-spaces mode).
fn mp_nibble(b: u8) -> Option<u8> {
    match b {
        b'0'..=b'9' => Some(b - b'0'),
        b'.' => Some(0xA),
        b'E' => Some(0xB),
        b'\n' => Some(0xC),
        b'G' => Some(0xD),
        b'X' => Some(0xE),
        _ => None,
    }
}

fn mp_command(out: &mut Vec<u8>, command: u8) {
    out.extend_from_slice(&[MP_SIGNAL, MP_SIGNAL, command]);
}

fn trim_blanks(mut s: &[u8]) -> &[u8] {
    while let [b' ' | b'\t', rest @ ..] = s {
        s = rest;
    }
    while let [rest @ .., b' ' | b'\t'] = s {
        s = rest;
    }
    s
}

/// MeatPack-encodes one chunk of G-code text ("MeatPack with comments", no-spaces mode).
fn meatpack(text: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(text.len() * 2 / 3 + 16);
    mp_command(&mut out, MP_ENABLE_PACKING);
    mp_command(&mut out, MP_ENABLE_NO_SPACES);
    let mut packing = true;
    let mut line = Vec::new();
    for raw in text.split(|&b| b == b'\n') {
        match raw.first() {
            None | Some(b'\r') => continue,
            Some(b';') => {
                if packing {
                    mp_command(&mut out, MP_DISABLE_PACKING);
                    packing = false;
                }
                out.extend_from_slice(raw);
                out.push(b'\n');
                continue;
            }
            Some(_) => {}
        }
        let code = raw.iter().position(|&b| b == b';').map_or(raw, |p| &raw[..p]);
        let code = trim_blanks(code);
        if code.is_empty() {
            continue;
        }
        line.clear();
        if code[0] == b'G' && code.get(1).is_some_and(u8::is_ascii_digit) {
            for &b in code {
                match b {
                    b' ' | b'\t' => {}
                    b'e' | b'x' | b'g' => line.push(b.to_ascii_uppercase()),
                    _ => line.push(b),
                }
            }
        } else {
            line.extend_from_slice(code);
        }
        line.push(b'\n');
        if !packing {
            mp_command(&mut out, MP_ENABLE_PACKING);
            packing = true;
        }
        for pair in line.chunks(2) {
            let first = pair[0];
            let second = pair.get(1).copied().unwrap_or(b'\n');
            match (mp_nibble(first), mp_nibble(second)) {
                (Some(lo), Some(hi)) => out.push(hi << 4 | lo),
                (Some(lo), None) => out.extend_from_slice(&[0xF0 | lo, second]),
                (None, Some(hi)) => out.extend_from_slice(&[hi << 4 | 0x0F, first]),
                (None, None) => out.extend_from_slice(&[0xFF, first, second]),
            }
        }
    }
    out
}

// ---------------------------------------------------------------------------------------------------
// Heatshrink (LZSS), window 2^12, lookahead 2^4, as libbgcode's "Heatshrink 12,4".
//
// Bits are written most significant first. A literal is a 1 bit and the byte; a back-reference is a 0
// bit, (distance - 1) in 12 bits and (length - 1) in 4 bits, for a copy of 3..=16 bytes from 1..=4096
// bytes back (the copy may overlap what it writes). The last byte is padded with 0 bits, which readers
// ignore since they never make a whole back-reference.
//
// Written here rather than taken from the `heatshrink` crate (0.2, no_std): its encoder compares every
// position with the whole 4 KiB window (about 40x slower than these hash chains on G-code, seconds per MB)
// and writes into a caller-sized buffer.
// ---------------------------------------------------------------------------------------------------

const HS_WINDOW_BITS: u32 = 12;
const HS_LOOKAHEAD_BITS: u32 = 4;
const HS_WINDOW: usize = 1 << HS_WINDOW_BITS;
const HS_MAX_MATCH: usize = 1 << HS_LOOKAHEAD_BITS;
/// Shorter copies cost more bits than literals (the reference encoder's break-even).
const HS_MIN_MATCH: usize = 3;
/// Hash-chain steps per position; bounds the time on adversarial input (same result for the same input).
const HS_MAX_CHAIN: usize = 4096;
const HS_HASH_BITS: u32 = 14;
const HS_NONE: u32 = u32::MAX;

/// Heatshrink-compresses `data`: longest match (nearest on ties) through hash chains, taken unless the
/// next position has a longer one (one step of lazy matching).
fn heatshrink(data: &[u8]) -> Vec<u8> {
    let n = data.len();
    let mut bits = BitWriter { out: Vec::with_capacity(n / 2 + 8), acc: 0, count: 0 };
    let mut chains = HsChains { head: vec![HS_NONE; 1 << HS_HASH_BITS], prev: vec![HS_NONE; HS_WINDOW], inserted: 0 };
    let mut i = 0;
    while i < n {
        let (len, dist) = chains.longest(data, i);
        if len >= HS_MIN_MATCH && (len == HS_MAX_MATCH || chains.longest(data, i + 1).0 <= len) {
            // 0 bit, distance - 1, length - 1: 17 bits.
            bits.put(((dist - 1) << HS_LOOKAHEAD_BITS | (len - 1)) as u32, 1 + HS_WINDOW_BITS + HS_LOOKAHEAD_BITS);
            i += len;
        } else {
            bits.put(0x100 | u32::from(data[i]), 9);
            i += 1;
        }
    }
    bits.finish()
}

/// Hash chains over the positions of the data: `head` holds the latest position with a given hash of its
/// next 3 bytes, `prev` the one before it with the same hash, for the last [`HS_WINDOW`] positions (older
/// ones are out of reach anyway).
struct HsChains {
    head: Vec<u32>,
    prev: Vec<u32>,
    /// Positions below this one are in the chains.
    inserted: usize,
}

impl HsChains {
    /// Longest match (length, distance) for position `i` within the window; length 0 if none.
    fn longest(&mut self, data: &[u8], i: usize) -> (usize, usize) {
        let max_len = HS_MAX_MATCH.min(data.len().saturating_sub(i));
        if max_len < HS_MIN_MATCH {
            return (0, 0);
        }
        while self.inserted < i {
            let k = self.inserted;
            let h = hs_hash(data, k);
            self.prev[k % HS_WINDOW] = self.head[h];
            self.head[h] = size_u32(k);
            self.inserted += 1;
        }
        let (mut best_len, mut best_dist) = (0, 0);
        let mut cand = self.head[hs_hash(data, i)];
        let mut steps = 0;
        while cand != HS_NONE && steps < HS_MAX_CHAIN {
            let j = cand as usize;
            if j >= i || i - j > HS_WINDOW {
                break;
            }
            let len = data[j..j + max_len].iter().zip(&data[i..i + max_len]).take_while(|(a, b)| a == b).count();
            if len > best_len {
                (best_len, best_dist) = (len, i - j);
                if len == max_len {
                    break;
                }
            }
            cand = self.prev[j % HS_WINDOW];
            steps += 1;
        }
        (best_len, best_dist)
    }
}

/// Hash of the 3 bytes at `i` (the caller checks that they exist).
fn hs_hash(data: &[u8], i: usize) -> usize {
    let v = u32::from(data[i]) << 16 | u32::from(data[i + 1]) << 8 | u32::from(data[i + 2]);
    (v.wrapping_mul(0x9E37_79B1) >> (32 - HS_HASH_BITS)) as usize
}

/// Most-significant-bit-first bit writer.
struct BitWriter {
    out: Vec<u8>,
    acc: u32,
    count: u32,
}

impl BitWriter {
    /// Appends the low `count` (at most 24) bits of `value`.
    fn put(&mut self, value: u32, count: u32) {
        self.acc = self.acc << count | value;
        self.count += count;
        while self.count >= 8 {
            self.count -= 8;
            self.out.push((self.acc >> self.count) as u8);
        }
        self.acc &= (1 << self.count) - 1;
    }

    fn finish(mut self) -> Vec<u8> {
        if self.count > 0 {
            self.out.push((self.acc << (8 - self.count)) as u8);
        }
        self.out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn kv(pairs: &[(&str, &str)]) -> Vec<(String, String)> {
        pairs.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect()
    }

    fn input<'a>(printer: &'a [(String, String)], gcode: &'a str) -> Input<'a> {
        Input { file_metadata: &[], printer_metadata: printer, thumbnails: &[], print_metadata: &[], slicer_metadata: &[], gcode, gcode_more: "" }
    }

    /// Bit-by-bit CRC-32 (reflected 0xEDB88320), independent of crc32fast.
    fn crc32_bitwise(data: &[u8]) -> u32 {
        let mut crc = !0u32;
        for &b in data {
            crc ^= u32::from(b);
            for _ in 0..8 {
                crc = if crc & 1 != 0 { crc >> 1 ^ 0xEDB8_8320 } else { crc >> 1 };
            }
        }
        !crc
    }

    /// One parsed block: type, compression, uncompressed size, parameters, payload.
    struct Block {
        kind: u16,
        compression: u16,
        uncompressed: usize,
        params: Vec<u8>,
        data: Vec<u8>,
    }

    fn u16_at(b: &[u8], at: usize) -> u16 {
        u16::from_le_bytes([b[at], b[at + 1]])
    }

    fn u32_at(b: &[u8], at: usize) -> usize {
        u32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]]) as usize
    }

    /// Reads a whole file, checking the header, every CRC and that the blocks end with the file.
    fn parse(file: &[u8]) -> Vec<Block> {
        assert_eq!(&file[..10], b"GCDE\x01\x00\x00\x00\x01\x00");
        let mut blocks = Vec::new();
        let mut pos = 10;
        while pos < file.len() {
            let (kind, compression, uncompressed) = (u16_at(file, pos), u16_at(file, pos + 2), u32_at(file, pos + 4));
            let (header, size) = if compression == 0 { (8, uncompressed) } else { (12, u32_at(file, pos + 8)) };
            let params = if kind == BLOCK_THUMBNAIL { 6 } else { 2 };
            let end = pos + header + params + size;
            assert_eq!(u32_at(file, end) as u32, crc32_bitwise(&file[pos..end]), "CRC of block at {pos}");
            let p = pos + header;
            blocks.push(Block { kind, compression, uncompressed, params: file[p..p + params].to_vec(), data: file[p + params..end].to_vec() });
            pos = end + 4;
        }
        assert_eq!(pos, file.len());
        blocks
    }

    fn heatshrink_decode(data: &[u8], size: usize) -> Vec<u8> {
        let cfg = ::heatshrink::Config::new(12, 4).unwrap();
        // The crate's decoder wants a spare byte of room even when the data fill `size` exactly.
        let mut out = vec![0u8; size + 1];
        let got = ::heatshrink::decode(data, &mut out, &cfg).unwrap().to_vec();
        assert_eq!(got.len(), size);
        got
    }

    /// A MeatPack reader after libbgcode's: signals, nibbles, full bytes, then its re-spacing of G lines and
    /// dropping of a '\n' right after another.
    fn meatpack_decode(data: &[u8]) -> Vec<u8> {
        let (mut packing, mut no_spaces) = (false, false);
        let (mut full, mut held) = (0, None);
        let mut chars = Vec::new();
        let mut i = 0;
        while i < data.len() {
            if data[i] == 0xFF && data.get(i + 1) == Some(&0xFF) {
                match data[i + 2] {
                    251 => packing = true,
                    250 | 249 => packing = false,
                    247 => no_spaces = true,
                    246 => no_spaces = false,
                    _ => {}
                }
                i += 3;
                continue;
            }
            let b = data[i];
            i += 1;
            if !packing {
                chars.push(b);
                continue;
            }
            if full > 0 {
                chars.push(b);
                chars.extend(held.take());
                full -= 1;
                continue;
            }
            let ch = |n: u8| match n {
                0..=9 => b'0' + n,
                10 => b'.',
                11 if no_spaces => b'E',
                11 => b' ',
                12 => b'\n',
                13 => b'G',
                14 => b'X',
                _ => unreachable!(),
            };
            let (lo, hi) = (b & 0xF, b >> 4);
            if lo == 0xF {
                full += 1;
                if hi == 0xF {
                    full += 1;
                } else {
                    held = Some(ch(hi));
                }
            } else {
                chars.push(ch(lo));
                if ch(lo) != b'\n' {
                    if hi == 0xF {
                        full += 1;
                    } else {
                        chars.push(ch(hi));
                    }
                }
            }
        }
        let mut out: Vec<u8> = Vec::new();
        let mut spacing = false;
        for c in chars {
            let line_start = out.last().is_none_or(|&l| l == b'\n');
            if c == b'G' && line_start {
                spacing = true;
            } else if c == b'\n' {
                spacing = false;
            } else if spacing && out.last() != Some(&b' ') && b"XYZEFIJRSGPWHCA".contains(&c) {
                out.push(b' ');
            }
            if c != b'\n' || out.last() != Some(&b'\n') {
                out.push(c);
            }
        }
        out
    }

    /// What the reader gives back for `text` (the rules in the module documentation).
    fn expected(text: &str) -> String {
        let mut out = String::new();
        for line in text.split('\n') {
            if line.starts_with(';') {
                out.push_str(line);
                out.push('\n');
                continue;
            }
            if line.is_empty() || line.starts_with('\r') {
                continue;
            }
            let code = line.split(';').next().unwrap_or("").trim_matches([' ', '\t']);
            if code.is_empty() {
                continue;
            }
            let code: String = if code.starts_with('G') && code[1..].starts_with(|c: char| c.is_ascii_digit()) {
                code.chars().filter(|&c| c != ' ' && c != '\t').map(|c| if "exg".contains(c) { c.to_ascii_uppercase() } else { c }).collect()
            } else {
                code.to_string()
            };
            // The reader re-spaces every line that starts with 'G'.
            let respace = code.starts_with('G');
            for (k, c) in code.chars().enumerate() {
                if respace && k > 0 && "XYZEFIJRSGPWHCA".contains(c) && !out.ends_with(' ') {
                    out.push(' ');
                }
                out.push(c);
            }
            out.push('\n');
        }
        out
    }

    /// Encodes, parses, checks the layout and returns the decoded G-code text.
    fn round_trip(input: &Input) -> String {
        let file = encode(input);
        assert_eq!(file, encode(input), "deterministic");
        let mut text = Vec::new();
        for b in parse(&file).iter().filter(|b| b.kind == BLOCK_GCODE) {
            assert_eq!((b.compression, b.params.as_slice()), (COMPRESSION_HEATSHRINK_12_4, &[2u8, 0][..]));
            text.extend(meatpack_decode(&heatshrink_decode(&b.data, b.uncompressed)));
        }
        String::from_utf8(text).unwrap()
    }

    /// Compares texts line by line, reporting only the first difference.
    #[track_caller]
    fn same_text(got: &str, want: &str, what: &str) {
        if got != want {
            let (g, w): (Vec<&str>, Vec<&str>) = (got.split('\n').collect(), want.split('\n').collect());
            let k = (0..g.len().max(w.len())).find(|&k| g.get(k) != w.get(k)).unwrap_or(0);
            let cut = |l: Option<&&str>| l.map(|l| l.chars().take(120).collect::<String>());
            panic!("{what}: line {k}: got {:?}, want {:?}", cut(g.get(k)), cut(w.get(k)));
        }
    }

    /// Deterministic pseudo-random numbers (64-bit LCG, high bits).
    struct Lcg(u64);
    impl Lcg {
        fn next(&mut self, n: usize) -> usize {
            self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((self.0 >> 33) as usize) % n
        }
    }

    /// A print-like G-code text of about `bytes` bytes.
    fn sample_gcode(bytes: usize) -> String {
        let mut rng = Lcg(7);
        let mut s = String::from("; generated by weft 0.1.0\n; printer: Generic 220 × 220\nM140 S60 ; bed\nG28 ; home\nG90\nM82\n");
        let mut layer = 0;
        while s.len() < bytes {
            layer += 1;
            s += &format!(";LAYER_CHANGE\n;Z:{:.2}\nG1 Z{:.2} F600\n;TYPE:Lattice\n", layer as f64 * 0.2, layer as f64 * 0.2);
            for k in 0..40 {
                let (x, y) = (100.0 + rng.next(2000) as f64 / 100.0, 100.0 + rng.next(2000) as f64 / 100.0);
                s += &format!("G1 X{x:.3} Y{y:.3} E{:.5}\n", layer as f64 + k as f64 * 0.0123);
            }
        }
        s
    }

    #[test]
    fn header_bytes() {
        let printer = kv(&[("printer_model", "MK4")]);
        let file = encode(&input(&printer, "G28\n"));
        assert_eq!(&file[..10], &[b'G', b'C', b'D', b'E', 1, 0, 0, 0, 1, 0]);
    }

    #[test]
    fn block_layout_and_crc() {
        assert_eq!(crc32fast::hash(b"123456789"), 0xCBF4_3926);
        let printer = kv(&[("a", "b")]);
        let file = encode(&input(&printer, ""));
        // Printer metadata: type 3, uncompressed, 4 bytes; INI encoding; "a=b\n"; CRC32 of all that.
        let block = [3, 0, 0, 0, 4, 0, 0, 0, 0, 0, b'a', b'=', b'b', b'\n'];
        assert_eq!(&file[10..24], &block);
        assert_eq!(&file[24..28], &crc32_bitwise(&block).to_le_bytes());
        // Then empty print and slicer metadata (uncompressed even for the slicer), then one G-code block.
        assert_eq!(&file[28..38], &[4, 0, 0, 0, 0, 0, 0, 0, 0, 0]);
        assert_eq!(&file[42..52], &[2, 0, 0, 0, 0, 0, 0, 0, 0, 0]);
        let blocks = parse(&file);
        assert_eq!(blocks.iter().map(|b| b.kind).collect::<Vec<_>>(), [3, 4, 2, 1]);
        // Empty G-code: MeatPack's "enable packing", "no spaces" and nothing else.
        assert_eq!(heatshrink_decode(&blocks[3].data, blocks[3].uncompressed), [0xFF, 0xFF, 251, 0xFF, 0xFF, 247]);
    }

    #[test]
    fn block_order_compression_and_metadata() {
        let file_md = kv(&[("Producer", "weft 0.1.0")]);
        let printer = kv(&[("printer_model", "MK4"), ("filament used [mm]", "12.5"), ("bad=key\nx", "two\r\nlines")]);
        let print = kv(&[("estimated printing time (normal mode)", "1m 2s")]);
        let slicer = kv(&[("layer_height", "0.2"), ("notes", "ünïcode ✓ = fine")]);
        let thumbs = [
            Thumbnail { width: 16, height: 16, format: ThumbnailFormat::Png, image: vec![1, 2, 3] },
            Thumbnail { width: 0, height: 16, format: ThumbnailFormat::Png, image: vec![4] },
            Thumbnail { width: 8, height: 8, format: ThumbnailFormat::Png, image: vec![] },
            Thumbnail { width: 313, height: 173, format: ThumbnailFormat::Png, image: vec![5; 1000] },
        ];
        let gcode = sample_gcode(200_000);
        let input = Input {
            file_metadata: &file_md,
            printer_metadata: &printer,
            thumbnails: &thumbs,
            print_metadata: &print,
            slicer_metadata: &slicer,
            gcode: &gcode,
            gcode_more: "",
        };
        let file = encode(&input);
        let blocks = parse(&file);
        let kinds: Vec<u16> = blocks.iter().map(|b| b.kind).collect();
        assert_eq!(kinds[..6], [0, 3, 5, 5, 4, 2]);
        assert!(kinds[6..].iter().all(|&k| k == BLOCK_GCODE) && kinds.len() == 6 + gcode_chunks(gcode.as_bytes()).len());
        assert!(kinds.len() >= 9, "200 kB make several G-code blocks");
        let compressions: Vec<u16> = blocks.iter().map(|b| b.compression).collect();
        assert_eq!(compressions[..6], [0, 0, 0, 0, 0, 1]);
        assert_eq!(blocks[0].data, b"Producer=weft 0.1.0\n");
        assert_eq!(blocks[1].data, "printer_model=MK4\nfilament used [mm]=12.5\nbad_key_x=two  lines\n".as_bytes());
        assert_eq!((blocks[2].params.as_slice(), blocks[2].data.as_slice()), (&[0u8, 0, 16, 0, 16, 0][..], &[1u8, 2, 3][..]));
        assert_eq!(blocks[3].params, [0, 0, 0x39, 1, 173, 0]);
        assert_eq!(blocks[3].data, vec![5; 1000]);
        assert_eq!(blocks[4].data, b"estimated printing time (normal mode)=1m 2s\n");
        let slicer_ini = miniz_oxide::inflate::decompress_to_vec_zlib(&blocks[5].data).unwrap();
        assert_eq!((slicer_ini.as_slice(), blocks[5].uncompressed), ("layer_height=0.2\nnotes=ünïcode ✓ = fine\n".as_bytes(), slicer_ini.len()));
        same_text(&round_trip(&input), &expected(&gcode), "sample");
    }

    #[test]
    fn gcode_chunks_cut_at_line_ends() {
        let line = "G1 X100.123 Y100.456 E1.23456\n";
        let text = line.repeat(10_000);
        let chunks = gcode_chunks(text.as_bytes());
        assert_eq!(chunks.concat(), text.as_bytes());
        assert_eq!(chunks.len(), text.len().div_ceil(GCODE_BLOCK_BYTES / line.len() * line.len()));
        for c in &chunks {
            assert!(c.len() <= GCODE_BLOCK_BYTES && c.ends_with(b"\n"));
            assert!(c.len() + line.len() > GCODE_BLOCK_BYTES || std::ptr::eq(c, chunks.last().unwrap()));
        }
        // Exactly full, one byte over, a giant line alone, no final newline.
        let full = "x".repeat(GCODE_BLOCK_BYTES - 1) + "\n";
        assert_eq!(gcode_chunks(full.as_bytes()).len(), 1);
        assert_eq!(gcode_chunks(format!("{full}G1\n").as_bytes()).len(), 2);
        let giant = format!("G1\n{}\nG1 X1", "y".repeat(3 * GCODE_BLOCK_BYTES));
        let chunks = gcode_chunks(giant.as_bytes());
        assert_eq!(chunks.iter().map(|c| c.len()).collect::<Vec<_>>(), [3, 3 * GCODE_BLOCK_BYTES + 1, 5]);
        assert!(gcode_chunks(b"").is_empty());
    }

    #[test]
    fn heatshrink_round_trips() {
        let mut rng = Lcg(1);
        let random: Vec<u8> = (0..20_000).map(|_| rng.next(256) as u8).collect();
        let few_symbols: Vec<u8> = (0..50_000).map(|_| b"G1X.\n"[rng.next(5)]).collect();
        // A match exactly the whole window back, and nothing nearer.
        let mut far = random[..HS_WINDOW].to_vec();
        far.extend_from_slice(&random[..64]);
        let gcode = sample_gcode(70_000).into_bytes();
        let cases: [&[u8]; 10] = [b"", b"a", b"ab", b"abc", b"abcabcabcabcabcabcabcabcabcabc", &[0; 10_000], &random, &few_symbols, &far, &gcode];
        for data in cases {
            let packed = heatshrink(data);
            assert_eq!(heatshrink_decode(&packed, data.len()), data, "length {}", data.len());
        }
        assert!(heatshrink(&[0; 10_000]).len() < 1_500);
        assert!(heatshrink(&gcode).len() < gcode.len() / 2);
        assert!(heatshrink(&far).len() < far.len() * 9 / 8 - 40, "the far copy is found");
        assert!(heatshrink(&random).len() <= random.len() * 9 / 8 + 1);
    }

    #[test]
    fn meatpack_bytes() {
        // "G1X10.5\n": G1 -> 0x1D, X1 -> 0x1E, 0. -> 0xA0, 5\n -> 0xC5 (first character in the low nibble).
        assert_eq!(meatpack(b"G1 X10.5\n"), [0xFF, 0xFF, 251, 0xFF, 0xFF, 247, 0x1D, 0x1E, 0xA0, 0xC5]);
        // "G1\n" is odd: padded with '\n'; the comment goes out unpacked.
        let mut want = vec![0xFF, 0xFF, 251, 0xFF, 0xFF, 247, 0x1D, 0xCC, 0xFF, 0xFF, 250];
        want.extend_from_slice(b";c\n");
        want.extend_from_slice(&[0xFF, 0xFF, 251, 0x1D, 0xCC]);
        assert_eq!(meatpack(b"G1\n;c\nG1\n"), want);
        // Unpackable characters: second one, first one, both.
        assert_eq!(meatpack(b"1M\n")[6..], [0xF1, b'M', 0xCC]);
        assert_eq!(meatpack(b"M1\n")[6..], [0x1F, b'M', 0xCC]);
        assert_eq!(meatpack(b"MS\n")[6..], [0xFF, b'M', b'S', 0xCC]);
    }

    #[test]
    fn meatpack_round_trips() {
        let exact = [
            "G1 X10.5 Y-3 E.1234\n",
            "G0 X113.64 Y115 F9000\n",
            "G1 Z0.148 F600\nG92 E0\nG28 W\nG4 P500\nG2 X1 Y2 I3 J4 E5\nG29 P1\n",
            "M104 S215\nM107\nT0\nM117 Layer 3 of 40\nM486 S1 A\"G1 part\"\n",
            "; generated by weft 0.1.0\n;TYPE:Lattice\n; printer: Generic 220 × 220 ✓ ünïcode\n;\n",
            "g1 x10 y5 e1\nm104 s200\n",
            "G1 X1*45\nN10 G1 X1*45\n*\n",
            "M118 E1 Echo with spaces   inside\n",
            "X\nE\n..\n0\n",
        ];
        for text in exact {
            assert_eq!(expected(text), text, "the model keeps canonical text");
            assert_eq!(String::from_utf8(meatpack_decode(&meatpack(text.as_bytes()))).unwrap(), text);
        }
        let normalised = [
            ("G28 ; home\n", "G28\n"),
            ("  M104 S200  \t; nozzle\n", "M104 S200\n"),
            ("G1  X1\tY2 e3 x4 g5\n", "G1 X1 Y2 E3 X4 G5\n"),
            ("G1X10Y20E.5F1800\n", "G1 X10 Y20 E.5 F1800\n"),
            ("\n\n   \n\t\n  ; indented comment\nG1\r\n\r\nM1\n", "G1\r\nM1\n"),
            ("G1 X1", "G1 X1\n"),
            ("M\0 X1\nG1 X\0\n", "M\0 X1\nG1 X\0\n"),
        ];
        for (text, want) in normalised {
            assert_eq!(expected(text), want);
            assert_eq!(String::from_utf8(meatpack_decode(&meatpack(text.as_bytes()))).unwrap(), want, "{text:?}");
        }
        let long_g = format!("G1 X{} Y2\n", "1".repeat(150_000));
        let long_comment = format!(";{}\n", "ü ".repeat(100_000));
        let long_other = format!("M117 {}\n", "a b ".repeat(50_000).trim_end());
        for text in [long_g, long_comment, long_other] {
            same_text(&String::from_utf8(meatpack_decode(&meatpack(text.as_bytes()))).unwrap(), &text, "long line");
        }
    }

    #[test]
    fn any_text_round_trips() {
        let palette = [
            "G", "G1 ", "X", "Y", "E", "e", "x", "g", "1", "0", ".", "-", " ", "  ", "\t", "\n", "\n", "\n", "\r", ";", "*", "\0", "M", "ü", "✓", "𝄞", "=",
            "F", "S", "Z",
        ];
        let mut rng = Lcg(42);
        for round in 0..300 {
            let len = rng.next(if round % 50 == 0 { 40_000 } else { 400 });
            let text: String = (0..len).map(|_| palette[rng.next(palette.len())]).collect();
            let printer = kv(&[("printer_model", "MK4")]);
            same_text(&round_trip(&input(&printer, &text)), &expected(&text), &format!("round {round}"));
        }
        let printer = kv(&[]);
        for text in ["", "\n", "\n\n\n", ";", "G", "G1", "\r\n", " \u{a0} "] {
            same_text(&round_trip(&input(&printer, text)), &expected(text), &format!("{text:?}"));
        }
        let giant = format!("G1 X1\n;{}\nG1 X2\n", "é".repeat(100_000));
        same_text(&round_trip(&input(&printer, &giant)), &giant, "giant comment");
    }
}

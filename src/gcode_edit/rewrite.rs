//! Rewriting one number of a G-code line in place: find the word's digits, print the new value
//! in the style the file writes that word.
//!
//! Only the digits of the word change; the letter, the spacing, other words and the comment
//! are copied as they are. The style is read from the file: the number of decimals (the most
//! the `E` words read so far have shown, so PrusaSlicer's trimmed `E.0261` still gets its
//! fifth decimal back; the editor reads those of the first moves and of every infill move), whether trailing zeros are written (Cura and Slic3r write `E1.20000`,
//! PrusaSlicer 2.4+ trims to `E1.2`: trimmed until a word with a trailing zero is seen) and
//! whether a leading zero is (PrusaSlicer writes `E.02612`, others `E0.02612`: written until a
//! word without one is seen).
//! Formatting is Rust's exact decimal rounding of the f64, identical on every target.

use crate::motion::lex::parse_number;
use std::io::Write;

/// Most decimals a rewritten number gets, whatever the file wrote (a thousandth of a micrometre
/// of filament; bounds the length of an edited line).
pub const MAX_DECIMALS: usize = 10;

/// Where a word's number is in a line, and how it is written.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Word {
    /// First byte of the number (after the letter).
    pub start: usize,
    /// One past its last byte.
    pub end: usize,
    /// Digits after the point.
    pub decimals: usize,
    /// Written with digits before the point (`0.5`, not `.5`).
    pub leading_zero: bool,
    /// Its last decimal is a `0` (the file does not trim trailing zeros).
    pub trailing_zero: bool,
}

/// A word of a line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Found {
    /// The word, when the line has it with a number.
    pub word: Option<Word>,
    /// The line carries a `*` checksum (which an edit would invalidate).
    pub checksum: bool,
}

/// Finds the number of word `letter` (uppercase; lowercase in the file matches) in a line the
/// lexer has read: the first such letter outside comments (`;…`, `(…)`). A lexed `G0`–`G3`
/// line has every letter as a word and none twice, so this is the word the lexer read.
pub fn find_word(line: &[u8], letter: u8) -> Found {
    let mut i = 0;
    let mut word = None;
    let mut checksum = false;
    while i < line.len() {
        match line[i] {
            b';' => break,
            b'(' => {
                i = line[i..].iter().position(|&b| b == b')').map_or(line.len(), |p| i + p + 1);
                continue;
            }
            b'*' => checksum = true,
            b if word.is_none() && b.to_ascii_uppercase() == letter => {
                if let Some((_, n)) = parse_number(&line[i + 1..]) {
                    let text = &line[i + 1..i + 1 + n];
                    let digits = text.strip_prefix(b"-").or_else(|| text.strip_prefix(b"+")).unwrap_or(text);
                    let point = digits.iter().position(|&b| b == b'.');
                    let decimals = point.map_or(0, |p| digits.len() - p - 1);
                    word = Some(Word {
                        start: i + 1,
                        end: i + 1 + n,
                        decimals,
                        leading_zero: point != Some(0),
                        trailing_zero: decimals > 0 && digits.last() == Some(&b'0'),
                    });
                    i += 1 + n;
                    continue;
                }
            }
            _ => {}
        }
        i += 1;
    }
    Found { word, checksum }
}

/// How numbers of one word are written in a file, learnt as its words are read.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Style {
    /// Most decimals seen (at most [`MAX_DECIMALS`]).
    pub decimals: usize,
    /// A word with a trailing zero was seen: the file pads to its decimals.
    pub pads: bool,
    /// A word without a leading zero (`.5`) was seen: the file drops them.
    pub bare: bool,
}

impl Style {
    /// Learns from one word.
    #[inline]
    pub fn learn(&mut self, w: &Word) {
        self.decimals = self.decimals.max(w.decimals.min(MAX_DECIMALS));
        self.pads |= w.trailing_zero;
        self.bare |= !w.leading_zero;
    }
}

/// Powers of ten up to [`MAX_DECIMALS`], exact in f64.
const POW10: [f64; MAX_DECIMALS + 1] = [1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10];

/// `v` rounded to `decimals` (at most [`MAX_DECIMALS`]) into `buf` as `[-]digits.digits`,
/// exactly as `format!("{v:.decimals$}")` writes it (round half to even on the binary value),
/// without the formatter's cost: the scaled value is rounded in f64 and checked to be far
/// enough from a tie that the f64 product's rounding cannot have decided it; otherwise, and
/// for large numbers, the standard formatter writes it.
/// Returns the value written (the f64 nearest to it, as the lexer would read it back).
fn fixed(buf: &mut Vec<u8>, v: f64, decimals: usize) -> f64 {
    let scaled = v.abs() * POW10[decimals];
    // Below 2^52 the product's error is under 1/2 ulp ≤ 2^-53 · 2^52 = 0.5 · 2^-1.
    if scaled < (1u64 << 52) as f64 {
        let floor = scaled.floor();
        let frac = scaled - floor;
        // The product is within scaled · 2^-53 of the exact one: a fraction that far from
        // one half rounds the same way for both.
        if (frac - 0.5).abs() > scaled * f64::EPSILON + 1e-300 {
            let n = floor as u64 + u64::from(frac > 0.5);
            if v.is_sign_negative() {
                buf.push(b'-');
            }
            let mut digits = [0u8; 20];
            let mut k = digits.len();
            let mut m = n;
            loop {
                k -= 1;
                digits[k] = b'0' + (m % 10) as u8;
                m /= 10;
                if m == 0 {
                    break;
                }
            }
            // At least one digit before the point.
            while digits.len() - k < decimals + 1 {
                k -= 1;
                digits[k] = b'0';
            }
            let point = digits.len() - decimals;
            buf.extend_from_slice(&digits[k..point]);
            if decimals > 0 {
                buf.push(b'.');
                buf.extend_from_slice(&digits[point..]);
            }
            // n < 2^53 and 10^d are exact: the quotient is the correctly rounded value of the
            // decimal written, as `parse_number` computes it.
            let value = n as f64 / POW10[decimals];
            return if v.is_sign_negative() { -value } else { value };
        }
    }
    let start = buf.len();
    let _ = write!(buf, "{:.*}", decimals, v);
    parse_number(&buf[start..]).map_or(f64::NAN, |p| p.0)
}

/// Appends `v` to `out` in `style` and returns the value written (trailing zeros and a
/// leading zero do not change it); `scratch` is reused between calls (no allocation once it
/// has grown).
pub fn write_number(out: &mut Vec<u8>, scratch: &mut Vec<u8>, v: f64, style: Style) -> f64 {
    scratch.clear();
    let value = fixed(scratch, v, style.decimals.min(MAX_DECIMALS));
    // A tiny negative rounds to "-0.000": write it as zero.
    if scratch.first() == Some(&b'-') && scratch[1..].iter().all(|&b| b == b'0' || b == b'.') {
        scratch.remove(0);
    }
    if !style.pads && scratch.contains(&b'.') {
        while scratch.last() == Some(&b'0') {
            scratch.pop();
        }
        if scratch.last() == Some(&b'.') {
            scratch.pop();
        }
    }
    let neg = usize::from(scratch.first() == Some(&b'-'));
    if style.bare && scratch.len() > neg + 2 && scratch[neg] == b'0' && scratch[neg + 1] == b'.' {
        scratch.remove(neg);
    }
    out.extend_from_slice(scratch);
    if value == 0.0 {
        0.0
    } else {
        value
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fmt(v: f64, decimals: usize, pads: bool, text: &[u8]) -> String {
        let mut style = Style { decimals, pads, bare: false };
        style.learn(&find_word(text, b'E').word.unwrap());
        let mut out = Vec::new();
        let value = write_number(&mut out, &mut Vec::new(), v, style);
        assert_eq!(value, parse_number(&out).unwrap().0);
        String::from_utf8(out).unwrap()
    }

    #[test]
    fn finds_the_word_outside_comments() {
        let l = b"G1 X10 (E9) Y2 e.02612 ; E5";
        let f = find_word(l, b'E');
        let w = f.word.unwrap();
        assert_eq!(&l[w.start..w.end], b".02612");
        assert_eq!((w.decimals, w.leading_zero, w.trailing_zero, f.checksum), (5, false, false, false));
        let l = b"G1X40E4.50*12";
        let f = find_word(l, b'E');
        let w = f.word.unwrap();
        assert_eq!(&l[w.start..w.end], b"4.50");
        assert!(w.trailing_zero && w.leading_zero && f.checksum);
        assert_eq!(find_word(b"G1 X1 ; E1", b'E').word, None);
    }

    #[test]
    fn fixed_point_matches_the_formatter() {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut buf = Vec::new();
        let mut ties = vec![0.5, 1.5, 2.5, 0.125, 0.375, -0.5, 0.000005, 1.000005, 2.675, 1e-320, -1e-7, 123456.5, 4503599627370495.5];
        for k in 0..200_000 {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let v = f64::from_bits(state);
            let v = if v.is_finite() { v.rem_euclid(2e4) - 1e4 } else { 0.0 };
            ties.push(if k % 2 == 0 { v } else { (v * 1e5).round() / 1e5 + 0.000005 });
        }
        for &v in &ties {
            for d in 0..=MAX_DECIMALS {
                buf.clear();
                let value = fixed(&mut buf, v, d);
                assert_eq!(String::from_utf8(buf.clone()).unwrap(), format!("{v:.d$}"), "{v} to {d}");
                assert_eq!(value, parse_number(&buf).unwrap().0, "{v} to {d}");
            }
        }
    }

    #[test]
    fn numbers_keep_the_file_style() {
        assert_eq!(fmt(0.0123456, 5, true, b"E0.10000"), "0.01235");
        assert_eq!(fmt(0.0120, 5, false, b"E.0261"), ".012");
        assert_eq!(fmt(1.5, 5, false, b"E.0261"), "1.5");
        assert_eq!(fmt(0.9, 5, false, b"E.0261"), ".9");
        assert_eq!(fmt(0.9, 5, true, b"E1.50000"), "0.90000");
        assert_eq!(fmt(2.0, 5, false, b"E.0261"), "2");
        assert_eq!(fmt(0.0, 5, false, b"E.0261"), "0");
        assert_eq!(fmt(-0.000001, 5, true, b"E1.00000"), "0.00000");
        assert_eq!(fmt(-0.25, 3, true, b"E-.500"), "-.250");
        assert_eq!(fmt(3.0, 0, false, b"E3"), "3");
    }
}

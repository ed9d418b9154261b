//! Byte-level G-code lexing: words, numbers, comments. No allocation per line. Shared by the
//! analyzer and the writer (which reads its start/end templates and user codes with it).

/// Powers of ten exactly representable as f64.
const POW10: [f64; 23] = [1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22];

/// Parses a decimal number `[+-]?digits[.digits]` (or `.digits`) at the start of `s`.
/// Returns the value and the bytes consumed; `None` when there is no digit.
/// Exact (correctly rounded) for up to 15 significant digits and 22 decimals, which covers
/// everything slicers write; longer forms fall back to the standard library parser.
#[inline]
pub fn parse_number(s: &[u8]) -> Option<(f64, usize)> {
    let mut i = 0;
    let mut neg = false;
    if let Some(&c) = s.first() {
        if c == b'-' || c == b'+' {
            neg = c == b'-';
            i = 1;
        }
    }
    // Digits before and after the point; the mantissa is accumulated in a separate pass only
    // when it is short enough for the fast path (fewer than 19 digits), which keeps the scan
    // loops free of the accumulator's dependency chain.
    let int_start = i;
    while i < s.len() && s[i].is_ascii_digit() {
        i += 1;
    }
    let int_end = i;
    let mut frac_start = i;
    if i < s.len() && s[i] == b'.' {
        i += 1;
        frac_start = i;
        while i < s.len() && s[i].is_ascii_digit() {
            i += 1;
        }
    }
    let int_digits = int_end - int_start;
    let frac_digits = i - frac_start;
    let digits = int_digits + frac_digits;
    if digits == 0 {
        return None;
    }
    let v = if digits < 19 {
        // Fewer than 19 digits: the mantissa fits in a u64 (< 10^18 < 2^63).
        let mut mant: u64 = 0;
        for &b in &s[int_start..int_end] {
            mant = mant * 10 + (b - b'0') as u64;
        }
        for &b in &s[frac_start..i] {
            mant = mant * 10 + (b - b'0') as u64;
        }
        if mant < (1u64 << 53) && frac_digits < POW10.len() {
            Some(mant as f64 / POW10[frac_digits])
        } else {
            None
        }
    } else {
        None
    };
    let v = match v {
        Some(v) => v,
        None => {
            // Rare: too many digits for the fast path.
            let text = std::str::from_utf8(&s[usize::from(neg || s[0] == b'+')..i]).ok()?;
            text.parse::<f64>().ok()?
        }
    };
    Some((if neg { -v } else { v }, i))
}

/// Largest magnitude a word's number may have: 10 km (or 10 km of filament, 10^7 mm/min, 10^7
/// ms of dwell). No machine reaches it, absolute E of the largest spool stays far below it, and
/// sums of such numbers over any file stay finite (no inf or NaN totals).
pub const MAX_WORD_MAGNITUDE: f64 = 1.0e7;
/// Smallest positive feed rate (`F`, mm/min) and acceleration (`M204`, mm/s²) accepted: one
/// micrometre per minute. Slower is not a speed any machine runs at, and a feed near zero would
/// make the time estimate infinite.
pub const MIN_RATE: f64 = 1.0e-3;

/// Parameter words of one line: a value per letter A–Z.
#[derive(Clone, Copy, Debug)]
pub struct Words {
    /// Bit `L - 'A'` set when letter L appeared with a number.
    pub mask: u32,
    /// Bit set when the letter appeared without a number (G28 X flags).
    pub flags: u32,
    /// Values by letter.
    pub vals: [f64; 26],
}

impl Default for Words {
    fn default() -> Self {
        Words { mask: 0, flags: 0, vals: [0.0; 26] }
    }
}

impl Words {
    /// The value of `letter` (uppercase) when present with a number.
    #[inline]
    pub fn get(&self, letter: u8) -> Option<f64> {
        let k = (letter - b'A') as usize;
        if self.mask & (1 << k) != 0 {
            Some(self.vals[k])
        } else {
            None
        }
    }

    /// Sets `letter` (uppercase) to `v`, as if the line had it (the writer describes the moves
    /// it prints this way, with the values exactly as printed).
    #[inline]
    pub fn set(&mut self, letter: u8, v: f64) {
        let k = (letter - b'A') as usize;
        self.vals[k] = v;
        self.mask |= 1 << k;
    }

    /// Whether `letter` appeared at all.
    #[inline]
    pub fn has(&self, letter: u8) -> bool {
        let k = (letter - b'A') as u32;
        (self.mask | self.flags) & (1 << k) != 0
    }
}

/// The command word of a line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Command {
    /// No command word (blank, comment-only or unknown).
    None,
    /// `G<n>`; `sub` is the part after a dot (`G29.1` → 1).
    G(u32, u32),
    /// `M<n>`.
    M(u32),
    /// `T<n>` or other command letters we ignore.
    Other,
    /// Parameters without a command word (`X10 Y5`): repeats the modal motion.
    Modal,
    /// A named command (Klipper's extended G-code: `EXCLUDE_OBJECT_START NAME=part`,
    /// `SET_PRINT_STATS_INFO`, a macro): a letter followed by a letter or `_`.
    Named,
}

/// One lexed line.
#[derive(Debug)]
pub struct Line<'a> {
    /// The command.
    pub cmd: Command,
    /// Its parameters (only for commands the analyzer interprets).
    pub words: Words,
    /// Text after `;`, if any.
    pub comment: Option<&'a [u8]>,
    /// The text of a [`Command::Named`] line and the arguments of `M486` (object labels),
    /// before any comment; `None` for other lines.
    pub args: Option<&'a [u8]>,
}

/// `s[i..]` up to its comment, and the comment (text after `;`).
fn split_comment(s: &[u8], i: usize) -> (&[u8], Option<&[u8]>) {
    let mut j = i;
    while j < s.len() {
        match s[j] {
            b';' => return (&s[i..j], Some(&s[j + 1..])),
            b'(' => j = skip_paren(s, j),
            _ => j += 1,
        }
    }
    (&s[i.min(s.len())..], None)
}

/// Whether the analyzer reads this command's parameters (and so checks them strictly).
#[inline]
fn interpreted(cmd: Command) -> bool {
    matches!(cmd, Command::G(0..=4 | 10 | 11 | 20 | 21 | 28 | 90 | 91 | 92, 0) | Command::M(82 | 83 | 204) | Command::Modal)
}

/// Skips a `( … )` comment starting at `i` (which holds `(`); returns the index after it.
#[inline]
fn skip_paren(s: &[u8], i: usize) -> usize {
    match s[i..].iter().position(|&b| b == b')') {
        Some(p) => i + p + 1,
        None => s.len(),
    }
}

#[inline]
fn find_comment(s: &[u8], mut i: usize) -> Option<&[u8]> {
    while i < s.len() {
        match s[i] {
            b';' => return Some(&s[i + 1..]),
            b'(' => i = skip_paren(s, i),
            _ => i += 1,
        }
    }
    None
}

/// Lexes one line (without its newline). `Err` describes a malformed parameter.
pub fn lex_line(s: &[u8]) -> Result<Line<'_>, String> {
    let mut words = Words::default();
    let mut cmd = Command::None;
    let mut i = 0;
    while i < s.len() {
        let b = s[i];
        match b {
            b' ' | b'\t' | b'\r' | 0x0b | 0x0c => i += 1,
            b';' => return Ok(Line { cmd, words, comment: Some(&s[i + 1..]), args: None }),
            b'(' => i = skip_paren(s, i),
            b'*' => {
                // Checksum: skip its digits, keep reading (a comment may follow).
                i += 1;
                while i < s.len() && s[i].is_ascii_digit() {
                    i += 1;
                }
            }
            b'%' if cmd == Command::None => i += 1,
            _ if b.is_ascii_alphabetic() => {
                let letter = b.to_ascii_uppercase();
                i += 1;
                let num = parse_number(&s[i..]);
                if cmd == Command::None && matches!(letter, b'G' | b'M' | b'T' | b'N') {
                    if letter == b'N' {
                        // Line number: skip it.
                        if let Some((_, n)) = num {
                            i += n;
                        }
                        continue;
                    }
                    let code = match num {
                        Some((v, n)) => {
                            i += n;
                            v
                        }
                        None => -1.0,
                    };
                    cmd = if !(0.0..=1.0e6).contains(&code) {
                        Command::Other
                    } else {
                        let whole = code as u32;
                        let sub = ((code - whole as f64) * 10.0 + 0.5) as u32;
                        match letter {
                            b'G' => Command::G(whole, sub),
                            b'M' => Command::M(whole),
                            _ => Command::Other,
                        }
                    };
                    if cmd == Command::M(486) {
                        let (args, comment) = split_comment(s, i);
                        return Ok(Line { cmd, words, comment, args: Some(args) });
                    }
                    if !interpreted(cmd) {
                        // Free-form arguments (M117 text, file names): only look for a comment.
                        return Ok(Line { cmd, words, comment: find_comment(s, i), args: None });
                    }
                    continue;
                }
                if cmd == Command::None {
                    if matches!(s.get(i), Some(c) if c.is_ascii_alphabetic() || *c == b'_') {
                        let (args, comment) = split_comment(s, i - 1);
                        return Ok(Line { cmd: Command::Named, words, comment, args: Some(args) });
                    }
                    cmd = Command::Modal;
                }
                let k = (letter - b'A') as usize;
                match num {
                    Some((v, n)) => {
                        let text = &s[i..i + n];
                        i += n;
                        if let Some(len) = exponent_len(&s[i..]) {
                            // Firmware reads `X1e10` as X1 followed by an E word: refuse the
                            // ambiguity rather than pick a reading.
                            let exp = String::from_utf8_lossy(&s[i..i + len]);
                            return Err(format!(
                                "{}{}{exp} has an exponent, which G-code numbers do not have (a printer would read '{exp}' as an E word)",
                                letter as char,
                                String::from_utf8_lossy(text),
                            ));
                        }
                        if !v.is_finite() || v.abs() > MAX_WORD_MAGNITUDE {
                            return Err(format!(
                                "{}{} is out of range: numbers are at most {MAX_WORD_MAGNITUDE:.0} in size (10 km), far beyond any machine",
                                letter as char,
                                String::from_utf8_lossy(text)
                            ));
                        }
                        if v > 0.0 && v < MIN_RATE && is_rate(cmd, letter) {
                            return Err(format!(
                                "{}{} is slower than {MIN_RATE} (mm/min or mm/s²), which no machine runs at",
                                letter as char,
                                String::from_utf8_lossy(text)
                            ));
                        }
                        if words.mask & (1 << k) != 0 {
                            return Err(format!("{} appears twice on the line", letter as char));
                        }
                        words.vals[k] = v;
                        words.mask |= 1 << k;
                        if let Some(&next) = s.get(i) {
                            if !(next.is_ascii_alphabetic() || matches!(next, b' ' | b'\t' | b'\r' | b';' | b'(' | b'*' | 0x0b | 0x0c)) {
                                return Err(format!("cannot read the number after {} (unexpected '{}')", letter as char, printable(next)));
                            }
                        }
                    }
                    None => {
                        if !matches!(cmd, Command::G(28, _)) && b"XYZEFIJRPS".contains(&letter) {
                            return Err(format!("{} is not followed by a number", letter as char));
                        }
                        words.flags |= 1 << k;
                    }
                }
            }
            _ => {
                if interpreted(cmd) {
                    return Err(format!("unexpected '{}'", printable(b)));
                }
                // Junk on an otherwise empty line: ignore the line but keep its comment.
                return Ok(Line { cmd: Command::None, words, comment: find_comment(s, i), args: None });
            }
        }
    }
    Ok(Line { cmd, words, comment: None, args: None })
}

/// Length of an exponent (`e5`, `e-3`, `e+10`) at the start of `s`, if there is one. Only a
/// lowercase `e` counts: `X10E5` is the compact form of `X10 E5`.
#[inline]
fn exponent_len(s: &[u8]) -> Option<usize> {
    if s.first() != Some(&b'e') {
        return None;
    }
    let sign = usize::from(matches!(s.get(1), Some(b'+' | b'-')));
    let digits = s[1 + sign..].iter().take_while(|b| b.is_ascii_digit()).count();
    (digits > 0).then_some(1 + sign + digits)
}

/// Whether `letter` of `cmd` is a feed rate or an acceleration (bounded below by [`MIN_RATE`]).
#[inline]
fn is_rate(cmd: Command, letter: u8) -> bool {
    match cmd {
        Command::G(0..=3, 0) | Command::Modal => letter == b'F',
        Command::M(204) => matches!(letter, b'S' | b'P' | b'T'),
        _ => false,
    }
}

fn printable(b: u8) -> String {
    if b.is_ascii_graphic() {
        (b as char).to_string()
    } else {
        format!("\\x{b:02x}")
    }
}

/// Position of the first byte that cannot appear in a text file (NUL and other C0 controls
/// except tab, LF, VT, FF, CR and ESC).
pub fn first_binary_byte(bytes: &[u8]) -> Option<usize> {
    #[inline]
    fn bad(b: u8) -> bool {
        b < 0x20 && !matches!(b, b'\t' | b'\n' | 0x0b | 0x0c | b'\r' | 0x1b)
    }
    let mut base = 0;
    for chunk in bytes.chunks(256) {
        if chunk.iter().fold(false, |acc, &b| acc | bad(b)) {
            return chunk.iter().position(|&b| bad(b)).map(|p| base + p);
        }
        base += chunk.len();
    }
    None
}

/// Whether the file has layer-change comments (`;LAYER:` or `;LAYER_CHANGE`).
pub fn has_layer_comments(bytes: &[u8]) -> bool {
    let mut i = 0;
    while let Some(p) = bytes[i..].iter().position(|&b| b == b';') {
        let rest = &bytes[i + p + 1..];
        let rest = trim_start(rest);
        if rest.starts_with(b"LAYER:") || rest.starts_with(b"LAYER_CHANGE") {
            return true;
        }
        i += p + 1;
    }
    false
}

/// Drops leading spaces and tabs.
#[inline]
pub fn trim_start(s: &[u8]) -> &[u8] {
    let n = s.iter().take_while(|&&b| b == b' ' || b == b'\t').count();
    &s[n..]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers() {
        assert_eq!(parse_number(b"12.5 "), Some((12.5, 4)));
        assert_eq!(parse_number(b"-.5"), Some((-0.5, 3)));
        assert_eq!(parse_number(b"+3"), Some((3.0, 2)));
        assert_eq!(parse_number(b"0.1"), Some((0.1, 3)));
        assert_eq!(parse_number(b"1234567890.123456789012"), Some(("1234567890.123456789012".parse().unwrap(), 23)));
        assert_eq!(parse_number(b"-"), None);
        assert_eq!(parse_number(b"."), None);
        assert_eq!(parse_number(b"x"), None);
        for s in ["0.00001", "123.456", "99999.99999", "0.3", "7.0e0"] {
            let (v, _) = parse_number(s.as_bytes()).unwrap();
            let end = s.find('e').unwrap_or(s.len());
            assert_eq!(v, s[..end].parse::<f64>().unwrap(), "{s}");
        }
    }

    #[test]
    fn lexing() {
        let l = lex_line(b"N12 g1 x10.5Y-2 e.25 *71 ; hi").unwrap();
        assert_eq!(l.cmd, Command::G(1, 0));
        assert_eq!(l.words.get(b'X'), Some(10.5));
        assert_eq!(l.words.get(b'Y'), Some(-2.0));
        assert_eq!(l.words.get(b'E'), Some(0.25));
        assert_eq!(l.comment, Some(&b" hi"[..]));
        let l = lex_line(b"M117 Hello (world); x").unwrap();
        assert_eq!(l.cmd, Command::M(117));
        assert_eq!(l.comment, Some(&b" x"[..]));
        assert!(lex_line(b"G1 X1.2.3").is_err());
        assert!(lex_line(b"G1 Xabc").is_err());
        assert!(lex_line(b"G28 X Y").is_ok());
        let l = lex_line(b"X5 (c) Y6").unwrap();
        assert_eq!(l.cmd, Command::Modal);
        assert_eq!(l.words.get(b'Y'), Some(6.0));
    }

    #[test]
    fn refusals() {
        // Exponents (lowercase e right after a number) are refused; uppercase E is the E word.
        for s in ["G1 X1e5", "G1 E1e300", "G1 Y2.5e-3", "X3e+2", "g1 x1e1"] {
            let e = lex_line(s.as_bytes()).unwrap_err();
            assert!(e.contains("exponent"), "{s}: {e}");
        }
        let l = lex_line(b"G1X1E5").unwrap();
        assert_eq!((l.words.get(b'X'), l.words.get(b'E')), (Some(1.0), Some(5.0)));
        // A lone `e` after a number is an E word without a number (refused as such).
        assert!(lex_line(b"G1 X1e").unwrap_err().contains("E is not followed"));
        // Twice the same letter; magnitudes; rates.
        assert!(lex_line(b"G1 X1 X2").unwrap_err().contains("twice"));
        assert!(lex_line(b"G1 X-10000000 E10000000").is_ok());
        assert!(lex_line(b"G1 X10000000.001").unwrap_err().contains("out of range"));
        assert!(lex_line(b"G1 F0.001").is_ok());
        assert!(lex_line(b"G1 F0.0009").unwrap_err().contains("slower"));
        assert!(lex_line(b"M204 T0.0000001").unwrap_err().contains("slower"));
        assert!(lex_line(b"G4 S0.0000001").is_ok());
        // Commands the analyzer does not interpret keep free-form arguments.
        assert!(lex_line(b"M117 1e5 X1e5 X1e99999").is_ok());
    }
}

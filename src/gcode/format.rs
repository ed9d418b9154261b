//! Deterministic number formatting: integer arithmetic only, identical on every target.

const POW10: [f64; 10] = [1.0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9];

/// `v` scaled by `10^decimals` and rounded half away from zero, as [`push_fixed`] prints it;
/// `None` when it prints as `0` (zero, non-finite, or ≥ 9·10^18 after scaling).
fn scaled(v: f64, decimals: usize) -> Option<f64> {
    let r = (v * POW10[decimals]).round();
    if !r.is_finite() || r.abs() >= 9.0e18 || r == 0.0 {
        None
    } else {
        Some(r)
    }
}

/// Appends `v` rounded half away from zero to `decimals` (≤ 9) decimal places, trailing
/// zeros trimmed (`1.5`, `10`, `0.25`). Never prints `-0`; non-finite or absurdly large
/// values (≥ 9·10^18 after scaling) print as `0` (the writer validates its inputs first).
pub fn push_fixed(out: &mut String, v: f64, decimals: usize) {
    push_fixed_read(out, v, decimals);
}

/// [`push_fixed`], returning the value printed ([`as_printed`]) from the same rounding.
pub(crate) fn push_fixed_read(out: &mut String, v: f64, decimals: usize) -> f64 {
    let decimals = decimals.min(9);
    let Some(r) = scaled(v, decimals) else {
        out.push('0');
        return 0.0;
    };
    let mut n = r as i64;
    if n < 0 {
        out.push('-');
        n = -n;
    }
    let n = n as u64;
    let scale = POW10[decimals] as u64;
    push_u64(out, n / scale);
    let mut frac = n % scale;
    if frac != 0 {
        let mut digits = decimals;
        while frac % 10 == 0 {
            frac /= 10;
            digits -= 1;
        }
        out.push('.');
        let mut buf = [b'0'; 9];
        for slot in buf[..digits].iter_mut().rev() {
            *slot = b'0' + (frac % 10) as u8;
            frac /= 10;
        }
        for &b in &buf[..digits] {
            out.push(b as char);
        }
    }
    r / POW10[decimals]
}

/// The value a reader gets back from `v` printed by [`push_fixed`] with `decimals` places
/// (the same f64 the analyzer's number parser returns for that text: both are the correctly
/// rounded quotient of the printed integer by a power of ten).
pub fn as_printed(v: f64, decimals: usize) -> f64 {
    let decimals = decimals.min(9);
    scaled(v, decimals).map_or(0.0, |r| r / POW10[decimals])
}

/// `v` at `decimals` (≤ 9) places as an integer (`round(v · 10^decimals)`), to compare what
/// would be printed without printing it.
pub(crate) fn printed_units(v: f64, decimals: usize) -> i64 {
    (v * POW10[decimals.min(9)]).round() as i64
}

/// `v` formatted by [`push_fixed`].
pub fn fixed(v: f64, decimals: usize) -> String {
    let mut s = String::new();
    push_fixed(&mut s, v, decimals);
    s
}

/// Appends an unsigned integer in decimal.
pub fn push_u64(out: &mut String, mut n: u64) {
    let mut buf = [0u8; 20];
    let mut i = buf.len();
    loop {
        i -= 1;
        buf[i] = b'0' + (n % 10) as u8;
        n /= 10;
        if n == 0 {
            break;
        }
    }
    for &b in &buf[i..] {
        out.push(b as char);
    }
}

/// A duration as PrusaSlicer writes it: `1d 2h 3m 4s`, leading zero units omitted (`45s`, `2m 5s`).
pub fn duration(seconds: f64) -> String {
    let total = if seconds.is_finite() && seconds > 0.0 { seconds.round() as u64 } else { 0 };
    let (d, h, m, s) = (total / 86_400, total / 3600 % 24, total / 60 % 60, total % 60);
    let mut out = String::new();
    if d > 0 {
        out.push_str(&format!("{d}d "));
    }
    if d > 0 || h > 0 {
        out.push_str(&format!("{h}h "));
    }
    if d > 0 || h > 0 || m > 0 {
        out.push_str(&format!("{m}m "));
    }
    out.push_str(&format!("{s}s"));
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fixed_formats() {
        assert_eq!(fixed(10.0, 3), "10");
        assert_eq!(fixed(0.2, 3), "0.2");
        assert_eq!(fixed(-0.0001, 3), "0");
        assert_eq!(fixed(-0.0, 3), "0");
        assert_eq!(fixed(-1.25, 3), "-1.25");
        assert_eq!(fixed(1.23456789, 5), "1.23457");
        assert_eq!(fixed(0.000_05, 5), "0.00005");
        assert_eq!(fixed(123.0005, 3), "123.001");
        assert_eq!(fixed(f64::NAN, 3), "0");
        assert_eq!(fixed(9000.4, 0), "9000");
    }

    #[test]
    fn printed_values_read_back_exactly() {
        for v in [0.1, 12.345_67, -3.000_4, 123_456.789_49, 1e-7, -0.0004, 7.5e12, 0.3] {
            for d in [0, 3, 5, 7] {
                let text = fixed(v, d);
                let (back, _) = crate::motion::lex::parse_number(text.as_bytes()).unwrap();
                assert_eq!(back.to_bits(), as_printed(v, d).to_bits(), "{v} {d} {text}");
            }
        }
    }

    #[test]
    fn durations() {
        assert_eq!(duration(45.2), "45s");
        assert_eq!(duration(125.0), "2m 5s");
        assert_eq!(duration(3723.0), "1h 2m 3s");
        assert_eq!(duration(90_000.0), "1d 1h 0m 0s");
        assert_eq!(duration(f64::NAN), "0s");
    }
}

//! Generators of design inputs (see the module above): hostile templates, names, `--set`
//! paths, nesting and share links. Each output grows linearly in `n`.

/// A start/end G-code template of `n` bytes: `M117 ` then `{x` pairs on one line, no `}`.
/// Every `{` is unclosed; an expander that looks for each one's `}` to the line's end does
/// quadratic work.
pub fn unclosed_braces_template(n: usize) -> String {
    let mut s = String::with_capacity(n);
    s.push_str(&"M117 "[..n.min(5)]);
    while s.len() < n {
        s.push(if s.len() % 2 == 1 { '{' } else { 'x' });
    }
    s
}

/// A template of `n` `{design_name}` placeholders (13·n bytes) on lines of 20: with a long
/// design name its expansion is about n × the name's length (a template bomb).
pub fn template_bomb(n: usize) -> String {
    let mut s = String::with_capacity(13 * n + n / 20 + 1);
    for i in 0..n {
        s.push_str("{design_name}");
        if i % 20 == 19 {
            s.push('\n');
        }
    }
    s
}

/// A design (JSON) whose name is `n` bytes (`a`…`z` repeated); the rest is the default cube.
pub fn long_name_design(n: usize) -> String {
    let name: String = (0..n).map(|i| (b'a' + (i % 26) as u8) as char).collect();
    format!(r#"{{"version":1,"name":"{name}","job":{{"kind":"slice","input":{{"builtin":{{"shape":"cube","size":[20,20,20]}}}}}}}}"#)
}

/// A `--set` assignment whose path has `n` nested keys: `job.a.a.…=1` (about 2·n bytes).
/// Applied blindly it builds objects `n` deep, which overflow the stack when dropped.
pub fn deep_set_path(n: usize) -> String {
    let mut s = String::with_capacity(2 * n + 6);
    s.push_str("job");
    for _ in 1..n.max(1) {
        s.push_str(".a");
    }
    s.push_str("=1");
    s
}

/// A design (JSON) with a value nested `n` arrays deep in its job (`"x": [[[…]]]`).
pub fn nested_design_json(n: usize) -> String {
    format!(r#"{{"version":1,"name":"deep","job":{{"kind":"slice","x":{}{}}}}}"#, "[".repeat(n), "]".repeat(n))
}

/// A share-link fragment (`#d=…`) of about `n` bytes whose design inflates about 119-fold: a
/// hand-made deflate stream (fixed Huffman codes) of a design whose name is `a` repeated by
/// 258-byte back-references, 13 bits each. Up to n ≈ 35 000 the design fits
/// [`crate::design::MAX_DESIGN_BYTES`] (and is refused for its name); beyond, the inflater
/// hits that limit.
pub fn share_bomb_fragment(n: usize) -> String {
    use base64::Engine;
    let prefix = br#"{"version":1,"job":{"kind":"slice"},"name":"a"#;
    let suffix = br#""}"#;
    // Bits available in the base64 text (6 per character) after the literals and the block's
    // header and end; each back-reference takes 13.
    let fixed_bits = 3 + 8 * (prefix.len() + suffix.len()) + 7;
    // At least one: below ~68 bytes the literals alone fill n, and that design (name "a") is
    // valid, not a bomb (a fuzz run drawing such an n saw a "bomb" decode).
    let refs = ((6 * n.saturating_sub(3)).saturating_sub(fixed_bits) / 13).max(1);
    let mut w = Bits::default();
    w.put(1, 1); // last block
    w.put(1, 2); // fixed Huffman codes
    for &b in prefix {
        w.literal(b);
    }
    for _ in 0..refs {
        w.huffman(0b1100_0101, 8); // length code 285: 258 bytes
        w.huffman(0, 5); // distance code 0: 1 byte back
    }
    for &b in suffix {
        w.literal(b);
    }
    w.huffman(0, 7); // end of block (256)
    format!("#d={}", base64::engine::general_purpose::URL_SAFE_NO_PAD.encode(w.finish()))
}

/// A little-endian bit writer (deflate's bit order).
#[derive(Default)]
struct Bits {
    bytes: Vec<u8>,
    acc: u32,
    n: u32,
}

impl Bits {
    /// `count` bits of `value`, low bit first.
    fn put(&mut self, value: u32, count: u32) {
        for i in 0..count {
            self.acc |= ((value >> i) & 1) << self.n;
            self.n += 1;
            if self.n == 8 {
                self.bytes.push(self.acc as u8);
                self.acc = 0;
                self.n = 0;
            }
        }
    }

    /// A Huffman code of `len` bits, high bit first.
    fn huffman(&mut self, code: u32, len: u32) {
        for i in (0..len).rev() {
            self.put((code >> i) & 1, 1);
        }
    }

    /// A literal byte below 144 (fixed code 0x30 + byte, 8 bits).
    fn literal(&mut self, b: u8) {
        debug_assert!(b < 144);
        self.huffman(0x30 + b as u32, 8);
    }

    fn finish(mut self) -> Vec<u8> {
        if self.n > 0 {
            self.bytes.push(self.acc as u8);
        }
        self.bytes
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_grow_linearly() {
        for n in [100, 400] {
            assert_eq!(unclosed_braces_template(n).len(), n);
            assert_eq!(template_bomb(n).matches("{design_name}").count(), n);
            assert!(long_name_design(n).len() > n && long_name_design(n).len() < n + 200);
            assert_eq!(deep_set_path(n).split('=').next().unwrap().split('.').count(), n);
            assert!(nested_design_json(n).len() > 2 * n);
            let f = share_bomb_fragment(n);
            assert!(f.len().abs_diff(n) <= 4, "{} for {n}", f.len());
        }
    }

    #[test]
    fn the_share_bomb_inflates_to_a_long_name() {
        let f = share_bomb_fragment(3000);
        let bytes = crate::design::share::unpack(&f[3..]).unwrap();
        let v: serde_json::Value = serde_json::from_slice(&bytes).unwrap();
        let name = v["name"].as_str().unwrap();
        assert!(name.len() > 100 * 3000 && name.bytes().all(|b| b == b'a'), "{}", name.len());
    }
}

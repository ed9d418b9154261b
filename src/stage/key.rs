//! Cache keys: a 128-bit hash of what a stage output was computed from.

use super::*;

/// A stage output's identity: a 128-bit hash of what it was computed from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Key(u64, u64);

impl Key {
    /// Hash of `bytes` (two independent 64-bit multiply–rotate streams, 8 bytes at a time;
    /// deterministic on every target, fast enough for 200 MB inputs).
    pub fn of_bytes(bytes: &[u8]) -> Key {
        let mut h = Hasher::new(bytes.len());
        h.words(bytes);
        h.finish(&bytes[bytes.len() / 8 * 8..])
    }

    /// [`Key::of_bytes`] of a source's bytes, read in pieces (the same key as in memory).
    pub fn of_source(source: &dyn ByteSource) -> Result<Key, String> {
        if let Some(all) = source.as_slice() {
            return Ok(Key::of_bytes(all));
        }
        let len = source.len();
        let mut h = Hasher::new(len);
        // A multiple of 8, so every piece but the last is whole words.
        let mut buf = vec![0u8; crate::source::WHOLE_PIECE_BYTES.min(len)];
        let mut offset = 0;
        while offset < len {
            let n = buf.len().min(len - offset);
            source.read_at(offset, &mut buf[..n])?;
            offset += n;
            h.words(&buf[..n]);
            if offset == len {
                return Ok(h.finish(&buf[n / 8 * 8..n]));
            }
        }
        Ok(h.finish(&[]))
    }

    /// Hash of a stage name, its design parts (as JSON) and its upstream keys.
    pub fn of(stage: &str, parts: &impl Serialize, upstream: &[Key]) -> Key {
        let mut bytes = stage.as_bytes().to_vec();
        bytes.push(0);
        bytes.extend(serde_json::to_vec(parts).unwrap_or_default());
        for k in upstream {
            bytes.extend(k.0.to_le_bytes());
            bytes.extend(k.1.to_le_bytes());
        }
        Key::of_bytes(&bytes)
    }
}

/// Two independent 64-bit multiply–rotate streams, 8 bytes at a time.
pub(super) struct Hasher {
    a: u64,
    b: u64,
}

impl Hasher {
    const K1: u64 = 0x9E37_79B9_7F4A_7C15;
    const K2: u64 = 0xC2B2_AE3D_27D4_EB4F;

    pub(super) fn new(len: usize) -> Hasher {
        Hasher { a: 0x243F_6A88_85A3_08D3u64 ^ len as u64, b: 0x1319_8A2E_0370_7344u64 }
    }

    /// The whole words of `bytes` (a trailing part of under 8 bytes is left for `finish`).
    pub(super) fn words(&mut self, bytes: &[u8]) {
        for c in bytes.chunks_exact(8) {
            let w = u64::from_le_bytes([c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]]);
            self.a = (self.a ^ w).wrapping_mul(Self::K1).rotate_left(29);
            self.b = (self.b ^ w.rotate_left(17)).wrapping_mul(Self::K2).rotate_left(31);
        }
    }

    pub(super) fn finish(mut self, tail: &[u8]) -> Key {
        for &byte in tail {
            self.a = (self.a ^ byte as u64).wrapping_mul(Self::K1).rotate_left(29);
            self.b = (self.b ^ byte as u64).wrapping_mul(Self::K2).rotate_left(31);
        }
        let (a, b) = (self.a, self.b);
        Key(fmix(a ^ b.rotate_left(32)), fmix(b ^ a))
    }
}

pub(super) fn fmix(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

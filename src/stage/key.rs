//! Cache keys: a 128-bit hash of what a stage output was computed from (XXH3-128, the
//! `xxhash-rust` crate: the same bits on every target, streamed for inputs read in pieces).

use super::*;
use xxhash_rust::xxh3::Xxh3;

/// A stage output's identity: a 128-bit hash of what it was computed from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Key(u64, u64);

impl Key {
    fn of_digest(d: u128) -> Key {
        Key((d >> 64) as u64, d as u64)
    }

    /// Hash of `bytes`.
    pub fn of_bytes(bytes: &[u8]) -> Key {
        Key::of_digest(xxhash_rust::xxh3::xxh3_128(bytes))
    }

    /// [`Key::of_bytes`] of a source's bytes, read in pieces (the same key as in memory).
    pub fn of_source(source: &dyn ByteSource) -> Result<Key, String> {
        if let Some(all) = source.as_slice() {
            return Ok(Key::of_bytes(all));
        }
        let len = source.len();
        let mut h = Xxh3::new();
        let mut buf = vec![0u8; crate::source::WHOLE_PIECE_BYTES.min(len)];
        let mut offset = 0;
        while offset < len {
            let n = buf.len().min(len - offset);
            source.read_at(offset, &mut buf[..n])?;
            h.update(&buf[..n]);
            offset += n;
        }
        Ok(Key::of_digest(h.digest128()))
    }

    /// Hash of a stage name, its design parts (as JSON) and its upstream keys.
    pub fn of(stage: &str, parts: &impl Serialize, upstream: &[Key]) -> Key {
        let mut h = Xxh3::new();
        h.update(stage.as_bytes());
        h.update(&[0]);
        h.update(&serde_json::to_vec(parts).unwrap_or_default());
        for k in upstream {
            h.update(&k.0.to_le_bytes());
            h.update(&k.1.to_le_bytes());
        }
        Key::of_digest(h.digest128())
    }
}

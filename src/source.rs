//! Bytes read in ranges: a loaded file whose bytes stay outside the core (in the browser, the
//! dropped `File` in the browser's blob store), so a 50 MB G-code is never copied whole into
//! wasm memory. Readers that go line by line take [`for_each_line_chunk`]; the others read
//! the whole file ([`read_all`]).

use std::borrow::Cow;

/// Bytes that can be read in ranges. Bytes in memory (`&[u8]`, `Vec<u8>`, `Cow<[u8]>`) are
/// one piece, borrowed, never copied.
pub trait ByteSource {
    /// Length, bytes.
    fn len(&self) -> usize;
    /// Whether there are no bytes.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Fills `buf` with the bytes at `offset..offset + buf.len()` (within [`ByteSource::len`]);
    /// an error says why they could not be read (the file was moved or deleted).
    fn read_at(&self, offset: usize, buf: &mut [u8]) -> Result<(), String>;
    /// All bytes, when they are already in memory.
    fn as_slice(&self) -> Option<&[u8]> {
        None
    }
}

impl ByteSource for &[u8] {
    fn len(&self) -> usize {
        <[u8]>::len(self)
    }
    fn read_at(&self, offset: usize, buf: &mut [u8]) -> Result<(), String> {
        let end = offset.checked_add(buf.len()).filter(|&e| e <= <[u8]>::len(self)).ok_or_else(|| "read past the end".to_string())?;
        buf.copy_from_slice(&self[offset..end]);
        Ok(())
    }
    fn as_slice(&self) -> Option<&[u8]> {
        Some(self)
    }
}

impl ByteSource for Vec<u8> {
    fn len(&self) -> usize {
        Vec::len(self)
    }
    fn read_at(&self, offset: usize, buf: &mut [u8]) -> Result<(), String> {
        self.as_slice().read_at(offset, buf)
    }
    fn as_slice(&self) -> Option<&[u8]> {
        Some(self)
    }
}

impl ByteSource for Cow<'_, [u8]> {
    fn len(&self) -> usize {
        <[u8]>::len(self)
    }
    fn read_at(&self, offset: usize, buf: &mut [u8]) -> Result<(), String> {
        (&**self).read_at(offset, buf)
    }
    fn as_slice(&self) -> Option<&[u8]> {
        Some(self)
    }
}

/// Why a chunked read stopped: the source could not be read, or the caller said stop.
#[derive(Debug)]
pub enum ChunkError<E> {
    /// The source's message.
    Read(String),
    /// The caller's error.
    Stopped(E),
}

/// Chunk size of [`for_each_line_chunk`] for sources not in memory: large enough that reading
/// costs little per byte, small beside the 50–200 MB files it is for.
pub const CHUNK_BYTES: usize = 4 << 20;

/// Piece size of [`read_all`] and of hashing a whole source: each read from the browser's
/// blob store is a round trip to the browser process, so a whole file is read in few, large
/// pieces (a 50 MB file in a worker, Chromium 148: 235–285 ms in 1 MiB pieces, 143–159 ms in
/// 4 MiB, 98–130 ms in 16 MiB, 87–114 ms in 32 MiB). The browser makes a buffer of this size
/// outside the core for each read, so it stays a small part of the file it is for.
pub const WHOLE_PIECE_BYTES: usize = 16 << 20;

/// Calls `f` with consecutive pieces of `src` that end at a line end (`\n`), the last one at the
/// end of the source; together they are the whole source, in order. A source in memory is one
/// piece (no copy); otherwise pieces are at most `chunk_bytes` (a line longer than that is split
/// across pieces: callers with a line limit below `chunk_bytes` refuse it before that matters).
/// Memory: one buffer of `chunk_bytes`.
pub fn for_each_line_chunk<E>(src: &dyn ByteSource, chunk_bytes: usize, f: &mut dyn FnMut(&[u8]) -> Result<(), E>) -> Result<(), ChunkError<E>> {
    if let Some(all) = src.as_slice() {
        return f(all).map_err(ChunkError::Stopped);
    }
    let len = src.len();
    let chunk_bytes = chunk_bytes.max(1);
    let mut buf = vec![0u8; chunk_bytes.min(len)];
    // buf[..kept] is the tail of the previous read (an unfinished line).
    let (mut offset, mut kept) = (0usize, 0usize);
    while offset < len {
        let n = (buf.len() - kept).min(len - offset);
        src.read_at(offset, &mut buf[kept..kept + n]).map_err(ChunkError::Read)?;
        offset += n;
        let filled = kept + n;
        let cut = if offset == len {
            filled
        } else {
            match memchr::memrchr(b'\n', &buf[..filled]) {
                Some(p) => p + 1,
                None => filled,
            }
        };
        f(&buf[..cut]).map_err(ChunkError::Stopped)?;
        buf.copy_within(cut..filled, 0);
        kept = filled - cut;
    }
    Ok(())
}

/// The whole of `src`: borrowed when in memory, read otherwise.
pub fn read_all(src: &dyn ByteSource) -> Result<Cow<'_, [u8]>, String> {
    if let Some(all) = src.as_slice() {
        return Ok(Cow::Borrowed(all));
    }
    // In pieces: a source outside the core (the browser's blob store) makes a buffer of its
    // own for each read, which stays small this way.
    let mut v = vec![0u8; src.len()];
    for (k, piece) in v.chunks_mut(WHOLE_PIECE_BYTES).enumerate() {
        src.read_at(k * WHOLE_PIECE_BYTES, piece)?;
    }
    Ok(Cow::Owned(v))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A source not in memory, to exercise the chunking.
    struct Far(Vec<u8>);
    impl ByteSource for Far {
        fn len(&self) -> usize {
            self.0.len()
        }
        fn read_at(&self, offset: usize, buf: &mut [u8]) -> Result<(), String> {
            self.0.read_at(offset, buf)
        }
    }

    #[test]
    fn pieces_end_at_line_ends_and_make_the_whole() {
        let text: Vec<u8> = (0..500).flat_map(|i| format!("G1 X{i} E{}\n", i * 7).into_bytes()).chain(b"M84".iter().copied()).collect();
        for chunk in [1, 7, 16, 100, 4096, 1 << 20] {
            let mut joined = Vec::new();
            let mut pieces = 0;
            for_each_line_chunk::<()>(&Far(text.clone()), chunk, &mut |p| {
                // Every piece but the last ends a line, unless a line is longer than the chunk.
                if chunk >= 16 && joined.len() + p.len() < text.len() {
                    assert_eq!(p.last(), Some(&b'\n'), "chunk {chunk}");
                }
                joined.extend_from_slice(p);
                pieces += 1;
                Ok(())
            })
            .unwrap();
            assert_eq!(joined, text, "chunk {chunk}");
            assert!(chunk < text.len() || pieces == 1);
        }
        let mut pieces = 0;
        for_each_line_chunk::<()>(&text.as_slice(), 16, &mut |_| {
            pieces += 1;
            Ok(())
        })
        .unwrap();
        assert_eq!(pieces, 1, "a slice is passed whole");
    }

    #[test]
    fn errors_of_the_source_and_the_caller_come_back() {
        struct Broken;
        impl ByteSource for Broken {
            fn len(&self) -> usize {
                10
            }
            fn read_at(&self, _: usize, _: &mut [u8]) -> Result<(), String> {
                Err("gone".into())
            }
        }
        assert!(matches!(for_each_line_chunk::<()>(&Broken, 4, &mut |_| Ok(())), Err(ChunkError::Read(m)) if m == "gone"));
        let r = for_each_line_chunk(&Far(b"a\nb\nc\n".to_vec()), 2, &mut |_| Err(7));
        assert!(matches!(r, Err(ChunkError::Stopped(7))));
        assert_eq!(read_all(&Far(b"xyz".to_vec())).unwrap().as_ref(), b"xyz");
    }

    #[test]
    fn a_whole_source_is_read_in_few_pieces_and_hashes_as_in_memory() {
        /// A source not in memory that counts its reads.
        struct Counted(Vec<u8>, std::cell::Cell<usize>);
        impl ByteSource for Counted {
            fn len(&self) -> usize {
                self.0.len()
            }
            fn read_at(&self, offset: usize, buf: &mut [u8]) -> Result<(), String> {
                self.1.set(self.1.get() + 1);
                self.0.read_at(offset, buf)
            }
        }
        let n = 2 * WHOLE_PIECE_BYTES + 13;
        let bytes: Vec<u8> = (0..n).map(|i| (i.wrapping_mul(2_654_435_761) >> 13) as u8).collect();
        let far = Counted(bytes.clone(), Default::default());
        assert!(read_all(&far).unwrap().as_ref() == bytes.as_slice());
        assert_eq!(far.1.get(), 3, "three reads for two whole pieces and a rest");
        assert_eq!(crate::stage::Key::of_source(&far).unwrap(), crate::stage::Key::of_bytes(&bytes));
        assert_eq!(far.1.get(), 6);
    }
}

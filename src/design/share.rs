//! Share links: the whole design in the URL fragment, `#d=` + base64url(deflate(JSON)).
//!
//! A design that slices an uploaded mesh carries the mesh too when the file is at most
//! [`MAX_EMBED_BYTES`]; larger meshes stay out of the link and the note says so.

use base64::engine::general_purpose::URL_SAFE_NO_PAD;
use base64::Engine;

/// Largest total size of the files embedded in a share link, bytes (256 KiB).
pub const MAX_EMBED_BYTES: usize = 256 * 1024;
/// Longest fragment accepted when opening a link, characters (2 MiB, Chromium's URL limit).
pub const MAX_FRAGMENT_CHARS: usize = 2 * 1024 * 1024;
/// Largest inflated size of an embedded file accepted ([`unpack`]), bytes. The design JSON
/// itself inflates to at most [`super::MAX_DESIGN_BYTES`].
pub const MAX_INFLATED_BYTES: usize = 16 * 1024 * 1024;
/// Longest `embedded` text (in total) a design may hold, characters: [`MAX_EMBED_BYTES`] of
/// incompressible data deflated (stored blocks add 5 bytes per 64 KiB) then in base64url
/// (4 characters per 3 bytes), with room to spare.
pub const MAX_EMBEDDED_CHARS: usize = (MAX_EMBED_BYTES + MAX_EMBED_BYTES / 1024 + 64).div_ceil(3) * 4;
/// Fragment key.
pub const FRAGMENT_KEY: &str = "d=";

/// Why a link could not be opened.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum Error {
    /// No `d=` in the fragment.
    #[error("this link has no design in it (a weft link ends in '#d=…'); ask for the link again")]
    Missing,
    /// Over [`MAX_FRAGMENT_CHARS`].
    #[error("this link is {chars} characters long, over the {MAX_FRAGMENT_CHARS}-character limit; share the design file instead")]
    TooLong {
        /// Its length.
        chars: usize,
    },
    /// A character a link's data never holds (a space, a line break, `%`…).
    #[error("this link is damaged: character {position} of its design ({}) cannot be in a link, so the link was changed while copying; copy the whole link again", shown(*found))]
    Character {
        /// 1-based character position within the data.
        position: usize,
        /// The character.
        found: char,
    },
    /// The data is cut short or altered: its length or last character is impossible, or it
    /// does not unpack, or it unpacks to something that is not text.
    #[error("this link is damaged: it was cut short or changed while copying; ask for the link again")]
    Damaged,
    /// It unpacks to more than the limit.
    #[error("this link unpacks to more than {limit} bytes, the limit for a design: it is not a weft link, or it was altered; ask for the link again or share the design file")]
    TooBig {
        /// The limit, bytes.
        limit: usize,
    },
    /// The design inside is not valid (the design's own message, naming the field).
    #[error(transparent)]
    Design(#[from] super::Error),
}

/// A character as a message quotes it: printable ones in quotes, others by name or code.
fn shown(c: char) -> String {
    match c {
        ' ' => "a space".into(),
        '\n' | '\r' => "a line break".into(),
        '\t' => "a tab".into(),
        c if c.is_control() || c.is_whitespace() => format!("the invisible character U+{:04X}", c as u32),
        c => format!("'{c}'"),
    }
}

/// base64url(deflate(bytes)), as used in links and for embedded meshes.
pub fn pack(bytes: &[u8]) -> String {
    URL_SAFE_NO_PAD.encode(miniz_oxide::deflate::compress_to_vec(bytes, 9))
}

/// Inverse of [`pack`], bounded by [`MAX_INFLATED_BYTES`].
pub fn unpack(text: &str) -> Result<Vec<u8>, Error> {
    unpack_limited(text, MAX_INFLATED_BYTES)
}

/// Inverse of [`pack`], refusing data that inflates to more than `limit` bytes (the inflater
/// stops there: a bomb costs at most `limit` bytes and the time to write them).
pub fn unpack_limited(text: &str, limit: usize) -> Result<Vec<u8>, Error> {
    if let Some((i, found)) = text.chars().enumerate().find(|&(_, c)| !(c.is_ascii_alphanumeric() || c == '-' || c == '_')) {
        return Err(Error::Character { position: i + 1, found });
    }
    // Every decoding error left (a length of 4n+1, a last character with bits past the end)
    // means characters were lost or changed.
    let raw = URL_SAFE_NO_PAD.decode(text.as_bytes()).map_err(|_| Error::Damaged)?;
    miniz_oxide::inflate::decompress_to_vec_with_limit(&raw, limit).map_err(|e| match e.status {
        miniz_oxide::inflate::TINFLStatus::HasMoreOutput => Error::TooBig { limit },
        _ => Error::Damaged,
    })
}

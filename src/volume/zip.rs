//! A zip of a folder (a DICOM series, region meshes) → its entries as a file list.
//!
//! Bounded before inflating: the central directory signatures are counted (an upper bound
//! of what the zip reader will parse) and the entries kept are checked against
//! [`MAX_FILES`]; their declared sizes add up under [`MAX_UNZIPPED_BYTES`]; and each entry
//! is inflated through a reader that stops one byte past its declared size, so an entry
//! lying about its size (the zip-bomb trick) is caught after at most that many bytes.
//! Directories, `__MACOSX/` resource forks and dot-files (`.DS_Store`) are left out; names
//! only label entries (nothing is ever written to or opened by path).

use super::read::{base_name, clean, Error, MAX_FILES, MAX_UNZIPPED_BYTES};
use std::io::{Cursor, Read};

/// An entry to read.
#[derive(Clone, Debug)]
pub(crate) struct Entry {
    /// Index in the archive.
    pub index: usize,
    /// Name (with its folders).
    pub name: String,
    /// Declared uncompressed size, bytes.
    pub size: u64,
}

fn zip_err(file: &str, message: impl Into<String>) -> Error {
    Error::Zip { file: clean(file), message: message.into() }
}

/// Entries left out: directories, macOS metadata, dot-files.
fn ignored(name: &str) -> Option<&'static str> {
    if name.ends_with('/') || name.ends_with('\\') {
        Some("a folder")
    } else if name.starts_with("__MACOSX/") || name.contains("/__MACOSX/") {
        Some("macOS metadata")
    } else if base_name(name).starts_with('.') {
        Some("a hidden file")
    } else {
        None
    }
}

/// Counts central directory headers (`PK\1\2`): every entry the zip reader parses has one.
fn count_central_headers(bytes: &[u8]) -> usize {
    bytes.windows(4).filter(|w| *w == b"PK\x01\x02").count()
}

fn open<'a>(file: &str, bytes: &'a [u8]) -> Result<::zip::ZipArchive<Cursor<&'a [u8]>>, Error> {
    // A forged directory of millions of entries costs memory in the zip reader before any
    // is read: refuse it from the signature count first (4× slack for signatures that
    // happen to sit in stored pixel data).
    if count_central_headers(bytes) > 4 * MAX_FILES {
        return Err(zip_err(file, format!("the archive lists more than {} entries; zip one folder only", 4 * MAX_FILES)));
    }
    ::zip::ZipArchive::new(Cursor::new(bytes)).map_err(|_| zip_err(file, "the zip archive cannot be opened: it is cut short or damaged; zip the folder again"))
}

/// The entries to read, checked against [`MAX_FILES`] and [`MAX_UNZIPPED_BYTES`].
pub(crate) fn list(file: &str, bytes: &[u8]) -> Result<Vec<Entry>, Error> {
    let mut zip = open(file, bytes)?;
    if zip.len() > 4 * MAX_FILES {
        return Err(zip_err(file, format!("the archive has {} entries, more than {}; zip one folder only", zip.len(), 4 * MAX_FILES)));
    }
    let mut out = Vec::new();
    let mut total: u64 = 0;
    for index in 0..zip.len() {
        let e = zip.by_index_raw(index).map_err(|_| zip_err(file, format!("entry {index} cannot be read: the archive is damaged; zip the folder again")))?;
        let name = e.name().map(|n| n.to_string()).unwrap_or_else(|_| format!("entry-{index}"));
        if e.is_dir() || ignored(&name).is_some() {
            continue;
        }
        if e.encrypted() {
            return Err(zip_err(file, format!("{} is encrypted; zip the folder without a password", clean(&name))));
        }
        total = total.saturating_add(e.size());
        out.push(Entry { index, name, size: e.size() });
    }
    if out.len() > MAX_FILES {
        return Err(zip_err(file, format!("the archive holds {} files, more than the {MAX_FILES} weft reads; zip one folder only", out.len())));
    }
    if total > MAX_UNZIPPED_BYTES {
        return Err(zip_err(
            file,
            format!(
                "the archive would unpack to {} MiB, more than the {} MiB weft unpacks (a zip bomb, or a folder too big to import); zip one folder, a series cropped if needed",
                total >> 20,
                MAX_UNZIPPED_BYTES >> 20
            ),
        ));
    }
    if out.is_empty() {
        return Err(zip_err(file, "the archive holds no files; zip the folder"));
    }
    Ok(out)
}

/// `name: reason` of the entries [`list`] leaves out (folders excepted), for the report.
pub(crate) fn skipped(bytes: &[u8]) -> Vec<String> {
    let Ok(mut zip) = ::zip::ZipArchive::new(Cursor::new(bytes)) else { return Vec::new() };
    let mut out = Vec::new();
    for index in 0..zip.len().min(4 * MAX_FILES) {
        let Ok(e) = zip.by_index_raw(index) else { continue };
        let Ok(name) = e.name().map(|n| n.to_string()) else { continue };
        if let Some(why) = ignored(&name) {
            if why != "a folder" && out.len() < 100 {
                out.push(format!("{}: {why}", clean(&name)));
            }
        }
    }
    out
}

/// Inflates `entries` (each up to `head` bytes when given, else whole). An entry inflating
/// to more than it declares, or failing its checksum, is refused.
pub(crate) fn inflate(file: &str, bytes: &[u8], entries: &[Entry], head: Option<usize>) -> Result<Vec<(String, Vec<u8>)>, Error> {
    let mut zip = open(file, bytes)?;
    let mut out = Vec::with_capacity(entries.len());
    for e in entries {
        let shown = clean(&e.name);
        let entry = zip
            .by_index(e.index)
            .map_err(|_| zip_err(file, format!("{shown} cannot be unpacked (unknown compression or damaged); zip the folder again with plain deflate")))?;
        let want = match head {
            Some(h) => e.size.min(h as u64),
            None => e.size,
        };
        let mut buf = Vec::with_capacity(want as usize);
        let mut limited = entry.take(want + 1);
        let got = limited.read_to_end(&mut buf);
        match got {
            Ok(_) if buf.len() as u64 > e.size => {
                return Err(zip_err(file, format!("{shown} unpacks to more than the {} bytes it declares (a zip bomb?); zip the folder again", e.size)));
            }
            Ok(_) if head.is_none() && (buf.len() as u64) < e.size => {
                return Err(zip_err(file, format!("{shown} unpacks to {} bytes, not the {} it declares; the archive is damaged", buf.len(), e.size)));
            }
            Ok(_) => {}
            // A head read stops early, before the checksum; a damaged entry is caught by
            // the whole read.
            Err(_) if head.is_some() => {}
            Err(_) => return Err(zip_err(file, format!("{shown} cannot be unpacked: its data is damaged; zip the folder again"))),
        }
        buf.truncate(want as usize);
        out.push((e.name.clone(), buf));
    }
    Ok(out)
}

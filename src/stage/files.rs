//! Files a run reads: held in memory or outside the core, each hashed once for cache keys.

use super::*;

/// Where a file's bytes are.
#[derive(Clone)]
pub(super) enum Content {
    /// In memory.
    Bytes(Arc<Vec<u8>>),
    /// Outside the core (the browser's blob store), read in ranges when a stage needs it.
    Far(Arc<dyn ByteSource>),
}

impl std::fmt::Debug for Content {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Content::Bytes(b) => write!(f, "Bytes({} bytes)", b.len()),
            Content::Far(s) => write!(f, "Far({} bytes)", s.len()),
        }
    }
}

/// A loaded file and the hash of its bytes (computed once, for cache keys).
#[derive(Clone, Debug)]
pub(super) struct FileEntry {
    content: Content,
    hash: Key,
}

/// Files available to a run, by name (uploaded on the page, `--input` on the CLI). Each is
/// stored once and hashed once; stages parse them lazily through [`Ctx::mesh`]. A file may
/// stay outside the core ([`Files::insert_source`]): stages that read line by line stream it
/// ([`Ctx::file_source`]), the others read it whole when they run.
#[derive(Clone, Debug, Default)]
pub struct Files {
    map: BTreeMap<String, FileEntry>,
}

/// A loaded file's bytes for a stage: in memory (borrowed, or unpacked from a share link), or
/// read in ranges from outside the core.
pub enum FileSource<'a> {
    /// In memory.
    Bytes(std::borrow::Cow<'a, [u8]>),
    /// Outside the core.
    Far(Arc<dyn ByteSource>),
}

impl ByteSource for FileSource<'_> {
    fn len(&self) -> usize {
        match self {
            FileSource::Bytes(b) => b.len(),
            FileSource::Far(s) => s.len(),
        }
    }
    fn read_at(&self, offset: usize, buf: &mut [u8]) -> Result<(), String> {
        match self {
            FileSource::Bytes(b) => b.read_at(offset, buf),
            FileSource::Far(s) => s.read_at(offset, buf),
        }
    }
    fn as_slice(&self) -> Option<&[u8]> {
        match self {
            FileSource::Bytes(b) => Some(b),
            FileSource::Far(s) => s.as_slice(),
        }
    }
}

impl Files {
    /// No files.
    pub fn new() -> Files {
        Files::default()
    }

    /// Adds (or replaces) `name`.
    pub fn insert(&mut self, name: String, bytes: Vec<u8>) {
        let hash = Key::of_bytes(&bytes);
        self.map.insert(name, FileEntry { content: Content::Bytes(Arc::new(bytes)), hash });
    }

    /// Adds (or replaces) `name`, whose bytes stay in `source` (read once now, in pieces, to
    /// hash them; the message says why they could not be read).
    pub fn insert_source(&mut self, name: String, source: Arc<dyn ByteSource>) -> Result<(), String> {
        let hash = Key::of_source(&*source)?;
        self.map.insert(name, FileEntry { content: Content::Far(source), hash });
        Ok(())
    }

    /// Removes `name`; whether it was there.
    pub fn remove(&mut self, name: &str) -> bool {
        self.map.remove(name).is_some()
    }

    /// The bytes of `name`, when they are in memory.
    pub fn get(&self, name: &str) -> Option<&[u8]> {
        self.map.get(name).and_then(|e| match &e.content {
            Content::Bytes(b) => Some(b.as_slice()),
            Content::Far(_) => None,
        })
    }

    /// The bytes of `name`, wherever they are.
    pub fn source(&self, name: &str) -> Option<FileSource<'_>> {
        self.map.get(name).map(|e| match &e.content {
            Content::Bytes(b) => FileSource::Bytes(std::borrow::Cow::Borrowed(b.as_slice())),
            Content::Far(s) => FileSource::Far(s.clone()),
        })
    }

    /// All the bytes of `name`: borrowed when in memory, read when not.
    pub(super) fn whole(&self, name: &str) -> Option<Result<std::borrow::Cow<'_, [u8]>, Error>> {
        self.map.get(name).map(|e| match &e.content {
            Content::Bytes(b) => Ok(std::borrow::Cow::Borrowed(b.as_slice())),
            Content::Far(s) => crate::source::read_all(&**s)
                .map(|b| std::borrow::Cow::Owned(b.into_owned()))
                .map_err(|message| Error::Unreadable { name: name.to_string(), message }),
        })
    }

    /// The size of `name` in bytes, known without reading it.
    pub fn size(&self, name: &str) -> Option<usize> {
        self.map.get(name).map(|e| match &e.content {
            Content::Bytes(b) => b.len(),
            Content::Far(s) => s.len(),
        })
    }

    /// Whether `name` is loaded.
    pub fn contains(&self, name: &str) -> bool {
        self.map.contains_key(name)
    }

    /// Names, sorted.
    pub fn names(&self) -> impl Iterator<Item = &str> {
        self.map.keys().map(String::as_str)
    }

    pub(super) fn hash(&self, name: &str) -> Option<Key> {
        self.map.get(name).map(|e| e.hash)
    }
}

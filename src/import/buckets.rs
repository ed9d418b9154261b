//! Parallel building blocks of the importer: passes over items in fixed chunks, arrays kept in
//! chunks, and hash partitioning (records spread over buckets small enough that one bucket's
//! table stays in a core's cache, each bucket then worked on its own, on every core).
//!
//! Why partition: one table over millions of keys misses the caches on almost every lookup,
//! and more so the bigger it is, so the cleaner grew faster than its input (4× the triangles
//! took 6–7× the time). Why chunks: a large array's pages are mapped when first written
//! (about 0.4 ms a MB natively), so arrays are made in chunks by the threads that fill them.
//! Every result made here is a function of the items alone (the first of a group, a flag, a
//! count), never of the bucket layout or the thread count, so the output is the same bytes
//! however the work is split.

use crate::par;
use std::ops::Range;
use std::sync::atomic::{AtomicU32, AtomicUsize, Ordering};

/// Items per chunk: the unit of work spread over the threads (fixed, so the chunks never
/// depend on the thread count) and of chunked arrays.
pub(super) const CHUNK: usize = 1 << 16;

/// Records a bucket holds on average: a bucket's records and table fit a core's L2.
const PER_BUCKET: usize = 1 << 13;

/// Most buckets: scattering into more streams than the TLB covers would miss on every write.
const MAX_BUCKETS: usize = 1 << 10;

/// Items per chunk of [`partition`]: a chunk's records and their sorting stay in cache.
const PART_CHUNK: usize = 1 << 13;

/// The chunks of `0..n` of `size` items (at least one, maybe empty).
fn chunks_of(n: usize, size: usize) -> Vec<Range<usize>> {
    (0..n.div_ceil(size).max(1)).map(|c| c * size..((c + 1) * size).min(n)).collect()
}

/// `f(range)` for the chunks of `0..n` of [`CHUNK`] items, on every core; the results in
/// chunk order (none when `n` is 0).
pub(super) fn map_chunks<R, F>(n: usize, f: F) -> Vec<R>
where
    R: Send,
    F: Fn(Range<usize>) -> R + Sync,
{
    par::map_chunks(n, CHUNK, f)
}

/// [`map_chunks`] with a scratch value (a table, a buffer) reused along a run of chunks.
pub(super) fn map_chunks_with<R, S, F>(n: usize, f: F) -> Vec<R>
where
    R: Send,
    S: Default,
    F: Fn(Range<usize>, &mut S) -> R + Sync,
{
    map_chunks_of(n, CHUNK, f)
}

/// [`map_chunks_with`] over chunks of `size` items.
fn map_chunks_of<R, S, F>(n: usize, size: usize, f: F) -> Vec<R>
where
    R: Send,
    S: Default,
    F: Fn(Range<usize>, &mut S) -> R + Sync,
{
    let ranges = chunks_of(n, size);
    let runs = (4 * par::threads()).min(ranges.len());
    par::map_runs(ranges.len(), runs, &mut |_| {}, |cs, tick| {
        let mut scratch = S::default();
        cs.map(|c| {
            let r = f(ranges.get(c).cloned().unwrap_or_default(), &mut scratch);
            tick();
            r
        })
        .collect()
    })
}

/// An array of `n` items held in chunks of [`CHUNK`], each made (and its memory first
/// touched) by the thread that fills it.
pub(super) struct Chunked<T> {
    len: usize,
    parts: Vec<Vec<T>>,
}

impl<T: Send> Chunked<T> {
    /// `f(range)` gives the items of each chunk (exactly `range.len()` of them).
    pub fn new(n: usize, f: impl Fn(Range<usize>) -> Vec<T> + Sync) -> Self {
        Chunked { len: n, parts: map_chunks(n, f) }
    }

    /// Number of items.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Item `i`.
    #[inline]
    pub fn get(&self, i: usize) -> Option<&T> {
        self.parts.get(i / CHUNK)?.get(i % CHUNK)
    }
}

/// A chunked array of `u32` that the threads may write, each slot by one writer only (so its
/// content is the same at any thread count). Relaxed atomics are plain loads and stores.
pub(super) struct Words(Chunked<AtomicU32>);

impl Words {
    /// `n` words, word `i` = `f(i)`.
    pub fn new(n: usize, f: impl Fn(usize) -> u32 + Sync) -> Self {
        Words(Chunked::new(n, |range| range.map(|i| AtomicU32::new(f(i))).collect()))
    }

    /// The words of `parts` (each [`CHUNK`] long but the last), in place.
    pub fn from_parts(parts: Vec<Vec<u32>>) -> Self {
        let len = parts.iter().map(Vec::len).sum();
        // Same size and alignment: each part is converted where it lies, not copied.
        Words(Chunked { len, parts: parts.into_iter().map(|p| p.into_iter().map(AtomicU32::new).collect()).collect() })
    }

    /// Word `i` (`u32::MAX` out of range).
    #[inline]
    pub fn get(&self, i: usize) -> u32 {
        self.0.get(i).map_or(u32::MAX, |w| w.load(Ordering::Relaxed))
    }

    /// Sets word `i`.
    #[inline]
    pub fn set(&self, i: usize, value: u32) {
        if let Some(w) = self.0.get(i) {
            w.store(value, Ordering::Relaxed);
        }
    }
}

/// Buckets (a power of two) for about `records` records.
pub(super) fn bucket_count(records: usize) -> usize {
    (records / PER_BUCKET).next_power_of_two().clamp(1, MAX_BUCKETS)
}

/// The bucket of hash `h` among `buckets` (a power of two): its top bits, so the low bits
/// stay free for a bucket's own table.
#[inline]
pub(super) fn bucket_of(h: u64, buckets: usize) -> usize {
    match buckets.trailing_zeros() {
        0 => 0,
        bits => (h >> (64 - bits)) as usize,
    }
}

/// Records grouped by bucket, in item order within a bucket (and, for one item, in the order
/// it emitted them): each chunk of items keeps its records sorted by bucket, with offsets.
pub(super) struct Buckets {
    count: usize,
    chunks: Vec<(Vec<u64>, Vec<u32>)>,
}

impl Buckets {
    /// Number of buckets.
    pub fn len(&self) -> usize {
        self.count
    }

    /// Replaces `out` by bucket `b`'s records.
    pub fn read(&self, b: usize, out: &mut Vec<u64>) {
        out.clear();
        for (records, offsets) in &self.chunks {
            if let (Some(&lo), Some(&hi)) = (offsets.get(b), offsets.get(b + 1)) {
                out.extend_from_slice(records.get(lo as usize..hi as usize).unwrap_or_default());
            }
        }
    }
}

/// Spreads the records items `0..n` emit over `buckets` buckets: `emit(i, out)` writes item
/// `i`'s (bucket, record) pairs to `out` and returns how many (at most `K`). One pass over the
/// items in chunks, on every core, each chunk sorting its own records by bucket in cache
/// (8 bytes a record, 4 a bucket and chunk). `None` when there are more than `limit` records
/// in all, found before they are all held: the chunks add their counts as they finish, so
/// the one that passes the limit sees it (which one depends on the threads; whether one
/// does, only on the items).
pub(super) fn partition<const K: usize, F>(n: usize, buckets: usize, limit: usize, emit: F) -> Option<Buckets>
where
    F: Fn(usize, &mut [(usize, u64); K]) -> usize + Sync,
{
    let buckets = buckets.max(1);
    let total = AtomicUsize::new(0);
    let chunks = map_chunks_of(n, PART_CHUNK, |range, emitted: &mut Vec<(u32, u64)>| {
        emitted.clear();
        let mut out = [(0, 0); K];
        let mut offsets = vec![0u32; buckets + 1];
        for i in range {
            let k = emit(i, &mut out);
            for &(b, r) in out.iter().take(k) {
                emitted.push((b as u32, r));
                if let Some(c) = offsets.get_mut(b + 1) {
                    *c += 1;
                }
            }
        }
        if total.fetch_add(emitted.len(), Ordering::Relaxed).saturating_add(emitted.len()) > limit {
            return None;
        }
        for b in 0..buckets {
            let before = offsets.get(b).copied().unwrap_or(0);
            if let Some(o) = offsets.get_mut(b + 1) {
                *o += before;
            }
        }
        let mut cursor = offsets.clone();
        let mut records = vec![0u64; emitted.len()];
        for &(b, r) in emitted.iter() {
            if let Some(at) = cursor.get_mut(b as usize) {
                if let Some(slot) = records.get_mut(*at as usize) {
                    *slot = r;
                }
                *at += 1;
            }
        }
        Some((records, offsets))
    });
    let chunks = chunks.into_iter().collect::<Option<Vec<_>>>()?;
    Some(Buckets { count: buckets, chunks })
}

/// `f(records, scratch)` for every bucket's records, on every core, the results in bucket
/// order; `scratch` is reused along a run of buckets.
pub(super) fn each_bucket<R, S, F>(buckets: &Buckets, f: F) -> Vec<R>
where
    R: Send,
    S: Default,
    F: Fn(&[u64], &mut S) -> R + Sync,
{
    let n = buckets.len();
    let runs = (4 * par::threads()).min(n);
    par::map_runs(n, runs, &mut |_| {}, |range, tick| {
        let (mut records, mut scratch) = (Vec::new(), S::default());
        range
            .map(|b| {
                buckets.read(b, &mut records);
                let r = f(&records, &mut scratch);
                tick();
                r
            })
            .collect()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn partition_keeps_item_order_in_each_bucket() {
        for n in [0usize, 1, 5, CHUNK + 3, 3 * CHUNK] {
            let buckets = 8;
            let p = partition::<2, _>(n, buckets, usize::MAX, |i, out| {
                out[0] = (i % buckets, i as u64);
                out[1] = ((i * 7 + 1) % buckets, (i as u64) << 32);
                1 + usize::from(i % 3 == 0)
            })
            .unwrap();
            assert_eq!(p.len(), buckets);
            let (mut total, mut recs) = (0, Vec::new());
            for b in 0..buckets {
                p.read(b, &mut recs);
                total += recs.len();
                let items: Vec<u64> = recs.iter().map(|&r| if r >> 32 != 0 { r >> 32 } else { r }).collect();
                assert!(items.windows(2).all(|w| w[0] <= w[1]), "bucket {b} out of order");
            }
            assert_eq!(total, n + n.div_ceil(3));
            let two = |_: usize, out: &mut [(usize, u64); 2]| {
                out[1] = (0, 0);
                2
            };
            assert!(partition::<2, _>(n, buckets, (2 * n).saturating_sub(1), two).is_none() || n == 0);
            assert!(partition::<2, _>(n, buckets, 2 * n, two).is_some());
        }
    }

    #[test]
    fn chunked_arrays_and_buckets() {
        let n = 3 * CHUNK + 10;
        let w = Words::new(n, |i| i as u32 * 2);
        assert_eq!((w.get(0), w.get(CHUNK + 1), w.get(n - 1), w.get(n)), (0, 2 * CHUNK as u32 + 2, 2 * (n as u32 - 1), u32::MAX));
        w.set(5, 7);
        assert_eq!(w.get(5), 7);
        let p = Words::from_parts(vec![(0..CHUNK as u32).collect(), vec![9, 8]]);
        assert_eq!((p.get(3), p.get(CHUNK), p.get(CHUNK + 1), p.get(CHUNK + 2)), (3, 9, 8, u32::MAX));
        assert_eq!(bucket_of(u64::MAX, 1), 0);
        assert_eq!(bucket_of(u64::MAX, 1024), 1023);
        assert_eq!(bucket_count(0), 1);
    }
}

//! A count of the work done on the calling thread: the items the inner loops of weft's
//! scanners, searches and indexes visit (bytes scanned, candidates tested, cells entered).
//!
//! The tests' growth checks ("this stage is linear in its input") read it instead of a
//! clock: the same input gives the same count on any machine under any load, so the verdict
//! cannot depend on what else the machine is doing. Times are reported by `weft bench`.
//!
//! Loops add in batches (a scan adds the bytes it passed over, a query the candidates it
//! tested), so counting costs one thread-local add per batch. Work that a parallel loop
//! hands to other threads is counted on those threads: a check runs its work on a pool of
//! one thread and reads the count there.

use std::cell::Cell;

thread_local! {
    static DONE: Cell<u64> = const { Cell::new(0) };
}

/// Counts `items` of work on this thread.
#[inline]
pub fn add(items: usize) {
    DONE.with(|c| c.set(c.get().wrapping_add(items as u64)));
}

/// The work counted on this thread so far.
pub fn done() -> u64 {
    DONE.with(Cell::get)
}

#[cfg(test)]
mod tests {
    #[test]
    fn counts_per_thread() {
        let before = super::done();
        super::add(3);
        super::add(4);
        assert_eq!(super::done() - before, 7);
        let other = std::thread::spawn(|| {
            super::add(5);
            super::done()
        })
        .join()
        .unwrap();
        assert_eq!(other, 5);
        assert_eq!(super::done() - before, 7);
    }
}

//! Deterministic measures of work for the growth checks: no test here asserts on time.
//!
//! [`measure`] runs a closure on a rayon pool of one thread of its own (every parallel loop
//! of weft then runs on that thread) and reads there
//! - the items weft's inner loops counted (`weft::work`: bytes scanned, candidates tested),
//! - the heap allocations made on that thread, their bytes and the peak of live bytes, from
//!   the counting allocator of this test binary ([`Counting`]).
//!
//! The same input gives the same counts on any machine under any load, so a check such as
//! "import grows linearly" gives one verdict everywhere. Times live in `weft bench --scaling`
//! and BENCHMARKS.md.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::sync::atomic::{AtomicI64, AtomicU32, AtomicU64, Ordering::Relaxed};

/// The test binary's allocator: the system's, counting what threads tagged by [`measure`]
/// allocate (a thread-local tag, so the tests running beside it on other threads do not
/// count).
pub struct Counting;

/// Slots of counters, one a measurement in progress (slot 0 is "not counted").
const SLOTS: usize = 32;

struct Slot {
    allocs: AtomicU64,
    bytes: AtomicU64,
    live: AtomicI64,
    peak: AtomicI64,
}

#[allow(clippy::declare_interior_mutable_const)]
const EMPTY: Slot = Slot { allocs: AtomicU64::new(0), bytes: AtomicU64::new(0), live: AtomicI64::new(0), peak: AtomicI64::new(0) };
static COUNTS: [Slot; SLOTS] = [EMPTY; SLOTS];
/// Bit i set: slot i is taken (bit 0 always).
static TAKEN: AtomicU32 = AtomicU32::new(1);

thread_local! {
    static TAG: Cell<usize> = const { Cell::new(0) };
}

fn tag() -> usize {
    TAG.try_with(Cell::get).unwrap_or(0)
}

fn on_alloc(size: usize) {
    let t = tag();
    if t != 0 {
        let s = &COUNTS[t];
        s.allocs.fetch_add(1, Relaxed);
        s.bytes.fetch_add(size as u64, Relaxed);
        let live = s.live.fetch_add(size as i64, Relaxed) + size as i64;
        s.peak.fetch_max(live, Relaxed);
    }
}

fn on_free(size: usize) {
    let t = tag();
    if t != 0 {
        COUNTS[t].live.fetch_sub(size as i64, Relaxed);
    }
}

// The only unsafe code of the tests: a global allocator must be an `unsafe impl`. Every call
// goes straight to the system allocator with the caller's arguments.
#[allow(unsafe_code)]
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        on_alloc(layout.size());
        // SAFETY: the caller's layout, passed on unchanged.
        unsafe { System.alloc(layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        on_alloc(layout.size());
        // SAFETY: as above.
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        on_free(layout.size());
        // SAFETY: `ptr` was allocated by `System` with this layout (every allocation of this
        // binary goes through here).
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        on_free(layout.size());
        on_alloc(new_size);
        // SAFETY: as for dealloc; the new size is the caller's.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

/// What one run of a closure did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Work {
    /// Items counted by weft's inner loops (`weft::work`).
    pub items: u64,
    /// Heap allocations (a reallocation counts as one).
    pub allocs: u64,
    /// Bytes those allocations asked for.
    pub bytes: u64,
    /// The highest live heap of the run, bytes over where it started.
    pub peak: u64,
}

/// Takes a free slot of counters (waits while every slot is in use).
fn take_slot() -> usize {
    loop {
        let taken = TAKEN.load(Relaxed);
        let free = (!taken).trailing_zeros() as usize;
        if free < SLOTS && TAKEN.compare_exchange(taken, taken | (1 << free), Relaxed, Relaxed).is_ok() {
            return free;
        }
        if free >= SLOTS {
            std::thread::yield_now();
        }
    }
}

/// Runs `f` on a pool of one thread of its own and returns what it did ([`Work`]) and its
/// result. The counts are the same on every run of the same input.
pub fn measure<R: Send>(f: impl FnOnce() -> R + Send) -> (Work, R) {
    let slot = take_slot();
    // The pool's thread leaves the slot (untags itself) on its way out and says so: the slot is
    // free for the next measurement only then, so nothing the thread frees or allocates while
    // it ends counts in another measurement that took the same slot.
    let (left, gone) = std::sync::mpsc::channel::<()>();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .start_handler(move |_| TAG.with(|t| t.set(slot)))
        .exit_handler(move |_| {
            TAG.with(|t| t.set(0));
            let _ = left.send(());
        })
        .build()
        .expect("a pool of one thread");
    let out = pool.install(|| {
        let c = &COUNTS[slot];
        for a in [&c.allocs, &c.bytes] {
            a.store(0, Relaxed);
        }
        c.live.store(0, Relaxed);
        c.peak.store(0, Relaxed);
        let items = weft::work::done();
        let r = f();
        let w =
            Work { items: weft::work::done() - items, allocs: c.allocs.load(Relaxed), bytes: c.bytes.load(Relaxed), peak: c.peak.load(Relaxed).max(0) as u64 };
        (w, r)
    });
    drop(pool);
    // Err: the thread ended without its exit handler (it panicked); it counts nothing more.
    let _ = gone.recv();
    TAKEN.fetch_and(!(1 << slot), Relaxed);
    out
}

/// [`measure`] without the result.
pub fn work(f: impl FnOnce() + Send) -> Work {
    measure(f).0
}

/// The allowed growth of a linear measure when the input grows `k` times: room for
/// n·log n and for a vector's doubling landing on the other side of a power of two
/// (`k^1.25 × 1.6`: 9.1 at k = 4, 21.5 at k = 8, where quadratic growth gives 16 and 64).
pub fn linear_limit(k: f64) -> f64 {
    k.powf(1.25) * 1.6
}

/// Asserts that every measure of `big` is within [`linear_limit`] of `small`'s when the input
/// grew `k` times. Items are checked where the code under test counts them; allocations
/// always (a run that allocates nothing at the small size must allocate nothing at the big
/// one either). Prints both rows.
pub fn assert_linear(name: &str, k: f64, small: Work, big: Work) {
    println!("{name}: n {small:?}; {k:.1}n {big:?}");
    let limit = linear_limit(k);
    for (what, a, b) in [
        ("items counted", small.items, big.items),
        ("allocations", small.allocs, big.allocs),
        ("bytes allocated", small.bytes, big.bytes),
        ("peak live bytes", small.peak, big.peak),
    ] {
        // A handful of fixed allocations at the small size would make any ratio look large:
        // the measure counts from 64 up.
        let ratio = b as f64 / (a.max(64)) as f64;
        assert!(ratio < limit, "{name}: {what} grew {ratio:.1}× ({a} → {b}) for {k:.1}× the input (limit {limit:.1}): not linear");
    }
}

/// Measures `run` on `small` and `big` and asserts linear growth ([`assert_linear`]).
pub fn assert_linear_run<T: Sync>(name: &str, k: f64, small: &T, big: &T, run: impl Fn(&T) + Sync) {
    let (a, b) = (work(|| run(small)), work(|| run(big)));
    assert_linear(name, k, a, b);
}

#[test]
fn counts_are_the_same_on_every_run_and_only_the_measured_thread_counts() {
    let make = || {
        let v: Vec<u64> = (0..10_000).collect();
        weft::work::add(v.len());
        let s: Vec<String> = v.iter().map(|i| i.to_string()).collect();
        std::hint::black_box(s.len())
    };
    let (a, b) = (work(|| _ = make()), work(|| _ = make()));
    assert_eq!(a, b);
    assert_eq!(a.items, 10_000);
    assert!(a.allocs >= 10_001 && a.bytes >= 80_000, "{a:?}");
    // The same work on the test's own thread is not counted by a measurement beside it.
    let idle = work(|| ());
    assert_eq!(idle.items, 0);
    assert!(idle.allocs < 8, "{idle:?}");
}

#[test]
fn a_quadratic_loop_fails_the_check() {
    let quadratic = |n: &usize| {
        for i in 0..*n {
            weft::work::add(i);
        }
    };
    let (a, b) = (work(|| quadratic(&1000)), work(|| quadratic(&4000)));
    let r = std::panic::catch_unwind(|| assert_linear("quadratic", 4.0, a, b));
    assert!(r.is_err(), "{a:?} {b:?}");
    let linear = |n: &usize| weft::work::add(*n);
    assert_linear_run("linear", 4.0, &1000, &4000, linear);
}

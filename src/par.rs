//! Parallel loops over independent items, with the output of a sequential loop.
//!
//! Every stage that works item by item (layers, beams, queries) goes through these two
//! functions. The results come back in item order and each item is computed from its index
//! alone (an item that needs randomness seeds it from the design's seed and its index), so the
//! output is the same bytes at any thread count. Natively the items run on rayon's pool (the
//! CLI sizes it: `weft run --threads N`; a test runs in `ThreadPool::install`). In the browser
//! the `wasm-threads` build runs them on rayon's pool of web workers sharing the module's
//! memory (wasm-bindgen-rayon; the page sizes it); the plain wasm build, for pages that are not
//! cross-origin isolated, runs the same loops on its one thread.
//!
//! Progress stays on the calling thread: a stage's progress callback is not `Send` (the
//! worker's posts messages), so the caller reads a counter of finished items when a run ends
//! (or every 20 ms natively; wasm has no clock for a timed wait, so there at each run's end)
//! while the pool works, and runs pending items itself when it is one of the pool's threads.

use std::ops::Range;
#[cfg(any(not(target_arch = "wasm32"), feature = "wasm-threads"))]
use std::sync::atomic::{AtomicUsize, Ordering};

/// Cancel in the browser's threaded module: the page sets this word of the shared memory
/// (its address is `cancelFlagAddress()`), then terminates the worker and its pool. A worker
/// busy in wasm is only killed two seconds after `terminate()` (Chromium's forcible
/// termination delay), so the loops stop by themselves: runs not yet started are skipped,
/// and the caller, instead of going on with missing results, sleeps until it is killed. The
/// worker's progress callback throws on it too (`src/wasm.rs`). Never set natively.
static CANCELLED: std::sync::atomic::AtomicU32 = std::sync::atomic::AtomicU32::new(0);

/// The cancel word (see `CANCELLED`): the wasm boundary hands its address to the page.
pub fn cancel_flag() -> &'static std::sync::atomic::AtomicU32 {
    &CANCELLED
}

/// Whether the page has cancelled this run (always false natively).
pub fn cancelled() -> bool {
    CANCELLED.load(std::sync::atomic::Ordering::Relaxed) != 0
}

/// Threads the loops of this thread use (1 in the plain wasm build).
pub fn threads() -> usize {
    #[cfg(any(not(target_arch = "wasm32"), feature = "wasm-threads"))]
    {
        rayon::current_num_threads()
    }
    #[cfg(all(target_arch = "wasm32", not(feature = "wasm-threads")))]
    {
        1
    }
}

/// `f(i)` for every `i` in `0..n`, in order; `progress(done)` as items finish.
pub fn map<R, F>(n: usize, progress: &mut dyn FnMut(usize), f: F) -> Vec<R>
where
    R: Send,
    F: Fn(usize) -> R + Sync,
{
    // Sixteen runs a thread: enough for items of uneven cost to even out, few enough that
    // spawning and waking (microseconds each) stay small beside short items (a pair's
    // geodesic, a node).
    let runs = n.min(16 * threads());
    map_runs(n, runs, progress, |range, tick| {
        range
            .map(|i| {
                let r = f(i);
                tick();
                r
            })
            .collect()
    })
}

/// Items `0..n` cut into `runs` contiguous runs of about equal length: `f(range, tick)` makes
/// the results of one run, in order, calling `tick()` after each item; the runs' results are
/// joined in order. For items that share set-up work along a run (a plane sweep over layers).
pub fn map_runs<R, F>(n: usize, runs: usize, progress: &mut dyn FnMut(usize), f: F) -> Vec<R>
where
    R: Send,
    F: Fn(Range<usize>, &dyn Fn()) -> Vec<R> + Sync,
{
    let runs = runs.clamp(1, n.max(1));
    let bounds: Vec<Range<usize>> = (0..runs).map(|k| k * n / runs..(k + 1) * n / runs).filter(|r| !r.is_empty()).collect();
    if threads() <= 1 || bounds.len() <= 1 {
        // One thread: the ticks report (about every hundredth of the items).
        let step = (n / 100).max(1);
        let done = std::cell::Cell::new(0usize);
        let progress = std::cell::RefCell::new(progress);
        let tick = || {
            done.set(done.get() + 1);
            if done.get() % step == 0 {
                (progress.borrow_mut())(done.get());
            }
        };
        let mut out = Vec::with_capacity(n);
        for r in bounds {
            out.extend(f(r, &tick));
        }
        (progress.borrow_mut())(done.get());
        return out;
    }
    #[cfg(all(target_arch = "wasm32", not(feature = "wasm-threads")))]
    unreachable!("one thread in the plain wasm build");
    #[cfg(any(not(target_arch = "wasm32"), feature = "wasm-threads"))]
    {
        /// Counts a run as ended however it ends (a panic is raised again by the scope), and
        /// wakes the caller.
        struct Ended<'a>(&'a AtomicUsize, std::sync::mpsc::Sender<()>);
        impl Drop for Ended<'_> {
            fn drop(&mut self) {
                self.0.fetch_add(1, Ordering::Release);
                let _ = self.1.send(());
            }
        }
        let done = AtomicUsize::new(0);
        let ended = AtomicUsize::new(0);
        let runs = bounds.len();
        let mut parts: Vec<Option<Vec<R>>> = (0..runs).map(|_| None).collect();
        let f = &f;
        let (done_ref, ended_ref) = (&done, &ended);
        let (wake, woken) = std::sync::mpsc::channel::<()>();
        let in_pool = rayon::current_thread_index().is_some();
        rayon::in_place_scope(|s| {
            for (slot, r) in parts.iter_mut().zip(bounds.iter().cloned()) {
                let wake = wake.clone();
                s.spawn(move |_| {
                    let _end = Ended(ended_ref, wake);
                    if cancelled() {
                        return;
                    }
                    *slot = Some(f(r, &|| {
                        done_ref.fetch_add(1, Ordering::Relaxed);
                    }))
                });
            }
            // Report while the pool works: woken by each run's end, or every 20 ms. A pool
            // thread helps with the runs instead of waiting (a 1-thread pool would otherwise
            // never run them).
            let mut last = usize::MAX;
            loop {
                let over = ended.load(Ordering::Acquire) >= runs;
                let d = done.load(Ordering::Relaxed);
                if d != last {
                    progress(d);
                    last = d;
                }
                if over {
                    break;
                }
                if in_pool && matches!(rayon::yield_now(), Some(rayon::Yield::Executed)) {
                    continue;
                }
                #[cfg(not(target_arch = "wasm32"))]
                {
                    let wait = if in_pool { 1 } else { 20 };
                    let _ = woken.recv_timeout(std::time::Duration::from_millis(wait));
                }
                // std's timed wait reads a clock wasm32-unknown-unknown does not have (it
                // panics): sleep until a run ends. A pool thread gets here only when no run
                // was left for it to take, so every run not ended is on another thread.
                #[cfg(target_arch = "wasm32")]
                {
                    let _ = woken.recv();
                }
            }
        });
        if cancelled() {
            // Some runs were skipped: let the progress callback stop the run (it throws in
            // the browser), else sleep until the page's terminate() ends this worker.
            progress(done.load(Ordering::Relaxed));
            loop {
                std::thread::park();
            }
        }
        parts.into_iter().flat_map(|p| p.unwrap_or_default()).collect()
    }
}

/// `f()` run on one of the pool's threads, this thread sleeping until it returns (when it is
/// not a pool thread already and there is more than one thread; else `f()` here). For a
/// stretch of short parallel rounds: from a pool thread, a round's runs go to that thread's
/// own queue and it works on them too, where an outside caller is one thread more than the
/// pool, woken at every run's end (in the browser through `Atomics.wait`, at a cost that
/// short rounds feel). `f` cannot report progress (the caller's callback is not `Send`):
/// keep stretches short and report between them.
pub fn on_pool<R: Send>(f: impl FnOnce() -> R + Send) -> R {
    #[cfg(any(not(target_arch = "wasm32"), feature = "wasm-threads"))]
    if threads() > 1 && rayon::current_thread_index().is_none() {
        return rayon::scope(|_| f());
    }
    f()
}

/// Whether the calling thread may hand work to the pool and wait for its results in a
/// pipeline of its own ([`recv`], [`ordered`]): more than one thread. A pool thread may too,
/// in the browser as well, where it has no timed wait: [`recv`] blocks only when the pool has
/// no pending work left, so every task waited for is running on another thread; the tasks of
/// these pipelines wait for nothing themselves, so that thread finishes them.
pub fn can_wait_on_pool() -> bool {
    threads() > 1
}

/// The next result from work spawned on the pool (`rayon::scope`): a pool thread runs
/// pending work while none is ready (a small pool might otherwise have no thread left for
/// it), any other thread sleeps until one comes. `None` once every sender is gone.
#[cfg(any(not(target_arch = "wasm32"), feature = "wasm-threads"))]
pub fn recv<T>(rx: &std::sync::mpsc::Receiver<T>) -> Option<T> {
    use std::sync::mpsc::TryRecvError;
    let in_pool = rayon::current_thread_index().is_some();
    loop {
        match rx.try_recv() {
            Ok(v) => return Some(v),
            Err(TryRecvError::Disconnected) => return None,
            Err(TryRecvError::Empty) => {}
        }
        if !in_pool {
            return rx.recv().ok();
        }
        if matches!(rayon::yield_now(), Some(rayon::Yield::Executed)) {
            continue;
        }
        #[cfg(not(target_arch = "wasm32"))]
        match rx.recv_timeout(std::time::Duration::from_millis(1)) {
            Ok(v) => return Some(v),
            Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => return None,
            Err(std::sync::mpsc::RecvTimeoutError::Timeout) => {}
        }
        // std's timed wait reads a clock wasm32-unknown-unknown does not have. A pool thread
        // gets here (the analyzer's interpreter runs on one) only when no work was left for
        // it to run, so every task it spawned and waits for is running on another thread:
        // wait for its result without a timeout.
        #[cfg(target_arch = "wasm32")]
        return rx.recv().ok();
    }
}

/// A task's answer on a channel, `(index, Some(result))`; a task that ends without one (it
/// was skipped, or it panicked) answers `(index, None)` as its `Reply` drops, so whoever
/// waits for it never waits forever.
#[cfg(any(not(target_arch = "wasm32"), feature = "wasm-threads"))]
pub(crate) struct Reply<T> {
    tx: std::sync::mpsc::Sender<(usize, Option<T>)>,
    index: usize,
    sent: bool,
}

#[cfg(any(not(target_arch = "wasm32"), feature = "wasm-threads"))]
impl<T> Reply<T> {
    /// The answer of task `index`, to be sent on `tx`.
    pub(crate) fn new(tx: &std::sync::mpsc::Sender<(usize, Option<T>)>, index: usize) -> Self {
        Reply { tx: tx.clone(), index, sent: false }
    }

    /// Answers with `value`.
    pub(crate) fn send(mut self, value: T) {
        self.sent = self.tx.send((self.index, Some(value))).is_ok();
    }
}

#[cfg(any(not(target_arch = "wasm32"), feature = "wasm-threads"))]
impl<T> Drop for Reply<T> {
    fn drop(&mut self) {
        if !self.sent {
            let _ = self.tx.send((self.index, None));
        }
    }
}

/// `produce(k)` for every `k` in `0..n` on the pool, and `consume(k, result)` on this thread in
/// order of `k` as the results come: a pipeline whose second stage is sequential (sums in a
/// fixed order). At most `ahead` items past the one being consumed are produced or waiting, so
/// the memory in flight is bounded. On one thread (or where [`can_wait_on_pool`] says no) it
/// is the plain loop. `consume` returning `Err` stops it (items not started are skipped).
pub fn ordered<R, E, P, C>(n: usize, ahead: usize, produce: P, mut consume: C) -> Result<(), E>
where
    R: Send,
    P: Fn(usize) -> R + Sync,
    C: FnMut(usize, R) -> Result<(), E>,
{
    #[cfg(any(not(target_arch = "wasm32"), feature = "wasm-threads"))]
    if n > 1 && can_wait_on_pool() {
        use std::sync::atomic::AtomicBool;
        let stop = AtomicBool::new(false);
        let (tx, rx) = std::sync::mpsc::channel::<(usize, Option<R>)>();
        let (produce, stop) = (&produce, &stop);
        return rayon::in_place_scope(|s| {
            let mut waiting: std::collections::VecDeque<Option<R>> = std::collections::VecDeque::new();
            let mut spawned = 0;
            for k in 0..n {
                while spawned < n && spawned <= k + ahead.max(1) {
                    let reply = Reply::new(&tx, spawned);
                    let i = spawned;
                    s.spawn(move |_| {
                        if !stop.load(Ordering::Relaxed) && !cancelled() {
                            reply.send(produce(i));
                        }
                    });
                    spawned += 1;
                }
                // waiting[j] holds item k + j once it has come.
                while waiting.front().is_none_or(|r| r.is_none()) {
                    match recv(&rx) {
                        Some((i, Some(r))) => {
                            let j = i - k;
                            if waiting.len() <= j {
                                waiting.resize_with(j + 1, || None);
                            }
                            waiting[j] = Some(r);
                        }
                        // Skipped or panicked: after a cancel, sleep until the page ends the
                        // worker (as map does); after a panic, leave (the scope raises it).
                        _ => {
                            stop.store(true, Ordering::Relaxed);
                            while cancelled() {
                                std::thread::park();
                            }
                            return Ok(());
                        }
                    }
                }
                let r = waiting.pop_front().flatten().expect("item k has come");
                if let Err(e) = consume(k, r) {
                    stop.store(true, Ordering::Relaxed);
                    return Err(e);
                }
            }
            Ok(())
        });
    }
    let _ = ahead;
    for k in 0..n {
        consume(k, produce(k))?;
    }
    Ok(())
}

/// Sorts `v` by `cmp`, on every thread of the pool. `cmp` must be a total order on the
/// elements (ties broken by an index, say): then every sort gives the one sorted order, and
/// the result is the same at any thread count (rayon's parallel quicksort and std's differ
/// only in how they order equal elements).
pub fn sort_unstable_by<T, F>(v: &mut [T], cmp: F)
where
    T: Send,
    F: Fn(&T, &T) -> std::cmp::Ordering + Sync,
{
    #[cfg(any(not(target_arch = "wasm32"), feature = "wasm-threads"))]
    if threads() > 1 && v.len() >= PARALLEL_SORT_MIN {
        use rayon::slice::ParallelSliceMut;
        return v.par_sort_unstable_by(cmp);
    }
    v.sort_unstable_by(cmp)
}

/// Below this many elements a sort stays on the calling thread (splitting costs more).
#[cfg(any(not(target_arch = "wasm32"), feature = "wasm-threads"))]
const PARALLEL_SORT_MIN: usize = 1 << 15;

/// `f` over `0..n` cut into chunks of `chunk` items (the last one shorter), in order: for a
/// sum over many items whose value must not depend on the thread count. The chunks are fixed
/// by `chunk` alone, so summing the chunks' partial results in order rounds the same at any
/// thread count.
pub fn map_chunks<R, F>(n: usize, chunk: usize, f: F) -> Vec<R>
where
    R: Send,
    F: Fn(Range<usize>) -> R + Sync,
{
    let chunk = chunk.max(1);
    let chunks = n.div_ceil(chunk);
    map(chunks, &mut |_| {}, |k| f(k * chunk..((k + 1) * chunk).min(n)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_parallel_sort_and_chunks_give_the_same_result_at_any_thread_count() {
        let keys: Vec<u64> = (0..200_000u64).map(|i| (i * 2_654_435_761) % 1_000).collect();
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| {
                let mut order: Vec<u32> = (0..keys.len() as u32).collect();
                sort_unstable_by(&mut order, |&a, &b| keys[a as usize].cmp(&keys[b as usize]).then(a.cmp(&b)));
                let sums = map_chunks(keys.len(), 4096, |r| r.map(|i| 1.0 / (1.0 + keys[i] as f64)).sum::<f64>());
                (order, sums.iter().sum::<f64>().to_bits(), sums.len())
            })
        };
        let one = run(1);
        assert!(one.0.windows(2).all(|w| (keys[w[0] as usize], w[0]) < (keys[w[1] as usize], w[1])), "sorted");
        assert_eq!(one.2, 200_000usize.div_ceil(4096));
        assert_eq!(run(2), one);
        assert_eq!(run(4), one);
    }
}

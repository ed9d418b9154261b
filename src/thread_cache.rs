//! A per-thread cache of small memory blocks in front of the system allocator: the global
//! allocator of the browser's threaded module (`wasm-threads`) only.
//!
//! Why: the standard library's wasm32 allocator (dlmalloc) guards every allocation and free
//! with one global spin lock. Where several pool threads allocate small blocks at a high rate
//! (the axisymmetric repulsion's geodesic solves: about 1.5 M allocations in 0.6 s), the
//! threads queue on that lock, and a thread the browser deschedules while holding it stalls
//! the others for its whole time slice: in the worker the repulsion ran *slower* on 2 threads
//! than on 1 (0.82×) while the threaded module on a 1-thread pool ran as fast as the plain
//! one. Here each thread keeps its freed small blocks in its own lists (no lock, no shared
//! cache line) and reuses them; only a miss or an overflow reaches the locked allocator.
//! No maintained pure-Rust crate does this for wasm32 threads (talc, lol_alloc and dlmalloc
//! take one lock; mimalloc is C), hence this file.
//!
//! Bounded: a thread keeps at most [`MAX_CACHED_BYTES`] per size class (12 classes, so about
//! 3 MiB a thread at most); beyond that blocks go back to the system allocator. Blocks freed
//! on another thread than the one that made them join that thread's lists (one heap, so any
//! thread may reuse any block). Nothing here touches output: the G-code is the same bytes.

#![allow(unsafe_code)]

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::ptr;
use std::sync::atomic::{AtomicBool, Ordering};

/// Whether the caches are in use: only once every thread's thread-local storage is set up
/// ([`enable`]). A wasm thread allocates its stack and its thread-local block before it has
/// thread-local storage, so touching the lists then would write through an unset base.
static ENABLED: AtomicBool = AtomicBool::new(false);

/// Starts using the per-thread caches. Call once every thread that will allocate runs (the
/// threaded module does after its pool's threads have all run a task); threads started
/// later must not allocate through this allocator. Blocks are class-sized either way, so
/// blocks made before and freed after (or the reverse) stay consistent.
pub fn enable() {
    ENABLED.store(true, Ordering::Release);
}

#[inline]
fn enabled() -> bool {
    ENABLED.load(Ordering::Relaxed)
}

/// Smallest class, bytes (room for the free list's link and the usual 16-byte alignment).
const MIN_BLOCK: usize = 16;
/// Size classes: powers of two from [`MIN_BLOCK`] to 32 KiB.
const CLASSES: usize = 12;
/// Alignment of every cached block; requests for more go straight to the system allocator.
const ALIGN: usize = 16;
/// Bytes of free blocks a thread keeps per class.
pub const MAX_CACHED_BYTES: usize = 256 * 1024;

/// One class's free list on one thread: its first block and how many it holds. A free block's
/// first word links to the next.
struct FreeList {
    head: Cell<*mut u8>,
    count: Cell<usize>,
}

thread_local! {
    // Constant-initialised and without a destructor: reading it never allocates (this runs
    // inside the allocator).
    static LISTS: [FreeList; CLASSES] = const { [const { FreeList { head: Cell::new(ptr::null_mut()), count: Cell::new(0) } }; CLASSES] };
}

/// The allocator: [`System`] with a per-thread cache of small blocks.
pub struct ThreadCache;

/// The class of a request (`None`: served by the system allocator as asked).
#[inline]
fn class_of(size: usize, align: usize) -> Option<usize> {
    if align > ALIGN || size == 0 || size > block_of(CLASSES - 1) {
        return None;
    }
    let block = size.max(MIN_BLOCK).next_power_of_two();
    Some((block.trailing_zeros() - MIN_BLOCK.trailing_zeros()) as usize)
}

/// Bytes of a block of class `c`.
#[inline]
const fn block_of(c: usize) -> usize {
    MIN_BLOCK << c
}

/// The layout every block of class `c` is made and freed with.
#[inline]
fn class_layout(c: usize) -> Layout {
    // Sizes are powers of two up to 32 KiB, alignment 16: always valid.
    Layout::from_size_align(block_of(c), ALIGN).unwrap_or(Layout::new::<u8>())
}

unsafe impl GlobalAlloc for ThreadCache {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let Some(c) = class_of(layout.size(), layout.align()) else {
            return unsafe { System.alloc(layout) };
        };
        if !enabled() {
            return unsafe { System.alloc(class_layout(c)) };
        }
        let cached = LISTS.with(|lists| {
            let list = &lists[c];
            let head = list.head.get();
            if !head.is_null() {
                // SAFETY: a block in the list is free, ours, and at least 16 bytes: its first
                // word is the link written by `dealloc`.
                list.head.set(unsafe { (head as *mut *mut u8).read() });
                list.count.set(list.count.get() - 1);
            }
            head
        });
        if cached.is_null() {
            unsafe { System.alloc(class_layout(c)) }
        } else {
            cached
        }
    }

    unsafe fn dealloc(&self, block: *mut u8, layout: Layout) {
        let Some(c) = class_of(layout.size(), layout.align()) else {
            return unsafe { System.dealloc(block, layout) };
        };
        let kept = enabled()
            && LISTS.with(|lists| {
                let list = &lists[c];
                if list.count.get() * block_of(c) >= MAX_CACHED_BYTES {
                    return false;
                }
                // SAFETY: the block is ours now (freed by its owner) and at least 16 bytes.
                unsafe { (block as *mut *mut u8).write(list.head.get()) };
                list.head.set(block);
                list.count.set(list.count.get() + 1);
                true
            });
        if !kept {
            unsafe { System.dealloc(block, class_layout(c)) }
        }
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        if class_of(layout.size(), layout.align()).is_none() {
            // Large blocks: fresh memory is zero already, which the system allocator knows.
            return unsafe { System.alloc_zeroed(layout) };
        }
        let block = unsafe { self.alloc(layout) };
        if !block.is_null() {
            unsafe { ptr::write_bytes(block, 0, layout.size()) };
        }
        block
    }

    unsafe fn realloc(&self, block: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let (from, to) = (class_of(layout.size(), layout.align()), class_of(new_size, layout.align()));
        match (from, to) {
            // Both large: the system allocator may grow in place.
            (None, None) => unsafe { System.realloc(block, layout, new_size) },
            // The block already has room.
            (Some(a), Some(b)) if a == b => block,
            _ => {
                let Ok(new_layout) = Layout::from_size_align(new_size, layout.align()) else {
                    return ptr::null_mut();
                };
                let moved = unsafe { self.alloc(new_layout) };
                if !moved.is_null() {
                    unsafe {
                        ptr::copy_nonoverlapping(block, moved, layout.size().min(new_size));
                        self.dealloc(block, layout);
                    }
                }
                moved
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn classes_cover_every_small_request() {
        assert_eq!(class_of(1, 1), Some(0));
        assert_eq!(class_of(16, 8), Some(0));
        assert_eq!(class_of(17, 8), Some(1));
        assert_eq!(class_of(32 * 1024, 16), Some(CLASSES - 1));
        assert_eq!(class_of(32 * 1024 + 1, 16), None);
        assert_eq!(class_of(64, 32), None, "over-aligned requests pass through");
        assert_eq!(class_of(0, 1), None);
        for size in 1..=block_of(CLASSES - 1) {
            let c = class_of(size, 8).unwrap();
            assert!(block_of(c) >= size && (c == 0 || block_of(c - 1) < size), "{size}");
        }
    }

    /// Blocks made, filled, grown, shrunk and freed on several threads at once (some freed on
    /// another thread than their maker's) keep their contents, and the lists stay bounded.
    #[test]
    fn blocks_keep_their_contents_across_threads() {
        // Blocks made before the caches are enabled, freed after.
        let early: Vec<(*mut u8, Layout)> =
            (1..200).map(|s| Layout::from_size_align(s * 7, 8).unwrap()).map(|l| (unsafe { ThreadCache.alloc(l) }, l)).collect();
        enable();
        for (p, l) in early {
            unsafe { ThreadCache.dealloc(p, l) };
        }
        let a = ThreadCache;
        let (send, recv) = std::sync::mpsc::channel::<(usize, usize, u8)>();
        std::thread::scope(|s| {
            for t in 0..4u8 {
                let send = send.clone();
                let a = &a;
                s.spawn(move || {
                    let mut seed = 0x9e37_79b9_7f4a_7c15u64 ^ t as u64;
                    let mut live: Vec<(*mut u8, usize, u8)> = Vec::new();
                    for k in 0..20_000usize {
                        seed ^= seed << 13;
                        seed ^= seed >> 7;
                        seed ^= seed << 17;
                        let size = 1 + (seed % 3000) as usize * if k % 97 == 0 { 40 } else { 1 };
                        let fill = (seed >> 32) as u8;
                        let layout = Layout::from_size_align(size, 8).unwrap();
                        let p = unsafe {
                            if k % 5 == 0 {
                                a.alloc_zeroed(layout)
                            } else {
                                a.alloc(layout)
                            }
                        };
                        assert!(!p.is_null());
                        if k % 5 == 0 {
                            assert!(unsafe { std::slice::from_raw_parts(p, size) }.iter().all(|&b| b == 0));
                        }
                        unsafe { ptr::write_bytes(p, fill, size) };
                        live.push((p, size, fill));
                        if live.len() > 64 {
                            let (p, size, fill) = live.swap_remove((seed % 64) as usize);
                            assert!(unsafe { std::slice::from_raw_parts(p, size) }.iter().all(|&b| b == fill));
                            let layout = Layout::from_size_align(size, 8).unwrap();
                            if k % 3 == 0 {
                                // Grown or shrunk: the kept prefix is intact.
                                let new_size = 1 + (seed >> 20) as usize % 5000;
                                let q = unsafe { a.realloc(p, layout, new_size) };
                                assert!(unsafe { std::slice::from_raw_parts(q, size.min(new_size)) }.iter().all(|&b| b == fill));
                                unsafe { a.dealloc(q, Layout::from_size_align(new_size, 8).unwrap()) };
                            } else if k % 3 == 1 {
                                // Freed by another thread.
                                send.send((p as usize, size, fill)).unwrap();
                            } else {
                                unsafe { a.dealloc(p, layout) };
                            }
                        }
                    }
                    for (p, size, _) in live {
                        unsafe { a.dealloc(p, Layout::from_size_align(size, 8).unwrap()) };
                    }
                    LISTS.with(|lists| {
                        for (c, list) in lists.iter().enumerate() {
                            assert!(list.count.get() * block_of(c) <= MAX_CACHED_BYTES);
                        }
                    });
                });
            }
            drop(send);
            s.spawn(|| {
                for (p, size, fill) in recv {
                    let p = p as *mut u8;
                    assert!(unsafe { std::slice::from_raw_parts(p, size) }.iter().all(|&b| b == fill));
                    unsafe { a.dealloc(p, Layout::from_size_align(size, 8).unwrap()) };
                }
            });
        });
    }
}

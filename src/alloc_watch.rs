//! A global allocator that counts each thread's live heap bytes and their peak, so the fuzzer can say how much
//! memory one input made the loader hold (a hostile file claiming a 2048^3 world or a 4 GiB chunk must not get
//! it). The `glowbrick` binary installs it (`main.rs`); where it is not installed `is_installed` is false and the
//! peaks read 0. The counts are thread-local cells: no locks and no contention on the hot path.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::sync::atomic::{AtomicBool, Ordering};

/// The system allocator, counted.
pub struct WatchingAllocator;

static INSTALLED: AtomicBool = AtomicBool::new(false);

thread_local! {
    // Signed: memory freed on another thread than the one that allocated it makes a thread's count go down.
    static LIVE: Cell<isize> = const { Cell::new(0) };
    static PEAK: Cell<isize> = const { Cell::new(0) };
}

fn note(delta: isize) {
    // `try_with`: never fails for const-initialised cells without destructors, but costs nothing to be safe.
    let _ = LIVE.try_with(|live| {
        let now = live.get() + delta;
        live.set(now);
        let _ = PEAK.try_with(|peak| peak.set(peak.get().max(now)));
    });
}

// SAFETY: every call forwards to `System` with the caller's arguments unchanged; the counting touches only
// thread-local cells and never allocates.
unsafe impl GlobalAlloc for WatchingAllocator {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        // A load first: a store on every allocation would bounce this cache line between threads.
        if !INSTALLED.load(Ordering::Relaxed) {
            INSTALLED.store(true, Ordering::Relaxed);
        }
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            note(layout.size() as isize);
        }
        p
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        let p = unsafe { System.alloc_zeroed(layout) };
        if !p.is_null() {
            note(layout.size() as isize);
        }
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) };
        note(-(layout.size() as isize));
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if !p.is_null() {
            note(new_size as isize - layout.size() as isize);
        }
        p
    }
}

/// Whether the running binary counts allocations.
pub fn is_installed() -> bool {
    INSTALLED.load(Ordering::Relaxed)
}

/// A mark on this thread's heap: `peak_bytes` is how far above it the thread's live bytes went since.
pub struct HeapMark(isize);

impl HeapMark {
    /// Starts watching this thread from now (resets its peak to what it holds now).
    pub fn now() -> Self {
        let live = LIVE.try_with(Cell::get).unwrap_or(0);
        let _ = PEAK.try_with(|peak| peak.set(live));
        HeapMark(live)
    }

    /// The most this thread held above the mark since it was taken.
    pub fn peak_bytes(&self) -> u64 {
        (PEAK.try_with(Cell::get).unwrap_or(0) - self.0).max(0) as u64
    }
}

/// Hands the heap's free pages back to the system. glibc keeps what a thread's arena freed for that thread's next
/// allocation, so a server that copies its world for each save and encodes it for each join would otherwise sit
/// at the high-water mark of those copies for good (docs/bench/net/soak.md). Elsewhere it does nothing.
pub fn return_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        unsafe extern "C" {
            fn malloc_trim(pad: usize) -> i32;
        }
        // SAFETY: malloc_trim takes no pointers and only releases memory glibc's allocator holds free.
        unsafe {
            malloc_trim(0);
        }
    }
}

//! The binary's allocator: the system allocator, with transparent huge
//! pages asked for on large blocks (Linux).
//!
//! A million-element fabric keeps a few arrays of hundreds of megabytes
//! (the Hessian's values, its 3x3-block copy, the multigrid levels) and
//! first writes them during set-up and the first step. With 4 KiB pages
//! the kernel takes one page fault per 4 KiB on that first write — a large
//! share of a big run's CPU time in the kernel clearing pages
//! (docs/performance.md, "Two rounds before") — and the memory-bound sparse products of every later
//! Krylov iteration walk those arrays through a TLB that holds few 4 KiB
//! pages. Where the system leaves transparent huge pages to `madvise`
//! (`/sys/kernel/mm/transparent_hugepage/enabled` = `[madvise]`, the
//! common default), this allocator marks every block of 4 MiB or more
//! `MADV_HUGEPAGE` before its first use, so the kernel backs it with 2 MiB
//! pages where it can. Small blocks, and other systems, are the system
//! allocator's as they are. The advice is a hint: if the kernel has no
//! huge page to give, it gives small ones, and nothing else changes.

use std::alloc::{GlobalAlloc, Layout, System};

/// [`System`], with `MADV_HUGEPAGE` on blocks of [`HUGE_BLOCK`] bytes or more.
pub struct HugePageAlloc;

/// Blocks from this size on are advised (bytes): two huge pages, so that
/// at least one whole 2 MiB page lies inside the block.
pub const HUGE_BLOCK: usize = 4 << 20;

const HUGE_PAGE: usize = 2 << 20;

/// Advises the whole 2 MiB pages inside `[ptr, ptr + size)`.
#[cfg(target_os = "linux")]
fn advise(ptr: *mut u8, size: usize) {
    if ptr.is_null() || size < HUGE_BLOCK {
        return;
    }
    let start = (ptr as usize).div_ceil(HUGE_PAGE) * HUGE_PAGE;
    let end = (ptr as usize + size) / HUGE_PAGE * HUGE_PAGE;
    if end > start {
        // SAFETY: the range lies inside a block this process just got
        // from the allocator; madvise only changes how the kernel backs
        // it (an error, e.g. THP compiled out, leaves it as it was).
        unsafe {
            libc::madvise(start as *mut libc::c_void, end - start, libc::MADV_HUGEPAGE);
        }
    }
}

#[cfg(not(target_os = "linux"))]
fn advise(_ptr: *mut u8, _size: usize) {}

// SAFETY: every call is forwarded to `System` unchanged; `advise` touches
// no memory.
unsafe impl GlobalAlloc for HugePageAlloc {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        // SAFETY: the caller's contract, passed on.
        let p = unsafe { System.alloc(layout) };
        advise(p, layout.size());
        p
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        // SAFETY: the caller's contract, passed on.
        let p = unsafe { System.alloc_zeroed(layout) };
        advise(p, layout.size());
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: the caller's contract, passed on.
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        // SAFETY: the caller's contract, passed on.
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        advise(p, new_size);
        p
    }
}

//! The module's global allocator: mimalloc for small blocks, the system allocator for large
//! ones.
//!
//! mimalloc serves the millions of small allocations of an unwrap of thousands of small charts
//! across the worker threads (glibc's allocator measured 1.3–1.6× slower end to end on a
//! 47k-chart mesh: it grows and trims its heaps, page faults and zeroing). But mimalloc keeps a
//! freed large block's memory resident until a later allocation purges it, so the large
//! temporaries a solve frees before its largest allocation (pattern and ordering buffers before
//! a sparse factorization) still count in the peak: measured 115–150 MB at 1M triangles with
//! `abf`. Blocks of [`LARGE`] bytes or more therefore go to the system allocator, which maps
//! them on their own and returns them at once. There are few of them, so their speed does not
//! matter.
//!
//! Preconditions: `dealloc` and `realloc` receive the layout the block was allocated with
//! (`GlobalAlloc`'s contract), whose size says which allocator owns it.

use std::alloc::{GlobalAlloc, Layout, System};

use mimalloc::MiMalloc;

/// Blocks of at least this many bytes come from the system allocator.
pub const LARGE: usize = 1 << 20;

/// mimalloc below [`LARGE`] bytes, the system allocator from there on (module docs).
pub struct SplitAllocator;

impl SplitAllocator {
    #[inline]
    fn large(size: usize) -> bool {
        size >= LARGE
    }
}

unsafe impl GlobalAlloc for SplitAllocator {
    #[inline]
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if Self::large(layout.size()) {
            System.alloc(layout)
        } else {
            MiMalloc.alloc(layout)
        }
    }

    #[inline]
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        if Self::large(layout.size()) {
            System.alloc_zeroed(layout)
        } else {
            MiMalloc.alloc_zeroed(layout)
        }
    }

    #[inline]
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        if Self::large(layout.size()) {
            System.dealloc(ptr, layout)
        } else {
            MiMalloc.dealloc(ptr, layout)
        }
    }

    #[inline]
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        match (Self::large(layout.size()), Self::large(new_size)) {
            (true, true) => System.realloc(ptr, layout, new_size),
            (false, false) => MiMalloc.realloc(ptr, layout, new_size),
            _ => {
                // The block moves to the other allocator: allocate, copy, free.
                let new_layout = Layout::from_size_align_unchecked(new_size, layout.align());
                let new = self.alloc(new_layout);
                if !new.is_null() {
                    std::ptr::copy_nonoverlapping(ptr, new, layout.size().min(new_size));
                    self.dealloc(ptr, layout);
                }
                new
            }
        }
    }
}

//! The process's allocator: the system's, with large blocks in transparent huge pages.
//!
//! A scene of a hundred million triangles fills tens of gigabytes of fresh memory, and on a
//! virtual machine each 4 KiB page's first touch costs a fault of over a microsecond, taken
//! under locks that the cores filling buffers in parallel contend for. Blocks of at least
//! [`HUGE`] bytes are advised (`madvise(MADV_HUGEPAGE)`) to be backed by 2 MiB pages where
//! the kernel allows it (`/sys/kernel/mm/transparent_hugepage/enabled` set to `madvise` or
//! `always`): 512 times fewer faults. Elsewhere the advice is a no-op.
//!
//! Only on machines of at least [`MIN_CPUS`] processors: on the 16-core H200 host a
//! 100-million-triangle render's first image came 10-33% sooner with the advice, but on a
//! 2-core machine a 10-million-triangle one was 7-10% slower (where few cores fault at once,
//! there is little contention to save, and zeroing a 2 MiB page at a time costs more):
//! docs/bench/2026-12-04-scale.md.

use std::alloc::{GlobalAlloc, Layout, System};

/// Blocks from this size on are advised to use huge pages.
pub(crate) const HUGE: usize = 32 << 20;

/// Machines with fewer online processors than this get no advice.
pub(crate) const MIN_CPUS: i64 = 8;

/// The system allocator, advising huge pages for large blocks.
pub struct HugePages;

/// Advises huge pages for a large block, on machines of many processors.
fn advise(ptr: *mut u8, size: usize) {
    #[cfg(target_os = "linux")]
    if many_cpus() {
        advise_huge_pages(ptr, size);
    }
    #[cfg(not(target_os = "linux"))]
    let _ = (ptr, size);
}

/// Advises huge pages for the whole 2 MiB pages inside `[ptr, ptr + size)`; returns
/// `madvise`'s result (0, or -1 where the kernel refuses; true where no page is whole).
#[cfg(target_os = "linux")]
fn advise_huge_pages(ptr: *mut u8, size: usize) -> bool {
    const PAGE: usize = 2 << 20;
    let start = (ptr as usize).next_multiple_of(PAGE);
    let end = (ptr as usize + size) / PAGE * PAGE;
    if end <= start {
        return true;
    }
    // SAFETY: the range lies inside a block this allocator handed out, and the advice
    // changes only how its pages are backed, never their contents.
    unsafe { libc::madvise(start as *mut libc::c_void, end - start, libc::MADV_HUGEPAGE) == 0 }
}

/// Whether the machine has [`MIN_CPUS`] or more online processors (asked once; `sysconf`
/// allocates nothing, which an allocator must not).
#[cfg(target_os = "linux")]
fn many_cpus() -> bool {
    use std::sync::atomic::{AtomicU8, Ordering};
    static ANSWER: AtomicU8 = AtomicU8::new(0); // 0 unknown, 1 no, 2 yes
    match ANSWER.load(Ordering::Relaxed) {
        0 => {
            // SAFETY: sysconf reads a system value and touches no memory of ours.
            let cpus = unsafe { libc::sysconf(libc::_SC_NPROCESSORS_ONLN) };
            let many = cpus as i64 >= MIN_CPUS;
            ANSWER.store(1 + many as u8, Ordering::Relaxed);
            many
        }
        answer => answer == 2,
    }
}

// SAFETY: every call is forwarded to `System` unchanged; the advice after it touches no
// memory.
unsafe impl GlobalAlloc for HugePages {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        // SAFETY: the caller's contract is `System`'s.
        let ptr = unsafe { System.alloc(layout) };
        if layout.size() >= HUGE && !ptr.is_null() {
            advise(ptr, layout.size());
        }
        ptr
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        // SAFETY: as above.
        let ptr = unsafe { System.alloc_zeroed(layout) };
        if layout.size() >= HUGE && !ptr.is_null() {
            advise(ptr, layout.size());
        }
        ptr
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: as above.
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        // SAFETY: as above.
        let new = unsafe { System.realloc(ptr, layout, new_size) };
        if new_size >= HUGE && !new.is_null() {
            advise(new, new_size);
        }
        new
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn large_blocks_keep_their_contents_through_the_advice_and_a_reallocation() {
        let size = 3 * HUGE;
        let layout = Layout::from_size_align(size, 64).unwrap();
        // SAFETY: a non-zero size; the block is written and read within its bounds and
        // freed with the layout of its last allocation.
        unsafe {
            let ptr = HugePages.alloc_zeroed(layout);
            assert!(!ptr.is_null());
            let block = std::slice::from_raw_parts_mut(ptr, size);
            assert!(block.iter().all(|&b| b == 0), "zeroed");
            for (i, b) in block.iter_mut().enumerate() {
                *b = (i % 251) as u8;
            }
            // The advice itself, which the allocator gives only on machines of many cores.
            #[cfg(target_os = "linux")]
            assert!(advise_huge_pages(ptr, size), "madvise refused");
            let bigger = HugePages.realloc(ptr, layout, size + HUGE);
            assert!(!bigger.is_null());
            let block = std::slice::from_raw_parts(bigger, size);
            assert!(block.iter().enumerate().all(|(i, &b)| b == (i % 251) as u8));
            HugePages.dealloc(bigger, Layout::from_size_align(size + HUGE, 64).unwrap());
        }
    }
}

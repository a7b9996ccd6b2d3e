//! Memory for the BVH's large arrays, backed by huge pages where the system allows.
//!
//! Rays in a large scene reach nodes and leaf blocks scattered over hundreds of megabytes. With
//! 4 KiB pages nearly every such access also misses the TLB (a few thousand entries cover
//! about 10 MB), and the page walk is itself a chain of cache misses. 2 MiB pages make the
//! whole BVH of a 5 M-triangle scene a few hundred TLB entries. Linux's transparent huge pages
//! are often enabled for memory that asks for them (`madvise` mode, as on Debian), not for all
//! memory; Embree asks too. Elsewhere, or where the system refuses, this is ordinary memory.
//!
//! Measured (`gather_rays cast`, 2 threads, medians of 3 interleaved runs, this project's
//! 2-core VM in `madvise` mode): the 5.2 M-triangle sphere of `benches/embree/compare.sh`
//! (256² × 64 rays) traced in 3.26 s instead of 3.72 s, `hall` (608 K triangles, 128² × 256)
//! in 0.66 s instead of 0.76 s; `cube` (77 K triangles, a BVH of 6 MB) did not change.

/// Huge page size on x86-64 and AArch64 Linux.
const HUGE_PAGE: usize = 2 << 20;

/// An empty vector with room for `capacity` values, its memory fresh from the allocator (not
/// yet touched) and advised to be backed by huge pages: the pages that lie wholly inside it
/// are, as they are first written, if the system allows. (Fresh is why not `vec![x; n]` or a
/// zeroed allocation: for types aligned beyond 16 bytes the standard allocator zeroes by
/// writing, which would back the memory with small pages before the advice.)
pub(crate) fn with_capacity<T>(capacity: usize) -> Vec<T> {
    let values: Vec<T> = Vec::with_capacity(capacity);
    advise_huge_pages(values.as_ptr() as usize, capacity * std::mem::size_of::<T>());
    values
}

#[cfg(target_os = "linux")]
fn advise_huge_pages(start: usize, bytes: usize) {
    let begin = start.next_multiple_of(HUGE_PAGE);
    let end = (start + bytes) / HUGE_PAGE * HUGE_PAGE;
    if end > begin {
        // SAFETY: the range lies inside one live allocation; MADV_HUGEPAGE changes how it is
        // backed, never its contents. Refusal (no THP support) leaves ordinary pages.
        unsafe { libc::madvise(begin as *mut libc::c_void, end - begin, libc::MADV_HUGEPAGE) };
    }
}

#[cfg(not(target_os = "linux"))]
fn advise_huge_pages(_start: usize, _bytes: usize) {}

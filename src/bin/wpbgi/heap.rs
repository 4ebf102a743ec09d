//! The process's heap policy: freed memory stays with the allocator for the next allocation
//! instead of going back to the kernel.
//!
//! glibc's malloc returns the free top of a heap to the kernel once it exceeds its trim
//! threshold (128 KiB at first, raised as large blocks are freed). A bake's bounces, and a
//! relight's, free and allocate hundreds of MB of maps and links a bounce, so each bounce
//! faulted in again pages the kernel had just taken back, and the kernel cleared every one:
//! `clear_page` was 23 % of a cbox-glossy relight's perf samples. The same setting given to
//! the previous binary through `GLIBC_TUNABLES=glibc.malloc.trim_threshold=…` took that
//! relight to 5.23 and 5.39 s from 5.99 and 5.86 s (two alternated pairs, the same cache
//! byte for byte; with this commit's other change, docs/relight.md). Peak memory is
//! unchanged (1.62 GB either way): what a bounce frees the next one reuses. (Setting the
//! threshold also stops glibc raising its mmap threshold, so blocks over 128 KiB are still
//! mapped and unmapped one by one; keeping those too was not measurably faster.) What the process does not give back it holds
//! until it exits, at most its peak; the commands here run one job and exit (the preview's
//! window holds its peak while it stays open).
//!
//! The library leaves the allocator alone: a host that embeds it sets its own policy.

/// Keep freed memory in the process's heaps (glibc only; elsewhere nothing to do).
pub fn keep_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        // SAFETY: mallopt only sets a parameter of the allocator; called first thing in
        // main, before any other thread exists. Its answer (1 when set) changes nothing
        // here: without it the default policy holds.
        unsafe {
            libc::mallopt(libc::M_TRIM_THRESHOLD, libc::c_int::MAX);
        }
    }
}

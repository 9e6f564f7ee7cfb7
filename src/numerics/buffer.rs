//! Large sample buffers. A 10^7-sample channel is 80 MB; faulting it in 4 KiB pages cost a
//! third of reading an LDV record (kernel page-fault and page-clearing time, measured with
//! perf). numpy asks the kernel for transparent huge pages for such arrays; so do we.

/// An empty `Vec<f64>` with room for `capacity` samples, backed by huge pages where the
/// kernel allows it (Linux `madvise(MADV_HUGEPAGE)`; elsewhere a plain allocation).
pub fn sample_buffer(capacity: usize) -> Vec<f64> {
    let v: Vec<f64> = Vec::with_capacity(capacity);
    advise_huge_pages(&v);
    v
}

#[cfg(target_os = "linux")]
fn advise_huge_pages(v: &Vec<f64>) {
    const HUGE: usize = 2 << 20;
    let bytes = v.capacity() * std::mem::size_of::<f64>();
    if bytes < 4 * HUGE {
        return;
    }
    // madvise needs a page-aligned start; advise the 2 MiB-aligned part inside the buffer.
    let start = v.as_ptr() as usize;
    let aligned = (start + HUGE - 1) & !(HUGE - 1);
    let end = (start + bytes) & !(HUGE - 1);
    if end > aligned {
        // SAFETY: the range lies inside this Vec's own allocation; MADV_HUGEPAGE is a hint
        // that changes no contents and whose failure is harmless, so its result is ignored.
        unsafe {
            libc::madvise(
                aligned as *mut libc::c_void,
                end - aligned,
                libc::MADV_HUGEPAGE,
            );
        }
    }
}

#[cfg(not(target_os = "linux"))]
fn advise_huge_pages(_: &Vec<f64>) {}

#[cfg(test)]
mod tests {
    #[test]
    fn buffers_are_empty_with_the_requested_room() {
        let v = super::sample_buffer(3_000_000);
        assert!(v.is_empty() && v.capacity() >= 3_000_000);
        let small = super::sample_buffer(10);
        assert!(small.capacity() >= 10);
    }
}

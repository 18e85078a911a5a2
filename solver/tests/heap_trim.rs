//! `solver solve` gives the heap's freed pages back to the kernel after import
//! and set-up (`cli/solve/memory.rs`, `return_freed_memory`), because the
//! memory estimate counts live structures only. This checks the claim the
//! estimate's accuracy rests on: freed heap memory that glibc would keep
//! resident leaves the resident set. It is its own test binary so that no
//! other test allocates beside it while the resident set is read.

/// VmRSS of this process, bytes.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
fn resident() -> u64 {
    let status = std::fs::read_to_string("/proc/self/status").expect("reading /proc/self/status");
    let line = status
        .lines()
        .find(|l| l.starts_with("VmRSS:"))
        .expect("VmRSS in /proc/self/status");
    let kib: u64 = line["VmRSS:".len()..]
        .trim()
        .trim_end_matches("kB")
        .trim()
        .parse()
        .expect("VmRSS in kB");
    kib * 1024
}

#[cfg(all(target_os = "linux", target_env = "gnu"))]
#[test]
fn freed_heap_pages_leave_the_resident_set() {
    // 64 MiB in 512-byte blocks: below glibc's mmap threshold, so they come
    // from the heap, as the solver's many small vectors do, and each is
    // written so that its pages are resident.
    const BLOCK: usize = 512;
    const FREED: usize = 64 << 20;
    let mut blocks: Vec<Box<[u8]>> = (0..FREED / BLOCK)
        .map(|i| vec![(i % 251) as u8 + 1; BLOCK].into_boxed_slice())
        .collect();
    // A block allocated after them keeps the heap's top above them, so
    // free() alone cannot shrink the heap: the freed memory stays resident,
    // as set-up's transients did below the solver's own state.
    let pin = vec![7u8; BLOCK];
    blocks.clear();
    blocks.shrink_to_fit();
    let freed = resident();
    solver::cli::solve::memory::return_freed_memory();
    let trimmed = resident();
    // At least half of what was freed must leave: the rest of the margin is
    // glibc's bins and partly used pages at the edges of the freed range.
    assert!(
        freed.saturating_sub(trimmed) >= (FREED / 2) as u64,
        "resident set {freed} B after freeing {FREED} B, {trimmed} B after the trim: \
         the freed heap stayed resident"
    );
    // Read after the trim so that `pin` is still allocated while it runs.
    assert_eq!(pin[0], 7);
}

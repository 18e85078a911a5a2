//! The default memory budget, from the machine's available memory (the one
//! place `solver solve` reads /proc; the solver core only sees the bytes).

use crate::solve::budget::human_bytes;

/// The default budget is this fraction of MemAvailable: the rest is left to
/// the page cache and to whatever else starts while the solve runs.
pub const AVAILABLE_FRACTION: f64 = 0.8;

/// The budget when /proc/meminfo cannot be read (not Linux, a sandbox).
pub const FALLBACK_BUDGET: u64 = 4 << 30;

/// `MemAvailable` in bytes from the text of /proc/meminfo (`MemAvailable:
/// 123456 kB`); `None` when absent or malformed.
pub fn parse_mem_available(meminfo: &str) -> Option<u64> {
    parse_field(meminfo, "MemAvailable:")
}

/// `VmRSS`, the resident set, in bytes from the text of /proc/self/status;
/// `None` when absent or malformed.
pub fn parse_resident(status: &str) -> Option<u64> {
    parse_field(status, "VmRSS:")
}

/// The process's resident bytes now, where /proc/self/status can be read.
/// Read after import (the solver's estimate starts from it, `solve::budget`).
#[allow(clippy::disallowed_methods)] // An edge: the resident size is read from the system.
pub fn resident_bytes() -> Option<u64> {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .as_deref()
        .and_then(parse_resident)
}

/// The value of the line starting with `name` (`name 123456 kB`), in bytes.
fn parse_field(text: &str, name: &str) -> Option<u64> {
    let line = text.lines().find(|l| l.starts_with(name))?;
    let mut words = line[name.len()..].split_whitespace();
    let value: u64 = words.next()?.parse().ok()?;
    match words.next() {
        Some("kB") => value.checked_mul(1024),
        None => Some(value),
        Some(_) => None,
    }
}

/// The default budget and how it was found, for the line printed at the start.
pub fn default_budget() -> (u64, String) {
    #[allow(clippy::disallowed_methods)] // An edge: the default budget is read from the system.
    let available = std::fs::read_to_string("/proc/meminfo")
        .ok()
        .as_deref()
        .and_then(parse_mem_available);
    match available {
        Some(bytes) => {
            let budget = (bytes as f64 * AVAILABLE_FRACTION) as u64;
            (
                budget,
                format!(
                    "{:.0}% of MemAvailable {}",
                    100.0 * AVAILABLE_FRACTION,
                    human_bytes(bytes as u128)
                ),
            )
        }
        None => (
            FALLBACK_BUDGET,
            "the fallback: /proc/meminfo MemAvailable could not be read".into(),
        ),
    }
}

/// Returns the heap's free pages to the kernel (glibc's `malloc_trim`).
///
/// Import and set-up free most of what they allocate (the OBJ's text and
/// parse tables, contact cuts, every vector that doubled as it grew, whose
/// old blocks are freed as it moves), but glibc keeps freed heap memory
/// resident for reuse. The memory estimate counts live structures only
/// (`solve/budget.rs`), so that freed memory was the largest part of its
/// error: on the 100k Cornell boxes at draft, 48 MiB of freed heap stayed
/// resident after set-up, and the peak RSS fell from 262.5 MB to 227.3 MB
/// with the trim (docs/lab/memory-at-scale.md, "At scale: the freed heap, the
/// per-surface term and the view"). Called between phases, never during a shot; elsewhere than glibc
/// it does nothing.
pub fn return_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: malloc_trim takes no pointer; it walks glibc's own arenas under
    // their locks, so it may be called at any time from any thread.
    unsafe {
        libc::malloc_trim(0);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resident_set_is_read_in_bytes() {
        let status = "Name:\tsolver\nVmPeak:\t  900 kB\nVmRSS:\t  254244 kB\nRssAnon:\t 1 kB\n";
        assert_eq!(parse_resident(status), Some(254_244 * 1024));
        assert_eq!(parse_resident("VmRSS:\t 12 MB\n"), None);
        assert_eq!(parse_resident("Name:\tsolver\n"), None);
    }

    #[test]
    fn mem_available_is_read_in_bytes() {
        let text = "MemTotal:       24576000 kB\nMemFree:         1000 kB\nMemAvailable:   \
                    12288000 kB\n";
        assert_eq!(parse_mem_available(text), Some(12_288_000 * 1024));
        assert_eq!(parse_mem_available("MemTotal: 5 kB\n"), None);
        assert_eq!(parse_mem_available("MemAvailable: many kB\n"), None);
    }
}

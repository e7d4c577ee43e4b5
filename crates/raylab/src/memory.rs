//! How much memory the machine has free: the bound that every large allocation of a render
//! (meshes, BVHs, films) is checked against first, so that an absurd size is a clear error
//! rather than an abort.

/// Bytes of memory available to a new allocation, as the kernel estimates it (`MemAvailable`
/// in `/proc/meminfo`), or `None` where that is not known.
pub fn available_bytes() -> Option<u64> {
    let meminfo = std::fs::read_to_string("/proc/meminfo").ok()?;
    parse_meminfo(&meminfo, "MemAvailable:")
}

fn parse_meminfo(meminfo: &str, key: &str) -> Option<u64> {
    let line = meminfo.lines().find(|line| line.starts_with(key))?;
    let kib: u64 = line[key.len()..].trim().trim_end_matches("kB").trim().parse().ok()?;
    kib.checked_mul(1024)
}

/// Asks the cache for the line at `address` (a hint; never faults).
#[inline(always)]
pub fn prefetch(address: *const u8) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        // SAFETY: a prefetch never faults, whatever the address.
        unsafe { _mm_prefetch::<_MM_HINT_T0>(address.cast()) };
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = address;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_mem_available() {
        let text = "MemTotal:       24000000 kB\nMemAvailable:   20000000 kB\n";
        assert_eq!(parse_meminfo(text, "MemAvailable:"), Some(20_000_000 * 1024));
        assert_eq!(parse_meminfo(text, "SwapTotal:"), None);
    }
}

//! What the machine has: memory, cores.

/// Bytes of memory available to a new allocation, as the kernel estimates it (`MemAvailable`
/// in `/proc/meminfo`), or `None` where that is not known.
pub fn available_memory_bytes() -> Option<u64> {
    let meminfo = std::fs::read_to_string("/proc/meminfo").ok()?;
    parse_meminfo(&meminfo, "MemAvailable:")
}

fn parse_meminfo(meminfo: &str, key: &str) -> Option<u64> {
    let line = meminfo.lines().find(|line| line.starts_with(key))?;
    let kib: u64 = line[key.len()..].trim().trim_end_matches("kB").trim().parse().ok()?;
    kib.checked_mul(1024)
}

/// Fails with a one-line error when a `width×height` picture needs more memory (`bytes`) than
/// the machine has available.
pub fn check_memory(bytes: u64, width: u32, height: u32) -> anyhow::Result<()> {
    if let Some(available) = available_memory_bytes()
        && bytes > available
    {
        anyhow::bail!(
            "image size {width}×{height} needs {} of memory, but only {} is available",
            raylab::film::format_bytes(bytes),
            raylab::film::format_bytes(available)
        );
    }
    Ok(())
}

/// The BVH over a scene's triangles, or one line saying why not: more triangles than a BVH
/// holds, or more memory for the build than the machine has available. `name` names the scene.
pub fn build_bvh(name: &str, geometry: &raylab::Geometry) -> anyhow::Result<raylab::SceneBvh> {
    // A mesh drawn in several places is built over once.
    check_bvh_memory(name, geometry.stored_len(), available_memory_bytes())?;
    raylab::SceneBvh::build(geometry).map_err(|e| anyhow::anyhow!("{name}: {e}"))
}

/// Whether a BVH over `triangles` fits in `available` bytes (unknown: assumed to fit).
fn check_bvh_memory(name: &str, triangles: usize, available: Option<u64>) -> anyhow::Result<()> {
    let bytes = raylab::Bvh::build_bytes_estimate(triangles);
    if let Some(available) = available
        && bytes > available
    {
        anyhow::bail!(
            "{name}: {triangles} triangles need about {} of memory for the BVH, but only {} is \
             available",
            raylab::film::format_bytes(bytes),
            raylab::film::format_bytes(available)
        );
    }
    Ok(())
}

/// The number of threads the machine runs at once.
pub fn cores() -> usize {
    std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_bvh_larger_than_the_memory_is_one_line_error() {
        let error = check_bvh_memory("big.ply", 200_000_000, Some(8 << 30)).unwrap_err();
        let message = error.to_string();
        assert!(message.starts_with("big.ply: 200000000 triangles need about"), "{message}");
        assert!(!message.contains('\n'), "{message}");
        assert!(check_bvh_memory("small.obj", 1000, Some(8 << 30)).is_ok());
        assert!(check_bvh_memory("unknown.obj", 200_000_000, None).is_ok());
    }

    #[test]
    fn reads_mem_available() {
        let text = "MemTotal:       24000000 kB\nMemAvailable:   20000000 kB\n";
        assert_eq!(parse_meminfo(text, "MemAvailable:"), Some(20_000_000 * 1024));
        assert_eq!(parse_meminfo(text, "SwapTotal:"), None);
    }
}

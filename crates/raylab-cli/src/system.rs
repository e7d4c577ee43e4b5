//! What the machine has: cores (memory is the library's `raylab::memory`).

/// The number of threads the machine runs at once.
pub fn cores() -> usize {
    std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1)
}

//! What the machine offers a bake: its physical and its available memory, from Linux's
//! `/proc/meminfo`. Elsewhere the figures are unknown (`None`) and the checks that need them
//! are skipped, never guessed.

/// Physical memory, in bytes.
pub(crate) fn total_memory() -> Option<u64> {
    meminfo("MemTotal:")
}

/// Memory available to a new allocation without swapping (the kernel's estimate), in bytes.
pub(crate) fn available_memory() -> Option<u64> {
    meminfo("MemAvailable:")
}

/// The `/proc/meminfo` line `key`, in bytes (the file gives kB).
fn meminfo(key: &str) -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    text.lines()
        .find_map(|l| l.strip_prefix(key))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<u64>().ok())
        .map(|kb| kb * 1024)
}

//! Peak memory of this process: the resident set's high-water mark (Linux `VmHWM`), which
//! writing 5 to `/proc/self/clear_refs` resets (Linux 4.0 and later), so that each run of a
//! comparison reports its own peak. Elsewhere there is no figure (`None`).

/// Reset the high-water mark to the current resident set, where the OS allows.
pub fn reset_peak() {
    let _ = std::fs::write("/proc/self/clear_refs", "5");
}

/// The process's peak resident memory in bytes since it started or since [`reset_peak`].
pub fn peak() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

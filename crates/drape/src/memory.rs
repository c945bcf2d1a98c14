//! What memory a run may have, and what a mesh and its Hessian's pattern
//! need: read before the large allocations (the model's sparse pattern,
//! mass matrix and element data), so that a mesh too large for the machine
//! is refused with the estimate instead of aborting the process when an
//! allocation fails.

/// Memory a run needs per mesh node (bytes): the model, the Hessian's
/// pattern and values in 3x3 blocks, the solver's factor or multigrid
/// hierarchy, the state and the frame snapshots — about 1.6 kB a node with
/// a direct solver on T3 elements, the figure the node cap of 3e6 nodes
/// (`[mesh]`, README) is set by.
pub const BYTES_PER_NODE: u64 = 1600;

/// Memory the Hessian's pattern needs per 3x3 node block (bytes): for each
/// of its 9 entries the value (the Newton workspace's Hessian), the row
/// index and the index of the mirrored entry, each index held twice (by
/// the model's pattern and by the linear solver) — 5 words — and per block
/// the node graph's row and the mass matrix's value. What the linear
/// solver builds on the pattern at the first step (a factor and its fill,
/// a multigrid hierarchy, copies of the values) is not counted: its size
/// is not known before its symbolic analysis. So the estimate is a floor:
/// a pattern it refuses cannot be run.
pub const BYTES_PER_BLOCK: u64 = 9 * 5 * 8 + 2 * 8;

/// The estimate for a mesh of `nodes` nodes (bytes).
pub fn estimate(nodes: usize) -> u64 {
    (nodes as u64).saturating_mul(BYTES_PER_NODE)
}

/// The estimate for a Hessian pattern of `blocks` 3x3 node blocks (bytes;
/// see [`BYTES_PER_BLOCK`], and `solver::pattern::block_count` for the
/// count).
pub fn pattern_estimate(blocks: usize) -> u64 {
    (blocks as u64).saturating_mul(BYTES_PER_BLOCK)
}

/// The most memory this process may use, and what sets it: the
/// address-space limit (`ulimit -v`, `prlimit --as`) or the memory the
/// system has available, whichever is smaller; `None` where neither can
/// be read (not Linux).
pub fn available() -> Option<(u64, &'static str)> {
    smaller(
        address_space_limit().map(|b| (b, "address-space limit of the process")),
        memory_available(),
    )
}

/// The memory this process may still allocate, and what sets it: what is
/// left under its address-space limit (the limit less the address space it
/// maps already: the program, its threads' stacks and arenas, what it has
/// allocated) or the memory the system has available, whichever is
/// smaller; `None` where neither can be read (not Linux).
pub fn headroom() -> Option<(u64, &'static str)> {
    let left = address_space_limit().map(|limit| {
        let mapped = status_kib("VmSize:").unwrap_or(0).saturating_mul(1024);
        (
            limit.saturating_sub(mapped),
            "left under the address-space limit of the process",
        )
    });
    smaller(left, memory_available())
}

/// The smaller of two figures, either of which may be unknown.
fn smaller(
    a: Option<(u64, &'static str)>,
    b: Option<(u64, &'static str)>,
) -> Option<(u64, &'static str)> {
    match (a, b) {
        (Some(a), Some(b)) => Some(if a.0 <= b.0 { a } else { b }),
        (a, b) => a.or(b),
    }
}

/// The soft address-space limit (bytes), when there is one.
fn address_space_limit() -> Option<u64> {
    std::fs::read_to_string("/proc/self/limits")
        .ok()
        .and_then(|text| {
            text.lines()
                .find(|l| l.starts_with("Max address space"))
                .and_then(|l| l.split_whitespace().nth(3))
                .and_then(|soft| soft.parse::<u64>().ok())
        })
}

/// The memory the system has available (bytes).
fn memory_available() -> Option<(u64, &'static str)> {
    kib_field("/proc/meminfo", "MemAvailable:")
        .map(|kib| (kib.saturating_mul(1024), "memory available on this machine"))
}

/// A field of this process's `/proc/self/status` (kB).
fn status_kib(field: &str) -> Option<u64> {
    kib_field("/proc/self/status", field)
}

/// The value of the line starting with `field` in the `/proc` file `path`,
/// in kB.
fn kib_field(path: &str, field: &str) -> Option<u64> {
    std::fs::read_to_string(path).ok().and_then(|text| {
        text.lines()
            .find_map(|l| l.strip_prefix(field))
            .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<u64>().ok())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_estimate_is_linear_and_saturates() {
        assert_eq!(estimate(1000), 1_600_000);
        assert_eq!(estimate(usize::MAX), u64::MAX);
        if cfg!(target_os = "linux") {
            let (bytes, _) = available().expect("Linux has /proc/meminfo");
            assert!(bytes > 0);
        }
    }

    /// The pattern's estimate: 376 bytes a block (5 words for each of 9
    /// entries, 2 a block), saturating; the headroom is no more than what
    /// is available, and, in this process, which maps its own program,
    /// less than its address-space limit when it has one.
    #[test]
    fn the_pattern_estimate_and_the_headroom() {
        assert_eq!(BYTES_PER_BLOCK, 376);
        assert_eq!(pattern_estimate(7 * 1000), 2_632_000);
        assert_eq!(pattern_estimate(usize::MAX), u64::MAX);
        if cfg!(target_os = "linux") {
            let (left, _) = headroom().expect("Linux has /proc/meminfo");
            let (all, _) = available().expect("Linux has /proc/meminfo");
            assert!(left <= all && left > 0);
            if let Some(limit) = address_space_limit().filter(|l| *l < u64::MAX) {
                assert!(left < limit);
            }
            assert!(status_kib("VmSize:").is_some_and(|kib| kib > 0));
        }
    }
}

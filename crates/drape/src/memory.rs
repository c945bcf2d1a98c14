//! What memory a run may have, and what a mesh needs: read before the
//! large allocations (the model's sparse pattern, mass matrix and element
//! data), so that a mesh too large for the machine is refused with the
//! estimate instead of aborting the process when an allocation fails.

/// Memory a run needs per mesh node (bytes): the model, the Hessian's
/// pattern and values in 3x3 blocks, the solver's factor or multigrid
/// hierarchy, the state and the frame snapshots — about 1.6 kB a node with
/// a direct solver on T3 elements, the figure the node cap of 3e6 nodes
/// (`[mesh]`, README) is set by.
pub const BYTES_PER_NODE: u64 = 1600;

/// The estimate for a mesh of `nodes` nodes (bytes).
pub fn estimate(nodes: usize) -> u64 {
    (nodes as u64).saturating_mul(BYTES_PER_NODE)
}

/// The most memory this process may use, and what sets it: the
/// address-space limit (`ulimit -v`, `prlimit --as`) or the memory the
/// system has available, whichever is smaller; `None` where neither can
/// be read (not Linux).
pub fn available() -> Option<(u64, &'static str)> {
    let limit = std::fs::read_to_string("/proc/self/limits")
        .ok()
        .and_then(|text| {
            text.lines()
                .find(|l| l.starts_with("Max address space"))
                .and_then(|l| l.split_whitespace().nth(3))
                .and_then(|soft| soft.parse::<u64>().ok())
        })
        .map(|b| (b, "address-space limit of the process"));
    let free = std::fs::read_to_string("/proc/meminfo")
        .ok()
        .and_then(|text| {
            text.lines()
                .find_map(|l| l.strip_prefix("MemAvailable:"))
                .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<u64>().ok())
        })
        .map(|kib| (kib.saturating_mul(1024), "memory available on this machine"));
    match (limit, free) {
        (Some(a), Some(b)) => Some(if a.0 <= b.0 { a } else { b }),
        (a, b) => a.or(b),
    }
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
}

//! The memory budget of a process (`--max-memory`) and the check made before an import
//! (the other estimates live in the libraries beside the code that allocates; see
//! `rigport_model::budget`).
//!
//! ```
//! use rigport_pipeline::memory;
//!
//! let given = memory::process_budget(Some(1 << 30));
//! assert_eq!((given.limit, given.origin), (1 << 30, "--max-memory"));
//! let default = memory::process_budget(None);
//! assert!(default.limit > 0);
//! let plan = rigport_import::detect::Source::Bvh("../../fixtures/bvh/end_sites.bvh".into());
//! assert!(memory::check_import(&plan, &given).is_ok());
//! assert!(memory::check_import(&plan, &rigport_pipeline::MemoryBudget { limit: 10, origin: "test" }).is_err());
//! ```

use rigport_import::detect::Source;
use rigport_model::budget::{self, MemoryBudget, OverBudget};

/// Importers hold a file's bytes, their parse and the model at once: about this many
/// times the input's size (measured: 4.2x for a 36 MB AMC; text and binary inputs alike).
const IMPORT_FACTOR: u64 = 5;

/// The budget for `--max-memory` (bytes), or the default: 3/4 of the memory this process
/// may use (the smallest of `MemTotal`, a cgroup `memory.max` and an address-space limit),
/// or 8 GB when unknown.
pub fn process_budget(max_memory: Option<u64>) -> MemoryBudget {
    match max_memory {
        Some(limit) => MemoryBudget {
            limit,
            origin: "--max-memory",
        },
        None => match machine_memory() {
            Some(total) => MemoryBudget {
                limit: total / 4 * 3,
                origin: "default: 3/4 of the memory this process may use",
            },
            None => DEFAULT,
        },
    }
}

/// The budget when nothing is known: 8 GB.
pub const DEFAULT: MemoryBudget = MemoryBudget {
    limit: 8_000_000_000,
    origin: "default",
};

/// The machine's memory in bytes, as this process may use it.
fn machine_memory() -> Option<u64> {
    let meminfo = std::fs::read_to_string("/proc/meminfo").ok()?;
    let total_kb: u64 = meminfo
        .lines()
        .find_map(|l| l.strip_prefix("MemTotal:"))?
        .trim()
        .trim_end_matches("kB")
        .trim()
        .parse()
        .ok()?;
    let total = total_kb.saturating_mul(1024);
    let cgroup = std::fs::read_to_string("/sys/fs/cgroup/memory.max")
        .ok()
        .and_then(|s| s.trim().parse::<u64>().ok());
    Some(
        [cgroup, address_space_limit()]
            .into_iter()
            .flatten()
            .fold(total, u64::min),
    )
}

/// The soft limit on this process's address space (`ulimit -v`, `prlimit --as`), from
/// `/proc/self/limits`; `None` when unlimited or unknown.
fn address_space_limit() -> Option<u64> {
    let limits = std::fs::read_to_string("/proc/self/limits").ok()?;
    let line = limits
        .lines()
        .find(|l| l.starts_with("Max address space"))?;
    line.split_whitespace().nth(3)?.parse().ok()
}

/// Checks that importing `plan` fits `budget`.
///
/// # Errors
/// An [`OverBudget`] naming the input and its size.
pub fn check_import(plan: &Source, budget: &MemoryBudget) -> Result<(), OverBudget> {
    let bytes: u64 = plan
        .files()
        .iter()
        .filter_map(|f| std::fs::metadata(f).ok())
        .map(|m| m.len())
        .sum();
    budget.check(
        format_args!(
            "{}: reading {} of input",
            plan.label(),
            budget::format_bytes(bytes)
        ),
        bytes.saturating_mul(IMPORT_FACTOR),
    )
}

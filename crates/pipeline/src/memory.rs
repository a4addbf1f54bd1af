//! The memory budget of a process and the check made before an import
//! (the other estimates live in the libraries beside the code that allocates; see
//! `rigport_model::budget`).

use rigport_import::detect::Source;
use rigport_model::budget::{self, MemoryBudget, OverBudget};

/// Importers hold a file's bytes, their parse and the model at once: about this many
/// times the input's size (measured: 4.2x for a 36 MB AMC; text and binary inputs alike).
const IMPORT_FACTOR: u64 = 5;

/// The budget `given` (bytes; `given_by` names where it came from in messages), or the
/// default: 3/4 of the memory this process may use (the smallest of `MemTotal`, the memory
/// limit of its cgroup or any cgroup above it, v1 or v2, and an address-space limit), or
/// 8 GB when unknown.
///
/// ```
/// use rigport_pipeline::memory;
///
/// let given = memory::process_budget(Some(1 << 30), "the limit given");
/// assert_eq!((given.limit, given.origin), (1 << 30, "the limit given"));
/// let default = memory::process_budget(None, "the limit given");
/// assert!(default.limit > 0 && default.origin.starts_with("default"));
/// ```
pub fn process_budget(given: Option<u64>, given_by: &'static str) -> MemoryBudget {
    match given {
        Some(limit) => MemoryBudget {
            limit,
            origin: given_by,
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
///
/// ```
/// assert_eq!(rigport_pipeline::memory::DEFAULT.limit, 8_000_000_000);
/// ```
pub const DEFAULT: MemoryBudget = MemoryBudget {
    limit: 8_000_000_000,
    origin: "default",
};

static INSTALLED: std::sync::OnceLock<MemoryBudget> = std::sync::OnceLock::new();

/// Sets this process's budget, once: a program's `main` calls it with the budget its
/// flags give ([`process_budget`] or [`shared_budget`]); a second call keeps the first.
/// [`crate::load::Input::new`] takes it.
///
/// ```
/// use rigport_pipeline::memory::{install, installed, process_budget};
/// install(process_budget(Some(1 << 30), "the limit given"));
/// assert_eq!(installed().limit, 1 << 30);
/// ```
pub fn install(budget: MemoryBudget) {
    let _ = INSTALLED.set(budget);
}

/// The budget [`install`]ed, or [`MemoryBudget::UNLIMITED`] when none was (a library
/// caller that sets none).
///
/// ```
/// // No program installed one in this doctest: unlimited.
/// let budget = rigport_pipeline::memory::installed();
/// assert_eq!(budget, rigport_pipeline::MemoryBudget::UNLIMITED);
/// ```
pub fn installed() -> MemoryBudget {
    INSTALLED.get().copied().unwrap_or(MemoryBudget::UNLIMITED)
}

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
    let read = |path: &str| std::fs::read_to_string(path).ok();
    Some(
        [cgroup_limit(read), address_space_limit()]
            .into_iter()
            .flatten()
            .fold(total, u64::min),
    )
}

/// Limits at or above this are "no limit" (cgroup v1 writes `LONG_MAX` rounded to pages).
const NO_CGROUP_LIMIT: u64 = 1 << 62;

/// The smallest memory limit of the cgroups this process is in, read through `read` (a
/// file's text by path): cgroup v2's `memory.max` and v1's `memory.limit_in_bytes`, in the
/// process's own cgroup (from `/proc/self/cgroup`) and every cgroup above it (a limit on a
/// parent binds its children), with the mount's root as a fallback (in a container
/// without its own cgroup namespace the listed path does not exist under the mount).
/// `None` when no limit is set or nothing can be read.
fn cgroup_limit(read: impl Fn(&str) -> Option<String>) -> Option<u64> {
    let own = read("/proc/self/cgroup").unwrap_or_default();
    let mut files: Vec<String> = Vec::new();
    let mut push_chain = |mount: &str, path: &str, file: &str| {
        let mut dir = path.trim_end_matches('/').to_string();
        loop {
            files.push(format!("{mount}{dir}/{file}"));
            match dir.rfind('/') {
                Some(i) => dir.truncate(i),
                None => break,
            }
        }
    };
    let mut seen_v1 = false;
    for line in own.lines() {
        let mut parts = line.splitn(3, ':');
        let (Some(id), Some(controllers), Some(path)) = (parts.next(), parts.next(), parts.next())
        else {
            continue;
        };
        if id == "0" && controllers.is_empty() {
            // v2: mounted at /sys/fs/cgroup (unified) or /sys/fs/cgroup/unified (hybrid).
            push_chain("/sys/fs/cgroup", path, "memory.max");
            push_chain("/sys/fs/cgroup/unified", path, "memory.max");
        } else if controllers.split(',').any(|c| c == "memory") {
            seen_v1 = true;
            push_chain("/sys/fs/cgroup/memory", path, "memory.limit_in_bytes");
        }
    }
    if own.is_empty() {
        files.push("/sys/fs/cgroup/memory.max".into());
    }
    if !seen_v1 {
        files.push("/sys/fs/cgroup/memory/memory.limit_in_bytes".into());
    }
    files
        .iter()
        .filter_map(|f| read(f))
        .filter_map(|text| text.trim().parse::<u64>().ok())
        .filter(|&limit| limit < NO_CGROUP_LIMIT)
        .min()
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
pub(crate) fn check_import(plan: &Source, budget: &MemoryBudget) -> Result<(), OverBudget> {
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

/// `whole` shared by `workers` tasks running at once (0: one per core), each getting an
/// equal part; its origin says so, with `shared_by` naming the tasks. The origin is made
/// once per process: it outlives every message that quotes it.
///
/// ```
/// use rigport_pipeline::{memory::shared_budget, MemoryBudget};
///
/// let whole = MemoryBudget { limit: 1 << 30, origin: "given" };
/// let part = shared_budget(whole, 4, "4 items");
/// assert_eq!((part.limit, part.origin), (1 << 28, "given, shared by 4 items"));
/// assert_eq!(shared_budget(whole, 1, "one"), whole);
/// ```
pub fn shared_budget(whole: MemoryBudget, workers: usize, shared_by: &str) -> MemoryBudget {
    let workers = match workers {
        0 => std::thread::available_parallelism().map_or(1, usize::from),
        n => n,
    };
    if workers <= 1 {
        return whole;
    }
    let origin = format!("{}, shared by {shared_by}", whole.origin);
    whole.shared_by(workers, Box::leak(origin.into_boxed_str()))
}

/// Allocates and frees one 8 MiB block, untouched: for a program's `main`, before any real
/// work.
///
/// glibc's malloc serves each block of 128 KiB or more with its own `mmap` and returns it
/// with `munmap` on free: a conversion reads a file, fills value arrays and builds the
/// output through several such blocks, each paying two system calls and fresh-page faults,
/// and every `munmap` after a helper thread has run also interrupts the other cores to
/// flush their TLBs. Freeing an mmapped block raises glibc's dynamic threshold to that
/// block's size (`M_MMAP_THRESHOLD`, glibc `malloc.c`), so from then on blocks up to 8 MiB
/// come from the heap, which keeps and reuses freed memory. Measured on the kick BVH
/// (BENCHMARKS.md, 300 interleaved runs): 7% less wall and 8% less CPU time per
/// `rigport convert`. Other allocators ignore this; it costs one `mmap` and one `munmap`
/// of pages never touched.
///
/// ```
/// rigport_pipeline::memory::raise_malloc_mmap_threshold();
/// ```
pub fn raise_malloc_mmap_threshold() {
    drop(std::hint::black_box(Vec::<u8>::with_capacity(8 << 20)));
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashMap;

    #[test]
    fn an_import_is_checked_against_the_budget() {
        let plan = Source::Bvh("../../fixtures/bvh/end_sites.bvh".into());
        let roomy = process_budget(Some(1 << 30), "the limit given");
        assert!(check_import(&plan, &roomy).is_ok());
        let tight = MemoryBudget {
            limit: 10,
            origin: "test",
        };
        assert!(check_import(&plan, &tight).is_err());
    }

    fn limit(files: &[(&str, &str)]) -> Option<u64> {
        let files: HashMap<String, String> = files
            .iter()
            .map(|(k, v)| ((*k).to_string(), (*v).to_string()))
            .collect();
        cgroup_limit(|path| files.get(path).cloned())
    }

    #[test]
    fn cgroup_v2_limits_of_the_own_group_and_its_parents() {
        let own = ("/proc/self/cgroup", "0::/user.slice/job.scope\n");
        assert_eq!(
            limit(&[
                own,
                (
                    "/sys/fs/cgroup/user.slice/job.scope/memory.max",
                    "2000000000\n"
                )
            ]),
            Some(2_000_000_000)
        );
        // A parent's limit binds; "max" is none.
        assert_eq!(
            limit(&[
                own,
                ("/sys/fs/cgroup/user.slice/job.scope/memory.max", "max\n"),
                ("/sys/fs/cgroup/user.slice/memory.max", "1000000000\n"),
            ]),
            Some(1_000_000_000)
        );
        assert_eq!(limit(&[own]), None);
    }

    #[test]
    fn cgroup_v1_memory_controller_and_container_roots() {
        let own = (
            "/proc/self/cgroup",
            "9:name=systemd:/\n4:memory:/rptest\n0::/\n",
        );
        assert_eq!(
            limit(&[
                own,
                (
                    "/sys/fs/cgroup/memory/rptest/memory.limit_in_bytes",
                    "1999998976\n"
                ),
                (
                    "/sys/fs/cgroup/memory/memory.limit_in_bytes",
                    "9223372036854771712\n"
                ),
            ]),
            Some(1_999_998_976)
        );
        // A container without a cgroup namespace: the listed path is not under the mount,
        // whose root holds the container's limit.
        let docker = ("/proc/self/cgroup", "4:memory:/docker/abc\n");
        assert_eq!(
            limit(&[
                docker,
                ("/sys/fs/cgroup/memory/memory.limit_in_bytes", "536870912\n"),
            ]),
            Some(536_870_912)
        );
    }
}

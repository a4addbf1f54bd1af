//! This run's memory budget (`--max-memory`; `rigport_pipeline::memory`), set once in
//! `main` and read by every command.

use std::sync::OnceLock;

use rigport_model::budget::MemoryBudget;

static BUDGET: OnceLock<MemoryBudget> = OnceLock::new();

/// Sets the budget from `--max-memory` (bytes) or the default (a second call keeps the
/// first).
pub fn set(max_memory: Option<u64>) {
    let _ = BUDGET.set(rigport_pipeline::memory::process_budget(
        max_memory,
        "--max-memory",
    ));
}

/// Sets the budget as [`set`], shared by `workers` items running at once (`rigport batch
/// --jobs`, 0: one per core), each getting an equal part.
pub fn set_shared(max_memory: Option<u64>, workers: usize) {
    let workers = match workers {
        0 => std::thread::available_parallelism().map_or(1, usize::from),
        n => n,
    };
    let whole = rigport_pipeline::memory::process_budget(max_memory, "--max-memory");
    // Once per process: the origin outlives every message that quotes it.
    let origin = format!(
        "{}, shared by the batch's --jobs items in flight",
        whole.origin
    );
    let _ = BUDGET.set(whole.shared_by(workers, Box::leak(origin.into_boxed_str())));
}

/// This run's budget.
pub fn budget() -> MemoryBudget {
    *BUDGET.get_or_init(|| rigport_pipeline::memory::DEFAULT)
}

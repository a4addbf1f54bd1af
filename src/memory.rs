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
    let shared_by = "the batch's --jobs items in flight";
    let _ = BUDGET.set(rigport_pipeline::memory::shared_budget(
        max_memory,
        "--max-memory",
        workers,
        shared_by,
    ));
}

/// This run's budget.
pub fn budget() -> MemoryBudget {
    *BUDGET.get_or_init(|| rigport_pipeline::memory::DEFAULT)
}

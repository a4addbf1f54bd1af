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
    let _ = BUDGET.set(shared(whole, workers));
}

/// This run's budget.
pub fn budget() -> MemoryBudget {
    *BUDGET.get_or_init(|| rigport_pipeline::memory::DEFAULT)
}

/// `budget` shared by `workers` items in flight at once (`rigport batch --jobs`): each
/// item gets an equal part, so that together they stay within the whole.
fn shared(budget: MemoryBudget, workers: usize) -> MemoryBudget {
    let workers = workers.max(1) as u64;
    if workers == 1 {
        return budget;
    }
    let origin = match budget.origin {
        "--max-memory" => "--max-memory, shared by the batch's --jobs items in flight",
        o if o.starts_with("default: 3/4") => {
            "default: 3/4 of the memory this process may use, shared by the batch's --jobs items in flight"
        }
        _ => "default, shared by the batch's --jobs items in flight",
    };
    MemoryBudget {
        limit: budget.limit / workers,
        origin,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_shared_budget_splits_and_says_so() {
        let whole = rigport_pipeline::memory::process_budget(Some(2_000_000_000), "--max-memory");
        let part = shared(whole, 4);
        assert_eq!(part.limit, 500_000_000);
        assert!(part.origin.contains("--max-memory") && part.origin.contains("shared"));
        assert_eq!(shared(whole, 1), whole);
    }
}

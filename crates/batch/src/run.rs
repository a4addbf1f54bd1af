//! The runner: a shard's items on a rayon pool, each through an [`Executor`].

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use rayon::prelude::*;

use crate::manifest::Item;
use crate::report::{location_of, Failure, FailureKind, Record, Status};
use crate::resume::{self, Sidecar};
use crate::shard::Shard;

/// How to run.
#[derive(Clone, Debug)]
pub struct RunOptions {
    /// Where outputs (and `.rigport-batch/`) go.
    pub out_dir: PathBuf,
    /// Worker threads; 0 means one per core.
    pub jobs: usize,
    /// The items to run.
    pub shard: Shard,
    /// Skip items whose outputs exist and whose sidecar matches.
    pub resume: bool,
    /// The version recorded in resume keys (a new version redoes everything).
    pub version: String,
}

/// An item's failure, as an executor reports it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ItemError {
    /// Input (do not retry) or output (retry).
    pub kind: FailureKind,
    /// The message with its causes, e.g. `walk.bvh:12:5: expected OFFSET`.
    pub message: String,
}

/// Runs one item: reads `item.inputs`, writes every path of `outputs` (the item's outputs
/// inside the output folder, whose parent folders exist), and returns its warnings.
/// Called from several threads at once.
pub trait Executor: Sync {
    /// Runs the item.
    ///
    /// # Errors
    /// The item's failure; the runner records it and goes on.
    fn execute(&self, item: &Item, outputs: &[PathBuf]) -> Result<Vec<String>, ItemError>;
}

impl<F> Executor for F
where
    F: Fn(&Item, &[PathBuf]) -> Result<Vec<String>, ItemError> + Sync,
{
    fn execute(&self, item: &Item, outputs: &[PathBuf]) -> Result<Vec<String>, ItemError> {
        self(item, outputs)
    }
}

/// Counts after each finished item, for a progress bar.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Progress {
    /// Items finished (done, skipped or failed).
    pub finished: usize,
    /// Items in this shard.
    pub total: usize,
    /// Of which failed.
    pub failed: usize,
    /// Of which skipped.
    pub skipped: usize,
}

/// Why a run could not start.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The thread pool could not be built.
    #[error("cannot start {jobs} worker threads")]
    Pool {
        /// Threads asked for.
        jobs: usize,
        /// Why.
        #[source]
        source: rayon::ThreadPoolBuildError,
    },
}

/// Runs the items of `options.shard` and returns their records in manifest order.
/// Each item is a task of its own (idle threads take the next one), so one slow item
/// does not hold back a whole half of the list; memory is bounded by `jobs` items in
/// flight plus one small record per item. A panicking executor fails its item only.
///
/// # Errors
/// The pool could not be built.
pub fn run(
    items: &[Item],
    options: &RunOptions,
    executor: &impl Executor,
    progress: &(dyn Fn(Progress) + Sync),
) -> Result<Vec<Record>, RunError> {
    let mine: Vec<&Item> = items
        .iter()
        .filter(|i| options.shard.contains(i.index))
        .collect();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(options.jobs)
        .thread_name(|i| format!("batch-{i}"))
        .build()
        .map_err(|source| RunError::Pool {
            jobs: options.jobs,
            source,
        })?;
    let finished = AtomicUsize::new(0);
    let failed = AtomicUsize::new(0);
    let skipped = AtomicUsize::new(0);
    let total = mine.len();
    let digests = resume::Digests::default();
    let records = pool.install(|| {
        mine.par_iter()
            .with_max_len(1)
            .map(|item| {
                let record = run_one(item, options, executor, &digests);
                match record.status {
                    Status::Failed => failed.fetch_add(1, Ordering::Relaxed),
                    Status::Skipped => skipped.fetch_add(1, Ordering::Relaxed),
                    Status::Done => 0,
                };
                progress(Progress {
                    finished: finished.fetch_add(1, Ordering::Relaxed) + 1,
                    total,
                    failed: failed.load(Ordering::Relaxed),
                    skipped: skipped.load(Ordering::Relaxed),
                });
                record
            })
            .collect()
    });
    Ok(records)
}

fn slash_path(p: &Path) -> String {
    p.components()
        .map(|c| c.as_os_str().to_string_lossy())
        .collect::<Vec<_>>()
        .join("/")
}

fn run_one(
    item: &Item,
    options: &RunOptions,
    executor: &impl Executor,
    digests: &resume::Digests,
) -> Record {
    let start = Instant::now();
    let outputs: Vec<PathBuf> = item
        .outputs
        .iter()
        .map(|o| options.out_dir.join(o))
        .collect();
    let mut record = Record {
        index: item.index,
        id: item.id.clone(),
        command: item.command.clone(),
        status: Status::Done,
        outputs: item.outputs.iter().map(|o| slash_path(o)).collect(),
        warnings: Vec::new(),
        error: None,
        seconds: 0.0,
    };
    // An unreadable input has no key: the item runs and reports the error itself.
    let key = resume::key(item, &options.version, digests).ok();
    let sidecar_path = resume::sidecar_path(&options.out_dir, &item.id);
    if options.resume {
        if let (Some(key), Some(sidecar)) = (&key, resume::read_sidecar(&sidecar_path, &item.id)) {
            if &sidecar.key == key {
                if let Some(error) = sidecar.error {
                    record.status = Status::Failed;
                    record.error = Some(error);
                    record.seconds = elapsed(start);
                    return record;
                }
                if outputs.iter().all(|o| o.is_file()) {
                    record.status = Status::Skipped;
                    record.warnings = sidecar.warnings;
                    record.seconds = elapsed(start);
                    return record;
                }
            }
        }
    }
    // A sidecar of an older state must not survive a failed redo.
    let _ = std::fs::remove_file(&sidecar_path);
    let result = execute(item, executor, &outputs).map(|warnings| {
        record.warnings = warnings;
    });
    let failure = result.err().map(|e| Failure {
        kind: e.kind,
        location: location_of(&e.message),
        message: e.message,
    });
    let recorded = failure
        .as_ref()
        .filter(|f| f.kind == FailureKind::Input)
        .cloned();
    if let (Some(key), true) = (key, failure.is_none() || recorded.is_some()) {
        let sidecar = Sidecar {
            id: item.id.clone(),
            key,
            warnings: record.warnings.clone(),
            error: recorded,
        };
        if let Err(e) = resume::write_sidecar(&sidecar_path, &sidecar) {
            let message = format!("cannot write {}: {e}", sidecar_path.display());
            record.error = Some(Failure {
                kind: FailureKind::Output,
                location: location_of(&message),
                message,
            });
        }
    }
    if failure.is_some() {
        record.error = failure;
    }
    if record.error.is_some() {
        record.status = Status::Failed;
    }
    record.seconds = elapsed(start);
    record
}

/// Seconds since `start`, rounded to milliseconds.
fn elapsed(start: Instant) -> f64 {
    (start.elapsed().as_secs_f64() * 1000.0).round() / 1000.0
}

fn execute(
    item: &Item,
    executor: &impl Executor,
    outputs: &[PathBuf],
) -> Result<Vec<String>, ItemError> {
    for o in outputs {
        if let Some(dir) = o.parent() {
            std::fs::create_dir_all(dir).map_err(|e| ItemError {
                kind: FailureKind::Output,
                message: format!("cannot write {}: {e}", dir.display()),
            })?;
        }
    }
    catch_unwind(AssertUnwindSafe(|| executor.execute(item, outputs))).unwrap_or_else(|panic| {
        let what = panic
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| panic.downcast_ref::<String>().cloned())
            .unwrap_or_default();
        Err(ItemError {
            kind: FailureKind::Input,
            message: format!("internal error (a bug in rigport, please report it): {what}"),
        })
    })
}

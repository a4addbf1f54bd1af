//! rigport's batch engine: many items from one manifest, on one machine or many.
//!
//! The engine knows no file format and no command: a [`manifest`] lists items (or a folder
//! is expanded into `convert` items with `rigport_import::detect`), a [`Shard`] picks this
//! process's share, and [`run`] hands each item to an [`Executor`] on a rayon pool, with
//! [`resume`] sidecars to skip finished work and one [`Record`] per item for the
//! [`report`]. The `rigport batch` command's executor runs the CLI's commands in-process.
//!
//! ```
//! use std::path::PathBuf;
//! use rigport_batch::{manifest, run, Item, ItemError, RunOptions, Shard, Status};
//!
//! let dir = tempfile::tempdir()?;
//! let text = r#"{"id": "a", "command": "copy", "inputs": ["in.txt"], "outputs": ["a/out.txt"]}
//! {"id": "b", "command": "copy", "inputs": ["missing.txt"], "outputs": ["b.txt"]}"#;
//! std::fs::write(dir.path().join("in.txt"), "hello")?;
//! let items = manifest::parse(text, "m.jsonl", dir.path())?;
//! // An executor: here, copy the one input to the one output.
//! let copy = |item: &Item, outputs: &[PathBuf]| -> Result<Vec<String>, ItemError> {
//!     let bytes = std::fs::read(&item.inputs[0]).map_err(|e| ItemError {
//!         kind: rigport_batch::FailureKind::Input,
//!         message: format!("{}: {e}", item.inputs[0].display()),
//!     })?;
//!     std::fs::write(&outputs[0], bytes).map_err(|e| ItemError {
//!         kind: rigport_batch::FailureKind::Output,
//!         message: e.to_string(),
//!     })?;
//!     Ok(vec![])
//! };
//! let options = RunOptions {
//!     out_dir: dir.path().join("out"),
//!     jobs: 2,
//!     shard: Shard::ALL,
//!     resume: true,
//!     version: "test".into(),
//! };
//! let records = run(&items, &options, &copy, &|_| {})?;
//! assert_eq!(records[0].status, Status::Done);
//! assert_eq!(records[1].status, Status::Failed);
//! assert_eq!(rigport_batch::exit_code(&records), 1);
//! // Resumed: the finished item is skipped, the bad input reported again without a rerun.
//! let again = run(&items, &options, &copy, &|_| {})?;
//! assert_eq!(again[0].status, Status::Skipped);
//! assert_eq!(again[1].error, records[1].error);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![warn(missing_docs)]

pub mod command_line;
pub mod manifest;
pub mod report;
pub mod resume;
mod run;
pub mod shard;

pub use manifest::{Expansion, Item, ManifestError};
pub use report::{exit_code, Failure, FailureKind, Record, Status, Summary};
pub use run::{run, Executor, ItemError, Progress, RunError, RunOptions};
pub use shard::{Shard, ShardError};

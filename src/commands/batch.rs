//! `rigport batch` and `rigport batch-report`: the CLI over `rigport_batch`. Each item is
//! one rigport command run in-process: its arguments are parsed as a command line, and the
//! command runs with a context that captures its warnings for the report.

use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

use anyhow::{anyhow, Result};
use rigport_batch::{manifest, report, FailureKind, Item, ItemError, Record, Shard, Summary};

use crate::context::{Captured, Context};
use crate::exit::{self, OutputError, UsageError};

/// `rigport batch`.
#[derive(Debug, clap::Args)]
pub struct BatchArgs {
    /// A JSON Lines manifest, or a folder: one `convert` item per asset found in it.
    pub manifest: PathBuf,
    /// The output folder (item outputs are relative to it).
    #[arg(long, short, value_name = "OUT_DIR")]
    pub output: PathBuf,
    /// Worker threads (default: one per core).
    #[arg(long, short, value_name = "N")]
    pub jobs: Option<usize>,
    /// Run shard I of N: the items at manifest positions k with k mod N = I. Default from
    /// JOB_COMPLETION_INDEX/JOB_COMPLETIONS (Kubernetes Indexed Job) or
    /// SLURM_ARRAY_TASK_ID/SLURM_ARRAY_TASK_COUNT (Slurm array), else every item.
    #[arg(long, value_name = "I/N")]
    pub shard: Option<String>,
    /// Skip items whose outputs exist and whose sidecar records the same input bytes,
    /// options and rigport version.
    #[arg(long)]
    pub resume: bool,
    /// The report (default: OUT_DIR/.rigport-batch/report-I-of-N.jsonl).
    #[arg(long, value_name = "R.jsonl")]
    pub report: Option<PathBuf>,
    /// For a folder: the output extension of its items (glb, gltf, usda, usdc or usdz).
    #[arg(long, default_value = "glb", value_name = "EXT")]
    pub to: String,
    /// For a folder: options every item gets, split on spaces ("--fps 30").
    #[arg(long, value_name = "ARGS", allow_hyphen_values = true)]
    pub convert_options: Option<String>,
}

/// `rigport batch-report`.
#[derive(Debug, clap::Args)]
pub struct BatchReportArgs {
    /// The reports to merge.
    #[arg(required = true)]
    pub reports: Vec<PathBuf>,
    /// Also write the merged report (manifest order) here.
    #[arg(long, short, value_name = "R.jsonl")]
    pub output: Option<PathBuf>,
}

/// Parses one item's command line (`rigport COMMAND ...`) and runs it in-process with a
/// quiet context that collects its warnings into `captured`: the command's result, or
/// clap's message when the arguments do not parse; with `deny_warnings` (or the
/// item's own flag) a warning fails it. Passed in by the dispatcher (`commands::run_item`):
/// command modules do not import each other, the dispatcher or the top-level parser.
pub type RunItem = fn(Vec<OsString>, bool, Captured) -> Result<Result<()>, String>;

/// The commands an item may run: those that read inputs and write one output file. Files
/// an item reads besides its inputs (retarget's `--onto` rig and `--map`, combine's motions, cloth's garment,
/// ik's handles, animate's keys) go in its options.
const COMMANDS: [&str; 13] = [
    "convert", "animate", "retime", "sequence", "ik", "footlock", "retarget", "combine", "cloth",
    "skin", "bake", "render", "eval",
];

/// Runs `batch`.
pub fn run(ctx: &Context, args: &BatchArgs, run_item: RunItem) -> Result<()> {
    let how = manifest::Expansion::new(
        &args.to,
        args.convert_options.as_deref(),
        Some(args.output.clone()),
    );
    let items = manifest::load(&args.manifest, &how)?;
    let shard = Shard::resolve(args.shard.as_deref(), "--shard", |k| std::env::var(k).ok())
        .map_err(|e| match e {
            e @ rigport_batch::ShardError::MissingCount { .. } => {
                UsageError(format!("{e} (or pass --shard I/N)"))
            }
            e => UsageError(e.to_string()),
        })?;
    let options = rigport_batch::RunOptions {
        out_dir: args.output.clone(),
        jobs: args.jobs.unwrap_or(0),
        shard,
        resume: args.resume,
        version: env!("CARGO_PKG_VERSION").into(),
    };
    let total = items.iter().filter(|i| shard.contains(i.index)).count();
    let bar = ctx.bar(
        total,
        "{wide_bar} {pos}/{len} items, {per_sec}, ETA {eta}, {msg}",
    );
    let deny = ctx.deny_warnings;
    let execute = |item: &Item, outputs: &[PathBuf]| execute(run_item, deny, item, outputs);
    let records = rigport_batch::run(&items, &options, &execute, &|p| {
        bar.set_position(p.finished as u64);
        bar.set_message(format!("{} failed, {} skipped", p.failed, p.skipped));
    })?;
    bar.finish_and_clear();
    let path = (args.report.clone())
        .unwrap_or_else(|| rigport_batch::resume::default_report(&args.output, shard));
    finish(ctx, &records, Some(&path))
}

/// Runs `batch-report`: merges, writes the merged report if asked, prints the summary and
/// exits as `batch` would have for all the items together.
pub fn report(ctx: &Context, args: &BatchReportArgs) -> Result<()> {
    finish(ctx, &report::merge(&args.reports)?, args.output.as_deref())
}

/// Writes the report, prints the summary, and fails as the records say (exit 1 or 3).
fn finish(ctx: &Context, records: &[Record], path: Option<&Path>) -> Result<()> {
    if let Some(path) = path {
        report::write(path, records).map_err(|e| {
            let path = path.display().to_string();
            anyhow::Error::new(e).context(OutputError { path })
        })?;
    }
    if !ctx.quiet {
        eprint!("{}", Summary::of(records));
        path.inspect(|p| eprintln!("report: {}", p.display()));
    }
    match report::verdict(records) {
        None => Ok(()),
        Some(v) => match v.failed_output {
            Some(path) => Err(anyhow!(v.message).context(OutputError { path })),
            None => Err(anyhow!(v.message)),
        },
    }
}

/// Runs one item in-process.
fn execute(
    run_item: RunItem,
    deny_warnings: bool,
    item: &Item,
    outputs: &[PathBuf],
) -> Result<Vec<String>, ItemError> {
    let argv = rigport_batch::command_line::argv("rigport", item, &COMMANDS, outputs)?;
    let captured = Arc::new(Mutex::new(Vec::new()));
    let result = run_item(argv, deny_warnings, Arc::clone(&captured))
        .map_err(|text| rigport_batch::command_line::unparsed(item, &text))?;
    let warnings = std::mem::take(&mut *captured.lock().unwrap_or_else(|e| e.into_inner()));
    result.map(|()| warnings).map_err(|e| ItemError {
        kind: match exit::code_for(&e) {
            exit::OUTPUT => FailureKind::Output,
            _ => FailureKind::Input,
        },
        message: format!("{e:#}"),
    })
}

//! `rigport batch` and `rigport batch-report`: the CLI over `rigport_batch`. Each item is
//! one rigport command run in-process: its arguments are parsed as a command line, and the
//! command runs with a context that captures its warnings for the report.

use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

use anyhow::{anyhow, Result};
use clap::Parser as _;
use rigport_batch::{manifest, report, FailureKind, Item, ItemError, Record, Shard, Summary};

use crate::cli::{BatchArgs, BatchReportArgs, Cli, Command};
use crate::context::Context;
use crate::exit::{self, OutputError, UsageError};

/// Runs one parsed command (`commands::run_command`, passed in: command modules do not
/// import each other or the dispatcher).
pub type RunCommand = fn(Context, Command) -> Result<()>;

/// The commands an item may run: those that read inputs and write one output file.
const COMMANDS: [&str; 8] = [
    "convert", "animate", "retime", "sequence", "ik", "bake", "render", "eval",
];

/// Runs `batch`.
pub fn run(ctx: &Context, args: &BatchArgs, run_command: RunCommand) -> Result<()> {
    let how = manifest::Expansion::new(
        &args.to,
        args.convert_options.as_deref(),
        Some(args.output.clone()),
    );
    let items = manifest::load(&args.manifest, &how)?;
    let shard = Shard::resolve(args.shard.as_deref(), |k| std::env::var(k).ok())
        .map_err(|e| UsageError(e.to_string()))?;
    let options = rigport_batch::RunOptions {
        out_dir: args.output.clone(),
        jobs: args.jobs.unwrap_or(0),
        shard,
        resume: args.resume,
        version: env!("CARGO_PKG_VERSION").into(),
    };
    let bar = progress_bar(
        ctx,
        items.iter().filter(|i| shard.contains(i.index)).count(),
    );
    let deny = ctx.deny_warnings;
    let execute = |item: &Item, outputs: &[PathBuf]| execute(run_command, deny, item, outputs);
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
    let Some(verdict) = report::verdict(records) else {
        return Ok(());
    };
    let output_failure = records
        .iter()
        .find(|r| (r.error.as_ref()).is_some_and(|e| e.kind == FailureKind::Output));
    match output_failure {
        Some(r) => Err(anyhow!(verdict).context(OutputError {
            path: r.outputs.join(", "),
        })),
        None => Err(anyhow!(verdict)),
    }
}

/// Runs one item in-process.
fn execute(
    run_command: RunCommand,
    deny_warnings: bool,
    item: &Item,
    outputs: &[PathBuf],
) -> Result<Vec<String>, ItemError> {
    let input = |message: String| ItemError {
        kind: FailureKind::Input,
        message,
    };
    if !COMMANDS.contains(&item.command.as_str()) {
        let expected = COMMANDS.join(", ");
        let message = format!(
            "command {:?} cannot run in a batch; expected one of {expected}",
            item.command
        );
        return Err(input(message));
    }
    let [output] = outputs else {
        return Err(input(format!("{} writes one output", item.command)));
    };
    let mut argv: Vec<OsString> = vec!["rigport".into(), item.command.clone().into()];
    argv.extend(item.inputs.iter().map(|p| p.clone().into_os_string()));
    argv.extend(item.options.iter().map(OsString::from));
    argv.extend(["-o".into(), output.clone().into_os_string()]);
    let cli = Cli::try_parse_from(argv).map_err(|e| {
        let text = e.to_string();
        let first = text.lines().next().unwrap_or_default();
        input(format!(
            "{}: {}",
            item.command,
            first.trim_start_matches("error: ")
        ))
    })?;
    let captured = Arc::new(Mutex::new(Vec::new()));
    let ctx = Context {
        quiet: true,
        deny_warnings: deny_warnings || cli.deny_warnings,
        captured: Some(Arc::clone(&captured)),
    };
    let result = run_command(ctx, cli.command);
    let warnings = std::mem::take(&mut *captured.lock().unwrap_or_else(|e| e.into_inner()));
    result.map(|()| warnings).map_err(|e| ItemError {
        kind: match exit::code_for(&e) {
            exit::OUTPUT => FailureKind::Output,
            _ => FailureKind::Input,
        },
        message: format!("{e:#}"),
    })
}

/// Items, rate, ETA and failures, on a terminal only.
fn progress_bar(ctx: &Context, total: usize) -> indicatif::ProgressBar {
    use std::io::IsTerminal;
    if ctx.quiet || !std::io::stderr().is_terminal() {
        return indicatif::ProgressBar::hidden();
    }
    let template = "{wide_bar} {pos}/{len} items, {per_sec}, ETA {eta}, {msg}";
    let style = indicatif::ProgressStyle::with_template(template)
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar());
    indicatif::ProgressBar::new(total as u64).with_style(style)
}

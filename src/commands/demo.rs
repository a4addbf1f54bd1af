//! `rigport demo`: the built-in procedural character (`rigport_pipeline::demo`), written
//! with no input files.

use std::path::PathBuf;

use anyhow::Result;
use rigport_pipeline::demo::DemoOptions;

use crate::context::Context;

/// `rigport demo`.
#[derive(Debug, clap::Args)]
pub struct DemoArgs {
    /// Folder to write into (created if missing).
    #[arg(long, short, default_value = "rigport-demo", value_name = "DIR")]
    pub output: PathBuf,
    /// Mesh detail: 1 (default, several thousand vertices) and up.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=4))]
    pub detail: u32,
    /// The shared corpus folder: one rig of each family in it is rendered to
    /// `DIR/corpus/<family>.png` (default: `../shared/corpus` relative to the current
    /// directory; skipped with a note when absent).
    #[arg(long, value_name = "CORPUS_DIR", conflicts_with = "no_corpus")]
    pub corpus: Option<PathBuf>,
    /// Do not render corpus rigs.
    #[arg(long)]
    pub no_corpus: bool,
}

/// Runs `demo`.
pub fn run(ctx: &Context, args: &DemoArgs) -> Result<()> {
    let options = DemoOptions {
        detail: args.detail,
        output: args.output.clone(),
        // The README runs the demo from the repository root, beside which the corpus lives.
        corpus: (!args.no_corpus)
            .then(|| (args.corpus.clone()).unwrap_or_else(|| PathBuf::from("../shared/corpus"))),
    };
    ctx.run(|progress| rigport_pipeline::demo(&options, progress))
}

//! `rigport bake` (being written).

use anyhow::Result;

use super::Context;

/// `rigport bake` arguments.
#[derive(Debug, clap::Args)]
pub struct BakeArgs {
    /// The rig.
    #[command(flatten)]
    pub input: crate::cli::InputArgs,
}

/// Runs `bake`.
pub fn run(_ctx: &Context, _args: &BakeArgs) -> Result<()> {
    anyhow::bail!("rigport bake is not available yet")
}

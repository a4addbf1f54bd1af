//! `rigport render` (being written).

use anyhow::Result;

use super::Context;

/// `rigport render` arguments.
#[derive(Debug, clap::Args)]
pub struct RenderArgs {
    /// The rig.
    #[command(flatten)]
    pub input: crate::cli::InputArgs,
}

/// Runs `render`.
pub fn run(_ctx: &Context, _args: &RenderArgs) -> Result<()> {
    anyhow::bail!("rigport render is not available yet")
}

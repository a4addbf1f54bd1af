//! `rigport verify`: whether CANDIDATE plays like REFERENCE (`rigport_pipeline::verify`);
//! exit code 5 when it does not.

use std::path::PathBuf;

use anyhow::Result;
use rigport_pipeline::load::Input;
use rigport_pipeline::verify::{Clips, Times, VerifyOptions, DEFAULT_TOLERANCE};

use crate::args::frame_rate;
use crate::context::Context;
use crate::exit::Mismatch;

/// `rigport verify` (docs/help/verify.txt).
#[derive(Debug, clap::Args)]
pub struct VerifyArgs {
    /// The file (or rig folder) that plays right.
    pub reference: PathBuf,
    /// The file (or rig folder) to check against it.
    pub candidate: PathBuf,
    /// AMC motions of an .asf REFERENCE (as `convert --motion`).
    #[arg(long, value_name = "M.amc")]
    pub motion: Vec<PathBuf>,
    /// The reference's clip to compare (default: the first).
    #[arg(long, value_name = "NAME", conflicts_with = "all_clips")]
    pub clip: Option<String>,
    /// Compare every clip (paired by name, then order).
    #[arg(long)]
    pub all_clips: bool,
    /// Compare every 1/F s (default: at every key time of either clip).
    #[arg(long, value_name = "F", value_parser = frame_rate, conflicts_with = "at_keys")]
    pub fps: Option<f32>,
    /// Compare only at the key times both clips share.
    #[arg(long)]
    pub at_keys: bool,
    /// Pass within this fraction of the reference's bounding-box diagonal.
    #[arg(long, value_name = "REL", default_value_t = DEFAULT_TOLERANCE)]
    pub tol: f64,
    /// Print the report as JSON.
    #[arg(long)]
    pub json: bool,
    /// Draw the worst frame coloured by deviation, with a colour scale, to this PNG.
    #[arg(long, value_name = "OUT.png")]
    pub picture: Option<PathBuf>,
}

/// Runs `verify`: prints the report, and fails with [`Mismatch`] (exit 5) beyond `--tol`.
pub fn run(ctx: &Context, args: &VerifyArgs) -> Result<()> {
    let input = |path: &PathBuf| Input::new(vec![path.clone()]);
    let options = VerifyOptions {
        clips: Clips::from_flags(args.clip.as_deref(), args.all_clips),
        times: Times::from_flags(args.fps, args.at_keys),
        tolerance: args.tol,
        json: args.json,
        picture: args.picture.clone(),
        ..VerifyOptions::new(input(&args.candidate))
    };
    let mut passed = true;
    ctx.run(|progress| {
        let mut reference = input(&args.reference);
        reference.files.motions.clone_from(&args.motion);
        let verdict = rigport_pipeline::verify(&reference, &options, progress)?;
        passed = verdict.passed;
        Ok(verdict.report)
    })?;
    anyhow::ensure!(passed, Mismatch(args.tol));
    Ok(())
}

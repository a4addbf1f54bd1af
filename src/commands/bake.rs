//! `rigport bake`: a dual quaternion skinning result baked into an ordinary (LBS) glTF as
//! per-frame corrective morph targets in bind space (FORMATS.md, "glTF 2.0 skins and
//! animation"; the eval side is `rigport_deform::bake`).

use anyhow::{bail, Result};
use rigport_deform::bake::asset::{bake_dqs, DqsBakeOptions};
use rigport_model::{SkinningMethod, Warning};

use crate::cli::{BakeArgs, OutputArgs};
use crate::context::Context;
use crate::input;
use crate::output;

/// Runs `bake`.
pub fn run(ctx: &Context, args: &BakeArgs) -> Result<()> {
    if !output::format_of(&args.output)?.is_gltf() {
        bail!(
            "{}: bake writes glTF (.glb/.gltf); a .usda declares DQS directly (`rigport convert --skinning dqs`)",
            args.output.display()
        );
    }
    if let Some(fps) = args.fps {
        if !(fps.is_finite() && fps > 0.0) {
            bail!("--fps {fps}: expected a positive frame rate");
        }
    }
    if let Some(t) = args.threshold {
        if !(t.is_finite() && t >= 0.0) {
            bail!("--threshold {t}: expected a distance >= 0");
        }
    }
    let out_args = OutputArgs {
        output: args.output.clone(),
        max_influences: Some(args.max_influences),
        // The DQS corrections are measured against what truncation leaves.
        influences_fit: rigport_model::InfluencesFit::Truncate,
        reduce_tolerance: None,
        // The file itself is LBS; the DQS result lives in its morph targets.
        skinning: Some(SkinningMethod::Lbs),
        up_axis: None,
        meters_per_unit: None,
    };
    let (plan, imported) = ctx.step("reading input", || input::load_single(&args.input))?;
    let mut asset = imported.asset;
    let mut warnings = imported.warnings;
    let skinning = args
        .skinning
        .unwrap_or(asset.skins.first().map(|s| s.method).unwrap_or_default());
    if skinning == SkinningMethod::Lbs {
        warnings.push(Warning::Note {
            location: plan.label(),
            message: "--skinning lbs: glTF skins with LBS already, no corrective targets needed; writing the plain file".into(),
        });
        return output::write_asset(ctx, &asset, warnings, &out_args);
    }
    let reports = ctx.step("baking DQS correctives", || {
        bake_dqs(
            &mut asset,
            &DqsBakeOptions {
                clip: args.clip.as_deref(),
                fps: args.fps,
                threshold: args.threshold,
                correctives: args.correctives,
            },
            // Exactly the influences the glTF will hold, so the viewer's LBS is what we invert.
            |skeleton, skin| {
                rigport_export::gltf_influences(skeleton, skin, usize::from(args.max_influences))
            },
            &plan.label(),
            &mut warnings,
        )
    })?;
    // The DQS result is baked into the targets: the file itself skins linearly.
    asset
        .skins
        .iter_mut()
        .for_each(|s| s.method = Default::default());
    output::write_asset(ctx, &asset, warnings, &out_args)?;
    if !ctx.quiet {
        for report in &reports {
            eprintln!("{report}");
        }
        let mut size = std::fs::metadata(&args.output).map_or(0, |m| m.len());
        if args
            .output
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("gltf"))
        {
            size += std::fs::metadata(args.output.with_extension("bin")).map_or(0, |m| m.len());
        }
        eprintln!("file size: {size} bytes");
    }
    Ok(())
}

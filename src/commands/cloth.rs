//! `rigport cloth`: a garment simulated on the animated body and baked into the output
//! (the work is `rigport_deform::cloth::asset`).

use std::path::Path;

use anyhow::{Context as _, Result};
use rigport_deform::cloth::asset::{self, GarmentSource};
use rigport_deform::cloth::{ClothOptions, PinSelection};

use crate::cli::{ClothArgs, OutputArgs};
use crate::context::Context;
use crate::{input, output};

/// Runs `cloth`.
pub fn run(ctx: &Context, args: &ClothArgs) -> Result<()> {
    let (plan, imported) = ctx.step("reading input", || input::load_single(&args.input))?;
    let mut asset = imported.asset;
    let mut warnings = imported.warnings;
    let garment_path = Path::new(&args.garment);
    let source =
        if garment_path.is_file() {
            let obj = rigport_import::obj::import(garment_path)
                .with_context(|| format!("cannot read the garment {}", garment_path.display()))?;
            warnings.extend(obj.warnings);
            let mesh =
                obj.asset.meshes.into_iter().next().with_context(|| {
                    format!("the garment {} holds no mesh", garment_path.display())
                })?;
            GarmentSource::Mesh(Box::new(mesh))
        } else {
            GarmentSource::Named(&args.garment)
        };
    let mut pins = Vec::new();
    if !args.pin_vertices.is_empty() {
        pins.push(PinSelection::Vertices(args.pin_vertices.clone()));
    }
    pins.extend(args.pin_below.map(PinSelection::Below));
    pins.extend(args.pin_above.map(PinSelection::Above));
    let opts = ClothOptions {
        clip: args.clip.as_deref(),
        fps: args.fps,
        seconds: args.seconds,
        substeps: args.substeps,
        thickness: args.thickness,
        ..ClothOptions::default()
    };
    let bar = progress_bar(ctx);
    let report = asset::run(
        &mut asset,
        source,
        &pins,
        &opts,
        args.targets.map(|k| k as usize),
        &mut warnings,
        |done, total| {
            if let Some(bar) = &bar {
                bar.set_length(total as u64);
                bar.set_position(done as u64);
            }
        },
    )
    .with_context(|| format!("cannot simulate the garment on {}", plan.label()))?;
    if let Some(bar) = bar {
        bar.finish_and_clear();
    }
    let out_args = OutputArgs {
        output: args.output.clone(),
        max_influences: None,
        influences_fit: rigport_model::InfluencesFit::Truncate,
        reduce_tolerance: None,
        skinning: None,
        up_axis: None,
        meters_per_unit: None,
    };
    output::write_asset_with(ctx, &asset, warnings, &out_args, true)?;
    if !ctx.quiet {
        eprintln!("{report}");
    }
    Ok(())
}

/// A frame counter with ETA on stderr, on a terminal and without --quiet only.
fn progress_bar(ctx: &Context) -> Option<indicatif::ProgressBar> {
    use std::io::IsTerminal;
    if ctx.quiet || !std::io::stderr().is_terminal() {
        return None;
    }
    let bar = indicatif::ProgressBar::new(0);
    if let Ok(style) = indicatif::ProgressStyle::with_template(
        "simulating cloth {bar:30} {pos}/{len} frames, ETA {eta}",
    ) {
        bar.set_style(style);
    }
    Some(bar)
}

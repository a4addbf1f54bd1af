//! `rigport demo`: the built-in procedural character (`rigport_demo`), written with no
//! input files.

use std::path::{Path, PathBuf};

use anyhow::{Context as _, Result};
use rigport_demo::{clips, corpus, pictures};
use rigport_export::{GltfOptions, UsdOptions};

use crate::cli::DemoArgs;
use crate::context::Context;
use crate::exit::OutputError;

/// Runs `demo`.
pub fn run(ctx: &Context, args: &DemoArgs) -> Result<()> {
    let demo = ctx.step("building the demo character", || {
        rigport_demo::build(args.detail)
    })?;
    std::fs::create_dir_all(&args.output).with_context(|| OutputError {
        path: args.output.display().to_string(),
    })?;
    // The clips' keys and handles, as examples for `rigport animate` and `rigport ik`.
    let keys_path = args.output.join("wave.keys.json");
    write(&keys_path, clips::WAVE_KEYS_JSON.as_bytes())?;
    let reach_path = args.output.join("reach.handles.json");
    write(&reach_path, clips::REACH_HANDLES_JSON.as_bytes())?;
    let twist_path = args.output.join("twist.keys.json");
    write(&twist_path, clips::TWIST_KEYS_JSON.as_bytes())?;
    let out = args.output.join("demo.glb");
    let prepared = rigport_export::prepare_gltf(&demo.asset, &out, &GltfOptions::default())?;
    let out_usd = args.output.join("demo.usda");
    let prepared_usd = rigport_export::prepare_usd(&demo.asset, &out_usd, &UsdOptions::default())?;
    let mut warnings = demo.warnings.clone();
    warnings.extend(prepared.warnings().iter().cloned());
    warnings.extend(prepared_usd.warnings().iter().cloned());
    let limit = usize::from(rigport_demo::DQS_INFLUENCES);
    let (twist_asset, bake_reports) = ctx.step("baking DQS correctives", || {
        rigport_demo::twist_dqs(
            &demo,
            |skeleton, skin| rigport_export::gltf_influences(skeleton, skin, limit),
            &mut warnings,
        )
    })?;
    let out_dqs = args.output.join("twist_dqs.glb");
    let options = GltfOptions {
        max_influences: limit,
    };
    let prepared_dqs = rigport_export::prepare_gltf(&twist_asset, &out_dqs, &options)?;
    warnings.extend(prepared_dqs.warnings().iter().cloned());
    let (skirt_asset, skirt_report) = ctx.step("simulating the skirt", || {
        rigport_demo::skirt::bake(&demo, &mut warnings, |_, _| {})
    })?;
    let out_skirt = args.output.join("skirt.glb");
    let prepared_skirt =
        rigport_export::prepare_gltf(&skirt_asset, &out_skirt, &GltfOptions::default())?;
    warnings.extend(prepared_skirt.warnings().iter().cloned());
    ctx.report(&warnings)?;
    for (prepared, path) in [
        (&prepared, &out),
        (&prepared_dqs, &out_dqs),
        (&prepared_skirt, &out_skirt),
    ] {
        prepared.write().with_context(|| OutputError {
            path: path.display().to_string(),
        })?;
    }
    prepared_usd.write().with_context(|| OutputError {
        path: out_usd.display().to_string(),
    })?;
    let pictures = ctx.step("rendering pictures", || {
        let mut all = pictures::pictures(&demo)?;
        all.push(pictures::skirt_picture(&skirt_asset)?);
        Ok::<_, rigport_demo::DemoError>(all)
    })?;
    for picture in &pictures {
        write(&args.output.join(&picture.file), &picture.bytes)?;
    }
    let corpus_lines = match corpus_dir(args) {
        None => Vec::new(),
        Some(dir) if !dir.is_dir() => vec![format!(
            "corpus: {} not found; no corpus pictures (--corpus DIR to point at it)",
            dir.display()
        )],
        Some(dir) => ctx.step("rendering corpus rigs", || {
            corpus_pictures(&dir, &args.output)
        })?,
    };
    if ctx.quiet {
        return Ok(());
    }
    let asset = &demo.asset;
    let mesh = &asset.meshes[0];
    let (lo, hi) = mesh.bounds().unwrap_or_default();
    let clip = |k: usize| asset.clips.get(k).map_or(0.0, |c| c.duration());
    println!("rigport demo: a procedural character in Pinocchio's layout");
    println!(
        "  mesh: {} vertices, {} triangles, {:.2} m tall",
        mesh.vertex_count(),
        mesh.triangles.len(),
        hi.y - lo.y
    );
    println!(
        "  skeleton: {} joints (one per bone, rotating about its head)",
        asset.skeleton.len()
    );
    let keys = keys_path.display();
    println!("  clip \"wave\": {:.1} s, keyed in {keys}", clip(0));
    let reach = reach_path.display();
    println!(
        "  clip \"reach\": {:.1} s, IK (damped least squares) from {reach}",
        clip(1)
    );
    let twist = twist_path.display();
    println!(
        "  clip \"twist\": {:.1} s, the left forearm twists 150 deg, keyed in {twist}",
        clip(2)
    );
    println!("  wrote {} and {}", out.display(), out_usd.display());
    let dqs = out_dqs.display();
    println!("  wrote {dqs} (clip \"twist\", DQS baked into corrective morph targets)");
    for line in bake_reports
        .iter()
        .flat_map(|r| r.to_string().lines().map(String::from).collect::<Vec<_>>())
    {
        println!("    {line}");
    }
    let skirt = out_skirt.display();
    println!("  wrote {skirt} (clip \"wave\" with a skirt simulated on it, morph targets)");
    println!("    {skirt_report}");
    for picture in &pictures {
        let path = args.output.join(&picture.file);
        println!("  wrote {} ({})", path.display(), picture.what);
    }
    for line in &corpus_lines {
        println!("  {line}");
    }
    Ok(())
}

/// Writes `bytes` to `path` atomically.
fn write(path: &Path, bytes: &[u8]) -> Result<()> {
    rigport_export::write_atomic(path, bytes).with_context(|| OutputError {
        path: path.display().to_string(),
    })
}

/// The corpus folder to render from, `None` with `--no-corpus`.
fn corpus_dir(args: &DemoArgs) -> Option<PathBuf> {
    if args.no_corpus {
        return None;
    }
    // The README runs the demo from the repository root, beside which the corpus lives.
    Some(
        args.corpus
            .clone()
            .unwrap_or_else(|| PathBuf::from("../shared/corpus")),
    )
}

/// Renders one rig of each corpus family to `out/corpus/<family>.png` (Model1's keys
/// beside it as an example); a rig that fails to load or render becomes a warning line on
/// stderr, not a failure. Returns one line per picture written.
///
/// # Errors
/// The `corpus` output folder cannot be created, or a picture cannot be written.
fn corpus_pictures(corpus: &Path, out: &Path) -> Result<Vec<String>> {
    let out = out.join("corpus");
    std::fs::create_dir_all(&out).with_context(|| OutputError {
        path: out.display().to_string(),
    })?;
    let mut lines = Vec::new();
    for rig in &corpus::CORPUS_RIGS {
        let first = rig.files.first().copied().unwrap_or(rig.family);
        let picture = match corpus::picture(corpus, rig) {
            Ok(picture) => picture,
            Err(e) => {
                let e = anyhow::Error::from(e);
                eprintln!(
                    "warning: corpus {}: skipped: {e:#}",
                    corpus.join(first).display()
                );
                continue;
            }
        };
        if rig.model1_keys {
            let keys = out.join(format!("{}.keys.json", rig.family));
            write(&keys, clips::MODEL1_KEYS_JSON.as_bytes())?;
        }
        let path = out.join(format!("{}.png", rig.family));
        write(&path, &picture.png)?;
        let what = match &picture.clip {
            Some(name) => format!("clip {name:?}"),
            None => "rest pose".into(),
        };
        lines.push(format!(
            "wrote {} ({}, {what}, {} of {} frames)",
            path.display(),
            picture.label,
            picture.frames_drawn,
            picture.frames
        ));
    }
    Ok(lines)
}

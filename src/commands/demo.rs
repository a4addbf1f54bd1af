//! `rigport demo`: the built-in procedural character (`rigport_pipeline::demo`), written
//! with no input files.

use std::path::PathBuf;

use anyhow::Result;
use rigport_pipeline::demo;

use crate::cli::DemoArgs;
use crate::context::Context;

/// Runs `demo`.
pub fn run(ctx: &Context, args: &DemoArgs) -> Result<()> {
    let bar = ctx.spinner();
    let progress = |step: &str| bar.set_message(step.to_string());
    let prepared = demo::prepare(args.detail, &args.output, &progress);
    bar.finish_and_clear();
    let prepared = prepared?;
    ctx.report(prepared.warnings())?;
    let bar = ctx.spinner();
    let progress = |step: &str| bar.set_message(step.to_string());
    // The README runs the demo from the repository root, beside which the corpus lives.
    let corpus = (!args.no_corpus)
        .then(|| (args.corpus.clone()).unwrap_or_else(|| PathBuf::from("../shared/corpus")));
    let written = prepared.write(corpus.as_deref(), &progress)?;
    bar.finish_and_clear();
    for line in &written.corpus_skipped {
        eprintln!("warning: {line}");
    }
    if ctx.quiet {
        return Ok(());
    }
    let asset = &written.demo.asset;
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
    let [keys, reach, twist] = written.keys.each_ref().map(|p| p.display());
    println!("  clip \"wave\": {:.1} s, keyed in {keys}", clip(0));
    println!(
        "  clip \"reach\": {:.1} s, IK (damped least squares) from {reach}",
        clip(1)
    );
    println!(
        "  clip \"twist\": {:.1} s, the left forearm twists 150 deg, keyed in {twist}",
        clip(2)
    );
    println!(
        "  wrote {} and {}",
        written.glb.display(),
        written.usd.display()
    );
    let dqs = written.dqs.display();
    println!("  wrote {dqs} (clip \"twist\", DQS baked into corrective morph targets)");
    for line in &written.bake_lines {
        println!("    {line}");
    }
    let skirt = written.skirt.display();
    println!("  wrote {skirt} (clip \"wave\" with a skirt simulated on it, morph targets)");
    println!("    {}", written.skirt_report);
    for (path, what) in &written.pictures {
        println!("  wrote {} ({what})", path.display());
    }
    for line in &written.corpus_lines {
        println!("  {line}");
    }
    Ok(())
}

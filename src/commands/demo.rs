//! `rigport demo`: the built-in procedural character, written with no input files.

use anyhow::{Context as _, Result};
use rigport_export::GltfOptions;
use rigport_import::{demo, pinocchio};

use super::Context;
use crate::cli::DemoArgs;
use crate::exit::OutputError;

/// Runs `demo`.
pub fn run(ctx: &Context, args: &DemoArgs) -> Result<()> {
    let rig = ctx.step("generating the demo character", || {
        demo::character(args.detail)
    });
    let skeleton = pinocchio::PinocchioSkeleton {
        positions: rig.joint_positions.clone(),
        parents: rig.joint_parents.clone(),
    };
    // Bone k is named after the joint it ends at; the root keeps its own name.
    let imported = pinocchio::assemble(
        "demo",
        rig.mesh.clone(),
        &skeleton,
        Some(&rig.joint_names),
        &rig.bone_weights,
        None,
    )
    .context("the built-in demo rig is invalid (a rigport bug)")?;
    std::fs::create_dir_all(&args.output).with_context(|| OutputError {
        path: args.output.display().to_string(),
    })?;
    let out = args.output.join("demo.glb");
    let prepared = rigport_export::prepare_gltf(&imported.asset, &out, &GltfOptions::default())?;
    let mut warnings = imported.warnings.clone();
    warnings.extend(prepared.warnings().iter().cloned());
    ctx.report(&warnings)?;
    prepared.write().with_context(|| OutputError {
        path: out.display().to_string(),
    })?;
    if !ctx.quiet {
        let asset = &imported.asset;
        let mesh = &asset.meshes[0];
        let (lo, hi) = mesh.bounds().unwrap_or_default();
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
        println!("  wrote {}", out.display());
    }
    Ok(())
}

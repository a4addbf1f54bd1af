//! `rigport demo`: the built-in procedural character, written with no input files.

use anyhow::{Context as _, Result};
use rigport_export::{GltfOptions, UsdOptions};
use rigport_import::{demo, pinocchio};

use super::Context;
use crate::cli::DemoArgs;
use crate::exit::OutputError;
use crate::keys;

/// The demo's IK handles: the left fingertip reaches forward and up (offsets from its rest
/// position, metres), then returns.
const REACH_HANDLES: &str = r#"{
  "fps": 30,
  "handles": [
    {"joint": "fingertip_l", "relative": true, "offset": [0.16, 0, 0],
     "keys": [{"time": 0, "position": [0, 0, 0]},
              {"time": 1, "position": [-0.35, 0.15, 0.35]},
              {"time": 2, "position": [0, 0, 0]}]}
  ]
}
"#;

/// The demo's keyframed clip: the left arm waves (bone `forearm_l` is the upper arm, bone
/// `hand_l` the forearm: Pinocchio names a bone after the joint it ends at), the head nods,
/// the body bobs; the last key equals the first so the clip loops.
const WAVE_KEYS: &str = r#"{
  "name": "wave",
  "fps": 30,
  "keys": [
    {"frame": 0,  "pose": {}},
    {"frame": 15, "pose": {"forearm_l": {"euler_deg": [0, 0, 75]}, "hand_l": {"euler_deg": [0, 0, 40]},
                           "head": {"euler_deg": [10, 0, 0]}}, "translation": [0, -0.02, 0]},
    {"frame": 30, "pose": {"forearm_l": {"euler_deg": [0, 0, 80]}, "hand_l": {"euler_deg": [0, 0, 80]},
                           "head": {"euler_deg": [-5, 10, 0]}}},
    {"frame": 45, "pose": {"forearm_l": {"euler_deg": [0, 0, 75]}, "hand_l": {"euler_deg": [0, 0, 30]},
                           "head": {"euler_deg": [10, -10, 0]}}, "translation": [0, -0.02, 0]},
    {"frame": 60, "pose": {}}
  ]
}
"#;

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
    // The keyframed clip, from a keys file written beside the outputs as an example for
    // `rigport animate`.
    let keys_path = args.output.join("wave.keys.json");
    rigport_export::write_atomic(&keys_path, WAVE_KEYS.as_bytes()).with_context(|| {
        OutputError {
            path: keys_path.display().to_string(),
        }
    })?;
    let mut imported = imported;
    let wave = keys::load(&keys_path, &imported.asset.skeleton, "wave")
        .context("the built-in demo keys are invalid (a rigport bug)")?;
    imported.asset.clips.push(wave);
    // The IK reach clip: the left fingertip (bone `fingertip_l` turns about the wrist; the
    // offset puts the effector at the finger's tip) reaches forward and up, then back.
    let reach_path = args.output.join("reach.handles.json");
    rigport_export::write_atomic(&reach_path, REACH_HANDLES.as_bytes()).with_context(|| {
        OutputError {
            path: reach_path.display().to_string(),
        }
    })?;
    let (mut reach, _, reach_warnings) = super::ik::solve(
        ctx,
        &imported.asset.skeleton,
        &reach_path,
        &super::ik::IkOptions {
            method: rigport_eval::ik::IkMethod::Dls {
                lambda: rigport_eval::ik::Lambda::Adaptive,
            },
            fps: None,
            tolerance: None,
            max_iterations: 100,
            substep: None,
            free_root: false,
        },
    )
    .context("the built-in demo reach is invalid (a rigport bug)")?;
    reach.name = "reach".into();
    imported.warnings.extend(reach_warnings);
    imported.asset.clips.push(reach);
    let out = args.output.join("demo.glb");
    let prepared = rigport_export::prepare_gltf(&imported.asset, &out, &GltfOptions::default())?;
    let out_usd = args.output.join("demo.usda");
    let prepared_usd =
        rigport_export::prepare_usd(&imported.asset, &out_usd, &UsdOptions::default())?;
    let mut warnings = imported.warnings.clone();
    warnings.extend(prepared.warnings().iter().cloned());
    warnings.extend(prepared_usd.warnings().iter().cloned());
    ctx.report(&warnings)?;
    prepared.write().with_context(|| OutputError {
        path: out.display().to_string(),
    })?;
    prepared_usd.write().with_context(|| OutputError {
        path: out_usd.display().to_string(),
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
        println!(
            "  clip \"wave\": {:.1} s, keyed in {}",
            asset.clips[0].duration(),
            keys_path.display()
        );
        println!(
            "  clip \"reach\": {:.1} s, IK (damped least squares) from {}",
            asset.clips[1].duration(),
            reach_path.display()
        );
        println!("  wrote {} and {}", out.display(), out_usd.display());
    }
    Ok(())
}

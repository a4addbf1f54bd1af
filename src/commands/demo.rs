//! `rigport demo`: the built-in procedural character, written with no input files.

use std::path::{Path, PathBuf};

use anyhow::{Context as _, Result};
use rigport_eval::bake::pipeline::{bake_dqs, DqsBakeOptions};
use rigport_eval::ik::clip::{solve_clip, ClipSolveOptions, HandleTargets};
use rigport_export::{GltfOptions, UsdOptions};
use rigport_import::{demo, pinocchio};
use rigport_model::Asset;
use rigport_render::{FrameTime, RenderOptions, SkinningChoice, View};

use crate::cli::{DemoArgs, InputArgs};
use crate::context::Context;
use crate::exit::OutputError;
use crate::{input, keys};

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

/// The demo's LBS-vs-DQS clip: the left forearm (bone `hand_l`, from the elbow at x = 0.46 m
/// to the wrist at x = 0.71 m) twists about its own axis, 0 -> 150 deg -> 0 over 2 s. The
/// demo's joints have identity rest rotations (Pinocchio layout) and pose entries rotate in
/// the joint's rest frame, so the bone axis is the rest frame's +X. Linear blending of a
/// 150 deg twist with the untwisted upper arm collapses the skin where the weights blend
/// ("candy wrapper", Kavan et al. 2008, fig. 1); DQS keeps its volume.
const TWIST_KEYS: &str = r#"{
  "name": "twist",
  "fps": 30,
  "keys": [
    {"frame": 0,  "pose": {}},
    {"frame": 30, "pose": {"hand_l": {"euler_deg": [150, 0, 0]}}},
    {"frame": 60, "pose": {}}
  ]
}
"#;

/// The time of the twist clip's largest twist, seconds (frame 30 of [`TWIST_KEYS`]).
const TWIST_PEAK_S: f32 = 1.0;

/// A small posed clip for the corpus's Model1 human (Pinocchio bone names: `bone_13` and
/// `bone_16` are the upper arms, turning about the shoulders at joints 12 and 15; `bone_14`
/// and `bone_17` the forearms): both arms rise sideways and come back down.
const MODEL1_KEYS: &str = r#"{
  "name": "arms",
  "fps": 30,
  "keys": [
    {"frame": 0,  "pose": {}},
    {"frame": 15, "pose": {"bone_13": {"euler_deg": [0, 0, -60]}, "bone_14": {"euler_deg": [0, 0, -30]},
                           "bone_16": {"euler_deg": [0, 0, 60]},  "bone_17": {"euler_deg": [0, 0, 30]}}},
    {"frame": 30, "pose": {}}
  ]
}
"#;

/// Size of one view (one contact-sheet cell, one GIF frame) in the demo's pictures, pixels.
const CELL_PX: u32 = 256;
/// Frame rate of `wave.gif`.
const GIF_FPS: f32 = 15.0;
/// Size of each half of `twist_lbs_vs_dqs.png`, pixels: larger than a sheet cell, since the
/// camera frames the whole body and the forearm is a small part of it.
const TWIST_PX: u32 = 384;

/// One rig of a shared corpus family (paths relative to the corpus folder).
struct CorpusRig {
    /// The family folder, also the picture's name (`corpus/<family>.png`).
    family: &'static str,
    /// Input files, as `rigport render` takes them.
    files: &'static [&'static str],
    /// Keys for a small clip when the rig has none (`None`: draw its own first clip, or
    /// the rest pose).
    keys: Option<&'static str>,
    /// Where the camera looks from.
    view: View,
}

/// The corpus rigs the demo renders, one per family.
const CORPUS_RIGS: [CorpusRig; 6] = [
    CorpusRig {
        family: "1_pinocchio",
        files: &[
            "1_pinocchio/berkeley_cs184__severus-snape_mobius-ants/human_model1/Model1.obj",
            "1_pinocchio/berkeley_cs184__severus-snape_mobius-ants/human_model1/skeleton.out",
            "1_pinocchio/berkeley_cs184__severus-snape_mobius-ants/human_model1/attachment.out",
        ],
        keys: Some(MODEL1_KEYS),
        view: View::Front,
    },
    CorpusRig {
        family: "2_csci520_ik_skinning",
        files: &["2_csci520_ik_skinning/tydia/armadillo/skin.config"],
        keys: None,
        view: View::ThreeQuarter,
    },
    CorpusRig {
        family: "3_acclaim_asf_amc",
        files: &[
            "3_acclaim_asf_amc/usc_csci520_mocapPlayer__shreyabhaumik/07-walk.asf",
            "3_acclaim_asf_amc/usc_csci520_mocapPlayer__shreyabhaumik/07_05-walk.amc",
        ],
        keys: None,
        view: View::Front,
    },
    CorpusRig {
        family: "4_bvh",
        files: &["4_bvh/bandai_namco_ds1/dataset-1_walk_normal_002.bvh"],
        keys: None,
        view: View::Side,
    },
    CorpusRig {
        family: "5_gltf",
        files: &["5_gltf/khronos_samples__nobuyuki83_delfem2/CesiumMan.glb"],
        keys: None,
        view: View::Front,
    },
    CorpusRig {
        family: "6_usd",
        files: &["6_usd/openusd_usdskel__PixarAnimationStudios/testUsdSkelBakeSkinning/dqs.usda"],
        keys: None,
        view: View::Front,
    },
];

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
    write(&keys_path, WAVE_KEYS.as_bytes())?;
    let mut imported = imported;
    let wave = keys::load(&keys_path, &imported.asset.skeleton, "wave")
        .context("the built-in demo keys are invalid (a rigport bug)")?;
    imported.asset.clips.push(wave);
    // The IK reach clip: the left fingertip (bone `fingertip_l` turns about the wrist; the
    // offset puts the effector at the finger's tip) reaches forward and up, then back.
    let reach_path = args.output.join("reach.handles.json");
    write(&reach_path, REACH_HANDLES.as_bytes())?;
    let reach_handles = rigport_import::json::handles::read(&reach_path, &imported.asset.skeleton)
        .context("the built-in demo reach is invalid (a rigport bug)")?;
    let solved = ctx
        .step("solving", || {
            solve_clip(
                &imported.asset.skeleton,
                &reach_handles,
                &ClipSolveOptions::default(),
                "reach",
                &reach_path.display().to_string(),
            )
        })
        .context("the built-in demo reach is invalid (a rigport bug)")?;
    let reach = solved.clip;
    imported.warnings.extend(solved.warnings);
    // The targets the reach was solved for, drawn as markers on its picture.
    let reach_targets = HandleTargets::new(&imported.asset.skeleton, reach_handles.tracks);
    imported.asset.clips.push(reach);
    // The twist clip, keyed like wave (the LBS-vs-DQS comparison of issue 5).
    let twist_path = args.output.join("twist.keys.json");
    write(&twist_path, TWIST_KEYS.as_bytes())?;
    let twist = keys::load(&twist_path, &imported.asset.skeleton, "twist")
        .context("the built-in demo twist keys are invalid (a rigport bug)")?;
    imported.asset.clips.push(twist);
    let out = args.output.join("demo.glb");
    let prepared = rigport_export::prepare_gltf(&imported.asset, &out, &GltfOptions::default())?;
    let out_usd = args.output.join("demo.usda");
    let prepared_usd =
        rigport_export::prepare_usd(&imported.asset, &out_usd, &UsdOptions::default())?;
    let mut warnings = imported.warnings.clone();
    warnings.extend(prepared.warnings().iter().cloned());
    warnings.extend(prepared_usd.warnings().iter().cloned());
    // The twist clip alone, its DQS baked into corrective morph targets (`rigport bake`'s
    // code path) so any glTF viewer shows DQS. Sampled at the keys' 30 fps so a viewer's
    // linear morph-weight interpolation between samples stays close to DQS.
    let out_dqs = args.output.join("twist_dqs.glb");
    let mut twist_asset = imported.asset.clone();
    twist_asset.clips.retain(|c| c.name == "twist");
    let dqs_influences: u8 = 4;
    let bake_reports = ctx
        .step("baking DQS correctives", || {
            bake_dqs(
                &mut twist_asset,
                &DqsBakeOptions {
                    clip: Some("twist"),
                    fps: Some(30.0),
                    ..DqsBakeOptions::default()
                },
                |skeleton, skin| {
                    rigport_export::gltf_influences(skeleton, skin, usize::from(dqs_influences))
                },
                "demo",
                &mut warnings,
            )
        })
        .context("cannot bake the demo's twist clip (a rigport bug)")?;
    let prepared_dqs = rigport_export::prepare_gltf(
        &twist_asset,
        &out_dqs,
        &GltfOptions {
            max_influences: usize::from(dqs_influences),
        },
    )?;
    warnings.extend(prepared_dqs.warnings().iter().cloned());
    ctx.report(&warnings)?;
    prepared.write().with_context(|| OutputError {
        path: out.display().to_string(),
    })?;
    prepared_usd.write().with_context(|| OutputError {
        path: out_usd.display().to_string(),
    })?;
    prepared_dqs.write().with_context(|| OutputError {
        path: out_dqs.display().to_string(),
    })?;
    let pictures = ctx.step("rendering pictures", || {
        demo_pictures(&imported.asset, &reach_targets, &args.output)
    })?;
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
        println!(
            "  clip \"twist\": {:.1} s, the left forearm twists 150 deg, keyed in {}",
            asset.clips[2].duration(),
            twist_path.display()
        );
        println!("  wrote {} and {}", out.display(), out_usd.display());
        println!(
            "  wrote {} (clip \"twist\", DQS baked into corrective morph targets)",
            out_dqs.display()
        );
        for report in &bake_reports {
            for line in report.to_string().lines() {
                println!("    {line}");
            }
        }
        for (path, what) in &pictures {
            println!("  wrote {} ({what})", path.display());
        }
        for line in &corpus_lines {
            println!("  {line}");
        }
    }
    Ok(())
}

/// Writes `bytes` to `path` atomically.
fn write(path: &Path, bytes: &[u8]) -> Result<()> {
    rigport_export::write_atomic(path, bytes).with_context(|| OutputError {
        path: path.display().to_string(),
    })
}

/// Renders the demo's pictures into `dir`, the reach clip with its IK `reach_targets` as
/// markers; returns each file with a description.
///
/// # Errors
/// Rendering (a rigport bug for the built-in rig) or writing fails.
fn demo_pictures(
    asset: &Asset,
    reach_targets: &HandleTargets,
    dir: &Path,
) -> Result<Vec<(PathBuf, String)>> {
    let sheet = RenderOptions {
        width: CELL_PX,
        height: CELL_PX,
        ..RenderOptions::default()
    };
    let mut written = Vec::new();
    // The reach goes forward as much as up: seen from the front it would hardly move.
    for (clip, markers, view) in [
        ("wave", None, View::Front),
        (
            "reach",
            Some(reach_targets as &dyn rigport_render::Markers),
            View::ThreeQuarter,
        ),
    ] {
        let path = dir.join(format!("{clip}.png"));
        let options = RenderOptions { view, ..sheet };
        let bytes = rigport_render::render_clip_png(asset, Some(clip), markers, &options)
            .with_context(|| format!("cannot render the demo's {clip:?} clip (a rigport bug)"))?;
        write(&path, &bytes)?;
        let extra = if markers.is_some() {
            ", three-quarter view, IK targets as magenta crosshairs"
        } else {
            ""
        };
        written.push((path, format!("contact sheet of clip {clip:?}, LBS{extra}")));
    }
    let path = dir.join("wave.gif");
    let bytes = rigport_render::render_clip_gif(asset, Some("wave"), None, GIF_FPS, &sheet)
        .context("cannot render the demo's wave clip (a rigport bug)")?;
    write(&path, &bytes)?;
    written.push((
        path,
        format!("clip \"wave\", {CELL_PX}x{CELL_PX} at {GIF_FPS} fps"),
    ));
    // One frame at the largest twist, LBS left and DQS right through the same camera; no
    // skeleton overlay, whose bone line would hide the collapsed forearm.
    let path = dir.join("twist_lbs_vs_dqs.png");
    let twist = rigport_render::find_clip(asset, Some("twist"))?;
    let frames = rigport_render::render_frames(
        asset,
        twist,
        &[FrameTime {
            number: 30,
            time: TWIST_PEAK_S,
        }],
        None,
        &RenderOptions {
            width: TWIST_PX,
            height: TWIST_PX,
            view: View::Front,
            skinning: SkinningChoice::Both,
            skeleton: false,
            frame_counter: false,
            ..RenderOptions::default()
        },
    )
    .context("cannot render the demo's twist clip (a rigport bug)")?;
    let frame = frames
        .first()
        .context("the renderer returned no picture (a rigport bug)")?;
    write(&path, &rigport_render::encode_png(frame)?)?;
    written.push((
        path,
        format!("clip \"twist\" at {TWIST_PEAK_S} s: LBS left, DQS right"),
    ));
    Ok(written)
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

/// Renders one rig of each corpus family to `out/corpus/<family>.png`; a rig that fails
/// to load or render becomes a warning line on stderr, not a failure. Returns one line per
/// picture written.
///
/// # Errors
/// The `corpus` output folder cannot be created.
fn corpus_pictures(corpus: &Path, out: &Path) -> Result<Vec<String>> {
    let out = out.join("corpus");
    std::fs::create_dir_all(&out).with_context(|| OutputError {
        path: out.display().to_string(),
    })?;
    let mut lines = Vec::new();
    for rig in &CORPUS_RIGS {
        match corpus_picture(corpus, &out, rig) {
            Ok(line) => lines.push(line),
            Err(e) => eprintln!(
                "warning: corpus {}: skipped: {e:#}",
                corpus
                    .join(rig.files.first().copied().unwrap_or(rig.family))
                    .display()
            ),
        }
    }
    Ok(lines)
}

/// Loads one corpus rig the way `rigport render` does and writes its contact sheet.
fn corpus_picture(corpus: &Path, out: &Path, rig: &CorpusRig) -> Result<String> {
    let inputs = InputArgs {
        inputs: rig.files.iter().map(|f| corpus.join(f)).collect(),
        mesh: None,
        skeleton: None,
        attachment: None,
        motion: Vec::new(),
        amc_fps: None,
        no_bone_mesh: false,
    };
    let (plan, mut imported) = input::load_single(&inputs)?;
    if let Some(text) = rig.keys {
        let keys_path = out.join(format!("{}.keys.json", rig.family));
        write(&keys_path, text.as_bytes())?;
        let clip = keys::load(&keys_path, &imported.asset.skeleton, "demo")?;
        imported.asset.clips.insert(0, clip);
    }
    let asset = &imported.asset;
    let clip = rigport_render::find_clip(asset, None)?;
    let frames = rigport_render::frame_list(asset, clip, None, None)?;
    let options = RenderOptions {
        width: CELL_PX,
        height: CELL_PX,
        view: rig.view,
        ..RenderOptions::default()
    };
    let bytes = rigport_render::render_sheet_png(asset, clip, &frames, None, &options)?;
    let path = out.join(format!("{}.png", rig.family));
    write(&path, &bytes)?;
    let what = match clip {
        Some(c) => format!("clip {:?}", c.name),
        None => "rest pose".into(),
    };
    Ok(format!(
        "wrote {} ({}, {what}, {} of {} frames)",
        path.display(),
        plan.label(),
        frames.len().min(rigport_render::SHEET_FRAMES),
        frames.len()
    ))
}

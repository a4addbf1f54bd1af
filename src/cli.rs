//! The top-level command line: the global flags and the subcommands (each command's own
//! arguments are in its file under `commands/`).

use clap::{Parser, Subcommand};

use crate::{commands, exit};

/// Bring legacy character rigs and motion into glTF 2.0.
#[derive(Debug, Parser)]
#[command(name = "rigport", version, about, after_help = exit::HELP)]
pub struct Cli {
    /// The command.
    #[command(subcommand)]
    pub command: Command,
    /// Print nothing but errors and warnings.
    #[arg(long, short, global = true)]
    pub quiet: bool,
    /// Treat every warning as an error (exit code 4, no output written).
    #[arg(long, global = true)]
    pub deny_warnings: bool,
    /// The most memory a run may plan to use (e.g. 2G, 500M, 1.5GiB); requests estimated
    /// above it are refused before they allocate (exit 1). Default: 3/4 of the machine's
    /// memory (of its cgroup or `ulimit -v` limit when lower).
    #[arg(long, global = true, value_name = "SIZE", value_parser = parse_memory_size)]
    pub max_memory: Option<u64>,
}

/// `--max-memory`'s value.
fn parse_memory_size(text: &str) -> Result<u64, String> {
    rigport_model::budget::parse_bytes(text)
        .ok_or_else(|| format!("expected a size such as 2G, 500M or 1.5GiB, not {text:?}"))
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Convert a rig to glTF (.glb, or .gltf + .bin).
    #[command(after_help = include_str!("../docs/help/convert.txt"))]
    Convert(commands::convert::ConvertArgs),
    /// Describe rigs: joints with parents, meshes, influence histogram, clips.
    Inspect(commands::inspect::InspectArgs),
    /// Pose a rig, or play one of its clips, and dump the skinned result as .npz for numpy.
    #[command(
        after_help = format!(
            "{}\n\n{}",
            rigport_import::json::pose::FORMAT,
            rigport_export::npz::EVAL_DUMP_FORMAT
        )
    )]
    Eval(commands::eval::EvalArgs),
    /// Keyframe a rig from a JSON file of poses and write it with the clip.
    #[command(after_help = rigport_import::json::keys::FORMAT)]
    Animate(commands::animate::AnimateArgs),
    /// Re-time a clip (resample, speed, warp curve, reverse, trim), baked to linear keys.
    #[command(after_help = include_str!("../docs/help/root_motion.txt"))]
    Retime(commands::retime::RetimeArgs),
    /// Put a motion (BVH, ASF/AMC, glTF clip) onto another rig: joints mapped by the body
    /// roles both skeletons' structure shows or --map, rotations transferred relative to
    /// each rest pose, hips scaled.
    #[command(after_help = include_str!("../docs/help/retarget.txt"))]
    Retarget(commands::retarget::RetargetArgs),
    /// Put many motions onto one rig as named clips (taken or retargeted), in one file.
    #[command(override_usage = "rigport combine [OPTIONS] RIG MOTION... -o OUT")]
    #[command(after_help = include_str!("../docs/help/combine.txt"))]
    Combine(commands::combine::CombineArgs),
    /// Play clips one after another with crossfades, optionally as a seamless loop.
    Sequence(commands::sequence::SequenceArgs),
    /// Solve IK handles moving over time, one pose per frame, baked into a clip.
    #[command(after_help = rigport_import::json::handles::FORMAT)]
    Ik(commands::ik::IkArgs),
    /// Hold mocap feet still while they touch the ground (two-bone IK on the legs).
    #[command(after_help = include_str!("../docs/help/footlock.txt"))]
    Footlock(commands::footlock::FootlockArgs),
    /// Bake a skinning result (DQS) into a glTF every viewer plays back exactly.
    Bake(commands::bake::BakeArgs),
    /// Simulate a garment (XPBD cloth) on the animated body and bake it into the file.
    Cloth(commands::cloth::ClothArgs),
    /// Skin weights by bone heat for a mesh and a skeleton: attachment.out or a rig.
    Skin(commands::skin::SkinArgs),
    /// Render rigs and clips to PNG contact sheets or GIF/APNG animations (CPU, headless).
    Render(commands::render::RenderArgs),
    /// Check that CANDIDATE plays like REFERENCE (any two formats), and show where not.
    #[command(after_help = include_str!("../docs/help/verify.txt"))]
    Verify(commands::verify::VerifyArgs),
    /// Write the built-in demo character (no input files needed).
    Demo(commands::demo::DemoArgs),
    /// Run many items from a JSON Lines manifest (or every asset of a folder), in-process
    /// on --jobs threads; shards, resume and a per-item report (docs/scale.md).
    #[command(after_help = include_str!("../docs/help/batch.txt"))]
    Batch(commands::batch::BatchArgs),
    /// Merge batch reports (the shards of one run) and print the summary table.
    BatchReport(commands::batch::BatchReportArgs),
}

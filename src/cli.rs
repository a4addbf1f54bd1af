//! Command-line arguments, as clap parses them (the raw layer; commands resolve them).

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand};

use crate::exit;

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
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Convert a rig to glTF (.glb, or .gltf + .bin).
    #[command(after_help = "Examples:\n  \
        rigport convert --mesh Model1.obj --skeleton skeleton.out --attachment attachment.out -o model1.glb\n  \
        rigport convert Model1.obj skeleton.out attachment.out -o model1.gltf\n  \
        rigport convert path/to/rig_folder -o rig.glb\n  \
        rigport convert CesiumMan.glb -o cesium.gltf")]
    Convert(ConvertArgs),
    /// Describe rigs: joints with parents, meshes, influence histogram, clips.
    Inspect(InspectArgs),
    /// Pose a rig and dump the skinned result (LBS) as .npz for numpy.
    #[command(
        after_help = "POSE.json maps joint names to a rotation applied in the joint's rest frame \
        (local = rest_local * delta):\n  \
        {\"bone_5\": {\"quat\": [x, y, z, w]}, \"bone_7\": {\"euler_deg\": [x, y, z], \"order\": \"xyz\"}}\n\
        \"xyz\" lists the axes in the order they are applied: R = Rz * Ry * Rx.\n\n\
        The .npz holds positions, rest_positions (V x 3, source vertex order), joint_names, \
        joint_world and skin_matrices (J x 4 x 4, column vectors: p' = M p), \
        influence_joints and influence_weights (V x K, zero-padded)."
    )]
    Eval(EvalArgs),
    /// Write the built-in demo character (no input files needed).
    Demo(DemoArgs),
}

/// Where a rig comes from.
#[derive(Debug, Args)]
pub struct InputArgs {
    /// Input files or folders: a .glb/.gltf; an .obj with Pinocchio skeleton and attachment
    /// .out files (told apart by name or content); a USC CSCI 520 skin.config; or a folder
    /// holding one of these sets.
    pub inputs: Vec<PathBuf>,
    /// The OBJ mesh of a Pinocchio rig.
    #[arg(long, value_name = "M.obj")]
    pub mesh: Option<PathBuf>,
    /// Pinocchio `skeleton.out` (index x y z parent per line).
    #[arg(long, value_name = "S.out")]
    pub skeleton: Option<PathBuf>,
    /// Pinocchio `attachment.out` (one row of bone weights per OBJ vertex).
    #[arg(long, value_name = "A.out")]
    pub attachment: Option<PathBuf>,
}

/// `rigport convert`.
#[derive(Debug, Args)]
pub struct ConvertArgs {
    /// The rig.
    #[command(flatten)]
    pub input: InputArgs,
    /// Output file: .glb, or .gltf (+ a .bin of the same stem beside it).
    #[arg(long, short, value_name = "OUT")]
    pub output: PathBuf,
    /// Influences kept per vertex: 1 to 8; above 4, vertices with more than 4 get a second
    /// set (JOINTS_1/WEIGHTS_1). Each vertex keeps its largest weights, renormalized.
    #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u8).range(1..=8))]
    pub max_influences: u8,
}

/// `rigport inspect`.
#[derive(Debug, Args)]
pub struct InspectArgs {
    /// The rigs.
    #[command(flatten)]
    pub input: InputArgs,
    /// Print JSON (one object per asset, in an array) for machines.
    #[arg(long)]
    pub json: bool,
}

/// `rigport eval`.
#[derive(Debug, Args)]
pub struct EvalArgs {
    /// The rig.
    #[command(flatten)]
    pub input: InputArgs,
    /// The pose (see below); the rest pose when absent.
    #[arg(long, value_name = "POSE.json")]
    pub pose: Option<PathBuf>,
    /// The .npz dump to write.
    #[arg(long = "out", short = 'o', value_name = "DUMP.npz")]
    pub output: PathBuf,
    /// Skin with the influences a glTF export with this limit writes (1 to 8) instead of
    /// all of them: shows what a viewer of that file computes.
    #[arg(long, value_parser = clap::value_parser!(u8).range(1..=8))]
    pub max_influences: Option<u8>,
}

/// `rigport demo`.
#[derive(Debug, Args)]
pub struct DemoArgs {
    /// Folder to write into (created if missing).
    #[arg(long, short, default_value = "rigport-demo", value_name = "DIR")]
    pub output: PathBuf,
    /// Mesh detail: 1 (default, several thousand vertices) and up.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=4))]
    pub detail: u32,
}

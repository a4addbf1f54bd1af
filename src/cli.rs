//! Command-line arguments, as clap parses them (the raw layer; commands resolve them).

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand};
use rigport_model::{InfluencesFit, SkinningMethod, UpAxis};

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
    #[command(after_help = "Examples:\n  \
        rigport convert --mesh Model1.obj --skeleton skeleton.out --attachment attachment.out -o model1.glb\n  \
        rigport convert Model1.obj skeleton.out attachment.out -o model1.gltf\n  \
        rigport convert path/to/rig_folder -o rig.glb\n  \
        rigport convert CesiumMan.glb -o cesium.gltf")]
    Convert(ConvertArgs),
    /// Describe rigs: joints with parents, meshes, influence histogram, clips.
    Inspect(InspectArgs),
    /// Pose a rig, or play one of its clips, and dump the skinned result as .npz for numpy.
    #[command(
        after_help = "POSE.json maps joint names to a rotation applied in the joint's rest frame \
        (local = rest_local * delta):\n  \
        {\"bone_5\": {\"quat\": [x, y, z, w]}, \"bone_7\": {\"euler_deg\": [x, y, z], \"order\": \"xyz\"}}\n\
        \"xyz\" lists the axes in the order they are applied: R = Rz * Ry * Rx.\n\n\
        The .npz holds positions, rest_positions (V x 3, source vertex order), joint_names, \
        joint_world and skin_matrices (J x 4 x 4, column vectors: p' = M p), \
        influence_joints and influence_weights (V x K, zero-padded), skinning ([\"lbs\"] or \
        [\"dqs\"]).\n\n\
        Without --pose, a rig with clips plays one (--clip, default the first) and the arrays \
        that change get a leading frame axis: times (F, seconds), positions (F x V x 3), \
        joint_world and skin_matrices (F x J x 4 x 4)."
    )]
    Eval(EvalArgs),
    /// Keyframe a rig from a JSON file of poses and write it with the clip.
    #[command(after_help = "KEYS.json:\n  \
        {\"name\": \"wave\", \"fps\": 30, \"keys\": [\n    \
        {\"time\": 0.0, \"pose\": {}},\n    \
        {\"time\": 0.5, \"pose\": {\"bone_5\": {\"euler_deg\": [0, 0, 45], \"order\": \"xyz\"}}, \"translation\": [0, 0.1, 0]},\n    \
        {\"frame\": 30, \"pose\": {\"bone_5\": {\"quat\": [0, 0, 0, 1]}}}]}\n\
        Each key is a whole pose: joints it does not list are at rest. Pose entries are those of \
        `rigport eval --pose`. \"time\" is in seconds; \"frame\" needs \"fps\". \"translation\" moves \
        the root from its rest position (root motion, the rig's length unit). Between keys, \
        rotations are slerped and translations lerped (glTF LINEAR).")]
    Animate(AnimateArgs),
    /// Re-time a clip (resample, speed, warp curve, reverse, trim), baked to linear keys.
    Retime(RetimeArgs),
    /// Put a motion (BVH, ASF/AMC, glTF clip) onto another rig: joints mapped by name
    /// conventions or --map, rotations transferred relative to each rest pose, hips scaled.
    #[command(
        after_help = "MAP.json: {\"joints\": {\"SOURCE\": \"TARGET\" or [\"TARGET\", ...]}, \"pelvis\": {\"source\": \"S\", \"target\": \"T\"}} (pelvis optional)."
    )]
    Retarget(RetargetArgs),
    /// Play clips one after another with crossfades, optionally as a seamless loop.
    Sequence(SequenceArgs),
    /// Solve IK handles moving over time, one pose per frame, baked into a clip.
    #[command(after_help = "HANDLES.json:\n  \
        {\"fps\": 30, \"handles\": [{\"joint\": \"bone_12\", \"relative\": false, \"offset\": [0, 0.1, 0], \"weight\": 1,\n    \
        \"keys\": [{\"time\": 0, \"position\": [x, y, z]}, {\"time\": 2, \"position\": [x, y, z]}]}]}\n\
        Targets are model-space positions in the rig's length unit (\"relative\": offsets from the \
        effector's rest position), linear between keys. \"offset\" (optional) is the effector point \
        in the joint's frame, e.g. a bone's tip. Every ancestor of a handle may rotate; each frame \
        starts from the previous frame's solution.\n\
        Chain-aware fields (any of them: only the handles' chains move, each frame starts from the \
        input pose, the root is locked unless \"root_motion\": \"free\"): per handle \"root\", \
        \"pin\": true (no keys; \"orient\": true keeps the rotation too), \"solver\": \"two_bone\" \
        with \"pole\" [x,y,z] (also per key), \"twist_deg\", \"soften\" 0-1 and \"weight\" 0-1; per key \
        \"rotation\" [x,y,z,w] (model space); top level \"base\": \"<clip>\", \"root_motion\", \
        \"limits\": {\"joint\": {\"x\": [min_deg, max_deg], \"order\": \"xyz\"}} (rest frame; ASF \
        dof/limits apply too). Limits are clamps of Euler angles relative to rest.")]
    Ik(IkArgs),
    /// Hold mocap feet still while they touch the ground (two-bone IK on the legs).
    #[command(
        after_help = "Feet are found by name (CMU ASF lfoot/ltoes, cgspeed BVH and Mixamo \
        LeftFoot/LeftToeBase, Bandai Namco Foot_L/Toes_L, Pinocchio's human template) unless \
        --foot names them. Only the legs' hip, knee and ankle rotations change. Slides are in \
        skeleton heights: per contact frame, the joint's distance from its touch-down position."
    )]
    Footlock(FootlockArgs),
    /// Bake a skinning result (DQS) into a glTF every viewer plays back exactly.
    Bake(BakeArgs),
    /// Simulate a garment (XPBD cloth) on the animated body and bake it into the file.
    Cloth(ClothArgs),
    /// Render rigs and clips to PNG contact sheets or GIF/APNG animations (CPU, headless).
    Render(RenderArgs),
    /// Write the built-in demo character (no input files needed).
    Demo(DemoArgs),
    /// Run many items from a JSON Lines manifest (or every asset of a folder), in-process
    /// on --jobs threads; shards, resume and a per-item report (docs/scale.md).
    #[command(
        after_help = "Manifest line: {\"id\": \"kick\", \"command\": \"convert\", \"inputs\": [\"kick.bvh\"], \"options\": [\"--fps\", \"30\"], \"outputs\": [\"kick.glb\"]}\n\
        Exit codes: 0 every item done or skipped; 1 some items had bad input (the others finished; \
        do not retry); 2 usage; 3 an output could not be written (retry)."
    )]
    Batch(BatchArgs),
    /// Merge batch reports (the shards of one run) and print the summary table.
    BatchReport(BatchReportArgs),
}

/// `rigport batch`.
#[derive(Debug, Args)]
pub struct BatchArgs {
    /// A JSON Lines manifest, or a folder: one `convert` item per asset found in it.
    pub manifest: PathBuf,
    /// The output folder (item outputs are relative to it).
    #[arg(long, short, value_name = "OUT_DIR")]
    pub output: PathBuf,
    /// Worker threads (default: one per core).
    #[arg(long, short, value_name = "N")]
    pub jobs: Option<usize>,
    /// Run shard I of N: the items at manifest positions k with k mod N = I. Default from
    /// JOB_COMPLETION_INDEX/JOB_COMPLETIONS (Kubernetes Indexed Job) or
    /// SLURM_ARRAY_TASK_ID/SLURM_ARRAY_TASK_COUNT (Slurm array), else every item.
    #[arg(long, value_name = "I/N")]
    pub shard: Option<String>,
    /// Skip items whose outputs exist and whose sidecar records the same input bytes,
    /// options and rigport version.
    #[arg(long)]
    pub resume: bool,
    /// The report (default: OUT_DIR/.rigport-batch/report-I-of-N.jsonl).
    #[arg(long, value_name = "R.jsonl")]
    pub report: Option<PathBuf>,
    /// For a folder: the output extension of its items (glb, gltf, usda, usdc or usdz).
    #[arg(long, default_value = "glb", value_name = "EXT")]
    pub to: String,
    /// For a folder: options every item gets, split on spaces ("--fps 30").
    #[arg(long, value_name = "ARGS", allow_hyphen_values = true)]
    pub convert_options: Option<String>,
}

/// `rigport batch-report`.
#[derive(Debug, Args)]
pub struct BatchReportArgs {
    /// The reports to merge.
    #[arg(required = true)]
    pub reports: Vec<PathBuf>,
    /// Also write the merged report (manifest order) here.
    #[arg(long, short, value_name = "R.jsonl")]
    pub output: Option<PathBuf>,
}

/// Where a rig comes from.
#[derive(Clone, Debug, Args)]
pub struct InputArgs {
    /// Input files or folders: a .glb/.gltf; an .obj with Pinocchio skeleton and attachment
    /// .out files (told apart by name or content); a USC CSCI 520 skin.config; or a folder
    /// holding one of these sets. Required unless --mesh, --skeleton or --attachment
    /// names the files.
    #[arg(required_unless_present_any = ["mesh", "skeleton", "attachment"])]
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
    /// An AMC motion for the .asf skeleton among the inputs (repeat for several clips;
    /// .amc files may also be given as inputs).
    #[arg(long, value_name = "M.amc")]
    pub motion: Vec<PathBuf>,
    /// Frame rate of AMC motions, which do not state one (default: 120, CMU's rate).
    #[arg(long, value_name = "FPS")]
    pub amc_fps: Option<f32>,
    /// Do not generate a bone mesh for skeleton-only inputs (ASF/AMC, BVH). By default each
    /// bone gets a small skinned shape so viewers show the motion.
    #[arg(long)]
    pub no_bone_mesh: bool,
}

/// Where and how an asset is written.
#[derive(Debug, Args)]
pub struct OutputArgs {
    /// Output file: .glb, .gltf (+ a .bin of the same stem beside it), .usda, .usdc or .usdz.
    #[arg(long, short, value_name = "OUT")]
    pub output: PathBuf,
    /// Influences kept per vertex: 1 to 8 (glTF default 4; above 4, vertices with more get
    /// a second set, JOINTS_1/WEIGHTS_1, which three.js, model-viewer, Filament, Bevy and
    /// Unity ignore). USD keeps every influence unless this is given.
    #[arg(long, value_parser = clap::value_parser!(u8).range(1..=8))]
    pub max_influences: Option<u8>,
    /// How a vertex with more influences than the limit drops the rest: `truncate` keeps
    /// its largest weights, renormalized (what Blender, gltfpack and Assimp do); `refit`
    /// fits K weights so the deformation stays closest to all weights' over the clips'
    /// frames (or a range-of-motion pose set) and prints both deviations.
    #[arg(long, value_enum, default_value_t = InfluencesFit::Truncate)]
    pub influences_fit: InfluencesFit,
    /// Remove animation keys while every joint's world position stays within D (in the
    /// rig's length unit) of the full clip at every original key time.
    #[arg(long, value_name = "D")]
    pub reduce_tolerance: Option<f32>,
    /// Skinning method a .usda declares (primvars:skel:skinningMethod; default: each skin's
    /// own, as the source declares it). glTF is always LBS; use `rigport bake --skinning
    /// dqs` to bake DQS into a glTF.
    #[arg(long, value_enum)]
    pub skinning: Option<SkinningMethod>,
    /// The `upAxis` a .usda declares (default: the source's; the root prim's transform
    /// converts). glTF is always +Y up in metres.
    #[arg(long, value_enum, value_name = "AXIS")]
    pub up_axis: Option<UpAxis>,
    /// The `metersPerUnit` a .usda declares (default: the source's, 1 when it states none;
    /// the root prim's transform converts).
    #[arg(long, value_name = "M")]
    pub meters_per_unit: Option<f64>,
}

/// `rigport convert`.
#[derive(Debug, Args)]
pub struct ConvertArgs {
    /// The rig.
    #[command(flatten)]
    pub input: InputArgs,
    /// Where to write.
    #[command(flatten)]
    pub output: OutputArgs,
    /// Frame rate of AMC motions (the same as --amc-fps; default 120).
    #[arg(long, value_name = "FPS")]
    pub fps: Option<f32>,
}

/// `rigport animate`.
#[derive(Debug, Args)]
pub struct AnimateArgs {
    /// The rig.
    #[command(flatten)]
    pub input: InputArgs,
    /// The keyframes (see below).
    #[arg(long, value_name = "KEYS.json")]
    pub keys: PathBuf,
    /// Where to write.
    #[command(flatten)]
    pub output: OutputArgs,
}

/// `rigport retarget`.
#[derive(Debug, Args)]
pub struct RetargetArgs {
    /// The motion (a .bvh, an .asf with --motion/.amc, a glTF with clips).
    #[command(flatten)]
    pub input: InputArgs,
    /// The rig to put it on: files or a folder, as for inputs.
    #[arg(long, value_name = "RIG", required = true, num_args = 1..)]
    pub onto: Vec<PathBuf>,
    /// A joint map (see below); default: chosen by joint names.
    #[arg(long, value_name = "MAP.json")]
    pub map: Option<PathBuf>,
    /// The clip to retarget (default: the first).
    #[arg(long, value_name = "NAME")]
    pub clip: Option<String>,
    /// Plant the target's feet during their ground contacts (foot locking).
    #[arg(long)]
    pub plant_feet: bool,
    /// Turn the arms so the wrists follow the source's, scaled like the hips.
    #[arg(long)]
    pub match_hands: bool,
    /// Print the report as JSON on stdout.
    #[arg(long)]
    pub json: bool,
    /// Where to write.
    #[command(flatten)]
    pub output: OutputArgs,
}

/// `rigport retime`.
#[derive(Debug, Args)]
#[command(group(clap::ArgGroup::new("how").required(true).args(["frames", "fps", "speed", "warp", "reverse", "trim"])))]
pub struct RetimeArgs {
    /// The rig with its clips.
    #[command(flatten)]
    pub input: InputArgs,
    /// Resample to N frames over the same duration.
    #[arg(long, value_name = "N")]
    pub frames: Option<usize>,
    /// Resample at F frames per second over the same duration.
    #[arg(long, value_name = "F")]
    pub fps: Option<f32>,
    /// Play S times as fast (0.5 = half speed, twice as long).
    #[arg(long, value_name = "S")]
    pub speed: Option<f32>,
    /// Warp curve: output_seconds:source_seconds keys, monotone, e.g. 0:0,1:0.4,2:2.
    #[arg(long, value_name = "KEYS", allow_hyphen_values = true)]
    pub warp: Option<String>,
    /// Play backwards.
    #[arg(long)]
    pub reverse: bool,
    /// Keep only START..END seconds (times shift to start at 0).
    #[arg(long, value_name = "START..END")]
    pub trim: Option<String>,
    /// The clip to retime (default: the first).
    #[arg(long, value_name = "NAME")]
    pub clip: Option<String>,
    /// Where to write.
    #[command(flatten)]
    pub output: OutputArgs,
}

/// `rigport ik`.
#[derive(Debug, Args)]
pub struct IkArgs {
    /// The rig.
    #[command(flatten)]
    pub input: InputArgs,
    /// The handle tracks (see below).
    #[arg(long, value_name = "HANDLES.json")]
    pub handles: PathBuf,
    /// Solver: dls (damped least squares, adaptive damping), pinv (SVD pseudo-inverse),
    /// transpose (Jacobian transpose), ccd, fabrik.
    #[arg(long, default_value = "dls")]
    pub solver: String,
    /// Frames per second of the baked clip (default: the file's, else 30).
    #[arg(long, value_name = "F")]
    pub fps: Option<f32>,
    /// A handle has converged within this distance of its target (default: 1e-4 of the
    /// skeleton's height).
    #[arg(long, value_name = "T")]
    pub tolerance: Option<f32>,
    /// Most iterations per frame (per sub-step).
    #[arg(long, default_value_t = 100, value_name = "N")]
    pub max_iterations: u32,
    /// Fixed damping for dls (default: adaptive from the residual).
    #[arg(long, value_name = "L")]
    pub lambda: Option<f32>,
    /// Split target moves longer than D into sub-steps.
    #[arg(long, value_name = "D")]
    pub substep: Option<f32>,
    /// Let the root translate too (Jacobian solvers); the same as `"root_motion": "free"`
    /// in the handles file.
    #[arg(long)]
    pub free_root: bool,
    /// Print the residual summary as JSON on stdout.
    #[arg(long)]
    pub json: bool,
    /// Where to write.
    #[command(flatten)]
    pub output: OutputArgs,
}

/// `rigport footlock`.
#[derive(Debug, Args)]
pub struct FootlockArgs {
    /// The rig with its motion.
    #[command(flatten)]
    pub input: InputArgs,
    /// The clip to clean (default: the first).
    #[arg(long, value_name = "NAME")]
    pub clip: Option<String>,
    /// A foot: its ankle joint and, optionally, its toe joint (repeat for each foot).
    #[arg(long = "foot", value_name = "ANKLE[,TOE]")]
    pub feet: Vec<String>,
    /// Contact height: above a joint's lowest point, in skeleton heights (default 0.025).
    #[arg(long, value_name = "H")]
    pub height: Option<f32>,
    /// Contact speed: skeleton heights per second (default 0.25).
    #[arg(long, value_name = "V")]
    pub speed: Option<f32>,
    /// Seconds over which a leg eases into and out of a contact (default 0.1).
    #[arg(long, value_name = "S")]
    pub blend: Option<f32>,
    /// Pin each contact where it starts (default: at the joint's mean position over it).
    #[arg(long)]
    pub pin_first: bool,
    /// How much longer a leg may grow to reach a pin, as a fraction (default 0.1; 0 keeps
    /// bone lengths and lets such frames slide).
    #[arg(long, value_name = "F")]
    pub max_stretch: Option<f32>,
    /// Print the report as JSON on stdout.
    #[arg(long)]
    pub json: bool,
    /// Where to write.
    #[command(flatten)]
    pub output: OutputArgs,
}

/// `rigport sequence`.
#[derive(Debug, Args)]
pub struct SequenceArgs {
    /// The rigs whose clips play one after another (the first rig's skeleton and meshes
    /// are written; the others' clips are matched to it by joint name). A rig with several
    /// clips contributes all of them, in order.
    #[command(flatten)]
    pub input: InputArgs,
    /// Frames over which each clip blends into the next (slerp).
    #[arg(long, default_value_t = 0, value_name = "FRAMES")]
    pub crossfade: usize,
    /// Make the result loop seamlessly (its end blends into its start over --crossfade
    /// frames, at least one).
    #[arg(long = "loop")]
    pub looping: bool,
    /// Frame rate of the result (default: the first clip's).
    #[arg(long, value_name = "F")]
    pub fps: Option<f32>,
    /// Where to write.
    #[command(flatten)]
    pub output: OutputArgs,
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
    /// The clip to play (default: the first).
    #[arg(long, value_name = "NAME", conflicts_with = "pose")]
    pub clip: Option<String>,
    /// Sample the clip at F frames per second (default: at its own key times).
    #[arg(long, value_name = "F", conflicts_with = "pose")]
    pub fps: Option<f32>,
    /// Skinning method (default: the one the source declares for its skin, LBS unless a
    /// USD mesh says `dualQuaternion`).
    #[arg(long, value_enum)]
    pub skinning: Option<SkinningMethod>,
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
    /// The shared corpus folder: one rig of each family in it is rendered to
    /// DIR/corpus/<family>.png (default: `../shared/corpus` relative to the current
    /// directory; skipped with a note when absent).
    #[arg(long, value_name = "CORPUS_DIR", conflicts_with = "no_corpus")]
    pub corpus: Option<PathBuf>,
    /// Do not render corpus rigs.
    #[arg(long)]
    pub no_corpus: bool,
}

/// `rigport bake` arguments.
#[derive(Debug, clap::Args)]
#[command(
    after_help = "For every sampled frame and skinned vertex, with M the vertex's blended \
    LBS matrix (of the influences the glTF holds), the frame's target holds \
    M^-1 * p_dqs - p_rest, so a viewer's LBS of the morphed vertex lands on the DQS result. \
    Morph weights are animated (LINEAR, one key per frame) so that exactly frame k's target \
    is active at its time."
)]
pub struct BakeArgs {
    /// The rig, with at least one clip.
    #[command(flatten)]
    pub input: InputArgs,
    /// Output file: .glb or .gltf (+ .bin).
    #[arg(long, short, value_name = "OUT")]
    pub output: PathBuf,
    /// The skinning to bake (default: the one the source declares for its skin). `lbs`
    /// needs no correction and writes the plain file.
    #[arg(long, value_enum)]
    pub skinning: Option<SkinningMethod>,
    /// The clip to bake (default: the first).
    #[arg(long, value_name = "NAME")]
    pub clip: Option<String>,
    /// Sample the clip at F frames per second (default: at its own key times).
    #[arg(long, value_name = "F")]
    pub fps: Option<f32>,
    /// Corrections no longer than D (bind-space units) are left out of the sparse targets
    /// (default: 1e-6 of the bounding-box diagonal of the skinned meshes).
    #[arg(long, value_name = "D")]
    pub threshold: Option<f32>,
    /// Compress the per-frame targets to K shared targets (PCA) with per-frame weights.
    #[arg(long, value_name = "K", value_parser = clap::value_parser!(u32).range(1..))]
    pub correctives: Option<u32>,
    /// Influences kept per vertex in the glTF (1 to 8), and used for the DQS being baked.
    #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u8).range(1..=8))]
    pub max_influences: u8,
}

/// `rigport cloth` arguments.
#[derive(Debug, clap::Args)]
#[command(
    after_help = "The garment is a mesh of the input by name (e.g. the `Grid` of the USTC \
course's arm_with_cloth.usda, whose primvars:ControlPoints mark the pinned vertices) or an \
.obj in the rig's model space. Each pinned vertex is bound at rest to the nearest point of \
the skinned body and follows it exactly; the others are simulated (XPBD: inextensible edges, \
bending, gravity down the scene's up axis, damping, substeps) and collide with capsules \
fitted to the bones. glTF gets the garment as its own mesh animated by morph targets (one \
per frame, or --targets K shared ones) and a weights track; USD gets its points as time \
samples beside the UsdSkel body. Only the simulated clip is written."
)]
pub struct ClothArgs {
    /// The rig, with at least one clip.
    #[command(flatten)]
    pub input: InputArgs,
    /// The garment: the name of an unskinned mesh of the input, or an .obj file.
    #[arg(long, value_name = "GARMENT")]
    pub garment: String,
    /// Output file: .glb, .gltf (+ .bin), .usda, .usdc or .usdz.
    #[arg(long, short, value_name = "OUT")]
    pub output: PathBuf,
    /// The clip to simulate (default: the first).
    #[arg(long, value_name = "NAME")]
    pub clip: Option<String>,
    /// Pin these garment vertices (source numbering, comma-separated).
    #[arg(long, value_name = "LIST", value_delimiter = ',')]
    pub pin_vertices: Vec<u32>,
    /// Pin the garment vertices at or below height H (scene up axis and units).
    #[arg(long, value_name = "H", allow_hyphen_values = true)]
    pub pin_below: Option<f32>,
    /// Pin the garment vertices at or above height H.
    #[arg(long, value_name = "H", allow_hyphen_values = true)]
    pub pin_above: Option<f32>,
    /// Output frames per second (default: the clip's key rate when 24 or more, else 30).
    #[arg(long, value_name = "F")]
    pub fps: Option<f32>,
    /// Simulate S seconds, looping the clip (default: the clip once).
    #[arg(long, value_name = "S")]
    pub seconds: Option<f32>,
    /// Substeps per frame (default: 1200 per second).
    #[arg(long, value_name = "N")]
    pub substeps: Option<u32>,
    /// Collision thickness in model units (default: 1% of the body's diagonal).
    #[arg(long, value_name = "D")]
    pub thickness: Option<f32>,
    /// Compress the per-frame targets to K shared ones (PCA), as `bake --correctives`.
    #[arg(long, value_name = "K", value_parser = clap::value_parser!(u32).range(1..))]
    pub targets: Option<u32>,
}

/// `rigport render` arguments.
#[derive(Debug, clap::Args)]
#[command(
    after_help = "A .png output is a contact sheet: a grid of up to 16 frames evenly \
chosen from the sampled ones. A .gif output is a looping animation of every sampled frame \
(default 25 fps; the frame delay follows --fps, at least 0.02 s); .apng likewise, in full \
colour. All frames share one camera \
framed on the bounds of all of them. A rig without clips renders its rest pose.

--handles HANDLES.json (the file `rigport ik` takes; see `rigport ik --help`) draws each \
handle's target at each frame's time as a magenta crosshair over the mesh and skeleton; \
`relative` positions are offsets from the effector's rest position, as for `rigport ik`. \
The targets take part in the framing, so one away from the body is in the picture too.

--camera perspective frames the same bounds with a 35 deg (vertical) pinhole camera on the \
view axis through their centre, as far away as needed for their nearest face to be drawn \
at the orthographic scale, so everything fits inside the margin."
)]
pub struct RenderArgs {
    /// The rig.
    #[command(flatten)]
    pub input: crate::cli::InputArgs,
    /// The picture to write: .png (contact sheet), .gif or .apng (animation).
    #[arg(long, short, value_name = "OUT.png|OUT.gif|OUT.apng")]
    pub output: PathBuf,
    /// The clip to draw (default: the first).
    #[arg(long, value_name = "NAME")]
    pub clip: Option<String>,
    /// Sample the clip at F frames per second (default: its key times for .png, 25 for
    /// animations).
    #[arg(long, value_name = "F")]
    pub fps: Option<f32>,
    /// Keep sampled frames a..b (0-based, b excluded; `a..` and `..b` work too).
    #[arg(long, value_name = "a..b", value_parser = parse_range)]
    pub frames: Option<FrameRange>,
    /// Size of one view in pixels (`--skinning both` pictures are twice as wide).
    #[arg(long, value_name = "WxH", default_value = "512x512", value_parser = parse_size)]
    pub size: (u32, u32),
    /// Where the camera looks from: front (+Z), side (+X), top (+Y) or three-quarter.
    #[arg(long, value_enum, default_value_t = ViewArg::Front)]
    pub view: ViewArg,
    /// Orthographic (parallel) or perspective (35 deg field of view) projection.
    #[arg(long, value_enum, default_value_t = CameraArg::Ortho)]
    pub camera: CameraArg,
    /// Draw the targets of these IK handles (HANDLES.json, as `rigport ik` reads it) as
    /// markers, at each frame's time.
    #[arg(long, value_name = "HANDLES.json")]
    pub handles: Option<PathBuf>,
    /// Skinning method; `both` draws LBS (left) and DQS (right) with the same camera.
    /// Default: the method the source declares for its skin (LBS unless a USD mesh says
    /// `dualQuaternion`).
    #[arg(long, value_name = "lbs|dqs|both", value_parser = render_skinning)]
    pub skinning: Option<&'static [SkinningMethod]>,
    /// Do not draw the skeleton over the mesh.
    #[arg(long)]
    pub no_skeleton: bool,
    /// Do not draw the frame number.
    #[arg(long)]
    pub no_frame_counter: bool,
}

/// A half-open range of frame indices.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FrameRange {
    /// First index kept.
    pub start: usize,
    /// First index not kept; `None`: through the last.
    pub end: Option<usize>,
}

/// `--view`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum ViewArg {
    /// From +Z looking towards -Z.
    Front,
    /// From +X.
    Side,
    /// From +Y, looking down.
    Top,
    /// From the front-right, slightly above.
    ThreeQuarter,
}

/// `--camera`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum CameraArg {
    /// Orthographic: sizes do not change with depth.
    Ortho,
    /// Perspective, 35 deg vertical field of view.
    Perspective,
}

/// `rigport render --skinning`: one method, or `both` (LBS left, DQS right).
fn render_skinning(s: &str) -> Result<&'static [SkinningMethod], String> {
    match s {
        "both" => Ok(rigport_render::LBS_AND_DQS),
        "lbs" => Ok(&[SkinningMethod::Lbs]),
        "dqs" => Ok(&[SkinningMethod::Dqs]),
        _ => Err(format!("{s:?}: expected lbs, dqs or both")),
    }
}

fn parse_range(s: &str) -> Result<FrameRange, String> {
    let (a, b) = s
        .split_once("..")
        .ok_or_else(|| format!("{s:?}: expected a..b"))?;
    let num = |t: &str| -> Result<Option<usize>, String> {
        if t.is_empty() {
            return Ok(None);
        }
        t.parse()
            .map(Some)
            .map_err(|_| format!("{t:?}: expected a frame index"))
    };
    let start = num(a)?.unwrap_or(0);
    let end = num(b)?;
    if end.is_some_and(|e| e <= start) {
        return Err(format!("{s:?}: the range is empty"));
    }
    Ok(FrameRange { start, end })
}

fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("{s:?}: expected WxH, e.g. 512x512"))?;
    let px = |t: &str| -> Result<u32, String> {
        match t.parse::<u32>() {
            Ok(v) if (1..=16384).contains(&v) => Ok(v),
            _ => Err(format!("{t:?}: expected 1 to 16384 pixels")),
        }
    };
    Ok((px(w)?, px(h)?))
}

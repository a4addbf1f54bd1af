//! The argument groups and value parsers the commands share: where a rig comes from
//! ([`InputArgs`]), where and how an asset is written ([`OutputArgs`]), and the one check
//! of each kind of number (a frame rate, a distance), so every flag says the same thing.

use std::path::PathBuf;

use clap::Args;
use rigport_model::{Compression, InfluencesFit, SkinningMethod, UpAxis};
use std::str::FromStr as _;

use rigport_pipeline::load::{Input, Inputs};
use rigport_pipeline::units::InputUnits;
use rigport_pipeline::write::{Output, WriteOptions};

/// Where a rig comes from.
#[derive(Clone, Debug, Args)]
pub struct InputArgs {
    /// Input files or folders: a .glb/.gltf; an .obj with Pinocchio skeleton and attachment .out
    /// files (told apart by name or content); a USC CSCI 520 skin.config; or a folder holding
    /// one of these sets. Required unless --mesh, --skeleton or --attachment names the files.
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
    /// An AMC motion for the .asf among the inputs (repeat for several; or give .amc inputs).
    #[arg(long, value_name = "M.amc")]
    pub motion: Vec<PathBuf>,
    /// Frame rate of AMC motions, which do not state one (default: 120, CMU's rate).
    #[arg(long, value_name = "FPS", value_parser = frame_rate)]
    pub amc_fps: Option<f32>,
    /// No bone mesh for skeleton-only inputs (ASF/AMC, BVH; by default each bone gets one).
    #[arg(long)]
    pub no_bone_mesh: bool,
    /// Skin weights where the rig has none (a Pinocchio mesh and skeleton without attachment,
    /// a CSCI 520 folder without weights): auto (bone heat).
    #[arg(long, value_name = "auto", value_parser = ["auto"])]
    pub weights: Option<String>,
    /// Unit of inputs that state none (BVH, OBJ/Pinocchio, CSCI 520): m, cm, mm, in, ft, metres
    /// per unit, or auto (cm for a human 100-250 units tall). Default: m, warned if too tall.
    #[arg(long, value_name = "UNIT", value_parser = InputUnits::from_str)]
    pub input_units: Option<InputUnits>,
    /// Apply --input-units even to a file that states its own unit (ASF, USD, glTF).
    #[arg(long, requires = "input_units")]
    pub force_units: bool,
}

impl InputArgs {
    /// The pipeline's view of these arguments, within this run's memory budget.
    pub fn to_input(&self) -> Input {
        Input {
            files: Inputs {
                paths: self.inputs.clone(),
                mesh: self.mesh.clone(),
                skeleton: self.skeleton.clone(),
                attachment: self.attachment.clone(),
                motions: self.motion.clone(),
                amc_fps: self.amc_fps,
                auto_weights: self.weights.is_some(),
            },
            bone_mesh: !self.no_bone_mesh,
            budget: rigport_pipeline::memory::installed(),
            units: self.input_units,
            force_units: self.force_units,
        }
    }
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
    /// Reduce animation keys while every joint and points 3 cm from it (or the vertices it
    /// skins) stay within D (rig units; without D, 1 mm) of the full clip at every key time.
    #[arg(long, value_name = "D", value_parser = distance)]
    pub reduce_tolerance: Option<Option<f32>>,
    /// Reducing keys (core glTF), also fit CUBICSPLINE tracks where smaller. three.js and
    /// Babylon.js play them; Blender's importer drops their tangents.
    #[arg(long)]
    pub reduce_cubic: bool,
    /// glTF compression: meshopt (EXT_meshopt_compression, required; reduces keys as above).
    #[arg(long, value_enum, value_name = "C", default_value_t = Compression::None)]
    pub compress: Compression,
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

impl OutputArgs {
    /// The pipeline's view of these arguments.
    pub fn to_output(&self) -> Output {
        Output {
            path: self.output.clone(),
            options: WriteOptions {
                max_influences: self.max_influences.map(usize::from),
                influences_fit: self.influences_fit,
                skinning: self.skinning,
                up_axis: self.up_axis,
                meters_per_unit: self.meters_per_unit,
                morphs_as_points: false,
                compression: self.compress,
            },
            reduce_tolerance: self.reduce_tolerance.flatten(),
            reduce: self.reduce_tolerance.is_some(),
            cubic: self.reduce_cubic,
        }
    }
}

/// The value parsers of the numbers every command shares (`--fps`, `--amc-fps`:
/// a frame rate; `--reduce-tolerance`, `--threshold`: a distance; `--lambda`; `--speed`).
pub use rigport_pipeline::numbers::{distance, frame_rate, non_negative, positive};

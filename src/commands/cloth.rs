//! `rigport cloth`: a garment simulated on the animated body and baked into the output
//! (`rigport_pipeline::cloth`).

use std::path::PathBuf;

use anyhow::Result;
use rigport_deform::cloth::PinSelection;
use rigport_pipeline::cloth::ClothRequest;

use crate::args::{frame_rate, InputArgs};
use crate::context::Context;

/// `rigport cloth` arguments.
#[derive(Debug, clap::Args)]
#[command(after_help = include_str!("../../docs/help/cloth.txt"))]
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
    #[arg(long, value_name = "F", value_parser = frame_rate)]
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
    /// Seconds of pre-roll settling the garment into the first pose and each cut (default 2).
    #[arg(long, value_name = "S")]
    pub preroll: Option<f32>,
    /// Collide with the whole body, not only the bones near the garment at rest (and up).
    #[arg(long)]
    pub collide_all: bool,
    /// Keep a simulation past the stability limits (warning W007) instead of failing.
    #[arg(long)]
    pub allow_unstable: bool,
    /// Print the report as JSON on stdout, with every frame's measurements.
    #[arg(long)]
    pub json: bool,
    /// Compress the per-frame targets to K shared ones (PCA), as `bake --correctives`.
    #[arg(long, value_name = "K", value_parser = clap::value_parser!(u32).range(1..))]
    pub targets: Option<u32>,
}

/// Runs `cloth`.
pub fn run(ctx: &Context, args: &ClothArgs) -> Result<()> {
    let mut pins = Vec::new();
    if !args.pin_vertices.is_empty() {
        pins.push(PinSelection::Vertices(args.pin_vertices.clone()));
    }
    pins.extend(args.pin_below.map(PinSelection::Below));
    pins.extend(args.pin_above.map(PinSelection::Above));
    let request = ClothRequest {
        garment: args.garment.clone(),
        pins,
        clip: args.clip.clone(),
        fps: args.fps,
        seconds: args.seconds,
        substeps: args.substeps,
        thickness: args.thickness,
        preroll: args.preroll,
        collide_all: args.collide_all,
        allow_unstable: args.allow_unstable,
        json: args.json,
        targets: args.targets,
        output: args.output.clone(),
    };
    ctx.run(|progress| rigport_pipeline::cloth(&args.input.to_input(), &request, progress))
}

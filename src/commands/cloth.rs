//! `rigport cloth`: a garment simulated on the animated body and baked into the output
//! (`rigport_pipeline::cloth`; its [`ClothRequest`] is the flags, but the pins).

use anyhow::Result;
use rigport_deform::cloth::PinSelection;
use rigport_pipeline::cloth::ClothRequest;

use crate::args::InputArgs;
use crate::context::Context;

/// `rigport cloth` arguments.
#[derive(Debug, clap::Args)]
#[command(after_help = include_str!("../../docs/help/cloth.txt"))]
pub struct ClothArgs {
    /// The rig, with at least one clip.
    #[command(flatten)]
    pub input: InputArgs,
    /// The garment, the simulation and the output.
    #[command(flatten)]
    pub request: ClothRequest,
    /// Pin these garment vertices (source numbering, comma-separated).
    #[arg(long, value_name = "LIST", value_delimiter = ',')]
    pub pin_vertices: Vec<u32>,
    /// Pin the garment vertices at or below height H (scene up axis and units).
    #[arg(long, value_name = "H", allow_hyphen_values = true)]
    pub pin_below: Option<f32>,
    /// Pin the garment vertices at or above height H.
    #[arg(long, value_name = "H", allow_hyphen_values = true)]
    pub pin_above: Option<f32>,
}

/// Runs `cloth`.
pub fn run(ctx: &Context, args: &ClothArgs) -> Result<()> {
    let mut request = args.request.clone();
    if !args.pin_vertices.is_empty() {
        request
            .pins
            .push(PinSelection::Vertices(args.pin_vertices.clone()));
    }
    request.pins.extend(args.pin_below.map(PinSelection::Below));
    request.pins.extend(args.pin_above.map(PinSelection::Above));
    ctx.run(|progress| rigport_pipeline::cloth(&args.input.to_input(), &request, progress))
}

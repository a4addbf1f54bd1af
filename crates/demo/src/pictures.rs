//! The demo's pictures: contact sheets of `wave` and `reach` (with its IK targets), a GIF of
//! `wave`, one frame of `twist` skinned with LBS and DQS side by side, and a contact sheet
//! of the skirt simulated on `wave` ([`skirt_picture`]).

use rigport_model::Asset;
use rigport_render::{FrameTime, RenderOptions, View, LBS_AND_DQS};

use crate::clips::TWIST_PEAK_S;
use crate::{Demo, DemoError};

/// Size of one view (one contact-sheet cell, one GIF frame) in the demo's pictures, pixels.
pub const CELL_PX: u32 = 256;
/// Frame rate of `wave.gif`.
pub const GIF_FPS: f32 = 15.0;
/// Size of each half of `twist_lbs_vs_dqs.png`, pixels: larger than a sheet cell, since the
/// camera frames the whole body and the forearm is a small part of it.
pub const TWIST_PX: u32 = 384;

/// One encoded picture.
#[derive(Clone, Debug, PartialEq)]
pub struct Picture {
    /// Its file name (`wave.png`).
    pub file: String,
    /// The PNG or GIF bytes.
    pub bytes: Vec<u8>,
    /// What it shows, for messages.
    pub what: String,
}

/// Renders the demo's pictures, in the order `wave.png`, `reach.png`, `wave.gif`,
/// `twist_lbs_vs_dqs.png`.
///
/// # Errors
/// [`DemoError::Render`] (a rigport bug for the built-in rig).
pub fn pictures(demo: &Demo) -> Result<Vec<Picture>, DemoError> {
    let asset = &demo.asset;
    let failed = |what: &str| {
        let what = format!("the demo's {what} clip (a rigport bug)");
        move |source| DemoError::Render { what, source }
    };
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
            Some(&demo.reach_targets as &dyn rigport_render::Markers),
            View::ThreeQuarter,
        ),
    ] {
        let options = RenderOptions { view, ..sheet };
        let bytes = rigport_render::render_clip_png(asset, Some(clip), markers, &options)
            .map_err(failed(&format!("{clip:?}")))?;
        let extra = if markers.is_some() {
            ", three-quarter view, IK targets as magenta crosshairs"
        } else {
            ""
        };
        written.push(Picture {
            file: format!("{clip}.png"),
            bytes,
            what: format!("contact sheet of clip {clip:?}, LBS{extra}"),
        });
    }
    let bytes = rigport_render::render_clip_gif(asset, Some("wave"), None, GIF_FPS, &sheet)
        .map_err(failed("wave"))?;
    written.push(Picture {
        file: "wave.gif".into(),
        bytes,
        what: format!("clip \"wave\", {CELL_PX}x{CELL_PX} at {GIF_FPS} fps"),
    });
    // One frame at the largest twist, LBS left and DQS right through the same camera; no
    // skeleton overlay, whose bone line would hide the collapsed forearm.
    let twist = rigport_render::find_clip(asset, Some("twist")).map_err(failed("twist"))?;
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
            skinning: LBS_AND_DQS,
            skeleton: false,
            frame_counter: false,
            ..RenderOptions::default()
        },
    )
    .map_err(failed("twist"))?;
    let bytes = match frames.first() {
        Some(frame) => rigport_render::encode_png(frame).map_err(failed("twist"))?,
        None => {
            return Err(failed("twist")(rigport_render::RenderError::EmptyAnimation));
        }
    };
    written.push(Picture {
        file: "twist_lbs_vs_dqs.png".into(),
        bytes,
        what: format!("clip \"twist\" at {TWIST_PEAK_S} s: LBS left, DQS right"),
    });
    Ok(written)
}

/// `skirt.png`: a contact sheet of the demo with its skirt ([`crate::skirt::bake`]'s asset),
/// evenly chosen frames of the simulated clip, seen three-quarter so the bell's depth shows.
///
/// # Errors
/// [`DemoError::Render`] (a rigport bug).
pub fn skirt_picture(asset: &Asset) -> Result<Picture, DemoError> {
    let clip = crate::skirt::CLIP;
    let options = RenderOptions {
        width: CELL_PX,
        height: CELL_PX,
        view: View::ThreeQuarter,
        ..RenderOptions::default()
    };
    let bytes =
        rigport_render::render_clip_png(asset, Some(clip), None, &options).map_err(|source| {
            DemoError::Render {
                what: format!("the demo's skirt on clip {clip:?} (a rigport bug)"),
                source,
            }
        })?;
    Ok(Picture {
        file: "skirt.png".into(),
        bytes,
        what: format!("contact sheet of the skirt simulated on clip {clip:?}, three-quarter view"),
    })
}

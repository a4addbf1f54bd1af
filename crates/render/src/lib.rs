//! rigport's CPU renderer: pictures of rigs and clips on a headless machine.
//!
//! A small z-buffered triangle rasterizer ([`raster`]) draws the skinned meshes with flat,
//! two-sided shading (a fixed directional light plus ambient) through an orthographic
//! camera ([`camera`]) framed once on the bounds of every rendered frame, so the character
//! does not jump. The skeleton is drawn on top (bones as lines, joints as discs) and an
//! optional frame counter in a corner. [`render_clip_png`] writes a contact sheet,
//! [`render_clip_gif`] an animation.
//!
//! Output is deterministic: frames are evaluated independently (in parallel with rayon),
//! bounds are combined with exact min/max, and nothing depends on time or hash order.
#![warn(missing_docs)]

pub mod camera;
mod encode;
pub mod raster;

use rayon::prelude::*;
use rigport_eval::sample::{CompiledClip, SampleError, SampleJob};
use rigport_eval::{EvalError, Pose, Rig, RigOutput, SkinningMethod};
use rigport_model::glam::{Mat4, Vec3};
use rigport_model::{Asset, Clip};

pub use camera::{Bounds, Camera, View};
pub use encode::{
    apng_delay_ms, contact_sheet, encode_apng, encode_gif, encode_png, gif_delay_cs, pick_evenly,
};
pub use raster::{Framebuffer, Rgba};

/// The background colour of every picture.
pub const BACKGROUND: Rgba = [38, 41, 48, 255];
/// Bone lines of the skeleton overlay.
pub const BONE_COLOR: Rgba = [240, 96, 64, 255];
/// Joint discs of the skeleton overlay.
pub const JOINT_COLOR: Rgba = [255, 214, 80, 255];
/// The frame counter.
pub const TEXT_COLOR: Rgba = [235, 235, 235, 255];
/// Base colours of meshes, mesh `i` uses entry `i % 4`.
pub const MESH_COLORS: [Rgba; 4] = [
    [222, 196, 164, 255],
    [150, 182, 222, 255],
    [170, 210, 160, 255],
    [220, 164, 182, 255],
];
/// Shading levels per mesh colour: flat shading is quantized to these so that every
/// picture uses the fixed [`palette`] (GIF frames then need no colour quantization).
pub const SHADE_LEVELS: usize = 48;
/// Fraction of the light every face gets regardless of its orientation.
const AMBIENT: f32 = 0.28;
/// Picture fraction left free on each side when framing.
const MARGIN: f32 = 0.08;
/// Most frames on a contact sheet.
pub const SHEET_FRAMES: usize = 16;

/// Every colour the renderer writes: background, overlay, text, then
/// [`SHADE_LEVELS`] shades of each mesh colour (at most 256 entries, one GIF palette).
pub fn palette() -> Vec<Rgba> {
    let mut p = vec![BACKGROUND, BONE_COLOR, JOINT_COLOR, TEXT_COLOR];
    for base in MESH_COLORS {
        for level in 0..SHADE_LEVELS {
            p.push(shade(base, level));
        }
    }
    p
}

/// `base` at shading level `level` of `SHADE_LEVELS` (0 = ambient only, last = fully lit).
fn shade(base: Rgba, level: usize) -> Rgba {
    let lit = level as f32 / (SHADE_LEVELS - 1) as f32;
    let k = AMBIENT + (1.0 - AMBIENT) * lit;
    let c = |v: u8| (f32::from(v) * k).round().clamp(0.0, 255.0) as u8;
    [c(base[0]), c(base[1]), c(base[2]), 255]
}

/// Which skinning the meshes are drawn with.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SkinningChoice {
    /// Linear blend skinning.
    #[default]
    Lbs,
    /// Dual quaternion skinning.
    Dqs,
    /// LBS on the left, DQS on the right, same camera: pictures are twice as wide.
    Both,
}

impl SkinningChoice {
    fn methods(self) -> &'static [SkinningMethod] {
        match self {
            SkinningChoice::Lbs => &[SkinningMethod::Lbs],
            SkinningChoice::Dqs => &[SkinningMethod::Dqs],
            SkinningChoice::Both => &[SkinningMethod::Lbs, SkinningMethod::Dqs],
        }
    }
}

/// How pictures are drawn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderOptions {
    /// Width of one view in pixels (a `Both` picture is twice as wide).
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Where the camera looks from.
    pub view: View,
    /// Skinning method(s).
    pub skinning: SkinningChoice,
    /// Draw the skeleton on top.
    pub skeleton: bool,
    /// Write the frame number in the top-left corner.
    pub frame_counter: bool,
}

impl Default for RenderOptions {
    fn default() -> Self {
        Self {
            width: 512,
            height: 512,
            view: View::Front,
            skinning: SkinningChoice::Lbs,
            skeleton: true,
            frame_counter: true,
        }
    }
}

/// One frame to draw: a number for the counter and a time in the clip.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameTime {
    /// Shown by the frame counter.
    pub number: u64,
    /// Seconds into the clip (ignored for the rest pose).
    pub time: f32,
}

/// Errors of the renderer.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// The picture size is zero or too large.
    #[error("picture size {width}x{height}: expected 1 to 16384 pixels each way")]
    Size {
        /// Requested width in pixels.
        width: u32,
        /// Requested height in pixels.
        height: u32,
    },
    /// No clip has the requested name.
    #[error("no clip named {name:?}; clips: {available:?}")]
    NoClip {
        /// The requested name.
        name: String,
        /// The asset's clip names.
        available: Vec<String>,
    },
    /// The frame rate is not a positive number.
    #[error("frame rate {fps}: expected a positive number")]
    Fps {
        /// The rate given, frames per second.
        fps: f32,
    },
    /// Nothing to draw: the frame list is empty.
    #[error("no frames to render")]
    EmptyAnimation,
    /// A GIF frame is too large or the frames differ in size.
    #[error("GIF frames must be at most 65535x65535 and all the same size (got {width}x{height})")]
    GifSize {
        /// Width in pixels.
        width: u32,
        /// Height in pixels.
        height: u32,
    },
    /// An animation frame differs in size from the first.
    #[error("animation frames must all be the same size (got one of {width}x{height})")]
    FrameSize {
        /// Width in pixels.
        width: u32,
        /// Height in pixels.
        height: u32,
    },
    /// The rig cannot be evaluated.
    #[error("the rig cannot be evaluated")]
    Eval(#[from] EvalError),
    /// The clip does not fit the skeleton, or a sample time is bad.
    #[error("the clip cannot be sampled")]
    Sample(#[from] SampleError),
    /// The PNG encoder failed.
    #[error("PNG encoding failed")]
    Png(#[from] png::EncodingError),
    /// The GIF encoder failed.
    #[error("GIF encoding failed")]
    Gif(#[from] gif::EncodingError),
}

/// The clip of `asset` named `name`, or its first clip when `name` is `None` (`None` when
/// it has no clips: render the rest pose).
///
/// # Errors
/// [`RenderError::NoClip`] when no clip has that name.
pub fn find_clip<'a>(
    asset: &'a Asset,
    name: Option<&str>,
) -> Result<Option<&'a Clip>, RenderError> {
    match name {
        None => Ok(asset.clips.first()),
        Some(name) => asset
            .clips
            .iter()
            .find(|c| c.name == name)
            .map(Some)
            .ok_or_else(|| RenderError::NoClip {
                name: name.to_string(),
                available: asset.clips.iter().map(|c| c.name.clone()).collect(),
            }),
    }
}

/// The sample times of `clip` (seconds): every `1 / fps` from its start, plus its end; its
/// key times when `fps` is `None`; `[0]` without a clip (the rest pose).
///
/// # Errors
/// [`RenderError::Fps`] for a non-positive or non-finite `fps`, [`RenderError::Sample`]
/// if the clip does not fit the skeleton.
pub fn clip_times(
    asset: &Asset,
    clip: Option<&Clip>,
    fps: Option<f32>,
) -> Result<Vec<f32>, RenderError> {
    if let Some(fps) = fps {
        if !(fps.is_finite() && fps > 0.0) {
            return Err(RenderError::Fps { fps });
        }
    }
    let Some(clip) = clip else {
        return Ok(vec![0.0]);
    };
    let compiled = CompiledClip::new(clip, &asset.skeleton)?;
    Ok(match fps {
        None => compiled.key_times(),
        Some(fps) => rigport_eval::sample::sample_times(compiled.start(), compiled.end(), fps),
    })
}

/// Per-thread evaluation state.
struct Evaluator<'a> {
    rig: &'a Rig<'a>,
    clip: Option<&'a CompiledClip<'a>>,
    rest: &'a Pose,
}

impl Evaluator<'_> {
    fn pose(
        &self,
        time: f32,
        method: SkinningMethod,
        pose: &mut Pose,
        out: &mut RigOutput,
    ) -> Result<(), RenderError> {
        if let Some(clip) = self.clip {
            SampleJob {
                clip,
                time,
                rest: &self.rest.local,
                output: &mut pose.local,
            }
            .run()?;
        }
        self.rig.evaluate_with(pose, method, out)?;
        Ok(())
    }
}

/// The model-space position of a joint matrix.
fn origin(m: &Mat4) -> Vec3 {
    m.w_axis.truncate()
}

/// Renders `frames` of `clip` (the rest pose without a clip), one picture per frame: the
/// meshes as `rig` skins them and the skeleton, all frames through one camera framed on
/// the bounds of all of them. Pictures are `options.width` x `options.height`, twice as
/// wide for [`SkinningChoice::Both`].
///
/// # Errors
/// [`RenderError::Size`] for a zero or over-large size, [`RenderError::Eval`] /
/// [`RenderError::Sample`] if the asset cannot be evaluated or the clip sampled.
pub fn render_frames(
    asset: &Asset,
    clip: Option<&Clip>,
    frames: &[FrameTime],
    options: &RenderOptions,
) -> Result<Vec<Framebuffer>, RenderError> {
    let (w, h) = (options.width, options.height);
    if !(1..=16384).contains(&w) || !(1..=16384).contains(&h) {
        return Err(RenderError::Size {
            width: w,
            height: h,
        });
    }
    let rig = Rig::new(asset)?;
    let compiled = clip
        .map(|c| CompiledClip::new(c, &asset.skeleton))
        .transpose()?;
    let rest = Pose::rest(&asset.skeleton);
    let eval = Evaluator {
        rig: &rig,
        clip: compiled.as_ref(),
        rest: &rest,
    };
    let methods = options.skinning.methods();
    let rotation = options.view.model_to_view();
    let init = || (rest.clone(), RigOutput::default());

    // Pass 1: view-space bounds over every frame and method (exact min/max, so the result
    // does not depend on how rayon splits the work).
    let bounds = frames
        .par_iter()
        .map_init(init, |(pose, out), f| -> Result<Bounds, RenderError> {
            let mut b = Bounds::default();
            for &method in methods {
                eval.pose(f.time, method, pose, out)?;
                for positions in &out.positions {
                    for &p in positions {
                        b.add(rotation * p);
                    }
                }
                for m in &out.joint_model {
                    b.add(rotation * origin(m));
                }
            }
            Ok(b)
        })
        .try_reduce(Bounds::default, |a, b| Ok(a.union(b)))?;
    let camera = Camera::framing(options.view, bounds, w, h, MARGIN);

    // Pass 2: draw. Evaluating again costs less memory than keeping every frame's vertices.
    frames
        .par_iter()
        .map_init(init, |(pose, out), f| -> Result<Framebuffer, RenderError> {
            let mut picture = Framebuffer::color_only(w * methods.len() as u32, h, BACKGROUND);
            for (k, &method) in methods.iter().enumerate() {
                eval.pose(f.time, method, pose, out)?;
                let mut panel = Framebuffer::new(w, h, BACKGROUND);
                draw_meshes(&mut panel, asset, &out.positions, &camera);
                if options.skeleton {
                    draw_skeleton(&mut panel, asset, &out.joint_model, &camera);
                }
                if options.frame_counter {
                    let scale = (w.min(h) / 128).max(1);
                    let at = i64::from(2 * scale);
                    panel.number(f.number, at, at, scale, TEXT_COLOR);
                }
                if methods.len() > 1 {
                    // Side by side: name each panel's method in its top-right corner.
                    let label = match method {
                        SkinningMethod::Lbs => "LBS",
                        SkinningMethod::Dqs => "DQS",
                    };
                    let scale = (w.min(h) / 128).max(1);
                    let s = i64::from(scale);
                    let x = i64::from(w) - (4 * label.len() as i64 + 1) * s;
                    panel.text(label, x, 2 * s, scale, TEXT_COLOR);
                }
                picture.blit(&panel, k as u32 * w, 0);
            }
            Ok(picture)
        })
        .collect()
}

/// Draws every mesh's triangles, flat and two-sided: the light comes from the camera's
/// upper left, fixed in view space so every view is lit alike.
fn draw_meshes(fb: &mut Framebuffer, asset: &Asset, positions: &[Vec<Vec3>], camera: &Camera) {
    let light = Vec3::new(-0.4, 0.6, 0.7).normalize();
    for (mi, (mesh, posed)) in asset.meshes.iter().zip(positions).enumerate() {
        let base = MESH_COLORS[mi % MESH_COLORS.len()];
        for tri in &mesh.triangles {
            let (Some(&a), Some(&b), Some(&c)) = (
                posed.get(tri[0] as usize),
                posed.get(tri[1] as usize),
                posed.get(tri[2] as usize),
            ) else {
                continue;
            };
            let n = camera.to_view((b - a).cross(c - a)).normalize_or_zero();
            // Two-sided: a back face is lit as if it faced the viewer.
            let lit = n.dot(light).abs();
            let level = (lit * (SHADE_LEVELS - 1) as f32).round() as usize;
            let color = shade(base, level.min(SHADE_LEVELS - 1));
            fb.triangle(
                [camera.project(a), camera.project(b), camera.project(c)],
                color,
            );
        }
    }
}

/// Draws bones (joint to parent) as lines, then joints as discs, over everything.
fn draw_skeleton(fb: &mut Framebuffer, asset: &Asset, joint_model: &[Mat4], camera: &Camera) {
    let size = fb.width().min(fb.height());
    let thickness = (size / 256).max(1);
    let radius = (size as f32 / 128.0).max(1.5);
    let screen = |m: &Mat4| {
        let p = camera.project(origin(m));
        [p[0], p[1]]
    };
    for (j, parent) in asset.skeleton.parents().enumerate() {
        if let (Some(p), Some(m)) = (parent, joint_model.get(j)) {
            if let Some(pm) = joint_model.get(p.get()) {
                fb.line(screen(pm), screen(m), thickness, BONE_COLOR);
            }
        }
    }
    for m in joint_model {
        fb.disc(screen(m), radius, JOINT_COLOR);
    }
}

/// The frames of `clip` to draw: sample times at `fps` (key times when `None`), keeping
/// the sample indices in `range` (half-open, clamped to the samples), numbered by index.
///
/// # Errors
/// As [`clip_times`].
pub fn frame_list(
    asset: &Asset,
    clip: Option<&Clip>,
    fps: Option<f32>,
    range: Option<(usize, Option<usize>)>,
) -> Result<Vec<FrameTime>, RenderError> {
    let times = clip_times(asset, clip, fps)?;
    let (a, b) = range.unwrap_or((0, None));
    let b = b.unwrap_or(times.len()).min(times.len());
    Ok(times
        .iter()
        .enumerate()
        .skip(a)
        .take(b.saturating_sub(a))
        .map(|(i, &time)| FrameTime {
            number: i as u64,
            time,
        })
        .collect())
}

/// A PNG contact sheet of `frames`: up to [`SHEET_FRAMES`] of them evenly chosen, framed
/// on the chosen ones, laid out by [`contact_sheet`].
///
/// # Errors
/// As [`render_frames`] and [`encode_png`]; [`RenderError::EmptyAnimation`] without frames.
pub fn render_sheet_png(
    asset: &Asset,
    clip: Option<&Clip>,
    frames: &[FrameTime],
    options: &RenderOptions,
) -> Result<Vec<u8>, RenderError> {
    if frames.is_empty() {
        return Err(RenderError::EmptyAnimation);
    }
    let chosen: Vec<FrameTime> = pick_evenly(frames.len(), SHEET_FRAMES)
        .into_iter()
        .filter_map(|i| frames.get(i).copied())
        .collect();
    let pictures = render_frames(asset, clip, &chosen, options)?;
    encode_png(&contact_sheet(&pictures, BACKGROUND))
}

/// A looping GIF of `frames`, `delay_cs` hundredths of a second each (see
/// [`gif_delay_cs`]).
///
/// # Errors
/// As [`render_frames`] and [`encode_gif`].
pub fn render_gif(
    asset: &Asset,
    clip: Option<&Clip>,
    frames: &[FrameTime],
    delay_cs: u16,
    options: &RenderOptions,
) -> Result<Vec<u8>, RenderError> {
    let pictures = render_frames(asset, clip, frames, options)?;
    encode_gif(&pictures, delay_cs)
}

/// A looping animated PNG of `frames`, `delay_ms` milliseconds each (see
/// [`apng_delay_ms`]).
///
/// # Errors
/// As [`render_frames`] and [`encode_apng`].
pub fn render_apng(
    asset: &Asset,
    clip: Option<&Clip>,
    frames: &[FrameTime],
    delay_ms: u16,
    options: &RenderOptions,
) -> Result<Vec<u8>, RenderError> {
    let pictures = render_frames(asset, clip, frames, options)?;
    encode_apng(&pictures, delay_ms)
}

/// The demo's helper: a PNG contact sheet of the clip named `clip` (the first clip when
/// `None`, the rest pose when the asset has none), sampled at its key times.
///
/// # Errors
/// [`RenderError::NoClip`], and as [`render_sheet_png`].
pub fn render_clip_png(
    asset: &Asset,
    clip: Option<&str>,
    options: &RenderOptions,
) -> Result<Vec<u8>, RenderError> {
    let clip = find_clip(asset, clip)?;
    let frames = frame_list(asset, clip, None, None)?;
    render_sheet_png(asset, clip, &frames, options)
}

/// The demo's helper: a GIF of the clip named `clip` (as [`render_clip_png`]) sampled at
/// `fps` frames per second and played at that rate.
///
/// # Errors
/// [`RenderError::NoClip`], [`RenderError::Fps`], and as [`render_gif`].
pub fn render_clip_gif(
    asset: &Asset,
    clip: Option<&str>,
    fps: f32,
    options: &RenderOptions,
) -> Result<Vec<u8>, RenderError> {
    let clip = find_clip(asset, clip)?;
    let frames = frame_list(asset, clip, Some(fps), None)?;
    render_gif(asset, clip, &frames, gif_delay_cs(fps), options)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rigport_model::{Joint, Mesh, Skeleton, Transform};

    /// One joint and an unskinned unit square in the XY plane (model space), two CCW
    /// triangles.
    fn square() -> Asset {
        let skeleton = Skeleton::new(vec![Joint {
            name: "root".into(),
            parent: None,
            rest_local: Transform::IDENTITY,
        }])
        .unwrap();
        let mesh = Mesh {
            positions: vec![
                Vec3::new(-1.0, -1.0, 0.0),
                Vec3::new(1.0, -1.0, 0.0),
                Vec3::new(1.0, 1.0, 0.0),
                Vec3::new(-1.0, 1.0, 0.0),
            ],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
            source_vertex: vec![0, 1, 2, 3],
            ..Mesh::default()
        };
        Asset {
            skeleton,
            meshes: vec![mesh],
            ..Asset::default()
        }
    }

    #[test]
    fn rest_pose_square_is_framed_with_the_margin() {
        let asset = square();
        let options = RenderOptions {
            width: 100,
            height: 100,
            skeleton: false,
            frame_counter: false,
            ..RenderOptions::default()
        };
        let frames = frame_list(&asset, None, None, None).unwrap();
        assert_eq!(frames.len(), 1);
        let pics = render_frames(&asset, None, &frames, &options).unwrap();
        let drawn: Vec<usize> = pics[0]
            .pixels()
            .iter()
            .enumerate()
            .filter(|(_, &c)| c != BACKGROUND)
            .map(|(i, _)| i)
            .collect();
        // An 8% margin on each side of 100 px leaves an 84 x 84 square.
        assert_eq!(drawn.len(), 84 * 84);
        assert_eq!(drawn.first(), Some(&(8 * 100 + 8)));
        // Facing the camera and the light alike: one colour.
        let c = pics[0].pixels()[drawn[0]];
        assert!(drawn.iter().all(|&i| pics[0].pixels()[i] == c));
        assert!(palette().contains(&c));

        // Seen edge-on from the side, the square is a vertical line of no area.
        let side = RenderOptions {
            view: View::Side,
            ..options
        };
        let pics = render_frames(&asset, None, &frames, &side).unwrap();
        assert!(pics[0].pixels().iter().all(|&c| c == BACKGROUND));
    }

    #[test]
    fn both_is_twice_as_wide_and_overlay_is_drawn() {
        let asset = square();
        let options = RenderOptions {
            width: 40,
            height: 30,
            skinning: SkinningChoice::Both,
            ..RenderOptions::default()
        };
        let frames = frame_list(&asset, None, None, None).unwrap();
        let pics = render_frames(&asset, None, &frames, &options).unwrap();
        assert_eq!((pics[0].width(), pics[0].height()), (80, 30));
        assert!(pics[0].pixels().contains(&JOINT_COLOR));
        assert!(pics[0].pixels().contains(&TEXT_COLOR));
        assert!(matches!(
            render_frames(
                &asset,
                None,
                &frames,
                &RenderOptions {
                    width: 0,
                    ..options
                }
            ),
            Err(RenderError::Size { .. })
        ));
        assert!(matches!(
            render_clip_png(&asset, Some("walk"), &options),
            Err(RenderError::NoClip { .. })
        ));
    }

    /// The column range `[min, max]` of non-background pixels and their count.
    fn extent(fb: &Framebuffer) -> (u32, u32, usize) {
        let mut out = (u32::MAX, 0, 0);
        for y in 0..fb.height() {
            for x in 0..fb.width() {
                if fb.get(x, y) != Some(BACKGROUND) {
                    out = (out.0.min(x), out.1.max(x), out.2 + 1);
                }
            }
        }
        out
    }

    #[test]
    fn one_camera_frames_the_whole_clip() {
        use rigport_model::{Clip, Interpolation, JointIndex, Track, TrackTarget};
        let mut asset = square();
        asset.meshes[0].attached_to = Some(JointIndex(0));
        asset.clips.push(Clip {
            name: "slide".into(),
            tracks: vec![Track {
                target: TrackTarget::Translation(JointIndex(0)),
                interpolation: Interpolation::Linear,
                times: vec![0.0, 1.0],
                values: vec![0.0, 0.0, 0.0, 4.0, 0.0, 0.0],
            }],
        });
        let options = RenderOptions {
            width: 100,
            height: 100,
            skeleton: false,
            frame_counter: false,
            ..RenderOptions::default()
        };
        let clip = find_clip(&asset, Some("slide")).unwrap();
        let frames = frame_list(&asset, clip, Some(2.0), None).unwrap();
        let times: Vec<f32> = frames.iter().map(|f| f.time).collect();
        assert_eq!(times, vec![0.0, 0.5, 1.0]);
        let pics = render_frames(&asset, clip, &frames, &options).unwrap();
        // Bounds x in [-1, 5], y in [-1, 1]: 84 px over 6 units is 14 px per unit, so the
        // 2-unit square is 28 px wide in every frame and slides from the left margin (8) to
        // the right one (92, exclusive).
        let e: Vec<_> = pics.iter().map(extent).collect();
        assert_eq!(e[0], (8, 35, 28 * 28));
        assert_eq!(e[1], (36, 63, 28 * 28));
        assert_eq!(e[2], (64, 91, 28 * 28));
        // Only the chosen frames are framed: the last one alone fills the picture's width.
        let last = render_frames(&asset, clip, &frames[2..], &options).unwrap();
        assert_eq!(extent(&last[0]).2, 84 * 84);
        // Rendering again, or in a different split, gives the same pixels.
        let again = render_frames(&asset, clip, &frames, &options).unwrap();
        assert_eq!(pics, again);
    }

    #[test]
    fn palette_fits_a_gif() {
        let p = palette();
        assert!(p.len() <= 256);
        let mut sorted = p.clone();
        sorted.sort_unstable();
        sorted.dedup();
        assert!(sorted.len() > 4 * SHADE_LEVELS / 2);
    }
}

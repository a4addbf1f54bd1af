//! rigport's CPU renderer: pictures of rigs and clips on a headless machine.
//!
//! A small z-buffered triangle rasterizer ([`raster`]) draws the skinned meshes with flat,
//! two-sided shading (a fixed directional light plus ambient) through a camera
//! ([`camera`]), orthographic by default or perspective ([`Projection`], near-plane
//! clipped), framed once on the bounds of every rendered frame, so the character does not
//! jump. The skeleton is drawn on top (bones as lines, joints as discs), then optional
//! markers ([`Markers`]: model-space points over time, such as IK targets, which take part
//! in the framing so a point outside the body stays in the picture), and an optional frame
//! counter in a corner. [`render_sheet_png`] writes a contact sheet, [`render_gif`] and
//! [`render_apng`] animations; [`render_clip_png`] and [`render_clip_gif`] are shortcuts
//! for a named clip. The crate reads no file format: callers resolve their inputs (clips,
//! IK handle files) into an [`Asset`] and [`Markers`].
//!
//! Output is deterministic: frames are evaluated independently (in parallel with rayon),
//! bounds are combined with exact min/max, and nothing depends on time or hash order.
#![warn(missing_docs)]

pub mod camera;
pub mod deviation;
mod encode;
pub mod raster;
mod surface;

use rayon::prelude::*;
use rigport_eval::sample::{CompiledClip, SampleError, SampleJob};
use rigport_eval::{EvalError, MorphWeights, Pose, Rig, RigOutput};
use rigport_model::glam::{Mat4, Vec3};
use rigport_model::SkinningMethod;
use rigport_model::{Asset, Clip, NoSuchClip};

pub use camera::{Bounds, Camera, ClippedPolygon, Lens, Projection, View};
pub use encode::{
    apng_delay_ms, contact_sheet, encode_apng, encode_gif, encode_png, gif_delay_cs, pick_evenly,
};
pub use raster::{Framebuffer, Rgba};
pub use surface::MESH_COLORS;
use surface::{Look, Surfaces};

/// The background colour of every picture.
pub const BACKGROUND: Rgba = [38, 41, 48, 255];
/// Bone lines of the skeleton overlay.
pub const BONE_COLOR: Rgba = [240, 96, 64, 255];
/// Joint discs of the skeleton overlay.
pub const JOINT_COLOR: Rgba = [255, 214, 80, 255];
/// The frame counter.
pub const TEXT_COLOR: Rgba = [235, 235, 235, 255];
/// Markers ([`Markers`], e.g. IK targets): a magenta that no mesh shade or overlay uses.
pub const MARKER_COLOR: Rgba = [255, 48, 255, 255];
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
/// [`SHADE_LEVELS`] shades of each mesh colour, then the marker colour (at most 256
/// entries, one GIF palette; later additions go last so earlier colours keep their GIF
/// indices).
pub fn palette() -> Vec<Rgba> {
    let mut p = vec![BACKGROUND, BONE_COLOR, JOINT_COLOR, TEXT_COLOR];
    for base in MESH_COLORS {
        for level in 0..SHADE_LEVELS {
            p.push(shade(base, level));
        }
    }
    p.push(MARKER_COLOR);
    p
}

/// `base` at shading level `level` of `SHADE_LEVELS` (0 = ambient only, last = fully lit).
fn shade(base: Rgba, level: usize) -> Rgba {
    let k = light_factor(level);
    let c = |v: u8| (f32::from(v) * k).round().clamp(0.0, 255.0) as u8;
    [c(base[0]), c(base[1]), c(base[2]), 255]
}

/// The light factor of shading level `level` (0 = ambient only, last = fully lit).
fn light_factor(level: usize) -> f32 {
    let lit = level as f32 / (SHADE_LEVELS - 1) as f32;
    AMBIENT + (1.0 - AMBIENT) * lit
}

/// LBS on the left, DQS on the right, same camera: a [`RenderOptions::skinning`] whose
/// pictures are twice as wide.
pub const LBS_AND_DQS: &[SkinningMethod] = &[SkinningMethod::Lbs, SkinningMethod::Dqs];

/// How pictures are drawn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderOptions {
    /// Width of one view in pixels (a picture of [`LBS_AND_DQS`] is twice as wide).
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Where the camera looks from.
    pub view: View,
    /// Orthographic or perspective, framed on the same bounds.
    pub projection: Projection,
    /// The skinning methods, one view each, side by side left to right (none: LBS).
    pub skinning: &'static [SkinningMethod],
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
            projection: Projection::Orthographic,
            skinning: &[SkinningMethod::Lbs],
            skeleton: true,
            frame_counter: true,
        }
    }
}

/// Points drawn over every frame as markers (a crosshair in [`MARKER_COLOR`] on top of the
/// meshes and the skeleton), e.g. the targets of IK handles. Their positions take part in
/// the camera's framing, so a marker away from the body is in the picture too.
///
/// Closures `Fn(f32, &mut Vec<Vec3>)` implement it, and a `Vec` or array of points is a set
/// of markers that stay put:
///
/// ```
/// use rigport_render::Markers;
/// use rigport_model::glam::Vec3;
/// let rising = |t: f32, out: &mut Vec<Vec3>| out.push(Vec3::new(0.0, t, 0.0));
/// let mut at = Vec::new();
/// rising.markers_at(2.0, &mut at);
/// [Vec3::X].markers_at(2.0, &mut at);
/// assert_eq!(at, [Vec3::new(0.0, 2.0, 0.0), Vec3::X]);
/// ```
pub trait Markers: Sync {
    /// Appends the model-space positions of the markers at `time` (seconds into the clip,
    /// as [`FrameTime::time`]) to `out`. Non-finite positions are not drawn.
    fn markers_at(&self, time: f32, out: &mut Vec<Vec3>);
}

/// IK handle targets over time, as `rigport ik` solves for them.
impl Markers for rigport_ik::clip::HandleTargets {
    fn markers_at(&self, time: f32, out: &mut Vec<Vec3>) {
        self.targets_at(time, out);
    }
}

impl<F: Fn(f32, &mut Vec<Vec3>) + Sync> Markers for F {
    fn markers_at(&self, time: f32, out: &mut Vec<Vec3>) {
        self(time, out);
    }
}

impl Markers for Vec<Vec3> {
    fn markers_at(&self, _time: f32, out: &mut Vec<Vec3>) {
        out.extend_from_slice(self);
    }
}

impl<const N: usize> Markers for [Vec3; N] {
    fn markers_at(&self, _time: f32, out: &mut Vec<Vec3>) {
        out.extend_from_slice(self);
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
    #[error(transparent)]
    NoClip(#[from] NoSuchClip),
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
    /// The frame grid would hold more than `rigport_eval::sample::MAX_FRAMES` frames.
    #[error(transparent)]
    Frames(EvalError),
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
    Ok(asset.clip(name)?)
}

/// The sample times of `clip` (seconds): every `1 / fps` from its start, plus its end; its
/// key times when `fps` is `None`; `[0]` without a clip (the rest pose).
///
/// # Errors
/// [`RenderError::Fps`] for a non-positive or non-finite `fps`, [`RenderError::Frames`] for
/// one that needs too many frames, [`RenderError::Sample`]
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
        Some(fps) => rigport_eval::sample::FrameGrid::new(compiled.start(), compiled.end(), fps)
            .map_err(RenderError::Frames)?
            .into_times(),
    })
}

/// Per-thread evaluation state.
struct Evaluator<'a> {
    rig: &'a Rig<'a>,
    clip: Option<&'a CompiledClip<'a>>,
    rest: &'a Pose,
}

impl Evaluator<'_> {
    /// Samples the clip's joints and morph weights at `time` and evaluates the frame.
    fn pose(
        &self,
        time: f32,
        method: SkinningMethod,
        frame: &mut (Pose, MorphWeights),
        out: &mut RigOutput,
    ) -> Result<(), RenderError> {
        let (pose, weights) = frame;
        if let Some(clip) = self.clip {
            SampleJob {
                clip,
                time,
                rest: &self.rest.local,
                output: &mut pose.local,
            }
            .run()?;
            weights.sample(clip, time)?;
        }
        self.rig.evaluate_frame(pose, weights, method, out)?;
        Ok(())
    }
}

/// The model-space position of a joint matrix.
fn origin(m: &Mat4) -> Vec3 {
    m.w_axis.truncate()
}

/// Renders `frames` of `clip` (the rest pose without a clip), one picture per frame: the
/// meshes as `rig` skins them, the skeleton and the `markers` at each frame's time, all
/// frames through one camera framed on the bounds of all of them (markers included).
/// Pictures are `options.width` x `options.height`, twice as wide for
/// [`LBS_AND_DQS`].
///
/// # Errors
/// [`RenderError::Size`] for a zero or over-large size, [`RenderError::Eval`] /
/// [`RenderError::Sample`] if the asset cannot be evaluated or the clip sampled.
pub fn render_frames(
    asset: &Asset,
    clip: Option<&Clip>,
    frames: &[FrameTime],
    markers: Option<&dyn Markers>,
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
    // No method given draws LBS, the default.
    let methods = match options.skinning {
        [] => &[SkinningMethod::Lbs][..],
        methods => methods,
    };
    let rotation = options.view.model_to_view();
    let init = || {
        (
            (rest.clone(), rig.rest_weights().clone()),
            RigOutput::default(),
            Vec::new(),
        )
    };

    // Pass 1: view-space bounds over every frame and method (exact min/max, so the result
    // does not depend on how rayon splits the work).
    let bounds = frames
        .par_iter()
        .map_init(
            init,
            |(frame, out, points), f| -> Result<Bounds, RenderError> {
                let mut b = Bounds::default();
                if let Some(markers) = markers {
                    points.clear();
                    markers.markers_at(f.time, points);
                    for &p in points.iter() {
                        b.add(rotation * p);
                    }
                }
                for &method in methods {
                    eval.pose(f.time, method, frame, out)?;
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
            },
        )
        .try_reduce(Bounds::default, |a, b| Ok(a.union(b)))?;
    let camera = Camera::framing_with(options.view, options.projection, bounds, w, h, MARGIN);
    let surfaces = Surfaces::new(asset);

    // Pass 2: draw. Evaluating again costs less memory than keeping every frame's vertices.
    frames
        .par_iter()
        .map_init(
            init,
            |(frame, out, points), f| -> Result<Framebuffer, RenderError> {
                let mut picture = Framebuffer::color_only(w * methods.len() as u32, h, BACKGROUND);
                points.clear();
                if let Some(markers) = markers {
                    markers.markers_at(f.time, points);
                }
                for (k, &method) in methods.iter().enumerate() {
                    eval.pose(f.time, method, frame, out)?;
                    let mut panel = Framebuffer::new(w, h, BACKGROUND);
                    draw_meshes(&mut panel, asset, &out.positions, &camera, &surfaces);
                    if options.skeleton {
                        draw_skeleton(&mut panel, asset, &out.joint_model, &camera);
                    }
                    draw_markers(&mut panel, points, &camera);
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
            },
        )
        .collect()
}

/// Draws every mesh's triangles, flat and two-sided: the light comes from the camera's
/// upper left, fixed in view space so every view is lit alike. A mesh with a material
/// shows its base colour (factor, and texture sampled with its UVs: see `surface.rs`); one
/// without shows a [`MESH_COLORS`] entry.
fn draw_meshes(
    fb: &mut Framebuffer,
    asset: &Asset,
    positions: &[Vec<Vec3>],
    camera: &Camera,
    surfaces: &Surfaces,
) {
    let light = Vec3::new(-0.4, 0.6, 0.7).normalize();
    for (mi, (mesh, posed)) in asset.meshes.iter().zip(positions).enumerate() {
        let look = surfaces.look(asset, mi);
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
            let k = light_factor(level.min(SHADE_LEVELS - 1));
            let flat = look.color(*tri, [1.0, 0.0, 0.0], k);
            if let (Look::Textured { .. }, Some(pa), Some(pb), Some(pc)) = (
                &look,
                camera.project(a),
                camera.project(b),
                camera.project(c),
            ) {
                // Wholly in front of the near plane: textured per pixel.
                fb.triangle_shaded([pa, pb, pc], |w| look.color(*tri, w, k));
                continue;
            }
            // Clipped to the near plane under perspective: 0, 1 or 2 triangles.
            for t in camera.clip_triangle([a, b, c]).triangles() {
                fb.triangle(t, flat);
            }
        }
    }
}

/// Draws bones (joint to parent) as lines, then joints as discs, over everything.
fn draw_skeleton(fb: &mut Framebuffer, asset: &Asset, joint_model: &[Mat4], camera: &Camera) {
    let size = fb.width().min(fb.height());
    let thickness = (size / 256).max(1);
    let radius = (size as f32 / 128.0).max(1.5);
    for (j, parent) in asset.skeleton.parents().enumerate() {
        if let (Some(p), Some(m)) = (parent, joint_model.get(j)) {
            if let Some(pm) = joint_model.get(p.get()) {
                if let Some([a, b]) = camera.clip_segment(origin(pm), origin(m)) {
                    fb.line(a, b, thickness, BONE_COLOR);
                }
            }
        }
    }
    for m in joint_model {
        if let Some([x, y, _]) = camera.project(origin(m)) {
            fb.disc([x, y], radius, JOINT_COLOR);
        }
    }
}

/// Draws each marker as a crosshair (a ring with a cross through it) in [`MARKER_COLOR`],
/// outlined in the background colour so it stands out on the mesh and the skeleton alike;
/// over everything, ignoring depth. Points behind the camera are skipped.
fn draw_markers(fb: &mut Framebuffer, points: &[Vec3], camera: &Camera) {
    let size = fb.width().min(fb.height());
    let radius = (size as f32 / 40.0).max(3.0);
    let thickness = (size / 256).max(1) + 1;
    let arm = radius * 1.6;
    let screen: Vec<[f32; 2]> = points
        .iter()
        .filter_map(|&p| camera.project(p))
        .map(|[x, y, _]| [x, y])
        .collect();
    // All outlines first, so one marker's outline does not cut into another's colour.
    for (color, width) in [(BACKGROUND, thickness + 2), (MARKER_COLOR, thickness)] {
        for &[x, y] in &screen {
            let half = width as f32 * 0.5;
            fb.ring([x, y], radius - half, radius + half, color);
            fb.line([x - arm, y], [x + arm, y], width, color);
            fb.line([x, y - arm], [x, y + arm], width, color);
        }
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

/// A PNG contact sheet of `frames` (with `markers`, see [`render_frames`]): up to
/// [`SHEET_FRAMES`] of them evenly chosen, framed on the chosen ones, laid out by
/// [`contact_sheet`].
///
/// # Errors
/// As [`render_frames`] and [`encode_png`]; [`RenderError::EmptyAnimation`] without frames.
pub fn render_sheet_png(
    asset: &Asset,
    clip: Option<&Clip>,
    frames: &[FrameTime],
    markers: Option<&dyn Markers>,
    options: &RenderOptions,
) -> Result<Vec<u8>, RenderError> {
    if frames.is_empty() {
        return Err(RenderError::EmptyAnimation);
    }
    let chosen: Vec<FrameTime> = pick_evenly(frames.len(), SHEET_FRAMES)
        .into_iter()
        .filter_map(|i| frames.get(i).copied())
        .collect();
    let pictures = render_frames(asset, clip, &chosen, markers, options)?;
    encode_png(&contact_sheet(&pictures, BACKGROUND))
}

/// A looping GIF of `frames` (with `markers`, see [`render_frames`]), `delay_cs`
/// hundredths of a second each (see [`gif_delay_cs`]).
///
/// # Errors
/// As [`render_frames`] and [`encode_gif`].
pub fn render_gif(
    asset: &Asset,
    clip: Option<&Clip>,
    frames: &[FrameTime],
    markers: Option<&dyn Markers>,
    delay_cs: u16,
    options: &RenderOptions,
) -> Result<Vec<u8>, RenderError> {
    let pictures = render_frames(asset, clip, frames, markers, options)?;
    encode_gif(&pictures, delay_cs)
}

/// A looping animated PNG of `frames` (with `markers`, see [`render_frames`]), `delay_ms`
/// milliseconds each (see [`apng_delay_ms`]).
///
/// # Errors
/// As [`render_frames`] and [`encode_apng`].
pub fn render_apng(
    asset: &Asset,
    clip: Option<&Clip>,
    frames: &[FrameTime],
    markers: Option<&dyn Markers>,
    delay_ms: u16,
    options: &RenderOptions,
) -> Result<Vec<u8>, RenderError> {
    let pictures = render_frames(asset, clip, frames, markers, options)?;
    encode_apng(&pictures, delay_ms)
}

/// The demo's helper: a PNG contact sheet of the clip named `clip` (the first clip when
/// `None`, the rest pose when the asset has none), sampled at its key times, with
/// `markers` (see [`render_frames`]).
///
/// # Errors
/// [`RenderError::NoClip`], and as [`render_sheet_png`].
pub fn render_clip_png(
    asset: &Asset,
    clip: Option<&str>,
    markers: Option<&dyn Markers>,
    options: &RenderOptions,
) -> Result<Vec<u8>, RenderError> {
    let clip = find_clip(asset, clip)?;
    let frames = frame_list(asset, clip, None, None)?;
    render_sheet_png(asset, clip, &frames, markers, options)
}

/// The demo's helper: a GIF of the clip named `clip` (as [`render_clip_png`]) sampled at
/// `fps` frames per second and played at that rate, with `markers`.
///
/// # Errors
/// [`RenderError::NoClip`], [`RenderError::Fps`], and as [`render_gif`].
pub fn render_clip_gif(
    asset: &Asset,
    clip: Option<&str>,
    markers: Option<&dyn Markers>,
    fps: f32,
    options: &RenderOptions,
) -> Result<Vec<u8>, RenderError> {
    let clip = find_clip(asset, clip)?;
    let frames = frame_list(asset, clip, Some(fps), None)?;
    render_gif(asset, clip, &frames, markers, gif_delay_cs(fps), options)
}

#[cfg(test)]
mod tests;

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
mod encode;
pub mod raster;
mod surface;

use rayon::prelude::*;
use rigport_eval::sample::{CompiledClip, SampleError, SampleJob};
use rigport_eval::{EvalError, Pose, Rig, RigOutput, SkinningMethod};
use rigport_model::glam::{Mat4, Vec3};
use rigport_model::{Asset, Clip, TrackTarget};

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
    /// Orthographic or perspective, framed on the same bounds.
    pub projection: Projection,
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
            projection: Projection::Orthographic,
            skinning: SkinningChoice::Lbs,
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
impl Markers for rigport_eval::ik::clip::HandleTargets {
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
        if let Some(clip) = self.clip {
            self.morph_unskinned(clip, time, out);
        }
        Ok(())
    }

    /// Unskinned meshes attached to no joint whose morph weights the clip animates (a
    /// garment baked by `rigport cloth`): rest positions plus the weighted targets at
    /// `time`. Skinned meshes keep their rest shape (morphing before skinning is not drawn).
    fn morph_unskinned(&self, clip: &CompiledClip<'_>, time: f32, out: &mut RigOutput) {
        let asset = self.rig.asset();
        for track in clip.weight_tracks() {
            let TrackTarget::MorphWeights(m) = track.target else {
                continue;
            };
            let mi = m.get();
            let Some(mesh) = asset.meshes.get(mi) else {
                continue;
            };
            if self.rig.skin_of_mesh(mi).is_some() || mesh.attached_to.is_some() {
                continue;
            }
            let mut weights = vec![0.0; track.components()];
            if rigport_eval::sample::sample_weights(track, time, &mut weights).is_err() {
                continue;
            }
            let Some(dst) = out.positions.get_mut(mi) else {
                continue;
            };
            for (target, &w) in mesh.morph_targets.iter().zip(&weights) {
                if w != 0.0 {
                    for (p, d) in dst.iter_mut().zip(&target.position_deltas) {
                        *p += *d * w;
                    }
                }
            }
        }
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
/// [`SkinningChoice::Both`].
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
    let methods = options.skinning.methods();
    let rotation = options.view.model_to_view();
    let init = || (rest.clone(), RigOutput::default(), Vec::new());

    // Pass 1: view-space bounds over every frame and method (exact min/max, so the result
    // does not depend on how rayon splits the work).
    let bounds = frames
        .par_iter()
        .map_init(
            init,
            |(pose, out, points), f| -> Result<Bounds, RenderError> {
                let mut b = Bounds::default();
                if let Some(markers) = markers {
                    points.clear();
                    markers.markers_at(f.time, points);
                    for &p in points.iter() {
                        b.add(rotation * p);
                    }
                }
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
            |(pose, out, points), f| -> Result<Framebuffer, RenderError> {
                let mut picture = Framebuffer::color_only(w * methods.len() as u32, h, BACKGROUND);
                points.clear();
                if let Some(markers) = markers {
                    markers.markers_at(f.time, points);
                }
                for (k, &method) in methods.iter().enumerate() {
                    eval.pose(f.time, method, pose, out)?;
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
        let pics = render_frames(&asset, None, &frames, None, &options).unwrap();
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
        let pics = render_frames(&asset, None, &frames, None, &side).unwrap();
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
        let pics = render_frames(&asset, None, &frames, None, &options).unwrap();
        assert_eq!((pics[0].width(), pics[0].height()), (80, 30));
        assert!(pics[0].pixels().contains(&JOINT_COLOR));
        assert!(pics[0].pixels().contains(&TEXT_COLOR));
        assert!(matches!(
            render_frames(
                &asset,
                None,
                &frames,
                None,
                &RenderOptions {
                    width: 0,
                    ..options
                }
            ),
            Err(RenderError::Size { .. })
        ));
        assert!(matches!(
            render_clip_png(&asset, Some("walk"), None, &options),
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
        let pics = render_frames(&asset, clip, &frames, None, &options).unwrap();
        // Bounds x in [-1, 5], y in [-1, 1]: 84 px over 6 units is 14 px per unit, so the
        // 2-unit square is 28 px wide in every frame and slides from the left margin (8) to
        // the right one (92, exclusive).
        let e: Vec<_> = pics.iter().map(extent).collect();
        assert_eq!(e[0], (8, 35, 28 * 28));
        assert_eq!(e[1], (36, 63, 28 * 28));
        assert_eq!(e[2], (64, 91, 28 * 28));
        // Only the chosen frames are framed: the last one alone fills the picture's width.
        let last = render_frames(&asset, clip, &frames[2..], None, &options).unwrap();
        assert_eq!(extent(&last[0]).2, 84 * 84);
        // Rendering again, or in a different split, gives the same pixels.
        let again = render_frames(&asset, clip, &frames, None, &options).unwrap();
        assert_eq!(pics, again);
    }

    /// The pixels of `color` in `fb`, as `(x, y)`.
    fn pixels_of(fb: &Framebuffer, color: Rgba) -> Vec<(u32, u32)> {
        (0..fb.height())
            .flat_map(|y| (0..fb.width()).map(move |x| (x, y)))
            .filter(|&(x, y)| fb.get(x, y) == Some(color))
            .collect()
    }

    #[test]
    fn markers_are_framed_and_drawn_on_top() {
        let asset = square();
        let options = RenderOptions {
            width: 100,
            height: 100,
            skeleton: false,
            frame_counter: false,
            ..RenderOptions::default()
        };
        let frames = frame_list(&asset, None, None, None).unwrap();
        let plain = render_frames(&asset, None, &frames, None, &options).unwrap();
        assert!(pixels_of(&plain[0], MARKER_COLOR).is_empty());
        // One marker far to the right, one behind the square's centre.
        let points = [Vec3::new(5.0, 0.0, 0.0), Vec3::new(0.0, 0.0, -3.0)];
        let marked = render_frames(&asset, None, &frames, Some(&points), &options).unwrap();
        let fb = &marked[0];
        // Bounds x in [-1, 5]: 14 px per unit from x = 8, so the far marker's centre is at
        // (92, 50) (a pixel corner) and the square spans columns 8..36.
        for (x, y) in [(91, 49), (92, 50), (91, 50), (92, 49)] {
            assert_eq!(fb.get(x, y), Some(MARKER_COLOR), "far marker at ({x}, {y})");
        }
        // The behind one is drawn over the square, depth ignored.
        assert_eq!(fb.get(21, 50), Some(MARKER_COLOR));
        // The crosshair is inside the picture, clear of its border.
        assert!(pixels_all(fb)
            .iter()
            .all(|&(x, y)| (1..99).contains(&x) && (1..99).contains(&y)));
        // The square got smaller to make room: 28 px instead of 84.
        let square_px = fb
            .pixels()
            .iter()
            .filter(|&&c| c != BACKGROUND && c != MARKER_COLOR)
            .count();
        assert!(square_px < 28 * 28, "{square_px}");
        // Markers move with time: a closure of time, evaluated at each frame's time.
        let moving = |t: f32, out: &mut Vec<Vec3>| out.push(Vec3::new(t, 0.0, 0.0));
        let at_zero = render_frames(&asset, None, &frames, Some(&moving), &options).unwrap();
        assert_eq!(at_zero[0].get(50, 50), Some(MARKER_COLOR));
        // Deterministic.
        let again = render_frames(&asset, None, &frames, Some(&points), &options).unwrap();
        assert_eq!(marked, again);
    }

    /// A closed box `[-1, 1] x [0, 3] x [-0.5, 0.5]`, unskinned, 12 triangles.
    fn boxy() -> Asset {
        let mut asset = square();
        let (lo, hi) = (Vec3::new(-1.0, 0.0, -0.5), Vec3::new(1.0, 3.0, 0.5));
        let positions: Vec<Vec3> = (0..8)
            .map(|i| {
                Vec3::new(
                    if i & 1 == 0 { lo.x } else { hi.x },
                    if i & 2 == 0 { lo.y } else { hi.y },
                    if i & 4 == 0 { lo.z } else { hi.z },
                )
            })
            .collect();
        let quads = [
            [0, 1, 3, 2],
            [4, 6, 7, 5],
            [0, 4, 5, 1],
            [2, 3, 7, 6],
            [0, 2, 6, 4],
            [1, 5, 7, 3],
        ];
        asset.meshes[0].triangles = quads
            .iter()
            .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
            .collect();
        asset.meshes[0].source_vertex = (0..8).collect();
        asset.meshes[0].positions = positions;
        asset
    }

    #[test]
    fn perspective_keeps_the_silhouette_inside_and_is_deterministic() {
        let asset = boxy();
        let frames = frame_list(&asset, None, None, None).unwrap();
        for view in [View::Front, View::Side, View::Top, View::ThreeQuarter] {
            let ortho = RenderOptions {
                width: 120,
                height: 100,
                view,
                skeleton: false,
                frame_counter: false,
                ..RenderOptions::default()
            };
            let persp = RenderOptions {
                projection: Projection::PERSPECTIVE,
                ..ortho
            };
            let o = render_frames(&asset, None, &frames, None, &ortho).unwrap();
            let p = render_frames(&asset, None, &frames, None, &persp).unwrap();
            let (po, pp) = (extent(&o[0]), extent(&p[0]));
            // Inside the margin (8% of 120 px = 9.6 px per side), not empty, and no larger
            // than the orthographic picture, whose nearest face it draws at the same scale.
            assert!(pp.0 >= 9 && pp.1 <= 120 - 10, "{view:?}: columns {pp:?}");
            assert!(
                pp.2 > po.2 / 3 && pp.2 <= po.2 + 2 * 120,
                "{view:?}: {pp:?} vs {po:?}"
            );
            let rows: Vec<u32> = pixels_all(&p[0]).iter().map(|&(_, y)| y).collect();
            assert!(rows.iter().all(|&y| (8..=91).contains(&y)), "{view:?}");
            // Seen head-on along an axis, the box's near face hides the rest and is drawn at
            // the orthographic scale (checked below); from three-quarters the far parts shrink.
            if view == View::ThreeQuarter {
                assert!(o != p, "{view:?}: perspective differs from orthographic");
            }
            let again = render_frames(&asset, None, &frames, None, &persp).unwrap();
            assert!(p == again, "{view:?}: not deterministic");
            assert!(p[0].pixels().iter().all(|c| palette().contains(c)));
        }
        // Seen from the front, the near face (z = 0.5) hides the far one: the perspective
        // silhouette of a box seen head-on is its near face, drawn at the orthographic scale.
        let front = RenderOptions {
            width: 100,
            height: 100,
            skeleton: false,
            frame_counter: false,
            projection: Projection::PERSPECTIVE,
            ..RenderOptions::default()
        };
        let p = render_frames(&asset, None, &frames, None, &front).unwrap();
        let o = render_frames(
            &asset,
            None,
            &frames,
            None,
            &RenderOptions {
                projection: Projection::Orthographic,
                ..front
            },
        )
        .unwrap();
        let (cp, co) = (extent(&p[0]).2, extent(&o[0]).2);
        assert!(cp.abs_diff(co) <= 2 * 84, "{cp} vs {co}");
    }

    #[test]
    fn perspective_shrinks_far_things_and_depth_test_keeps_the_near_one() {
        // Two equal squares facing the camera, the second 3 units farther and shifted right
        // so that the near one hides part of it.
        let near = square().meshes.remove(0);
        let mut far = near.clone();
        for p in &mut far.positions {
            *p += Vec3::new(1.0, 0.0, -3.0);
        }
        let options = RenderOptions {
            width: 100,
            height: 100,
            skeleton: false,
            frame_counter: false,
            projection: Projection::PERSPECTIVE,
            ..RenderOptions::default()
        };
        let mut a = square();
        a.meshes = vec![near.clone(), far.clone()];
        let mut b = square();
        b.meshes = vec![far, near];
        let frames = frame_list(&a, None, None, None).unwrap();
        let pa = render_frames(&a, None, &frames, None, &options).unwrap();
        let pb = render_frames(&b, None, &frames, None, &options).unwrap();
        // Facing the camera, each square is one shade of its mesh's colour.
        let color = |fb: &Framebuffer, base: Rgba| -> Rgba {
            fb.pixels()
                .iter()
                .copied()
                .find(|&c| (0..SHADE_LEVELS).any(|l| shade(base, l) == c))
                .unwrap()
        };
        let (a0, a1) = (color(&pa[0], MESH_COLORS[0]), color(&pa[0], MESH_COLORS[1]));
        let (b0, b1) = (color(&pb[0], MESH_COLORS[0]), color(&pb[0], MESH_COLORS[1]));
        // Drawn in either order, the near square wins the same pixels.
        assert_eq!(pixels_of(&pa[0], a0), pixels_of(&pb[0], b1));
        assert_eq!(pixels_of(&pa[0], a1), pixels_of(&pb[0], b0));
        // The far square is drawn smaller: fewer rows than the near one.
        let rows = |px: Vec<(u32, u32)>| {
            let (lo, hi) = px
                .iter()
                .fold((u32::MAX, 0), |(lo, hi), &(_, y)| (lo.min(y), hi.max(y)));
            hi + 1 - lo
        };
        let (near_rows, far_rows) = (rows(pixels_of(&pa[0], a0)), rows(pixels_of(&pa[0], a1)));
        assert!(
            far_rows + 10 < near_rows,
            "near {near_rows} rows, far {far_rows}"
        );
    }

    /// Every non-background pixel.
    fn pixels_all(fb: &Framebuffer) -> Vec<(u32, u32)> {
        (0..fb.height())
            .flat_map(|y| (0..fb.width()).map(move |x| (x, y)))
            .filter(|&(x, y)| fb.get(x, y) != Some(BACKGROUND))
            .collect()
    }

    #[test]
    fn geometry_behind_or_across_the_near_plane_does_not_panic() {
        // A camera framed on a small region near the origin, then a mesh, bones and markers
        // that reach behind the eye.
        let mut b = Bounds::default();
        b.add(Vec3::new(-1.0, -1.0, -1.0));
        b.add(Vec3::new(1.0, 1.0, 1.0));
        let camera = Camera::framing_with(View::Front, Projection::PERSPECTIVE, b, 64, 64, 0.08);
        let Lens::Perspective { eye_z, .. } = camera.lens else {
            panic!("{:?}", camera.lens);
        };
        let mut asset = square();
        asset.meshes[0].positions = vec![
            Vec3::new(-1.0, -1.0, 0.0),
            Vec3::new(1.0, -1.0, 0.0),
            Vec3::new(0.0, 1.0, eye_z + 10.0),
            Vec3::new(0.0, 0.0, eye_z),
            Vec3::new(0.0, 0.0, f32::NAN),
        ];
        asset.meshes[0].source_vertex = (0..5).collect();
        asset.meshes[0].triangles = vec![[0, 1, 2], [2, 3, 4], [0, 1, 3], [0, 3, 4]];
        let mut fb = Framebuffer::new(64, 64, BACKGROUND);
        let positions = [asset.meshes[0].positions.clone()];
        draw_meshes(&mut fb, &asset, &positions, &camera, &Surfaces::new(&asset));
        let drawn = pixels_all(&fb).len();
        assert!(drawn > 0, "the part in front of the near plane is drawn");
        let behind = Mat4::from_translation(Vec3::new(0.0, 0.0, eye_z + 5.0));
        draw_skeleton(&mut fb, &asset, &[behind], &camera);
        draw_markers(
            &mut fb,
            &[Vec3::new(0.0, 0.0, eye_z + 1.0), Vec3::NAN, Vec3::ZERO],
            &camera,
        );
        assert!(fb.pixels().contains(&MARKER_COLOR));
        assert!(!fb.pixels().contains(&JOINT_COLOR));
    }

    #[test]
    fn palette_fits_a_gif() {
        let p = palette();
        assert!(p.len() <= 256);
        assert_eq!(p.last(), Some(&MARKER_COLOR));
        assert_eq!(p.iter().filter(|&&c| c == MARKER_COLOR).count(), 1);
        let mut sorted = p.clone();
        sorted.sort_unstable();
        sorted.dedup();
        assert!(sorted.len() > 4 * SHADE_LEVELS / 2);
    }
}

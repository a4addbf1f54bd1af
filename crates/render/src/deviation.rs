//! A picture of where two rigs differ: the reference's meshes at one frame coloured by
//! each vertex's deviation on a colour scale (blue 0 to red at the scale's top, shaded
//! like [`crate::render_frames`]' meshes), the worst vertices ringed, the same meshes as a
//! wireframe beside it, and the colour scale with its top value in millimetres.

use rigport_model::glam::Vec3;
use rigport_model::Mesh;

use crate::camera::{Bounds, Camera, Projection, View};
use crate::raster::{Framebuffer, Rgba};
use crate::{
    light_factor, RenderError, BACKGROUND, MARGIN, MARKER_COLOR, SHADE_LEVELS, TEXT_COLOR,
};

/// The colour scale's stops, from no deviation to the scale's top.
const STOPS: [Rgba; 5] = [
    [40, 60, 210, 255],
    [0, 170, 230, 255],
    [40, 200, 80, 255],
    [240, 220, 40, 255],
    [230, 30, 30, 255],
];
/// The wireframe's lines.
const WIRE_COLOR: Rgba = [170, 176, 190, 255];

/// What to draw: meshes posed at one frame (one position per vertex, in a +Y up frame)
/// and each vertex's deviation (metres; an empty list: not compared).
#[derive(Clone, Copy, Debug)]
pub struct DeviationPicture<'a> {
    /// The meshes (their triangles).
    pub meshes: &'a [Mesh],
    /// Per mesh, its posed vertices.
    pub positions: &'a [Vec<Vec3>],
    /// Per mesh, per vertex, its deviation (metres).
    pub deviation: &'a [Vec<f32>],
    /// The deviation at the top of the scale (metres, positive).
    pub scale_max: f32,
    /// `(mesh, vertex)` of the vertices to ring.
    pub marked: &'a [(usize, usize)],
}

/// A marked vertex's pixel centre in the picture (`None`: behind the camera or unknown).
pub type MarkPixel = Option<[f32; 2]>;

/// The colour of deviation fraction `u` of the scale (clamped to 0..1).
///
/// ```
/// use rigport_render::deviation::scale_color;
/// assert_eq!(scale_color(0.0), [40, 60, 210, 255]);
/// assert_eq!(scale_color(1.0), [230, 30, 30, 255]);
/// ```
pub fn scale_color(u: f32) -> Rgba {
    let u = if u.is_finite() {
        u.clamp(0.0, 1.0)
    } else {
        1.0
    };
    let x = u * (STOPS.len() - 1) as f32;
    let k = (x.floor() as usize).min(STOPS.len() - 2);
    let t = x - k as f32;
    let (a, b) = (STOPS[k], STOPS[k + 1]);
    let mix = |i: usize| (f32::from(a[i]) + (f32::from(b[i]) - f32::from(a[i])) * t).round() as u8;
    [mix(0), mix(1), mix(2), 255]
}

/// Draws `picture` from the front: the coloured meshes (`width` x `height`), the
/// wireframe beside them, and the colour scale to the right (a quarter of `width`).
/// Returns the picture and the pixel centre of each marked vertex, in `marked` order
/// (`None` behind the camera or unknown).
///
/// # Errors
/// [`RenderError::Size`] for a zero or over-large size.
pub fn render_deviation(
    picture: &DeviationPicture<'_>,
    width: u32,
    height: u32,
) -> Result<(Framebuffer, Vec<MarkPixel>), RenderError> {
    if !(16..=8192).contains(&width) || !(16..=8192).contains(&height) {
        return Err(RenderError::Size { width, height });
    }
    let view = View::Front;
    let rotation = view.model_to_view();
    let mut bounds = Bounds::default();
    for &p in picture.positions.iter().flatten() {
        bounds.add(rotation * p);
    }
    let camera = Camera::framing_with(
        view,
        Projection::Orthographic,
        bounds,
        width,
        height,
        MARGIN,
    );
    let legend = (width / 4).max(24);
    let mut out = Framebuffer::color_only(2 * width + legend, height, BACKGROUND);
    let mut panel = Framebuffer::new(width, height, BACKGROUND);
    let light = Vec3::new(-0.4, 0.6, 0.7).normalize();
    let top = if picture.scale_max > 0.0 {
        picture.scale_max
    } else {
        1.0
    };
    for (mi, mesh) in picture.meshes.iter().enumerate() {
        let (Some(posed), Some(dev)) = (picture.positions.get(mi), picture.deviation.get(mi))
        else {
            continue;
        };
        for tri in &mesh.triangles {
            let corner = |k: usize| posed.get(tri[k] as usize).copied();
            let (Some(a), Some(b), Some(c)) = (corner(0), corner(1), corner(2)) else {
                continue;
            };
            let (Some(pa), Some(pb), Some(pc)) =
                (camera.project(a), camera.project(b), camera.project(c))
            else {
                continue;
            };
            let n = camera.to_view((b - a).cross(c - a)).normalize_or_zero();
            let level = (n.dot(light).abs() * (SHADE_LEVELS - 1) as f32).round() as usize;
            let k = light_factor(level.min(SHADE_LEVELS - 1));
            let d = |i: usize| dev.get(tri[i] as usize).copied().unwrap_or(0.0) / top;
            let (da, db, dc) = (d(0), d(1), d(2));
            panel.triangle_shaded([pa, pb, pc], |w| {
                let c = scale_color(w[0] * da + w[1] * db + w[2] * dc);
                let s = |v: u8| (f32::from(v) * k).round() as u8;
                [s(c[0]), s(c[1]), s(c[2]), 255]
            });
        }
    }
    let size = width.min(height);
    let radius = (size as f32 / 60.0).max(3.0);
    let thickness = (size / 256).max(1) + 1;
    let mut centres = Vec::with_capacity(picture.marked.len());
    for &(m, v) in picture.marked {
        let at = picture
            .positions
            .get(m)
            .and_then(|p| p.get(v))
            .and_then(|&p| camera.project(p))
            .map(|[x, y, _]| [x, y]);
        if let Some(c) = at {
            let half = thickness as f32 * 0.5;
            panel.ring(c, radius - half - 1.0, radius + half + 1.0, BACKGROUND);
            panel.ring(c, radius - half, radius + half, MARKER_COLOR);
        }
        centres.push(at);
    }
    out.blit(&panel, 0, 0);
    let mut wire = Framebuffer::color_only(width, height, BACKGROUND);
    for (mi, mesh) in picture.meshes.iter().enumerate() {
        let Some(posed) = picture.positions.get(mi) else {
            continue;
        };
        for tri in &mesh.triangles {
            for (i, j) in [(0, 1), (1, 2), (2, 0)] {
                if let (Some(&a), Some(&b)) =
                    (posed.get(tri[i] as usize), posed.get(tri[j] as usize))
                {
                    if let Some([pa, pb]) = camera.clip_segment(a, b) {
                        wire.line(pa, pb, 1, WIRE_COLOR);
                    }
                }
            }
        }
    }
    out.blit(&wire, width, 0);
    draw_scale(&mut out, 2 * width, legend, height, picture.scale_max);
    Ok((out, centres))
}

/// The colour scale in the strip from `x0`, `strip` wide: a bar from 0 (bottom) to the
/// top value (top), labelled with the top value in millimetres and 0.
fn draw_scale(fb: &mut Framebuffer, x0: u32, strip: u32, height: u32, top_m: f32) {
    let scale = (height / 160).max(1);
    let s = i64::from(scale);
    let bar_x = i64::from(x0) + i64::from(strip) / 4;
    let bar_w = (i64::from(strip) / 4).max(4);
    let (y_top, y_bottom) = (12 * s + 4, i64::from(height) - 10 * s - 4);
    let span = (y_bottom - y_top).max(1);
    for y in y_top..=y_bottom {
        let c = scale_color((y_bottom - y) as f32 / span as f32);
        for x in bar_x..bar_x + bar_w {
            fb.put(x, y, c);
        }
    }
    let mm = top_m * 1000.0;
    let label = if mm >= 0.01 {
        format!("{mm:.3}")
    } else {
        format!("{mm:.1E}")
    };
    let tx = i64::from(x0) + 2;
    fb.text(&label, tx, 2, scale, TEXT_COLOR);
    fb.text("MM", tx, 2 + 6 * s, scale, TEXT_COLOR);
    fb.text("0", tx, y_bottom + 3 * s, scale, TEXT_COLOR);
}

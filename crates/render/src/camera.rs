//! Views, projections, and the camera framed on a set of points.
//!
//! View space: the camera looks down view -Z, view +Y is up on the picture, view +X to the
//! right. The orthographic camera draws view space at a fixed scale; the perspective camera
//! is a pinhole on the view +Z side of everything it frames, with triangles and lines
//! clipped to its near plane ([`Camera::clip_triangle`], [`Camera::clip_segment`]).

use rigport_model::glam::{Mat3, Vec3};

/// Where the camera looks from (rigport's frame: +Y up, right-handed).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum View {
    /// From +Z looking towards -Z, +Y up, +X to the right.
    #[default]
    Front,
    /// From +X looking towards -X, +Y up, -Z to the right.
    Side,
    /// From +Y looking down, -Z up on the picture, +X to the right.
    Top,
    /// From the front-right and slightly above: direction `(1, 0.6, 1)`, +Y up.
    ThreeQuarter,
}

impl View {
    /// The rotation from model space to view space, where the camera looks down view -Z,
    /// view +Y is up on the picture and view +X to the right.
    pub fn model_to_view(self) -> Mat3 {
        let (towards_camera, up) = match self {
            View::Front => (Vec3::Z, Vec3::Y),
            View::Side => (Vec3::X, Vec3::Y),
            View::Top => (Vec3::Y, Vec3::NEG_Z),
            View::ThreeQuarter => (Vec3::new(1.0, 0.6, 1.0).normalize(), Vec3::Y),
        };
        let z = towards_camera;
        let x = up.cross(z).normalize();
        let y = z.cross(x);
        // Rows x, y, z: the transpose of the camera's basis.
        Mat3::from_cols(x, y, z).transpose()
    }
}

/// Axis-aligned bounds in view space; empty until a finite point is added.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds {
    /// Smallest coordinates.
    pub min: Vec3,
    /// Largest coordinates.
    pub max: Vec3,
}

impl Default for Bounds {
    fn default() -> Self {
        Self {
            min: Vec3::splat(f32::INFINITY),
            max: Vec3::splat(f32::NEG_INFINITY),
        }
    }
}

impl Bounds {
    /// Grows the bounds to hold `p`; non-finite points are ignored.
    pub fn add(&mut self, p: Vec3) {
        if p.is_finite() {
            self.min = self.min.min(p);
            self.max = self.max.max(p);
        }
    }

    /// The union of two bounds (exact, so the order of unions does not matter).
    pub fn union(self, other: Bounds) -> Bounds {
        Bounds {
            min: self.min.min(other.min),
            max: self.max.max(other.max),
        }
    }

    /// Whether no point was added.
    pub fn is_empty(&self) -> bool {
        self.min.x > self.max.x
    }
}

/// How the camera projects view space onto the picture.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Projection {
    /// Parallel projection: sizes do not change with depth.
    #[default]
    Orthographic,
    /// A pinhole camera with a vertical field of view of `fov_y_deg` degrees (over the
    /// picture's height), placed so that the framed bounds fit (see [`Camera::framing`]).
    Perspective {
        /// Vertical field of view in degrees, in (0, 180); other values use
        /// [`Projection::DEFAULT_FOV_Y_DEG`].
        fov_y_deg: f32,
    },
}

impl Projection {
    /// The field of view `rigport render --camera perspective` uses: about a 40 mm lens on
    /// a full-frame camera's 24 mm height, little distortion.
    pub const DEFAULT_FOV_Y_DEG: f32 = 35.0;

    /// A perspective projection with [`Projection::DEFAULT_FOV_Y_DEG`].
    pub const PERSPECTIVE: Projection = Projection::Perspective {
        fov_y_deg: Self::DEFAULT_FOV_Y_DEG,
    };
}

/// How a [`Camera`] maps view space to pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Lens {
    /// `scale` pixels per unit at every depth; depth is view z.
    Orthographic,
    /// A pinhole at view-space `(center.x, center.y, eye_z)` looking down view -Z: a point
    /// at distance `d = eye_z - z` in front of it lands `focal_px / d` pixels per unit from
    /// the picture's centre; depth is `1 / d` (affine in screen space, so the rasterizer's
    /// linear interpolation of it is exact). Points with `d < near` are not drawn.
    Perspective {
        /// View-space z of the eye.
        eye_z: f32,
        /// Focal length in pixels: `height / 2 / tan(fov_y / 2)`.
        focal_px: f32,
        /// Distance of the near plane from the eye, model units, > 0.
        near: f32,
    },
}

/// Up to four screen-space corners (`[x, y, depth]`): a triangle clipped to the near plane,
/// a convex polygon of `len` corners (0, 3 or 4). Draw it as the fan `(0, 1, 2)`,
/// `(0, 2, 3)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClippedPolygon {
    /// The corners; entries from `len` on are unused.
    pub corners: [[f32; 3]; 4],
    /// How many corners are used.
    pub len: usize,
}

impl ClippedPolygon {
    /// The polygon as 0, 1 or 2 triangles (a fan from the first corner).
    pub fn triangles(&self) -> impl Iterator<Item = [[f32; 3]; 3]> + '_ {
        let c = &self.corners;
        (2..self.len.min(4)).map(move |k| [c[0], c[k - 1], c[k]])
    }
}

/// A camera: model space -> screen pixels of a `width` x `height` picture.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Model to view rotation.
    pub rotation: Mat3,
    /// The view-space point drawn at the picture's centre (for a perspective lens, the eye
    /// sits on the view +Z axis through it).
    pub center: Vec3,
    /// Pixels per model-space unit; for a perspective lens, at the depth of the framed
    /// bounds' nearest face.
    pub scale: f32,
    /// Orthographic or perspective.
    pub lens: Lens,
    /// Picture width in pixels.
    pub width: u32,
    /// Picture height in pixels.
    pub height: u32,
}

/// Fraction of the eye's distance to the framed bounds at which the near plane sits: any
/// value in (0, 1) keeps everything framed in front of it.
const NEAR_FRACTION: f32 = 0.01;

impl Camera {
    /// An orthographic camera looking from `view` that fits `bounds` (view space, see
    /// [`View::model_to_view`]) into the picture with `margin` (a fraction of the picture
    /// size, e.g. 0.08) free on every side. Empty or flat bounds get a unit scale.
    pub fn framing(view: View, bounds: Bounds, width: u32, height: u32, margin: f32) -> Self {
        Self::framing_with(
            view,
            Projection::Orthographic,
            bounds,
            width,
            height,
            margin,
        )
    }

    /// A camera looking from `view` with `projection` that fits `bounds` into the picture
    /// with `margin` free on every side. The orthographic camera is [`Camera::framing`]'s.
    /// The perspective camera's eye is on the view +Z axis through the bounds' centre, at
    /// the distance where the bounds' nearest face is drawn at the orthographic scale: every
    /// point of the box is at least that far, so it lands no farther from the centre than
    /// under the orthographic camera, and the whole box fits.
    pub fn framing_with(
        view: View,
        projection: Projection,
        bounds: Bounds,
        width: u32,
        height: u32,
        margin: f32,
    ) -> Self {
        let rotation = view.model_to_view();
        let mut camera = if bounds.is_empty() {
            Self {
                rotation,
                center: Vec3::ZERO,
                scale: 1.0,
                lens: Lens::Orthographic,
                width,
                height,
            }
        } else {
            let extent = bounds.max - bounds.min;
            let free = (1.0 - 2.0 * margin).clamp(0.05, 1.0);
            let sx = width as f32 * free / extent.x;
            let sy = height as f32 * free / extent.y;
            let scale = match (sx.is_finite() && sx > 0.0, sy.is_finite() && sy > 0.0) {
                (true, true) => sx.min(sy),
                (true, false) => sx,
                (false, true) => sy,
                (false, false) => 1.0,
            };
            Self {
                rotation,
                center: (bounds.min + bounds.max) * 0.5,
                scale,
                lens: Lens::Orthographic,
                width,
                height,
            }
        };
        if let Projection::Perspective { fov_y_deg } = projection {
            let fov = if fov_y_deg.is_finite() && fov_y_deg > 0.0 && fov_y_deg < 180.0 {
                fov_y_deg
            } else {
                Projection::DEFAULT_FOV_Y_DEG
            };
            let focal_px = height as f32 * 0.5 / (fov.to_radians() * 0.5).tan();
            // focal_px / distance = scale at the nearest face.
            let distance = focal_px / camera.scale;
            let front = if bounds.is_empty() {
                camera.center.z
            } else {
                bounds.max.z
            };
            camera.lens = Lens::Perspective {
                eye_z: front + distance,
                focal_px,
                near: distance * NEAR_FRACTION,
            };
        }
        camera
    }

    /// The view-space position of model-space `p`.
    pub fn to_view(&self, p: Vec3) -> Vec3 {
        self.rotation * p
    }

    /// Screen position `[x, y, depth]` of model-space `p`: pixels from the top-left corner,
    /// depth larger nearer the camera (model units for the orthographic lens, `1 / distance`
    /// for the perspective one). `None` when `p` is not in front of the near plane (or not
    /// finite, for a perspective lens).
    pub fn project(&self, p: Vec3) -> Option<[f32; 3]> {
        self.project_view(self.to_view(p))
    }

    /// As [`Camera::project`], for a view-space point.
    pub fn project_view(&self, v: Vec3) -> Option<[f32; 3]> {
        match self.lens {
            Lens::Orthographic => Some(self.orthographic(v)),
            Lens::Perspective { eye_z, near, .. } => {
                let d = eye_z - v.z;
                (d >= near).then(|| self.perspective(v, d))
            }
        }
    }

    /// The orthographic projection of view-space `v`.
    fn orthographic(&self, v: Vec3) -> [f32; 3] {
        let v = v - self.center;
        [
            self.width as f32 * 0.5 + v.x * self.scale,
            self.height as f32 * 0.5 - v.y * self.scale,
            v.z,
        ]
    }

    /// The perspective projection of view-space `v` at distance `d` (> 0) from the eye.
    fn perspective(&self, v: Vec3, d: f32) -> [f32; 3] {
        let focal_px = match self.lens {
            Lens::Perspective { focal_px, .. } => focal_px,
            Lens::Orthographic => self.scale,
        };
        let k = focal_px / d;
        [
            self.width as f32 * 0.5 + (v.x - self.center.x) * k,
            self.height as f32 * 0.5 - (v.y - self.center.y) * k,
            1.0 / d,
        ]
    }

    /// The near plane as (eye z, near distance) for a perspective lens.
    fn near_plane(&self) -> Option<(f32, f32)> {
        match self.lens {
            Lens::Orthographic => None,
            Lens::Perspective { eye_z, near, .. } => Some((eye_z, near)),
        }
    }

    /// The model-space triangle `tri` on screen, clipped to the near plane (Sutherland and
    /// Hodgman against one plane): empty when it lies wholly behind it or a corner is not
    /// finite, a triangle or a quadrilateral otherwise. The orthographic lens never clips.
    pub fn clip_triangle(&self, tri: [Vec3; 3]) -> ClippedPolygon {
        let mut out = ClippedPolygon {
            corners: [[0.0; 3]; 4],
            len: 0,
        };
        let view = tri.map(|p| self.to_view(p));
        let Some((eye_z, near)) = self.near_plane() else {
            out.corners = [
                self.orthographic(view[0]),
                self.orthographic(view[1]),
                self.orthographic(view[2]),
                [0.0; 3],
            ];
            out.len = 3;
            return out;
        };
        if !view.iter().all(|v| v.is_finite()) {
            return out;
        }
        // Distance from the eye along the view direction; >= near is kept.
        let d = view.map(|v| eye_z - v.z);
        for i in 0..3 {
            let j = (i + 1) % 3;
            let (a_in, b_in) = (d[i] >= near, d[j] >= near);
            if a_in {
                out.corners[out.len] = self.perspective(view[i], d[i]);
                out.len += 1;
            }
            if a_in != b_in {
                // The edge crosses the plane: its point at distance `near` from the eye.
                let t = (d[i] - near) / (d[i] - d[j]);
                out.corners[out.len] = self.perspective(view[i] + (view[j] - view[i]) * t, near);
                out.len += 1;
            }
        }
        out
    }

    /// The model-space segment `a -> b` on screen (`[x, y]` ends), clipped to the near
    /// plane; `None` when it lies wholly behind it or is not finite.
    pub fn clip_segment(&self, a: Vec3, b: Vec3) -> Option<[[f32; 2]; 2]> {
        let (va, vb) = (self.to_view(a), self.to_view(b));
        let xy = |p: [f32; 3]| [p[0], p[1]];
        let Some((eye_z, near)) = self.near_plane() else {
            return Some([xy(self.orthographic(va)), xy(self.orthographic(vb))]);
        };
        if !(va.is_finite() && vb.is_finite()) {
            return None;
        }
        let (da, db) = (eye_z - va.z, eye_z - vb.z);
        let cut = || {
            let t = (da - near) / (da - db);
            xy(self.perspective(va + (vb - va) * t, near))
        };
        match (da >= near, db >= near) {
            (true, true) => Some([xy(self.perspective(va, da)), xy(self.perspective(vb, db))]),
            (true, false) => Some([xy(self.perspective(va, da)), cut()]),
            (false, true) => Some([cut(), xy(self.perspective(vb, db))]),
            (false, false) => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn views_are_rotations_that_face_the_camera() {
        for (view, towards) in [
            (View::Front, Vec3::Z),
            (View::Side, Vec3::X),
            (View::Top, Vec3::Y),
        ] {
            let r = view.model_to_view();
            assert!((r.determinant() - 1.0).abs() < 1e-6);
            assert!((r * towards - Vec3::Z).length() < 1e-6, "{view:?}");
        }
        // From the side, the character's front (+Z) is to the left of the picture.
        assert!((View::Side.model_to_view() * Vec3::Z).x < -0.99);
    }

    #[test]
    fn framing_centres_and_fits() {
        let mut b = Bounds::default();
        b.add(Vec3::new(-1.0, 0.0, 0.0));
        b.add(Vec3::new(1.0, 4.0, 0.0));
        let cam = Camera::framing(View::Front, b, 100, 100, 0.1);
        assert_eq!(cam.scale, 20.0);
        assert_eq!(
            cam.project(Vec3::new(0.0, 2.0, 0.0)),
            Some([50.0, 50.0, 0.0])
        );
        assert_eq!(
            cam.project(Vec3::new(1.0, 4.0, 0.0)),
            Some([70.0, 10.0, 0.0])
        );
    }

    /// The bounds of the box `[-1, 1] x [0, 4] x [-2, 1]` (view = model for the front view).
    fn deep_box() -> (Bounds, Vec<Vec3>) {
        let mut b = Bounds::default();
        let mut corners = Vec::new();
        for x in [-1.0, 1.0] {
            for y in [0.0, 4.0] {
                for z in [-2.0, 1.0] {
                    let p = Vec3::new(x, y, z);
                    b.add(p);
                    corners.push(p);
                }
            }
        }
        (b, corners)
    }

    #[test]
    fn perspective_fits_the_box_and_draws_its_front_at_the_orthographic_scale() {
        let (b, corners) = deep_box();
        let ortho = Camera::framing(View::Front, b, 100, 100, 0.1);
        let cam = Camera::framing_with(View::Front, Projection::PERSPECTIVE, b, 100, 100, 0.1);
        let Lens::Perspective {
            eye_z,
            focal_px,
            near,
        } = cam.lens
        else {
            panic!("{:?}", cam.lens);
        };
        // 35 deg over 100 px: focal 50 / tan(17.5 deg) = 158.58 px; the front face (z = 1)
        // at the orthographic 20 px per unit.
        assert!((focal_px - 158.58).abs() < 0.01, "{focal_px}");
        assert!((eye_z - (1.0 + focal_px / 20.0)).abs() < 1e-4, "{eye_z}");
        assert!(near > 0.0 && near < eye_z - 1.0);
        for p in corners {
            let [x, y, depth] = cam.project(p).unwrap();
            // Inside the free area (80 x 80 px around the centre), at most as far out as
            // the orthographic camera draws it.
            assert!((10.0 - 1e-3..=90.0 + 1e-3).contains(&x), "{p}: x {x}");
            assert!((10.0 - 1e-3..=90.0 + 1e-3).contains(&y), "{p}: y {y}");
            let [ox, oy, _] = ortho.project(p).unwrap();
            assert!((x - 50.0).abs() <= (ox - 50.0).abs() + 1e-3);
            assert!((y - 50.0).abs() <= (oy - 50.0).abs() + 1e-3);
            assert!((depth - 1.0 / (eye_z - p.z)).abs() < 1e-6);
        }
        // The front top corner lands exactly where the orthographic camera puts it; the back
        // one nearer the centre; the nearer point has the larger depth.
        let front = cam.project(Vec3::new(1.0, 4.0, 1.0)).unwrap();
        let back = cam.project(Vec3::new(1.0, 4.0, -2.0)).unwrap();
        assert!((front[0] - 70.0).abs() < 1e-3 && (front[1] - 10.0).abs() < 1e-3);
        assert!(back[0] < front[0] && back[1] > front[1] && back[2] < front[2]);
        // Behind the eye: not projected.
        assert_eq!(cam.project(Vec3::new(0.0, 2.0, eye_z + 1.0)), None);
        assert_eq!(cam.project(Vec3::new(0.0, 2.0, eye_z - near * 0.5)), None);
        assert_eq!(cam.project(Vec3::NAN), None);
    }

    #[test]
    fn near_plane_clips_triangles_and_segments() {
        let (b, _) = deep_box();
        let cam = Camera::framing_with(View::Front, Projection::PERSPECTIVE, b, 100, 100, 0.1);
        let Lens::Perspective { eye_z, near, .. } = cam.lens else {
            panic!("{:?}", cam.lens);
        };
        let plane = eye_z - near;
        // Wholly in front: unchanged.
        let front = [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ];
        let poly = cam.clip_triangle(front);
        assert_eq!(poly.len, 3);
        assert_eq!(poly.corners[1], cam.project(front[1]).unwrap());
        assert_eq!(poly.triangles().count(), 1);
        // Wholly behind the eye: nothing.
        let behind = front.map(|p| p + Vec3::new(0.0, 0.0, eye_z + 5.0));
        assert_eq!(cam.clip_triangle(behind).len, 0);
        // One corner behind the eye: a quadrilateral, its new corners on the near plane
        // (depth 1 / near), every coordinate finite.
        let crossing = [
            Vec3::new(-1.0, 1.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(0.0, 2.0, eye_z + 3.0),
        ];
        let poly = cam.clip_triangle(crossing);
        assert_eq!(poly.len, 4);
        assert_eq!(poly.triangles().count(), 2);
        let on_plane = poly.corners[..poly.len]
            .iter()
            .filter(|c| (c[2] - 1.0 / near).abs() < 1e-3 / near)
            .count();
        assert_eq!(on_plane, 2);
        assert!(poly.corners.iter().flatten().all(|v| v.is_finite()));
        // Two corners behind: a smaller triangle.
        let two = [
            Vec3::new(-1.0, 1.0, 0.0),
            Vec3::new(1.0, 1.0, plane + 1.0),
            Vec3::new(0.0, 2.0, eye_z + 3.0),
        ];
        assert_eq!(cam.clip_triangle(two).len, 3);
        // Not finite: nothing.
        assert_eq!(cam.clip_triangle([Vec3::NAN, front[1], front[2]]).len, 0);
        // Segments.
        assert!(cam.clip_segment(front[0], front[1]).is_some());
        assert_eq!(cam.clip_segment(behind[0], behind[1]), None);
        let [start, end] = cam.clip_segment(crossing[0], crossing[2]).unwrap();
        let p = cam.project(crossing[0]).unwrap();
        assert_eq!(start, [p[0], p[1]]);
        assert!(end[0].is_finite() && end[1].is_finite());
        // The orthographic camera never clips.
        let ortho = Camera::framing(View::Front, b, 100, 100, 0.1);
        assert_eq!(ortho.clip_triangle(behind).len, 3);
    }
}

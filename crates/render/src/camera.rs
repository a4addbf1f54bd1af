//! Views and the orthographic camera framed on a set of points.

use rigport_model::glam::{Mat3, Vec3};

/// Where the orthographic camera looks from (rigport's frame: +Y up, right-handed).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
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

/// An orthographic camera: model space -> screen pixels of a `width` x `height` picture.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Model to view rotation.
    pub rotation: Mat3,
    /// The view-space point drawn at the picture's centre.
    pub center: Vec3,
    /// Pixels per model-space unit.
    pub scale: f32,
    /// Picture width in pixels.
    pub width: u32,
    /// Picture height in pixels.
    pub height: u32,
}

impl Camera {
    /// A camera looking from `view` that fits `bounds` (view space, see
    /// [`View::model_to_view`]) into the picture with `margin` (a fraction of the picture
    /// size, e.g. 0.08) free on every side. Empty or flat bounds get a unit scale.
    pub fn framing(view: View, bounds: Bounds, width: u32, height: u32, margin: f32) -> Self {
        let rotation = view.model_to_view();
        if bounds.is_empty() {
            return Self {
                rotation,
                center: Vec3::ZERO,
                scale: 1.0,
                width,
                height,
            };
        }
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
            width,
            height,
        }
    }

    /// The view-space position of model-space `p`.
    pub fn to_view(&self, p: Vec3) -> Vec3 {
        self.rotation * p
    }

    /// Screen position `[x, y, depth]` of model-space `p`: pixels from the top-left corner,
    /// depth in model units, larger nearer the camera.
    pub fn project(&self, p: Vec3) -> [f32; 3] {
        let v = self.to_view(p) - self.center;
        [
            self.width as f32 * 0.5 + v.x * self.scale,
            self.height as f32 * 0.5 - v.y * self.scale,
            v.z,
        ]
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
        assert_eq!(cam.project(Vec3::new(0.0, 2.0, 0.0)), [50.0, 50.0, 0.0]);
        assert_eq!(cam.project(Vec3::new(1.0, 4.0, 0.0)), [70.0, 10.0, 0.0]);
    }
}

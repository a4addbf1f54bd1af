//! Where an asset sits in its source's scene: up axis, and the transform from model space
//! (the skeleton's space) to the scene. Units are [`crate::Asset::meters_per_unit`].

use glam::{DMat4, DVec4};

/// The axis a scene calls up. Both are right-handed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum UpAxis {
    /// +Y up (glTF, USD's default, Maya, most formats).
    #[default]
    Y,
    /// +Z up (Blender, 3ds Max, many USD files exported from Blender).
    Z,
}

impl UpAxis {
    /// The USD token (`"Y"` / `"Z"`).
    pub fn as_str(self) -> &'static str {
        match self {
            UpAxis::Y => "Y",
            UpAxis::Z => "Z",
        }
    }

    /// Parses `"Y"`/`"y"` or `"Z"`/`"z"`.
    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "Y" | "y" => Some(UpAxis::Y),
            "Z" | "z" => Some(UpAxis::Z),
            _ => None,
        }
    }

    /// The rotation taking coordinates of a scene with up axis `self` to one with up axis
    /// `to`, keeping the other horizontal axis (+X) and handedness: Z-up to Y-up maps
    /// `(x, y, z)` to `(x, z, -y)` (a -90° turn about +X, what Blender's glTF exporter
    /// does), Y-up to Z-up the inverse.
    pub fn conversion_to(self, to: UpAxis) -> DMat4 {
        match (self, to) {
            (UpAxis::Y, UpAxis::Y) | (UpAxis::Z, UpAxis::Z) => DMat4::IDENTITY,
            (UpAxis::Z, UpAxis::Y) => DMat4::from_cols(
                DVec4::new(1.0, 0.0, 0.0, 0.0),
                DVec4::new(0.0, 0.0, -1.0, 0.0),
                DVec4::new(0.0, 1.0, 0.0, 0.0),
                DVec4::W,
            ),
            (UpAxis::Y, UpAxis::Z) => DMat4::from_cols(
                DVec4::new(1.0, 0.0, 0.0, 0.0),
                DVec4::new(0.0, 0.0, 1.0, 0.0),
                DVec4::new(0.0, -1.0, 0.0, 0.0),
                DVec4::W,
            ),
        }
    }
}

/// The scene frame of an [`crate::Asset`]: how the source placed the model in its world.
///
/// The model keeps the source's numbers (its unit, its up axis); this says what they mean,
/// and exporters convert from it (glTF: +Y up, metres; USD: the source's frame unless
/// asked for another). `model_to_scene` is the static transform of the skeleton's space in
/// the scene (in USD, every `xformOp` above and on the Skeleton prim): every joint, every
/// skinned mesh's bind-space points and every unskinned mesh are in model space, and the
/// scene sees them through this matrix. Animated transforms above the skeleton are not
/// held here: importers turn them into root motion (tracks on the root joint).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SceneFrame {
    /// The source scene's up axis.
    pub up_axis: UpAxis,
    /// Model space -> scene space (column vectors), in the scene's unit and axes.
    pub model_to_scene: DMat4,
}

impl Default for SceneFrame {
    fn default() -> Self {
        Self {
            up_axis: UpAxis::Y,
            model_to_scene: DMat4::IDENTITY,
        }
    }
}

impl SceneFrame {
    /// Model space -> a scene with up axis `up` whose unit is `target_mpu` metres, given the
    /// asset's `meters_per_unit` (`None`: the source states no unit, so none is converted).
    /// `target_mpu = None` keeps the source's unit.
    pub fn model_to(
        &self,
        meters_per_unit: Option<f64>,
        up: UpAxis,
        target_mpu: Option<f64>,
    ) -> DMat4 {
        let scale = match (meters_per_unit, target_mpu) {
            (Some(from), Some(to))
                if from.is_finite() && from > 0.0 && to.is_finite() && to > 0.0 =>
            {
                from / to
            }
            _ => 1.0,
        };
        DMat4::from_scale(glam::DVec3::splat(scale))
            * self.up_axis.conversion_to(up)
            * self.model_to_scene
    }

    /// The scene's up direction in model space (unit length): the inverse of
    /// `model_to_scene` applied to the up axis; +Y when that inverse is degenerate.
    pub fn up_in_model(&self) -> glam::Vec3 {
        let up = match self.up_axis {
            UpAxis::Y => glam::DVec3::Y,
            UpAxis::Z => glam::DVec3::Z,
        };
        let v = self.model_to_scene.inverse().transform_vector3(up);
        let v = v.as_vec3().normalize_or_zero();
        if v == glam::Vec3::ZERO || !v.is_finite() {
            glam::Vec3::Y
        } else {
            v
        }
    }

    /// Model space -> glTF's frame (+Y up, metres): [`SceneFrame::model_to`] with Y and 1 m.
    /// Sources that state no unit keep their numbers.
    pub fn model_to_gltf(&self, meters_per_unit: Option<f64>) -> DMat4 {
        self.model_to(meters_per_unit, UpAxis::Y, Some(1.0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    #[test]
    fn z_up_to_y_up_keeps_handedness_and_maps_up_to_up() {
        let m = UpAxis::Z.conversion_to(UpAxis::Y);
        assert_eq!(m.transform_vector3(DVec3::Z), DVec3::Y);
        assert_eq!(m.transform_vector3(DVec3::X), DVec3::X);
        assert!((m.determinant() - 1.0).abs() < 1e-12);
        let back = UpAxis::Y.conversion_to(UpAxis::Z) * m;
        assert!(back.abs_diff_eq(DMat4::IDENTITY, 1e-12));
    }

    #[test]
    fn up_in_model_undoes_the_placement() {
        let z_up = SceneFrame {
            up_axis: UpAxis::Z,
            model_to_scene: UpAxis::Y.conversion_to(UpAxis::Z),
        };
        assert!(z_up.up_in_model().abs_diff_eq(glam::Vec3::Y, 1e-6));
        let plain_z = SceneFrame {
            up_axis: UpAxis::Z,
            ..SceneFrame::default()
        };
        assert_eq!(plain_z.up_in_model(), glam::Vec3::Z);
        assert_eq!(SceneFrame::default().up_in_model(), glam::Vec3::Y);
    }

    #[test]
    fn gltf_frame_scales_stated_units_only() {
        let f = SceneFrame::default();
        let p = DVec3::new(0.0, 28.0, 0.0);
        let asf = f.model_to_gltf(Some(0.0254 / 0.45)).transform_point3(p);
        assert!((asf.y - 28.0 * 0.0254 / 0.45).abs() < 1e-12);
        assert_eq!(f.model_to_gltf(None).transform_point3(p), p);
    }
}

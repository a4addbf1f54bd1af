//! The conventions every value in a rigport [`crate::Asset`] follows.
//!
//! | what | convention |
//! |---|---|
//! | lengths | the source file's own unit, kept unless the user asks for a conversion; [`crate::Asset::meters_per_unit`] says what it is when known |
//! | axes | right-handed; the source's up axis is kept and recorded in [`crate::Asset::frame`] ([`crate::UpAxis`]); exporters convert (glTF is +Y up in metres) |
//! | placement | model space is the skeleton's space; [`crate::SceneFrame::model_to_scene`] places it in the source's scene (USD `xformOp`s above the skeleton); animated placement becomes root-joint tracks |
//! | matrices | column vectors (`p' = M * p`), column-major storage (glam's) |
//! | quaternions | `[x, y, z, w]`, unit length, Hamilton product |
//! | transform order | scale, then rotate, then translate: `M = T * R * S` |
//! | Euler angles | an order string lists the axes in the order they are **applied**: `"xyz"` = `Rz * Ry * Rx` |
//! | time | seconds, starting at 0 unless the source says otherwise |
//! | joints | parents before children; a joint's `rest_local` is relative to its parent |
//!
//! Spaces are named in field names: `local_` (relative to the parent joint), `model_`
//! (relative to the asset root), `bind_` / `inv_bind_` (model space at bind time).
//! The model keeps the source's units and up axis; exporters convert to what their format
//! defines. Euler-order conversions live only in importers.

use glam::Vec3;

/// The default up axis of a rigport asset (when [`crate::Asset::frame`] says +Y, the usual
/// case); a Z-up source keeps its axes and says so in its [`crate::SceneFrame`].
pub const UP: Vec3 = Vec3::Y;

/// Weights smaller than this are treated as zero when influences are compacted.
///
/// Pinocchio writes weights with 4 decimals, so anything below 1e-6 is noise from
/// arithmetic, not authored data.
pub const WEIGHT_EPSILON: f32 = 1e-6;

use glam::{EulerRot, Quat};

/// An Euler rotation order, written as the axes in the order they are **applied** to a
/// point: `Xyz` (`"xyz"`) is `R = Rz · Ry · Rx` for column vectors.
///
/// This is the Maya / CSCI 520 / Acclaim reading. BVH channel lists read the other way round
/// (the first listed is the outermost), so a BVH `Zrotation Xrotation Yrotation` is `Yxz`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum EulerOrder {
    /// `Rz · Ry · Rx`.
    Xyz,
    /// `Rx · Rz · Ry`.
    Yzx,
    /// `Ry · Rx · Rz`.
    Zxy,
    /// `Ry · Rz · Rx`.
    Xzy,
    /// `Rz · Rx · Ry`.
    Yxz,
    /// `Rx · Ry · Rz`.
    Zyx,
}

impl EulerOrder {
    /// All six orders.
    pub const ALL: [EulerOrder; 6] = [
        EulerOrder::Xyz,
        EulerOrder::Yzx,
        EulerOrder::Zxy,
        EulerOrder::Xzy,
        EulerOrder::Yxz,
        EulerOrder::Zyx,
    ];

    /// Parses `"xyz"`, `"ZXY"`, ... (case-insensitive).
    pub fn parse(s: &str) -> Option<Self> {
        Some(match s.to_ascii_lowercase().as_str() {
            "xyz" => EulerOrder::Xyz,
            "yzx" => EulerOrder::Yzx,
            "zxy" => EulerOrder::Zxy,
            "xzy" => EulerOrder::Xzy,
            "yxz" => EulerOrder::Yxz,
            "zyx" => EulerOrder::Zyx,
            _ => return None,
        })
    }

    /// The lower-case name (`"xyz"`).
    pub fn as_str(self) -> &'static str {
        match self {
            EulerOrder::Xyz => "xyz",
            EulerOrder::Yzx => "yzx",
            EulerOrder::Zxy => "zxy",
            EulerOrder::Xzy => "xzy",
            EulerOrder::Yxz => "yxz",
            EulerOrder::Zyx => "zyx",
        }
    }

    /// The rotation for angles in radians about x, y and z (`angles_rad = [ax, ay, az]`,
    /// whatever the order).
    pub fn to_quat(self, angles_rad: [f32; 3]) -> Quat {
        let [x, y, z] = angles_rad;
        // glam's EulerRot names the outermost rotation first: `ZYX` builds Rz·Ry·Rx, and
        // from_euler takes the angles in that same outer-to-inner sequence.
        let (rot, a, b, c) = match self {
            EulerOrder::Xyz => (EulerRot::ZYX, z, y, x),
            EulerOrder::Yzx => (EulerRot::XZY, x, z, y),
            EulerOrder::Zxy => (EulerRot::YXZ, y, x, z),
            EulerOrder::Xzy => (EulerRot::YZX, y, z, x),
            EulerOrder::Yxz => (EulerRot::ZXY, z, x, y),
            EulerOrder::Zyx => (EulerRot::XYZ, x, y, z),
        };
        Quat::from_euler(rot, a, b, c)
    }

    /// As [`EulerOrder::to_quat`] with angles in degrees.
    pub fn to_quat_deg(self, angles_deg: [f32; 3]) -> Quat {
        self.to_quat(angles_deg.map(f32::to_radians))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Mat3;

    #[test]
    fn euler_orders_apply_first_letter_first() {
        let angles = [0.3_f32, -0.7, 1.1];
        let rx = Mat3::from_rotation_x(angles[0]);
        let ry = Mat3::from_rotation_y(angles[1]);
        let rz = Mat3::from_rotation_z(angles[2]);
        let expect = |o| match o {
            EulerOrder::Xyz => rz * ry * rx,
            EulerOrder::Yzx => rx * rz * ry,
            EulerOrder::Zxy => ry * rx * rz,
            EulerOrder::Xzy => ry * rz * rx,
            EulerOrder::Yxz => rz * rx * ry,
            EulerOrder::Zyx => rx * ry * rz,
        };
        for o in EulerOrder::ALL {
            let got = Mat3::from_quat(o.to_quat(angles));
            assert!(
                got.abs_diff_eq(expect(o), 1e-6),
                "{o:?}: {got} vs {}",
                expect(o)
            );
            assert_eq!(EulerOrder::parse(&o.as_str().to_uppercase()), Some(o));
        }
    }
}

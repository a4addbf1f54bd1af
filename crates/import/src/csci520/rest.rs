//! `jointRestTransforms.txt` and the assignment's rest transform `T · R_xyz(orient) ·
//! R_order(angles)`.

use std::path::Path;

use glam::{DQuat, DVec3, Vec3};
use rigport_model::conventions::EulerOrder;
use rigport_model::Transform;

use crate::{ImportError, Location, Problem};

use super::types::RestTransforms;

/// The three number sections of `jointRestTransforms.txt`, for messages.
const SECTIONS: [&str; 3] = ["translation", "rest angle", "joint orient"];

/// Parses `jointRestTransforms.txt` for `joint_count` joints.
///
/// The file is read as a stream, as the course's loader does: `9 · joint_count` numbers
/// separated by any white space (translations, rest angles, joint orients, `[x, y, z]` per
/// joint), then, if anything but white space follows, `joint_count` rotate orders, each the
/// next three characters after white space (so `xyzzxy` is two orders), case-insensitive.
///
/// # Errors
/// At the line of the offending token: a number that does not parse or is not finite, a
/// translation too large for `f32`, a rotate order other than `xyz yzx zxy xzy yxz zyx`,
/// anything after the last rotate order. Fewer numbers than needed, or fewer rotate orders
/// than joints, is [`Problem::Truncated`] at the last line holding data; an empty file is
/// [`Problem::Empty`].
pub fn parse_rest_transforms(
    text: &str,
    path: &Path,
    joint_count: usize,
) -> Result<RestTransforms, ImportError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut cursor = Cursor::new(text);
    let per_section = joint_count.saturating_mul(3);
    let total = joint_count.saturating_mul(9);
    let mut values: Vec<f64> = Vec::with_capacity(total.min(1 << 20));
    let mut last_line = 0;
    while values.len() < total {
        let Some((token, line)) = cursor.token() else {
            if last_line == 0 {
                return Err(ImportError::new(Location::file(path), Problem::Empty));
            }
            return Err(ImportError::new(
                Location::line(path, last_line),
                Problem::Truncated(format!(
                    "{} numbers for {joint_count} joints, expected {total}: {per_section} translations, {per_section} rest angles and {per_section} joint orients",
                    values.len()
                )),
            ));
        };
        last_line = line;
        let k = values.len();
        let section = SECTIONS
            .get(k / per_section.max(1))
            .copied()
            .unwrap_or("value");
        let joint = (k % per_section.max(1)) / 3;
        let at = || Location::line(path, line);
        let value: f64 = token.parse().map_err(|_| {
            ImportError::syntax(
                at(),
                format!("a number ({section} of joint {joint})"),
                token,
            )
        })?;
        if !value.is_finite() {
            return Err(ImportError::invalid(
                at(),
                format!("{section} {token} of joint {joint} is not finite"),
            ));
        }
        if k < per_section && !(value as f32).is_finite() {
            return Err(ImportError::invalid(
                at(),
                format!("translation {token} of joint {joint} is too large for f32"),
            ));
        }
        values.push(value);
    }
    let triples = |section: usize| -> Vec<DVec3> {
        values
            .get(section * per_section..(section + 1) * per_section)
            .unwrap_or_default()
            .chunks_exact(3)
            .map(DVec3::from_slice)
            .collect()
    };
    let mut rest = RestTransforms {
        translations: triples(0),
        rest_angles_deg: triples(1),
        joint_orients_deg: triples(2),
        rotate_orders: vec![EulerOrder::Xyz; joint_count],
        rotate_orders_given: false,
    };
    cursor.skip_white_space();
    if cursor.at_end() {
        return Ok(rest);
    }
    rest.rotate_orders_given = true;
    for (joint, slot) in rest.rotate_orders.iter_mut().enumerate() {
        let Some((token, line)) = cursor.three_chars() else {
            return Err(ImportError::new(
                Location::line(path, last_line),
                Problem::Truncated(format!(
                    "rotate orders for {joint} of {joint_count} joints: give one per joint or none"
                )),
            ));
        };
        last_line = line;
        *slot = EulerOrder::parse(token).ok_or_else(|| {
            ImportError::syntax(
                Location::line(path, line),
                format!("a rotate order (xyz, yzx, zxy, xzy, yxz or zyx) for joint {joint}"),
                token,
            )
        })?;
    }
    if let Some((token, line)) = cursor.token() {
        return Err(ImportError::syntax(
            Location::line(path, line),
            format!("the end of the file after {joint_count} rotate orders"),
            token,
        ));
    }
    Ok(rest)
}

/// A position in a text that counts lines, for the stream-read rest transforms.
struct Cursor<'a> {
    text: &'a str,
    pos: usize,
    /// 1-based line of `pos`.
    line: usize,
}

impl<'a> Cursor<'a> {
    fn new(text: &'a str) -> Self {
        Self {
            text,
            pos: 0,
            line: 1,
        }
    }

    fn at_end(&self) -> bool {
        self.pos >= self.text.len()
    }

    fn skip_white_space(&mut self) {
        while let Some(&b) = self.text.as_bytes().get(self.pos) {
            if !b.is_ascii_whitespace() {
                break;
            }
            if b == b'\n' {
                self.line += 1;
            }
            self.pos += 1;
        }
    }

    /// The next white-space-delimited token and its line.
    fn token(&mut self) -> Option<(&'a str, usize)> {
        self.skip_white_space();
        let start = self.pos;
        let bytes = self.text.as_bytes();
        while bytes
            .get(self.pos)
            .is_some_and(|b| !b.is_ascii_whitespace())
        {
            self.pos += 1;
        }
        // Both ends are at an ASCII byte or the end: char boundaries.
        let token = self.text.get(start..self.pos)?;
        (!token.is_empty()).then_some((token, self.line))
    }

    /// The next three characters after white space (fewer at the end of the text) and the
    /// line they start on; `None` at the end.
    fn three_chars(&mut self) -> Option<(&'a str, usize)> {
        self.skip_white_space();
        let line = self.line;
        let rest = self.text.get(self.pos..)?;
        if rest.is_empty() {
            return None;
        }
        let len = rest.char_indices().nth(3).map_or(rest.len(), |(i, _)| i);
        let chars = rest.get(..len)?;
        self.line += chars.bytes().filter(|&b| b == b'\n').count();
        self.pos += len;
        Some((chars, line))
    }
}

/// The rotation `R_xyz(joint_orient) · R_order(angles)` of the assignment's
/// `local = T · R_xyz(jointOrient) · R_order(angles)`, angles in degrees `[x, y, z]`
/// (column vectors: the orient is applied after, i.e. outside, the rest angles).
pub fn local_rotation(joint_orient_deg: DVec3, angles_deg: DVec3, order: EulerOrder) -> DQuat {
    euler_rotation(EulerOrder::Xyz, joint_orient_deg) * euler_rotation(order, angles_deg)
}

/// The rotation of Euler angles in degrees `[x, y, z]` applied in `order` (the first
/// letter first: `xyz` is `Rz · Ry · Rx`), in `f64`.
pub fn euler_rotation(order: EulerOrder, angles_deg: DVec3) -> DQuat {
    order.as_str().bytes().fold(DQuat::IDENTITY, |q, axis| {
        let elementary = match axis {
            b'x' => DQuat::from_rotation_x(angles_deg.x.to_radians()),
            b'y' => DQuat::from_rotation_y(angles_deg.y.to_radians()),
            _ => DQuat::from_rotation_z(angles_deg.z.to_radians()),
        };
        // A later letter is applied later: it multiplies from the left.
        elementary * q
    })
}

/// A joint's local rest transform `T(translation) · R_xyz(joint_orient) · R_order(angles)`
/// (translation in the files' unit, angles in degrees), computed in `f64` and rounded to
/// `f32` once: translation, unit rotation with `w >= 0`, scale 1.
pub fn rest_local_transform(
    translation: DVec3,
    joint_orient_deg: DVec3,
    angles_deg: DVec3,
    order: EulerOrder,
) -> Transform {
    let mut q = local_rotation(joint_orient_deg, angles_deg, order).normalize();
    if q.w < 0.0 {
        q = -q;
    }
    Transform {
        translation: translation.as_vec3(),
        rotation: q.as_quat(),
        scale: Vec3::ONE,
    }
}

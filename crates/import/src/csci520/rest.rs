//! `jointRestTransforms.txt` and the assignment's rest transform `T · R_xyz(orient) ·
//! R_order(angles)`.

use std::path::Path;

use glam::{DQuat, DVec3, Vec3};
use rigport_model::conventions::EulerOrder;
use rigport_model::Transform;

use crate::text::{self, Cursor, NumberIssue};
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
        let Some(t) = cursor.next_token() else {
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
        let (token, line) = (t.text, t.line);
        last_line = line;
        let k = values.len();
        let section = SECTIONS
            .get(k / per_section.max(1))
            .copied()
            .unwrap_or("value");
        let at = || cursor.location(path, t);
        let value: f64 = text::number(token, section, at)?;
        if k < per_section && !(value as f32).is_finite() {
            return Err(text::number_error(
                at(),
                section,
                token,
                NumberIssue::OutOfRange("f32"),
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
    cursor.skip_space(true);
    if cursor.pos >= text.len() {
        return Ok(rest);
    }
    rest.rotate_orders_given = true;
    for (joint, slot) in rest.rotate_orders.iter_mut().enumerate() {
        let Some((token, line)) = three_chars(&mut cursor) else {
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
    if let Some(t) = cursor.next_token() {
        let (token, line) = (t.text, t.line);
        return Err(ImportError::syntax(
            Location::line(path, line),
            format!("the end of the file after {joint_count} rotate orders"),
            token,
        ));
    }
    Ok(rest)
}

/// The next three characters after white space (fewer at the end of the text) and the
/// line they start on; `None` at the end. The cursor moves past them, counting the line
/// ends among them (LF, CRLF or a lone CR).
fn three_chars<'a>(cursor: &mut Cursor<'a>) -> Option<(&'a str, usize)> {
    cursor.skip_space(true);
    let line = cursor.line;
    let rest = cursor.text.get(cursor.pos..)?;
    if rest.is_empty() {
        return None;
    }
    let len = rest.char_indices().nth(3).map_or(rest.len(), |(i, _)| i);
    let chars = rest.get(..len)?;
    let bytes = cursor.text.as_bytes();
    for (i, b) in chars.bytes().enumerate() {
        let at = cursor.pos + i;
        // A CR followed by LF ends one line, counted at the LF (which may come after
        // the three characters, where the cursor counts it).
        let lone_cr = b == b'\r' && bytes.get(at + 1) != Some(&b'\n');
        if b == b'\n' || lone_cr {
            cursor.line += 1;
            cursor.line_start = at + 1;
        }
    }
    cursor.pos += len;
    Some((chars, line))
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

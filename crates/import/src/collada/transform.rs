//! A node's transform elements (`<matrix>`, `<translate>`, `<rotate>`, `<scale>`,
//! `<lookat>`, `<skew>`), in document order, and their composition (COLLADA 1.4.1 §5,
//! "Transform elements": the node's local matrix is the product of its elements in the
//! order written, so the last one applies to a point first).
//!
//! Each element keeps its `sid` and its raw values, so an animation channel can replace
//! the whole value or one component of it before the node is composed again.

use rigport_model::glam::{DMat4, DQuat, DVec3};

use super::xml::{child_elements, row_major, Doc, Node};
use crate::ImportError;

/// What a transform element is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Kind {
    /// 16 values, row-major.
    Matrix,
    /// x y z.
    Translate,
    /// axis x y z, angle in degrees.
    Rotate,
    /// x y z.
    Scale,
    /// eye, interest, up (9 values).
    Lookat,
    /// angle in degrees, rotation axis, translation axis (7 values).
    Skew,
}

impl Kind {
    fn of(tag: &str) -> Option<Self> {
        Some(match tag {
            "matrix" => Kind::Matrix,
            "translate" => Kind::Translate,
            "rotate" => Kind::Rotate,
            "scale" => Kind::Scale,
            "lookat" => Kind::Lookat,
            "skew" => Kind::Skew,
            _ => return None,
        })
    }

    /// How many values the element holds.
    pub(super) fn len(self) -> usize {
        match self {
            Kind::Matrix => 16,
            Kind::Translate | Kind::Scale => 3,
            Kind::Rotate => 4,
            Kind::Lookat => 9,
            Kind::Skew => 7,
        }
    }

    /// The value index a member selector names (`X`, `Y`, `Z`, `ANGLE`; COLLADA 1.4.1 §3,
    /// "Address Syntax").
    pub(super) fn member(self, name: &str) -> Option<usize> {
        match (self, name) {
            (Kind::Rotate, "ANGLE") => Some(3),
            (_, "X") => Some(0),
            (_, "Y") => Some(1),
            (_, "Z") => Some(2),
            (Kind::Rotate, "W") => Some(3),
            _ => None,
        }
    }
}

/// One transform element.
#[derive(Clone, Debug)]
pub(super) struct Element {
    pub(super) kind: Kind,
    pub(super) sid: Option<String>,
    pub(super) values: Vec<f64>,
}

/// The transform elements of `node`, in order.
///
/// # Errors
/// An element with another number of values than its kind holds, or a value that is not a
/// number.
pub(super) fn read(doc: &Doc, node: Node) -> Result<Vec<Element>, ImportError> {
    let mut out = Vec::new();
    for e in child_elements(node) {
        let Some(kind) = Kind::of(e.tag_name().name()) else {
            continue;
        };
        let values = doc.floats(e)?;
        if values.len() != kind.len() {
            return Err(ImportError::count(
                doc.at(e),
                "values",
                values.len(),
                kind.len(),
            ));
        }
        out.push(Element {
            kind,
            sid: e.attribute("sid").map(str::to_string),
            values,
        });
    }
    Ok(out)
}

/// The local matrix of `elements`, composed in order.
pub(super) fn compose(elements: &[Element]) -> DMat4 {
    elements
        .iter()
        .fold(DMat4::IDENTITY, |m, e| m * matrix(e.kind, &e.values))
}

/// One element's matrix (values as [`Kind::len`] says; missing values read as 0).
pub(super) fn matrix(kind: Kind, values: &[f64]) -> DMat4 {
    let v = |i: usize| values.get(i).copied().unwrap_or(0.0);
    let v3 = |i: usize| DVec3::new(v(i), v(i + 1), v(i + 2));
    match kind {
        Kind::Matrix => {
            let mut m = [0.0; 16];
            for (k, x) in m.iter_mut().enumerate() {
                *x = v(k);
            }
            row_major(&m)
        }
        Kind::Translate => DMat4::from_translation(v3(0)),
        Kind::Scale => DMat4::from_scale(v3(0)),
        Kind::Rotate => match v3(0).try_normalize() {
            Some(axis) => DMat4::from_quat(DQuat::from_axis_angle(axis, v(3).to_radians())),
            None => DMat4::IDENTITY,
        },
        Kind::Lookat => {
            // The node sits at `eye` looking at `interest` (-Z forward, `up` +Y): the
            // inverse of the view matrix.
            let (eye, interest, up) = (v3(0), v3(3), v3(6));
            let forward = interest - eye;
            if forward.length_squared() == 0.0 || forward.cross(up).length_squared() == 0.0 {
                DMat4::from_translation(eye)
            } else {
                DMat4::look_at_rh(eye, interest, up).inverse()
            }
        }
        Kind::Skew => {
            // RenderMan's skew as COLLADA adopts it: points move along the translation
            // axis `b` in proportion to their distance along the rotation axis `a`, by
            // tan(angle): p' = p + tan(angle) (a . p) b (a shear; `a` is made
            // perpendicular to `b` first so the shear is area-preserving).
            let (a, b) = (v3(1), v3(4));
            let Some(b) = b.try_normalize() else {
                return DMat4::IDENTITY;
            };
            let Some(a) = (a - b * a.dot(b)).try_normalize() else {
                return DMat4::IDENTITY;
            };
            let t = v(0).to_radians().tan();
            if !t.is_finite() {
                return DMat4::IDENTITY;
            }
            let shear = |axis: DVec3| axis + b * (t * a.dot(axis));
            DMat4::from_cols(
                shear(DVec3::X).extend(0.0),
                shear(DVec3::Y).extend(0.0),
                shear(DVec3::Z).extend(0.0),
                rigport_model::glam::DVec4::W,
            )
        }
    }
}

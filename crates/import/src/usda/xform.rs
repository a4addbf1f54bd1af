//! `UsdGeomXformable`: a prim's local transform from its `xformOpOrder`, and world
//! transforms through its ancestors.
//!
//! Ops (column vectors; the op order lists the outermost first, so the local matrix is
//! the product in list order): `translate`, `scale` (`double3`/`float3`/`half3`),
//! `rotateX`/`rotateY`/`rotateZ` (degrees), `rotateXYZ` ... `rotateZYX` (degrees, the first
//! named axis applied first), `orient` (a quaternion, written `(w, x, y, z)`), `transform`
//! (`matrix4d`, row vectors, transposed here); any with a `:suffix`, and `!invert!`
//! inverting one. `!resetXformStack!` in the order makes the prim ignore its ancestors'
//! transforms.

use glam::{DMat4, DQuat, DVec3};

use super::layer::Value;
use super::stage::{Prim, Prop};
use super::values::{matrix, number, tokens, tuple};

/// The column-vector matrix of a USD row-vector `matrix4d` as written (rows): USD's row
/// `i` is the column `i` of the column-vector matrix (translation in the last row there,
/// the last column here).
pub(super) fn usd_matrix(rows: &[[f64; 4]; 4]) -> DMat4 {
    DMat4::from_cols_array_2d(rows)
}

/// A prim's evaluated local transform.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Local {
    /// The local matrix (column vectors).
    pub matrix: DMat4,
    /// Whether the op order starts with `!resetXformStack!`.
    pub resets: bool,
    /// Whether any op is time-sampled with more than one sample.
    pub animated: bool,
}

/// The value of an op attribute at `time` (time code; `None`: the default value, else the
/// first sample). Between samples: linear interpolation of numbers, as USD interpolates
/// `double3`, `float` and matrices component-wise; quaternions are slerped by the caller
/// ([`Sampled::quat`]), as USD's `GfSlerp`.
fn value_at<'l>(prop: &Prop<'l>, time: Option<f64>) -> Option<Sampled<'l>> {
    let samples = prop.samples.as_ref().filter(|s| !s.is_empty());
    match (time, samples) {
        (Some(t), Some(s)) => {
            let first = s.first()?;
            let last = s.last()?;
            if t <= first.0 {
                return Some(Sampled::One(first.1));
            }
            if t >= last.0 {
                return Some(Sampled::One(last.1));
            }
            let k = s.iter().position(|(st, _)| *st > t)?;
            let (a, b) = (s.get(k - 1)?, s.get(k)?);
            if (a.0 - t).abs() == 0.0 {
                return Some(Sampled::One(a.1));
            }
            Some(Sampled::Mix(a.1, b.1, (t - a.0) / (b.0 - a.0)))
        }
        _ => match prop.default {
            Some(v) if *v != Value::None => Some(Sampled::One(v)),
            _ => samples
                .and_then(|s| s.first())
                .map(|(_, v)| Sampled::One(v)),
        },
    }
}

enum Sampled<'l> {
    One(&'l Value),
    Mix(&'l Value, &'l Value, f64),
}

impl Sampled<'_> {
    fn map<const N: usize>(&self, read: impl Fn(&Value) -> Option<[f64; N]>) -> Option<[f64; N]> {
        match self {
            Sampled::One(v) => read(v),
            Sampled::Mix(a, b, u) => {
                let (a, b) = (read(a)?, read(b)?);
                let mut out = [0.0; N];
                for k in 0..N {
                    out[k] = a[k] + (b[k] - a[k]) * u;
                }
                Some(out)
            }
        }
    }
}

impl Sampled<'_> {
    /// A quaternion value `(w, x, y, z)` as written; between samples `GfSlerp` (OpenUSD
    /// `pxr/base/gf/quat.template.cpp`, what `Usd_Lerp` uses for quaternions): the
    /// shorter arc, on the components as authored (not normalized), linear within 1e-5.
    fn quat(&self) -> Option<[f64; 4]> {
        match self {
            Sampled::One(v) => tuple::<4>(v),
            Sampled::Mix(a, b, u) => {
                let (a, b) = (tuple::<4>(a)?, tuple::<4>(b)?);
                let mut cos = (0..4).map(|k| a[k] * b[k]).sum::<f64>();
                let flip = cos < 0.0;
                if flip {
                    cos = -cos;
                }
                let (s0, mut s1) = if 1.0 - cos > 1e-5 {
                    let theta = cos.acos();
                    let sin = theta.sin();
                    (((1.0 - u) * theta).sin() / sin, (u * theta).sin() / sin)
                } else {
                    (1.0 - u, *u)
                };
                if flip {
                    s1 = -s1;
                }
                Some(std::array::from_fn(|k| s0 * a[k] + s1 * b[k]))
            }
        }
    }
}

/// The rotation of an `orient` value `(w, x, y, z)` as `UsdGeomXformOp` makes it: a unit
/// quaternion as is; otherwise through `GfRotation(quat)`, i.e. the angle `2 acos(w)`
/// about the normalized imaginary part (not the normalized quaternion: Reality Converter
/// writes `(0.707, 0, 0, 0.707)`, which USD turns by 90.017°).
fn orient_rotation([w, x, y, z]: [f64; 4]) -> DQuat {
    let q = DQuat::from_xyzw(x, y, z, w);
    if (q.length_squared() - 1.0).abs() <= 1e-9 {
        return q.normalize();
    }
    let axis = DVec3::new(x, y, z);
    let len = axis.length();
    if len <= 1e-10 {
        return DQuat::IDENTITY;
    }
    DQuat::from_axis_angle(axis / len, 2.0 * w.clamp(-1.0, 1.0).acos())
}

fn flat_matrix(v: &Value) -> Option<[f64; 16]> {
    let m = matrix(v)?;
    let mut out = [0.0; 16];
    for (r, row) in m.iter().enumerate() {
        out[r * 4..r * 4 + 4].copy_from_slice(row);
    }
    Some(out)
}

fn axis_rotation(axis: char, degrees: f64) -> DQuat {
    let a = degrees.to_radians();
    match axis {
        'X' => DQuat::from_rotation_x(a),
        'Y' => DQuat::from_rotation_y(a),
        _ => DQuat::from_rotation_z(a),
    }
}

/// The matrix of one op `name` (without `!invert!`), or an error message.
fn op_matrix(prim: &Prim<'_>, name: &str, time: Option<f64>) -> Result<DMat4, String> {
    let prop = prim
        .prop(name)
        .ok_or_else(|| format!("xformOpOrder names {name}, which is not authored"))?;
    let v = value_at(prop, time).ok_or_else(|| format!("{name} has no value"))?;
    let kind = name
        .strip_prefix("xformOp:")
        .map(|k| k.split(':').next().unwrap_or(k))
        .ok_or_else(|| format!("{name} is not an xformOp"))?;
    let bad = || format!("{name} has a value of the wrong type");
    let m = match kind {
        "translate" => DMat4::from_translation(DVec3::from(v.map(tuple::<3>).ok_or_else(bad)?)),
        "scale" => DMat4::from_scale(DVec3::from(v.map(tuple::<3>).ok_or_else(bad)?)),
        "rotateX" | "rotateY" | "rotateZ" => {
            let [deg] = v.map(|x| number(x).map(|n| [n])).ok_or_else(bad)?;
            DMat4::from_quat(axis_rotation(kind.chars().last().unwrap_or('X'), deg))
        }
        "orient" => DMat4::from_quat(orient_rotation(v.quat().ok_or_else(bad)?)),
        "transform" => {
            let f = v.map(flat_matrix).ok_or_else(bad)?;
            let mut rows = [[0.0; 4]; 4];
            for (r, row) in rows.iter_mut().enumerate() {
                row.copy_from_slice(&f[r * 4..r * 4 + 4]);
            }
            usd_matrix(&rows)
        }
        k if k.len() == 9 && k.starts_with("rotate") => {
            let order: Vec<char> = k["rotate".len()..].chars().collect();
            if !order.iter().all(|c| matches!(c, 'X' | 'Y' | 'Z')) {
                return Err(format!("unknown xformOp {name}"));
            }
            let angles = v.map(tuple::<3>).ok_or_else(bad)?;
            let angle = |c: char| match c {
                'X' => angles[0],
                'Y' => angles[1],
                _ => angles[2],
            };
            // The first named axis is applied first: R = R(third) · R(second) · R(first).
            let q = order
                .iter()
                .fold(DQuat::IDENTITY, |q, &c| axis_rotation(c, angle(c)) * q);
            DMat4::from_quat(q)
        }
        _ => return Err(format!("unknown xformOp {name}")),
    };
    Ok(m)
}

/// Whether an op attribute has more than one time sample.
fn op_animated(prim: &Prim<'_>, name: &str) -> bool {
    prim.prop(name)
        .and_then(|p| p.samples.as_ref())
        .is_some_and(|s| s.len() > 1 && s.windows(2).any(|w| w[0].1 != w[1].1))
}

/// The local transform of `prim` at `time` (see [`value_at`]); `None` when it authors no
/// `xformOpOrder`.
pub(super) fn local(prim: &Prim<'_>, time: Option<f64>) -> Result<Option<Local>, String> {
    let Some(order) = prim.prop("xformOpOrder") else {
        return Ok(None);
    };
    let Some(order) = order
        .default
        .filter(|v| **v != Value::None)
        .map(|v| tokens(v).ok_or_else(|| "xformOpOrder is not a token[]".to_string()))
        .transpose()?
    else {
        return Ok(None);
    };
    let mut out = Local {
        matrix: DMat4::IDENTITY,
        resets: false,
        animated: false,
    };
    for op in order {
        if op == "!resetXformStack!" {
            out.resets = true;
            out.matrix = DMat4::IDENTITY;
            continue;
        }
        let (name, invert) = match op.strip_prefix("!invert!") {
            Some(n) => (n, true),
            None => (op, false),
        };
        let m = op_matrix(prim, name, time)?;
        out.animated |= op_animated(prim, name);
        out.matrix *= if invert { m.inverse() } else { m };
    }
    Ok(Some(out))
}

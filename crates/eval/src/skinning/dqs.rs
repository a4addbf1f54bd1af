//! Dual quaternion skinning, following UsdSkel so results can be compared with it.
//!
//! # The algorithm (UsdSkel's `dualQuaternion` skinning method)
//! This follows OpenUSD's `pxr/usd/usdSkel/utils.cpp` (`_ConvertToDualQuaternions`,
//! `_GetPivotJointIndex`, `_SkinPointsDQS`, `_SkinNormalsDQS`) step by step, so that
//! `tools/check_skinning.py` can compare our output with `UsdSkel.SkinPoints`:
//!
//! 1. **Per joint, once per frame** ([`decompose`]): the skinning matrix `M = [A | t]` is
//!    split, in double precision, into the rigid part `T(t) * R` and the remaining
//!    scale/shear `S = Rᵀ A`, so `A = R S` (column vectors: `S` is applied first). `R` is
//!    the orthogonal factor of the polar decomposition of `A` (what `GfMatrix4d::Factor`
//!    computes via an eigen-decomposition of `A Aᵀ`; we use scaled Newton iteration, which
//!    converges to the same matrix), negated when `det A < 0` so that it is a proper
//!    rotation and the mirror ends up in `S`. A joint with `|det A| < 1e-10` (Factor's
//!    singularity test) becomes the zero dual quaternion with `S = I`.
//! 2. The rigid part becomes the unit dual quaternion `(q, ½ (t, 0) q)`.
//! 3. If any joint of the palette has `S` differing from the identity by more than `1e-6`
//!    in some element (UsdSkel's `hasJointScale`), every point is first scaled by the
//!    linear blend `Σ wᵢ Sᵢ p`; otherwise `p` is used as is.
//! 4. The **pivot** is the point's highest-weight joint (the first one on ties). Every
//!    influence whose rotation quaternion has a negative dot product with the pivot's
//!    enters the blend with its weight negated, so all lie in the pivot's hemisphere.
//! 5. The blended dual quaternion `Σ ±wᵢ q̂ᵢ` is normalized (both parts divided by the
//!    real part's length; a blend shorter than `1e-10` becomes the identity) and applied
//!    to the scaled point.
//!
//! # Where this differs from Kavan et al. 2008
//! "Geometric Skinning with Approximate Dual Quaternion Blending" (ACM TOG 27(4)):
//! - **Hemisphere test**: the paper's reference code aligns every quaternion with the
//!   *first* influence; UsdSkel (and we) align with the *highest-weight* influence. The two
//!   agree whenever the first influence is also the heaviest.
//! - **Scale/shear**: the paper's section 4.3 handles non-rigid joints the same way (blend
//!   the scale/shear matrices linearly, then apply the blended dual quaternion), but
//!   UsdSkel decides it *per palette* (`hasJointScale`): when no joint scales, the point
//!   is not multiplied by `Σ wᵢ` — which only matters when weights do not sum to 1.
//! - **Normalization**: identical (divide by the real part's norm); UsdSkel additionally
//!   removes the dual part's component along the real part, which does not change the
//!   transform of a point (it only changes the scalar part of `dual * conj(real)`).
//! - **Degenerate joints**: a singular joint matrix contributes nothing to the rotation but
//!   still its weight times the identity to the scale blend (UsdSkel's rule; the paper does
//!   not discuss it).
//!
//! # Normals
//! As UsdSkel's `_SkinNormalsDQS`: the normal is blended linearly with each joint's
//! normal scale matrix `Sᵢ⁻¹` (the scale/shear part of the inverse transpose `A⁻ᵀ = R S⁻¹`)
//! when the palette has scale, then rotated by the blended rotation (the real part of the
//! blended dual quaternion, same pivot and signs) and renormalized.
//!
//! # Where rigport's rules differ from UsdSkel's
//! - A vertex with no influence, or only zero weights, keeps its rest position and normal
//!   (UsdSkel's LBS would move it to the origin).
//! - The per-vertex blend runs in `f32` (UsdSkel: `f64`); the per-joint decomposition runs
//!   in `f64` like UsdSkel's. Expect differences of a few `f32` ulps of the coordinates.
//! - The hemisphere test uses the `f32` rotation quaternions; a pair of joints rotated
//!   exactly 180° apart (dot product within about `1e-7` of zero) may be flipped
//!   differently.
//! - A mirrored joint (`det A < 0`) gives normals that follow the point path (rotation
//!   `R`, scale `S⁻¹` including the mirror); UsdSkel's normal path orthonormalizes the
//!   improper matrix instead, with an undefined quaternion.

use glam::{DMat3, DQuat, DVec3, Mat3, Mat4, Quat, Vec3, Vec3A, Vec4};
use rigport_model::{Influence, Influences};

use super::common::{
    check_lengths, check_palette, for_vertex_chunks, Frame, Hemisphere, JointDq, Sym3,
    MIN_REAL_LENGTH,
};
use super::simd;
use crate::EvalError;

/// Joint matrices whose upper 3x3 has `|det| < SINGULAR_DET` are singular (the `eps`
/// default of `GfMatrix4d::Factor`, which `_ConvertToDualQuaternions` calls).
const SINGULAR_DET: f64 = 1e-10;

/// UsdSkel's `hasJointScale` tolerance: `GfIsClose(jointScale, identity, 1e-6)`.
const SCALE_TOLERANCE: f64 = 1e-6;

/// The per-vertex hemisphere test reads a precomputed sign table (palette x palette signs
/// per frame) when the palette has at most this many joints, else it takes dot products.
const SIGN_TABLE_MAX_JOINTS: usize = 128;

/// A dual quaternion `real + ε dual`; as a rigid transform (unit real part, dual part
/// orthogonal to it) it rotates by `real`, then translates by `2 dual real*`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DualQuat {
    /// Rotation part (xyzw).
    pub real: Quat,
    /// Translation part: `½ (t, 0) * real`.
    pub dual: Quat,
}

impl DualQuat {
    /// The identity transform.
    pub const IDENTITY: Self = Self {
        real: Quat::IDENTITY,
        dual: Quat::from_xyzw(0.0, 0.0, 0.0, 0.0),
    };

    /// Rotation `rotation` (unit quaternion) followed by translation `translation`.
    pub fn from_rotation_translation(rotation: Quat, translation: Vec3) -> Self {
        let t = Quat::from_xyzw(translation.x, translation.y, translation.z, 0.0);
        Self {
            real: rotation,
            dual: (t * rotation) * 0.5,
        }
    }

    /// Normalized as UsdSkel's `GfDualQuat::Normalize`: both parts divided by the real
    /// part's length, then the dual part made orthogonal to the real part. A real part
    /// shorter than `1e-10` gives the identity.
    pub fn normalized(self) -> Self {
        let real = Vec4::from(self.real);
        let len = real.length();
        // `is_nan` too: a NaN length is not a valid rotation either.
        if len < MIN_REAL_LENGTH || len.is_nan() {
            return Self::IDENTITY;
        }
        let real = real / len;
        let dual = Vec4::from(self.dual) / len;
        let dual = dual - real * real.dot(dual);
        Self {
            real: Quat::from_vec4(real),
            dual: Quat::from_vec4(dual),
        }
    }

    /// The translation `2 (dual * conj(real))` of a normalized dual quaternion.
    pub fn translation(self) -> Vec3 {
        let (r, d) = (Vec4::from(self.real), Vec4::from(self.dual));
        let (rv, dv) = (r.truncate(), d.truncate());
        2.0 * (r.w * dv - d.w * rv + rv.cross(dv))
    }

    /// Applies a normalized dual quaternion to a point: rotate, then translate.
    pub fn transform_point3(self, p: Vec3) -> Vec3 {
        self.real * p + self.translation()
    }
}

/// The parts of one joint skinning matrix that UsdSkel's DQS uses (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JointDecomposition {
    /// The rigid part `T(t) * R` as a unit dual quaternion.
    pub rigid: DualQuat,
    /// The remaining scale/shear `S = Rᵀ A` (column vectors; applied before `rigid`).
    pub scale: Mat3,
}

/// Splits a skinning matrix (column vectors, affine) into rigid part and scale/shear the
/// way UsdSkel's `_ConvertToDualQuaternions` does, in double precision.
///
/// Returns `None` when the upper 3x3 is singular (`|det| < 1e-10`) or not finite; UsdSkel
/// then uses the zero dual quaternion and `S = I`.
pub fn decompose(m: &Mat4) -> Option<JointDecomposition> {
    let (rotation, translation, scale) = decompose_f64(m)?;
    let rotation = rotation.as_quat();
    Some(JointDecomposition {
        rigid: DualQuat::from_rotation_translation(rotation, translation.as_vec3()),
        scale: scale.as_mat3(),
    })
}

/// [`decompose`] in `f64`: rotation, translation, scale/shear with `A = R S`.
fn decompose_f64(m: &Mat4) -> Option<(DQuat, DVec3, DMat3)> {
    let a = DMat3::from_cols(
        m.x_axis.truncate().as_dvec3(),
        m.y_axis.truncate().as_dvec3(),
        m.z_axis.truncate().as_dvec3(),
    );
    let det = a.determinant();
    if det.abs() < SINGULAR_DET || !det.is_finite() || !a.is_finite() {
        return None;
    }
    let mut r = polar_orthogonal(a)?;
    if det < 0.0 {
        // Factor puts the mirror into the scale (all three factors negative), leaving a
        // proper rotation: for 3x3, -Q has determinant +1 when Q has -1.
        r = -r;
    }
    let scale = r.transpose() * a;
    let rotation = DQuat::from_mat3(&r).normalize();
    let translation = m.w_axis.truncate().as_dvec3();
    translation
        .is_finite()
        .then_some((rotation, translation, scale))
}

/// The orthogonal factor `Q` of the polar decomposition `A = Q P` (`P` symmetric positive
/// definite) of an invertible matrix, by Newton's iteration `X ← ½ (γX + X⁻ᵀ/γ)` with
/// Higham's Frobenius-norm scaling `γ` (Higham 1986, "Computing the polar decomposition
/// with applications", SIAM J. Sci. Stat. Comput. 7(4)), which converges quadratically.
fn polar_orthogonal(a: DMat3) -> Option<DMat3> {
    let frobenius = |m: &DMat3| {
        (m.x_axis.length_squared() + m.y_axis.length_squared() + m.z_axis.length_squared()).sqrt()
    };
    let mut x = a;
    let mut scaled = true;
    for _ in 0..100 {
        let det = x.determinant();
        if det == 0.0 || !det.is_finite() {
            return None;
        }
        let inv_t = x.inverse().transpose();
        let gamma = if scaled {
            (frobenius(&inv_t) / frobenius(&x)).sqrt()
        } else {
            1.0
        };
        let next = (x * gamma + inv_t * (1.0 / gamma)) * 0.5;
        let diff = frobenius(&(next - x));
        x = next;
        if diff < 1e-2 {
            // Near convergence scaling no longer helps, and plain Newton keeps the last
            // digits (Higham's recommendation).
            scaled = false;
        }
        if diff <= 4.0 * f64::EPSILON {
            break;
        }
    }
    x.is_finite().then_some(x)
}

/// Per-frame joint data for dual quaternion skinning, computed from the skinning matrices
/// by the jobs that take it (UsdSkel's per-call `_ConvertToDualQuaternions`), and kept by
/// the caller so that `run()` allocates nothing.
///
/// Create it once with room for the largest palette and frame count you will skin, and
/// reuse it for every frame.
#[derive(Clone, Debug, Default)]
pub struct DqsPalette {
    joint_capacity: usize,
    frame_capacity: usize,
    /// Palette size of the current contents.
    joints: usize,
    /// Frames of the current contents.
    frames: usize,
    /// `frames x joints`.
    dq: Vec<JointDq>,
    /// `frames x joints`: the scale/shear part `S⁻¹` of each joint's normal matrix.
    normal_scale: Vec<Sym3>,
    /// Per frame: does any joint have scale or shear (UsdSkel's `hasJointScale`)?
    has_scale: Vec<bool>,
    /// Per frame: are all pairwise dot products of the joints' quaternions non-negative?
    /// Then no influence is ever flipped and the per-vertex loop skips the test.
    aligned: Vec<bool>,
    /// `frames x joints x joints` signs (+1 or -1) of `real[j] · real[pivot]` at
    /// `[frame][pivot][j]`, when `joints <= SIGN_TABLE_MAX_JOINTS`.
    signs: Vec<f32>,
}

impl DqsPalette {
    /// Room for palettes of up to `joints` joints and up to `frames` frames at once
    /// (`80 + 36 + (joints <= 128 ? 4 * joints : 0)` bytes per joint and frame).
    pub fn new(joints: usize, frames: usize) -> Self {
        let n = joints.saturating_mul(frames);
        let table = if joints <= SIGN_TABLE_MAX_JOINTS {
            n.saturating_mul(joints)
        } else {
            0
        };
        Self {
            joint_capacity: joints,
            frame_capacity: frames,
            joints: 0,
            frames: 0,
            dq: vec![JointDq::default(); n],
            normal_scale: vec![Sym3::IDENTITY; n],
            has_scale: vec![false; frames],
            aligned: vec![false; frames],
            signs: vec![1.0; table],
        }
    }

    /// The largest palette it has room for.
    pub fn joint_capacity(&self) -> usize {
        self.joint_capacity
    }

    /// The most frames it has room for.
    pub fn frame_capacity(&self) -> usize {
        self.frame_capacity
    }

    /// Converts `frames` consecutive palettes of `joints` skinning matrices each
    /// (`frame_skin_matrices.len() == frames * joints`). Allocates nothing.
    pub(crate) fn prepare(
        &mut self,
        frame_skin_matrices: &[Mat4],
        joints: usize,
        frames: usize,
    ) -> Result<(), EvalError> {
        if joints > self.joint_capacity {
            return Err(EvalError::Length {
                what: "DqsPalette joints",
                expected: joints,
                found: self.joint_capacity,
            });
        }
        if frames > self.frame_capacity {
            return Err(EvalError::Length {
                what: "DqsPalette frames",
                expected: frames,
                found: self.frame_capacity,
            });
        }
        let n = joints * frames;
        if frame_skin_matrices.len() != n {
            return Err(EvalError::Length {
                what: "skin matrices",
                expected: n,
                found: frame_skin_matrices.len(),
            });
        }
        self.joints = joints;
        self.frames = frames;
        let table = joints <= SIGN_TABLE_MAX_JOINTS;
        for f in 0..frames {
            let range = f * joints..(f + 1) * joints;
            let mut has_scale = false;
            for ((m, dq), ns) in frame_skin_matrices[range.clone()]
                .iter()
                .zip(&mut self.dq[range.clone()])
                .zip(&mut self.normal_scale[range.clone()])
            {
                match decompose_f64(m) {
                    Some((rotation, translation, scale)) => {
                        let t = DQuat::from_xyzw(translation.x, translation.y, translation.z, 0.0);
                        let dual = (t * rotation) * 0.5;
                        *dq = JointDq {
                            real: Vec4::from(rotation.as_quat()),
                            dual: Vec4::from(dual.as_quat()),
                            scale: Sym3::from_dmat3(&scale),
                        };
                        *ns = Sym3::from_dmat3(&scale.inverse());
                        let off = (scale - DMat3::IDENTITY).abs();
                        has_scale |= off.x_axis.max_element() > SCALE_TOLERANCE
                            || off.y_axis.max_element() > SCALE_TOLERANCE
                            || off.z_axis.max_element() > SCALE_TOLERANCE;
                    }
                    None => {
                        *dq = JointDq::default();
                        *ns = Sym3::IDENTITY;
                    }
                }
            }
            self.has_scale[f] = has_scale;
            self.aligned[f] = false;
            if table {
                let dq = &self.dq[range];
                let signs = &mut self.signs[f * joints * joints..(f + 1) * joints * joints];
                let mut aligned = true;
                for (pivot, row) in dq.iter().zip(signs.chunks_exact_mut(joints)) {
                    for (j, s) in dq.iter().zip(row) {
                        *s = sign_of(j.real, pivot.real);
                        aligned &= *s > 0.0;
                    }
                }
                self.aligned[f] = aligned;
            }
        }
        Ok(())
    }

    /// The prepared data of frame `f` (`f < frames` of the last `prepare`).
    pub(crate) fn frame(&self, f: usize) -> Frame<'_> {
        let j = self.joints;
        let signs = if j <= SIGN_TABLE_MAX_JOINTS {
            Some(&self.signs[f * j * j..(f + 1) * j * j])
        } else {
            None
        };
        Frame {
            dq: &self.dq[f * j..(f + 1) * j],
            normal_scale: &self.normal_scale[f * j..(f + 1) * j],
            has_scale: self.has_scale[f],
            aligned: self.aligned[f],
            signs,
        }
    }
}

/// `-1.0` when `q` lies in the other hemisphere than `pivot` (`_SkinPointsDQS`: `GfDot <
/// 0` flips the weight), else `1.0`.
#[inline(always)]
fn sign_of(q: Vec4, pivot: Vec4) -> f32 {
    if q.dot(pivot) < 0.0 {
        -1.0
    } else {
        1.0
    }
}

/// Reads the precomputed sign table.
#[derive(Clone, Copy)]
struct Table<'a> {
    signs: &'a [f32],
    joints: usize,
    row: &'a [f32],
}

impl Hemisphere for Table<'_> {
    #[inline(always)]
    fn for_pivot(self, _dq: &[JointDq], pivot: usize) -> Self {
        let start = pivot * self.joints;
        Self {
            row: &self.signs[start..start + self.joints],
            ..self
        }
    }
    #[inline(always)]
    fn sign(self, _dq: &JointDq, j: usize) -> f32 {
        self.row[j]
    }
}

/// Takes the dot product with the pivot's quaternion.
#[derive(Clone, Copy)]
struct Dot {
    pivot: Vec4,
}

impl Hemisphere for Dot {
    #[inline(always)]
    fn for_pivot(self, dq: &[JointDq], pivot: usize) -> Self {
        Self {
            pivot: dq[pivot].real,
        }
    }
    #[inline(always)]
    fn sign(self, dq: &JointDq, _j: usize) -> f32 {
        sign_of(dq.real, self.pivot)
    }
}

/// Every joint lies in every other's hemisphere this frame: nothing to flip.
#[derive(Clone, Copy)]
struct Aligned;

impl Hemisphere for Aligned {
    #[inline(always)]
    fn for_pivot(self, _dq: &[JointDq], _pivot: usize) -> Self {
        self
    }
    #[inline(always)]
    fn sign(self, _dq: &JointDq, _j: usize) -> f32 {
        1.0
    }
}

/// The blend of one vertex: unnormalized dual quaternion and the scaled point.
#[derive(Clone, Copy)]
struct Blend {
    real: Vec4,
    dual: Vec4,
    scaled: Vec3A,
    /// `Σ wᵢ Sᵢ⁻¹` when normals are skinned and the palette has scale.
    normal_scale: Sym3,
}

/// Blends `W` influences (the pivot is `joints[pivot_slot]`); joint indices must be valid
/// (checked when the job is validated).
#[inline(always)]
fn blend_fixed<const W: usize, const SCALE: bool, H: Hemisphere>(
    frame: &Frame<'_>,
    hemisphere: H,
    joints: &[u32; W],
    weights: &[f32; W],
    pivot_slot: usize,
    p: Vec3A,
) -> (Vec4, Vec4, Vec3A) {
    let h = hemisphere.for_pivot(frame.dq, joints[pivot_slot] as usize);
    let mut real = Vec4::ZERO;
    let mut dual = Vec4::ZERO;
    let mut s = Sym3::ZERO;
    for k in 0..W {
        let j = joints[k] as usize;
        let d = &frame.dq[j];
        let w = weights[k];
        if SCALE {
            s.add_scaled(&d.scale, Vec4::splat(w));
        }
        let sw = Vec4::splat(w * h.sign(d, j));
        real += d.real * sw;
        dual += d.dual * sw;
    }
    let scaled = if SCALE { s.mul_vec3a(p) } else { p };
    (real, dual, scaled)
}

/// The slice version of [`blend_fixed`] for rows of any length, with the normal blend.
fn blend_row<H: Hemisphere>(
    frame: &Frame<'_>,
    hemisphere: H,
    row: &[Influence],
    p: Vec3A,
    normals: bool,
) -> Blend {
    let pivot = pivot_slot(row);
    let pivot_joint = row.get(pivot).map_or(0, |i| i.joint as usize);
    let h = hemisphere.for_pivot(frame.dq, pivot_joint);
    let mut b = Blend {
        real: Vec4::ZERO,
        dual: Vec4::ZERO,
        scaled: Vec3A::ZERO,
        normal_scale: Sym3::ZERO,
    };
    let mut s = Sym3::ZERO;
    for inf in row {
        let j = inf.joint as usize;
        let d = &frame.dq[j];
        let w = inf.weight;
        if frame.has_scale {
            s.add_scaled(&d.scale, Vec4::splat(w));
            if normals {
                b.normal_scale
                    .add_scaled(&frame.normal_scale[j], Vec4::splat(w));
            }
        }
        let sw = w * h.sign(d, j);
        b.real += d.real * sw;
        b.dual += d.dual * sw;
    }
    b.scaled = if frame.has_scale { s.mul_vec3a(p) } else { p };
    b
}

/// The slot of the highest weight, the first one on ties (`_GetPivotJointIndex`).
pub(crate) fn pivot_slot(row: &[Influence]) -> usize {
    let mut best = 0;
    for (k, inf) in row.iter().enumerate().skip(1) {
        if row[best].weight < inf.weight {
            best = k;
        }
    }
    best
}

/// Normalizes a blended dual quaternion and applies it to `v` (see the module docs):
/// with `n² = |real|²`, `u = real.xyz × v + dual.xyz`, the result is
/// `v + (2/n²) (real.w u + real.xyz × u − dual.w real.xyz)`, which expands to UsdSkel's
/// "divide both parts by `n`, rotate, add `2 dual real*`" without dividing twice.
#[inline(always)]
fn apply(real: Vec4, dual: Vec4, v: Vec3A) -> Vec3A {
    let n2 = real.length_squared();
    if n2 < MIN_REAL_LENGTH * MIN_REAL_LENGTH || n2.is_nan() {
        return v;
    }
    let rv = Vec3A::from(real.truncate());
    let dv = Vec3A::from(dual.truncate());
    let u = rv.cross(v) + dv;
    v + (u * real.w + rv.cross(u) - rv * dual.w) * (2.0 / n2)
}

/// Rotates `n` by the normalized `real` and renormalizes (`_SkinNormalsDQS`).
#[inline(always)]
fn rotate_normal(real: Vec4, n: Vec3A, rest: Vec3A) -> Vec3A {
    let n2 = real.length_squared();
    let rotated = if n2 >= MIN_REAL_LENGTH * MIN_REAL_LENGTH {
        let rv = Vec3A::from(real.truncate());
        let u = rv.cross(n);
        n + (u * real.w + rv.cross(u)) * (2.0 / n2)
    } else {
        n
    };
    rotated.try_normalize().unwrap_or(rest)
}

/// [`apply`] on four vertices at once, one per SIMD lane (structure of arrays): the
/// normalization and the two cross products need no shuffles this way.
#[inline(always)]
fn apply4(real: [Vec4; 4], dual: [Vec4; 4], v: [Vec3A; 4]) -> [Vec3A; 4] {
    let r = Mat4::from_cols(real[0], real[1], real[2], real[3]).transpose();
    let d = Mat4::from_cols(dual[0], dual[1], dual[2], dual[3]).transpose();
    let p = Mat4::from_cols(
        v[0].extend(0.0),
        v[1].extend(0.0),
        v[2].extend(0.0),
        v[3].extend(0.0),
    )
    .transpose();
    let (rx, ry, rz, rw) = (r.x_axis, r.y_axis, r.z_axis, r.w_axis);
    let (dx, dy, dz, dw) = (d.x_axis, d.y_axis, d.z_axis, d.w_axis);
    let (px, py, pz) = (p.x_axis, p.y_axis, p.z_axis);
    let n2 = rx * rx + ry * ry + rz * rz + rw * rw;
    let valid = n2.cmpge(Vec4::splat(MIN_REAL_LENGTH * MIN_REAL_LENGTH));
    let s = Vec4::select(valid, Vec4::splat(2.0) / n2, Vec4::ZERO);
    // u = r × p + d
    let ux = ry * pz - rz * py + dx;
    let uy = rz * px - rx * pz + dy;
    let uz = rx * py - ry * px + dz;
    // t = rw u + r × u − dw r
    let tx = rw * ux + (ry * uz - rz * uy) - dw * rx;
    let ty = rw * uy + (rz * ux - rx * uz) - dw * ry;
    let tz = rw * uz + (rx * uy - ry * ux) - dw * rz;
    let out = Mat4::from_cols(px + tx * s, py + ty * s, pz + tz * s, Vec4::ZERO).transpose();
    [
        Vec3A::from(out.x_axis.truncate()),
        Vec3A::from(out.y_axis.truncate()),
        Vec3A::from(out.z_axis.truncate()),
        Vec3A::from(out.w_axis.truncate()),
    ]
}

/// Skins the positions of one chunk of a fixed-width influence layout (`W` slots per
/// vertex, pivot in slot 0) with one frame. Joint indices are valid (checked at setup).
pub(crate) fn skin_fixed<const W: usize>(
    frame: &Frame<'_>,
    joints: &[u32],
    weights: &[f32],
    rest: &[Vec3],
    out: &mut [Vec3],
) {
    if frame.aligned {
        skin_fixed_h::<W, _>(frame, Aligned, joints, weights, rest, out);
        return;
    }
    match frame.signs {
        Some(signs) => skin_fixed_h::<W, _>(frame, table(signs, frame), joints, weights, rest, out),
        None => skin_fixed_h::<W, _>(frame, Dot { pivot: Vec4::ZERO }, joints, weights, rest, out),
    }
}

fn skin_fixed_h<const W: usize, H: Hemisphere>(
    frame: &Frame<'_>,
    h: H,
    joints: &[u32],
    weights: &[f32],
    rest: &[Vec3],
    out: &mut [Vec3],
) {
    if frame.has_scale {
        skin_fixed_with::<W, true, H>(frame, h, joints, weights, rest, out);
    } else {
        skin_fixed_with::<W, false, H>(frame, h, joints, weights, rest, out);
    }
}

fn table<'a>(signs: &'a [f32], frame: &Frame<'a>) -> Table<'a> {
    Table {
        signs,
        joints: frame.dq.len(),
        row: signs,
    }
}

/// [`blend_fixed`] of one vertex's `W` slots (pivot first).
#[inline(always)]
fn vertex_fixed<const W: usize, const SCALE: bool, H: Hemisphere>(
    frame: &Frame<'_>,
    h: H,
    j: &[u32],
    w: &[f32],
    p: Vec3,
) -> (Vec4, Vec4, Vec3A) {
    // `chunks_exact(W)` makes these conversions infallible.
    match (<&[u32; W]>::try_from(j), <&[f32; W]>::try_from(w)) {
        (Ok(j), Ok(w)) => blend_fixed::<W, SCALE, H>(frame, h, j, w, 0, Vec3A::from(p)),
        _ => (Vec4::ZERO, Vec4::ZERO, Vec3A::from(p)),
    }
}

#[inline(always)]
fn skin_fixed_with<const W: usize, const SCALE: bool, H: Hemisphere>(
    frame: &Frame<'_>,
    h: H,
    joints: &[u32],
    weights: &[f32],
    rest: &[Vec3],
    out: &mut [Vec3],
) {
    // With AVX2 + FMA, blocks of eight vertices go through the SIMD kernel; the rest (or
    // everything, on other CPUs) through the portable loop below.
    let done = simd::dqs_fixed::<W, SCALE, H>(frame, h, joints, weights, rest, out);
    let (joints, weights) = (&joints[done * W..], &weights[done * W..]);
    let (rest, out) = (&rest[done..], &mut out[done..]);
    // Blocks of four vertices share the normalization and transform (`apply4`). The
    // lanes are spelled out so that the compiler sees constant offsets into the block.
    let mut j4 = joints.chunks_exact(4 * W);
    let mut w4 = weights.chunks_exact(4 * W);
    let mut r4 = rest.chunks_exact(4);
    let mut o4 = out.chunks_exact_mut(4);
    for (((j, w), r), o) in (&mut j4).zip(&mut w4).zip(&mut r4).zip(&mut o4) {
        let (Ok(r), Ok(o)) = (<&[Vec3; 4]>::try_from(r), <&mut [Vec3; 4]>::try_from(o)) else {
            continue;
        };
        let lane = |l: usize| (&j[l * W..(l + 1) * W], &w[l * W..(l + 1) * W]);
        let (j0, w0) = lane(0);
        let (j1, w1) = lane(1);
        let (j2, w2) = lane(2);
        let (j3, w3) = lane(3);
        let b0 = vertex_fixed::<W, SCALE, H>(frame, h, j0, w0, r[0]);
        let b1 = vertex_fixed::<W, SCALE, H>(frame, h, j1, w1, r[1]);
        let b2 = vertex_fixed::<W, SCALE, H>(frame, h, j2, w2, r[2]);
        let b3 = vertex_fixed::<W, SCALE, H>(frame, h, j3, w3, r[3]);
        let q = apply4(
            [b0.0, b1.0, b2.0, b3.0],
            [b0.1, b1.1, b2.1, b3.1],
            [b0.2, b1.2, b2.2, b3.2],
        );
        *o = q.map(Vec3::from);
    }
    let tail = j4
        .remainder()
        .chunks_exact(W)
        .zip(w4.remainder().chunks_exact(W))
        .zip(r4.remainder())
        .zip(o4.into_remainder());
    for (((j, w), p), o) in tail {
        let (re, du, sc) = vertex_fixed::<W, SCALE, H>(frame, h, j, w, *p);
        *o = Vec3::from(apply(re, du, sc));
    }
}

/// Skins the positions of one chunk of a variable-width (CSR) layout with one frame:
/// `offsets` has one more entry than `rest` and indexes the full arrays, of which
/// `joints`/`weights` start at `base`; each row has its pivot first.
pub(crate) fn skin_sparse(
    frame: &Frame<'_>,
    offsets: &[u32],
    base: usize,
    joints: &[u32],
    weights: &[f32],
    rest: &[Vec3],
    out: &mut [Vec3],
) {
    // With AVX2 + FMA, blocks of eight vertices go through the SIMD kernel; the rest (or
    // everything, on other CPUs) through the portable loop below.
    use super::simd::dqs_sparse as simd;
    let done = match (frame.aligned, frame.signs) {
        (true, _) => simd(frame, Aligned, offsets, base, joints, weights, rest, out),
        (false, Some(signs)) => {
            let h = table(signs, frame);
            simd(frame, h, offsets, base, joints, weights, rest, out)
        }
        (false, None) => {
            let h = Dot { pivot: Vec4::ZERO };
            simd(frame, h, offsets, base, joints, weights, rest, out)
        }
    };
    let (offsets, rest, out) = (&offsets[done..], &rest[done..], &mut out[done..]);
    let h_table = frame.signs.map(|s| table(s, frame));
    for ((w2, p), o) in offsets.windows(2).zip(rest).zip(out) {
        let (a, b) = (w2[0] as usize - base, w2[1] as usize - base);
        let (Some(js), Some(ws)) = (joints.get(a..b), weights.get(a..b)) else {
            continue;
        };
        let Some(&pivot) = js.first() else {
            *o = *p;
            continue;
        };
        let pv = Vec3A::from(*p);
        let mut real = Vec4::ZERO;
        let mut dual = Vec4::ZERO;
        let mut s = Sym3::ZERO;
        let dq = frame.dq;
        let pivot_real = dq[pivot as usize].real;
        let row = h_table.map(|t| t.for_pivot(dq, pivot as usize));
        for (&j, &w) in js.iter().zip(ws) {
            let d = &dq[j as usize];
            if frame.has_scale {
                s.add_scaled(&d.scale, Vec4::splat(w));
            }
            let sign = match row {
                _ if frame.aligned => 1.0,
                Some(t) => t.sign(d, j as usize),
                None => sign_of(d.real, pivot_real),
            };
            real += d.real * (w * sign);
            dual += d.dual * (w * sign);
        }
        let scaled = if frame.has_scale { s.mul_vec3a(pv) } else { pv };
        *o = Vec3::from(apply(real, dual, scaled));
    }
}

/// Dual quaternion skinning of one frame, UsdSkel's `dualQuaternion` method (see the
/// module docs for the exact rules).
///
/// Same inputs and outputs as [`crate::LbsJob`], plus the caller-owned [`DqsPalette`] the
/// per-joint dual quaternions are computed into.
pub struct DqsJob<'a> {
    /// Skinning matrix per palette joint (see [`crate::skinning_matrices`]).
    pub skin_matrices: &'a [Mat4],
    /// Influences per vertex; joint values index `skin_matrices`.
    pub influences: &'a Influences,
    /// Bind-space positions, one per vertex.
    pub rest_positions: &'a [Vec3],
    /// Bind-space unit normals, one per vertex (optional).
    pub rest_normals: Option<&'a [Vec3]>,
    /// Output: skinned model-space positions (same length as `rest_positions`).
    pub out_positions: &'a mut [Vec3],
    /// Output: skinned unit normals (required when `rest_normals` is given).
    pub out_normals: Option<&'a mut [Vec3]>,
    /// Scratch with room for at least `skin_matrices.len()` joints and one frame.
    pub palette: &'a mut DqsPalette,
}

impl DqsJob<'_> {
    /// Checks every length, every influence's joint index and the palette's capacity.
    ///
    /// # Errors
    /// [`EvalError::Length`] or [`EvalError::Index`].
    pub fn validate(&self) -> Result<(), EvalError> {
        check_lengths(
            self.influences,
            self.rest_positions,
            self.rest_normals,
            self.out_positions.len(),
            self.out_normals.as_deref().map(<[Vec3]>::len),
        )?;
        check_palette(self.influences, self.skin_matrices.len())?;
        if self.palette.joint_capacity() < self.skin_matrices.len()
            || self.palette.frame_capacity() < 1
        {
            return Err(EvalError::Length {
                what: "DqsPalette joints",
                expected: self.skin_matrices.len(),
                found: self.palette.joint_capacity(),
            });
        }
        Ok(())
    }

    /// Runs the job on the calling thread. Allocates nothing.
    ///
    /// # Errors
    /// As [`DqsJob::validate`], which it calls first.
    pub fn run(&mut self) -> Result<(), EvalError> {
        self.run_with(false)
    }

    /// Runs the job on the current rayon thread pool, in chunks of vertices (serially
    /// below a grain size, like UsdSkel). Allocates nothing itself.
    ///
    /// # Errors
    /// As [`DqsJob::validate`], which it calls first.
    pub fn par_run(&mut self) -> Result<(), EvalError> {
        self.run_with(true)
    }

    fn run_with(&mut self, parallel: bool) -> Result<(), EvalError> {
        self.validate()?;
        let joints = self.skin_matrices.len();
        self.palette.prepare(self.skin_matrices, joints, 1)?;
        let frame = self.palette.frame(0);
        let influences = self.influences;
        let rest = self.rest_positions;
        let rest_normals = self.rest_normals;
        let chunk = |start: usize, out: &mut [Vec3], out_n: Option<&mut [Vec3]>| match frame.signs {
            _ if frame.aligned => dqs_rows(
                &frame,
                Aligned,
                influences,
                start,
                rest,
                rest_normals,
                out,
                out_n,
            ),
            Some(s) => dqs_rows(
                &frame,
                table(s, &frame),
                influences,
                start,
                rest,
                rest_normals,
                out,
                out_n,
            ),
            None => dqs_rows(
                &frame,
                Dot { pivot: Vec4::ZERO },
                influences,
                start,
                rest,
                rest_normals,
                out,
                out_n,
            ),
        };
        for_vertex_chunks(
            parallel,
            self.out_positions,
            self.out_normals.as_deref_mut(),
            chunk,
        );
        Ok(())
    }
}

/// [`blend_fixed`] of a CSR row of exactly `W` influences.
#[inline(always)]
fn blend_csr<const W: usize, const SCALE: bool, H: Hemisphere>(
    frame: &Frame<'_>,
    h: H,
    row: &[Influence],
    p: Vec3A,
) -> (Vec4, Vec4, Vec3A) {
    let j: [u32; W] = std::array::from_fn(|k| row.get(k).map_or(0, |i| i.joint));
    let w: [f32; W] = std::array::from_fn(|k| row.get(k).map_or(0.0, |i| i.weight));
    blend_fixed::<W, SCALE, H>(frame, h, &j, &w, pivot_slot(row), p)
}

/// The positions-only loop of [`dqs_rows`], specialized for rows of 1 to 4 influences.
fn dqs_rows_positions<const SCALE: bool, H: Hemisphere>(
    frame: &Frame<'_>,
    h: H,
    influences: &Influences,
    start: usize,
    rest: &[Vec3],
    out: &mut [Vec3],
) {
    for (i, o) in out.iter_mut().enumerate() {
        let v = start + i;
        let (Some(p), row) = (rest.get(v), influences.vertex(v)) else {
            continue;
        };
        if row.iter().all(|inf| inf.weight == 0.0) {
            *o = *p;
            continue;
        }
        let p = Vec3A::from(*p);
        let (real, dual, scaled) = match row.len() {
            1 => blend_csr::<1, SCALE, H>(frame, h, row, p),
            2 => blend_csr::<2, SCALE, H>(frame, h, row, p),
            3 => blend_csr::<3, SCALE, H>(frame, h, row, p),
            4 => blend_csr::<4, SCALE, H>(frame, h, row, p),
            _ => {
                let b = blend_row(frame, h, row, p, false);
                (b.real, b.dual, b.scaled)
            }
        };
        *o = Vec3::from(apply(real, dual, scaled));
    }
}

/// DQS of vertices `start..start + out.len()` read from CSR influences (validated).
#[allow(clippy::too_many_arguments)]
fn dqs_rows<H: Hemisphere>(
    frame: &Frame<'_>,
    h: H,
    influences: &Influences,
    start: usize,
    rest: &[Vec3],
    rest_normals: Option<&[Vec3]>,
    out: &mut [Vec3],
    mut out_normals: Option<&mut [Vec3]>,
) {
    let normals = rest_normals.is_some() && out_normals.is_some();
    if !normals {
        return match frame.has_scale {
            true => dqs_rows_positions::<true, H>(frame, h, influences, start, rest, out),
            false => dqs_rows_positions::<false, H>(frame, h, influences, start, rest, out),
        };
    }
    for (i, o) in out.iter_mut().enumerate() {
        let v = start + i;
        let (Some(p), row) = (rest.get(v), influences.vertex(v)) else {
            continue;
        };
        let rest_n = rest_normals.and_then(|r| r.get(v)).copied();
        let out_n = out_normals.as_deref_mut().and_then(|o| o.get_mut(i));
        if row.iter().all(|inf| inf.weight == 0.0) {
            // rigport's rule: no influence keeps the rest pose.
            *o = *p;
            if let (Some(on), Some(rn)) = (out_n, rest_n) {
                *on = rn;
            }
            continue;
        }
        let b = blend_row(frame, h, row, Vec3A::from(*p), normals);
        *o = Vec3::from(apply(b.real, b.dual, b.scaled));
        if let (Some(on), Some(rn)) = (out_n, rest_n) {
            let n = Vec3A::from(rn);
            let scaled = if frame.has_scale {
                b.normal_scale.mul_vec3a(n)
            } else {
                n
            };
            *on = Vec3::from(rotate_normal(b.real, scaled, n));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Naive scalar reference in `f64`, written from the UsdSkel algorithm with the joint
    /// decomposition given (not computed): rotation, translation and scale/shear per joint.
    fn naive_dqs(joints: &[(DQuat, DVec3, DMat3)], row: &[(usize, f64)], p: DVec3) -> DVec3 {
        let eps = 1e-6;
        let has_scale = joints.iter().any(|(_, _, s)| {
            (*s - DMat3::IDENTITY)
                .abs()
                .to_cols_array()
                .iter()
                .any(|e| *e > eps)
        });
        let mut pivot = 0;
        for (k, (_, w)) in row.iter().enumerate() {
            if row[pivot].1 < *w {
                pivot = k;
            }
        }
        let qp = joints[row[pivot].0].0;
        let (mut real, mut dual) = ([0.0f64; 4], [0.0f64; 4]);
        let mut scaled = DVec3::ZERO;
        for &(j, w) in row {
            let (q, t, s) = joints[j];
            if has_scale {
                scaled += (s * p) * w;
            }
            let d = DQuat::from_xyzw(t.x, t.y, t.z, 0.0) * q * 0.5;
            let w = if q.dot(qp) < 0.0 { -w } else { w };
            for (acc, x) in real.iter_mut().zip(q.to_array()) {
                *acc += x * w;
            }
            for (acc, x) in dual.iter_mut().zip(d.to_array()) {
                *acc += x * w;
            }
        }
        if !has_scale {
            scaled = p;
        }
        let r = DQuat::from_array(real);
        let d = DQuat::from_array(dual);
        let len = r.length();
        let (r, d) = (r * (1.0 / len), d * (1.0 / len));
        let t = d * r.conjugate() * 2.0;
        r * scaled + DVec3::new(t.x, t.y, t.z)
    }

    fn mat4(q: DQuat, t: DVec3, s: DMat3) -> Mat4 {
        let a = DMat3::from_quat(q) * s;
        Mat4::from_cols(
            a.x_axis.as_vec3().extend(0.0),
            a.y_axis.as_vec3().extend(0.0),
            a.z_axis.as_vec3().extend(0.0),
            t.as_vec3().extend(1.0),
        )
    }

    /// A rotation, translation and symmetric positive definite scale/shear.
    fn joint(max_stretch: f64) -> impl Strategy<Value = (DQuat, DVec3, DMat3)> {
        (
            prop::array::uniform3(-3.2f64..3.2),
            prop::array::uniform3(-2.0f64..2.0),
            prop::array::uniform3(-max_stretch..=max_stretch),
            prop::array::uniform3(-1.0f64..1.0),
        )
            .prop_map(|(r, t, st, sr)| {
                let q = DQuat::from_euler(glam::EulerRot::XYZ, r[0], r[1], r[2]);
                let frame = DMat3::from_euler(glam::EulerRot::ZYX, sr[0], sr[1], sr[2]);
                let diag = DMat3::from_diagonal(DVec3::new(1.0 + st[0], 1.0 + st[1], 1.0 + st[2]));
                (q, DVec3::from(t), frame * diag * frame.transpose())
            })
    }

    fn influences(rows: &[Vec<(usize, f64)>]) -> Influences {
        Influences::from_rows(rows.iter().map(|r| {
            r.iter()
                .map(|&(j, w)| Influence {
                    joint: j as u32,
                    weight: w as f32,
                })
                .collect::<Vec<_>>()
        }))
    }

    fn run_dqs(skin: &[Mat4], infl: &Influences, rest: &[Vec3], parallel: bool) -> Vec<Vec3> {
        let mut out = vec![Vec3::ZERO; rest.len()];
        let mut palette = DqsPalette::new(skin.len(), 1);
        let mut job = DqsJob {
            skin_matrices: skin,
            influences: infl,
            rest_positions: rest,
            rest_normals: None,
            out_positions: &mut out,
            out_normals: None,
            palette: &mut palette,
        };
        if parallel {
            job.par_run().unwrap();
        } else {
            job.run().unwrap();
        }
        out
    }

    fn rows_strategy(joints: usize) -> impl Strategy<Value = Vec<Vec<(usize, f64)>>> {
        prop::collection::vec(
            prop::collection::vec((0..joints, 0.01f64..1.0), 1..7),
            1..40,
        )
        .prop_map(|rows| {
            rows.into_iter()
                .map(|r| {
                    let sum: f64 = r.iter().map(|x| x.1).sum();
                    r.into_iter().map(|(j, w)| (j, w / sum)).collect()
                })
                .collect()
        })
    }

    proptest! {
        #[test]
        fn decompose_recovers_rotation_and_scale((q, t, s) in joint(0.5)) {
            let m = mat4(q, t, s);
            let d = decompose(&m).unwrap();
            let back = Mat4::from_rotation_translation(d.rigid.real, d.rigid.translation())
                * Mat4::from_mat3(d.scale);
            prop_assert!(back.abs_diff_eq(m, 1e-5), "{back} vs {m}");
            let (dq, _, ds) = decompose_f64(&m).unwrap();
            prop_assert!(dq.dot(q).abs() > 1.0 - 1e-6, "rotation {dq} vs {q}");
            prop_assert!((ds - s).abs().to_cols_array().iter().all(|e| *e < 1e-5), "scale {ds} vs {s}");
        }

        #[test]
        fn fast_equals_naive_reference(
            joints in prop::collection::vec(joint(0.3), 1..9),
            rows in rows_strategy(8),
            pts in prop::collection::vec(prop::array::uniform3(-2.0f32..2.0), 40),
        ) {
            let n = joints.len();
            let rows: Vec<Vec<(usize, f64)>> = rows.into_iter().map(|r| r.into_iter().map(|(j, w)| (j % n, w)).collect()).collect();
            let skin: Vec<Mat4> = joints.iter().map(|&(q, t, s)| mat4(q, t, s)).collect();
            // The reference gets the f32 matrices' exact decomposition: re-derive it from
            // what the job sees, so only the blend is compared.
            let exact: Vec<(DQuat, DVec3, DMat3)> = skin.iter().map(|m| decompose_f64(m).unwrap()).collect();
            let infl = influences(&rows);
            let rest: Vec<Vec3> = pts[..rows.len()].iter().map(|p| Vec3::from(*p)).collect();
            let serial = run_dqs(&skin, &infl, &rest, false);
            for (v, row) in rows.iter().enumerate() {
                let expect = naive_dqs(&exact, row, rest[v].as_dvec3()).as_vec3();
                prop_assert!(serial[v].abs_diff_eq(expect, 2e-5), "vertex {v}: {} vs {expect}", serial[v]);
            }
            // The fixed-width fast path agrees with the row path.
            let packed = crate::skinning::PackedInfluences::new(&infl);
            let mut fast = vec![Vec3::ZERO; rest.len()];
            crate::skinning::skin_frames(crate::skinning::SkinningMethod::Dqs, &packed, &rest, &skin, &mut fast).unwrap();
            for (v, (a, b)) in fast.iter().zip(&serial).enumerate() {
                prop_assert!(a.abs_diff_eq(*b, 1e-5), "vertex {v}: {a} vs {b}");
            }
        }

        #[test]
        fn single_influence_is_that_joints_matrix(
            joints in prop::collection::vec(joint(0.5), 1..6),
            pts in prop::collection::vec(prop::array::uniform3(-2.0f32..2.0), 1..30),
        ) {
            let skin: Vec<Mat4> = joints.iter().map(|&(q, t, s)| mat4(q, t, s)).collect();
            let n = skin.len();
            let rows: Vec<Vec<(usize, f64)>> = (0..pts.len()).map(|v| vec![(v % n, 1.0)]).collect();
            let rest: Vec<Vec3> = pts.iter().map(|p| Vec3::from(*p)).collect();
            let out = run_dqs(&skin, &influences(&rows), &rest, false);
            for (v, p) in rest.iter().enumerate() {
                let expect = skin[v % n].transform_point3(*p);
                prop_assert!(out[v].abs_diff_eq(expect, 1e-5), "vertex {v}: {} vs {expect}", out[v]);
            }
        }

        #[test]
        fn rigid_blend_of_one_transform_is_exact(
            (q, t, _) in joint(0.0),
            weights in prop::collection::vec(0.05f64..1.0, 1..6),
            p in prop::array::uniform3(-3.0f32..3.0),
        ) {
            // Several palette entries with the same rigid transform (two of them with the
            // quaternion's sign flipped): any blend must be that transform exactly.
            let m = mat4(q, t, DMat3::IDENTITY);
            let skin = vec![m; weights.len()];
            let sum: f64 = weights.iter().sum();
            let row: Vec<(usize, f64)> = weights.iter().enumerate().map(|(j, w)| (j, w / sum)).collect();
            let rest = [Vec3::from(p)];
            let out = run_dqs(&skin, &influences(&[row]), &rest, false);
            let expect = m.transform_point3(rest[0]);
            prop_assert!(out[0].abs_diff_eq(expect, 1e-5), "{} vs {expect}", out[0]);
        }

        #[test]
        fn normalization_is_idempotent(
            r in prop::array::uniform4(-2.0f32..2.0),
            d in prop::array::uniform4(-2.0f32..2.0),
        ) {
            let dq = DualQuat { real: Quat::from_array(r), dual: Quat::from_array(d) };
            let once = dq.normalized();
            let twice = once.normalized();
            prop_assert!(Vec4::from(once.real).abs_diff_eq(Vec4::from(twice.real), 1e-6));
            prop_assert!(Vec4::from(once.dual).abs_diff_eq(Vec4::from(twice.dual), 1e-5));
            prop_assert!((Vec4::from(once.real).length() - 1.0).abs() < 1e-5 || once == DualQuat::IDENTITY);
        }
    }

    /// A little-endian `f4`/`i4` `.npy` array (numpy's `lib/format.py`, version 1.0).
    fn read_npy(path: &std::path::Path) -> (Vec<usize>, Vec<f32>) {
        let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        assert_eq!(&bytes[..6], b"\x93NUMPY", "{}", path.display());
        let (len_at, len_size) = if bytes[6] == 1 { (8, 2) } else { (8, 4) };
        let mut hl = [0u8; 4];
        hl[..len_size].copy_from_slice(&bytes[len_at..len_at + len_size]);
        let header_end = len_at + len_size + u32::from_le_bytes(hl) as usize;
        let header = std::str::from_utf8(&bytes[len_at + len_size..header_end]).unwrap();
        assert!(header.contains("'fortran_order': False"), "{header}");
        let shape_txt = header
            .split("'shape': (")
            .nth(1)
            .unwrap()
            .split(')')
            .next()
            .unwrap();
        let shape: Vec<usize> = shape_txt
            .split(',')
            .filter(|s| !s.trim().is_empty())
            .map(|s| s.trim().parse().unwrap())
            .collect();
        let data = &bytes[header_end..];
        let values = data.chunks_exact(4).map(|c| {
            let b = [c[0], c[1], c[2], c[3]];
            if header.contains("'<f4'") {
                f32::from_le_bytes(b)
            } else if header.contains("'<i4'") {
                i32::from_le_bytes(b) as f32
            } else {
                panic!("dtype in {header}")
            }
        });
        (shape, values.collect())
    }

    /// Writes a `<f4` `.npy` array.
    fn write_npy(path: &std::path::Path, shape: &[usize], data: &[f32]) {
        let dims: Vec<String> = shape.iter().map(|d| d.to_string()).collect();
        let mut header = format!(
            "{{'descr': '<f4', 'fortran_order': False, 'shape': ({},), }}",
            dims.join(", ")
        );
        while (10 + header.len() + 1) % 64 != 0 {
            header.push(' ');
        }
        header.push('\n');
        let mut bytes = b"\x93NUMPY\x01\x00".to_vec();
        bytes.extend_from_slice(&(header.len() as u16).to_le_bytes());
        bytes.extend_from_slice(header.as_bytes());
        bytes.extend(data.iter().flat_map(|x| x.to_le_bytes()));
        std::fs::write(path, bytes).unwrap();
    }

    /// Pixar's `testUsdSkelBakeSkinning` (LBS and DQS inputs with baked baselines):
    /// `tools/check_skinning.py --export-usd` reads the inputs with usd-core, rigport skins
    /// them, and the result must match Pixar's baseline and `UsdSkel.SkinPoints` within
    /// 1e-5 of the bounding-box diagonal (`check_skinning.py`'s default tolerance).
    #[test]
    fn pixar_bake_skinning_baselines() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
        let case = root.join(
            "../shared/corpus/6_usd/openusd_usdskel__PixarAnimationStudios/testUsdSkelBakeSkinning",
        );
        let ci = std::env::var("CI").is_ok_and(|v| !v.is_empty());
        if !case.is_dir() {
            assert!(
                !ci,
                "corpus case {} is absent and CI is set",
                case.display()
            );
            eprintln!("SKIPPED: corpus case {} is absent", case.display());
            return;
        }
        let python = std::env::var_os("RIGPORT_PYTHON")
            .map(std::path::PathBuf::from)
            .unwrap_or_else(|| root.join("tools/.venv/bin/python"));
        if !python.exists() {
            assert!(
                !ci,
                "no Python with usd-core at {} and CI is set",
                python.display()
            );
            eprintln!(
                "SKIPPED: no Python with usd-core at {} (run tools/setup.sh)",
                python.display()
            );
            return;
        }
        let checker = root.join("tools/check_skinning.py");
        for (name, method) in [
            ("lbs", crate::skinning::SkinningMethod::Lbs),
            ("dqs", crate::skinning::SkinningMethod::Dqs),
        ] {
            let dir =
                std::env::temp_dir().join(format!("rigport-pixar-{}-{name}", std::process::id()));
            let export = std::process::Command::new(&python)
                .arg(&checker)
                .arg("--export-usd")
                .arg(case.join(format!("{name}.usda")))
                .arg("--baseline")
                .arg(case.join(format!("baseline/{name}.baked.usda")))
                .arg("--out")
                .arg(&dir)
                .output()
                .unwrap();
            assert!(
                export.status.success(),
                "export of {name}.usda failed: {}{}",
                String::from_utf8_lossy(&export.stdout),
                String::from_utf8_lossy(&export.stderr)
            );
            let (rshape, rest) = read_npy(&dir.join("rest_positions.npy"));
            let (pshape, baseline) = read_npy(&dir.join("positions.npy"));
            let (mshape, mats) = read_npy(&dir.join("skin_matrices.npy"));
            let (ishape, joints) = read_npy(&dir.join("influence_joints.npy"));
            let (_, weights) = read_npy(&dir.join("influence_weights.npy"));
            let (v, f, j, k) = (rshape[0], pshape[0], mshape[1], ishape[1]);
            let rest: Vec<Vec3> = rest.chunks_exact(3).map(Vec3::from_slice).collect();
            // Row-major storage of column-vector matrices: glam's column-major reader gives
            // the transpose.
            let mats: Vec<Mat4> = mats
                .chunks_exact(16)
                .map(|m| Mat4::from_cols_slice(m).transpose())
                .collect();
            let rows: Vec<Vec<(usize, f64)>> = (0..v)
                .map(|i| {
                    (0..k)
                        .map(|c| (joints[i * k + c] as usize, weights[i * k + c] as f64))
                        .collect()
                })
                .collect();
            let infl = influences(&rows);
            let packed = crate::skinning::PackedInfluences::new(&infl);
            let mut out = vec![Vec3::ZERO; f * v];
            crate::skinning::skin_frames(method, &packed, &rest, &mats, &mut out).unwrap();
            // The one-frame jobs on the CSR rows agree with the packed path.
            let mut palette = DqsPalette::new(j, 1);
            for frame in 0..f {
                let mut one = vec![Vec3::ZERO; v];
                let skin = &mats[frame * j..(frame + 1) * j];
                match method {
                    crate::skinning::SkinningMethod::Lbs => crate::LbsJob {
                        skin_matrices: skin,
                        influences: &infl,
                        rest_positions: &rest,
                        rest_normals: None,
                        out_positions: &mut one,
                        out_normals: None,
                    }
                    .run()
                    .unwrap(),
                    crate::skinning::SkinningMethod::Dqs => DqsJob {
                        skin_matrices: skin,
                        influences: &infl,
                        rest_positions: &rest,
                        rest_normals: None,
                        out_positions: &mut one,
                        out_normals: None,
                        palette: &mut palette,
                    }
                    .run()
                    .unwrap(),
                }
                for (a, b) in one.iter().zip(&out[frame * v..(frame + 1) * v]) {
                    assert!(a.abs_diff_eq(*b, 1e-6), "{name} frame {frame}: {a} vs {b}");
                }
            }
            let mut worst = 0.0f32;
            for frame in 0..f {
                let base: Vec<Vec3> = baseline[frame * v * 3..(frame + 1) * v * 3]
                    .chunks_exact(3)
                    .map(Vec3::from_slice)
                    .collect();
                let (lo, hi) = base.iter().fold((Vec3::MAX, Vec3::MIN), |(lo, hi), p| {
                    (lo.min(*p), hi.max(*p))
                });
                let diag = (hi - lo).length();
                for (a, b) in out[frame * v..(frame + 1) * v].iter().zip(&base) {
                    worst = worst.max(a.distance(*b) / diag);
                }
            }
            eprintln!("{name}: {f} frames x {v} points, max deviation from Pixar's baseline {worst:.2e} of the diagonal");
            assert!(worst <= 1e-5, "{name}: {worst}");
            let flat: Vec<f32> = out.iter().flat_map(|p| p.to_array()).collect();
            write_npy(&dir.join("positions.npy"), &pshape, &flat);
            let check = std::process::Command::new(&python)
                .arg(&checker)
                .arg(&dir)
                .arg("--quiet")
                .output()
                .unwrap();
            let report = String::from_utf8_lossy(&check.stdout);
            eprintln!("{report}");
            assert_eq!(
                check.status.code(),
                Some(0),
                "{name}: {report}{}",
                String::from_utf8_lossy(&check.stderr)
            );
            std::fs::remove_dir_all(&dir).unwrap();
        }
    }

    #[test]
    fn hemisphere_follows_the_heaviest_joint() {
        // Two joints rotated +170° and -170° about Z are 20° apart through 180°: an even
        // blend is the 180° rotation (the short way round), never the identity.
        let a = Mat4::from_rotation_z(170f32.to_radians());
        let b = Mat4::from_rotation_z(-170f32.to_radians());
        let infl = Influences::from_rows([[
            Influence {
                joint: 0,
                weight: 0.5,
            },
            Influence {
                joint: 1,
                weight: 0.5,
            },
        ]]);
        let out = run_dqs(&[a, b], &infl, &[Vec3::X], false);
        assert!(out[0].abs_diff_eq(-Vec3::X, 1e-5), "{}", out[0]);
        // 70/30 towards +170°: 170 + 0.3 * 20 = 176° (blended along the short arc).
        let infl = Influences::from_rows([[
            Influence {
                joint: 0,
                weight: 0.7,
            },
            Influence {
                joint: 1,
                weight: 0.3,
            },
        ]]);
        let out = run_dqs(&[a, b], &infl, &[Vec3::X], false);
        let angle = out[0].y.atan2(out[0].x).to_degrees();
        assert!((angle - 176.0).abs() < 0.5, "angle {angle}");
    }

    #[test]
    fn opposite_hemispheres_are_flipped_to_the_pivot() {
        // Quaternions as the decomposition extracts them (largest component positive) with
        // a negative dot product: the lighter one must enter the blend negated.
        let qa = Quat::from_rotation_z(170f32.to_radians());
        let qb = Quat::from_xyzw(0.8, 0.0, -0.5, 0.33).normalize();
        let (da, db) = (
            decompose(&Mat4::from_quat(qa)).unwrap().rigid.real,
            decompose(&Mat4::from_quat(qb)).unwrap().rigid.real,
        );
        assert!(da.dot(db) < -0.3, "{da} {db}");
        let infl = Influences::from_rows([[
            Influence {
                joint: 0,
                weight: 0.4,
            },
            Influence {
                joint: 1,
                weight: 0.6,
            },
        ]]);
        let p = Vec3::new(0.3, -0.7, 0.5);
        let out = run_dqs(
            &[Mat4::from_quat(qa), Mat4::from_quat(qb)],
            &infl,
            &[p],
            false,
        );
        // Pivot = joint 1 (0.6): joint 0 is flipped.
        let aligned = (db * 0.6 - da * 0.4).normalize() * p;
        let unaligned = (db * 0.6 + da * 0.4).normalize() * p;
        assert!(aligned.distance(unaligned) > 0.1);
        assert!(out[0].abs_diff_eq(aligned, 1e-5), "{} vs {aligned}", out[0]);
    }

    #[test]
    fn frames_in_blocks_of_the_palette_capacity_match_one_frame_jobs() {
        use crate::skinning::{PackedInfluences, SkinFramesJob, SkinningMethod};
        let joints = 6;
        let frames = 5;
        let mats: Vec<Mat4> = (0..joints * frames)
            .map(|i| {
                let f = i as f32;
                Mat4::from_scale_rotation_translation(
                    Vec3::new(1.0 + 0.01 * (f % 3.0), 1.0, 0.98),
                    Quat::from_euler(glam::EulerRot::XYZ, 0.3 * f, -0.2 * f, 0.7 * f),
                    Vec3::new(f.sin(), f.cos(), 0.1 * f),
                )
            })
            .collect();
        let rows: Vec<Vec<(usize, f64)>> = (0..50)
            .map(|v| {
                (0..1 + v % 5)
                    .map(|k| ((v + 2 * k) % joints, 1.0 + k as f64))
                    .collect()
            })
            .collect();
        let infl = influences(&rows);
        let rest: Vec<Vec3> = (0..50)
            .map(|v| Vec3::new(v as f32 * 0.1, 1.0, -0.5))
            .collect();
        let packed = PackedInfluences::new(&infl);
        let mut out = vec![Vec3::ZERO; rest.len() * frames];
        // Room for two frames: the job prepares and skins frames 0-1, 2-3, then 4.
        let mut palette = DqsPalette::new(joints, 2);
        SkinFramesJob {
            method: SkinningMethod::Dqs,
            influences: &packed,
            rest_positions: &rest,
            frame_skin_matrices: &mats,
            out_positions: &mut out,
            palette: &mut palette,
        }
        .run()
        .unwrap();
        for f in 0..frames {
            let one = run_dqs(&mats[f * joints..(f + 1) * joints], &infl, &rest, false);
            for (v, (a, b)) in out[f * rest.len()..(f + 1) * rest.len()]
                .iter()
                .zip(&one)
                .enumerate()
            {
                // The packed path sums the pivot first: float rounding only (the weights
                // here are not normalized, so the points reach |p| ~ 60).
                assert!(
                    a.abs_diff_eq(*b, 1e-6 * (1.0 + b.length())),
                    "frame {f} vertex {v}: {a} vs {b}"
                );
            }
        }
    }

    #[test]
    fn singular_joint_and_unweighted_vertex() {
        let zero = Mat4::from_scale(Vec3::splat(1e-5));
        let t = Mat4::from_translation(Vec3::new(1.0, 2.0, 3.0));
        let infl = Influences::from_rows([
            vec![
                Influence {
                    joint: 0,
                    weight: 0.5,
                },
                Influence {
                    joint: 1,
                    weight: 0.5,
                },
            ],
            vec![],
            vec![Influence {
                joint: 0,
                weight: 0.0,
            }],
        ]);
        let rest = [
            Vec3::ONE,
            Vec3::new(4.0, 5.0, 6.0),
            Vec3::new(7.0, 8.0, 9.0),
        ];
        let out = run_dqs(&[t, zero], &infl, &rest, false);
        // The singular joint contributes no rotation or translation, and its weight
        // times the identity to the scale blend (which is on: it "scales"), so the
        // point is t applied to 0.5 p + 0.5 p.
        assert!(
            out[0].abs_diff_eq(Vec3::ONE + Vec3::new(1.0, 2.0, 3.0), 1e-6),
            "{}",
            out[0]
        );
        assert_eq!(out[1], rest[1]);
        assert_eq!(out[2], rest[2]);
        assert!(decompose(&zero).is_none());
    }

    #[test]
    fn normals_rotate_with_the_blend() {
        let r = Mat4::from_rotation_y(0.8) * Mat4::from_scale(Vec3::new(2.0, 1.0, 1.0));
        let infl = Influences::from_rows([[Influence {
            joint: 0,
            weight: 1.0,
        }]]);
        let rest_n = [Vec3::new(1.0, 1.0, 0.0).normalize()];
        let mut out = [Vec3::ZERO];
        let mut out_n = [Vec3::ZERO];
        let mut palette = DqsPalette::new(1, 1);
        DqsJob {
            skin_matrices: &[r],
            influences: &infl,
            rest_positions: &[Vec3::ZERO],
            rest_normals: Some(&rest_n),
            out_positions: &mut out,
            out_normals: Some(&mut out_n),
            palette: &mut palette,
        }
        .run()
        .unwrap();
        // A single joint's normal matrix: the inverse transpose of its 3x3.
        let a = Mat3::from_mat4(r);
        let expect = (a.inverse().transpose() * rest_n[0]).normalize();
        assert!(
            out_n[0].abs_diff_eq(expect, 1e-5),
            "{} vs {expect}",
            out_n[0]
        );
    }

    #[test]
    fn parallel_equals_serial_and_palette_is_checked() {
        let skin: Vec<Mat4> = (0..5)
            .map(|j| {
                Mat4::from_rotation_translation(
                    Quat::from_rotation_x(j as f32),
                    Vec3::splat(j as f32),
                )
            })
            .collect();
        let n = 3 * crate::skinning::common::GRAIN + 17;
        let infl = Influences::from_rows((0..n).map(|v| {
            [
                Influence {
                    joint: (v % 5) as u32,
                    weight: 0.75,
                },
                Influence {
                    joint: ((v / 5) % 5) as u32,
                    weight: 0.25,
                },
            ]
        }));
        let rest: Vec<Vec3> = (0..n)
            .map(|v| Vec3::new(v as f32 * 1e-3, 1.0, -1.0))
            .collect();
        assert_eq!(
            run_dqs(&skin, &infl, &rest, true),
            run_dqs(&skin, &infl, &rest, false)
        );
        let mut out = vec![Vec3::ZERO; n];
        let mut small = DqsPalette::new(4, 1);
        let job = DqsJob {
            skin_matrices: &skin,
            influences: &infl,
            rest_positions: &rest,
            rest_normals: None,
            out_positions: &mut out,
            out_normals: None,
            palette: &mut small,
        };
        assert!(matches!(
            job.validate(),
            Err(EvalError::Length {
                what: "DqsPalette joints",
                ..
            })
        ));
    }
}

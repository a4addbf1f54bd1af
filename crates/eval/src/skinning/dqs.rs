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

use glam::{DMat3, DQuat, Mat4, Vec3, Vec3A, Vec4};
use rigport_model::{Influence, Influences};

use super::common::{
    check_lengths, check_palette, for_vertex_chunks, Frame, Hemisphere, JointDq, Sym3,
    MIN_REAL_LENGTH,
};
use super::simd;
use crate::EvalError;

mod decompose;
mod job;

use decompose::decompose_f64;
pub use decompose::{decompose, DualQuat, JointDecomposition};
pub use job::DqsJob;

/// UsdSkel's `hasJointScale` tolerance: `GfIsClose(jointScale, identity, 1e-6)`.
const SCALE_TOLERANCE: f64 = 1e-6;

/// The per-vertex hemisphere test reads a precomputed sign table (palette x palette signs
/// per frame) when the palette has at most this many joints, else it takes dot products.
const SIGN_TABLE_MAX_JOINTS: usize = 128;

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

#[cfg(test)]
mod tests;

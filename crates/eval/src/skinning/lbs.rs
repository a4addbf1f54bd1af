//! Linear blend skinning: the one-frame [`LbsJob`] over CSR rows and the fixed-width and
//! sparse loops of the multi-frame path.

use glam::{Mat4, Vec3, Vec3A};
use rigport_model::{Influence, Influences};

use crate::EvalError;

use super::common::{check_lengths, check_palette, for_vertex_chunks};

/// Whether a row has no non-zero weight (rigport keeps such vertices at rest).
#[inline(always)]
fn unweighted(row: &[Influence]) -> bool {
    row.iter().all(|i| i.weight == 0.0)
}

/// `Σ wₖ M[jₖ]` over `W` influences; joint indices are valid (checked beforehand).
#[inline(always)]
fn lbs_blend<const W: usize>(mats: &[Mat4], joints: &[u32; W], weights: &[f32; W]) -> Mat4 {
    let m = &mats[joints[0] as usize];
    let w = weights[0];
    let mut b = Mat4::from_cols(m.x_axis * w, m.y_axis * w, m.z_axis * w, m.w_axis * w);
    for k in 1..W {
        let m = &mats[joints[k] as usize];
        let w = weights[k];
        b.x_axis += m.x_axis * w;
        b.y_axis += m.y_axis * w;
        b.z_axis += m.z_axis * w;
        b.w_axis += m.w_axis * w;
    }
    b
}

/// `Σ wₖ M[jₖ]` over a row of any length.
#[inline(always)]
fn lbs_blend_row(mats: &[Mat4], row: &[Influence]) -> Mat4 {
    let arrays = |r: &[Influence]| -> ([u32; 4], [f32; 4]) {
        let mut j = [0; 4];
        let mut w = [0.0; 4];
        for (k, inf) in r.iter().take(4).enumerate() {
            j[k] = inf.joint;
            w[k] = inf.weight;
        }
        (j, w)
    };
    let (j, w) = arrays(row);
    match row.len() {
        1 => lbs_blend::<1>(mats, &[j[0]], &[w[0]]),
        2 => lbs_blend::<2>(mats, &[j[0], j[1]], &[w[0], w[1]]),
        3 => lbs_blend::<3>(mats, &[j[0], j[1], j[2]], &[w[0], w[1], w[2]]),
        4 => lbs_blend::<4>(mats, &j, &w),
        _ => {
            let mut b = Mat4::ZERO;
            for inf in row {
                let m = &mats[inf.joint as usize];
                b.x_axis += m.x_axis * inf.weight;
                b.y_axis += m.y_axis * inf.weight;
                b.z_axis += m.z_axis * inf.weight;
                b.w_axis += m.w_axis * inf.weight;
            }
            b
        }
    }
}

/// The blended matrix applied to a point (affine: the bottom row is not needed).
#[inline(always)]
fn lbs_apply(b: &Mat4, p: Vec3) -> Vec3 {
    (b.x_axis * p.x + b.y_axis * p.y + b.z_axis * p.z + b.w_axis).truncate()
}

/// The blended matrix's cofactor (`det · A⁻ᵀ`) applied to a normal, renormalized: the
/// normal of the skinned surface whatever the blend's scale, shear or mirroring.
#[inline(always)]
fn lbs_normal(b: &Mat4, n: Vec3) -> Option<Vec3> {
    let (x, y, z) = (
        Vec3A::from(b.x_axis.truncate()),
        Vec3A::from(b.y_axis.truncate()),
        Vec3A::from(b.z_axis.truncate()),
    );
    let c = y.cross(z) * n.x + z.cross(x) * n.y + x.cross(y) * n.z;
    c.try_normalize().map(Vec3::from)
}

/// Linear blend skinning of one frame: `p' = Σ wᵢ · S[jᵢ] · p` for every vertex.
///
/// Weights are used as given (importers and exporters normalize); a vertex with no
/// influence, or only zero weights, keeps its rest position and normal. Normals are
/// transformed by the cofactor of the blended matrix's upper 3x3 (its inverse transpose
/// up to scale) and renormalized; UsdSkel instead blends each joint's inverse transpose,
/// which is the same for rigid and uniformly scaled joints.
pub struct LbsJob<'a> {
    /// Skinning matrix per palette joint (see [`skinning_matrices`](crate::skinning::skinning_matrices)).
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
}

impl LbsJob<'_> {
    /// Checks every length and every influence's joint index.
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
        check_palette(self.influences, self.skin_matrices.len())
    }

    /// Runs the job on the calling thread. Allocates nothing.
    ///
    /// # Errors
    /// As [`LbsJob::validate`], which it calls first.
    pub fn run(&mut self) -> Result<(), EvalError> {
        self.run_with(false)
    }

    /// Runs the job on the current rayon thread pool, in chunks of vertices (serially
    /// below a grain size, like UsdSkel). Allocates nothing itself.
    ///
    /// # Errors
    /// As [`LbsJob::validate`], which it calls first.
    pub fn par_run(&mut self) -> Result<(), EvalError> {
        self.run_with(true)
    }

    fn run_with(&mut self, parallel: bool) -> Result<(), EvalError> {
        self.validate()?;
        let (mats, influences, rest, rest_n) = (
            self.skin_matrices,
            self.influences,
            self.rest_positions,
            self.rest_normals,
        );
        let chunk = |start: usize, out: &mut [Vec3], out_n: Option<&mut [Vec3]>| {
            lbs_rows(mats, influences, start, rest, rest_n, out, out_n);
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

/// LBS of vertices `start..start + out.len()` from CSR rows (validated).
fn lbs_rows(
    mats: &[Mat4],
    influences: &Influences,
    start: usize,
    rest: &[Vec3],
    rest_normals: Option<&[Vec3]>,
    out: &mut [Vec3],
    mut out_normals: Option<&mut [Vec3]>,
) {
    for (i, o) in out.iter_mut().enumerate() {
        let v = start + i;
        let (Some(p), row) = (rest.get(v), influences.vertex(v)) else {
            continue;
        };
        let rest_n = rest_normals.and_then(|r| r.get(v)).copied();
        let out_n = out_normals.as_deref_mut().and_then(|o| o.get_mut(i));
        if unweighted(row) {
            *o = *p;
            if let (Some(on), Some(rn)) = (out_n, rest_n) {
                *on = rn;
            }
            continue;
        }
        let b = lbs_blend_row(mats, row);
        *o = lbs_apply(&b, *p);
        if let (Some(on), Some(rn)) = (out_n, rest_n) {
            *on = lbs_normal(&b, rn).unwrap_or(rn);
        }
    }
}

/// LBS over a fixed-width chunk.
pub(super) fn lbs_fixed<const W: usize>(
    mats: &[Mat4],
    joints: &[u32],
    weights: &[f32],
    rest: &[Vec3],
    out: &mut [Vec3],
) {
    if super::simd::try_lbs_fixed::<W>(mats, joints, weights, rest, out) {
        return;
    }
    for (((j, w), p), o) in joints
        .chunks_exact(W)
        .zip(weights.chunks_exact(W))
        .zip(rest)
        .zip(out)
    {
        let (Ok(j), Ok(w)) = (<&[u32; W]>::try_from(j), <&[f32; W]>::try_from(w)) else {
            continue;
        };
        *o = lbs_apply(&lbs_blend::<W>(mats, j, w), *p);
    }
}

/// LBS over a sparse chunk: `offsets` (one more than `rest`) index the full arrays, of
/// which `joints`/`weights` start at `base`.
pub(super) fn lbs_sparse(
    mats: &[Mat4],
    offsets: &[u32],
    base: usize,
    joints: &[u32],
    weights: &[f32],
    rest: &[Vec3],
    out: &mut [Vec3],
) {
    if super::simd::try_lbs_sparse(mats, offsets, base, joints, weights, rest, out) {
        return;
    }
    for ((o2, p), o) in offsets.windows(2).zip(rest).zip(out) {
        let (a, b) = (o2[0] as usize - base, o2[1] as usize - base);
        let mut m = Mat4::ZERO;
        for (&j, &w) in joints[a..b].iter().zip(&weights[a..b]) {
            let s = &mats[j as usize];
            m.x_axis += s.x_axis * w;
            m.y_axis += s.y_axis * w;
            m.z_axis += s.z_axis * w;
            m.w_axis += s.w_axis * w;
        }
        *o = lbs_apply(&m, *p);
    }
}

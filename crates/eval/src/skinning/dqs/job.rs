//! [`DqsJob`]: dual quaternion skinning of one frame's positions (and normals) from
//! sparse influences, with the blend loops specialized by row width.

use super::*;

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

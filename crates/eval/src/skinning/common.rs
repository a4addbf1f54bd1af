//! What the skinning kernels share: the skinning matrices of a palette, the checks a job
//! runs once (buffer lengths, palette indices), the split of vertices into chunks for
//! rayon, and the per-frame joint data of dual quaternion skinning that both the portable
//! and the SIMD loops read.

use glam::{DMat3, Mat4, Vec3, Vec3A, Vec4};
use rayon::prelude::*;
use rigport_model::{Influences, JointIndex};

use crate::EvalError;

/// Below this many vertices per task, splitting work across threads costs more than it
/// saves (UsdSkel's `_ParallelForN` uses 1000 points; our per-vertex work is smaller).
pub(crate) const GRAIN: usize = 4096;

/// A blended dual quaternion whose real part is shorter than this becomes the identity
/// (`GfDualQuatd::Normalize`'s default `eps`, `GF_MIN_VECTOR_LENGTH`).
pub(crate) const MIN_REAL_LENGTH: f32 = 1e-10;

/// Fills `out[p] = model[palette[p]] * inv_bind[p]`: the skinning matrix of each palette
/// joint, mapping bind-space points to posed model-space points.
///
/// # Errors
/// [`EvalError::Length`] if `inv_bind` or `out` differ in length from `palette`,
/// [`EvalError::Index`] if a palette entry is not in `model`.
pub fn skinning_matrices(
    model: &[Mat4],
    palette: &[JointIndex],
    inv_bind: &[Mat4],
    out: &mut [Mat4],
) -> Result<(), EvalError> {
    for (what, found) in [("inv_bind", inv_bind.len()), ("out", out.len())] {
        if found != palette.len() {
            return Err(EvalError::Length {
                what,
                expected: palette.len(),
                found,
            });
        }
    }
    for (p, joint) in palette.iter().enumerate() {
        let m = model.get(joint.get()).ok_or(EvalError::Index {
            what: "palette",
            index: p,
        })?;
        out[p] = *m * inv_bind[p];
    }
    Ok(())
}

/// Checks the per-vertex buffer lengths of a one-frame job.
pub(crate) fn check_lengths(
    influences: &Influences,
    rest_positions: &[Vec3],
    rest_normals: Option<&[Vec3]>,
    out_positions: usize,
    out_normals: Option<usize>,
) -> Result<(), EvalError> {
    let n = rest_positions.len();
    let mut lengths = [
        ("influences", influences.vertex_count()),
        ("out_positions", out_positions),
        ("rest_normals", n),
        ("out_normals", n),
    ];
    match (rest_normals, out_normals) {
        (Some(r), Some(o)) => {
            lengths[2].1 = r.len();
            lengths[3].1 = o;
        }
        (None, None) => {}
        (Some(_), None) => {
            return Err(EvalError::Length {
                what: "out_normals",
                expected: n,
                found: 0,
            })
        }
        (None, Some(o)) => {
            return Err(EvalError::Length {
                what: "rest_normals",
                expected: o,
                found: 0,
            })
        }
    }
    for (what, found) in lengths {
        if found != n {
            return Err(EvalError::Length {
                what,
                expected: n,
                found,
            });
        }
    }
    Ok(())
}

/// Checks that every influence's joint indexes a palette of `palette_len` matrices.
pub(crate) fn check_palette(influences: &Influences, palette_len: usize) -> Result<(), EvalError> {
    match influences
        .entries()
        .iter()
        .find(|i| i.joint as usize >= palette_len)
    {
        Some(bad) => Err(EvalError::Index {
            what: "influences",
            index: bad.joint as usize,
        }),
        None => Ok(()),
    }
}

/// Runs `chunk(start, positions, normals)` over the output in one call, or over
/// [`GRAIN`]-sized chunks on rayon when `parallel` and the output holds at least two grains
/// (UsdSkel's serial fallback below a grain size).
pub(crate) fn for_vertex_chunks<F>(
    parallel: bool,
    out_positions: &mut [Vec3],
    out_normals: Option<&mut [Vec3]>,
    chunk: F,
) where
    F: Fn(usize, &mut [Vec3], Option<&mut [Vec3]>) + Sync,
{
    if !parallel || out_positions.len() < 2 * GRAIN {
        chunk(0, out_positions, out_normals);
        return;
    }
    match out_normals {
        Some(out_n) => out_positions
            .par_chunks_mut(GRAIN)
            .zip(out_n.par_chunks_mut(GRAIN))
            .enumerate()
            .for_each(|(c, (o, on))| chunk(c * GRAIN, o, Some(on))),
        None => out_positions
            .par_chunks_mut(GRAIN)
            .enumerate()
            .for_each(|(c, o)| chunk(c * GRAIN, o, None)),
    }
}

/// A symmetric 3x3 matrix as two SIMD vectors: the diagonal `(xx, yy, zz, 0)` and the
/// off-diagonal `(xy, xz, yz, 0)`. The scale/shear part `S = Rᵀ A` of a polar
/// decomposition is symmetric (it is `±(AᵀA)^½`), so this halves the per-influence blend
/// of the scale matrices (rounding the `f64` matrix's tiny asymmetry away).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub(crate) struct Sym3 {
    pub(crate) diag: Vec4,
    pub(crate) off: Vec4,
}

impl Sym3 {
    pub(super) const ZERO: Self = Self {
        diag: Vec4::ZERO,
        off: Vec4::ZERO,
    };
    pub(super) const IDENTITY: Self = Self {
        diag: Vec4::new(1.0, 1.0, 1.0, 0.0),
        off: Vec4::ZERO,
    };

    pub(super) fn from_dmat3(m: &DMat3) -> Self {
        let avg = |a: f64, b: f64| (0.5 * (a + b)) as f32;
        Self {
            diag: Vec4::new(m.x_axis.x as f32, m.y_axis.y as f32, m.z_axis.z as f32, 0.0),
            off: Vec4::new(
                avg(m.y_axis.x, m.x_axis.y),
                avg(m.z_axis.x, m.x_axis.z),
                avg(m.z_axis.y, m.y_axis.z),
                0.0,
            ),
        }
    }

    #[inline(always)]
    pub(super) fn add_scaled(&mut self, other: &Self, w: Vec4) {
        self.diag += other.diag * w;
        self.off += other.off * w;
    }

    #[inline(always)]
    pub(super) fn mul_vec3a(&self, p: Vec3A) -> Vec3A {
        use glam::Vec4Swizzles;
        let p = p.extend(0.0);
        let o = self.off;
        let r = self.diag * p + o.xxyw() * p.yxxw() + o.yzzw() * p.zzyw();
        Vec3A::from(r.truncate())
    }
}

/// One joint's data for the per-vertex DQS loop (`f32`, SIMD-friendly; 64 bytes, one
/// cache line).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub(crate) struct JointDq {
    /// Rotation quaternion (xyzw); zero for a singular joint.
    pub(crate) real: Vec4,
    /// Dual part `½ (t, 0) real`; zero for a singular joint.
    pub(crate) dual: Vec4,
    /// Scale/shear `S` (identity for a singular joint).
    pub(crate) scale: Sym3,
}

impl Default for JointDq {
    fn default() -> Self {
        Self {
            real: Vec4::ZERO,
            dual: Vec4::ZERO,
            scale: Sym3::IDENTITY,
        }
    }
}

/// One frame of a [`DqsPalette`].
#[derive(Clone, Copy)]
pub(crate) struct Frame<'a> {
    pub(crate) dq: &'a [JointDq],
    pub(super) normal_scale: &'a [Sym3],
    /// Does any joint have scale or shear (then points are scaled by the blended
    /// scale/shear before the rigid part)?
    pub(crate) has_scale: bool,
    pub(super) aligned: bool,
    pub(super) signs: Option<&'a [f32]>,
}

/// How the per-vertex loop finds the hemisphere sign of joint `j` relative to the pivot.
pub(crate) trait Hemisphere: Copy {
    /// Called once per vertex.
    fn for_pivot(self, dq: &[JointDq], pivot: usize) -> Self;
    /// The sign of joint `j`.
    fn sign(self, dq: &JointDq, j: usize) -> f32;
}

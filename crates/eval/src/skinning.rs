//! Skinning: linear blend skinning (LBS), the method switch, and the fast multi-frame path
//! shared with dual quaternion skinning ([`crate::dqs`]).
//!
//! Two ways in:
//! - [`LbsJob`] and [`crate::dqs::DqsJob`] skin one frame straight from the model's
//!   [`Influences`] (CSR rows of any length), positions and normals; `validate()` checks
//!   every index, `run()` calls it and then allocates nothing.
//! - [`PackedInfluences`] is built once per mesh (setup: indices checked, zero weights
//!   dropped, the heaviest joint first, fixed width when no vertex has more than 8
//!   influences) and drives [`SkinFramesJob`] / [`skin_frames`]: positions for any number
//!   of frames, each vertex's influences read once per block of up to 16 frames, with
//!   specialized loops per width (1..=8) and SIMD-friendly glam types.
//!
//! Both have rayon variants (`par_run`, [`par_skin_frames`]) that split the vertices into
//! chunks and run serially below a grain size, as UsdSkel does.
//!
//! LBS follows UsdSkel's `classicLinear` (`_SkinPointsLBS` in OpenUSD's
//! `pxr/usd/usdSkel/utils.cpp`): `p' = Σ wᵢ Mᵢ p` over the non-zero weights, used as given
//! (not renormalized). rigport's own rule: a vertex with no influence, or only zero
//! weights, keeps its rest position (UsdSkel would move it to the origin).

use glam::{Mat4, Vec3, Vec3A};
use rayon::prelude::*;
use rigport_model::{Influence, Influences, JointIndex};

use crate::dqs::{self, DqsPalette};
use crate::EvalError;

/// Re-exported so callers can size the thread pool the `par_*` entry points run in
/// (`rayon::ThreadPoolBuilder::new().num_threads(2).build()?.install(|| ...)`).
pub use rayon;

/// Below this many vertices per task, splitting work across threads costs more than it
/// saves (UsdSkel's `_ParallelForN` uses 1000 points; our per-vertex work is smaller).
pub(crate) const GRAIN: usize = 4096;

/// Vertices per inner block of the multi-frame path: their influences (at most
/// `LEAF * 8 * 8` bytes) stay in cache while a block of frames is skinned.
const LEAF: usize = 1024;

/// Frames skinned per pass over a block of vertices.
const FRAME_BLOCK: usize = 16;

/// How skinned positions are computed from the joints' skinning matrices: the model's
/// [`rigport_model::SkinningMethod`] (LBS, or DQS as UsdSkel computes it, see
/// [`crate::dqs`]), re-exported under its old path.
pub use rigport_model::SkinningMethod;

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
    /// Skinning matrix per palette joint (see [`skinning_matrices`]).
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

/// How [`PackedInfluences`] stores its rows.
#[derive(Clone, Debug, PartialEq)]
enum Layout {
    /// No vertex has a non-zero weight.
    Empty,
    /// `width` slots per vertex (`joints`, `weights`: `vertex_count * width`); shorter rows
    /// are padded with weight 0 on their first joint (joint 0 for unweighted vertices).
    Fixed { width: usize },
    /// Rows of any length: vertex `v` is `offsets[v]..offsets[v + 1]`.
    Sparse { offsets: Vec<u32> },
}

/// Influences prepared once for the fast skinning paths (ozz's "runtime" form of the
/// model's [`Influences`]): zero weights dropped (UsdSkel skips them), each row's heaviest
/// joint moved first (the DQS pivot, first one on ties), and a fixed-width structure of
/// arrays when no vertex has more than 8 non-zero influences, so the per-vertex loops are
/// specialized per width and read weights as whole vectors.
#[derive(Clone, Debug, PartialEq)]
pub struct PackedInfluences {
    vertex_count: usize,
    joint_bound: usize,
    max_per_vertex: usize,
    layout: Layout,
    joints: Vec<u32>,
    weights: Vec<f32>,
    /// Vertices without a non-zero weight, ascending; they keep their rest position.
    unweighted: Vec<u32>,
}

/// Rows with more non-zero influences than this use the sparse layout.
const MAX_FIXED_WIDTH: usize = 8;

impl PackedInfluences {
    /// Packs `influences` (one pass to size, one to fill).
    pub fn new(influences: &Influences) -> Self {
        let nonzero = |row: &[Influence]| row.iter().filter(|i| i.weight != 0.0).count();
        let max_per_vertex = influences.rows().map(nonzero).max().unwrap_or(0);
        let layout = match max_per_vertex {
            0 => Layout::Empty,
            w if w <= MAX_FIXED_WIDTH => Layout::Fixed { width: w },
            _ => Layout::Sparse {
                offsets: Vec::with_capacity(influences.vertex_count() + 1),
            },
        };
        let mut packed = Self {
            vertex_count: influences.vertex_count(),
            joint_bound: 0,
            max_per_vertex,
            layout,
            joints: Vec::new(),
            weights: Vec::new(),
            unweighted: Vec::new(),
        };
        let slots = match &packed.layout {
            Layout::Empty => 0,
            Layout::Fixed { width } => packed.vertex_count * width,
            Layout::Sparse { .. } => influences.entries().len(),
        };
        packed.joints.reserve_exact(slots);
        packed.weights.reserve_exact(slots);
        if let Layout::Sparse { offsets } = &mut packed.layout {
            offsets.push(0);
        }
        let mut row_buf: Vec<Influence> = Vec::with_capacity(max_per_vertex);
        for (v, row) in influences.rows().enumerate() {
            row_buf.clear();
            row_buf.extend(row.iter().filter(|i| i.weight != 0.0));
            if row_buf.is_empty() {
                packed.unweighted.push(v as u32);
            }
            let pivot = dqs::pivot_slot(&row_buf);
            if let Some(head) = row_buf.get_mut(..=pivot) {
                head.rotate_right(1);
            }
            for inf in &row_buf {
                packed.joint_bound = packed.joint_bound.max(inf.joint as usize + 1);
                packed.joints.push(inf.joint);
                packed.weights.push(inf.weight);
            }
            match &mut packed.layout {
                Layout::Empty => {}
                Layout::Fixed { width } => {
                    let pad = row_buf.first().map_or(0, |i| i.joint);
                    for _ in row_buf.len()..*width {
                        packed.joints.push(pad);
                        packed.weights.push(0.0);
                    }
                }
                Layout::Sparse { offsets } => offsets.push(packed.joints.len() as u32),
            }
        }
        if matches!(packed.layout, Layout::Fixed { .. }) {
            // Padding may point at joint 0.
            packed.joint_bound = packed.joint_bound.max(1);
        }
        packed
    }

    /// Number of vertices.
    pub fn vertex_count(&self) -> usize {
        self.vertex_count
    }

    /// The palette size the influences need: largest joint index + 1 (0 without any).
    pub fn joint_bound(&self) -> usize {
        self.joint_bound
    }

    /// The largest number of non-zero influences on one vertex.
    pub fn max_per_vertex(&self) -> usize {
        self.max_per_vertex
    }

    /// The fixed number of slots per vertex, or `None` for the sparse layout (more than 8
    /// non-zero influences on some vertex) or when no vertex has any.
    pub fn width(&self) -> Option<usize> {
        match self.layout {
            Layout::Fixed { width } => Some(width),
            _ => None,
        }
    }

    /// Skins vertices `v0..v0 + out.len()` with one frame's palette. `mats` has at least
    /// `joint_bound` entries; `dqs` is that frame's prepared DQS data for [`SkinningMethod::Dqs`].
    fn skin_leaf(&self, kind: Kind<'_>, v0: usize, rest: &[Vec3], out: &mut [Vec3]) {
        let n = out.len();
        match &self.layout {
            Layout::Empty => out.copy_from_slice(rest),
            Layout::Fixed { width } => {
                let (a, b) = (v0 * width, (v0 + n) * width);
                let (js, ws) = (&self.joints[a..b], &self.weights[a..b]);
                macro_rules! widths {
                    ($($w:literal)*) => {
                        match *width {
                            $($w => match kind {
                                Kind::Lbs(m) => lbs_fixed::<$w>(m, js, ws, rest, out),
                                Kind::Dqs(f) => dqs::skin_fixed::<$w>(&f, js, ws, rest, out),
                            },)*
                            _ => {}
                        }
                    };
                }
                widths!(1 2 3 4 5 6 7 8);
            }
            Layout::Sparse { offsets } => {
                let offs = &offsets[v0..=v0 + n];
                let (a, b) = (offs[0] as usize, offs[n] as usize);
                let (js, ws) = (&self.joints[a..b], &self.weights[a..b]);
                // Offsets relative to the chunk's start.
                match kind {
                    Kind::Lbs(m) => lbs_sparse(m, offs, a, js, ws, rest, out),
                    Kind::Dqs(f) => dqs::skin_sparse(&f, offs, a, js, ws, rest, out),
                }
            }
        }
        // Unweighted vertices keep their rest position.
        let lo = self.unweighted.partition_point(|&v| (v as usize) < v0);
        let hi = self.unweighted.partition_point(|&v| (v as usize) < v0 + n);
        for &v in &self.unweighted[lo..hi] {
            let i = v as usize - v0;
            out[i] = rest[i];
        }
    }
}

/// One frame's palette, in the form the method needs.
#[derive(Clone, Copy)]
enum Kind<'a> {
    Lbs(&'a [Mat4]),
    Dqs(dqs::Frame<'a>),
}

/// LBS over a fixed-width chunk.
fn lbs_fixed<const W: usize>(
    mats: &[Mat4],
    joints: &[u32],
    weights: &[f32],
    rest: &[Vec3],
    out: &mut [Vec3],
) {
    if crate::simd::try_lbs_fixed::<W>(mats, joints, weights, rest, out) {
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
fn lbs_sparse(
    mats: &[Mat4],
    offsets: &[u32],
    base: usize,
    joints: &[u32],
    weights: &[f32],
    rest: &[Vec3],
    out: &mut [Vec3],
) {
    if crate::simd::try_lbs_sparse(mats, offsets, base, joints, weights, rest, out) {
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

/// Skins positions for any number of frames from [`PackedInfluences`]: the bake path.
///
/// `frame_skin_matrices` holds `F` palettes back to back (frame-major, `F * J` matrices,
/// `J >= influences.joint_bound()`), `out_positions` receives `F` position arrays back to
/// back (`F * V`, `V = rest_positions.len()`), so `F = out_positions.len() / V`. Vertices
/// are processed in blocks whose influences stay in cache while up to 16 frames are
/// skinned, so each vertex's influences are read from memory once per block of frames.
pub struct SkinFramesJob<'a> {
    /// LBS or DQS.
    pub method: SkinningMethod,
    /// The mesh's influences, packed once.
    pub influences: &'a PackedInfluences,
    /// Bind-space positions, one per vertex.
    pub rest_positions: &'a [Vec3],
    /// `F x J` skinning matrices, frame-major.
    pub frame_skin_matrices: &'a [Mat4],
    /// Output: `F x V` skinned model-space positions, frame-major.
    pub out_positions: &'a mut [Vec3],
    /// Scratch for [`SkinningMethod::Dqs`], with room for `J` joints and at least one frame
    /// (frames are prepared in blocks of up to its frame capacity, at most 16); unused by
    /// LBS (pass `&mut DqsPalette::default()`).
    pub palette: &'a mut DqsPalette,
}

/// Sizes derived by [`SkinFramesJob::validate`].
#[derive(Clone, Copy, Debug)]
struct FrameShape {
    vertices: usize,
    frames: usize,
    joints: usize,
    block: usize,
}

impl SkinFramesJob<'_> {
    /// Checks the buffer lengths against each other, the palette size against the
    /// influences' joint bound (indices were checked when packing), and the DQS scratch.
    ///
    /// # Errors
    /// [`EvalError::Length`] or [`EvalError::Index`].
    pub fn validate(&self) -> Result<(), EvalError> {
        self.shape().map(|_| ())
    }

    fn shape(&self) -> Result<FrameShape, EvalError> {
        let v = self.rest_positions.len();
        if self.influences.vertex_count() != v {
            return Err(EvalError::Length {
                what: "influences",
                expected: v,
                found: self.influences.vertex_count(),
            });
        }
        // Without vertices there is nothing to skin (and no frame count to derive).
        let frames = self.out_positions.len().checked_div(v).unwrap_or(0);
        if frames * v != self.out_positions.len() {
            return Err(EvalError::Length {
                what: "out_positions (a multiple of the vertex count)",
                expected: (frames + 1) * v,
                found: self.out_positions.len(),
            });
        }
        let joints = self
            .frame_skin_matrices
            .len()
            .checked_div(frames)
            .unwrap_or(0);
        if frames > 0 && joints * frames != self.frame_skin_matrices.len() {
            return Err(EvalError::Length {
                what: "frame_skin_matrices (frames x joints)",
                expected: (joints + 1) * frames,
                found: self.frame_skin_matrices.len(),
            });
        }
        if frames > 0 && joints < self.influences.joint_bound() {
            return Err(EvalError::Index {
                what: "influences",
                index: self.influences.joint_bound() - 1,
            });
        }
        let mut block = FRAME_BLOCK.min(frames.max(1));
        if self.method == SkinningMethod::Dqs && frames > 0 {
            if self.palette.joint_capacity() < joints || self.palette.frame_capacity() == 0 {
                return Err(EvalError::Length {
                    what: "DqsPalette joints",
                    expected: joints,
                    found: self.palette.joint_capacity(),
                });
            }
            block = block.min(self.palette.frame_capacity());
        }
        Ok(FrameShape {
            vertices: v,
            frames,
            joints,
            block,
        })
    }

    /// Runs the job on the calling thread. Allocates nothing.
    ///
    /// # Errors
    /// As [`SkinFramesJob::validate`], which it calls first.
    pub fn run(&mut self) -> Result<(), EvalError> {
        self.run_with(false)
    }

    /// Runs the job on the current rayon thread pool: each block of frames is split into
    /// vertex chunks of at least 4096 vertices (serially below that). Allocates nothing
    /// itself.
    ///
    /// # Errors
    /// As [`SkinFramesJob::validate`], which it calls first.
    pub fn par_run(&mut self) -> Result<(), EvalError> {
        self.run_with(true)
    }

    fn run_with(&mut self, parallel: bool) -> Result<(), EvalError> {
        let shape = self.shape()?;
        let FrameShape {
            vertices: v,
            frames,
            joints,
            block,
        } = shape;
        if frames == 0 {
            return Ok(());
        }
        let mut f0 = 0;
        let mut rows = self.out_positions.chunks_mut(v);
        while f0 < frames {
            let nf = block.min(frames - f0);
            let mats = &self.frame_skin_matrices[f0 * joints..(f0 + nf) * joints];
            if self.method == SkinningMethod::Dqs {
                self.palette.prepare(mats, joints, nf)?;
            }
            let mut outs: [&mut [Vec3]; FRAME_BLOCK] = Default::default();
            for slot in outs.iter_mut().take(nf) {
                *slot = rows.next().unwrap_or_default();
            }
            let ctx = Block {
                method: self.method,
                influences: self.influences,
                rest: self.rest_positions,
                mats,
                joints,
                palette: self.palette,
                frames: nf,
            };
            if parallel && v >= 2 * GRAIN {
                ctx.par_skin(outs, 0);
            } else {
                ctx.skin(&mut outs, 0);
            }
            f0 += nf;
        }
        Ok(())
    }
}

/// One block of frames of a [`SkinFramesJob`].
#[derive(Clone, Copy)]
struct Block<'a> {
    method: SkinningMethod,
    influences: &'a PackedInfluences,
    rest: &'a [Vec3],
    /// `frames x joints`.
    mats: &'a [Mat4],
    joints: usize,
    palette: &'a DqsPalette,
    frames: usize,
}

impl Block<'_> {
    /// Skins vertices `v0..v0 + outs[0].len()` for every frame of the block, `LEAF`
    /// vertices at a time, frames inner.
    fn skin(&self, outs: &mut [&mut [Vec3]; FRAME_BLOCK], v0: usize) {
        let n = outs[0].len();
        let mut start = 0;
        while start < n {
            let len = LEAF.min(n - start);
            let rest = &self.rest[v0 + start..v0 + start + len];
            for (f, out) in outs.iter_mut().take(self.frames).enumerate() {
                let kind = match self.method {
                    SkinningMethod::Lbs => {
                        Kind::Lbs(&self.mats[f * self.joints..(f + 1) * self.joints])
                    }
                    SkinningMethod::Dqs => Kind::Dqs(self.palette.frame(f)),
                };
                let o = &mut out[start..start + len];
                self.influences.skin_leaf(kind, v0 + start, rest, o);
            }
            start += len;
        }
    }

    /// [`Block::skin`] split recursively with `rayon::join` down to `GRAIN` vertices.
    fn par_skin(&self, mut outs: [&mut [Vec3]; FRAME_BLOCK], v0: usize) {
        let n = outs[0].len();
        if n < 2 * GRAIN {
            self.skin(&mut outs, v0);
            return;
        }
        // Split at a multiple of 8 (the DQS kernels' vertex block: 8 AVX2 lanes, or 4 SSE
        // lanes), so serial and parallel runs group vertices alike and agree bit for bit.
        let mid = (n / 2) & !7;
        let mut left: [&mut [Vec3]; FRAME_BLOCK] = Default::default();
        let mut right: [&mut [Vec3]; FRAME_BLOCK] = Default::default();
        for ((o, l), r) in outs.iter_mut().zip(&mut left).zip(&mut right) {
            let at = mid.min(o.len());
            let (a, b) = std::mem::take(o).split_at_mut(at);
            *l = a;
            *r = b;
        }
        rayon::join(
            || self.par_skin(left, v0),
            || self.par_skin(right, v0 + mid),
        );
    }
}

/// Convenience for [`SkinFramesJob`] on the calling thread: allocates the DQS scratch
/// (`J x min(F, 16)` joint entries) itself.
///
/// ```
/// use rigport_eval::skinning::{skin_frames, PackedInfluences, SkinningMethod};
/// use rigport_model::glam::{Mat4, Vec3};
/// use rigport_model::{Influence, Influences};
///
/// // One vertex at +Y, half on each of two joints.
/// let half = |joint| Influence { joint, weight: 0.5 };
/// let packed = PackedInfluences::new(&Influences::from_rows([[half(0), half(1)]]));
/// // Two frames of a two-joint palette, frame-major: in the second, joint 1 turns 120°
/// // about Z.
/// let turn = Mat4::from_rotation_z(120f32.to_radians());
/// let mats = [Mat4::IDENTITY, Mat4::IDENTITY, Mat4::IDENTITY, turn];
/// let mut out = [Vec3::ZERO; 2];
/// skin_frames(SkinningMethod::Lbs, &packed, &[Vec3::Y], &mats, &mut out)?;
/// assert_eq!(out[0], Vec3::Y);
/// assert!((out[1].length() - 0.5).abs() < 1e-6); // LBS pulls the point halfway in...
/// skin_frames(SkinningMethod::Dqs, &packed, &[Vec3::Y], &mats, &mut out)?;
/// let halfway = Mat4::from_rotation_z(60f32.to_radians()).transform_point3(Vec3::Y);
/// assert!(out[1].abs_diff_eq(halfway, 1e-6)); // ...DQS turns it halfway, 60°.
/// # Ok::<(), rigport_eval::EvalError>(())
/// ```
///
/// # Errors
/// As [`SkinFramesJob::validate`].
pub fn skin_frames(
    method: SkinningMethod,
    influences: &PackedInfluences,
    rest_positions: &[Vec3],
    frame_skin_matrices: &[Mat4],
    out_positions: &mut [Vec3],
) -> Result<(), EvalError> {
    frames_job(
        method,
        influences,
        rest_positions,
        frame_skin_matrices,
        out_positions,
        false,
    )
}

/// [`skin_frames`] on the current rayon thread pool (see [`SkinFramesJob::par_run`]).
///
/// # Errors
/// As [`SkinFramesJob::validate`].
pub fn par_skin_frames(
    method: SkinningMethod,
    influences: &PackedInfluences,
    rest_positions: &[Vec3],
    frame_skin_matrices: &[Mat4],
    out_positions: &mut [Vec3],
) -> Result<(), EvalError> {
    frames_job(
        method,
        influences,
        rest_positions,
        frame_skin_matrices,
        out_positions,
        true,
    )
}

fn frames_job(
    method: SkinningMethod,
    influences: &PackedInfluences,
    rest_positions: &[Vec3],
    frame_skin_matrices: &[Mat4],
    out_positions: &mut [Vec3],
    parallel: bool,
) -> Result<(), EvalError> {
    let v = rest_positions.len();
    let frames = out_positions.len().checked_div(v).unwrap_or(0);
    let joints = frame_skin_matrices.len().checked_div(frames).unwrap_or(0);
    let mut palette = match method {
        SkinningMethod::Lbs => DqsPalette::default(),
        SkinningMethod::Dqs => DqsPalette::new(joints, frames.clamp(1, FRAME_BLOCK)),
    };
    let mut job = SkinFramesJob {
        method,
        influences,
        rest_positions,
        frame_skin_matrices,
        out_positions,
        palette: &mut palette,
    };
    if parallel {
        job.par_run()
    } else {
        job.run()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Quat;
    use proptest::prelude::*;

    /// Scalar reference: blends the transformed points instead of the matrices.
    fn naive(skin: &[Mat4], infl: &Influences, rest: &[Vec3]) -> Vec<Vec3> {
        rest.iter()
            .enumerate()
            .map(|(v, p)| {
                let row = infl.vertex(v);
                if row.iter().all(|i| i.weight == 0.0) {
                    return *p;
                }
                row.iter()
                    .map(|i| skin[i.joint as usize].transform_point3(*p) * i.weight)
                    .sum()
            })
            .collect()
    }

    fn matrix() -> impl Strategy<Value = Mat4> {
        (
            prop::array::uniform3(-3.0f32..3.0),
            prop::array::uniform3(-3.2f32..3.2),
            prop::array::uniform3(0.8f32..1.2),
        )
            .prop_map(|(t, r, s)| {
                Mat4::from_scale_rotation_translation(
                    Vec3::from(s),
                    Quat::from_euler(glam::EulerRot::XYZ, r[0], r[1], r[2]),
                    Vec3::from(t),
                )
            })
    }

    fn rows(max_len: usize) -> impl Strategy<Value = Vec<Vec<(u32, f32)>>> {
        prop::collection::vec(
            prop::collection::vec(
                (0u32..16, prop_oneof![Just(0.0f32), 0.01f32..1.0]),
                0..max_len,
            ),
            1..40,
        )
    }

    fn make_influences(rows: &[Vec<(u32, f32)>], n: u32) -> Influences {
        Influences::from_rows(rows.iter().map(|r| {
            let sum: f32 = r.iter().map(|x| x.1).sum::<f32>().max(1e-6);
            r.iter()
                .map(move |&(j, w)| Influence {
                    joint: j % n,
                    weight: w / sum,
                })
                .collect::<Vec<_>>()
        }))
    }

    fn lbs(skin: &[Mat4], infl: &Influences, rest: &[Vec3]) -> Vec<Vec3> {
        let mut out = vec![Vec3::ZERO; rest.len()];
        LbsJob {
            skin_matrices: skin,
            influences: infl,
            rest_positions: rest,
            rest_normals: None,
            out_positions: &mut out,
            out_normals: None,
        }
        .run()
        .unwrap();
        out
    }

    proptest! {
        #[test]
        fn matches_naive_and_single_influence_is_exact(
            skin in prop::collection::vec(matrix(), 1..8),
            rows in rows(5),
            pts in prop::collection::vec(prop::array::uniform3(-2.0f32..2.0), 40),
        ) {
            let n = skin.len() as u32;
            let infl = make_influences(&rows, n);
            let rest: Vec<Vec3> = pts[..rows.len()].iter().map(|p| Vec3::from(*p)).collect();
            let out = lbs(&skin, &infl, &rest);
            for (v, (a, b)) in out.iter().zip(naive(&skin, &infl, &rest)).enumerate() {
                prop_assert!(a.abs_diff_eq(b, 1e-4), "vertex {v}: {a} vs {b}");
            }
            // Single influence: exactly that joint's matrix.
            let single = Influences::from_rows(rest.iter().enumerate().map(|(v, _)| [Influence { joint: v as u32 % n, weight: 1.0 }]));
            let out = lbs(&skin, &single, &rest);
            for (v, p) in rest.iter().enumerate() {
                let expect = skin[v % n as usize].transform_point3(*p);
                prop_assert!(out[v].abs_diff_eq(expect, 1e-5), "vertex {v}: {} vs {expect}", out[v]);
            }
        }

        #[test]
        fn packed_frames_match_the_row_job(
            skin in prop::collection::vec(matrix(), 16 * 3),
            rows in rows(11),
            pts in prop::collection::vec(prop::array::uniform3(-2.0f32..2.0), 40),
            frames in 1usize..4,
        ) {
            // 16 joints per frame, up to 3 frames; rows up to 10 long exercise the fixed
            // widths and the sparse layout.
            let infl = make_influences(&rows, 16);
            let rest: Vec<Vec3> = pts[..rows.len()].iter().map(|p| Vec3::from(*p)).collect();
            let packed = PackedInfluences::new(&infl);
            let mats = &skin[..16 * frames];
            let mut out = vec![Vec3::ZERO; rest.len() * frames];
            skin_frames(SkinningMethod::Lbs, &packed, &rest, mats, &mut out).unwrap();
            let mut par = vec![Vec3::ZERO; rest.len() * frames];
            par_skin_frames(SkinningMethod::Lbs, &packed, &rest, mats, &mut par).unwrap();
            prop_assert_eq!(&out, &par);
            for f in 0..frames {
                let expect = lbs(&mats[16 * f..16 * (f + 1)], &infl, &rest);
                for (v, (a, b)) in out[f * rest.len()..(f + 1) * rest.len()].iter().zip(&expect).enumerate() {
                    prop_assert!(a.abs_diff_eq(*b, 1e-4), "frame {f} vertex {v}: {a} vs {b}");
                }
            }
        }
    }

    #[test]
    fn packing_drops_zeros_and_puts_the_pivot_first() {
        let inf = |joint, weight| Influence { joint, weight };
        let infl = Influences::from_rows([
            vec![inf(3, 0.2), inf(5, 0.0), inf(1, 0.5), inf(2, 0.3)],
            vec![],
            vec![inf(7, 0.5), inf(6, 0.5)],
        ]);
        let p = PackedInfluences::new(&infl);
        assert_eq!(p.width(), Some(3));
        assert_eq!(p.max_per_vertex(), 3);
        assert_eq!(p.joint_bound(), 8);
        assert_eq!(p.joints, [1, 3, 2, 0, 0, 0, 7, 6, 7]);
        assert_eq!(p.weights, [0.5, 0.2, 0.3, 0.0, 0.0, 0.0, 0.5, 0.5, 0.0]);
        assert_eq!(p.unweighted, [1]);
        let wide = Influences::from_rows([(0..9).map(|j| inf(j, 0.1))]);
        assert_eq!(PackedInfluences::new(&wide).width(), None);
        assert_eq!(
            PackedInfluences::new(&Influences::from_rows([[inf(0, 0.0)]])).width(),
            None
        );
    }

    #[test]
    fn large_mesh_parallel_equals_serial_and_keeps_unweighted_at_rest() {
        let skin: Vec<Mat4> = (0..24)
            .map(|j| {
                Mat4::from_rotation_translation(
                    Quat::from_rotation_z(j as f32 * 0.3),
                    Vec3::X * j as f32,
                )
            })
            .collect();
        let n = 2 * GRAIN + 1001;
        let infl = Influences::from_rows((0..n).map(|v| {
            if v % 97 == 0 {
                vec![]
            } else {
                vec![
                    Influence {
                        joint: (v % 12) as u32,
                        weight: 0.6,
                    },
                    Influence {
                        joint: (v % 7) as u32,
                        weight: 0.4,
                    },
                ]
            }
        }));
        let rest: Vec<Vec3> = (0..n)
            .map(|v| Vec3::new(1.0, v as f32 * 1e-3, 0.5))
            .collect();
        let packed = PackedInfluences::new(&infl);
        for method in [SkinningMethod::Lbs, SkinningMethod::Dqs] {
            let mut a = vec![Vec3::ZERO; 2 * n];
            let mut b = vec![Vec3::ZERO; 2 * n];
            skin_frames(method, &packed, &rest, &skin, &mut a).unwrap();
            par_skin_frames(method, &packed, &rest, &skin, &mut b).unwrap();
            assert_eq!(a, b, "{method:?}");
            assert_eq!(a[97], rest[97]);
            assert_eq!(a[n + 97 * 5], rest[97 * 5]);
        }
        let mut a = vec![Vec3::ZERO; n];
        let mut b = vec![Vec3::ZERO; n];
        LbsJob {
            skin_matrices: &skin,
            influences: &infl,
            rest_positions: &rest,
            rest_normals: None,
            out_positions: &mut a,
            out_normals: None,
        }
        .run()
        .unwrap();
        LbsJob {
            skin_matrices: &skin,
            influences: &infl,
            rest_positions: &rest,
            rest_normals: None,
            out_positions: &mut b,
            out_normals: None,
        }
        .par_run()
        .unwrap();
        assert_eq!(a, b);
    }

    #[test]
    fn frames_job_checks_sizes() {
        let infl = Influences::from_rows([
            [Influence {
                joint: 2,
                weight: 1.0,
            }],
            [Influence {
                joint: 0,
                weight: 1.0,
            }],
        ]);
        let packed = PackedInfluences::new(&infl);
        let rest = [Vec3::ZERO; 2];
        let mats = [Mat4::IDENTITY; 4];
        let mut out = [Vec3::ZERO; 5];
        assert!(matches!(
            skin_frames(SkinningMethod::Lbs, &packed, &rest, &mats, &mut out),
            Err(EvalError::Length { .. })
        ));
        let mut out = [Vec3::ZERO; 4];
        // Two frames of two joints: joint 2 is out of range.
        assert_eq!(
            skin_frames(SkinningMethod::Lbs, &packed, &rest, &mats, &mut out),
            Err(EvalError::Index {
                what: "influences",
                index: 2
            })
        );
        let mut palette = DqsPalette::new(2, 1);
        let mut job = SkinFramesJob {
            method: SkinningMethod::Dqs,
            influences: &packed,
            rest_positions: &rest,
            frame_skin_matrices: &mats[..3],
            out_positions: &mut out[..2],
            palette: &mut palette,
        };
        assert!(matches!(
            job.run(),
            Err(EvalError::Length {
                what: "DqsPalette joints",
                ..
            })
        ));
    }

    #[test]
    fn normals_use_the_cofactor() {
        let m = Mat4::from_scale(Vec3::new(2.0, 1.0, 1.0)) * Mat4::from_rotation_z(0.3);
        let infl = Influences::from_rows([
            vec![Influence {
                joint: 0,
                weight: 1.0,
            }],
            vec![],
        ]);
        let rest_n = [Vec3::new(1.0, 1.0, 0.0).normalize(), Vec3::Y];
        let mut out = [Vec3::ZERO; 2];
        let mut out_n = [Vec3::ZERO; 2];
        LbsJob {
            skin_matrices: &[m],
            influences: &infl,
            rest_positions: &[Vec3::ONE, Vec3::ONE],
            rest_normals: Some(&rest_n),
            out_positions: &mut out,
            out_normals: Some(&mut out_n),
        }
        .run()
        .unwrap();
        let expect = (glam::Mat3::from_mat4(m).inverse().transpose() * rest_n[0]).normalize();
        assert!(
            out_n[0].abs_diff_eq(expect, 1e-6),
            "{} vs {expect}",
            out_n[0]
        );
        assert_eq!(out_n[1], Vec3::Y);
        assert_eq!(out[1], Vec3::ONE);
    }

    #[test]
    fn rejects_bad_joint_index() {
        let infl = Influences::from_rows([[Influence {
            joint: 3,
            weight: 1.0,
        }]]);
        let mut out = [Vec3::ZERO];
        let job = LbsJob {
            skin_matrices: &[Mat4::IDENTITY],
            influences: &infl,
            rest_positions: &[Vec3::ZERO],
            rest_normals: None,
            out_positions: &mut out,
            out_normals: None,
        };
        assert_eq!(
            job.validate(),
            Err(EvalError::Index {
                what: "influences",
                index: 3
            })
        );
    }
}

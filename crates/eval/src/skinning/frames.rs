//! The multi-frame path: influences packed once ([`PackedInfluences`]), then
//! [`SkinFramesJob`] skins blocks of frames with LBS or DQS (the method switch).

use glam::{Mat4, Vec3};
use rigport_model::{Influence, Influences};

use crate::EvalError;

use super::common::{Frame, GRAIN};
use super::dqs::{self, DqsPalette};
use super::lbs::{lbs_fixed, lbs_sparse};

/// Vertices per inner block of the multi-frame path: their influences (at most
/// `LEAF * 8 * 8` bytes) stay in cache while a block of frames is skinned.
const LEAF: usize = 1024;

/// Frames skinned per pass over a block of vertices.
const FRAME_BLOCK: usize = 16;

use rigport_model::SkinningMethod;

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
    pub(super) joints: Vec<u32>,
    pub(super) weights: Vec<f32>,
    /// Vertices without a non-zero weight, ascending; they keep their rest position.
    pub(super) unweighted: Vec<u32>,
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
    Dqs(Frame<'a>),
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
/// use rigport_eval::skinning::{skin_frames, PackedInfluences};
/// use rigport_model::glam::{Mat4, Vec3};
/// use rigport_model::{Influence, Influences, SkinningMethod};
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

//! The arrays of a `rigport eval` dump.

use std::io;
use std::path::Path;

use glam::{Mat4, Vec3};
use rigport_model::{Asset, JointIndex, SkinBinding};

use super::{Data, NpzWriter, Spill};

/// Row-major 4x4 (numpy's C order) of a column-vector matrix, so `M[j] @ p` works in numpy.
fn push_row_major(out: &mut Vec<f32>, m: &Mat4) {
    out.extend_from_slice(&m.transpose().to_cols_array());
}

/// Vertex `v`'s influences as (skeleton joint, weight): through `skin` (the binding that
/// deforms its mesh), else weight 1 on the joint the mesh is `attached_to`, else none.
///
/// ```
/// use rigport_export::npz::influence_row;
/// use rigport_model::JointIndex;
///
/// // A mesh without skin, attached to joint 3.
/// assert_eq!(influence_row(None, Some(JointIndex(3)), 0), vec![(3, 1.0)]);
/// assert!(influence_row(None, None, 0).is_empty());
/// ```
pub fn influence_row(
    skin: Option<&SkinBinding>,
    attached_to: Option<JointIndex>,
    v: usize,
) -> Vec<(i32, f32)> {
    match (skin, attached_to) {
        (Some(skin), _) => skin
            .influences
            .vertex(v)
            .iter()
            .map(|i| (skin.joints[i.joint as usize].0 as i32, i.weight))
            .collect(),
        (None, Some(j)) => vec![(j.0 as i32, 1.0)],
        (None, None) => Vec::new(),
    }
}

/// Rows of (joint, weight) as two row-major `rows x K` tables zero-padded to the widest
/// row's `K`: (joints, weights, K).
///
/// ```
/// let (joints, weights, k) = rigport_export::npz::padded(&[vec![(1, 0.5), (2, 0.5)], vec![(4, 1.0)]]);
/// assert_eq!((joints, weights, k), (vec![1, 2, 4, 0], vec![0.5, 0.5, 1.0, 0.0], 2));
/// ```
pub fn padded(rows: &[Vec<(i32, f32)>]) -> (Vec<i32>, Vec<f32>, usize) {
    let k = rows.iter().map(Vec::len).max().unwrap_or(0);
    let mut joints = Vec::with_capacity(rows.len() * k);
    let mut weights = Vec::with_capacity(rows.len() * k);
    for row in rows {
        for slot in 0..k {
            let (j, w) = row.get(slot).copied().unwrap_or((0, 0.0));
            joints.push(j);
            weights.push(w);
        }
    }
    (joints, weights, k)
}

/// The arrays of a `rigport eval` dump, filled frame by frame: `times` (with frames),
/// `positions` (`[F,] V, 3`, model space), `rest_positions` (`V, 3`), `joint_names` (`J`),
/// `joint_world` and `skin_matrices` (`[F,] J, 4, 4`, row-major so `M[j] @ p` works in
/// numpy), `influence_joints` and `influence_weights` (`V, K`, zero-padded) and `skinning`
/// (`"lbs"` or `"dqs"`).
///
/// Vertices are listed mesh by mesh, each mesh in its source vertex order (for OBJ-based
/// rigs: the `v` line order), taking the first output vertex made from each source vertex.
/// `skin_matrices[j]` uses the inverse bind matrix of the first skin whose palette has
/// joint `j`, or the inverse of its rest model matrix when no skin uses it.
///
/// The per-frame arrays are held in memory, or with [`EvalDump::spill_into`] up to
/// [`SPILL_LIMIT`](super::SPILL_LIMIT) bytes each in memory and the rest in unnamed
/// temporary files, so that a clip of any length dumps in bounded memory.
#[derive(Debug)]
pub struct EvalDump {
    /// Per dumped vertex: (mesh, mesh vertex).
    vertices: Vec<(usize, usize)>,
    /// Per mesh, per mesh vertex: its dumped row (the row of its source vertex).
    mesh_rows: Vec<Vec<u32>>,
    rest_positions: Vec<f32>,
    influence_joints: Vec<i32>,
    influence_weights: Vec<f32>,
    max_influences: usize,
    inv_bind: Vec<Mat4>,
    names: Vec<String>,
    skinning: &'static str,
    /// Frames pushed.
    frames: usize,
    times: Spill,
    positions: Spill,
    joint_world: Spill,
    skin_matrices: Spill,
    /// One frame's rows, reused: (positions, joint_world, skin_matrices).
    scratch: (Vec<f32>, Vec<f32>, Vec<f32>),
}

impl EvalDump {
    /// The frame-independent arrays of `asset`, skinned with `skinning` (`"lbs"` or
    /// `"dqs"`); `skin_of_mesh(m)` is the skin binding that deforms mesh `m`, if any (the
    /// evaluator's `Rig::skin_of_mesh`).
    pub fn new(
        asset: &Asset,
        skin_of_mesh: impl Fn(usize) -> Option<usize>,
        skinning: &'static str,
    ) -> Self {
        let rest = asset.skeleton.model_rest_matrices();
        let joint_count = asset.skeleton.len();
        let mut inv_bind: Vec<Option<Mat4>> = vec![None; joint_count];
        for skin in &asset.skins {
            for (p, j) in skin.joints.iter().enumerate() {
                inv_bind[j.get()].get_or_insert(skin.inv_bind[p]);
            }
        }
        let inv_bind = inv_bind
            .iter()
            .zip(&rest)
            .map(|(ib, r)| ib.unwrap_or_else(|| r.inverse()))
            .collect();
        let mut vertices = Vec::new();
        let mut rest_positions = Vec::new();
        let mut rows: Vec<Vec<(i32, f32)>> = Vec::new();
        let mut mesh_rows = Vec::with_capacity(asset.meshes.len());
        for (mi, mesh) in asset.meshes.iter().enumerate() {
            let skin = skin_of_mesh(mi).and_then(|s| asset.skins.get(s));
            let firsts = mesh.first_vertex_of_source();
            // Every source vertex has a first vertex (`source_vertex` lists each), so each
            // mesh vertex's source has a row.
            let mut row_of_source = vec![u32::MAX; firsts.len()];
            let mut next = vertices.len() as u32;
            for (row, &v) in row_of_source.iter_mut().zip(&firsts) {
                if v != u32::MAX {
                    *row = next;
                    next += 1;
                }
            }
            mesh_rows.push(
                mesh.source_vertex
                    .iter()
                    .map(|&s| row_of_source[s as usize])
                    .collect(),
            );
            for &v in &firsts {
                let Some(v) = (v != u32::MAX).then_some(v as usize) else {
                    continue;
                };
                vertices.push((mi, v));
                rest_positions.extend_from_slice(&mesh.positions[v].to_array());
                rows.push(influence_row(skin, mesh.attached_to, v));
            }
        }
        let (influence_joints, influence_weights, k) = padded(&rows);
        Self {
            vertices,
            mesh_rows,
            rest_positions,
            influence_joints,
            influence_weights,
            max_influences: k,
            inv_bind,
            names: asset
                .skeleton
                .joints()
                .iter()
                .map(|j| j.name.clone())
                .collect(),
            skinning,
            frames: 0,
            times: Spill::new(None),
            positions: Spill::new(None),
            joint_world: Spill::new(None),
            skin_matrices: Spill::new(None),
            scratch: Default::default(),
        }
    }

    /// Moves the per-frame arrays beyond [`SPILL_LIMIT`](super::SPILL_LIMIT) bytes each
    /// into unnamed temporary files in `dir` (best the output's own folder: the bytes then
    /// land on the disk that is to hold the output, not on a `tmpfs` in memory). Call it
    /// before the first [`EvalDump::push`].
    #[must_use]
    pub fn spill_into(mut self, dir: &Path) -> Self {
        self.times = Spill::new(Some(dir));
        self.positions = Spill::new(Some(dir));
        self.joint_world = Spill::new(Some(dir));
        self.skin_matrices = Spill::new(Some(dir));
        self
    }

    /// Appends one evaluated frame at `time` seconds: `joint_model` has one model-space
    /// matrix per joint, `positions[m]` the posed model-space positions of mesh `m` (the
    /// evaluator's `RigOutput`).
    ///
    /// # Errors
    /// Creating or writing a temporary file ([`EvalDump::spill_into`]); never in memory.
    ///
    /// # Panics
    /// If the sizes do not match the asset given to [`EvalDump::new`] (a caller bug).
    pub fn push(
        &mut self,
        time: f32,
        joint_model: &[Mat4],
        positions: &[Vec<Vec3>],
    ) -> io::Result<()> {
        let (rows, world, skin) = &mut self.scratch;
        rows.clear();
        world.clear();
        skin.clear();
        for (j, ib) in self.inv_bind.iter().enumerate() {
            push_row_major(world, &joint_model[j]);
            push_row_major(skin, &(joint_model[j] * *ib));
        }
        for &(m, v) in &self.vertices {
            rows.extend_from_slice(&positions[m][v].to_array());
        }
        self.times.extend_f32(&[time])?;
        self.positions.extend_f32(rows)?;
        self.joint_world.extend_f32(world)?;
        self.skin_matrices.extend_f32(skin)?;
        self.frames += 1;
        Ok(())
    }

    /// The arrays themselves, for a caller that keeps them in memory (the Python
    /// bindings): the same values [`EvalDump::finish`] writes, always with the frame axis.
    ///
    /// # Errors
    /// Reading back a temporary file ([`EvalDump::spill_into`]); never in memory.
    pub fn into_arrays(self) -> io::Result<EvalArrays> {
        Ok(EvalArrays {
            frames: self.frames,
            vertices: self.vertices.len(),
            mesh_rows: self.mesh_rows,
            joints: self.names.len(),
            max_influences: self.max_influences,
            times: self.times.into_f32()?,
            positions: self.positions.into_f32()?,
            joint_world: self.joint_world.into_f32()?,
            skin_matrices: self.skin_matrices.into_f32()?,
            rest_positions: self.rest_positions,
            joint_names: self.names,
            influence_joints: self.influence_joints,
            influence_weights: self.influence_weights,
            skinning: self.skinning,
        })
    }

    /// The `.npz` arrays; with `frames`, the per-frame arrays get a leading frame axis and
    /// `times` is written.
    pub fn finish(self, frames: bool) -> NpzWriter {
        let v = self.vertices.len();
        let j = self.names.len();
        let f = self.frames;
        let lead = |shape: &[usize]| -> Vec<usize> {
            if frames {
                std::iter::once(f).chain(shape.iter().copied()).collect()
            } else {
                shape.to_vec()
            }
        };
        let mut npz = NpzWriter::default();
        if frames {
            npz.add_spill("times", &[f], self.times);
        }
        npz.add_spill("positions", &lead(&[v, 3]), self.positions);
        npz.add("rest_positions", &[v, 3], Data::F32(self.rest_positions));
        npz.add("joint_names", &[j], Data::Str(self.names));
        npz.add_spill("joint_world", &lead(&[j, 4, 4]), self.joint_world);
        npz.add_spill("skin_matrices", &lead(&[j, 4, 4]), self.skin_matrices);
        let k = self.max_influences;
        npz.add(
            "influence_joints",
            &[v, k],
            Data::I32(self.influence_joints),
        );
        npz.add(
            "influence_weights",
            &[v, k],
            Data::F32(self.influence_weights),
        );
        npz.add("skinning", &[1], Data::Str(vec![self.skinning.to_string()]));
        npz
    }
}

/// The arrays of an [`EvalDump`] held in memory ([`EvalDump::into_arrays`]), flat and
/// C-ordered, with the sizes that shape them: `F` frames, `V` vertices, `J` joints, `K`
/// influences per vertex.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct EvalArrays {
    /// `F`.
    pub frames: usize,
    /// `V`.
    pub vertices: usize,
    /// Per mesh of the asset, per vertex of that mesh: its row in `positions` (the row of
    /// its source vertex), so `positions[f][mesh_rows[m][v]]` is mesh `m`'s vertex `v`.
    pub mesh_rows: Vec<Vec<u32>>,
    /// `J`.
    pub joints: usize,
    /// `K`.
    pub max_influences: usize,
    /// `F` seconds.
    pub times: Vec<f32>,
    /// `F x V x 3`, model space.
    pub positions: Vec<f32>,
    /// `F x J x 4 x 4`, row-major.
    pub joint_world: Vec<f32>,
    /// `F x J x 4 x 4`, row-major.
    pub skin_matrices: Vec<f32>,
    /// `V x 3`.
    pub rest_positions: Vec<f32>,
    /// `J` names.
    pub joint_names: Vec<String>,
    /// `V x K`, zero-padded.
    pub influence_joints: Vec<i32>,
    /// `V x K`, zero-padded.
    pub influence_weights: Vec<f32>,
    /// `"lbs"` or `"dqs"`.
    pub skinning: &'static str,
}

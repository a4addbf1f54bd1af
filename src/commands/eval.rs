//! `rigport eval`: pose a rig and dump the skinned result as `.npz`.

use anyhow::{Context as _, Result};
use rigport_eval::sample::{CompiledClip, FrameGrid, SampleJob};
use rigport_eval::skinning::SkinningMethod;
use rigport_eval::{Pose, Rig, RigOutput};
use rigport_model::glam::Mat4;
use rigport_model::Asset;

use crate::cli::{EvalArgs, Skinning};
use crate::context::{clip_names, Context};
use crate::exit::OutputError;
use crate::input;
use crate::npz::{Data, NpzWriter};

/// Row-major 4x4 (numpy's C order) of a column-vector matrix, so `M[j] @ p` works in numpy.
fn push_row_major(out: &mut Vec<f32>, m: &Mat4) {
    out.extend_from_slice(&m.transpose().to_cols_array());
}

/// The arrays of an eval dump, filled frame by frame.
///
/// Vertices are listed mesh by mesh, each mesh in its source vertex order (for OBJ-based
/// rigs: the `v` line order), taking the first output vertex made from each source vertex.
/// `skin_matrices[j]` uses the inverse bind matrix of the first skin whose palette has
/// joint `j`, or the inverse of its rest model matrix when no skin uses it.
pub struct Dump {
    /// Per dumped vertex: (mesh, mesh vertex).
    vertices: Vec<(usize, usize)>,
    rest_positions: Vec<f32>,
    influence_joints: Vec<i32>,
    influence_weights: Vec<f32>,
    max_influences: usize,
    inv_bind: Vec<Mat4>,
    names: Vec<String>,
    skinning: &'static str,
    times: Vec<f32>,
    positions: Vec<f32>,
    joint_world: Vec<f32>,
    skin_matrices: Vec<f32>,
}

impl Dump {
    /// The frame-independent arrays of `asset` as `rig` skins it.
    pub fn new(asset: &Asset, rig: &Rig<'_>, skinning: &'static str) -> Self {
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
        for (mi, mesh) in asset.meshes.iter().enumerate() {
            let skin = rig.skin_of_mesh(mi).map(|s| &asset.skins[s]);
            for &v in &mesh.first_vertex_of_source() {
                let Some(v) = (v != u32::MAX).then_some(v as usize) else {
                    continue;
                };
                vertices.push((mi, v));
                rest_positions.extend_from_slice(&mesh.positions[v].to_array());
                rows.push(match (skin, mesh.attached_to) {
                    (Some(skin), _) => skin
                        .influences
                        .vertex(v)
                        .iter()
                        .map(|i| (skin.joints[i.joint as usize].0 as i32, i.weight))
                        .collect(),
                    (None, Some(j)) => vec![(j.0 as i32, 1.0)],
                    (None, None) => Vec::new(),
                });
            }
        }
        let k = rows.iter().map(Vec::len).max().unwrap_or(0);
        let mut influence_joints = Vec::with_capacity(rows.len() * k);
        let mut influence_weights = Vec::with_capacity(rows.len() * k);
        for row in &rows {
            for slot in 0..k {
                let (j, w) = row.get(slot).copied().unwrap_or((0, 0.0));
                influence_joints.push(j);
                influence_weights.push(w);
            }
        }
        Self {
            vertices,
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
            times: Vec::new(),
            positions: Vec::new(),
            joint_world: Vec::new(),
            skin_matrices: Vec::new(),
        }
    }

    /// Appends one evaluated frame at `time` seconds.
    pub fn push(&mut self, time: f32, posed: &RigOutput) {
        self.times.push(time);
        for (j, ib) in self.inv_bind.iter().enumerate() {
            push_row_major(&mut self.joint_world, &posed.joint_model[j]);
            push_row_major(&mut self.skin_matrices, &(posed.joint_model[j] * *ib));
        }
        for &(m, v) in &self.vertices {
            self.positions
                .extend_from_slice(&posed.positions[m][v].to_array());
        }
    }

    /// The `.npz` arrays; with `frames`, the per-frame arrays get a leading frame axis and
    /// `times` is written.
    pub fn finish(self, frames: bool) -> NpzWriter {
        let v = self.vertices.len();
        let j = self.names.len();
        let f = self.times.len();
        let lead = |shape: &[usize]| -> Vec<usize> {
            if frames {
                std::iter::once(f).chain(shape.iter().copied()).collect()
            } else {
                shape.to_vec()
            }
        };
        let mut npz = NpzWriter::default();
        if frames {
            npz.add("times", &[f], Data::F32(self.times));
        }
        npz.add("positions", &lead(&[v, 3]), Data::F32(self.positions));
        npz.add("rest_positions", &[v, 3], Data::F32(self.rest_positions));
        npz.add("joint_names", &[j], Data::Str(self.names));
        npz.add(
            "joint_world",
            &lead(&[j, 4, 4]),
            Data::F32(self.joint_world),
        );
        npz.add(
            "skin_matrices",
            &lead(&[j, 4, 4]),
            Data::F32(self.skin_matrices),
        );
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

/// Estimated peak bytes of a dump of `frames` frames: positions (f32 x 3 per vertex) and
/// two 4x4 f32 matrices per joint, held as values and again as the `.npz` bytes (measured:
/// a 676 MB dump at a 1.59 GB peak).
fn dump_memory(frames: usize, vertices: usize, joints: usize) -> u64 {
    let per_frame = (vertices as u64)
        .saturating_mul(12)
        .saturating_add((joints as u64).saturating_mul(128));
    (frames as u64).saturating_mul(per_frame).saturating_mul(5) / 2
}

/// Runs `eval`.
pub fn run(ctx: &Context, args: &EvalArgs) -> Result<()> {
    let (plan, imported) = ctx.step("reading input", || input::load_single(&args.input))?;
    ctx.report(&imported.warnings)?;
    let mut limited = None;
    if let Some(max) = args.max_influences {
        let mut asset = imported.asset.clone();
        for skin in &mut asset.skins {
            skin.influences =
                rigport_export::gltf_influences(&imported.asset.skeleton, skin, usize::from(max));
        }
        limited = Some(asset);
    }
    let asset = limited.as_ref().unwrap_or(&imported.asset);
    if !asset.meshes.is_empty()
        && asset.skins.is_empty()
        && asset.meshes.iter().all(|m| m.attached_to.is_none())
    {
        anyhow::bail!(
            "{}: nothing to skin: the rig has no skin weights and no mesh attached to a joint",
            plan.label()
        );
    }
    // --skinning, else the method the source declares for its (first) skin.
    let method = match args.skinning {
        Some(Skinning::Lbs) => SkinningMethod::Lbs,
        Some(Skinning::Dqs) => SkinningMethod::Dqs,
        None => asset.skins.first().map(|s| s.method).unwrap_or_default(),
    };
    let method_name = match method {
        SkinningMethod::Lbs => "lbs",
        SkinningMethod::Dqs => "dqs",
    };
    let rig = Rig::new(asset).context("the rig cannot be evaluated")?;
    let mut dump = Dump::new(asset, &rig, method_name);
    let mut posed = RigOutput::default();
    let clip = match (&args.pose, &args.clip) {
        (Some(_), _) => None,
        (None, Some(name)) => Some(asset.clips.iter().find(|c| &c.name == name).ok_or_else(
            || {
                anyhow::anyhow!(
                    "{}: no clip named {name:?}; clips: {}",
                    plan.label(),
                    clip_names(asset)
                )
            },
        )?),
        (None, None) => asset.clips.first(),
    };
    let frames = clip.is_some();
    match clip {
        None => {
            if args.fps.is_some() {
                anyhow::bail!(
                    "{}: --fps needs a clip to sample; the rig has none",
                    plan.label()
                );
            }
            let pose = match &args.pose {
                Some(path) => {
                    let mut pose = Pose::rest(&asset.skeleton);
                    pose.apply(&rigport_import::json::pose::read(path, &asset.skeleton)?);
                    pose
                }
                None => Pose::rest(&asset.skeleton),
            };
            rig.evaluate_with(&pose, method, &mut posed)?;
            dump.push(0.0, &posed);
        }
        Some(clip) => {
            let compiled = CompiledClip::new(clip, &asset.skeleton)
                .with_context(|| format!("clip {:?} does not fit the skeleton", clip.name))?;
            let times = match args.fps {
                None => compiled.key_times(),
                Some(fps) => {
                    if !(fps.is_finite() && fps > 0.0) {
                        anyhow::bail!("--fps {fps}: expected a positive frame rate");
                    }
                    FrameGrid::new(compiled.start(), compiled.end(), fps)?.into_times()
                }
            };
            let vertices: usize = asset.meshes.iter().map(|m| m.positions.len()).sum();
            crate::memory::budget().check(
                format_args!(
                    "{}: {} frames of {vertices} vertices and {} joints",
                    args.output.display(),
                    times.len(),
                    asset.skeleton.len()
                ),
                dump_memory(times.len(), vertices, asset.skeleton.len()),
            )?;
            let rest = Pose::rest(&asset.skeleton);
            let mut pose = rest.clone();
            for &t in &times {
                SampleJob {
                    clip: &compiled,
                    time: t,
                    rest: &rest.local,
                    output: &mut pose.local,
                }
                .run()?;
                rig.evaluate_with(&pose, method, &mut posed)?;
                dump.push(t, &posed);
            }
        }
    }
    let bytes = dump.finish(frames).finish().with_context(|| OutputError {
        path: args.output.display().to_string(),
    })?;
    rigport_export::write_atomic(&args.output, &bytes).with_context(|| OutputError {
        path: args.output.display().to_string(),
    })?;
    if !ctx.quiet {
        let what = match clip {
            Some(c) => format!(", clip {:?}", c.name),
            None => String::new(),
        };
        eprintln!(
            "wrote {} ({} joints, {} meshes{what})",
            args.output.display(),
            asset.skeleton.len(),
            asset.meshes.len()
        );
    }
    Ok(())
}

//! `rigport eval`: pose a rig and dump the skinned result as `.npz`.

use anyhow::{Context as _, Result};
use rigport_eval::{Pose, Rig, RigOutput};
use rigport_model::glam::Mat4;
use rigport_model::Asset;

use super::Context;
use crate::cli::EvalArgs;
use crate::exit::OutputError;
use crate::npz::{Data, NpzWriter};
use crate::{input, pose};

/// Row-major 4x4 (numpy's C order) of a column-vector matrix, so `M[j] @ p` works in numpy.
fn push_row_major(out: &mut Vec<f32>, m: &Mat4) {
    out.extend_from_slice(&m.transpose().to_cols_array());
}

/// Builds the dump's arrays for one evaluated pose.
///
/// Vertices are listed mesh by mesh, each mesh in its source vertex order (for OBJ-based
/// rigs: the `v` line order), taking the first output vertex made from each source vertex.
/// `skin_matrices[j]` uses the inverse bind matrix of the first skin whose palette has
/// joint `j`, or the inverse of its rest model matrix when no skin uses it.
pub fn dump(asset: &Asset, rig: &Rig<'_>, posed: &RigOutput) -> NpzWriter {
    let rest = asset.skeleton.model_rest_matrices();
    let joint_count = asset.skeleton.len();
    let mut inv_bind: Vec<Option<Mat4>> = vec![None; joint_count];
    for skin in &asset.skins {
        for (p, j) in skin.joints.iter().enumerate() {
            inv_bind[j.get()].get_or_insert(skin.inv_bind[p]);
        }
    }
    let mut joint_world = Vec::with_capacity(joint_count * 16);
    let mut skin_matrices = Vec::with_capacity(joint_count * 16);
    for j in 0..joint_count {
        push_row_major(&mut joint_world, &posed.joint_model[j]);
        let ib = inv_bind[j].unwrap_or_else(|| rest[j].inverse());
        push_row_major(&mut skin_matrices, &(posed.joint_model[j] * ib));
    }

    let mut positions = Vec::new();
    let mut rest_positions = Vec::new();
    let mut rows: Vec<Vec<(i32, f32)>> = Vec::new();
    for (mi, mesh) in asset.meshes.iter().enumerate() {
        let skin = rig.skin_of_mesh(mi).map(|s| &asset.skins[s]);
        for &v in &mesh.first_vertex_of_source() {
            let Some(v) = (v != u32::MAX).then_some(v as usize) else {
                continue;
            };
            positions.extend_from_slice(&posed.positions[mi][v].to_array());
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
    let v = rows.len();
    let names: Vec<String> = asset
        .skeleton
        .joints()
        .iter()
        .map(|j| j.name.clone())
        .collect();
    let mut npz = NpzWriter::default();
    npz.add("positions", &[v, 3], Data::F32(positions));
    npz.add("rest_positions", &[v, 3], Data::F32(rest_positions));
    npz.add("joint_names", &[joint_count], Data::Str(names));
    npz.add("joint_world", &[joint_count, 4, 4], Data::F32(joint_world));
    npz.add(
        "skin_matrices",
        &[joint_count, 4, 4],
        Data::F32(skin_matrices),
    );
    npz.add("influence_joints", &[v, k], Data::I32(influence_joints));
    npz.add("influence_weights", &[v, k], Data::F32(influence_weights));
    npz
}

/// Runs `eval`.
pub fn run(ctx: &Context, args: &EvalArgs) -> Result<()> {
    let plan = input::single_plan(&args.input)?;
    let imported = ctx.step(&format!("reading {}", plan.label()), || plan.import())?;
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
    if asset.skins.is_empty() && asset.meshes.iter().all(|m| m.attached_to.is_none()) {
        anyhow::bail!(
            "{}: nothing to skin: the rig has no skin weights and no mesh attached to a joint",
            plan.label()
        );
    }
    let pose = match &args.pose {
        Some(path) => pose::load(path, &asset.skeleton)?,
        None => Pose::rest(&asset.skeleton),
    };
    let rig = Rig::new(asset).context("the rig cannot be evaluated")?;
    let mut posed = RigOutput::default();
    rig.evaluate(&pose, &mut posed)?;
    let bytes = dump(asset, &rig, &posed)
        .finish()
        .with_context(|| OutputError {
            path: args.output.display().to_string(),
        })?;
    rigport_export::write_atomic(&args.output, &bytes).with_context(|| OutputError {
        path: args.output.display().to_string(),
    })?;
    if !ctx.quiet {
        eprintln!(
            "wrote {} ({} joints, {} meshes)",
            args.output.display(),
            asset.skeleton.len(),
            asset.meshes.len()
        );
    }
    Ok(())
}

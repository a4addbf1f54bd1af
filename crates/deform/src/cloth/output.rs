//! A finished simulation into the asset: morph targets on the garment mesh and a
//! morph-weight track on the clip (one target per frame, one-hot weights, or a compressed
//! basis as the DQS bake does), so every writer can store it.

use rigport_model::{Asset, Interpolation, Mesh, MeshIndex, MorphTarget, Track, TrackTarget};

use super::{ClothError, Simulation};
use crate::bake::compress_correctives;
use rigport_eval::sample::{bake, ChannelMask};

/// What [`add_garment`] did.
#[derive(Clone, Debug, PartialEq)]
pub struct GarmentBake {
    /// The garment mesh's index in the asset.
    pub mesh: usize,
    /// Morph targets written.
    pub targets: usize,
    /// The largest distance between a frame's simulated position and what the targets
    /// and weights give (0 with one target per frame, up to rounding).
    pub max_error: f32,
}

/// Adds `mesh` (the garment, unskinned, in model space) to `asset` with the simulation as
/// morph targets, and a `LINEAR` morph-weight track at the frame times on the simulated
/// clip. Mesh vertices split at seams take their source vertex's particle. With
/// `targets = Some(k)` the per-frame displacements are compressed to at most `k` shared
/// targets ([`compress_correctives`]). When the simulation looped the clip, the clip's
/// joint tracks are replaced by the looped poses baked at the frame times.
///
/// # Errors
/// [`ClothError::NonFinite`] if the mesh does not fit the simulation's particle count,
/// and compression or baking failures.
pub fn add_garment(
    asset: &mut Asset,
    mut mesh: Mesh,
    sim: &Simulation,
    targets: Option<usize>,
) -> Result<GarmentBake, ClothError> {
    let frames = sim.times.len();
    let v = mesh.positions.len();
    if mesh.source_vertex.len() != v
        || mesh
            .source_vertex
            .iter()
            .any(|&s| s as usize >= sim.particles)
    {
        return Err(ClothError::PinVertex {
            garment: mesh.name.clone(),
            vertex: mesh.source_vertex_count() as u32,
            count: sim.particles,
        });
    }
    mesh.attached_to = None;
    mesh.morph_targets.clear();
    mesh.morph_weights.clear();
    let mut deltas = Vec::with_capacity(frames * v);
    for f in 0..frames {
        let x = sim.frame(f);
        for (rest, &s) in mesh.positions.iter().zip(&mesh.source_vertex) {
            deltas.push(x.get(s as usize).copied().unwrap_or(*rest) - *rest);
        }
    }
    let (morphs, weights, max_error) = match targets {
        Some(k) if k < frames => {
            let c = compress_correctives(&deltas, frames, k)?;
            let morphs = c
                .targets
                .into_iter()
                .enumerate()
                .map(|(i, d)| MorphTarget {
                    name: format!("cloth_{i}"),
                    position_deltas: d,
                    normal_deltas: None,
                })
                .collect();
            (morphs, c.frame_weights, c.max_error)
        }
        _ => {
            let morphs = deltas
                .chunks_exact(v.max(1))
                .enumerate()
                .map(|(f, d)| MorphTarget {
                    name: format!("frame_{f}"),
                    position_deltas: d.to_vec(),
                    normal_deltas: None,
                })
                .collect();
            let weights = (0..frames)
                .flat_map(|f| (0..frames).map(move |t| if t == f { 1.0 } else { 0.0 }))
                .collect();
            (morphs, weights, 0.0)
        }
    };
    let morphs: Vec<MorphTarget> = morphs;
    let count = morphs.len();
    mesh.morph_targets = morphs;
    let index = asset.meshes.len();
    asset.meshes.push(mesh);
    let clip = asset.clips.get_mut(sim.clip).ok_or(ClothError::NoClip)?;
    if let Some(poses) = &sim.looped_poses {
        let joints = asset.skeleton.len();
        let mask = ChannelMask::all(joints);
        let baked = bake(&clip.name, &sim.times, poses, &mask)?;
        clip.tracks = baked.tracks;
    }
    clip.tracks.push(Track {
        target: TrackTarget::MorphWeights(MeshIndex(index as u32)),
        interpolation: Interpolation::Linear,
        times: sim.times.clone(),
        values: weights,
    });
    Ok(GarmentBake {
        mesh: index,
        targets: count,
        max_error,
    })
}

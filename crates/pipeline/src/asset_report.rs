//! What is in a rig, as text or JSON (`rigport inspect`).

use std::io::Write;

use rigport_model::{Asset, TrackTarget};
use serde::Serialize;

/// What is in a rig (`rigport inspect`): its joints, meshes, skins and clips, as text
/// ([`AssetReport::write_text`]) or JSON (serde).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub(crate) struct AssetReport {
    /// Where the rig came from (its main file).
    pub source: String,
    /// The asset's name.
    pub name: String,
    /// Metres per source unit, when the source states it.
    pub meters_per_unit: Option<f64>,
    /// One entry per joint, parents first.
    pub joints: Vec<JointReport>,
    /// One entry per mesh.
    pub meshes: Vec<MeshReport>,
    /// One entry per clip.
    pub clips: Vec<ClipReport>,
    /// Names of the joints the rig marks as IK handles.
    pub ik_handles: Vec<String>,
    /// The import's warnings, as printed.
    pub warnings: Vec<String>,
}

/// One joint.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub(crate) struct JointReport {
    /// Its index in the skeleton.
    pub index: usize,
    /// Its name.
    pub name: String,
    /// Its parent's name (`None` for a root).
    pub parent: Option<String>,
    /// Rest translation relative to the parent, source units.
    pub rest_translation: [f32; 3],
    /// Rest rotation relative to the parent, quaternion xyzw.
    pub rest_rotation_xyzw: [f32; 4],
}

/// One mesh.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub(crate) struct MeshReport {
    /// Its name.
    pub name: String,
    /// Vertices (after splitting by normal and UV).
    pub vertices: usize,
    /// Vertices of the source.
    pub source_vertices: usize,
    /// Triangles.
    pub triangles: usize,
    /// Whether it has normals.
    pub has_normals: bool,
    /// Whether it has texture coordinates.
    pub has_uvs: bool,
    /// Morph targets.
    pub morph_targets: usize,
    /// Bounding box corners, model space (`None` for no vertices).
    pub bounds_min: Option<[f32; 3]>,
    /// See `bounds_min`.
    pub bounds_max: Option<[f32; 3]>,
    /// The joint a rigid mesh follows.
    pub attached_to: Option<String>,
    /// Present when skinned.
    pub skin: Option<SkinReport>,
}

/// A mesh's skin.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub(crate) struct SkinReport {
    /// Joints in its palette.
    pub palette_joints: usize,
    /// The most influences on one vertex.
    pub max_influences: usize,
    /// `influence_histogram[k]` = vertices with exactly k influences.
    pub influence_histogram: Vec<usize>,
}

/// One clip.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub(crate) struct ClipReport {
    /// Its name.
    pub name: String,
    /// Its duration, seconds.
    pub duration_s: f32,
    /// Tracks.
    pub tracks: usize,
    /// Keys over all tracks.
    pub keys: usize,
    /// Joints with at least one track.
    pub animated_joints: usize,
}

impl AssetReport {
    /// The report of `asset`, read from `source`, with its import `warnings`.
    pub(crate) fn new(source: String, asset: &Asset, warnings: Vec<String>) -> AssetReport {
        let skel = &asset.skeleton;
        let joints = skel
            .joints()
            .iter()
            .enumerate()
            .map(|(index, j)| JointReport {
                index,
                name: j.name.clone(),
                parent: j.parent.map(|p| skel.joint(p).name.clone()),
                rest_translation: j.rest_local.translation.to_array(),
                rest_rotation_xyzw: j.rest_local.rotation.to_array(),
            })
            .collect();
        let meshes = asset
            .meshes
            .iter()
            .enumerate()
            .map(|(mi, m)| {
                let skin = asset.skins.iter().find(|s| s.mesh.get() == mi).map(|s| {
                    let max = s.influences.max_per_vertex();
                    let mut hist = vec![0; max + 1];
                    for row in s.influences.rows() {
                        hist[row.len()] += 1;
                    }
                    SkinReport {
                        palette_joints: s.joints.len(),
                        max_influences: max,
                        influence_histogram: hist,
                    }
                });
                let bounds = m.bounds();
                MeshReport {
                    name: m.name.clone(),
                    vertices: m.vertex_count(),
                    source_vertices: m.source_vertex_count(),
                    triangles: m.triangles.len(),
                    has_normals: m.normals.is_some(),
                    has_uvs: m.uvs.is_some(),
                    morph_targets: m.morph_targets.len(),
                    bounds_min: bounds.map(|b| b.0.to_array()),
                    bounds_max: bounds.map(|b| b.1.to_array()),
                    attached_to: m.attached_to.map(|j| skel.joint(j).name.clone()),
                    skin,
                }
            })
            .collect();
        let clips = asset
            .clips
            .iter()
            .map(|c| {
                let mut joints: Vec<usize> = c
                    .tracks
                    .iter()
                    .filter_map(|t| match t.target {
                        TrackTarget::Translation(j)
                        | TrackTarget::Rotation(j)
                        | TrackTarget::Scale(j) => Some(j.get()),
                        TrackTarget::MorphWeights(_) => None,
                    })
                    .collect();
                joints.sort_unstable();
                joints.dedup();
                ClipReport {
                    name: c.name.clone(),
                    duration_s: c.duration(),
                    tracks: c.tracks.len(),
                    keys: c.tracks.iter().map(|t| t.times.len()).sum(),
                    animated_joints: joints.len(),
                }
            })
            .collect();
        AssetReport {
            source,
            name: asset.name.clone(),
            meters_per_unit: asset.meters_per_unit,
            joints,
            meshes,
            clips,
            ik_handles: asset
                .ik_handles
                .iter()
                .map(|j| skel.joint(*j).name.clone())
                .collect(),
            warnings,
        }
    }

    /// Writes the report as indented text (without the warnings).
    ///
    /// # Errors
    /// Writing to `out` fails.
    pub(crate) fn write_text(&self, out: &mut impl Write) -> std::io::Result<()> {
        let r = self;
        writeln!(out, "{} ({})", r.name, r.source)?;
        if let Some(m) = r.meters_per_unit {
            writeln!(out, "  units: {m} m per unit")?;
        }
        writeln!(out, "  joints: {}", r.joints.len())?;
        for j in &r.joints {
            match &j.parent {
                Some(p) => writeln!(out, "    {:4} {} <- {}", j.index, j.name, p)?,
                None => writeln!(out, "    {:4} {} (root)", j.index, j.name)?,
            }
        }
        writeln!(out, "  meshes: {}", r.meshes.len())?;
        for m in &r.meshes {
            write!(
                out,
                "    {:?}: {} vertices ({} source), {} triangles",
                m.name, m.vertices, m.source_vertices, m.triangles
            )?;
            if m.has_normals {
                write!(out, ", normals")?;
            }
            if m.has_uvs {
                write!(out, ", uvs")?;
            }
            if m.morph_targets > 0 {
                write!(out, ", {} morph targets", m.morph_targets)?;
            }
            if let Some(j) = &m.attached_to {
                write!(out, ", attached to {j}")?;
            }
            writeln!(out)?;
            if let (Some(lo), Some(hi)) = (m.bounds_min, m.bounds_max) {
                writeln!(out, "      bounds: {lo:?} .. {hi:?}")?;
            }
            if let Some(s) = &m.skin {
                writeln!(
                    out,
                    "      skinned by {} joints, up to {} influences per vertex",
                    s.palette_joints, s.max_influences
                )?;
                let hist: Vec<String> = s
                    .influence_histogram
                    .iter()
                    .enumerate()
                    .filter(|(_, n)| **n > 0)
                    .map(|(k, n)| format!("{k}: {n}"))
                    .collect();
                writeln!(
                    out,
                    "      vertices by influence count: {}",
                    hist.join(", ")
                )?;
            }
        }
        if !r.ik_handles.is_empty() {
            writeln!(out, "  IK handles: {}", r.ik_handles.join(", "))?;
        }
        writeln!(out, "  clips: {}", r.clips.len())?;
        for c in &r.clips {
            writeln!(
                out,
                "    {:?}: {:.3} s, {} tracks on {} joints, {} keys",
                c.name, c.duration_s, c.tracks, c.animated_joints, c.keys
            )?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use rigport_model::{Asset, Joint, Skeleton, Transform};

    use super::AssetReport;

    #[test]
    fn lists_the_joints_as_text() {
        let root = Joint {
            name: "hips".into(),
            parent: None,
            rest_local: Transform::IDENTITY,
        };
        let asset = Asset {
            skeleton: Skeleton::new(vec![root]).expect("one root"),
            ..Asset::default()
        };
        let report = AssetReport::new("hips.bvh".into(), &asset, Vec::new());
        let mut text = Vec::new();
        report.write_text(&mut text).expect("in memory");
        assert!(String::from_utf8_lossy(&text).contains("joints: 1\n       0 hips (root)"));
    }
}

//! Time-sampled `xformOp`s on the Skeleton prim or above it (SkelRoot, Xforms: a Reality
//! Converter or Blender file that moves the whole character) become root motion.
//!
//! The model keeps one static placement (`SceneFrame::model_to_scene`, the world transform
//! `M0` at the default time); at time code `t` UsdSkel places the skeleton by `W(t)`, so
//! every root joint's local transform becomes `M0⁻¹ · W(t) · L(t)` (`L` its own track, or
//! its rest transform), decomposed to TRS (shear is lost). It is sampled at every time
//! sample of those ops, every key of the joint's tracks and every integer time code in
//! between, so it is exact at those times; between them the TRS is interpolated (translate
//! and rotate ops animated together move the joint on a curve USD would sample the same
//! way only at the frames). Every clip gets it; without a SkelAnimation it is a clip of its
//! own, named after the prim whose transforms are animated.
//!
//! A static (unskinned) mesh under time-sampled ops (Reality Converter's `AnimatedCube`,
//! `BoxAnimated`) gets a root joint of its own, named after the mesh prim, whose rest is
//! the prim's transform in model space at the default time (`M0⁻¹ · W`) and whose tracks
//! are `M0⁻¹ · W(t)`, sampled at the same times as root motion; the mesh is attached to it
//! with its points in the prim's own space. glTF then plays it as node animation and USD
//! through a rigid binding.

use glam::{DMat4, DQuat, DVec3};
use rigport_model::glam::{Quat, Vec3};
use rigport_model::{
    Clip, Interpolation, Joint, JointIndex, Mesh, MeshIndex, Skeleton, Track, TrackTarget,
};

use super::importer::Importer;
use super::skeleton::{matches_trs, trs_of};
use super::xform;
use crate::ImportError;

/// A static mesh under time-sampled transforms: its index in the asset, its prim, and the
/// prims whose ops are animated.
pub(super) struct MovingMesh {
    pub(super) mesh: MeshIndex,
    pub(super) prim: usize,
    pub(super) animated: Vec<String>,
}

/// Most samples of root motion one clip may get (one per integer time code): a stage
/// whose transforms span more time codes is sampled at their own samples only.
const MAX_FRAMES: f64 = 100_000.0;

/// The value of a LINEAR track at `t` (seconds): lerp, slerp for rotations, held outside.
fn sample(track: &Track, t: f32) -> Vec<f32> {
    let c = track.components();
    let n = track.times.len();
    let at = |k: usize| track.values.get(k * c..(k + 1) * c).unwrap_or_default();
    let (Some(&first), Some(&last)) = (track.times.first(), track.times.last()) else {
        return Vec::new();
    };
    if t <= first || n == 1 {
        return at(0).to_vec();
    }
    if t >= last {
        return at(n - 1).to_vec();
    }
    let k = track.times.partition_point(|&x| x <= t).saturating_sub(1);
    let (t0, t1) = (track.times[k], track.times[k + 1]);
    let u = (t - t0) / (t1 - t0);
    let (a, b) = (at(k), at(k + 1));
    if matches!(track.target, TrackTarget::Rotation(_)) && c == 4 {
        let qa = Quat::from_slice(a);
        let qb = Quat::from_slice(b);
        return qa.slerp(qb, u).to_array().to_vec();
    }
    a.iter().zip(b).map(|(x, y)| x + (y - x) * u).collect()
}

/// Scales a mesh's points and morph deltas by `scale` (per axis, in its own space), its
/// normals and normal deltas by the inverse transpose; a mirroring scale flips the winding.
fn scale_mesh(mesh: &mut Mesh, scale: Vec3) {
    for p in &mut mesh.positions {
        *p *= scale;
    }
    let inverse = scale.recip();
    if let Some(normals) = &mut mesh.normals {
        for n in normals {
            *n = (*n * inverse).normalize_or_zero();
        }
    }
    for target in &mut mesh.morph_targets {
        for d in &mut target.position_deltas {
            *d *= scale;
        }
        if let Some(deltas) = &mut target.normal_deltas {
            for d in deltas {
                *d *= inverse;
            }
        }
    }
    if scale.x * scale.y * scale.z < 0.0 {
        for t in &mut mesh.triangles {
            t.swap(1, 2);
        }
    }
}

impl<'l> Importer<'l, '_> {
    /// The world transform of prim `index` at time code `time` (`None`: the default time).
    pub(super) fn world_at(&self, index: usize, time: Option<f64>) -> Result<DMat4, ImportError> {
        let mut m = DMat4::IDENTITY;
        for p in self.stage.ancestry(index) {
            let local = xform::local(p, time).map_err(|e| self.err(&p.path, e))?;
            if let Some(local) = local {
                m = local.matrix * m;
                if local.resets {
                    break;
                }
            }
        }
        Ok(m)
    }

    /// Time codes of every `xformOp` sample on prim `index` and its ancestors (up to a
    /// `!resetXformStack!`), sorted, without duplicates.
    fn xform_sample_times(&self, index: usize) -> Vec<f64> {
        let mut times = Vec::new();
        for p in self.stage.ancestry(index) {
            for (name, prop) in &p.props {
                if name.starts_with("xformOp:") {
                    if let Some(s) = &prop.samples {
                        times.extend(s.iter().map(|(t, _)| *t).filter(|t| t.is_finite()));
                    }
                }
            }
            if xform::local(p, None)
                .ok()
                .flatten()
                .is_some_and(|l| l.resets)
            {
                break;
            }
        }
        times.sort_by(f64::total_cmp);
        times.dedup();
        times
    }

    /// The time codes transforms of prim `index` are sampled at: every `xformOp` sample on
    /// it and its ancestors and every integer time code between the first and the last
    /// (unless there are more than [`MAX_FRAMES`]); empty when nothing is time-sampled.
    fn xform_times(&self, index: usize) -> Vec<f64> {
        let samples = self.xform_sample_times(index);
        let (Some(&first), Some(&last)) = (samples.first(), samples.last()) else {
            return Vec::new();
        };
        let mut times = samples.clone();
        if last - first <= MAX_FRAMES {
            let mut tc = first.ceil();
            while tc < last {
                times.push(tc);
                tc += 1.0;
            }
        }
        times
    }

    /// Attaches every static mesh of `moving` to a new root joint carrying its animated
    /// transforms (see the module doc), added to every clip (a clip of its own, named after
    /// the first animated prim, when there is none).
    pub(super) fn moving_meshes(
        &mut self,
        skeleton: &mut Skeleton,
        meshes: &mut [Mesh],
        clips: &mut Vec<Clip>,
        moving: &[MovingMesh],
    ) -> Result<(), ImportError> {
        if moving.is_empty() {
            return Ok(());
        }
        let mut joints = skeleton.joints().to_vec();
        let limits = skeleton.limits().to_vec();
        let inverse_m0 = self.skel_world.inverse();
        let mut tracks = Vec::new();
        for m in moving {
            let prim = self.prim(m.prim).clone();
            let mut name = prim.name.to_string();
            let mut k = 1;
            while joints.iter().any(|j| j.name == name) {
                k += 1;
                name = format!("{}_{k}", prim.name);
            }
            let joint = JointIndex(joints.len() as u32);
            let rest = inverse_m0 * self.world_at(m.prim, None)?;
            let mut rest_trs = trs_of(&rest);
            let mut out = [Vec::new(), Vec::new(), Vec::new()];
            let mut seconds = Vec::new();
            let mut prev: Option<Quat> = None;
            let mut sheared = !matches_trs(&rest, &trs_of(&rest));
            let mut times = self.xform_times(m.prim);
            times.sort_by(f64::total_cmp);
            times.dedup_by(|a, b| ((*a / self.tcps) as f32) == ((*b / self.tcps) as f32));
            let mut samples = Vec::with_capacity(times.len());
            for &tc in &times {
                let local = inverse_m0 * self.world_at(m.prim, Some(tc))?;
                let trs = trs_of(&local);
                sheared |= !matches_trs(&local, &trs);
                samples.push(trs);
            }
            // A scale that does not change over time (the skeleton's space is often scaled
            // against the mesh's: a centimetre stage's `scale 100`) goes into the points,
            // so the joint's scale is 1 (SkelAnimation scales are half precision).
            let fixed = rest_trs.scale;
            let constant = samples
                .iter()
                .all(|t| (t.scale - fixed).abs().max_element() <= 1e-6 * fixed.abs().max_element());
            if constant && fixed != Vec3::ONE && fixed.min_element().abs() > 0.0 {
                if let Some(mesh) = meshes.get_mut(m.mesh.get()) {
                    scale_mesh(mesh, fixed);
                }
                rest_trs.scale = Vec3::ONE;
                for t in &mut samples {
                    t.scale = Vec3::ONE;
                }
            }
            joints.push(Joint {
                name: name.clone(),
                parent: None,
                rest_local: rest_trs,
            });
            for (trs, &tc) in samples.iter().zip(&times) {
                let mut q = trs.rotation;
                if prev.is_some_and(|p| p.dot(q) < 0.0) {
                    q = -q;
                }
                prev = Some(q);
                out[0].extend(trs.translation.to_array());
                out[1].extend(q.to_array());
                out[2].extend(trs.scale.to_array());
                seconds.push((tc / self.tcps) as f32);
            }
            for (target, values) in [
                TrackTarget::Translation(joint),
                TrackTarget::Rotation(joint),
                TrackTarget::Scale(joint),
            ]
            .into_iter()
            .zip(out)
            {
                tracks.push(Track {
                    target,
                    interpolation: Interpolation::Linear,
                    times: seconds.clone(),
                    values,
                });
            }
            if let Some(mesh) = meshes.get_mut(m.mesh.get()) {
                mesh.attached_to = Some(joint);
                mesh.node_name = name.clone();
            }
            let path = prim.path.clone();
            self.note(
                &path,
                format!(
                    "a static mesh under time-sampled transforms (xformOp) on {}: attached to \
                     a joint {name:?} that carries them (sampled at every time code between \
                     their samples)",
                    m.animated.join(", ")
                ),
            );
            if sheared {
                self.repaired(
                    &path,
                    "its transform has shear, which a joint's translation, rotation and scale \
                     cannot hold: the shear is lost",
                );
            }
        }
        let mut built = Skeleton::new(joints).map_err(|problems| {
            self.err(
                &self.prim(moving[0].prim).path,
                problems
                    .iter()
                    .map(ToString::to_string)
                    .collect::<Vec<_>>()
                    .join("; "),
            )
        })?;
        built.set_limits(limits);
        *skeleton = built;
        if clips.is_empty() {
            let name = moving[0]
                .animated
                .first()
                .and_then(|p| p.trim_matches(['<', '>']).rsplit('/').next())
                .unwrap_or("xform")
                .to_string();
            clips.push(Clip {
                name,
                tracks: Vec::new(),
            });
        }
        for clip in clips.iter_mut() {
            clip.tracks.extend(tracks.iter().cloned());
        }
        Ok(())
    }

    /// Adds the animated transforms above Skeleton prim `skel_index` to every clip as root
    /// motion (see the module doc); `name` names the clip made when there is none.
    pub(super) fn root_motion(
        &self,
        skel_index: usize,
        skeleton: &Skeleton,
        clips: &mut Vec<Clip>,
        name: &str,
    ) -> Result<(), ImportError> {
        let xform_times = self.xform_times(skel_index);
        if xform_times.is_empty() {
            return Ok(());
        }
        let inverse_m0 = self.skel_world.inverse();
        let roots: Vec<usize> = skeleton
            .joints()
            .iter()
            .enumerate()
            .filter(|(_, j)| j.parent.is_none())
            .map(|(i, _)| i)
            .collect();
        if clips.is_empty() {
            clips.push(Clip {
                name: name.to_string(),
                tracks: Vec::new(),
            });
        }
        for clip in clips.iter_mut() {
            for &j in &roots {
                let joint = JointIndex(j as u32);
                let rest = skeleton.joints()[j].rest_local;
                let own: Vec<Track> = clip
                    .tracks
                    .iter()
                    .filter(|t| {
                        matches!(t.target,
                            TrackTarget::Translation(x) | TrackTarget::Rotation(x)
                            | TrackTarget::Scale(x) if x == joint)
                    })
                    .cloned()
                    .collect();
                clip.tracks.retain(|t| {
                    !matches!(t.target,
                        TrackTarget::Translation(x) | TrackTarget::Rotation(x)
                        | TrackTarget::Scale(x) if x == joint)
                });
                // Key times in time codes: the transforms' and the joint's own keys.
                let mut times: Vec<f64> = xform_times.clone();
                for t in &own {
                    times.extend(t.times.iter().map(|&s| f64::from(s) * self.tcps));
                }
                times.sort_by(f64::total_cmp);
                times.dedup_by(|a, b| ((*a / self.tcps) as f32) == ((*b / self.tcps) as f32));
                let of = |target: fn(JointIndex) -> TrackTarget| {
                    own.iter().find(|t| t.target == target(joint))
                };
                let (tt, rt, st) = (
                    of(TrackTarget::Translation),
                    of(TrackTarget::Rotation),
                    of(TrackTarget::Scale),
                );
                let mut out = [Vec::new(), Vec::new(), Vec::new()];
                let mut seconds = Vec::with_capacity(times.len());
                let mut prev: Option<Quat> = None;
                for &tc in &times {
                    let s = (tc / self.tcps) as f32;
                    let t = tt.map_or(rest.translation, |t| Vec3::from_slice(&sample(t, s)));
                    let r = rt.map_or(rest.rotation, |t| Quat::from_slice(&sample(t, s)));
                    let sc = st.map_or(rest.scale, |t| Vec3::from_slice(&sample(t, s)));
                    let local = DMat4::from_scale_rotation_translation(
                        sc.as_dvec3(),
                        r.as_dquat().normalize(),
                        t.as_dvec3(),
                    );
                    let m = inverse_m0 * self.world_at(skel_index, Some(tc))? * local;
                    let (scale, rotation, translation): (DVec3, DQuat, DVec3) =
                        m.to_scale_rotation_translation();
                    let mut q = rotation.normalize().as_quat();
                    if prev.is_some_and(|p| p.dot(q) < 0.0) {
                        q = -q;
                    }
                    prev = Some(q);
                    out[0].extend(translation.as_vec3().to_array());
                    out[1].extend(q.to_array());
                    out[2].extend(scale.as_vec3().to_array());
                    seconds.push(s);
                }
                for (target, values) in [
                    TrackTarget::Translation(joint),
                    TrackTarget::Rotation(joint),
                    TrackTarget::Scale(joint),
                ]
                .into_iter()
                .zip(out)
                {
                    clip.tracks.push(Track {
                        target,
                        interpolation: Interpolation::Linear,
                        times: seconds.clone(),
                        values,
                    });
                }
            }
        }
        Ok(())
    }
}

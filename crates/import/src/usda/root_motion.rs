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

use glam::{DMat4, DQuat, DVec3};
use rigport_model::glam::{Quat, Vec3};
use rigport_model::{Clip, Interpolation, JointIndex, Skeleton, Track, TrackTarget};

use super::importer::Importer;
use super::xform;
use crate::ImportError;

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

    /// Adds the animated transforms above Skeleton prim `skel_index` to every clip as root
    /// motion (see the module doc); `name` names the clip made when there is none.
    pub(super) fn root_motion(
        &self,
        skel_index: usize,
        skeleton: &Skeleton,
        clips: &mut Vec<Clip>,
        name: &str,
    ) -> Result<(), ImportError> {
        let samples = self.xform_sample_times(skel_index);
        let (Some(&first), Some(&last)) = (samples.first(), samples.last()) else {
            return Ok(());
        };
        let mut xform_times = samples.clone();
        if last - first <= MAX_FRAMES {
            let mut tc = first.ceil();
            while tc < last {
                xform_times.push(tc);
                tc += 1.0;
            }
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

//! The error of a reduced clip against its original, measured as the reducer measures it:
//! model-space distances of joints and of virtual points fixed to them, at every original
//! key time. With one distance for every joint, 3 cm, this is ACL's error metric (virtual
//! vertices at a "shell distance" from each bone; ACL's `docs/error_metrics.md`).

use rigport_model::quantize::rotation_as_i16;
use rigport_model::{Clip, Interpolation, Skeleton};

use super::channel::{collect_channels, Kind};
use super::{ReduceError, ReduceOptions, Reducer, Tuning};

/// The largest and the mean model-space error.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PointError {
    /// The largest distance, in the skeleton's length unit, over every joint, virtual point
    /// and original key time.
    pub max: f32,
    /// The mean over joints and original key times of the largest of a joint's points.
    pub mean: f32,
}

/// The error of `reduced` (the same tracks as `original`, with fewer keys) against
/// `original`, with virtual points at `point_distance[j]` from each joint `j` (see
/// [`ReduceOptions::point_distance`]); with `rotations_i16`, the reduced clip's LINEAR and
/// STEP rotations are read as 16-bit normalized components, as a writer stores them.
///
/// ```
/// use rigport_anim::reduce::{metric::point_error, reduce_clip, ReduceOptions};
/// use rigport_model::glam::{Quat, Vec3};
/// use rigport_model::{Clip, Interpolation, Joint, JointIndex, Skeleton, Track, TrackTarget, Transform};
///
/// let skeleton = Skeleton::new(vec![Joint { name: "hip".into(), parent: None,
///     rest_local: Transform::IDENTITY }]).expect("valid");
/// let times: Vec<f32> = (0..61).map(|k| k as f32 / 60.0).collect();
/// let values = times.iter().flat_map(|t| Quat::from_rotation_y(3.0 * t).to_array()).collect();
/// let clip = Clip { name: "turn".into(), tracks: vec![Track {
///     target: TrackTarget::Rotation(JointIndex(0)), interpolation: Interpolation::Linear,
///     times, values }] };
/// let options = ReduceOptions { tolerance: 1e-4, point_distance: vec![0.03],
///     rotations_i16: true, uniform_rate: true };
/// let (reduced, stats) = reduce_clip(&clip, &skeleton, &options)?;
/// let acl = point_error(&clip, &reduced, &skeleton, &[0.03], true)?;
/// assert_eq!(acl.max, stats.max_error);
/// assert!(acl.max <= 1e-4 && acl.mean <= acl.max);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// # Errors
/// As [`super::reduce`], for either clip; a track of `reduced` that does not animate what
/// the same track of `original` does is [`ReduceError::Mismatch`].
pub fn point_error(
    original: &Clip,
    reduced: &Clip,
    skeleton: &Skeleton,
    point_distance: &[f32],
    rotations_i16: bool,
) -> Result<PointError, ReduceError> {
    // Validates the reduced clip's tracks too.
    collect_channels(reduced, skeleton, false, false)?;
    let channels = collect_channels(original, skeleton, false, false)?;
    let options = ReduceOptions {
        point_distance: point_distance.to_vec(),
        ..ReduceOptions::default()
    };
    let mut reducer = Reducer::new(skeleton, &options, Tuning::DEFAULT, channels)?;
    for chan in &mut reducer.channels {
        let track = reduced
            .tracks
            .get(chan.track)
            .filter(|t| t.target == chan.original.target)
            .ok_or_else(|| ReduceError::Mismatch {
                clip: reduced.name.clone(),
                track: chan.track,
            })?;
        let mut track = track.clone();
        if rotations_i16
            && chan.kind == Kind::Rotation
            && track.interpolation != Interpolation::CubicSpline
        {
            for key in track.values.chunks_exact_mut(4) {
                let q = rotation_as_i16([key[0], key[1], key[2], key[3]]);
                key.copy_from_slice(&q);
            }
        }
        chan.reduced = Some(track);
    }
    let (errors, mean) = reducer.errors()?;
    Ok(PointError {
        max: errors.iter().copied().fold(0.0, f32::max),
        mean,
    })
}

//! The error of a reduced clip against its original, measured as the reducer measures it:
//! model-space distances of joints and of virtual points fixed to them, at every original
//! key time. With one distance for every joint, 3 cm, this is ACL's error metric (virtual
//! vertices at a "shell distance" from each bone; ACL's `docs/error_metrics.md`).

use rigport_model::{Clip, Interpolation, Skeleton};

use super::channel::{as_written, collect_channels, Kind};
use super::codec::{cubic_as_written, rotations_at_bits};
use super::{Codec, ReduceError, ReduceOptions, Reducer, Tuning};

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
/// [`ReduceOptions::point_distance`]); with a `codec`, the reduced clip's LINEAR and STEP
/// values are read as the writer stores them.
///
/// ```
/// use rigport_anim::reduce::{metric::point_error, reduce_clip, Codec, ReduceOptions};
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
///     codec: Some(Codec::I16), uniform_rate: true, cubic: true };
/// let (reduced, stats) = reduce_clip(&clip, &skeleton, &options)?;
/// let acl = point_error(&clip, &reduced, &skeleton, &[0.03], Some(&Codec::I16))?;
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
    codec: Option<&Codec>,
) -> Result<PointError, ReduceError> {
    point_error_bits(original, reduced, skeleton, point_distance, codec, &[])
}

/// [`point_error`] with the reduced clip's rotation tracks read at `rotation_bits` per
/// track ([`super::ReduceStats::rotation_bits`]; 0 or past the end: the codec's default).
///
/// # Errors
/// As [`point_error`].
pub fn point_error_bits(
    original: &Clip,
    reduced: &Clip,
    skeleton: &Skeleton,
    point_distance: &[f32],
    codec: Option<&Codec>,
    rotation_bits: &[u8],
) -> Result<PointError, ReduceError> {
    // Validates the reduced clip's tracks too.
    collect_channels(reduced, skeleton, None, false, false)?;
    let channels = collect_channels(original, skeleton, None, false, false)?;
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
        let bits = rotation_bits.get(chan.track).copied().filter(|&b| b > 0);
        let coded = codec.and_then(|codec| {
            if track.interpolation == Interpolation::CubicSpline {
                cubic_as_written(track, chan.kind == Kind::Rotation, codec)
            } else if let (Some(bits), Some(lower), Kind::Rotation) =
                (bits, codec.rotation_bits, chan.kind)
            {
                Some(rotations_at_bits(track, lower.written, bits))
            } else {
                as_written(track, chan.kind, codec)
            }
        });
        let track = coded.unwrap_or_else(|| track.clone());
        chan.reduced = Some(track);
    }
    let (errors, mean) = reducer.errors()?;
    Ok(PointError {
        max: errors.iter().copied().fold(0.0, f32::max),
        mean,
    })
}

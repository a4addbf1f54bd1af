//! What each rotation track costs on its own at a bound: issue 34's floor for a clip.
//!
//! `cargo run --release --example compact_track_alone -- PLAIN.glb [TOLERANCE]`
//! (`PLAIN.glb`: an unreduced glb in metres, such as `rigport convert 07-walk.asf --motion
//! 07_05-walk.amc -o plain.glb`; `TOLERANCE` in metres, default 0.001).
//!
//! For each LINEAR rotation track of the first clip, the reducer runs at the bound with
//! every *other* track exact: turned STEP, which the reducer keeps as it is and which plays
//! the source value at every source frame. The error is measured as the acceptance
//! measures it: joints and virtual points 3 cm from each joint (not the mesh's vertices,
//! which `rigport convert` also holds), 16-bit rotations, a uniform rate and CUBICSPLINE
//! fits tried as `convert --reduce-tolerance` tries them. So each track gets the whole bound
//! for itself, which no file can give every track at once.
//!
//! It prints, per track, the keys and bytes kept (a key's value: 8 bytes LINEAR, 24 or 48
//! cubic; plus 4 bytes of time per key unless its keys are at a uniform rate, whose times
//! are shared), and the sums: the bytes, and the keys times 4 (every kept value as four
//! bytes, the smallest rotation core glTF stores, with no time at all). It also runs each
//! track with LINEAR keys allowed 8-bit normalized components (4 bytes a key;
//! `Codec::CORE`, as `rigport convert` writes them): where the reducer takes them, a track
//! may cost its 8-bit keys' bytes; where it keeps 16 bits, its keys need them. That sum
//! takes each track's smaller cost. And it runs each track as `--compress meshopt` does
//! (LINEAR keys, the `QUATERNION` filter's bits per track), counting the bytes
//! meshoptimizer's codec makes of its keys alone (and of its times unless they are at a
//! uniform rate). Each sum is a floor on the animation bytes of a file within the bound
//! only as far as errors of different tracks cannot cancel; it is an estimate, not a
//! proof.

use std::path::PathBuf;

use rigport_anim::reduce::{reduce_clip, Codec, ReduceOptions, RotationBits};
use rigport_model::{Interpolation, Track, TrackTarget};

/// The `QUATERNION` filter's bits the reducer may pick with meshopt (as `rigport convert
/// --compress meshopt` does).
const MESHOPT_BITS: [u8; 10] = [6, 7, 8, 9, 10, 11, 12, 13, 14, 15];

/// Whether a reduced track's keys are at a uniform rate (their times shared).
fn uniform(kept: &Track) -> bool {
    let step = kept.times.get(1).map_or(0.0, |t| t - kept.times[0]);
    kept.times
        .windows(2)
        .rev()
        .skip(1)
        .all(|w| ((w[1] - w[0]) - step).abs() <= 1e-4)
}

/// Bytes of a reduced track: its values, and its times unless they are at a uniform rate.
fn track_bytes(kept: &Track, linear_value: usize) -> usize {
    let n = kept.times.len();
    let value = match kept.interpolation {
        Interpolation::CubicSpline if kept.values.iter().all(|v| v.abs() <= 1.0) => 24,
        Interpolation::CubicSpline => 48,
        _ => linear_value,
    };
    // Keys at a uniform rate share their times with other tracks.
    n * value + if uniform(kept) { 0 } else { 4 * n }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let path = PathBuf::from(
        args.next()
            .ok_or("usage: compact_track_alone PLAIN.glb [TOL]")?,
    );
    let tolerance: f32 = args.next().map_or(Ok(0.001), |t| t.parse())?;
    let asset = rigport_import::gltf::import(&path)?.asset;
    let clip = asset.clips.first().ok_or("no clip")?;
    let frames = clip.tracks.iter().map(|t| t.times.len()).max().unwrap_or(0);
    let options = ReduceOptions {
        tolerance,
        point_distance: vec![0.03; asset.skeleton.len()],
        codec: Some(Codec::I16),
        uniform_rate: true,
        cubic: true,
    };
    println!("{} ({frames} frames), {tolerance} m", path.display());
    let bytes8 = ReduceOptions {
        codec: Some(Codec::CORE),
        cubic: false,
        ..options.clone()
    };
    let meshopt = ReduceOptions {
        codec: Some(Codec {
            rotation: rigport_export::meshopt_rotation_as_written,
            vector: Some(rigport_export::meshopt_vector_as_written),
            rotation_bits: Some(RotationBits {
                written: rigport_export::meshopt_rotations_as_written_bits,
                choices: &MESHOPT_BITS,
                key_bytes: |_| 8,
            }),
            key_time_bytes: 64,
        }),
        cubic: false,
        ..options.clone()
    };
    println!(
        "| joint | keys kept | bytes | 8-bit keys | 8-bit bytes | meshopt keys | meshopt bytes |"
    );
    println!("|---|---:|---:|---:|---:|---:|---:|");
    let (mut keys, mut bytes, mut tracks, mut least, mut packed) = (0, 0, 0, 0, 0);
    for (ti, track) in clip.tracks.iter().enumerate() {
        let TrackTarget::Rotation(joint) = track.target else {
            continue;
        };
        if track.interpolation != Interpolation::Linear || track.times.len() <= 2 {
            continue;
        }
        let mut alone = clip.clone();
        for (k, other) in alone.tracks.iter_mut().enumerate() {
            if k != ti {
                other.interpolation = Interpolation::Step;
            }
        }
        let (reduced, _) = reduce_clip(&alone, &asset.skeleton, &options)?;
        let kept = &reduced.tracks[ti];
        let n = kept.times.len();
        let b = track_bytes(kept, 8);
        // 8-bit keys: when the reducer picks fewer bits than 16 for the track (the other,
        // STEP, tracks stay at 16), within the bound as verified.
        let (reduced8, stats8) = reduce_clip(&alone, &asset.skeleton, &bytes8)?;
        let eight = (stats8.rotation_bits.get(ti).copied().unwrap_or(0) > 0).then(|| {
            (
                reduced8.tracks[ti].times.len(),
                track_bytes(&reduced8.tracks[ti], 4),
            )
        });
        // meshopt: the track's keys at the bits the reducer picks, through the writer's
        // filter and codec on their own (and their times, unless at a uniform rate).
        let (reduced_mo, stats_mo) = reduce_clip(&alone, &asset.skeleton, &meshopt)?;
        let kept_mo = &reduced_mo.tracks[ti];
        let bits = stats_mo.rotation_bits.get(ti).copied().unwrap_or(0);
        let mut b_mo = rigport_export::meshopt_encoded_bytes(&kept_mo.values, 4, bits);
        if !uniform(kept_mo) {
            b_mo += rigport_export::meshopt_encoded_bytes(&kept_mo.times, 1, 0);
        }
        let name = &asset.skeleton.joints()[joint.get()].name;
        let (n8, b8) = eight.map_or(("-".to_string(), "-".to_string()), |(n8, b8)| {
            (n8.to_string(), b8.to_string())
        });
        let n_mo = kept_mo.times.len();
        println!("| {name} | {n} | {b} | {n8} | {b8} | {n_mo} | {b_mo} |");
        keys += n;
        bytes += b;
        least += eight.map_or(b, |(_, b8)| b.min(b8));
        packed += b_mo;
        tracks += 1;
    }
    println!(
        "{tracks} tracks: {keys} keys, {bytes} bytes; keys x 4 = {} bytes; each track's \
         smaller of 16 and 8 bits: {least} bytes; meshopt: {packed} bytes",
        4 * keys
    );
    Ok(())
}

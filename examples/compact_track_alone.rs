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
//! track with LINEAR keys as 8-bit normalized components (4 bytes a key, each component
//! rounded to the nearest 1/127 and read back normalized, so the length error a reader
//! would compose as a scale is not counted), as the reducer picks bits per track: where it
//! takes them, a track may cost its 8-bit keys' bytes; where it keeps 16 bits, its keys need
//! them. The last sum takes each track's smaller cost. Each sum is a floor on the
//! animation bytes of a file within the bound only as far as errors of different tracks
//! cannot cancel; it is an estimate, not a proof.

use std::path::PathBuf;

use rigport_anim::reduce::{reduce_clip, Codec, ReduceOptions, RotationBits};
use rigport_model::{Interpolation, Track, TrackTarget};

/// Rotation keys as 8-bit normalized components read back (nearest rounding), whatever
/// the bits asked (the reducer asks for fewer than 16 only for the track it reduces).
fn rotations_as_i8(keys: &[[f32; 4]], _bits: u8) -> Vec<[f32; 4]> {
    keys.iter()
        .map(|q| q.map(|c| (c.clamp(-1.0, 1.0) * 127.0).round() / 127.0))
        .collect()
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
    let step = kept.times.get(1).map_or(0.0, |t| t - kept.times[0]);
    let uniform = kept
        .times
        .windows(2)
        .rev()
        .skip(1)
        .all(|w| ((w[1] - w[0]) - step).abs() <= 1e-4);
    n * value + if uniform { 0 } else { 4 * n }
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
        codec: Some(Codec {
            rotation_bits: Some(RotationBits {
                written: rotations_as_i8,
                choices: &[8],
                key_bytes: |_| 4,
            }),
            ..Codec::I16
        }),
        cubic: false,
        ..options.clone()
    };
    println!("| joint | keys kept | bytes | 8-bit keys | 8-bit bytes |");
    println!("|---|---:|---:|---:|---:|");
    let (mut keys, mut bytes, mut tracks, mut least) = (0, 0, 0, 0);
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
        let name = &asset.skeleton.joints()[joint.get()].name;
        let (n8, b8) = eight.map_or(("-".to_string(), "-".to_string()), |(n8, b8)| {
            (n8.to_string(), b8.to_string())
        });
        println!("| {name} | {n} | {b} | {n8} | {b8} |");
        keys += n;
        bytes += b;
        least += eight.map_or(b, |(_, b8)| b.min(b8));
        tracks += 1;
    }
    println!(
        "{tracks} tracks: {keys} keys, {bytes} bytes; keys x 4 = {} bytes; each track's \
         smaller of 16 and 8 bits: {least} bytes",
        4 * keys
    );
    Ok(())
}

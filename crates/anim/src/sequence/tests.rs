use super::*;
use glam::{Quat, Vec3};
use rigport_eval::test_support::{angle, chain, rot, sample_at, smooth_clip, tra, track};
use rigport_model::JointIndex;

const FPS: f32 = 30.0;

fn params() -> Vec<(f32, f32, f32)> {
    vec![(0.8, 2.0, 0.3), (1.2, 3.1, -1.0), (0.4, 5.0, 2.0)]
}

/// The clip's poses at each of its first track's key times.
fn frames(clip: &Clip, skeleton: &Skeleton) -> (Vec<f32>, Vec<Vec<Transform>>) {
    let times = CompiledClip::new(clip, skeleton).unwrap().key_times();
    let poses = times
        .iter()
        .map(|&t| sample_at(clip, skeleton, t))
        .collect();
    (times, poses)
}

/// Largest change between consecutive frames: (translation distance, rotation angle).
fn largest_step(poses: &[Vec<Transform>]) -> (f32, f32) {
    let mut worst = (0.0f32, 0.0f32);
    for pair in poses.windows(2) {
        for (a, b) in pair[0].iter().zip(&pair[1]) {
            worst.0 = worst.0.max(a.translation.distance(b.translation));
            worst.1 = worst.1.max(angle(a.rotation, b.rotation));
        }
    }
    worst
}

/// `clip` with its root translation moved so that the first key's X and Z are 0, as a
/// clip authored at its own origin would be.
fn at_origin(mut clip: Clip) -> Clip {
    for track in &mut clip.tracks {
        if track.target == tra(0) {
            let (x, z) = (track.values[0], track.values[2]);
            for key in track.values.chunks_exact_mut(3) {
                key[0] -= x;
                key[2] -= z;
            }
        }
    }
    clip
}

#[test]
fn pieces_of_one_motion_concatenate_back_into_it_without_teleporting() {
    let skeleton = chain(3);
    let whole = smooth_clip(3, 61, FPS, &params()); // 0..2 s
    let (whole_times, whole_poses) = frames(&whole, &skeleton);
    let step = largest_step(&whole_poses);
    for crossfade in [0usize, 1, 4, 10] {
        // The second piece starts `crossfade` frames before the first ends, at its origin.
        let first = trim(&whole, &skeleton, 0.0, 1.0).unwrap();
        let second_start = (31 - crossfade) as f32 / FPS;
        let second = at_origin(trim(&whole, &skeleton, second_start, 2.0).unwrap());
        assert!(second.tracks[0].values[0].abs() < 1e-6);
        let out = concatenate(&[&first, &second], &skeleton, crossfade, None).unwrap();
        assert_eq!(out.name, "smooth+smooth");
        let (times, poses) = frames(&out, &skeleton);
        assert_eq!(times.len(), 61, "crossfade {crossfade}");
        // Both pieces agree during the overlap and the root continues where the first
        // left off, so the result is the whole motion again.
        for (f, (pose, want)) in poses.iter().zip(&whole_poses).enumerate() {
            assert!((times[f] - whole_times[f]).abs() < 1e-5);
            for (j, (a, b)) in pose.iter().zip(want).enumerate() {
                assert!(
                    a.translation.abs_diff_eq(b.translation, 1e-4),
                    "crossfade {crossfade} frame {f} joint {j}: {} vs {}",
                    a.translation,
                    b.translation
                );
                assert!(
                    angle(a.rotation, b.rotation) < 1e-4,
                    "crossfade {crossfade} frame {f} joint {j}"
                );
            }
        }
        let got = largest_step(&poses);
        assert!(
            got.0 <= step.0 + 1e-5 && got.1 <= step.1 + 1e-5,
            "{got:?} vs {step:?}"
        );
    }
}

#[test]
fn a_walk_then_a_run_keeps_moving_forward_across_every_seam() {
    let skeleton = chain(3);
    let walk = smooth_clip(3, 31, FPS, &params());
    let run = Clip {
        name: "run".into(),
        ..smooth_clip(3, 21, FPS, &[(0.6, 4.0, 0.0), (1.0, 2.5, 1.0)])
    };
    let inputs = [&walk, &run, &walk];
    let mut input_step = (0.0f32, 0.0f32);
    for clip in inputs {
        let s = largest_step(&frames(clip, &skeleton).1);
        input_step = (input_step.0.max(s.0), input_step.1.max(s.1));
    }
    for crossfade in [0usize, 6] {
        let out = concatenate(&inputs, &skeleton, crossfade, Some(FPS)).unwrap();
        let (times, poses) = frames(&out, &skeleton);
        assert_eq!(times.len(), 31 + 21 + 31 - 2 * crossfade);
        assert_eq!(out.name, "smooth+run+smooth");
        for (f, pair) in poses.windows(2).enumerate() {
            let (a, b) = (pair[0][0].translation, pair[1][0].translation);
            // Both clips walk along +X and +Z: never back, never further than a step.
            assert!(
                b.x > a.x && b.z > a.z,
                "frame {f}: root goes back from {a} to {b}"
            );
            // Heights differ between the clips and are not offset: compare X and Z.
            let flat = Vec3::new(b.x - a.x, 0.0, b.z - a.z).length();
            assert!(
                flat <= input_step.0 + 1e-5,
                "frame {f}: root jumps {flat} > {}",
                input_step.0
            );
        }
        // The root's height is not offset.
        assert!(poses
            .iter()
            .all(|p| (p[0].translation.y - 1.0).abs() <= 0.05 + 1e-6));
        if crossfade > 0 {
            // Rotations: each blended frame moves at most a step plus 1/(c+1) of the
            // pose difference between the clips.
            let got = largest_step(&poses).1;
            assert!(got < input_step.1 + 2.0 / (crossfade + 1) as f32, "{got}");
        }
    }
}

#[test]
fn channels_are_the_union_with_rest_where_a_clip_is_silent() {
    let skeleton = chain(3);
    let rest = rest_locals(&skeleton);
    let a = Clip {
        name: "a".into(),
        tracks: vec![track(
            rot(1),
            Interpolation::Linear,
            &[0.0, 0.5],
            &[0., 0., 0., 1., 0., 0.247404, 0., 0.968912],
        )],
    };
    let scale = TrackTarget::Scale(JointIndex(2));
    let mesh = TrackTarget::MorphWeights(MeshIndex(4));
    let b = Clip {
        name: "b".into(),
        tracks: vec![
            track(
                scale,
                Interpolation::Linear,
                &[0.0, 0.5],
                &[2., 2., 2., 3., 3., 3.],
            ),
            track(
                mesh,
                Interpolation::Linear,
                &[0.0, 0.5],
                &[1.0, 0.5, 0.0, 0.5],
            ),
        ],
    };
    let out = concatenate(&[&a, &b], &skeleton, 0, Some(10.0)).unwrap();
    let mut targets: Vec<_> = out.tracks.iter().map(|t| t.target).collect();
    targets.sort();
    assert_eq!(targets, vec![rot(1), scale, mesh]);
    let (times, poses) = frames(&out, &skeleton);
    assert_eq!(times.len(), 12);
    assert_eq!(poses[0][2].scale, rest[2].scale, "a does not scale joint 2");
    assert_eq!(poses[6][2].scale, Vec3::splat(2.0));
    assert!(
        angle(poses[11][1].rotation, rest[1].rotation) < 1e-6,
        "b does not rotate joint 1"
    );
    let weights = out.tracks.iter().find(|t| t.target == mesh).unwrap();
    assert_eq!(
        &weights.values[..2],
        &[0.0, 0.0],
        "a does not animate the mesh"
    );
    assert_eq!(&weights.values[12..14], &[1.0, 0.5]);
    assert_eq!(&weights.values[22..], &[0.0, 0.5]);
}

#[test]
fn crossfade_weights_rise_strictly_between_zero_and_one() {
    let skeleton = chain(2);
    let constant = |name: &str, x: f32| Clip {
        name: name.into(),
        tracks: vec![track(
            tra(1),
            Interpolation::Linear,
            &[0.0, 1.0],
            &[x, 0., 0., x, 0., 0.],
        )],
    };
    let (a, b) = (constant("a", 0.0), constant("b", 1.0));
    // 5 frames each at 4 fps; 3 overlap: weights 1/4, 2/4, 3/4 on b.
    let out = concatenate(&[&a, &b], &skeleton, 3, Some(4.0)).unwrap();
    let x: Vec<f32> = out.tracks[0].values.chunks(3).map(|v| v[0]).collect();
    assert_eq!(x, vec![0.0, 0.0, 0.25, 0.5, 0.75, 1.0, 1.0]);
    assert_eq!(
        out.tracks[0].times,
        vec![0.0, 0.25, 0.5, 0.75, 1.0, 1.25, 1.5]
    );
}

#[test]
fn concatenate_errors() {
    let skeleton = chain(3);
    let clip = smooth_clip(3, 5, FPS, &params());
    assert_eq!(
        concatenate(&[], &skeleton, 0, None),
        Err(SequenceError::Empty)
    );
    // 5 frames: a crossfade of 5 at one end leaves none of its own; 3 at both ends of
    // a middle clip neither.
    assert_eq!(
        concatenate(&[&clip, &clip], &skeleton, 5, None),
        Err(SequenceError::CrossfadeTooLong {
            clip: 0,
            frames: 5,
            crossfade: 5,
            ends: 1
        })
    );
    assert!(concatenate(&[&clip, &clip], &skeleton, 4, None).is_ok());
    assert_eq!(
        concatenate(&[&clip, &clip, &clip], &skeleton, 3, None),
        Err(SequenceError::CrossfadeTooLong {
            clip: 1,
            frames: 5,
            crossfade: 3,
            ends: 2
        })
    );
    assert!(
        concatenate(&[&clip], &skeleton, 100, None).is_ok(),
        "one clip has no seam"
    );
    let pose = Clip {
        name: "p".into(),
        tracks: vec![track(
            rot(0),
            Interpolation::Linear,
            &[0.0],
            &[0., 0., 0., 1.],
        )],
    };
    assert_eq!(
        concatenate(&[&pose, &clip], &skeleton, 0, None),
        Err(SequenceError::NoFps { clip: 0 })
    );
    assert_eq!(
        concatenate(&[&pose, &clip], &skeleton, 0, Some(0.0)),
        Err(SequenceError::BadFps { fps: 0.0 })
    );
    assert_eq!(
        concatenate(&[&pose, &clip], &skeleton, 0, Some(30.0))
            .unwrap()
            .tracks[0]
            .times
            .len(),
        6
    );
    let bad = Clip {
        name: "bad".into(),
        tracks: vec![track(
            rot(9),
            Interpolation::Linear,
            &[0.0],
            &[0., 0., 0., 1.],
        )],
    };
    assert!(matches!(
        concatenate(&[&clip, &bad], &skeleton, 0, None),
        Err(SequenceError::Clip {
            clip: 1,
            source: SampleError::JointOutOfRange { .. }
        })
    ));
    let mesh = TrackTarget::MorphWeights(MeshIndex(0));
    let two = Clip {
        name: "2".into(),
        tracks: vec![track(mesh, Interpolation::Linear, &[0.0, 1.0], &[0.0; 4])],
    };
    let three = Clip {
        name: "3".into(),
        tracks: vec![track(mesh, Interpolation::Linear, &[0.0, 1.0], &[0.0; 6])],
    };
    assert_eq!(
        concatenate(&[&two, &three], &skeleton, 0, None),
        Err(SequenceError::MorphTargets {
            mesh: MeshIndex(0),
            first: 0,
            expected: 2,
            clip: 1,
            found: 3
        })
    );
    assert!(matches!(
        concatenate(&[&clip], &skeleton, 0, Some(1e12)),
        Err(SequenceError::Sample(SampleError::TooManySamples { .. }))
    ));
}

#[test]
fn loops_close_and_keep_the_root_drift() {
    let skeleton = chain(3);
    let mut clip = smooth_clip(3, 31, FPS, &params());
    let mesh = TrackTarget::MorphWeights(MeshIndex(0));
    clip.tracks
        .push(track(mesh, Interpolation::Linear, &[0.0, 1.0], &[0.2, 1.0]));
    let (_, source) = frames(&clip, &skeleton);
    for blend_frames in [1usize, 8, 30] {
        let looped = make_loop(&clip, &skeleton, blend_frames).unwrap();
        assert_eq!(looped.name, clip.name);
        let (times, poses) = frames(&looped, &skeleton);
        assert_eq!(times.len(), 31);
        let (first, last) = (&poses[0], &poses[30]);
        for (j, (a, b)) in first.iter().zip(last).enumerate() {
            assert!(
                a.rotation.abs_diff_eq(b.rotation, 1e-6)
                    || a.rotation.abs_diff_eq(-b.rotation, 1e-6),
                "blend {blend_frames} joint {j}: {:?} vs {:?}",
                a.rotation,
                b.rotation
            );
            assert!(a.scale.abs_diff_eq(b.scale, 1e-6));
        }
        // The root's height closes; its horizontal drift is the source's.
        assert!((first[0].translation.y - last[0].translation.y).abs() < 1e-6);
        for (f, pose) in poses.iter().enumerate() {
            let (x, z) = (pose[0].translation.x, pose[0].translation.z);
            assert!(
                (x - source[f][0].translation.x).abs() < 1e-6
                    && (z - source[f][0].translation.z).abs() < 1e-6
            );
        }
        assert!(
            last[0].translation.x - first[0].translation.x > 1.2,
            "drift kept"
        );
        // Frames before the blend are untouched.
        for f in 0..31 - blend_frames {
            for (a, b) in poses[f].iter().zip(&source[f]) {
                assert!(angle(a.rotation, b.rotation) < 1e-5, "frame {f}");
            }
        }
        let weights = looped.tracks.iter().find(|t| t.target == mesh).unwrap();
        assert_eq!(weights.values.len(), 31);
        assert_eq!(weights.values[30], weights.values[0]);
        for track in &looped.tracks {
            if let TrackTarget::Rotation(_) = track.target {
                for k in 1..track.times.len() {
                    let d = Quat::from_slice(track.key_value(k - 1))
                        .dot(Quat::from_slice(track.key_value(k)));
                    assert!(d >= 0.0);
                }
            }
        }
    }
    assert_eq!(
        make_loop(&clip, &skeleton, 0),
        Err(SequenceError::LoopBlend {
            blend_frames: 0,
            frames: 31
        })
    );
    assert_eq!(
        make_loop(&clip, &skeleton, 31),
        Err(SequenceError::LoopBlend {
            blend_frames: 31,
            frames: 31
        })
    );
}

#[test]
fn trims_cut_at_the_bounds_and_start_at_zero() {
    let skeleton = chain(3);
    let clip = smooth_clip(3, 31, FPS, &params());
    let cut = trim(&clip, &skeleton, 0.25, 0.75).unwrap();
    assert_eq!(cut.name, clip.name);
    let times = cut.tracks[0].times.clone();
    // Cuts at 0.25 and 0.75 (off the 1/30 grid), keys 8/30 … 22/30 between.
    assert_eq!(times.len(), 2 + 15);
    assert_eq!(times[0], 0.0);
    assert!((times[16] - 0.5).abs() < 1e-6);
    assert!((times[1] - (8.0 / 30.0 - 0.25)).abs() < 1e-6);
    for (&t, shifted) in [0.25f32, 0.5, 0.75].iter().zip([0.0f32, 0.25, 0.5]) {
        let (a, b) = (
            sample_at(&clip, &skeleton, t),
            sample_at(&cut, &skeleton, shifted),
        );
        for (x, y) in a.iter().zip(&b) {
            assert!(x.translation.abs_diff_eq(y.translation, 1e-5), "{t}");
            assert!(angle(x.rotation, y.rotation) < 1e-5, "{t}");
        }
    }
    // On key times: exactly those keys, no near-duplicates.
    let on_keys = trim(&clip, &skeleton, 0.1, 0.2).unwrap();
    assert_eq!(on_keys.tracks[0].times.len(), 4);
    // Beyond the clip: clamped.
    let clamped = trim(&clip, &skeleton, -5.0, 0.5).unwrap();
    assert_eq!(clamped.tracks[0].times.len(), 16);
    assert_eq!(
        trim(&clip, &skeleton, 0.5, 0.5),
        Err(SequenceError::TrimRange {
            start: 0.5,
            end: 0.5
        })
    );
    assert_eq!(
        trim(&clip, &skeleton, 0.6, 0.5),
        Err(SequenceError::TrimRange {
            start: 0.6,
            end: 0.5
        })
    );
    assert!(matches!(
        trim(&clip, &skeleton, f32::NAN, 0.5),
        Err(SequenceError::TrimRange { .. })
    ));
    assert_eq!(
        trim(&clip, &skeleton, 2.0, 3.0),
        Err(SequenceError::TrimOutside {
            start: 2.0,
            end: 3.0,
            clip_start: 0.0,
            clip_end: 1.0
        })
    );
}

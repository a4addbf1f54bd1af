use super::*;
use crate::test_support::{angle, chain, rot, sample_at, tra, track};
use glam::EulerRot;
use proptest::prelude::*;
use rigport_model::{JointIndex, MeshIndex};

// ---- the naive reference: linear search, glTF Appendix C formulas in f64 ----

fn naive_component(track: &Track, time: f32, c: usize) -> f64 {
    let comps = track.components();
    let cubic = track.interpolation == Interpolation::CubicSpline;
    let at = |k: usize, e: usize| {
        let slot = if cubic { 3 * k + e } else { k };
        f64::from(track.values[slot * comps + c])
    };
    let n = track.times.len();
    let t = f64::from(time);
    if t <= f64::from(track.times[0]) {
        return at(0, 1);
    }
    if t >= f64::from(track.times[n - 1]) {
        return at(n - 1, 1);
    }
    let mut k = 0;
    while f64::from(track.times[k + 1]) <= t {
        k += 1;
    }
    let (t0, t1) = (f64::from(track.times[k]), f64::from(track.times[k + 1]));
    let td = t1 - t0;
    let u = (t - t0) / td;
    match track.interpolation {
        Interpolation::Step => at(k, 1),
        Interpolation::Linear => (1.0 - u) * at(k, 1) + u * at(k + 1, 1),
        Interpolation::CubicSpline => {
            let (u2, u3) = (u * u, u * u * u);
            (2.0 * u3 - 3.0 * u2 + 1.0) * at(k, 1)
                + td * (u3 - 2.0 * u2 + u) * at(k, 2)
                + (-2.0 * u3 + 3.0 * u2) * at(k + 1, 1)
                + td * (u3 - u2) * at(k + 1, 0)
        }
    }
}

/// glTF Appendix C slerp: `a = acos|d|`, `s = sign(d)`.
fn naive_slerp(a: [f64; 4], b: [f64; 4], u: f64) -> [f64; 4] {
    let dot: f64 = (0..4).map(|i| a[i] * b[i]).sum();
    let s = if dot < 0.0 { -1.0 } else { 1.0 };
    let angle = dot.abs().min(1.0).acos();
    let (wa, wb) = if angle < 1e-9 {
        (1.0 - u, u)
    } else {
        (
            ((1.0 - u) * angle).sin() / angle.sin(),
            (u * angle).sin() / angle.sin(),
        )
    };
    let r: Vec<f64> = (0..4).map(|i| wa * a[i] + s * wb * b[i]).collect();
    let len = r.iter().map(|v| v * v).sum::<f64>().sqrt();
    [r[0] / len, r[1] / len, r[2] / len, r[3] / len]
}

fn naive_rotation(track: &Track, time: f32) -> Quat {
    let key = |k: usize| {
        let q = track.key_value(k);
        let len = q.iter().map(|v| f64::from(*v).powi(2)).sum::<f64>().sqrt();
        [0, 1, 2, 3].map(|i| f64::from(q[i]) / len)
    };
    let n = track.times.len();
    let r = if track.interpolation == Interpolation::Linear
        && time > track.times[0]
        && time < track.times[n - 1]
    {
        let k = track.times.iter().rposition(|&t| t <= time).unwrap();
        let u = f64::from(time - track.times[k]) / f64::from(track.times[k + 1] - track.times[k]);
        naive_slerp(key(k), key(k + 1), u)
    } else {
        let c = [0, 1, 2, 3].map(|c| naive_component(track, time, c));
        let len = c.iter().map(|v| v * v).sum::<f64>().sqrt();
        c.map(|v| v / len)
    };
    Quat::from_xyzw(r[0] as f32, r[1] as f32, r[2] as f32, r[3] as f32)
}

// ---- strategies ----

fn quat() -> impl Strategy<Value = Quat> {
    prop::array::uniform3(-3.2f32..3.2)
        .prop_map(|r| Quat::from_euler(EulerRot::ZYX, r[0], r[1], r[2]))
}

fn key_times(max: usize) -> impl Strategy<Value = Vec<f32>> {
    prop::collection::vec(0.01f32..0.5, 1..max).prop_map(|gaps| {
        let mut t = 0.0;
        gaps.iter()
            .map(|g| {
                let now = t;
                t += g;
                now
            })
            .collect()
    })
}

fn interpolation() -> impl Strategy<Value = Interpolation> {
    prop_oneof![
        Just(Interpolation::Step),
        Just(Interpolation::Linear),
        Just(Interpolation::CubicSpline)
    ]
}

/// A random track on `target` with `times`, values in [-2, 2] (rotations: random unit
/// quaternions, random signs; cubic tangents in [-2, 2]).
fn random_track(target: TrackTarget) -> impl Strategy<Value = Track> {
    (key_times(12), interpolation()).prop_flat_map(move |(times, interpolation)| {
        let n = times.len();
        let per_key = if interpolation == Interpolation::CubicSpline {
            3
        } else {
            1
        };
        (
            prop::collection::vec(-2.0f32..2.0, n * 4 * per_key),
            prop::collection::vec(quat(), n),
            prop::collection::vec(any::<bool>(), n),
        )
            .prop_map(move |(raw, quats, flips)| {
                let comps = match target {
                    TrackTarget::Rotation(_) => 4,
                    _ => 3,
                };
                let mut values: Vec<f32> = raw[..n * comps * per_key].to_vec();
                if comps == 4 {
                    for k in 0..n {
                        let q = if flips[k] { -quats[k] } else { quats[k] };
                        let at = if per_key == 3 { (3 * k + 1) * 4 } else { k * 4 };
                        values[at..at + 4].copy_from_slice(&q.to_array());
                    }
                }
                Track {
                    target,
                    interpolation,
                    times: times.clone(),
                    values,
                }
            })
    })
}

proptest! {
    #[test]
    fn sampling_matches_the_naive_reference(
        translation in random_track(tra(0)),
        rotation in random_track(rot(0)),
        scale in random_track(TrackTarget::Scale(JointIndex(0))),
        probes in prop::collection::vec(-0.5f32..7.0, 16),
    ) {
        let skeleton = chain(1);
        let clip = Clip { name: "c".into(), tracks: vec![translation.clone(), rotation.clone(), scale.clone()] };
        for &time in &probes {
            // The job clamps to the clip; the reference clamps per track.
            let compiled = CompiledClip::new(&clip, &skeleton).unwrap();
            let t = time.clamp(compiled.start(), compiled.end());
            let got = sample_at(&clip, &skeleton, time)[0];
            for (track, v) in [(&translation, got.translation), (&scale, got.scale)] {
                for c in 0..3 {
                    let want = naive_component(track, t, c);
                    prop_assert!((f64::from(v[c]) - want).abs() <= 1e-4 * (1.0 + want.abs()),
                        "{:?} at {t}: component {c} {} vs {want}", track.interpolation, v[c]);
                }
            }
            let want = naive_rotation(&rotation, t);
            prop_assert!(angle(got.rotation, want) < 1e-3,
                "{:?} at {t}: {:?} vs {want:?}", rotation.interpolation, got.rotation);
            prop_assert!((got.rotation.length() - 1.0).abs() < 1e-5, "norm {}", got.rotation.length());
        }
    }

    #[test]
    fn linear_sampling_at_key_times_returns_the_keys(
        translation in random_track(tra(0)),
        rotation in random_track(rot(1)),
    ) {
        let skeleton = chain(2);
        let translation = Track { interpolation: Interpolation::Linear, times: translation.times.clone(), values: translation.values[..translation.times.len() * 3].to_vec(), ..translation };
        let n = rotation.times.len();
        let values: Vec<f32> = (0..n).flat_map(|k| rotation.key_value(k).to_vec()).collect();
        let rotation = Track { interpolation: Interpolation::Linear, values, ..rotation };
        let clip = Clip { name: "c".into(), tracks: vec![translation.clone(), rotation.clone()] };
        for (k, &t) in translation.times.iter().enumerate() {
            let got = sample_at(&clip, &skeleton, t)[0].translation;
            prop_assert!(got.abs_diff_eq(Vec3::from_slice(translation.key_value(k)), 1e-6), "key {k}: {got}");
        }
        for (k, &t) in rotation.times.iter().enumerate() {
            let got = sample_at(&clip, &skeleton, t)[1].rotation;
            let want = Quat::from_slice(rotation.key_value(k));
            prop_assert!(got.abs_diff_eq(want, 1e-6), "key {k}: {got:?} vs {want:?}");
        }
    }

    #[test]
    fn slerp_endpoints_and_unit_length(a in quat(), b in quat(), flip in any::<bool>(), u in 0.0f32..1.0) {
        let b = if flip { -b } else { b };
        prop_assert!(slerp(a, b, 0.0).abs_diff_eq(a, 1e-6));
        let end = slerp(a, b, 1.0);
        prop_assert!(end.abs_diff_eq(b, 1e-6) || end.abs_diff_eq(-b, 1e-6), "{end:?} vs {b:?}");
        let mid = slerp(a, b, u);
        prop_assert!((mid.length() - 1.0).abs() < 1e-6);
        // Shortest path: the angle travelled is u times the whole angle.
        prop_assert!((angle(a, mid) - u * angle(a, b)).abs() < 2e-3, "{} vs {}", angle(a, mid), u * angle(a, b));
    }

    #[test]
    fn sampling_a_bake_at_the_frame_times_gives_the_frames(
        times in key_times(10),
        poses in prop::collection::vec((prop::array::uniform3(-2.0f32..2.0), quat(), any::<bool>(), prop::array::uniform3(0.5f32..2.0)), 30),
    ) {
        let skeleton = chain(3);
        let joints = 3;
        let frames: Vec<Transform> = (0..times.len() * joints).map(|i| {
            let (t, q, flip, s) = poses[i % poses.len()];
            Transform { translation: Vec3::from(t), rotation: if flip { -q } else { q }, scale: Vec3::from(s) }
        }).collect();
        let clip = bake("b", &times, &frames, &ChannelMask::all(joints)).unwrap();
        for (f, &t) in times.iter().enumerate() {
            let got = sample_at(&clip, &skeleton, t);
            for j in 0..joints {
                let want = frames[f * joints + j];
                prop_assert!(got[j].translation.abs_diff_eq(want.translation, 1e-6));
                prop_assert!(got[j].scale.abs_diff_eq(want.scale, 1e-6));
                prop_assert!(angle(got[j].rotation, want.rotation) < 1e-3, "frame {f} joint {j}: {:?} vs {:?}", got[j].rotation, want.rotation);
                prop_assert!(got[j].rotation.abs_diff_eq(want.rotation, 1e-6) || got[j].rotation.abs_diff_eq(-want.rotation, 1e-6));
            }
        }
        // Sign continuity of every baked rotation track.
        for track in clip.tracks.iter().filter(|t| matches!(t.target, TrackTarget::Rotation(_))) {
            for k in 1..track.times.len() {
                let d = Quat::from_slice(track.key_value(k - 1)).dot(Quat::from_slice(track.key_value(k)));
                prop_assert!(d >= 0.0, "key {k}: dot {d}");
            }
        }
    }
}

#[test]
fn cubic_spline_reproduces_a_cubic_with_tangents_scaled_by_the_interval() {
    // x(t) = t³ on keys 0 and 2 s (interval 2): values 0, 8; derivatives 0, 12. A
    // Hermite spline reproduces any cubic exactly, so x(1) = 1 and x(1.5) = 3.375;
    // forgetting the interval factor would give 0.5 + ... instead.
    let skeleton = chain(1);
    let values = [
        0.0, 0.0, 0.0, /**/ 0.0, 1.0, 0.0, /**/ 0.0, 0.0,
        0.0, // key 0: in, value, out
        12.0, 0.0, 0.0, /**/ 8.0, 1.0, 0.0, /**/ 12.0, 0.0, 0.0, // key 1
    ];
    let clip = Clip {
        name: "cubic".into(),
        tracks: vec![track(
            tra(0),
            Interpolation::CubicSpline,
            &[0.0, 2.0],
            &values,
        )],
    };
    for (t, want) in [(0.0, 0.0), (1.0, 1.0), (1.5, 3.375), (2.0, 8.0), (5.0, 8.0)] {
        let got = sample_at(&clip, &skeleton, t)[0].translation;
        assert!((got.x - want).abs() < 1e-5, "t={t}: {} vs {want}", got.x);
        assert!((got.y - 1.0).abs() < 1e-6);
    }
}

#[test]
fn step_holds_and_unanimated_channels_are_rest() {
    let skeleton = chain(2);
    let rest = rest_locals(&skeleton);
    let clip = Clip {
        name: "step".into(),
        tracks: vec![track(
            tra(1),
            Interpolation::Step,
            &[1.0, 2.0, 3.0],
            &[1., 0., 0., 2., 0., 0., 3., 0., 0.],
        )],
    };
    for (t, want) in [
        (0.0, 1.0),
        (1.0, 1.0),
        (1.99, 1.0),
        (2.0, 2.0),
        (2.5, 2.0),
        (3.0, 3.0),
        (9.0, 3.0),
    ] {
        let got = sample_at(&clip, &skeleton, t);
        assert_eq!(got[1].translation.x, want, "t={t}");
        assert_eq!(got[1].rotation, rest[1].rotation);
        assert_eq!(got[1].scale, rest[1].scale);
        assert_eq!(got[0], rest[0]);
    }
    let compiled = CompiledClip::new(&clip, &skeleton).unwrap();
    assert_eq!(
        (compiled.start(), compiled.end(), compiled.duration()),
        (1.0, 3.0, 2.0)
    );
}

#[test]
fn key_times_are_the_union_and_fps_the_median_spacing() {
    let skeleton = chain(2);
    let clip = Clip {
        name: "k".into(),
        tracks: vec![
            track(
                tra(0),
                Interpolation::Linear,
                &[0.0, 0.1, 0.2, 0.6],
                &[0.0; 12],
            ),
            track(
                rot(1),
                Interpolation::Linear,
                &[0.1, 0.3, 0.4],
                &[0., 0., 0., 1.].repeat(3),
            ),
            track(
                TrackTarget::MorphWeights(MeshIndex(0)),
                Interpolation::Linear,
                &[5.0, 6.0],
                &[0.0; 4],
            ),
        ],
    };
    let compiled = CompiledClip::new(&clip, &skeleton).unwrap();
    assert_eq!(compiled.key_times(), vec![0.0, 0.1, 0.2, 0.3, 0.4, 0.6]);
    // Gaps 0.1, 0.1, 0.1, 0.1, 0.2 (up to float noise): median 0.1.
    assert!(
        (compiled.fps().unwrap() - 10.0).abs() < 1e-3,
        "{:?}",
        compiled.fps()
    );
    // Weights count towards the clip's range but not its frames.
    assert_eq!((compiled.start(), compiled.end()), (0.0, 6.0));
    let single = Clip {
        name: "one".into(),
        tracks: vec![track(tra(0), Interpolation::Linear, &[0.5], &[0.0; 3])],
    };
    assert_eq!(CompiledClip::new(&single, &skeleton).unwrap().fps(), None);
    let empty = Clip::default();
    let compiled = CompiledClip::new(&empty, &skeleton).unwrap();
    assert_eq!(
        (compiled.start(), compiled.end(), compiled.fps()),
        (0.0, 0.0, None)
    );
}

#[test]
fn compile_rejects_each_invalid_field() {
    let skeleton = chain(2);
    let ok_rot = [0., 0., 0., 1., 0., 0., 0., 1.];
    let cases: Vec<(Vec<Track>, SampleError)> = vec![
        (
            vec![track(rot(2), Interpolation::Linear, &[0., 1.], &ok_rot)],
            SampleError::JointOutOfRange {
                track: 0,
                joint: 2,
                joints: 2,
            },
        ),
        (
            vec![track(rot(0), Interpolation::Linear, &[], &[])],
            SampleError::NoKeys { track: 0 },
        ),
        (
            vec![track(
                rot(0),
                Interpolation::Linear,
                &[0., 1.],
                &ok_rot[..7],
            )],
            SampleError::ValueCount {
                track: 0,
                keys: 2,
                expected: 8,
                found: 7,
            },
        ),
        (
            vec![track(
                rot(0),
                Interpolation::CubicSpline,
                &[0., 1.],
                &ok_rot,
            )],
            SampleError::ValueCount {
                track: 0,
                keys: 2,
                expected: 24,
                found: 8,
            },
        ),
        (
            vec![track(
                TrackTarget::MorphWeights(MeshIndex(0)),
                Interpolation::Linear,
                &[0., 1.],
                &[0.; 3],
            )],
            SampleError::WeightCount {
                track: 0,
                keys: 2,
                found: 3,
            },
        ),
        (
            vec![track(
                tra(0),
                Interpolation::Linear,
                &[0., f32::NAN],
                &[0.; 6],
            )],
            SampleError::NonFiniteTime {
                track: 0,
                key: 1,
                time: f32::NAN,
            },
        ),
        (
            vec![track(
                tra(0),
                Interpolation::Linear,
                &[0., 1., 1.],
                &[0.; 9],
            )],
            SampleError::TimeNotIncreasing {
                track: 0,
                key: 2,
                time: 1.0,
                previous: 1.0,
            },
        ),
        (
            vec![track(
                tra(0),
                Interpolation::Linear,
                &[0., 1.],
                &[0., 0., 0., 0., f32::INFINITY, 0.],
            )],
            SampleError::NonFiniteValue { track: 0, index: 4 },
        ),
        (
            vec![track(
                rot(0),
                Interpolation::Linear,
                &[0., 1.],
                &[0., 0., 0., 1., 0., 0., 0., 0.],
            )],
            SampleError::ZeroRotation { track: 0, key: 1 },
        ),
        (
            vec![
                track(rot(1), Interpolation::Linear, &[0., 1.], &ok_rot),
                track(tra(1), Interpolation::Linear, &[0.], &[0.; 3]),
                track(rot(1), Interpolation::Step, &[0., 1.], &ok_rot),
            ],
            SampleError::DuplicateChannel {
                first: 0,
                second: 2,
                target: rot(1),
            },
        ),
        (
            vec![
                track(
                    TrackTarget::MorphWeights(MeshIndex(3)),
                    Interpolation::Linear,
                    &[0.],
                    &[0.],
                ),
                track(
                    TrackTarget::MorphWeights(MeshIndex(3)),
                    Interpolation::Linear,
                    &[0.],
                    &[0.],
                ),
            ],
            SampleError::DuplicateChannel {
                first: 0,
                second: 1,
                target: TrackTarget::MorphWeights(MeshIndex(3)),
            },
        ),
    ];
    for (tracks, want) in cases {
        let clip = Clip {
            name: "bad".into(),
            tracks,
        };
        let got = CompiledClip::new(&clip, &skeleton).err();
        // NaN != NaN: compare the messages.
        assert_eq!(
            got.as_ref().map(ToString::to_string),
            Some(want.to_string()),
            "{got:?}"
        );
    }
    let err = SampleError::DuplicateChannel {
        first: 0,
        second: 2,
        target: rot(1),
    };
    assert_eq!(
        err.to_string(),
        "tracks 0 and 2 both animate the rotation of joint #1"
    );
}

#[test]
fn job_validates_lengths_and_time() {
    let skeleton = chain(2);
    let clip = Clip::default();
    let compiled = CompiledClip::new(&clip, &skeleton).unwrap();
    let rest = rest_locals(&skeleton);
    let mut short = [Transform::IDENTITY; 1];
    let job = SampleJob {
        clip: &compiled,
        time: 0.0,
        rest: &rest,
        output: &mut short,
    };
    assert_eq!(
        job.validate(),
        Err(SampleError::Length {
            what: "output",
            expected: 2,
            found: 1
        })
    );
    let mut out = [Transform::IDENTITY; 2];
    let mut job = SampleJob {
        clip: &compiled,
        time: f32::INFINITY,
        rest: &rest,
        output: &mut out,
    };
    assert!(matches!(
        job.run(),
        Err(SampleError::NonFiniteSampleTime { .. })
    ));
    let job = SampleJob {
        clip: &compiled,
        time: 0.0,
        rest: &rest[..1],
        output: &mut out,
    };
    assert!(matches!(
        job.validate(),
        Err(SampleError::Length { what: "rest", .. })
    ));
}

#[test]
fn weights_sample_in_all_modes_and_check_sizes() {
    let mesh = TrackTarget::MorphWeights(MeshIndex(0));
    let linear = track(
        mesh,
        Interpolation::Linear,
        &[0.0, 1.0],
        &[0.0, 1.0, 1.0, 0.0],
    );
    let mut out = [0.0; 2];
    sample_weights(&linear, 0.25, &mut out).unwrap();
    assert_eq!(out, [0.25, 0.75]);
    let step = Track {
        interpolation: Interpolation::Step,
        ..linear.clone()
    };
    sample_weights(&step, 0.99, &mut out).unwrap();
    assert_eq!(out, [0.0, 1.0]);
    // One target, cubic with zero tangents: smoothstep, 0.5 at the middle.
    let cubic = track(
        mesh,
        Interpolation::CubicSpline,
        &[0.0, 1.0],
        &[0., 0., 0., 0., 1., 0.],
    );
    let mut one = [0.0];
    sample_weights(&cubic, 0.5, &mut one).unwrap();
    assert!((one[0] - 0.5).abs() < 1e-6);
    sample_weights(&cubic, 0.25, &mut one).unwrap();
    assert!((one[0] - 0.15625).abs() < 1e-6, "{}", one[0]);
    assert_eq!(
        sample_weights(&linear, 0.5, &mut one),
        Err(SampleError::Length {
            what: "weights",
            expected: 2,
            found: 1
        })
    );
    let broken = track(mesh, Interpolation::Linear, &[0.0, 1.0], &[0.0; 3]);
    assert!(matches!(
        sample_weights(&broken, 0.5, &mut one),
        Err(SampleError::ValueCount { .. })
    ));
}

#[test]
fn bake_rejects_bad_input_and_keeps_signs_continuous() {
    let frames = [Transform::IDENTITY; 4];
    let mask = ChannelMask::all(2);
    assert_eq!(
        bake("x", &[0.0, 0.0], &frames, &mask).err(),
        Some(SampleError::FrameTime {
            frame: 1,
            time: 0.0,
            previous: 0.0
        })
    );
    assert!(matches!(
        bake("x", &[0.0, f32::NAN], &frames, &mask),
        Err(SampleError::FrameTime { frame: 1, .. })
    ));
    assert_eq!(
        bake("x", &[0.0], &frames, &mask).err(),
        Some(SampleError::Length {
            what: "frames",
            expected: 2,
            found: 4
        })
    );
    assert_eq!(
        bake("x", &[], &[], &mask).err(),
        Some(SampleError::NoFrames)
    );
    let mut zero = frames;
    zero[3].rotation = Quat::from_xyzw(0.0, 0.0, 0.0, 0.0);
    assert_eq!(
        bake("x", &[0.0, 1.0], &zero, &mask).err(),
        Some(SampleError::FrameValue { frame: 1, joint: 1 })
    );
    // Not baked, so not checked.
    let only_translation = ChannelMask {
        rotation: vec![false; 2],
        ..ChannelMask::all(2)
    };
    assert!(bake("x", &[0.0, 1.0], &zero, &only_translation).is_ok());
    let uneven = ChannelMask {
        scale: vec![true],
        ..ChannelMask::all(2)
    };
    assert!(matches!(
        bake("x", &[0.0, 1.0], &frames, &uneven),
        Err(SampleError::Length {
            what: "channels.scale",
            ..
        })
    ));

    // Rotations alternate sign and grow by 0.3 rad: baked keys all have dot >= 0.
    let q = |i: usize| {
        let q = Quat::from_rotation_y(0.3 * i as f32) * 2.0; // not unit either
        if i % 2 == 1 {
            -q
        } else {
            q
        }
    };
    let frames: Vec<Transform> = (0..6)
        .map(|i| Transform {
            rotation: q(i),
            ..Transform::IDENTITY
        })
        .collect();
    let times: Vec<f32> = (0..6).map(|i| i as f32 / 30.0).collect();
    let mask = ChannelMask {
        translation: vec![false],
        rotation: vec![true],
        scale: vec![false],
    };
    let clip = bake("signs", &times, &frames, &mask).unwrap();
    assert_eq!(clip.tracks.len(), 1);
    let track = &clip.tracks[0];
    assert_eq!(track.interpolation, Interpolation::Linear);
    for k in 0..6 {
        let key = Quat::from_slice(track.key_value(k));
        assert!((key.length() - 1.0).abs() < 1e-6);
        assert!(angle(key, q(k)) < 1e-3);
        if k > 0 {
            assert!(
                key.dot(Quat::from_slice(track.key_value(k - 1))) >= 0.0,
                "key {k}"
            );
        }
    }
}

#[test]
fn channel_masks() {
    let clip = Clip {
        name: "m".into(),
        tracks: vec![
            track(tra(0), Interpolation::Linear, &[0.], &[0.; 3]),
            track(rot(1), Interpolation::Linear, &[0.], &[0., 0., 0., 1.]),
            track(rot(7), Interpolation::Linear, &[0.], &[0., 0., 0., 1.]),
            track(
                TrackTarget::MorphWeights(MeshIndex(0)),
                Interpolation::Linear,
                &[0.],
                &[0.],
            ),
        ],
    };
    let mask = ChannelMask::of_clip(&clip, 2);
    assert_eq!(mask.translation, vec![true, false]);
    assert_eq!(mask.rotation, vec![false, true]);
    assert_eq!(mask.scale, vec![false, false]);
    let mut union = ChannelMask::none(1);
    union.scale[0] = true;
    union.union_with(&mask);
    assert_eq!(union.translation, vec![true, false]);
    assert_eq!(union.scale, vec![true, false]);
    assert_eq!(ChannelMask::all(3).rotation, vec![true; 3]);
}

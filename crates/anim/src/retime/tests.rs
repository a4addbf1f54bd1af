use super::*;
use glam::Quat;
use proptest::prelude::*;
use rigport_eval::test_support::{angle, chain, rot, sample_at, smooth_clip, tra, track};
use rigport_model::{JointIndex, MeshIndex};

const FPS: f32 = 30.0;

fn params() -> Vec<(f32, f32, f32)> {
    vec![(0.8, 2.0, 0.3), (1.2, 3.1, -1.0), (0.4, 5.0, 2.0)]
}

/// Every rotation track's consecutive keys have a non-negative dot product.
fn assert_sign_continuous(clip: &Clip) {
    for track in &clip.tracks {
        if let TrackTarget::Rotation(_) = track.target {
            for k in 1..track.times.len() {
                let d = Quat::from_slice(track.key_value(k - 1))
                    .dot(Quat::from_slice(track.key_value(k)));
                assert!(d >= 0.0, "{:?} key {k}: dot {d}", track.target);
            }
        }
    }
}

fn targets(clip: &Clip) -> Vec<TrackTarget> {
    let mut t: Vec<_> = clip.tracks.iter().map(|t| t.target).collect();
    t.sort();
    t
}

/// The largest difference between two clips' samples at `probes` (seconds in `a`),
/// `b` sampled at `map(t)`: (translation distance, rotation angle in radians).
fn max_difference(
    a: &Clip,
    b: &Clip,
    skeleton: &Skeleton,
    probes: impl Iterator<Item = f32>,
    map: impl Fn(f32) -> f32,
) -> (f32, f32) {
    let mut worst = (0.0f32, 0.0f32);
    for t in probes {
        let (pa, pb) = (sample_at(a, skeleton, t), sample_at(b, skeleton, map(t)));
        for (x, y) in pa.iter().zip(&pb) {
            worst.0 = worst
                .0
                .max(x.translation.distance(y.translation))
                .max(x.scale.distance(y.scale));
            worst.1 = worst.1.max(angle(x.rotation, y.rotation));
        }
    }
    worst
}

#[test]
fn same_frame_count_is_the_identity() {
    let skeleton = chain(4);
    let clip = smooth_clip(4, 31, FPS, &params());
    let out = retime(&clip, &skeleton, &Retime::Frames(31)).unwrap();
    assert_eq!(out.name, clip.name);
    assert_eq!(targets(&out), targets(&clip));
    let mut worst = 0.0f32;
    for (a, b) in clip.tracks.iter().zip(&out.tracks) {
        assert_eq!(a.target, b.target);
        assert_eq!(b.interpolation, Interpolation::Linear);
        assert_eq!(a.times.len(), b.times.len());
        for (x, y) in a
            .times
            .iter()
            .zip(&b.times)
            .chain(a.values.iter().zip(&b.values))
        {
            worst = worst.max((x - y).abs());
        }
    }
    assert!(worst <= 1e-6, "largest difference {worst}");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]
    #[test]
    fn up_then_down_sampling_comes_back(
        p in prop::collection::vec((0.1f32..1.5, 0.5f32..6.0, -3.0f32..3.0), 1..4),
        frames in 2usize..40,
    ) {
        let skeleton = chain(3);
        let clip = smooth_clip(3, frames, FPS, &p);
        let up = retime(&clip, &skeleton, &Retime::Frames(2 * frames - 1)).unwrap();
        let back = retime(&up, &skeleton, &Retime::Frames(frames)).unwrap();
        let times = &clip.tracks[0].times;
        let (dt, da) = max_difference(&clip, &back, &skeleton, times.iter().copied(), |t| t);
        prop_assert!(da <= 1e-4, "rotation differs by {da} rad");
        prop_assert!(dt <= 1e-5, "translation differs by {dt}");
        for (a, b) in clip.tracks.iter().zip(&back.tracks) {
            prop_assert_eq!(a.times.len(), b.times.len());
        }
    }

    #[test]
    fn speed_and_reverse_move_keys_exactly_in_every_mode(
        interpolation in prop_oneof![Just(Interpolation::Step), Just(Interpolation::Linear), Just(Interpolation::CubicSpline)],
        raw in prop::collection::vec(-1.0f32..1.0, 6 * 4 * 3),
        start in 0.0f32..2.0,
        speed in 0.25f32..4.0,
        probes in prop::collection::vec(0.0f32..1.0, 12),
    ) {
        // Translation and rotation tracks with 6 keys at uneven times from `start`.
        let skeleton = chain(1);
        let times: Vec<f32> = [0.0, 0.1, 0.25, 0.3, 0.6, 1.0].iter().map(|t| start + t).collect();
        let per_key = if interpolation == Interpolation::CubicSpline { 3 } else { 1 };
        let mut rotation = raw[..6 * 4 * per_key].to_vec();
        for k in 0..6 {
            let at = if per_key == 3 { (3 * k + 1) * 4 } else { 4 * k };
            rotation[at + 3] += 2.0; // keep keys well away from zero
        }
        let clip = Clip {
            name: "moves".into(),
            tracks: vec![
                track(tra(0), interpolation, &times, &raw[..6 * 3 * per_key]),
                track(rot(0), interpolation, &times, &rotation),
            ],
        };
        let (s, e) = (start, start + 1.0);
        let probes = probes.iter().map(|u| s + u);
        let fast = retime(&clip, &skeleton, &Retime::Speed(speed)).unwrap();
        let (dt, da) = max_difference(&clip, &fast, &skeleton, probes.clone(), |t| s + (t - s) / speed);
        prop_assert!(dt < 1e-4 && da < 1e-3, "speed: {dt} {da}");
        prop_assert!((CompiledClip::new(&fast, &skeleton).unwrap().duration() - 1.0 / speed).abs() < 1e-5);
        let reversed = retime(&clip, &skeleton, &Retime::Reverse).unwrap();
        // STEP holds mirror to the other side of each key, so compare it at the keys only.
        let (dt, da) = if interpolation == Interpolation::Step {
            max_difference(&clip, &reversed, &skeleton, times.iter().copied(), |t| s + e - t)
        } else {
            max_difference(&clip, &reversed, &skeleton, probes, |t| s + e - t)
        };
        prop_assert!(dt < 1e-4 && da < 1e-3, "reverse: {dt} {da}");
        for out in [&fast, &reversed] {
            prop_assert!(out.tracks.iter().all(|t| t.interpolation == interpolation));
        }
    }
}

#[test]
fn speed_half_doubles_the_duration_and_keeps_the_keys() {
    let skeleton = chain(3);
    let clip = smooth_clip(3, 25, FPS, &params());
    let slow = retime(&clip, &skeleton, &Retime::Speed(0.5)).unwrap();
    assert!((slow.duration() - 2.0 * clip.duration()).abs() < 1e-6);
    for (a, b) in clip.tracks.iter().zip(&slow.tracks) {
        assert_eq!(a.times.len(), b.times.len());
        assert_eq!(a.values, b.values);
    }
    assert_sign_continuous(&slow);
}

#[test]
fn reverse_twice_is_the_identity() {
    let skeleton = chain(3);
    let mut clip = smooth_clip(3, 20, FPS, &params());
    // A cubic track too, whose tangents must be negated and swapped.
    clip.tracks.push(track(
        TrackTarget::Scale(JointIndex(2)),
        Interpolation::CubicSpline,
        &[0.0, 0.2, 0.5],
        &[
            0.1, 0.2, 0.3, 1.0, 1.1, 1.2, -0.3, 0.2, 0.1, /**/ 0.5, 0.5, 0.5, 1.5, 1.0, 0.8,
            0.0, 0.1, 0.2, /**/ 1.0, 0.0, 2.0, 0.9, 0.9, 0.9, 3.0, 3.0, 3.0,
        ],
    ));
    let once = retime(&clip, &skeleton, &Retime::Reverse).unwrap();
    let cubic = once.tracks.last().unwrap();
    // The first reversed key was the last: in = -(old out), value, out = -(old in).
    assert_eq!(
        &cubic.values[..9],
        &[-3.0, -3.0, -3.0, 0.9, 0.9, 0.9, -1.0, -0.0, -2.0]
    );
    assert!((cubic.times[0] - (0.0 + clip.duration() - 0.5)).abs() < 1e-6);
    assert_sign_continuous(&once);
    let twice = retime(&once, &skeleton, &Retime::Reverse).unwrap();
    for (a, b) in clip.tracks.iter().zip(&twice.tracks) {
        assert_eq!(a.target, b.target);
        for (x, y) in a.times.iter().zip(&b.times) {
            assert!((x - y).abs() <= 1e-6, "{x} vs {y}");
        }
        assert_eq!(a.values, b.values);
    }
}

#[test]
fn fps_includes_an_off_grid_end_and_resamples_weights() {
    let skeleton = chain(2);
    let weights = TrackTarget::MorphWeights(MeshIndex(0));
    let clip = Clip {
        name: "w".into(),
        tracks: vec![
            track(
                tra(1),
                Interpolation::Linear,
                &[0.0, 0.9],
                &[0.0, 0.0, 0.0, 0.9, 0.0, 0.0],
            ),
            track(
                weights,
                Interpolation::Linear,
                &[0.0, 0.9],
                &[0.0, 1.0, 0.9, 0.1],
            ),
        ],
    };
    let out = retime(&clip, &skeleton, &Retime::Fps(4.0)).unwrap();
    assert_eq!(targets(&out), targets(&clip));
    let times = &out.tracks[0].times;
    assert_eq!(times, &vec![0.0, 0.25, 0.5, 0.75, 0.9]);
    let w = out.tracks.iter().find(|t| t.target == weights).unwrap();
    assert_eq!(&w.times, times);
    assert!(
        (w.values[2] - 0.25).abs() < 1e-6 && (w.values[3] - 0.75).abs() < 1e-6,
        "{:?}",
        w.values
    );
    // On the grid: the end is not doubled.
    let on_grid = retime(&clip, &skeleton, &Retime::Fps(10.0)).unwrap();
    assert_eq!(on_grid.tracks[0].times.len(), 10);
    assert_eq!(*on_grid.tracks[0].times.last().unwrap(), 0.9);
}

#[test]
fn warp_samples_the_source_at_the_warped_time() {
    let skeleton = chain(3);
    let clip = smooth_clip(3, 31, FPS, &params());
    let curve = WarpCurve::parse("0:0, 1:0.25 ,2:1").unwrap();
    let out = retime(&clip, &skeleton, &Retime::Warp(curve.clone())).unwrap();
    assert_eq!(targets(&out), targets(&clip));
    let times = out.tracks[0].times.clone();
    assert_eq!(times.len(), 61, "2 s at the source's 30 fps");
    assert_eq!(*times.last().unwrap(), 2.0);
    // At every output key the pose is the source's at warp(t); between keys it is
    // linear in the output, so compare at the keys.
    let (dt, da) = max_difference(&out, &clip, &skeleton, times.iter().copied(), |t| {
        curve.source_time(t)
    });
    assert!(dt < 1e-5 && da < 1e-5, "{dt} {da}");
    assert_eq!(curve.source_time(0.5), 0.125);
    assert_eq!(curve.source_time(1.5), 0.625);
    assert_eq!(curve.source_time(9.0), 1.0);
    assert_sign_continuous(&out);
    // A flat stretch holds a pose.
    let hold = WarpCurve::parse("0:0.5,1:0.5").unwrap();
    let held = retime(&clip, &skeleton, &Retime::Warp(hold)).unwrap();
    let (_, da) = max_difference(&held, &clip, &skeleton, [0.0, 0.3, 1.0].into_iter(), |_| {
        0.5
    });
    assert!(da < 1e-5);
}

#[test]
fn warp_errors_name_the_key() {
    let err = |text: &str| WarpCurve::parse(text).unwrap_err().to_string();
    assert_eq!(
        err("0:0,0.5:1.2,1:1.3,2:0.5"),
        "warp key 3 (2:0.5): source time goes backwards from 1.3"
    );
    assert_eq!(
        err("0:0,1:0.4,1:2"),
        "warp key 2 (1:2): output time does not come after 1"
    );
    assert_eq!(
        err("0:0,1-2"),
        "warp key 1 (1-2): expected output_seconds:source_seconds, e.g. 1:0.4"
    );
    assert_eq!(
        err("0:0,,1:1"),
        "warp key 1 (): expected output_seconds:source_seconds, e.g. 1:0.4"
    );
    assert_eq!(
        err("0:0,1:x"),
        "warp key 1 (1:x): expected output_seconds:source_seconds, e.g. 1:0.4"
    );
    assert_eq!(err("0:0,1:inf"), "warp key 1 (1:inf): times must be finite");
    assert_eq!(
        err("-1:0,1:1"),
        "warp key 0 (-1:0): output time -1 is negative"
    );
    assert_eq!(err("0:0"), "a warp curve needs at least 2 keys, found 1");
    assert_eq!(
        WarpCurve::new(vec![(0.0, 1.0), (1.0, 0.5)])
            .unwrap_err()
            .to_string(),
        "warp key 1 (1:0.5): source time goes backwards from 1"
    );
    // Outside the clip (1 s long), beyond the millisecond tolerance.
    let skeleton = chain(3);
    let clip = smooth_clip(3, 31, FPS, &params());
    let outside = WarpCurve::parse("0:0,1:1.0005,2:1.5").unwrap();
    assert_eq!(
        retime(&clip, &skeleton, &Retime::Warp(outside))
            .unwrap_err()
            .to_string(),
        "warp key 2 (2:1.5): source time is outside the clip [0, 1]"
    );
    let within = WarpCurve::parse("0:0,1:1.0005").unwrap();
    assert!(retime(&clip, &skeleton, &Retime::Warp(within)).is_ok());
}

#[test]
fn invalid_requests_are_errors() {
    let skeleton = chain(3);
    let clip = smooth_clip(3, 5, FPS, &params());
    let run = |how: Retime| retime(&clip, &skeleton, &how).unwrap_err();
    assert_eq!(
        run(Retime::Frames(1)),
        RetimeError::TooFewFrames { frames: 1 }
    );
    assert_eq!(run(Retime::Fps(0.0)), RetimeError::BadFps { fps: 0.0 });
    assert!(matches!(
        run(Retime::Fps(f32::NAN)),
        RetimeError::BadFps { .. }
    ));
    assert_eq!(
        run(Retime::Speed(-1.0)),
        RetimeError::BadSpeed { speed: -1.0 }
    );
    assert!(matches!(
        run(Retime::Fps(1e9)),
        RetimeError::Sample(SampleError::TooManySamples { .. })
    ));
    assert!(matches!(
        run(Retime::Frames(usize::MAX)),
        RetimeError::Sample(SampleError::TooManySamples { .. })
    ));
    // A speed so high that distinct key times (far from 0) collapse to one float.
    let late = Clip {
        name: "late".into(),
        tracks: vec![track(
            tra(0),
            Interpolation::Linear,
            &[1000.0, 1000.5],
            &[0.0; 6],
        )],
    };
    assert!(matches!(
        retime(&late, &skeleton, &Retime::Speed(1e9)),
        Err(RetimeError::Output(SampleError::TimeNotIncreasing { .. }))
    ));
    let pose = Clip {
        name: "pose".into(),
        tracks: vec![track(
            rot(0),
            Interpolation::Linear,
            &[0.0],
            &[0.0, 0.0, 0.0, 1.0],
        )],
    };
    let run = |how: Retime| retime(&pose, &skeleton, &how);
    assert_eq!(
        run(Retime::Frames(3)).unwrap_err(),
        RetimeError::ZeroDuration { frames: 3 }
    );
    let warp = WarpCurve::parse("0:0,1:0").unwrap();
    assert_eq!(run(Retime::Warp(warp)).unwrap_err(), RetimeError::NoFps);
    assert_eq!(run(Retime::Fps(30.0)).unwrap().tracks[0].times, vec![0.0]);
    let bad = Clip {
        name: "bad".into(),
        tracks: vec![track(
            rot(5),
            Interpolation::Linear,
            &[0.0],
            &[0.0, 0.0, 0.0, 1.0],
        )],
    };
    assert!(matches!(
        retime(&bad, &skeleton, &Retime::Reverse),
        Err(RetimeError::Clip(SampleError::JointOutOfRange { .. }))
    ));
}

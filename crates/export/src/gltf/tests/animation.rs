//! Animation tracks: what glTF cannot hold, constant tracks, clip durations.

//! Round trips through an independent reader (the `gltf` crate), layout rules read from the
//! JSON, determinism and atomic writing.

use gltf::animation::util::ReadOutputs;
use rigport_model::{Interpolation, JointIndex, MeshIndex, Track, TrackTarget};

use super::*;
use crate::test_assets;

#[test]
fn tracks_gltf_cannot_hold_are_dropped_with_warnings() {
    let mut asset = test_assets::rig();
    let clip = &mut asset.clips[0];
    let morph_on_hat = Track {
        target: TrackTarget::MorphWeights(MeshIndex(1)),
        interpolation: Interpolation::Linear,
        times: vec![0.0],
        values: vec![1.0],
    };
    let wrong_count = Track {
        target: TrackTarget::MorphWeights(MeshIndex(0)),
        interpolation: Interpolation::Linear,
        times: vec![0.0],
        values: vec![1.0, 0.0, 0.0],
    };
    let duplicate = clip.tracks[0].clone();
    clip.tracks.extend([morph_on_hat, wrong_count, duplicate]);
    let mut one_key_cubic = clip.tracks[3].clone();
    one_key_cubic.times.truncate(1);
    one_key_cubic.values.truncate(12);
    asset.clips[1].tracks[0] = Track {
        target: TrackTarget::Rotation(JointIndex(1)),
        ..one_key_cubic
    };
    asset.clips.push(rigport_model::Clip {
        name: "empty".into(),
        tracks: Vec::new(),
    });
    let out = glb(&asset, 4);
    let messages: Vec<String> = out.warnings.iter().map(ToString::to_string).collect();
    let has = |s: &str| messages.iter().any(|m| m.contains(s));
    assert!(
        has("clip \"wave\" track 5: repaired: track dropped: mesh \"hat\" has no morph targets"),
        "{messages:#?}"
    );
    assert!(has(
        "clip \"wave\" track 6: repaired: track dropped: 3 weights per key for the 2 morph targets"
    ));
    assert!(has(
        "clip \"wave\" track 7: repaired: track dropped: an earlier track"
    ));
    assert!(has(
        "clip \"idle\" track 0: one-key cubic spline written as STEP"
    ));
    assert!(has(
        "clip \"empty\": repaired: clip has no exportable track"
    ));
    let (doc, buffers) = import(&out.glb);
    let data = |b: gltf::Buffer| Some(&*buffers[b.index()]);
    assert_eq!(doc.animations().count(), 2);
    let idle = doc.animations().nth(1).expect("idle");
    let ch = idle.channels().next().expect("channel");
    assert_eq!(
        ch.sampler().interpolation(),
        gltf::animation::Interpolation::Step
    );
    let ReadOutputs::Rotations(r) = ch.reader(data).read_outputs().expect("outputs") else {
        panic!("rotation outputs expected");
    };
    let r: Vec<[f32; 4]> = r.into_f32().collect();
    assert_eq!(r, [rigport_model::glam::Quat::IDENTITY.to_array()]);
}

fn keys(n: usize, step: f32) -> Vec<f32> {
    (0..n).map(|k| k as f32 * step).collect()
}

fn repeat(value: &[f32], n: usize) -> Vec<f32> {
    value.repeat(n)
}

/// One channel as read back: (node, property, interpolation, times, flat outputs).
type ReadChannel = (
    usize,
    gltf::animation::Property,
    gltf::animation::Interpolation,
    Vec<f32>,
    Vec<f32>,
);

fn read_channels(glb: &[u8], animation: usize) -> Vec<ReadChannel> {
    let (doc, buffers) = import(glb);
    let data = |b: gltf::Buffer| Some(&*buffers[b.index()]);
    let anim = doc.animations().nth(animation).expect("animation");
    anim.channels()
        .map(|ch| {
            let reader = ch.reader(data);
            let times: Vec<f32> = reader.read_inputs().expect("inputs").collect();
            let values: Vec<f32> = match reader.read_outputs().expect("outputs") {
                ReadOutputs::Translations(t) | ReadOutputs::Scales(t) => t.flatten().collect(),
                ReadOutputs::Rotations(r) => r.into_f32().flatten().collect(),
                ReadOutputs::MorphTargetWeights(w) => w.into_f32().collect(),
            };
            (
                ch.target().node().index(),
                ch.target().property(),
                ch.sampler().interpolation(),
                times,
                values,
            )
        })
        .collect()
}

#[test]
fn constant_tracks_are_dropped_at_rest_and_reduced_to_two_keys_elsewhere() {
    use gltf::animation::{Interpolation as I, Property as P};
    use rigport_model::glam::Quat;
    let mut asset = test_assets::rig();
    let rest_rot = asset.skeleton.joints()[1].rest_local.rotation;
    let t5 = keys(5, 0.25);
    let track = |target, interpolation, times: &[f32], values: Vec<f32>| Track {
        target,
        interpolation,
        times: times.to_vec(),
        values,
    };
    let tip_rest = asset.skeleton.joints()[2].rest_local.translation;
    asset.clips = vec![rigport_model::Clip {
        name: "still".into(),
        tracks: vec![
            // 0: joint 1's rest translation: dropped.
            track(
                TrackTarget::Translation(JointIndex(1)),
                Interpolation::Linear,
                &t5,
                repeat(&[0.0, 1.0, 0.0], 5),
            ),
            // 1: joint 1's rest rotation, stored as q, -q and 2q: dropped.
            track(
                TrackTarget::Rotation(JointIndex(1)),
                Interpolation::Linear,
                &t5,
                [1.0f32, -1.0, 2.0, 1.0, -2.0]
                    .iter()
                    .flat_map(|s| (rest_rot * *s).to_array())
                    .collect(),
            ),
            // 2: constant 1.5 scale (one key off by 1e-7 relative): two STEP keys.
            track(
                TrackTarget::Scale(JointIndex(2)),
                Interpolation::Step,
                &t5,
                [
                    repeat(&[1.5; 3], 3),
                    vec![1.5, 1.5 * (1.0 + 1e-7), 1.5],
                    repeat(&[1.5; 3], 1),
                ]
                .concat(),
            ),
            // 3: varying rotation: written as it is.
            track(
                TrackTarget::Rotation(JointIndex(0)),
                Interpolation::Linear,
                &t5,
                (0..5)
                    .flat_map(|k| Quat::from_rotation_y(0.3 * k as f32).to_array())
                    .collect(),
            ),
            // 4: the mesh's default morph weights [0, 0.25]: dropped.
            track(
                TrackTarget::MorphWeights(MeshIndex(0)),
                Interpolation::Linear,
                &t5,
                repeat(&[0.0, 0.25], 5),
            ),
            // 5: constant cubic spline with zero tangents, not at rest: two cubic keys.
            track(
                TrackTarget::Translation(JointIndex(0)),
                Interpolation::CubicSpline,
                &[0.0, 0.5, 1.0],
                repeat(&[0.0, 0.0, 0.0, 0.2, 0.0, 0.0, 0.0, 0.0, 0.0], 3),
            ),
            // 6: 2e-6 (relative) from joint 2's rest translation: not at rest, two keys.
            track(
                TrackTarget::Translation(JointIndex(2)),
                Interpolation::Linear,
                &t5,
                repeat(&(tip_rest * (1.0 + 2e-6)).to_array(), 5),
            ),
            // 7: 1e-7 (relative) from joint 0's unit scale: at rest, dropped.
            track(
                TrackTarget::Scale(JointIndex(0)),
                Interpolation::Linear,
                &t5,
                repeat(&[1.0 + 1e-7; 3], 5),
            ),
            // 8: joint 2's rest rotation (identity) turned by 2e-3 rad (|dot| = 1 - 5e-7):
            // not at rest, two keys.
            track(
                TrackTarget::Rotation(JointIndex(2)),
                Interpolation::Linear,
                &t5,
                repeat(&Quat::from_rotation_x(2e-3).to_array(), 5),
            ),
        ],
    }];
    let out = glb(&asset, 4);
    assert_eq!(
        out.warnings,
        glb(&test_assets::rig(), 4).warnings,
        "dropping constant tracks is lossless: no new warning"
    );
    let channels = read_channels(&out.glb, 0);
    let summary: Vec<(usize, P, I, Vec<f32>)> = channels
        .iter()
        .map(|(n, p, i, t, _)| (*n, *p, *i, t.clone()))
        .collect();
    assert_eq!(
        summary,
        [
            (2, P::Scale, I::Step, vec![0.0, 1.0]),
            (0, P::Rotation, I::Linear, t5.clone()),
            (0, P::Translation, I::CubicSpline, vec![0.0, 1.0]),
            (2, P::Translation, I::Linear, vec![0.0, 1.0]),
            (2, P::Rotation, I::Linear, vec![0.0, 1.0]),
        ]
    );
    assert_eq!(channels[0].4, repeat(&[1.5; 3], 2));
    assert_close(
        &channels[1].4,
        &asset.clips[0].tracks[3].values,
        "varying rotation",
    );
    assert_eq!(
        channels[2].4,
        repeat(&[0.0, 0.0, 0.0, 0.2, 0.0, 0.0, 0.0, 0.0, 0.0], 2)
    );
    assert_eq!(
        channels[3].4,
        repeat(&(tip_rest * (1.0 + 2e-6)).to_array(), 2)
    );
    assert_close(
        &channels[4].4,
        &repeat(&Quat::from_rotation_x(2e-3).to_array(), 2),
        "constant rotation",
    );
    assert_khronos_valid(&out.glb);
}

#[test]
fn an_animation_keeps_its_clip_duration_when_tracks_are_dropped() {
    use gltf::animation::{Interpolation as I, Property as P};
    use rigport_model::glam::Quat;
    let mut asset = test_assets::rig();
    let rest_rot = asset.skeleton.joints()[1].rest_local.rotation.to_array();
    let at_rest = |target, times: Vec<f32>, value: &[f32]| Track {
        target,
        interpolation: Interpolation::Linear,
        values: repeat(value, times.len()),
        times,
    };
    asset.clips = vec![
        rigport_model::Clip {
            name: "rest_only".into(),
            tracks: vec![
                at_rest(
                    TrackTarget::Rotation(JointIndex(1)),
                    vec![0.0, 0.5, 2.0],
                    &rest_rot,
                ),
                at_rest(
                    TrackTarget::Translation(JointIndex(1)),
                    vec![0.0, 0.5, 2.0],
                    &[0.0, 1.0, 0.0],
                ),
            ],
        },
        rigport_model::Clip {
            name: "short_motion".into(),
            tracks: vec![
                Track {
                    target: TrackTarget::Rotation(JointIndex(0)),
                    interpolation: Interpolation::Linear,
                    times: vec![0.5, 1.0],
                    values: [Quat::IDENTITY, Quat::from_rotation_y(1.0)]
                        .iter()
                        .flat_map(|q| q.to_array())
                        .collect(),
                },
                at_rest(TrackTarget::Scale(JointIndex(1)), keys(3, 1.0), &[1.0; 3]),
                at_rest(
                    TrackTarget::Scale(JointIndex(2)),
                    vec![1.0, 2.0, 3.0],
                    &[1.0; 3],
                ),
                at_rest(TrackTarget::Scale(JointIndex(0)), keys(5, 0.5), &[1.0; 3]),
                at_rest(
                    TrackTarget::Translation(JointIndex(2)),
                    vec![0.25, 3.0],
                    &[0.0, 1.0, 0.0],
                ),
            ],
        },
    ];
    let out = glb(&asset, 4);
    assert!(
        !out.warnings.iter().any(|w| w.to_string().contains("clip")),
        "{:?}",
        out.warnings
    );
    let json = glb_json(&out.glb);
    assert_eq!(json["animations"].as_array().expect("animations").len(), 2);

    // Every track at rest: the first stays, with its first and last key.
    let rest_only = read_channels(&out.glb, 0);
    assert_eq!(rest_only.len(), 1);
    let (node, property, interpolation, times, values) = &rest_only[0];
    assert_eq!(
        (*node, *property, *interpolation),
        (1, P::Rotation, I::Linear)
    );
    assert_eq!(times, &[0.0, 2.0]);
    assert_close(values, &repeat(&rest_rot, 2), "rest rotation");

    // The motion ends at 1 s, the clip at 3 s and starts at 0: the first at-rest track
    // reaching 3 s (scale of joint 2; not the later translation) and then the first
    // reaching 0 (scale of joint 1) stay, with two keys each.
    let short = read_channels(&out.glb, 1);
    let summary: Vec<(usize, P, Vec<f32>)> = short
        .iter()
        .map(|(n, p, _, t, _)| (*n, *p, t.clone()))
        .collect();
    assert_eq!(
        summary,
        [
            (0, P::Rotation, vec![0.5, 1.0]),
            (1, P::Scale, vec![0.0, 2.0]),
            (2, P::Scale, vec![1.0, 3.0]),
        ]
    );
    for (anim, clip) in json["animations"]
        .as_array()
        .expect("animations")
        .iter()
        .zip(&asset.clips)
    {
        let inputs = anim["samplers"]
            .as_array()
            .expect("samplers")
            .iter()
            .map(|s| &json["accessors"][s["input"].as_u64().expect("input") as usize]);
        let (lo, hi) = inputs.fold((f64::INFINITY, 0.0f64), |(lo, hi), acc| {
            (
                lo.min(acc["min"][0].as_f64().expect("min")),
                hi.max(acc["max"][0].as_f64().expect("max")),
            )
        });
        assert_eq!((lo, hi as f32), (0.0, clip.duration()), "{}", clip.name);
    }
    assert_khronos_valid(&out.glb);
}

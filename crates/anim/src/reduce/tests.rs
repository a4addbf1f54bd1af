use super::*;
use glam::{Mat4, Quat};
use rigport_model::{Interpolation, Joint, MeshIndex, TrackTarget};

/// xorshift64*: deterministic test data without a dependency.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f32 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 40) as f32 / (1u64 << 24) as f32
    }
    fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.next()
    }
}

/// A random tree: joint i's parent is one of the earlier joints, offsets 0.2–1 long.
fn random_skeleton(rng: &mut Rng, n: usize) -> Skeleton {
    let joints = (0..n)
        .map(|i| {
            let parent = (i > 0).then(|| JointIndex((rng.next() * i as f32) as u32));
            let dir = Vec3::new(
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
            )
            .normalize_or(Vec3::Y);
            Joint {
                name: format!("j{i}"),
                parent,
                rest_local: Transform {
                    translation: if i == 0 {
                        Vec3::ZERO
                    } else {
                        dir * rng.range(0.2, 1.0)
                    },
                    rotation: Quat::from_rotation_y(rng.range(-1.0, 1.0)),
                    scale: Vec3::ONE,
                },
            }
        })
        .collect();
    Skeleton::new(joints).unwrap()
}

fn quats(qs: impl IntoIterator<Item = Quat>) -> Vec<f32> {
    qs.into_iter().flat_map(|q| q.to_array()).collect()
}

/// Smooth random motion at 120 fps: a sum of two sines per axis per joint, a root
/// translation, a LINEAR scale on one joint and a STEP scale on another.
fn random_clip(rng: &mut Rng, skeleton: &Skeleton, frames: usize) -> Clip {
    let times: Vec<f32> = (0..frames).map(|f| f as f32 / 120.0).collect();
    let mut tracks = Vec::new();
    for j in 0..skeleton.len() {
        let rest = skeleton.joints()[j].rest_local.rotation;
        let waves: Vec<[f32; 4]> = (0..6)
            .map(|_| {
                [
                    rng.range(0.05, 0.6),
                    rng.range(0.2, 3.0),
                    rng.range(0.0, 6.3),
                    0.0,
                ]
            })
            .collect();
        let angles = |t: f32, axis: usize| {
            let w1 = waves[2 * axis];
            let w2 = waves[2 * axis + 1];
            w1[0] * (w1[1] * t + w1[2]).sin() + w2[0] * (w2[1] * 2.0 * t + w2[2]).sin()
        };
        tracks.push(Track {
            target: TrackTarget::Rotation(JointIndex(j as u32)),
            interpolation: Interpolation::Linear,
            times: times.clone(),
            values: quats(times.iter().map(|&t| {
                rest * Quat::from_euler(
                    glam::EulerRot::ZYX,
                    angles(t, 0),
                    angles(t, 1),
                    angles(t, 2),
                )
            })),
        });
    }
    tracks.push(Track {
        target: TrackTarget::Translation(JointIndex(0)),
        interpolation: Interpolation::Linear,
        times: times.clone(),
        values: times
            .iter()
            .flat_map(|&t| [0.5 * t, 0.1 * (3.0 * t).sin(), 0.2 * (1.3 * t).cos()])
            .collect(),
    });
    tracks.push(Track {
        target: TrackTarget::Scale(JointIndex(1)),
        interpolation: Interpolation::Linear,
        times: times.clone(),
        values: times
            .iter()
            .flat_map(|&t| {
                let s = 1.0 + 0.2 * (2.0 * t).sin();
                [s, s, 1.0 / s]
            })
            .collect(),
    });
    let step_times: Vec<f32> = times.iter().step_by(17).copied().collect();
    tracks.push(Track {
        target: TrackTarget::Scale(JointIndex(2)),
        interpolation: Interpolation::Step,
        values: step_times
            .iter()
            .flat_map(|&t| [1.0 + 0.1 * t, 1.0, 1.0])
            .collect(),
        times: step_times,
    });
    Clip {
        name: "random".into(),
        tracks,
    }
}

/// The naive reference: binary search, f64 slerp and Hermite, recursive FK.
fn naive_positions(clip: &Clip, skeleton: &Skeleton, t: f32) -> Vec<Vec3> {
    let mut local: Vec<Transform> = skeleton.joints().iter().map(|j| j.rest_local).collect();
    let mut done = std::collections::BTreeSet::new();
    for track in &clip.tracks {
        if !done.insert(track.target) {
            continue;
        }
        let c = track.components();
        let times = &track.times;
        let k = times.partition_point(|&x| x <= t).saturating_sub(1);
        let (k0, k1, u) = if t <= times[0] || k + 1 == times.len() || times[k] == t {
            (k, k, 0.0)
        } else {
            (
                k,
                k + 1,
                f64::from((t - times[k]) / (times[k + 1] - times[k])),
            )
        };
        if track.interpolation == Interpolation::CubicSpline {
            // glTF 2.0 Appendix C in f64: Hermite on the components, tangents times the
            // key interval, then (rotations) normalized.
            let part = |k: usize, p: usize| -> Vec<f64> {
                let at = (3 * k + p) * c;
                track.values[at..at + c]
                    .iter()
                    .map(|&v| f64::from(v))
                    .collect()
            };
            let dt = f64::from(times[k1] - times[k0]);
            let (u2, u3) = (u * u, u * u * u);
            let h = [
                2.0 * u3 - 3.0 * u2 + 1.0,
                u3 - 2.0 * u2 + u,
                -2.0 * u3 + 3.0 * u2,
                u3 - u2,
            ];
            let (p0, m0, p1, m1) = (part(k0, 1), part(k0, 2), part(k1, 1), part(k1, 0));
            let v: Vec<f32> = (0..c)
                .map(|i| {
                    (h[0] * p0[i] + h[1] * dt * m0[i] + h[2] * p1[i] + h[3] * dt * m1[i]) as f32
                })
                .collect();
            match track.target {
                TrackTarget::Translation(j) => local[j.get()].translation = Vec3::from_slice(&v),
                TrackTarget::Scale(j) => local[j.get()].scale = Vec3::from_slice(&v),
                TrackTarget::Rotation(j) => {
                    local[j.get()].rotation = Quat::from_slice(&v).normalize();
                }
                TrackTarget::MorphWeights(_) => {}
            }
            continue;
        }
        let u = if track.interpolation == Interpolation::Step {
            0.0
        } else {
            u
        };
        let at = |k: usize| -> Vec<f64> {
            track.values[k * c..(k + 1) * c]
                .iter()
                .map(|&v| f64::from(v))
                .collect()
        };
        let (a, b) = (at(k0), at(k1));
        let value: Vec<f64> = if c == 4 {
            let norm = |q: &[f64]| {
                let l = q.iter().map(|x| x * x).sum::<f64>().sqrt();
                q.iter().map(|x| x / l).collect::<Vec<f64>>()
            };
            let (a, mut b) = (norm(&a), norm(&b));
            let mut dot: f64 = a.iter().zip(&b).map(|(x, y)| x * y).sum();
            if dot < 0.0 {
                b.iter_mut().for_each(|x| *x = -*x);
                dot = -dot;
            }
            let omega = dot.min(1.0).acos();
            if omega < 1e-9 {
                a
            } else {
                let (wa, wb) = (
                    ((1.0 - u) * omega).sin() / omega.sin(),
                    (u * omega).sin() / omega.sin(),
                );
                a.iter().zip(&b).map(|(x, y)| wa * x + wb * y).collect()
            }
        } else {
            a.iter().zip(&b).map(|(x, y)| x + (y - x) * u).collect()
        };
        let v: Vec<f32> = value.iter().map(|&x| x as f32).collect();
        match track.target {
            TrackTarget::Translation(j) => local[j.get()].translation = Vec3::from_slice(&v),
            TrackTarget::Scale(j) => local[j.get()].scale = Vec3::from_slice(&v),
            TrackTarget::Rotation(j) => local[j.get()].rotation = Quat::from_slice(&v).normalize(),
            TrackTarget::MorphWeights(_) => {}
        }
    }
    fn world(skeleton: &Skeleton, local: &[Transform], j: usize) -> Mat4 {
        let m = local[j].to_mat4();
        match skeleton.joints()[j].parent {
            Some(p) => world(skeleton, local, p.get()) * m,
            None => m,
        }
    }
    (0..skeleton.len())
        .map(|j| world(skeleton, &local, j).w_axis.truncate())
        .collect()
}

/// The largest joint position difference at every original key time, measured by the
/// naive reference.
fn measured_error(original: &Clip, reduced: &Clip, skeleton: &Skeleton) -> f32 {
    let mut times: Vec<f32> = original
        .tracks
        .iter()
        .filter(|t| !matches!(t.target, TrackTarget::MorphWeights(_)))
        .flat_map(|t| t.times.iter().copied())
        .collect();
    times.sort_by(f32::total_cmp);
    times.dedup();
    let mut worst = 0.0f32;
    for t in times {
        let a = naive_positions(original, skeleton, t);
        let b = naive_positions(reduced, skeleton, t);
        for (p, q) in a.iter().zip(&b) {
            worst = worst.max(p.distance(*q));
        }
    }
    worst
}

/// Every reduced track keeps the first and last key and a subset of the original keys,
/// values bit for bit; non-LINEAR tracks are unchanged.
fn assert_subset(original: &Clip, reduced: &Clip) {
    assert_eq!(original.tracks.len(), reduced.tracks.len());
    assert_eq!(original.duration(), reduced.duration());
    for (o, r) in original.tracks.iter().zip(&reduced.tracks) {
        assert_eq!((o.target, o.interpolation), (r.target, r.interpolation));
        if o.interpolation != Interpolation::Linear
            || matches!(o.target, TrackTarget::MorphWeights(_))
        {
            assert_eq!(o, r);
            continue;
        }
        assert_eq!(r.times.first(), o.times.first());
        assert_eq!(r.times.last(), o.times.last());
        let c = o.components();
        for (k, t) in r.times.iter().enumerate() {
            let ko = o
                .times
                .iter()
                .position(|x| x == t)
                .expect("an original time");
            assert_eq!(r.values[k * c..(k + 1) * c], o.values[ko * c..(ko + 1) * c]);
        }
    }
}

#[test]
fn bound_holds_on_random_smooth_clips() {
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    for case in 0..4 {
        let skeleton = random_skeleton(&mut rng, 6 + 3 * case);
        let clip = random_clip(&mut rng, &skeleton, 240);
        for tolerance in [1e-3, 1e-2, 0.05] {
            let (reduced, stats) = reduce(&clip, &skeleton, tolerance).unwrap();
            assert_subset(&clip, &reduced);
            let measured = measured_error(&clip, &reduced, &skeleton);
            // The naive reference slerps in f64: it may differ from the reducer's f32
            // sampling by a few ulps of the skeleton's size (a few units here).
            assert!(
                measured <= tolerance + 2e-5,
                "case {case} tol {tolerance}: measured {measured}, stats {stats:?}"
            );
            assert!(
                (measured - stats.max_error).abs() <= 2e-5,
                "case {case}: measured {measured} vs reported {}",
                stats.max_error
            );
            assert!(stats.max_error <= tolerance);
            println!("case {case} tol {tolerance}: {stats:?}");
            // At 1 mm, motion this fast needs most of its 120 fps keys.
            let factor = if tolerance < 0.01 { 1 } else { 3 };
            assert!(
                stats.keys_after * factor < stats.keys_before,
                "case {case} tol {tolerance}: smooth motion keeps few keys: {stats:?}"
            );
        }
    }
}

#[test]
fn bound_holds_across_a_sharp_step() {
    // A chain of 4 along +X; the root's translation jumps by 1 between two frames and
    // joint 1's rotation flips by 120 degrees between two others.
    let skeleton = Skeleton::new(
        (0..4)
            .map(|i| Joint {
                name: format!("j{i}"),
                parent: (i > 0).then(|| JointIndex(i - 1)),
                rest_local: Transform::from_translation(if i > 0 { Vec3::X } else { Vec3::ZERO }),
            })
            .collect(),
    )
    .unwrap();
    let times: Vec<f32> = (0..100).map(|f| f as f32 / 30.0).collect();
    let clip = Clip {
        name: "step".into(),
        tracks: vec![
            Track {
                target: TrackTarget::Translation(JointIndex(0)),
                interpolation: Interpolation::Linear,
                times: times.clone(),
                values: (0..100)
                    .flat_map(|f| [if f < 40 { 0.0 } else { 1.0 }, 0.01 * f as f32, 0.0])
                    .collect(),
            },
            Track {
                target: TrackTarget::Rotation(JointIndex(1)),
                interpolation: Interpolation::Linear,
                times: times.clone(),
                values: quats((0..100).map(|f| {
                    let a = if f < 70 {
                        0.002 * f as f32
                    } else {
                        2.1 + 0.002 * f as f32
                    };
                    Quat::from_rotation_z(a)
                })),
            },
        ],
    };
    for tolerance in [1e-4, 1e-2] {
        let (reduced, stats) = reduce(&clip, &skeleton, tolerance).unwrap();
        assert_subset(&clip, &reduced);
        let measured = measured_error(&clip, &reduced, &skeleton);
        assert!(measured <= tolerance + 1e-5, "{measured} {stats:?}");
        // The keys on both sides of each step survive; the ramps between go.
        let tr = &reduced.tracks[0].times;
        assert!(tr.contains(&times[39]) && tr.contains(&times[40]), "{tr:?}");
        let rot = &reduced.tracks[1].times;
        assert!(
            rot.contains(&times[69]) && rot.contains(&times[70]),
            "{rot:?}"
        );
        assert!(tr.len() <= 6 && rot.len() <= 6, "{tr:?} {rot:?}");
    }
}

#[test]
fn tolerance_zero_keeps_every_non_redundant_key() {
    let mut rng = Rng(7);
    let skeleton = random_skeleton(&mut rng, 8);
    let clip = random_clip(&mut rng, &skeleton, 120);
    let (reduced, stats) = reduce(&clip, &skeleton, 0.0).unwrap();
    assert_eq!(reduced, clip, "no key of smooth motion is redundant");
    assert_eq!(stats.keys_before, stats.keys_after);
    assert_eq!(stats.max_error, 0.0);

    // Runs of equal values: only their interior keys go, and the result is exact.
    let mut held = clip.clone();
    let rot = &mut held.tracks[3];
    let first: Vec<f32> = rot.values[40..44].to_vec();
    for k in 10..=30 {
        rot.values[4 * k..4 * k + 4].copy_from_slice(&first);
    }
    let root = held
        .tracks
        .iter_mut()
        .find(|t| t.target == TrackTarget::Translation(JointIndex(0)))
        .unwrap();
    for k in 100..120 {
        let v: Vec<f32> = root.values[300..303].to_vec();
        root.values[3 * k..3 * k + 3].copy_from_slice(&v);
    }
    let (reduced, stats) = reduce(&held, &skeleton, 0.0).unwrap();
    assert_subset(&held, &reduced);
    assert_eq!(stats.keys_before - stats.keys_after, 19 + 18, "{stats:?}");
    assert_eq!(reduced.tracks[3].times.len(), 120 - 19);
    assert!(!reduced.tracks[3].times.contains(&held.tracks[3].times[20]));
    assert_eq!(stats.max_error, 0.0);
    assert_eq!(measured_error(&held, &reduced, &skeleton), 0.0);
}

#[test]
fn linear_ramps_reduce_to_two_keys() {
    let skeleton = Skeleton::new(vec![
        Joint {
            name: "root".into(),
            parent: None,
            rest_local: Transform::IDENTITY,
        },
        Joint {
            name: "arm".into(),
            parent: Some(JointIndex(0)),
            rest_local: Transform::from_translation(Vec3::new(0.0, 2.0, 0.0)),
        },
        Joint {
            name: "hand".into(),
            parent: Some(JointIndex(1)),
            rest_local: Transform::from_translation(Vec3::new(0.0, 1.0, 0.0)),
        },
    ])
    .unwrap();
    let times: Vec<f32> = (0..100).map(|f| f as f32 * 0.01).collect();
    let clip = Clip {
        name: "ramp".into(),
        tracks: vec![
            Track {
                target: TrackTarget::Translation(JointIndex(0)),
                interpolation: Interpolation::Linear,
                times: times.clone(),
                values: times.iter().flat_map(|&t| [t, 2.0 * t, -3.0 * t]).collect(),
            },
            Track {
                // Constant angular velocity: slerp between the ends is the same path.
                // Every other key is stored as -q, the same rotation.
                target: TrackTarget::Rotation(JointIndex(1)),
                interpolation: Interpolation::Linear,
                times: times.clone(),
                values: quats(times.iter().enumerate().map(|(k, &t)| {
                    let q = Quat::from_rotation_x(1.5 * t);
                    if k % 2 == 1 {
                        -q
                    } else {
                        q
                    }
                })),
            },
        ],
    };
    let (reduced, stats) = reduce(&clip, &skeleton, 1e-4).unwrap();
    for track in &reduced.tracks {
        assert_eq!(track.times, [times[0], times[99]]);
    }
    assert_eq!((stats.keys_before, stats.keys_after), (200, 4));
    assert!(measured_error(&clip, &reduced, &skeleton) <= 1e-4);
}

#[test]
fn stats_count_every_track_and_other_tracks_are_kept() {
    let mut rng = Rng(99);
    let skeleton = random_skeleton(&mut rng, 5);
    let mut clip = random_clip(&mut rng, &skeleton, 60);
    clip.tracks.push(Track {
        target: TrackTarget::Translation(JointIndex(3)),
        interpolation: Interpolation::CubicSpline,
        times: vec![0.0, 0.25, 0.5],
        values: (0..27).map(|i| (i as f32 * 0.37).sin() * 0.1).collect(),
    });
    clip.tracks.push(Track {
        target: TrackTarget::MorphWeights(MeshIndex(0)),
        interpolation: Interpolation::Linear,
        times: vec![0.0, 0.1, 0.2, 0.3],
        values: vec![0.0, 0.0, 0.0, 0.0],
    });
    // A second track for the same property: kept, not sampled.
    let mut duplicate = clip.tracks[0].clone();
    duplicate.values.iter_mut().for_each(|v| *v = -*v);
    clip.tracks.push(duplicate);
    let (reduced, stats) = reduce(&clip, &skeleton, 0.01).unwrap();
    assert_subset(&clip, &reduced);
    let count = |c: &Clip| c.tracks.iter().map(|t| t.times.len()).sum::<usize>();
    assert_eq!(stats.keys_before, count(&clip));
    assert_eq!(stats.keys_after, count(&reduced));
    assert!(stats.keys_after < stats.keys_before);
    let n = clip.tracks.len();
    assert_eq!(reduced.tracks[n - 1], clip.tracks[n - 1], "duplicate kept");
    assert_eq!(
        reduced.tracks[n - 2],
        clip.tracks[n - 2],
        "morph weights kept"
    );
    assert_eq!(reduced.tracks[n - 3], clip.tracks[n - 3], "cubic kept");
    assert!(
        stats.max_error > 0.0 && stats.max_error <= 0.01,
        "{stats:?}"
    );
}

#[test]
fn verification_tightens_and_restores_until_the_bound_holds() {
    let mut rng = Rng(0x00DE_C0DE);
    let skeleton = random_skeleton(&mut rng, 10);
    let clip = random_clip(&mut rng, &skeleton, 240);
    let tolerance = 0.01;
    let (plain, _) = reduce(&clip, &skeleton, tolerance).unwrap();
    // Local tolerances 50 times too loose: the first round fails, tightening repairs it.
    let loose = Tuning {
        budget_scale: 50.0,
        ..Tuning::DEFAULT
    };
    let (tightened, stats) = reduce_with(&clip, &skeleton, tolerance, loose).unwrap();
    assert_subset(&clip, &tightened);
    assert!(measured_error(&clip, &tightened, &skeleton) <= tolerance + 2e-5);
    assert!(stats.max_error <= tolerance);
    assert_ne!(tightened, plain, "another path to the bound");
    // No tightening allowed: the failing chains come back whole, and the bound holds.
    let no_rounds = Tuning {
        budget_scale: 50.0,
        tighten_rounds: 0,
    };
    let (restored, stats) = reduce_with(&clip, &skeleton, tolerance, no_rounds).unwrap();
    assert_subset(&clip, &restored);
    assert!(measured_error(&clip, &restored, &skeleton) <= tolerance + 2e-5);
    assert!(stats.max_error <= tolerance);
    let whole = restored
        .tracks
        .iter()
        .zip(&clip.tracks)
        .filter(|(r, o)| r.interpolation == Interpolation::Linear && r == o)
        .count();
    assert!(whole > 0, "some tracks restored whole");
    assert!(stats.keys_after < stats.keys_before, "{stats:?}");
}

#[test]
fn bad_inputs_are_reported() {
    let mut rng = Rng(3);
    let skeleton = random_skeleton(&mut rng, 3);
    let clip = random_clip(&mut rng, &skeleton, 10);
    for tolerance in [-1.0, f32::NAN, f32::INFINITY] {
        assert!(matches!(
            reduce(&clip, &skeleton, tolerance),
            Err(ReduceError::Tolerance { .. })
        ));
    }
    let mut bad = clip.clone();
    bad.tracks[1].target = TrackTarget::Rotation(JointIndex(7));
    assert_eq!(
        reduce(&bad, &skeleton, 0.1).unwrap_err(),
        ReduceError::UnknownJoint {
            clip: "random".into(),
            track: 1,
            joint: JointIndex(7),
            joints: 3
        }
    );
    let mut bad = clip.clone();
    bad.tracks[0].values.pop();
    assert!(matches!(
        reduce(&bad, &skeleton, 0.1).unwrap_err(),
        ReduceError::BadTrack {
            track: 0,
            problem: TrackProblem::ValueCount {
                expected: 40,
                found: 39
            },
            ..
        }
    ));
    let mut bad = clip.clone();
    bad.tracks[2].values[8..12].fill(0.0);
    assert!(matches!(
        reduce(&bad, &skeleton, 0.1).unwrap_err(),
        ReduceError::BadTrack {
            track: 2,
            problem: TrackProblem::ZeroRotation { key: 2 },
            ..
        }
    ));
    let mut bad = clip.clone();
    bad.tracks[0].times[5] = bad.tracks[0].times[4];
    assert!(matches!(
        reduce(&bad, &skeleton, 0.1).unwrap_err(),
        ReduceError::BadTrack {
            track: 0,
            problem: TrackProblem::Times { key: 5 },
            ..
        }
    ));
    let mut bad = clip;
    bad.tracks[0].times.clear();
    assert!(matches!(
        reduce(&bad, &skeleton, 0.1).unwrap_err(),
        ReduceError::BadTrack {
            track: 0,
            problem: TrackProblem::NoKeys,
            ..
        }
    ));
}

#[test]
fn mocap_sized_clip_is_fast() {
    // 30 joints x 5000 frames at 120 fps, like CMU 131_04-dance.
    let mut rng = Rng(131);
    let skeleton = random_skeleton(&mut rng, 30);
    let clip = random_clip(&mut rng, &skeleton, 5000);
    let start = std::time::Instant::now();
    let (_, stats) = reduce(&clip, &skeleton, 0.01).unwrap();
    let elapsed = start.elapsed();
    println!("30 joints x 5000 frames: {stats:?} in {elapsed:?}");
    assert!(stats.max_error <= 0.01);
    if !cfg!(debug_assertions) {
        assert!(elapsed.as_secs_f32() < 0.5, "{elapsed:?}");
    }
}

/// A root spinning three full turns about Y in 12° steps, then one step of 200° between two
/// keys (which a viewer's shortest-path slerp plays as -160°), then still: the reduced clip
/// (key removal, uniform rate, 16-bit rotations, virtual points) turns the same way at
/// every time, between keys too, and by the same total angle (glTF-Transform #501: keys
/// more than 180° apart collapse a spin or turn it backwards).
#[test]
fn spins_and_steps_over_180_degrees_keep_their_direction() {
    let skeleton = Skeleton::new(vec![
        Joint {
            name: "root".into(),
            parent: None,
            rest_local: Transform::IDENTITY,
        },
        Joint {
            name: "arm".into(),
            parent: Some(JointIndex(0)),
            rest_local: Transform {
                translation: Vec3::new(0.5, 0.0, 0.0),
                ..Transform::IDENTITY
            },
        },
    ])
    .expect("valid");
    let step = 12f32.to_radians();
    // `wobble`: the spin speeds up and slows down (±50% of its 12° per frame, back in
    // phase after the three turns), which slerp between far keys cannot follow and cubic
    // Hermite segments can: CUBICSPLINE tracks then win.
    let spin = |wobble: f32| {
        let mut angles: Vec<f32> = (0..=90)
            .map(|k| {
                let phase = std::f32::consts::TAU * k as f32 / 45.0;
                k as f32 * step + wobble * 45.0 * step * 0.5 / std::f32::consts::TAU * phase.sin()
            })
            .collect(); // 3 turns
        let spun = *angles.last().expect("keys");
        angles.push(spun + 200f32.to_radians());
        angles.extend([angles[91]; 10]);
        angles
    };
    let angles = spin(0.0);
    let times: Vec<f32> = (0..angles.len()).map(|k| k as f32 / 30.0).collect();
    let clip_of = |angles: &[f32]| Clip {
        name: "spin".into(),
        tracks: vec![Track {
            target: TrackTarget::Rotation(JointIndex(0)),
            interpolation: Interpolation::Linear,
            times: times.clone(),
            values: quats(angles.iter().map(|&a| Quat::from_rotation_y(a))),
        }],
    };
    let clip = clip_of(&angles);
    let wobbly = clip_of(&spin(1.0));
    let mut cubic_tracks = 0;
    for (options, clip) in [
        ReduceOptions {
            tolerance: 1e-3,
            point_distance: vec![0.03; 2],
            codec: Some(Codec::I16),
            uniform_rate: true,
            cubic: false,
        },
        ReduceOptions {
            tolerance: 0.05,
            ..ReduceOptions::default()
        },
        // CUBICSPLINE fits: components interpolated, then normalized, across the turns.
        ReduceOptions {
            tolerance: 1e-3,
            point_distance: vec![0.03; 2],
            codec: Some(Codec::I16),
            uniform_rate: true,
            cubic: true,
        },
        ReduceOptions {
            tolerance: 0.05,
            cubic: true,
            ..ReduceOptions::default()
        },
        ReduceOptions {
            tolerance: 1e-2,
            point_distance: vec![0.03; 2],
            codec: Some(Codec::I16),
            uniform_rate: true,
            cubic: true,
        },
    ]
    .into_iter()
    // The wobbly spin at the 1 mm and 1 cm bounds (`follows` allows 2 cm between
    // source frames).
    .flat_map(|options| {
        let tight = options.tolerance <= 0.01;
        let both = [(options.clone(), &clip), (options, &wobbly)];
        both.into_iter().take(if tight { 2 } else { 1 })
    }) {
        let (reduced, stats) = reduce_clip(clip, &skeleton, &options).expect("reduces");
        assert!(stats.max_error <= options.tolerance, "{stats:?}");
        // The wobble at 1 mm on LINEAR keys needs every key.
        let wobbles = std::ptr::eq(clip, &wobbly);
        assert!(
            stats.keys_after < stats.keys_before + usize::from(wobbles),
            "{stats:?}"
        );
        follows(clip, &reduced, &skeleton, &times).expect("same direction");
        cubic_tracks += usize::from(reduced.tracks[0].interpolation == Interpolation::CubicSpline);
    }
    // A uniform spin is what slerp reproduces exactly: LINEAR keys win there, and on the
    // wobble at 30 keys per second too (a cubic key, 52 bytes as floats, covers too few
    // frames); `cubic_spins_and_steps_keep_their_direction` has cubic tracks win.
    assert_eq!(cubic_tracks, 0);
    // The check catches the failure: every 16th key (192° apart) turns backwards.
    let every_16th: Vec<usize> = (0..times.len())
        .step_by(16)
        .chain([times.len() - 1])
        .collect();
    let mut backwards = clip.clone();
    backwards.tracks[0] = pick_keys(&clip.tracks[0], &every_16th);
    assert!(follows(&clip, &backwards, &skeleton, &times).is_err());
}

/// Whether `reduced` turns as `clip` does at ten samples per source interval: the arm stays
/// where the source puts it, the heading turns by the same signed amount in every sub-step,
/// and by the same total (three turns one way, then -160°).
fn follows(clip: &Clip, reduced: &Clip, skeleton: &Skeleton, times: &[f32]) -> Result<(), String> {
    let pi = std::f32::consts::PI;
    let wrap = |d: f32| (d + pi).rem_euclid(2.0 * pi) - pi;
    let (mut total_a, mut total_b) = (0.0f32, 0.0f32);
    let (mut last_a, mut last_b) = (0.0f32, 0.0f32);
    for k in 0..(times.len() - 1) * 10 + 1 {
        let t = k as f32 / 300.0;
        let a = naive_positions(clip, skeleton, t)[1];
        let b = naive_positions(reduced, skeleton, t)[1];
        if a.distance(b) >= 0.02 {
            return Err(format!("t {t}: {a} vs {b}"));
        }
        let (ha, hb) = (a.z.atan2(a.x), b.z.atan2(b.x));
        if k > 0 {
            let (da, db) = (wrap(ha - last_a), wrap(hb - last_b));
            if (da - db).abs() >= 0.05 {
                return Err(format!("t {t}: turned {da} in the source, {db} reduced"));
            }
            total_a += da;
            total_b += db;
        }
        (last_a, last_b) = (ha, hb);
    }
    let expected = -(6.0 * pi - 160f32.to_radians());
    if (total_a - expected).abs() >= 1e-2 || (total_b - total_a).abs() >= 1e-2 {
        return Err(format!(
            "turned {total_b}, source {total_a}, expected {expected}"
        ));
    }
    Ok(())
}

/// Virtual points, 16-bit rotations and the uniform rate on random motion: the bound holds
/// as `point_error` measures it (the same numbers), kept keys are original keys, and at
/// 3 cm points the reduction still removes keys.
#[test]
fn bound_holds_with_points_rotations_i16_and_uniform_rates() {
    let mut rng = Rng(0x5eed_1234_abcd);
    let skeleton = random_skeleton(&mut rng, 12);
    let clip = random_clip(&mut rng, &skeleton, 240);
    let points = vec![0.03; skeleton.len()];
    for tolerance in [1e-3, 1e-2] {
        let options = ReduceOptions {
            tolerance,
            point_distance: points.clone(),
            codec: Some(Codec::I16),
            uniform_rate: true,
            cubic: false,
        };
        let (reduced, stats) = reduce_clip(&clip, &skeleton, &options).expect("reduces");
        assert!(stats.coded);
        assert!(stats.max_error <= tolerance, "{stats:?}");
        assert!(stats.keys_after < stats.keys_before, "{stats:?}");
        assert_subset(&clip, &reduced);
        let measured = metric::point_error(&clip, &reduced, &skeleton, &points, Some(&Codec::I16))
            .expect("measures");
        assert_eq!(measured.max, stats.max_error);
        assert!(measured.mean <= measured.max);
        // Joints alone, without rounding, by the naive reference: within the bound too
        // (rounding moves a joint by well under the bound here).
        assert!(measured_error(&clip, &reduced, &skeleton) <= tolerance * 1.05);
    }
}

/// Rounding to 16 bits alone over the bound: rotations are measured (and must be written)
/// as floats.
#[test]
fn rounding_that_exceeds_the_bound_falls_back_to_floats() {
    let mut rng = Rng(0xfeed);
    let skeleton = random_skeleton(&mut rng, 6);
    let clip = random_clip(&mut rng, &skeleton, 60);
    let options = ReduceOptions {
        tolerance: 1e-7,
        point_distance: vec![0.03; skeleton.len()],
        codec: Some(Codec::I16),
        uniform_rate: true,
        cubic: false,
    };
    let (_, stats) = reduce_clip(&clip, &skeleton, &options).expect("reduces");
    assert!(!stats.coded);
    assert!(stats.max_error <= 1e-7, "{stats:?}");
}

/// CUBICSPLINE fits on random smooth motion: the bound holds at every source frame by the
/// naive reference (f64 Hermite, recursive FK) and by `point_error`, with and without
/// 16-bit rotations; cubic tracks make the clip fewer bytes than LINEAR keys alone.
#[test]
fn cubic_fits_hold_the_bound_at_every_source_frame() {
    let mut rng = Rng(0xC0B1_C5EE_D000_0001);
    let skeleton = random_skeleton(&mut rng, 10);
    let clip = random_clip(&mut rng, &skeleton, 360);
    let points = vec![0.03; skeleton.len()];
    for (tolerance, codec) in [
        (1e-3, Some(Codec::I16)),
        (1e-3, None),
        (1e-2, Some(Codec::I16)),
    ] {
        let options = |cubic| ReduceOptions {
            tolerance,
            point_distance: points.clone(),
            codec,
            uniform_rate: true,
            cubic,
        };
        let (reduced, stats) = reduce_clip(&clip, &skeleton, &options(true)).expect("reduces");
        assert!(stats.max_error <= tolerance, "{stats:?}");
        let cubic: Vec<&Track> = reduced
            .tracks
            .iter()
            .filter(|t| t.interpolation == Interpolation::CubicSpline)
            .collect();
        assert!(
            !cubic.is_empty(),
            "tol {tolerance}: smooth motion fits cubics"
        );
        for track in &cubic {
            assert_eq!(
                track.values.len(),
                track.times.len() * 3 * track.components()
            );
        }
        let measured = metric::point_error(&clip, &reduced, &skeleton, &points, codec.as_ref())
            .expect("measures");
        assert_eq!(measured.max, stats.max_error);
        // Joints alone, by the naive reference at every source frame (16-bit rounding
        // included in the reducer's figure, not in the reference's: a few percent).
        let naive = measured_error(&clip, &reduced, &skeleton);
        assert!(
            naive <= tolerance * 1.05,
            "tol {tolerance}: naive {naive}, {stats:?}"
        );
        // Fewer bytes than LINEAR keys: values (8 bytes per 16-bit rotation, 12 per
        // vector) and a time per key, as an upper bound on both.
        let bytes = |clip: &Clip| -> usize {
            clip.tracks
                .iter()
                .map(|t| {
                    let value = if codec.is_some() && t.components() == 4 {
                        8
                    } else {
                        4 * t.components()
                    };
                    let per = if t.interpolation == Interpolation::CubicSpline {
                        3
                    } else {
                        1
                    };
                    t.times.len() * (per * value + 4)
                })
                .sum()
        };
        let (linear, _) = reduce_clip(&clip, &skeleton, &options(false)).expect("reduces");
        assert!(
            bytes(&reduced) < bytes(&linear),
            "tol {tolerance}: {} vs {}",
            bytes(&reduced),
            bytes(&linear)
        );
    }
}

/// A 16-bit cubic rotation holds tangents in `[-1, 1]` only: a fit whose tangents leave it
/// is written (and measured) as floats, one inside it as 16-bit components.
#[test]
fn cubic_tangents_out_of_16_bit_range_fall_back_to_floats() {
    let track = |tangent: f32| Track {
        target: TrackTarget::Rotation(JointIndex(0)),
        interpolation: Interpolation::CubicSpline,
        times: vec![0.0, 1.0],
        values: vec![
            0.0, 0.0, 0.0, 0.0, /**/ 0.0, 0.0, 0.0, 1.0, /**/ 0.0, tangent, 0.0,
            0.0, //
            0.0, tangent, 0.0, 0.0, /**/ 0.0, 0.6, 0.0, 0.8, /**/ 0.0, 0.0, 0.0, 0.0,
        ],
    };
    let inside = codec::cubic_as_written(&track(0.7), true, &Codec::I16).expect("16-bit");
    assert!((inside.values[9] - 0.7).abs() <= 0.5 / 32767.0 && inside.values[9] != 0.7);
    assert!(codec::cubic_as_written(&track(1.5), true, &Codec::I16).is_none());
    // A fast spin (4 turns a second: quaternion components change by up to 4π per second)
    // still reduces within the bound with cubic tracks, whatever the storage.
    let skeleton = Skeleton::new(vec![
        Joint {
            name: "root".into(),
            parent: None,
            rest_local: Transform::IDENTITY,
        },
        Joint {
            name: "arm".into(),
            parent: Some(JointIndex(0)),
            rest_local: Transform::from_translation(Vec3::X),
        },
    ])
    .expect("valid");
    let times: Vec<f32> = (0..241).map(|k| k as f32 / 120.0).collect();
    let clip = Clip {
        name: "fast".into(),
        tracks: vec![Track {
            target: TrackTarget::Rotation(JointIndex(0)),
            interpolation: Interpolation::Linear,
            times: times.clone(),
            values: quats(times.iter().map(|&t| {
                Quat::from_rotation_y(8.0 * std::f32::consts::PI * t)
                    * Quat::from_rotation_x(0.3 * t)
            })),
        }],
    };
    let options = ReduceOptions {
        tolerance: 1e-3,
        point_distance: vec![0.03; 2],
        codec: Some(Codec::I16),
        uniform_rate: true,
        cubic: true,
    };
    let (reduced, stats) = reduce_clip(&clip, &skeleton, &options).expect("reduces");
    assert!(stats.max_error <= 1e-3, "{stats:?}");
    assert!(measured_error(&clip, &reduced, &skeleton) <= 1.05e-3);
    let out = &reduced.tracks[0];
    if out.interpolation == Interpolation::CubicSpline {
        let written = codec::cubic_as_written(out, true, &Codec::I16);
        // Either every component fits 16 bits and is rounded, or the track stays floats.
        let in_range = out.values.iter().all(|v| v.abs() <= 1.0);
        assert_eq!(written.is_some(), in_range);
    }
    follows_spin(&clip, &reduced, &skeleton);
}

/// The arm's heading turns by the same amount as the source's between source frames.
fn follows_spin(clip: &Clip, reduced: &Clip, skeleton: &Skeleton) {
    let times = &clip.tracks[0].times;
    for w in times.windows(2) {
        for s in 0..4 {
            let t = w[0] + (w[1] - w[0]) * s as f32 / 4.0;
            let a = naive_positions(clip, skeleton, t)[1];
            let b = naive_positions(reduced, skeleton, t)[1];
            assert!(a.distance(b) < 0.01, "t {t}: {a} vs {b}");
        }
    }
}

/// CUBICSPLINE tracks on a spin of four and a half turns whose speed varies, then one step
/// of 200° between two keys (played as -160°, as the source's slerp does), then still: the
/// cubic fit wins, holds the bound, and turns the same way as the source between every
/// two source frames and by the same total (glTF-Transform #501).
#[test]
fn cubic_spins_and_steps_keep_their_direction() {
    let skeleton = Skeleton::new(vec![
        Joint {
            name: "root".into(),
            parent: None,
            rest_local: Transform::IDENTITY,
        },
        Joint {
            name: "arm".into(),
            parent: Some(JointIndex(0)),
            rest_local: Transform::from_translation(Vec3::new(0.5, 0.0, 0.0)),
        },
    ])
    .expect("valid");
    let tau = std::f32::consts::TAU;
    let mut angles: Vec<f32> = (0..=360)
        .map(|k| {
            let t = k as f32 / 120.0;
            1.5 * tau * t + 0.8 * (0.7 * tau * t).sin()
        })
        .collect();
    let spun = *angles.last().expect("keys");
    angles.push(spun + 200f32.to_radians());
    let held = *angles.last().expect("keys");
    angles.extend([held; 20]);
    let times: Vec<f32> = (0..angles.len()).map(|k| k as f32 / 120.0).collect();
    let clip = Clip {
        name: "spin".into(),
        tracks: vec![Track {
            target: TrackTarget::Rotation(JointIndex(0)),
            interpolation: Interpolation::Linear,
            times: times.clone(),
            values: quats(angles.iter().map(|&a| Quat::from_rotation_y(a))),
        }],
    };
    let options = ReduceOptions {
        tolerance: 1e-3,
        point_distance: vec![0.03; 2],
        codec: Some(Codec::I16),
        uniform_rate: true,
        cubic: true,
    };
    let (reduced, stats) = reduce_clip(&clip, &skeleton, &options).expect("reduces");
    assert_eq!(reduced.tracks[0].interpolation, Interpolation::CubicSpline);
    assert!(stats.max_error <= 1e-3, "{stats:?}");
    assert!(stats.keys_after * 4 < stats.keys_before, "{stats:?}");
    assert!(measured_error(&clip, &reduced, &skeleton) <= 1.05e-3);
    // The heading, at four sub-steps per source frame: the same signed turn each sub-step
    // (the source slerps between its frames) and the same total.
    let pi = std::f32::consts::PI;
    let wrap = |d: f32| (d + pi).rem_euclid(tau) - pi;
    let heading = |c: &Clip, t: f32| {
        let p = naive_positions(c, &skeleton, t)[1];
        p.z.atan2(p.x)
    };
    let (mut total_a, mut total_b) = (0.0f32, 0.0f32);
    let (mut last_a, mut last_b) = (heading(&clip, 0.0), heading(&reduced, 0.0));
    for k in 1..(times.len() - 1) * 4 + 1 {
        let t = k as f32 / 480.0;
        let (a, b) = (heading(&clip, t), heading(&reduced, t));
        let (da, db) = (wrap(a - last_a), wrap(b - last_b));
        // The same way; by the same amount but across the 200° step, where a cubic segment
        // (components interpolated, then normalized) turns unevenly where slerp does not.
        let same_way = da.abs() < 1e-3 || da.signum() == db.signum();
        assert!(
            same_way && (da - db).abs() < 0.15,
            "t {t}: turned {da} in the source, {db} reduced"
        );
        total_a += da;
        total_b += db;
        (last_a, last_b) = (a, b);
    }
    // Rotation about +Y turns +X towards -Z: headings (atan2(z, x)) decrease.
    let expected = -(spun - 160f32.to_radians());
    assert!((total_a - expected).abs() < 1e-2, "{total_a} vs {expected}");
    assert!((total_b - total_a).abs() < 1e-2, "{total_b} vs {total_a}");
}

/// A test codec's rounding with `bits` per component: each component on a grid of
/// `2^-(bits - 1)`, not normalized (a reader composes it as it is).
fn grid(keys: &[[f32; 4]], bits: u8) -> Vec<[f32; 4]> {
    let step = 1.0 / f32::from(1u16 << (bits - 1));
    keys.iter()
        .map(|q| q.map(|c| (c / step).round() * step))
        .collect()
}

/// 16-bit rotations by default, `grid` at the bits the reducer picks.
const GRID: Codec = Codec {
    rotation: rigport_model::quantize::rotation_as_i16,
    vector: None,
    rotation_bits: Some(RotationBits {
        written: grid,
        choices: &[6, 7, 8, 9, 10, 11, 12, 13, 14, 15],
        key_bytes: |_| 8,
    }),
    key_time_bytes: 4,
};

/// A random 12-joint rig's 240-frame clip reduced within 1 mm (points at 3 cm) through
/// `codec`, LINEAR keys: the skeleton, the clip, the points, the reduced clip and its
/// stats, after asserting that the bound holds as the tracks are written at their bits.
fn reduce_through(seed: u64, codec: Codec) -> (Skeleton, Clip, Vec<f32>, Clip, ReduceStats) {
    let mut rng = Rng(seed);
    let skeleton = random_skeleton(&mut rng, 12);
    let clip = random_clip(&mut rng, &skeleton, 240);
    let points = vec![0.03; skeleton.len()];
    let options = ReduceOptions {
        tolerance: 1e-3,
        point_distance: points.clone(),
        codec: Some(codec),
        uniform_rate: true,
        cubic: false,
    };
    let (reduced, stats) = reduce_clip(&clip, &skeleton, &options).expect("reduces");
    assert!(stats.coded && stats.max_error <= 1e-3, "{stats:?}");
    assert_eq!(stats.rotation_bits.len(), reduced.tracks.len());
    let measured = metric::point_error_bits(
        &clip,
        &reduced,
        &skeleton,
        &points,
        Some(&codec),
        &stats.rotation_bits,
    )
    .expect("measures");
    assert_eq!(measured.max, stats.max_error);
    (skeleton, clip, points, reduced, stats)
}

/// The bits `stats` reports for `joint`'s rotation track (0: the codec's default).
fn joint_bits(reduced: &Clip, stats: &ReduceStats, joint: usize) -> u8 {
    let k = reduced
        .tracks
        .iter()
        .position(|t| t.target == TrackTarget::Rotation(JointIndex(joint as u32)))
        .expect("a rotation track per joint");
    stats.rotation_bits[k]
}

/// The joints no joint has as parent.
fn leaves(skeleton: &Skeleton) -> Vec<usize> {
    let parents: Vec<Option<JointIndex>> = skeleton.parents().collect();
    (0..skeleton.len())
        .filter(|&j| !parents.contains(&Some(JointIndex(j as u32))))
        .collect()
}

/// With a codec that takes bits per track, each rotation track gets the fewest its
/// tolerance allows: a leaf, whose rotation moves only its 3 cm points, fewer than the
/// root, which moves the whole chain; the bound holds as the tracks are written, at those
/// bits; a codec with one precision reports none.
#[test]
fn rotation_bits_are_picked_per_track_within_the_bound() {
    let (skeleton, clip, points, reduced, stats) = reduce_through(0x00b1_75ee_d5ee, GRID);
    let bits_of = |joint: usize| match joint_bits(&reduced, &stats, joint) {
        0 => 16,
        b => b,
    };
    let leaf = *leaves(&skeleton).last().expect("a leaf");
    assert!(bits_of(leaf) < bits_of(0), "{:?}", stats.rotation_bits);
    assert!(bits_of(leaf) < 16, "{:?}", stats.rotation_bits);
    // The root moves every joint: its tolerance is a few 1e-4 rad, which 15 bits hold.
    assert!(bits_of(0) < 16, "{:?}", stats.rotation_bits);
    // Only rotation tracks have bits.
    for (track, &bits) in reduced.tracks.iter().zip(&stats.rotation_bits) {
        assert!(bits == 0 || matches!(track.target, TrackTarget::Rotation(_)));
    }
    // Read at the default precision instead, the clip is another one: the bits matter.
    let default =
        metric::point_error(&clip, &reduced, &skeleton, &points, Some(&GRID)).expect("measures");
    assert_ne!(default.max, stats.max_error);
    let one = ReduceOptions {
        tolerance: 1e-3,
        point_distance: points,
        codec: Some(Codec::I16),
        uniform_rate: true,
        cubic: false,
    };
    let (_, stats) = reduce_clip(&clip, &skeleton, &one).expect("reduces");
    assert!(stats.rotation_bits.is_empty());
}

/// Core glTF's codec offers 8-bit rotations: a leaf (3 cm points) takes them, the root
/// (which moves the whole chain) keeps 16 bits, and the bound holds as written.
#[test]
fn core_codec_gives_leaves_8_bit_rotations_within_the_bound() {
    let (skeleton, _, _, reduced, stats) = reduce_through(0x0c0e_8b17, Codec::CORE);
    let bits_of = |joint: usize| joint_bits(&reduced, &stats, joint);
    let leaves = leaves(&skeleton);
    assert!(
        leaves.iter().any(|&j| bits_of(j) == 8),
        "{:?}",
        stats.rotation_bits
    );
    assert_eq!(bits_of(0), 0, "{:?}", stats.rotation_bits);
    assert!(stats.rotation_bits.iter().all(|&b| b == 0 || b == 8));
}

//! Cloth on a skinned box arm that bends at the elbow: pins follow the skin exactly, the
//! garment stays outside the capsules, stretch stays small, runs are bit-identical.

use glam::{Quat, Vec3};
use rigport_model::{
    Asset, Clip, Influence, Influences, Interpolation, Joint, JointIndex, Mesh, MeshIndex,
    Skeleton, SkinBinding, Track, TrackTarget, Transform,
};

use super::*;
use rigport_eval::sample::{CompiledClip, SampleJob};
use rigport_eval::{Pose, Rig, RigOutput};
use rigport_model::UpAxis;

/// A Z-up arm like the USTC course's: joints at z = 0, 2, 4; a 1 x 1 x 4 box skinned
/// rigidly (bottom half to the shoulder, top half to the elbow); the elbow bends 90
/// degrees about X over one second.
fn arm() -> Asset {
    let skeleton = Skeleton::new(vec![
        Joint {
            name: "shoulder".into(),
            parent: None,
            rest_local: Transform::IDENTITY,
        },
        Joint {
            name: "elbow".into(),
            parent: Some(JointIndex(0)),
            rest_local: Transform::from_translation(Vec3::Z * 2.0),
        },
        Joint {
            name: "hand".into(),
            parent: Some(JointIndex(1)),
            rest_local: Transform::from_translation(Vec3::Z * 2.0),
        },
    ])
    .expect("a valid skeleton");
    let mut positions = Vec::new();
    let mut rows = Vec::new();
    let rings = 9;
    for r in 0..rings {
        let z = 4.0 * r as f32 / (rings - 1) as f32;
        for (x, y) in [(-0.5, -0.5), (0.5, -0.5), (0.5, 0.5), (-0.5, 0.5)] {
            positions.push(Vec3::new(x, y, z));
            rows.push([Influence {
                joint: u32::from(z > 2.0),
                weight: 1.0,
            }]);
        }
    }
    let mut triangles = Vec::new();
    for r in 0..rings - 1 {
        for k in 0..4u32 {
            let a = r * 4 + k;
            let b = r * 4 + (k + 1) % 4;
            triangles.push([a, b, b + 4]);
            triangles.push([a, b + 4, a + 4]);
        }
    }
    let n = positions.len();
    let inv_bind = skeleton
        .model_rest_matrices()
        .iter()
        .take(2)
        .map(|m| m.inverse())
        .collect();
    let bend = Track {
        target: TrackTarget::Rotation(JointIndex(1)),
        interpolation: Interpolation::Linear,
        times: vec![0.0, 1.0],
        values: [Quat::IDENTITY, Quat::from_rotation_x(1.2)]
            .iter()
            .flat_map(|q| q.to_array())
            .collect(),
    };
    let mut asset = Asset {
        name: "arm".into(),
        skeleton,
        meshes: vec![Mesh {
            name: "arm".into(),
            positions,
            triangles,
            source_vertex: (0..n as u32).collect(),
            ..Mesh::default()
        }],
        skins: vec![SkinBinding {
            method: Default::default(),
            mesh: MeshIndex(0),
            joints: vec![JointIndex(0), JointIndex(1)],
            inv_bind,
            influences: Influences::from_rows(rows),
        }],
        clips: vec![Clip {
            name: "bend".into(),
            tracks: vec![bend],
        }],
        ..Asset::default()
    };
    asset.frame.up_axis = UpAxis::Z;
    asset
}

/// A 5 x 5 flag off the arm's side at the top, pinned at the two points on the skin.
fn flag() -> Garment {
    let mut positions = Vec::new();
    for r in 0..5 {
        for c in 0..5 {
            positions.push(Vec3::new(-1.0 + 0.5 * c as f32, -2.5 + 0.5 * r as f32, 4.0));
        }
    }
    let mut triangles = Vec::new();
    for r in 0..4u32 {
        for c in 0..4u32 {
            let a = r * 5 + c;
            triangles.push([a, a + 5, a + 1]);
            triangles.push([a + 1, a + 5, a + 6]);
        }
    }
    Garment {
        positions,
        triangles,
        pinned: vec![21, 23],
    }
}

#[test]
fn pins_follow_the_skin_and_the_flag_falls() {
    let asset = arm();
    let mut warnings = Vec::new();
    let sim = simulate(
        &asset,
        &flag(),
        &ClothOptions::default(),
        &mut warnings,
        |_, _| {},
    )
    .expect("simulates");
    assert_eq!(sim.times.len(), 31, "the clip's 1 s at the default 30 fps");
    // The forearm the flag hangs beside, and the upper arm that carries it (`region`).
    assert_eq!(sim.capsules.len(), 2);
    // Pins sit exactly on their bound skin points in every frame.
    let rig = Rig::new(&asset).expect("compiles");
    let compiled = CompiledClip::new(&asset.clips[0], &asset.skeleton).expect("fits");
    let rest = Pose::rest(&asset.skeleton);
    let mut pose = rest.clone();
    let mut out = RigOutput::default();
    for (f, &t) in sim.times.iter().enumerate() {
        SampleJob {
            clip: &compiled,
            time: t,
            rest: &rest.local,
            output: &mut pose.local,
        }
        .run()
        .expect("samples");
        rig.evaluate(&pose, &mut out).expect("evaluates");
        for (p, sp) in &sim.pins {
            assert_eq!(sim.frame(f)[*p as usize], sp.eval(&out.positions[0]));
        }
    }
    let worst = sim.worst();
    assert!(worst.max_stretch < 0.1, "{worst:?}");
    assert!(worst.max_penetration <= 1e-5 * sim.diagonal, "{worst:?}");
    // Gravity is -Z here: the far edge fell.
    assert!(sim.frame(30)[0].z < 3.0, "{}", sim.frame(30)[0]);
}

#[test]
fn same_bytes_on_any_thread_count() {
    let asset = arm();
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("a pool");
        pool.install(|| {
            simulate(
                &asset,
                &flag(),
                // Looped, the elbow snaps back from 69 degrees to straight in one frame
                // and throws the flag past the speed limit: kept, as asked.
                &ClothOptions {
                    seconds: Some(2.5),
                    allow_unstable: true,
                    ..ClothOptions::default()
                },
                &mut Vec::new(),
                |_, _| {},
            )
            .expect("simulates")
        })
    };
    let a = run(1);
    let b = run(3);
    assert!(a.looped_poses.is_some());
    let bits = |s: &Simulation| -> Vec<u32> {
        s.positions
            .iter()
            .flat_map(|p| p.to_array().map(f32::to_bits))
            .collect()
    };
    assert_eq!(bits(&a), bits(&b));
}

#[test]
fn bad_input_gets_typed_errors() {
    let asset = arm();
    let mut g = flag();
    g.pinned.clear();
    assert!(matches!(
        simulate(
            &asset,
            &g,
            &ClothOptions::default(),
            &mut Vec::new(),
            |_, _| {}
        ),
        Err(ClothError::NoPins { .. })
    ));
    let mut g = flag();
    g.positions[3].x = f32::NAN;
    assert!(matches!(
        simulate(
            &asset,
            &g,
            &ClothOptions::default(),
            &mut Vec::new(),
            |_, _| {}
        ),
        Err(ClothError::NonFinite { .. })
    ));
    let opts = ClothOptions {
        damping: f32::NAN,
        ..ClothOptions::default()
    };
    assert!(matches!(
        simulate(&asset, &flag(), &opts, &mut Vec::new(), |_, _| {}),
        Err(ClothError::BadOption { .. })
    ));
    // A garment through the arm: a warning, and it ends outside.
    let mut g = flag();
    g.positions[7] = Vec3::new(0.0, 0.0, 3.0);
    let mut warnings = Vec::new();
    let sim = simulate(
        &asset,
        &g,
        &ClothOptions::default(),
        &mut warnings,
        |_, _| {},
    )
    .expect("simulates");
    assert!(
        warnings
            .iter()
            .any(|w| w.to_string().contains("start inside")),
        "{warnings:?}"
    );
    assert_eq!(sim.worst().body_inside, 0, "{:?}", sim.worst());
}

#[test]
fn a_looped_snap_is_unstable_with_the_frame_and_limit_as_data() {
    let asset = arm();
    // By default the jump back to the clip's start is a cut: the garment settles into it.
    let looped = ClothOptions {
        seconds: Some(2.5),
        ..ClothOptions::default()
    };
    let sim = simulate(&asset, &flag(), &looped, &mut Vec::new(), |_, _| {}).expect("settled");
    assert_eq!(sim.cuts.len(), 2, "{:?}", sim.cuts);
    assert_eq!(sim.cuts[0].frame, 30, "{:?}", sim.cuts);
    assert!(sim.stats.iter().all(|s| s.max_stretch < 0.1));
    // Without settling (no pre-roll) and with one substep a frame, it is thrown.
    let opts = ClothOptions {
        preroll: Some(0.0),
        substeps: Some(1),
        ..looped
    };
    let err = simulate(&asset, &flag(), &opts, &mut Vec::new(), |_, _| {}).unwrap_err();
    let ClothError::Unstable {
        frame,
        measure,
        value,
        limit,
        ..
    } = err
    else {
        panic!("{err:?}");
    };
    // The clip ends at 1 s (frame 30) and starts over: the flag flies just after.
    assert!((30..=40).contains(&frame), "{err}");
    assert!(value > limit, "{err}");
    assert_eq!(measure, Measure::Stretch, "{err}");
    // Kept on request, with a coded warning naming the same frame.
    let mut warnings = Vec::new();
    let kept = ClothOptions {
        allow_unstable: true,
        ..opts
    };
    simulate(&asset, &flag(), &kept, &mut warnings, |_, _| {}).expect("kept");
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    assert_eq!(warnings[0].code(), "W007");
    assert!(
        warnings[0]
            .to_string()
            .contains(&format!("first at frame {frame} ")),
        "{}",
        warnings[0]
    );
}

#[test]
fn baked_targets_reproduce_the_frames() {
    let mut asset = arm();
    let g = flag();
    let sim = simulate(
        &asset,
        &g,
        &ClothOptions::default(),
        &mut Vec::new(),
        |_, _| {},
    )
    .expect("simulates");
    let n = g.positions.len();
    let mesh = Mesh {
        name: "flag".into(),
        positions: g.positions.clone(),
        triangles: g.triangles.clone(),
        source_vertex: (0..n as u32).collect(),
        ..Mesh::default()
    };
    let bake = add_garment(&mut asset, mesh, &sim, None).expect("bakes");
    assert_eq!(bake.targets, sim.times.len());
    let m = &asset.meshes[bake.mesh];
    for f in [0, 7, 30] {
        for (i, p) in sim.frame(f).iter().enumerate() {
            let q = m.positions[i] + m.morph_targets[f].position_deltas[i];
            assert!((q - *p).length() < 1e-5, "{q} vs {p}");
        }
    }
    assert!(asset.validate().is_ok());
}

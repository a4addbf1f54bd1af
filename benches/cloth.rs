//! Criterion benchmark of the cloth solver (`rigport_deform::cloth`): particle-substeps per
//! second for square garments of 2,500 (50 x 50) and 10,000 (100 x 100) particles.
//!
//! `cargo bench --bench cloth`. The garment hangs from a bending box arm (the USTC course's
//! layout: 1 x 1 x 4, joints at z = 0, 2, 4, Z up), pinned along one edge over the arm's
//! top; 12 frames at 60 fps with 20 substeps each (1200 substeps per second, the default),
//! collisions with the arm's two capsules on. Throughput is reported as elements =
//! frames x substeps x particles. The solver is serial (Gauss-Seidel in a fixed order, for
//! bit-identical results on any thread count); only the per-frame body skinning runs on
//! rayon, and it is negligible here (36 body vertices).

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use rigport_deform::cloth::{simulate, ClothOptions, Garment};
use rigport_model::glam::{Quat, Vec3};
use rigport_model::{
    Asset, Clip, Influence, Influences, Interpolation, Joint, JointIndex, Mesh, MeshIndex,
    Skeleton, SkinBinding, Track, TrackTarget, Transform, UpAxis,
};

const FRAMES: usize = 12;
const FPS: f32 = 60.0;
const SUBSTEPS: u32 = 20;

/// The box arm bending 1.2 rad at the elbow over 0.2 s.
fn arm() -> Asset {
    let joint = |name: &str, parent: Option<u32>, z: f32| Joint {
        name: name.into(),
        parent: parent.map(JointIndex),
        rest_local: Transform::from_translation(Vec3::Z * z),
    };
    let skeleton = Skeleton::new(vec![
        joint("shoulder", None, 0.0),
        joint("elbow", Some(0), 2.0),
        joint("hand", Some(1), 2.0),
    ])
    .expect("a valid skeleton");
    let (mut positions, mut rows, mut triangles) = (Vec::new(), Vec::new(), Vec::new());
    let rings = 9u32;
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
    for r in 0..rings - 1 {
        for k in 0..4u32 {
            let (a, b) = (r * 4 + k, r * 4 + (k + 1) % 4);
            triangles.push([a, b, b + 4]);
            triangles.push([a, b + 4, a + 4]);
        }
    }
    let n = positions.len() as u32;
    let inv_bind = skeleton
        .model_rest_matrices()
        .iter()
        .take(2)
        .map(|m| m.inverse())
        .collect();
    let bend = Track {
        target: TrackTarget::Rotation(JointIndex(1)),
        interpolation: Interpolation::Linear,
        times: vec![0.0, FRAMES as f32 / FPS],
        values: [Quat::IDENTITY, Quat::from_rotation_x(1.2)]
            .iter()
            .flat_map(|q| q.to_array())
            .collect(),
    };
    let mut asset = Asset {
        skeleton,
        meshes: vec![Mesh {
            positions,
            triangles,
            source_vertex: (0..n).collect(),
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

/// An `n x n` sheet, 2 m square, level with the arm's top at z = 4 and off its -Y side,
/// pinned along its edge on the arm.
fn sheet(n: u32) -> Garment {
    let step = 2.0 / (n - 1) as f32;
    let mut positions = Vec::new();
    for r in 0..n {
        for c in 0..n {
            positions.push(Vec3::new(
                -1.0 + step * c as f32,
                -2.5 + step * r as f32,
                4.0,
            ));
        }
    }
    let mut triangles = Vec::new();
    for r in 0..n - 1 {
        for c in 0..n - 1 {
            let a = r * n + c;
            triangles.push([a, a + n, a + 1]);
            triangles.push([a + 1, a + n, a + n + 1]);
        }
    }
    // The last row (y = -0.5) where it lies over the arm (|x| <= 0.5).
    let pinned = (0..n)
        .map(|c| (n - 1) * n + c)
        .filter(|&i| positions[i as usize].x.abs() <= 0.5)
        .collect();
    Garment {
        positions,
        triangles,
        pinned,
    }
}

fn bench(c: &mut Criterion) {
    let asset = arm();
    let mut group = c.benchmark_group("cloth");
    group.sample_size(10);
    for n in [50u32, 100] {
        let garment = sheet(n);
        let particles = garment.positions.len();
        // No pre-roll: the figure is the solver's over the clip's frames, comparable with
        // the ones recorded before the pre-roll existed (BENCHMARKS.md).
        let opts = ClothOptions {
            fps: Some(FPS),
            substeps: Some(SUBSTEPS),
            preroll: Some(0.0),
            ..ClothOptions::default()
        };
        // Frames after the first, each SUBSTEPS substeps.
        let steps = (FRAMES as u64) * u64::from(SUBSTEPS) * particles as u64;
        group.throughput(Throughput::Elements(steps));
        group.bench_with_input(
            BenchmarkId::new("particle_substeps", particles),
            &garment,
            |b, g| {
                b.iter(|| {
                    let sim =
                        simulate(&asset, g, &opts, &mut Vec::new(), |_, _| {}).expect("simulates");
                    assert_eq!(sim.times.len(), FRAMES + 1);
                    black_box(sim.positions.len())
                });
            },
        );
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);

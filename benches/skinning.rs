//! Criterion benchmarks of LBS and DQS skinning throughput (vertices x frames per second).
//!
//! `cargo bench --bench skinning`. Two inputs:
//! - `skinning_1Mx4`: 1,000,000 vertices with 4 influences each (seeded random joints among
//!   64 and random weights summing to 1), random rigid + slightly scaled skinning matrices
//!   (scale 1 ± 5% per axis, so UsdSkel's DQS takes its scale/shear path);
//! - `skinning_model1`: the largest skinned rig of the shared corpus, the Pinocchio rig
//!   `human_model1` (13,336 vertices, 18 joints, up to 13 non-zero weights per vertex), in
//!   seeded random poses; skipped with a message when the corpus is absent.
//!
//! Each runs LBS and DQS, on a rayon pool of 1 and of 2 threads, as
//! `job_f1` (the one-frame [`LbsJob`] / [`DqsJob`] on the model's CSR influences),
//! `packed_f1` (one frame through [`par_skin_frames`] on [`PackedInfluences`]) and
//! `packed_f8` (an 8-frame bake through [`par_skin_frames`]). Throughput is reported as
//! elements = vertices x frames.
//!
//! The arrays are also written, in the `rigport eval` dump layout, to
//! `target/skinning-bench/<input>/` (plus rigport's first-frame positions per method), so
//! that `tools/bench_skinning.py` can time `UsdSkel.SkinPoints` on the same arrays and
//! print the ratios against the estimates criterion leaves in `target/criterion/`.

use std::hint::black_box;
use std::path::{Path, PathBuf};

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use rigport_eval::dqs::{DqsJob, DqsPalette};
use rigport_eval::skinning::{par_skin_frames, rayon, PackedInfluences};
use rigport_eval::{LbsJob, Pose, Rig, RigOutput};
use rigport_import::pinocchio;
use rigport_model::glam::{EulerRot, Mat4, Quat, Vec3};
use rigport_model::SkinningMethod;
use rigport_model::{Influence, Influences};

/// Frames of the bake variant.
const FRAMES: usize = 8;

/// xorshift64*: a tiny seeded generator, so the inputs are the same on every run.
struct Rng(u64);

impl Rng {
    fn next_u64(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    /// Uniform in [0, 1).
    fn unit(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }
    fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.unit()
    }
}

/// One benchmark input: a mesh's influences and `FRAMES` palettes.
struct Input {
    name: &'static str,
    rest: Vec<Vec3>,
    influences: Influences,
    /// `FRAMES x joints`, frame-major.
    frame_mats: Vec<Mat4>,
    joints: usize,
}

fn random_input(vertices: usize, joints: usize, per_vertex: usize) -> Input {
    let mut rng = Rng(0x5EED_1234_ABCD_0001);
    let rest: Vec<Vec3> = (0..vertices)
        .map(|_| {
            Vec3::new(
                rng.range(-1.0, 1.0),
                rng.range(0.0, 2.0),
                rng.range(-0.5, 0.5),
            )
        })
        .collect();
    let influences = Influences::from_rows((0..vertices).map(|_| {
        let w: Vec<f32> = (0..per_vertex).map(|_| rng.range(0.05, 1.0)).collect();
        let sum: f32 = w.iter().sum();
        w.into_iter()
            .map(|w| Influence {
                joint: (rng.next_u64() % joints as u64) as u32,
                weight: w / sum,
            })
            .collect::<Vec<_>>()
    }));
    let frame_mats = (0..FRAMES * joints)
        .map(|_| {
            let rotation = Quat::from_euler(
                EulerRot::XYZ,
                rng.range(-3.1, 3.1),
                rng.range(-1.5, 1.5),
                rng.range(-3.1, 3.1),
            );
            let scale = Vec3::new(
                rng.range(0.95, 1.05),
                rng.range(0.95, 1.05),
                rng.range(0.95, 1.05),
            );
            let t = Vec3::new(
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
            );
            Mat4::from_scale_rotation_translation(scale, rotation, t)
        })
        .collect();
    Input {
        name: "skinning_1Mx4",
        rest,
        influences,
        frame_mats,
        joints,
    }
}

/// The Pinocchio rig `human_model1` in `FRAMES` seeded random poses (each joint rotated
/// by up to ±0.4 rad about each axis from its rest orientation).
fn model1_input() -> Option<Input> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(
        "../shared/corpus/1_pinocchio/berkeley_cs184__severus-snape_mobius-ants/human_model1",
    );
    let files = ["Model1.obj", "skeleton.out", "attachment.out"].map(|f| dir.join(f));
    if !files.iter().all(|f| f.exists()) {
        eprintln!("SKIPPED: corpus rig {} is absent", dir.display());
        return None;
    }
    let asset = pinocchio::import(&files[0], &files[1], &files[2])
        .expect("Model1 imports")
        .asset;
    let skin = asset.skins.first().expect("Model1 has a skin");
    let rig = Rig::new(&asset).expect("Model1 compiles");
    let mut rng = Rng(0x5EED_0000_0000_0002);
    let mut out = RigOutput::default();
    let mut frame_mats = Vec::new();
    for _ in 0..FRAMES {
        let mut pose = Pose::rest(&asset.skeleton);
        for l in pose.local.iter_mut() {
            let delta = Quat::from_euler(
                EulerRot::XYZ,
                rng.range(-0.4, 0.4),
                rng.range(-0.4, 0.4),
                rng.range(-0.4, 0.4),
            );
            l.rotation = (l.rotation * delta).normalize();
        }
        rig.evaluate(&pose, &mut out).expect("evaluates");
        frame_mats.extend_from_slice(&out.skin_matrices[0]);
    }
    Some(Input {
        name: "skinning_model1",
        rest: asset.meshes[skin.mesh.get()].positions.clone(),
        influences: skin.influences.clone(),
        frame_mats,
        joints: skin.joints.len(),
    })
}

/// Writes a little-endian `.npy` (numpy `lib/format.py`, version 1.0).
fn write_npy(path: &Path, descr: &str, shape: &[usize], data: &[u8]) {
    let dims: Vec<String> = shape.iter().map(usize::to_string).collect();
    let mut header = format!(
        "{{'descr': '{descr}', 'fortran_order': False, 'shape': ({},), }}",
        dims.join(", ")
    );
    while (10 + header.len() + 1) % 64 != 0 {
        header.push(' ');
    }
    header.push('\n');
    let mut bytes = b"\x93NUMPY\x01\x00".to_vec();
    bytes.extend_from_slice(&(header.len() as u16).to_le_bytes());
    bytes.extend_from_slice(header.as_bytes());
    bytes.extend_from_slice(data);
    std::fs::write(path, bytes).expect("writes the benchmark arrays");
}

fn f32_bytes(v: impl IntoIterator<Item = f32>) -> Vec<u8> {
    v.into_iter().flat_map(f32::to_le_bytes).collect()
}

/// The input in the dump layout, for `tools/bench_skinning.py`.
fn write_arrays(input: &Input, packed: &PackedInfluences) {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("target/skinning-bench")
        .join(input.name);
    std::fs::create_dir_all(&dir).expect("creates target/skinning-bench");
    let v = input.rest.len();
    let k = input.influences.max_per_vertex();
    let mut joints = Vec::with_capacity(v * k);
    let mut weights = Vec::with_capacity(v * k);
    for row in input.influences.rows() {
        for slot in 0..k {
            let inf = row.get(slot).copied().unwrap_or(Influence {
                joint: 0,
                weight: 0.0,
            });
            joints.extend_from_slice(&(inf.joint as i32).to_le_bytes());
            weights.push(inf.weight);
        }
    }
    write_npy(
        &dir.join("rest_positions.npy"),
        "<f4",
        &[v, 3],
        &f32_bytes(input.rest.iter().flat_map(|p| p.to_array())),
    );
    write_npy(&dir.join("influence_joints.npy"), "<i4", &[v, k], &joints);
    write_npy(
        &dir.join("influence_weights.npy"),
        "<f4",
        &[v, k],
        &f32_bytes(weights),
    );
    // Row-major storage of the column-vector matrices (numpy `M @ p`).
    let mats = f32_bytes(
        input
            .frame_mats
            .iter()
            .flat_map(|m| m.transpose().to_cols_array()),
    );
    write_npy(
        &dir.join("skin_matrices.npy"),
        "<f4",
        &[FRAMES, input.joints, 4, 4],
        &mats,
    );
    for (method, name) in [(SkinningMethod::Lbs, "lbs"), (SkinningMethod::Dqs, "dqs")] {
        let mut out = vec![Vec3::ZERO; v];
        par_skin_frames(
            method,
            packed,
            &input.rest,
            &input.frame_mats[..input.joints],
            &mut out,
        )
        .expect("skins");
        write_npy(
            &dir.join(format!("positions_{name}.npy")),
            "<f4",
            &[v, 3],
            &f32_bytes(out.iter().flat_map(|p| p.to_array())),
        );
    }
}

fn bench_input(c: &mut Criterion, input: &Input, with_jobs: bool) {
    let packed = PackedInfluences::new(&input.influences);
    write_arrays(input, &packed);
    let v = input.rest.len();
    let j = input.joints;
    let mut group = c.benchmark_group(input.name);
    group.sample_size(10);
    group.warm_up_time(std::time::Duration::from_secs(1));
    group.measurement_time(std::time::Duration::from_secs(3));
    let mut out = vec![Vec3::ZERO; v * FRAMES];
    let mut palette = DqsPalette::new(j, 1);
    for threads in [1usize, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("a rayon pool");
        let id = format!("{threads}t");
        for (method, name) in [(SkinningMethod::Lbs, "lbs"), (SkinningMethod::Dqs, "dqs")] {
            if with_jobs {
                group.throughput(Throughput::Elements(v as u64));
                group.bench_function(BenchmarkId::new(format!("{name}_job_f1"), &id), |b| {
                    b.iter(|| {
                        pool.install(|| match method {
                            SkinningMethod::Lbs => LbsJob {
                                skin_matrices: &input.frame_mats[..j],
                                influences: &input.influences,
                                rest_positions: black_box(&input.rest),
                                rest_normals: None,
                                out_positions: &mut out[..v],
                                out_normals: None,
                            }
                            .par_run(),
                            SkinningMethod::Dqs => DqsJob {
                                skin_matrices: &input.frame_mats[..j],
                                influences: &input.influences,
                                rest_positions: black_box(&input.rest),
                                rest_normals: None,
                                out_positions: &mut out[..v],
                                out_normals: None,
                                palette: &mut palette,
                            }
                            .par_run(),
                        })
                        .expect("skins")
                    })
                });
            }
            for frames in [1, FRAMES] {
                group.throughput(Throughput::Elements((v * frames) as u64));
                group.bench_function(
                    BenchmarkId::new(format!("{name}_packed_f{frames}"), &id),
                    |b| {
                        b.iter(|| {
                            pool.install(|| {
                                par_skin_frames(
                                    method,
                                    &packed,
                                    black_box(&input.rest),
                                    &input.frame_mats[..j * frames],
                                    &mut out[..v * frames],
                                )
                            })
                            .expect("skins")
                        })
                    },
                );
            }
        }
    }
    group.finish();
}

fn skinning(c: &mut Criterion) {
    let input = random_input(1_000_000, 64, 4);
    bench_input(c, &input, true);
    drop(input);
    if let Some(input) = model1_input() {
        bench_input(c, &input, false);
    }
}

criterion_group!(benches, skinning);
criterion_main!(benches);

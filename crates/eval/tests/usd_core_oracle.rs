//! The usd-core oracle for skinning: Pixar's own testUsdSkelBakeSkinning case (corpus),
//! exported by usd-core (`tools/check_skinning.py`) and skinned by rigport with LBS and DQS,
//! compared point by point with what UsdSkel bakes. It runs Python with usd-core, so it is
//! an integration test, not a unit test of the skinning module.

#![allow(clippy::unwrap_used)]

use rigport_eval::dqs::{DqsJob, DqsPalette};
use rigport_model::glam::{Mat4, Vec3};
use rigport_model::{Influence, Influences};

/// Sparse influences from `(joint, weight)` rows.
fn influences(rows: &[Vec<(usize, f64)>]) -> Influences {
    Influences::from_rows(rows.iter().map(|r| {
        r.iter()
            .map(|&(joint, weight)| Influence {
                joint: joint as u32,
                weight: weight as f32,
            })
            .collect::<Vec<_>>()
    }))
}

/// A `<f4`/`<i4` `.npy` array ([`rigport_testkit::npy::read_npy`]) as `f32` values (the
/// `f64` it reads them into holds each exactly).
fn read_npy(path: &std::path::Path) -> (Vec<usize>, Vec<f32>) {
    let array = rigport_testkit::npy::read_npy(path);
    (
        array.shape,
        array.numbers.iter().map(|&v| v as f32).collect(),
    )
}

/// Writes a `<f4` `.npy` array.
fn write_npy(path: &std::path::Path, shape: &[usize], data: &[f32]) {
    let dims: Vec<String> = shape.iter().map(|d| d.to_string()).collect();
    let mut header = format!(
        "{{'descr': '<f4', 'fortran_order': False, 'shape': ({},), }}",
        dims.join(", ")
    );
    while (10 + header.len() + 1) % 64 != 0 {
        header.push(' ');
    }
    header.push('\n');
    let mut bytes = b"\x93NUMPY\x01\x00".to_vec();
    bytes.extend_from_slice(&(header.len() as u16).to_le_bytes());
    bytes.extend_from_slice(header.as_bytes());
    bytes.extend(data.iter().flat_map(|x| x.to_le_bytes()));
    std::fs::write(path, bytes).unwrap();
}

/// Pixar's `testUsdSkelBakeSkinning` (LBS and DQS inputs with baked baselines):
/// `tools/check_skinning.py --export-usd` reads the inputs with usd-core, rigport skins
/// them, and the result must match Pixar's baseline and `UsdSkel.SkinPoints` within
/// 1e-5 of the bounding-box diagonal (`check_skinning.py`'s default tolerance).
#[test]
fn pixar_bake_skinning_baselines() {
    let root = rigport_testkit::repo();
    // The one corpus rule (rigport-testkit): skip when absent, fail in CI.
    let Some(case) = rigport_testkit::corpus(
        "6_usd/openusd_usdskel__PixarAnimationStudios/testUsdSkelBakeSkinning",
    ) else {
        return;
    };
    let python = std::env::var_os("RIGPORT_PYTHON")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| root.join("tools/.venv/bin/python"));
    let what = format!(
        "Python with usd-core at {} (run tools/setup.sh)",
        python.display()
    );
    if rigport_testkit::require(&what, python.exists().then_some(())).is_none() {
        return;
    }
    let checker = root.join("tools/check_skinning.py");
    for (name, method) in [
        ("lbs", rigport_model::SkinningMethod::Lbs),
        ("dqs", rigport_model::SkinningMethod::Dqs),
    ] {
        let dir = std::env::temp_dir().join(format!("rigport-pixar-{}-{name}", std::process::id()));
        let export = std::process::Command::new(&python)
            .arg(&checker)
            .arg("--export-usd")
            .arg(case.join(format!("{name}.usda")))
            .arg("--baseline")
            .arg(case.join(format!("baseline/{name}.baked.usda")))
            .arg("--out")
            .arg(&dir)
            .output()
            .unwrap();
        assert!(
            export.status.success(),
            "export of {name}.usda failed: {}{}",
            String::from_utf8_lossy(&export.stdout),
            String::from_utf8_lossy(&export.stderr)
        );
        let (rshape, rest) = read_npy(&dir.join("rest_positions.npy"));
        let (pshape, baseline) = read_npy(&dir.join("positions.npy"));
        let (mshape, mats) = read_npy(&dir.join("skin_matrices.npy"));
        let (ishape, joints) = read_npy(&dir.join("influence_joints.npy"));
        let (_, weights) = read_npy(&dir.join("influence_weights.npy"));
        let (v, f, j, k) = (rshape[0], pshape[0], mshape[1], ishape[1]);
        let rest: Vec<Vec3> = rest.chunks_exact(3).map(Vec3::from_slice).collect();
        // Row-major storage of column-vector matrices: glam's column-major reader gives
        // the transpose.
        let mats: Vec<Mat4> = mats
            .chunks_exact(16)
            .map(|m| Mat4::from_cols_slice(m).transpose())
            .collect();
        let rows: Vec<Vec<(usize, f64)>> = (0..v)
            .map(|i| {
                (0..k)
                    .map(|c| (joints[i * k + c] as usize, weights[i * k + c] as f64))
                    .collect()
            })
            .collect();
        let infl = influences(&rows);
        let packed = rigport_eval::skinning::PackedInfluences::new(&infl);
        let mut out = vec![Vec3::ZERO; f * v];
        rigport_eval::skinning::skin_frames(method, &packed, &rest, &mats, &mut out).unwrap();
        // The one-frame jobs on the CSR rows agree with the packed path.
        let mut palette = DqsPalette::new(j, 1);
        for frame in 0..f {
            let mut one = vec![Vec3::ZERO; v];
            let skin = &mats[frame * j..(frame + 1) * j];
            match method {
                rigport_model::SkinningMethod::Lbs => rigport_eval::LbsJob {
                    skin_matrices: skin,
                    influences: &infl,
                    rest_positions: &rest,
                    rest_normals: None,
                    out_positions: &mut one,
                    out_normals: None,
                }
                .run()
                .unwrap(),
                rigport_model::SkinningMethod::Dqs => DqsJob {
                    skin_matrices: skin,
                    influences: &infl,
                    rest_positions: &rest,
                    rest_normals: None,
                    out_positions: &mut one,
                    out_normals: None,
                    palette: &mut palette,
                }
                .run()
                .unwrap(),
            }
            for (a, b) in one.iter().zip(&out[frame * v..(frame + 1) * v]) {
                assert!(a.abs_diff_eq(*b, 1e-6), "{name} frame {frame}: {a} vs {b}");
            }
        }
        let mut worst = 0.0f32;
        for frame in 0..f {
            let base: Vec<Vec3> = baseline[frame * v * 3..(frame + 1) * v * 3]
                .chunks_exact(3)
                .map(Vec3::from_slice)
                .collect();
            let (lo, hi) = base.iter().fold((Vec3::MAX, Vec3::MIN), |(lo, hi), p| {
                (lo.min(*p), hi.max(*p))
            });
            let diag = (hi - lo).length();
            for (a, b) in out[frame * v..(frame + 1) * v].iter().zip(&base) {
                worst = worst.max(a.distance(*b) / diag);
            }
        }
        eprintln!("{name}: {f} frames x {v} points, max deviation from Pixar's baseline {worst:.2e} of the diagonal");
        assert!(worst <= 1e-5, "{name}: {worst}");
        let flat: Vec<f32> = out.iter().flat_map(|p| p.to_array()).collect();
        write_npy(&dir.join("positions.npy"), &pshape, &flat);
        let check = std::process::Command::new(&python)
            .arg(&checker)
            .arg(&dir)
            .arg("--quiet")
            .output()
            .unwrap();
        let report = String::from_utf8_lossy(&check.stdout);
        eprintln!("{report}");
        assert_eq!(
            check.status.code(),
            Some(0),
            "{name}: {report}{}",
            String::from_utf8_lossy(&check.stderr)
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}

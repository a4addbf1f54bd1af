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

/// A little-endian `f4`/`i4` `.npy` array (numpy's `lib/format.py`, version 1.0).
fn read_npy(path: &std::path::Path) -> (Vec<usize>, Vec<f32>) {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    assert_eq!(&bytes[..6], b"\x93NUMPY", "{}", path.display());
    let (len_at, len_size) = if bytes[6] == 1 { (8, 2) } else { (8, 4) };
    let mut hl = [0u8; 4];
    hl[..len_size].copy_from_slice(&bytes[len_at..len_at + len_size]);
    let header_end = len_at + len_size + u32::from_le_bytes(hl) as usize;
    let header = std::str::from_utf8(&bytes[len_at + len_size..header_end]).unwrap();
    assert!(header.contains("'fortran_order': False"), "{header}");
    let shape_txt = header
        .split("'shape': (")
        .nth(1)
        .unwrap()
        .split(')')
        .next()
        .unwrap();
    let shape: Vec<usize> = shape_txt
        .split(',')
        .filter(|s| !s.trim().is_empty())
        .map(|s| s.trim().parse().unwrap())
        .collect();
    let data = &bytes[header_end..];
    let values = data.chunks_exact(4).map(|c| {
        let b = [c[0], c[1], c[2], c[3]];
        if header.contains("'<f4'") {
            f32::from_le_bytes(b)
        } else if header.contains("'<i4'") {
            i32::from_le_bytes(b) as f32
        } else {
            panic!("dtype in {header}")
        }
    });
    (shape, values.collect())
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
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let case = root.join(
        "../shared/corpus/6_usd/openusd_usdskel__PixarAnimationStudios/testUsdSkelBakeSkinning",
    );
    let ci = std::env::var("CI").is_ok_and(|v| !v.is_empty());
    if !case.is_dir() {
        assert!(
            !ci,
            "corpus case {} is absent and CI is set",
            case.display()
        );
        eprintln!("SKIPPED: corpus case {} is absent", case.display());
        return;
    }
    let python = std::env::var_os("RIGPORT_PYTHON")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| root.join("tools/.venv/bin/python"));
    if !python.exists() {
        assert!(
            !ci,
            "no Python with usd-core at {} and CI is set",
            python.display()
        );
        eprintln!(
            "SKIPPED: no Python with usd-core at {} (run tools/setup.sh)",
            python.display()
        );
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

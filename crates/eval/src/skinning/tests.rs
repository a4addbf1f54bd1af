use glam::{Mat4, Vec3};
use rigport_model::{Influence, Influences, SkinningMethod};

use super::common::GRAIN;
use super::dqs::DqsPalette;
use super::*;
use crate::EvalError;
use glam::Quat;
use proptest::prelude::*;

/// Scalar reference: blends the transformed points instead of the matrices.
fn naive(skin: &[Mat4], infl: &Influences, rest: &[Vec3]) -> Vec<Vec3> {
    rest.iter()
        .enumerate()
        .map(|(v, p)| {
            let row = infl.vertex(v);
            if row.iter().all(|i| i.weight == 0.0) {
                return *p;
            }
            row.iter()
                .map(|i| skin[i.joint as usize].transform_point3(*p) * i.weight)
                .sum()
        })
        .collect()
}

fn matrix() -> impl Strategy<Value = Mat4> {
    (
        prop::array::uniform3(-3.0f32..3.0),
        prop::array::uniform3(-3.2f32..3.2),
        prop::array::uniform3(0.8f32..1.2),
    )
        .prop_map(|(t, r, s)| {
            Mat4::from_scale_rotation_translation(
                Vec3::from(s),
                Quat::from_euler(glam::EulerRot::XYZ, r[0], r[1], r[2]),
                Vec3::from(t),
            )
        })
}

fn rows(max_len: usize) -> impl Strategy<Value = Vec<Vec<(u32, f32)>>> {
    prop::collection::vec(
        prop::collection::vec(
            (0u32..16, prop_oneof![Just(0.0f32), 0.01f32..1.0]),
            0..max_len,
        ),
        1..40,
    )
}

fn make_influences(rows: &[Vec<(u32, f32)>], n: u32) -> Influences {
    Influences::from_rows(rows.iter().map(|r| {
        let sum: f32 = r.iter().map(|x| x.1).sum::<f32>().max(1e-6);
        r.iter()
            .map(move |&(j, w)| Influence {
                joint: j % n,
                weight: w / sum,
            })
            .collect::<Vec<_>>()
    }))
}

fn lbs(skin: &[Mat4], infl: &Influences, rest: &[Vec3]) -> Vec<Vec3> {
    let mut out = vec![Vec3::ZERO; rest.len()];
    LbsJob {
        skin_matrices: skin,
        influences: infl,
        rest_positions: rest,
        rest_normals: None,
        out_positions: &mut out,
        out_normals: None,
    }
    .run()
    .unwrap();
    out
}

proptest! {
    #[test]
    fn matches_naive_and_single_influence_is_exact(
        skin in prop::collection::vec(matrix(), 1..8),
        rows in rows(5),
        pts in prop::collection::vec(prop::array::uniform3(-2.0f32..2.0), 40),
    ) {
        let n = skin.len() as u32;
        let infl = make_influences(&rows, n);
        let rest: Vec<Vec3> = pts[..rows.len()].iter().map(|p| Vec3::from(*p)).collect();
        let out = lbs(&skin, &infl, &rest);
        for (v, (a, b)) in out.iter().zip(naive(&skin, &infl, &rest)).enumerate() {
            prop_assert!(a.abs_diff_eq(b, 1e-4), "vertex {v}: {a} vs {b}");
        }
        // Single influence: exactly that joint's matrix.
        let single = Influences::from_rows(rest.iter().enumerate().map(|(v, _)| [Influence { joint: v as u32 % n, weight: 1.0 }]));
        let out = lbs(&skin, &single, &rest);
        for (v, p) in rest.iter().enumerate() {
            let expect = skin[v % n as usize].transform_point3(*p);
            prop_assert!(out[v].abs_diff_eq(expect, 1e-5), "vertex {v}: {} vs {expect}", out[v]);
        }
    }

    #[test]
    fn packed_frames_match_the_row_job(
        skin in prop::collection::vec(matrix(), 16 * 3),
        rows in rows(11),
        pts in prop::collection::vec(prop::array::uniform3(-2.0f32..2.0), 40),
        frames in 1usize..4,
    ) {
        // 16 joints per frame, up to 3 frames; rows up to 10 long exercise the fixed
        // widths and the sparse layout.
        let infl = make_influences(&rows, 16);
        let rest: Vec<Vec3> = pts[..rows.len()].iter().map(|p| Vec3::from(*p)).collect();
        let packed = PackedInfluences::new(&infl);
        let mats = &skin[..16 * frames];
        let mut out = vec![Vec3::ZERO; rest.len() * frames];
        skin_frames(SkinningMethod::Lbs, &packed, &rest, mats, &mut out).unwrap();
        let mut par = vec![Vec3::ZERO; rest.len() * frames];
        par_skin_frames(SkinningMethod::Lbs, &packed, &rest, mats, &mut par).unwrap();
        prop_assert_eq!(&out, &par);
        for f in 0..frames {
            let expect = lbs(&mats[16 * f..16 * (f + 1)], &infl, &rest);
            for (v, (a, b)) in out[f * rest.len()..(f + 1) * rest.len()].iter().zip(&expect).enumerate() {
                prop_assert!(a.abs_diff_eq(*b, 1e-4), "frame {f} vertex {v}: {a} vs {b}");
            }
        }
    }
}

#[test]
fn packing_drops_zeros_and_puts_the_pivot_first() {
    let inf = |joint, weight| Influence { joint, weight };
    let infl = Influences::from_rows([
        vec![inf(3, 0.2), inf(5, 0.0), inf(1, 0.5), inf(2, 0.3)],
        vec![],
        vec![inf(7, 0.5), inf(6, 0.5)],
    ]);
    let p = PackedInfluences::new(&infl);
    assert_eq!(p.width(), Some(3));
    assert_eq!(p.max_per_vertex(), 3);
    assert_eq!(p.joint_bound(), 8);
    assert_eq!(p.joints, [1, 3, 2, 0, 0, 0, 7, 6, 7]);
    assert_eq!(p.weights, [0.5, 0.2, 0.3, 0.0, 0.0, 0.0, 0.5, 0.5, 0.0]);
    assert_eq!(p.unweighted, [1]);
    let wide = Influences::from_rows([(0..9).map(|j| inf(j, 0.1))]);
    assert_eq!(PackedInfluences::new(&wide).width(), None);
    assert_eq!(
        PackedInfluences::new(&Influences::from_rows([[inf(0, 0.0)]])).width(),
        None
    );
}

#[test]
fn large_mesh_parallel_equals_serial_and_keeps_unweighted_at_rest() {
    let skin: Vec<Mat4> = (0..24)
        .map(|j| {
            Mat4::from_rotation_translation(
                Quat::from_rotation_z(j as f32 * 0.3),
                Vec3::X * j as f32,
            )
        })
        .collect();
    let n = 2 * GRAIN + 1001;
    let infl = Influences::from_rows((0..n).map(|v| {
        if v % 97 == 0 {
            vec![]
        } else {
            vec![
                Influence {
                    joint: (v % 12) as u32,
                    weight: 0.6,
                },
                Influence {
                    joint: (v % 7) as u32,
                    weight: 0.4,
                },
            ]
        }
    }));
    let rest: Vec<Vec3> = (0..n)
        .map(|v| Vec3::new(1.0, v as f32 * 1e-3, 0.5))
        .collect();
    let packed = PackedInfluences::new(&infl);
    for method in [SkinningMethod::Lbs, SkinningMethod::Dqs] {
        let mut a = vec![Vec3::ZERO; 2 * n];
        let mut b = vec![Vec3::ZERO; 2 * n];
        skin_frames(method, &packed, &rest, &skin, &mut a).unwrap();
        par_skin_frames(method, &packed, &rest, &skin, &mut b).unwrap();
        assert_eq!(a, b, "{method:?}");
        assert_eq!(a[97], rest[97]);
        assert_eq!(a[n + 97 * 5], rest[97 * 5]);
    }
    let mut a = vec![Vec3::ZERO; n];
    let mut b = vec![Vec3::ZERO; n];
    LbsJob {
        skin_matrices: &skin,
        influences: &infl,
        rest_positions: &rest,
        rest_normals: None,
        out_positions: &mut a,
        out_normals: None,
    }
    .run()
    .unwrap();
    LbsJob {
        skin_matrices: &skin,
        influences: &infl,
        rest_positions: &rest,
        rest_normals: None,
        out_positions: &mut b,
        out_normals: None,
    }
    .par_run()
    .unwrap();
    assert_eq!(a, b);
}

#[test]
fn frames_job_checks_sizes() {
    let infl = Influences::from_rows([
        [Influence {
            joint: 2,
            weight: 1.0,
        }],
        [Influence {
            joint: 0,
            weight: 1.0,
        }],
    ]);
    let packed = PackedInfluences::new(&infl);
    let rest = [Vec3::ZERO; 2];
    let mats = [Mat4::IDENTITY; 4];
    let mut out = [Vec3::ZERO; 5];
    assert!(matches!(
        skin_frames(SkinningMethod::Lbs, &packed, &rest, &mats, &mut out),
        Err(EvalError::Length { .. })
    ));
    let mut out = [Vec3::ZERO; 4];
    // Two frames of two joints: joint 2 is out of range.
    assert_eq!(
        skin_frames(SkinningMethod::Lbs, &packed, &rest, &mats, &mut out),
        Err(EvalError::Index {
            what: "influences",
            index: 2
        })
    );
    let mut palette = DqsPalette::new(2, 1);
    let mut job = SkinFramesJob {
        method: SkinningMethod::Dqs,
        influences: &packed,
        rest_positions: &rest,
        frame_skin_matrices: &mats[..3],
        out_positions: &mut out[..2],
        palette: &mut palette,
    };
    assert!(matches!(
        job.run(),
        Err(EvalError::Length {
            what: "DqsPalette joints",
            ..
        })
    ));
}

#[test]
fn normals_use_the_cofactor() {
    let m = Mat4::from_scale(Vec3::new(2.0, 1.0, 1.0)) * Mat4::from_rotation_z(0.3);
    let infl = Influences::from_rows([
        vec![Influence {
            joint: 0,
            weight: 1.0,
        }],
        vec![],
    ]);
    let rest_n = [Vec3::new(1.0, 1.0, 0.0).normalize(), Vec3::Y];
    let mut out = [Vec3::ZERO; 2];
    let mut out_n = [Vec3::ZERO; 2];
    LbsJob {
        skin_matrices: &[m],
        influences: &infl,
        rest_positions: &[Vec3::ONE, Vec3::ONE],
        rest_normals: Some(&rest_n),
        out_positions: &mut out,
        out_normals: Some(&mut out_n),
    }
    .run()
    .unwrap();
    let expect = (glam::Mat3::from_mat4(m).inverse().transpose() * rest_n[0]).normalize();
    assert!(
        out_n[0].abs_diff_eq(expect, 1e-6),
        "{} vs {expect}",
        out_n[0]
    );
    assert_eq!(out_n[1], Vec3::Y);
    assert_eq!(out[1], Vec3::ONE);
}

#[test]
fn rejects_bad_joint_index() {
    let infl = Influences::from_rows([[Influence {
        joint: 3,
        weight: 1.0,
    }]]);
    let mut out = [Vec3::ZERO];
    let job = LbsJob {
        skin_matrices: &[Mat4::IDENTITY],
        influences: &infl,
        rest_positions: &[Vec3::ZERO],
        rest_normals: None,
        out_positions: &mut out,
        out_normals: None,
    };
    assert_eq!(
        job.validate(),
        Err(EvalError::Index {
            what: "influences",
            index: 3
        })
    );
}

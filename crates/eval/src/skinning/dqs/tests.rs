use super::decompose::decompose_f64;
use super::*;
use glam::{DVec3, Mat3, Quat};
use proptest::prelude::*;

/// Naive scalar reference in `f64`, written from the UsdSkel algorithm with the joint
/// decomposition given (not computed): rotation, translation and scale/shear per joint.
fn naive_dqs(joints: &[(DQuat, DVec3, DMat3)], row: &[(usize, f64)], p: DVec3) -> DVec3 {
    let eps = 1e-6;
    let has_scale = joints.iter().any(|(_, _, s)| {
        (*s - DMat3::IDENTITY)
            .abs()
            .to_cols_array()
            .iter()
            .any(|e| *e > eps)
    });
    let mut pivot = 0;
    for (k, (_, w)) in row.iter().enumerate() {
        if row[pivot].1 < *w {
            pivot = k;
        }
    }
    let qp = joints[row[pivot].0].0;
    let (mut real, mut dual) = ([0.0f64; 4], [0.0f64; 4]);
    let mut scaled = DVec3::ZERO;
    for &(j, w) in row {
        let (q, t, s) = joints[j];
        if has_scale {
            scaled += (s * p) * w;
        }
        let d = DQuat::from_xyzw(t.x, t.y, t.z, 0.0) * q * 0.5;
        let w = if q.dot(qp) < 0.0 { -w } else { w };
        for (acc, x) in real.iter_mut().zip(q.to_array()) {
            *acc += x * w;
        }
        for (acc, x) in dual.iter_mut().zip(d.to_array()) {
            *acc += x * w;
        }
    }
    if !has_scale {
        scaled = p;
    }
    let r = DQuat::from_array(real);
    let d = DQuat::from_array(dual);
    let len = r.length();
    let (r, d) = (r * (1.0 / len), d * (1.0 / len));
    let t = d * r.conjugate() * 2.0;
    r * scaled + DVec3::new(t.x, t.y, t.z)
}

fn mat4(q: DQuat, t: DVec3, s: DMat3) -> Mat4 {
    let a = DMat3::from_quat(q) * s;
    Mat4::from_cols(
        a.x_axis.as_vec3().extend(0.0),
        a.y_axis.as_vec3().extend(0.0),
        a.z_axis.as_vec3().extend(0.0),
        t.as_vec3().extend(1.0),
    )
}

/// A rotation, translation and symmetric positive definite scale/shear.
fn joint(max_stretch: f64) -> impl Strategy<Value = (DQuat, DVec3, DMat3)> {
    (
        prop::array::uniform3(-3.2f64..3.2),
        prop::array::uniform3(-2.0f64..2.0),
        prop::array::uniform3(-max_stretch..=max_stretch),
        prop::array::uniform3(-1.0f64..1.0),
    )
        .prop_map(|(r, t, st, sr)| {
            let q = DQuat::from_euler(glam::EulerRot::XYZ, r[0], r[1], r[2]);
            let frame = DMat3::from_euler(glam::EulerRot::ZYX, sr[0], sr[1], sr[2]);
            let diag = DMat3::from_diagonal(DVec3::new(1.0 + st[0], 1.0 + st[1], 1.0 + st[2]));
            (q, DVec3::from(t), frame * diag * frame.transpose())
        })
}

fn influences(rows: &[Vec<(usize, f64)>]) -> Influences {
    Influences::from_rows(rows.iter().map(|r| {
        r.iter()
            .map(|&(j, w)| Influence {
                joint: j as u32,
                weight: w as f32,
            })
            .collect::<Vec<_>>()
    }))
}

fn run_dqs(skin: &[Mat4], infl: &Influences, rest: &[Vec3], parallel: bool) -> Vec<Vec3> {
    let mut out = vec![Vec3::ZERO; rest.len()];
    let mut palette = DqsPalette::new(skin.len(), 1);
    let mut job = DqsJob {
        skin_matrices: skin,
        influences: infl,
        rest_positions: rest,
        rest_normals: None,
        out_positions: &mut out,
        out_normals: None,
        palette: &mut palette,
    };
    if parallel {
        job.par_run().unwrap();
    } else {
        job.run().unwrap();
    }
    out
}

fn rows_strategy(joints: usize) -> impl Strategy<Value = Vec<Vec<(usize, f64)>>> {
    prop::collection::vec(
        prop::collection::vec((0..joints, 0.01f64..1.0), 1..7),
        1..40,
    )
    .prop_map(|rows| {
        rows.into_iter()
            .map(|r| {
                let sum: f64 = r.iter().map(|x| x.1).sum();
                r.into_iter().map(|(j, w)| (j, w / sum)).collect()
            })
            .collect()
    })
}

proptest! {
    #[test]
    fn decompose_recovers_rotation_and_scale((q, t, s) in joint(0.5)) {
        let m = mat4(q, t, s);
        let d = decompose(&m).unwrap();
        let back = Mat4::from_rotation_translation(d.rigid.real, d.rigid.translation())
            * Mat4::from_mat3(d.scale);
        prop_assert!(back.abs_diff_eq(m, 1e-5), "{back} vs {m}");
        let (dq, _, ds) = decompose_f64(&m).unwrap();
        prop_assert!(dq.dot(q).abs() > 1.0 - 1e-6, "rotation {dq} vs {q}");
        prop_assert!((ds - s).abs().to_cols_array().iter().all(|e| *e < 1e-5), "scale {ds} vs {s}");
    }

    #[test]
    fn fast_equals_naive_reference(
        joints in prop::collection::vec(joint(0.3), 1..9),
        rows in rows_strategy(8),
        pts in prop::collection::vec(prop::array::uniform3(-2.0f32..2.0), 40),
    ) {
        let n = joints.len();
        let rows: Vec<Vec<(usize, f64)>> = rows.into_iter().map(|r| r.into_iter().map(|(j, w)| (j % n, w)).collect()).collect();
        let skin: Vec<Mat4> = joints.iter().map(|&(q, t, s)| mat4(q, t, s)).collect();
        // The reference gets the f32 matrices' exact decomposition: re-derive it from
        // what the job sees, so only the blend is compared.
        let exact: Vec<(DQuat, DVec3, DMat3)> = skin.iter().map(|m| decompose_f64(m).unwrap()).collect();
        let infl = influences(&rows);
        let rest: Vec<Vec3> = pts[..rows.len()].iter().map(|p| Vec3::from(*p)).collect();
        let serial = run_dqs(&skin, &infl, &rest, false);
        for (v, row) in rows.iter().enumerate() {
            let expect = naive_dqs(&exact, row, rest[v].as_dvec3()).as_vec3();
            prop_assert!(serial[v].abs_diff_eq(expect, 2e-5), "vertex {v}: {} vs {expect}", serial[v]);
        }
        // The fixed-width fast path agrees with the row path.
        let packed = crate::skinning::PackedInfluences::new(&infl);
        let mut fast = vec![Vec3::ZERO; rest.len()];
        crate::skinning::skin_frames(rigport_model::SkinningMethod::Dqs, &packed, &rest, &skin, &mut fast).unwrap();
        for (v, (a, b)) in fast.iter().zip(&serial).enumerate() {
            prop_assert!(a.abs_diff_eq(*b, 1e-5), "vertex {v}: {a} vs {b}");
        }
    }

    #[test]
    fn single_influence_is_that_joints_matrix(
        joints in prop::collection::vec(joint(0.5), 1..6),
        pts in prop::collection::vec(prop::array::uniform3(-2.0f32..2.0), 1..30),
    ) {
        let skin: Vec<Mat4> = joints.iter().map(|&(q, t, s)| mat4(q, t, s)).collect();
        let n = skin.len();
        let rows: Vec<Vec<(usize, f64)>> = (0..pts.len()).map(|v| vec![(v % n, 1.0)]).collect();
        let rest: Vec<Vec3> = pts.iter().map(|p| Vec3::from(*p)).collect();
        let out = run_dqs(&skin, &influences(&rows), &rest, false);
        for (v, p) in rest.iter().enumerate() {
            let expect = skin[v % n].transform_point3(*p);
            prop_assert!(out[v].abs_diff_eq(expect, 1e-5), "vertex {v}: {} vs {expect}", out[v]);
        }
    }

    #[test]
    fn rigid_blend_of_one_transform_is_exact(
        (q, t, _) in joint(0.0),
        weights in prop::collection::vec(0.05f64..1.0, 1..6),
        p in prop::array::uniform3(-3.0f32..3.0),
    ) {
        // Several palette entries with the same rigid transform (two of them with the
        // quaternion's sign flipped): any blend must be that transform exactly.
        let m = mat4(q, t, DMat3::IDENTITY);
        let skin = vec![m; weights.len()];
        let sum: f64 = weights.iter().sum();
        let row: Vec<(usize, f64)> = weights.iter().enumerate().map(|(j, w)| (j, w / sum)).collect();
        let rest = [Vec3::from(p)];
        let out = run_dqs(&skin, &influences(&[row]), &rest, false);
        let expect = m.transform_point3(rest[0]);
        prop_assert!(out[0].abs_diff_eq(expect, 1e-5), "{} vs {expect}", out[0]);
    }

    #[test]
    fn normalization_is_idempotent(
        r in prop::array::uniform4(-2.0f32..2.0),
        d in prop::array::uniform4(-2.0f32..2.0),
    ) {
        let dq = DualQuat { real: Quat::from_array(r), dual: Quat::from_array(d) };
        let once = dq.normalized();
        let twice = once.normalized();
        prop_assert!(Vec4::from(once.real).abs_diff_eq(Vec4::from(twice.real), 1e-6));
        prop_assert!(Vec4::from(once.dual).abs_diff_eq(Vec4::from(twice.dual), 1e-5));
        prop_assert!((Vec4::from(once.real).length() - 1.0).abs() < 1e-5 || once == DualQuat::IDENTITY);
    }
}

#[test]
fn hemisphere_follows_the_heaviest_joint() {
    // Two joints rotated +170° and -170° about Z are 20° apart through 180°: an even
    // blend is the 180° rotation (the short way round), never the identity.
    let a = Mat4::from_rotation_z(170f32.to_radians());
    let b = Mat4::from_rotation_z(-170f32.to_radians());
    let infl = Influences::from_rows([[
        Influence {
            joint: 0,
            weight: 0.5,
        },
        Influence {
            joint: 1,
            weight: 0.5,
        },
    ]]);
    let out = run_dqs(&[a, b], &infl, &[Vec3::X], false);
    assert!(out[0].abs_diff_eq(-Vec3::X, 1e-5), "{}", out[0]);
    // 70/30 towards +170°: 170 + 0.3 * 20 = 176° (blended along the short arc).
    let infl = Influences::from_rows([[
        Influence {
            joint: 0,
            weight: 0.7,
        },
        Influence {
            joint: 1,
            weight: 0.3,
        },
    ]]);
    let out = run_dqs(&[a, b], &infl, &[Vec3::X], false);
    let angle = out[0].y.atan2(out[0].x).to_degrees();
    assert!((angle - 176.0).abs() < 0.5, "angle {angle}");
}

#[test]
fn opposite_hemispheres_are_flipped_to_the_pivot() {
    // Quaternions as the decomposition extracts them (largest component positive) with
    // a negative dot product: the lighter one must enter the blend negated.
    let qa = Quat::from_rotation_z(170f32.to_radians());
    let qb = Quat::from_xyzw(0.8, 0.0, -0.5, 0.33).normalize();
    let (da, db) = (
        decompose(&Mat4::from_quat(qa)).unwrap().rigid.real,
        decompose(&Mat4::from_quat(qb)).unwrap().rigid.real,
    );
    assert!(da.dot(db) < -0.3, "{da} {db}");
    let infl = Influences::from_rows([[
        Influence {
            joint: 0,
            weight: 0.4,
        },
        Influence {
            joint: 1,
            weight: 0.6,
        },
    ]]);
    let p = Vec3::new(0.3, -0.7, 0.5);
    let out = run_dqs(
        &[Mat4::from_quat(qa), Mat4::from_quat(qb)],
        &infl,
        &[p],
        false,
    );
    // Pivot = joint 1 (0.6): joint 0 is flipped.
    let aligned = (db * 0.6 - da * 0.4).normalize() * p;
    let unaligned = (db * 0.6 + da * 0.4).normalize() * p;
    assert!(aligned.distance(unaligned) > 0.1);
    assert!(out[0].abs_diff_eq(aligned, 1e-5), "{} vs {aligned}", out[0]);
}

#[test]
fn frames_in_blocks_of_the_palette_capacity_match_one_frame_jobs() {
    use crate::skinning::{PackedInfluences, SkinFramesJob};
    use rigport_model::SkinningMethod;
    let joints = 6;
    let frames = 5;
    let mats: Vec<Mat4> = (0..joints * frames)
        .map(|i| {
            let f = i as f32;
            Mat4::from_scale_rotation_translation(
                Vec3::new(1.0 + 0.01 * (f % 3.0), 1.0, 0.98),
                Quat::from_euler(glam::EulerRot::XYZ, 0.3 * f, -0.2 * f, 0.7 * f),
                Vec3::new(f.sin(), f.cos(), 0.1 * f),
            )
        })
        .collect();
    let rows: Vec<Vec<(usize, f64)>> = (0..50)
        .map(|v| {
            (0..1 + v % 5)
                .map(|k| ((v + 2 * k) % joints, 1.0 + k as f64))
                .collect()
        })
        .collect();
    let infl = influences(&rows);
    let rest: Vec<Vec3> = (0..50)
        .map(|v| Vec3::new(v as f32 * 0.1, 1.0, -0.5))
        .collect();
    let packed = PackedInfluences::new(&infl);
    let mut out = vec![Vec3::ZERO; rest.len() * frames];
    // Room for two frames: the job prepares and skins frames 0-1, 2-3, then 4.
    let mut palette = DqsPalette::new(joints, 2);
    SkinFramesJob {
        method: SkinningMethod::Dqs,
        influences: &packed,
        rest_positions: &rest,
        frame_skin_matrices: &mats,
        out_positions: &mut out,
        palette: &mut palette,
    }
    .run()
    .unwrap();
    for f in 0..frames {
        let one = run_dqs(&mats[f * joints..(f + 1) * joints], &infl, &rest, false);
        for (v, (a, b)) in out[f * rest.len()..(f + 1) * rest.len()]
            .iter()
            .zip(&one)
            .enumerate()
        {
            // The packed path sums the pivot first: float rounding only (the weights
            // here are not normalized, so the points reach |p| ~ 60).
            assert!(
                a.abs_diff_eq(*b, 1e-6 * (1.0 + b.length())),
                "frame {f} vertex {v}: {a} vs {b}"
            );
        }
    }
}

#[test]
fn singular_joint_and_unweighted_vertex() {
    let zero = Mat4::from_scale(Vec3::splat(1e-5));
    let t = Mat4::from_translation(Vec3::new(1.0, 2.0, 3.0));
    let infl = Influences::from_rows([
        vec![
            Influence {
                joint: 0,
                weight: 0.5,
            },
            Influence {
                joint: 1,
                weight: 0.5,
            },
        ],
        vec![],
        vec![Influence {
            joint: 0,
            weight: 0.0,
        }],
    ]);
    let rest = [
        Vec3::ONE,
        Vec3::new(4.0, 5.0, 6.0),
        Vec3::new(7.0, 8.0, 9.0),
    ];
    let out = run_dqs(&[t, zero], &infl, &rest, false);
    // The singular joint contributes no rotation or translation, and its weight
    // times the identity to the scale blend (which is on: it "scales"), so the
    // point is t applied to 0.5 p + 0.5 p.
    assert!(
        out[0].abs_diff_eq(Vec3::ONE + Vec3::new(1.0, 2.0, 3.0), 1e-6),
        "{}",
        out[0]
    );
    assert_eq!(out[1], rest[1]);
    assert_eq!(out[2], rest[2]);
    assert!(decompose(&zero).is_none());
}

#[test]
fn normals_rotate_with_the_blend() {
    let r = Mat4::from_rotation_y(0.8) * Mat4::from_scale(Vec3::new(2.0, 1.0, 1.0));
    let infl = Influences::from_rows([[Influence {
        joint: 0,
        weight: 1.0,
    }]]);
    let rest_n = [Vec3::new(1.0, 1.0, 0.0).normalize()];
    let mut out = [Vec3::ZERO];
    let mut out_n = [Vec3::ZERO];
    let mut palette = DqsPalette::new(1, 1);
    DqsJob {
        skin_matrices: &[r],
        influences: &infl,
        rest_positions: &[Vec3::ZERO],
        rest_normals: Some(&rest_n),
        out_positions: &mut out,
        out_normals: Some(&mut out_n),
        palette: &mut palette,
    }
    .run()
    .unwrap();
    // A single joint's normal matrix: the inverse transpose of its 3x3.
    let a = Mat3::from_mat4(r);
    let expect = (a.inverse().transpose() * rest_n[0]).normalize();
    assert!(
        out_n[0].abs_diff_eq(expect, 1e-5),
        "{} vs {expect}",
        out_n[0]
    );
}

#[test]
fn parallel_equals_serial_and_palette_is_checked() {
    let skin: Vec<Mat4> = (0..5)
        .map(|j| {
            Mat4::from_rotation_translation(Quat::from_rotation_x(j as f32), Vec3::splat(j as f32))
        })
        .collect();
    let n = 3 * crate::skinning::common::GRAIN + 17;
    let infl = Influences::from_rows((0..n).map(|v| {
        [
            Influence {
                joint: (v % 5) as u32,
                weight: 0.75,
            },
            Influence {
                joint: ((v / 5) % 5) as u32,
                weight: 0.25,
            },
        ]
    }));
    let rest: Vec<Vec3> = (0..n)
        .map(|v| Vec3::new(v as f32 * 1e-3, 1.0, -1.0))
        .collect();
    assert_eq!(
        run_dqs(&skin, &infl, &rest, true),
        run_dqs(&skin, &infl, &rest, false)
    );
    let mut out = vec![Vec3::ZERO; n];
    let mut small = DqsPalette::new(4, 1);
    let job = DqsJob {
        skin_matrices: &skin,
        influences: &infl,
        rest_positions: &rest,
        rest_normals: None,
        out_positions: &mut out,
        out_normals: None,
        palette: &mut small,
    };
    assert!(matches!(
        job.validate(),
        Err(EvalError::Length {
            what: "DqsPalette joints",
            ..
        })
    ));
}

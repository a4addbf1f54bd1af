//! Bone heat on meshes made here: a bar bent by two bones, and the cases it must survive.

use super::*;

/// A box-section bar along +X from 0 to `len`, `rings` rings of 4 vertices, capped.
fn bar(len: f32, rings: u32, offset: Vec3) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let mut p = Vec::new();
    for r in 0..rings {
        let x = len * r as f32 / (rings - 1) as f32;
        for (y, z) in [(-0.1, -0.1), (0.1, -0.1), (0.1, 0.1), (-0.1, 0.1)] {
            p.push(offset + Vec3::new(x, y, z));
        }
    }
    let mut t = Vec::new();
    for r in 0..rings - 1 {
        for k in 0..4u32 {
            let (a, b) = (r * 4 + k, r * 4 + (k + 1) % 4);
            t.push([a, b, b + 4]);
            t.push([a, b + 4, a + 4]);
        }
    }
    let last = (rings - 1) * 4;
    t.push([0, 2, 1]);
    t.push([0, 3, 2]);
    t.push([last, last + 1, last + 2]);
    t.push([last, last + 2, last + 3]);
    (p, t)
}

fn two_bones() -> Vec<Bone> {
    vec![
        Bone {
            head: Vec3::ZERO,
            tail: Vec3::X,
        },
        Bone {
            head: Vec3::X,
            tail: Vec3::X * 2.0,
        },
    ]
}

fn weight_of(row: &[(u32, f32)], bone: u32) -> f32 {
    row.iter().find(|e| e.0 == bone).map_or(0.0, |e| e.1)
}

#[test]
fn each_end_follows_its_bone_and_the_joint_blends() {
    let (p, t) = bar(2.0, 21, Vec3::ZERO);
    let w = bone_heat(&p, &t, &two_bones(), &HeatOptions::default(), &|_, _| {}).expect("weights");
    assert_eq!(w.rows.len(), p.len());
    for (v, row) in w.rows.iter().enumerate() {
        let sum: f32 = row.iter().map(|e| e.1).sum();
        assert!((sum - 1.0).abs() < 1e-5, "vertex {v}: {row:?}");
    }
    // Ends: all on their bone; the middle ring shares.
    assert!(weight_of(&w.rows[0], 0) > 0.99);
    assert!(weight_of(&w.rows[p.len() - 1], 1) > 0.99);
    let mid = 10 * 4;
    let (a, b) = (weight_of(&w.rows[mid], 0), weight_of(&w.rows[mid], 1));
    assert!((a - 0.5).abs() < 0.2 && (b - 0.5).abs() < 0.2, "{a} {b}");
    // Monotone along the bar.
    let along: Vec<f32> = (0..21).map(|r| weight_of(&w.rows[r * 4], 1)).collect();
    assert!(along.windows(2).all(|w| w[1] >= w[0] - 1e-4), "{along:?}");
    assert_eq!(w.repairs, Repairs::default());
}

#[test]
fn it_never_fails_and_counts_what_it_repaired() {
    // Two disconnected bars, the second far from every bone and behind a wall of
    // nothing: still weighted (by heat, it sees the bones: nothing blocks).
    let (mut p, mut t) = bar(2.0, 11, Vec3::ZERO);
    let (p2, t2) = bar(2.0, 11, Vec3::new(0.0, 3.0, 0.0));
    let base = p.len() as u32;
    p.extend(p2);
    t.extend(t2.iter().map(|f| f.map(|i| i + base)));
    // A zero-area face, a duplicate vertex, and a vertex in no face.
    t.push([0, 0, 1]);
    p.push(p[5]);
    t.push([p.len() as u32 - 1, 6, 7]);
    p.push(Vec3::new(5.0, 5.0, 5.0));
    let w = bone_heat(&p, &t, &two_bones(), &HeatOptions::default(), &|_, _| {}).expect("weights");
    assert_eq!(w.rows.len(), p.len());
    assert!(w.rows.iter().all(|r| {
        let s: f32 = r.iter().map(|e| e.1).sum();
        (s - 1.0).abs() < 1e-5 && r.iter().all(|e| e.1.is_finite())
    }));
    assert_eq!(w.repairs.welded, 1);
    assert!(w.repairs.degenerate_faces >= 1);
    // The lone vertex: by distance, on the nearer bone (the second).
    assert_eq!(w.rows[p.len() - 1][0].0, 1);
    assert!(w.repairs.by_distance >= 1);
    // A non-manifold fan: three faces on one edge.
    let fan_p = vec![
        Vec3::new(0.5, 0.0, 0.3),
        Vec3::new(1.5, 0.0, 0.3),
        Vec3::new(1.0, 0.5, 0.3),
        Vec3::new(1.0, -0.5, 0.3),
        Vec3::new(1.0, 0.0, 0.8),
    ];
    let fan_t = vec![[0, 1, 2], [1, 0, 3], [0, 1, 4]];
    let w = bone_heat(
        &fan_p,
        &fan_t,
        &two_bones(),
        &HeatOptions::default(),
        &|_, _| {},
    )
    .expect("fan");
    assert_eq!(w.repairs.non_manifold_edges, 1);
    assert_eq!(w.rows.len(), 5);
}

#[test]
fn a_vertex_that_sees_no_bone_takes_its_neighbours_weights() {
    // The far end's faces turned inside out: their vertices face away from the bone (a
    // bone is seen from the side a vertex faces), so they have no heat source and take
    // their weights from the rest of the bar by diffusion.
    let (p, mut t) = bar(2.0, 21, Vec3::ZERO);
    let flipped = 16 * 8;
    for f in t.iter_mut().take(20 * 8).skip(flipped) {
        f.swap(1, 2);
    }
    let one = vec![Bone {
        head: Vec3::ZERO,
        tail: Vec3::X * 2.0,
    }];
    let w = bone_heat(&p, &t, &one, &HeatOptions::default(), &|_, _| {}).expect("weights");
    assert!(w.repairs.unseen > 0, "{:?}", w.repairs);
    assert_eq!(w.repairs.by_distance, 0, "{:?}", w.repairs);
    assert!(w.rows.iter().all(|r| r == &vec![(0, 1.0)]));
}

#[test]
fn bad_input_is_refused() {
    let (p, t) = bar(2.0, 3, Vec3::ZERO);
    assert_eq!(
        bone_heat(&p, &[], &two_bones(), &HeatOptions::default(), &|_, _| {}),
        Err(WeightsError::NoFaces)
    );
    assert_eq!(
        bone_heat(&p, &t, &[], &HeatOptions::default(), &|_, _| {}),
        Err(WeightsError::NoBones)
    );
    assert!(matches!(
        bone_heat(
            &p,
            &[[0, 1, 99]],
            &two_bones(),
            &HeatOptions::default(),
            &|_, _| {}
        ),
        Err(WeightsError::BadIndex { vertex: 99, .. })
    ));
}

#[test]
fn progress_reaches_its_total_in_at_most_about_a_hundred_calls() {
    // 2,000 vertices, 3 bones: sight, factorization and solves count 2,000 units each.
    let (p, t) = bar(3.0, 500, Vec3::ZERO);
    let bones = vec![
        two_bones()[0],
        two_bones()[1],
        Bone {
            head: Vec3::X * 2.0,
            tail: Vec3::X * 3.0,
        },
    ];
    let calls = std::sync::Mutex::new(Vec::new());
    let heat = bone_heat(&p, &t, &bones, &HeatOptions::default(), &|done, total| {
        calls.lock().unwrap().push((done, total));
    })
    .expect("weights");
    assert_eq!(heat.rows.len(), 2000);
    let calls = calls.into_inner().unwrap();
    assert!(calls.iter().all(|&(_, total)| total == 6000), "{calls:?}");
    assert_eq!(calls.first(), Some(&(0, 6000)));
    assert_eq!(calls.iter().map(|c| c.0).max(), Some(6000), "{calls:?}");
    assert_eq!(calls.iter().filter(|c| c.0 == 6000).count(), 1, "{calls:?}");
    // At most one call per 1% (threads may cross a step together), the factorization and
    // the solves a third each, told when done.
    assert!((30..=110).contains(&calls.len()), "{} calls", calls.len());
    let sight = calls.iter().filter(|c| c.0 > 0 && c.0 <= 2000).count();
    assert!(sight >= 30, "{sight} calls while checking sight: {calls:?}");
    assert_eq!(calls.iter().filter(|c| c.0 == 4000).count(), 1, "{calls:?}");
}

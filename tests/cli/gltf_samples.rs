//! Acceptance 3: the corpus' glTF samples re-export clean and play back the same.

use std::collections::HashMap;

use rigport_model::glam::{Mat4, Quat, Vec3};

use crate::common::*;
use crate::gltf_read::{self, GltfChannel, GltfScene};

/// The name rigport gives a node: its own, or `node_<i>` when it has none.
fn key_names(scene: &GltfScene) -> Vec<String> {
    scene
        .node_names
        .iter()
        .enumerate()
        .map(|(i, n)| {
            if n.is_empty() {
                format!("node_{i}")
            } else {
                n.clone()
            }
        })
        .collect()
}

/// Samples a channel at time `t` (glTF §3.11: STEP, LINEAR with slerp, CUBICSPLINE).
fn sample(ch: &GltfChannel, t: f32) -> Vec<f32> {
    let times = &ch.times;
    let cubic = ch.interpolation == "CubicSpline";
    let value = |k: usize| -> Vec<f32> {
        if cubic {
            ch.values[3 * k + 1].clone()
        } else {
            ch.values[k].clone()
        }
    };
    if t <= times[0] {
        return value(0);
    }
    let last = times.len() - 1;
    if t >= times[last] {
        return value(last);
    }
    let k = times.partition_point(|&x| x <= t) - 1;
    let (t0, t1) = (times[k], times[k + 1]);
    let dt = t1 - t0;
    let u = (t - t0) / dt;
    match ch.interpolation.as_str() {
        "Step" => value(k),
        "Linear" if ch.path == "Rotation" => {
            let a = Quat::from_slice(&value(k));
            let b = Quat::from_slice(&value(k + 1));
            a.slerp(b, u).to_array().to_vec()
        }
        "Linear" => value(k)
            .iter()
            .zip(value(k + 1))
            .map(|(a, b)| a + (b - a) * u)
            .collect(),
        _ => {
            let (p0, m0) = (&ch.values[3 * k + 1], &ch.values[3 * k + 2]);
            let (p1, m1) = (&ch.values[3 * (k + 1) + 1], &ch.values[3 * (k + 1)]);
            let (u2, u3) = (u * u, u * u * u);
            let h00 = 2.0 * u3 - 3.0 * u2 + 1.0;
            let h10 = u3 - 2.0 * u2 + u;
            let h01 = -2.0 * u3 + 3.0 * u2;
            let h11 = u3 - u2;
            let mut v: Vec<f32> = (0..p0.len())
                .map(|i| h00 * p0[i] + h10 * dt * m0[i] + h01 * p1[i] + h11 * dt * m1[i])
                .collect();
            if ch.path == "Rotation" {
                v = Quat::from_slice(&v).normalize().to_array().to_vec();
            }
            v
        }
    }
}

/// World matrices of every node at time `t` of animation `a`.
fn world_at(scene: &GltfScene, a: usize, t: f32) -> Vec<Mat4> {
    let mut local = scene.local.clone();
    for ch in &scene.animations[a].channels {
        let v = sample(ch, t);
        let l = &mut local[ch.node];
        match ch.path.as_str() {
            "Translation" => l.0 = Vec3::from_slice(&v),
            "Rotation" => l.1 = Quat::from_slice(&v).normalize(),
            "Scale" => l.2 = Vec3::from_slice(&v),
            _ => {}
        }
    }
    let animated = GltfScene {
        node_names: scene.node_names.clone(),
        parents: scene.parents.clone(),
        local,
        skins: Vec::new(),
        animations: Vec::new(),
    };
    animated.world(&HashMap::new())
}

fn normalized_skin(scene: &mut GltfScene) {
    for skin in &mut scene.skins {
        for row in &mut skin.influences {
            let s: f32 = row.iter().map(|x| x.1).sum();
            for x in row.iter_mut() {
                x.1 /= s;
            }
        }
    }
}

#[test]
fn gltf_samples_reexport_clean_and_play_back_the_same() {
    for sample_path in GLTF_SAMPLES {
        let Some(src) = corpus(sample_path) else {
            continue;
        };
        let dir = scratch();
        let mut source = gltf_read::read(&src);
        normalized_skin(&mut source);
        let src_names = key_names(&source);
        for ext in ["glb", "gltf"] {
            let out = dir.path().join(format!("out.{ext}"));
            rigport_ok(&[
                "convert",
                src.to_str().unwrap(),
                "-o",
                out.to_str().unwrap(),
            ]);
            assert_valid(&out);
            let mut ours = gltf_read::read(&out);
            normalized_skin(&mut ours);
            let ours_by_name = ours.node_by_name();
            // Every skin joint keeps its name (skinned-mesh nodes need not: glTF ignores them).
            let map: Vec<Option<usize>> = src_names
                .iter()
                .map(|n| ours_by_name.get(n.as_str()).copied())
                .collect();
            for s in &source.skins {
                for &j in &s.joints {
                    assert!(
                        map[j].is_some(),
                        "{sample_path}: joint {} lost",
                        src_names[j]
                    );
                }
            }
            assert_eq!(source.skins.len(), ours.skins.len(), "{sample_path}");
            assert_eq!(
                source.animations.len(),
                ours.animations.len(),
                "{sample_path}"
            );
            // Geometry: the same bind-space positions.
            for (s, o) in source.skins.iter().zip(&ours.skins) {
                assert_eq!(s.positions, o.positions, "{sample_path}");
            }
            let diag = source.skins.iter().flat_map(|s| &s.positions).fold(
                (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
                |(lo, hi), p| (lo.min(*p), hi.max(*p)),
            );
            let diag = (diag.1 - diag.0).length().max(1e-6);
            let mut frames = 0;
            for (a, anim) in source.animations.iter().enumerate() {
                if !anim.name.is_empty() {
                    assert_eq!(
                        anim.name, ours.animations[a].name,
                        "{sample_path}: clip name"
                    );
                }
                let mut times: Vec<f32> =
                    anim.channels.iter().flat_map(|c| c.times.clone()).collect();
                times.sort_by(f32::total_cmp);
                times.dedup();
                for &t in &times {
                    frames += 1;
                    let ws = world_at(&source, a, t);
                    let wo = world_at(&ours, a, t);
                    // Joint world transforms (every source node), relative to their size.
                    for (i, m) in ws.iter().enumerate() {
                        if source.skins.iter().all(|s| !s.joints.contains(&i)) {
                            continue;
                        }
                        let scale = m.to_cols_array().iter().fold(1.0f32, |x, y| x.max(y.abs()));
                        let Some(o) = map[i] else { continue };
                        let d = (*m - wo[o])
                            .to_cols_array()
                            .iter()
                            .fold(0.0f32, |x, y| x.max(y.abs()));
                        assert!(
                            d <= 1e-5 * scale,
                            "{sample_path} {ext} anim {a} t={t} node {}: {d}",
                            src_names[i]
                        );
                    }
                    // Skinned positions.
                    for s in 0..source.skins.len() {
                        let ps = source.skin_positions(s, &ws);
                        let po = ours.skin_positions(s, &wo);
                        let d = ps
                            .iter()
                            .zip(&po)
                            .map(|(a, b)| (*a - *b).length())
                            .fold(0.0, f32::max);
                        assert!(d <= 1e-5 * diag, "{sample_path} {ext} anim {a} t={t}: skinned deviation {d} (diag {diag})");
                    }
                }
            }
            eprintln!("{sample_path} -> {ext}: {frames} key times compared");
        }
    }
}

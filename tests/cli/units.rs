//! Input units (issue 30, first step): a source that states no unit is read in the unit
//! `--input-units` gives; without it, a skeleton too tall for metres is warning W008 naming
//! its height and the flag; a file that states its unit keeps it unless `--force-units`.

use std::path::Path;

use crate::common::{corpus, rigport, rigport_ok};

/// How tall the skeleton of a glb stands in the first frame of its first clip (metres:
/// `rigport eval`'s joint positions), or its first mesh at rest (`rigport inspect`) when it
/// has no clip.
fn glb_height(glb: &Path) -> f64 {
    let npz = glb.with_extension("npz");
    let out = rigport(&["eval", glb.to_str().unwrap(), "-o", npz.to_str().unwrap()]);
    if out.status.success() {
        let dump = crate::common::read_npz(&npz);
        let world = &dump["joint_world"];
        let joints = world.shape[world.shape.len() - 3];
        // Frame 0; row-major column-vector matrices: y is element [1][3].
        let ys: Vec<f64> = (0..joints).map(|j| world.numbers[j * 16 + 7]).collect();
        let lo = ys.iter().copied().fold(f64::MAX, f64::min);
        return ys.iter().copied().fold(f64::MIN, f64::max) - lo;
    }
    let out = rigport(&["inspect", "--json", glb.to_str().unwrap()]);
    assert!(out.status.success());
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let mesh = &json[0]["meshes"][0];
    mesh["bounds_max"][1].as_f64().unwrap() - mesh["bounds_min"][1].as_f64().unwrap()
}

#[test]
fn a_centimetre_bvh_plays_at_human_height_with_input_units() {
    let Some(kick) = corpus("4_bvh/bandai_namco_ds1/dataset-1_kick_normal_001.bvh") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let (plain, cm) = (dir.path().join("plain.glb"), dir.path().join("cm.glb"));
    let kick = kick.to_str().unwrap();
    let warned = rigport_ok(&["convert", kick, "-o", plain.to_str().unwrap()]);
    assert!(
        warned.contains("warning[W008]")
            && warned.contains("units tall")
            && warned.contains("--input-units cm"),
        "{warned}"
    );
    assert!(glb_height(&plain) > 100.0, "read as metres: a giant");
    let quiet = rigport_ok(&[
        "convert",
        kick,
        "--input-units",
        "cm",
        "-o",
        cm.to_str().unwrap(),
    ]);
    assert!(!quiet.contains("W008"), "{quiet}");
    let h = glb_height(&cm);
    assert!((1.0..=2.0).contains(&h), "{h} m");
    // `auto` makes the same guess, and says so.
    let auto = dir.path().join("auto.glb");
    let said = rigport_ok(&[
        "convert",
        kick,
        "--input-units",
        "auto",
        "-o",
        auto.to_str().unwrap(),
    ]);
    assert!(said.contains("read as centimetres"), "{said}");
    assert!((glb_height(&auto) - h).abs() < 1e-9);
}

#[test]
fn a_unit_the_file_states_wins_unless_forced() {
    let (Some(asf), Some(amc)) = (
        corpus("3_acclaim_asf_amc/usc_csci520_mocapPlayer__shreyabhaumik/07-walk.asf"),
        corpus("3_acclaim_asf_amc/usc_csci520_mocapPlayer__shreyabhaumik/07_05-walk.amc"),
    ) else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("walk.glb");
    let (asf, amc, out_s) = (
        asf.to_str().unwrap(),
        amc.to_str().unwrap(),
        out.to_str().unwrap(),
    );
    let refused = rigport(&["convert", asf, amc, "--input-units", "cm", "-o", out_s]);
    let stderr = String::from_utf8_lossy(&refused.stderr);
    assert_eq!(refused.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("states") && stderr.contains("--force-units"),
        "{stderr}"
    );
    assert!(!out.exists());
    rigport_ok(&[
        "convert",
        asf,
        amc,
        "--input-units",
        "cm",
        "--force-units",
        "-o",
        out_s,
    ]);
    assert!(out.is_file());
}

#[test]
fn pinocchio_and_csci520_rigs_take_input_units() {
    let fixture = |f: &str| crate::common::repo().join("fixtures/pinocchio").join(f);
    let dir = tempfile::tempdir().unwrap();
    let (m, mm) = (dir.path().join("m.glb"), dir.path().join("mm.glb"));
    let rig = [
        fixture("branch.obj"),
        fixture("branch_skeleton.out"),
        fixture("branch_attachment.out"),
    ];
    let rig: Vec<&str> = rig.iter().map(|p| p.to_str().unwrap()).collect();
    let mut args = vec!["convert"];
    args.extend(&rig);
    rigport_ok(&[&args[..], &["-o", m.to_str().unwrap()]].concat());
    rigport_ok(
        &[
            &args[..],
            &["--input-units", "mm", "-o", mm.to_str().unwrap()],
        ]
        .concat(),
    );
    let ratio = glb_height(&mm) / glb_height(&m);
    assert!((ratio - 0.001).abs() < 1e-9, "{ratio}");
    let Some(hand) = corpus("2_csci520_ik_skinning/tydia/hand") else {
        return;
    };
    let cm = dir.path().join("hand.glb");
    rigport_ok(&[
        "convert",
        hand.to_str().unwrap(),
        "--input-units",
        "cm",
        "-o",
        cm.to_str().unwrap(),
    ]);
    assert!(cm.is_file());
}

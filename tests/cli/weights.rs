//! `--weights auto` (issue 33): a Pinocchio mesh and skeleton without an `attachment.out`
//! get weights by bone heat; without the flag the error names it. Meshes made here that
//! bone heat must survive (two disconnected boxes, a non-manifold fan, a zero-area face, a
//! vertex in no face) all convert to a valid glb whose every weight row sums to 1, with
//! the repairs in a W003 warning.

use std::fmt::Write as _;
use std::path::Path;

use crate::common::*;

const MODEL1: &str = "1_pinocchio/berkeley_cs184__severus-snape_mobius-ants/human_model1";

#[test]
fn a_pinocchio_rig_without_attachment_gets_weights_with_the_flag() {
    let Some(dir) = corpus(MODEL1) else {
        return;
    };
    let (mesh, skeleton) = (dir.join("Model1.obj"), dir.join("skeleton.out"));
    let out_dir = scratch();
    let out = out_dir.path().join("auto.glb");
    let args = |extra: &[&'static str]| {
        let mut a = vec![
            "convert".to_string(),
            mesh.display().to_string(),
            skeleton.display().to_string(),
            "-o".into(),
            out.display().to_string(),
        ];
        a.extend(extra.iter().map(|s| s.to_string()));
        a
    };
    let refused = rigport(&args(&[]).iter().map(String::as_str).collect::<Vec<_>>());
    let stderr = String::from_utf8_lossy(&refused.stderr);
    assert!(!refused.status.success());
    assert!(
        stderr.contains("missing --attachment (or --weights auto)"),
        "{stderr}"
    );
    assert!(!out.exists());
    let log = rigport_ok(
        &args(&["--weights", "auto"])
            .iter()
            .map(String::as_str)
            .collect::<Vec<_>>(),
    );
    assert!(
        log.contains("skin weights computed by bone heat for 13336 vertices and 17 bones"),
        "{log}"
    );
    assert!(!log.contains("W003"), "a clean mesh needs no repair: {log}");
    assert_valid(&out);
}

/// A box from `lo` to `hi` as OBJ `v`/`f` lines, vertices numbered from `base` (1-based).
fn cube(text: &mut String, lo: [f32; 3], hi: [f32; 3], base: usize) {
    for k in 0..8 {
        let p = [
            if k & 1 == 0 { lo[0] } else { hi[0] },
            if k & 2 == 0 { lo[1] } else { hi[1] },
            if k & 4 == 0 { lo[2] } else { hi[2] },
        ];
        writeln!(text, "v {} {} {}", p[0], p[1], p[2]).unwrap();
    }
    for f in [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ] {
        writeln!(
            text,
            "f {} {} {} {}",
            base + f[0],
            base + f[1],
            base + f[2],
            base + f[3]
        )
        .unwrap();
    }
}

fn write_rig(dir: &Path, obj: &str) -> (String, String) {
    let mesh = dir.join("mesh.obj");
    let skeleton = dir.join("skeleton.out");
    std::fs::write(&mesh, obj).unwrap();
    // A vertical chain of three joints through the first box.
    std::fs::write(
        &skeleton,
        "0 0.5 0.0 0.5 -1\n1 0.5 0.5 0.5 0\n2 0.5 1.0 0.5 1\n",
    )
    .unwrap();
    (mesh.display().to_string(), skeleton.display().to_string())
}

#[test]
fn broken_meshes_all_get_weights_and_the_repairs_are_counted() {
    let dir = scratch();
    let mut obj = String::new();
    // A box around the skeleton, a second box beside it (disconnected), a non-manifold
    // fan on one of its edges, a face with no area, a vertex in no face.
    cube(&mut obj, [0.0, 0.0, 0.0], [1.0, 1.0, 1.0], 1);
    cube(&mut obj, [2.0, 0.0, 0.0], [3.0, 1.0, 1.0], 9);
    obj.push_str("v 2.5 1.5 0.0\nf 11 12 17\n");
    obj.push_str("v 0.2 0.2 0.0\nf 1 2 18\nf 18 18 2\n");
    obj.push_str("v 5 5 5\n");
    let (mesh, skeleton) = write_rig(dir.path(), &obj);
    let out = dir.path().join("broken.glb");
    let log = rigport_ok(&[
        "convert",
        &mesh,
        &skeleton,
        "--weights",
        "auto",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(
        log.contains("warning[W003]") && log.contains("automatic weights:"),
        "{log}"
    );
    assert!(log.contains("non-manifold edges"), "{log}");
    assert!(log.contains("weighted by distance"), "{log}");
    assert_valid(&out);
    // Every vertex of the written skin has weights summing to 1.
    let asset = rigport_import::gltf::import(&out).unwrap().asset;
    let skin = &asset.skins[0];
    assert_eq!(
        skin.influences.vertex_count(),
        asset.meshes[skin.mesh.get()].positions.len()
    );
    for row in skin.influences.rows() {
        let sum: f32 = row.iter().map(|i| i.weight).sum();
        assert!((sum - 1.0).abs() < 1e-3, "{row:?}");
    }
}

/// The corpus's SMPL mesh (6,890 vertices, no attachment) with its pynocchio skeleton,
/// whose root is written as its own parent (read as the root, with a W003 repair).
#[test]
fn the_smpl_rest_mesh_converts_with_automatic_weights() {
    let Some(dir) = corpus("1_pinocchio/pynocchio_smpl__kulendu") else {
        return;
    };
    let out_dir = scratch();
    let out = out_dir.path().join("smpl.glb");
    let log = rigport_ok(&[
        "convert",
        dir.join("rest.obj").to_str().unwrap(),
        dir.join("smpl_skeleton.out").to_str().unwrap(),
        "--weights",
        "auto",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(log.contains("read as the root (-1)"), "{log}");
    assert!(
        log.contains("bone heat for 6890 vertices and 23 bones"),
        "{log}"
    );
    assert_valid(&out);
}

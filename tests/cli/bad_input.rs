//! Acceptance 4: bad input gives exit code 1, a message naming file and line, and no output.

use std::path::{Path, PathBuf};

use crate::common::*;

const OBJ: &str = "v 0 0 0\nv 0 1 0\nv 0 2 0\nv 1 2 0\nf 1 2 3\nf 2 4 3\n";
const SKELETON: &str = "0 0 0 0 -1\n1 0 1 0 0\n2 0 2 0 1\n";
const ATTACHMENT: &str = "1 0 \n0.5 0.5 \n0 1 \n0 1 \n";

/// A small valid Pinocchio rig in `dir`, with one file replaced.
fn rig(dir: &Path, replace: Option<(&str, &str)>) -> [PathBuf; 3] {
    let files = [
        ("mesh.obj", OBJ),
        ("skeleton.out", SKELETON),
        ("attachment.out", ATTACHMENT),
    ];
    files.map(|(name, text)| {
        let text = match replace {
            Some((n, t)) if n == name => t,
            _ => text,
        };
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    })
}

/// Runs convert (to .glb and .gltf) and eval on the inputs; each must fail with exit code 1,
/// a message containing every `needles` entry, and leave the output folder empty.
fn assert_rejected(inputs: &[&Path], needles: &[&str]) {
    for out_name in ["out.glb", "out.gltf", "dump.npz"] {
        let out_dir = scratch();
        let out = out_dir.path().join(out_name);
        let mut args: Vec<&str> = vec![if out_name.ends_with("npz") {
            "eval"
        } else {
            "convert"
        }];
        args.extend(inputs.iter().map(|p| p.to_str().unwrap()));
        args.extend(["-o", out.to_str().unwrap()]);
        let result = rigport(&args);
        let stderr = String::from_utf8_lossy(&result.stderr);
        assert_eq!(
            result.status.code(),
            Some(1),
            "{args:?}: expected exit 1; stderr:\n{stderr}"
        );
        for needle in needles {
            assert!(
                stderr.contains(needle),
                "{args:?}: {needle:?} not in:\n{stderr}"
            );
        }
        assert!(!stderr.contains("panicked"), "{stderr}");
        let left: Vec<_> = std::fs::read_dir(out_dir.path()).unwrap().collect();
        assert!(left.is_empty(), "{args:?} left files behind: {left:?}");
    }
}

fn check_case(file: &str, text: &str, needles: &[&str]) {
    let dir = scratch();
    let [m, s, a] = rig(dir.path(), Some((file, text)));
    assert_rejected(&[&m, &s, &a], needles);
}

#[test]
fn the_valid_base_rig_converts() {
    let dir = scratch();
    let [m, s, a] = rig(dir.path(), None);
    let out = dir.path().join("ok.glb");
    rigport_ok(&[
        "convert",
        m.to_str().unwrap(),
        s.to_str().unwrap(),
        a.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_valid(&out);
}

#[test]
fn missing_file() {
    let dir = scratch();
    let [m, s, _] = rig(dir.path(), None);
    let missing = dir.path().join("attachment.out.missing");
    let out_dir = scratch();
    let out = out_dir.path().join("out.glb");
    let result = rigport(&[
        "convert",
        "--mesh",
        m.to_str().unwrap(),
        "--skeleton",
        s.to_str().unwrap(),
        "--attachment",
        missing.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert_eq!(result.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("attachment.out.missing"), "{stderr}");
    assert!(!out.exists());
}

#[test]
fn attachment_rows_differ_from_obj_vertices() {
    check_case(
        "attachment.out",
        "1 0 \n0.5 0.5 \n0 1 \n",
        &["attachment.out:", "3", "4"],
    );
}

#[test]
fn attachment_wrong_column_count() {
    check_case(
        "attachment.out",
        "1 0 \n0.5 0.25 0.25 \n0 1 \n0 1 \n",
        &["attachment.out:2"],
    );
}

#[test]
fn attachment_nan_weight() {
    check_case(
        "attachment.out",
        "1 0 \n0.5 NaN \n0 1 \n0 1 \n",
        &["attachment.out:2"],
    );
}

#[test]
fn attachment_negative_weight() {
    check_case(
        "attachment.out",
        "1 0 \n0.5 0.5 \n0 1 \n-0.5 1.5 \n",
        &["attachment.out:4", "negative"],
    );
}

#[test]
fn skeleton_parent_cycle() {
    check_case(
        "skeleton.out",
        "0 0 0 0 -1\n1 0 1 0 2\n2 0 2 0 1\n",
        &["skeleton.out", "cycle"],
    );
}

#[test]
fn skeleton_root_is_its_own_parent() {
    // Joint 0 is the root by the format's rules, so a root written with parent 0 (as the
    // pynocchio SMPL files write it) is repaired, with a W003 at its line; under
    // --deny-warnings that is exit 4 and nothing written. Another joint that is its own
    // parent stays an error.
    let dir = scratch();
    let [m, s, a] = rig(
        dir.path(),
        Some(("skeleton.out", "0 0 0 0 0\n1 0 1 0 0\n2 0 2 0 1\n")),
    );
    let out = dir.path().join("repaired.glb");
    let args = [
        m.to_str().unwrap(),
        s.to_str().unwrap(),
        a.to_str().unwrap(),
    ];
    let log = rigport_ok(&[
        "convert",
        args[0],
        args[1],
        args[2],
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(
        log.contains("warning[W003]") && log.contains("skeleton.out:1"),
        "{log}"
    );
    assert_valid(&out);
    let denied = dir.path().join("denied.glb");
    let o = rigport(&[
        "convert",
        args[0],
        args[1],
        args[2],
        "--deny-warnings",
        "-o",
        denied.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(4));
    assert!(!denied.exists());
    check_case(
        "skeleton.out",
        "0 0 0 0 -1\n1 0 1 0 1\n2 0 2 0 1\n",
        &["skeleton.out:2", "its own parent"],
    );
}

#[test]
fn empty_files() {
    check_case("skeleton.out", "", &["skeleton.out", "empty"]);
    check_case("attachment.out", "", &["attachment.out"]);
    check_case("mesh.obj", "", &["mesh.obj"]);
}

#[test]
fn malformed_obj_line() {
    check_case(
        "mesh.obj",
        "v 0 0 0\nv 0 1 zero\nv 0 2 0\nv 1 2 0\nf 1 2 3\n",
        &["mesh.obj:2"],
    );
    check_case(
        "mesh.obj",
        "v 0 0 0\nv 0 1 0\nv 0 2 0\nv 1 2 0\nf 1 2 9\n",
        &["mesh.obj:5"],
    );
}

#[test]
fn truncated_glb() {
    let Some(src) = corpus(GLTF_SAMPLES[0]) else {
        return;
    };
    let bytes = std::fs::read(src).unwrap();
    let dir = scratch();
    for cut in [10usize, 100, bytes.len() / 2, bytes.len() - 1] {
        let p = dir.path().join(format!("cut{cut}.glb"));
        std::fs::write(&p, &bytes[..cut]).unwrap();
        assert_rejected(&[&p], &[&format!("cut{cut}.glb")]);
    }
}

#[test]
fn bad_pose_file_names_line_and_joint() {
    let dir = scratch();
    let [m, s, a] = rig(dir.path(), None);
    let pose = dir.path().join("pose.json");
    let out = dir.path().join("d.npz");
    for (text, needle) in [
        (
            "{\"bone_1\": {\"quat\": [0,0,0,1]},\n \"nope\": {\"quat\": [0,0,0,1]}}",
            "nope",
        ),
        (
            "{\"bone_1\": {\"euler_deg\": [0,0,1], \"order\": \"abc\"}}",
            "abc",
        ),
        ("{\"bone_1\": \n {\"quat\": [0,0,0,1]", "pose.json:2"),
    ] {
        std::fs::write(&pose, text).unwrap();
        let r = rigport(&[
            "eval",
            m.to_str().unwrap(),
            s.to_str().unwrap(),
            a.to_str().unwrap(),
            "--pose",
            pose.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ]);
        let stderr = String::from_utf8_lossy(&r.stderr);
        assert_eq!(r.status.code(), Some(1), "{stderr}");
        assert!(stderr.contains(needle), "{needle:?} not in {stderr}");
        assert!(!out.exists());
    }
}

#[test]
fn usage_errors_exit_2() {
    let r = rigport(&["convert", "--max-influences", "9", "x.glb", "-o", "y.glb"]);
    assert_eq!(r.status.code(), Some(2));
    let r = rigport(&["frobnicate"]);
    assert_eq!(r.status.code(), Some(2));
}

#[test]
fn deny_warnings_exits_4_and_writes_nothing() {
    let dir = scratch();
    // Row 2 sums to 0.9996: renormalized with a warning.
    let [m, s, a] = rig(
        dir.path(),
        Some(("attachment.out", "1 0 \n0.4998 0.4998 \n0 1 \n0 1 \n")),
    );
    let out = dir.path().join("out.glb");
    let args = [
        "convert",
        m.to_str().unwrap(),
        s.to_str().unwrap(),
        a.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ];
    let mut denied = vec!["--deny-warnings"];
    denied.extend(args);
    let r = rigport(&denied);
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(4), "{stderr}");
    assert!(stderr.contains("renormalized 1 weight rows"), "{stderr}");
    assert!(!out.exists());
    // Without the flag the same input converts, with the warning printed.
    let stderr = rigport_ok(&args);
    assert!(stderr.contains("warning[W001]:"), "{stderr}");
    assert!(out.exists());
}

#[test]
fn unwritable_output_exits_3() {
    let dir = scratch();
    let [m, s, a] = rig(dir.path(), None);
    let out = dir.path().join("no/such/folder/out.glb");
    let r = rigport(&[
        "convert",
        m.to_str().unwrap(),
        s.to_str().unwrap(),
        a.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(3), "{stderr}");
    assert!(stderr.contains("out.glb"), "{stderr}");
}

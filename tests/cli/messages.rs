//! Issue 15, messages: errors name their file and place, once, with one wording per problem
//! class, and the same asset is refused the same way by every command.

use crate::common::*;

#[test]
fn no_input_is_a_usage_error() {
    let dir = scratch();
    let out = dir.path().join("out.glb");
    for args in [
        vec!["convert", "-o", out.to_str().unwrap()],
        vec!["inspect"],
        vec!["eval", "--out", "x.npz"],
    ] {
        let r = rigport(&args);
        let stderr = String::from_utf8_lossy(&r.stderr);
        assert_eq!(r.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains("<INPUTS>"), "{stderr}");
    }
    assert!(!out.exists());
}

/// The fixture Pinocchio rig with the OBJ's faces removed, in `dir`.
fn faceless_rig(dir: &std::path::Path) -> [String; 3] {
    let fixtures = repo().join("fixtures/pinocchio");
    let obj = std::fs::read_to_string(fixtures.join("branch.obj")).unwrap();
    let points: String = obj
        .lines()
        .filter(|l| !l.starts_with("f "))
        .map(|l| format!("{l}\n"))
        .collect();
    let mesh = dir.join("points.obj");
    std::fs::write(&mesh, points).unwrap();
    [
        mesh,
        fixtures.join("branch_skeleton.out"),
        fixtures.join("branch_attachment.out"),
    ]
    .map(|p| p.to_str().unwrap().to_string())
}

#[test]
fn an_obj_without_faces_is_refused_the_same_way_everywhere() {
    let dir = scratch();
    let rig = faceless_rig(dir.path());
    let expected = format!("{}: no faces: rigport needs triangles to skin", rig[0]);
    for (command, out) in [
        ("convert", "out.glb"),
        ("convert", "out.gltf"),
        ("convert", "out.usda"),
        ("eval", "out.npz"),
        ("render", "out.png"),
    ] {
        let out = dir.path().join(out);
        for inputs in [&rig[..], &rig[..1]] {
            let mut args = vec![command];
            args.extend(inputs.iter().map(String::as_str));
            args.extend(["-o", out.to_str().unwrap()]);
            let r = rigport(&args);
            let stderr = String::from_utf8_lossy(&r.stderr);
            assert_eq!(r.status.code(), Some(1), "{args:?}: {stderr}");
            assert!(stderr.contains(&expected), "{args:?}: {stderr}");
            assert!(!out.exists(), "{args:?}");
        }
    }
}

#[test]
fn a_usda_with_cr_only_line_ends_reads_as_with_lf() {
    let dir = scratch();
    let text = std::fs::read_to_string(repo().join("fixtures/usda/skinned_arm.usda")).unwrap();
    assert!(!text.contains('\r'));
    let mut outputs = Vec::new();
    for (sub, ends) in [("lf", "\n"), ("cr", "\r"), ("crlf", "\r\n")] {
        let folder = dir.path().join(sub);
        std::fs::create_dir(&folder).unwrap();
        let input = folder.join("arm.usda");
        std::fs::write(&input, text.replace('\n', ends)).unwrap();
        let out = folder.join("arm.glb");
        rigport_ok(&[
            "convert",
            input.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ]);
        outputs.push(std::fs::read(&out).unwrap());
    }
    assert_eq!(outputs[0], outputs[1], "CR-only differs from LF");
    assert_eq!(outputs[0], outputs[2], "CRLF differs from LF");
    // Line numbers count lone CRs too: a bad token on line 3.
    let bad = dir.path().join("bad.usda");
    std::fs::write(&bad, "#usda 1.0\r\rdef $\r").unwrap();
    let r = rigport(&[
        "convert",
        bad.to_str().unwrap(),
        "-o",
        dir.path().join("bad.glb").to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("bad.usda:3:5"), "{stderr}");
}

#[test]
fn a_csci520_weight_too_small_to_renormalize_names_the_weights_line() {
    let dir = scratch();
    let rig = dir.path().join("rig");
    std::fs::create_dir(&rig).unwrap();
    let fixture = repo().join("fixtures/csci520/chain");
    for entry in std::fs::read_dir(&fixture).unwrap() {
        let entry = entry.unwrap();
        std::fs::copy(entry.path(), rig.join(entry.file_name())).unwrap();
    }
    let weights = rig.join("jointWeights.txt");
    let text = std::fs::read_to_string(&weights).unwrap();
    let line = text.lines().position(|l| l == "5 1 1.0").unwrap() + 1;
    std::fs::write(&weights, text.replace("5 1 1.0", "5 1 1e-320")).unwrap();
    let out = dir.path().join("out.glb");
    let r = rigport(&[
        "convert",
        rig.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains(&format!("jointWeights.txt:{line}: ")),
        "{stderr}"
    );
    assert!(!stderr.contains("jointRestTransforms"), "{stderr}");
    assert!(!out.exists());
}

/// A quaternion of length ~1.4e38 (finite in f32, but its f32 length overflows) is a
/// rotation like any other: `[1e38, 0, 0, 1e38]` is 90 degrees about x, in POSE.json and in
/// KEYS.json alike.
#[test]
fn a_huge_but_finite_quaternion_is_normalized_not_refused() {
    let dir = scratch();
    let s = |p: &std::path::Path| p.to_str().unwrap().to_string();
    let skel = repo().join("fixtures/bvh/end_sites.bvh");
    let mut npz = Vec::new();
    for (name, quat) in [
        ("huge", "[1e38, 0, 0, 1e38]"),
        ("unit", "[0.70710678, 0, 0, 0.70710678]"),
    ] {
        let pose = dir.path().join(format!("{name}.json"));
        std::fs::write(&pose, format!(r#"{{"Head": {{"quat": {quat}}}}}"#)).unwrap();
        let out = dir.path().join(format!("{name}.npz"));
        rigport_ok(&["eval", &s(&skel), "--pose", &s(&pose), "--out", &s(&out)]);
        npz.push(read_npz(&out)["joint_world"].numbers.clone());

        let keys = dir.path().join(format!("{name}.keys.json"));
        std::fs::write(
            &keys,
            format!(
                r#"{{"name": "bend", "keys": [{{"time": 0, "pose": {{"Head": {{"quat": {quat}}}}}}}, {{"time": 1, "pose": {{}}}}]}}"#
            ),
        )
        .unwrap();
        let glb = dir.path().join(format!("{name}.glb"));
        rigport_ok(&["animate", &s(&skel), "--keys", &s(&keys), "-o", &s(&glb)]);
        assert_valid(&glb);
    }
    let max = npz[0]
        .iter()
        .zip(&npz[1])
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(
        max < 1e-6,
        "the huge quaternion poses like the unit one: {max:e}"
    );
}

/// Every number is checked by the one parser of its kind before any work: exit 2, naming
/// the flag and what is expected.
#[test]
fn bad_numbers_are_refused_by_their_one_check() {
    let dir = scratch();
    let out = dir.path().join("out.glb");
    let out = out.to_str().unwrap();
    let bvh = repo().join("fixtures/bvh/end_sites.bvh");
    let bvh = bvh.to_str().unwrap();
    for (args, message) in [
        (
            vec!["convert", bvh, "--reduce-tolerance=-1"],
            "'--reduce-tolerance [<D>]': expected a distance >= 0",
        ),
        (
            vec!["retime", bvh, "--speed", "0"],
            "'--speed <S>': expected a positive number",
        ),
        (
            vec!["retime", bvh, "--fps", "inf"],
            "'--fps <F>': expected a positive frame rate",
        ),
        (
            vec!["ik", bvh, "--handles", bvh, "--lambda=-1"],
            "'--lambda <L>': expected a number >= 0",
        ),
        (
            vec!["eval", bvh, "--fps", "0"],
            "'--fps <F>': expected a positive frame rate",
        ),
    ] {
        let mut args = args.clone();
        args.extend(["-o", out]);
        let r = rigport(&args);
        let stderr = String::from_utf8_lossy(&r.stderr);
        assert_eq!(r.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(message), "{args:?}: {stderr}");
    }
    assert!(!dir.path().join("out.glb").exists());
}

/// The input errors about flags name them (the library names the inputs; the CLI words
/// them with its flags) and exit 1.
#[test]
fn input_errors_name_the_flags() {
    let dir = scratch();
    let out = dir.path().join("out.glb");
    let out = out.to_str().unwrap();
    let fixtures = repo().join("fixtures");
    let obj = fixtures.join("pinocchio/branch.obj");
    let bvh = fixtures.join("bvh/end_sites.bvh");
    let (obj, bvh) = (obj.to_str().unwrap(), bvh.to_str().unwrap());
    for (args, message) in [
        (
            vec!["convert", "--mesh", obj, "--attachment", obj, "-o", out],
            "error: a Pinocchio rig needs a mesh, a skeleton and an attachment; missing --skeleton\n",
        ),
        (
            vec!["convert", bvh, "--amc-fps", "30", "-o", out],
            "error: --amc-fps sets the frame rate of AMC motions and needs an .asf input; to \
             resample a clip use `rigport retime --fps`\n",
        ),
        // The deprecated `convert --fps` is the same flag, with a note.
        (
            vec!["convert", bvh, "--fps", "30", "-o", out],
            "error: --amc-fps sets the frame rate of AMC motions and needs an .asf input; to \
             resample a clip use `rigport retime --fps`\n",
        ),
    ] {
        let r = rigport(&args);
        let stderr = String::from_utf8_lossy(&r.stderr);
        assert_eq!(r.status.code(), Some(1), "{args:?}: {stderr}");
        assert!(stderr.ends_with(message), "{args:?}: {stderr}");
    }
    // A frame rate that is not positive is refused by the one frame-rate check (exit 2).
    let r = rigport(&["convert", bvh, "--amc-fps", "0", "-o", out]);
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("'--amc-fps <FPS>': expected a positive frame rate"),
        "{stderr}"
    );
    let r = rigport(&["convert", bvh, "--fps", "30", "-o", out]);
    assert!(
        String::from_utf8_lossy(&r.stderr).contains("deprecated for convert"),
        "the deprecated --fps is noted"
    );
}

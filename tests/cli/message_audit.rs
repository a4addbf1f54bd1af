//! Issue 15, the message audit: every negative input we keep or can make (the failing
//! fixtures, the corpus' glTF-Validator negative tests, and one broken file per format and
//! per JSON input made here) is run through the command that reads it, and each refusal
//! must exit 1, name the file, and name a place in it: a line (`file:12`), a JSON path
//! (`at /skins/0`), a prim path (`</Root/Mesh>`) or a byte offset.

use std::path::{Path, PathBuf};

use crate::common::*;

/// A place in a file, after the file's name: `:<digits>`, ` at /`, `</`, `byte `.
fn names_a_place(message: &str, file: &str) -> bool {
    message.match_indices(file).any(|(i, _)| {
        let rest = &message[i + file.len()..];
        rest.strip_prefix(':')
            .is_some_and(|r| r.starts_with(|c: char| c.is_ascii_digit()))
            || rest.starts_with(": at /")
            || rest.starts_with(": </")
            || rest.starts_with(": byte ")
            || rest.starts_with(": at byte ")
    })
}

/// One refusal to audit: the command line and the file whose place the message must name.
struct Case {
    label: String,
    args: Vec<String>,
    file: PathBuf,
}

fn convert_case(label: &str, inputs: &[&Path], file: &Path, out: &Path) -> Case {
    let mut args = vec!["convert".to_string()];
    args.extend(inputs.iter().map(|p| p.display().to_string()));
    args.extend(["-o".to_string(), out.display().to_string()]);
    Case {
        label: label.to_string(),
        args,
        file: file.to_path_buf(),
    }
}

/// Broken files made here, one or more per format: (name, contents).
const BROKEN: &[(&str, &str)] = &[
    ("coords.obj", "v 0 0 0\nv 1 0\nv 0 1 0\nf 1 2 3\n"),
    ("face.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n"),
    ("channels.bvh", "HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0 0\n  CHANNELS 7 Xposition Yposition Zposition Zrotation Xrotation Yrotation Wrong\n}\nMOTION\nFrames: 1\nFrame Time: 0.1\n0 0 0 0 0 0\n"),
    ("values.bvh", "HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0 0\n  CHANNELS 3 Zrotation Xrotation Yrotation\n  End Site\n  {\n    OFFSET 0 1 0\n  }\n}\nMOTION\nFrames: 2\nFrame Time: 0.1\n0 0 0\n0 zero 0\n"),
    ("dof.asf", ":version 1.10\n:name x\n:units\n  length 1\n  angle deg\n:root\n  order TX TY TZ RX RY RZ\n  axis XYZ\n  position 0 0 0\n  orientation 0 0 0\n:bonedata\n  begin\n    id 1\n    name bone\n    direction 0 1 0\n    length one\n    axis 0 0 0 XYZ\n  end\n:hierarchy\n  begin\n    root bone\n  end\n"),
    ("syntax.usda", "#usda 1.0\n(\n    upAxis = \"Y\"\n)\n\ndef Xform \"Root\"\n{\n    double3 xformOp:translate = (0, 0, \n}\n"),
    ("truncated.usdc", "PXR-USDC\u{0}\u{0}\u{0}\u{0}\u{0}\u{0}\u{0}\u{0}\u{0}\u{0}\u{0}\u{0}\u{0}\u{0}"),
    ("json.gltf", "{\"asset\": {\"version\": \"2.0\"},\n \"nodes\": [ {\"name\": \"a\", } ]\n}\n"),
    ("index.gltf", "{\"asset\": {\"version\": \"2.0\"}, \"scenes\": [{\"nodes\": [3]}], \"nodes\": [{}]}\n"),
];

#[test]
fn every_refusal_names_its_file_and_a_place_in_it() {
    let dir = scratch();
    let out = dir.path().join("out.glb");
    let fixtures = repo().join("fixtures");
    let mut cases = Vec::new();

    // Kept inputs: every fixture and corpus negative test that the reader refuses.
    let mut kept: Vec<PathBuf> = Vec::new();
    for sub in ["bvh", "usda", "gltf", "asf_amc", "usdc"] {
        for entry in std::fs::read_dir(fixtures.join(sub)).unwrap() {
            let p = entry.unwrap().path();
            let ext = p.extension().and_then(|e| e.to_str()).unwrap_or("");
            if ["bvh", "usda", "usdc", "usdz", "gltf", "glb", "asf"].contains(&ext) {
                kept.push(p);
            }
        }
    }
    if let Some(negatives) = corpus("5_gltf/validator_negative_tests__KhronosGroup") {
        for group in std::fs::read_dir(negatives).unwrap() {
            let group = group.unwrap().path();
            if !group.is_dir() {
                continue;
            }
            for entry in std::fs::read_dir(group).unwrap() {
                let p = entry.unwrap().path();
                if p.extension().is_some_and(|e| e == "gltf" || e == "glb") {
                    kept.push(p);
                }
            }
        }
    }
    kept.sort();
    for p in &kept {
        let label = p.file_name().unwrap().to_string_lossy().to_string();
        cases.push(convert_case(&label, &[p], p, &out));
    }
    for config in std::fs::read_dir(fixtures.join("csci520/variants")).unwrap() {
        let config = config.unwrap().path();
        cases.push(convert_case(
            &config.display().to_string(),
            &[&config],
            &config,
            &out,
        ));
    }

    // Broken files made here.
    for (name, text) in BROKEN {
        let p = dir.path().join(name);
        std::fs::write(&p, text).unwrap();
        if name.ends_with(".obj") {
            // An OBJ alone is a mesh without a rig; with the fixture Pinocchio files it is
            // the rig's mesh.
            let pino = fixtures.join("pinocchio");
            let skeleton = pino.join("branch_skeleton.out");
            let attachment = pino.join("branch_attachment.out");
            let mut case = convert_case(name, &[&p], &p, &out);
            case.args.splice(
                1..2,
                [
                    "--mesh".to_string(),
                    p.display().to_string(),
                    "--skeleton".to_string(),
                    skeleton.display().to_string(),
                    "--attachment".to_string(),
                    attachment.display().to_string(),
                ],
            );
            cases.push(case);
        } else {
            cases.push(convert_case(name, &[&p], &p, &out));
        }
    }
    // Values that overflow f32 in a good USD file: a texture coordinate and a point.
    let arm = std::fs::read_to_string(fixtures.join("usda/skinned_arm.usda")).unwrap();
    for (name, from, to) in [
        (
            "st_overflow.usda",
            "(0.5, 1.2), (0, 1)]",
            "(0.5, 1e39), (0, 1)]",
        ),
        ("point_overflow.usda", "(0.5, 5, 0)]", "(0.5, 5e39, 0)]"),
    ] {
        assert!(arm.contains(from), "fixture changed: {from}");
        let p = dir.path().join(name);
        std::fs::write(&p, arm.replace(from, to)).unwrap();
        cases.push(convert_case(name, &[&p], &p, &out));
    }
    // A broken AMC for a good ASF.
    let asf = fixtures.join("asf_amc/chain.asf");
    let amc = dir.path().join("frame.amc");
    std::fs::write(
        &amc,
        ":FULLY-SPECIFIED\n:DEGREES\n1\nroot 0 0 0 0 0 0\n2\nroot 0 0 zero 0 0 0\n",
    )
    .unwrap();
    cases.push(convert_case("frame.amc", &[&asf, &amc], &amc, &out));
    // Broken Pinocchio skeleton and attachment.
    let pino = fixtures.join("pinocchio");
    let skeleton = dir.path().join("skeleton.out");
    std::fs::write(&skeleton, "0 0 0 0 -1\n1 0 1 zero 0\n").unwrap();
    cases.push(convert_case(
        "skeleton.out",
        &[
            &pino.join("branch.obj"),
            &skeleton,
            &pino.join("branch_attachment.out"),
        ],
        &skeleton,
        &out,
    ));

    // The JSON inputs, through the commands that read them.
    let bvh = fixtures.join("bvh/end_sites.bvh");
    let json_cases: [(&str, &str, &str, &str); 3] = [
        ("pose.json", "eval", "--pose", "{\"Head\": {\"quat\": [0, 0, 0]}}"),
        ("keys.json", "animate", "--keys", "{\"keys\": [{\"time\": -1, \"pose\": {}}]}"),
        ("handles.json", "ik", "--handles", "{\"handles\": [{\"joint\": \"Nobody\", \"keys\": [{\"time\": 0, \"position\": [0, 0, 0]}]}]}"),
    ];
    for (name, command, flag, text) in json_cases {
        let p = dir.path().join(name);
        std::fs::write(&p, text).unwrap();
        let target = if command == "eval" {
            dir.path().join("out.npz")
        } else {
            out.clone()
        };
        let out_flag = if command == "eval" { "--out" } else { "-o" };
        cases.push(Case {
            label: name.to_string(),
            args: [
                command,
                &bvh.display().to_string(),
                flag,
                &p.display().to_string(),
                out_flag,
                &target.display().to_string(),
            ]
            .map(String::from)
            .to_vec(),
            file: p,
        });
    }

    let mut refused = 0;
    let mut problems = Vec::new();
    for case in &cases {
        let args: Vec<&str> = case.args.iter().map(String::as_str).collect();
        let _ = std::fs::remove_file(&out);
        let r = rigport(&args);
        let stderr = String::from_utf8_lossy(&r.stderr).to_string();
        if r.status.success() {
            continue; // a fixture that converts (with or without warnings) is not a refusal
        }
        refused += 1;
        let file = case.file.display().to_string();
        if r.status.code() != Some(1) {
            problems.push(format!(
                "{}: exit {:?}: {stderr}",
                case.label,
                r.status.code()
            ));
        } else if !names_a_place(&stderr, &file) {
            problems.push(format!("{}: no place in {file}: {stderr}", case.label));
        }
        if out.exists() {
            problems.push(format!(
                "{}: wrote {} after refusing",
                case.label,
                out.display()
            ));
        }
    }
    eprintln!("audited {refused} refusals of {} cases", cases.len());
    assert!(refused >= 20, "the audit ran {refused} refusals only");
    assert!(
        problems.is_empty(),
        "{} messages fail the audit:\n{}",
        problems.len(),
        problems.join("\n")
    );
}

/// Issue 14, item 5: every text importer words a bad number the same way, at the number's
/// line and column: `<file>:<line>:<column>: <what> "<token>" is not a number` (or `is not
/// finite`, `is out of range for <type>`), whatever the format; and line numbers count LF,
/// CRLF and a lone CR alike.
#[test]
fn bad_numbers_read_the_same_in_every_text_format() {
    let dir = scratch();
    let out = dir.path().join("out.glb");
    let fixtures = repo().join("fixtures");
    let pino = fixtures.join("pinocchio");
    let chain = fixtures.join("csci520/chain");
    let write = |name: &str, text: &str| {
        let p = dir.path().join(name);
        std::fs::write(&p, text).unwrap();
        p
    };
    let bvh_text = |eol: &str, value: &str| {
        [
            "HIERARCHY",
            "ROOT Hips",
            "{",
            "  OFFSET 0 0 0",
            "  CHANNELS 3 Zrotation Xrotation Yrotation",
            "  End Site",
            "  {",
            "    OFFSET 0 1 0",
            "  }",
            "}",
            "MOTION",
            "Frames: 2",
            "Frame Time: 0.1",
            "0 0 0",
            &format!("0 {value} 0"),
            "",
        ]
        .join(eol)
    };
    // (case, the file to blame, the command line, what the message must hold after the
    // file's name).
    let mut cases: Vec<(&str, PathBuf, Vec<String>, &str)> = Vec::new();
    let convert = |inputs: &[&Path]| {
        let mut args = vec!["convert".to_string()];
        args.extend(inputs.iter().map(|p| p.display().to_string()));
        args.extend(["-o".to_string(), out.display().to_string()]);
        args
    };
    for (name, eol) in [("lf.bvh", "\n"), ("crlf.bvh", "\r\n"), ("cr.bvh", "\r")] {
        let p = write(name, &bvh_text(eol, "zero"));
        cases.push((
            name,
            p.clone(),
            convert(&[&p]),
            ":15:3: motion value \"zero\" is not a number",
        ));
    }
    let p = write("nan.bvh", &bvh_text("\n", "NaN"));
    cases.push((
        "nan.bvh",
        p.clone(),
        convert(&[&p]),
        ":15:3: motion value \"NaN\" is not finite",
    ));
    let p = write("big.obj", "v 0 0 0\nv 1 0 1e39\nv 0 1 0\nf 1 2 3\n");
    cases.push((
        "big.obj",
        p.clone(),
        convert(&[&p]),
        ":2:7: coordinate \"1e39\" is out of range for f32",
    ));
    let p = write("zero_skeleton.out", "0 0 0 0 -1\n1 0 1 zero 0\n");
    let args = convert(&[
        &pino.join("branch.obj"),
        &p,
        &pino.join("branch_attachment.out"),
    ]);
    cases.push((
        "skeleton.out",
        p,
        args,
        ":2:7: coordinate \"zero\" is not a number",
    ));
    let attachment = std::fs::read_to_string(pino.join("branch_attachment.out")).unwrap();
    let mut rows: Vec<String> = attachment.lines().map(String::from).collect();
    let last = rows.len() - 1;
    rows[last] = format!("{} x", rows[last].trim_end());
    let p = write("x_attachment.out", &rows.join("\r\n"));
    let args = convert(&[
        &pino.join("branch.obj"),
        &pino.join("branch_skeleton.out"),
        &p,
    ]);
    let expected_x = format!(":{}:", last + 1);
    cases.push(("attachment.out", p, args, "weight \"x\" is not a number"));
    // A CSCI 520 folder whose weights file has an entry with a bad weight.
    let rig = dir.path().join("rig");
    std::fs::create_dir_all(&rig).unwrap();
    for entry in std::fs::read_dir(&chain).unwrap() {
        let entry = entry.unwrap().path();
        std::fs::copy(&entry, rig.join(entry.file_name().unwrap())).unwrap();
    }
    let weights = rig.join("jointWeights.txt");
    let text = std::fs::read_to_string(&weights).unwrap();
    std::fs::write(&weights, text.replacen("0 2 1.0", "0 2 1.0e999", 1)).unwrap();
    let args = convert(&[&rig.join("skin.config")]);
    cases.push((
        "jointWeights.txt",
        weights,
        args,
        ":2:5: weight \"1.0e999\" is out of range for f64",
    ));
    let amc = write(
        "bad.amc",
        ":FULLY-SPECIFIED\n:DEGREES\n1\nroot 0 0 0 0 0 inf\n",
    );
    let args = convert(&[&fixtures.join("asf_amc/chain.asf"), &amc]);
    cases.push((
        "bad.amc",
        amc,
        args,
        ":4:16: dof value \"inf\" is not finite",
    ));

    let mut problems = Vec::new();
    for (label, file, args, expected) in &cases {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let r = rigport(&args);
        let stderr = String::from_utf8_lossy(&r.stderr).to_string();
        let file = file.display().to_string();
        let at_file = stderr.find(&file).map(|i| &stderr[i + file.len()..]);
        let ok = r.status.code() == Some(1)
            && at_file.is_some_and(|rest| {
                if *label == "attachment.out" {
                    rest.starts_with(&expected_x) && rest.contains(expected)
                } else {
                    rest.starts_with(expected)
                }
            });
        if !ok {
            problems.push(format!(
                "{label}: expected {file}{expected}, got {:?}: {stderr}",
                r.status.code()
            ));
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

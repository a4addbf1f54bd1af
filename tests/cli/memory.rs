//! Issue 15, memory: requests are estimated and checked against the budget
//! (`--max-memory`, default 3/4 of the memory the process may use) before they allocate,
//! and refused with exit 1, a message naming the size and the limit, and no output.

use std::path::{Path, PathBuf};

use crate::common::*;

/// A one-bone ASF and an AMC of `frames` frames in `dir`.
fn long_motion(dir: &Path, frames: usize) -> (PathBuf, PathBuf) {
    let asf = dir.join("one.asf");
    std::fs::write(
        &asf,
        ":version 1.10\n:name one\n:units\n  length 1.0\n  angle deg\n:root\n  order TX TY TZ RX RY RZ\n  axis XYZ\n  position 0 0 0\n  orientation 0 0 0\n:bonedata\n  begin\n    id 1\n    name bone\n    direction 0 1 0\n    length 1\n    axis 0 0 0 XYZ\n    dof rx ry rz\n  end\n:hierarchy\n  begin\n    root bone\n  end\n",
    )
    .unwrap();
    let mut amc = String::from(":FULLY-SPECIFIED\n:DEGREES\n");
    for i in 1..=frames {
        amc.push_str(&format!(
            "{i}\nroot 0 0 0 0 0 {}\nbone {} 0 0\n",
            i % 90,
            i % 45
        ));
    }
    let amc_path = dir.join("long.amc");
    std::fs::write(&amc_path, amc).unwrap();
    (asf, amc_path)
}

fn refused(args: &[&str], out: &Path, limit: &str) {
    let r = rigport(args);
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(1), "{args:?}: {stderr}");
    assert!(
        stderr.contains("needs about") && stderr.contains(&format!("limit of {limit}")),
        "the message names the size and the limit: {stderr}"
    );
    assert!(stderr.contains("--max-memory"), "{stderr}");
    assert!(!out.exists(), "no output after a refusal");
}

#[test]
fn a_long_motion_over_the_budget_is_refused_before_it_allocates() {
    let dir = scratch();
    let (asf, amc) = long_motion(dir.path(), 100_000);
    let s = |p: &Path| p.to_str().unwrap().to_string();
    let usda = dir.path().join("long.usda");
    refused(
        &[
            "convert",
            &s(&asf),
            &s(&amc),
            "-o",
            &s(&usda),
            "--max-memory",
            "50M",
        ],
        &usda,
        "50.0 MB",
    );
    // eval streams its frames to the file (memory does not grow with the frame count), so
    // the same motion fits a small budget; below what it holds, it is still refused.
    let npz = dir.path().join("long.npz");
    let eval = |budget: &str| {
        vec![
            "eval".to_string(),
            s(&asf),
            s(&amc),
            "--out".into(),
            s(&npz),
            "--max-memory".into(),
            budget.into(),
        ]
    };
    let args = eval("30M");
    refused(
        &args.iter().map(String::as_str).collect::<Vec<_>>(),
        &npz,
        "30.0 MB",
    );
    let args = eval("100M");
    rigport_ok(&args.iter().map(String::as_str).collect::<Vec<_>>());
    let dump = read_npz(&npz);
    assert_eq!(dump["times"].shape, [100_000]);
    let joints = dump["joint_names"].shape[0];
    assert_eq!(dump["joint_world"].shape, [100_000, joints, 4, 4]);
    assert_eq!(dump["skin_matrices"].shape, [100_000, joints, 4, 4]);
    // Frame i of the AMC turns the root by i % 90 degrees about z: its world matrix's
    // first row starts with cos.
    let last = &dump["joint_world"].numbers[99_999 * joints * 16..];
    let angle = (100_000 % 90) as f64;
    assert!(
        (last[0] - angle.to_radians().cos()).abs() < 1e-5,
        "{}",
        last[0]
    );
    std::fs::remove_file(&npz).unwrap();
    // Reading alone: about five times the input's size.
    let glb = dir.path().join("long.glb");
    refused(
        &[
            "convert",
            &s(&asf),
            &s(&amc),
            "-o",
            &s(&glb),
            "--max-memory",
            "5M",
        ],
        &glb,
        "5.0 MB",
    );
    // Within the budget, the same requests succeed.
    rigport_ok(&[
        "convert",
        "-q",
        &s(&asf),
        &s(&amc),
        "-o",
        &s(&usda),
        "--max-memory",
        "1G",
    ]);
    assert!(usda.exists());
}

#[test]
fn max_memory_takes_sizes_and_refuses_nonsense() {
    let dir = scratch();
    let out = dir.path().join("x.glb");
    let bvh = repo().join("fixtures/bvh/end_sites.bvh");
    for ok in ["2G", "1.5GiB", "500M", "100000000"] {
        rigport_ok(&[
            "convert",
            "-q",
            bvh.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--max-memory",
            ok,
        ]);
    }
    for bad in ["0", "lots", "-1G", "2 X"] {
        let r = rigport(&[
            "convert",
            bvh.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--max-memory",
            bad,
        ]);
        assert_eq!(r.status.code(), Some(2), "--max-memory {bad}");
    }
}

/// An address-space limit (`ulimit -v`) lowers the default budget: the run is refused
/// with a message instead of aborting when an allocation fails.
#[test]
fn the_default_budget_follows_an_address_space_limit() {
    if std::process::Command::new("prlimit")
        .arg("--version")
        .output()
        .is_err()
    {
        eprintln!("SKIPPED: prlimit (util-linux) is not installed");
        return;
    }
    let dir = scratch();
    let (asf, amc) = long_motion(dir.path(), 200_000);
    let usda = dir.path().join("long.usda");
    let out = std::process::Command::new("prlimit")
        .arg("--as=200000000")
        .arg(env!("CARGO_BIN_EXE_rigport"))
        .args([
            "convert",
            asf.to_str().unwrap(),
            amc.to_str().unwrap(),
            "-o",
        ])
        .arg(&usda)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("limit of 150.0 MB (default: 3/4"),
        "{stderr}"
    );
    assert!(!usda.exists());
}

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
    let mut prlimit = std::process::Command::new("prlimit");
    prlimit.arg("--as=200000000");
    refused_under_150_mb(prlimit);
}

/// Runs `wrapper rigport convert` of a 200,000-frame motion to `.usda` (the wrapper limits
/// the memory to 200 MB and execs the rest of its arguments) and checks the refusal: exit
/// 1, the default budget of 150.0 MB named, no output.
fn refused_under_150_mb(mut wrapper: std::process::Command) {
    let dir = scratch();
    let (asf, amc) = long_motion(dir.path(), 200_000);
    let usda = dir.path().join("long.usda");
    let out = wrapper
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

/// A memory cgroup's limit lowers the default budget (cgroup v1 `memory.limit_in_bytes`,
/// or v2 `memory.max`, of the process's own cgroup): the run is refused with a message
/// instead of being killed by the kernel. Needs a writable cgroup file system (root);
/// skips otherwise.
#[test]
fn the_default_budget_follows_a_cgroup_memory_limit() {
    let name = format!("rigport-test-{}", std::process::id());
    let v1 = Path::new("/sys/fs/cgroup/memory");
    let v2 = Path::new("/sys/fs/cgroup");
    let (group, limit_file) = if v1.join("memory.limit_in_bytes").exists() {
        (v1.join(&name), "memory.limit_in_bytes")
    } else if std::fs::read_to_string(v2.join("cgroup.subtree_control"))
        .is_ok_and(|c| c.split_whitespace().any(|c| c == "memory"))
    {
        (v2.join(&name), "memory.max")
    } else {
        eprintln!("SKIPPED: no memory cgroup controller to make a group in");
        return;
    };
    if std::fs::create_dir(&group).is_err()
        || std::fs::write(group.join(limit_file), "200000000").is_err()
    {
        let _ = std::fs::remove_dir(&group);
        eprintln!("SKIPPED: cannot make a memory cgroup (not root?)");
        return;
    }
    /// Removes the group when the test ends, passed or failed.
    struct Group(std::path::PathBuf);
    impl Drop for Group {
        fn drop(&mut self) {
            let _ = std::fs::remove_dir(&self.0);
        }
    }
    let group = Group(group);
    let mut sh = std::process::Command::new("sh");
    sh.arg("-c")
        .arg("echo $$ > \"$0/cgroup.procs\" && exec \"$@\"")
        .arg(&group.0);
    // The kernel rounds the limit down to pages: 199,999,488 bytes, 3/4 of it 150.0 MB.
    refused_under_150_mb(sh);
}

/// Runs `rigport args` with `env` and returns its exit code (`None` when killed), its peak
/// resident memory in bytes as the kernel measured it for that one process (`wait4`, from
/// Python, since this crate forbids `unsafe`), and its stderr; `None` without `python3`.
fn run_measured(args: &[&str], env: &[(&str, &str)]) -> Option<(Option<i32>, u64, String)> {
    const WAIT4: &str = "import os, subprocess, sys\n\
p = subprocess.Popen(sys.argv[2:], stdout=subprocess.DEVNULL, stderr=open(sys.argv[1], 'w'))\n\
_, status, usage = os.wait4(p.pid, 0)\n\
print(os.waitstatus_to_exitcode(status), usage.ru_maxrss)\n";
    let dir = scratch();
    let err_path = dir.path().join("stderr");
    let out = std::process::Command::new("python3")
        .arg("-c")
        .arg(WAIT4)
        .arg(&err_path)
        .arg(env!("CARGO_BIN_EXE_rigport"))
        .args(args)
        .envs(env.iter().copied())
        .output();
    let out = match out {
        Ok(out) if out.status.success() => out,
        other => {
            assert!(std::env::var_os("CI").is_none(), "python3: {other:?}");
            eprintln!("SKIPPED: python3 is needed to measure a child's peak memory");
            return None;
        }
    };
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    let mut fields = text.split_whitespace();
    let code: i32 = fields.next().unwrap().parse().unwrap();
    // Linux reports ru_maxrss in KiB.
    let peak: u64 = fields.next().unwrap().parse::<u64>().unwrap() * 1024;
    let stderr = std::fs::read_to_string(err_path).unwrap();
    Some(((code >= 0).then_some(code), peak, stderr))
}

/// A `.usda` text longer than the writer's spill size is streamed to its file as it is
/// built: the same bytes as one built in memory, at a peak lower by most of the text.
/// (The spill size is 64 MiB; `RIGPORT_TEST_USD_SPILL_BYTES` lowers it so a debug build
/// shows it on a small clip.)
#[test]
fn a_long_usd_text_is_streamed_not_held() {
    let dir = scratch();
    let (asf, amc) = long_motion(dir.path(), 150_000);
    let s = |p: &Path| p.to_str().unwrap().to_string();
    let streamed = dir.path().join("streamed.usda");
    let held = dir.path().join("held.usda");
    let run = |out: &Path, spill: &str| {
        let (code, peak, stderr) = run_measured(
            &["convert", "-q", &s(&asf), &s(&amc), "-o", &s(out)],
            &[("RIGPORT_TEST_USD_SPILL_BYTES", spill)],
        )?;
        assert_eq!(code, Some(0), "{stderr}");
        Some(peak)
    };
    let Some(peak_streamed) = run(&streamed, "1000000") else {
        return;
    };
    let Some(peak_held) = run(&held, "1000000000000") else {
        return;
    };
    let text = std::fs::read(&streamed).unwrap();
    assert!(
        text == std::fs::read(&held).unwrap(),
        "streaming changes no byte"
    );
    let len = text.len() as u64;
    assert!(len > 20_000_000, "a text of {len} bytes");
    eprintln!("{len} bytes of USD text: peak {peak_streamed} bytes streamed, {peak_held} held");
    assert!(
        peak_streamed + len / 2 < peak_held,
        "streamed peak {peak_streamed} not below the held peak {peak_held} by half the text ({len})"
    );
    let names: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert!(names.iter().all(|n| !n.ends_with(".tmp")), "{names:?}");
}

/// Issue 15's case, an ASF with one bone and an AMC of 10^7 frames (375 MB): to `.usda`
/// (a 1.86 GB file) it succeeds within 2 GB of memory, and `eval` either succeeds within
/// 2 GB or is refused with exit 1 naming the size and the limit; never an abort. Minutes in
/// a release build, so not in the default run:
/// `cargo test --release --test cli memory::ten_million -- --ignored --nocapture`.
#[test]
#[ignore = "minutes and 3 GB of disk; run with --ignored in a release build"]
fn ten_million_frames_within_two_gigabytes() {
    let dir = scratch();
    let (asf, amc) = long_motion(dir.path(), 10_000_000);
    let s = |p: &Path| p.to_str().unwrap().to_string();
    let usda = dir.path().join("long.usda");
    let Some((code, peak, stderr)) =
        run_measured(&["convert", "-q", &s(&asf), &s(&amc), "-o", &s(&usda)], &[])
    else {
        return;
    };
    let len = std::fs::metadata(&usda).map(|m| m.len()).unwrap_or(0);
    eprintln!("convert -> .usda: exit {code:?}, peak {peak} bytes, file {len} bytes");
    assert_eq!(code, Some(0), "{stderr}");
    assert!(peak < 2_000_000_000, "peak {peak} bytes");
    let text = std::fs::read_to_string(&usda).unwrap();
    assert!(
        text.contains("    10000000: ["),
        "the last frame's samples are written"
    );
    drop(text);
    std::fs::remove_file(&usda).unwrap();
    let npz = dir.path().join("long.npz");
    let Some((code, peak, stderr)) =
        run_measured(&["eval", &s(&asf), &s(&amc), "--out", &s(&npz)], &[])
    else {
        return;
    };
    eprintln!("eval -> .npz: exit {code:?}, peak {peak} bytes: {stderr}");
    match code {
        Some(0) => assert!(peak < 2_000_000_000, "peak {peak} bytes"),
        Some(1) => assert!(
            stderr.contains("needs about") && stderr.contains("limit of"),
            "{stderr}"
        ),
        other => panic!("eval ended with {other:?}: {stderr}"),
    }
}

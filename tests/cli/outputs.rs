//! Issue 15, outputs: only regular files are replaced (exit 3 otherwise, the special file
//! untouched), an output that is one of the inputs is a usage error (exit 2), output
//! extensions are checked by every command (exit 2), symbolic links are followed and their
//! target replaced (a .gltf link is refused), exit-3 messages name the file once, and no temporary file outlives an
//! interrupted run or (swept on the next write) a killed one.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use crate::common::*;

/// The fixture Pinocchio rig: mesh, skeleton, attachment.
fn rig() -> [String; 3] {
    let dir = repo().join("fixtures/pinocchio");
    ["branch.obj", "branch_skeleton.out", "branch_attachment.out"]
        .map(|f| dir.join(f).to_str().unwrap().to_string())
}

/// `rigport <command> <rig> -o <out>` (eval: `--out`).
fn run_on_rig(command: &str, out: &Path) -> (Option<i32>, String) {
    let rig = rig();
    let mut args: Vec<&str> = vec![command];
    args.extend(rig.iter().map(String::as_str));
    args.extend(["-o", out.to_str().unwrap()]);
    let r = rigport(&args);
    (
        r.status.code(),
        String::from_utf8_lossy(&r.stderr).into_owned(),
    )
}

/// The names in `dir`, sorted.
fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn a_directory_as_output_exits_3_and_stays() {
    let dir = scratch();
    for name in ["out.glb", "out.gltf", "out.usda", "out.npz"] {
        let out = dir.path().join(name);
        std::fs::create_dir(&out).unwrap();
        let command = if name.ends_with("npz") {
            "eval"
        } else {
            "convert"
        };
        let (code, stderr) = run_on_rig(command, &out);
        assert_eq!(code, Some(3), "{name}: {stderr}");
        assert!(stderr.contains("not a regular file"), "{stderr}");
        assert!(out.is_dir());
    }
    // The .bin beside a .gltf is checked before anything is written.
    std::fs::create_dir(dir.path().join("split.bin")).unwrap();
    let (code, stderr) = run_on_rig("convert", &dir.path().join("split.gltf"));
    assert_eq!(code, Some(3), "{stderr}");
    assert!(stderr.contains("split.bin"), "{stderr}");
    assert!(!dir.path().join("split.gltf").exists());
}

#[cfg(unix)]
#[test]
fn a_fifo_or_device_as_output_exits_3_and_stays() {
    use std::os::unix::fs::FileTypeExt as _;
    let dir = scratch();
    let fifo = dir.path().join("pipe.glb");
    let made = Command::new("mkfifo").arg(&fifo).status();
    if require("mkfifo", made.ok().filter(|s| s.success())).is_some() {
        let (code, stderr) = run_on_rig("convert", &fifo);
        assert_eq!(code, Some(3), "{stderr}");
        assert!(stderr.contains("fifo"), "{stderr}");
        assert!(std::fs::symlink_metadata(&fifo)
            .unwrap()
            .file_type()
            .is_fifo());
    }
    // A character device (the numbers of /dev/full), made in the scratch folder: making
    // one needs root, so without it the test is skipped.
    let device = dir.path().join("full.npz");
    let made = Command::new("mknod")
        .arg(&device)
        .args(["c", "1", "7"])
        .stderr(Stdio::null())
        .status();
    if made.is_ok_and(|s| s.success()) {
        let (code, stderr) = run_on_rig("eval", &device);
        assert_eq!(code, Some(3), "{stderr}");
        assert!(stderr.contains("character device"), "{stderr}");
        assert!(std::fs::symlink_metadata(&device)
            .unwrap()
            .file_type()
            .is_char_device());
    } else {
        eprintln!("SKIPPED: mknod needs root");
    }
    assert!(names(dir.path()).iter().all(|n| !n.ends_with(".tmp")));
}

#[test]
fn an_output_that_is_an_input_exits_2_and_writes_nothing() {
    let dir = scratch();
    let glb = dir.path().join("same.glb");
    let s = |p: &PathBuf| p.to_str().unwrap().to_string();
    run_on_rig("convert", &glb);
    let before = std::fs::read(&glb).unwrap();
    let mut others = vec![glb.clone()];
    #[cfg(unix)]
    {
        let link = dir.path().join("link.glb");
        std::os::unix::fs::symlink("same.glb", &link).unwrap();
        others.push(link);
    }
    let hard = dir.path().join("hard.glb");
    std::fs::hard_link(&glb, &hard).unwrap();
    others.push(hard);
    for other in &others {
        for (input, output) in [(&glb, other), (other, &glb)] {
            let r = rigport(&["convert", &s(input), "-o", &s(output)]);
            let stderr = String::from_utf8_lossy(&r.stderr);
            assert_eq!(
                r.status.code(),
                Some(2),
                "{input:?} -> {output:?}: {stderr}"
            );
            assert!(stderr.contains("one of the inputs"), "{stderr}");
            assert_eq!(std::fs::read(&glb).unwrap(), before);
        }
    }
    // Any input counts: a Pinocchio file, a keys file.
    let rig = rig();
    let mesh_copy = dir.path().join("mesh.obj");
    std::fs::copy(&rig[0], &mesh_copy).unwrap();
    let keys = dir.path().join("keys.gltf");
    std::fs::write(&keys, "{\"keys\": []}").unwrap();
    let r = rigport(&[
        "animate",
        &s(&mesh_copy),
        &rig[1],
        &rig[2],
        "--keys",
        &s(&keys),
        "-o",
        &s(&keys),
    ]);
    assert_eq!(r.status.code(), Some(2));
    assert_eq!(std::fs::read_to_string(&keys).unwrap(), "{\"keys\": []}");
    let names = names(dir.path());
    assert!(names.iter().all(|n| !n.ends_with(".tmp")), "{names:?}");
}

#[test]
fn every_command_checks_its_output_extension() {
    let dir = scratch();
    let rig = rig();
    let out = |name: &str| dir.path().join(name).to_str().unwrap().to_string();
    let cases: [(&str, String, &str); 5] = [
        ("eval", out("dump.txt"), ".npz"),
        ("convert", out("model.obj"), ".glb"),
        ("render", out("sheet.jpg"), ".png"),
        ("bake", out("baked.usda"), "glTF"),
        ("convert", out("noext"), ".glb"),
    ];
    for (command, output, needle) in cases {
        let mut args = vec![command];
        args.extend(rig.iter().map(String::as_str));
        args.extend(["-o", &output]);
        if command == "bake" {
            args.extend(["--skinning", "dqs"]);
        }
        let r = rigport(&args);
        let stderr = String::from_utf8_lossy(&r.stderr);
        assert_eq!(r.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(needle), "{args:?}: {stderr}");
    }
    assert!(names(dir.path()).is_empty());
}

#[cfg(unix)]
#[test]
fn a_symlink_is_followed_and_its_target_replaced() {
    let dir = scratch();
    std::fs::create_dir(dir.path().join("real")).unwrap();
    let target = dir.path().join("real/model.glb");
    std::fs::write(&target, b"old").unwrap();
    let link = dir.path().join("link.glb");
    std::os::unix::fs::symlink("real/model.glb", &link).unwrap();
    let (code, stderr) = run_on_rig("convert", &link);
    assert_eq!(code, Some(0), "{stderr}");
    assert!(std::fs::symlink_metadata(&link).unwrap().is_symlink());
    assert_eq!(&std::fs::read(&target).unwrap()[..4], b"glTF");
    // A .gltf through a link is refused: readers find its .bin relative to the path they
    // open, so no place for the .bin suits both the link and its target.
    let gltf_link = dir.path().join("split.gltf");
    std::os::unix::fs::symlink("real/split_target.gltf", &gltf_link).unwrap();
    let (code, stderr) = run_on_rig("convert", &gltf_link);
    assert_eq!(code, Some(3), "{stderr}");
    assert!(stderr.contains("symbolic link"), "{stderr}");
    assert_eq!(names(&dir.path().join("real")), ["model.glb"]);
    assert_eq!(names(dir.path()), ["link.glb", "real", "split.gltf"]);
}

#[test]
fn exit_3_messages_name_the_file_once() {
    let dir = scratch();
    for name in ["out.glb", "out.gltf", "out.usda", "out.npz"] {
        let out = dir.path().join("no/such/folder").join(name);
        let command = if name.ends_with("npz") {
            "eval"
        } else {
            "convert"
        };
        let (code, stderr) = run_on_rig(command, &out);
        assert_eq!(code, Some(3), "{stderr}");
        assert_eq!(stderr.matches("cannot write").count(), 1, "{stderr}");
        assert_eq!(stderr.matches(name).count(), 1, "{stderr}");
    }
}

/// Starts `command` (writing `out_name`) with every rename delayed, waits for its
/// temporary file, sends `signal`, and checks the exit code and that nothing is left.
#[cfg(unix)]
fn interrupt_while_writing(command: &str, out_name: &str, signal: &str, code: i32) {
    let dir = scratch();
    let out = dir.path().join(out_name);
    let mut child = Command::new(env!("CARGO_BIN_EXE_rigport"))
        .arg(command)
        .args(rig())
        .arg("-o")
        .arg(&out)
        .env("RIGPORT_TEST_RENAME_DELAY_MS", "30000")
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    loop {
        if names(dir.path()).iter().any(|n| n.ends_with(".tmp")) {
            break;
        }
        if let Some(status) = child.try_wait().unwrap() {
            panic!("rigport ended ({status}) before writing a temporary file");
        }
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "no temporary file appeared"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    let killed = Command::new("kill")
        .args([signal, &child.id().to_string()])
        .status()
        .unwrap();
    assert!(killed.success());
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(code), "{command} {signal}: {status}");
    assert_eq!(
        names(dir.path()),
        Vec::<String>::new(),
        "{command} {signal}"
    );
}

#[cfg(unix)]
#[test]
fn sigterm_removes_temp_files_and_exits_143() {
    interrupt_while_writing("convert", "out.gltf", "-TERM", 143);
    // eval streams its `.npz` into the temporary file: the same registry removes it.
    interrupt_while_writing("eval", "out.npz", "-TERM", 143);
}

#[cfg(unix)]
#[test]
fn sigint_removes_temp_files_and_exits_130() {
    interrupt_while_writing("convert", "out.gltf", "-INT", 130);
    interrupt_while_writing("eval", "out.npz", "-INT", 130);
}

#[test]
fn stale_temp_files_of_dead_processes_are_swept() {
    if !Path::new("/proc/self").exists() {
        eprintln!("SKIPPED: no /proc (the sweep is Linux only)");
        return;
    }
    let dir = scratch();
    // Left by killed runs: pids above Linux's maximum (4194304) never run.
    for stale in [".out.glb.99999999.0.tmp", ".other.usda.88888888.12.tmp"] {
        std::fs::write(dir.path().join(stale), b"partial").unwrap();
    }
    // Not of our naming: kept.
    std::fs::write(dir.path().join(".notes.99999999.tmp"), b"mine").unwrap();
    let (code, stderr) = run_on_rig("convert", &dir.path().join("out.glb"));
    assert_eq!(code, Some(0), "{stderr}");
    assert_eq!(names(dir.path()), [".notes.99999999.tmp", "out.glb"]);
}

//! `rigport batch` and `batch-report` (issue 21): a whole-corpus manifest, shards equal to
//! one run, resume, a killed run resumed, manifest errors, exit codes.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use crate::common::{corpus, repo, rigport, scratch};

/// Every file under `dir` (relative path -> bytes), reports left out (their `seconds`
/// vary).
fn files(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    fn walk(root: &Path, dir: &Path, out: &mut BTreeMap<String, Vec<u8>>) {
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                walk(root, &path, out);
            } else {
                let rel = path.strip_prefix(root).unwrap().display().to_string();
                if !rel.ends_with(".jsonl") {
                    out.insert(rel, std::fs::read(&path).unwrap());
                }
            }
        }
    }
    let mut out = BTreeMap::new();
    walk(dir, dir, &mut out);
    out
}

/// A report's records with `seconds` zeroed.
fn records(path: &Path) -> Vec<serde_json::Value> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .map(|l| {
            let mut v: serde_json::Value = serde_json::from_str(l).unwrap();
            v["seconds"] = 0.0.into();
            v
        })
        .collect()
}

fn report_of(out: &Path) -> PathBuf {
    out.join(".rigport-batch/report-0-of-1.jsonl")
}

fn batch(args: &[&Path], extra: &[&str]) -> std::process::Output {
    let mut all: Vec<&str> = vec!["batch", "--quiet"];
    let texts: Vec<String> = args.iter().map(|p| p.display().to_string()).collect();
    all.push(&texts[0]);
    all.push("-o");
    all.push(&texts[1]);
    all.extend(extra);
    rigport(&all)
}

/// A manifest line.
fn item(id: &str, command: &str, inputs: &[&Path], options: &[&str], output: &str) -> String {
    serde_json::json!({
        "id": id,
        "command": command,
        "inputs": inputs.iter().map(|p| p.display().to_string()).collect::<Vec<_>>(),
        "options": options,
        "outputs": [output],
    })
    .to_string()
}

/// A small mixed manifest over corpus files (None: corpus absent).
fn mixed_manifest(dir: &Path) -> Option<PathBuf> {
    let dash = corpus("4_bvh/bandai_namco_ds1/dataset-1_dash_normal_001.bvh")?;
    let keepon = corpus("1_pinocchio/berkeley_cs184__icheung_Keepon/keepon")?;
    let simple = corpus("5_gltf/khronos_samples__nobuyuki83_delfem2/RiggedSimple.glb")?;
    let bad = corpus("5_gltf/validator_negative_tests__KhronosGroup/skin/unresolved_joint.gltf")?;
    let lines = [
        item("dash", "convert", &[&dash], &[], "bvh/dash.glb"),
        item(
            "dash-fast",
            "retime",
            &[&dash],
            &["--speed", "2"],
            "bvh/dash_fast.glb",
        ),
        item(
            "dash-trim",
            "retime",
            &[&dash],
            &["--trim", "0..0.5"],
            "bvh/dash_trim.usda",
        ),
        item("keepon", "convert", &[&keepon], &[], "keepon.glb"),
        item("simple", "convert", &[&simple], &[], "gltf/simple.gltf"),
        item(
            "missing",
            "convert",
            &[&dir.join("missing.bvh")],
            &[],
            "missing.glb",
        ),
        item("bad", "convert", &[&bad], &[], "bad.glb"),
        item("simple-npz", "eval", &[&simple], &[], "simple.npz"),
    ];
    let path = dir.join("m.jsonl");
    std::fs::write(&path, lines.join("\n") + "\n").unwrap();
    Some(path)
}

#[test]
fn whole_corpus_as_one_manifest() {
    let Some(root) = corpus("") else { return };
    let tmp = scratch();
    let out = tmp.path().join("out");
    let run = batch(&[&root, &out], &["--jobs", "2"]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    // The corpus holds Khronos negative tests and broken rigs: those fail, the rest finish.
    assert_eq!(run.status.code(), Some(1), "{stderr}");
    let report = records(&report_of(&out));
    assert!(report.len() >= 60, "{} items", report.len());
    let mut done = 0;
    for (k, r) in report.iter().enumerate() {
        assert_eq!(r["index"], k, "manifest order");
        match r["status"].as_str().unwrap() {
            "done" => {
                done += 1;
                let output = out.join(r["outputs"][0].as_str().unwrap());
                let bytes = std::fs::read(&output).unwrap();
                assert_eq!(&bytes[..4], b"glTF", "{}", output.display());
            }
            "failed" => {
                let error = &r["error"];
                assert_eq!(error["kind"], "input", "{r}");
                // Its own error: the message names the item's file.
                let id = r["id"].as_str().unwrap();
                let name = id.rsplit('/').next().unwrap();
                let message = error["message"].as_str().unwrap();
                assert!(
                    message.contains(Path::new(name).file_stem().unwrap().to_str().unwrap())
                        || message.contains(".out"),
                    "{id}: {message}"
                );
                assert!(error["location"].is_string(), "{r}");
            }
            other => panic!("{other}"),
        }
    }
    assert!(done >= 40, "{done} done");
    // Every item is in the report, each once.
    let ids: std::collections::BTreeSet<&str> =
        report.iter().map(|r| r["id"].as_str().unwrap()).collect();
    assert_eq!(ids.len(), report.len());
    for must in [
        "4_bvh/bandai_namco_ds1/dataset-1_kick_normal_001.bvh",
        "3_acclaim_asf_amc/usc_csci520_mocapPlayer__shreyabhaumik/07-walk.asf",
        "1_pinocchio/edinburgh_cav_arma2__gpfvic_CAV1/arma2.obj",
        "5_gltf/khronos_samples__nobuyuki83_delfem2/CesiumMan.glb",
    ] {
        assert!(ids.contains(must), "{must} missing");
    }
}

#[test]
fn shards_make_the_same_files_and_report_as_one_run() {
    let tmp = scratch();
    let Some(manifest) = mixed_manifest(tmp.path()) else {
        return;
    };
    let one = tmp.path().join("one");
    let run = batch(&[&manifest, &one], &["--jobs", "2"]);
    assert_eq!(
        run.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    // Three processes at once into one folder, as a cluster's shards would.
    let sharded = tmp.path().join("sharded");
    let children: Vec<_> = (0..3)
        .map(|i| {
            Command::new(env!("CARGO_BIN_EXE_rigport"))
                .args(["batch", "--quiet", "--jobs", "1", "--shard"])
                .arg(format!("{i}/3"))
                .arg(&manifest)
                .arg("-o")
                .arg(&sharded)
                .stderr(Stdio::piped())
                .spawn()
                .unwrap()
        })
        .collect();
    for child in children {
        let out = child.wait_with_output().unwrap();
        assert!(matches!(out.status.code(), Some(0 | 1)), "{out:?}");
    }
    let a = files(&one);
    let b = files(&sharded);
    assert_eq!(a.keys().collect::<Vec<_>>(), b.keys().collect::<Vec<_>>());
    assert!(a == b, "shard outputs differ from one run");
    assert!(a.contains_key("gltf/simple.bin"));
    // The environment of a Kubernetes Indexed Job picks the shard too.
    let env_run = tmp.path().join("env");
    let out = Command::new(env!("CARGO_BIN_EXE_rigport"))
        .args(["batch", "--quiet"])
        .arg(&manifest)
        .arg("-o")
        .arg(&env_run)
        .env("JOB_COMPLETION_INDEX", "1")
        .env("JOB_COMPLETIONS", "3")
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0), "{out:?}");
    let shard1 = records(&env_run.join(".rigport-batch/report-1-of-3.jsonl"));
    let ids: Vec<&str> = shard1.iter().map(|r| r["id"].as_str().unwrap()).collect();
    assert_eq!(ids, ["dash-fast", "simple", "simple-npz"]);

    let reports: Vec<String> = (0..3)
        .map(|i| {
            let p = sharded.join(format!(".rigport-batch/report-{i}-of-3.jsonl"));
            p.display().to_string()
        })
        .collect();
    let merged = tmp.path().join("merged.jsonl");
    let merged_arg = merged.display().to_string();
    let mut args = vec!["batch-report", "-o", &merged_arg];
    args.extend(reports.iter().map(String::as_str));
    let out = rigport(&args);
    let table = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{table}");
    assert!(
        table.contains("failed items:") && table.contains("missing:"),
        "{table}"
    );
    assert_eq!(records(&merged), records(&report_of(&one)));
    // A report given twice is refused, naming both places.
    let out = rigport(&["batch-report", &reports[0], &reports[0]]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("is also at"));
}

#[test]
fn resume_skips_finished_items_and_redoes_a_changed_input() {
    let Some(dash) = corpus("4_bvh/bandai_namco_ds1/dataset-1_dash_normal_001.bvh") else {
        return;
    };
    let Some(asf) = corpus("3_acclaim_asf_amc/lowerbody_edge_case__cvikramk_TimeGAN/02.asf") else {
        return;
    };
    let tmp = scratch();
    let dir = tmp.path();
    std::fs::copy(&dash, dir.join("a.bvh")).unwrap();
    std::fs::copy(&dash, dir.join("b.bvh")).unwrap();
    std::fs::copy(&asf, dir.join("c.asf")).unwrap();
    let lines = [
        r#"{"id": "a", "command": "convert", "inputs": ["a.bvh"], "outputs": ["a.glb"]}"#,
        r#"{"id": "b", "command": "retime", "inputs": ["b.bvh"], "options": ["--fps", "24"], "outputs": ["b.glb"]}"#,
        r#"{"id": "c", "command": "convert", "inputs": ["c.asf"], "outputs": ["c.usda"]}"#,
        r#"{"id": "bad", "command": "retime", "inputs": ["a.bvh"], "options": ["--speed", "-1"], "outputs": ["bad.glb"]}"#,
    ];
    let manifest = dir.join("m.jsonl");
    std::fs::write(&manifest, lines.join("\n")).unwrap();
    let out = dir.join("out");
    let status = |report: &[serde_json::Value]| -> Vec<String> {
        report
            .iter()
            .map(|r| {
                format!(
                    "{} {}",
                    r["id"].as_str().unwrap(),
                    r["status"].as_str().unwrap()
                )
            })
            .collect()
    };
    let first = batch(&[&manifest, &out], &["--resume"]);
    assert_eq!(first.status.code(), Some(1));
    let first_report = records(&report_of(&out));
    assert_eq!(
        status(&first_report),
        ["a done", "b done", "c done", "bad failed"]
    );
    let before = files(&out);

    let second = batch(&[&manifest, &out], &["--resume"]);
    assert_eq!(
        second.status.code(),
        Some(1),
        "the bad input is reported again"
    );
    let report = records(&report_of(&out));
    assert_eq!(
        status(&report),
        ["a skipped", "b skipped", "c skipped", "bad failed"]
    );
    assert_eq!(report[3]["error"], first_report[3]["error"]);
    assert_eq!(report[0]["warnings"], first_report[0]["warnings"]);
    assert!(files(&out) == before);

    // Change one input's bytes: exactly the items reading it are redone.
    let mut text = std::fs::read(dir.join("b.bvh")).unwrap();
    text.extend_from_slice(b"\n");
    std::fs::write(dir.join("b.bvh"), text).unwrap();
    batch(&[&manifest, &out], &["--resume"]);
    let report = records(&report_of(&out));
    assert_eq!(
        status(&report),
        ["a skipped", "b done", "c skipped", "bad failed"]
    );
    // A deleted output is redone too; without --resume everything runs.
    std::fs::remove_file(out.join("c.usda")).unwrap();
    batch(&[&manifest, &out], &["--resume"]);
    assert_eq!(
        status(&records(&report_of(&out))),
        ["a skipped", "b skipped", "c done", "bad failed"]
    );
    batch(&[&manifest, &out], &[]);
    assert_eq!(
        status(&records(&report_of(&out))),
        ["a done", "b done", "c done", "bad failed"]
    );
}

#[test]
fn a_killed_run_resumes_to_the_same_outputs() {
    let Some(dash) = corpus("4_bvh/bandai_namco_ds1/dataset-1_dash_normal_001.bvh") else {
        return;
    };
    let tmp = scratch();
    let lines: Vec<String> = (0..10)
        .map(|k| {
            let speed = format!("{}", 0.5 + 0.25 * f64::from(k));
            item(
                &format!("dash{k}"),
                "retime",
                &[&dash],
                &["--speed", &speed],
                &format!("d{k}.glb"),
            )
        })
        .collect();
    let manifest = tmp.path().join("m.jsonl");
    std::fs::write(&manifest, lines.join("\n")).unwrap();
    let clean = tmp.path().join("clean");
    let run = batch(&[&manifest, &clean], &["--jobs", "2"]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );

    let out = tmp.path().join("out");
    // Every rename waits 150 ms, so the kill lands while items are being written.
    let mut child = Command::new(env!("CARGO_BIN_EXE_rigport"))
        .args(["batch", "--quiet", "--jobs", "2"])
        .arg(&manifest)
        .arg("-o")
        .arg(&out)
        .env("RIGPORT_TEST_RENAME_DELAY_MS", "150")
        .spawn()
        .unwrap();
    let sidecars = out.join(".rigport-batch/items");
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(120);
    while std::fs::read_dir(&sidecars).map_or(0, |d| d.count()) < 3 {
        assert!(std::time::Instant::now() < deadline, "no progress");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    child.kill().unwrap(); // SIGKILL: no cleanup at all
    child.wait().unwrap();
    let partial = files(&out);
    assert!(
        partial.keys().filter(|k| k.ends_with(".glb")).count() < 10,
        "killed too late"
    );

    let resumed = batch(&[&manifest, &out], &["--resume", "--jobs", "2"]);
    assert!(
        resumed.status.success(),
        "{}",
        String::from_utf8_lossy(&resumed.stderr)
    );
    let report = records(&report_of(&out));
    assert!(report.iter().any(|r| r["status"] == "skipped"));
    assert!(report.iter().any(|r| r["status"] == "done"));
    // Same files, same bytes, and no temporary file of the killed process left.
    assert!(files(&out) == files(&clean), "resumed outputs differ");
}

#[test]
fn manifest_errors_name_the_line_and_exit_codes_tell_input_from_output() {
    let tmp = scratch();
    let dir = tmp.path();
    let manifest = dir.join("m.jsonl");
    std::fs::write(
        &manifest,
        "{\"command\": \"convert\", \"inputs\": [\"a.bvh\"], \"outputs\": [\"a.glb\"]}\n\n{\"command\": \"convert\", \"inputs\": [\"b.bvh\"]}\n",
    )
    .unwrap();
    let out = batch(&[&manifest, &dir.join("out")], &[]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("m.jsonl:3:") && stderr.contains("outputs"),
        "{stderr}"
    );
    assert!(!dir.join("out").exists(), "nothing runs on a bad manifest");

    let Some(dash) = corpus("4_bvh/bandai_namco_ds1/dataset-1_dash_normal_001.bvh") else {
        return;
    };
    // An output that cannot be written (its folder is a file): exit 3, the rest done.
    let lines = [
        item("ok", "convert", &[&dash], &[], "ok.glb"),
        item("blocked", "convert", &[&dash], &[], "blocker/x.glb"),
        item("unknown", "inspect", &[&dash], &[], "i.glb"),
    ];
    std::fs::write(&manifest, lines.join("\n")).unwrap();
    let target = dir.join("out3");
    std::fs::create_dir_all(&target).unwrap();
    std::fs::write(target.join("blocker"), b"a file").unwrap();
    let out = batch(&[&manifest, &target], &[]);
    assert_eq!(
        out.status.code(),
        Some(3),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let report = records(&report_of(&target));
    assert_eq!(report[0]["status"], "done");
    assert_eq!(report[1]["error"]["kind"], "output");
    assert_eq!(report[2]["error"]["kind"], "input");
    assert!(report[2]["error"]["message"]
        .as_str()
        .unwrap()
        .contains("cannot run in a batch"));
    assert!(target.join("ok.glb").is_file());
}

/// Opt-in (`RIGPORT_TEST_RAY=1`, Ray installed in tools/.venv-ray, see docs/scale.md):
/// three shards as Ray tasks on a local Ray give the files and merged report of one run.
#[test]
fn ray_shards_equal_one_run() {
    if std::env::var_os("RIGPORT_TEST_RAY").is_none() {
        eprintln!("SKIPPED: set RIGPORT_TEST_RAY=1 (and install Ray, docs/scale.md) to run");
        return;
    }
    let python = crate::common::repo().join("tools/.venv-ray/bin/python");
    assert!(
        python.exists(),
        "{} missing: see docs/scale.md",
        python.display()
    );
    let tmp = scratch();
    let Some(manifest) = mixed_manifest(tmp.path()) else {
        return;
    };
    let one = tmp.path().join("one");
    batch(&[&manifest, &one], &[]);
    let ray_out = tmp.path().join("ray");
    for data in [false, true] {
        let _ = std::fs::remove_dir_all(&ray_out);
        let mut cmd = Command::new(&python);
        cmd.arg(crate::common::repo().join("tools/ray_shards.py"))
            .arg("--rigport")
            .arg(env!("CARGO_BIN_EXE_rigport"))
            .arg("--manifest")
            .arg(&manifest)
            .arg("--out")
            .arg(&ray_out)
            .args(["--shards", "3"]);
        if data {
            if Command::new(&python)
                .args(["-c", "import ray.data, pyarrow"])
                .status()
                .is_ok_and(|s| !s.success())
            {
                eprintln!("SKIPPED: Ray Data (pip install 'ray[data]') is not installed");
                continue;
            }
            cmd.arg("--data");
        }
        let out = cmd.output().unwrap();
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert_eq!(
            out.status.code(),
            Some(1),
            "{stdout}{}",
            String::from_utf8_lossy(&out.stderr)
        );
        assert!(files(&ray_out) == files(&one), "Ray shard outputs differ");
        let merged = tmp.path().join("merged.jsonl");
        let mut args = vec!["batch-report".to_string(), "-o".into()];
        args.push(merged.display().to_string());
        for i in 0..3 {
            let p = ray_out.join(format!(".rigport-batch/report-{i}-of-3.jsonl"));
            args.push(p.display().to_string());
        }
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        rigport(&args);
        assert_eq!(records(&merged), records(&report_of(&one)));
        eprintln!(
            "ray ({}): {stdout}",
            if data { "Ray Data" } else { "tasks" }
        );
    }
}

/// The memory budget is shared by the items in flight: with `--jobs 2` each item is checked
/// against half of `--max-memory` (the report names the share), with `--jobs 1` against all
/// of it. A BVH whose glTF needs about 48 kB fits 60 kB alone, not 30 kB.
#[test]
fn the_memory_budget_is_shared_by_the_jobs() {
    let dir = scratch();
    let input = dir.path().join("in");
    std::fs::create_dir(&input).unwrap();
    let repo = Path::new(env!("CARGO_MANIFEST_DIR"));
    std::fs::copy(
        repo.join("fixtures/bvh/end_sites.bvh"),
        input.join("end_sites.bvh"),
    )
    .unwrap();
    let one = dir.path().join("one");
    let r = batch(&[&input, &one], &["--jobs", "1", "--max-memory", "60000"]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    assert!(one.join("end_sites.glb").exists());
    let two = dir.path().join("two");
    let r = batch(&[&input, &two], &["--jobs", "2", "--max-memory", "60000"]);
    assert_eq!(r.status.code(), Some(1));
    let rec = records(&report_of(&two));
    let message = rec[0]["error"]["message"].as_str().unwrap();
    assert!(
        message.contains("over the limit of 30.0 kB (--max-memory, shared by the batch's --jobs items in flight)"),
        "{message}"
    );
    assert!(!two.join("end_sites.glb").exists());
}

/// A Pinocchio mesh paired with another mesh's weights (the Armadillo's mesh and skeleton
/// with the human scan's `attachment.out`, cut to the Armadillo's 8988 rows): it converts
/// with a W005 warning that the weights may belong to another mesh, `--deny-warnings`
/// refuses it (exit 4, nothing written), and a batch reports the warning for the item.
#[test]
fn weights_of_another_mesh_are_reported_and_denied() {
    let armadillo = "1_pinocchio/berkeley_cs184__icheung_Keepon/armadillo";
    let human = "1_pinocchio/berkeley_cs184__severus-snape_mobius-ants/human_model1";
    let (Some(obj), Some(skel), Some(att)) = (
        corpus(&format!("{armadillo}/Armadillo.obj")),
        corpus(&format!("{armadillo}/skeleton.out")),
        corpus(&format!("{human}/attachment.out")),
    ) else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let rows = std::fs::read_to_string(&obj)
        .unwrap()
        .lines()
        .filter(|l| l.starts_with("v "))
        .count();
    let cut: String = std::fs::read_to_string(&att)
        .unwrap()
        .lines()
        .take(rows)
        .map(|l| format!("{l}\n"))
        .collect();
    let mixed = dir.path().join("human_attachment.out");
    std::fs::write(&mixed, cut).unwrap();
    let (obj_s, skel_s, mixed_s) = (
        obj.to_str().unwrap(),
        skel.to_str().unwrap(),
        mixed.to_str().unwrap(),
    );
    let out = dir.path().join("mixed.glb");
    let denied = rigport(&[
        "convert",
        "--deny-warnings",
        "--mesh",
        obj_s,
        "--skeleton",
        skel_s,
        "--attachment",
        mixed_s,
        "-o",
        out.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&denied.stderr);
    assert_eq!(denied.status.code(), Some(4), "{stderr}");
    assert!(
        stderr.contains("warning[W005]") && stderr.contains("may belong to another mesh"),
        "{stderr}"
    );
    assert!(!out.exists());

    let manifest = dir.path().join("m.jsonl");
    let line = serde_json::json!({
        "id": "mixed",
        "command": "convert",
        "inputs": [obj_s, skel_s, mixed_s],
        "outputs": ["mixed.glb"],
    });
    std::fs::write(&manifest, format!("{line}\n")).unwrap();
    let outdir = dir.path().join("out");
    let run = batch(&[&manifest, &outdir], &[]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let report = records(&report_of(&outdir));
    let warnings = report[0]["warnings"].to_string();
    assert!(warnings.contains("W005"), "{warnings}");
}

/// One item of each command that reads inputs and writes one file, footlock, retarget and
/// cloth among them: every item is done, and a `--resume` run skips them all.
#[test]
fn every_single_output_command_runs_in_a_batch_and_resumes() {
    let (Some(dash), Some(human), Some(arm)) = (
        corpus("4_bvh/bandai_namco_ds1/dataset-1_dash_normal_001.bvh"),
        corpus("1_pinocchio/berkeley_cs184__severus-snape_mobius-ants/human_model1"),
        corpus("6_usd/ustc_cg_24_hw10__USTC-CG/arm_with_cloth.usda"),
    ) else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let fixtures = repo().join("fixtures");
    let branch = |ext: &str| fixtures.join(format!("pinocchio/branch{ext}"));
    let (obj, skel, att) = (
        branch(".obj"),
        branch("_skeleton.out"),
        branch("_attachment.out"),
    );
    let handles = dir.path().join("reach.json");
    std::fs::write(
        &handles,
        r#"{"fps": 10, "handles": [{"joint": "bone_2", "relative": true,
            "keys": [{"time": 0, "position": [0, 0, 0]}, {"time": 1, "position": [0.1, -0.1, 0]}]}]}"#,
    )
    .unwrap();
    let skin = fixtures.join("gltf/skin_basic.glb");
    let (human_s, handles_s) = (human.display().to_string(), handles.display().to_string());
    let lines = [
        item(
            "retime",
            "retime",
            &[&dash],
            &["--speed", "2"],
            "dash_fast.glb",
        ),
        item("footlock", "footlock", &[&dash], &[], "dash_clean.glb"),
        item(
            "retarget",
            "retarget",
            &[&dash],
            &["--onto", &human_s],
            "dash_on_human.glb",
        ),
        item(
            "cloth",
            "cloth",
            &[&arm],
            &["--garment", "Grid", "--seconds", "0.5"],
            "arm_cloth.glb",
        ),
        item(
            "ik",
            "ik",
            &[&obj, &skel, &att],
            &["--handles", &handles_s],
            "reach.glb",
        ),
        item(
            "bake",
            "bake",
            &[&skin],
            &["--skinning", "dqs"],
            "bend_dqs.glb",
        ),
        item(
            "render",
            "render",
            &[&dash],
            &["--size", "64x64"],
            "dash.png",
        ),
    ];
    let manifest = dir.path().join("m.jsonl");
    std::fs::write(&manifest, lines.join("\n") + "\n").unwrap();
    let out = dir.path().join("out");
    let run = batch(&[&manifest, &out], &[]);
    let report = records(&report_of(&out));
    for r in &report {
        assert_eq!(r["status"], "done", "{r}");
    }
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    assert_eq!(report.len(), lines.len());
    let again = batch(&[&manifest, &out], &["--resume"]);
    assert!(again.status.success());
    for r in records(&report_of(&out)) {
        assert_eq!(r["status"], "skipped", "{r}");
    }
}

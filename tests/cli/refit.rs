//! Issue 17, influence refit from the CLI: `--influences-fit refit` fits 4 influences per
//! vertex over the clip's frames, reports both deviations, and three.js plays the refit
//! glb exactly as rigport evaluates that file.

use crate::common::*;
use crate::three::three_eval;

/// The `max A -> B` pair of the refit report line.
fn report_max(stderr: &str) -> (f64, f64) {
    let line = stderr
        .lines()
        .find(|l| l.starts_with("influences: skin 0 refitted to 4"))
        .unwrap_or_else(|| panic!("no refit report: {stderr}"));
    let after = line.split(", max ").nth(1).expect("max figures");
    let mut numbers = after
        .split([' ', ','])
        .filter_map(|w| w.parse::<f64>().ok());
    (numbers.next().unwrap(), numbers.next().unwrap())
}

#[test]
fn a_refit_glb_plays_in_three_as_rigport_evaluates_it() {
    let Some(dir_in) = corpus("1_pinocchio/edinburgh_cav_arma2__gpfvic_CAV1") else {
        return;
    };
    let dir = scratch();
    let s = |p: &std::path::Path| p.to_str().unwrap().to_string();
    let keys = dir.path().join("bend.json");
    std::fs::write(
        &keys,
        r#"{"name": "bend", "keys": [
            {"time": 0, "pose": {}},
            {"time": 1, "pose": {"bone_3": {"euler_deg": [0, 0, 60]}, "bone_7": {"euler_deg": [80, 0, 0]}}},
            {"time": 2, "pose": {"bone_3": {"euler_deg": [0, 40, -50]}, "bone_12": {"euler_deg": [0, 0, 70]}}}]}"#,
    )
    .unwrap();
    let glb = dir.path().join("refit.glb");
    let r = rigport(&[
        "animate",
        &s(&dir_in.join("arma2.obj")),
        &s(&dir_in.join("skeleton2.out")),
        &s(&dir_in.join("attachment2.out")),
        "--keys",
        &s(&keys),
        "--influences-fit",
        "refit",
        "-o",
        &s(&glb),
    ]);
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert!(r.status.success(), "{stderr}");
    let (truncated, refit) = report_max(&stderr);
    assert!(
        refit <= truncated,
        "refit max {refit:e} above truncation's {truncated:e} on the poses it was fitted to"
    );
    assert_valid(&glb);

    let Some((_, three)) = three_eval(&glb, &["--clip", "bend", "--fps", "10"]) else {
        return;
    };
    let npz = dir.path().join("refit.npz");
    rigport_ok(&[
        "eval",
        &s(&glb),
        "--clip",
        "bend",
        "--fps",
        "10",
        "--out",
        &s(&npz),
    ]);
    let ours = &read_npz(&npz)["positions"];
    assert_eq!(three.shape, ours.shape);
    let frame = ours.shape[1] * 3;
    let (mut lo, mut hi) = ([f64::MAX; 3], [f64::MIN; 3]);
    for p in ours.numbers[..frame].chunks_exact(3) {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let diag = (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>().sqrt();
    let max = three
        .numbers
        .iter()
        .zip(&ours.numbers)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    eprintln!(
        "refit arma2: three.js vs rigport eval: {:.2e} of the diagonal",
        max / diag
    );
    assert!(max / diag <= 1e-5, "{:e}", max / diag);
}

#[test]
fn usd_keeps_every_influence_unless_max_influences_is_given() {
    let dir = scratch();
    let fixtures = repo().join("fixtures/pinocchio");
    let s = |p: &std::path::Path| p.to_str().unwrap().to_string();
    let rig = [
        s(&fixtures.join("branch.obj")),
        s(&fixtures.join("branch_skeleton.out")),
        s(&fixtures.join("branch_attachment.out")),
    ];
    let elements = |args: &[&str]| -> String {
        let out = dir.path().join("x.usda");
        let mut all = vec![
            "convert",
            "-q",
            &rig[0],
            &rig[1],
            &rig[2],
            "-o",
            out.to_str().unwrap(),
        ];
        all.extend_from_slice(args);
        rigport_ok(&all);
        let text = std::fs::read_to_string(&out).unwrap();
        let after = text
            .split("primvars:skel:jointIndices")
            .nth(1)
            .expect("joint indices");
        after
            .split("elementSize = ")
            .nth(1)
            .and_then(|e| e.split_whitespace().next())
            .unwrap_or_default()
            .to_string()
    };
    assert_eq!(elements(&[]), "2", "all influences by default");
    assert_eq!(elements(&["--max-influences", "1"]), "1");
    assert_eq!(
        elements(&["--max-influences", "1", "--influences-fit", "refit"]),
        "1"
    );
}

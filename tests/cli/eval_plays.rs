//! `rigport eval` plays what viewers play (issue 28): morph targets, blend shapes and
//! time-sampled points are applied before skinning, so its dump equals UsdSkel (usd-core)
//! for a `.usda` and three.js for a `.glb`, at every frame, to 1e-6 of the diagonal.

use std::path::Path;

use crate::common::{self, repo, rigport_ok, NpyArray};
use crate::frames::run_usd_world;
use crate::three::{in_three_order, three_eval};
use crate::usd::python;

const POINT_CACHE: &str = "fixtures/usda/point_cache.usda";

/// UsdSkel's points of every mesh of `stage` at `seconds`, in the first Skeleton's space
/// (rigport's model space), frame by frame, flat (tests/cli/usd_world.py --model-space).
fn usdskel_points(py: &Path, stage: &Path, seconds: &[f64], clip: Option<&str>) -> Vec<f64> {
    run_usd_world(py, stage, Some(seconds), clip, &["--model-space"])
        .iter()
        .flat_map(|f| f.points.iter().flatten().copied())
        .collect()
}

/// `rigport eval FILE --clip CLIP --fps FPS`: the frame times and the positions.
fn eval(file: &Path, clip: &str, fps: &str, dir: &Path) -> (Vec<f64>, NpyArray) {
    let npz = dir.join("eval.npz");
    rigport_ok(&[
        "eval",
        file.to_str().unwrap(),
        "--clip",
        clip,
        "--fps",
        fps,
        "-o",
        npz.to_str().unwrap(),
    ]);
    let mut dump = common::read_npz(&npz);
    let times = dump.remove("times").expect("times").numbers;
    (times, dump.remove("positions").expect("positions"))
}

/// The largest distance between `a` and `b` (frames x vertices x 3, flat) over the
/// diagonal of `a`'s bounds over all frames.
fn deviation(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len(), "same number of positions");
    let (mut lo, mut hi) = ([f64::MAX; 3], [f64::MIN; 3]);
    for p in a.chunks_exact(3) {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let diagonal = (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>().sqrt();
    let worst = a
        .chunks_exact(3)
        .zip(b.chunks_exact(3))
        .map(|(p, q)| (0..3).map(|k| (p[k] - q[k]).powi(2)).sum::<f64>().sqrt())
        .fold(0.0, f64::max);
    worst / diagonal
}

/// A point cache (a static mesh under a scaled, turned Xform whose points are time-sampled,
/// with a default value besides the samples) beside a skinned arm: `rigport eval` of the
/// `.usda` equals UsdSkel between and at the samples, and the `.glb` rigport converts it
/// to plays in three.js as rigport evaluates it.
#[test]
fn eval_plays_time_sampled_points_as_usdskel_and_three_do() {
    let dir = common::scratch();
    let usda = repo().join(POINT_CACHE);
    let (times, ours) = eval(&usda, "Bend", "120", dir.path());
    assert_eq!(times.len(), 11, "0 .. 2.5/30 s at 120 fps");
    // The flag moves: its points differ between the first and the last frame.
    let frame = ours.shape[1] * 3;
    assert_ne!(
        ours.numbers[..frame],
        ours.numbers[ours.numbers.len() - frame..]
    );
    if let Some(py) = python() {
        let usd = usdskel_points(&py, &usda, &times, None);
        let dev = deviation(&usd, &ours.numbers);
        eprintln!("point cache: rigport eval vs UsdSkel: {dev:.2e} of the diagonal");
        assert!(dev <= 1e-6, "rigport eval and UsdSkel differ by {dev:e}");
    }
    let glb = dir.path().join("cache.glb");
    rigport_ok(&[
        "convert",
        usda.to_str().unwrap(),
        "-o",
        glb.to_str().unwrap(),
    ]);
    let (_, from_glb) = eval(&glb, "Bend", "120", dir.path());
    let secs: Vec<String> = times.iter().map(|t| format!("{t}")).collect();
    let Some((report, three)) = three_eval(&glb, &["--clip", "Bend", "--times", &secs.join(",")])
    else {
        return;
    };
    let dev = deviation(&three.numbers, &in_three_order(&glb, &report, &from_glb));
    eprintln!("point cache as glb: rigport eval vs three.js: {dev:.2e} of the diagonal");
    assert!(dev <= 1e-6, "rigport eval and three.js differ by {dev:e}");
}

/// A cloth bake (the corpus arm with its cloth grid): `rigport eval` of the `.usda` (the
/// garment as time-sampled points) equals UsdSkel, and of the `.glb` (morph targets)
/// equals three.js, at every frame.
#[test]
fn eval_plays_cloth_bakes_as_usdskel_and_three_do() {
    let Some(arm) = common::corpus("6_usd/ustc_cg_24_hw10__USTC-CG/arm_with_cloth.usda") else {
        return;
    };
    let dir = common::scratch();
    let (usda, glb) = (dir.path().join("arm.usda"), dir.path().join("arm.glb"));
    for out in [&usda, &glb] {
        rigport_ok(&[
            "cloth",
            "-q",
            arm.to_str().unwrap(),
            "--garment",
            "Grid",
            "-o",
            out.to_str().unwrap(),
        ]);
    }
    let (times, ours) = eval(&usda, "Anim", "24", dir.path());
    if let Some(py) = python() {
        let usd = usdskel_points(&py, &usda, &times, None);
        let dev = deviation(&usd, &ours.numbers);
        eprintln!("cloth .usda: rigport eval vs UsdSkel: {dev:.2e} of the diagonal");
        assert!(dev <= 1e-6, "rigport eval and UsdSkel differ by {dev:e}");
    }
    let (times, from_glb) = eval(&glb, "Anim", "24", dir.path());
    let secs: Vec<String> = times.iter().map(|t| format!("{t}")).collect();
    let Some((report, three)) = three_eval(&glb, &["--clip", "Anim", "--times", &secs.join(",")])
    else {
        return;
    };
    let dev = deviation(&three.numbers, &in_three_order(&glb, &report, &from_glb));
    eprintln!("cloth .glb: rigport eval vs three.js: {dev:.2e} of the diagonal");
    assert!(dev <= 1e-6, "rigport eval and three.js differ by {dev:e}");
}

/// The clip names of `file`, in its order (`rigport inspect --json`).
fn clips_of(file: &Path) -> Vec<String> {
    let out = crate::common::rigport(&["inspect", "--json", file.to_str().unwrap()]);
    assert!(out.status.success(), "inspect {}", file.display());
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).expect("inspect JSON");
    json[0]["clips"]
        .as_array()
        .expect("clips")
        .iter()
        .map(|c| c["name"].as_str().expect("a clip name").to_string())
        .collect()
}

/// Every clip of `file` at 30 fps: `rigport eval` equals three.js (`.glb`) or UsdSkel
/// (`.usda`, each clip's variant when there are several), to 1e-6 of the diagonal.
/// Returns the files' worst deviation.
fn plays_as_viewers_do(file: &Path, dir: &Path) -> f64 {
    let clips = clips_of(file);
    assert!(!clips.is_empty(), "{}: no clip to play", file.display());
    let mut worst = 0.0f64;
    for clip in &clips {
        let (times, ours) = eval(file, clip, "30", dir);
        assert!(ours.shape[1] > 0, "{}: no vertex to play", file.display());
        let dev = if file.extension().is_some_and(|e| e == "usda") {
            let Some(py) = python() else {
                return 0.0;
            };
            let variant = (clips.len() > 1).then_some(clip.as_str());
            deviation(&usdskel_points(&py, file, &times, variant), &ours.numbers)
        } else {
            let secs: Vec<String> = times.iter().map(|t| format!("{t}")).collect();
            let Some((report, three)) =
                three_eval(file, &["--clip", clip, "--times", &secs.join(",")])
            else {
                return 0.0;
            };
            deviation(&three.numbers, &in_three_order(file, &report, &ours))
        };
        eprintln!("{} {clip:?}: {dev:.2e} of the diagonal", file.display());
        assert!(dev <= 1e-6, "{} {clip:?}: {dev:e}", file.display());
        worst = worst.max(dev);
    }
    worst
}

/// Every file the demo writes (its character with three clips as `.glb` and `.usda` clip
/// variants, the DQS twist baked into corrective morph targets, the skirt's cloth bake as
/// morph targets) and the skirt converted to `.usda` (61 blend shapes driven by a
/// SkelAnimation) play in `rigport eval` as in three.js and UsdSkel.
#[test]
fn every_demo_file_plays_in_eval_as_in_the_viewers() {
    let dir = common::scratch();
    let demo = common::demo_outputs();
    let mut files: Vec<_> = std::fs::read_dir(&demo)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "glb" || e == "usda"))
        .collect();
    files.sort();
    assert_eq!(files.len(), 4, "{files:?}");
    let skirt = dir.path().join("skirt.usda");
    rigport_ok(&[
        "convert",
        "-q",
        demo.join("skirt.glb").to_str().unwrap(),
        "-o",
        skirt.to_str().unwrap(),
    ]);
    files.push(skirt);
    for file in &files {
        plays_as_viewers_do(file, dir.path());
    }
}

/// One output of each kind the commands write from the project's fixtures, as `.glb` and
/// `.usda`: skeleton-only motion (ASF/AMC, BVH: a generated bone mesh), morph targets
/// (glTF; two primitives of one size), USD rigid bindings, COLLADA skin over morph, a DQS
/// bake and a retimed clip: `rigport eval` plays each as three.js and UsdSkel do (clip
/// variants: the demo's `.usda`).
#[test]
fn every_kind_of_output_plays_in_eval_as_in_the_viewers() {
    let dir = common::scratch();
    let fixture = |p: &str| repo().join(p).to_str().unwrap().to_string();
    let runs: Vec<(&str, Vec<String>)> = vec![
        (
            "amc",
            vec![
                "convert".into(),
                fixture("fixtures/asf_amc/translation.asf"),
                fixture("fixtures/asf_amc/translation.amc"),
            ],
        ),
        (
            "bvh",
            vec!["convert".into(), fixture("fixtures/bvh/mixed_orders.bvh")],
        ),
        (
            "morph",
            vec!["convert".into(), fixture("fixtures/gltf/morph_sparse.gltf")],
        ),
        (
            "rigid",
            vec!["convert".into(), fixture("fixtures/usda/rigid_subset.usda")],
        ),
        (
            "collada",
            vec![
                "convert".into(),
                fixture("fixtures/collada/skinned_quad.dae"),
            ],
        ),
        // DQS: baked into morph targets for glTF, declared (`dualQuaternion`) for USD.
        (
            "dqs",
            vec![
                "bake".into(),
                fixture("fixtures/usda/skinned_arm.usda"),
                "--skinning".into(),
                "dqs".into(),
            ],
        ),
        (
            "dqs_declared",
            vec![
                "convert".into(),
                fixture("fixtures/usda/skinned_arm.usda"),
                "--skinning".into(),
                "dqs".into(),
            ],
        ),
        (
            "retimed",
            vec![
                "retime".into(),
                fixture("fixtures/usda/skinned_arm.usda"),
                "--speed".into(),
                "0.5".into(),
            ],
        ),
        // Compact clips: reduced keys, the mesh quantized (`KHR_mesh_quantization`), and
        // `EXT_meshopt_compression` (three.js with its meshopt decoder).
        (
            "compact",
            vec![
                "convert".into(),
                fixture("fixtures/bvh/mixed_orders.bvh"),
                "--reduce-tolerance".into(),
            ],
        ),
        (
            "meshopt",
            vec![
                "convert".into(),
                fixture("fixtures/bvh/mixed_orders.bvh"),
                "--compress".into(),
                "meshopt".into(),
            ],
        ),
    ];
    for (name, args) in &runs {
        let exts: &[&str] = match *name {
            "dqs" | "meshopt" => &["glb"],
            "dqs_declared" => &["usda"],
            _ => &["glb", "usda"],
        };
        for ext in exts {
            let out = dir.path().join(format!("{name}.{ext}"));
            let mut all: Vec<&str> = args.iter().map(String::as_str).collect();
            all.extend(["-q", "-o", out.to_str().unwrap()]);
            rigport_ok(&all);
            plays_as_viewers_do(&out, dir.path());
        }
    }
}

/// Compact glb files whose 16-bit rotation keys are not quite unit length (the corpus's
/// Bandai kick, reduced, and with meshopt): a key near a half turn about one axis has no
/// 16-bit neighbour within 1e-5 of unit length, three.js composes such keys as stored
/// (normalizing only where its slerp lerps), and so does `rigport eval`, which was 1.5e-5
/// and 2.0e-5 of the diagonal off three.js while it normalized every key.
#[test]
fn compact_files_with_keys_off_unit_length_play_in_eval_as_in_three() {
    let Some(bvh) = common::corpus("4_bvh/bandai_namco_ds1/dataset-1_kick_normal_001.bvh") else {
        return;
    };
    let dir = common::scratch();
    for (name, flags) in [
        ("reduced", &["--reduce-tolerance"][..]),
        ("meshopt", &["--compress", "meshopt"][..]),
    ] {
        let glb = dir.path().join(format!("{name}.glb"));
        let mut args = vec![
            "convert",
            "-q",
            bvh.to_str().unwrap(),
            "--input-units",
            "auto",
            "-o",
            glb.to_str().unwrap(),
        ];
        args.extend(flags);
        rigport_ok(&args);
        plays_as_viewers_do(&glb, dir.path());
    }
}

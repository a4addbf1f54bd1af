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

/// The demo's `.usda` (three clips in variants) and its skirt converted to `.usda` (61
/// blend shapes driven by a SkelAnimation): `rigport eval` equals UsdSkel at every frame.
#[test]
fn eval_plays_the_demo_usd_and_its_blend_shapes_as_usdskel_does() {
    let Some(py) = python() else {
        return;
    };
    let dir = common::scratch();
    let demo = dir.path().join("demo");
    rigport_ok(&["demo", "-q", "--no-corpus", "-o", demo.to_str().unwrap()]);
    let skirt = dir.path().join("skirt.usda");
    rigport_ok(&[
        "convert",
        "-q",
        demo.join("skirt.glb").to_str().unwrap(),
        "-o",
        skirt.to_str().unwrap(),
    ]);
    for (file, clip, variant) in [
        (demo.join("demo.usda"), "wave", Some("wave")),
        (demo.join("demo.usda"), "twist", Some("twist")),
        (skirt.clone(), "wave", None),
    ] {
        let (times, ours) = eval(&file, clip, "10", dir.path());
        let usd = usdskel_points(&py, &file, &times, variant);
        let dev = deviation(&usd, &ours.numbers);
        eprintln!(
            "{} {clip}: rigport eval vs UsdSkel: {dev:.2e} of the diagonal",
            file.display()
        );
        assert!(dev <= 1e-6, "{}: {dev:e}", file.display());
    }
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

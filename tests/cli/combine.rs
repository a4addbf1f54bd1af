//! `rigport combine` (issue 30): many motions onto one rig as named clips in one file.
//! Retargeted clips play as `rigport retarget` of each file alone (three.js, UsdSkel per
//! clip variant); clips of the rig's own skeleton are taken with their tracks as `convert`
//! writes them; every input kind in one run; names, repeats and errors.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

use crate::common::*;
use crate::frames::usd_world;
use crate::motion::BVH;
use crate::three::three_eval;
use crate::usd::python;

const HUMAN_MODEL1: &str = "1_pinocchio/berkeley_cs184__severus-snape_mobius-ants/human_model1";
const CMU: &str = "3_acclaim_asf_amc/usc_csci520_mocapPlayer__shreyabhaumik";

fn s(p: &Path) -> &str {
    p.to_str().expect("UTF-8 path")
}

/// `rigport combine ARGS --json`: the report.
fn combine_json(args: &[&str]) -> serde_json::Value {
    let mut all = vec!["combine", "--json"];
    all.extend_from_slice(args);
    let run = rigport(&all);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "combine {args:?}: {stderr}");
    serde_json::from_slice(&run.stdout).expect("combine --json")
}

/// Largest distance between `a` and `b` (flat xyz) over the diagonal of `b`'s first
/// `frame` numbers.
fn deviation(a: &[f64], b: &[f64], frame: usize) -> f64 {
    assert_eq!(a.len(), b.len(), "same number of positions");
    let points: Vec<[f64; 3]> = b[..frame]
        .chunks_exact(3)
        .map(|p| [p[0], p[1], p[2]])
        .collect();
    let diagonal = crate::frames::diagonal(&points);
    let worst = a
        .chunks_exact(3)
        .zip(b.chunks_exact(3))
        .map(|(p, q)| (0..3).map(|k| (p[k] - q[k]).powi(2)).sum::<f64>().sqrt())
        .fold(0.0, f64::max);
    worst / diagonal
}

/// A corpus BVH folder onto `human_model1`: one glb with one clip per file, valid, each
/// clip as three.js plays it equal to `rigport retarget` of that file alone; the same as
/// `.usdz`: clean under usd-core's validators, one clip variant per clip, UsdSkel per
/// variant equal to the glb's clip in three.js.
#[test]
fn a_bvh_folder_onto_model1_plays_as_separate_retargets() {
    let Some(rig) = corpus(HUMAN_MODEL1) else {
        return;
    };
    let bvhs: Vec<PathBuf> = BVH.iter().filter_map(|b| corpus(b)).collect();
    let dir = scratch();
    let folder = dir.path().join("bvh");
    std::fs::create_dir(&folder).unwrap();
    for b in &bvhs {
        std::os::unix::fs::symlink(b, folder.join(b.file_name().unwrap())).unwrap();
    }
    let glb = dir.path().join("library.glb");
    let report = combine_json(&[s(&rig), s(&folder), "-o", s(&glb)]);
    let clips = report["clips"].as_array().unwrap();
    assert_eq!(clips.len(), bvhs.len(), "{report}");
    assert_valid(&glb);
    let usdz = dir.path().join("library.usdz");
    // The glb's four influences per vertex (USD would keep all of Model1's, up to 18).
    let four = ["--max-influences", "4"];
    rigport_ok(
        &[
            &["combine", "-q", s(&rig), s(&folder), "-o", s(&usdz)],
            &four[..],
        ]
        .concat(),
    );
    let py = python();
    if let Some(py) = &py {
        let out = Command::new(py)
            .arg(repo().join("tools/check_usdz.py"))
            .arg(&usdz)
            .output()
            .unwrap();
        let text = String::from_utf8_lossy(&out.stdout).to_string();
        assert!(
            out.status.success() && text.contains("0 findings"),
            "{text}"
        );
        let (ok, text) = crate::usd::check_usd(py, &usdz, None);
        assert!(ok, "{text}");
    }
    for (k, clip) in clips.iter().enumerate() {
        let name = clip["clip"].as_str().unwrap();
        assert_eq!(clip["how"], "retargeted", "{clip}");
        let source = PathBuf::from(clip["source"].as_str().unwrap());
        assert_eq!(name, source.file_stem().unwrap().to_str().unwrap());
        let single = dir.path().join(format!("single_{k}.glb"));
        rigport_ok(&[
            "retarget",
            "-q",
            s(&source),
            "--onto",
            s(&rig),
            "-o",
            s(&single),
        ]);
        // Twelve of the clip's frames (evenly spaced keys), from first to last.
        let duration = clip["duration_s"].as_f64().unwrap();
        let last = clip["frames"].as_f64().unwrap() - 1.0;
        let seconds: Vec<f64> = (0..12)
            .map(|i| (f64::from(i) * last / 11.0).round() * duration / last)
            .collect();
        let times: Vec<String> = seconds.iter().map(|t| format!("{t}")).collect();
        let times = times.join(",");
        let Some((report, ours)) = three_eval(&glb, &["--clip", name, "--times", &times]) else {
            return;
        };
        let (_, alone) = three_eval(&single, &["--clip-index", "0", "--times", &times]).unwrap();
        let frame = ours.shape[1] * 3;
        let dev = deviation(&ours.numbers, &alone.numbers, frame);
        eprintln!("{name}: combined vs retarget alone, three.js: {dev:.2e} of the diagonal");
        assert!(dev <= 1e-6, "{name}: {dev:e}");
        let Some(py) = &py else {
            continue;
        };
        // UsdSkel's points of the clip's variant, in three's mesh order (the only
        // skinned mesh of Model1 is the one three reports).
        assert_eq!(report["meshes"].as_array().unwrap().len(), 1, "{report}");
        // The variant's name: the clip's, made a USD identifier.
        let variant: String = (name.chars())
            .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
            .collect();
        let usd: Vec<f64> = usd_world(py, &usdz, Some(&seconds), Some(&variant))
            .iter()
            .flat_map(|f| f.points.iter().flatten().copied())
            .collect();
        let dev = deviation(&usd, &ours.numbers, frame);
        eprintln!("{name}: usdz variant in UsdSkel vs glb clip in three.js: {dev:.2e}");
        assert!(dev <= 1e-5, "{name}: {dev:e}");
    }
}

/// The tracks of every animation of a glb: (clip, node, path) -> (times, values).
fn tracks(glb: &Path) -> BTreeMap<(String, String, String), (Vec<f32>, Vec<f32>)> {
    let (doc, buffers, _) = gltf::import(glb).unwrap();
    let mut out = BTreeMap::new();
    for anim in doc.animations() {
        let clip = anim.name().unwrap_or_default().to_string();
        for ch in anim.channels() {
            let reader = ch.reader(|b| Some(&buffers[b.index()].0[..]));
            let times: Vec<f32> = reader.read_inputs().unwrap().collect();
            use gltf::animation::util::ReadOutputs;
            let values: Vec<f32> = match reader.read_outputs().unwrap() {
                ReadOutputs::Translations(v) | ReadOutputs::Scales(v) => v.flatten().collect(),
                ReadOutputs::Rotations(r) => r.into_f32().flatten().collect(),
                ReadOutputs::MorphTargetWeights(w) => w.into_f32().collect(),
            };
            let node = ch.target().node().name().unwrap_or_default().to_string();
            let path = format!("{:?}", ch.target().property());
            out.insert((clip.clone(), node, path), (times, values));
        }
    }
    out
}

/// Every CMU 07 clip of the corpus onto `07-walk.asf` (the AMC files given alone go with
/// the `.asf` rig): taken directly, with tracks equal to `convert` of each ASF/AMC pair.
/// The corpus' folder of CMU subjects as one motion: 07 taken, the other subjects' clips
/// retargeted.
#[test]
fn cmu_07_clips_onto_their_asf_are_taken_as_convert_writes_them() {
    let (Some(asf), Some(folder)) = (corpus(&format!("{CMU}/07-walk.asf")), corpus(CMU)) else {
        return;
    };
    let amcs: Vec<PathBuf> = std::fs::read_dir(&folder)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| {
            let name = p.file_name().unwrap().to_string_lossy().to_string();
            name.starts_with("07_") && name.ends_with(".amc")
        })
        .collect();
    assert!(!amcs.is_empty());
    let dir = scratch();
    let glb = dir.path().join("cmu.glb");
    let mut args = vec![s(&asf)];
    args.extend(amcs.iter().map(|p| s(p)));
    args.extend(["-o", s(&glb)]);
    let report = combine_json(&args);
    let combined = tracks(&glb);
    for (clip, amc) in report["clips"].as_array().unwrap().iter().zip(&amcs) {
        assert_eq!(clip["how"], "taken", "{clip}");
        let name = clip["clip"].as_str().unwrap();
        let single = dir.path().join("single.glb");
        rigport_ok(&["convert", "-q", s(&asf), s(amc), "-o", s(&single)]);
        let alone = tracks(&single);
        let mut compared = 0;
        let mut worst = 0.0f32;
        for ((_, node, path), (times, values)) in &alone {
            let key = (name.to_string(), node.clone(), path.clone());
            let (t, v) = combined.get(&key).unwrap_or_else(|| panic!("{key:?}"));
            assert_eq!(t.len(), times.len(), "{key:?}");
            for (a, b) in t.iter().zip(times).chain(v.iter().zip(values)) {
                worst = worst.max((a - b).abs());
            }
            compared += 1;
        }
        eprintln!("{name}: {compared} tracks taken, largest difference from convert {worst:e}");
        assert!(compared > 20 && worst <= 1e-7, "{name}: {worst:e}");
    }
    // The folder of subjects: 07 taken, the other subjects (other bone lengths)
    // retargeted, in sorted order.
    let report = combine_json(&[s(&asf), s(&folder), "-o", s(&dir.path().join("all.glb"))]);
    let hows: Vec<(String, String)> = report["clips"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| {
            (
                c["clip"].as_str().unwrap().into(),
                c["how"].as_str().unwrap().into(),
            )
        })
        .collect();
    eprintln!("the CMU folder onto 07-walk.asf: {hows:?}");
    assert_eq!(hows[0], ("07_05-walk".to_string(), "taken".to_string()));
    assert!(
        hows[1..].iter().all(|(_, how)| how == "retargeted"),
        "{hows:?}"
    );
}

/// BVH, ASF/AMC, a glTF clip and an animation-only FBX in one run onto `human_model1`.
#[test]
fn every_motion_kind_in_one_run() {
    let files = [
        "4_bvh/cmu_cgspeed__nobuyuki83_delfem2/walk.bvh",
        &format!("{CMU}/09-run.asf"),
        &format!("{CMU}/09_06-run.amc"),
        "5_gltf/khronos_samples__nobuyuki83_delfem2/CesiumMan.glb",
        "7_fbx/assimp_test_models__assimp/animation_with_skeleton.fbx",
    ]
    .map(corpus);
    let (Some(rig), Some(files)) = (
        corpus(HUMAN_MODEL1),
        files.into_iter().collect::<Option<Vec<_>>>(),
    ) else {
        return;
    };
    let dir = scratch();
    let glb = dir.path().join("mixed.glb");
    let mut args = vec![s(&rig)];
    args.extend(files.iter().map(|p| s(p)));
    args.extend([
        "--plant-feet",
        "--fps",
        "30",
        "--amc-fps",
        "120",
        "-o",
        s(&glb),
    ]);
    let report = combine_json(&args);
    let clips = report["clips"].as_array().unwrap();
    for c in clips {
        eprintln!(
            "{}: {} from {}, {} frames, {:.2} s, slide {} -> {}",
            c["clip"],
            c["how"],
            c["source"],
            c["frames"],
            c["duration_s"].as_f64().unwrap(),
            c["slide_unplanted"],
            c["slide_planted"]
        );
        assert_eq!(c["how"], "retargeted");
    }
    let names: Vec<&str> = clips.iter().map(|c| c["clip"].as_str().unwrap()).collect();
    assert!(names.len() >= 4, "{names:?}");
    assert_eq!(&names[..3], ["walk", "09_06-run", "CesiumMan"]);
    assert_valid(&glb);
}

/// Names: file stems, `--name` overrides, repeats suffixed with a warning; a broken
/// motion exits 1 naming it and writes nothing; a rig without a skeleton is a usage error.
#[test]
fn names_repeats_and_errors() {
    let dir = scratch();
    let bvh = repo().join("fixtures/bvh/end_sites.bvh");
    let other = repo().join("fixtures/bvh/mixed_orders.bvh");
    let out = dir.path().join("named.glb");
    // mixed_orders.bvh is no body: its joints are mapped by name onto the rig's.
    let map = dir.path().join("map.json");
    std::fs::write(&map, r#"{"joints": {"Hips": "Hips", "Head": "Head"}}"#).unwrap();
    let run = rigport(&[
        "combine",
        "--json",
        s(&bvh),
        s(&bvh),
        s(&other),
        s(&bvh),
        "--name",
        "mixed_orders=spin",
        "--map",
        s(&map),
        "-o",
        s(&out),
    ]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    let report: serde_json::Value = serde_json::from_slice(&run.stdout).unwrap();
    let names: Vec<&str> = (report["clips"].as_array().unwrap().iter())
        .map(|c| c["clip"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["end_sites", "spin", "end_sites_2"]);
    assert!(
        stderr.contains("warning[W003]") && stderr.contains("end_sites_2"),
        "{stderr}"
    );
    assert_valid(&out);

    let broken = dir.path().join("broken.bvh");
    std::fs::write(&broken, "HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0\n").unwrap();
    let none = dir.path().join("none.glb");
    let run = rigport(&["combine", s(&bvh), s(&bvh), s(&broken), "-o", s(&none)]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("broken.bvh"), "{stderr}");
    assert!(!none.exists());

    let obj = dir.path().join("plane.obj");
    std::fs::write(&obj, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let run = rigport(&["combine", s(&obj), s(&bvh), "-o", s(&none)]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("no skeleton"), "{stderr}");
    let run = rigport(&[
        "combine",
        s(&bvh),
        s(&bvh),
        "--name",
        "nope=x",
        "-o",
        s(&none),
    ]);
    assert_eq!(run.status.code(), Some(2));
    assert!(!none.exists());
}

//! `rigport footlock` on every corpus BVH and ASF/AMC clip (issue 16): during the contacts
//! it reports, the feet hold still to 1e-3 of the skeleton's height; the output validates
//! clean; every joint outside the legs is where the source puts it. Measured on the
//! written glTF with the test-only reader and sampler, against `rigport convert` of the
//! same input.

use std::collections::HashSet;
use std::path::Path;

use rigport_model::glam::Vec3;

use crate::common::*;
use crate::gltf_read::{self, GltfScene};
use crate::motion::{gltf_pose, ASF_AMC, BVH};

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Per frame (the animation's key times), every node's world position.
fn frames(scene: &GltfScene) -> Vec<Vec<Vec3>> {
    let times = scene.animations[0]
        .channels
        .iter()
        .map(|c| &c.times)
        .max_by_key(|t| t.len())
        .unwrap()
        .clone();
    times.iter().map(|&t| gltf_pose(scene, 0, t)).collect()
}

/// The nodes below (and at) each leg's hip: the ankle's grandparent.
fn leg_nodes(scene: &GltfScene, ankles: &[String]) -> HashSet<usize> {
    let by_name = scene.node_by_name();
    let hips: Vec<usize> = ankles
        .iter()
        .map(|a| {
            let ankle = by_name[a.as_str()];
            let knee = scene.parents[ankle].unwrap();
            scene.parents[knee].unwrap()
        })
        .collect();
    (0..scene.parents.len())
        .filter(|&n| {
            let mut cur = Some(n);
            while let Some(c) = cur {
                if hips.contains(&c) {
                    return true;
                }
                cur = scene.parents[c];
            }
            false
        })
        .collect()
}

/// Runs footlock and convert on `input`, checks the three acceptance points and prints the
/// slides.
fn check(label: &str, input: &[&str]) {
    let dir = scratch();
    let (src, out) = (dir.path().join("src.glb"), dir.path().join("out.glb"));
    let mut args = vec!["footlock"];
    args.extend_from_slice(input);
    args.extend_from_slice(&["-o", s(&out), "--json", "--quiet"]);
    let run = rigport(&args);
    assert!(
        run.status.success(),
        "{label}: {}",
        String::from_utf8_lossy(&run.stderr)
    );
    let report: serde_json::Value = serde_json::from_slice(&run.stdout).unwrap();
    let mut convert = vec!["convert"];
    convert.extend_from_slice(input);
    convert.extend_from_slice(&["-o", s(&src), "--quiet"]);
    rigport_ok(&convert);
    assert_valid(&out);

    let (a, b) = (gltf_read::read(&src), gltf_read::read(&out));
    let (before, after) = (frames(&a), frames(&b));
    assert_eq!(before.len(), after.len(), "{label}: frame count");
    assert_eq!(before.len() as u64, report["frames"].as_u64().unwrap());
    let lo = before[0].iter().fold(Vec3::MAX, |m, p| m.min(*p));
    let hi = before[0].iter().fold(Vec3::MIN, |m, p| m.max(*p));
    let height = f64::from((hi - lo).max_element());
    let by_name = b.node_by_name();

    let feet = report["feet"].as_array().unwrap();
    let ankles: Vec<String> = feet
        .iter()
        .map(|f| f["ankle"].as_str().unwrap().to_string())
        .collect();
    let legs = leg_nodes(&b, &ankles);
    let mut outside = 0.0f64;
    for (fa, fb) in before.iter().zip(&after) {
        for (n, (pa, pb)) in fa.iter().zip(fb).enumerate() {
            if !legs.contains(&n) {
                outside = outside.max(f64::from((*pa - *pb).length()));
            }
        }
    }
    assert!(
        outside <= 1e-5 * height,
        "{label}: a joint outside the legs moved {:.3e} of the height",
        outside / height
    );

    let mut contacts = 0;
    for foot in feet {
        let (mut src_max, mut out_max) = (0.0f64, 0.0f64);
        for c in foot["contacts"].as_array().unwrap() {
            let node = by_name[c["joint"].as_str().unwrap()];
            let (start, end) = (
                c["start_frame"].as_u64().unwrap() as usize,
                c["end_frame"].as_u64().unwrap() as usize,
            );
            for f in start..=end {
                let d = |fr: &[Vec<Vec3>]| f64::from((fr[f][node] - fr[start][node]).length());
                src_max = src_max.max(d(&before) / height);
                out_max = out_max.max(d(&after) / height);
            }
            contacts += 1;
        }
        eprintln!(
            "{label}: foot {}: {} contacts, slide before {src_max:.3e}, after {out_max:.3e} of the height (report: {:.3e} -> {:.3e}, stretch {:.2}%)",
            foot["label"].as_str().unwrap(),
            foot["contacts"].as_array().unwrap().len(),
            foot["slide_before"]["max"].as_f64().unwrap(),
            foot["slide_after"]["max"].as_f64().unwrap(),
            100.0 * foot["stretch"].as_f64().unwrap(),
        );
        assert!(
            out_max <= 1e-3,
            "{label}: foot {} slides {out_max:.3e} of the height during its contacts",
            foot["label"]
        );
    }
    assert!(contacts > 0, "{label}: no contact detected");
    eprintln!(
        "{label}: joints outside the legs moved at most {:.1e} of the height",
        outside / height
    );
}

#[test]
fn footlock_holds_the_feet_of_every_corpus_asf_amc_clip() {
    for (asf, amc) in ASF_AMC {
        let (Some(asf), Some(amc)) = (corpus(asf), corpus(amc)) else {
            return;
        };
        let label = amc.file_name().unwrap().to_string_lossy().into_owned();
        check(&label, &[s(&asf), "--motion", s(&amc)]);
    }
}

#[test]
fn footlock_holds_the_feet_of_every_corpus_bvh_clip() {
    for rel in BVH {
        let Some(path) = corpus(rel) else {
            return;
        };
        let label = path.file_name().unwrap().to_string_lossy().into_owned();
        check(&label, &[s(&path)]);
    }
}

#[test]
fn footlock_rejects_unknown_feet_and_rigs_without_feet() {
    let dir = scratch();
    let out = dir.path().join("out.glb");
    // Two joints and no leg: no foot by any known name.
    let bvh = dir.path().join("arm.bvh");
    std::fs::write(
        &bvh,
        "HIERARCHY\nROOT Shoulder\n{\n  OFFSET 0 0 0\n  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n  JOINT Elbow\n  {\n    OFFSET 1 0 0\n    CHANNELS 3 Zrotation Xrotation Yrotation\n    End Site\n    {\n      OFFSET 1 0 0\n    }\n  }\n}\nMOTION\nFrames: 3\nFrame Time: 0.1\n0 0 0 0 0 0 0 0 0\n0 0 0 10 0 0 5 0 0\n0 0 0 20 0 0 10 0 0\n",
    )
    .unwrap();
    let cases: [(&[&str], &str); 3] = [
        (&[s(&bvh)], "no feet found"),
        (
            &[s(&bvh), "--foot", "Ankle,Toe"],
            "no joint named \"Ankle\"",
        ),
        (&[s(&bvh), "--foot", "Elbow"], "\"Elbow\" cannot be a foot"),
    ];
    for (input, message) in cases {
        let mut args = vec!["footlock"];
        args.extend_from_slice(input);
        args.extend_from_slice(&["-o", s(&out)]);
        let run = rigport(&args);
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert_eq!(run.status.code(), Some(1), "{input:?}: {stderr}");
        assert!(stderr.contains(message), "{input:?}: {stderr}");
        assert!(!out.exists(), "{input:?}: no output on failure");
    }
}

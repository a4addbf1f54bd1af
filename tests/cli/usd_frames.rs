//! Issue 22, file by file: USD as people ship it (Blender `.usda`, tinyusdz `.usdc`,
//! Reality Converter `.usdz`, and usd-core fixtures written all three ways) converts to a
//! `.glb` that three.js plays like UsdSkel's evaluation of the source in +Y-up metres (1e-5
//! of the diagonal, every key time), and to a `.usda` that UsdSkel evaluates like the
//! source (1e-6); Pixar's bake tests' `.usda` equal Pixar's baked baselines (1e-6).

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::common::*;
use crate::frames::{deviation, diagonal, usd_world, Frame};
use crate::gltf_read;
use crate::three::three_eval;
use crate::usd::{check_usd, python};

const USD: &str = "6_usd";

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn dist(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>().sqrt()
}

/// The key times (seconds) of the source's first clip as `rigport eval` samples it;
/// `None` without a clip (then the default time is compared).
fn key_times(source: &Path, dir: &Path) -> Option<Vec<f64>> {
    let npz = dir.join("keys.npz");
    rigport_ok(&["eval", s(source), "--out", s(&npz), "--quiet"]);
    read_npz(&npz).get("times").map(|t| t.numbers.clone())
}

/// What the checks measured for one source: `.usda` and `.glb` against the source.
struct Measured {
    usda: f64,
    glb: f64,
}

/// three.js's world positions of every glTF vertex at `times` (the first clip), per frame.
fn three_frames(glb: &Path, times: Option<&[f64]>) -> Option<Vec<Vec<[f64; 3]>>> {
    let animated = !gltf_read::read(glb).animations.is_empty();
    let list = times.map(|t| {
        t.iter()
            .map(|x| format!("{x}"))
            .collect::<Vec<_>>()
            .join(",")
    });
    let mut args: Vec<&str> = Vec::new();
    if animated {
        args.extend(["--clip-index", "0"]);
    }
    if let (true, Some(l)) = (animated, &list) {
        args.extend(["--times", l.as_str()]);
    }
    let (_, npy) = three_eval(glb, &args)?;
    let (frames, v) = (npy.shape[0], npy.shape[1]);
    Some(
        (0..frames)
            .map(|f| {
                (0..v)
                    .map(|i| [0, 1, 2].map(|k| npy.numbers[(f * v + i) * 3 + k]))
                    .collect()
            })
            .collect(),
    )
}

/// The largest deviation, relative to each frame's diagonal, of three's glTF vertices
/// from the source points: each glTF vertex (split on seams) is matched with the source
/// point whose trajectory is nearest.
fn glb_deviation(three: &[Vec<[f64; 3]>], want: &[Frame]) -> f64 {
    let frames = three.len().min(want.len());
    assert!(frames > 0);
    let n = want[0].points.len();
    let v = three[0].len();
    let cost = |i: usize, a: usize| -> f64 {
        (0..frames)
            .map(|f| dist(&three[f][i], &want[f].points[a]))
            .sum()
    };
    let map: Vec<usize> = (0..v)
        .map(|i| {
            (0..n)
                .min_by(|&a, &b| cost(i, a).total_cmp(&cost(i, b)))
                .unwrap()
        })
        .collect();
    let mut dev = 0.0f64;
    for f in 0..frames {
        let d = diagonal(&want[f].points).max(1e-30);
        for (i, &a) in map.iter().enumerate() {
            dev = dev.max(dist(&three[f][i], &want[f].points[a]) / d);
        }
    }
    dev
}

/// Binding properties on prims without `SkelBindingAPI` (tinyusdz's `usdskel-001`):
/// usd-core 23.08 and later ignore them, so its evaluation of such a file neither animates
/// nor skins; rigport reads them (with a warning on a skinned mesh, `skin.rs`). The reference for such a
/// source is then usd-core's evaluation of a copy with the API applied where binding
/// properties are authored: the file as its author meant it.
const APPLY_BINDING_API: &str = r#"
import sys
from pxr import Usd, UsdSkel
s = Usd.Stage.Open(sys.argv[1])
n = 0
for p in s.Traverse():
    if not p.HasAPI(UsdSkel.BindingAPI) and any(
            a.startswith(("skel:", "primvars:skel:")) for a in p.GetPropertyNames()):
        UsdSkel.BindingAPI.Apply(p)
        n += 1
if n:
    s.Export(sys.argv[2])
print(n)
"#;

/// `source`, or the copy [`APPLY_BINDING_API`] makes when it applies the API somewhere.
fn reference(py: &Path, source: &Path, dir: &Path) -> PathBuf {
    let name = source
        .file_name()
        .unwrap()
        .to_string_lossy()
        .replace('.', "_");
    let copy = dir.join(format!("{name}_bound.usda"));
    let out = Command::new(py)
        .args(["-c", APPLY_BINDING_API])
        .arg(source)
        .arg(&copy)
        .output()
        .expect("python runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    if String::from_utf8_lossy(&out.stdout).trim() == "0" {
        return source.to_path_buf();
    }
    copy
}

/// Converts `source` to `.glb` (glTF-Validator clean) and `.usda` (usd-core's validators
/// and tools/check_usd.py), and measures both against UsdSkel's evaluation of the source
/// in +Y-up metres at its key times. `None` when three.js is missing (skip).
fn measure(py: &Path, source: &Path, dir: &Path) -> Option<Measured> {
    let name = source
        .file_name()
        .unwrap()
        .to_string_lossy()
        .replace('.', "_");
    let glb = dir.join(format!("{name}.glb"));
    let usda = dir.join(format!("{name}.usda"));
    rigport_ok(&["convert", s(source), "-o", s(&glb), "--quiet"]);
    assert_valid(&glb);
    rigport_ok(&["convert", s(source), "-o", s(&usda), "--quiet"]);
    let (ok, report) = check_usd(py, &usda, None);
    assert!(ok, "{}: {report}", source.display());
    let times = key_times(source, dir);
    let reference = reference(py, source, dir);
    let want = usd_world(py, &reference, times.as_deref(), None);
    let got = usd_world(py, &usda, times.as_deref(), None);
    assert_eq!(got.len(), want.len());
    let usda_dev = got
        .iter()
        .zip(&want)
        .map(|(g, w)| deviation(&g.points, &w.points))
        .fold(0.0, f64::max);
    if want.iter().all(|f| f.points.is_empty()) {
        // Nothing to draw (tinyusdz's inbetween test holds a lone BlendShape prim).
        eprintln!("{}: no points to compare", source.display());
        return Some(Measured {
            usda: usda_dev,
            glb: 0.0,
        });
    }
    let three = three_frames(&glb, times.as_deref())?;
    let glb_dev = glb_deviation(&three, &want);
    eprintln!(
        "{}: {} frames; .usda vs source under UsdSkel {usda_dev:e}, .glb in three.js vs \
         UsdSkel in Y-up metres {glb_dev:e} (of the diagonal)",
        source.display(),
        want.len()
    );
    Some(Measured {
        usda: usda_dev,
        glb: glb_dev,
    })
}

/// Runs [`measure`] on every source, failing with every source over `usda_tol` / `glb_tol`.
fn measure_all(sources: &[PathBuf], usda_tol: f64, glb_tol: f64) {
    let Some(py) = python() else {
        return;
    };
    let dir = scratch();
    let mut report = Vec::new();
    for source in sources {
        let Some(m) = measure(&py, source, dir.path()) else {
            return;
        };
        if m.usda > usda_tol || m.glb > glb_tol {
            report.push(format!(
                "{}: usda {:e}, glb {:e}",
                source.display(),
                m.usda,
                m.glb
            ));
        }
    }
    assert!(report.is_empty(), "{report:#?}");
}

#[test]
fn reality_converter_usdz_with_animated_transforms_play_in_glb_and_usda() {
    let sources: Vec<PathBuf> = ["AnimatedCube", "BoxAnimated", "AnimatedTriangle"]
        .iter()
        .filter_map(|n| corpus(&format!("{USD}/usdz_test_assets__usd-wg/{n}.usdz")))
        .collect();
    // The static meshes move: their transforms are not frozen at the default time.
    if let Some(cube) = sources.first() {
        let dir = scratch();
        let glb = dir.path().join("cube.glb");
        let stderr = rigport_ok(&["convert", s(cube), "-o", s(&glb)]);
        assert!(stderr.contains("1 clips"), "{stderr}");
        assert!(!stderr.contains("default time is used"), "{stderr}");
        // In USD the mesh keeps its own animated xformOps, as in the source.
        let usda = dir.path().join("cube.usda");
        rigport_ok(&["convert", s(cube), "-o", s(&usda), "--quiet"]);
        let text = std::fs::read_to_string(&usda).unwrap();
        assert!(
            text.contains("quatf xformOp:orient.timeSamples = {"),
            "{text}"
        );
        assert!(
            !text.contains("jointIndices"),
            "not a rigid binding: {text}"
        );
    }
    measure_all(&sources, 1e-6, 1e-5);
}

#[test]
fn tinyusdz_crate_files_convert_like_usdskel_evaluates_them() {
    let sources: Vec<PathBuf> = [
        "tests_usdc_usdskel-001.usdc",
        "tests_usdc_skeleton-purpose-001.usdc",
        "tests_usdc_inbetween-blendshape-001.usdc",
        "models_blendshape.usdc",
    ]
    .iter()
    .filter_map(|n| corpus(&format!("{USD}/tinyusdz_tests__lighttransport/{n}")))
    .collect();
    // usdskel-001 is UsdSkel's arm with its 4-digit quaternion (0.7071, 0.7071, 0, 0),
    // normalized with a warning as arm.usda's (1.5e-5 of the diagonal, expected).
    let (arm, rest): (Vec<PathBuf>, Vec<PathBuf>) = sources
        .into_iter()
        .partition(|p| p.ends_with("tests_usdc_usdskel-001.usdc"));
    measure_all(&rest, 1e-6, 1e-5);
    measure_all(&arm, 2e-5, 2e-5);
}

/// arm.usda's 4-digit quaternions ((0.7071, 0.7071, 0, 0)) are normalized with a warning,
/// which moves it by 1.5e-5 of the diagonal (measured, both outputs): that difference is
/// expected.
#[test]
fn blender_arms_play_in_three_like_usdskel_in_y_up_metres() {
    let arm = corpus(&format!("{USD}/ustc_cg_24_hw10__USTC-CG/arm.usda"));
    let cloth = corpus(&format!(
        "{USD}/ustc_cg_24_hw10__USTC-CG/arm_with_cloth.usda"
    ));
    measure_all(&cloth.into_iter().collect::<Vec<_>>(), 1e-6, 1e-5);
    measure_all(&arm.into_iter().collect::<Vec<_>>(), 2e-5, 2e-5);
}

/// tests/cli/usd_frames.py: a Z-up, centimetre stage with animated xforms above a scaled and
/// rotated SkelRoot, blend shapes with an inbetween and an animated static mesh, written
/// as `.usda`, `.usdc` and `.usdz`.
#[test]
fn usd_core_fixture_in_text_crate_and_package_plays_everywhere() {
    let Some(py) = python() else {
        return;
    };
    let dir = scratch();
    let out = Command::new(&py)
        .arg(repo().join("tests/cli/usd_frames.py"))
        .arg(dir.path())
        .output()
        .expect("python runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let sources: Vec<PathBuf> = ["usda", "usdc", "usdz"]
        .iter()
        .map(|e| dir.path().join(format!("frames.{e}")))
        .collect();
    measure_all(&sources, 1e-6, 1e-5);
}

/// UsdSkel's evaluation of rigport's `.usda` of Pixar's bake inputs against Pixar's
/// `baseline/*.baked.usda`, mesh by mesh (same name, same point count), at every baked
/// time code: the largest deviation relative to the baked frame's diagonal.
const AGAINST_BASELINE: &str = r#"
import json, sys
import numpy as np
from pxr import Usd, UsdGeom
sys.path.insert(0, sys.argv[3])
import check_usd as cu
ours, base = Usd.Stage.Open(sys.argv[1]), Usd.Stage.Open(sys.argv[2])
cache, skinning, _ = cu.skel_queries_of(ours)
baked = [p for p in base.Traverse() if p.IsA(UsdGeom.Mesh)]
mine = {p.GetName(): p for p in ours.Traverse() if p.IsA(UsdGeom.Mesh)}
times = UsdGeom.Mesh(baked[0]).GetPointsAttr().GetTimeSamples()
counts, worst = [], 0.0
from pxr import Vt
for tc in times:
    want, got = [], []
    for p in baked:
        w = np.asarray(UsdGeom.Mesh(p).GetPointsAttr().Get(tc), dtype=np.float64)
        m = np.asarray(UsdGeom.XformCache(tc).GetLocalToWorldTransform(p))
        want.append(w @ m[:3, :3] + m[3, :3])
        q = mine[p.GetName()]
        pts = Vt.Vec3fArray(UsdGeom.Mesh(q).GetPointsAttr().Get(tc))
        sq, query = skinning[q.GetPath()]
        assert query.ComputeSkinnedPoints(sq.ComputeSkinningTransforms(tc), pts, tc)
        m = np.asarray(UsdGeom.XformCache(tc).GetLocalToWorldTransform(sq.GetPrim()))
        got.append(np.asarray(pts, dtype=np.float64) @ m[:3, :3] + m[3, :3])
        counts.append([p.GetName(), len(w), len(pts)])
    w, g = np.concatenate(want), np.concatenate(got)
    d = np.linalg.norm(w.max(0) - w.min(0))
    worst = max(worst, float(np.linalg.norm(g - w, axis=1).max() / d))
print(json.dumps({"worst": worst, "frames": len(times), "counts": counts[:len(baked)]}))
"#;

#[test]
fn pixar_bake_inputs_as_usda_equal_pixars_baselines() {
    const BAKE: &str = "6_usd/openusd_usdskel__PixarAnimationStudios/testUsdSkelBakeSkinning";
    let Some(py) = python() else {
        return;
    };
    let dir = scratch();
    for name in ["lbs", "dqs"] {
        let (Some(source), Some(baseline)) = (
            corpus(&format!("{BAKE}/{name}.usda")),
            corpus(&format!("{BAKE}/baseline/{name}.baked.usda")),
        ) else {
            continue;
        };
        let out = dir.path().join(format!("{name}.usda"));
        rigport_ok(&["convert", s(&source), "-o", s(&out), "--quiet"]);
        let run = Command::new(&py)
            .args(["-c", AGAINST_BASELINE])
            .arg(&out)
            .arg(&baseline)
            .arg(repo().join("tools"))
            .output()
            .expect("python runs");
        assert!(
            run.status.success(),
            "{}",
            String::from_utf8_lossy(&run.stderr)
        );
        let v: serde_json::Value = serde_json::from_slice(&run.stdout).unwrap();
        for c in v["counts"].as_array().unwrap() {
            assert_eq!(c[1], c[2], "{name}: point counts {c}");
        }
        let worst = v["worst"].as_f64().unwrap();
        eprintln!(
            "{name}.usda -> .usda vs Pixar's {name}.baked.usda, {} time codes: {worst:e} of \
             the diagonal",
            v["frames"]
        );
        assert!(worst <= 1e-6, "{name}: {worst:e}");
    }
}

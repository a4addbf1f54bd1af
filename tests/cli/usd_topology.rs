//! USD -> USD keeps mesh topology (issue 22): points are not split on face-varying
//! normals or UVs, polygons stay polygons, face-varying primvars stay face-varying.

use std::process::Command;

use crate::common::*;
use crate::usd::{check_usd, python};

/// Per Mesh (in stage order): name, point count, faceVertexCounts, faceVertexIndices and
/// the normals' interpolation, as usd-core reads them.
const TOPOLOGY: &str = r#"
import json, sys
from pxr import Usd, UsdGeom
out = []
stage = Usd.Stage.Open(sys.argv[1])
for p in stage.Traverse():
    if p.IsA(UsdGeom.Mesh):
        m = UsdGeom.Mesh(p)
        out.append([p.GetName(), len(m.GetPointsAttr().Get()),
                    list(m.GetFaceVertexCountsAttr().Get()),
                    list(m.GetFaceVertexIndicesAttr().Get()), m.GetNormalsInterpolation()])
print(json.dumps(out))
"#;

fn topology(py: &std::path::Path, stage: &std::path::Path) -> serde_json::Value {
    let out = Command::new(py)
        .args(["-c", TOPOLOGY])
        .arg(stage)
        .output()
        .expect("python runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

#[test]
fn usd_to_usda_keeps_points_faces_and_face_varying_normals() {
    let Some(source) =
        corpus("6_usd/openusd_usdskel__PixarAnimationStudios/testUsdSkelBakeSkinning/lbs.usda")
    else {
        return;
    };
    let Some(py) = python() else {
        return;
    };
    let dir = scratch();
    let out = dir.path().join("lbs.usda");
    rigport_ok(&[
        "convert",
        source.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    let (ok, report) = check_usd(&py, &out, None);
    assert!(ok, "{report}");
    let want = topology(&py, &source);
    let got = topology(&py, &out);
    // The source's three Meshes (its curves and implicit surfaces are not imported).
    assert_eq!(
        got, want,
        "points, faces and normals' interpolation are the source's"
    );
    let fv = got
        .as_array()
        .unwrap()
        .iter()
        .find(|m| m[0] == "MeshWithFaceVaryingNormals")
        .unwrap();
    assert_eq!(fv[1], 12, "12 points stay 12");
    assert_eq!(fv[4], "faceVarying");
    assert!(
        !std::fs::read_to_string(&out)
            .unwrap()
            .contains("rigport:sourceVertex"),
        "points are the source's: no map needed"
    );
}

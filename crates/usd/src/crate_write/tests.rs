//! Round trips: text -> our crate writer -> our crate reader gives the text's layer.

use std::path::Path;

use super::write;
use crate::layer::{Layer, Meta, PrimBody, Value};
use crate::parse::parse;

/// Line and column numbers cleared (a binary layer has none).
pub(crate) fn without_lines(layer: &Layer) -> Layer {
    fn metas(m: &mut [Meta]) {
        for x in m {
            x.line = 0;
            // A list op of one item may be written without brackets.
            if matches!(x.key.as_str(), "variantSets" | "apiSchemas")
                && !matches!(x.value, Value::List(_))
            {
                x.value = Value::List(vec![x.value.clone()]);
            }
        }
    }
    fn body(b: &mut PrimBody) {
        for p in &mut b.props {
            p.line = 0;
            p.column = 0;
            metas(&mut p.meta);
        }
        for c in &mut b.children {
            c.line = 0;
            metas(&mut c.meta);
            body(&mut c.body);
        }
        for s in &mut b.variant_sets {
            s.line = 0;
            for (_, m, b) in &mut s.variants {
                metas(m);
                body(b);
            }
        }
    }
    let mut out = layer.clone();
    metas(&mut out.meta);
    body(&mut out.root);
    out
}

pub(crate) const SAMPLE: &str = r#"#usda 1.0
(
    defaultPrim = "Root"
    doc = "made by a test"
    endTimeCode = 2
    metersPerUnit = 0.01
    startTimeCode = 0
    timeCodesPerSecond = 24
    upAxis = "Z"
)

def SkelRoot "Root" (
    prepend apiSchemas = ["SkelBindingAPI"]
    kind = "component"
    variants = {
        string clip = "b"
    }
    prepend variantSets = "clip"
)
{
    def Skeleton "Skel"
    {
        uniform token[] joints = ["a", "a/b"]
        uniform matrix4d[] bindTransforms = [( (1, 0, 0, 0), (0, 1, 0, 0), (0, 0, 1, 0), (0, 0, 0, 1) ), ( (1, 0, 0, 0), (0, 1, 0, 0), (0, 0, 1, 0), (0, 2.5, 0, 1) )]
        rel skel:animationSource = </Root/Anim>
    }

    def SkelAnimation "Anim"
    {
        uniform token[] joints = ["a", "a/b"]
        quatf[] rotations.timeSamples = {
            0: [(1, 0, 0, 0), (0.70710677, 0.70710677, 0, 0)],
            2: [(1, 0, 0, 0), (0, 1, 0, 0)],
        }
        half3[] scales = [(1, 1, 1), (0.5, 2, 1)]
        float3[] translations = [(0, 0, 0), (0, 2.5, 0)]
        float[] blendShapeWeights.timeSamples = {
            1: [0.25],
        }
    }

    def Mesh "Mesh" (
        prepend apiSchemas = ["SkelBindingAPI", "MaterialBindingAPI"]
    )
    {
        int[] faceVertexCounts = [3]
        int[] faceVertexIndices = [0, 1, 2]
        point3f[] points = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]
        normal3f[] normals = [(0, 0, 1), (0, 0, 1), (0, 0, 1)] (
            interpolation = "vertex"
        )
        texCoord2f[] primvars:st = [(0, 0), (1, 0), (0, 1)] (
            interpolation = "vertex"
        )
        int[] primvars:skel:jointIndices = [0, 1, 1, 1, 0, 0] (
            elementSize = 2
            interpolation = "vertex"
        )
        float[] primvars:skel:jointWeights = [0.5, 0.5, 1, 0, 1, 0] (
            elementSize = 2
            interpolation = "vertex"
        )
        int[] primvars:rigport:sourceVertex = [0, 1, 2, 3, 3, 3, 4, -5, 70000, -2147483648, 2147483647, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16] (
            interpolation = "vertex"
        )
        uniform token primvars:skel:skinningMethod = "dualQuaternion"
        uniform token subdivisionScheme = "none"
        double3 xformOp:translate = (1, 2, 3)
        uniform token[] xformOpOrder = ["xformOp:translate"]
        rel material:binding = </Root/Mat>
        rel skel:skeleton = </Root/Skel>
    }

    def Material "Mat"
    {
        token outputs:surface.connect = </Root/Mat/Surface.outputs:surface>

        def Shader "Surface"
        {
            uniform token info:id = "UsdPreviewSurface"
            color3f inputs:diffuseColor.connect = </Root/Mat/Tex.outputs:rgb>
            float inputs:roughness = 0.5
            token outputs:surface
        }

        def Shader "Tex"
        {
            uniform token info:id = "UsdUVTexture"
            asset inputs:file = @tex.png@
            token inputs:wrapS = "repeat"
            float3 outputs:rgb
        }
    }
    variantSet "clip" = {
        "a" (
            customData = {
                double endTimeCode = 1
                double startTimeCode = 0
            }
        ) {
            over "Skel"
            {
                rel skel:animationSource = </Root/Anim>
            }

        }
        "b" {
            over "Skel"
            {
                rel skel:animationSource = </Root/Anim>
            }

        }
    }
}
"#;

#[test]
fn our_reader_reads_what_we_write() {
    let path = Path::new("sample.usda");
    let text = parse(SAMPLE, path).unwrap();
    let bytes = write(&text, path).unwrap();
    let back = crate::crate_file::read(&bytes, Path::new("sample.usdc")).unwrap();
    let expected = without_lines(&text);
    assert_eq!(back.meta, expected.meta);
    for (a, b) in back.root.children.iter().zip(&expected.root.children) {
        assert_eq!(a, b);
    }
    assert_eq!(back, expected);
}

#[test]
fn bad_values_name_their_line() {
    let path = Path::new("bad.usda");
    let text = parse(
        "#usda 1.0\ndef Xform \"A\"\n{\n    float3 x = (1, 2)\n}\n",
        path,
    )
    .unwrap();
    let e = write(&text, path).unwrap_err().to_string();
    assert!(
        e.starts_with("bad.usda:4: default: 2 numbers where 3 are needed"),
        "{e}"
    );
    let text = parse("#usda 1.0\ndef Xform \"A\"\n{\n    foo3 x = 1\n}\n", path).unwrap();
    let e = write(&text, path).unwrap_err().to_string();
    assert!(e.contains("unknown value type \"foo3\""), "{e}");
}

/// The venv's Python (`RIGPORT_PYTHON`, else `tools/.venv/bin/python`), or `None` when
/// absent (a failure when `CI` is set).
pub(crate) fn python() -> Option<std::path::PathBuf> {
    let path = std::env::var_os("RIGPORT_PYTHON")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| {
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tools/.venv/bin/python")
        });
    if path.exists() {
        return Some(path);
    }
    assert!(
        std::env::var_os("CI").is_none_or(|v| v.is_empty()),
        "{} is missing and CI is set: run bash tools/setup.sh",
        path.display()
    );
    eprintln!(
        "SKIPPED: {} not found (run bash tools/setup.sh)",
        path.display()
    );
    None
}

/// usd-core opens each pair (text, ours) and compares the layers as `Sdf` holds them:
/// every spec with its fields and values (`Sdf.Layer.ExportToString` of both, and spec by
/// spec the paths and info keys with values, which also shows the target and connection
/// specs the text leaves out).
pub(crate) const SAME_LAYER: &str = r#"
import sys
from pxr import Sdf
def fields(layer):
    out = {}
    def visit(path):
        spec = layer.GetObjectAtPath(path)
        keys = sorted(spec.ListInfoKeys()) if spec is not None and hasattr(spec, "ListInfoKeys") else []
        out[str(path)] = [(k, repr(spec.GetInfo(k))) for k in keys]
    layer.Traverse(Sdf.Path.absoluteRootPath, visit)
    return out
bad = 0
for i in range(1, len(sys.argv), 2):
    a = Sdf.Layer.OpenAsAnonymous(sys.argv[i])
    b = Sdf.Layer.OpenAsAnonymous(sys.argv[i + 1])
    assert a and b, sys.argv[i:i + 2]
    if a.ExportToString() != b.ExportToString():
        print("DIFFERENT TEXT", sys.argv[i], sys.argv[i + 1]); bad += 1
        import difflib
        for l in list(difflib.unified_diff(a.ExportToString().splitlines(), b.ExportToString().splitlines(), lineterm=""))[:40]: print(l)
    fa, fb = fields(a), fields(b)
    if fa != fb:
        bad += 1
        print("DIFFERENT FIELDS", sys.argv[i])
        for p in sorted(set(fa) | set(fb)):
            if fa.get(p) != fb.get(p): print(p, fa.get(p), fb.get(p))
sys.exit(1 if bad else 0)
"#;

#[test]
fn usd_core_reads_our_crate_file_as_the_text() {
    let Some(python) = python() else { return };
    let dir = tempfile::tempdir().unwrap();
    let usda = dir.path().join("sample.usda");
    let usdc = dir.path().join("sample.usdc");
    std::fs::write(&usda, SAMPLE).unwrap();
    let layer = parse(SAMPLE, &usda).unwrap();
    std::fs::write(&usdc, write(&layer, &usda).unwrap()).unwrap();
    let out = std::process::Command::new(python)
        .arg("-c")
        .arg(SAME_LAYER)
        .arg(&usda)
        .arg(&usdc)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn our_reader_reads_usd_cores_crate_file_and_ours_alike() {
    let Some(python) = python() else { return };
    let dir = tempfile::tempdir().unwrap();
    let usda = dir.path().join("sample.usda");
    let theirs = dir.path().join("theirs.usdc");
    std::fs::write(&usda, SAMPLE).unwrap();
    let status = std::process::Command::new(python)
        .arg("-c")
        .arg("import sys; from pxr import Sdf; assert Sdf.Layer.FindOrOpen(sys.argv[1]).Export(sys.argv[2])")
        .arg(&usda)
        .arg(&theirs)
        .status()
        .unwrap();
    assert!(status.success());
    let ours = write(&parse(SAMPLE, &usda).unwrap(), &usda).unwrap();
    let a = crate::crate_file::read(&std::fs::read(&theirs).unwrap(), &theirs).unwrap();
    let b = crate::crate_file::read(&ours, Path::new("ours.usdc")).unwrap();
    assert_eq!(a, b);
}

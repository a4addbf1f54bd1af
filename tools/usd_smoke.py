"""Smoke test for the Python side of rigport's test tooling (tools/.venv).

Checks that usd-core (pxr.Usd, pxr.UsdSkel, pxr.UsdGeom) and numpy import,
prints their versions, and round-trips a tiny in-memory SkelRoot/Skeleton stage
so a broken USD install fails here rather than deep inside a Rust test.

    tools/.venv/bin/python tools/usd_smoke.py

Exit 0 on success, 1 on any failure. The real USD checker comes later.
"""

from __future__ import annotations

import sys


def main() -> int:
    try:
        import numpy as np
        from pxr import Gf, Sdf, Usd, UsdGeom, UsdSkel, Vt
    except ImportError as exc:  # pragma: no cover - environment problem
        print(f"usd_smoke: import failed: {exc}", file=sys.stderr)
        print("usd_smoke: run `bash tools/setup.sh` and use tools/.venv/bin/python", file=sys.stderr)
        return 1

    from importlib.metadata import PackageNotFoundError, version

    try:
        usd_core = version("usd-core")
    except PackageNotFoundError:  # pxr from elsewhere (a USD build on PYTHONPATH)
        usd_core = "not from pip"
    pxr_version = ".".join(str(part) for part in Usd.GetVersion())
    print(f"usd_smoke: python {sys.version.split()[0]} ({sys.executable})")
    print(f"usd_smoke: usd-core {usd_core} (pxr.Usd.GetVersion() {pxr_version})")
    print(f"usd_smoke: numpy {np.__version__}")

    # A two-joint skeleton with a bind pose, written to a string and read back.
    stage = Usd.Stage.CreateInMemory("smoke.usda")
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.y)
    UsdGeom.SetStageMetersPerUnit(stage, 1.0)
    root = UsdSkel.Root.Define(stage, "/Rig")
    skel = UsdSkel.Skeleton.Define(stage, "/Rig/Skel")
    joints = ["hip", "hip/knee"]
    skel.CreateJointsAttr(joints)
    bind = np.stack([np.eye(4), np.eye(4)])
    bind[1, 3, 1] = 1.0  # knee one unit up (row-major, translation in row 3)
    skel.CreateBindTransformsAttr(Vt.Matrix4dArray.FromNumpy(bind))
    skel.CreateRestTransformsAttr([Gf.Matrix4d(1.0), Gf.Matrix4d(1.0).SetTranslate(Gf.Vec3d(0, 1, 0))])

    text = stage.GetRootLayer().ExportToString()
    layer = Sdf.Layer.CreateAnonymous(".usda")
    if not layer.ImportFromString(text):
        print("usd_smoke: FAILED to re-import the exported layer", file=sys.stderr)
        return 1
    stage2 = Usd.Stage.Open(layer)
    skel2 = UsdSkel.Skeleton(stage2.GetPrimAtPath("/Rig/Skel"))
    checks = {
        "SkelRoot prim": bool(root) and stage2.GetPrimAtPath("/Rig").IsA(UsdSkel.Root),
        "joints round-trip": list(skel2.GetJointsAttr().Get()) == joints,
        "bind transforms round-trip": np.allclose(np.array(skel2.GetBindTransformsAttr().Get()), bind),
        "skeleton topology valid": UsdSkel.Topology(skel2.GetJointsAttr().Get()).Validate()[0],
        "up axis Y": UsdGeom.GetStageUpAxis(stage2) == UsdGeom.Tokens.y,
    }
    failed = [name for name, ok in checks.items() if not ok]
    for name, ok in checks.items():
        print(f"usd_smoke: {'ok  ' if ok else 'FAIL'} {name}")
    if failed:
        print(f"usd_smoke: FAILED: {', '.join(failed)}", file=sys.stderr)
        return 1
    print("usd_smoke: OK")
    return 0


if __name__ == "__main__":
    sys.exit(main())

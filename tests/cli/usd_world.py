"""UsdSkel's evaluation of a stage in +Y-up metres, for tests/cli/frames.rs.

    python usd_world.py STAGE TOOLS_DIR SECONDS_JSON [--clip NAME] [--model-space]

Prints JSON: {"tcps", "up", "mpu", "frames": [{"joints": [[x,y,z]...], "points": [[x,y,z]...]}]}
Joints: the first Skeleton's joint world translations (ComputeJointWorldTransforms, every
xformOp above it applied); points: every Mesh under the default prim, skinned by UsdSkel
(tools/check_usd.py's `mesh_points`: blend shapes, skinning method, world transforms).
Both are then multiplied by the stage's metersPerUnit and turned +Y up ((x, y, z) ->
(x, z, -y) for a Z-up stage). SECONDS_JSON lists times in seconds (time code = seconds x
timeCodesPerSecond, snapped as check_usd.py does); `null` means the default time.
--model-space gives the points in the first Skeleton's space (rigport's model space: the
world points times the inverse of the Skeleton's world transform at that time) in the
stage's own units and axes, as `rigport eval` dumps them.
"""

import json
import sys

import numpy as np
from pxr import Usd, UsdGeom


def main() -> None:
    path, tools, seconds = sys.argv[1], sys.argv[2], json.loads(sys.argv[3])
    sys.path.insert(0, tools)
    import check_usd as cu

    stage = Usd.Stage.Open(path)
    if "--clip" in sys.argv:
        name = sys.argv[sys.argv.index("--clip") + 1]
        stage.GetDefaultPrim().GetVariantSet("clip").SetVariantSelection(name)
    cache, skinning, skel_queries = cu.skel_queries_of(stage)
    mpu = UsdGeom.GetStageMetersPerUnit(stage)
    up = UsdGeom.GetStageUpAxis(stage)
    tcps = stage.GetTimeCodesPerSecond()

    def fix(a):
        a = np.asarray(a, dtype=np.float64).reshape(-1, 3) * mpu
        if up == "Z":
            a = np.stack([a[:, 0], a[:, 2], -a[:, 1]], axis=1)
        return a.tolist()

    frames = []
    for s in seconds if seconds is not None else [None]:
        time = Usd.TimeCode.Default() if s is None else Usd.TimeCode(cu.time_code(float(s), tcps))
        joints = []
        if skel_queries:
            w = np.asarray(skel_queries[0].ComputeJointWorldTransforms(UsdGeom.XformCache(time)))
            joints = fix(w[:, 3, :3]) if len(w) else []
        points = cu.mesh_points(stage, cache, skinning, time, np)
        if "--model-space" in sys.argv:
            to_model = np.identity(4)
            if skel_queries:
                world = UsdGeom.XformCache(time).GetLocalToWorldTransform(skel_queries[0].GetPrim())
                to_model = np.linalg.inv(np.asarray(world))
            p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
            points = (p @ to_model[:3, :3] + to_model[3, :3]).tolist()
        else:
            points = fix(points)
        frames.append({"joints": joints, "points": points})
    print(json.dumps({"tcps": tcps, "up": up, "mpu": mpu, "frames": frames}))


if __name__ == "__main__":
    main()

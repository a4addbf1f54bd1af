"""Blender's FBX import (tools/blender/blender_frames.py's .npz) against UsdSkel's evaluation
of rigport's .usda of the same file, for tests/cli/fbx_blender.rs. Runs in tools/.venv
(usd-core), using tools/check_usd.py's evaluation (the one tests/cli/usd_world.py uses).

    tools/.venv/bin/python tools/blender/compare_usd.py USDA BLENDER_NPZ SPEC_JSON

SPEC_JSON: {"clip": NAME or null, "seconds": [t, ...]} (the .usda's clip times, seconds
from the clip's start, the same frames as the Blender times). Points are compared in +Y-up
metres (metersPerUnit applied, a Z-up stage turned).

Vertex correspondence: each .usda Mesh's points name their FBX control point
(`primvars:rigport:sourceVertex`, or the identity), and Blender keeps the control points as
its mesh's vertices in order, so point i is Blender vertex source[i] of the mesh object
that matches best at the first time ("index"). When no object matches by index within
1e-3 of the diagonal, each point takes the nearest Blender vertex at the first time
("nearest").

Prints JSON: {"worst": max over frames of max |usd - blender| / diagonal(usd frame),
"frames": [...per frame...], "meshes": [{"prim", "object", "match", "worst"}]}.
"""

import json
import os
import re
import sys

import numpy as np
from pxr import Usd, UsdGeom

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
import check_usd as cu  # noqa: E402


def y_up(stage, a):
    a = np.asarray(a, dtype=np.float64).reshape(-1, 3) * UsdGeom.GetStageMetersPerUnit(stage)
    if UsdGeom.GetStageUpAxis(stage) == "Z":
        a = np.stack([a[:, 0], a[:, 2], -a[:, 1]], axis=1)
    return a


def mesh_table(stage):
    """(prim path, point count, source vertex per point) of every Mesh, in the order
    check_usd.mesh_points lists their points."""
    root = stage.GetDefaultPrim() or stage.GetPseudoRoot()
    out = []
    for prim in Usd.PrimRange(root):
        if not prim.IsA(UsdGeom.Mesh):
            continue
        points = UsdGeom.Mesh(prim).GetPointsAttr().Get()
        if points is None:
            continue
        attr = prim.GetAttribute("primvars:rigport:sourceVertex")
        source = attr.Get() if attr and attr.HasValue() else None
        source = np.arange(len(points)) if source is None else np.asarray(source)
        out.append((str(prim.GetPath()), len(points), source))
    return out


def nearest(a, b):
    """For each row of a, the index of the nearest row of b."""
    out = np.empty(len(a), dtype=np.int64)
    for s in range(0, len(a), 512):
        d = ((a[s:s + 512, None, :] - b[None, :, :]) ** 2).sum(-1)
        out[s:s + 512] = d.argmin(1)
    return out


def main():
    usda, npz, spec = sys.argv[1], sys.argv[2], json.loads(sys.argv[3])
    stage = Usd.Stage.Open(usda)
    if spec.get("clip"):
        # The variant is the clip's name made a USD identifier (rigport's W003 repair).
        vset = stage.GetDefaultPrim().GetVariantSet("clip")
        name = spec["clip"]
        if name not in vset.GetVariantNames():
            name = re.sub(r"[^A-Za-z0-9]", "_", name)
            name = "_" + name if name[:1].isdigit() else name
        vset.SetVariantSelection(name)
    cache, skinning, _ = cu.skel_queries_of(stage)
    tcps = stage.GetTimeCodesPerSecond()
    usd = [y_up(stage, cu.mesh_points(stage, cache, skinning,
                                     Usd.TimeCode(cu.time_code(float(t), tcps)), np))
           for t in spec["seconds"]]
    bl = np.load(npz)
    names = list(bl["names"])
    blender = [bl[f"points_{k}"] for k in range(len(names))]
    all_blender = np.concatenate([b[0] for b in blender]) if blender else np.zeros((0, 3))
    diag0 = np.linalg.norm(usd[0].max(0) - usd[0].min(0))
    # Per .usda point: its Blender trajectory (F x 3).
    want = np.empty((len(spec["seconds"]), len(usd[0]), 3))
    meshes, start = [], 0
    for prim, n, source in mesh_table(stage):
        mine = slice(start, start + n)
        best = None
        for k, b in enumerate(blender):
            if len(b[0]) <= source.max(initial=0):
                continue
            cost = np.linalg.norm(usd[0][mine] - b[0][source], axis=1).max() / diag0
            if best is None or cost < best[0]:
                best = (cost, k)
        if best is not None and best[0] <= 1e-3:
            k = best[1]
            want[:, mine] = blender[k][:, source]
            match, obj = "index", names[k]
        else:
            flat = np.concatenate([b for b in blender], axis=1)
            idx = nearest(usd[0][mine], all_blender)
            want[:, mine] = flat[:, idx]
            match, obj = "nearest", "*"
        meshes.append({"prim": prim, "object": str(obj), "match": match, "range": [start, start + n]})
        start += n
    frames = []
    for f, u in enumerate(usd):
        diag = np.linalg.norm(u.max(0) - u.min(0))
        d = np.linalg.norm(u - want[f], axis=1) / diag
        i = int(d.argmax())
        frames.append({"t": spec["seconds"][f], "dev": float(d[i]), "point": i})
        for m in meshes:
            a, b = m["range"]
            m["worst"] = max(m.get("worst", 0.0), float(d[a:b].max(initial=0.0)))
    print(json.dumps({"worst": max((f["dev"] for f in frames), default=0.0),
                      "frames": frames, "meshes": meshes}))


if __name__ == "__main__":
    main()

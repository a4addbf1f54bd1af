"""UsdSkel blend-shape fixtures and normals, for tests/cli/usd_blendshapes.rs.

    python usd_blendshapes.py make DIR
        writes DIR/shapes.usda and DIR/shapes.usdc (the same stage; see `make`)
    python usd_blendshapes.py normals STAGE TIME_CODES_JSON
        prints JSON {"frames": [{"points": [...], "normals": [...]}]}: every skinning
        target's points and normals after UsdSkel's blend shapes (points with
        UsdSkel.BlendShapeQuery.ComputeDeformedPoints; normals with the same sub-shape
        weights and each sub-shape's normalOffsets, then normalized, as UsdSkel's
        ComputeDeformedNormals, which usd-core's Python does not wrap), in source point
        order (a rigport output's `primvars:rigport:sourceVertex` maps its vertices back).
    python usd_blendshapes.py baked STAGE TIME_CODES_JSON
        the same JSON from the points and normals authored on every Mesh (a baked baseline).
"""

import json
import sys

import numpy as np
from pxr import Gf, Sdf, Usd, UsdGeom, UsdSkel, Vt


def make(out_dir: str) -> None:
    """A Y-up, metre stage: a SkelRoot with a two-joint Skeleton, a skinned grid with two
    blend shapes (`smile`: dense, inbetweens at -0.5, 0.25 and 0.7; `puff`: sparse
    pointIndices, an inbetween at 0.5) and a blend-shape-only grid under a rotated and
    scaled Xform (`lid`: sparse, an inbetween at 0.4). The SkelAnimation bends the second
    joint and drives the weights across the inbetweens between its samples, and below 0
    and above 1."""
    stage = Usd.Stage.CreateInMemory()
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.y)
    UsdGeom.SetStageMetersPerUnit(stage, 1.0)
    stage.SetTimeCodesPerSecond(24)
    stage.SetStartTimeCode(0)
    stage.SetEndTimeCode(30)
    root = UsdSkel.Root.Define(stage, "/Root")
    stage.SetDefaultPrim(root.GetPrim())
    skel = UsdSkel.Skeleton.Define(stage, "/Root/Skel")
    joints = ["base", "base/tip"]
    skel.CreateJointsAttr(joints)
    rest = [Gf.Matrix4d(1).SetTranslate(Gf.Vec3d(0, 0, 0)), Gf.Matrix4d(1).SetTranslate(Gf.Vec3d(0, 1, 0))]
    bind = [rest[0], rest[0] * rest[1]]
    skel.CreateRestTransformsAttr(rest)
    skel.CreateBindTransformsAttr(bind)
    UsdSkel.BindingAPI.Apply(root.GetPrim()).CreateSkeletonRel().SetTargets([skel.GetPath()])

    anim = UsdSkel.Animation.Define(stage, "/Root/Skel/Anim")
    anim.CreateJointsAttr(joints)
    anim.CreateTranslationsAttr([Gf.Vec3f(0, 0, 0), Gf.Vec3f(0, 1, 0)])
    anim.CreateScalesAttr([Gf.Vec3h(1, 1, 1), Gf.Vec3h(1, 1, 1)])
    rot = anim.CreateRotationsAttr()
    anim.CreateBlendShapesAttr(["smile", "puff", "lid"])
    weights = anim.CreateBlendShapeWeightsAttr()
    samples = {
        0: ([0.0, 0.2, 0.0], 0.0),
        10: ([1.0, 0.9, 0.9], 30.0),
        20: ([-0.6, 0.1, -0.3], -20.0),
        30: ([1.4, 0.0, 1.2], 10.0),
    }
    for tc, (w, deg) in samples.items():
        weights.Set(Vt.FloatArray(w), tc)
        q = Gf.Rotation(Gf.Vec3d(0, 0, 1), deg).GetQuat()
        rot.Set([Gf.Quatf(1, 0, 0, 0), Gf.Quatf(q)], tc)
    UsdSkel.BindingAPI.Apply(skel.GetPrim()).CreateAnimationSourceRel().SetTargets([anim.GetPath()])

    def grid(path: str, nx: int, ny: int):
        mesh = UsdGeom.Mesh.Define(stage, path)
        pts = [Gf.Vec3f(0.5 * i, 0.5 * j, 0.0) for j in range(ny) for i in range(nx)]
        counts, idx = [], []
        for j in range(ny - 1):
            for i in range(nx - 1):
                a = j * nx + i
                counts.append(4)
                idx += [a, a + 1, a + 1 + nx, a + nx]
        mesh.CreatePointsAttr(pts)
        mesh.CreateFaceVertexCountsAttr(counts)
        mesh.CreateFaceVertexIndicesAttr(idx)
        mesh.CreateSubdivisionSchemeAttr("none")
        mesh.CreateExtentAttr(UsdGeom.Boundable.ComputeExtentFromPlugins(mesh, Usd.TimeCode.Default()))
        return mesh, len(pts)

    body, n = grid("/Root/Body", 3, 4)
    binding = UsdSkel.BindingAPI.Apply(body.GetPrim())
    ji, jw = [], []
    for k in range(n):
        y = (k // 3) * 0.5
        t = min(max(y / 1.5, 0.0), 1.0)
        ji += [0, 1]
        jw += [1.0 - t, t]
    binding.CreateJointIndicesPrimvar(False, 2).Set(ji)
    binding.CreateJointWeightsPrimvar(False, 2).Set(jw)
    binding.CreateGeomBindTransformAttr(Gf.Matrix4d(1))

    smile = UsdSkel.BlendShape.Define(stage, "/Root/Body/smile")
    smile.CreateOffsetsAttr([Gf.Vec3f(0.1 * (k % 3), 0.05 * k, 0.2) for k in range(n)])
    for name, w, scale in [("neg", -0.5, -0.3), ("quarter", 0.25, 0.5), ("most", 0.7, 0.4)]:
        ib = smile.CreateInbetween(name)
        ib.SetWeight(w)
        ib.SetOffsets([Gf.Vec3f(scale * (k % 2), 0.0, scale * 0.1 * k) for k in range(n)])
    puff = UsdSkel.BlendShape.Define(stage, "/Root/Body/puff")
    puff.CreatePointIndicesAttr([1, 4, 10])
    puff.CreateOffsetsAttr([Gf.Vec3f(0, 0, 0.3), Gf.Vec3f(0.1, 0, 0.5), Gf.Vec3f(-0.2, 0.1, 0)])
    ib = puff.CreateInbetween("half")
    ib.SetWeight(0.5)
    ib.SetOffsets([Gf.Vec3f(0, 0.2, 0), Gf.Vec3f(0, 0, 0.4), Gf.Vec3f(0, 0, 0)])
    binding.CreateBlendShapesAttr(["smile", "puff"])
    binding.CreateBlendShapeTargetsRel().SetTargets([smile.GetPath(), puff.GetPath()])

    holder = UsdGeom.Xform.Define(stage, "/Root/Holder")
    xf = UsdGeom.XformCommonAPI(holder)
    xf.SetTranslate(Gf.Vec3d(2, 0.5, -1))
    xf.SetRotate(Gf.Vec3f(0, 35, 10))
    xf.SetScale(Gf.Vec3f(1.5, 1.5, 1.5))
    lid, m = grid("/Root/Holder/Lid", 2, 3)
    lid_binding = UsdSkel.BindingAPI.Apply(lid.GetPrim())
    shape = UsdSkel.BlendShape.Define(stage, "/Root/Holder/Lid/lid")
    shape.CreatePointIndicesAttr([2, 3, 5])
    shape.CreateOffsetsAttr([Gf.Vec3f(0, 0, 0.4), Gf.Vec3f(0.1, 0, 0.4), Gf.Vec3f(0, 0.3, 0)])
    ib = shape.CreateInbetween("part")
    ib.SetWeight(0.4)
    ib.SetOffsets([Gf.Vec3f(0, 0, 0.3), Gf.Vec3f(0, 0, 0.1), Gf.Vec3f(0.2, 0, 0)])
    lid_binding.CreateBlendShapesAttr(["lid"])
    lid_binding.CreateBlendShapeTargetsRel().SetTargets([shape.GetPath()])

    stage.GetRootLayer().Export(f"{out_dir}/shapes.usda")
    stage.GetRootLayer().Export(f"{out_dir}/shapes.usdc")


def normals(path: str, time_codes: list) -> None:
    stage = Usd.Stage.Open(path)
    cache = UsdSkel.Cache()
    targets = []
    for prim in stage.Traverse():
        if prim.IsA(UsdSkel.Root):
            root = UsdSkel.Root(prim)
            cache.Populate(root, Usd.PrimDefaultPredicate)
            for b in cache.ComputeSkelBindings(root, Usd.PrimDefaultPredicate):
                sq = cache.GetSkelQuery(b.GetSkeleton())
                targets += [(sq, q) for q in b.GetSkinningTargets()]
    frames = []
    for tc in time_codes:
        pts_all, nrm_all = [], []
        for sq, q in targets:
            prim = q.GetPrim()
            mesh = UsdGeom.Mesh(prim)
            pv = UsdGeom.PrimvarsAPI(prim).GetPrimvar("normals")
            attr = pv.GetAttr() if pv and pv.HasAuthoredValue() else mesh.GetNormalsAttr()
            points = Vt.Vec3fArray(mesh.GetPointsAttr().Get(tc))
            nrm = np.asarray(attr.Get(tc), dtype=np.float64)
            w = sq.GetAnimQuery().ComputeBlendShapeWeights(tc)
            mapper = q.GetBlendShapeMapper()
            if mapper and not mapper.IsNull():
                w = mapper.Remap(w)
            bq = UsdSkel.BlendShapeQuery(UsdSkel.BindingAPI(prim))
            sub, shape_of, sub_idx = bq.ComputeSubShapeWeights(w)
            indices = bq.ComputeBlendShapePointIndices()
            bq.ComputeDeformedPoints(sub, shape_of, sub_idx, indices, bq.ComputeSubShapePointOffsets(), points)
            for weight, b, s in zip(sub, shape_of, sub_idx):
                inbetween = bq.GetInbetween(s)
                off = (inbetween.GetNormalOffsets() if inbetween
                       else bq.GetBlendShape(b).GetNormalOffsetsAttr().Get())
                if off is None or len(off) == 0:
                    continue
                ix = np.asarray(indices[b]) if len(indices[b]) else np.arange(len(nrm))
                nrm[ix] += weight * np.asarray(off, dtype=np.float64)
            nrm /= np.linalg.norm(nrm, axis=1)[:, None]
            pts = np.asarray(points, dtype=np.float64)
            sv = UsdGeom.PrimvarsAPI(prim).GetPrimvar("rigport:sourceVertex")
            if sv and sv.HasAuthoredValue():
                first = {}
                for v, s in enumerate(list(sv.Get())):
                    first.setdefault(s, v)
                order = [first[s] for s in sorted(first)]
                pts, nrm = pts[order], nrm[order]
            pts_all += pts.tolist()
            nrm_all += nrm.tolist()
        frames.append({"points": pts_all, "normals": nrm_all})
    print(json.dumps({"frames": frames}))


def baked(path: str, time_codes: list) -> None:
    stage = Usd.Stage.Open(path)
    meshes = [UsdGeom.Mesh(p) for p in stage.Traverse() if p.IsA(UsdGeom.Mesh)]
    frames = []
    for tc in time_codes:
        pts, nrm = [], []
        for mesh in meshes:
            pts += np.asarray(mesh.GetPointsAttr().Get(tc), dtype=np.float64).tolist()
            nrm += np.asarray(mesh.GetNormalsAttr().Get(tc), dtype=np.float64).tolist()
        frames.append({"points": pts, "normals": nrm})
    print(json.dumps({"frames": frames}))


if __name__ == "__main__":
    if sys.argv[1] == "make":
        make(sys.argv[2])
    elif sys.argv[1] == "baked":
        baked(sys.argv[2], json.loads(sys.argv[3]))
    elif sys.argv[1] == "normals":
        normals(sys.argv[2], json.loads(sys.argv[3]))
    else:
        sys.exit(f"unknown command {sys.argv[1]!r}")

"""A usd-core fixture for tests/cli/usd_frames.rs: everything that places a character in a
Blender- or Reality-Converter-like stage, in one file written three ways.

    python usd_frames.py DIR     writes DIR/frames.usda, DIR/frames.usdc, DIR/frames.usdz

A Z-up, centimetre stage (24 time codes per second, 0..24): an Xform `Mover` with
time-sampled translate and rotateZ and a static scale 2 above a SkelRoot that is itself
translated, rotated (rotateX 30, rotateZ 15) and scaled (1.5); a two-joint Skeleton with
its own SkelAnimation; a skinned leg with a blend shape `bulge` that has an inbetween at
0.4, driven below 0, across the inbetween and above 1; and a static mesh `Prop` under an
Xform `Spinner` whose orient (slerped by USD) and translate are time-sampled.
"""

import sys

from pxr import Gf, Usd, UsdGeom, UsdSkel, UsdUtils, Vt


def box(stage, path, pts_z):
    mesh = UsdGeom.Mesh.Define(stage, path)
    pts = [Gf.Vec3f(x, y, z) for z in pts_z for (x, y) in ((-0.3, -0.3), (0.3, -0.3), (0.3, 0.3), (-0.3, 0.3))]
    mesh.CreatePointsAttr(pts)
    counts, idx = [], []
    for ring in range(len(pts_z) - 1):
        for k in range(4):
            a, b = ring * 4 + k, ring * 4 + (k + 1) % 4
            counts.append(4)
            idx += [a, b, b + 4, a + 4]
    mesh.CreateFaceVertexCountsAttr(counts)
    mesh.CreateFaceVertexIndicesAttr(idx)
    mesh.CreateSubdivisionSchemeAttr("none")
    return mesh, pts


def make(out_dir):
    stage = Usd.Stage.CreateInMemory()
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.z)
    UsdGeom.SetStageMetersPerUnit(stage, 0.01)
    stage.SetTimeCodesPerSecond(24)
    stage.SetStartTimeCode(0)
    stage.SetEndTimeCode(24)
    world = UsdGeom.Xform.Define(stage, "/World")
    stage.SetDefaultPrim(world.GetPrim())
    mover = UsdGeom.Xform.Define(stage, "/World/Mover")
    t = mover.AddTranslateOp()
    r = mover.AddRotateZOp()
    s = mover.AddScaleOp()
    for tc, (x, deg) in {0: (0.0, 0.0), 12: (50.0, 90.0), 24: (80.0, 120.0)}.items():
        t.Set(Gf.Vec3d(x, 0.2 * x, 10.0), tc)
        r.Set(deg, tc)
    s.Set(Gf.Vec3f(2, 2, 2))

    root = UsdSkel.Root.Define(stage, "/World/Mover/Char")
    root.AddTranslateOp().Set(Gf.Vec3d(0, 5, 3))
    root.AddRotateXYZOp().Set(Gf.Vec3f(30, 0, 15))
    root.AddScaleOp().Set(Gf.Vec3f(1.5, 1.5, 1.5))
    skel = UsdSkel.Skeleton.Define(stage, "/World/Mover/Char/Skel")
    joints = ["hip", "hip/knee"]
    skel.CreateJointsAttr(joints)
    rest = [Gf.Matrix4d(1).SetTranslate(Gf.Vec3d(0, 0, 1)), Gf.Matrix4d(1).SetTranslate(Gf.Vec3d(0, 0, 2))]
    skel.CreateRestTransformsAttr(rest)
    skel.CreateBindTransformsAttr([rest[0], rest[0] * rest[1]])
    UsdSkel.BindingAPI.Apply(root.GetPrim()).CreateSkeletonRel().SetTargets([skel.GetPath()])
    anim = UsdSkel.Animation.Define(stage, "/World/Mover/Char/Skel/Anim")
    anim.CreateJointsAttr(joints)
    anim.CreateTranslationsAttr([Gf.Vec3f(0, 0, 1), Gf.Vec3f(0, 0, 2)])
    anim.CreateScalesAttr([Gf.Vec3h(1, 1, 1), Gf.Vec3h(1, 1, 1)])
    anim.CreateBlendShapesAttr(["bulge"])
    rot = anim.CreateRotationsAttr()
    weights = anim.CreateBlendShapeWeightsAttr()
    for tc, (deg, w) in {0: (0.0, -0.2), 6: (40.0, 0.7), 12: (10.0, 0.3), 24: (-30.0, 1.3)}.items():
        q = Gf.Quatf(Gf.Rotation(Gf.Vec3d(1, 0, 0), deg).GetQuat())
        rot.Set([Gf.Quatf(Gf.Rotation(Gf.Vec3d(0, 0, 1), deg / 2).GetQuat()), q], tc)
        weights.Set(Vt.FloatArray([w]), tc)
    UsdSkel.BindingAPI.Apply(skel.GetPrim()).CreateAnimationSourceRel().SetTargets([anim.GetPath()])

    leg, pts = box(stage, "/World/Mover/Char/Leg", (0.5, 1.5, 2.5, 3.5))
    b = UsdSkel.BindingAPI.Apply(leg.GetPrim())
    ji, jw = [], []
    for p in pts:
        w = min(max((p[2] - 1.0) / 1.5, 0.0), 1.0)
        ji += [0, 1]
        jw += [1 - w, w]
    b.CreateJointIndicesPrimvar(False, 2).Set(ji)
    b.CreateJointWeightsPrimvar(False, 2).Set(jw)
    b.CreateGeomBindTransformAttr(Gf.Matrix4d(1))
    shape = UsdSkel.BlendShape.Define(stage, "/World/Mover/Char/Leg/bulge")
    shape.CreateOffsetsAttr([Gf.Vec3f(0.2 * p[0], 0.2 * p[1], 0.05) for p in pts[4:8]])
    shape.CreatePointIndicesAttr([4, 5, 6, 7])
    shape.CreateInbetween("half").SetOffsets([Gf.Vec3f(0.3 * p[0], 0.3 * p[1], 0.0) for p in pts[4:8]])
    shape.GetInbetween("half").SetWeight(0.4)
    b.CreateBlendShapesAttr(["bulge"])
    b.CreateBlendShapeTargetsRel().SetTargets([shape.GetPath()])

    spinner = UsdGeom.Xform.Define(stage, "/World/Spinner")
    st = spinner.AddTranslateOp()
    so = spinner.AddOrientOp()
    for tc, (x, q) in {0: (0.0, Gf.Quatf(1, 0, 0, 0)), 12: (3.0, Gf.Quatf(0, 0, 0, 1)), 24: (5.0, Gf.Quatf(0.707, 0.707, 0, 0))}.items():
        st.Set(Gf.Vec3d(x, -4, 1), tc)
        so.Set(q, tc)
    box(stage, "/World/Spinner/Prop", (0.0, 0.8))

    stage.GetRootLayer().Export(f"{out_dir}/frames.usda")
    stage.GetRootLayer().Export(f"{out_dir}/frames.usdc")
    if not UsdUtils.CreateNewUsdzPackage(f"{out_dir}/frames.usdc", f"{out_dir}/frames.usdz"):
        raise SystemExit("usdz packaging failed")


make(sys.argv[1])

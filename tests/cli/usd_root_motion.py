"""A usd-core fixture for tests/cli/usd_root_motion.rs: a Z-up, centimetre stage whose
character moves by time-sampled xformOps above its SkelRoot (translate and rotateZ animated,
a static scale 2 on the same prim, a static translate on the SkelRoot), with a two-joint
SkelAnimation of its own.

    python usd_root_motion.py DIR      writes DIR/moving.usda
"""

import sys
from pxr import Gf, Usd, UsdGeom, UsdSkel
def make(out_dir):
    stage = Usd.Stage.CreateInMemory()
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.z)
    UsdGeom.SetStageMetersPerUnit(stage, 0.01)
    stage.SetTimeCodesPerSecond(24)
    stage.SetStartTimeCode(0); stage.SetEndTimeCode(24)
    world = UsdGeom.Xform.Define(stage, "/World")
    stage.SetDefaultPrim(world.GetPrim())
    mover = UsdGeom.Xform.Define(stage, "/World/Mover")
    t = mover.AddTranslateOp(); r = mover.AddRotateZOp(); s = mover.AddScaleOp()
    for tc, (x, deg) in {0: (0.0, 0.0), 12: (50.0, 90.0), 24: (80.0, 120.0)}.items():
        t.Set(Gf.Vec3d(x, 0.2 * x, 10.0), tc)
        r.Set(deg, tc)
    s.Set(Gf.Vec3f(2, 2, 2))
    root = UsdSkel.Root.Define(stage, "/World/Mover/Char")
    UsdGeom.XformCommonAPI(root).SetTranslate(Gf.Vec3d(0, 5, 0))
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
    rot = anim.CreateRotationsAttr()
    for tc, deg in {0: 0.0, 6: 40.0, 24: -30.0}.items():
        q = Gf.Quatf(Gf.Rotation(Gf.Vec3d(1, 0, 0), deg).GetQuat())
        rot.Set([Gf.Quatf(Gf.Rotation(Gf.Vec3d(0, 0, 1), deg / 2).GetQuat()), q], tc)
    UsdSkel.BindingAPI.Apply(skel.GetPrim()).CreateAnimationSourceRel().SetTargets([anim.GetPath()])
    mesh = UsdGeom.Mesh.Define(stage, "/World/Mover/Char/Leg")
    pts = [Gf.Vec3f(x, y, z) for z in (0.5, 1.5, 2.5, 3.5) for (x, y) in ((-0.3, -0.3), (0.3, -0.3), (0.3, 0.3), (-0.3, 0.3))]
    mesh.CreatePointsAttr(pts)
    counts, idx = [], []
    for ring in range(3):
        for k in range(4):
            a, b = ring * 4 + k, ring * 4 + (k + 1) % 4
            counts.append(4); idx += [a, b, b + 4, a + 4]
    mesh.CreateFaceVertexCountsAttr(counts); mesh.CreateFaceVertexIndicesAttr(idx)
    mesh.CreateSubdivisionSchemeAttr("none")
    b = UsdSkel.BindingAPI.Apply(mesh.GetPrim())
    ji, jw = [], []
    for p in pts:
        w = min(max((p[2] - 1.0) / 1.5, 0.0), 1.0)
        ji += [0, 1]; jw += [1 - w, w]
    b.CreateJointIndicesPrimvar(False, 2).Set(ji)
    b.CreateJointWeightsPrimvar(False, 2).Set(jw)
    b.CreateGeomBindTransformAttr(Gf.Matrix4d(1))
    stage.GetRootLayer().Export(f"{out_dir}/moving.usda")
make(sys.argv[1])

"""How far UsdSkel's own evaluation of a stage's first skeleton is from an exact one.

    python usd_exact.py STAGE.usda

UsdSkelAnimation holds float data (`quatf` rotations, `float3` translations, `half3`
scales) and USD interpolates it in that precision (`GfSlerp` on `GfQuatf`). This script
evaluates the same time samples in double precision: per time code (every whole frame of
the stage's range and every sample time) each joint's translation and scale are lerped and
its rotation slerped between the two samples around it (held before the first and after the
last, as USD does), composed as translate * rotate * scale, joints without animation at
their rest transform, each joint's skeleton-space transform its local one times its
parent's (row vectors, as USD). It compares the rotation part with UsdSkel's
`SkeletonQuery.ComputeJointSkelTransforms` at the same time code.

It also reports where UsdSkel's own difference comes from:
- at the sample times, where nothing is interpolated, UsdSkel equals the same evaluation
  with each local rotation matrix built in float from the `quatf` (`GfMatrix3f(GfQuatf)`)
  and composed in double: "float_matrix_at_samples" is the largest 3x3 difference there;
- between samples, USD's slerp of `quatf`s is computed in float and its result is not
  renormalized: "local_length_max" is how far a local quaternion UsdSkel evaluates is from
  unit length, and "world_row_length_max" how far a row of a skeleton-space 3x3 is from
  unit length (a scale the chain composes; it is 0 in an exact evaluation).

stdout: JSON {"times": N, "joints": J, "rotation_max": largest absolute difference of a
3x3 entry, "worst": {"time": tc, "joint": name}, "float_matrix_at_samples",
"local_length_max", "world_row_length_max"}.
"""

import json
import sys

import numpy as np
from pxr import Usd, UsdSkel


def quat_matrix(q):
    """Row-vector rotation matrix of a (w, x, y, z) quaternion (GfMatrix3d(GfQuatd))."""
    w, x, y, z = q / np.linalg.norm(q)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y + w * z), 2 * (x * z - w * y)],
        [2 * (x * y - w * z), 1 - 2 * (x * x + z * z), 2 * (y * z + w * x)],
        [2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)],
    ])


def quat_matrix_float(q):
    """quat_matrix computed in float32 from the quaternion as stored (GfMatrix3f(GfQuatf))."""
    w, x, y, z = (np.float32(c) for c in q)
    one, two = np.float32(1), np.float32(2)
    m = np.array([
        [one - two * (y * y + z * z), two * (x * y + w * z), two * (x * z - w * y)],
        [two * (x * y - w * z), one - two * (x * x + z * z), two * (y * z + w * x)],
        [two * (x * z + w * y), two * (y * z - w * x), one - two * (x * x + y * y)],
    ], dtype=np.float32)
    return m.astype(np.float64)


def slerp(q0, q1, a):
    c = float(np.dot(q0, q1))
    if c < 0.0:
        q1, c = -q1, -c
    theta = np.arccos(min(c, 1.0))
    s = np.sin(theta)
    if s < 1e-12:
        return (1 - a) * q0 + a * q1
    return (np.sin((1 - a) * theta) * q0 + np.sin(a * theta) * q1) / s


def sampled(attr, to_array):
    times = list(attr.GetTimeSamples())
    if not times:
        value = attr.Get()
        return [0.0], [to_array(value)] if value is not None else []
    return times, [to_array(attr.Get(t)) for t in times]


def at(times, values, tc, mix):
    """The value at tc: held outside the samples, mixed between the two around it."""
    if tc <= times[0]:
        return values[0]
    if tc >= times[-1]:
        return values[-1]
    k = int(np.searchsorted(times, tc, side="right")) - 1
    a = (tc - times[k]) / (times[k + 1] - times[k])
    return np.array([mix(x, y, a) for x, y in zip(values[k], values[k + 1])])


def main() -> None:
    stage = Usd.Stage.Open(sys.argv[1])
    skel = next(UsdSkel.Skeleton(p) for p in stage.Traverse() if p.IsA(UsdSkel.Skeleton))
    cache = UsdSkel.Cache()
    root = next(UsdSkel.Root(p) for p in stage.Traverse() if p.IsA(UsdSkel.Root))
    cache.Populate(root, Usd.PrimDefaultPredicate)
    query = cache.GetSkelQuery(skel)
    joints = [str(j) for j in skel.GetJointsAttr().Get()]
    parents = [joints.index(j.rsplit("/", 1)[0]) if "/" in j else -1 for j in joints]
    rest = [np.array(m, dtype=np.float64) for m in skel.GetRestTransformsAttr().Get()]
    anim = UsdSkel.Animation(query.GetAnimQuery().GetPrim())
    anim_joints = [str(j) for j in anim.GetJointsAttr().Get()]
    where = {j: i for i, j in enumerate(anim_joints)}
    vec = lambda v: np.array([list(x) for x in v], dtype=np.float64)
    quats = lambda v: np.array([[q.GetReal(), *q.GetImaginary()] for q in v], dtype=np.float64)
    tt, tv = sampled(anim.GetTranslationsAttr(), vec)
    rt, rv = sampled(anim.GetRotationsAttr(), quats)
    st, sv = sampled(anim.GetScalesAttr(), vec)
    lerp = lambda x, y, a: (1 - a) * x + a * y
    codes = set(tt) | set(rt) | set(st)
    if stage.HasAuthoredTimeCodeRange():
        codes |= set(np.arange(stage.GetStartTimeCode(), stage.GetEndTimeCode() + 0.5, 1.0).tolist())
    samples = set(rt)
    anim_query = query.GetAnimQuery()

    def compose(tc, rotation_matrix, mix):
        t = at(tt, tv, tc, lerp)
        r = at(rt, rv, tc, mix)
        s = at(st, sv, tc, lerp)
        world = []
        for j, name in enumerate(joints):
            if name in where:
                i = where[name]
                local = np.diag([*s[i], 1.0])
                local[:3, :3] = np.diag(s[i]) @ rotation_matrix(r[i])
                local[3, :3] = t[i]
            else:
                local = rest[j]
            world.append(local if parents[j] < 0 else local @ world[parents[j]])
        return world

    worst, where_worst = 0.0, None
    float_at_samples = local_length = row_length = 0.0
    for tc in sorted(codes):
        world = compose(tc, quat_matrix, slerp)
        usd = np.array(query.ComputeJointSkelTransforms(Usd.TimeCode(tc)), dtype=np.float64)
        for j in range(len(joints)):
            d = float(np.abs(usd[j][:3, :3] - world[j][:3, :3]).max())
            if d > worst:
                worst, where_worst = d, {"time": tc, "joint": joints[j]}
        rows = np.linalg.norm(usd[:, :3, :3], axis=2)
        row_length = max(row_length, float(np.abs(rows - 1.0).max()))
        _, rotations, _ = anim_query.ComputeJointLocalTransformComponents(Usd.TimeCode(tc))
        if len(rotations):
            lengths = np.linalg.norm(quats(rotations), axis=1)
            local_length = max(local_length, float(np.abs(lengths - 1.0).max()))
        if tc in samples:
            floats = compose(tc, quat_matrix_float, slerp)
            for j in range(len(joints)):
                d = float(np.abs(usd[j][:3, :3] - floats[j][:3, :3]).max())
                float_at_samples = max(float_at_samples, d)
    print(json.dumps({"times": len(codes), "joints": len(joints), "rotation_max": worst,
                      "worst": where_worst, "float_matrix_at_samples": float_at_samples,
                      "local_length_max": local_length,
                      "world_row_length_max": row_length}))


if __name__ == "__main__":
    main()

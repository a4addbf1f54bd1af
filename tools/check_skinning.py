#!/usr/bin/env python3
"""Check rigport's skinned positions against usd-core's UsdSkel.SkinPoints.

Usage:
  tools/.venv/bin/python tools/check_skinning.py DUMP [DUMP ...] [--method lbs|dqs] [--tolerance T]
  tools/.venv/bin/python tools/check_skinning.py --export-usd IN.usda --baseline BAKED.usda --out OUT

DUMP is what `rigport eval ... -o DUMP.npz` writes (src/commands/eval.rs, `Dump`), or a
directory of `NAME.npy` files with the same arrays:
  rest_positions     V x 3         bind-space points
  positions          V x 3, or F x V x 3 with frames: rigport's skinned points
  skin_matrices      J x 4 x 4, or F x J x 4 x 4: per joint skinning matrix, row-major
                     storage of a column-vector matrix (numpy `M @ p` works; USD, which
                     uses row vectors, gets the transpose)
  influence_joints   V x K int, zero padded; indices into skin_matrices
  influence_weights  V x K float, zero padded
  skinning           ["lbs"] or ["dqs"] (optional, default lbs; --method overrides)
  times              F (optional; seconds of each frame)

Every frame is recomputed with UsdSkel.SkinPoints (skinning method `classicLinear` or
`dualQuaternion`, geomBindTransform identity: the dump's rest points are already in bind
space), and the deviation |rigport - UsdSkel| of each vertex is divided by the diagonal of
the UsdSkel result's bounding box for that frame. One line per frame gives the max and mean
relative deviation; the run fails if any frame's max exceeds --tolerance (default 1e-5).

rigport's one rule that differs from UsdSkel's: a vertex without a non-zero weight keeps its
rest position (UsdSkel would move it to the origin), so such vertices are compared with their
rest position.

--export-usd reads Pixar's test case (e.g. ../shared/corpus/6_usd/openusd_usdskel__
PixarAnimationStudios/testUsdSkelBakeSkinning/dqs.usda) with usd-core: the rest points of
every point-based skinned prim (geomBindTransform applied), their influences (remapped to the
skeleton's joint order), and the skinning transforms at every time code, and writes them in
the dump layout with `positions` taken from the baked baseline (BAKED.usda). OUT ending in
.npz gets an .npz, else a directory of .npy files. Checking that output compares usd-core
with Pixar's own baseline; a Rust test (crates/eval/src/skinning/dqs.rs) skins the same arrays with
rigport.

Exit status: 0 within tolerance, 1 over tolerance, 2 bad input or usage.
"""

from __future__ import annotations

import argparse
import os
import sys

import numpy as np

EXIT_OK, EXIT_OVER, EXIT_BAD = 0, 1, 2

TOKENS = {"lbs": "classicLinear", "dqs": "dualQuaternion"}


class BadInput(Exception):
    """The dump cannot be checked (missing array, wrong shape, unknown method...)."""


def load_arrays(path: str) -> dict[str, np.ndarray]:
    """The arrays of an .npz file or of a directory of .npy files."""
    if os.path.isdir(path):
        out = {}
        for name in sorted(os.listdir(path)):
            if name.endswith(".npy"):
                out[name[:-4]] = np.load(os.path.join(path, name), allow_pickle=False)
        if not out:
            raise BadInput(f"{path}: no .npy files in the directory")
        return out
    try:
        with np.load(path, allow_pickle=False) as npz:
            return {k: npz[k] for k in npz.files}
    except (OSError, ValueError) as e:
        raise BadInput(f"{path}: cannot read as .npz: {e}") from e


def save_arrays(path: str, arrays: dict[str, np.ndarray]) -> None:
    if path.endswith(".npz"):
        np.savez(path, **arrays)
        return
    os.makedirs(path, exist_ok=True)
    for k, v in arrays.items():
        np.save(os.path.join(path, k + ".npy"), v, allow_pickle=False)


def require(arrays, name, ndims, dtype_kind):
    if name not in arrays:
        raise BadInput(f"missing array {name!r} (have: {', '.join(sorted(arrays))})")
    a = arrays[name]
    if a.ndim not in ndims:
        raise BadInput(f"{name}: expected {' or '.join(map(str, ndims))} dimensions, got shape {a.shape}")
    if a.dtype.kind not in dtype_kind:
        raise BadInput(f"{name}: unexpected dtype {a.dtype}")
    return a


def method_of(arrays, override: str | None) -> str:
    if override:
        return override
    if "skinning" not in arrays:
        return "lbs"
    raw = arrays["skinning"]
    value = str(raw.reshape(-1)[0]) if raw.size else ""
    if value not in TOKENS:
        raise BadInput(f"skinning: unknown method {value!r} (expected lbs or dqs)")
    return value


def normalized_dump(arrays):
    """Checked arrays with a leading frame axis: rest (V,3), positions (F,V,3),
    mats (F,J,4,4), joints (V,K), weights (V,K), times (F)."""
    rest = require(arrays, "rest_positions", (2,), "f").astype(np.float32)
    pos = require(arrays, "positions", (2, 3), "f").astype(np.float32)
    mats = require(arrays, "skin_matrices", (3, 4), "f").astype(np.float64)
    joints = require(arrays, "influence_joints", (2,), "iu")
    weights = require(arrays, "influence_weights", (2,), "f").astype(np.float32)
    if rest.shape[1:] != (3,):
        raise BadInput(f"rest_positions: expected V x 3, got {rest.shape}")
    v = rest.shape[0]
    if pos.ndim == 2:
        pos = pos[None]
    if mats.ndim == 3:
        mats = mats[None]
    if pos.shape[1:] != (v, 3):
        raise BadInput(f"positions: expected (F x) {v} x 3, got {arrays['positions'].shape}")
    if mats.shape[2:] != (4, 4):
        raise BadInput(f"skin_matrices: expected (F x) J x 4 x 4, got {arrays['skin_matrices'].shape}")
    if mats.shape[0] != pos.shape[0]:
        raise BadInput(f"{pos.shape[0]} frames of positions but {mats.shape[0]} of skin_matrices")
    if joints.shape != weights.shape or joints.shape[0] != v:
        raise BadInput(f"influences: joints {joints.shape} and weights {weights.shape}, expected {v} x K")
    j = mats.shape[1]
    if joints.size and (joints.min() < 0 or joints.max() >= j):
        raise BadInput(f"influence_joints: values must lie in 0..{j - 1}, found {joints.min()}..{joints.max()}")
    f = pos.shape[0]
    times = arrays.get("times")
    times = np.asarray(times, dtype=np.float64).reshape(-1) if times is not None else np.arange(f, dtype=np.float64)
    if times.shape[0] != f:
        raise BadInput(f"times: {times.shape[0]} values for {f} frames")
    if not (np.isfinite(rest).all() and np.isfinite(mats).all() and np.isfinite(weights).all()):
        raise BadInput("non-finite values in rest_positions, skin_matrices or influence_weights")
    return rest, pos, mats, joints.astype(np.int32), weights, times


def usd_skin(method: str, rest, mats, joints, weights):
    """UsdSkel.SkinPoints of one frame (mats: J x 4 x 4 column-vector matrices)."""
    from pxr import Gf, UsdSkel, Vt

    v, k = joints.shape
    if k == 0:
        return rest.copy()
    xforms = Vt.Matrix4dArray.FromNumpy(np.ascontiguousarray(np.transpose(mats, (0, 2, 1))))
    points = Vt.Vec3fArray.FromNumpy(np.ascontiguousarray(rest))
    ok = UsdSkel.SkinPoints(
        TOKENS[method],
        Gf.Matrix4d(1.0),
        xforms,
        Vt.IntArray.FromNumpy(np.ascontiguousarray(joints.reshape(-1))),
        Vt.FloatArray.FromNumpy(np.ascontiguousarray(weights.reshape(-1))),
        k,
        points,
        False,
    )
    if not ok:
        raise BadInput("UsdSkel.SkinPoints refused the arrays (see its warning above)")
    return np.array(points, dtype=np.float32).reshape(v, 3)


def check(args, dump) -> int:
    arrays = load_arrays(dump)
    method = method_of(arrays, args.method)
    rest, pos, mats, joints, weights, times = normalized_dump(arrays)
    unweighted = ~(weights != 0).any(axis=1) if weights.size else np.ones(rest.shape[0], bool)
    worst = 0.0
    print(f"{dump}: {pos.shape[0]} frame(s), {rest.shape[0]} vertices, {mats.shape[1]} joints, "
          f"{joints.shape[1]} influences/vertex, method {method} ({TOKENS[method]}), "
          f"{int(unweighted.sum())} unweighted vertices kept at rest")
    print(f"{'frame':>5} {'time':>9} {'max/diag':>10} {'mean/diag':>10} {'max abs':>10} {'diag':>10}")
    for f in range(pos.shape[0]):
        expect = usd_skin(method, rest, mats[f], joints, weights)
        expect[unweighted] = rest[unweighted]
        lo, hi = expect.min(axis=0), expect.max(axis=0)
        diag = float(np.linalg.norm(hi - lo)) if expect.size else 0.0
        if diag == 0.0:
            diag = 1.0
        dev = np.linalg.norm(pos[f].astype(np.float64) - expect.astype(np.float64), axis=1)
        if not np.isfinite(dev).all():
            dev = np.where(np.isfinite(dev), dev, np.inf)
        mx = float(dev.max()) if dev.size else 0.0
        mean = float(dev.mean()) if dev.size else 0.0
        worst = max(worst, mx / diag)
        if not args.quiet or mx / diag > args.tolerance:
            print(f"{f:5d} {times[f]:9.4f} {mx / diag:10.3e} {mean / diag:10.3e} {mx:10.3e} {diag:10.4g}")
    ok = worst <= args.tolerance
    print(f"max deviation {worst:.3e} of the bounding-box diagonal (tolerance {args.tolerance:g}): "
          f"{'OK' if ok else 'FAIL'}")
    return EXIT_OK if ok else EXIT_OVER


def export_usd(args) -> int:
    from pxr import Gf, Usd, UsdGeom, UsdSkel

    stage = Usd.Stage.Open(args.export_usd)
    if not stage:
        raise BadInput(f"{args.export_usd}: cannot open")
    baked = Usd.Stage.Open(args.baseline) if args.baseline else None
    if args.baseline and not baked:
        raise BadInput(f"{args.baseline}: cannot open")
    cache = UsdSkel.Cache()
    parts = []  # (prim path, rest, joints, weights, skinningQuery)
    skel_query = None
    methods = set()
    for prim in stage.Traverse():
        if not prim.IsA(UsdSkel.Root):
            continue
        root = UsdSkel.Root(prim)
        cache.Populate(root, Usd.PrimDefaultPredicate)
        for binding in cache.ComputeSkelBindings(root, Usd.PrimDefaultPredicate):
            sq = cache.GetSkelQuery(binding.GetSkeleton())
            if skel_query is not None and sq.GetPrim() != skel_query.GetPrim():
                raise BadInput("more than one skeleton: the dump layout has one palette")
            skel_query = sq
            skel_joints = list(sq.GetJointOrder())
            for target in binding.GetSkinningTargets():
                tprim = target.GetPrim()
                if not tprim.IsA(UsdGeom.PointBased) or target.IsRigidlyDeformed():
                    continue  # rigid prims (Sphere, Cube...) move by SkinTransform, no points
                points = np.asarray(UsdGeom.PointBased(tprim).GetPointsAttr().Get(), dtype=np.float64)
                bind = np.array(target.GetGeomBindTransform(), dtype=np.float64)  # row vectors
                rest = (np.c_[points, np.ones(len(points))] @ bind)[:, :3].astype(np.float32)
                idx, wts = target.ComputeVaryingJointInfluences(len(points))
                k = target.GetNumInfluencesPerComponent()
                idx = np.asarray(idx, dtype=np.int32).reshape(len(points), k)
                wts = np.asarray(wts, dtype=np.float32).reshape(len(points), k)
                order = target.GetJointOrder()
                if order:
                    remap = np.array([skel_joints.index(str(n)) for n in order], dtype=np.int32)
                    idx = remap[idx]
                methods.add(str(target.GetSkinningMethod()))
                parts.append((tprim.GetPath(), rest, idx, wts))
    if not parts or skel_query is None:
        raise BadInput(f"{args.export_usd}: no point-based skinned prim")
    if len(methods) != 1:
        raise BadInput(f"mixed skinning methods {sorted(methods)}")
    method = {v: k for k, v in TOKENS.items()}[methods.pop()]
    k = max(p[2].shape[1] for p in parts)
    pad = lambda a: np.pad(a, ((0, 0), (0, k - a.shape[1])))
    rest = np.concatenate([p[1] for p in parts])
    joints = np.concatenate([pad(p[2]) for p in parts])
    weights = np.concatenate([pad(p[3]) for p in parts])
    start, end = stage.GetStartTimeCode(), stage.GetEndTimeCode()
    codes = [float(t) for t in np.arange(start, end + 0.5)]
    mats, positions = [], []
    for t in codes:
        xfc = UsdGeom.XformCache(t)
        skel_world = xfc.GetLocalToWorldTransform(skel_query.GetPrim())
        xf = np.array(skel_query.ComputeSkinningTransforms(t), dtype=np.float64)  # row vectors
        frame_pos = []
        for path, prest, _, _ in parts:
            prim_world = xfc.GetLocalToWorldTransform(stage.GetPrimAtPath(path))
            extra = np.array(skel_world * prim_world.GetInverse(), dtype=np.float64)
            if not np.allclose(extra, np.eye(4), atol=1e-9):
                raise BadInput(f"{path}: not in the skeleton's space; the dump layout has one palette")
            if baked:
                pts = UsdGeom.PointBased(baked.GetPrimAtPath(path)).GetPointsAttr().Get(t)
                frame_pos.append(np.asarray(pts, dtype=np.float32))
            else:
                frame_pos.append(np.full_like(prest, np.nan))
        mats.append(np.transpose(xf, (0, 2, 1)).astype(np.float32))
        positions.append(np.concatenate(frame_pos))
    tcps = stage.GetTimeCodesPerSecond() or 24.0
    arrays = {
        "rest_positions": rest,
        "positions": np.stack(positions).astype(np.float32),
        "skin_matrices": np.stack(mats),
        "influence_joints": joints.astype(np.int32),
        "influence_weights": weights.astype(np.float32),
        "joint_names": np.array([str(j) for j in skel_query.GetJointOrder()]),
        "skinning": np.array([method]),
        "times": (np.array(codes) / tcps).astype(np.float32),
        "time_codes": np.array(codes, dtype=np.float32),
    }
    save_arrays(args.out, arrays)
    print(f"wrote {args.out}: {len(parts)} prim(s), {rest.shape[0]} points, {k} influences/point, "
          f"{len(codes)} time codes, method {method}")
    return EXIT_OK


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter,
                                epilog="Exit status: 0 within tolerance, 1 over it, 2 bad input.")
    p.add_argument("dump", nargs="*",
                   help="rigport eval dumps (.npz or directory of .npy), each checked in turn")
    p.add_argument("--method", choices=sorted(TOKENS), help="override the dump's skinning method")
    p.add_argument("--tolerance", type=float, default=1e-5,
                   help="max deviation as a fraction of the bounding-box diagonal (default 1e-5)")
    p.add_argument("--quiet", action="store_true", help="print only frames over tolerance and the summary")
    p.add_argument("--export-usd", metavar="IN.usda", help="write a UsdSkel test case in the dump layout")
    p.add_argument("--baseline", metavar="BAKED.usda", help="with --export-usd: baked points to store as positions")
    p.add_argument("--out", metavar="OUT", help="with --export-usd: output .npz or directory")
    try:
        args = p.parse_args(argv)
    except SystemExit as e:
        return EXIT_BAD if e.code else EXIT_OK
    try:
        if args.export_usd:
            if not args.out:
                p.error("--export-usd needs --out")
            return export_usd(args)
        if not args.dump:
            print("check_skinning.py: need a DUMP (or --export-usd)", file=sys.stderr)
            return EXIT_BAD
        # Each dump's summary line ends in OK or FAIL; the exit status is the worst.
        return max(check(args, dump) for dump in args.dump)
    except BadInput as e:
        print(f"check_skinning.py: {e}", file=sys.stderr)
        return EXIT_BAD


if __name__ == "__main__":
    sys.exit(main())

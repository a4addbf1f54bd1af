"""Check a UsdSkel .usda written by rigport, and optionally compare it with a `rigport eval` dump.

    tools/.venv/bin/python tools/check_usd.py OUT.usda [--against DUMP.npz] [--tolerance T]
                                            [--clip NAME] [--strict] [--quiet]

1. usd-core's validators, as `usdchecker` runs them:
   - `UsdUtils.ComplianceChecker` (the classic usdchecker rules) when this usd-core still has
     it. usd-core 26.11 no longer ships it (usdchecker there runs the new framework), so it
     is reported as skipped;
   - the `UsdValidation` framework (usd-core >= 24.11): every registered validator except
     the usdz-package ones, on the stage as composed and then once per variant of every
     variant set (what `usdchecker --useNewValidationFramework` does). Errors fail the check,
     warnings too with --strict.
2. rigport's own checks, which usdchecker lacks: per Skeleton, joints parents-first with a
   valid topology and bind/rest arrays of the joint count; per bound prim, SkelBindingAPI
   applied, `skel:skeleton` resolving to a Skeleton, jointIndices/jointWeights with equal
   elementSize and interpolation, sized elementSize x points (vertex) or elementSize
   (constant), indices in range, weights non-negative and summing to 1 per point (1e-6);
   per SkelAnimation, every array matching `joints` / `blendShapes` at every time sample;
   stage metadata upAxis, metersPerUnit, defaultPrim, and timeCodesPerSecond when animated.
3. With --against DUMP.npz: for every entry of the dump's `times` (seconds; no `times` means
   one pose, compared at the default time, i.e. the rest pose), evaluate the stage with
   UsdSkel at time code = seconds x timeCodesPerSecond (snapped to an integer when within
   1e-3 frames of one, as the exporter writes keys): joint world transforms
   (`SkeletonQuery.ComputeJointWorldTransforms`) against `joint_world` (F x J x 4 x 4, or
   J x 4 x 4; row-major storage of column-vector matrices, so the transpose of USD's), and
   points (blend shapes via `BlendShapeQuery`, then `SkinningQuery.ComputeSkinnedPoints`,
   which honours `primvars:skel:skinningMethod`; unbound meshes by their transform) against
   `positions` (F x V x 3 or V x 3). Points are taken mesh by mesh in stage order, each in
   source-vertex order: point i of a mesh is source vertex i unless the mesh has
   `primvars:rigport:sourceVertex`, in which case source vertex s is the first point whose
   entry is s (the rule `rigport eval` dumps with). Joints are compared by index: the
   Skeleton's `joints` are the dump's `joint_names` in the same order (names sanitized to
   USD identifiers may differ; only the count must match).
   A dump's `skinning` entry ("lbs" / "dqs", as `rigport eval --skinning` writes it) must
   match every skinned mesh's skinningMethod.
   Per frame it prints the largest and mean deviation relative to the diagonal of the
   dump's bounding box at that frame (points; joint positions when there are no points):
   for joints, the translation difference / diagonal and, separately, the largest
   difference of the 3x3 part. Exceeding --tolerance (default 1e-5) fails.
   --clip NAME selects the variant NAME of the `clip` variant set first (default: the
   file's selection, the first clip).

Exit status: 0 all checks pass; 1 a validator error, a rigport check failure or a
deviation over tolerance; 2 usage error, unreadable input or no validator available.

    tools/.venv/bin/python tools/check_usd.py --batch JOBS.json

runs several checks in one process (usd-core loads once): JOBS.json is a list of argument
lists, each what one call above takes. Each job's output, its error output included, comes
between a line `==> check_usd job I` and a line `<== check_usd job I exit N`, N its exit
status as above; the batch exits with the largest.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import sys
from dataclasses import dataclass, field

WEIGHT_SUM_TOLERANCE = 1e-6


class DumpError(Exception):
    """The --against dump cannot be read."""


@dataclass
class Report:
    errors: list[str] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    quiet: bool = False

    def error(self, msg: str) -> None:
        self.errors.append(msg)
        print(f"ERROR: {msg}")

    def warn(self, msg: str) -> None:
        self.warnings.append(msg)
        print(f"WARNING: {msg}")

    def info(self, msg: str) -> None:
        if not self.quiet:
            print(msg)


# ----------------------------------------------------------------------------- validators


def run_compliance_checker(path: str, report: Report) -> bool:
    """The classic usdchecker rules; returns whether they could run."""
    try:
        from pxr import UsdUtils

        checker_cls = getattr(UsdUtils, "ComplianceChecker", None)
        if checker_cls is None:
            from pxr.UsdUtils.complianceChecker import ComplianceChecker as checker_cls  # type: ignore
    except ImportError:
        report.info("validators: UsdUtils.ComplianceChecker not in this usd-core (removed in favour of UsdValidation); skipped")
        return False
    checker = checker_cls(arkit=False, skipARKitRootLayerCheck=False, rootPackageOnly=False,
                          skipVariants=False, verbose=False)
    checker.CheckCompliance(path)
    for msg in checker.GetWarnings():
        report.warn(f"ComplianceChecker: {msg}")
    for msg in list(checker.GetErrors()) + list(checker.GetFailedChecks()):
        report.error(f"ComplianceChecker: {msg}")
    report.info(f"validators: UsdUtils.ComplianceChecker ran ({len(checker.GetRules())} rules)")
    return True


def run_validation_framework(stage, report: Report) -> bool:
    """usdchecker --useNewValidationFramework; returns whether the framework exists."""
    try:
        from pxr import UsdValidation
    except ImportError:
        report.info("validators: UsdValidation framework not in this usd-core; skipped")
        return False
    registry = UsdValidation.ValidationRegistry()
    names = sorted(
        m.name
        for m in registry.GetAllValidatorMetadata()
        if "UsdzValidators" not in list(m.GetKeywords())
        and m.name != "usdUtilsValidators:RootPackageValidator"
    )
    validators = registry.GetOrLoadValidatorsByName(names)
    context = UsdValidation.ValidationContext(validators)
    error_type = UsdValidation.ValidationErrorType

    def collect(where: str) -> None:
        for err in context.Validate(stage):
            kind = err.GetType()
            text = f"UsdValidation{where}: {err.GetErrorAsString()}"
            if kind == error_type.Error:
                report.error(text)
            elif kind == error_type.Warn:
                report.warn(text)
            else:
                report.info(f"info: {text}")

    collect("")
    # Every variant of every variant set (with the empty selection), as usdchecker does.
    from pxr import Usd

    combos = 0
    with Usd.EditContext(stage, stage.GetSessionLayer()):
        for prim in stage.Traverse():
            sets = prim.GetVariantSets()
            for set_name in sets.GetNames():
                vset = sets.GetVariantSet(set_name)
                for variant in list(vset.GetVariantNames()) + [""]:
                    vset.SetVariantSelection(variant)
                    collect(f" [{prim.GetPath()} {set_name}={variant or '(none)'}]")
                    combos += 1
                vset.ClearVariantSelection()
    report.info(f"validators: UsdValidation ran {len(names)} validators on the stage and {combos} variant selections")
    return True


# ------------------------------------------------------------------------- rigport checks


def joint_parent(path: str) -> str | None:
    return path.rsplit("/", 1)[0] if "/" in path else None


def check_skeleton(skel, report: Report) -> None:
    from pxr import UsdSkel

    where = str(skel.GetPath())
    joints = skel.GetJointsAttr().Get()
    if joints is None:
        report.error(f"{where}: Skeleton has no joints attribute")
        return
    joints = list(joints)
    index = {}
    for i, j in enumerate(joints):
        if j in index:
            report.error(f"{where}: joint {j!r} listed twice")
        index[j] = i
        parent = joint_parent(j)
        if parent is not None and parent in index and index[parent] > i:
            report.error(f"{where}: joint {i} {j!r} comes before its parent")
        if parent is not None and parent not in index and parent in joints:
            report.error(f"{where}: joint {i} {j!r} comes before its parent {parent!r}")
    ok, why = UsdSkel.Topology(joints).Validate()
    if not ok:
        report.error(f"{where}: invalid joint topology: {why}")
    for attr in (skel.GetBindTransformsAttr(), skel.GetRestTransformsAttr()):
        value = attr.Get()
        if value is None:
            report.error(f"{where}: {attr.GetName()} not authored")
        elif len(value) != len(joints):
            report.error(f"{where}: {attr.GetName()} has {len(value)} matrices for {len(joints)} joints")


def check_animation(anim, report: Report) -> None:
    where = str(anim.GetPath())
    joints = anim.GetJointsAttr().Get()
    n = 0 if joints is None else len(joints)
    for attr in (anim.GetTranslationsAttr(), anim.GetRotationsAttr(), anim.GetScalesAttr()):
        if not attr.HasAuthoredValue():
            report.error(f"{where}: {attr.GetName()} not authored")
            continue
        times = [None] + list(attr.GetTimeSamples())
        for t in times:
            value = attr.Get() if t is None else attr.Get(t)
            if value is not None and len(value) != n:
                report.error(f"{where}: {attr.GetName()} at {'default' if t is None else t} has {len(value)} entries for {n} joints")
    shapes = anim.GetBlendShapesAttr().Get()
    weights_attr = anim.GetBlendShapeWeightsAttr()
    if shapes is not None or weights_attr.HasAuthoredValue():
        m = 0 if shapes is None else len(shapes)
        for t in [None] + list(weights_attr.GetTimeSamples()):
            value = weights_attr.Get() if t is None else weights_attr.Get(t)
            if value is not None and len(value) != m:
                report.error(f"{where}: blendShapeWeights at {'default' if t is None else t} has {len(value)} entries for {m} blend shapes")


def has_skel_properties(prim) -> bool:
    return any(
        name.startswith("skel:") or name.startswith("primvars:skel:")
        for name in prim.GetPropertyNames()
        if prim.GetProperty(name).IsAuthored()
    )


def check_binding(prim, report: Report) -> None:
    import numpy as np
    from pxr import UsdGeom, UsdSkel

    where = str(prim.GetPath())
    if not prim.HasAPI(UsdSkel.BindingAPI):
        report.error(f"{where}: has skel binding properties but SkelBindingAPI is not applied")
    binding = UsdSkel.BindingAPI(prim)
    rel = binding.GetSkeletonRel()
    skeleton = None
    if rel and rel.HasAuthoredTargets():
        targets = rel.GetTargets()
        stage = prim.GetStage()
        resolved = [stage.GetPrimAtPath(t) for t in targets]
        if len(targets) != 1 or not resolved[0] or not resolved[0].IsA(UsdSkel.Skeleton):
            report.error(f"{where}: skel:skeleton {[str(t) for t in targets]} does not resolve to one Skeleton")
        else:
            skeleton = UsdSkel.Skeleton(resolved[0])
    else:
        inherited = binding.GetInheritedSkeleton()
        if inherited:
            skeleton = inherited

    anim_rel = binding.GetAnimationSourceRel()
    if anim_rel and anim_rel.HasAuthoredTargets():
        targets = anim_rel.GetTargets()
        stage = prim.GetStage()
        if len(targets) != 1 or not stage.GetPrimAtPath(targets[0]).IsA(UsdSkel.Animation):
            report.error(f"{where}: skel:animationSource {[str(t) for t in targets]} does not resolve to one SkelAnimation")

    indices_pv = binding.GetJointIndicesPrimvar()
    weights_pv = binding.GetJointWeightsPrimvar()
    has_indices = indices_pv and indices_pv.HasAuthoredValue()
    has_weights = weights_pv and weights_pv.HasAuthoredValue()
    if not has_indices and not has_weights:
        return
    if has_indices != has_weights:
        report.error(f"{where}: only one of primvars:skel:jointIndices / jointWeights is authored")
        return
    if skeleton is None:
        report.error(f"{where}: joint influences but no skel:skeleton binding")
        return
    es_i, es_w = indices_pv.GetElementSize(), weights_pv.GetElementSize()
    interp_i, interp_w = indices_pv.GetInterpolation(), weights_pv.GetInterpolation()
    if es_i != es_w:
        report.error(f"{where}: jointIndices elementSize {es_i} != jointWeights elementSize {es_w}")
        return
    if interp_i != interp_w:
        report.error(f"{where}: jointIndices interpolation {interp_i} != jointWeights interpolation {interp_w}")
        return
    if interp_i not in ("vertex", "constant"):
        report.error(f"{where}: joint influence interpolation {interp_i!r} (UsdSkel supports vertex and constant)")
        return
    indices = np.asarray(indices_pv.Get(), dtype=np.int64)
    weights = np.asarray(weights_pv.Get(), dtype=np.float64)
    if len(indices) != len(weights):
        report.error(f"{where}: {len(indices)} joint indices but {len(weights)} joint weights")
        return
    if es_i < 1:
        report.error(f"{where}: elementSize {es_i} < 1")
        return
    points = UsdGeom.PointBased(prim).GetPointsAttr().Get() if prim.IsA(UsdGeom.PointBased) else None
    if interp_i == "vertex":
        n_points = 0 if points is None else len(points)
        if len(indices) != es_i * n_points:
            report.error(f"{where}: {len(indices)} joint indices for {n_points} points x elementSize {es_i}")
            return
    elif len(indices) != es_i:
        report.error(f"{where}: constant influences need elementSize ({es_i}) entries, found {len(indices)}")
        return
    joint_order = binding.GetJointsAttr().Get() or skeleton.GetJointsAttr().Get() or []
    n_joints = len(joint_order)
    bad = np.nonzero((indices < 0) | (indices >= n_joints))[0]
    if len(bad):
        report.error(f"{where}: joint index {int(indices[bad[0]])} at entry {int(bad[0])} out of range for {n_joints} joints ({len(bad)} such entries)")
    if (weights < 0).any():
        report.error(f"{where}: {int((weights < 0).sum())} negative joint weights")
    sums = weights.reshape(-1, es_i).sum(axis=1)
    off = np.abs(sums - 1.0)
    worst = int(np.argmax(off)) if len(off) else 0
    if len(off) and off[worst] > WEIGHT_SUM_TOLERANCE:
        report.error(f"{where}: joint weights of point {worst} sum to {sums[worst]:.9g} ({int((off > WEIGHT_SUM_TOLERANCE).sum())} points off by more than {WEIGHT_SUM_TOLERANCE:g})")


def rigport_checks(stage, report: Report) -> None:
    from pxr import Usd, UsdGeom, UsdSkel

    layer_md = stage.GetRootLayer()
    if not stage.GetDefaultPrim():
        report.error("stage: no defaultPrim")
    if not stage.HasAuthoredMetadata("upAxis"):
        report.error("stage: upAxis not authored")
    if not stage.HasAuthoredMetadata("metersPerUnit"):
        report.error("stage: metersPerUnit not authored")
    animated = False
    counts = {"Skeleton": 0, "SkelAnimation": 0, "bound": 0}
    for prim in stage.Traverse(Usd.TraverseInstanceProxies(Usd.PrimAllPrimsPredicate)):
        if prim.IsA(UsdSkel.Skeleton):
            counts["Skeleton"] += 1
            check_skeleton(UsdSkel.Skeleton(prim), report)
        if prim.IsA(UsdSkel.Animation):
            counts["SkelAnimation"] += 1
            anim = UsdSkel.Animation(prim)
            check_animation(anim, report)
            animated |= any(a.GetNumTimeSamples() > 0 for a in prim.GetAttributes())
        if has_skel_properties(prim):
            counts["bound"] += 1
            check_binding(prim, report)
    if animated and not layer_md.HasTimeCodesPerSecond():
        report.error("stage: animated but timeCodesPerSecond not authored")
    report.info(
        f"rigport checks: {counts['Skeleton']} Skeleton, {counts['SkelAnimation']} SkelAnimation, "
        f"{counts['bound']} prims with skel bindings; up {UsdGeom.GetStageUpAxis(stage)}, "
        f"{UsdGeom.GetStageMetersPerUnit(stage)} m/unit, {stage.GetTimeCodesPerSecond()} time codes/s"
    )


# ----------------------------------------------------------------------------- comparison


def skel_queries_of(stage):
    """A populated `UsdSkel.Cache`, the skinning targets by prim path (skeleton query, skinning
    query), and a skeleton query per Skeleton prim in stage order."""
    from pxr import Usd, UsdSkel

    cache = UsdSkel.Cache()
    skinning = {}
    skel_queries = []
    for prim in stage.Traverse():
        if prim.IsA(UsdSkel.Root):
            root = UsdSkel.Root(prim)
            cache.Populate(root, Usd.PrimDefaultPredicate)
            for binding in cache.ComputeSkelBindings(root, Usd.PrimDefaultPredicate):
                skel_query = cache.GetSkelQuery(binding.GetSkeleton())
                for query in binding.GetSkinningTargets():
                    skinning[query.GetPrim().GetPath()] = (skel_query, query)
    for prim in stage.Traverse():
        if prim.IsA(UsdSkel.Skeleton):
            skel_queries.append(cache.GetSkelQuery(UsdSkel.Skeleton(prim)))
    return cache, skinning, skel_queries


def mesh_points(stage, cache, skinning, time, np):
    """Evaluated points of every Mesh under the default prim, stage order, dump order."""
    from pxr import Usd, UsdGeom, UsdSkel, Vt

    root = stage.GetDefaultPrim() or stage.GetPseudoRoot()
    xform_cache = UsdGeom.XformCache(time)
    out = []
    for prim in Usd.PrimRange(root):
        if not prim.IsA(UsdGeom.Mesh):
            continue
        mesh = UsdGeom.Mesh(prim)
        points = mesh.GetPointsAttr().Get(time)
        if points is None:
            continue
        points = Vt.Vec3fArray(points)
        entry = skinning.get(prim.GetPath())
        if entry is None:
            world = xform_cache.GetLocalToWorldTransform(prim)
            pts = np.asarray(points, dtype=np.float64)
            pts = pts @ np.asarray(world)[:3, :3] + np.asarray(world)[3, :3]
        else:
            skel_query, query = entry
            if query.HasBlendShapes():
                anim_query = skel_query.GetAnimQuery()
                if anim_query:
                    weights = anim_query.ComputeBlendShapeWeights(time)
                    mapper = query.GetBlendShapeMapper()
                    if mapper and not mapper.IsNull():
                        weights = mapper.Remap(weights)
                    shapes = UsdSkel.BlendShapeQuery(UsdSkel.BindingAPI(prim))
                    sub, bs_idx, sub_idx = shapes.ComputeSubShapeWeights(weights)
                    shapes.ComputeDeformedPoints(sub, bs_idx, sub_idx, shapes.ComputeBlendShapePointIndices(),
                                                 shapes.ComputeSubShapePointOffsets(), points)
            if query.HasJointInfluences():
                xforms = skel_query.ComputeSkinningTransforms(time)
                if not query.ComputeSkinnedPoints(xforms, points, time):
                    raise RuntimeError(f"{prim.GetPath()}: UsdSkel could not skin the points")
                # Skinned points are in skeleton space.
                world = xform_cache.GetLocalToWorldTransform(skel_query.GetPrim())
            else:
                world = xform_cache.GetLocalToWorldTransform(prim)
            pts = np.asarray(points, dtype=np.float64)
            pts = pts @ np.asarray(world)[:3, :3] + np.asarray(world)[3, :3]
        pv = UsdGeom.PrimvarsAPI(prim).GetPrimvar("rigport:sourceVertex")
        if pv and pv.HasAuthoredValue():
            source = np.asarray(pv.Get(), dtype=np.int64)
            first = {}
            for v, s in enumerate(source.tolist()):
                first.setdefault(s, v)
            order = [first[s] for s in sorted(first)]
            pts = pts[order]
        out.append(pts)
    if not out:
        return np.zeros((0, 3))
    return np.concatenate(out)


def time_code(seconds: float, tcps: float) -> float:
    """seconds x tcps, snapped to the nearest integer when within 1e-3 frames of it (or the
    f32 noise of the time, 2^-21 relative, when larger): the rule rigport's exporter writes
    keys with. Dump times are f32, so without it key k of a 30.00003 fps BVH clip at 10 s
    comes back as frame k + 2e-5, which on a fast motion is 1e-5 of the pose off the key."""
    tc = seconds * tcps
    whole = round(tc)
    return float(whole) if abs(tc - whole) <= max(1e-3, abs(tc) * 2.0**-21) else tc


def compare(stage, dump_path: str, tolerance: float, report: Report) -> None:
    import numpy as np
    from pxr import Usd, UsdGeom, UsdSkel

    try:
        with np.load(dump_path, allow_pickle=False) as npz:
            dump = {k: npz[k] for k in npz.files}
    except Exception as exc:  # zipfile.BadZipFile, OSError, ValueError (pickled arrays)...
        raise DumpError(f"cannot read the dump: {exc}") from exc
    times = dump.get("times")
    joint_world = dump.get("joint_world")
    positions = dump.get("positions")
    names = dump.get("joint_names")
    if joint_world is not None and joint_world.ndim == 3:
        joint_world = joint_world[None]
    if positions is not None and positions.ndim == 2:
        positions = positions[None]
    frames = 1 if times is None else len(times)
    for key, arr in (("joint_world", joint_world), ("positions", positions)):
        if arr is not None and len(arr) != frames:
            report.error(f"dump: {key} has {len(arr)} frames but times has {frames}")
            return

    cache, skinning, skel_queries = skel_queries_of(stage)
    skel_query = skel_queries[0] if skel_queries else None
    if joint_world is not None and joint_world.shape[1] > 0:
        if skel_query is None:
            report.error("compare: the dump has joints but the stage has no Skeleton")
            return
        usd_joints = list(skel_query.GetJointOrder())
        if len(usd_joints) != joint_world.shape[1]:
            report.error(f"compare: the Skeleton has {len(usd_joints)} joints, the dump {joint_world.shape[1]}")
            return
        if names is not None:
            differ = [(str(n), j) for n, j in zip(names.tolist(), usd_joints) if j.rsplit("/", 1)[-1] != str(n)]
            if differ:
                report.info(f"compare: {len(differ)} joint names differ from the dump (sanitized), e.g. {differ[0]}")

    # `rigport eval` records its skinning method ("lbs" / "dqs"); a stage skinning the other
    # way cannot match, so say so plainly instead of listing every point.
    dump_method = dump.get("skinning")
    if dump_method is not None and dump_method.size:
        wanted = {"lbs": "classicLinear", "dqs": "dualQuaternion"}.get(str(dump_method.flat[0]), str(dump_method.flat[0]))
        for path, (_, query) in sorted(skinning.items()):
            if query.HasJointInfluences() and not query.IsRigidlyDeformed() and query.GetSkinningMethod() != wanted:
                report.error(f"compare: {path} skins with {query.GetSkinningMethod()} but the dump was made with {wanted}")

    tcps = stage.GetTimeCodesPerSecond()
    worst = 0.0
    anim_name = skel_query.GetAnimQuery().GetPrim().GetPath() if skel_query and skel_query.GetAnimQuery() else None
    report.info(f"compare: {frames} frame(s) against {dump_path}; animation {anim_name}; {tcps} time codes/s; tolerance {tolerance:g} of the bounding-box diagonal")
    for f in range(frames):
        time = Usd.TimeCode.Default() if times is None else Usd.TimeCode(time_code(float(times[f]), tcps))
        label = "default" if times is None else f"t={float(times[f]):.6g}s tc={time.GetValue():.6g}"
        ref_pts = None if positions is None else positions[f].astype(np.float64)
        parts = []
        diag = 0.0
        if ref_pts is not None and len(ref_pts):
            diag = float(np.linalg.norm(ref_pts.max(axis=0) - ref_pts.min(axis=0)))
        if joint_world is not None and joint_world.shape[1] > 0 and diag == 0.0:
            jp = joint_world[f][:, :3, 3].astype(np.float64)
            diag = float(np.linalg.norm(jp.max(axis=0) - jp.min(axis=0)))
        if diag == 0.0:
            diag = 1.0
        if joint_world is not None and joint_world.shape[1] > 0:
            usd = np.asarray(skel_query.ComputeJointWorldTransforms(UsdGeom.XformCache(time)), dtype=np.float64)
            # USD: row vectors (translation in row 3); dump: column vectors.
            usd = usd.transpose(0, 2, 1)
            ref = joint_world[f].astype(np.float64)
            dt = np.linalg.norm(usd[:, :3, 3] - ref[:, :3, 3], axis=1) / diag
            dr = np.abs(usd[:, :3, :3] - ref[:, :3, :3]).reshape(len(ref), -1).max(axis=1)
            parts.append(f"joints translation max {dt.max():.3e} mean {dt.mean():.3e}, 3x3 max {dr.max():.3e}")
            worst = max(worst, float(dt.max()), float(dr.max()))
            if max(dt.max(), dr.max()) > tolerance:
                j = int(np.argmax(np.maximum(dt, dr)))
                report.error(f"frame {f} ({label}): joint {j} {skel_query.GetJointOrder()[j]!r} off by {max(dt[j], dr[j]):.3e}")
        if ref_pts is not None:
            pts = mesh_points(stage, cache, skinning, time, np)
            if pts.shape != ref_pts.shape:
                report.error(f"frame {f} ({label}): the stage has {len(pts)} points, the dump {len(ref_pts)}")
                continue
            if len(pts):
                d = np.linalg.norm(pts - ref_pts, axis=1) / diag
                parts.append(f"points max {d.max():.3e} mean {d.mean():.3e}")
                worst = max(worst, float(d.max()))
                if d.max() > tolerance:
                    v = int(np.argmax(d))
                    report.error(f"frame {f} ({label}): point {v} off by {d[v]:.3e} of the diagonal: USD {pts[v].tolist()} vs dump {ref_pts[v].tolist()}")
        print(f"frame {f} ({label}, diagonal {diag:.6g}): " + "; ".join(parts))
    report.info(f"compare: largest deviation {worst:.3e} (tolerance {tolerance:g})")


# ----------------------------------------------------------------------------------- main


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("usd", help="the .usda (or any USD file) to check")
    parser.add_argument("--against", metavar="DUMP.npz", help="a `rigport eval` dump to compare with")
    parser.add_argument("--tolerance", type=float, default=1e-5,
                        help="largest deviation allowed, relative to the bounding-box diagonal (default 1e-5)")
    parser.add_argument("--clip", metavar="NAME", help="select this variant of the `clip` variant set before comparing")
    parser.add_argument("--strict", action="store_true", help="validator warnings fail the check too")
    parser.add_argument("--quiet", action="store_true", help="print only problems and per-frame lines")
    args = parser.parse_args(argv)

    try:
        from pxr import Usd
    except ImportError as exc:
        print(f"check_usd: cannot import pxr ({exc}); run `bash tools/setup.sh` and use tools/.venv/bin/python", file=sys.stderr)
        return 2
    report = Report(quiet=args.quiet)
    try:
        stage = Usd.Stage.Open(args.usd)
    except Exception as exc:  # pxr raises Tf.ErrorException for parse errors
        print(f"check_usd: {args.usd}: cannot open: {exc}", file=sys.stderr)
        return 2
    if not stage:
        print(f"check_usd: {args.usd}: cannot open", file=sys.stderr)
        return 2
    report.info(f"check_usd: {args.usd} (usd-core {'.'.join(map(str, Usd.GetVersion()))})")

    ran_classic = run_compliance_checker(args.usd, report)
    ran_framework = run_validation_framework(stage, report)
    if not ran_classic and not ran_framework:
        print("check_usd: no USD validator available in this usd-core", file=sys.stderr)
        return 2
    rigport_checks(stage, report)

    if args.clip is not None:
        prim = stage.GetDefaultPrim()
        vset = prim.GetVariantSets().GetVariantSet("clip") if prim and prim.GetVariantSets().HasVariantSet("clip") else None
        if vset is None or args.clip not in vset.GetVariantNames():
            names = [] if vset is None else list(vset.GetVariantNames())
            print(f"check_usd: no clip variant {args.clip!r} (have {names})", file=sys.stderr)
            return 2
        with Usd.EditContext(stage, stage.GetSessionLayer()):
            vset.SetVariantSelection(args.clip)
    if args.against:
        try:
            compare(stage, args.against, args.tolerance, report)
        except DumpError as exc:
            print(f"check_usd: {args.against}: {exc}", file=sys.stderr)
            return 2

    failed = bool(report.errors) or (args.strict and bool(report.warnings))
    print(f"check_usd: {'FAILED' if failed else 'OK'}: {len(report.errors)} errors, {len(report.warnings)} warnings")
    return 1 if failed else 0


def main_batch(path: str) -> int:
    """Runs every job of the JSON list at `path` (see the module text)."""
    with open(path, encoding="utf-8") as f:
        jobs = json.load(f)
    worst = 0
    for i, argv in enumerate(jobs):
        print(f"==> check_usd job {i}", flush=True)
        with contextlib.redirect_stderr(sys.stdout):
            try:
                rc = main([str(a) for a in argv])
            except SystemExit as exc:  # argparse's usage errors
                rc = exc.code if isinstance(exc.code, int) else 2
        print(f"<== check_usd job {i} exit {rc}", flush=True)
        worst = max(worst, rc)
    return worst


if __name__ == "__main__":
    if len(sys.argv) == 3 and sys.argv[1] == "--batch":
        sys.exit(main_batch(sys.argv[2]))
    sys.exit(main())

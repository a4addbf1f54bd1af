"""Check that two USD files hold the same layer and evaluate the same (usd-core).

    tools/.venv/bin/python tools/same_usd.py A.usda B.usdc [--quiet]

Used for rigport's `.usdc` / `.usdz` outputs against its `.usda` of the same input:
1. The root layers as `Sdf` holds them: `ExportToString` of both, and spec by spec the
   paths (target and connection specs included) with every info key and its value.
2. The composed stages under every selection of every variant set (one set at a time, and
   the authored selections): every prim's type, applied schemas and every attribute's
   value at the default time and, for an attribute with time samples, at each time code
   of the stage's range and each authored sample time, compared exactly (`==` on the values usd-core returns; asset
   paths as authored, since a package resolves them to its members).
3. UsdSkel's evaluation at those times under those selections: per Skeleton the skinning
   transforms (`SkeletonQuery.ComputeSkinningTransforms`) and per skinned prim the
   skinned points (`SkinningQuery.ComputeSkinnedPoints`, which applies the skinning
   method), compared exactly.

Exit status: 0 the same; 1 a difference (the first ones printed); 2 usage error or a file
usd-core cannot open.
"""

from __future__ import annotations

import sys


def shown(value):
    """A comparable text of a field value (list ops by their item lists)."""
    if hasattr(value, "prependedItems"):
        return repr((value.isExplicit, list(value.explicitItems), list(value.addedItems),
                     list(value.prependedItems), list(value.appendedItems),
                     list(value.deletedItems), list(value.orderedItems)))
    return repr(value)


def layer_specs(layer):
    from pxr import Sdf

    out = {}

    def visit(path):
        spec = layer.GetObjectAtPath(path)
        keys = sorted(spec.ListInfoKeys()) if spec is not None and hasattr(spec, "ListInfoKeys") else []
        out[str(path)] = [(k, shown(spec.GetInfo(k))) for k in keys]

    layer.Traverse(Sdf.Path.absoluteRootPath, visit)
    return out


def times_of(stage):
    times = set()
    if stage.HasAuthoredTimeCodeRange():
        start, end = stage.GetStartTimeCode(), stage.GetEndTimeCode()
        t = int(start)
        while t <= end:
            times.add(float(t))
            t += 1
    for prim in stage.TraverseAll():
        for attr in prim.GetAttributes():
            times.update(attr.GetTimeSamples())
    return sorted(times)


def authored(value):
    """Asset paths as authored: a package resolves them to its members, a loose layer to
    files beside it."""
    if hasattr(value, "resolvedPath"):
        return value.path
    return value


def stage_values(stage, times):
    from pxr import Usd

    out = []
    for prim in stage.TraverseAll():
        out.append((str(prim.GetPath()), prim.GetTypeName(), list(prim.GetAppliedSchemas())))
        for attr in prim.GetAttributes():
            out.append((str(attr.GetPath()), "default", authored(attr.Get(Usd.TimeCode.Default()))))
            # An attribute without samples (nor value clips, which rigport never writes) holds
            # its default at every time: its times are compared, its value once.
            samples = attr.GetTimeSamples()
            out.append((str(attr.GetPath()), "samples", list(samples)))
            if samples:
                for t in times:
                    out.append((str(attr.GetPath()), t, authored(attr.Get(t))))
        for rel in prim.GetRelationships():
            out.append((str(rel.GetPath()), [str(p) for p in rel.GetTargets()]))
    return out


def skel_values(stage, times):
    from pxr import Usd, UsdGeom, UsdSkel

    out = []
    cache = UsdSkel.Cache()
    for prim in stage.Traverse():
        if not prim.IsA(UsdSkel.Root):
            continue
        root = UsdSkel.Root(prim)
        cache.Populate(root, Usd.PrimDefaultPredicate)
        for binding in cache.ComputeSkelBindings(root, Usd.PrimDefaultPredicate):
            skel_query = cache.GetSkelQuery(binding.GetSkeleton())
            for t in times:
                xforms = skel_query.ComputeSkinningTransforms(t)
                # Vt arrays compare element by element in C++ (`==`), without a Python list.
                out.append((str(binding.GetSkeleton().GetPath()), t, xforms))
                for target in binding.GetSkinningTargets():
                    points_attr = UsdGeom.PointBased(target.GetPrim()).GetPointsAttr()
                    points = points_attr.Get(t)
                    if points is None:
                        continue
                    target.ComputeSkinnedPoints(xforms, points, t)
                    out.append((str(target.GetPrim().GetPath()), t, points))
    return out


def selections(stage):
    """(prim path, set, variant) choices: the authored selection, then each variant."""
    out = [None]
    for prim in stage.TraverseAll():
        sets = prim.GetVariantSets()
        for name in sets.GetNames():
            for variant in sets.GetVariantSet(name).GetVariantNames():
                out.append((prim.GetPath(), name, variant))
    return out


def evaluate(stage, choice):
    from pxr import Usd

    with Usd.EditContext(stage, stage.GetSessionLayer()):
        stage.GetSessionLayer().Clear()
        if choice is not None:
            path, name, variant = choice
            stage.GetPrimAtPath(path).GetVariantSets().GetVariantSet(name).SetVariantSelection(variant)
    times = times_of(stage)
    return stage_values(stage, times), skel_values(stage, times), len(times)


def first_difference(a, b):
    for i, (x, y) in enumerate(zip(a, b)):
        if x != y:
            return f"item {i}: {str(x)[:300]} != {str(y)[:300]}"
    if len(a) != len(b):
        return f"{len(a)} items against {len(b)}"
    return None


def main(argv):
    args = [a for a in argv if not a.startswith("--")]
    quiet = "--quiet" in argv
    if len(args) != 2:
        print(__doc__)
        return 2
    from pxr import Sdf, Usd

    layers = [Sdf.Layer.FindOrOpen(p) for p in args]
    stages = [Usd.Stage.Open(p) for p in args]
    if not all(layers) or not all(stages):
        print("cannot open", args)
        return 2
    bad = []
    # A package's root layer is its first member.
    roots = [s.GetRootLayer() for s in stages]
    if roots[0].ExportToString() != roots[1].ExportToString():
        bad.append("the layers export to different text")
    diff = first_difference(sorted(layer_specs(roots[0]).items()), sorted(layer_specs(roots[1]).items()))
    if diff:
        bad.append(f"specs differ: {diff}")
    checked = 0
    for choice in selections(stages[0]):
        (va, sa, n), (vb, sb, _) = evaluate(stages[0], choice), evaluate(stages[1], choice)
        where = "authored selections" if choice is None else f"{choice[0]} {choice[1]}={choice[2]}"
        for what, x, y in (("values", va, vb), ("UsdSkel evaluation", sa, sb)):
            diff = first_difference(x, y)
            if diff:
                bad.append(f"{where}: {what} differ: {diff}")
        checked += 1
        if not quiet:
            print(f"{where}: {len(va)} values, {len(sa)} UsdSkel results at {n} times: same")
    for b in bad:
        print("DIFFERENT:", b)
    if not bad:
        print(f"same layer and evaluation under {checked} selections: {args[0]} {args[1]}")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

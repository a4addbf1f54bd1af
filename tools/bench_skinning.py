#!/usr/bin/env python3
"""Time usd-core's UsdSkel.SkinPoints on the arrays of `cargo bench --bench skinning` and
print rigport's throughput next to it, with the ratios.

Usage (from the repo root, after `cargo bench --bench skinning`):
  tools/.venv/bin/python tools/bench_skinning.py [--data target/skinning-bench]
      [--criterion target/criterion] [--repeat 3] [--threads 2]

benches/skinning.rs writes each input in the `rigport eval` dump layout to
target/skinning-bench/<input>/ (rest_positions, influence_joints, influence_weights,
skin_matrices F x J x 4 x 4, and rigport's first-frame result per method,
positions_lbs.npy / positions_dqs.npy), and criterion leaves its estimates in
target/criterion/<input>/<method>_<variant>/<threads>t/new/. This script:
  - times UsdSkel.SkinPoints (classicLinear / dualQuaternion) on every frame of the same
    arrays, serially (inSerial=True: 1 thread) and in parallel with PXR_WORK_THREAD_LIMIT
    threads (default 2), best of --repeat runs, excluding array conversions;
  - checks rigport's first-frame positions against UsdSkel's (max deviation relative to
    the bounding-box diagonal);
  - prints vertices x frames per second for both and rigport / usd-core ratios.

rigport's figures are criterion's mean time per iteration (new/estimates.json) and the
element count it was told (new/benchmark.json: vertices x frames). Exit status: 0, or 2
when the inputs are missing.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time


def parse_args():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--data", default="target/skinning-bench", help="arrays written by the bench")
    p.add_argument("--criterion", default="target/criterion", help="criterion's output folder")
    p.add_argument("--repeat", type=int, default=3, help="UsdSkel runs per measurement (best is kept)")
    p.add_argument("--threads", type=int, default=2, help="threads for UsdSkel's parallel run")
    return p.parse_args()


ARGS = parse_args()
# usd-core reads its thread limit when pxr loads.
os.environ["PXR_WORK_THREAD_LIMIT"] = str(ARGS.threads)

import numpy as np  # noqa: E402
from pxr import Gf, UsdSkel, Vt  # noqa: E402

TOKENS = {"lbs": "classicLinear", "dqs": "dualQuaternion"}


def criterion_rate(case: str, bench: str, threads: int):
    """rigport's vertices x frames per second, or None if the bench did not run."""
    d = os.path.join(ARGS.criterion, case, bench, f"{threads}t", "new")
    try:
        with open(os.path.join(d, "estimates.json")) as f:
            ns = json.load(f)["mean"]["point_estimate"]
        with open(os.path.join(d, "benchmark.json")) as f:
            elements = json.load(f)["throughput"]["Elements"]
    except (OSError, KeyError, TypeError, ValueError):
        return None
    return elements / (ns * 1e-9)


def usd_rate(method, rest_vt, mats_vt, idx_vt, wts_vt, k, serial):
    """Best vertices x frames per second over --repeat runs of every frame."""
    v = len(rest_vt)
    best = None
    for _ in range(ARGS.repeat):
        points = [Vt.Vec3fArray(rest_vt) for _ in mats_vt]
        t0 = time.perf_counter()
        for xf, pts in zip(mats_vt, points):
            if not UsdSkel.SkinPoints(TOKENS[method], Gf.Matrix4d(1.0), xf, idx_vt, wts_vt, k, pts, serial):
                raise RuntimeError("UsdSkel.SkinPoints failed")
        dt = time.perf_counter() - t0
        best = dt if best is None else min(best, dt)
    return v * len(mats_vt) / best, points[0]


def fmt(rate):
    return f"{rate / 1e6:8.1f}" if rate else "       -"


def main() -> int:
    if not os.path.isdir(ARGS.data):
        print(f"bench_skinning.py: {ARGS.data} is missing: run `cargo bench --bench skinning` first",
              file=sys.stderr)
        return 2
    print(f"M vertices x frames per second; usd-core parallel runs use PXR_WORK_THREAD_LIMIT={ARGS.threads}")
    header = (f"{'input':16} {'method':6} {'thr':>3} | {'rigport job_f1':>14} {'packed_f1':>9} {'packed_f8':>9} | "
              f"{'usd-core':>8} | {'f8/usd':>6} {'job/usd':>7}")
    print(header)
    print("-" * len(header))
    for case in sorted(os.listdir(ARGS.data)):
        d = os.path.join(ARGS.data, case)
        load = lambda n: np.load(os.path.join(d, n + ".npy"))
        try:
            rest = load("rest_positions").astype(np.float32)
            idx = load("influence_joints").astype(np.int32)
            wts = load("influence_weights").astype(np.float32)
            mats = load("skin_matrices").astype(np.float64)
        except OSError as e:
            print(f"bench_skinning.py: {d}: {e}", file=sys.stderr)
            return 2
        k = idx.shape[1]
        rest_vt = Vt.Vec3fArray.FromNumpy(np.ascontiguousarray(rest))
        idx_vt = Vt.IntArray.FromNumpy(np.ascontiguousarray(idx.reshape(-1)))
        wts_vt = Vt.FloatArray.FromNumpy(np.ascontiguousarray(wts.reshape(-1)))
        # Column-vector matrices stored row-major; USD wants row vectors: the transpose.
        mats_vt = [Vt.Matrix4dArray.FromNumpy(np.ascontiguousarray(np.transpose(m, (0, 2, 1)))) for m in mats]
        for method in ("lbs", "dqs"):
            check = ""
            for threads in (1, 2):
                rate, first = usd_rate(method, rest_vt, mats_vt, idx_vt, wts_vt, k, threads == 1)
                ours = {var: criterion_rate(case, f"{method}_{var}", threads)
                        for var in ("job_f1", "packed_f1", "packed_f8")}
                ratio = lambda r: f"{r / rate:6.1f}x" if r else "     -"
                print(f"{case:16} {method:6} {threads:3d} | {fmt(ours['job_f1']):>14} {fmt(ours['packed_f1']):>9} "
                      f"{fmt(ours['packed_f8']):>9} | {fmt(rate):>8} | {ratio(ours['packed_f8'])} {ratio(ours['job_f1']):>7}")
                if not check:
                    path = os.path.join(d, f"positions_{method}.npy")
                    if os.path.exists(path):
                        expect = np.array(first, dtype=np.float64).reshape(-1, 3)
                        got = np.load(path).astype(np.float64)
                        diag = np.linalg.norm(expect.max(0) - expect.min(0)) or 1.0
                        dev = np.linalg.norm(got - expect, axis=1).max() / diag
                        check = f"  rigport vs UsdSkel, frame 0: max deviation {dev:.2e} of the diagonal"
            print(check)
    return 0


if __name__ == "__main__":
    sys.exit(main())

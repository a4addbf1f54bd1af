#!/usr/bin/env python3
"""Compare rigport's compact glb sizes with gltfpack's, file by file, on a folder of BVH clips.

Usage (from the repo root, after `cargo build --release` and `bash tools/setup.sh`):
  python3 tools/compact_sizes.py FOLDER_OR_BVH... [--rigport target/release/rigport]
      [--units auto]

For each `.bvh` given (or found directly in a folder given), rigport writes the plain glb
(`convert X.bvh --input-units UNITS`), then from the same BVH:
  - `--reduce-tolerance` (the 1 mm default, core glTF), against gltfpack's default output
    from the plain glb (resample to 30 Hz, quantize);
  - `--compress meshopt` (the same bound), against `gltfpack -cc` from the plain glb.
It prints one row per clip (bytes and ratios, rigport's largest error as it reports it in
the rig's units) and the totals: the summed sizes, their ratio, the worst ratio and how
many clips come out bigger than gltfpack's. The errors are rigport's own measure; the
corpus test (`tests/cli/compact.rs`) measures the corpus files with three.js.

Exit status: 0; 1 when a clip comes out bigger than gltfpack's; 2 when an input or a tool
is missing or a command fails.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent


def clips(paths: list[str]) -> list[Path]:
    found: list[Path] = []
    for p in map(Path, paths):
        if p.is_dir():
            found.extend(sorted(p.glob("*.bvh")))
        else:
            found.append(p)
    return found


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("inputs", nargs="+")
    parser.add_argument("--rigport", default=str(REPO / "target/release/rigport"))
    parser.add_argument("--units", default="auto")
    args = parser.parse_args()
    gltfpack = REPO / "tools/node_modules/gltfpack/cli.js"
    inputs = clips(args.inputs)
    for needed in [Path(args.rigport), gltfpack, *inputs]:
        if not needed.exists():
            print(f"missing: {needed}", file=sys.stderr)
            return 2
    if not inputs:
        print("no .bvh given", file=sys.stderr)
        return 2
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp)

        def run(cmd: list[str]) -> str:
            done = subprocess.run(cmd, capture_output=True, text=True)
            if done.returncode != 0:
                raise RuntimeError(f"{' '.join(cmd)}: {done.stderr.strip()}")
            return done.stdout

        def rigport(bvh: Path, name: str, *flags: str) -> tuple[int, dict]:
            path = out / name
            report = run(
                [args.rigport, "convert", str(bvh), "--input-units", args.units,
                 "-o", str(path), "--json", *flags]
            )
            return path.stat().st_size, json.loads(report) if report.strip() else {}

        def gltfpack_size(plain: Path, name: str, *flags: str) -> int:
            path = out / name
            run(["node", str(gltfpack), *flags, "-i", str(plain), "-o", str(path)])
            return path.stat().st_size

        print(f"{'clip':48} {'core':>8} {'gltfpack':>8} {'ratio':>6} "
              f"{'meshopt':>8} {'-cc':>8} {'ratio':>6} {'max err':>9}")
        for bvh in inputs:
            try:
                rigport(bvh, "plain.glb")
                core, report = rigport(bvh, "core.glb", "--reduce-tolerance")
                meshopt, _ = rigport(bvh, "meshopt.glb", "--compress", "meshopt")
                gp = gltfpack_size(out / "plain.glb", "gp.glb")
                cc = gltfpack_size(out / "plain.glb", "cc.glb", "-cc")
            except RuntimeError as e:
                print(e, file=sys.stderr)
                return 2
            error = max((c["max_error"] for c in report.get("clips", [])), default=0.0)
            rows.append((bvh.stem, core, gp, meshopt, cc))
            print(f"{bvh.stem:48} {core:8} {gp:8} {core / gp:6.3f} "
                  f"{meshopt:8} {cc:8} {meshopt / cc:6.3f} {error:9.3e}")
    core, gp, mo, cc = (sum(r[i] for r in rows) for i in range(1, 5))
    worst_core = max(r[1] / r[2] for r in rows)
    worst_mo = max(r[3] / r[4] for r in rows)
    over_core = sum(r[1] > r[2] for r in rows)
    over_mo = sum(r[3] > r[4] for r in rows)
    print(f"{len(rows)} clips. core: {core / gp:.4f} of gltfpack's total, worst "
          f"{worst_core:.3f}, {over_core} bigger; meshopt: {mo / cc:.4f} of -cc's total, "
          f"worst {worst_mo:.3f}, {over_mo} bigger")
    return 1 if over_core or over_mo else 0


if __name__ == "__main__":
    sys.exit(main())

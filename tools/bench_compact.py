#!/usr/bin/env python3
"""Time compacting the corpus's longest clip with rigport and with gltfpack, side by side.

Usage (from the repo root, after `cargo build --release` and `bash tools/setup.sh`):
  python3 tools/bench_compact.py [--rigport target/release/rigport] [--repeat 5]
      [--corpus ../shared/corpus]

Both tools start from the same plain glb (`rigport convert 131-dance.asf --motion
131_04-dance.amc`: 32,580 keys, 502 KB, the corpus's longest clip) and write a compact glb:
  - rigport `convert plain.glb --reduce-tolerance` (1 mm, 16-bit rotations) against
    gltfpack's default (resample to 30 Hz, quantize);
  - rigport `convert plain.glb --compress meshopt` against `gltfpack -cc`.
Each command runs --repeat times (after one warm-up); the script prints the median and the
fastest wall time of each, whole processes (rigport reads, reduces, measures and writes;
gltfpack is the npm package, WebAssembly under Node), the output sizes, and the ratios.
Exit status: 0, or 2 when an input or a tool is missing.
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent


def timed(cmd: list[str], repeat: int) -> list[float]:
    subprocess.run(cmd, check=True, capture_output=True)
    runs = []
    for _ in range(repeat):
        start = time.perf_counter()
        subprocess.run(cmd, check=True, capture_output=True)
        runs.append(time.perf_counter() - start)
    return runs


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rigport", default=str(REPO / "target/release/rigport"))
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--corpus", default=str(REPO.parent / "shared/corpus"))
    args = parser.parse_args()
    folder = Path(args.corpus) / "3_acclaim_asf_amc/usc_csci520_mocapPlayer__shreyabhaumik"
    asf, amc = folder / "131-dance.asf", folder / "131_04-dance.amc"
    gltfpack = REPO / "tools/node_modules/gltfpack/cli.js"
    for needed in (Path(args.rigport), asf, amc, gltfpack):
        if not needed.exists():
            print(f"missing: {needed}", file=sys.stderr)
            return 2
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp)
        plain = out / "plain.glb"
        subprocess.run(
            [args.rigport, "convert", str(asf), "--motion", str(amc), "-o", str(plain)],
            check=True,
            capture_output=True,
        )
        pairs = [
            (
                "1 mm (core glTF)",
                [args.rigport, "convert", str(plain), "-o", str(out / "r.glb"), "--reduce-tolerance"],
                out / "r.glb",
                ["node", str(gltfpack), "-i", str(plain), "-o", str(out / "g.glb")],
                out / "g.glb",
            ),
            (
                "1 mm meshopt / -cc",
                [args.rigport, "convert", str(plain), "-o", str(out / "m.glb"), "--compress", "meshopt"],
                out / "m.glb",
                ["node", str(gltfpack), "-i", str(plain), "-o", str(out / "gc.glb"), "-cc"],
                out / "gc.glb",
            ),
        ]
        print(f"input: {plain.stat().st_size} bytes ({asf.name} + {amc.name}), {args.repeat} runs each")
        print(f"{'':20} {'rigport s (min)':>16} {'gltfpack s (min)':>17} {'ratio':>6} {'rigport B':>10} {'gltfpack B':>11}")
        for label, ours, our_out, theirs, their_out in pairs:
            a, b = timed(ours, args.repeat), timed(theirs, args.repeat)
            ma, mb = statistics.median(a), statistics.median(b)
            print(
                f"{label:20} {ma:>8.3f} ({min(a):.3f}) {mb:>9.3f} ({min(b):.3f}) {ma / mb:>6.2f}"
                f" {our_out.stat().st_size:>10} {their_out.stat().st_size:>11}"
            )
    return 0


if __name__ == "__main__":
    sys.exit(main())

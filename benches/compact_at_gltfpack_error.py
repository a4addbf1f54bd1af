#!/usr/bin/env python3
"""Compact clips against gltfpack at gltfpack's own error, and how much of each clip moves
faster than 30 keys a second can follow.

Usage (from the repo root, after `cargo build --release` and `bash tools/setup.sh`):
  python3 benches/compact_at_gltfpack_error.py [--rigport target/release/rigport]
      [--corpus ../shared/corpus]

For every corpus ASF/AMC and BVH clip (as tests/cli/compact.rs converts them: BVH with
`--input-units auto`):
  1. `rigport convert` writes the plain glb; gltfpack (npm, tools/node_modules) writes its
     default output from it (resample to 30 Hz, quantize);
  2. three.js measures gltfpack's largest joint and 3 cm point error against the plain glb
     (tools/three_joints.mjs, at every source frame);
  3. rigport writes `--reduce-tolerance E` with E that error (in the rig's unit), and
     three.js measures its error the same way;
  4. from `rigport eval` of the plain glb, the largest distance of a joint's model-space
     path from that path low-passed at 15 Hz (the Nyquist rate of gltfpack's 30 keys a
     second; linear trend removed, a tenth of a second left out at each end), and the share
     of (frame, joint) pairs where it passes 1 mm: motion that no representation with 30
     keys a second can hold within 1 mm ("-" for clips sampled at 30 Hz).
Prints one table row per clip. Exit status: 0, or 2 when an input or a tool is missing.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent


def clips(corpus: Path) -> list[tuple[str, list[str]]]:
    found = []
    acclaim = sorted((corpus / "3_acclaim_asf_amc").rglob("*.amc"))
    for amc in acclaim:
        subject = amc.stem.split("_")[0]
        asf = next(p for p in amc.parent.glob("*.asf") if p.stem.split("-")[0] == subject)
        found.append((amc.stem, [str(asf), "--motion", str(amc)]))
    for bvh in sorted((corpus / "4_bvh").rglob("*.bvh")):
        found.append((bvh.stem, [str(bvh), "--input-units", "auto"]))
    return found


def three_error(reference: Path, candidate: Path) -> float:
    out = subprocess.run(
        ["node", str(REPO / "tools/three_joints.mjs"), str(reference), str(candidate)],
        check=True, capture_output=True, text=True)
    return json.loads(out.stdout)["max"]


def high_band(rigport: str, glb: Path, npz: Path) -> tuple[float, float] | None:
    """Largest distance (m) of a joint's path from its 15 Hz low-pass, and the share of
    (frame, joint) pairs over 1 mm; `None` for a clip sampled at 30 Hz or less (nothing is
    above 15 Hz)."""
    subprocess.run([rigport, "eval", "-q", str(glb), "--out", str(npz)], check=True)
    dump = np.load(npz)
    paths = dump["joint_world"][:, :, :3, 3].astype(np.float64)
    frames = len(paths)
    dt = float(np.median(np.diff(dump["times"])))
    if 1.0 / dt <= 30.5:
        return None
    ramp = np.arange(frames)[:, None, None] / max(frames - 1, 1)
    detrended = paths - (paths[:1] + (paths[-1:] - paths[:1]) * ramp)
    mirrored = np.concatenate([-detrended[::-1], detrended, -detrended[::-1]])
    spectrum = np.fft.rfft(mirrored, axis=0)
    spectrum[np.fft.rfftfreq(len(mirrored), dt) > 15.0] = 0
    low = np.fft.irfft(spectrum, n=len(mirrored), axis=0)[frames:2 * frames]
    edge = max(1, int(round(0.1 / dt)))
    off = np.linalg.norm(detrended - low, axis=2)[edge:-edge]
    return float(off.max()), float((off > 1e-3).mean())


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rigport", default=str(REPO / "target/release/rigport"))
    parser.add_argument("--corpus", default=str(REPO.parent / "shared/corpus"))
    args = parser.parse_args()
    gltfpack = REPO / "tools/node_modules/gltfpack/cli.js"
    corpus = Path(args.corpus)
    if not gltfpack.exists() or not Path(args.rigport).exists() or not corpus.is_dir():
        print("needs gltfpack (bash tools/setup.sh), the rigport binary and the corpus",
              file=sys.stderr)
        return 2
    print("| clip | gltfpack bytes | gltfpack error | rigport bytes at that bound | rigport error "
          "| above 15 Hz: largest | (frame, joint) pairs over 1 mm |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    with tempfile.TemporaryDirectory() as tmp:
        for name, inputs in clips(corpus):
            plain, packed = Path(tmp, f"{name}.glb"), Path(tmp, f"{name}_gp.glb")
            ours = Path(tmp, f"{name}_r.glb")
            run = [args.rigport, "convert", "-q", *inputs]
            subprocess.run([*run, "-o", str(plain)], check=True)
            subprocess.run(["node", str(gltfpack), "-i", str(plain), "-o", str(packed)],
                           check=True, capture_output=True)
            gp_error = three_error(plain, packed)
            report = json.loads(subprocess.run(
                [*run, "-o", str(ours), "--reduce-tolerance", "--json"],
                check=True, capture_output=True, text=True).stdout)
            tolerance = gp_error / report["meters_per_unit"]
            subprocess.run([*run, "-o", str(ours), f"--reduce-tolerance={tolerance}"],
                           check=True)
            our_error = three_error(plain, ours)
            band = high_band(args.rigport, plain, Path(tmp, f"{name}.npz"))
            above = ("| - | - |" if band is None
                     else f"| {band[0] * 1000:.1f} mm | {band[1] * 100:.0f}% |")
            print(f"| {name} | {packed.stat().st_size:,} | {gp_error * 1000:.1f} mm "
                  f"| {ours.stat().st_size:,} | {our_error * 1000:.1f} mm {above}",
                  flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())

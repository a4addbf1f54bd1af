#!/usr/bin/env python3
"""Peer comparison robust to machine drift: rigport vs Assimp, runs interleaved.

    python3 benches/compare_assimp_interleaved.py [--case model1|bvh|asf|fbx] [--pairs N]
        [--bin target/dist/rigport] [--fbx FILE.fbx] [--assimp PATH]

hyperfine (benches/compare_assimp.sh) times all runs of one command, then all of the other;
on a shared VM the load drifts between the two blocks and the ratio swings (0.24x to 0.46x
seen in one hour). Here each pair runs rigport and Assimp back to back, alternating which
goes first, so both see the same machine. Prints both medians, the ratio of the medians and
the median of the per-pair ratios, as a markdown table row for BENCHMARKS.md.

Cases (inputs under ../shared/corpus):
  model1  human_model1 (Model1.obj, skeleton.out, attachment.out) -> .glb; Assimp reads the OBJ.
  bvh     the largest corpus BVH (Bandai Namco kick, 443 KB) -> .glb; Assimp reads the BVH.
  asf     131-dance.asf + 131_04-dance.amc -> .glb; Assimp has no ASF/AMC reader, so its
          column times the BVH case instead and only rigport's median is meaningful.
  fbx     --fbx FILE (issue 29: a Mixamo-size FBX, e.g. the one `tools/blender/make_fbx.py DIR
          mixamo_bench` writes) -> .glb; Assimp reads the same FBX.
--assimp picks the Assimp binary (default: `assimp` on PATH).
Needs: the dist build of rigport (cargo build --profile dist) and `assimp` (Debian assimp-utils). Exit 2 if missing.
"""
import argparse
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CORPUS = os.path.join(ROOT, "../shared/corpus")
MODEL = os.path.join(CORPUS, "1_pinocchio/berkeley_cs184__severus-snape_mobius-ants/human_model1")
KICK = os.path.join(CORPUS, "4_bvh/bandai_namco_ds1/dataset-1_kick_normal_001.bvh")
DANCE = os.path.join(CORPUS, "3_acclaim_asf_amc/usc_csci520_mocapPlayer__shreyabhaumik")


def case_files(case: str, fbx: str | None):
    """(label, rigport inputs, assimp input) for a case."""
    if case == "fbx":
        if fbx is None:
            raise SystemExit("--case fbx needs --fbx FILE")
        size = os.path.getsize(fbx) / 1e6 if os.path.exists(fbx) else 0.0
        return f"{os.path.basename(fbx)} ({size:.1f} MB)", [fbx], fbx
    if case == "model1":
        files = [os.path.join(MODEL, f) for f in ("Model1.obj", "skeleton.out", "attachment.out")]
        return "Model1", files, files[0]
    if case == "bvh":
        return "kick BVH (443 KB)", [KICK], KICK
    if case == "asf":
        files = [os.path.join(DANCE, "131-dance.asf"), os.path.join(DANCE, "131_04-dance.amc")]
        return "131_04-dance ASF/AMC (assimp: kick BVH)", files, KICK
    raise SystemExit(f"unknown case {case}")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--pairs", type=int, default=120)
    ap.add_argument("--case", default="model1", choices=["model1", "bvh", "asf", "fbx"])
    ap.add_argument("--bin", default=os.path.join(ROOT, "target/dist/rigport"))
    ap.add_argument("--fbx", help="the FBX of --case fbx")
    ap.add_argument("--assimp", default="assimp", help="the Assimp command (default: on PATH)")
    args = ap.parse_args()
    if not os.path.exists(args.bin):
        print(f"compare: {args.bin} missing: run cargo build --profile dist", file=sys.stderr)
        return 2
    if shutil.which(args.assimp) is None:
        print("compare: assimp missing: apt-get install -y assimp-utils", file=sys.stderr)
        return 2
    label, files, assimp_in = case_files(args.case, args.fbx)
    if not all(os.path.exists(f) for f in files + [assimp_in]):
        print(f"compare: corpus inputs missing: {files}", file=sys.stderr)
        return 2
    with tempfile.TemporaryDirectory() as out:
        ours = [args.bin, "convert", "-q", *files, "-o", os.path.join(out, "rigport.glb")]
        theirs = [args.assimp, "export", assimp_in, os.path.join(out, "assimp.glb"), "-fglb2"]
        for _ in range(5):  # warm-up
            subprocess.run(ours, capture_output=True, check=True)
            subprocess.run(theirs, capture_output=True, check=True)
        t_ours, t_theirs = [], []
        for i in range(args.pairs):
            order = [(ours, t_ours), (theirs, t_theirs)]
            for cmd, acc in order if i % 2 == 0 else reversed(order):
                t = time.perf_counter()
                subprocess.run(cmd, capture_output=True, check=True)
                acc.append(time.perf_counter() - t)
    mo, mt = statistics.median(t_ours) * 1e3, statistics.median(t_theirs) * 1e3
    pair = statistics.median(a / b for a, b in zip(t_ours, t_theirs))
    load = os.getloadavg()[0]
    print(f"{args.pairs} interleaved pairs, load {load:.2f}")
    print("| input | rigport convert (median) | assimp export -fglb2 (median) | ratio of medians | median pairwise ratio |")
    print("| --- | ---: | ---: | ---: | ---: |")
    print(f"| {label} | {mo:.1f} ms | {mt:.1f} ms | {mo / mt:.2f}x | {pair:.2f}x |")
    return 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/env python3
"""The Python bindings' overhead (issue 32): `rigport.open(...).evaluate(fps=25)` against
`rigport eval`'s in-process time (`examples/eval_in_process.rs`: import, sampling,
skinning, the `.npz` written), and against the same work in Rust (`--in-memory`: the
import and `rigport_pipeline::eval::evaluate`, no `.npz`: the bindings' own cost) on the corpus' largest Pinocchio rig, `human_model1`
(13,336 vertices, 18 joints), keyed with the 100-frame "arms" clip (3.96 s at 25 fps;
benches/render_gif.sh's clip) by `rigport animate`.

    cargo build --release --bin rigport --example eval_in_process
    tools/.venv/bin/maturin build --release -m crates/python/Cargo.toml --out /tmp/wheel
    tools/.venv/bin/pip install --force-reinstall --no-deps /tmp/wheel/rigport-*.whl
    tools/.venv/bin/python benches/python_evaluate.py [--rounds 6] [--runs 5]

Blocks of runs alternate between the two (this shared VM's speed drifts within minutes);
each side warms up once per block. Prints each side's median and their ratio.
"""

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import rigport

ROOT = Path(__file__).resolve().parent.parent
MODEL = ROOT.parent / "shared/corpus/1_pinocchio/berkeley_cs184__severus-snape_mobius-ants/human_model1"
KEYS = {
    "name": "arms",
    "fps": 25,
    "keys": [
        {"time": 0, "pose": {}},
        {"time": 1.98, "pose": {"bone_13": {"euler_deg": [0, 0, -60]}, "bone_14": {"euler_deg": [0, 0, -30]},
                                "bone_16": {"euler_deg": [0, 0, 60]}, "bone_17": {"euler_deg": [0, 0, 30]}}},
        {"time": 3.96, "pose": {}},
    ],
}


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--rounds", type=int, default=6)
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--target", default=str(ROOT / "target" / "release"))
    args = parser.parse_args()
    target = Path(args.target)
    work = Path(tempfile.mkdtemp())
    (work / "arms.keys.json").write_text(json.dumps(KEYS))
    glb = work / "arms.glb"
    subprocess.run(
        [target / "rigport", "animate", "-q", MODEL / "Model1.obj", MODEL / "skeleton.out",
         MODEL / "attachment.out", "--keys", work / "arms.keys.json", "-o", glb],
        check=True,
    )
    asset = rigport.open(glb)
    frames = asset.evaluate(fps=25)
    print(f"arms.glb: {frames.positions.shape[0]} frames x {frames.positions.shape[1]} vertices, "
          f"{len(frames.joint_names)} joints")
    ours, theirs, same = [], [], []

    def rust(*flags):
        done = subprocess.run(
            [target / "examples" / "eval_in_process", "--fps", "25", "--runs", str(args.runs), *flags, glb],
            check=True, capture_output=True, text=True,
        )
        line = done.stdout.strip()
        return [float(s) for s in line[line.index("(") + 1:-1].split()]

    for _ in range(args.rounds):
        theirs += rust()
        same += rust("--in-memory")
        rigport.open(glb).evaluate(fps=25)  # warm-up
        for _ in range(args.runs):
            start = time.perf_counter()
            rigport.open(glb).evaluate(fps=25)
            ours.append(time.perf_counter() - start)
    py, rs, rm = statistics.median(ours), statistics.median(theirs), statistics.median(same)
    print(f"rigport eval in-process (import + evaluate + .npz): median {rs * 1000:.1f} ms of {len(theirs)} runs")
    print(f"the same in Rust, arrays kept (import + evaluate):   median {rm * 1000:.1f} ms of {len(same)} runs")
    print(f"rigport.open(...).evaluate(fps=25) in Python:       median {py * 1000:.1f} ms of {len(ours)} runs")
    print(f"ratio Python / eval: {py / rs:.3f}; Python / the same in Rust: {py / rm:.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

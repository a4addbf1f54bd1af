"""Run `rigport batch` shards as Ray tasks (docs/scale.md; issue 21's engine test).

    tools/.venv-ray/bin/python tools/ray_shards.py --rigport BIN --manifest M.jsonl \
        --out OUT_DIR --shards 3 [--data]

Starts Ray on this machine (local mode: `ray.init()` without an address; pass
--address auto to join a running cluster), runs one task per shard, each calling
`rigport batch M --shard I/N -o OUT --resume`, prints every shard's exit code and
exits with the largest (0 all done, 1 bad inputs, 3 an output could not be written).
With --data the same shards run through Ray Data (`ray.data.range(N).map(...)`).
Merge the reports afterwards with `rigport batch-report OUT/.rigport-batch/report-*-of-N.jsonl`.
"""

import argparse
import subprocess

import ray


def run_shard(rigport, manifest, out, index, count, jobs):
    cmd = [rigport, "batch", manifest, "-o", out, "--shard", f"{index}/{count}",
           "--resume", "--jobs", str(jobs), "--quiet"]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    return {"shard": index, "code": proc.returncode, "stderr": proc.stderr[-2000:]}


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--rigport", required=True)
    p.add_argument("--manifest", required=True)
    p.add_argument("--out", required=True)
    p.add_argument("--shards", type=int, default=3)
    p.add_argument("--jobs", type=int, default=1, help="threads per shard")
    p.add_argument("--address", default=None, help="a Ray cluster (default: local)")
    p.add_argument("--data", action="store_true", help="use Ray Data instead of tasks")
    a = p.parse_args()
    # A loaded machine can make the local Ray's start time out: try three times.
    for attempt in range(3):
        try:
            ray.init(address=a.address, include_dashboard=False, log_to_driver=False)
            break
        except Exception:
            ray.shutdown()
            if attempt == 2:
                raise
    if a.data:
        from ray import data as ray_data  # needs `pip install 'ray[data]'`

        rows = ray_data.range(a.shards).map(
            lambda row: run_shard(a.rigport, a.manifest, a.out, row["id"], a.shards, a.jobs),
            num_cpus=a.jobs,
        ).take_all()
    else:
        task = ray.remote(num_cpus=a.jobs)(run_shard)
        rows = ray.get([task.remote(a.rigport, a.manifest, a.out, i, a.shards, a.jobs)
                        for i in range(a.shards)])
    worst = 0
    for row in sorted(rows, key=lambda r: r["shard"]):
        print(f"shard {row['shard']}/{a.shards}: exit {row['code']}")
        if row["code"] not in (0, 1):
            print(row["stderr"])
        worst = max(worst, row["code"])
    ray.shutdown()
    raise SystemExit(worst)


if __name__ == "__main__":
    try:
        main()
    except Exception:  # Ray's own failure, told apart from rigport's exit codes 0-3
        import traceback

        traceback.print_exc()
        raise SystemExit(70)

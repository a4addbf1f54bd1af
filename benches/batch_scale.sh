#!/usr/bin/env bash
# Scale benchmark of `rigport batch` (issue 21): a synthetic manifest of N motion clips
# (default 2,500) made from the corpus' BVH and ASF/AMC clips with retime/trim/resample
# variations, run with --jobs 1 and --jobs 2: wall time, items per second, parallel
# efficiency, peak RSS (GNU time -v); then a --resume run (every item skipped).
#
#   RIGPORT_BIN=target/release/rigport bash benches/batch_scale.sh [N]
#
# Peak memory is also measured for N/5 items, to show it does not grow with the manifest.
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${RIGPORT_BIN:-target/release/rigport}
n=${1:-2500}
corpus=${RIGPORT_CORPUS:-../shared/corpus}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

make_manifest() { # count -> manifest on stdout
  python3 - "$corpus" "$1" <<'PY'
import json, os, sys
corpus, n = sys.argv[1], int(sys.argv[2])
c = lambda p: os.path.abspath(os.path.join(corpus, p))
clips = [
    [c("4_bvh/bandai_namco_ds1/dataset-1_dash_normal_001.bvh")],
    [c("4_bvh/bandai_namco_ds1/dataset-1_walk_normal_002.bvh")],
    [c("4_bvh/bandai_namco_ds1/dataset-1_kick_normal_001.bvh")],
    [c("4_bvh/cmu_cgspeed__nobuyuki83_delfem2/walk.bvh")],
    [c("3_acclaim_asf_amc/usc_csci520_mocapPlayer__shreyabhaumik/07-walk.asf"),
     c("3_acclaim_asf_amc/usc_csci520_mocapPlayer__shreyabhaumik/07_05-walk.amc")],
    [c("3_acclaim_asf_amc/usc_csci520_mocapPlayer__shreyabhaumik/09-run.asf"),
     c("3_acclaim_asf_amc/usc_csci520_mocapPlayer__shreyabhaumik/09_06-run.amc")],
]
for k in range(n):
    inputs = clips[k % len(clips)]
    op = (k // len(clips)) % 4
    if op == 0:
        command, options = "retime", ["--speed", str(0.5 + 0.25 * (k % 7))]
    elif op == 1:
        command, options = "retime", ["--trim", f"0..{0.4 + 0.1 * (k % 5):.1f}"]
    elif op == 2:
        command, options = "retime", ["--fps", str(24 + 6 * (k % 4))]
    else:
        command, options = "convert", ["--no-bone-mesh"]
    print(json.dumps({"id": f"clip{k:05d}", "command": command, "inputs": inputs,
                      "options": options, "outputs": [f"clips/{k // 500:02d}/{k:05d}.glb"]}))
PY
}

run() { # label manifest out args...
  local label=$1 manifest=$2 out=$3; shift 3
  /usr/bin/time -v "$bin" batch --quiet "$manifest" -o "$out" "$@" 2> "$work/time.txt" || {
    echo "$label: rigport batch failed:"; cat "$work/time.txt"; exit 1; }
  local wall rss items cpu
  wall=$(awk -F': ' '/Elapsed \(wall clock\)/ {n=split($2,t,":"); s=0; for(i=1;i<=n;i++) s=s*60+t[i]; print s}' "$work/time.txt")
  rss=$(awk -F': ' '/Maximum resident set size/ {printf "%.0f", $2/1024}' "$work/time.txt")
  cpu=$(awk -F': ' '/User time|System time/ {s+=$2} END {print s}' "$work/time.txt")
  items=$(wc -l < "$manifest")
  printf '| %s | %d | %.2f s | %.1f | %.2f s | %.1f ms | %s MiB |\n' "$label" "$items" "$wall" \
    "$(echo "$items / $wall" | bc -l)" "$cpu" "$(echo "1000 * $cpu / $items" | bc -l)" "$rss"
}

make_manifest "$n" > "$work/m.jsonl"
make_manifest $((n / 5)) > "$work/small.jsonl"
echo "rigport: $("$bin" --version); $(nproc) cores; load $(cut -d' ' -f1-3 /proc/loadavg)"
echo
echo "| run | items | wall | items/s | CPU (user+sys) | CPU per item | peak RSS |"
echo "| --- | ---: | ---: | ---: | ---: | ---: | ---: |"
run "--jobs 1" "$work/m.jsonl" "$work/out1" --jobs 1
run "--jobs 2" "$work/m.jsonl" "$work/out2" --jobs 2
run "--jobs 2 --resume (all skipped)" "$work/m.jsonl" "$work/out2" --jobs 2 --resume
run "--jobs 2, N/5 items" "$work/small.jsonl" "$work/out3" --jobs 2
cmp -s <(cd "$work/out1" && find clips -type f | sort | xargs cat | md5sum) \
       <(cd "$work/out2" && find clips -type f | sort | xargs cat | md5sum) \
  && echo && echo "outputs of --jobs 1 and --jobs 2 are byte-identical"

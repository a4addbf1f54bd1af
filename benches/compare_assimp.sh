#!/usr/bin/env bash
# Peer comparison for BENCHMARKS.md: rigport vs Assimp, OBJ -> GLB, timed by
# hyperfine in ONE run (same machine state for both commands).
#
#   bash benches/compare_assimp.sh [--assimp-only] [--runs N] [--warmup N]
#
#   rigport convert --mesh Model1.obj --skeleton skeleton.out --attachment attachment.out -o x.glb
#   assimp export Model1.obj y.glb -fglb2
#
# Input: the Pinocchio "human_model1" rig from the shared corpus,
#   ../shared/corpus/1_pinocchio/berkeley_cs184__severus-snape_mobius-ants/human_model1/
# (override the folder with RIGPORT_BENCH_MODEL_DIR; RIGPORT_BENCH_BIN=path
# times that rigport binary instead of building target/dist/rigport).
#
# Installs nothing. Needs: cargo, python3 (reads hyperfine's JSON), and
#   assimp    Debian package assimp-utils
#   hyperfine Debian package hyperfine
#   -> apt-get install -y assimp-utils hyperfine
#
# Prints both medians and the ratio rigport/assimp as a markdown table row for
# BENCHMARKS.md; hyperfine's JSON is kept in <target-dir>/bench/compare_assimp.json.
# Note that Assimp writes the mesh only: rigport also writes the skeleton and
# the skin (joints/weights), so it does more work per file.
# --assimp-only times Assimp alone (for trying the script before rigport's
# `convert` exists). Exit: 0 ok, 1 a command failed, 2 missing tool or input.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"

RUNS=20
WARMUP=3
ASSIMP_ONLY=0
while (( $# )); do
  case "$1" in
    --assimp-only) ASSIMP_ONLY=1 ;;
    --runs) RUNS="${2:?--runs needs a number}"; shift ;;
    --warmup) WARMUP="${2:?--warmup needs a number}"; shift ;;
    -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "${BASH_SOURCE[0]}"; exit 0 ;;
    *) echo "compare_assimp: unknown argument: $1 (try --help)" >&2; exit 2 ;;
  esac
  shift
done
[[ "$RUNS" =~ ^[1-9][0-9]*$ && "$WARMUP" =~ ^[0-9]+$ ]] \
  || { echo "compare_assimp: --runs must be >= 1 and --warmup >= 0" >&2; exit 2; }

say() { printf '[compare_assimp] %s\n' "$*" >&2; }

# ------------------------------------------------------------------ tools
missing=()
command -v hyperfine >/dev/null 2>&1 || missing+=("hyperfine (Debian package hyperfine)")
command -v assimp >/dev/null 2>&1 || missing+=("assimp (Debian package assimp-utils)")
command -v python3 >/dev/null 2>&1 || missing+=("python3 (Debian package python3)")
if (( ${#missing[@]} )); then
  say "missing: ${missing[*]}"
  sudo=""; if (( EUID != 0 )); then sudo="sudo "; fi
  say "install them with: ${sudo}apt-get update && ${sudo}apt-get install -y assimp-utils hyperfine"
  exit 2
fi
(( ASSIMP_ONLY )) || [[ -n "${RIGPORT_BENCH_BIN:-}" ]] || command -v cargo >/dev/null 2>&1 \
  || { say "cargo not found (needed to build rigport)"; exit 2; }

# ------------------------------------------------------------------ input
MODEL_DIR="${RIGPORT_BENCH_MODEL_DIR:-$ROOT/../shared/corpus/1_pinocchio/berkeley_cs184__severus-snape_mobius-ants/human_model1}"
MESH="$MODEL_DIR/Model1.obj"
SKEL="$MODEL_DIR/skeleton.out"
ATTACH="$MODEL_DIR/attachment.out"
for f in "$MESH" "$SKEL" "$ATTACH"; do
  [[ -f "$f" ]] || { say "input not found: $f (shared corpus beside the repo, or set RIGPORT_BENCH_MODEL_DIR)"; exit 2; }
done
MODEL_DIR="$(cd "$MODEL_DIR" && pwd)"; MESH="$MODEL_DIR/Model1.obj"; SKEL="$MODEL_DIR/skeleton.out"; ATTACH="$MODEL_DIR/attachment.out"
VERTS="$(grep -c '^v ' "$MESH" || true)"
FACES="$(grep -c '^f ' "$MESH" || true)"
BONES="$(grep -c . "$SKEL" || true)"

# ------------------------------------------------------------------ build
TARGET_DIR="${CARGO_TARGET_DIR:-$ROOT/target}"
RIGPORT="$TARGET_DIR/dist/rigport"
if [[ -n "${RIGPORT_BENCH_BIN:-}" ]]; then
  RIGPORT="$(cd "$(dirname "$RIGPORT_BENCH_BIN")" && pwd)/$(basename "$RIGPORT_BENCH_BIN")"
  [[ -x "$RIGPORT" ]] || { say "RIGPORT_BENCH_BIN=$RIGPORT_BENCH_BIN is not an executable"; exit 2; }
  say "using RIGPORT_BENCH_BIN=$RIGPORT (no cargo build)"
elif (( ! ASSIMP_ONLY )); then
  say "cargo build --profile dist --bin rigport"
  cargo build --profile dist --bin rigport >&2
  [[ -x "$RIGPORT" ]] || { say "built, but no binary at $RIGPORT (CARGO_TARGET_DIR?)"; exit 2; }
fi

OUT="$(mktemp -d "${TMPDIR:-/tmp}/rigport-bench.XXXXXX")"
trap 'rm -rf "$OUT"' EXIT
mkdir -p "$TARGET_DIR/bench"
JSON="$TARGET_DIR/bench/compare_assimp.json"

q() { printf '%q' "$1"; }
CMD_RIGPORT="$(q "$RIGPORT") convert --mesh $(q "$MESH") --skeleton $(q "$SKEL") --attachment $(q "$ATTACH") -o $(q "$OUT/x.glb")"
# -fglb2: glTF 2.0 binary (without it, some Assimp versions pick glTF 1.0 for .glb).
CMD_ASSIMP="assimp export $(q "$MESH") $(q "$OUT/y.glb") -fglb2"

# ------------------------------------------------------------------ sanity run
# Each command once, untimed: it must succeed and write a non-empty file, or the
# timings would measure an error path.
check_once() { # name cmd output
  local name=$1 cmd=$2 out=$3 log="$OUT/$1.log"
  rm -f "$out"
  if ! bash -c "$cmd" >"$log" 2>&1; then
    say "$name failed: $cmd"; sed 's/^/    /' "$log" | tail -n 20 >&2; return 1
  fi
  if [[ ! -s "$out" ]]; then
    say "$name exited 0 but wrote no $out"; sed 's/^/    /' "$log" | tail -n 20 >&2; return 1
  fi
  say "$name ok: $(wc -c <"$out") bytes"
  # Informational: what the Khronos validator thinks of each output.
  if [[ -f "$ROOT/tools/node_modules/gltf-validator/package.json" ]] && command -v node >/dev/null 2>&1; then
    say "$name output: $(node "$ROOT/tools/validate_gltf.mjs" "$out" 2>&1 | head -n 1 | sed 's/^[^:]*: //') (glTF-Validator)"
  fi
}
check_once assimp "$CMD_ASSIMP" "$OUT/y.glb" || exit 1
if (( ! ASSIMP_ONLY )); then
  check_once rigport "$CMD_RIGPORT" "$OUT/x.glb" || {
    say "rigport convert failed: is the 'convert' subcommand there yet? (--assimp-only times Assimp alone)"
    exit 1
  }
fi

# ------------------------------------------------------------------ timing
# Wall-clock medians are only comparable on a quiet machine: say so when it isn't.
load1="$(cut -d' ' -f1 /proc/loadavg 2>/dev/null || echo 0)"
if awk -v l="$load1" -v c="$(nproc)" 'BEGIN { exit !(l > c / 2) }'; then
  say "WARNING: load average $load1 on $(nproc) cores: other work is running, wall times will be inflated and noisy"
fi
HF_ARGS=(--warmup "$WARMUP" --runs "$RUNS" --export-json "$JSON" --style basic)
# No intermediate shell: its start-up would be most of a short run.
hf_help="$(hyperfine --help 2>/dev/null || true)"
if [[ "$hf_help" == *"--shell=none"* ]]; then HF_ARGS+=(--shell=none); fi
if (( ASSIMP_ONLY )); then
  hyperfine "${HF_ARGS[@]}" --command-name assimp "$CMD_ASSIMP" >&2
else
  hyperfine "${HF_ARGS[@]}" --command-name rigport "$CMD_RIGPORT" --command-name assimp "$CMD_ASSIMP" >&2
fi

ASSIMP_VERSION="$(dpkg-query -W -f='${Version}' assimp-utils 2>/dev/null || true)"
[[ -n "$ASSIMP_VERSION" ]] || ASSIMP_VERSION="$(assimp version 2>/dev/null | grep -Eo '[Vv]ersion [0-9]+\.[0-9]+(\.[0-9]+)?' | head -n 1 | awk '{print $2}' || true)"
HF_VERSION="$(hyperfine --version | awk '{print $2}')"
if RIGPORT_REV="$(git rev-parse --short HEAD 2>/dev/null)"; then
  git diff --quiet HEAD -- 2>/dev/null || RIGPORT_REV="$RIGPORT_REV+dirty"
else
  RIGPORT_REV="(not a git checkout)"
fi
if (( ASSIMP_ONLY )); then RIGPORT_REV="(not run)"; fi

python3 - "$JSON" "$ASSIMP_ONLY" "$VERTS" "$FACES" "$BONES" "${ASSIMP_VERSION:-?}" "$HF_VERSION" \
  "$RIGPORT_REV" "$(nproc)" "$RUNS" "$WARMUP" "$load1" <<'PY'
import json, sys
path, assimp_only, verts, faces, bones, av, hv, rev, cores, runs, warmup, load = sys.argv[1:]
res = {r["command"]: r for r in json.load(open(path))["results"]}
def fmt(r):
    return f"{r['median'] * 1000:.1f} ms (mean {r['mean'] * 1000:.1f} ± {r['stddev'] * 1000:.1f})"
a = res["assimp"]
def cpu(r):
    return f"{(r['user'] + r['system']) * 1000:.1f} ms"
label = f"Model1 (Pinocchio human_model1: {verts} verts, {faces} faces, {bones} joints)"
print(f"\nhyperfine {hv}, {runs} runs + {warmup} warm-up, {cores} cores, load {load}; "
      f"assimp {av}; rigport {rev}")
print("mean CPU (user+sys): " + ", ".join(f"{n} {cpu(r)}" for n, r in res.items()) + "\n")
print("| input | rigport convert (median) | assimp export -fglb2 (median) | rigport / assimp |")
print("| --- | ---: | ---: | ---: |")
if assimp_only == "1":
    print(f"| {label} | (not run) | {fmt(a)} | - |")
else:
    r = res["rigport"]
    print(f"| {label} | {fmt(r)} | {fmt(a)} | {r['median'] / a['median']:.2f}x |")
PY
say "hyperfine JSON: $JSON"

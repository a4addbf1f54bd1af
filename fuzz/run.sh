#!/usr/bin/env bash
# Runs the coverage-guided fuzz targets (cargo fuzz + libFuzzer; see fuzz/README.md).
#
#   bash fuzz/run.sh [--runs N | --seconds S] [TARGET...]     (default: --seconds 60, all)
#
# Needs cargo-fuzz (`cargo install cargo-fuzz`) and a nightly toolchain (`cargo +nightly`);
# without them it says so and exits 0 (the test command then only replays the kept corpus,
# which fuzz/tests/regressions.rs does on stable). Each target runs with a 10 s per-input
# timeout and a 2 GB RSS limit; new coverage goes to fuzz/corpus/TARGET, crashes to
# fuzz/artifacts/TARGET. One summary line per target: runs, seconds, coverage.
# Exit status: 0 when no target crashed, hung or ran out of memory; 1 otherwise.
set -uo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"
limit=(-max_total_time=60)
targets=()
while [[ $# -gt 0 ]]; do
  case "$1" in
    --runs) limit=(-runs="$2"); shift 2 ;;
    --seconds) limit=(-max_total_time="$2"); shift 2 ;;
    -h|--help) sed -n '2,12p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) targets+=("$1"); shift ;;
  esac
done
if ! cargo fuzz --version >/dev/null 2>&1 || ! cargo +nightly --version >/dev/null 2>&1; then
  echo "fuzz: cargo-fuzz or the nightly toolchain is missing: no fuzzing run (cargo install cargo-fuzz)"
  exit 0
fi
if [[ ${#targets[@]} -eq 0 ]]; then
  mapfile -t targets < <(cargo fuzz list --fuzz-dir fuzz 2>/dev/null)
fi
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$ROOT/target/fuzz}"
flags=(--fuzz-dir fuzz --features libfuzzer -s none -O)
cargo +nightly fuzz build "${flags[@]}" >/dev/null || { echo "fuzz: build failed"; exit 1; }
status=0
for t in "${targets[@]}"; do
  mkdir -p "fuzz/corpus/$t" "fuzz/artifacts/$t"
  log="$(mktemp)"
  cargo +nightly fuzz run "${flags[@]}" "$t" "fuzz/corpus/$t" -- \
    "${limit[@]}" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 >"$log" 2>&1
  rc=$?
  runs="$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' | tail -1)"
  secs="$(grep -o 'Done [0-9]* runs in [0-9]* second' "$log" | grep -o 'in [0-9]*' | grep -o '[0-9]*' | tail -1)"
  cov="$(grep -o 'cov: [0-9]* ft: [0-9]*' "$log" | tail -1)"
  if [[ $rc -eq 0 ]]; then
    echo "fuzz: $t: ${runs:-?} runs in ${secs:-?} s, $cov, no crash"
  else
    status=1
    echo "fuzz: $t: FAILED (exit $rc) after ${runs:-?} runs; see fuzz/artifacts/$t; log:"
    grep -E 'ERROR|panicked|SUMMARY|Test unit written' "$log" | head -20
  fi
  rm -f "$log"
done
exit $status

#!/usr/bin/env bash
# Runs the coverage-guided fuzz targets (cargo fuzz + libFuzzer; see fuzz/README.md).
#
#   bash fuzz/run.sh [--dev] [--runs N | --seconds S] [TARGET...]   (default: --seconds 60, all)
#
# --scratch leaves fuzz/corpus as it is (new inputs go to a temporary folder; the test
# command's run uses it so a test run leaves no untracked files).
# --dev builds the targets without optimization (about 1 min instead of 2.5 on 2 cores, and
# about a tenth of the executions per second): the test command's short smoke run uses it.
# Needs cargo-fuzz (`cargo install cargo-fuzz`) and a nightly toolchain (`cargo +nightly`);
# without them it says so and exits 0 (the test command then only replays the kept corpus,
# which fuzz/tests/regressions.rs does on stable). Each target runs with a 10 s per-input
# timeout and a 2 GB RSS limit; new coverage goes to fuzz/corpus/TARGET, crashes to
# fuzz/artifacts/TARGET. One summary line per target: runs, seconds, coverage.
# Exit status: 0 when no target crashed, hung or ran out of memory; 1 when one did, or when
# our fuzz code does not compile; 3 when cargo-fuzz itself cannot build here (a tool or
# toolchain problem, not a finding: its first error line is printed).
set -uo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"
limit=(-max_total_time=60)
opt=(-O)
scratch=0
targets=()
while [[ $# -gt 0 ]]; do
  case "$1" in
    --runs) limit=(-runs="$2"); shift 2 ;;
    --seconds) limit=(-max_total_time="$2"); shift 2 ;;
    --dev) opt=(--dev); shift ;;
    --scratch) scratch=1; shift ;;
    -h|--help) sed -n '2,18p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//'; exit 0 ;;
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
flags=(--fuzz-dir fuzz --features libfuzzer -s none "${opt[@]}")
build_log="$(mktemp)"
if ! cargo +nightly fuzz build "${flags[@]}" >"$build_log" 2>&1; then
  if grep -q 'could not compile `rigport' "$build_log"; then
    echo "fuzz: our fuzz code does not compile:"
    grep -E '^(error|warning: unused)' -A6 "$build_log" | head -40
    rm -f "$build_log"
    exit 1
  fi
  echo "fuzz: cargo fuzz cannot build here (not a finding); its output ends:"
  grep -vE '^ +[0-9]+: |^ +at ' "$build_log" | tail -12
  first="$(grep -m1 -iE 'error' "$build_log" | cut -c1-160)"
  echo "fuzz: first error line: ${first:-none}"
  rm -f "$build_log"
  exit 3
fi
rm -f "$build_log"
status=0
for t in "${targets[@]}"; do
  mkdir -p "fuzz/corpus/$t" "fuzz/artifacts/$t"
  log="$(mktemp)"
  dirs=("fuzz/corpus/$t")
  if [[ $scratch == 1 ]]; then new="$(mktemp -d)"; dirs=("$new" "fuzz/corpus/$t"); fi
  cargo +nightly fuzz run "${flags[@]}" "$t" "${dirs[@]}" -- \
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
  if [[ $scratch == 1 ]]; then rm -rf "$new"; fi
done
exit $status

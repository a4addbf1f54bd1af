#!/usr/bin/env bash
# rigport's one test command (README, CI):   bash tools/test.sh
#
#  1. tools/setup.sh         pinned glTF-Validator (npm) + USD/numpy venv
#  2. validator self-check   tools/validate_gltf.mjs on two tiny inline assets
#  3. Rust tests             cargo nextest run --workspace (cargo test if no nextest)
#  4. doctests               cargo test --doc --workspace (with nextest only)
#  5. USD smoke              tools/.venv/bin/python tools/usd_smoke.py
#  6. rustfmt                cargo fmt --all -- --check
#  7. clippy                 cargo clippy --workspace --all-targets --locked -- -D warnings
#  8. output hashes          tools/output_hashes.sh (the demo and every corpus conversion
#                            hash as recorded in tools/output_hashes.txt)
#  8b. Python wheel         crates/python built by maturin (the test profile, the shared target
#                            folder: the library crates step 8 compiled are reused), installed
#                            into tools/.venv (and tools/.venv-blender), then pytest
#                            crates/python/tests: the wheel against the CLI on the corpus, the
#                            abi3 file under a second Python minor version, and inside Blender
#  9. module circles         tools/module_cycles.py (no file of a crate imports one that
#                            imports it back); tools/one_concept.py (each concept the model
#                            defines -- skinning method, up axis, influence fit, output
#                            format, the clip lookup -- is defined once; libraries name no
#                            flag); cargo doc --workspace --no-deps with warnings denied
# 10. fuzz (short)           fuzz/run.sh --dev --seconds RIGPORT_FUZZ_SECONDS (default 5) per
#                            target, when cargo-fuzz and a nightly toolchain are installed
#                            (skipped otherwise, or when cargo fuzz itself cannot build, with
#                            its error in the summary; the kept fuzz corpus is always replayed
#                            by the Rust tests, fuzz/tests/regressions.rs). 5 s keeps CI
#                            under 15 min; RIGPORT_FUZZ_SECONDS=60 is the issue's minute.
# then a summary. Steps 3-8 all run even if one fails; the exit status is 0
# only if every step passed.
#
# The Rust tests see:
#   RIGPORT_GLTF_VALIDATOR  absolute path of tools/validate_gltf.mjs (run it with node)
#   RIGPORT_PYTHON          absolute path of tools/.venv/bin/python (usd-core, numpy, maturin, pytest; step 8b installs the rigport wheel into it)
# Tests that need the corpus (../shared/corpus beside the repo) skip when it is
# absent, unless CI is set.
#
# Environment knobs:
#   RIGPORT_TEST_PROFILE=dev|release   cargo profile for the tests (default: dev).
#     dev is the faster choice on 2 cores: a cold build of the workspace's tests
#     took 173 CPU-s in dev against 443 CPU-s in release (opt-level 3 for every
#     dependency), and dev keeps debug assertions and overflow checks on.
#   RIGPORT_NO_NEXTEST=1               use plain `cargo test` even if nextest is installed
#   RIGPORT_SECOND_PYTHON=PATH         the Python (not 3.11) the abi3 wheel must also import
#                                      under (default: the first of pyenv's 3.13, 3.12, 3.10,
#                                      3.9, then python3.13 ... python3.9 on PATH)
#   RIGPORT_NO_BLENDER=1               do not install bpy (tools/.venv-blender); the Blender
#                                      tests then skip (and fail when CI is set)
#   extra arguments are passed to the test runner, e.g. `bash tools/test.sh -E 'test(fk)'`
#   for nextest or `bash tools/test.sh fk` for cargo test.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"

T_START=$SECONDS
CURRENT_STEP=""
STEP_NAMES=()
STEP_STATUS=()
STEP_SECS=()
STEP_NOTES=()
TOTAL_PASSED=0
TOTAL_FAILED=0
TOTAL_SKIPPED=0
COUNTS_KNOWN=1
FAILED=0
WORK="$(mktemp -d "${TMPDIR:-/tmp}/rigport-test.XXXXXX")"

banner() { printf '\n==> %s\n' "$*"; }
disk_free() { df -h --output=avail "$ROOT" 2>/dev/null | tail -1 | tr -d ' ' || echo '?'; }
DISK_FREE_START="$(disk_free)"

record() { # name status secs note
  STEP_NAMES+=("$1"); STEP_STATUS+=("$2"); STEP_SECS+=("$3"); STEP_NOTES+=("${4:-}")
  if [[ "$2" != PASS ]]; then FAILED=1; fi
  CURRENT_STEP=""
}

summary() {
  local rc=$? i
  rm -rf "$WORK"
  # A step that aborted the script (set -e) has not been recorded yet.
  if (( rc != 0 )) && [[ -n "${CURRENT_STEP:-}" ]]; then
    record "$CURRENT_STEP" FAIL "-" "aborted, exit $rc"
  fi
  printf '\n==================== rigport test summary ====================\n'
  for i in "${!STEP_NAMES[@]}"; do
    printf '  %-4s  %-44s %6ss  %s\n' "${STEP_STATUS[$i]}" "${STEP_NAMES[$i]}" \
      "${STEP_SECS[$i]}" "${STEP_NOTES[$i]}"
  done
  if [[ -d "$ROOT/../shared/corpus" ]]; then
    printf '  corpus: %s (present)\n' "$(cd "$ROOT/../shared/corpus" && pwd)"
  else
    if [[ -n "${CI:-}" ]]; then
      printf '  corpus: ../shared/corpus absent, and CI is set: the corpus tests fail rather than skip\n'
    else
      printf '  corpus: ../shared/corpus absent: the corpus tests skip\n'
    fi
  fi
  printf '  RIGPORT_GLTF_VALIDATOR=%s\n' "${RIGPORT_GLTF_VALIDATOR:-}"
  # A full disk makes builds and conversions fail in ways that look like other problems.
  printf '  disk free: %s at the start, %s now\n' "${DISK_FREE_START:-?}" "$(disk_free)"
  printf '  RIGPORT_PYTHON=%s\n' "${RIGPORT_PYTHON:-}"
  if (( rc == 0 && FAILED == 0 )); then
    printf 'ALL PASSED in %ss\n' "$((SECONDS - T_START))"
  else
    printf 'FAILED in %ss (see the step marked FAIL above)\n' "$((SECONDS - T_START))"
  fi
  if (( COUNTS_KNOWN == 1 )) && (( TOTAL_PASSED + TOTAL_FAILED > 0 )); then
    printf 'tests: %d passed, %d failed, %d skipped\n' "$TOTAL_PASSED" "$TOTAL_FAILED" "$TOTAL_SKIPPED"
  fi
  if (( rc == 0 && FAILED != 0 )); then exit 1; fi
  exit "$rc"
}
trap summary EXIT

# Strip ANSI colour codes (the logs are parsed for test counts) into LOG.plain.
# (grep reads files, never `sed | grep -q`: with pipefail, grep -q quitting
# early would make the pipeline fail.)
plain() { sed -E 's/\x1b\[[0-9;]*[A-Za-z]//g' "$1" > "$1.plain"; }

# ---------------------------------------------------------------------- 1 setup
CURRENT_STEP="setup (tools/setup.sh)"
banner "$CURRENT_STEP"
t0=$SECONDS
# Blender (bpy, for tests/cli/fbx_blender.rs and fbx_mixamo.rs): installed unless
# RIGPORT_NO_BLENDER=1 (about 15 s for a 373 MB wheel; its tests add about 50 s).
if [[ "${RIGPORT_NO_BLENDER:-0}" == 1 ]]; then bash tools/setup.sh; else bash tools/setup.sh --blender; fi
record "$CURRENT_STEP" PASS "$((SECONDS - t0))"

export RIGPORT_GLTF_VALIDATOR="$ROOT/tools/validate_gltf.mjs"
export RIGPORT_PYTHON="$ROOT/tools/.venv/bin/python"
if [[ "${RIGPORT_NO_BLENDER:-0}" != 1 ]]; then
  export RIGPORT_BLENDER_PYTHON="$ROOT/tools/.venv-blender/bin/python"
fi

# ------------------------------------------------------- 2 validator self-check
# A minimal valid asset must pass (exit 0); one without asset.version must fail
# (exit 1). Catches a broken validator install before the Rust tests rely on it.
CURRENT_STEP="validator self-check"
banner "$CURRENT_STEP"
t0=$SECONDS
printf '{"asset":{"version":"2.0"},"scenes":[{"nodes":[0]}],"nodes":[{"name":"root"}],"scene":0}\n' \
  > "$WORK/ok.gltf"
printf '{"asset":{}}\n' > "$WORK/bad.gltf"
set +e
node "$RIGPORT_GLTF_VALIDATOR" "$WORK/ok.gltf"; ok_rc=$?
node "$RIGPORT_GLTF_VALIDATOR" "$WORK/bad.gltf"; bad_rc=$?
set -e
if (( ok_rc == 0 && bad_rc == 1 )); then
  record "$CURRENT_STEP" PASS "$((SECONDS - t0))" "valid asset -> 0, invalid asset -> 1"
else
  record "$CURRENT_STEP" FAIL "$((SECONDS - t0))" "exit codes $ok_rc/$bad_rc, expected 0/1"
fi

# --------------------------------------------------------------- 3 Rust tests
PROFILE="${RIGPORT_TEST_PROFILE:-dev}"
case "$PROFILE" in
  release) PROFILE_ARGS=(--release) ;;
  dev|debug) PROFILE="dev"; PROFILE_ARGS=() ;;
  *) echo "tools/test.sh: RIGPORT_TEST_PROFILE must be release or dev, not '$PROFILE'" >&2; exit 2 ;;
esac
# Fresh CI clones build once: incremental caches only cost time there.
if [[ -n "${CI:-}" ]]; then export CARGO_INCREMENTAL="${CARGO_INCREMENTAL:-0}"; fi
COLOR=never
if [[ -t 1 ]]; then COLOR=always; fi
export CARGO_TERM_COLOR="${CARGO_TERM_COLOR:-$COLOR}"

lock_hint() { # explain the usual --locked failure
  if grep -q 'lock file .* needs to be updated\|cannot update the lock file' "$1.plain"; then
    echo "tools/test.sh: Cargo.lock is out of date with Cargo.toml: run 'cargo check --workspace' and commit Cargo.lock" >&2
    NOTE="$NOTE (Cargo.lock out of date with Cargo.toml)"
  fi
}

# Add "N passed; N failed; N ignored" from every libtest "test result:" line.
count_libtest() {
  local p f i
  read -r p f i < <(sed -nE 's/^test result: [A-Za-z]+\. ([0-9]+) passed; ([0-9]+) failed; ([0-9]+) ignored.*/\1 \2 \3/p' \
    "$1.plain" | awk '{p+=$1; f+=$2; i+=$3} END {print p+0, f+0, i+0}')
  TOTAL_PASSED=$((TOTAL_PASSED + p)); TOTAL_FAILED=$((TOTAL_FAILED + f)); TOTAL_SKIPPED=$((TOTAL_SKIPPED + i))
  NOTE="$p passed, $f failed, $i ignored"
}

USE_NEXTEST=0
if [[ "${RIGPORT_NO_NEXTEST:-0}" != 1 ]] && cargo nextest --version >/dev/null 2>&1; then USE_NEXTEST=1; fi

if (( USE_NEXTEST )); then
  CURRENT_STEP="Rust tests (cargo nextest, $PROFILE)"
  banner "$CURRENT_STEP"
  t0=$SECONDS
  log="$WORK/nextest.log"
  set +e
  cargo nextest run --workspace --locked "${PROFILE_ARGS[@]}" --no-fail-fast --no-tests=warn \
    --color "$CARGO_TERM_COLOR" "$@" 2>&1 | tee "$log"
  rc=${PIPESTATUS[0]}
  set -e
  # "Summary [  1.234s] 57 tests run: 55 passed, 2 failed, 3 skipped"
  plain "$log"
  line="$(grep -E '^ *Summary \[' "$log.plain" | tail -n 1 || true)"
  NOTE="${line#*] }"
  if [[ "$line" =~ ([0-9]+)\ passed ]]; then
    TOTAL_PASSED=$((TOTAL_PASSED + BASH_REMATCH[1]))
    [[ "$line" =~ ([0-9]+)\ failed ]] && TOTAL_FAILED=$((TOTAL_FAILED + BASH_REMATCH[1]))
    [[ "$line" =~ ([0-9]+)\ timed\ out ]] && TOTAL_FAILED=$((TOTAL_FAILED + BASH_REMATCH[1]))
    [[ "$line" =~ ([0-9]+)\ skipped ]] && TOTAL_SKIPPED=$((TOTAL_SKIPPED + BASH_REMATCH[1]))
  elif (( rc == 0 )); then
    NOTE="no tests found"
  else
    COUNTS_KNOWN=0; NOTE="did not finish: exit $rc"; lock_hint "$log"
  fi
  record "$CURRENT_STEP" "$( ((rc == 0)) && echo PASS || echo FAIL)" "$((SECONDS - t0))" "$NOTE"

  CURRENT_STEP="doctests (cargo test --doc, $PROFILE)"
  banner "$CURRENT_STEP"
  t0=$SECONDS
  log="$WORK/doctest.log"
  set +e
  cargo test --doc --workspace --locked "${PROFILE_ARGS[@]}" --no-fail-fast 2>&1 | tee "$log"
  rc=${PIPESTATUS[0]}
  set -e
  plain "$log"
  count_libtest "$log"
  if (( rc != 0 )) && ! grep -q '^test result:' "$log.plain"; then
    COUNTS_KNOWN=0; NOTE="did not finish: exit $rc"; lock_hint "$log"
  fi
  record "$CURRENT_STEP" "$( ((rc == 0)) && echo PASS || echo FAIL)" "$((SECONDS - t0))" "$NOTE"
else
  CURRENT_STEP="Rust tests + doctests (cargo test, $PROFILE)"
  banner "$CURRENT_STEP (cargo-nextest not used)"
  t0=$SECONDS
  log="$WORK/cargo-test.log"
  set +e
  cargo test --workspace --locked "${PROFILE_ARGS[@]}" --no-fail-fast "$@" 2>&1 | tee "$log"
  rc=${PIPESTATUS[0]}
  set -e
  plain "$log"
  count_libtest "$log"
  if (( rc != 0 )) && ! grep -q '^test result:' "$log.plain"; then
    COUNTS_KNOWN=0; NOTE="did not finish: exit $rc"; lock_hint "$log"
  fi
  record "$CURRENT_STEP" "$( ((rc == 0)) && echo PASS || echo FAIL)" "$((SECONDS - t0))" "$NOTE"
fi

# --------------------------------------------------------------- 5 USD smoke
CURRENT_STEP="USD smoke (tools/usd_smoke.py)"
banner "$CURRENT_STEP"
t0=$SECONDS
if "$RIGPORT_PYTHON" tools/usd_smoke.py; then
  record "$CURRENT_STEP" PASS "$((SECONDS - t0))" "pxr.Usd, pxr.UsdSkel, numpy import; skeleton round-trips"
else
  record "$CURRENT_STEP" FAIL "$((SECONDS - t0))"
fi

# ---------------------------------------------------------------- 6 rustfmt
CURRENT_STEP="rustfmt (cargo fmt --check)"
banner "$CURRENT_STEP"
t0=$SECONDS
if cargo fmt --all -- --check; then
  record "$CURRENT_STEP" PASS "$((SECONDS - t0))"
else
  record "$CURRENT_STEP" FAIL "$((SECONDS - t0))" "run cargo fmt --all"
fi

# ----------------------------------------------------------------- 7 clippy
CURRENT_STEP="clippy (-D warnings, $PROFILE)"
banner "$CURRENT_STEP"
t0=$SECONDS
if cargo clippy --workspace --all-targets --locked "${PROFILE_ARGS[@]}" -- -D warnings; then
  record "$CURRENT_STEP" PASS "$((SECONDS - t0))"
else
  record "$CURRENT_STEP" FAIL "$((SECONDS - t0))"
fi

# ---------------------------------------------------------- 8 output hashes
# What rigport writes for the demo and the corpus is recorded in tools/output_hashes.txt;
# a change that means to alter output updates that file in the same commit. Uses the test
# profile's binary: dev and release write the same bytes (no fast-math; checked by running
# the script with both), and CI then builds no release binary.
CURRENT_STEP="output hashes (tools/output_hashes.sh, $PROFILE)"
banner "$CURRENT_STEP"
t0=$SECONDS
BIN_DIR="$( [[ "$PROFILE" == release ]] && echo release || echo debug)"
hash_rc=0
hash_log="$(mktemp)"
# The binary step 3 built for the CLI tests (`CARGO_BIN_EXE_rigport`) when it is there and
# no older than the sources: `cargo build --bin rigport` would build the workspace a second
# time (without the dev-dependencies, some shared crates get other features), about 110 s
# on 2 cores from cold.
hash_bin="${CARGO_TARGET_DIR:-$ROOT/target}/$BIN_DIR/rigport"
newer_source="$(find "$ROOT/src" "$ROOT/crates" "$ROOT/Cargo.toml" "$ROOT/Cargo.lock" -newer "$hash_bin" \
  -name '*.rs' -o -newer "$hash_bin" -name 'Cargo.*' 2>/dev/null | head -1 || true)"
if [[ -x "$hash_bin" && -z "$newer_source" ]] || cargo build --locked "${PROFILE_ARGS[@]}" --bin rigport; then
  RIGPORT_BIN="$hash_bin" bash tools/output_hashes.sh \
    2> >(tee "$hash_log" >&2) || hash_rc=$?
else
  hash_rc=1
fi
sleep 0.2 # let tee finish
if [[ "$hash_rc" == 0 ]]; then
  record "$CURRENT_STEP" PASS "$((SECONDS - t0))"
elif [[ "$hash_rc" == 4 ]]; then
  # Recorded on another CPU/glibc or corpus: libm may round differently there (see the script).
  record "$CURRENT_STEP" PASS "$((SECONDS - t0))" \
    "not comparable: recorded on another platform or corpus; $(grep -m1 -oE '[0-9]+ of [0-9]+ outputs differ' "$hash_log")"
else
  record "$CURRENT_STEP" FAIL "$((SECONDS - t0))" \
    "$(grep -m1 -oE '[0-9]+ of [0-9]+ outputs differ: .{0,80}' "$hash_log" || echo 'build failed')"
fi
rm -f "$hash_log"

# ----------------------------------------------------- 8b Python wheel + pytest
# maturin builds crates/python in the test profile into the shared target folder: the
# library crates step 8 compiled (same features) are reused, only PyO3, numpy and the
# bindings compile. The wheel goes into both venvs; pytest runs it against the CLI of step 8.
CURRENT_STEP="Python wheel (maturin + pytest, $PROFILE)"
banner "$CURRENT_STEP"
t0=$SECONDS
wheel_dir="$WORK/wheel"
py_log="$WORK/pytest.log"
py_rc=0
# A second Python minor version for the abi3 check (the venvs are 3.11).
second_python="${RIGPORT_SECOND_PYTHON:-}"
if [[ -z "$second_python" ]]; then
  pyenv_root="$(pyenv root 2>/dev/null || echo "${PYENV_ROOT:-$HOME/.pyenv}")"
  for minor in 13 12 10 9; do
    for cand in "$pyenv_root"/versions/3."$minor".*/bin/python3 "$(command -v python3."$minor" 2>/dev/null || true)"; do
      if [[ -x "$cand" ]] && "$cand" -c 'import sys; sys.exit(sys.version_info[:2] == (3, 11))' 2>/dev/null; then
        second_python="$cand"; break 2
      fi
    done
  done
fi
maturin_args=(build --locked --profile "$PROFILE" --strip -m crates/python/Cargo.toml --out "$wheel_dir"
  --interpreter "$RIGPORT_PYTHON")
if "$ROOT/tools/.venv/bin/maturin" "${maturin_args[@]}"; then
  wheel="$(ls "$wheel_dir"/rigport-*.whl)"
  PIP_DISABLE_PIP_VERSION_CHECK=1 "$RIGPORT_PYTHON" -m pip install --quiet --no-deps --force-reinstall "$wheel"
  if [[ -n "${RIGPORT_BLENDER_PYTHON:-}" && -x "${RIGPORT_BLENDER_PYTHON:-}" ]]; then
    PIP_DISABLE_PIP_VERSION_CHECK=1 "$RIGPORT_BLENDER_PYTHON" -m pip install --quiet --no-deps --force-reinstall "$wheel"
  fi
  set +e
  RIGPORT_BIN="${CARGO_TARGET_DIR:-$ROOT/target}/$BIN_DIR/rigport" RIGPORT_WHEEL="$wheel" \
    RIGPORT_SECOND_PYTHON="$second_python" \
    "$RIGPORT_PYTHON" -m pytest -q -rs -p no:cacheprovider crates/python/tests 2>&1 | tee "$py_log"
  py_rc=${PIPESTATUS[0]}
  set -e
else
  py_rc=1
  : > "$py_log"
fi
plain "$py_log"
# "3 failed, 17 passed, 2 skipped, 4 warnings in 9.12s"
line="$(grep -E '^=*\s*[0-9]+ (passed|failed)' "$py_log.plain" | tail -n 1 || true)"
NOTE="$(sed -E 's/^=+ *//; s/ *=+$//' <<<"$line")"
[[ "$line" =~ ([0-9]+)\ passed ]] && TOTAL_PASSED=$((TOTAL_PASSED + BASH_REMATCH[1]))
[[ "$line" =~ ([0-9]+)\ failed ]] && TOTAL_FAILED=$((TOTAL_FAILED + BASH_REMATCH[1]))
[[ "$line" =~ ([0-9]+)\ skipped ]] && TOTAL_SKIPPED=$((TOTAL_SKIPPED + BASH_REMATCH[1]))
[[ -n "$line" ]] || NOTE="wheel build failed or pytest did not finish (exit $py_rc)"
NOTE="$NOTE; second Python: ${second_python:-none found}"
record "$CURRENT_STEP" "$( ((py_rc == 0)) && echo PASS || echo FAIL)" "$((SECONDS - t0))" "$NOTE"

# --------------------------------------------------------- 9 module circles
CURRENT_STEP="module circles (tools/module_cycles.py)"
banner "$CURRENT_STEP"
t0=$SECONDS
if python3 tools/module_cycles.py; then
  record "$CURRENT_STEP" PASS "$((SECONDS - t0))"
else
  record "$CURRENT_STEP" FAIL "$((SECONDS - t0))" "files that import each other (listed above)"
fi

CURRENT_STEP="rustdoc (cargo doc --no-deps, warnings denied)"
banner "$CURRENT_STEP"
t0=$SECONDS
if RUSTDOCFLAGS="-D warnings" cargo doc --workspace --no-deps --locked "${PROFILE_ARGS[@]}"; then
  record "$CURRENT_STEP" PASS "$((SECONDS - t0))"
else
  record "$CURRENT_STEP" FAIL "$((SECONDS - t0))" "broken or private doc links (listed above)"
fi

CURRENT_STEP="one concept, one type (tools/one_concept.py)"
banner "$CURRENT_STEP"
t0=$SECONDS
if python3 tools/one_concept.py --self-test && python3 tools/one_concept.py; then
  record "$CURRENT_STEP" PASS "$((SECONDS - t0))"
else
  record "$CURRENT_STEP" FAIL "$((SECONDS - t0))" "a concept defined twice (listed above)"
fi

# ------------------------------------------------------------- 10 fuzz (short)
CURRENT_STEP="fuzz (fuzz/run.sh, short)"
banner "$CURRENT_STEP"
t0=$SECONDS
fuzz_seconds="${RIGPORT_FUZZ_SECONDS:-5}"
fuzz_log="$(mktemp)"
if ! cargo fuzz --version >/dev/null 2>&1 || ! cargo +nightly --version >/dev/null 2>&1; then
  record "$CURRENT_STEP" PASS "$((SECONDS - t0))" "skipped: cargo-fuzz or nightly not installed"
elif [[ "$fuzz_seconds" == 0 ]]; then
  record "$CURRENT_STEP" PASS "$((SECONDS - t0))" "skipped: RIGPORT_FUZZ_SECONDS=0"
else
  fuzz_rc=0
  bash fuzz/run.sh --dev --scratch --seconds "$fuzz_seconds" >"$fuzz_log" 2>&1 || fuzz_rc=$?
  cat "$fuzz_log"
  if [[ "$fuzz_rc" == 0 ]]; then
    record "$CURRENT_STEP" PASS "$((SECONDS - t0))" "${fuzz_seconds} s per target (dev build), no crash"
  elif [[ "$fuzz_rc" == 3 ]]; then
    record "$CURRENT_STEP" PASS "$((SECONDS - t0))" \
      "skipped: cargo fuzz cannot build here ($(grep -m1 '^fuzz: first error line' "$fuzz_log" | cut -c25-120))"
  else
    record "$CURRENT_STEP" FAIL "$((SECONDS - t0))" \
      "$(grep -m1 -E '^fuzz: (our fuzz code|[a-z_0-9]+: FAILED)' "$fuzz_log" | cut -c1-100)"
  fi
fi
rm -f "$fuzz_log"
# The EXIT trap prints the summary and sets the exit status.

#!/usr/bin/env bash
# Install the external tools rigport's tests shell out to, into folders of this
# repo that git ignores:
#   tools/node_modules  Khronos glTF-Validator (npm gltf-validator), three.js
#                       (npm three, for tools/three_eval.mjs and three_source_eval.mjs)
#                       and gltfpack (npm gltfpack, the compact-clips peer)
#                       and @xmldom/xmldom (ColladaLoader's DOMParser in Node), pinned in
#                       tools/package.json + tools/package-lock.json, `npm ci`
#   tools/.venv         Python >= 3.11 venv with usd-core + numpy, and maturin + pytest
#                       for the Python wheel (crates/python), pinned in
#                       tools/requirements.txt
#   tools/.venv-blender optional (--blender, or RIGPORT_SETUP_BLENDER=1): Python 3.11 venv
#                       with Blender as a module (bpy, 373 MB wheel, 0.9 GB installed) and
#                       numpy < 2, pinned in tools/requirements-blender.txt; for the tests
#                       that compare with Blender's FBX importer (RIGPORT_BLENDER_PYTHON)
#
# Idempotent: each part writes a stamp holding a hash of its pin files (and of
# the interpreter it was built with); when the stamp matches, that part is
# skipped, so a warm run takes well under a second.
#
# usage: bash tools/setup.sh [--force] [--blender]   (or RIGPORT_SETUP_FORCE=1,
#        RIGPORT_SETUP_BLENDER=1)
# Needs: node >= 18 + npm, python3 >= 3.11 with the venv module, and the npm
# registry and PyPI reachable on a cold run. No stdin is read.
set -euo pipefail

TOOLS_DIR="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
NODE_MODULES="$TOOLS_DIR/node_modules"
VENV="$TOOLS_DIR/.venv"
NPM_STAMP="$NODE_MODULES/.rigport-setup-stamp"
VENV_STAMP="$VENV/.rigport-setup-stamp"

force="${RIGPORT_SETUP_FORCE:-0}"
blender="${RIGPORT_SETUP_BLENDER:-0}"
BLENDER_VENV="$TOOLS_DIR/.venv-blender"
for arg in "$@"; do
  case "$arg" in
    --force) force=1 ;;
    --blender) blender=1 ;;
    -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "${BASH_SOURCE[0]}"; exit 0 ;;
    *) echo "setup: unknown argument: $arg (try --help)" >&2; exit 2 ;;
  esac
done

say() { printf '[setup] %s\n' "$*"; }
die() {
  printf '[setup] ERROR: %s\n' "$1" >&2
  shift
  local line
  for line in "$@"; do printf '[setup]        %s\n' "$line" >&2; done
  exit 1
}

# Hash of files, plus extra strings (tool versions), as one hex digest.
hash_of() {
  local files=() extra=() a
  for a in "$@"; do
    if [[ -f "$a" ]]; then files+=("$a"); else extra+=("$a"); fi
  done
  { cat "${files[@]}"; printf '%s\n' "${extra[@]}"; } | sha256sum | cut -d' ' -f1
}

# ---------------------------------------------------------------- prerequisites
command -v sha256sum >/dev/null 2>&1 \
  || die "sha256sum not found." "Debian: apt-get install -y coreutils"

command -v node >/dev/null 2>&1 || die "node (Node.js >= 18) not found." \
  "Debian: apt-get install -y nodejs npm   (or any Node.js >= 18 on PATH)"
command -v npm >/dev/null 2>&1 || die "npm not found." \
  "Debian: apt-get install -y npm   (it comes with most Node.js installs)"
node_version="$(node --version)"           # v20.20.2
node_major="${node_version#v}"; node_major="${node_major%%.*}"
if ! [[ "$node_major" =~ ^[0-9]+$ ]] || (( node_major < 18 )); then
  die "Node.js $node_version is too old: need >= 18." \
      "Debian: apt-get install -y nodejs npm   (or a newer Node.js on PATH)"
fi

# One interpreter call answers everything (a pyenv shim costs a fork of bash
# per call): "<version> <real executable>", or exit 3 when too old, 4 without venv.
PYTHON=""
py_probe='import sys
if sys.version_info < (3, 11): sys.exit(3)
try:
    import venv, ensurepip
except ImportError:
    sys.exit(4)
print("%d.%d.%d" % sys.version_info[:3], sys.executable)'
py_found_no_venv=""
for cand in "${RIGPORT_SETUP_PYTHON:-}" python3.11 python3; do
  if [[ -z "$cand" ]] || ! command -v "$cand" >/dev/null 2>&1; then continue; fi
  rc=0; out="$("$cand" -c "$py_probe" 2>/dev/null)" || rc=$?
  if (( rc == 0 )) && [[ -n "$out" ]]; then
    py_version="${out%% *}"; PYTHON="${out#* }"; break
  elif (( rc == 4 )); then
    py_found_no_venv="$(command -v "$cand")"
  fi
done
if [[ -z "$PYTHON" && -n "$py_found_no_venv" ]]; then
  die "$py_found_no_venv has no venv/ensurepip module." "Debian: apt-get install -y python3-venv"
fi
[[ -n "$PYTHON" ]] || die "python3 >= 3.11 not found (tried \$RIGPORT_SETUP_PYTHON, python3.11, python3)." \
  "Debian 12: apt-get install -y python3 python3-venv   (Python 3.11)"
[[ "$py_version" == 3.11.* ]] \
  || say "note: Python $py_version (the pins in tools/requirements.txt are checked on 3.11)"

say "using node $node_version, python $py_version ($PYTHON)"

# One setup at a time per checkout (two test runs started together).
if command -v flock >/dev/null 2>&1; then
  lock="${TMPDIR:-/tmp}/rigport-setup-$(printf '%s' "$TOOLS_DIR" | sha256sum | cut -c1-16).lock"
  exec 9>"$lock"
  flock 9
fi

# ------------------------------------------------------------ glTF-Validator
npm_hash="$(hash_of "$TOOLS_DIR/package.json" "$TOOLS_DIR/package-lock.json" "node-major=$node_major")"
if [[ "$force" != 1 && -f "$NPM_STAMP" && "$(cat "$NPM_STAMP")" == "$npm_hash" \
      && -f "$NODE_MODULES/gltf-validator/package.json" && -f "$NODE_MODULES/three/package.json" \
      && -f "$NODE_MODULES/@xmldom/xmldom/package.json" ]]; then
  say "glTF-Validator + three.js: up to date in tools/node_modules (stamp matches package-lock.json)"
else
  say "glTF-Validator + three.js: npm ci in tools/ with npm $(npm --version 2>/dev/null) (exact versions from tools/package-lock.json)"
  t0=$SECONDS
  ( cd "$TOOLS_DIR" && npm ci --no-audit --no-fund --ignore-scripts --loglevel=error ) \
    || die "npm ci failed in tools/ (is the npm registry reachable?)"
  printf '%s\n' "$npm_hash" > "$NPM_STAMP"
  say "glTF-Validator + three.js: installed in $((SECONDS - t0))s"
fi
gv_version="$(cd "$TOOLS_DIR" && node -p 'require("gltf-validator/package.json").version')" \
  || die "tools/node_modules/gltf-validator is broken; re-run: bash tools/setup.sh --force"
say "glTF-Validator: gltf-validator $gv_version"

# ------------------------------------------------------------------ USD venv
venv_hash="$(hash_of "$TOOLS_DIR/requirements.txt" "python=$py_version" "python-path=$PYTHON")"
venv_list() { # "name==version ..." of the venv, and a check that its python runs
  "$VENV/bin/python" -c 'import importlib.metadata as m
print(" ".join(sorted(f"{d.name}=={d.version}" for d in m.distributions() if d.name not in ("pip", "setuptools"))))' 2>/dev/null
}
if [[ "$force" != 1 && -f "$VENV_STAMP" && "$(cat "$VENV_STAMP")" == "$venv_hash" ]] \
   && venv_pkgs="$(venv_list)"; then
  say "Python venv: up to date in tools/.venv (stamp matches requirements.txt)"
else
  say "Python venv: creating tools/.venv and installing tools/requirements.txt (wheels only)"
  t0=$SECONDS
  rm -rf "$VENV"
  "$PYTHON" -m venv "$VENV" || die "python -m venv failed." "Debian: apt-get install -y python3-venv"
  PIP_DISABLE_PIP_VERSION_CHECK=1 PIP_NO_INPUT=1 \
    "$VENV/bin/python" -m pip install --quiet --require-virtualenv --only-binary=:all: --no-compile \
      -r "$TOOLS_DIR/requirements.txt" \
    || die "pip install -r tools/requirements.txt failed (is PyPI reachable? wheels for Python $py_version?)"
  printf '%s\n' "$venv_hash" > "$VENV_STAMP"
  say "Python venv: installed in $((SECONDS - t0))s"
  venv_pkgs="$(venv_list)" || die "tools/.venv/bin/python does not run after install"
fi
say "Python venv: $venv_pkgs"

# ------------------------------------------------- Blender venv (optional)
if [[ "$blender" == 1 ]]; then
  blender_hash="$(hash_of "$TOOLS_DIR/requirements-blender.txt" "python=$py_version" "python-path=$PYTHON")"
  if [[ "$force" != 1 && -f "$BLENDER_VENV/.rigport-setup-stamp" \
        && "$(cat "$BLENDER_VENV/.rigport-setup-stamp")" == "$blender_hash" ]] \
     && "$BLENDER_VENV/bin/python" -c 'import bpy' >/dev/null 2>&1; then
    say "Blender venv: up to date in tools/.venv-blender (stamp matches requirements-blender.txt)"
  else
    [[ "$py_version" == 3.11.* ]] || die "bpy 4.5 needs Python 3.11, found $py_version." \
      "set RIGPORT_SETUP_PYTHON to a Python 3.11"
    say "Blender venv: creating tools/.venv-blender and installing tools/requirements-blender.txt (373 MB bpy wheel)"
    t0=$SECONDS
    rm -rf "$BLENDER_VENV"
    "$PYTHON" -m venv "$BLENDER_VENV" || die "python -m venv failed."
    PIP_DISABLE_PIP_VERSION_CHECK=1 PIP_NO_INPUT=1 \
      "$BLENDER_VENV/bin/python" -m pip install --quiet --require-virtualenv --only-binary=:all: --no-compile \
        -r "$TOOLS_DIR/requirements-blender.txt" \
      || die "pip install -r tools/requirements-blender.txt failed (is PyPI reachable?)"
    printf '%s\n' "$blender_hash" > "$BLENDER_VENV/.rigport-setup-stamp"
    say "Blender venv: installed in $((SECONDS - t0))s"
  fi
  say "Blender venv: bpy $("$BLENDER_VENV/bin/python" -c 'import bpy; print(bpy.app.version_string)' 2>/dev/null | tail -n 1)"
  say "ready: RIGPORT_BLENDER_PYTHON=$BLENDER_VENV/bin/python"
fi

say "ready: RIGPORT_GLTF_VALIDATOR=$TOOLS_DIR/validate_gltf.mjs RIGPORT_PYTHON=$VENV/bin/python"

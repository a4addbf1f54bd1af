#!/usr/bin/env bash
# Seeds fuzz/corpus/<target>/ from the project's own fixtures (fixtures/), composing the
# multi-file inputs the targets expect (see fuzz/src/lib.rs). Idempotent: files are named
# by content hash. The corpus then grows with what libFuzzer finds and is minimized with
# `cargo fuzz cmin` before it is committed (fuzz/README.md).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
F="$ROOT/fixtures"
C="$ROOT/fuzz/corpus"

put() { # target file...   (several files: joined with NUL bytes)
  local target="$1"; shift
  mkdir -p "$C/$target"
  local tmp; tmp="$(mktemp)"
  local first=1
  for f in "$@"; do
    if [[ $first == 0 ]]; then printf '\0' >> "$tmp"; fi
    cat "$f" >> "$tmp"; first=0
  done
  local h; h="$(sha1sum "$tmp" | cut -c1-16)"
  mv "$tmp" "$C/$target/seed-$h"
}

for f in "$F"/pinocchio/*.obj "$F"/csci520/chain/chain.obj; do put obj "$f"; done
put pinocchio "$F/pinocchio/branch.obj" "$F/pinocchio/branch_skeleton.out" "$F/pinocchio/branch_attachment.out"
put pinocchio "$F/pinocchio/branch.obj" "$F/pinocchio/quirks_skeleton.out" "$F/pinocchio/branch_attachment_root_column.out"
put csci520 "$F/csci520/chain/jointHierarchy.txt" "$F/csci520/chain/jointRestTransforms.txt" "$F/csci520/chain/jointWeights.txt" "$F/csci520/chain/chain.obj"
for f in "$F"/asf_amc/*.asf; do put asf "$f"; done
for f in "$F"/asf_amc/*.amc; do put amc "$f"; done
for f in "$F"/bvh/*.bvh; do put bvh "$f"; done
for f in "$F"/gltf/*.gltf "$F"/gltf/*.glb; do put gltf "$f"; done
for f in "$F"/usda/*.usda "$F"/usdc/*.usd?; do put usd "$f"; done
for f in "$F"/collada/*.dae "$F"/collada/*.zae; do put collada "$f"; done
put json_pose /dev/stdin <<<'{"Hips": {"quat": [0, 0, 0.3826834, 0.9238795]}, "Head": {"euler_deg": [10, 20, 30], "order": "zyx"}}'
put json_keys /dev/stdin <<<'{"name": "k", "keys": [{"time": 0, "pose": {"Hips": {"quat": [0,0,0,1]}}}, {"time": 1, "translation": [0, 1, 0], "pose": {"Head": {"euler_deg": [0, 45, 0]}}}]}'
for f in "$F"/ik/*.json; do put json_handles "$f"; done
put json_handles /dev/stdin <<<'{"fps": 30, "handles": [{"joint": "Hand", "relative": true, "keys": [{"time": 0, "position": [0, 0, 0]}, {"time": 1, "position": [0.1, 0.2, 0]}]}, {"joint": "Head", "keys": [{"time": 0.5, "position": [0, 1, 0]}]}]}'
ls "$C" | while read -r t; do echo "$t: $(ls "$C/$t" | wc -l) inputs"; done

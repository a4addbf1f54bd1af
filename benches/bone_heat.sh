#!/usr/bin/env bash
# Automatic weights (bone heat), rigport against Blender, side by side (issue 33):
# - the corpus's `human_model1` (13,336 vertices, 17 bones): rigport's `bone_heat`
#   (crates/deform/examples/bone_heat.rs, release) and Blender's armature parent with
#   automatic weights (tools/blender/auto_weights.py, bpy 4.5), each timing the weighting
#   alone, taken in turn, A B A B ..., so the shared machine's drift hits both;
# - the same mesh with every triangle cut into 9 (120,008 vertices, made by the example's
#   `--split 3` and written to a temp OBJ, not committed): wall time and peak memory of the
#   whole process (GNU time -v) for both;
# - rigport alone on the mesh split 1, 2, 3, 4 and 6 times (13k to 480k vertices): peak
#   memory per vertex, to show it grows linearly.
#
#   bash benches/bone_heat.sh [ROUNDS]
#
# Needs the corpus (RIGPORT_CORPUS, default ../shared/corpus) and Blender's Python
# (RIGPORT_BLENDER_PYTHON, default tools/.venv-blender/bin/python; bash tools/setup.sh
# --blender). Builds the example with `cargo build --release` (CARGO_TARGET_DIR honoured).
set -euo pipefail
cd "$(dirname "$0")/.."
rounds=${1:-5}
corpus=$(realpath "${RIGPORT_CORPUS:-../shared/corpus}")
bpy=${RIGPORT_BLENDER_PYTHON:-tools/.venv-blender/bin/python}
rig="$corpus/1_pinocchio/berkeley_cs184__severus-snape_mobius-ants/human_model1"
mesh="$rig/Model1.obj" skeleton="$rig/skeleton.out"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

cargo build --release -q -p rigport-deform --example bone_heat
example="${CARGO_TARGET_DIR:-target}/release/examples/bone_heat"
echo "threads: $(nproc) cores; load before: $(cut -d' ' -f1-3 /proc/loadavg)"

# rigport's first solve in a process pays for the thread pool and fresh pages, as Blender's
# one call per process does: both the first and the best of 3 are printed.
echo "== human_model1: rigport (first, best of 3 solves in one process) | Blender (one per process)"
for round in $(seq "$rounds"); do
  "$example" "$mesh" "$skeleton" --runs 3 > "$work/ours.txt"
  first=$(sed -n 's/^run 0: .* bones: \([0-9.]*\) s .*/\1/p' "$work/ours.txt")
  best=$(awk '/^best/ {print $4}' "$work/ours.txt")
  "$bpy" tools/blender/auto_weights.py "$mesh" "$skeleton" "$work/blender.txt" >/dev/null
  theirs=$(awk '/^# seconds/ {print $3}' "$work/blender.txt")
  awk -v r="$round" -v f="$first" -v a="$best" -v b="$theirs" 'BEGIN {
    printf "round %s: rigport first %.3f s, best %.3f s; Blender %.3f s; ratios %.2f, %.2f\n",
      r, f, a, b, f / b, a / b}'
done

timed() { # label command... -> prints wall, peak RSS
  /usr/bin/time -v "${@:2}" > "$work/out.txt" 2> "$work/time.txt" || { cat "$work/time.txt"; exit 1; }
  awk -v label="$1" -F': ' '
    /Elapsed \(wall clock\)/ {n = split($2, t, ":"); s = 0; for (i = 1; i <= n; i++) s = s * 60 + t[i]; w = s}
    /Maximum resident set size/ {m = $2 / 1024}
    END {printf "%s: process %.2f s wall, peak %.0f MiB\n", label, w, m}' "$work/time.txt"
}

echo "== human_model1 split 3 (120,008 vertices)"
timed "rigport" "$example" "$mesh" "$skeleton" --split 3 --write-obj "$work/split3.obj"
grep -E '^run' "$work/out.txt"
timed "Blender (bpy start-up, OBJ read, armature, weights, write)" \
  "$bpy" tools/blender/auto_weights.py "$work/split3.obj" "$skeleton" "$work/blender.txt"
head -3 "$work/blender.txt" | grep '^#'

echo "== rigport's peak memory by size (split N: every triangle cut into N*N)"
for n in 1 2 3 4 6; do
  timed "split $n" "$example" "$mesh" "$skeleton" --split "$n"
  vertices=$(sed -n 's/^run 0: \([0-9]*\) vertices.*: \([0-9.]*\) s .*/\1 \2/p' "$work/out.txt")
  awk -v v="$vertices" -F': ' '/Maximum resident set size/ {split(v, a, " ");
    printf "  %s vertices, weights %s s, %.2f KiB per vertex\n", a[1], a[2], $2 / a[1]}' "$work/time.txt"
done

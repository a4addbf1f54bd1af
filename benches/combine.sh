#!/usr/bin/env bash
# `rigport combine` against separate `rigport retarget` runs (issue 30): 20 BVH clips (the
# corpus' four BVH files, five copies each under their own names) onto the corpus'
# 13,336-vertex Pinocchio rig `human_model1`, as one `combine` into one .glb, and as 20
# `retarget` runs writing one .glb each. The two are run in turn, A B A B ..., and each
# pair's ratio taken, so that the shared machine's drift cancels; GNU time -v gives each
# run's wall, CPU and peak memory.
#
#   RIGPORT_BIN=target/release/rigport bash benches/combine.sh [PAIRS]
#
# Prints one row per pair and the medians. The acceptance: the median ratio at most 0.5.
set -euo pipefail
cd "$(dirname "$0")/.."
bin=$(realpath "${RIGPORT_BIN:-target/release/rigport}")
pairs=${1:-5}
corpus=$(realpath "${RIGPORT_CORPUS:-../shared/corpus}")
rig="$corpus/1_pinocchio/berkeley_cs184__severus-snape_mobius-ants/human_model1"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
mkdir "$work/clips" "$work/separate"
for copy in 1 2 3 4 5; do
  for bvh in bandai_namco_ds1/dataset-1_walk_normal_002 bandai_namco_ds1/dataset-1_dash_normal_001 \
      bandai_namco_ds1/dataset-1_kick_normal_001 cmu_cgspeed__nobuyuki83_delfem2/walk; do
    ln -s "$corpus/4_bvh/$bvh.bvh" "$work/clips/$(basename "$bvh")_$copy.bvh"
  done
done

# The two commands, as scripts so that each is one process tree to time.
cat > "$work/combine.sh" <<SH
exec "$bin" combine -q "$rig" "$work/clips" -o "$work/library.glb"
SH
cat > "$work/separate.sh" <<SH
for clip in "$work"/clips/*.bvh; do
  "$bin" retarget -q "\$clip" --onto "$rig" -o "$work/separate/\$(basename "\$clip" .bvh).glb"
done
SH

timed() { # script -> "wall cpu rss_mib"
  /usr/bin/time -v bash "$1" 2> "$work/time.txt" >/dev/null || { cat "$work/time.txt"; exit 1; }
  awk -F': ' '/Elapsed \(wall clock\)/ {n=split($2,t,":"); s=0; for(i=1;i<=n;i++) s=s*60+t[i]; w=s}
    /User time|System time/ {c+=$2} /Maximum resident set size/ {m=$2/1024}
    END {printf "%.3f %.3f %.0f\n", w, c, m}' "$work/time.txt"
}

bash "$work/combine.sh" 2>/dev/null; bash "$work/separate.sh" 2>/dev/null # warm-up
echo "| pair | combine wall | combine CPU | 20 x retarget wall | 20 x retarget CPU | wall ratio |"
echo "| ---: | ---: | ---: | ---: | ---: | ---: |"
ratios=()
for k in $(seq 1 "$pairs"); do
  read -r aw ac am < <(timed "$work/combine.sh")
  read -r bw bc bm < <(timed "$work/separate.sh")
  r=$(echo "$aw / $bw" | bc -l)
  ratios+=("$r")
  printf '| %d | %.2f s | %.2f s | %.2f s | %.2f s | %.2fx |\n' "$k" "$aw" "$ac" "$bw" "$bc" "$r"
done
printf 'median wall ratio: %.2fx (combine peak %s MiB)\n' \
  "$(printf '%s\n' "${ratios[@]}" | sort -g | awk '{a[NR]=$1} END {print a[int((NR+1)/2)]}')" "$am"

#!/usr/bin/env bash
# Hashes of what rigport writes: the demo's files and `convert` of every corpus rig and
# motion to .glb, .gltf (+ .bin) and .usda. Refactors must leave them unchanged (issue 14);
# a change that means to alter output updates tools/output_hashes.txt in the same commit
# and says why.
#
#   bash tools/output_hashes.sh            compare with tools/output_hashes.txt (exit 1 on a difference)
#   bash tools/output_hashes.sh --write    record the current hashes
#
# RIGPORT_BIN=path uses that binary instead of building `cargo build --release`.
# Needs ../shared/corpus (skips the corpus part, with a message, when it is absent).
#
# Same bytes are promised for the same platform: rigport's arithmetic is plain IEEE (no
# fast-math), but sin/cos/exp/pow come from the C library, whose results may differ in the
# last bit between CPUs (glibc picks FMA or SSE2 code at run time) and between glibc
# versions. The file therefore records the platform and corpus it was written on (the `#`
# lines). On a difference, the script names the outputs that differ; it exits 1 when the
# platform and corpus are the recorded ones (a real change), and 4 when they are not
# (not comparable here: rerun on the recording platform, or --write there).
set -euo pipefail
export LC_ALL=C
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"
MODE="${1:-check}"
if [[ -z "${RIGPORT_BIN:-}" ]]; then
  cargo build --release --locked --quiet
  RIGPORT_BIN="$ROOT/target/release/rigport"
fi
C="$ROOT/../shared/corpus"
OUT="$(mktemp -d "${TMPDIR:-/tmp}/rigport-hashes.XXXXXX")"
trap 'rm -rf "$OUT"' EXIT
LIST="$OUT/hashes.txt"
: > "$LIST"

# hash LABEL ARGS...: convert to the three outputs; an input rigport refuses records its exit code.
convert3() {
  local label="$1"; shift
  local ext
  for ext in glb gltf usda; do
    local dir="$OUT/$label.$ext.d"
    mkdir -p "$dir"
    local rc=0
    "$RIGPORT_BIN" convert "$@" -o "$dir/out.$ext" >/dev/null 2>"$dir/stderr" || rc=$?
    if (( rc != 0 )); then
      echo "exit-$rc  $label.$ext" >> "$LIST"
    fi
    local f
    for f in $(cd "$dir" && ls | grep -v '^stderr$' | sort); do
      echo "$(sha256sum < "$dir/$f" | cut -c1-64)  $label.$ext/$f" >> "$LIST"
    done
  done
}

# The demo (no corpus pictures: those are renders of corpus rigs, covered by the demo tests).
"$RIGPORT_BIN" demo --no-corpus -o "$OUT/demo" >/dev/null 2>&1
for f in $(cd "$OUT/demo" && find . -type f | sort); do
  echo "$(sha256sum < "$OUT/demo/$f" | cut -c1-64)  demo/${f#./}" >> "$LIST"
done

if [[ -d "$C" ]]; then
  P=1_pinocchio
  convert3 arma2 "$C/$P/edinburgh_cav_arma2__gpfvic_CAV1/arma2.obj" "$C/$P/edinburgh_cav_arma2__gpfvic_CAV1/skeleton2.out" "$C/$P/edinburgh_cav_arma2__gpfvic_CAV1/attachment2.out"
  convert3 keepon "$C/$P/berkeley_cs184__icheung_Keepon/keepon/keepon.obj" "$C/$P/berkeley_cs184__icheung_Keepon/keepon/skeleton.out" "$C/$P/berkeley_cs184__icheung_Keepon/keepon/attachment.out"
  convert3 armadillo_pin "$C/$P/berkeley_cs184__icheung_Keepon/armadillo/Armadillo.obj" "$C/$P/berkeley_cs184__icheung_Keepon/armadillo/skeleton.out" "$C/$P/berkeley_cs184__icheung_Keepon/armadillo/attachment.out"
  convert3 model1 "$C/$P/berkeley_cs184__severus-snape_mobius-ants/human_model1/Model1.obj" "$C/$P/berkeley_cs184__severus-snape_mobius-ants/human_model1/skeleton.out" "$C/$P/berkeley_cs184__severus-snape_mobius-ants/human_model1/attachment.out"
  for r in tydia/armadillo tydia/hand tydia/dragon shreyabhaumik/star; do
    convert3 "csci520_${r//\//_}" "$C/2_csci520_ik_skinning/$r/skin.config" --max-influences 8
  done
  A="$C/3_acclaim_asf_amc/usc_csci520_mocapPlayer__shreyabhaumik"
  convert3 asf_07walk "$A/07-walk.asf" --motion "$A/07_05-walk.amc"
  convert3 asf_09run "$A/09-run.asf" --motion "$A/09_06-run.amc"
  convert3 asf_131dance "$A/131-dance.asf" --motion "$A/131_04-dance.amc"
  convert3 asf_02 "$C/3_acclaim_asf_amc/lowerbody_edge_case__cvikramk_TimeGAN/02.asf"
  for f in "$C"/4_bvh/*/*.bvh; do convert3 "bvh_$(basename "$f" .bvh)" "$f"; done
  for f in "$C"/5_gltf/khronos_samples__nobuyuki83_delfem2/*.glb "$C"/5_gltf/bevy_assets__bevyengine_bevy/*.gltf \
           "$C"/5_gltf/blender_io_roundtrip__KhronosGroup/*.gltf; do
    convert3 "gltf_$(basename "$f")" "$f"
  done
  for f in $(cd "$C/6_usd" && find . -name '*.usda' -not -path '*/baseline/*' | sort); do
    convert3 "usd_$(echo "${f#./}" | tr '/' '_')" "$C/6_usd/$f"
  done
else
  echo "tools/output_hashes.sh: ../shared/corpus is absent: only the demo is hashed" >&2
fi

EXPECTED="$ROOT/tools/output_hashes.txt"
# One order whatever the locale or file system: by output name.
sort -k2 -o "$LIST" "$LIST"
platform() {
  local cpu flags libc
  cpu="$(grep -m1 '^model name' /proc/cpuinfo 2>/dev/null | cut -d: -f2- | sed 's/^ *//')"
  flags="$(grep -m1 '^flags' /proc/cpuinfo 2>/dev/null | grep -ow -E 'fma|avx2|avx512f' | sort -u | tr '\n' ' ' | sed 's/ $//')"
  libc="$(ldd --version 2>/dev/null | head -1 | grep -oE '[0-9]+\.[0-9]+$' || true)"
  echo "$(uname -m) ${cpu:-unknown cpu}; ${flags:-no fma/avx}; glibc ${libc:-unknown}"
}
corpus_id() {
  if [[ -f "$C/MANIFEST.tsv" ]]; then sha256sum < "$C/MANIFEST.tsv" | cut -c1-16; else echo absent; fi
}
HEADER_PLATFORM="# platform: $(platform)"
HEADER_CORPUS="# corpus MANIFEST.tsv sha256: $(corpus_id)"
# differ: names the outputs whose hash changed, appeared or went missing (at most 12 shown).
differ() {
  local expected_body="$1"
  local names
  names="$(diff <(echo "$expected_body") "$LIST" | grep -E '^[<>] ' | awk '{print $3}' | sort -u || true)"
  local n
  n="$(echo "$names" | grep -c . || true)"
  echo "tools/output_hashes.sh: $n of $(wc -l < "$LIST") outputs differ: $(echo "$names" | head -12 | tr '\n' ' ')" >&2
  if [[ "$(grep -m1 '^# platform:' "$EXPECTED" || true)" != "$HEADER_PLATFORM" \
     || "$(grep -m1 '^# corpus' "$EXPECTED" || true)" != "$HEADER_CORPUS" ]]; then
    echo "tools/output_hashes.sh: not comparable here: recorded on" >&2
    grep '^# ' "$EXPECTED" | sed 's/^/  /' >&2
    echo "  this machine:" >&2
    printf '  %s\n  %s\n' "$HEADER_PLATFORM" "$HEADER_CORPUS" >&2
    exit 4
  fi
  echo "tools/output_hashes.sh: outputs differ from tools/output_hashes.txt on its own platform and corpus" >&2
  exit 1
}
if [[ "$MODE" == --write ]]; then
  { echo "$HEADER_PLATFORM"; echo "$HEADER_CORPUS"; cat "$LIST"; } > "$EXPECTED"
  echo "wrote $(grep -vc "^#" "$EXPECTED") hashes to tools/output_hashes.txt"
elif [[ ! -d "$C" ]]; then
  # Only the demo lines can be compared.
  body="$(grep '  demo/' "$EXPECTED")"
  if diff <(echo "$body") "$LIST"; then echo "demo outputs unchanged"; else differ "$body"; fi
else
  body="$(grep -v '^#' "$EXPECTED")"
  if diff <(echo "$body") "$LIST"; then
    echo "all $(wc -l < "$LIST") outputs unchanged"
  else
    differ "$body"
  fi
fi

#!/usr/bin/env bash
# Issue 8, acceptance 3: a 100-frame 512x512 GIF of the largest shared rig in under 5 s on
# 2 cores.
#
#   bash benches/render_gif.sh [--runs N]
#
# The largest skinned rig of ../shared/corpus is the Pinocchio human `human_model1`
# (Model1.obj: 13,336 vertices, 26,668 triangles; 18 joints). Pinocchio files carry no
# motion, so the script first keys a 4-second "arms" clip on it with `rigport animate`
# (both arms rise sideways and come back down, the demo's clip slowed down), then times
#   rigport render arms.glb --fps 25 --frames 0..100 --size 512x512 -o arms.gif
# (100 frames: LBS, skeleton overlay, frame counter) with hyperfine, and prints the GIF's
# size and frame count. Needs the dist build (cargo build --profile dist) and hyperfine
# (Debian package `hyperfine`). Exit 2 when something is missing.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BIN="${RIGPORT_BIN:-$ROOT/target/dist/rigport}"
RUNS=10
if [[ "${1:-}" == "--runs" ]]; then RUNS="$2"; fi
MODEL="$ROOT/../shared/corpus/1_pinocchio/berkeley_cs184__severus-snape_mobius-ants/human_model1"
[[ -x "$BIN" ]] || { echo "render_gif: $BIN missing: run cargo build --profile dist" >&2; exit 2; }
command -v hyperfine >/dev/null || { echo "render_gif: hyperfine missing: apt-get install -y hyperfine" >&2; exit 2; }
[[ -f "$MODEL/Model1.obj" ]] || { echo "render_gif: corpus rig $MODEL missing" >&2; exit 2; }

WORK="$(mktemp -d)"
trap 'rm -rf "$WORK"' EXIT
cat > "$WORK/arms.keys.json" <<'EOF'
{
  "name": "arms",
  "fps": 25,
  "keys": [
    {"time": 0, "pose": {}},
    {"time": 2, "pose": {"bone_13": {"euler_deg": [0, 0, -60]}, "bone_14": {"euler_deg": [0, 0, -30]},
                         "bone_16": {"euler_deg": [0, 0, 60]},  "bone_17": {"euler_deg": [0, 0, 30]}}},
    {"time": 4, "pose": {}}
  ]
}
EOF
"$BIN" animate -q "$MODEL/Model1.obj" "$MODEL/skeleton.out" "$MODEL/attachment.out" \
  --keys "$WORK/arms.keys.json" -o "$WORK/arms.glb"
CMD="$BIN render -q $WORK/arms.glb --fps 25 --frames 0..100 --size 512x512 -o $WORK/arms.gif"
printf 'machine: %s cores, load %s\n' "$(nproc)" "$(cut -d' ' -f1 /proc/loadavg)"
hyperfine -N --warmup 1 --runs "$RUNS" "$CMD"
frames=$(python3 - "$WORK/arms.gif" <<'PYEOF'
import sys
# Walk the GIF's blocks (GIF89a spec) and count image descriptors: one per frame.
d = open(sys.argv[1], "rb").read()
def skip_sub_blocks(i):
    while d[i]:
        i += d[i] + 1
    return i + 1
i, frames = 13, 0
if d[10] & 0x80:
    i += 3 << ((d[10] & 7) + 1)
while d[i] != 0x3B:
    if d[i] == 0x21:
        i = skip_sub_blocks(i + 2)
    elif d[i] == 0x2C:
        frames += 1
        local = d[i + 9]
        i += 10 + ((3 << ((local & 7) + 1)) if local & 0x80 else 0)
        i = skip_sub_blocks(i + 1)
    else:
        raise SystemExit(f"unexpected GIF block {d[i]:#x} at byte {i}")
print(frames)
PYEOF
)
printf 'arms.gif: %s bytes, %s frames\n' "$(stat -c %s "$WORK/arms.gif")" "$frames"

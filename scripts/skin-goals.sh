#!/usr/bin/env bash
# Issue 29's goals, counted on the eight characters the docs measure them on (docs/deformation-quality.md,
# "Eight characters and more levers"): bakes each with `--stats` (gow_biped, the given influences, ROM
# clips where the character has no arm clips of its own) and prints the four counts and, per character,
# what they are made of. About 10 s on two cores, but a measuring tool, not a test.
#
# Usage: scripts/skin-goals.sh OUT_DIR [rigbake] [-- extra bake flags...]
#   OUT_DIR keeps every bake's GLB, stats and log; a second run with the same OUT_DIR re-bakes.
#   RIGBAKE_INFLUENCES (default 4) and RIGBAKE_SHARED_ASSETS as for the tests.
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
out="${1:?usage: scripts/skin-goals.sh OUT_DIR [rigbake] [-- bake flags]}"
shift
rigbake="$repo/build/rigbake"
if [ $# -gt 0 ] && [ "$1" != "--" ]; then rigbake="$1"; shift; fi
[ $# -gt 0 ] && [ "$1" = "--" ] && shift
extra=("$@")
assets="${RIGBAKE_SHARED_ASSETS:-$repo/../shared/assets}"
influences="${RIGBAKE_INFLUENCES:-4}"
[ -x "$rigbake" ] || { echo "skin-goals: no rigbake binary at $rigbake" >&2; exit 2; }
mkdir -p "$out"
"$rigbake" sample -o "$out/mannequin.input.glb" >/dev/null
# name, input, own clips (0: add ROM clips)
characters=(
  "mannequin|$out/mannequin.input.glb|1"
  "cyberpunk|$assets/Quaternius_Cyberpunk_Character.glb|1"
  "soldier|$assets/Quaternius_ModularWomen_Soldier.glb|0"
  "male_casual|$assets/fbx/Male_Casual.fbx|0"
  "female_casual|$assets/fbx/Female_Casual.fbx|0"
  "cowboy|$assets/fbx/Cowboy.fbx|0"
  "cesiumman|$assets/CesiumMan.glb|0"
  "kaykit|$assets/KayKit_Mannequin/manny_med_mod.gltf|0"
)
bakeOne() {
  local name="${1%%|*}" rest="${1#*|}"
  local input="${rest%%|*}" own="${rest##*|}"
  local rom=()
  [ "$own" = 0 ] && rom=(--rom)
  [ -f "$input" ] || { echo "skin-goals: missing $input" >&2; return 1; }
  "$rigbake" bake "$input" -o "$out/$name.glb" --stats "$out/$name.stats.json" --influences "$influences" "${rom[@]}" "${extra[@]}" \
    >"$out/$name.log" 2>&1 || { echo "skin-goals: bake of $name failed (see $out/$name.log)" >&2; return 1; }
}
pids=()
for c in "${characters[@]}"; do
  # two at a time: the bake uses both cores for part of its work, the rest is serial
  while [ "$(jobs -rp | wc -l)" -ge 2 ]; do sleep 1; done
  bakeOne "$c" &
  pids+=($!)
done
status=0
for p in "${pids[@]}"; do wait "$p" || status=1; done
[ $status = 0 ] || exit 1
/usr/bin/env python3 "$repo/scripts/skin-goals.py" "$out"

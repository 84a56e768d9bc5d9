#!/usr/bin/env bash
# The main job on the built-in sample character: installs what is needed, builds rigbake, writes the
# procedural mannequin, resolves its landmarks, places the God of War muscle preset, bakes the
# muscle joints with 10 influences per vertex and the talk's bicep jiggle, and validates the result
# (out/report/report.html).
# Outputs land in out/ (override with RIGBAKE_OUT=dir).
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
out="${RIGBAKE_OUT:-$repo/out}"
bash "$repo/scripts/install-deps.sh"
bash "$repo/scripts/build.sh" release >/dev/null
rigbake="$repo/build/rigbake"
mkdir -p "$out"

"$rigbake" sample -o "$out/mannequin.glb"
"$rigbake" landmarks "$out/mannequin.glb"
"$rigbake" place "$out/mannequin.glb" -o "$out/muscles.json"
"$rigbake" bake "$out/mannequin.glb" --muscles "$out/muscles.json" --influences 10 --jiggle biceps \
  -o "$out/mannequin_baked.glb" --stats "$out/bake_stats.json" --packed-out "$out/mannequin_baked.rbpk"
"$rigbake" validate "$out/mannequin_baked.glb" --muscles "$out/muscles.json" --report "$out/report" --khronos

echo
echo "Outputs in $out:"
ls -l "$out"

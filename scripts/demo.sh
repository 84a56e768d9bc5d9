#!/usr/bin/env bash
# The main job on the built-in sample character: installs what is needed, builds rigbake, writes the
# procedural mannequin, resolves its landmarks, places the God of War muscle preset and bakes the
# muscle joints with 10 influences per vertex.
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
"$rigbake" bake "$out/mannequin.glb" --muscles "$out/muscles.json" --influences 10 \
  -o "$out/mannequin_baked.glb" --stats "$out/bake_stats.json" --packed-out "$out/mannequin_baked.rbpk"

echo
echo "Outputs in $out:"
ls -l "$out"

#!/usr/bin/env bash
# Bakes a fixed set of characters with a fixed set of options and compares every output's SHA-256
# with the ones recorded in tests/data/golden-bakes.sha256, so that a refactoring (issue 30: the app/
# layer, the error table, split functions) can show that it left every output byte-identical.
#
# Usage: scripts/golden-bakes.sh check|record [path/to/rigbake]
#   check  (the default; a ctest runs it) exits 1 naming each output that changed, or a missing one.
#   record rewrites the table: only after a change that is meant to change the outputs (a new fit,
#          a format change), in the same commit, saying why.
# The set: the built-in mannequin (runtime and sampled motion, 4/7/10 influences, milli and unorm16
# weights, jiggle with and without a hit, a forced naming map), CesiumMan (a real GLB) and the sample
# as VRM 0.x and 1.0 (spring bones). Outputs: GLB/VRM, stats JSON, packed weights, muscle JSON.
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
mode="${1:-check}"
rigbake="${2:-$repo/build/rigbake}"
table="$repo/tests/data/golden-bakes.sha256"
assets="${RIGBAKE_SHARED_ASSETS:-$repo/../shared/assets}"
case "$mode" in check|record) ;; *) echo "usage: scripts/golden-bakes.sh check|record [rigbake]" >&2; exit 2 ;; esac
[ -x "$rigbake" ] || { echo "golden-bakes: no rigbake binary at $rigbake (build it first)" >&2; exit 2; }
# As the C++ tests do (tests/test_support.h): a missing asset fails under CI=true, and is skipped (77,
# ctest's SKIP_RETURN_CODE here) elsewhere.
if [ ! -f "$assets/CesiumMan.glb" ]; then
  echo "golden-bakes: shared asset missing: $assets/CesiumMan.glb" >&2
  [ "${CI:-}" = true ] && exit 1
  exit 77
fi

work="$(mktemp -d "${TMPDIR:-/tmp}/rigbake-golden-XXXXXX")"
trap 'rm -rf "$work"' EXIT
cd "$work"
# Relative names only: the stats name their character and output file, so the table must not hold a
# temporary directory's name.
run() { "$rigbake" "$@" >/dev/null 2>"$work/last.err" || { echo "golden-bakes: rigbake $* failed:" >&2; cat "$work/last.err" >&2; exit 1; }; }

run sample -o sample.glb
run sample --vrm 0 -o sample0.vrm
run sample --vrm 1 -o sample1.vrm
cp "$assets/CesiumMan.glb" CesiumMan.glb
cat >hits.json <<'EOF'
{"hits": [{"clip": "ArmRaise", "time": 0.5, "direction": [0, 0, 1], "magnitude": 1.5, "joints": ["LeftBicep"], "why": "punch from behind"}]}
EOF

# name: the stem of every file one bake writes; then the bake's arguments.
bake() {
  local name="$1" input="$2" ext="$3"
  shift 3
  run bake "$input" -o "$name.$ext" --stats "$name.stats.json" --packed-out "$name.rbpk" --muscles-out "$name.muscles.json" "$@"
}
bake sample-runtime sample.glb glb
bake sample-sampled-10 sample.glb glb --influences 10 --muscle-motion sampled
bake sample-both-7-unorm16 sample.glb glb --influences 7 --muscle-motion both --gltf-weights unorm16 --helper-joints
bake sample-jiggle sample.glb glb --influences 4 --muscle-motion both --response keep --jiggle gow_examples
bake sample-jiggle-hit sample.glb glb --jiggle biceps --hits hits.json
bake sample-map-rom sample.glb glb --map gow --rom
bake cesium-runtime CesiumMan.glb glb --influences 10
bake cesium-sampled CesiumMan.glb glb --muscle-motion sampled --fps 30
bake vrm0-jiggle sample0.vrm vrm --jiggle biceps
bake vrm1-jiggle sample1.vrm vrm --jiggle biceps --helper-joints

rm -f last.err hits.json sample.glb sample0.vrm sample1.vrm CesiumMan.glb
sha256sum -- * | LC_ALL=C sort -k2 >"$work/now.sha256"
# Not part of the table: the temporary file it was written to.
sed -i '/ now\.sha256$/d' "$work/now.sha256"
if [ "$mode" = record ]; then
  cp "$work/now.sha256" "$table"
  echo "golden-bakes: recorded $(wc -l <"$table") outputs in $table" >&2
  exit 0
fi
[ -f "$table" ] || { echo "golden-bakes: no table at $table (run: scripts/golden-bakes.sh record)" >&2; exit 1; }
if ! diff <(cat "$table") "$work/now.sha256" >"$work/diff.txt"; then
  echo "golden-bakes: outputs differ from $table (< recorded, > now):" >&2
  cat "$work/diff.txt" >&2
  exit 1
fi
echo "golden-bakes: all $(wc -l <"$table") outputs byte-identical to the recorded ones" >&2

#!/usr/bin/env bash
# Builds the runtime (runtime/*.cpp, the C API of runtime/rigbake_runtime.h) as WebAssembly with
# Debian's emscripten, the way meshoptimizer ships its decoders: one standalone .wasm (no emscripten JS
# glue; it imports two functions, which runtime/js/rigbake_runtime.mjs gives) beside the ES module that
# instantiates it. Output: build/wasm/rigbake_runtime.wasm and build/wasm/rigbake_runtime.mjs.
# Usage: scripts/build-wasm.sh [output-dir]. Idempotent: returns at once when the sources are unchanged.
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
out="${1:-$repo/build/wasm}"
if ! command -v emcc >/dev/null 2>&1; then
  echo "build-wasm: emcc is not on PATH (Debian package emscripten: scripts/install-deps.sh)" >&2
  exit 1
fi
mkdir -p "$out"
stamp="$(cd "$repo" && cat runtime/*.cpp runtime/*.h runtime/js/rigbake_runtime.mjs scripts/build-wasm.sh | sha256sum | cut -d' ' -f1)"
if [ -f "$out/rigbake_runtime.wasm" ] && [ -f "$out/stamp" ] && [ "$(cat "$out/stamp")" = "$stamp" ]; then
  echo "$out"
  exit 0
fi
exports=_malloc,_free
for f in $(grep -o 'rigbake_[a-z_]*(' "$repo/runtime/rigbake_runtime.h" | tr -d '(' | sort -u); do exports="$exports,_$f"; done
# -O3 and -msimd128: the muscle rig's lane loops (runtime/muscle_rig.cpp) vectorize to wasm SIMD as they
# do to SSE2 natively; -fno-math-errno -fno-trapping-math as in CMakeLists.txt (they change no result).
# STANDALONE_WASM: a reactor with _initialize, no JS glue. Memory grows on demand (a rig's size is the file's).
emcc -O3 -std=c++17 -msimd128 -fno-math-errno -fno-trapping-math -Wall -Wextra -Werror -I"$repo" \
  --no-entry -sSTANDALONE_WASM -sALLOW_MEMORY_GROWTH=1 -sEXPORTED_FUNCTIONS="$exports" \
  -o "$out/rigbake_runtime.wasm" "$repo"/runtime/*.cpp
cp "$repo/runtime/js/rigbake_runtime.mjs" "$out/rigbake_runtime.mjs"
echo "$stamp" >"$out/stamp"
echo "$out"

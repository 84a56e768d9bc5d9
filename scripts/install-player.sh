#!/usr/bin/env bash
# Installs the rigbake player (player/, docs/view.md) into .tools/player/ (gitignored; or the directory
# given as the first argument): three.js and esbuild at the versions player/package-lock.json pins,
# installed with `npm ci`, then esbuild bundles player/src/main.js, the rigbake-three plugin
# (player/plugin/), the WebAssembly runtime (scripts/build-wasm.sh: its ES module, and its .wasm as
# bytes) and three.js into ONE classic script, rigbake-player.js, which `rigbake view` copies beside the
# page it writes. One classic script because a page opened from file:// may not import ES modules or
# fetch() in Chromium; nothing is fetched when the page runs. Beside it, rigbake-draco.js: three's
# Draco decoder files (examples/jsm/libs/draco/gltf) in one classic script, which `rigbake view` adds
# to the page of a Draco-compressed file only.
#
# Idempotent: returns at once when the bundle was built from the same lock file and sources (a stamp
# of their SHA-256 sums). Needs node and npm on PATH, the npm registry (for `npm ci` only) and emcc
# (scripts/build-wasm.sh).
set -euo pipefail

REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
SOURCE="$REPO/player"
TARGET="$(mkdir -p "${1:-$REPO/.tools/player}" && cd "${1:-$REPO/.tools/player}" && pwd)"
BUNDLE="$TARGET/rigbake-player.js"
STAMP="$TARGET/stamp"

if ! command -v node >/dev/null 2>&1; then
  echo "install-player: node is not on PATH" >&2
  exit 1
fi
DRACO="$TARGET/rigbake-draco.js"
WASM_DIR="$(bash "$REPO/scripts/build-wasm.sh")"
stamp="$(cd "$SOURCE" && cat package.json package-lock.json $(find src plugin -type f \( -name '*.js' -o -name '*.json' \) | LC_ALL=C sort) \
  "$WASM_DIR/rigbake_runtime.wasm" "$REPO/runtime/js/rigbake_runtime.mjs" | sha256sum | cut -d' ' -f1)"
if [ -f "$BUNDLE" ] && [ -f "$DRACO" ] && [ -f "$STAMP" ] && [ "$(cat "$STAMP")" = "$stamp" ]; then
  echo "rigbake player already built in $TARGET ($(wc -c <"$BUNDLE") bytes)"
  exit 0
fi
mkdir -p "$TARGET"
if ! cmp -s "$SOURCE/package-lock.json" "$TARGET/package-lock.json" || [ ! -d "$TARGET/node_modules/three" ]; then
  if ! command -v npm >/dev/null 2>&1; then
    echo "install-player: npm is not on PATH" >&2
    exit 1
  fi
  cp "$SOURCE/package.json" "$SOURCE/package-lock.json" "$TARGET/"
  # --ignore-scripts: esbuild's postinstall only checks its platform binary, which npm installs as the
  # optional package @esbuild/linux-x64; the esbuild command finds it without the script.
  (cd "$TARGET" && npm ci --ignore-scripts --no-audit --no-fund >/dev/null)
fi
# The bundle: an IIFE (a classic script defining window.RigbakePlayer), minified, three.js's licence
# comment kept at the end. esbuild's output depends only on its version, the flags and the inputs, so
# the same sources give the same bytes (and `rigbake view` the same page).
# The .wasm goes in as a Uint8Array (esbuild's binary loader: base64 in the script, decoded at load);
# import.meta.url, which an IIFE has not, is a fixed file URL: three's DRACOLoader builds its default
# decoder URLs from it when the bundle loads, and neither they nor the runtime module's default .wasm
# URL are fetched (the page hands both the bytes).
NODE_PATH="$TARGET/node_modules" "$TARGET/node_modules/.bin/esbuild" "$SOURCE/src/main.js" \
  --bundle --format=iife --platform=browser --target=es2020 --minify --legal-comments=eof \
  --loader:.wasm=binary --alias:rigbake-runtime-wasm="$WASM_DIR/rigbake_runtime.wasm" \
  --define:import.meta.url='"file:///rigbake-player.js"' --log-level=warning --outfile="$BUNDLE.tmp"
mv "$BUNDLE.tmp" "$BUNDLE"
# Draco's wasm decoder and its wrapper as window.RIGBAKE_DRACO = {wrapper: "<js>", wasm: "<base64>"}.
node -e '
const fs = require("fs");
const dir = process.argv[1] + "/three/examples/jsm/libs/draco/gltf/";
const wrapper = fs.readFileSync(dir + "draco_wasm_wrapper.js", "utf8");
const wasm = fs.readFileSync(dir + "draco_decoder.wasm").toString("base64");
// "<" escaped so that the text is safe inside a page too.
const text = JSON.stringify(wrapper).replace(/</g, "\\u003c");
fs.writeFileSync(process.argv[2], "// three.js Draco decoder (draco_wasm_wrapper.js, draco_decoder.wasm; Apache-2.0, Google), for a file:// page.\nwindow.RIGBAKE_DRACO = {wrapper: " + text + ", wasm: \"" + wasm + "\"};\n");
' "$TARGET/node_modules" "$DRACO.tmp"
mv "$DRACO.tmp" "$DRACO"
echo "$stamp" >"$STAMP"
echo "rigbake player built: $BUNDLE ($(wc -c <"$BUNDLE") bytes; three $(node -p "require(process.argv[1]).version" "$TARGET/node_modules/three/package.json"))"

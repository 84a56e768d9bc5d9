#!/usr/bin/env bash
# Installs the rigbake player (player/, docs/view.md) into .tools/player/ (gitignored): three.js and
# esbuild at the versions player/package-lock.json pins, installed with `npm ci`, then esbuild bundles
# player/src/main.js and three.js into ONE classic script, .tools/player/rigbake-player.js, which
# `rigbake view` copies beside the page it writes. One classic script because a page opened from
# file:// may not import ES modules or fetch() in Chromium; nothing is fetched when the page runs.
#
# Idempotent: returns at once when the bundle was built from the same lock file and sources (a stamp
# of their SHA-256 sums). Needs node and npm on PATH and the npm registry (for `npm ci` only).
set -euo pipefail

REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
SOURCE="$REPO/player"
TARGET="$REPO/.tools/player"
BUNDLE="$TARGET/rigbake-player.js"
STAMP="$TARGET/stamp"

if ! command -v node >/dev/null 2>&1; then
  echo "install-player: node is not on PATH" >&2
  exit 1
fi
stamp="$(cd "$SOURCE" && cat package.json package-lock.json $(find src -type f -name '*.js' | LC_ALL=C sort) | sha256sum | cut -d' ' -f1)"
if [ -f "$BUNDLE" ] && [ -f "$STAMP" ] && [ "$(cat "$STAMP")" = "$stamp" ]; then
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
NODE_PATH="$TARGET/node_modules" "$TARGET/node_modules/.bin/esbuild" "$SOURCE/src/main.js" \
  --bundle --format=iife --platform=browser --target=es2020 --minify --legal-comments=eof \
  --log-level=warning --outfile="$BUNDLE.tmp"
mv "$BUNDLE.tmp" "$BUNDLE"
echo "$stamp" >"$STAMP"
echo "rigbake player built: $BUNDLE ($(wc -c <"$BUNDLE") bytes; three $(node -p "require(process.argv[1]).version" "$TARGET/node_modules/three/package.json"))"

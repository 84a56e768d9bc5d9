#!/usr/bin/env bash
# Installs the three-vrm check (tests/three_vrm/, tests/vrm_three_test.cpp) into .tools/three-vrm-check/
# (gitignored): three.js, @pixiv/three-vrm and esbuild at the versions tests/three_vrm/package-lock.json
# pins, installed with `npm ci`, then esbuild bundles tests/three_vrm/check.js with them into ONE classic
# script, .tools/three-vrm-check/three-vrm-check.js, that a test page opened from file:// can load.
#
# Idempotent: returns at once when the bundle was built from the same lock file and sources. Needs node
# and npm on PATH and the npm registry (for `npm ci` only).
set -euo pipefail

REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
SOURCE="$REPO/tests/three_vrm"
TARGET="$REPO/.tools/three-vrm-check"
BUNDLE="$TARGET/three-vrm-check.js"
STAMP="$TARGET/stamp"

if ! command -v node >/dev/null 2>&1; then
  echo "install-three-vrm-check: node is not on PATH" >&2
  exit 1
fi
stamp="$(cd "$SOURCE" && cat package.json package-lock.json check.js | sha256sum | cut -d' ' -f1)"
if [ -f "$BUNDLE" ] && [ -f "$STAMP" ] && [ "$(cat "$STAMP")" = "$stamp" ]; then
  echo "three-vrm check already built in $TARGET"
  exit 0
fi
mkdir -p "$TARGET"
if ! cmp -s "$SOURCE/package-lock.json" "$TARGET/package-lock.json" || [ ! -d "$TARGET/node_modules/@pixiv/three-vrm" ]; then
  if ! command -v npm >/dev/null 2>&1; then
    echo "install-three-vrm-check: npm is not on PATH" >&2
    exit 1
  fi
  cp "$SOURCE/package.json" "$SOURCE/package-lock.json" "$TARGET/"
  # --ignore-scripts: esbuild finds its platform binary (the optional @esbuild/linux-x64) without it.
  (cd "$TARGET" && npm ci --ignore-scripts --no-audit --no-fund >/dev/null)
fi
NODE_PATH="$TARGET/node_modules" "$TARGET/node_modules/.bin/esbuild" "$SOURCE/check.js" \
  --bundle --format=iife --platform=browser --target=es2020 --minify --legal-comments=eof \
  --log-level=warning --outfile="$BUNDLE.tmp"
mv "$BUNDLE.tmp" "$BUNDLE"
echo "$stamp" >"$STAMP"
echo "three-vrm check built: $BUNDLE (three-vrm $(node -p "require(process.argv[1]).version" "$TARGET/node_modules/@pixiv/three-vrm/package.json"))"

#!/usr/bin/env bash
# Installs glTF-Transform's CLI (npm @gltf-transform/cli) into .tools/gltf-transform/ (gitignored) for
# the tests that make Draco-compressed (KHR_draco_mesh_compression) copies of the shared characters.
# The whole dependency tree is pinned by scripts/gltf-transform/package-lock.json and installed with
# `npm ci`, so every machine encodes with the same draco3dgltf. Idempotent: returns at once when that
# lock file is already installed. Needs node and npm on PATH and the npm registry.
set -euo pipefail

REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
SOURCE="$REPO/scripts/gltf-transform"
TARGET="$REPO/.tools/gltf-transform"
BINARY="$TARGET/node_modules/.bin/gltf-transform"

if ! command -v node >/dev/null 2>&1; then
  echo "install-gltf-transform: node is not on PATH" >&2
  exit 1
fi
if [ -x "$BINARY" ] && cmp -s "$SOURCE/package-lock.json" "$TARGET/package-lock.json"; then
  echo "gltf-transform $(node -p "require(process.argv[1]).version" "$TARGET/node_modules/@gltf-transform/cli/package.json") already installed in $TARGET"
  exit 0
fi
if ! command -v npm >/dev/null 2>&1; then
  echo "install-gltf-transform: npm is not on PATH" >&2
  exit 1
fi
mkdir -p "$TARGET"
cp "$SOURCE/package.json" "$SOURCE/package-lock.json" "$TARGET/"
# --ignore-scripts: sharp's install script only looks for its prebuilt binary (shipped as an npm
# package) and would build libvips from source without it; the draco command needs neither.
(cd "$TARGET" && npm ci --ignore-scripts --no-audit --no-fund >/dev/null)
"$BINARY" --version >/dev/null
echo "gltf-transform $(node -p "require(process.argv[1]).version" "$TARGET/node_modules/@gltf-transform/cli/package.json") installed in $TARGET"

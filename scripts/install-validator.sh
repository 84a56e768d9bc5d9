#!/usr/bin/env bash
# Installs the Khronos glTF-Validator (npm package gltf-validator, compiled from Dart to JS) into
# .tools/ (gitignored) for scripts/gltf-validate.js and the tests. Idempotent: returns at once when the
# pinned version is already there. Needs node and npm on PATH and the npm registry.
set -euo pipefail

REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
VERSION="2.0.0-dev.3.10"
PACKAGE_JSON="$REPO/.tools/node_modules/gltf-validator/package.json"

if ! command -v node >/dev/null 2>&1; then
  echo "install-validator: node is not on PATH" >&2
  exit 1
fi
if [ -f "$PACKAGE_JSON" ] &&
   [ "$(node -p "require(process.argv[1]).version" "$PACKAGE_JSON")" = "$VERSION" ]; then
  echo "gltf-validator $VERSION already installed in $REPO/.tools"
  exit 0
fi
if ! command -v npm >/dev/null 2>&1; then
  echo "install-validator: npm is not on PATH" >&2
  exit 1
fi
npm install --prefix "$REPO/.tools" --save-exact --no-audit --no-fund "gltf-validator@$VERSION"
node -e "require(process.argv[1])" "$REPO/.tools/node_modules/gltf-validator" >/dev/null
echo "gltf-validator $VERSION installed in $REPO/.tools"

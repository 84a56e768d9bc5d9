#!/usr/bin/env bash
# Installs everything rigbake needs on Debian: the packages in scripts/deps-apt.txt and the npm tools
# (Khronos glTF-Validator, glTF-Transform) under .tools/. Fast when all of it is already there.
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"

as_root() {
  if [ "$(id -u)" -eq 0 ]; then "$@"; else sudo "$@"; fi
}

mapfile -t packages < <(grep -v -e '^#' -e '^[[:space:]]*$' "$repo/scripts/deps-apt.txt")
missing=()
for package in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed" || missing+=("$package")
done
if [ "${#missing[@]}" -gt 0 ]; then
  echo "rigbake: installing Debian packages: ${missing[*]}" >&2
  as_root apt-get update -qq
  as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

# Node.js and npm run the Khronos validator. Machines that already have them (possibly from another
# vendor's packages, which conflict with Debian's npm) keep theirs.
if ! command -v node >/dev/null 2>&1 || ! command -v npm >/dev/null 2>&1; then
  echo "rigbake: installing Debian packages: nodejs npm" >&2
  as_root apt-get update -qq
  as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends nodejs npm >/dev/null
fi

bash "$repo/scripts/install-validator.sh"
bash "$repo/scripts/install-gltf-transform.sh"
bash "$repo/scripts/install-player.sh"
# three-vrm 3.x for tests/vrm_convert_test.cpp (a VRM 0.x -> 1.0 bake played in headless Chromium).
bash "$repo/scripts/install-three-vrm-check.sh"
# rigbake's Blender add-on, installed and enabled in the Blender on PATH (docs/blender.md).
bash "$repo/scripts/install-blender-addon.sh"

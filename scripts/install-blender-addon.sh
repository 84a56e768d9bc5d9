#!/usr/bin/env bash
# Installs rigbake's Blender add-on (blender/rigbake_blender, docs/blender.md) into the user add-on
# folder of the Blender on PATH and enables it in that user's preferences, so that File > Import >
# glTF 2.0 of a rigbake bake builds the live muscle rig. Idempotent: returns at once when the
# installed copy is this repository's. The tests load the add-on from the repository itself, so they
# never test a stale copy; scripts/check-tools.sh checks the installed copy is this one.
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
source_dir="$repo/blender/rigbake_blender"

if ! command -v blender >/dev/null 2>&1; then
  echo "install-blender-addon: blender is not on PATH (Debian package blender)" >&2
  exit 1
fi
# Blender says where its user add-ons live (it depends on the version and $BLENDER_USER_SCRIPTS).
addons="$(blender --background --factory-startup --python-expr \
  'import bpy; print("RIGBAKE_ADDONS " + bpy.utils.user_resource("SCRIPTS", path="addons", create=True))' 2>/dev/null |
  sed -n 's/^RIGBAKE_ADDONS //p')"
if [ -z "$addons" ]; then
  echo "install-blender-addon: blender did not report its user add-on folder" >&2
  exit 1
fi
target="$addons/rigbake_blender"
if [ -d "$target" ] && diff -rq --exclude=__pycache__ "$source_dir" "$target" >/dev/null 2>&1 && [ -f "$addons/.rigbake_blender_enabled" ]; then
  echo "rigbake Blender add-on already installed in $target"
  exit 0
fi
rm -rf "$target.tmp" "$addons/.rigbake_blender_enabled"
mkdir -p "$target.tmp"
(cd "$source_dir" && find . -name __pycache__ -prune -o -type f -name '*.py' -print | while read -r file; do
  mkdir -p "$target.tmp/$(dirname "$file")"
  cp "$file" "$target.tmp/$file"
done)
rm -rf "$target"
mv "$target.tmp" "$target"
# Enable it and save the preferences (no --factory-startup here: keep the user's other settings).
output="$(blender --background --python-exit-code 1 --python-expr '
import addon_utils, bpy
addon_utils.enable("rigbake_blender", default_set=True, handle_error=None)
assert "rigbake_blender" in bpy.context.preferences.addons, "not enabled"
bpy.context.preferences.use_preferences_save = True
bpy.ops.wm.save_userpref()
print("RIGBAKE_ENABLED")
' 2>&1)" || true
case "$output" in
  *RIGBAKE_ENABLED*) touch "$addons/.rigbake_blender_enabled" ;;
  *) echo "install-blender-addon: blender could not enable the add-on: $(printf '%s\n' "$output" | grep -v '^$' | tail -n 1)" >&2
     exit 1 ;;
esac
echo "rigbake Blender add-on $(sed -n 's/.*"version": (\([0-9]*\), \([0-9]*\), \([0-9]*\)).*/\1.\2.\3/p' "$source_dir/__init__.py") installed and enabled in $target"

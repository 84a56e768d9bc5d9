#!/usr/bin/env bash
# Checks, before anything is built, that every outside program the test suite starts runs and has what
# it needs: a test that finds a program missing half-way through a 10-minute suite says less than one
# line here naming the Debian package (or the install script) that brings it. scripts/test.sh runs
# this right after scripts/install-deps.sh; run it alone to see what a machine lacks.
#
# What the tests start, and what provides it (scripts/deps-apt.txt installs the Debian packages):
#   blender            blender (+ blender-data: the io_scene_gltf2 add-on; python3-numpy: its importer
#                      imports numpy, and neither blender nor blender-data depends on or recommends it;
#                      rigbake's own add-on: scripts/install-blender-addon.sh)
#   chromium           chromium (fonts come through libfontconfig1 -> fontconfig-config -> fonts-dejavu-core)
#   node               nodejs (any vendor's) and the npm tools in .tools/ (scripts/install-validator.sh,
#                      scripts/install-gltf-transform.sh)
#   glslangValidator   glslang-tools
#   /usr/bin/python3   python3 + python3-jsonschema (tests/check_preset_schemas.py); python3 for the XML check;
#                      its pty module for the terminal progress test (cli_bake_test)
#   ninja              ninja-build (cli_build_test runs the emitted Ninja file)
#   gltfpack           gltfpack (compressed inputs: EXT_meshopt_compression, KHR_mesh_quantization)
#   emcc               emscripten (scripts/build-wasm.sh: the runtime as WebAssembly, tests/runtime_c_api_test.cpp)
#   clang++            clang + libclang-rt-dev (libFuzzer and the sanitizer runtimes): scripts/fuzz.sh
#   gltf-transform     npm @gltf-transform/cli (compressed inputs: KHR_draco_mesh_compression; optimize with
#                      rigbake's config, gltf-transform/, and without it: tests/rig_pipelines_test.cpp)
#
# Prints one line per problem on stderr and exits 1 when there is any; prints one summary line and
# exits 0 otherwise.
set -uo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
problems=0

missing() {
  echo "check-tools: $*" >&2
  problems=$((problems + 1))
}

have() { command -v "$1" >/dev/null 2>&1; }

# One triangle, buffer embedded: small enough to write here, real enough for the validator, gltfpack
# and glTF-Transform to read, process and write.
cat >"$work/triangle.gltf" <<'EOF'
{"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],
 "meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],
 "accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}],
 "bufferViews":[{"buffer":0,"byteLength":36}],
 "buffers":[{"byteLength":36,"uri":"data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA"}]}
EOF

# Blender: starts headless, its Python has numpy, and the glTF add-on is enabled with its importer.
if ! have blender; then
  missing "blender is not on PATH (Debian package blender)"
else
  blender_probe='
import importlib, sys
def report(what):
    print("RIGBAKE_MISSING " + what)
try:
    import numpy
except ImportError:
    report("numpy")
else:
    import addon_utils, bpy
    if not addon_utils.check("io_scene_gltf2")[1] or not hasattr(bpy.types, "IMPORT_SCENE_OT_gltf"):
        report("io_scene_gltf2")
    else:
        try:
            importlib.import_module("io_scene_gltf2.blender.imp.gltf2_blender_gltf")
            print("RIGBAKE_OK")
            print("RIGBAKE_ADDONS " + bpy.utils.user_resource("SCRIPTS", path="addons"))
        except ImportError as error:
            report("module " + str(error.name))
'
  output="$(timeout 120 blender --background --factory-startup --python-exit-code 1 --python-expr "$blender_probe" 2>&1)"
  case "$output" in
    *"RIGBAKE_OK"*) ;;
    *"RIGBAKE_MISSING numpy"*) missing "blender's Python cannot import numpy (Debian package python3-numpy)" ;;
    *"RIGBAKE_MISSING io_scene_gltf2"*) missing "blender has no enabled glTF add-on io_scene_gltf2 (Debian package blender-data)" ;;
    *"RIGBAKE_MISSING module "*)
      module="$(printf '%s\n' "$output" | sed -n 's/.*RIGBAKE_MISSING module //p' | head -n 1)"
      missing "blender's glTF importer cannot import Python module $module (apt-file search for it, add it to scripts/deps-apt.txt)" ;;
    *) missing "blender --background does not start: $(printf '%s\n' "$output" | grep -v '^$' | tail -n 1) (Debian package blender)" ;;
  esac
  # rigbake's add-on, installed from this repository (the tests load the repository's own copy).
  addons="$(printf '%s\n' "$output" | sed -n 's/^RIGBAKE_ADDONS //p' | head -n 1)"
  if [ -n "$addons" ] && ! diff -rq --exclude=__pycache__ "$repo/blender/rigbake_blender" "$addons/rigbake_blender" >/dev/null 2>&1; then
    missing "the rigbake Blender add-on in $addons is missing or not this repository's (run scripts/install-blender-addon.sh)"
  fi
fi

# Chromium: starts headless with the flags the tests use, a fresh profile and no network, and renders.
chromium_binary=""
for name in chromium chromium-browser google-chrome; do
  if have "$name"; then chromium_binary="$name"; break; fi
done
if [ -z "$chromium_binary" ]; then
  missing "chromium is not on PATH (Debian package chromium)"
else
  printf '<!doctype html><title>t</title><p id="probe">rigbake</p><script>document.getElementById("probe").textContent="rendered"</script>\n' \
    >"$work/probe.html"
  dom="$(timeout 120 "$chromium_binary" --headless --no-sandbox --disable-gpu --disable-quic --no-first-run \
    --disable-background-networking --disable-component-update --disable-sync --disable-dev-shm-usage \
    --user-data-dir="$work/chromium-profile" --dump-dom "file://$work/probe.html" 2>"$work/chromium.log")"
  case "$dom" in
    *'<p id="probe">rendered</p>'*) ;;
    *) missing "$chromium_binary --headless does not render a page: $(grep -v '^$' "$work/chromium.log" | tail -n 1) (Debian package chromium)" ;;
  esac
fi

# Node and the Khronos glTF-Validator: validates the triangle with 0 errors.
if ! have node; then
  missing "node is not on PATH (Debian package nodejs; scripts/install-deps.sh installs it)"
else
  report="$(timeout 120 node "$repo/scripts/gltf-validate.js" "$work/triangle.gltf" 2>&1)"
  case "$report" in
    *'"numErrors":0,'*) ;;
    *)
      last="$(printf '%s\n' "$report" | tail -n 1)"
      case "$last" in *install-validator*) hint="" ;; *) hint=" (run scripts/install-validator.sh)" ;; esac
      missing "node cannot run the Khronos glTF-Validator: $last$hint" ;;
  esac
  # glTF-Transform writes a Draco-compressed copy of the triangle (its draco3dgltf encoder runs in node).
  gltf_transform="${RIGBAKE_GLTF_TRANSFORM:-$repo/.tools/gltf-transform/node_modules/.bin/gltf-transform}"
  if [ ! -x "$gltf_transform" ]; then
    missing "gltf-transform is not installed at $gltf_transform (run scripts/install-gltf-transform.sh)"
  elif ! timeout 120 "$gltf_transform" draco "$work/triangle.gltf" "$work/triangle-draco.glb" >"$work/gltf-transform.log" 2>&1 ||
       ! grep -q KHR_draco_mesh_compression "$work/triangle-draco.glb"; then
    missing "gltf-transform draco fails: $(grep -v '^$' "$work/gltf-transform.log" | tail -n 1) (run scripts/install-gltf-transform.sh)"
  # ... and optimizes it with rigbake's config (gltf-transform/rigbake.config.mjs loads the CLI's own
  # @gltf-transform/core; optimize imports sharp and the meshopt encoder), as tests/rig_pipelines_test.cpp does.
  elif ! timeout 120 "$gltf_transform" optimize "$work/triangle.gltf" "$work/triangle-optimized.glb" \
         --config "$repo/gltf-transform/rigbake.config.mjs" >"$work/gltf-transform.log" 2>&1 ||
       ! grep -q EXT_meshopt_compression "$work/triangle-optimized.glb"; then
    missing "gltf-transform optimize --config gltf-transform/rigbake.config.mjs fails: $( (grep -m 1 'rror' "$work/gltf-transform.log" || tail -n 1 "$work/gltf-transform.log") | cut -c 1-200) (run scripts/install-gltf-transform.sh)"
  fi
  # three-vrm's bundle, which tests/vrm_convert_test.cpp loads into headless Chromium.
  if [ ! -s "$repo/.tools/three-vrm-check/three-vrm-check.js" ]; then
    missing "the three-vrm check bundle .tools/three-vrm-check/three-vrm-check.js is missing (run scripts/install-three-vrm-check.sh)"
  fi
fi

# gltfpack: writes an EXT_meshopt_compression copy of the triangle.
if ! have gltfpack; then
  missing "gltfpack is not on PATH (Debian package gltfpack)"
elif ! timeout 60 gltfpack -i "$work/triangle.gltf" -o "$work/triangle-meshopt.glb" -c >"$work/gltfpack.log" 2>&1 ||
     ! grep -q EXT_meshopt_compression "$work/triangle-meshopt.glb"; then
  missing "gltfpack -c fails: $(grep -v '^$' "$work/gltfpack.log" | tail -n 1) (Debian package gltfpack)"
fi

# glslangValidator compiles a trivial shader.
if ! have glslangValidator; then
  missing "glslangValidator is not on PATH (Debian package glslang-tools)"
else
  printf '#version 450\nvoid main() {}\n' >"$work/probe.vert"
  if ! glslangValidator "$work/probe.vert" >"$work/glslang.log" 2>&1; then
    missing "glslangValidator cannot compile a shader: $(tail -n 1 "$work/glslang.log") (Debian package glslang-tools)"
  fi
fi

# Debian's Python with jsonschema (the preset schema test runs /usr/bin/python3 by path).
if [ ! -x /usr/bin/python3 ]; then
  missing "/usr/bin/python3 is missing (Debian package python3)"
elif ! /usr/bin/python3 -c 'import jsonschema; jsonschema.Draft202012Validator' >/dev/null 2>&1; then
  missing "/usr/bin/python3 cannot import jsonschema with Draft 2020-12 (Debian package python3-jsonschema)"
fi
if ! python3 -c 'import xml.etree.ElementTree' >/dev/null 2>&1; then
  missing "python3 on PATH cannot parse XML (Debian package python3)"
fi
# The progress test runs a bake on a pseudo-terminal (Python's pty module, standard library).
if ! /usr/bin/python3 -c 'import pty, os; pid, fd = pty.fork(); os._exit(0) if pid == 0 else os.waitpid(pid, 0)' >/dev/null 2>&1; then
  missing "/usr/bin/python3 cannot open a pseudo-terminal (pty module; Debian package python3, and /dev/pts mounted)"
fi

# clang links a libFuzzer target with the sanitizers (scripts/fuzz.sh builds fuzz/ the same way).
if ! have clang++; then
  missing "clang++ is not on PATH (Debian package clang)"
else
  printf '#include <cstddef>\n#include <cstdint>\nextern "C" int LLVMFuzzerTestOneInput(const std::uint8_t*, std::size_t) { return 0; }\n' \
    >"$work/probe_fuzz.cpp"
  if ! clang++ -fsanitize=fuzzer,address,undefined "$work/probe_fuzz.cpp" -o "$work/probe_fuzz" >"$work/clang.log" 2>&1 ||
     ! "$work/probe_fuzz" -runs=1 >>"$work/clang.log" 2>&1; then
    missing "clang++ cannot build a libFuzzer target: $(grep -v '^$' "$work/clang.log" | tail -n 1) (Debian package libclang-rt-dev)"
  fi
fi

if ! have ninja; then
  missing "ninja is not on PATH (Debian package ninja-build)"
fi

# emcc compiles a trivial C file to a standalone WebAssembly module (its first run builds its system
# library cache, under the user's home).
if ! have emcc; then
  missing "emcc is not on PATH (Debian package emscripten)"
else
  echo 'int twice(int x) { return 2 * x; }' >"$work/probe.c"
  if ! emcc -O2 --no-entry -sSTANDALONE_WASM -sEXPORTED_FUNCTIONS=_twice -o "$work/probe.wasm" "$work/probe.c" >"$work/emcc.log" 2>&1; then
    missing "emcc cannot build WebAssembly: $(tail -n 1 "$work/emcc.log") (Debian package emscripten)"
  fi
fi

if [ "$problems" -gt 0 ]; then
  exit 1
fi
echo "check-tools: blender, chromium, node + gltf-validator + gltf-transform, gltfpack, glslang, python3, clang + libFuzzer, ninja, emcc all run" >&2

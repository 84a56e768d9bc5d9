#!/usr/bin/env bash
# The test command: installs what is needed, builds with warnings as errors, runs every test, runs the
# whole suite again under AddressSanitizer + UndefinedBehaviorSanitizer, then fuzzes the readers for a
# bounded time (scripts/fuzz.sh).
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$repo/scripts/install-deps.sh"
# Every outside program a test starts must run and have what it needs before the build starts: one
# line naming the missing package beats a test failing ten minutes in.
bash "$repo/scripts/check-tools.sh"

echo "== release build, all tests (at ${SECONDS} s)" >&2
bash "$repo/scripts/build.sh" release >/dev/null
# The runtime as WebAssembly, for the node test that compares it with the native library (seconds
# when its sources are unchanged).
bash "$repo/scripts/build-wasm.sh" >/dev/null
# The test binary's own bakes get the allocator setting the CLI gives itself (cli/huge_pages.cpp), and
# the CLI runs it starts need not restart for it.
echo "== release tests (at ${SECONDS} s)" >&2
GLIBC_TUNABLES="${GLIBC_TUNABLES:+$GLIBC_TUNABLES:}glibc.malloc.hugetlb=1:glibc.malloc.arena_max=1:glibc.malloc.mmap_threshold=8388608" \
  ctest --test-dir "$repo/build" --output-on-failure --parallel "$(nproc)" --timeout 600

# Tests that only hand written files to outside programs (Blender, the Khronos validator, Chromium,
# glslang) ran above; under the sanitizers they would time those programs, not rigbake. The 100k-vertex
# cases run the same code as the 12k ones, ten times over. The C program and Python ctypes case loads the
# runtime's shared library into /usr/bin/python3, which an AddressSanitizer-built library cannot enter
# (the ASan runtime must come first); the in-process C API cases run under the sanitizers.
# The sanitizer pass needs each code path once, not each character's figures (the release pass
# checked those on every asset): it runs every test on the sample (GLB and both VRMs), CesiumMan (GLB,
# bind pose = rest pose) and the KayKit mannequin (.gltf with external files, bind pose != rest pose).
# The FBX build manifest (five characters) and glTF-Transform's optimize run code the other FBX, build
# and pipeline cases run once already; under the sanitizers they took a minute and a half.
# Likewise the build cases that rebuild the same characters to test stamps, shards, the ninja graph and
# the weight precision (the build code runs under the sanitizers in the other build cases), the
# gltfpack/glTF-Transform stripping case (outside programs, then validate and view as elsewhere), and
# the runtime-against-sampled comparison (the runtime runs in the C API cases): 160 s of the pass's
# 875 s of test time. The two doc evaluators and the WebAssembly-in-node comparison time node running
# JavaScript and WebAssembly against bakes the other cases make (50 s of the pass under load). The
# suite-outputs fixture (the Khronos validator over every model written) ran in the release pass.
# The fit's smoothness term runs under the sanitizers in the build case that sets fit_smoothness; its
# Male_Casual case (three FBX bakes, 20 s under the sanitizers) measures figures the release pass checks.
# So does the occupied fit (the same build case sets fit_volume; the boxes test its exposure): its
# Cyberpunk case is four bakes, 20 s under the sanitizers. And the roughness cap (the build case sets
# fit_roughness_cap): its Cyberpunk and Male_Casual case is four bakes, 20 s. The three skin-figure cases
# that bake the mannequin again turned and moved, scaled to centimetres and hung under a new root check
# that the figures do not depend on the scene's unit or placement, arithmetic the release pass checks;
# their bakes run the figures' code that every other --stats bake here runs (32 s under the sanitizers).
# The same holds for the Cowboy turned and hung under one new root (three FBX bakes), for the mannequin
# with its limbs hung as a Biped hangs them and with its vertices in another order (four bakes, 12 s;
# the re-hanging runs here in the landmarks CLI case), for CesiumMan and Male Casual with their vertices
# in another order (four bakes; the cap loops' pairing runs here in the skin-volume sheet case and in
# every CesiumMan bake), and for validate --input on Female Casual (an FBX bake and two validations,
# 10 s; the mismatch case runs --input on the mannequin), and for Male Casual's hip, the place and the cut's
# share of its loss (an FBX bake and a validation; the places and the cut run in every --stats bake here). The every-frame region fit on Female Casual
# (three FBX bakes) and on the mannequin and CesiumMan split into one mesh per joint measures figures;
# its code runs here in the build case whose "regions" character sets fit_regions. So does the body row's
# case on Male and Female Casual (four FBX bakes): every bake here runs that row.
echo "== AddressSanitizer + UBSan build, every test of rigbake's own code (at ${SECONDS} s)" >&2
# The test binary and the CLI it runs: the benchmarks are not tests.
bash "$repo/scripts/build.sh" asan rigbake_tests rigbake >/dev/null
echo "== sanitizer tests (at ${SECONDS} s)" >&2
RIGBAKE_TEST_ASSETS="CesiumMan.glb,KayKit_Mannequin/manny_med_mod.gltf" \
ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
  ctest --test-dir "$repo/build-asan" --output-on-failure --parallel "$(nproc)" --timeout 900 --fixture-exclude-any suite_outputs \
  --exclude-regex "Blender|Python ctypes|Khronos|doc evaluator:|WebAssembly build in node|suite_outputs_folder|Chromium|GLSL|100k vertices|byte-identical|1, 2 and 3 threads|--threads|a manifest of the three FBX characters|glTF-Transform optimize with rigbake's config|cli build: (gltf_weights|--emit-ninja writes|outputs replaced after|--shard|a manifest's .rom.)|gltfpack and glTF-Transform copy strip|a runtime bake evaluated by the C\\+\\+ runtime matches|fit smoothness: on Male_Casual|fit volume: on Cyberpunk|fit roughness cap: at 1.2|skin figures: the (mannequin (turned 70|in centimetres|hung under a new root|with its clavicles under the neck|with its vertices and triangles)|Cowboy, whose two armature roots)|skin figures: CesiumMan and Male Casual with their vertices|validate --input: on Female Casual|deformation quality: Male Casual's hip|cli bake --fit-regions every-frame: Female Casual|seams: with the every-frame region fit|fit body row: Male and Female Casual"

# libFuzzer targets built with clang (fuzz/, tree build-fuzz/): every seed in tests/fuzz/ (the regression
# inputs among them), then 15 s of mutation per target, two targets at a time on two cores. Any crash,
# sanitizer report or undocumented error fails the run.
echo "== libFuzzer: the character loader, muscle files, presets, manifests, jiggle and hit files (at ${SECONDS} s)" >&2
bash "$repo/scripts/fuzz.sh" "${RIGBAKE_FUZZ_SECONDS:-15}"
echo "== every test passed in ${SECONDS} s" >&2

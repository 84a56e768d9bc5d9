#!/usr/bin/env bash
# Configures and builds rigbake. Usage: scripts/build.sh [release|debug|asan [target...]]
# (default: release, every target)
# Build trees: build/ (release, warnings as errors), build-asan/ (AddressSanitizer + UBSan).
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
kind="${1:-release}"
release_args=(-DCMAKE_BUILD_TYPE=Release)
case "$kind" in
  release) dir="$repo/build"; args=("${release_args[@]}") ;;
  debug) dir="$repo/build-debug"; args=(-DCMAKE_BUILD_TYPE=Debug) ;;
  # -O1 -g1: line tables for the sanitizers' stack traces, at half the compile time of -O2 -g.
  # The test cases are not instrumented: the sanitizer tree links the release tree's archive of them
  # (tests/CMakeLists.txt), brought up to date first.
  asan) dir="$repo/build-asan"
        args=(-DCMAKE_BUILD_TYPE=RelWithDebInfo "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g1" -DRIGBAKE_SANITIZE=ON
              "-DRIGBAKE_TEST_CASES_ARCHIVE=$repo/build/tests/librigbake_test_cases.a")
        cmake -S "$repo" -B "$repo/build" -G Ninja -DRIGBAKE_WERROR=ON "${release_args[@]}" >/dev/null
        cmake --build "$repo/build" --parallel "$(nproc)" --target rigbake_test_cases ;;
  *) echo "usage: scripts/build.sh [release|debug|asan [target...]]" >&2; exit 1 ;;
esac
cmake -S "$repo" -B "$dir" -G Ninja -DRIGBAKE_WERROR=ON "${args[@]}" >/dev/null
shift || true
targets=()
for target in "$@"; do targets+=(--target "$target"); done
cmake --build "$dir" --parallel "$(nproc)" "${targets[@]}"
echo "$dir"

#!/usr/bin/env bash
# The test command: installs what is needed, builds with warnings as errors, runs every test, then
# runs the whole suite again under AddressSanitizer + UndefinedBehaviorSanitizer.
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$repo/scripts/install-deps.sh"

echo "== release build, all tests" >&2
bash "$repo/scripts/build.sh" release >/dev/null
ctest --test-dir "$repo/build" --output-on-failure --parallel "$(nproc)" --timeout 600

echo "== AddressSanitizer + UBSan build, all tests" >&2
bash "$repo/scripts/build.sh" asan >/dev/null
ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
  ctest --test-dir "$repo/build-asan" --output-on-failure --parallel "$(nproc)" --timeout 900

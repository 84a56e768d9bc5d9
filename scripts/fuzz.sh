#!/usr/bin/env bash
# Builds rigbake's libFuzzer targets with clang (fuzz/CMakeLists.txt, tree build-fuzz/) and runs each
# for a bounded time on its seed corpus (tests/fuzz/, the shipped presets and examples). Every corpus
# file runs first, so the regression inputs of earlier findings are checked on every run; then the
# fuzzer mutates them. Any crash, sanitizer report, leak, uncaught exception, undocumented error code,
# input slower than 10 s or run past 2 GB fails the script, and the input is kept in
# build-fuzz/artifacts/ (reproduce: build-fuzz/TARGET_fuzz FILE; once fixed, add it to tests/fuzz/TARGET/).
#
# Usage: scripts/fuzz.sh [SECONDS_PER_TARGET [TARGET...]]   (default: 20 s, every target)
# Targets run side by side, one per core; what new inputs they find goes to a temporary folder, not
# into tests/.
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
seconds="${1:-20}"
shift || true
targets=("$@")
[ "${#targets[@]}" -gt 0 ] || targets=(character muscles preset manifest jiggle)
build="$repo/build-fuzz"

CXX=clang++ cmake -S "$repo/fuzz" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=None >/dev/null
cmake --build "$build" --parallel "$(nproc)" >/dev/null

# Seed folders per target: the committed corpus and the real files of that kind.
seeds_of() {
  case "$1" in
    character) echo "$repo/tests/fuzz/character" ;;
    muscles) echo "$repo/tests/fuzz/muscles" ;;
    preset) echo "$repo/tests/fuzz/preset $repo/presets/muscles $repo/presets/skeletons $repo/presets/regions" ;;
    manifest) echo "$repo/tests/fuzz/manifest $repo/examples" ;;
    jiggle) echo "$repo/tests/fuzz/jiggle $repo/presets/jiggle" ;;
  esac
}

work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
mkdir -p "$build/artifacts"
run_target() {
  local target="$1"
  mkdir -p "$work/$target"
  # shellcheck disable=SC2046  # the seed folders are one word each
  if "$build/${target}_fuzz" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
       -artifact_prefix="$build/artifacts/$target-" "$work/$target" $(seeds_of "$target") >"$work/$target.log" 2>&1; then
    echo "fuzz $target: $(grep -m 1 -o 'stat::number_of_executed_units: *[0-9]*' "$work/$target.log" | grep -o '[0-9]*$') runs in ${seconds} s, 0 crashes" >&2
  else
    echo "fuzz $target: FAILED (input kept in $build/artifacts/$target-*)" >&2
    grep -E 'ERROR|SUMMARY|rigbake fuzz|==[0-9]+==|Test unit written|#[0-9]+ ' "$work/$target.log" | head -n 40 >&2
    return 1
  fi
}
export -f run_target seeds_of
export build work seconds repo
printf '%s\n' "${targets[@]}" | xargs -P "$(nproc)" -I{} bash -c 'run_target {}'

#!/usr/bin/env bash
# The full test suite, as CI runs it: installs what is missing, builds, and runs
#   1. every GoogleTest suite through ctest on the Release build (build/);
#   2. the same suite under AddressSanitizer + UndefinedBehaviorSanitizer (build-asan/);
#   3. every fuzz target for a short, bounded time on a copy of its corpus (build-fuzz/).
# Any failure, sanitizer report or fuzzer finding fails the run.
#   tools/run-tests.sh             all three
#   tools/run-tests.sh --release   1 only (the quick local loop)
#   tools/run-tests.sh --asan      2 only
#   tools/run-tests.sh --fuzz      3 only
set -euo pipefail
cd "$(dirname "$0")/.."

stage=${1:-all}
case "$stage" in
  all | --release | --asan | --fuzz) ;;
  *) echo "usage: tools/run-tests.sh [--release | --asan | --fuzz]" >&2; exit 2 ;;
esac

run_suite() {  # $1: preset (release | asan), $2: build directory
  local started=$SECONDS
  if [ "$1" = asan ]; then bash tools/setup.sh --asan; else bash tools/setup.sh; fi
  ctest --test-dir "$2" --output-on-failure -j 2 --timeout 900
  echo "run-tests: $1 suite done in $((SECONDS - started)) s"
}

if [ "$stage" = all ] || [ "$stage" = --release ]; then run_suite release build; fi
if [ "$stage" = all ] || [ "$stage" = --asan ]; then run_suite asan build-asan; fi
if [ "$stage" = all ] || [ "$stage" = --fuzz ]; then
  started=$SECONDS
  bash tools/run-fuzzers.sh
  echo "run-tests: fuzzers done in $((SECONDS - started)) s"
fi

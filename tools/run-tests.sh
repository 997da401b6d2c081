#!/usr/bin/env bash
# The tests. Installs what is missing, builds, and runs:
#   tools/run-tests.sh             the full run, as CI runs it (.ci/run): every GoogleTest suite
#                                  under AddressSanitizer + UndefinedBehaviorSanitizer (build-asan/),
#                                  then every fuzz target for a short, bounded time (build-fuzz/)
#   tools/run-tests.sh --release   the quick loop: every GoogleTest suite on the Release build (build/)
#   tools/run-tests.sh --asan      the sanitized suite alone
#   tools/run-tests.sh --fuzz      the fuzzers alone
#   tools/run-tests.sh --all       Release suite, sanitized suite and fuzzers
# Every test runs in the full run; the Release suite is the same tests at -O3 without the
# sanitizers, which is what a developer runs between changes. Any failure, sanitizer report or
# fuzzer finding fails the run.
set -euo pipefail
cd "$(dirname "$0")/.."

stage=${1:-full}
case "$stage" in
  full | --release | --asan | --fuzz | --all) ;;
  *) echo "usage: tools/run-tests.sh [--release | --asan | --fuzz | --all]" >&2; exit 2 ;;
esac

run_suite() {  # $1: preset (release | asan), $2: build directory
  local started=$SECONDS
  if [ "$1" = asan ]; then bash tools/setup.sh --asan; else bash tools/setup.sh; fi
  local built=$SECONDS
  # CTest starts the costliest tests first when it knows their costs (Testing/Temporary/
  # CTestCostData.txt, written by each run). A fresh build has none and would run them in
  # declaration order, leaving a long test alone at the end: it starts from the sanitized costs
  # measured here (tests/ctest-costs.txt; only the order depends on them).
  if [ ! -f "$2/Testing/Temporary/CTestCostData.txt" ]; then
    mkdir -p "$2/Testing/Temporary"
    cp tests/ctest-costs.txt "$2/Testing/Temporary/CTestCostData.txt"
  fi
  ctest --test-dir "$2" --output-on-failure -j 2 --timeout 900
  echo "run-tests: $1 suite done in $((SECONDS - started)) s (build $((built - started)) s, tests $((SECONDS - built)) s)"
}

if [ "$stage" = --all ] || [ "$stage" = --release ]; then run_suite release build; fi
if [ "$stage" = --all ] || [ "$stage" = full ] || [ "$stage" = --asan ]; then run_suite asan build-asan; fi
if [ "$stage" = --all ] || [ "$stage" = full ] || [ "$stage" = --fuzz ]; then
  started=$SECONDS
  bash tools/run-fuzzers.sh
  echo "run-tests: fuzzers done in $((SECONDS - started)) s"
fi

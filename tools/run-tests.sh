#!/usr/bin/env bash
# The full test suite: install, build, run every GoogleTest suite through ctest.
#   tools/run-tests.sh          Release build
#   tools/run-tests.sh --asan   the same suite under AddressSanitizer + UBSan (build-asan/)
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/setup.sh "$@"
dir=build
if [ "${1:-}" = "--asan" ]; then dir=build-asan; fi
ctest --test-dir "$dir" --output-on-failure -j 2 --timeout 900

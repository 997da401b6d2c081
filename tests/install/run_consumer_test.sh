#!/usr/bin/env bash
# The installed package, end to end:
#   1. `cmake --install` the build into a fresh prefix;
#   2. configure and build tests/install/consumer against that prefix only (find_package(brittle));
#   3. bake a small pack with the installed CLI;
#   4. run the consumer on it: one impact, exit 0 and a contact line expected.
#
#   run_consumer_test.sh <build dir> <source dir>
# Environment: CMAKE, CXX (default: cmake and CMake's own compiler choice), CONSUMER_CXXFLAGS
# (the sanitizers, when the build has them). The work directory
# is removed on success and kept, with its path printed, on failure.
set -euo pipefail

build=$(cd "$1" && pwd)
src=$(cd "$2" && pwd)
cmake=${CMAKE:-cmake}
work=$(mktemp -d "${TMPDIR:-/tmp}/brittle-install-test.XXXXXX")
trap 'status=$?; if [ $status -eq 0 ]; then rm -rf "$work"; else echo "FAILED (exit $status); work directory kept: $work" >&2; fi' EXIT
prefix=$work/prefix
step() { echo "== $* ($SECONDS s)"; }

step "install the build into $prefix"
"$cmake" --install "$build" --prefix "$prefix"
config=$(find "$prefix" -name brittleConfig.cmake -print -quit)
for f in "$prefix/bin/brittle" "$prefix/include/brittle/core/Result.h" "$prefix/include/brittle/runtime/World.h" "$config"; do
  [ -f "$f" ] || { echo "not installed: $f" >&2; exit 1; }
done

step "configure and build the consumer against the installed package"
compiler=()
[ -n "${CXX:-}" ] && compiler=("-DCMAKE_CXX_COMPILER=$CXX")
[ -n "${CONSUMER_CXXFLAGS:-}" ] && compiler+=("-DCMAKE_CXX_FLAGS=$CONSUMER_CXXFLAGS")
"$cmake" -S "$src/tests/install/consumer" -B "$work/consumer" -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF "${compiler[@]}"
# The package must come from the prefix, never from the build tree.
found=$(sed -n 's/^brittle_DIR:PATH=//p' "$work/consumer/CMakeCache.txt")
case "$found" in
  "$prefix"/*) ;;
  *) echo "brittle was found at '$found', not in $prefix" >&2; exit 1 ;;
esac
"$cmake" --build "$work/consumer"

step "bake a pack with the installed CLI"
"$prefix/bin/brittle" bake --mesh "$src/assets/meshes/brick.off" --material concrete --tets 500 --modes 6 \
  --quiet --out "$work/brick.h5"

step "run the consumer"
"$work/consumer/brittle_consumer" "$work/brick.h5" brick | tee "$work/consumer.out"
grep -q '^brick: contact .* us, peak force .* N' "$work/consumer.out" || { echo "unexpected consumer output" >&2; exit 1; }
step "passed"

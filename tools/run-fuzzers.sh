#!/usr/bin/env bash
# Fuzzes brittle's readers (tests/fuzz) for a bounded time: installs clang and the libraries the
# targets need if they are missing, builds them into build-fuzz/, and runs each target on a copy
# of its seed corpus, so that a run never grows the repository.
#   tools/run-fuzzers.sh [SECONDS_PER_TARGET]    default 10: ten targets, two at a time, about a minute
# Exits non-zero when a target crashed, leaked, hung (10 s on one input) or went over 2 GiB, and
# prints how to reproduce it: build-fuzz/bin/<target> <input>.
# BRITTLE_FUZZ_CORPUS=<dir>: a corpus kept between runs (a CI cache, say). Each target also starts
# from <dir>/<target>, and what it found that adds coverage is merged back into it.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-10}
case $seconds in '' | *[!0-9]*) echo "usage: tools/run-fuzzers.sh [SECONDS_PER_TARGET]" >&2; exit 2 ;; esac

# clang-14 alone does not bring libFuzzer's runtime (libclang-rt-14-dev, only recommended) or
# llvm-symbolizer (llvm-14), which turns the sanitizers' stacks into file and line.
PACKAGES=(cmake make ninja-build clang-14 libclang-rt-14-dev llvm-14
  libeigen3-dev libtbb-dev libcgal-dev libopenvdb-dev libboost-iostreams-dev libhdf5-dev
  nlohmann-json3-dev libflann-dev libhnswlib-dev libfaiss-dev libblas-dev liblapack-dev)
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "fuzz: installing ${missing[*]}"
  $SUDO apt-get update -qq
  $SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
    -o Dpkg::Options::=--force-unsafe-io "${missing[@]}" >/dev/null
fi

build=build-fuzz
# Ninja (tools/setup.sh installs it): a target's units compile while the libraries it links are
# still being built, which Makefiles would wait for. A build directory made by another generator is
# made again.
if [ -f "$build/CMakeCache.txt" ] && ! grep -q '^CMAKE_GENERATOR:INTERNAL=Ninja$' "$build/CMakeCache.txt"; then
  rm -rf "$build"
fi
cmake -S tests/fuzz -B "$build" -G Ninja -DCMAKE_C_COMPILER=clang-14 -DCMAKE_CXX_COMPILER=clang++-14 >/dev/null
cmake --build "$build" -j 2

# Leaks inside libhdf5 itself are suppressed (tests/lsan.supp says which and why); anything
# undefined aborts; stacks are symbolized.
export LSAN_OPTIONS="suppressions=$PWD/tests/lsan.supp:print_suppressions=0"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
if [ -x /usr/lib/llvm-14/bin/llvm-symbolizer ]; then export ASAN_SYMBOLIZER_PATH=/usr/lib/llvm-14/bin/llvm-symbolizer; fi

# The seed pack, written by this build: a pack schema change reaches the fuzzers at once. The
# committed copy is the same file while the schema and the writer have not changed.
fresh_pack="$build/seed.pack.h5"
"$build/bin/brittle_fuzz_seed_pack" "$fresh_pack"
if ! cmp -s "$fresh_pack" tests/fuzz/corpus/fuzz_pack_bytes/seed.pack.h5; then
  echo "fuzz: note: tests/fuzz/corpus/fuzz_pack_bytes/seed.pack.h5 differs from what this build writes;"
  echo "      regenerate it with $build/bin/brittle_fuzz_seed_pack tests/fuzz/corpus/fuzz_pack_bytes/seed.pack.h5"
fi

# One target: fuzz it, then write its line of the table (and, when it failed, how to reproduce it)
# into $build/logs/<target>.report; its exit status says whether it failed.
fuzz_one() {
  local target=$1
  local corpus="$build/corpus/$target" artifacts="$build/artifacts/$target" log="$build/logs/$target.log"
  local report="$build/logs/$target.report"
  rm -rf "$corpus" "$artifacts"
  mkdir -p "$corpus" "$artifacts" "$(dirname "$log")"
  if [ -d "tests/fuzz/corpus/$target" ]; then cp -r "tests/fuzz/corpus/$target/." "$corpus/"; fi
  local kept=()
  if [ -n "${BRITTLE_FUZZ_CORPUS:-}" ]; then
    mkdir -p "$BRITTLE_FUZZ_CORPUS/$target"
    kept=("$BRITTLE_FUZZ_CORPUS/$target")
  fi
  local options=(-max_total_time="$seconds" -rss_limit_mb=2048 -timeout=10 -print_final_stats=1
    -artifact_prefix="$artifacts/")
  case $target in
    fuzz_mesh_reader) options+=(-dict=tests/fuzz/mesh.dict -max_len=4096) ;;
    fuzz_*_json) options+=(-dict=tests/fuzz/json.dict -max_len=4096) ;;
    fuzz_pack_bytes) cp "$fresh_pack" "$corpus/fresh.pack.h5" ;;
    # Its inputs are lists of edits: start at full length rather than growing from a few bytes.
    fuzz_pack_edits) options+=(-len_control=0 -max_len=512) ;;
  esac
  local status=0
  "$build/bin/$target" "${options[@]}" "$corpus" "${kept[@]}" >"$log" 2>&1 || status=$?
  local runs speed
  runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  speed=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -1)
  if [ "$status" -eq 0 ]; then
    printf '%-26s %10s %10s %8s\n' "$target" "${runs:-?}" "${speed:-?}" ok >"$report"
    if [ ${#kept[@]} -gt 0 ]; then
      "$build/bin/$target" -merge=1 "${kept[0]}" "$corpus" >>"$log" 2>&1 || echo "    (merging into ${kept[0]} failed: $log)" >>"$report"
    fi
    return 0
  fi
  {
    printf '%-26s %10s %10s %8s\n' "$target" "${runs:-?}" "${speed:-?}" "FAILED"
    grep -E "ERROR|SUMMARY|fuzz finding|runtime error" "$log" | head -5 | sed 's/^/    /'
    for input in "$artifacts"/*; do
      [ -e "$input" ] && echo "    reproduce: $build/bin/$target $input"
    done
    echo "    log: $log"
  } >"$report"
  return 1
}

# Two targets at a time, one a core (each libFuzzer process is single-threaded); the table is
# printed in the targets' order once all have run. Each target has its own corpus copy, artifacts
# and log, so the pairs share nothing.
mapfile -t targets < <(grep -v '^$' "$build/fuzz-targets.txt")
for target in "${targets[@]}"; do rm -f "$build/logs/$target.report"; done
failed=()
for ((i = 0; i < ${#targets[@]}; i += 2)); do
  pids=()
  for target in "${targets[@]:i:2}"; do
    fuzz_one "$target" &
    pids+=($!)
  done
  for j in "${!pids[@]}"; do
    wait "${pids[$j]}" || failed+=("${targets[$((i + j))]}")
  done
done
printf '%-26s %10s %10s %8s\n' target executions "exec/s" result
for target in "${targets[@]}"; do
  # A target whose run stopped before its report (its set-up failed) is listed as failed.
  cat "$build/logs/$target.report" 2>/dev/null || printf '%-26s %10s %10s %8s\n' "$target" "?" "?" "FAILED (no report; log: $build/logs/$target.log)"
done

if [ ${#failed[@]} -gt 0 ]; then
  echo "fuzz: findings in ${failed[*]}" >&2
  exit 1
fi
echo "fuzz: no findings"

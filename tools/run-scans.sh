#!/usr/bin/env bash
# Bakes real meshes nobody in this project wrote: every closed mesh of Debian's libcgal-demo
# sample data (data/meshes/*.off) that the validator accepts, at default settings
# (`brittle bake --mesh M --material porcelain`, nothing else).
#
#   tools/run-scans.sh [--brittle PATH] [--out CSV] [--only GLOB] [--timeout S]
#
# The meshes are fetched at run time (apt-get download libcgal-demo, then data.tar.gz from
# usr/share/doc/libcgal-dev; tests/common/fetch_cgal_meshes.sh) into build/test-data/cgal and are
# never committed. Each mesh gets one bake: the validator runs first inside it, so a mesh it
# rejects stops there with its typed error (exit 3) and is listed with that error; every other
# mesh is "accepted" and counts as baked or failed. Prints a Markdown table (mesh, validator,
# bake, adjustments, tets, seconds) and the counts, and writes the same rows as CSV
# (default docs/results/data/scans.csv). The results are in docs/results/scans.md.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
brittle=$root/build/bin/brittle
csv=$root/docs/results/data/scans.csv
only='*'
limit=900
while [ $# -gt 0 ]; do
  case "$1" in
    --brittle) brittle=$2; shift 2 ;;
    --out) csv=$2; shift 2 ;;
    --only) only=$2; shift 2 ;;
    --timeout) limit=$2; shift 2 ;;
    *) echo "usage: tools/run-scans.sh [--brittle PATH] [--out CSV] [--only GLOB] [--timeout S]" >&2; exit 2 ;;
  esac
done
[ -x "$brittle" ] || { echo "run-scans: no $brittle (build it: cmake --build --preset release --target brittle)" >&2; exit 2; }

data=${BRITTLE_BINARY_DIR:-$root/build}/test-data/cgal
bash "$root/tests/common/fetch_cgal_meshes.sh" "$data"
meshes=$data/data/meshes
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
mkdir -p "$(dirname "$csv")"
echo "mesh,validator,bake,adjustments,tets,seconds" >"$csv.tmp"

printf '| mesh | validator | bake | adjustments | tets | s |\n|---|---|---|---|---|---|\n'
files=0 accepted=0 baked=0
for path in "$meshes"/$only.off; do
  mesh=$(basename "$path")
  files=$((files + 1))
  start=$(date +%s.%N)
  set +e
  timeout "$limit" "$brittle" bake --mesh "$path" --material porcelain --out "$work/pack.h5" --quiet --json \
    >"$work/out.json" 2>"$work/err.txt"
  code=$?
  set -e
  seconds=$(echo "$(date +%s.%N) - $start" | bc -l | xargs printf '%.1f')
  error=$(sed -n 's/^error \[\([a-z_]*\)\].*/\1/p' "$work/err.txt" | head -n1)
  [ "$code" = 124 ] && error=timeout
  # "adjusted X: why" lines, joined; commas would break the CSV.
  adjustments=$(sed -n 's/^adjusted \([^:]*\):.*/\1/p' "$work/err.txt" | paste -sd ';' - | tr ',' ' ')
  # A failed bake names what it adjusted in its error ("...; adjusted: a, b, c (...").
  [ -z "$adjustments" ] && adjustments=$(sed -n 's/^error .*; adjusted: \([^(]*\).*/\1/p' "$work/err.txt" | sed 's/ *$//; s/, /;/g')
  tets=""
  if [ "$code" = 3 ]; then
    validator=$error bake="-"
  else
    validator=ok accepted=$((accepted + 1))
    if [ "$code" = 0 ]; then
      bake=ok baked=$((baked + 1))
      tets=$(jq '.objects[0].mesh.tets' "$work/out.json" 2>/dev/null || true)
    else
      bake=${error:-exit $code}
    fi
  fi
  rm -f "$work/pack.h5"
  echo "$mesh,$validator,$bake,$adjustments,$tets,$seconds" >>"$csv.tmp"
  printf '| %s | %s | %s | %s | %s | %s |\n' "$mesh" "$validator" "$bake" "${adjustments:--}" "${tets:--}" "$seconds"
  if [ "$bake" != ok ] && [ "$bake" != - ]; then sed 's/^/    /' "$work/err.txt" | tail -n 3 >&2; fi
done
mv "$csv.tmp" "$csv"
echo
echo "$files meshes, $accepted accepted by the validator, $baked baked, $((accepted - baked)) failed (table: $csv)"

#!/usr/bin/env bash
# The speed/accuracy charts, regenerated from scratch: each benchmark writes its CSV into
# docs/results/data/ and its chart script draws the PNG beside it and prints the figures that
# docs/results/*.md quote.
#   tools/run-charts.sh          the modal-integrator, mode-count, tet-resolution, fracture-statistics,
#                                exact-path (chart 5) and frame-time charts (~15 min)
#   tools/run-charts.sh --all    also the modal-solver, search, impact-latency and descriptor-resolution
#                                benchmarks, the last at 1k and 10k entries (about two hours on 2 cores)
set -euo pipefail
cd "$(dirname "$0")/.."
all=0
case "${1:-}" in
  "") ;;
  --all) all=1 ;;
  *) echo "usage: tools/run-charts.sh [--all]" >&2; exit 2 ;;
esac
bash tools/setup.sh
data=docs/results/data  # the CSVs and charts the results pages show
mkdir -p "$data"
cli=build/bin/brittle
plot() { /usr/bin/python3 "tools/scripts/$1" "${@:2}"; }

$cli bench integrators --csv $data/integrators.csv --timing-csv $data/integrator_timing.csv
plot plot_integrators.py $data/integrators.csv $data/integrator_timing.csv
$cli bench modes --csv $data/modes.csv
plot plot_modes.py $data/modes.csv
$cli bench resolution --csv $data/resolution.csv
plot plot_resolution.py $data/resolution.csv
$cli bench elements --csv $data/elements.csv
plot plot_elements.py $data/elements.csv
$cli bench fracture --csv $data/fracture.csv
plot plot_fracture.py $data/fracture.csv

# Charts on the default pack (baked here when the main job has not made it).
mkdir -p out
[ -f out/default.h5 ] || $cli bake --manifest assets/default-pack.json --out out/default.h5 --quiet
# The bodies' frequency errors, calibrated on the objects' own fragments (seeds 1001..; chart 5's
# seeds are held back from it), as the main job does.
$cli calibrate-errors out/default.h5 --quiet > /dev/null
# Chart 5: a fragment's database match against its own modal analysis (the exact path).
$cli bench exact-modes out/default.h5 --speeds 10,30 --seeds 2 --max-fragments 8 --repeats 1 --csv $data/exact_modes.csv --quiet
plot plot_exact_modes.py $data/exact_modes.csv
# Frame time of the default scenes: every frame's Bullet and fracture time, bodies over time,
# paced in wall time as a host runs them (the workers get the time between a contact and its frame).
mkdir -p $data/play
for scene in assets/scenes/*.json; do
  $cli play out/default.h5 "$scene" --real-time --frames-every 1 --out-stats "$data/play/$(basename "$scene")" > /dev/null
done
plot plot_frame_times.py $data/play/*.json --out $data/frame_times.png

if [ "$all" = 1 ]; then
  build/bin/brittle_bench_modal --tets 300 1000 3000 10000 30000 80000 --modes 20 40 --skip-eigen-ldlt \
    --out $data/modal_solve.csv
  plot plot_bench.py $data/modal_solve.csv
  $cli bench search --csv $data/search.csv --cost-csv $data/descriptor_cost.csv
  plot plot_search.py $data/search.csv $data/descriptor_cost.csv
  $cli bench impact --csv $data/impact_latency.csv
  plot plot_impact.py $data/impact_latency.csv
  # Descriptor resolution: moment order and voxels per axis, 1k entries (the 10k-entry database
  # costs ~8 min per setting on 2 cores; bench search's size axis is in the search chart).
  sweep=$(mktemp -d)
  pairs=()
  for order in 2 3 4 6 8; do
    $cli bench search --sizes 1000 --kinds moment --moment-order "$order" --index kd-forest:4:32 --queries 100 \
      --physics-queries 24 --quiet --csv "$sweep/moment-$order.csv" --cost-csv "$sweep/moment-$order-cost.csv"
    pairs+=("$sweep/moment-$order.csv" "$sweep/moment-$order-cost.csv")
  done
  for voxels in 8 16 32; do
    $cli bench search --sizes 1000 --kinds voxel,voxel-improved --voxel-resolution "$voxels" --index kd-forest:4:32 \
      --queries 100 --physics-queries 24 --quiet --csv "$sweep/voxel-$voxels.csv" --cost-csv "$sweep/voxel-$voxels-cost.csv"
    pairs+=("$sweep/voxel-$voxels.csv" "$sweep/voxel-$voxels-cost.csv")
  done
  plot plot_search_resolution.py $data/search_resolution.csv "${pairs[@]}"
  # The same at 10 000 entries (~8 min per setting; voxels at 32 per axis left out: 1.3 GB).
  pairs=()
  for order in 2 4 6 8; do
    $cli bench search --sizes 10000 --kinds moment --moment-order "$order" --index kd-forest:4:32 --queries 100 \
      --physics-queries 24 --quiet --csv "$sweep/moment-$order-10k.csv" --cost-csv "$sweep/moment-$order-10k-cost.csv"
    pairs+=("$sweep/moment-$order-10k.csv" "$sweep/moment-$order-10k-cost.csv")
  done
  for voxels in 8 16; do
    $cli bench search --sizes 10000 --kinds voxel,voxel-improved --voxel-resolution "$voxels" --index kd-forest:4:32 \
      --queries 100 --physics-queries 24 --quiet --csv "$sweep/voxel-$voxels-10k.csv" --cost-csv "$sweep/voxel-$voxels-10k-cost.csv"
    pairs+=("$sweep/voxel-$voxels-10k.csv" "$sweep/voxel-$voxels-10k-cost.csv")
  done
  plot plot_search_resolution.py $data/search_resolution_10k.csv "${pairs[@]}"
  rm -rf "$sweep"
fi

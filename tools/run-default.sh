#!/usr/bin/env bash
# The main job, end to end on the bundled default assets: install, build, bake the default pack,
# and print its inspection. Output: out/default.h5 (+ out/default.json, the inspection as JSON).
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/setup.sh
mkdir -p out
build/bin/brittle bake --manifest assets/default-pack.json --out out/default.h5
build/bin/brittle inspect out/default.h5 --json > out/default.json
echo "inspection JSON: out/default.json"

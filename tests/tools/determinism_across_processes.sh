#!/usr/bin/env bash
# Bit-identical across processes and thread counts. Each step runs in three separate processes
# whose heap and stack sit in different places: address-space randomisation stays on, and each
# process gets an environment of a different size (which moves its initial stack and what the
# loader allocates first). The third process of each step runs with BRITTLE_SIMD=sse2: the 128-bit
# forms of the loops that also have an AVX form (brittle/core/Simd.h), as on a CPU without AVX, so
# that the comparison also spans machines with and without it. Checked:
#   1. a fragment-database bake (bake-db) with 1, 2 and 1 worker threads gives the same pack data;
#   2. the search indexes built over a 1 200-entry database (every descriptor kind, the stored kinds
#      and the graphs, kd-forest and FAISS) are the same in each process (brittle query --digest);
#   3. a bake of the four default objects (the default manifest's meshes, materials, element
#      orders, stretch and contact spreads, at fewer modes, the vase at fewer elements) with a small
#      database gives the same pack data;
# (pack data: every dataset and attribute bit for bit, the wall-clock bake timings aside;
# compare_packs.py);
#   4. one breaking impact on each object (the main job's four impacts, and the plate's again with
#      cracks that end at cracks) gives the same fracture fingerprint (brittle impact: every value the impact computed, times aside), and that
#      fingerprint equals the golden value pinned in golden-fingerprints.txt beside this script.
#   determinism_across_processes.sh BRITTLE_CLI SOURCE_DIR [--pin]
# --pin writes this build's fingerprints into golden-fingerprints.txt instead of comparing: run it
# after a change that is meant to change fractures, and commit the file with the change.
set -euo pipefail
cli=$(realpath "$1")
src=$(realpath "$2")  # both absolute: the runs happen in a scratch folder
pin=${3:-}
golden="$src/tests/tools/golden-fingerprints.txt"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

pad() { head -c "$1" /dev/zero | tr '\0' 'x'; }  # an environment variable of $1 bytes
run() {  # run I N CMD...: process I (1–3) of a step, its environment N bytes larger; the third in
  # SSE2 registers only
  local simd=""
  [ "$1" = 3 ] && simd=sse2
  local size=$2
  shift 2
  env "BRITTLE_TEST_PAD=$(pad "$size")" "BRITTLE_SIMD=$simd" "$@"
}
all_equal() {  # all_equal WHAT VALUE...: every value equals the first, or the check fails naming WHAT
  local what=$1
  shift
  for value in "$@"; do
    [ "$value" = "$1" ] || { echo "FAIL: $what differs between processes: $*"; exit 1; }
  done
}
same_packs() {  # same_packs WHAT PACK...: every pack holds the first one's data, bit for bit
  local what=$1
  shift
  if ! /usr/bin/python3 "$src/tests/tools/compare_packs.py" "$@" > "$work/digests"; then
    echo "FAIL: $what differs between processes:"
    cat "$work/digests"
    exit 1
  fi
  echo "ok: $what, $# processes, data sha256 $(head -c 16 "$work/digests")"
}

# 1. The database bake, on 1, 2 and 1 threads.
for i in 1 2 3; do
  threads=$(( i == 2 ? 2 : 1 ))
  run "$i" $(( i * 3000 )) "$cli" bake-db --shapes "$src/assets/shapes/base-shapes.json" --entries 4 --seed 5 --tets 300 \
    --modes 6 --threads "$threads" --quiet --out "$work/db$i.h5" >/dev/null
done
same_packs "bake-db (threads 1, 2, 1; the third in SSE2)" "$work/db1.h5" "$work/db2.h5" "$work/db3.h5"

# 2. The search indexes a World builds from a pack's database, on a larger database (1 200
#    entries, descriptors only: every stored kind has several lists), built in each process and
#    compared by their digests (brittle query --digest: settings, data and what the build made).
"$cli" bake-db --shapes "$src/assets/shapes/base-shapes.json" --entries 1200 --seed 7 --descriptors-only --quiet \
  --out "$work/search.h5" >/dev/null
indexes=(
  "moment ivf" "moment hnsw" "moment kd-forest" "moment faiss-ivf"
  "voxel ivf-binary" "voxel faiss-binary-hnsw" "voxel-improved ivf" "voxel-improved hnsw-principal"
)
for spec in "${indexes[@]}"; do
  read -r descriptor index <<<"$spec"
  digests=()
  for i in 1 2 3; do
    digest=$(run "$i" $(( i * 4000 )) "$cli" query "$work/search.h5" --mesh "$src/assets/meshes/brick.off" \
      --descriptor "$descriptor" --index "$index" --k 1 --digest --json |
      python3 -c 'import json, sys; print(json.load(sys.stdin)["query"]["index_digest"])')
    digests+=("$digest")
  done
  all_equal "the $descriptor $index index" "${digests[@]}"
  echo "ok: $descriptor $index index, 3 processes (the third in SSE2), digest ${digests[0]}"
done

# 3. The four default objects, smaller, with a small database, all four in P2 as the default pack
#    bakes them (nodal-mean corner stresses, the node memo, the brick's and the ball's own contact
#    spread). The plate keeps its default size: at 1 000 tets its ring (3.8 cm) is wider than
#    0.05 D, and the 5 m/s hit reads 36 MPa at its corners' nodal means, short of glass's strength.
#    The brick and the ball keep theirs too; the vase's target of 1 500 gives Mesh_3's floor for its
#    wall, 6.25k tets.
cat > "$work/manifest.json" <<JSON
{
  "objects": [
    { "name": "glass-plate", "mesh": "$src/assets/meshes/plate.off", "material": "glass", "tets": 4000, "modes": 12, "element": "p2", "stretch": 2 },
    { "name": "porcelain-vase", "mesh": "$src/assets/meshes/vase.off", "material": "porcelain", "tets": 1500, "modes": 12, "element": "p2" },
    { "name": "brick", "mesh": "$src/assets/meshes/brick.off", "material": "concrete", "tets": 800, "modes": 12, "element": "p2", "contact_spread": 0.15 },
    { "name": "stone-ball", "mesh": "$src/assets/meshes/ball.off", "material": "stone", "tets": 1200, "modes": 12, "element": "p2", "contact_spread": 0.15 }
  ],
  "database": { "shapes": "$src/assets/shapes/base-shapes.json", "entries": 6, "seed": 1, "tets": 300, "modes": 6 }
}
JSON
for i in 1 2 3; do
  run "$i" $(( i * 5000 )) "$cli" bake --manifest "$work/manifest.json" --quiet --out "$work/pack$i.h5" >/dev/null
done
same_packs "bake of the four default objects (the third in SSE2)" "$work/pack1.h5" "$work/pack2.h5" "$work/pack3.h5"

# 4. The main job's four impacts (tools/run-default.sh), and the plate's with cracks that end at
#    cracks, each in three processes.
impacts=(
  "glass-plate --point 0.02,0.01,0.005 --normal 0,0,1 --speed 5 --impactor-mass 0.1 --impactor-radius 0.02"
  "porcelain-vase --point 0.0741,0,0.12 --normal 1,0,0 --speed 10 --impactor-mass 0.1 --impactor-radius 0.02"
  "brick --point 0.1075,0.05125,0.0325 --normal 0.7,0.5,0.5 --speed 10 --impactor-mass inf --impactor-radius inf"
  "stone-ball --point 0,0,-0.1 --normal 0,0,-1 --speed 15 --impactor-mass inf --impactor-radius inf"
  # and the plate's with cracks that end at cracks (CrackSettings::endAtCracks, off by default)
  "glass-plate --point 0.02,0.01,0.005 --normal 0,0,1 --speed 5 --impactor-mass 0.1 --impactor-radius 0.02 --end-at-cracks"
)
computed=()
for spec in "${impacts[@]}"; do
  read -r object args <<<"$spec"
  label=$object
  case " $args " in *" --end-at-cracks "*) label=$object+end-at-cracks ;; esac
  prints=()
  for i in 1 2 3; do
    # shellcheck disable=SC2086  # args is a list of flags
    print=$(run "$i" $(( i * 7000 )) "$cli" impact "$work/pack$i.h5" --object "$object" $args --json |
      python3 -c 'import json, sys; d = json.load(sys.stdin); print(d["fingerprint"], d["broken"], len(d["fragments"]))')
    prints+=("$print")
  done
  all_equal "the $label impact" "${prints[@]}"
  read -r fp broken fragments <<<"${prints[0]}"
  [ "$broken" = True ] || { echo "FAIL: the $label impact did not break the object"; exit 1; }
  echo "ok: $label impact, 3 processes (the third in SSE2), $fragments fragments, fingerprint $fp"
  computed+=("$label $fp")
done

if [ "$pin" = --pin ]; then
  {
    echo "# Fracture fingerprints of the main job's four impacts on the default objects (and the"
    echo "# plate's with cracks that end at cracks) as"
    echo "# tests/tools/determinism_across_processes.sh bakes them. Re-pin after an intended change:"
    echo "#   bash tests/tools/determinism_across_processes.sh build/bin/brittle . --pin"
    printf '%s\n' "${computed[@]}"
  } > "$golden"
  echo "pinned: $golden"
  exit 0
fi
for line in "${computed[@]}"; do
  read -r object fp <<<"$line"
  want=$(awk -v o="$object" '$1 == o { print $2 }' "$golden")
  if [ "$fp" != "$want" ]; then
    echo "FAIL: the $object impact's fingerprint $fp is not the pinned $want ($golden)."
    echo "      If the change was meant to change fractures, re-pin:"
    echo "      bash tests/tools/determinism_across_processes.sh build/bin/brittle . --pin"
    exit 1
  fi
done
echo "ok: all ${#computed[@]} fingerprints equal the pinned values"

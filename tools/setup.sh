#!/usr/bin/env bash
# Installs every Debian package brittle needs, then configures and builds into build/ (Release).
#   tools/setup.sh            Release build in build/: everything (libraries, CLI, tests, benchmarks)
#   tools/setup.sh --main     Release build in build/: the CLI alone (what the main job runs)
#   tools/setup.sh --asan     ASan + UBSan build in build-asan/
# Safe to re-run: apt-get skips what is installed and the build is incremental.
set -euo pipefail
cd "$(dirname "$0")/.."

PACKAGES=(cmake g++ pkg-config make ninja-build ccache
  libeigen3-dev libarpack2-dev libcgal-dev libopenvdb-dev libboost-iostreams-dev libhdf5-dev
  libblas-dev liblapack-dev libflann-dev libceres-dev calculix-ccx libhnswlib-dev libfaiss-dev libopenmpi-dev openmpi-bin libsuitesparse-dev libmetis-dev libtbb-dev libspectra-dev libcli11-dev nlohmann-json3-dev
  libgtest-dev libbenchmark-dev python3-matplotlib python3-numpy python3-h5py)
# The player (brittle play): Bullet for the rigid bodies, tinygltf for the replays.
PACKAGES+=(libbullet-dev libtinygltf-dev)
# The viewer (brittle view) and rendered frames: GLFW, OpenGL, Dear ImGui, stb for PNG; Xvfb and
# Mesa's software renderer run it without a display (tests, CI).
PACKAGES+=(libglfw3-dev libgl-dev libimgui-dev libstb-dev xvfb xauth libgl1-mesa-dri)

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
# The tests fetch Debian's libcgal-demo meshes with apt-get download, which needs package lists.
if [ ${#missing[@]} -gt 0 ] || ! ls /var/lib/apt/lists/*_Packages >/dev/null 2>&1; then
  echo "setup: installing ${missing[*]:-(package lists only)}"
  $SUDO apt-get update -qq
  if [ ${#missing[@]} -gt 0 ]; then
    # --force-unsafe-io: dpkg without an fsync per unpacked file, most of its time on a fresh
    # machine's hundreds of packages (a crash mid-install needs a re-run, as any failed install).
    $SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
      -o Dpkg::Options::=--force-unsafe-io "${missing[@]}" >/dev/null
  fi
fi

preset=release
targets=()
case "${1:-}" in
  "") ;;
  --asan) preset=asan ;;
  --main) targets=(--target brittle) ;;
  *) echo "usage: tools/setup.sh [--main | --asan]" >&2; exit 2 ;;
esac
cmake --preset "$preset" >/dev/null
# Two cores: two jobs. The Mesh_3 unit needs ~4.3 GiB of compiler memory on its own.
cmake --build --preset "$preset" -j 2 "${targets[@]}"

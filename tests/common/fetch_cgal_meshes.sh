#!/usr/bin/env bash
# Fetches the sample meshes of Debian's libcgal-demo package into $1 (data/meshes/*.off).
# They are real meshes nobody in this project wrote; they are fetched at test time, never committed.
set -euo pipefail
dest=${1:?usage: fetch_cgal_meshes.sh DEST_DIR}
mkdir -p "$dest"
cd "$dest"
# Tests run in parallel processes: one fetches, the others wait for it.
exec 9>"$dest/.lock"
flock 9
if [ -f data/meshes/.complete ]; then exit 0; fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
(cd "$work" && apt-get download libcgal-demo >/dev/null 2>&1) || {
  echo "fetch_cgal_meshes: 'apt-get download libcgal-demo' failed (run apt-get update?)" >&2; exit 1; }
dpkg-deb -x "$work"/libcgal-demo_*.deb "$work/x"
tar -xzf "$work/x/usr/share/doc/libcgal-dev/data.tar.gz" -C "$dest" data/meshes
test -f data/meshes/elephant.off
touch data/meshes/.complete

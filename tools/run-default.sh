#!/usr/bin/env bash
# The main job, end to end on the bundled default assets: install, build, bake the default pack
# (four objects and a 70-entry fragment database, its bodies' frequency errors calibrated), break each object with one impact, play the
# default scenes (assets/scenes/) in the Bullet player, print the results and write the fragments,
# the replays and their pictures.
# Output: out/default.h5 (+ out/default.json, its inspection), out/impacts/<object>.json,
# out/fragments/<object>/fragment-NN.off, out/pictures/<object>.png, out/replays/<scene>.glb,
# out/play/<scene>.json (statistics per event and frame), out/pictures/<scene>.png, and frames of
# the pane drawn by the viewer's renderer (out/frames/ball-through-pane/frame_NNNNNN.png, under
# xvfb-run when there is no display).
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/setup.sh --main  # the CLI alone: the tests are built by tools/run-tests.sh
rm -rf out/impacts out/fragments out/pictures out/replays out/play out/frames
mkdir -p out/impacts out/fragments out/replays out/play out/frames
build/bin/brittle bake --manifest assets/default-pack.json --out out/default.h5
# How far the matched bodies' own frequencies are off, calibrated on the objects' own fragments
# (about 2 min; World::frequencyError and `brittle impact` report it). Not at the default scenes'
# impacts (--scene): their models escalate more pieces to P2 checks, and the pane scene's frames
# then wait for them (docs/results/speed-accuracy.md, "Calibrated at the scene's own impacts").
build/bin/brittle calibrate-errors out/default.h5 --quiet > /dev/null
build/bin/brittle inspect out/default.h5 --json > out/default.json
echo "inspection JSON: out/default.json"

# One impact per object (points and normals in the object's frame; see assets/meshes/):
#   a 100 g steel ball at 5 m/s on the glass pane, the same ball at 10 m/s on the vase's side,
#   the brick dropped on a corner at 10 m/s, the stone ball dropped at 15 m/s (the ground is an
#   immovable flat impactor).
impact() {
  local object=$1
  shift
  echo
  build/bin/brittle impact out/default.h5 --object "$object" "$@" --out "out/fragments/$object"
  build/bin/brittle impact out/default.h5 --object "$object" "$@" --json > "out/impacts/$object.json"
}
impact glass-plate --point 0.02,0.01,0.005 --normal 0,0,1 --speed 5 --impactor-mass 0.1 --impactor-radius 0.02
impact porcelain-vase --point 0.0741,0,0.12 --normal 1,0,0 --speed 10 --impactor-mass 0.1 --impactor-radius 0.02
impact brick --point 0.1075,0.05125,0.0325 --normal 0.7,0.5,0.5 --speed 10 --impactor-mass inf --impactor-radius inf
impact stone-ball --point 0,0,-0.1 --normal 0,0,-1 --speed 15 --impactor-mass inf --impactor-radius inf
echo
/usr/bin/python3 tools/scripts/plot_fragments.py out/fragments/* --out out/pictures

# The default scenes: impacts come from Bullet's contacts, fragments become bodies and break again.
for scene in assets/scenes/*.json; do
  name=$(basename "$scene" .json)
  echo
  build/bin/brittle play out/default.h5 "$scene" --out "out/replays/$name.glb" --out-stats "out/play/$name.json"
done
echo
/usr/bin/python3 tools/scripts/plot_replay.py out/replays/*.glb --out out/pictures

# Frames of one scene drawn by the renderer (every 24th frame, 0.1 s apart); Xvfb and Mesa when
# there is no display.
draw=()
if [ -z "${DISPLAY:-}" ]; then draw=(xvfb-run -a -s "-screen 0 1280x800x24"); fi
"${draw[@]}" build/bin/brittle play out/default.h5 assets/scenes/ball-through-pane.json --frames out/frames/ball-through-pane \
  --frame-every 24 --frame-size 960x540 > /dev/null
echo "frames: $(ls out/frames/ball-through-pane | wc -l) pictures in out/frames/ball-through-pane/"

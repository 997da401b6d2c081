#!/usr/bin/env bash
# The viewer and the drawn frames under Xvfb with Mesa's software renderer:
#   1. `brittle view --script`: a static glass plate, a steel ball thrown at it; the screenshot
#      after the impact is not blank, and the viewer's own body count after the impact is greater
#      than before the throw plus the ball (the plate broke into fragments);
#   2. `brittle play --frames`: the expected number of PNG files, each not blank;
#   3. without a display, `brittle view` fails with a message that names xvfb-run.
#   view_under_xvfb.sh BRITTLE_CLI SOURCE_DIR
set -euo pipefail
cli=$1
src=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
export LIBGL_ALWAYS_SOFTWARE=1
# The processes that open a GL context run without LeakSanitizer in the sanitized build: Mesa's
# driver is unloaded at exit, so LSan reports its process-lifetime allocations from an unknown
# module that no suppression can name. AddressSanitizer and UBSan stay on; the bake and the play
# without frames keep leak checking. (Harmless in the Release build.)
gl=(env "ASAN_OPTIONS=${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_leaks=0")
"$cli" bake --mesh "$src/assets/meshes/plate.off" --material glass --name glass-plate --tets 3000 --modes 12 --quiet \
  --out "$work/plate.h5" >/dev/null
cat > "$work/pane.json" <<'JSON'
{ "duration": 0.5, "time_step": 0.004166667, "substeps": 2, "seed": 3,
  "floor": { "height": 0.0, "material": "concrete" },
  "objects": [ { "asset": "glass-plate", "name": "pane", "position": [0, 0, 0.4], "static": true } ] }
JSON
cat > "$work/script.json" <<JSON
{ "events": [
  { "frame": 10, "action": "screenshot", "file": "$work/before.png" },
  { "frame": 10, "action": "throw", "from": [0.05, -0.4, 0.9], "to": [0, 0, 0.4], "speed": 12, "radius": 0.03, "mass": 0.5 },
  { "frame": 90, "action": "camera", "yaw_deg": 60, "pitch_deg": 35 },
  { "frame": 100, "action": "screenshot", "file": "$work/after.png" },
  { "frame": 101, "action": "quit" } ] }
JSON
xvfb-run -a -s "-screen 0 1024x768x24" "${gl[@]}" "$cli" view "$work/plate.h5" "$work/pane.json" --script "$work/script.json" \
  --report "$work/report.json" --size 640x400
/usr/bin/python3 - "$work" <<'PY'
import json, sys
import matplotlib.image as mpimg
import numpy as np
work = sys.argv[1]
report = json.load(open(f"{work}/report.json"))
events = report["events"]
throw = next(e for e in events if e["action"] == "throw")
after = next(e for e in events if e["action"] == "screenshot" and e["file"].endswith("after.png"))
print(f"bodies: {throw['bodies']} before the throw, {after['bodies']} after the impact; breaks {report['breaks']}")
assert after["bodies"] > throw["bodies"] + 1, "the plate did not break into more bodies"
images = {}
for name in ("before.png", "after.png"):
    image = mpimg.imread(f"{work}/{name}")
    assert image.shape[:2] == (400, 640), image.shape
    rgb = (image[..., :3] * 255).astype(np.uint8).reshape(-1, 3)
    colours = len(np.unique(rgb, axis=0))
    spread = float(rgb.std())
    print(f"{name}: {colours} colours, pixel spread {spread:.1f}")
    assert colours >= 8 and spread > 10, f"{name} looks blank"  # a blank picture has one colour
    images[name] = rgb.astype(float)
change = float(np.abs(images["after.png"] - images["before.png"]).mean())
print(f"mean change between the two pictures: {change:.1f}")
assert change > 1.0, "the picture did not change after the impact"
PY
# Frames of a play: frame 0 and every 20th of 120.
"$cli" play "$work/plate.h5" "$work/pane.json" --json > /dev/null  # no display needed without --frames
xvfb-run -a -s "-screen 0 1024x768x24" "${gl[@]}" "$cli" play "$work/plate.h5" "$src/assets/scenes/plate-drop.json" \
  --frames "$work/frames" --frame-every 20 --frame-size 320x200 > /dev/null
count=$(ls "$work/frames" | grep -c '^frame_[0-9]\{6\}\.png$')
echo "frames: $count"
[ "$count" -eq 19 ] || { echo "expected 19 frames (0, 20, ..., 360)"; exit 1; }
/usr/bin/python3 - "$work/frames" <<'PY'
import pathlib, sys
import matplotlib.image as mpimg
import numpy as np
for path in sorted(pathlib.Path(sys.argv[1]).glob("frame_*.png")):
    image = mpimg.imread(path)
    assert image.shape[:2] == (200, 320), (path, image.shape)
    assert float((image[..., :3] * 255).std()) > 5, f"{path.name} looks blank"
PY
# No display: a clear error, not a crash.
if out=$(env -u DISPLAY -u WAYLAND_DISPLAY "${gl[@]}" "$cli" view "$work/plate.h5" "$work/pane.json" 2>&1); then
  echo "view without a display should fail"; exit 1
fi
echo "$out" | grep -q "xvfb-run" || { echo "no hint at xvfb-run: $out"; exit 1; }
echo "viewer under Xvfb: ok"

#!/usr/bin/env bash
# A replay of a default scene passes the Khronos glTF-Validator (npm), and every body node is
# animated: bakes a small plate with the CLI, plays assets/scenes/plate-drop.json with --out and
# validates the .glb (tools/scripts/validate-gltf.sh installs the validator into out/node/).
#   validate_replay.sh BRITTLE_CLI SOURCE_DIR
set -euo pipefail
cli=$1
src=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$cli" bake --mesh "$src/assets/meshes/plate.off" --material glass --name glass-plate --tets 3000 --modes 12 --quiet \
  --out "$work/plate.h5" >/dev/null
"$cli" play "$work/plate.h5" "$src/assets/scenes/plate-drop.json" --out "$work/plate-drop.glb" --json > "$work/stats.json"
grep -q '"breaks": [1-9]' "$work/stats.json" || { echo "the plate did not break"; exit 1; }
report=$(bash "$src/tools/scripts/validate-gltf.sh" "$work/plate-drop.glb")
echo "$report"
echo "$report" | grep -q ": 0 errors, 0 warnings" || { echo "the replay has validator errors or warnings"; exit 1; }
# Every body node carries translation, rotation and scale channels.
node - "$work/plate-drop.glb" <<'JS'
const fs = require('fs');
const bytes = fs.readFileSync(process.argv[2]);
const jsonLength = bytes.readUInt32LE(12);
const doc = JSON.parse(bytes.subarray(20, 20 + jsonLength).toString('utf8'));
const animated = new Map();
for (const a of doc.animations || []) for (const c of a.channels) {
  if (!animated.has(c.target.node)) animated.set(c.target.node, new Set());
  animated.get(c.target.node).add(c.target.path);
}
const bodies = doc.nodes.map((n, i) => [n, i]).filter(([n]) => n.mesh !== undefined);
const missing = bodies.filter(([, i]) => !['translation', 'rotation', 'scale'].every((p) => (animated.get(i) || new Set()).has(p)));
console.log(`${bodies.length} body nodes, ${missing.length} not fully animated`);
process.exit(bodies.length > 1 && missing.length === 0 ? 0 : 1);
JS

#!/usr/bin/env bash
# Validates glTF replays (brittle play --out replay.glb) with the Khronos glTF-Validator from npm.
#   tools/scripts/validate-gltf.sh out/replays/*.glb
# Installs the validator once into out/node/ (not committed). Exit code 1 if any file has errors.
set -euo pipefail
cd "$(dirname "$0")/../.."
if [ ! -d out/node/node_modules/gltf-validator ]; then
  mkdir -p out/node
  npm install --prefix out/node --no-audit --no-fund --silent gltf-validator@2.0.0-dev.3.10 >/dev/null
fi
NODE_PATH=out/node/node_modules node - "$@" <<'JS'
const fs = require('fs');
const validator = require('gltf-validator');
(async () => {
  let failed = false;
  for (const file of process.argv.slice(2)) {
    const report = await validator.validateBytes(new Uint8Array(fs.readFileSync(file)), { maxIssues: 20 });
    const i = report.issues;
    console.log(`${file}: ${i.numErrors} errors, ${i.numWarnings} warnings, ${i.numInfos} infos, ${i.numHints} hints`);
    for (const m of i.messages.filter((m) => m.severity <= 1)) console.log(`  ${m.severity === 0 ? 'error' : 'warning'} ${m.code}: ${m.message} (${m.pointer || ''})`);
    failed = failed || i.numErrors > 0;
  }
  process.exit(failed ? 1 : 0);
})();
JS

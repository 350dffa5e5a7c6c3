// Validates glTF files with the Khronos glTF validator (npm gltf-validator) and fails on any error.
// Usage: node validate_gltf.mjs FILE... ; exit 0 when every file has 0 errors, 1 otherwise, 2 on bad use.
// Prints one line per file: errors, warnings, infos and the first messages of each severity.
import fs from 'node:fs';
import path from 'node:path';
import { createRequire } from 'node:module';

const require = createRequire(process.env.PTERYLA_NODE_MODULES ? path.join(process.env.PTERYLA_NODE_MODULES, 'x.js') : import.meta.url);
const validator = require('gltf-validator');

const files = process.argv.slice(2);
if (files.length === 0) {
  console.error('usage: node validate_gltf.mjs FILE...');
  process.exit(2);
}
let failed = false;
for (const file of files) {
  const bytes = new Uint8Array(fs.readFileSync(file));
  const report = await validator.validateBytes(bytes, {
    uri: path.basename(file),
    maxIssues: 0,
    externalResourceFunction: (uri) => Promise.reject(new Error('external resource ' + uri + ': pteryla exports are self-contained')),
  });
  const i = report.issues;
  console.log(`${file}: ${i.numErrors} errors, ${i.numWarnings} warnings, ${i.numInfos} infos, ${i.numHints} hints`);
  const shown = {};
  for (const m of i.messages) {
    shown[m.severity] = (shown[m.severity] || 0) + 1;
    if (shown[m.severity] <= 5) console.log(`  [${['error', 'warning', 'info', 'hint'][m.severity]}] ${m.code} ${m.pointer || ''}: ${m.message}`);
  }
  const info = report.info || {};
  console.log(`  info: ${JSON.stringify({ version: info.version, generator: info.generator, extensionsUsed: info.extensionsUsed, animationCount: info.animationCount, materialCount: info.materialCount, totalTriangleCount: info.totalTriangleCount })}`);
  if (i.numErrors > 0) failed = true;
}
process.exit(failed ? 1 : 0);

// node validate_gltf.mjs FILE.glb: Khronos' glTF-Validator (npm gltf-validator) on one file.
// Prints the report's counts (errors, warnings, infos, hints) and every error and warning
// (code, JSON pointer, message); exits 1 on any error, or when the file cannot be read, 0
// otherwise (warnings are reported, not refused).
import { readFileSync } from 'node:fs';
import { validateBytes } from 'gltf-validator';

const file = process.argv[2];
if (!file) {
  console.error('usage: node validate_gltf.mjs FILE.glb');
  process.exit(2);
}
let bytes;
try {
  bytes = new Uint8Array(readFileSync(file));
} catch (e) {
  console.error(`validate_gltf: cannot read '${file}': ${e.message}`);
  process.exit(1);
}
const severities = ['error', 'warning', 'info', 'hint'];
try {
  const report = await validateBytes(bytes, { uri: file, maxIssues: 0 });
  const i = report.issues;
  console.log(`${file}: ${i.numErrors} errors, ${i.numWarnings} warnings, ${i.numInfos} infos, ${i.numHints} hints`);
  for (const m of i.messages) {
    if (m.severity > 1) continue;
    console.log(`  ${severities[m.severity]} ${m.code} at ${m.pointer || '/'}: ${m.message}`);
  }
  const info = report.info || {};
  console.log(`  ${info.drawCallCount ?? '?'} draw calls, ${info.totalVertexCount ?? '?'} vertices, ` +
              `${(info.resources || []).filter((r) => r.pointer.startsWith('/images')).length} images, ` +
              `extensions: ${(info.extensionsUsed || []).join(', ') || 'none'}`);
  process.exit(i.numErrors > 0 ? 1 : 0);
} catch (e) {
  console.error(`validate_gltf: '${file}' could not be validated: ${e.message || e}`);
  process.exit(1);
}

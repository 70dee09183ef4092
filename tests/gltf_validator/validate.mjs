// The Khronos glTF validator for tests/city_scene.rs: validates the glTF
// or GLB file named on the command line, loading its external buffers
// from beside it, and writes the validator's JSON report to stdout.

import { readFile } from 'node:fs/promises';
import path from 'node:path';
import validator from 'gltf-validator';

const file = process.argv[2];
if (!file) {
  console.error('usage: node validate.mjs FILE.gltf');
  process.exit(2);
}
const bytes = await readFile(file);
const report = await validator.validateBytes(new Uint8Array(bytes), {
  uri: path.basename(file),
  maxIssues: 0,
  externalResourceFunction: async (uri) =>
    new Uint8Array(await readFile(path.resolve(path.dirname(file), decodeURIComponent(uri)))),
});
process.stdout.write(JSON.stringify(report, null, 2));

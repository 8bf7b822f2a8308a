// Runs the Khronos glTF validator on one .gltf or .glb and prints a one-line JSON summary:
// {"file", "numErrors", "numWarnings", "errors": {CODE: count}, "codes": {CODE: count}}
// ("codes": every severity, infos such as UNUSED_OBJECT and hints included). External resources are
// read relative to the file. Exit 0 when the validator ran (whatever it found), 2 when not.
import { readFile } from 'node:fs/promises';
import path from 'node:path';
import { createRequire } from 'node:module';

const require = createRequire(import.meta.url);
const validator = require('gltf-validator');

const file = process.argv[2];
if (!file) {
  console.error('usage: node validate-gltf.mjs FILE.gltf|FILE.glb');
  process.exit(2);
}
try {
  const bytes = new Uint8Array(await readFile(file));
  const report = await validator.validateBytes(bytes, {
    uri: path.basename(file),
    maxIssues: 0,
    externalResourceFunction: (uri) =>
      readFile(path.resolve(path.dirname(file), decodeURIComponent(uri))).then((b) => new Uint8Array(b)),
  });
  const errors = {}, codes = {};
  for (const m of report.issues.messages) {
    if (m.severity === 0) errors[m.code] = (errors[m.code] || 0) + 1;
    codes[m.code] = (codes[m.code] || 0) + 1;
  }
  console.log(JSON.stringify({
    file,
    numErrors: report.issues.numErrors,
    numWarnings: report.issues.numWarnings,
    errors,
    codes,
  }));
} catch (e) {
  console.error(`validate-gltf: ${file}: ${e.message ?? e}`);
  process.exit(2);
}

// Validates glTF/GLB files with the Khronos glTF-Validator (npm package gltf-validator) and
// prints one JSON line per file: counts of errors, warnings, infos and hints, and the errors'
// and warnings' messages. Exits 1 when any file has an error. Used by tests/integration/export.rs and
// tests/integration/import_features.rs where `npm ci --prefix tools/gltf` has installed it.
const fs = require('fs');
const path = require('path');
const validator = require('gltf-validator');

(async () => {
  let failed = false;
  for (const file of process.argv.slice(2)) {
    const bytes = new Uint8Array(fs.readFileSync(file));
    const report = await validator.validateBytes(bytes, {
      uri: file,
      externalResourceFunction: (uri) =>
        Promise.resolve(new Uint8Array(fs.readFileSync(path.resolve(path.dirname(file), decodeURIComponent(uri))))),
    });
    const issues = report.issues;
    const messages = issues.messages
      .filter((m) => m.severity <= 1)
      .map((m) => `${m.code}: ${m.message} (${m.pointer || ''})`);
    console.log(JSON.stringify({
      file,
      errors: issues.numErrors,
      warnings: issues.numWarnings,
      infos: issues.numInfos,
      hints: issues.numHints,
      messages: messages.slice(0, 20),
    }));
    if (issues.numErrors > 0) failed = true;
  }
  process.exit(failed ? 1 : 0);
})();

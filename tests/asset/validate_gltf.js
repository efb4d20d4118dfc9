// Validates glTF files with the Khronos glTF validator (npm package gltf-validator):
//   node validate_gltf.js FILE...
// Prints one line per file (errors, warnings, and the first errors' codes and pointers) and
// exits 1 if any file has an error, 2 if the validator is not installed.
"use strict";
const fs = require("fs");
const path = require("path");

let validator;
try {
  validator = require("gltf-validator");
} catch (e) {
  console.error("validate_gltf.js: the npm package gltf-validator is not installed (cmake/bootstrap.sh test installs it): " + e.message);
  process.exit(2);
}

async function validate(file) {
  const bytes = new Uint8Array(fs.readFileSync(file));
  const folder = path.dirname(file);
  const report = await validator.validateBytes(bytes, {
    uri: path.basename(file),
    maxIssues: 100,
    externalResourceFunction: (uri) =>
      new Promise((resolve, reject) => {
        fs.readFile(path.join(folder, decodeURIComponent(uri)), (error, data) => (error ? reject(error.toString()) : resolve(new Uint8Array(data))));
      }),
  });
  const errors = report.issues.messages.filter((m) => m.severity === 0);
  const first = errors.slice(0, 5).map((m) => `${m.code} at ${m.pointer}: ${m.message}`).join("; ");
  console.log(`${file}: ${report.issues.numErrors} errors, ${report.issues.numWarnings} warnings${first ? " - " + first : ""}`);
  return report.issues.numErrors;
}

(async () => {
  let failed = 0;
  for (const file of process.argv.slice(2)) {
    try {
      if ((await validate(file)) > 0) failed += 1;
    } catch (e) {
      console.log(`${file}: the validator failed: ${e}`);
      failed += 1;
    }
  }
  process.exit(failed > 0 ? 1 : 0);
})();

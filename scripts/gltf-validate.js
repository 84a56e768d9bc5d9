#!/usr/bin/env node
// Validates one .gltf/.glb/.vrm file with the Khronos glTF-Validator (npm gltf-validator, installed
// into .tools/ by scripts/install-validator.sh) and prints a one-line JSON summary:
//   {"uri":..., "numErrors":N, "numWarnings":N, "numInfos":N, "numHints":N,
//    "issues":[{"code","severity","pointer","message"}, ...]}   (errors and warnings only)
// Exit status: 0 no errors, 1 the file has errors, 2 usage or unreadable file, 3 validator missing.
// Usage: node scripts/gltf-validate.js FILE [--full]   (--full prints the validator's whole report)
'use strict';

const fs = require('fs');
const path = require('path');

const args = process.argv.slice(2);
const full = args.includes('--full');
const files = args.filter((a) => a !== '--full');
if (files.length !== 1) {
  console.error('usage: node scripts/gltf-validate.js FILE [--full]');
  process.exit(2);
}
const file = path.resolve(files[0]);

const packageDir = process.env.RIGBAKE_GLTF_VALIDATOR ||
    path.join(__dirname, '..', '.tools', 'node_modules', 'gltf-validator');
let validator;
try {
  validator = require(packageDir);
} catch (error) {
  console.error('gltf-validator is not installed at ' + packageDir + ' (run scripts/install-validator.sh)');
  process.exit(3);
}

let bytes;
try {
  bytes = fs.readFileSync(file);
} catch (error) {
  console.error('cannot read ' + file + ': ' + error.message);
  process.exit(2);
}

// Severities of the validator's report: 0 error, 1 warning, 2 info, 3 hint.
const kSeverityNames = ['error', 'warning', 'info', 'hint'];

validator.validateBytes(new Uint8Array(bytes), {
  uri: path.basename(file),
  maxIssues: 0,
  writeTimestamp: false,
  // External buffers and images of a .gltf are looked up beside it, so they are validated too.
  externalResourceFunction: (uri) => new Promise((resolve, reject) => {
    const resource = path.resolve(path.dirname(file), decodeURIComponent(uri));
    fs.readFile(resource, (error, data) => (error ? reject(error.toString()) : resolve(new Uint8Array(data))));
  }),
}).then((report) => {
  if (full) {
    console.log(JSON.stringify(report, null, 2));
  } else {
    const issues = report.issues;
    console.log(JSON.stringify({
      uri: report.uri,
      numErrors: issues.numErrors,
      numWarnings: issues.numWarnings,
      numInfos: issues.numInfos,
      numHints: issues.numHints,
      issues: issues.messages.filter((m) => m.severity <= 1).map((m) => ({
        code: m.code,
        severity: kSeverityNames[m.severity],
        pointer: m.pointer,
        message: m.message,
      })),
    }));
  }
  process.exit(report.issues.numErrors > 0 ? 1 : 0);
}, (error) => {
  console.error('gltf-validator could not read ' + file + ': ' + error);
  process.exit(2);
});

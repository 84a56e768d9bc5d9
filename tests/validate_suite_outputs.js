#!/usr/bin/env node
// The Khronos glTF-Validator over every glTF, GLB and VRM any case of the suite made rigbake write
// (issue 34: "no NaN in any output, the validator run on every output of the suite"). The suite's
// ctests run with RIGBAKE_KEEP_OUTPUTS=FOLDER (tests/CMakeLists.txt), so every model a run commits is
// also copied there however briefly its case kept it; this runs last (a ctest fixture's cleanup).
//
// Per distinct file (by SHA-256: the determinism cases write the same bytes many times) it asks for 0
// validator errors and no JSON null anywhere in the document: glTF has no null value, and a NaN or an
// infinity reaches JSON as null (nlohmann's dump), which the validator does not see inside an
// extension it does not know (RIGBAKE_muscle_rig's "restLength": null, issue 34).
//
// usage: node validate_suite_outputs.js REPO FOLDER
// exit: 0 all valid, 1 some file is not, 2 usage or the validator is missing, 77 nothing was kept
// (a selection of cases that wrote no model; tests/cli_test.cpp checks that the copies are made).
'use strict';

const crypto = require('crypto');
const fs = require('fs');
const path = require('path');

const [repo, folder] = process.argv.slice(2);
if (!repo || !folder) {
  console.error('usage: node validate_suite_outputs.js REPO FOLDER');
  process.exit(2);
}
let validator;
try {
  validator = require(process.env.RIGBAKE_GLTF_VALIDATOR || path.join(repo, '.tools', 'node_modules', 'gltf-validator'));
} catch (error) {
  console.error('gltf-validator is not installed (run scripts/install-validator.sh)');
  process.exit(2);
}

// The JSON of a .gltf, or of a GLB's (and VRM's) first chunk.
function documentJson(bytes) {
  if (bytes.length >= 20 && bytes.readUInt32LE(0) === 0x46546c67) {
    const length = bytes.readUInt32LE(12);
    return bytes.subarray(20, 20 + length).toString('utf8');
  }
  return bytes.toString('utf8');
}

// JSON pointers of every null in `value`.
function nullsIn(value, pointer, found) {
  if (value === null) {
    found.push(pointer || '/');
  } else if (Array.isArray(value)) {
    value.forEach((item, i) => nullsIn(item, pointer + '/' + i, found));
  } else if (typeof value === 'object') {
    for (const key of Object.keys(value)) nullsIn(value[key], pointer + '/' + key.replace(/~/g, '~0').replace(/\//g, '~1'), found);
  }
  return found;
}

async function main() {
  // As bytes: a case writes a file whose name is not UTF-8 (tests/cli_test.cpp), which a string would mangle.
  const names = fs.existsSync(folder)
    ? fs.readdirSync(folder, { encoding: 'buffer' }).filter((n) => /\.(glb|gltf|vrm)$/.test(n.toString('latin1')))
        .sort(Buffer.compare)
    : [];
  if (names.length === 0) {
    console.log('no model was written by the cases run (skipped)');
    return 77;
  }
  const seen = new Map();  // SHA-256 -> first name
  let failures = 0;
  for (const name of names) {
    const bytes = fs.readFileSync(Buffer.concat([Buffer.from(folder + path.sep), name]));
    const hash = crypto.createHash('sha256').update(bytes).digest('hex');
    if (seen.has(hash)) continue;
    seen.set(hash, name.toString('latin1'));
    const problems = [];
    let json = null;
    try {
      json = JSON.parse(documentJson(bytes));
    } catch (error) {
      problems.push('JSON: ' + error.message);
    }
    if (json !== null) {
      const nulls = nullsIn(json, '', []);
      if (nulls.length > 0) problems.push(nulls.length + ' null value(s) (a NaN or infinity?) at ' + nulls.slice(0, 5).join(', '));
    }
    const report = await validator.validateBytes(new Uint8Array(bytes), { uri: name.toString('latin1'), maxIssues: 0, writeTimestamp: false });
    for (const message of report.issues.messages) {
      if (message.severity === 0) problems.push(message.code + ' ' + (message.pointer || '') + ': ' + message.message);
    }
    if (problems.length > 0) {
      ++failures;
      console.log('FAILED ' + name.toString('latin1') + ': ' + problems.slice(0, 5).join('; '));
    }
  }
  console.log(`${names.length} models written, ${seen.size} distinct, ${failures} with errors ` +
              '(Khronos glTF-Validator errors or JSON nulls)');
  return failures > 0 ? 1 : 0;
}

main().then((code) => process.exit(code), (error) => {
  console.error(error && error.stack ? error.stack : String(error));
  process.exit(2);
});

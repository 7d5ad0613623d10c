// Validates every .gltf/.glb in a folder with the Khronos glTF validator and fails on any error or
// warning (printing each message). Usage: node validate_gltf.js <dir> <expected file count>
// The validator module is found through NODE_PATH (the test sets it to .deps/npm/node_modules).
'use strict';
const fs = require('fs');
const path = require('path');
const validator = require('gltf-validator');

const kSeverityNames = ['error', 'warning', 'info', 'hint'];

async function validateFile(file) {
  const dir = path.dirname(file);
  const report = await validator.validateBytes(new Uint8Array(fs.readFileSync(file)), {
    uri: path.basename(file),
    maxIssues: 0,  // report every issue
    externalResourceFunction: (uri) =>
      new Promise((resolve, reject) => {
        fs.readFile(path.join(dir, decodeURIComponent(uri)), (err, data) =>
          err ? reject(err.toString()) : resolve(new Uint8Array(data)));
      }),
  });
  const issues = report.issues;
  const bad = issues.messages.filter((m) => m.severity <= 1);
  for (const m of bad)
    console.log(`${path.basename(file)}: ${kSeverityNames[m.severity]} ${m.code} at ${m.pointer || '-'}: ${m.message}`);
  const info = report.info || {};
  console.log(`${path.basename(file)}: ${issues.numErrors} errors, ${issues.numWarnings} warnings, ` +
              `${issues.numInfos} infos, ${issues.numHints} hints; ` +
              `${info.totalVertexCount} vertices, ${info.totalTriangleCount} triangles`);
  return issues.numErrors + issues.numWarnings;
}

async function main() {
  if (process.argv.length !== 4) {
    console.log('usage: node validate_gltf.js <dir> <expected file count>');
    return 2;
  }
  const dir = process.argv[2];
  const expected = Number(process.argv[3]);
  const files = fs.readdirSync(dir).filter((f) => /\.(gltf|glb)$/i.test(f)).sort()
                  .map((f) => path.join(dir, f));
  if (files.length !== expected) {
    console.log(`expected ${expected} glTF files in ${dir}, found ${files.length}`);
    return 1;
  }
  let problems = 0;
  for (const file of files) {
    try {
      problems += await validateFile(file);
    } catch (e) {
      console.log(`${file}: validator failed: ${e}`);
      problems += 1;
    }
  }
  console.log(`${files.length} files, ${problems} errors+warnings`);
  return problems === 0 ? 0 : 1;
}

main().then((code) => process.exit(code));

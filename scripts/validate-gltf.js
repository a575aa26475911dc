// Validates glTF files with the Khronos glTF validator (the npm package gltf-validator,
// which scripts/setup.sh installs into .tools/node): prints each file's report and exits
// with 1 if any file has an error or a warning.
//
//   NODE_PATH=.tools/node/node_modules node scripts/validate-gltf.js FILE.gltf FILE.glb …
const fs = require("fs");
const path = require("path");
const validator = require("gltf-validator");

const SEVERITY = ["error", "warning", "info", "hint"];

async function check(file) {
  const report = await validator.validateBytes(new Uint8Array(fs.readFileSync(file)), {
    uri: path.basename(file),
    // External buffers (a .gltf's .bin) are read from beside the file.
    externalResourceFunction: (uri) =>
      fs.promises
        .readFile(path.join(path.dirname(file), decodeURIComponent(uri)))
        .then((data) => new Uint8Array(data)),
  });
  const issues = report.issues;
  console.log(
    `${file}: ${issues.numErrors} errors, ${issues.numWarnings} warnings, ` +
      `${issues.numInfos} infos, ${issues.numHints} hints`,
  );
  for (const m of issues.messages) {
    console.log(`  ${SEVERITY[m.severity]} ${m.code} ${m.pointer || ""}: ${m.message}`);
  }
  return issues.numErrors + issues.numWarnings;
}

(async () => {
  let bad = 0;
  for (const file of process.argv.slice(2)) {
    bad += await check(file);
  }
  process.exit(bad > 0 ? 1 : 0);
})().catch((e) => {
  console.error(e);
  process.exit(2);
});

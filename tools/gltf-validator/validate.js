// Validate glTF/GLB files with the Khronos validator; prints one JSON report per file.
// Usage: node validate.js FILE...
const fs = require("fs");
const path = require("path");
const validator = require("gltf-validator");

(async () => {
  for (const file of process.argv.slice(2)) {
    const report = await validator.validateBytes(new Uint8Array(fs.readFileSync(file)), {
      uri: path.basename(file),
      maxIssues: 100,
    });
    console.log(JSON.stringify({ file, issues: report.issues }));
  }
})().catch((err) => {
  console.error(err);
  process.exit(1);
});

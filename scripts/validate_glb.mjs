// Runs the Khronos glTF validator (npm package gltf-validator, its `validateBytes` API) on GLB
// files and writes one JSON report: {file: {errors, warnings, infos, hints, messages}}, each
// message as "SEVERITY CODE pointer: message". Used by scripts/check_engines.sh.
//
//   node scripts/validate_glb.mjs VALIDATOR_PREFIX REPORT.json FILE.glb...
//
// VALIDATOR_PREFIX is the folder given to `npm install --prefix` (it holds node_modules/).
// A file the validator cannot read at all is reported with one error. Exits 2 only on a usage
// error: the counts are judged by the caller.
import { createRequire } from "node:module";
import { readFileSync, writeFileSync } from "node:fs";
import { basename, join, resolve } from "node:path";

const [prefix, reportPath, ...files] = process.argv.slice(2);
if (!prefix || !reportPath || files.length === 0) {
    console.error("usage: node validate_glb.mjs VALIDATOR_PREFIX REPORT.json FILE.glb...");
    process.exit(2);
}
const require = createRequire(import.meta.url);
const validator = require(join(resolve(prefix), "node_modules", "gltf-validator"));
const severity = ["ERROR", "WARNING", "INFO", "HINT"];

const report = { validatorVersion: validator.version() };
for (const file of files) {
    try {
        const r = await validator.validateBytes(new Uint8Array(readFileSync(file)), {
            uri: basename(file),
            maxIssues: 0, // no limit
        });
        report[file] = {
            errors: r.issues.numErrors,
            warnings: r.issues.numWarnings,
            infos: r.issues.numInfos,
            hints: r.issues.numHints,
            truncated: r.issues.truncated,
            messages: r.issues.messages.map(
                (m) => `${severity[m.severity] ?? m.severity} ${m.code} ${m.pointer ?? ""}: ${m.message}`,
            ),
        };
    } catch (e) {
        // The validator rejects the promise when it cannot even detect the format.
        report[file] = { errors: 1, warnings: 0, infos: 0, hints: 0, messages: [`ERROR ${e}`] };
    }
}
writeFileSync(reportPath, JSON.stringify(report, null, 1));


// Runs Khronos glTF-Validator (npm gltf-validator) on .gltf/.glb files, resolving external resources next to
// each file; prints one JSON line per file: {file, ok, errors, warnings, infos, issues: [{code, severity,
// pointer, message}]} (severity 0 error, 1 warning, 2 info, 3 hint), or {file, ok: false, fatal} when the
// validator could not run on it.
// Usage: node gltf_validate.mjs FILE...
import validator from 'gltf-validator';
import { readFile } from 'node:fs/promises';
import { dirname, join } from 'node:path';

for (const file of process.argv.slice(2)) {
    try {
        const bytes = new Uint8Array(await readFile(file));
        const report = await validator.validateBytes(bytes, {
            uri: file,
            maxIssues: 0,
            externalResourceFunction: (uri) => readFile(join(dirname(file), decodeURIComponent(uri))).then((b) => new Uint8Array(b)),
        });
        const issues = report.issues;
        process.stdout.write(JSON.stringify({
            file, ok: true, validator: report.validatorVersion,
            errors: issues.numErrors, warnings: issues.numWarnings, infos: issues.numInfos,
            issues: issues.messages.map((m) => ({ code: m.code, severity: m.severity, pointer: m.pointer ?? '', message: m.message })),
        }) + '\n');
    } catch (e) {
        process.stdout.write(JSON.stringify({ file, ok: false, fatal: String(e?.message ?? e) }) + '\n');
    }
}

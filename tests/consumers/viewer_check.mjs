// Opens `specbake view` (the before/after viewer, web/three/viewer/) in headless Chromium (WebGL 2 on
// SwiftShader) and waits for the page's report: specbake serves the baked folder on a free port and writes
// the first report the page posts (after FRAMES frames) to RESULT.json, then exits.
// Usage: node viewer_check.mjs SPECBAKE OUT RESULT.json FRAMES WIDTHxHEIGHT [TIMEOUT_SECONDS] [QUERY]
// Exit 0: RESULT.json written; 3: no Chromium installed (the caller skips); 1: any other failure (stderr).
import { spawn, spawnSync } from 'node:child_process';
import { mkdtempSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';

const [specbake, out, resultPath, frames, size, timeoutArg, extraQuery] = process.argv.slice(2);
if (!specbake || !out || !resultPath || !frames || !size) {
    process.stderr.write('usage: node viewer_check.mjs SPECBAKE OUT RESULT.json FRAMES WIDTHxHEIGHT [TIMEOUT_SECONDS] [QUERY]\n');
    process.exit(1);
}
const names = process.env.SPECBAKE_CHROMIUM ? [process.env.SPECBAKE_CHROMIUM] : ['chromium', 'chromium-browser', 'google-chrome'];
const chromium = names.map((n) => spawnSync('sh', ['-c', `command -v ${n}`], { encoding: 'utf8' }))
    .find((r) => r.status === 0)?.stdout.trim();
if (!chromium) {
    process.stderr.write('no chromium on PATH (Debian package chromium)\n');
    process.exit(3);
}

const profile = mkdtempSync(join(tmpdir(), 'specbake_chromium_'));
let browser = null, finished = false;
const viewer = spawn(specbake, ['view', out, '--port', '0', '--report', resultPath], { stdio: ['ignore', 'pipe', 'pipe'] });
let stdout = '', stderr = '';
function finish(code, message) {
    if (finished) return;
    finished = true;
    if (message) process.stderr.write(`${message}\nspecbake view's stderr:\n${stderr}`);
    if (browser && browser.exitCode === null) browser.kill('SIGKILL');
    if (viewer.exitCode === null) viewer.kill('SIGTERM');
    setTimeout(() => {
        rmSync(profile, { recursive: true, force: true });
        process.exit(code);
    }, 200);
}
viewer.stderr.on('data', (d) => { stderr += d; });
viewer.on('exit', (code) => (code === 0 ? finish(0) : finish(1, `specbake view exited with ${code}`)));
viewer.stdout.on('data', (d) => {
    stdout += d;
    const url = /^(http:\/\/\S+)$/m.exec(stdout)?.[1];
    if (!url || browser) return;
    const [w, h] = size.split('x');
    const args = ['--headless=new', '--no-sandbox', `--user-data-dir=${profile}`, '--use-angle=swiftshader',
        '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist', '--no-first-run', '--no-default-browser-check',
        '--disable-extensions', '--disable-background-networking', '--disable-component-update', '--disable-sync',
        '--mute-audio', '--force-device-scale-factor=1', `--window-size=${w},${h}`,
        `${url}?report=${frames}${extraQuery ? `&${extraQuery}` : ''}`];
    browser = spawn(chromium, args, { stdio: ['ignore', 'ignore', 'pipe'] });
    let chromeErr = '';
    browser.stderr.on('data', (d) => { chromeErr = (chromeErr + d).slice(-4000); });
    browser.on('exit', (code) => finish(1, `chromium exited (${code}) before the page reported; its stderr:\n${chromeErr}`));
});
setTimeout(() => finish(1, `the viewer did not report within ${timeoutArg || 150} s`), 1000 * Number(timeoutArg || 150)).unref();

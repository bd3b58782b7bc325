// Runs three.js's loaders on specbake outputs in headless Chromium (WebGL 2 on SwiftShader): serves this
// folder and a data folder on 127.0.0.1, opens browser_page.html (or the page JOB.json names in "page",
// e.g. browser_shaders.html), which posts back what it read.
// Usage: node browser_check.mjs JOB.json DATA_DIR RESULT.json [TIMEOUT_SECONDS]
// Exit 0: RESULT.json written; 3: no Chromium installed (the caller skips); 1: any other failure (stderr).
import { spawn, spawnSync } from 'node:child_process';
import { createServer } from 'node:http';
import { mkdtempSync, readFileSync, rmSync, statSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { dirname, extname, join, normalize, resolve, sep } from 'node:path';
import { fileURLToPath } from 'node:url';

const [jobPath, dataDir, resultPath, timeoutArg] = process.argv.slice(2);
if (!jobPath || !dataDir || !resultPath) {
    process.stderr.write('usage: node browser_check.mjs JOB.json DATA_DIR RESULT.json [TIMEOUT_SECONDS]\n');
    process.exit(1);
}
const timeoutMs = 1000 * Number(timeoutArg || 150);
const here = dirname(fileURLToPath(import.meta.url));
const job = JSON.parse(readFileSync(jobPath, 'utf8'));
const page = job.page ?? 'browser_page.html';
if (!/^[\w-]+\.html$/.test(page)) {
    process.stderr.write(`JOB.json names a page that is not an .html file of ${here}: ${page}\n`);
    process.exit(1);
}

function findChromium() {
    const names = process.env.SPECBAKE_CHROMIUM ? [process.env.SPECBAKE_CHROMIUM] : ['chromium', 'chromium-browser', 'google-chrome'];
    for (const name of names) {
        const found = spawnSync('sh', ['-c', `command -v ${name}`], { encoding: 'utf8' });
        if (found.status === 0) return found.stdout.trim();
    }
    return null;
}
const chromium = findChromium();
if (!chromium) {
    process.stderr.write('no chromium on PATH (Debian package chromium)\n');
    process.exit(3);
}

const mime = { '.html': 'text/html', '.js': 'text/javascript', '.mjs': 'text/javascript', '.json': 'application/json',
    '.wasm': 'application/wasm' };
// Only files under `root` are served: the page asks for nothing else.
function serveFile(res, root, rel) {
    const file = resolve(root, normalize(decodeURIComponent(rel)));
    if (!file.startsWith(resolve(root) + sep)) return res.writeHead(403).end();
    try {
        if (!statSync(file).isFile()) throw new Error('not a file');
        res.writeHead(200, { 'Content-Type': mime[extname(file)] || 'application/octet-stream', 'Cache-Control': 'no-store' });
        res.end(readFileSync(file));
    } catch {
        res.writeHead(404).end();
    }
}

const log = [];
let browser = null;
let finished = false;
const profile = mkdtempSync(join(tmpdir(), 'specbake_chromium_'));
function finish(code, message) {
    if (finished) return;
    finished = true;
    if (message) process.stderr.write(message + '\n');
    if (code !== 0 && log.length) process.stderr.write('page log (last lines):\n  ' + log.slice(-20).join('\n  ') + '\n');
    if (browser && browser.exitCode === null) browser.kill('SIGKILL');
    server.close();
    setTimeout(() => {
        rmSync(profile, { recursive: true, force: true });
        process.exit(code);
    }, 200);
}

const server = createServer((req, res) => {
    const url = new URL(req.url, 'http://127.0.0.1');
    if (req.method === 'POST') {
        const chunks = [];
        req.on('data', (c) => chunks.push(c));
        req.on('end', () => {
            const body = Buffer.concat(chunks).toString('utf8');
            res.writeHead(204).end();
            if (url.pathname === '/log') log.push(body);
            else if (url.pathname === '/result') {
                writeFileSync(resultPath, body);
                finish(0);
            }
        });
        return;
    }
    if (url.pathname === '/job.json') return serveFile(res, dirname(resolve(jobPath)), jobPath.split(/[\\/]/).pop());
    if (url.pathname.startsWith('/data/')) return serveFile(res, dataDir, url.pathname.slice(6));
    // The project's own browser modules (web/three/), as an application would serve them.
    if (url.pathname.startsWith('/web/')) return serveFile(res, resolve(here, '../../web'), url.pathname.slice(5));
    return serveFile(res, here, url.pathname.slice(1));
});

server.listen(0, '127.0.0.1', () => {
    const { port } = server.address();
    // SwiftShader: the same software rasteriser on every machine, so the read-back values are deterministic.
    const args = ['--headless=new', '--no-sandbox', `--user-data-dir=${profile}`, '--use-angle=swiftshader',
        '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist', '--no-first-run', '--no-default-browser-check',
        '--disable-extensions', '--disable-background-networking', '--disable-component-update', '--disable-sync',
        '--mute-audio', '--window-size=256,256'];
    // WebGPU jobs (browser_wgsl.html): Chromium's WebGPU (Dawn) on its SwiftShader Vulkan adapter.
    if (job.webgpu) args.push('--enable-unsafe-webgpu', '--use-webgpu-adapter=swiftshader', '--enable-features=Vulkan');
    args.push(`http://127.0.0.1:${port}/${page}`);
    browser = spawn(chromium, args, { stdio: ['ignore', 'ignore', 'pipe'] });
    let stderr = '';
    browser.stderr.on('data', (d) => { stderr = (stderr + d).slice(-4000); });
    browser.on('exit', (code) => finish(1, `chromium exited (${code}) before the page reported; its stderr:\n${stderr}`));
    browser.on('error', (e) => finish(1, `cannot start ${chromium}: ${e.message}`));
});
setTimeout(() => finish(1, `the page did not report within ${timeoutMs / 1000} s`), timeoutMs).unref();

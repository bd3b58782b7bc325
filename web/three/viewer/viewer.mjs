// specbake's before/after viewer (index.html; `specbake view OUT` serves it with /viewer.json, the scene
// folder under /scene/ and three.js under /three/). The scene is loaded twice with GLTFLoader, KTX2Loader
// and SpecbakeSpecularAAPlugin: the left copy with every material opted out (three.js's own shading, with
// its geometryRoughness), the right one with specbake's filtering. Both halves are drawn from one camera
// orbiting the scene slowly, under three.js's RoomEnvironment (PMREM) and a directional light, so the
// highlights crawl over the surface and aliasing shows as flicker.
//
// Frame time: each half is drawn and then waited for (a one-pixel readPixels forces the GPU to finish), and
// the wall time between is that half's; the labels show the median over the last 60 frames.
//
// Query: ?scene=PATH picks a scene of /viewer.json, ?distance=D sets the distance slider, ?orbit=0 starts
// paused; ?report=N renders N frames, then posts /report: per
// half the median frame time and the mean colour and lit-pixel fraction read back from the canvas, the
// plugin's report, three.js's revision and console errors (`specbake view --report FILE` writes it); with
// &png also the canvas with the labels drawn on it.
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { KTX2Loader } from 'three/addons/loaders/KTX2Loader.js';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { RoomEnvironment } from 'three/addons/environments/RoomEnvironment.js';
import { SpecbakeSpecularAAPlugin } from '../specbake-three.js';

const query = new URLSearchParams(location.search);
const reportAfter = Number(query.get('report') || 0);
const errors = [];
for (const level of ['error', 'warn']) {
    const original = console[level].bind(console);
    console[level] = (...args) => {
        errors.push({ level, text: args.map((a) => (a instanceof Error ? a.message : String(a))).join(' ').slice(0, 2000) });
        original(...args);
    };
}
const $ = (id) => document.getElementById(id);
function fail(message) {
    $('error').style.display = 'block';
    $('error').textContent = message;
    console.error(message);
    if (reportAfter) fetch('/report', { method: 'POST', body: JSON.stringify({ fatal: message, errors }) });
}

const canvas = $('view');
// preserveDrawingBuffer: the report reads the finished frame back.
const renderer = new THREE.WebGLRenderer({ canvas, antialias: false, preserveDrawingBuffer: true });
renderer.setPixelRatio(Math.min(window.devicePixelRatio, 2));
renderer.toneMapping = THREE.NeutralToneMapping;
renderer.setScissorTest(true);
const gl = renderer.getContext();
const ktx2 = new KTX2Loader().setTranscoderPath('/three/examples/jsm/libs/basis/').detectSupport(renderer);
const environment = new THREE.PMREMGenerator(renderer).fromScene(new RoomEnvironment(), 0.04).texture;
const camera = new THREE.PerspectiveCamera(35, 1, 0.01, 1000);
const controls = new OrbitControls(camera, canvas);
controls.enableDamping = false;
controls.autoRotate = true;

const halves = [
    { name: 'off', label: $('leftTime'), scene: null, times: [] },
    { name: 'on', label: $('rightTime'), scene: null, times: [] },
];
let plugins = [];
let radius = 1;

function makeScene(root) {
    const scene = new THREE.Scene();
    scene.background = new THREE.Color(0x202225);
    scene.environment = environment;
    const sun = new THREE.DirectionalLight(0xffffff, 2.5);
    sun.position.set(0.6, 1.0, 0.4);
    scene.add(root, sun);
    return scene;
}

async function load(path) {
    plugins = [];
    const roots = [];
    for (const enabled of [false, true]) {
        const loader = new GLTFLoader().setKTX2Loader(ktx2);
        loader.register((parser) => {
            const plugin = new SpecbakeSpecularAAPlugin(parser, { enabled });
            plugins.push(plugin);
            return plugin;
        });
        roots.push((await loader.loadAsync(`/scene/${path}`)).scene);
    }
    halves[0].scene = makeScene(roots[0]);
    halves[1].scene = makeScene(roots[1]);
    const box = new THREE.Box3().setFromObject(roots[1]);
    const sphere = box.getBoundingSphere(new THREE.Sphere());
    radius = sphere.radius || 1;
    controls.target.copy(sphere.center);
    camera.near = radius / 100;
    camera.far = radius * 100;
    placeCamera(new THREE.Vector3(0.3, 0.25, 1).normalize());
    for (const h of halves) h.times = [];
    const patched = plugins[1].report.patched.length, skipped = plugins[1].report.skipped;
    $('status').textContent = `three.js r${THREE.REVISION} from ${info.three.source} · ${patched} material(s) patched` +
        (skipped.length ? `, ${skipped.length} left as three.js draws them (${skipped.map((s) => `${s.name}: ${s.reason}`).join('; ')})` : '');
}

function placeCamera(direction) {
    const distance = Number($('distance').value) * radius / Math.sin(THREE.MathUtils.degToRad(camera.fov / 2));
    camera.position.copy(controls.target).addScaledVector(direction, distance);
    camera.updateProjectionMatrix();
    controls.update();
}

function median(values) {
    const s = [...values].sort((a, b) => a - b);
    return s.length ? s[s.length >> 1] : NaN;
}

const pixel = new Uint8Array(4);
let frames = 0, last = performance.now(), reported = false;
function drawFrame(now) {
    const dt = Math.min(0.1, (now - last) / 1000);
    last = now;
    controls.autoRotate = $('orbit').checked;
    controls.autoRotateSpeed = Number($('speed').value) * 4;  // 2 is one orbit in 30 s
    controls.update(dt);
    const width = canvas.clientWidth, height = canvas.clientHeight;
    renderer.setSize(width, height, false);
    const halfWidth = Math.floor(width / 2);
    camera.aspect = halfWidth / height;
    camera.updateProjectionMatrix();
    halves.forEach((h, i) => {
        if (!h.scene) return;
        renderer.setViewport(i * halfWidth, 0, halfWidth, height);
        renderer.setScissor(i * halfWidth, 0, halfWidth, height);
        const start = performance.now();
        renderer.render(h.scene, camera);
        gl.readPixels(Math.floor((i + 0.5) * halfWidth * renderer.getPixelRatio()), 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, pixel);
        h.times.push(performance.now() - start);
        if (h.times.length > 60) h.times.shift();
    });
    if (frames % 15 === 0)
        for (const h of halves) h.label.textContent = `${median(h.times).toFixed(1)} ms`;
    if (halves[1].scene && ++frames === reportAfter && !reported) {
        reported = true;
        report();
    }
    requestAnimationFrame(drawFrame);
}

// Mean colour (0-255) and the fraction of pixels that differ from the background, per half of the canvas.
function halfStatistics() {
    const w = gl.drawingBufferWidth, h = gl.drawingBufferHeight;
    const data = new Uint8Array(w * h * 4);
    gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, data);
    const background = new THREE.Color(0x202225).convertLinearToSRGB();
    const bg = [background.r, background.g, background.b].map((v) => Math.round(v * 255));
    const half = Math.floor(w / 2);
    return [0, 1].map((i) => {
        let lit = 0, n = 0;
        const sum = [0, 0, 0];
        for (let y = 0; y < h; ++y) {
            for (let x = i * half; x < (i + 1) * half; ++x) {
                const p = 4 * (y * w + x);
                for (let c = 0; c < 3; ++c) sum[c] += data[p + c];
                if (Math.abs(data[p] - bg[0]) + Math.abs(data[p + 1] - bg[1]) + Math.abs(data[p + 2] - bg[2]) > 6) ++lit;
                ++n;
            }
        }
        return { mean: sum.map((s) => s / n), litFraction: lit / n };
    });
}

// The canvas with the halves' labels and the split line drawn over it, as the page shows them.
function screenshot() {
    const shot = document.createElement('canvas');
    shot.width = gl.drawingBufferWidth;
    shot.height = gl.drawingBufferHeight;
    const g = shot.getContext('2d');
    g.drawImage(canvas, 0, 0);
    const scale = shot.width / canvas.clientWidth;
    g.fillStyle = '#e8e8e8';
    g.fillRect(Math.floor(shot.width / 2) - scale, 0, 2 * scale, shot.height);
    g.font = `${13 * scale}px sans-serif`;
    for (const [i, id] of [[0, 'left'], [1, 'right']]) {
        const text = $(id).textContent, x = (i * shot.width) / 2 + 8 * scale, y = 8 * scale;
        g.fillStyle = 'rgba(0, 0, 0, 0.55)';
        g.fillRect(x, y, g.measureText(text).width + 16 * scale, 26 * scale);
        g.fillStyle = '#e8e8e8';
        g.fillText(text, x + 8 * scale, y + 18 * scale);
    }
    return shot.toDataURL('image/png');
}

function report() {
    const stats = halfStatistics();
    const body = {
        three: THREE.REVISION, scene: current, size: [gl.drawingBufferWidth, gl.drawingBufferHeight], frames,
        webgl: gl.getParameter(gl.VERSION),
        halves: halves.map((h, i) => ({ name: h.name, frameMs: median(h.times), samples: h.times.length, ...stats[i] })),
        labels: [$('left').textContent, $('right').textContent],
        status: $('status').textContent,
        plugin: plugins[1].report, pluginOff: plugins[0].report,
        png: query.has('png') ? screenshot() : undefined,
        errors,
    };
    fetch('/report', { method: 'POST', body: JSON.stringify(body) });
}

let info, current;
try {
    info = await (await fetch('/viewer.json')).json();
    const select = $('scene');
    for (const s of info.scenes) select.add(new Option(s, s));
    current = query.get('scene') ?? info.scenes[0];
    if (!info.scenes.includes(current)) throw new Error(`?scene=${current}: not one of ${info.scenes.join(', ')}`);
    select.value = current;
    if (query.has('distance')) $('distance').value = query.get('distance');
    if (query.get('orbit') === '0') $('orbit').checked = false;
    select.onchange = () => { location.search = `?scene=${encodeURIComponent(select.value)}`; };
    $('distance').oninput = () => placeCamera(camera.position.clone().sub(controls.target).normalize());
    window.addEventListener('keydown', (e) => {
        if (e.code === 'Space') $('orbit').checked = !$('orbit').checked;
    });
    await load(current);
    requestAnimationFrame(drawFrame);
} catch (e) {
    fail(`specbake viewer: ${e?.message ?? e}`);
}

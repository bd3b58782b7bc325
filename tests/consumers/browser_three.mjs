// The page browser_check.mjs opens for three.js plugin jobs: each scene of /job.json is loaded twice with
// three.js's GLTFLoader (KTX2Loader set), with specbake's plugin (web/three/specbake-three.js) and without,
// and rendered under a directional, a point, a spot and a hemisphere light and a prefiltered environment
// (PMREM of RoomEnvironment) into an RGBA32F target: patched, patched with every material opted out, and
// unpatched, and the unpatched scene at 16 x 16 samples per pixel (box filter) with its textures read at full
// resolution as the ground truth. Reports
// shader errors, the plugin's report, the filters of the bound chains, and per image the mean, whether any
// value is not finite, the largest difference to the unpatched image and the RMSE to the ground truth.
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { KTX2Loader } from 'three/addons/loaders/KTX2Loader.js';
import { RoomEnvironment } from 'three/addons/environments/RoomEnvironment.js';
import { SpecbakeSpecularAAPlugin, setSpecbakeSpecularAA } from '/web/three/specbake-three.js';

const post = (path, body) => fetch(path, { method: 'POST', body });
const pageLog = (line) => post('/log', String(line));
let captured = [];
for (const level of ['error', 'warn']) {
    const original = console[level].bind(console);
    console[level] = (...args) => {
        const text = args.map((a) => (a instanceof Error ? a.message : String(a))).join(' ');
        captured.push({ level, text });
        pageLog(`${level}: ${text.slice(0, 2000)}`);
        original(...args);
    };
}

const size = 48;
const canvas = document.createElement('canvas');
canvas.width = canvas.height = size;
const renderer = new THREE.WebGLRenderer({ canvas, antialias: false });
renderer.debug.checkShaderErrors = true;
const ktx2 = new KTX2Loader().setTranscoderPath('/node_modules/three/examples/jsm/libs/basis/').detectSupport(renderer);
const environment = new THREE.PMREMGenerator(renderer).fromScene(new RoomEnvironment(), 0.04).texture;
const target = new THREE.WebGLRenderTarget(size, size, { type: THREE.FloatType, format: THREE.RGBAFormat });
const supersampling = 16;
const bigTarget = new THREE.WebGLRenderTarget(size * supersampling, size * supersampling,
    { type: THREE.FloatType, format: THREE.RGBAFormat });

// The image at `size` x `size`, or with `ground` the mean of 16 x 16 samples per pixel: the pixel
// integral the filtering approximates, from three.js's own unfiltered shading.
function render(root, ground = false) {
    const scene = new THREE.Scene();
    scene.environment = environment;
    scene.add(root);
    const box = new THREE.Box3().setFromObject(root);
    const center = box.getCenter(new THREE.Vector3()), extent = box.getSize(new THREE.Vector3()).length();
    // Far enough that the baked mips are minified (the quad covers about half the image).
    const camera = new THREE.PerspectiveCamera(30, 1, 0.01, 100);
    camera.position.copy(center).add(new THREE.Vector3(0.15, 0.1, 1).normalize().multiplyScalar(2.2 * extent));
    camera.lookAt(center);
    const sun = new THREE.DirectionalLight(0xffffff, 3);
    sun.position.set(-0.3, -0.2, 1);
    const point = new THREE.PointLight(0xffffff, 4, 0, 2);
    point.position.copy(center).add(new THREE.Vector3(0.2, 0.3, 0.8 * extent));
    const spot = new THREE.SpotLight(0xffffff, 4, 0, Math.PI / 5, 0.2, 2);
    spot.position.copy(camera.position);
    spot.target.position.copy(center);
    const sky = new THREE.HemisphereLight(0x8899ff, 0x221100, 0.5);
    scene.add(sun, point, spot, spot.target, sky);
    const n = ground ? supersampling : 1, big = size * n;
    renderer.setRenderTarget(ground ? bigTarget : target);
    renderer.render(scene, camera);
    const raw = new Float32Array(big * big * 4);
    renderer.readRenderTargetPixels(ground ? bigTarget : target, 0, 0, big, big, raw);
    renderer.setRenderTarget(null);
    scene.remove(root);
    if (!ground) return raw;
    const pixels = new Float32Array(size * size * 4);
    for (let y = 0; y < big; ++y)
        for (let x = 0; x < big; ++x)
            for (let c = 0; c < 4; ++c) pixels[4 * ((y / n | 0) * size + (x / n | 0)) + c] += raw[4 * (y * big + x) + c] / (n * n);
    return pixels;
}

function stats(pixels, reference, ground) {
    let sum = 0, finite = true, maxDiff = 0, squared = 0;
    for (let i = 0; i < pixels.length; i += 4) {
        for (let c = 0; c < 3; ++c) {
            const v = pixels[i + c];
            if (!Number.isFinite(v)) finite = false;
            sum += v;
            if (reference) maxDiff = Math.max(maxDiff, Math.abs(v - reference[i + c]));
            if (ground) squared += (v - ground[i + c]) ** 2;
        }
    }
    return { mean: sum / (3 * size * size), finite, maxDiff, rmseToGround: Math.sqrt(squared / (3 * size * size)) };
}

function materialsOf(root) {
    const out = new Set();
    root.traverse((o) => {
        if (o.isMesh) for (const m of Array.isArray(o.material) ? o.material : [o.material]) out.add(m);
    });
    return [...out];
}

async function checkScene(entry) {
    let plugin = null;
    const patchedLoader = new GLTFLoader().setKTX2Loader(ktx2);
    patchedLoader.register((parser) => (plugin = new SpecbakeSpecularAAPlugin(parser)));
    const patched = await patchedLoader.loadAsync(`/data/${entry.path}`);
    const plain = await new GLTFLoader().setKTX2Loader(ktx2).loadAsync(`/data/${entry.path}`);
    // The ground truth's copy reads every texture at its full resolution (no mips): the supersampling, not
    // the mip chain, averages the normal map over each pixel.
    const unfiltered = await new GLTFLoader().setKTX2Loader(ktx2).loadAsync(`/data/${entry.path}`);
    for (const m of materialsOf(unfiltered.scene)) {
        for (const slot of ['map', 'normalMap', 'roughnessMap', 'metalnessMap', 'clearcoatNormalMap', 'clearcoatRoughnessMap']) {
            if (!m[slot]) continue;
            m[slot].minFilter = THREE.LinearFilter;
            m[slot].needsUpdate = true;
        }
    }
    const materials = materialsOf(patched.scene);
    const chains = [];
    for (const m of materials) {
        const s = m.userData.specbake;
        if (!s) continue;
        for (const t of [s.baseTexture, s.coatTexture]) {
            if (t) chains.push({ minFilter: t.minFilter === THREE.LinearMipmapLinearFilter ? 'LinearMipmapLinear' : String(t.minFilter),
                levels: t.mipmaps?.length ?? 0, generateMipmaps: t.generateMipmaps, type: t.type });
        }
    }
    const ground = render(unfiltered.scene, true);
    const reference = render(plain.scene);
    const programsBefore = renderer.info.programs.length;
    const on = render(patched.scene);
    const states = materials.map((m) => setSpecbakeSpecularAA(m, false));
    const off = render(patched.scene);
    for (const m of materials) setSpecbakeSpecularAA(m, true);
    const onAgain = render(patched.scene);
    return {
        report: plugin.report, optOutCalls: states, chains,
        states: materials.map((m) => m.userData.specbake ? { base: m.userData.specbake.base, coat: m.userData.specbake.coat, curvature: m.userData.specbake.curvature } : null),
        programs: renderer.info.programs.length, programsBefore,
        reference: stats(reference, null, ground), on: stats(on, reference, ground), off: stats(off, reference, ground),
        onAgain: stats(onAgain, on, ground),
    };
}

async function main() {
    const job = await (await fetch('/job.json')).json();
    const results = [];
    for (const entry of job.scenes) {
        captured = [];
        try {
            const r = await checkScene(entry);
            results.push({ id: entry.id, ok: true, ...r, console: captured });
        } catch (e) {
            results.push({ id: entry.id, ok: false, error: String(e?.stack ?? e), console: captured });
        }
    }
    const gl = renderer.getContext();
    await post('/result', JSON.stringify({ three: THREE.REVISION, webgl: gl.getParameter(gl.VERSION), results }));
}
main().catch((e) => post('/result', JSON.stringify({ fatal: String(e?.stack ?? e) })));

// The page browser_check.mjs opens for simulator-match jobs: each baked scene of /job.json is loaded with
// GLTFLoader and specbake's plugin (web/three/specbake-three.js) and drawn as the simulator draws its frame
// (the frame.json `specbake verify --frame-data` wrote beside it): its camera, its directional lights with
// irradiance `radiance` (three.js: intensity, white), and specular only with F = 1 (every material white
// metal: no base colour, metalness or emissive map, no occlusion, no environment, no multiple-scattering
// compensation), into an RGBA32F target at
// the frame's size. Posts per scene the radiance (red) and coverage (alpha) rows top to bottom, patched and
// with every material opted out, and what the plugin patched.
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { KTX2Loader } from 'three/addons/loaders/KTX2Loader.js';
import { SpecbakeSpecularAAPlugin, setSpecbakeSpecularAA } from '/web/three/specbake-three.js';

const post = (path, body) => fetch(path, { method: 'POST', body });
let captured = [];
for (const level of ['error', 'warn']) {
    const original = console[level].bind(console);
    console[level] = (...args) => {
        captured.push({ level, text: args.map((a) => (a instanceof Error ? a.message : String(a))).join(' ').slice(0, 2000) });
        original(...args);
    };
}

const renderer = new THREE.WebGLRenderer({ canvas: document.createElement('canvas'), antialias: false });
renderer.debug.checkShaderErrors = true;
const ktx2 = new KTX2Loader().setTranscoderPath('/node_modules/three/examples/jsm/libs/basis/').detectSupport(renderer);

function render(root, frame) {
    const scene = new THREE.Scene();
    scene.add(root);
    for (const l of frame.lights) {
        if (l.type !== 'directional') throw new Error(`light type ${l.type}: only directional lights are matched`);
        const light = new THREE.DirectionalLight(0xffffff, l.radiance);
        light.position.set(...l.direction);  // towards the light; the target stays at the origin
        scene.add(light, light.target);
    }
    const c = frame.camera;
    const camera = new THREE.PerspectiveCamera(c.fovYDegrees, frame.width / frame.height, 0.01, 1000);
    camera.position.set(...c.position);
    camera.up.set(...c.up);
    camera.lookAt(new THREE.Vector3(...c.target));
    camera.updateMatrixWorld();
    const target = new THREE.WebGLRenderTarget(frame.width, frame.height, { type: THREE.FloatType, format: THREE.RGBAFormat });
    renderer.setRenderTarget(target);
    renderer.setClearColor(0x000000, 0);
    renderer.clear();
    renderer.render(scene, camera);
    const raw = new Float32Array(frame.width * frame.height * 4);
    renderer.readRenderTargetPixels(target, 0, 0, frame.width, frame.height, raw);
    renderer.setRenderTarget(null);
    target.dispose();
    scene.remove(root);
    const radiance = [], coverage = [];
    for (let y = frame.height - 1; y >= 0; --y)  // read back bottom-up; the simulator's row 0 is the top
        for (let x = 0; x < frame.width; ++x) {
            radiance.push(raw[4 * (y * frame.width + x)]);
            coverage.push(raw[4 * (y * frame.width + x) + 3]);
        }
    return { radiance, coverage };
}

async function checkScene(entry) {
    const frame = await (await fetch(`/data/${entry.frame}`)).json();
    let plugin = null;
    const loader = new GLTFLoader().setKTX2Loader(ktx2);
    loader.register((parser) => (plugin = new SpecbakeSpecularAAPlugin(parser)));
    const gltf = await loader.loadAsync(`/data/${entry.path}`);
    const materials = new Set();
    gltf.scene.traverse((o) => {
        if (o.isMesh) for (const m of Array.isArray(o.material) ? o.material : [o.material]) materials.add(m);
    });
    for (const m of materials) {
        // White metal: F0 = F90 = 1, so three.js's Schlick Fresnel is 1 and there is no diffuse term.
        m.color?.setRGB(1, 1, 1);
        m.map = null;
        m.metalness = 1;
        m.metalnessMap = null;
        m.emissive?.setRGB(0, 0, 0);
        m.emissiveMap = null;
        m.aoMap = null;
        m.vertexColors = false;
        // The simulator scatters once: three.js's multiple-scattering compensation of the direct specular
        // (material.multiScatteringCompensation, >= 1, growing with roughness) is taken out.
        const previous = m.onBeforeCompile;
        m.onBeforeCompile = (shader, r) => {
            previous.call(m, shader, r);
            shader.fragmentShader = shader.fragmentShader
                .replace('#include <lights_physical_pars_fragment>', THREE.ShaderChunk.lights_physical_pars_fragment)
                .replace('irradiance * specularBRDF * material.multiScatteringCompensation', 'irradiance * specularBRDF');
        };
        m.needsUpdate = true;
    }
    const on = render(gltf.scene, frame);
    for (const m of materials) setSpecbakeSpecularAA(m, false);
    const off = render(gltf.scene, frame);
    return { report: plugin.report, width: frame.width, height: frame.height, on, off };
}

async function main() {
    const job = await (await fetch('/job.json')).json();
    const results = [];
    for (const entry of job.scenes) {
        captured = [];
        try {
            results.push({ id: entry.id, ok: true, ...(await checkScene(entry)), console: captured });
        } catch (e) {
            results.push({ id: entry.id, ok: false, error: String(e?.stack ?? e), console: captured });
        }
    }
    await post('/result', JSON.stringify({ three: THREE.REVISION, results }));
}
main().catch((e) => post('/result', JSON.stringify({ fatal: String(e?.stack ?? e) })));

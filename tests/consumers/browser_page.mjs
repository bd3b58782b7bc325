// The page browser_check.mjs opens: loads each entry of /job.json with the three.js loader it names, reports
// size, format, type, filters and level count, and reads texels back from the GPU texture (a quad sampling
// textureLod at level k into an RGBA32F render target, then readPixels) at the sample points the job lists.
import * as THREE from 'three';
import { KTX2Loader } from 'three/addons/loaders/KTX2Loader.js';
import { DDSLoader } from 'three/addons/loaders/DDSLoader.js';
import { EXRLoader } from 'three/addons/loaders/EXRLoader.js';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';

const post = (path, body) => fetch(path, { method: 'POST', body });
const pageLog = (line) => post('/log', String(line));

// Console errors and warnings while a file is loaded are its rejection reasons (DDSLoader only logs).
let captured = [];
for (const level of ['error', 'warn']) {
    const original = console[level].bind(console);
    console[level] = (...args) => {
        const text = args.map((a) => (a instanceof Error ? a.message : String(a))).join(' ');
        captured.push(text);
        pageLog(`${level}: ${text}`);
        original(...args);
    };
}
window.addEventListener('error', (e) => pageLog(`uncaught: ${e.message}`));
window.addEventListener('unhandledrejection', (e) => pageLog(`unhandled rejection: ${e.reason}`));

// Names of three.js's format and type constants, for the report.
const constantName = (value, suffix) =>
    Object.keys(THREE).find((k) => k.endsWith(suffix) && THREE[k] === value) ?? String(value);

const canvas = document.createElement('canvas');
canvas.width = canvas.height = 1;
const renderer = new THREE.WebGLRenderer({ canvas, antialias: false, alpha: true });
const gl = renderer.getContext();

const ktx2 = new KTX2Loader().setTranscoderPath('/node_modules/three/examples/jsm/libs/basis/').detectSupport(renderer);
const loaders = {
    KTX2Loader: ktx2,
    DDSLoader: new DDSLoader(),
    EXRLoader: new EXRLoader().setDataType(THREE.FloatType),
    TextureLoader: new THREE.TextureLoader(),
};
const gltfLoader = new GLTFLoader().setKTX2Loader(ktx2);

// Level k of `texture` as RGBA floats, row 0 = the file's first row (textures are uploaded unflipped).
const quad = new THREE.Mesh(new THREE.PlaneGeometry(2, 2), new THREE.RawShaderMaterial({
    glslVersion: THREE.GLSL3,
    uniforms: { tex: { value: null }, lod: { value: 0 }, size: { value: new THREE.Vector2() } },
    vertexShader: 'in vec3 position; void main() { gl_Position = vec4(position.xy, 0.0, 1.0); }',
    fragmentShader: `precision highp float; precision highp sampler2D;
        uniform sampler2D tex; uniform float lod; uniform vec2 size; out vec4 color;
        void main() { color = textureLod(tex, gl_FragCoord.xy / size, lod); }`,
    depthTest: false,
}));
const scene = new THREE.Scene();
scene.add(quad);
const camera = new THREE.Camera();
function readLevel(texture, level, width, height) {
    const target = new THREE.WebGLRenderTarget(width, height, { type: THREE.FloatType, format: THREE.RGBAFormat,
        depthBuffer: false, minFilter: THREE.NearestFilter, magFilter: THREE.NearestFilter });
    while (gl.getError() !== gl.NO_ERROR);  // errors of earlier files are theirs
    quad.material.uniforms.tex.value = texture;
    quad.material.uniforms.lod.value = level;
    quad.material.uniforms.size.value.set(width, height);
    renderer.setRenderTarget(target);
    renderer.render(scene, camera);
    const pixels = new Float32Array(width * height * 4);
    renderer.readRenderTargetPixels(target, 0, 0, width, height, pixels);
    renderer.setRenderTarget(null);
    target.dispose();
    const glError = gl.getError();
    if (glError !== gl.NO_ERROR) throw new Error(`WebGL error 0x${glError.toString(16)} sampling level ${level}`);
    return pixels;
}

function describe(texture) {
    const mipmaps = texture.mipmaps ?? [];
    const image = texture.image ?? {};
    return {
        width: image.width ?? 0, height: image.height ?? 0,
        format: constantName(texture.format, 'Format'), type: constantName(texture.type, 'Type'),
        levels: mipmaps.length > 0 ? mipmaps.length : 1,
        mipSizes: mipmaps.map((m) => [m.width, m.height]),
        minFilter: constantName(texture.minFilter, 'Filter'), magFilter: constantName(texture.magFilter, 'Filter'),
        colorSpace: texture.colorSpace,
    };
}

async function checkTexture(entry) {
    const texture = await loaders[entry.loader].loadAsync(`/data/${entry.path}`);
    const info = describe(texture);
    if (!(info.width > 0) || (texture.isCompressedTexture && (texture.mipmaps ?? []).length === 0))
        throw new Error(captured.join('; ') || 'loader returned an empty texture');
    // Exact texels: no filtering, no colour conversion, rows as stored.
    texture.flipY = false;
    texture.colorSpace = THREE.NoColorSpace;
    texture.generateMipmaps = false;
    texture.minFilter = info.levels > 1 ? THREE.NearestMipmapNearestFilter : THREE.NearestFilter;
    texture.magFilter = THREE.NearestFilter;
    texture.needsUpdate = true;
    const values = [];
    const byLevel = new Map();
    for (const s of entry.samples ?? []) (byLevel.get(s.level) ?? byLevel.set(s.level, []).get(s.level)).push(s);
    const got = new Map();
    for (const [level, samples] of byLevel) {
        if (level >= info.levels) continue;
        const w = info.mipSizes[level]?.[0] ?? Math.max(1, info.width >> level);
        const h = info.mipSizes[level]?.[1] ?? Math.max(1, info.height >> level);
        const pixels = readLevel(texture, level, w, h);
        for (const s of samples) {
            const i = 4 * (s.y * w + s.x);
            got.set(s, Array.from(pixels.subarray(i, i + 4)));
        }
    }
    for (const s of entry.samples ?? []) values.push(got.get(s) ?? null);
    texture.dispose();
    return { ...info, values };
}

async function checkGltf(entry) {
    const gltf = await gltfLoader.loadAsync(`/data/${entry.path}`);
    let meshes = 0;
    const materials = new Map();
    gltf.scene.traverse((o) => {
        if (!o.isMesh) return;
        meshes += 1;
        for (const m of Array.isArray(o.material) ? o.material : [o.material]) materials.set(m.uuid, m);
    });
    const maps = {};
    for (const m of materials.values())
        for (const slot of ['map', 'normalMap', 'roughnessMap', 'metalnessMap', 'aoMap', 'clearcoatNormalMap'])
            if (m[slot]) (maps[slot] ??= []).push(describe(m[slot]));
    return { meshes, materials: materials.size, maps, extensionsUsed: gltf.parser.json.extensionsUsed ?? [] };
}

async function main() {
    const job = await (await fetch('/job.json')).json();
    const results = [];
    for (const entry of job.entries) {
        captured = [];
        const started = performance.now();
        try {
            const r = entry.loader === 'GLTFLoader' ? await checkGltf(entry) : await checkTexture(entry);
            results.push({ id: entry.id, ok: true, ...r, warnings: captured, ms: performance.now() - started });
        } catch (e) {
            results.push({ id: entry.id, ok: false, error: String(e?.message ?? e), warnings: captured });
        }
    }
    const debug = gl.getExtension('WEBGL_debug_renderer_info');
    await post('/result', JSON.stringify({
        webgl: gl.getParameter(gl.VERSION),
        renderer: debug ? gl.getParameter(debug.UNMASKED_RENDERER_WEBGL) : gl.getParameter(gl.RENDERER),
        three: THREE.REVISION, extensions: gl.getSupportedExtensions(), results,
    }));
}
main().catch((e) => post('/result', JSON.stringify({ fatal: String(e?.stack ?? e) })));

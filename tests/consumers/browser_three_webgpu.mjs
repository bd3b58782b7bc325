// The WGSL include in three.js's WebGPURenderer, as docs/shader-include.md#webgpu-wgsl shows it: the whole
// include as one TSL wgsl() code node, and wgslFn functions that list it among their includes.
// - "grid": a full-screen quad whose fragmentNode is a wgslFn of the quad's uv, (u, v, A.xx, D) with
//   r = 0.1 + 0.8 u, K = t (1, 0.5, 0.25), t = 2 v^2, A = specaa_widened_matrix(r^4, K) and
//   D = specaa_default_D(h, A, surface of roughness r), rendered into a size x size float target.
// - "sphere": a MeshStandardNodeMaterial sphere whose roughnessNode is specaa_filtered_roughness of the
//   vertex normal (the per-pixel kernel from its quad derivatives), lit by a directional light; then the
//   same roughness written as the fragment output and read back (float target); then
//   specaa_filtered_roughness_kernel with a one-texel kernel texture (job.texel, RGBA8) passed from TSL's
//   texture() and sampler() nodes, read back the same way.
// Posts the backend ("WebGPU" or the WebGL 2 fallback), every console error and uncaptured WebGPU error,
// and the read-backs.
import * as THREE from 'three/webgpu';
import { float, normalViewGeometry, sampler, texture, uv, vec4, wgsl, wgslFn } from 'three/tsl';
import specaaSource from '/web/three/specaa.wgsl.js';

const post = (path, body) => fetch(path, { method: 'POST', body });
const errors = [];
for (const level of ['error', 'warn']) {
    const original = console[level];
    console[level] = (...args) => {
        errors.push(`${level}: ${args.map(String).join(' ')}`);
        original(...args);
    };
}

const specaa = wgsl(specaaSource);
const gridFn = wgslFn(`
fn specbakeGrid(coord: vec2<f32>) -> vec4<f32> {
    var s: SpecaaSurface;
    s.roughness = 0.1 + 0.8 * coord.x;
    let t = 2.0 * coord.y * coord.y;
    let A = specaa_widened_matrix(specaa_base_alpha2(s), t * vec3<f32>(1.0, 0.5, 0.25));
    let h = vec3<f32>(0.3, 0.2, 0.932737905308881);
    return vec4<f32>(coord, A.x, specaa_default_D(h, A, s));
}`, [specaa]);
const roughnessFn = wgslFn(`
fn specbakeRoughness(roughness: f32, normal: vec3<f32>) -> f32 {
    var s: SpecaaSurface;
    s.roughness = roughness;
    s.normal = normal;
    return specaa_filtered_roughness(s);
}`, [specaa]);

const kernelRoughnessFn = wgslFn(`
fn specbakeKernelRoughness(roughness: f32, normal: vec3<f32>, coord: vec2<f32>, kernelTexture: texture_2d<f32>,
                           kernelSampler: sampler) -> f32 {
    var s: SpecaaSurface;
    s.roughness = roughness;
    s.normal = normal;
    s.uv = coord;
    return specaa_filtered_roughness_kernel(s, kernelTexture, kernelSampler);
}`, [specaa]);

async function readFloats(renderer, scene, camera, size) {
    const target = new THREE.RenderTarget(size, size, { type: THREE.FloatType });
    renderer.setRenderTarget(target);
    renderer.render(scene, camera);
    renderer.setRenderTarget(null);
    const pixels = await renderer.readRenderTargetPixelsAsync(target, 0, 0, size, size);
    target.dispose();
    return Array.from(pixels);
}

async function main() {
    const job = await (await fetch('/job.json')).json();
    const size = job.size;
    const renderer = new THREE.WebGPURenderer({ antialias: false });
    renderer.setSize(size, size);
    document.body.appendChild(renderer.domElement);
    await renderer.init();
    const backend = renderer.backend.isWebGPUBackend ? 'WebGPU' : 'WebGL 2 fallback';
    renderer.backend.device?.addEventListener('uncapturederror', (e) => errors.push(`uncaptured: ${e.error.message}`));
    const camera = new THREE.OrthographicCamera(-1, 1, 1, -1, 0.1, 10);
    camera.position.z = 2;

    const quadMaterial = new THREE.MeshBasicNodeMaterial();
    quadMaterial.fragmentNode = gridFn({ coord: uv() });
    const quad = new THREE.Scene();
    quad.add(new THREE.Mesh(new THREE.PlaneGeometry(2, 2), quadMaterial));
    const grid = await readFloats(renderer, quad, camera, size);

    const sphere = new THREE.Scene();
    const lit = new THREE.MeshStandardNodeMaterial({ color: 0xffffff, metalness: 0 });
    lit.roughnessNode = roughnessFn({ roughness: float(job.roughness), normal: normalViewGeometry });
    const mesh = new THREE.Mesh(new THREE.SphereGeometry(job.radius, 64, 32), lit);
    sphere.add(mesh);
    const light = new THREE.DirectionalLight(0xffffff, 3);
    light.position.set(1, 1, 2);
    sphere.add(light);
    const shaded = await readFloats(renderer, sphere, camera, size);
    const probe = new THREE.MeshBasicNodeMaterial();
    probe.fragmentNode = vec4(roughnessFn({ roughness: float(job.roughness), normal: normalViewGeometry }), 0, 0, 1);
    mesh.material = probe;
    const roughness = await readFloats(renderer, sphere, camera, size);
    // The same with a baked kernel texture: one texel (RGBA8), trilinear.
    const kernelMap = new THREE.DataTexture(new Uint8Array(job.texel), 1, 1);
    kernelMap.magFilter = THREE.LinearFilter;
    kernelMap.minFilter = THREE.LinearMipmapLinearFilter;
    kernelMap.needsUpdate = true;
    const kernelProbe = new THREE.MeshBasicNodeMaterial();
    const kernelNode = texture(kernelMap);
    kernelProbe.fragmentNode = vec4(kernelRoughnessFn({ roughness: float(job.roughness), normal: normalViewGeometry,
        coord: uv(), kernelTexture: kernelNode, kernelSampler: sampler(kernelNode) }), 0, 0, 1);
    mesh.material = kernelProbe;
    const kernelRoughness = await readFloats(renderer, sphere, camera, size);
    await post('/result', JSON.stringify({ backend, userAgent: navigator.userAgent, errors, grid, shaded, roughness,
        kernelRoughness }));
}
main().catch((e) => post('/result', JSON.stringify({ fatal: String(e?.stack ?? e), errors })));
